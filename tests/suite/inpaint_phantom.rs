//! Synthetic damaged vessels (inpaint/phantom): every kind gives a watertight, outward truth and
//! damaged mesh; the truth volume matches the analytic one (π R² L, Pappus for the arc, a fine
//! midpoint-rule integral of the analytic φ for the Y); the curved and occluded vessels fall in two
//! pieces; the stenosis throat is half the diameter; damaged and truth differ only inside D;
//! seeds move the damage; the CLI writes its three files or none.

use crate::common;
use common::*;
use nalgebra::Point3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::OnceLock;
use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::inpaint::phantom::{make_phantom, Phantom, PhantomKind, PhantomOptions};
use vesselmsr::inpaint::region::{Ball, RegionsFile};
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::TriMesh;

const R: f64 = 3.0;

/// The five phantoms at the default options (R = 3, h = R/8, seed 1), built once.
fn phantoms() -> &'static [Phantom] {
    static CELL: OnceLock<Vec<Phantom>> = OnceLock::new();
    CELL.get_or_init(|| {
        PhantomKind::ALL
            .iter()
            .map(|&k| make_phantom(k, &PhantomOptions::default()).unwrap())
            .collect()
    })
}

fn phantom(kind: PhantomKind) -> &'static Phantom {
    phantoms().iter().find(|p| p.kind == kind).unwrap()
}

/// ∫ [φ < 0] over the box [lo, hi] by the midpoint rule on cells of side `step` (the slabs of
/// cells counted in parallel: the count is the same).
fn integrate_inside(
    phi: impl Fn(&Point3<f64>) -> f64 + Sync,
    lo: Point3<f64>,
    hi: Point3<f64>,
    step: f64,
    keep: impl Fn(&Point3<f64>) -> bool + Sync,
) -> f64 {
    let n: Vec<usize> = (0..3)
        .map(|a| ((hi[a] - lo[a]) / step).ceil() as usize)
        .collect();
    let count: usize = (0..n[2])
        .into_par_iter()
        .map(|k| {
            let mut count = 0usize;
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let p = lo
                        + nalgebra::Vector3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5)
                            * step;
                    if keep(&p) && phi(&p) < 0.0 {
                        count += 1;
                    }
                }
            }
            count
        })
        .sum();
    count as f64 * step.powi(3)
}

/// The analytic volume of the truth: π R² L for the straight tubes, Pappus (π R² · bend · 2π/3)
/// for the arc, and for the Y the midpoint-rule integral of its analytic φ on cells of h/4.
fn analytic_truth_volume(p: &Phantom) -> f64 {
    match p.kind {
        PhantomKind::Tube | PhantomKind::Stenosis | PhantomKind::Occlusion => PI * R * R * 10.0 * R,
        PhantomKind::Curved => PI * R * R * (4.0 * R) * (2.0 * PI / 3.0),
        PhantomKind::Bifurcation => {
            let info = mesh_info(&p.truth);
            let pad = 2.0 * p.voxel;
            let lo = Point3::from(info.bbox_min) - nalgebra::Vector3::from([pad; 3]);
            let hi = Point3::from(info.bbox_max) + nalgebra::Vector3::from([pad; 3]);
            integrate_inside(|q| p.truth_sdf(q), lo, hi, p.voxel / 4.0, |_| true)
        }
    }
}

#[test]
fn every_kind_is_watertight_outward_with_the_analytic_truth_volume() {
    for p in phantoms() {
        let kind = p.kind;
        assert_eq!(p.radius, R);
        assert!(
            (p.voxel - R / 8.0).abs() < 1e-12,
            "{kind}: voxel {}",
            p.voxel
        );
        for (what, mesh) in [("truth", &p.truth), ("damaged", &p.damaged)] {
            let info = mesh_info(mesh);
            assert!(info.watertight, "{kind} {what}: {:?}", info.leaks());
            assert!(info.signed_volume > 0.0, "{kind} {what} faces inward");
            assert_eq!(info.orientation.as_str(), "outward", "{kind} {what}");
        }
        let volume = mesh_info(&p.truth).volume.unwrap();
        let expected = analytic_truth_volume(p);
        let r = rel(volume, expected);
        println!("{kind}: truth volume {volume:.3} vs analytic {expected:.3} (rel {r:.2e})");
        assert!(r < 0.02, "{kind}: truth volume {volume} vs {expected}");
        let damaged = mesh_info(&p.damaged).volume.unwrap();
        assert!(damaged < volume, "{kind}: damage removes volume");
        println!("{kind}: {}", p.description);
    }
}

