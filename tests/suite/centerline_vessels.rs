//! Centrelines of the phantoms and of the real vessels (issue 20): the stenosis phantom's
//! narrowing found at 50 ± 3% with no other lesion, no narrowing above 5% on the intact
//! phantoms; on every real vessel of ../shared/data/real one connected graph per component, no
//! terminal branch shorter than its radius, every open end an endpoint; the coronary's known
//! lesion found first; a region of `--stenoses` reported at its own throat, not a neighbour's.

use crate::common;

use nalgebra::Point3;
use vesselmsr::centerline::healthy::HealthyVessel;
use vesselmsr::centerline::profile::measure_profiles;
use vesselmsr::centerline::stenosis::{find_stenoses, Lesion, StenosisFindOptions};
use vesselmsr::centerline::{compute_centerline, Centerline, CenterlineOptions, EndKind};
use vesselmsr::inpaint::holes::{classify_loops, LoopKind, LoopOptions};
use vesselmsr::inpaint::phantom::{make_phantom, PhantomKind, PhantomOptions};
use vesselmsr::inpaint::region::Ball;
use vesselmsr::report::repair_report::{region_reports, DETECTED_STENOSIS};
use vesselmsr::TriMesh;

fn centerline(mesh: &TriMesh) -> Centerline {
    compute_centerline(mesh, &CenterlineOptions::default())
        .unwrap()
        .0
}

/// Lesions of at least 3% and the largest narrowing over all branches, in percent.
fn narrowings(mesh: &TriMesh, cl: &Centerline) -> (Vec<Lesion>, f64) {
    let profiles = measure_profiles(mesh, cl);
    let (lesions, branches) = find_stenoses(
        cl,
        &profiles,
        &StenosisFindOptions {
            min_degree_pct: 3.0,
        },
    );
    let max = branches
        .iter()
        .map(|b| b.max_narrowing_pct)
        .fold(0.0, f64::max);
    (lesions, max)
}

#[test]
fn phantoms_stenosis_found_and_intact_vessels_clear() {
    for kind in PhantomKind::ALL {
        let ph = make_phantom(kind, &PhantomOptions::default()).unwrap();
        let truth = centerline(&ph.truth);
        let (_, max) = narrowings(&ph.truth, &truth);
        println!(
            "{}: truth {} branches, largest narrowing {max:.2}%",
            kind.as_str(),
            truth.branches.len()
        );
        assert!(
            max < 5.0,
            "{}: intact vessel narrowed by {max}%",
            kind.as_str()
        );
        assert_eq!(
            truth.branches.len(),
            ph.centerlines.len(),
            "{}",
            kind.as_str()
        );
        if kind == PhantomKind::Stenosis {
            let cl = centerline(&ph.damaged);
            let (lesions, _) = narrowings(&ph.damaged, &cl);
            let l = &lesions[0];
            let at = Point3::from(l.position);
            println!(
                "stenosis: {:.2}% diameter ({:.2}% area) at {:.3} from the region's centre, length {:.3}, {} lesion(s) of 3% or more",
                l.diameter_stenosis_pct,
                l.area_stenosis_pct,
                (at - ph.regions[0].center).norm(),
                l.length,
                lesions.len()
            );
            assert!((l.diameter_stenosis_pct - 50.0).abs() <= 3.0);
            assert!((at - ph.regions[0].center).norm() <= ph.radius);
            assert_eq!(lesions.len(), 1);
        }
    }
}

/// A closed straight tube of radius `r` along z over [−len/2, len/2], narrowed by
/// 1 − depth·exp(−z²/2σ²) (a Gaussian narrowing of `depth` at z = 0), flat ends, fine rings.
fn narrowed_tube(r: f64, len: f64, depth: f64, sigma: f64) -> TriMesh {
    let (rings, seg) = (401, 64);
    let mut v = Vec::new();
    for i in 0..rings {
        let z = -0.5 * len + len * i as f64 / (rings - 1) as f64;
        let ri = r * (1.0 - depth * (-z * z / (2.0 * sigma * sigma)).exp());
        for j in 0..seg {
            let a = std::f64::consts::TAU * j as f64 / seg as f64;
            v.push(Point3::new(ri * a.cos(), ri * a.sin(), z));
        }
    }
    let (bottom, top) = (v.len() as u32, v.len() as u32 + 1);
    v.push(Point3::new(0.0, 0.0, -0.5 * len));
    v.push(Point3::new(0.0, 0.0, 0.5 * len));
    let at = |i: usize, j: usize| (i * seg + j % seg) as u32;
    let mut f = Vec::new();
    for i in 0..rings - 1 {
        for j in 0..seg {
            f.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            f.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    for j in 0..seg {
        f.push([bottom, at(0, j + 1), at(0, j)]);
        f.push([top, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    TriMesh::new(v, f)
}

/// A short lesion (σ = 0.6 radii, the benchmark's on the aneurysm's ICA) is reported at its
/// narrowest section: the median filter over a radius of arc that finds lesions reads a V-shaped
/// profile a quarter of its window out (this lesion's 50% came out at 43.9% from it, 1.1 radii off).
#[test]
fn a_short_lesion_is_measured_at_its_narrowest_section() {
    let r = 3.0;
    let mesh = narrowed_tube(r, 40.0, 0.5, 0.6 * r);
    assert!(vesselmsr::mesh::measures::signed_volume(&mesh) > 0.0);
    let cl = centerline(&mesh);
    let (lesions, _) = narrowings(&mesh, &cl);
    let l = &lesions[0];
    println!(
        "{:.2}% diameter ({:.2}% NASCET), min {:.4} against {:.4}, at z = {:.3}",
        l.diameter_stenosis_pct,
        l.nascet_stenosis_pct,
        l.min_diameter,
        l.reference_diameter,
        l.position[2]
    );
    assert!((l.diameter_stenosis_pct - 50.0).abs() <= 1.5, "{l:?}");
    assert!((l.min_diameter - r).abs() <= 0.05 * r, "{l:?}");
    assert!(l.position[2].abs() <= 0.1 * r, "{l:?}");
}

/// One connected graph per component: branches linked through their junctions.
fn graph_components(cl: &Centerline) -> usize {
    let mut parent: Vec<usize> = (0..cl.branches.len()).collect();
    fn find(p: &mut [usize], x: usize) -> usize {
        let mut r = x;
        while p[r] != r {
            r = p[r];
        }
        p[x] = r;
        r
    }
    for j in &cl.junctions {
        for w in j.branches.windows(2) {
            let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
            parent[a] = b;
        }
    }
    (0..cl.branches.len())
        .filter(|&b| find(&mut parent, b) == b)
        .count()
}

#[test]
fn real_vessels_graphs() {
    let Some(meshes) = common::real_meshes() else {
        return;
    };
    for (name, mesh) in meshes {
        if name.starts_with("cortex") {
            continue;
        }
        let cl = centerline(&mesh);
        let h = cl.voxel;
        let ends: Vec<_> = classify_loops(&mesh, &LoopOptions::default())
            .into_iter()
            .filter(|l| l.kind == LoopKind::End)
            .collect();
        println!(
            "{name}: {} component(s), {} branches, {} junctions, {} endpoints ({} open, {} open ends), total length {:.4}, h {h:.4}",
            cl.components,
            cl.branches.len(),
            cl.junctions.len(),
            cl.endpoints.len(),
            cl.endpoints.iter().filter(|e| e.open_end).count(),
            ends.len(),
            cl.total_length()
        );
        assert_eq!(graph_components(&cl), cl.components, "{name}");
        for b in &cl.branches {
            let terminal = b.start == EndKind::End || b.end == EndKind::End;
            let mut r = b.radius.clone();
            r.sort_by(f64::total_cmp);
            let radius = r[r.len() / 2];
            println!(
                "  branch {}: {:?} -> {:?}, length {:.4}, median radius {:.4}",
                b.id, b.start, b.end, b.length, radius
            );
            if terminal && cl.branches.len() > 1 {
                assert!(
                    b.length >= radius,
                    "{name}: spur {} ({} < {radius})",
                    b.id,
                    b.length
                );
            }
        }
        for l in &ends {
            let hit = cl
                .endpoints
                .iter()
                .filter(|e| e.open_end)
                .map(|e| (e.position - l.center).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                hit <= h,
                "{name}: open end at {:?} is {hit} from an endpoint",
                l.center
            );
            // Its radius is the loop's (it was the inscribed radius at the loop's centre: 0).
            let e = cl
                .endpoints
                .iter()
                .filter(|e| e.open_end)
                .min_by(|a, b| {
                    (a.position - l.center)
                        .norm()
                        .total_cmp(&(b.position - l.center).norm())
                })
                .unwrap();
            assert!(
                (e.radius - l.radius).abs() <= 1e-9 * l.radius,
                "{name}: open end radius {} against the loop's {}",
                e.radius,
                l.radius
            );
        }
        assert_eq!(
            cl.endpoints.iter().filter(|e| e.open_end).count(),
            ends.len(),
            "{name}"
        );
    }
}

#[test]
fn coronary_lesion_found() {
    let Some(dir) = common::real_dir() else {
        return;
    };
    let mesh = common::read_real(&dir, "coronary_stenosis_xray.stl");
    let cl = centerline(&mesh);
    let (lesions, _) = narrowings(&mesh, &cl);
    let known = Point3::new(26.0, -21.6, 68.2);
    let l = &lesions[0];
    let at = Point3::from(l.position);
    println!(
        "coronary: first lesion {:.1}% diameter ({:.1}% area), {:.3} mm from the known one, minimum {:.3} mm against {:.3} mm, length {:.3} mm; then {:?}",
        l.diameter_stenosis_pct,
        l.area_stenosis_pct,
        (at - known).norm(),
        l.min_diameter,
        l.reference_diameter,
        l.length,
        lesions[1..]
            .iter()
            .filter(|l| l.diameter_stenosis_pct >= 10.0)
            .map(|l| format!("{:.1}% at s = {:.1}", l.diameter_stenosis_pct, l.s))
            .collect::<Vec<_>>()
    );
    assert!((at - known).norm() <= 1.5);
    assert!((30.0..=60.0).contains(&l.diameter_stenosis_pct));
}

/// `repair --stenoses` reports each narrowing it found at its own throat: on a tube with two
/// narrowings 8 radii apart (50% and 35% of the radius), a ball on the shallower one large
/// enough to hold the deeper one's throat reports the shallower one's degree (as the centreline
/// finds it) when it is a detected narrowing's region, and the deepest narrowing in it when it
/// is a plain region.
#[test]
fn a_detected_narrowing_is_reported_at_its_own_throat() {
    let mut tube = vesselmsr::mesh::primitives::open_tube(3.0, 40.0, 96, 321);
    let dent = |z: f64, z0: f64, sigma: f64, depth: f64| {
        1.0 - depth * (-(z - z0).powi(2) / (2.0 * sigma * sigma)).exp()
    };
    for v in &mut tube.vertices {
        let f = dent(v.z, 16.0, 1.5, 0.5) * dent(v.z, 24.0, 2.5, 0.35);
        v.x *= f;
        v.y *= f;
    }
    let healthy = HealthyVessel::new(&tube, centerline(&tube), &StenosisFindOptions::default());
    let deep = healthy
        .lesions
        .iter()
        .max_by(|a, b| a.diameter_stenosis_pct.total_cmp(&b.diameter_stenosis_pct))
        .unwrap()
        .clone();
    let shallow = healthy
        .lesions
        .iter()
        .max_by(|a, b| a.position[2].total_cmp(&b.position[2]))
        .unwrap()
        .clone();
    let (pd, ps) = (Point3::from(deep.position), Point3::from(shallow.position));
    println!(
        "deep {:.1}% at z = {:.2}, shallow {:.1}% at z = {:.2}",
        deep.diameter_stenosis_pct, pd.z, shallow.diameter_stenosis_pct, ps.z
    );
    assert!(deep.diameter_stenosis_pct > shallow.diameter_stenosis_pct + 8.0);
    let ball = Ball {
        center: ps,
        radius: 1.1 * (pd - ps).norm(),
    };
    let reports = region_reports(
        &tube,
        &tube,
        &[ball, ball],
        &[DETECTED_STENOSIS.into(), "region".into()],
        Some(&healthy),
        None,
    );
    // Each throat's own figure: the region report's measure within half a radius of it.
    let own = |p: Point3<f64>| {
        let small = Ball {
            center: p,
            radius: 1.5,
        };
        healthy
            .measure_in(&tube, &small)
            .unwrap()
            .diameter_stenosis_pct
    };
    let pct = |k: usize| reports[k].diameter_stenosis_pct.unwrap();
    println!(
        "detected region {:.1}% (its throat {:.1}%), plain region {:.1}% (the deeper throat {:.1}%)",
        pct(0),
        own(ps),
        pct(1),
        own(pd)
    );
    assert!(own(pd) > own(ps) + 8.0);
    assert!((pct(0) - own(ps)).abs() < 1.0);
    assert!((pct(1) - own(pd)).abs() < 1.0);
}