#[test]
fn the_y_volume_integral_agrees_with_pi_r2_l_on_the_tube() {
    // The midpoint integral used as the Y's reference, checked on the straight tube.
    let p = phantom(PhantomKind::Tube);
    let half = 5.0 * R + 0.5;
    let lo = Point3::new(-R - 0.5, -R - 0.5, -half);
    let hi = Point3::new(R + 0.5, R + 0.5, half);
    let v = integrate_inside(|q| p.truth_sdf(q), lo, hi, p.voxel / 4.0, |_| true);
    let expected = PI * R * R * 10.0 * R;
    println!("tube: integral {v:.3} vs π R² L {expected:.3}");
    assert!(rel(v, expected) < 2e-3);
}

#[test]
fn components_two_pieces_for_a_gap_one_otherwise() {
    for p in phantoms() {
        let truth = mesh_info(&p.truth).components;
        let damaged = mesh_info(&p.damaged).components;
        let expected = match p.kind {
            PhantomKind::Curved | PhantomKind::Occlusion => 2,
            _ => 1,
        };
        println!("{}: components truth {truth}, damaged {damaged}", p.kind);
        assert_eq!(truth, 1, "{}", p.kind);
        assert_eq!(damaged, expected, "{}", p.kind);
    }
}

/// Points where the mesh edges cross the plane z = z0.
fn slice_z(mesh: &TriMesh, z0: f64) -> Vec<Point3<f64>> {
    let mut points = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for f in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if !seen.insert((a.min(b), a.max(b))) {
                continue;
            }
            let (pa, pb) = (mesh.vertices[a as usize], mesh.vertices[b as usize]);
            if (pa.z - z0) * (pb.z - z0) < 0.0 {
                let t = (z0 - pa.z) / (pb.z - pa.z);
                points.push(pa + (pb - pa) * t);
            }
        }
    }
    points
}

#[test]
fn stenosis_throat_is_half_the_diameter() {
    let p = phantom(PhantomKind::Stenosis);
    let throat = p.regions[0].center.z;
    for (z, expected) in [(throat, 0.5 * R), (throat + 4.5 * R * 0.9, R)] {
        let slice = slice_z(&p.damaged, z);
        assert!(slice.len() > 20, "slice at z = {z}");
        let rho: Vec<f64> = slice.iter().map(|q| q.x.hypot(q.y)).collect();
        let (min, max) = rho
            .iter()
            .fold((f64::INFINITY, 0f64), |(a, b), &r| (a.min(r), b.max(r)));
        let mean = rho.iter().sum::<f64>() / rho.len() as f64;
        println!(
            "stenosis slice z = {z:.3}: diameter mean {:.4}, min {:.4}, max {:.4} (expected {:.4})",
            2.0 * mean,
            2.0 * min,
            2.0 * max,
            2.0 * expected
        );
        assert!(rel(min, expected) < 0.05 && rel(max, expected) < 0.05);
    }
    // The truth keeps the full diameter there.
    for q in slice_z(&p.truth, throat) {
        assert!(rel(q.x.hypot(q.y), R) < 0.05);
    }
}

fn outside_all(regions: &[Ball], q: &Point3<f64>) -> bool {
    !regions.iter().any(|b| b.contains(q))
}

#[test]
fn damaged_and_truth_differ_only_inside_the_regions() {
    for p in phantoms() {
        let kind = p.kind;
        let tol = 0.5 * p.voxel;
        let truth = MeshBvh::new(&p.truth);
        let damaged = MeshBvh::new(&p.damaged);
        let mut worst_out = 0f64;
        let mut worst_in = 0f64;
        for q in &p.damaged.vertices {
            let d = truth.closest_point(q).distance;
            if outside_all(&p.regions, q) {
                worst_out = worst_out.max(d);
            } else {
                worst_in = worst_in.max(d);
            }
        }
        let mut worst_truth_out = 0f64;
        for q in &p.truth.vertices {
            if outside_all(&p.regions, q) {
                worst_truth_out = worst_truth_out.max(damaged.closest_point(q).distance);
            }
        }
        println!(
            "{kind}: outside D, damaged→truth {:.4}h, truth→damaged {:.4}h; inside D damaged→truth \
             up to {:.2}h",
            worst_out / p.voxel,
            worst_truth_out / p.voxel,
            worst_in / p.voxel
        );
        assert!(
            worst_out <= tol,
            "{kind}: damaged vertex {worst_out} off the truth outside D"
        );
        assert!(
            worst_truth_out <= tol,
            "{kind}: truth vertex {worst_truth_out} off the damaged outside D"
        );
        assert!(worst_in > 2.0 * p.voxel, "{kind}: no damage inside D");
    }
}

/// Volume of the solid bounded by `mesh` inside the ball, by the winding number on cells of
/// side `step` (midpoint rule).
fn volume_in_ball(mesh: &TriMesh, ball: &Ball, step: f64) -> f64 {
    let w = WindingNumber::new(mesh, WindingOptions::default());
    let pad = nalgebra::Vector3::from([ball.radius; 3]);
    integrate_inside(
        |q| 0.5 - w.winding_number(q),
        ball.center - pad,
        ball.center + pad,
        step,
        |q| ball.contains(q),
    )
}

#[test]
fn volumes_inside_the_regions() {
    for p in phantoms() {
        let kind = p.kind;
        assert_eq!(p.regions.len(), 1);
        let ball = &p.regions[0];
        // Cells of one voxel (half a voxel took 8 times the winding numbers, 24 s): the lost
        // volume matches the whole meshes' difference to 0.3% of the truth in D on each
        // phantom (0.6% on half-voxel cells), well inside the 2% allowed.
        let step = p.voxel;
        let truth_in = volume_in_ball(&p.truth, ball, step);
        let damaged_in = volume_in_ball(&p.damaged, ball, step);
        let truth = mesh_info(&p.truth).volume.unwrap();
        let damaged = mesh_info(&p.damaged).volume.unwrap();
        println!(
            "{kind}: D centre ({:.3}, {:.3}, {:.3}) radius {:.3}; volume in D: truth {truth_in:.2}, \
             damaged {damaged_in:.2} (removed {:.2}); whole meshes differ by {:.2}",
            ball.center.x,
            ball.center.y,
            ball.center.z,
            ball.radius,
            truth_in - damaged_in,
            truth - damaged
        );
        // All of the lost volume is inside D (to the sampling error of the integral).
        let lost_in = truth_in - damaged_in;
        assert!(
            (lost_in - (truth - damaged)).abs() < 0.02 * truth_in,
            "{kind}: lost {lost_in} in D vs {} in all",
            truth - damaged
        );
    }
}

#[test]
fn seeds_move_the_damage_and_repeat() {
    for kind in PhantomKind::ALL {
        let opts = |seed| PhantomOptions {
            seed,
            ..Default::default()
        };
        let a = make_phantom(kind, &opts(1)).unwrap();
        let again = make_phantom(kind, &opts(1)).unwrap();
        let b = make_phantom(kind, &opts(2)).unwrap();
        assert_eq!(a.damaged, again.damaged, "{kind}: same seed, same mesh");
        assert_eq!(a.regions, again.regions, "{kind}");
        assert_ne!(
            a.damaged, b.damaged,
            "{kind}: seeds 1 and 2 give the same damage"
        );
        assert_eq!(
            a.truth, b.truth,
            "{kind}: the truth does not depend on the seed"
        );
        let moved = (a.regions[0].center - b.regions[0].center).norm();
        println!("{kind}: seed 1 → 2 moves D by {moved:.4}");
        assert!(moved > 1e-3, "{kind}: D did not move");
    }
}

#[test]
fn kinds_parse_and_options_are_checked() {
    for kind in PhantomKind::ALL {
        assert_eq!(kind.as_str().parse::<PhantomKind>().unwrap(), kind);
    }
    let err = "vein".parse::<PhantomKind>().unwrap_err().to_string();
    for kind in PhantomKind::ALL {
        assert!(err.contains(kind.as_str()), "{err}");
    }
    for radius in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let opts = PhantomOptions {
            radius,
            ..Default::default()
        };
        assert!(
            make_phantom(PhantomKind::Tube, &opts).is_err(),
            "radius {radius}"
        );
    }
    for voxels_per_radius in [0.0, 1.0, f64::NAN, 1000.0] {
        let opts = PhantomOptions {
            voxels_per_radius,
            ..Default::default()
        };
        assert!(
            make_phantom(PhantomKind::Tube, &opts).is_err(),
            "{voxels_per_radius}"
        );
    }
    // Units are the caller's: a 100-fold radius scales the volume a million-fold (to 0.1%: the
    // grid's f32 values and its node count per axis are not exactly scale-invariant).
    let small = make_phantom(
        PhantomKind::Tube,
        &PhantomOptions {
            radius: 0.03,
            ..Default::default()
        },
    )
    .unwrap();
    let big = phantom(PhantomKind::Tube);
    let ratio = mesh_info(&big.truth).volume.unwrap() / mesh_info(&small.truth).volume.unwrap();
    assert!(rel(ratio, 1e6) < 1e-3, "{ratio}");
}

#[test]
fn cli_writes_the_three_files() {
    let tmp = tempfile::tempdir().unwrap();
    let damaged = tmp.path().join("damaged.stl");
    let truth = tmp.path().join("truth.ply");
    let regions = tmp.path().join("d.json");
    let report = vesselmsr_json(&[
        "phantom",
        "stenosis",
        "--json",
        "-o",
        damaged.to_str().unwrap(),
        "--truth",
        truth.to_str().unwrap(),
        "--regions-out",
        regions.to_str().unwrap(),
        "--seed",
        "3",
        "--radius",
        "2",
        "--voxel",
        "0.4",
    ]);
    println!("{report}");
    assert_eq!(report["kind"], "stenosis");
    assert_eq!(report["radius"], 2.0);
    assert!((report["voxel"].as_f64().unwrap() - 0.4).abs() < 1e-12);
    for path in [&damaged, &truth] {
        let mesh = vesselmsr::io::read_mesh(path).unwrap();
        assert!(mesh_info(&mesh).watertight, "{}", path.display());
    }
    let truth_mesh = vesselmsr::io::read_mesh(&truth).unwrap();
    let v = mesh_info(&truth_mesh).volume.unwrap();
    assert!(rel(v, report["truth_volume"].as_f64().unwrap()) < 1e-9);
    let file: RegionsFile =
        serde_json::from_str(&std::fs::read_to_string(&regions).unwrap()).unwrap();
    assert_eq!(file.regions.len(), 1);
    assert!((file.regions[0].radius - 3.0 * 1.2 * 2.0).abs() < 1e-9);
    assert_eq!(
        serde_json::to_value(file.regions[0]).unwrap(),
        report["regions"][0]
    );
    // Nothing else left in the folder (no temporaries).
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 3);
}

#[test]
fn cli_bad_arguments_exit_2_without_output() {
    let tmp = tempfile::tempdir().unwrap();
    let damaged = tmp.path().join("damaged.stl");
    let truth = tmp.path().join("truth.stl");
    let regions = tmp.path().join("d.json");
    let args = |kind: &'static str, extra: &[&'static str]| {
        let mut v: Vec<String> = vec![
            "phantom".into(),
            kind.into(),
            "-o".into(),
            damaged.to_string_lossy().into_owned(),
            "--truth".into(),
            truth.to_string_lossy().into_owned(),
            "--regions-out".into(),
            regions.to_string_lossy().into_owned(),
        ];
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let cases: [(Vec<String>, &str); 5] = [
        (args("vein", &[]), "bifurcation"),
        (args("tube", &["--radius", "0"]), "radius"),
        (args("tube", &["--radius=-1"]), "radius"),
        (args("tube", &["--voxel", "0"]), "voxel"),
        (args("tube", &["--voxel", "5"]), "voxel"),
    ];
    for (argv, word) in &cases {
        let argv: Vec<&str> = argv.iter().map(String::as_str).collect();
        assert_fails(&argv, word, &damaged);
        assert!(
            !truth.exists() && !regions.exists(),
            "{argv:?} left an output"
        );
    }
    // An unwritable truth format: refused before anything is written.
    let bad_truth = tmp.path().join("truth.xyz");
    let argv = [
        "phantom",
        "tube",
        "-o",
        damaged.to_str().unwrap(),
        "--truth",
        bad_truth.to_str().unwrap(),
        "--regions-out",
        regions.to_str().unwrap(),
    ];
    assert_fails(&argv, "format", &damaged);
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}
