//! Vessel repair (issue: inpainting) on the phantoms with known truth: accuracy inside D against
//! the truth, watertightness (ours and manifold3d's verdict), the triangles outside D kept as they
//! were, the report's figures, and bad input through the command line.

use crate::common;

use common::{
    assert_fails, hausdorff_in, in_regions, loop_kinds, oracle, vesselmsr, vesselmsr_json,
    volume_error_in,
};
use nalgebra::Point3;
use std::collections::HashSet;
use vesselmsr::bvh::MeshBvh;
use vesselmsr::inpaint::holes::{classify_loops, LoopKind, LoopOptions};
use vesselmsr::inpaint::phantom::{make_phantom, Phantom, PhantomKind, PhantomOptions};
use vesselmsr::inpaint::pipeline::{repair_vessel, RepairedVessel, VesselRepair};
use vesselmsr::inpaint::region::Ball;
use vesselmsr::inpaint::repair::{region_margin, repair, InpaintMethod, Repair, RepairOptions};
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::topology::connected_components;
use vesselmsr::report::stenosis::volume_in_ball;
use vesselmsr::TriMesh;

fn phantom(kind: PhantomKind) -> Phantom {
    make_phantom(kind, &PhantomOptions::default()).unwrap()
}

/// Repairs a phantom at its own voxel size with `method`.
fn repaired(ph: &Phantom, method: InpaintMethod) -> Repair {
    let opts = RepairOptions {
        method,
        voxel: Some(ph.voxel),
        ..RepairOptions::default()
    };
    repair(&ph.damaged, &ph.regions, &opts).unwrap()
}

/// Every triangle of `input` with all three vertices outside D is in `output`, same coordinates.
fn assert_outside_kept(input: &TriMesh, output: &TriMesh, balls: &[Ball]) {
    let key = |m: &TriMesh, f: &[u32; 3]| {
        let mut k: Vec<[u64; 3]> = f
            .iter()
            .map(|&v| m.vertices[v as usize].coords.map(f64::to_bits))
            .map(|c| [c.x, c.y, c.z])
            .collect();
        let min = (0..3).min_by_key(|&i| k[i]).unwrap();
        k.rotate_left(min);
        k
    };
    let have: HashSet<Vec<[u64; 3]>> = output.faces.iter().map(|f| key(output, f)).collect();
    let mut kept = 0;
    for f in &input.faces {
        if f.iter()
            .all(|&v| !in_regions(balls, &input.vertices[v as usize]))
        {
            assert!(
                have.contains(&key(input, f)),
                "a triangle outside D changed"
            );
            kept += 1;
        }
    }
    assert!(kept > 0);
}

#[test]
fn phantoms_are_restored_within_the_acceptance_bounds() {
    // (kind, Hausdorff bound in h, volume error bound)
    let cases = [
        (PhantomKind::Tube, 1.5, 0.05),
        (PhantomKind::Stenosis, 1.5, 0.05),
        (PhantomKind::Occlusion, 1.5, 0.05),
        (PhantomKind::Bifurcation, 1.5, 0.05),
        (PhantomKind::Curved, 1.5, 0.05),
    ];
    for (kind, hd_bound, vol_bound) in cases {
        let ph = phantom(kind);
        let r = repaired(&ph, InpaintMethod::Centerline);
        let hd = hausdorff_in(&r.mesh, &ph.truth, &ph.regions) / ph.voxel;
        let ve = volume_error_in(&r.mesh, &ph.truth, &ph.regions);
        let damaged_ve = volume_error_in(&ph.damaged, &ph.truth, &ph.regions);
        println!(
            "{}: Hausdorff in D {hd:.2}h, volume error in D {:+.2}% (damaged {:+.1}%), stitched {}",
            kind.as_str(),
            100.0 * ve,
            100.0 * damaged_ve,
            r.stitched
        );
        assert!(hd <= hd_bound, "{}: Hausdorff {hd}h", kind.as_str());
        assert!(
            ve.abs() <= vol_bound,
            "{}: volume error {ve}",
            kind.as_str()
        );
        assert!(mesh_info(&r.mesh).watertight);
        assert_eq!(connected_components(&r.mesh).0, 1);
        assert_manifold3d(&r.mesh);
        assert!(r.stitched, "{}: {:?}", kind.as_str(), r.fallback);
        assert_outside_kept(&ph.damaged, &r.mesh, &ph.regions);
    }
}

/// manifold3d's verdict on `mesh`: NoError (a closed oriented 2-manifold).
fn assert_manifold3d(mesh: &TriMesh) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.stl");
    vesselmsr::io::write_mesh(&path, mesh).unwrap();
    let check = oracle().check(&path);
    assert_eq!(check["manifold_status"], "NoError", "{check}");
}

#[test]
fn curved_gap_is_bridged_into_one_tube() {
    let ph = phantom(PhantomKind::Curved);
    assert_eq!(connected_components(&ph.damaged).0, 2);
    let r = repaired(&ph, InpaintMethod::Centerline);
    let ve = volume_error_in(&r.mesh, &ph.truth, &ph.regions);
    let hd = hausdorff_in(&r.mesh, &ph.truth, &ph.regions) / ph.voxel;
    println!(
        "curved: volume error in D {:+.2}%, Hausdorff in D {hd:.2}h",
        100.0 * ve
    );
    assert_eq!(connected_components(&r.mesh).0, 1);
    // The centreline fill follows the bend (the axial one, along the chord, was 4.6h / +7%).
    assert!(hd <= 1.5, "Hausdorff {hd}h");
    assert!(ve.abs() <= 0.05, "volume error {ve}");
    assert!(mesh_info(&r.mesh).watertight);
    assert_manifold3d(&r.mesh);
    assert_outside_kept(&ph.damaged, &r.mesh, &ph.regions);
}

#[test]
fn every_method_gives_a_closed_outward_vessel() {
    let tube = phantom(PhantomKind::Tube);
    for method in InpaintMethod::ALL {
        let r = repaired(&tube, method);
        let info = mesh_info(&r.mesh);
        let ve = volume_error_in(&r.mesh, &tube.truth, &tube.regions);
        println!(
            "tube, {method}: volume error in D {:+.1}%, {} iterations",
            100.0 * ve,
            r.iterations
        );
        assert!(info.watertight && info.signed_volume > 0.0, "{method}");
        // The report's c and T are the ones the method ran with (`paper` once reported msr's
        // T = R²/2 while running R², `flow` msr's c = 1/R while running 0.3/R).
        let (big_r, r2) = (r.radius_estimate, r.radius_estimate.powi(2));
        let used = match method {
            InpaintMethod::Flow => Some((0.3 / big_r, r2)),
            InpaintMethod::Paper => Some((1.0 / big_r, r2)),
            InpaintMethod::Msr => Some((1.0 / big_r, 0.5 * r2)),
            _ => None,
        };
        if let Some((c, t)) = used {
            assert!(
                (r.speed - c).abs() < 1e-9 * c && (r.time - t).abs() < 1e-9 * t,
                "{method}: reported c = {}, T = {}; ran c = {c}, T = {t}",
                r.speed,
                r.time
            );
        }
        // The fills that carry data across D or grow the shape add volume back into the chopped
        // wall; Algorithm 4 as written only smooths it (its viscosity is a curvature motion),
        // as ../shared/notes/inpainting.md measured.
        let damaged = volume_error_in(&tube.damaged, &tube.truth, &tube.regions);
        if method != InpaintMethod::Paper {
            assert!(ve > damaged, "{method}: {ve} vs damaged {damaged}");
        }
    }
}

#[test]
fn a_growth_speed_given_alone_sizes_the_grid_for_the_growth_that_runs() {
    // `-c` without `--time` sized the sub-box for c·(region radius)², not the c·T that runs
    // (T = R²/2 for msr): c = 1 on the tube's region (radius 6.6, 2.2 R) gave a growth margin of
    // 43.6 (a box about 110 units wide, against 37 now), and on the stenosis phantom's region
    // (3.6 R) `paper -c 0.712` was refused for 149 GiB. Now at
    // most the region's radius is allowed before R is known, and the grids are sized again
    // where the growth that runs needs more (c = 2: c·T = 8.3 > 6.6).
    let tube = phantom(PhantomKind::Tube);
    let rmax = tube.regions.iter().map(|b| b.radius).fold(0.0, f64::max);
    for c in [1.0, 2.0] {
        let opts = RepairOptions {
            method: InpaintMethod::Msr,
            speed: Some(c),
            ..RepairOptions::default()
        };
        let out = repair(&tube.damaged, &tube.regions, &opts).unwrap();
        let (h, t) = (out.voxel, out.time);
        assert!(
            (t - 0.5 * out.radius_estimate.powi(2)).abs() < 1e-9 * t,
            "T = {t}"
        );
        let exact = RepairOptions {
            time: Some(t),
            ..opts.clone()
        };
        // The box around the ball holds the growth c·T that ran, and not much more.
        let need = 2.0 * (rmax + region_margin(&exact, &tube.regions, h));
        let most = need + 2.0 * (rmax - c * t).max(0.0);
        let extent = out.grid_dims.map(|n| (n - 1) as f64 * h);
        println!(
            "c = {c}: c·T = {:.2}, box {extent:.1?}, need {need:.1}",
            c * t
        );
        assert!(mesh_info(&out.mesh).watertight, "c = {c}");
        for e in extent {
            assert!(
                e >= need - 2.0 * h && e <= most + 3.0 * h,
                "c = {c}: {e} vs {need}..{most}"
            );
        }
    }
}

#[test]
fn the_curvature_motions_work_at_an_eighth_of_the_radius_by_default() {
    // At the default rule's voxel (mean edge / 2: R/25 here) flow took 44–120 s a phantom, msr
    // 10–74 s and paper up to 1,100 s; at R/8, where their figures are measured, 1–27 s (R by
    // 2·volume/area, 2.46 on the chopped tube: R/9.7 here).
    let tube = phantom(PhantomKind::Tube);
    let r = tube.radius;
    for (method, lo, hi) in [
        (InpaintMethod::Centerline, 0.0, r / 16.0),
        (InpaintMethod::Msr, r / 10.0, r / 7.0),
    ] {
        let opts = RepairOptions {
            method,
            ..RepairOptions::default()
        };
        let out = repair(&tube.damaged, &tube.regions, &opts).unwrap();
        println!("{method}: default voxel {:.4} (R = {r})", out.voxel);
        assert!(out.voxel > lo && out.voxel < hi, "{method}: {}", out.voxel);
        assert!(mesh_info(&out.mesh).watertight);
    }
}

#[test]
fn cli_repairs_the_stenosis_phantom_and_reports_it() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n).to_string_lossy().into_owned();
    let made = vesselmsr(&[
        "phantom",
        "stenosis",
        "-o",
        &p("d.stl"),
        "--truth",
        &p("t.stl"),
        "--regions-out",
        &p("d.json"),
        "-q",
    ]);
    assert!(made.status.success());
    let report = vesselmsr_json(&[
        "repair",
        &p("d.stl"),
        "--regions",
        &p("d.json"),
        "-o",
        &p("out.stl"),
        "--voxel",
        "0.375",
        "--report",
        &p("r.json"),
        "--units",
        "mm",
        "--json",
        "-q",
    ]);
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("r.json")).unwrap()).unwrap();
    assert_eq!(file, report, "the report file is what --json prints");
    for key in [
        "input",
        "output",
        "regions",
        "watertight",
        "iterations",
        "converged",
        "parameters",
        "timings",
    ] {
        assert!(report.get(key).is_some(), "report lacks {key}");
    }
    assert_eq!(report["watertight"], true);
    assert_eq!(report["units"], "mm");
    // A vessel 8 voxels in radius: its patch is meshed on the fill's own grid (`patch_stride`).
    let params = &report["parameters"];
    assert_eq!(params["patch_voxel"], params["voxel"], "{params}");
    let region = &report["regions"][0];
    for key in [
        "center",
        "radius",
        "inpainted_volume",
        "inpainted_fraction",
        "diameter_stenosis_pct",
        "area_stenosis_pct",
        "nascet_stenosis_pct",
    ] {
        assert!(region.get(key).is_some(), "region lacks {key}");
    }
    let pct = region["diameter_stenosis_pct"].as_f64().unwrap();
    println!(
        "stenosis phantom: diameter stenosis {pct:.1}%, area {}",
        region["area_stenosis_pct"]
    );
    assert!((pct - 50.0).abs() <= 5.0, "diameter stenosis {pct}");
    // The inpainted volume is what the damage took away (truth − damaged in D).
    let ph = phantom(PhantomKind::Stenosis);
    let ball = ph.regions[0];
    let truth_in_d = volume_in_ball(&ph.truth, &ball);
    let removed = truth_in_d - volume_in_ball(&ph.damaged, &ball);
    let inpainted = region["inpainted_volume"].as_f64().unwrap();
    assert!(
        (inpainted - removed).abs() <= 0.05 * truth_in_d,
        "{inpainted} vs {removed}"
    );
    let fraction = region["inpainted_fraction"].as_f64().unwrap();
    let total = report["output"]["volume"].as_f64().unwrap();
    assert!((fraction - inpainted / total).abs() < 1e-9);
    // manifold3d's verdict on the written mesh.
    let check = oracle().check(std::path::Path::new(&p("out.stl")));
    assert_eq!(check["manifold_status"], "NoError", "{check}");
}

#[test]
fn cli_holes_and_open_ends() {
    // A wall patch cut from the shipped open-ended aorta: --holes finds it, the two ends stay
    // vessel ends; with --open-ends only those stay open.
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n).to_string_lossy().into_owned();
    let mut mesh = vesselmsr::io::read_mesh(std::path::Path::new(&common::aorta())).unwrap();
    let info = mesh_info(&mesh);
    let c = Point3::from(
        (nalgebra::Vector3::from(info.bbox_min) + nalgebra::Vector3::from(info.bbox_max)) / 2.0,
    );
    let bvh = MeshBvh::new(&mesh);
    let wall = bvh.closest_point(&c).point;
    let cut = 1.5 * info.mean_edge;
    mesh.faces.retain(|f| {
        f.iter()
            .all(|&v| (mesh.vertices[v as usize] - wall).norm() > cut)
    });
    let holed = p("holed.stl");
    vesselmsr::io::write_mesh(std::path::Path::new(&holed), &mesh).unwrap();
    let loops_before = mesh_info(&mesh).boundary_loops;
    let report = vesselmsr_json(&[
        "repair",
        &holed,
        "--holes",
        "-o",
        &p("out.stl"),
        "--json",
        "-q",
    ]);
    let kinds = loop_kinds(&report);
    println!("loops: {kinds:?}");
    assert_eq!(kinds.iter().filter(|k| **k == "hole").count(), 1);
    assert_eq!(kinds.len(), loops_before);
    assert_eq!(report["watertight"], true);
    let open = vesselmsr_json(&[
        "repair",
        &holed,
        "--holes",
        "--open-ends",
        "-o",
        &p("open.stl"),
        "--json",
        "-q",
    ]);
    let out = vesselmsr::io::read_mesh(std::path::Path::new(&p("open.stl"))).unwrap();
    assert_eq!(
        mesh_info(&out).boundary_loops,
        loops_before - 1,
        "{}",
        open["output"]
    );
}

#[test]
fn cli_bad_input_exits_2_without_output() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n).to_string_lossy().into_owned();
    let out = tmp.path().join("out.stl");
    let o = out.to_string_lossy().into_owned();
    let aorta = common::aorta();
    std::fs::write(p("bad.json"), "{\"regions\": [{\"centre\": [0,0,0]}]}").unwrap();
    std::fs::write(p("garbage.json"), "not json").unwrap();
    let (bad, garbage, missing) = (p("bad.json"), p("garbage.json"), p("missing.json"));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["repair", &aorta, "-o", &o, "--region", "1e6,1e6,1e6,1"],
            "region 1",
        ),
        (
            // Inside the bounding box, in its empty corner.
            vec!["repair", &aorta, "-o", &o, "--region", "206.7,102,13.5,0.5"],
            "touches no surface",
        ),
        (
            vec!["repair", &aorta, "-o", &o, "--region", "0,0,0,0"],
            "radius",
        ),
        (
            vec!["repair", &aorta, "-o", &o, "--region", "0,0,0,-2"],
            "radius",
        ),
        (
            vec!["repair", &aorta, "-o", &o, "--region", "1,2,3"],
            "x,y,z,r",
        ),
        (
            vec!["repair", &aorta, "-o", &o, "--regions", &bad],
            "bad.json",
        ),
        (
            vec!["repair", &aorta, "-o", &o, "--regions", &garbage],
            "garbage.json",
        ),
        (
            vec!["repair", &aorta, "-o", &o, "--regions", &missing],
            "missing.json",
        ),
        (vec!["repair", &aorta, "-o", &o], "no region"),
        (
            vec!["repair", &aorta, "-o", &o, "--region", "0,0,0,5", "-c", "0"],
            "speed",
        ),
        (
            vec![
                "repair", &aorta, "-o", &o, "--region", "0,0,0,5", "-c", "-1",
            ],
            "speed",
        ),
        (
            vec![
                "repair", &aorta, "-o", &o, "--region", "0,0,0,5", "--method", "magic",
            ],
            "magic",
        ),
    ];
    for (args, word) in &cases {
        assert_fails(args, word, &out);
    }
}

#[test]
fn real_coronary_stenosis_gets_a_tube_like_lumen_and_a_degree() {
    // The real focal stenosis of ../shared/data/real/coronary_stenosis_xray.stl (SOURCES.md: near
    // (26.0, −21.6, 68.2), mm), a 3 mm region around it.
    let Some(dir) = common::real_dir() else {
        return;
    };
    let input = common::read_real(&dir, "coronary_stenosis_xray.stl");
    let ball = Ball {
        center: Point3::new(26.0, -21.6, 68.2),
        radius: 3.0,
    };
    let r = repair(&input, &[ball], &RepairOptions::default()).unwrap();
    assert!(r.stitched, "{:?}", r.fallback);
    assert_eq!(connected_components(&r.mesh).0, 1);
    assert!(mesh_info(&r.mesh).watertight);
    assert_manifold3d(&r.mesh);
    assert_outside_kept(&r.closed_input, &r.mesh, &[ball]);
    let measure = |measured| {
        vesselmsr::report::repair_report::region_reports(
            &r.closed_input,
            &r.mesh,
            &[ball],
            &["region".into()],
            None,
            measured,
        )
    };
    // The winding numbers and volumes the self-checks measured are what fresh ones give.
    let (m_in, m_out) = r.measured.as_ref().expect("the stitch was checked");
    let reports = measure(Some([m_in, m_out]));
    assert_eq!(reports, measure(None));
    let g = &reports[0];
    println!(
        "coronary: inpainted {:.3} mm³ ({:.2}%), diameter stenosis {:?}%, area {:?}%, NASCET {:?}%, min input diameter {:?} mm, output {:?} mm",
        g.inpainted_volume,
        100.0 * g.inpainted_fraction,
        g.diameter_stenosis_pct,
        g.area_stenosis_pct,
        g.nascet_stenosis_pct,
        g.min_input_diameter,
        g.output_diameter_at_min
    );
    assert!(g.inpainted_volume > 0.0);
    let d = g
        .diameter_stenosis_pct
        .expect("a section through the lesion");
    assert!((30.0..70.0).contains(&d), "diameter stenosis {d}%");
    // The restored lumen at the lesion is about the size of the vessel next to it.
    let out = g.output_diameter_at_min.unwrap();
    assert!((2.0..3.2).contains(&out), "restored diameter {out} mm");
}

#[test]
fn an_inward_input_is_turned_outward_and_repaired() {
    // The stenosis phantom with every triangle flipped (as aorta_abdominal_capped is stored):
    // the repair faces outward, says so, and restores the same volume as from the outward input.
    let ph = phantom(PhantomKind::Stenosis);
    let mut inward = ph.damaged.clone();
    inward.flip_faces();
    assert!(mesh_info(&inward).signed_volume < 0.0);
    let opts = RepairOptions {
        voxel: Some(ph.voxel),
        ..RepairOptions::default()
    };
    let r = repair(&inward, &ph.regions, &opts).unwrap();
    let info = mesh_info(&r.mesh);
    assert!(info.watertight && info.signed_volume > 0.0);
    assert!(
        r.notices.iter().any(|n| n.contains("faced inward")),
        "{:?}",
        r.notices
    );
    let hd = hausdorff_in(&r.mesh, &ph.truth, &ph.regions) / ph.voxel;
    let ve = volume_error_in(&r.mesh, &ph.truth, &ph.regions);
    println!(
        "inward stenosis: Hausdorff in D {hd:.2}h, volume error in D {:+.2}%",
        100.0 * ve
    );
    assert!(hd <= 1.5 && ve.abs() <= 0.05, "{hd}h, {ve}");
    assert!(r.stitched, "{:?}", r.fallback);
}

/// `truth` with a 50% Gaussian narrowing (σ world units) at z = `z0` across its axis.
fn narrowed(truth: &TriMesh, z0: f64, sigma: f64) -> TriMesh {
    let mut damaged = truth.clone();
    for v in damaged.vertices.iter_mut() {
        let f = 1.0 - 0.5 * (-(v.z - z0).powi(2) / (2.0 * sigma * sigma)).exp();
        v.x *= f;
        v.y *= f;
    }
    damaged
}

/// Repairs the narrowing of `damaged` in the ball `d` as a narrowing's region (its lumen
/// intact) at voxel 0.25 and checks it is widened within 1.5h and 5% in D of `truth` (both open
/// tubes, compared with their ends capped), the damaged input more than 15% short there.
fn check_widened(truth: &TriMesh, damaged: &TriMesh, d: Ball, what: &str) {
    let d = [d];
    let h = 0.25;
    let opts = RepairOptions {
        voxel: Some(h),
        intact_lumen: vec![true],
        ..RepairOptions::default()
    };
    let r = repair(damaged, &d, &opts).unwrap();
    assert!(mesh_info(&r.mesh).watertight);
    assert_eq!(r.region_fill, ["widened"]);
    let (truth, _) = vesselmsr::mesh::cap::cap_holes(truth, &Default::default()).unwrap();
    let (closed, _) = vesselmsr::mesh::cap::cap_holes(damaged, &Default::default()).unwrap();
    let before = volume_error_in(&closed, &truth, &d);
    let hd = hausdorff_in(&r.mesh, &truth, &d) / h;
    let ve = volume_error_in(&r.mesh, &truth, &d);
    println!(
        "{what}: {hd:.2}h, {:+.2}% in D (damaged {:+.1}%)",
        100.0 * ve,
        100.0 * before
    );
    assert!(before < -0.15, "{what}: {before}");
    assert!(hd <= 1.5 && ve.abs() <= 0.05, "{what}: {hd}h {ve}");
}

#[test]
fn a_narrowing_whose_region_reaches_an_open_end_is_widened() {
    // A 50% narrowing 3 radii from a tube's open end, picked with a ball that holds the end's
    // rim (the end's cap is then in D). Its wall is the damage all the same: the ball was once
    // taken for a hole's, the fill kept off the narrowed wall, and nothing was restored (the
    // seed-26 iliac of benches/repair_real: 7.3h / −33% in D).
    let tube = vesselmsr::mesh::primitives::open_tube(3.0, 40.0, 96, 241);
    let z0 = 9.0;
    let d = Ball {
        center: Point3::new(0.0, 0.0, z0),
        radius: 10.0,
    };
    check_widened(
        &tube,
        &narrowed(&tube, z0, 2.7),
        d,
        "narrowing by an open end",
    );
}

#[test]
fn a_narrowing_before_a_bulb_is_widened_to_the_lumen_beside_it() {
    // A 50% narrowing (σ = 1.2 radii) whose tail runs into a bulb's flare 3.3 radii on (the
    // lumen doubling over 5 radii, as a carotid bulb), its region D reaching the flare. The
    // points between the lesion and the flare once read their shoulders across the lesion on
    // one side and up the bulb on the other, took that line for the healthy lumen, and widened
    // the lesion to it (the carotid narrowing of benches/repair_real, seeds 21 and 23: 2.8h /
    // +53% in D).
    let mut truth = vesselmsr::mesh::primitives::open_tube(3.0, 60.0, 96, 361);
    let (z0, z1, flare) = (20.0, 30.0, 15.0);
    for v in truth.vertices.iter_mut() {
        let t = ((v.z - z1) / flare).clamp(0.0, 1.0);
        let f = 1.0 + t * t * (3.0 - 2.0 * t);
        v.x *= f;
        v.y *= f;
    }
    let d = Ball {
        center: Point3::new(0.0, 0.0, z0),
        radius: 10.8,
    };
    check_widened(
        &truth,
        &narrowed(&truth, z0, 3.6),
        d,
        "narrowing before a bulb",
    );
}

/// A straight open tube (radius 3, ends cut at z = 0 and z = 40) chopped by a ball of radius 3
/// at (3, 0, `z`), its region D 1.3 chops wide, repaired at voxel 0.25: the damaged mesh, the
/// repair, and the repair's Hausdorff distance in D (voxels) and volume error in D against the
/// tube with its ends capped flat.
fn repair_tube_chopped_at(z: f64) -> (TriMesh, Repair, f64, f64) {
    let tube = vesselmsr::mesh::primitives::open_tube(3.0, 40.0, 96, 241);
    let chop = Ball {
        center: Point3::new(3.0, 0.0, z),
        radius: 3.0,
    };
    let damaged = common::punch_hole(&tube, chop.center, chop.radius);
    let d = [Ball {
        center: chop.center,
        radius: 1.3 * chop.radius,
    }];
    let h = 0.25;
    let opts = RepairOptions {
        voxel: Some(h),
        ..RepairOptions::default()
    };
    let r = repair(&damaged, &d, &opts).unwrap();
    assert!(mesh_info(&r.mesh).watertight);
    let (truth, _) = vesselmsr::mesh::cap::cap_holes(&tube, &Default::default()).unwrap();
    let hd = hausdorff_in(&r.mesh, &truth, &d) / h;
    let ve = volume_error_in(&r.mesh, &truth, &d);
    (damaged, r, hd, ve)
}

#[test]
fn a_hole_next_to_an_open_end_is_bridged_to_that_end() {
    // A wall chop whose region reaches the end at z = 0: on the centreline the vessel ends
    // inside D, at an open end. The fill bridges the intact section beyond D to the end's
    // centre and cuts it flat there (it once followed the damaged centreline, drawn off the
    // hole, and closed round: the carotid's chop by its end was 2.2h / −16.5%, now 0.15h).
    let (_, r, hd, ve) = repair_tube_chopped_at(4.0);
    assert!(
        r.guides
            .contains(&vesselmsr::inpaint::guided::GuideKind::DeadEnd),
        "{:?}",
        r.guides
    );
    println!("hole by an open end: {hd:.2}h, {:+.2}% in D", 100.0 * ve);
    // Measured 0.09h / −0.06% since 2026-12-07, the recentred curve's fade at its ends kept to
    // the arc its offsets need (0.33h / +0.14% before it, 0.51h with a fade over half a radius
    // whatever the offsets; 0.16h / −0.44% earlier; 0.51h / −1.27% with a harmonic fill of the wall's offsets;
    // 1.28h / −3.06% with the biharmonic one while the rays of the flat end's own section, which
    // graze the end's rim, were read; following the damaged centreline: 0.87h / −3.20%).
    assert!(hd <= 0.4, "{hd}h");
    assert!(ve.abs() <= 0.01, "{ve}");
}

#[test]
fn a_hole_that_bites_into_an_open_end_is_cut_flat_on_that_end() {
    // The chop now reaches the end's rim (centre 1 above the end at z = 0): the hole and the end
    // are one loop, a hole, and the vessel ends inside D at no open end. The part of the end's
    // rim the chop left lies in the end's plane: the fill is cut flat there, as the truth is
    // capped, instead of closing round along the damaged centreline. Measured 1.73h / −0.14%
    // (closed round: 7.47h / +18.5%).
    let (damaged, _, hd, ve) = repair_tube_chopped_at(1.0);
    assert_eq!(
        mesh_info(&damaged).boundary_loops,
        2,
        "the bite joins the end's loop"
    );
    println!(
        "hole biting an open end: {hd:.2}h, {:+.2}% in D",
        100.0 * ve
    );
    assert!(hd <= 2.5, "{hd}h");
    assert!(ve.abs() <= 0.02, "{ve}");
}

/// The wall's fine relief around a vessel is carried across a hole in its wall: a tube whose
/// radius ripples around it (16 lobes, R(1 + 0.06 cos 16θ), the same all along the tube; lobes
/// about 9 voxels apart at the voxel used) loses a ball of wall triangles, and `repair --holes`
/// puts the lobes back inside it. With 48 section rays (3 per lobe, as before the rays were
/// sized to the voxel) the fill inside the hole was 0.73 voxels off; at about one ray per 2
/// voxels (about 70 rays on the anchors' inscribed radius) 0.40 voxels.
#[test]
fn a_rippled_wall_is_carried_across_a_hole() {
    let (r, h) = (3.0_f64, 0.125_f64);
    let (lobes, depth) = (16.0_f64, 0.06_f64);
    let length = 10.0 * r;
    // Signed distance to first order: the radial gap over the wall's slope factor, the tube
    // cut flat at z = 0 and z = length.
    let wall = |theta: f64| r * (1.0 + depth * (lobes * theta).cos());
    let sdf = |p: &Point3<f64>| -> f64 {
        let rho = p.x.hypot(p.y);
        let theta = p.y.atan2(p.x);
        let slope = r * depth * lobes * (lobes * theta).sin() / rho.max(1e-9);
        let radial = (rho - wall(theta)) / (1.0 + slope * slope).sqrt();
        radial.max(-p.z).max(p.z - length)
    };
    let lo = Point3::new(-1.3 * r, -1.3 * r, -2.0 * h);
    let dims = [
        (2.6 * r / h) as usize + 2,
        (2.6 * r / h) as usize + 2,
        ((length + 4.0 * h) / h) as usize + 2,
    ];
    let transform = vesselmsr::grid::GridTransform::new(lo, h);
    let mut data = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = lo + nalgebra::Vector3::new(i as f64, j as f64, k as f64) * h;
                data.push(sdf(&p) as f32);
            }
        }
    }
    let phi = vesselmsr::grid::Grid3::from_data(dims, transform, data).unwrap();
    let mut mesh = vesselmsr::levelset::marching_cubes::extract_surface(
        &phi,
        &vesselmsr::levelset::marching_cubes::ExtractOptions::default(),
    )
    .unwrap();
    // A hole in the wall, half-way along: every triangle with a corner within 0.8 R of a wall
    // point (on a lobe's flank, where the relief is steepest).
    let theta0 = 0.5 * std::f64::consts::PI / lobes;
    let at = Point3::new(
        wall(theta0) * theta0.cos(),
        wall(theta0) * theta0.sin(),
        0.5 * length,
    );
    let cut = 0.8 * r;
    mesh.faces.retain(|f| {
        f.iter()
            .all(|&v| (mesh.vertices[v as usize] - at).norm() > cut)
    });
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n).to_string_lossy().into_owned();
    vesselmsr::io::write_mesh(std::path::Path::new(&p("holed.stl")), &mesh).unwrap();
    let voxel = h.to_string();
    let report = vesselmsr_json(&[
        "repair",
        &p("holed.stl"),
        "--holes",
        "--voxel",
        &voxel,
        "-o",
        &p("out.stl"),
        "--json",
        "-q",
    ]);
    assert_eq!(report["watertight"], true, "{}", report["output"]);
    assert_eq!(
        report["parameters"]["stitched"], true,
        "{}",
        report["parameters"]
    );
    let out = vesselmsr::io::read_mesh(std::path::Path::new(&p("out.stl"))).unwrap();
    // Within the hole (short of its rim, where the kept wall's own triangles begin), how far
    // the repaired wall lies from the rippled one.
    let worst = out
        .vertices
        .iter()
        .filter(|v| (*v - at).norm() < 0.8 * cut)
        .map(|v| sdf(v).abs())
        .fold(0.0, f64::max);
    println!(
        "rippled wall across the hole: worst {:.3} voxels",
        worst / h
    );
    assert!(worst > 0.0, "no vertex inside the hole");
    assert!(worst < 0.5 * h, "worst {:.3} voxels", worst / h);
}

/// Regions given as balls: the pipeline traces the centreline on a thread of its own while the
/// repair voxelizes (two threads) or first (one thread). The fill waits for it either way: the
/// same mesh and report (timings aside), the gap bridged along the centreline, not along an axis.
#[test]
fn the_centreline_traced_meanwhile_gives_the_same_repair() {
    let ph = phantom(PhantomKind::Curved);
    let request = VesselRepair {
        balls: ph.regions.clone(),
        options: RepairOptions {
            voxel: Some(ph.voxel),
            ..RepairOptions::default()
        },
        ..VesselRepair::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let done = pool.install(|| repair_vessel(&ph.damaged, &request, &mut |_| {}).unwrap());
        let mut report = serde_json::to_value(&done.report).unwrap();
        let timings = report.as_object_mut().unwrap().remove("timings").unwrap();
        assert!(timings["centerline"].as_f64().unwrap() > 0.0);
        (done.mesh, report)
    };
    let (first, first_report) = run(1);
    let (meanwhile, meanwhile_report) = run(2);
    assert_eq!(first.faces, meanwhile.faces);
    assert_eq!(first.vertices, meanwhile.vertices);
    assert_eq!(first_report, meanwhile_report);
    for region in first_report["regions"].as_array().unwrap() {
        assert_eq!(region["fill"], "bridge", "{region}");
    }
}

/// `mesh` repaired as `vesselmsr repair --holes` repairs it, with the defaults.
fn repaired_holes(mesh: &TriMesh) -> RepairedVessel {
    let request = VesselRepair {
        holes: true,
        ..VesselRepair::default()
    };
    repair_vessel(mesh, &request, &mut |_| {}).unwrap()
}

/// A cut through a vessel that strays about a quarter of its radius from its plane, both pieces
/// kept (a ball of 2.2 radii through a real vessel left loops 0.20–0.32 off their planes: the
/// `big` shape of `benches/repair_real -- --shapes`): beyond an end's tolerance, its loops were
/// taken for holes and each closed alone as a dead end, the vessel left in two pieces without a
/// word (5 of that study's 15 such cases). Two such loops on two pieces, facing each other, the
/// wall beside them running across their planes as beside an end, are one gap: bridged.
#[test]
fn a_tube_cut_through_off_plane_is_bridged_with_holes() {
    let tube = phantom(PhantomKind::Tube);
    let r = tube.radius;
    let damaged = common::cut_where(&tube.truth, |p| {
        (p.z - 0.27 * r * (2.0 * p.y.atan2(p.x)).sin()).abs() < 0.5 * r
    });
    let loops = classify_loops(&damaged, &LoopOptions::default());
    assert_eq!(loops.len(), 2);
    assert!(
        loops
            .iter()
            .all(|l| l.kind == LoopKind::Hole && l.may_be_cut()),
        "{loops:?}"
    );
    assert_eq!(connected_components(&damaged).0, 2, "the cut goes through");
    let done = repaired_holes(&damaged);
    let report = serde_json::to_value(&done.report).unwrap();
    assert_eq!(loop_kinds(&report), ["cut end", "cut end"], "{report}");
    let regions = report["regions"].as_array().unwrap();
    assert_eq!(regions.len(), 1, "{report}");
    assert_eq!(regions[0]["source"], "gap", "{report}");
    assert_eq!(regions[0]["fill"], "bridge", "{report}");
    let info = mesh_info(&done.mesh);
    assert!(info.watertight && info.signed_volume > 0.0);
    assert_eq!(info.components, 1, "the vessel is one piece again");
    let d = Ball {
        center: Point3::origin(),
        radius: 2.0 * r,
    };
    let hd = hausdorff_in(&done.mesh, &tube.truth, &[d]) / done.report.parameters.voxel;
    let ve = volume_error_in(&done.mesh, &tube.truth, &[d]);
    println!("tube cut through: {hd:.2}h, {:+.2}% in D", 100.0 * ve);
    assert!(hd <= 1.5, "{hd}h");
    assert!(ve.abs() <= 0.02, "{ve}");
}

/// A vessel the damage left in two pieces that no region joins is told so in the report.
#[test]
fn an_output_left_in_pieces_gets_a_notice() {
    let tube = phantom(PhantomKind::Tube);
    let r = tube.radius;
    // Cut across by a slab of 3R (both pieces kept): its two loops are planar clipped ends
    // (not rough), so nothing is bridged.
    let damaged = common::cut_where(&tube.truth, |p| p.z.abs() < 1.5 * r);
    assert_eq!(connected_components(&damaged).0, 2);
    let done = repaired_holes(&damaged);
    assert_eq!(mesh_info(&done.mesh).components, 2);
    assert!(
        done.report
            .notices
            .iter()
            .any(|n| n.contains("the output is in 2 pieces (the input in 2)")),
        "{:?}",
        done.report.notices
    );
}

/// A chop of `benches/repair_real` given as its region D (the chop is D over 1.3) on `truth`,
/// repaired with `--holes`: the repair, and its Hausdorff distance (voxels) and volume error in
/// D against `judged` (the truth with its open ends capped flat, as the benchmark judges).
fn repair_bench_chop(truth: &TriMesh, judged: &TriMesh, d: Ball) -> (RepairedVessel, f64, f64) {
    let chop = Ball {
        center: d.center,
        radius: d.radius / 1.3,
    };
    let damaged = common::chopped(truth, &chop);
    let done = repaired_holes(&damaged);
    let hd = hausdorff_in(&done.mesh, judged, &[d]) / done.report.parameters.voxel;
    let ve = volume_error_in(&done.mesh, judged, &[d]);
    (done, hd, ve)
}

/// A chop of `benches/repair_real` on the real vessel `file` (../shared/data/real; skipped when
/// absent) given as its region D: repaired as [`repair_bench_chop`] does, filled as `fill`,
/// stitched, and within `max_h` voxels and `max_ve` of the truth's volume in D.
fn check_bench_chop(file: &str, d: Ball, fill: &str, max_h: f64, max_ve: f64, what: &str) {
    let Some(dir) = common::real_dir() else {
        return;
    };
    let truth = common::read_real(&dir, file);
    let (judged, _) = vesselmsr::mesh::cap::cap_holes(&truth, &Default::default()).unwrap();
    let (done, hd, ve) = repair_bench_chop(&truth, &judged, d);
    let p = &done.report.parameters;
    assert_eq!(done.report.regions[0].fill, Some(fill));
    assert!(p.stitched, "{:?}", p.fallback);
    println!("{what}: {hd:.2}h, {:+.1}% in D", 100.0 * ve);
    assert!(hd <= max_h && ve.abs() <= max_ve, "{what}: {hd}h {ve}");
}

/// The aneurysm's junction chop in `benches/repair_real`'s draw of seed 28 (held out): its small
/// branch leaves the junction inside D for its open end just beyond D. The inscribed sphere
/// there is the end's (0.44 where the vessel's radius is 0.9): the branch was dropped as a spur
/// of the damage and the other two bridged, 15.57h / −20.1% in D. Its anchor now takes the
/// section's radius, and the three branches are joined at the junction.
#[test]
fn a_branch_from_a_junction_in_d_to_an_open_end_beside_it_is_kept() {
    let d = Ball {
        center: Point3::new(35.02669712897357, 33.07199631189985, 42.14149070000435),
        radius: 2.1173428676708927,
    };
    // 2.01h / +1.8% measured (4.06h / +6.5% with the junction branches' equal Hermite tangents,
    // `guided::JUNCTION_TANGENTS`; 4.03h / +7.1% with the wall chart's Laplacian isotropic too;
    // MeshLib 4.62h / +5.5%).
    let what = "seed 28's ICA junction chop";
    check_bench_chop("ica_aneurysm_c0015.stl", d, "junction", 4.5, 0.09, what);
}

/// The carotid bulb's wall chop in `benches/repair_real`'s draw of seed 34 (held out): the hole
/// lies on the bulb, whose wall swells out of the sections the anchors read beyond D. Between
/// the two anchors the wall chart's offsets over the hole are held by the readings on either
/// side; bounded at 0.8 section radii as past a tube's last reading (towards a junction
/// point), the fill stopped 1 mm (0.4 radii) inside the bulb's wall: 4.08h / −16.2% in D.
#[test]
fn a_hole_in_the_carotid_bulb_is_filled_out_to_the_bulb() {
    let d = Ball {
        center: Point3::new(
            0.04677393888806364,
            0.07397431432584933,
            0.030519097819464932,
        ),
        radius: 0.004698247262299089,
    };
    // 2.79h / −1.9% measured (3.10h / −4.8% with the wall chart's Laplacian isotropic; MeshLib
    // 4.52h / −15.4%).
    let what = "seed 34's carotid bulb chop";
    check_bench_chop("carotid_bifurcation.stl", d, "through", 3.5, 0.07, what);
}

/// The capped aorta's wall chop beside its closed upper end in `benches/repair_real`'s draw of
/// seed 34 (held out): no section is clear of D before the vessel ends, so the tube is a dead
/// end. It followed the damaged centreline, which bends 3.3 mm towards the wall the hole left,
/// and was capped round: 5.45h / −5.8% in D. It now runs to the vessel's intact section at the
/// centreline's tip, beyond D, and is cut flat there.
#[test]
fn a_chop_beside_a_closed_end_follows_the_vessel_to_its_end() {
    let d = Ball {
        center: Point3::new(216.48262805252878, 159.93062145492962, 28.266378768070645),
        radius: 15.082549126487605,
    };
    // 2.64h / −1.6% measured (2.17h / −1.5% with the chart's Laplacian isotropic; MeshLib
    // 9.02h / −12.6%).
    let what = "seed 34's capped aorta chop beside its end";
    check_bench_chop("aorta_abdominal_capped.stl", d, "dead-end", 3.0, 0.03, what);
}

/// Seed 34's chop over the capped aorta's bifurcation in `benches/repair_real` cuts the iliacs
/// off (the benchmark keeps the largest piece): the aorta stops inside D and nothing in the input
/// says what went on beyond it. It is capped round, as before (99h / −57% in D against the
/// truth with its bifurcation; MeshLib 122h), but now filled as a `stump`, with a notice that
/// its continuation, if the damage took one, is not restored.
#[test]
fn a_vessel_cut_off_inside_d_is_a_stump_with_a_notice() {
    let Some(dir) = common::real_dir() else {
        return;
    };
    let truth = common::read_real(&dir, "aorta_abdominal_capped.stl");
    let (judged, _) = vesselmsr::mesh::cap::cap_holes(&truth, &Default::default()).unwrap();
    let d = Ball {
        center: Point3::new(220.40084139937858, 128.05477877513914, 23.371687517340412),
        radius: 15.914295326887597,
    };
    let (done, hd, ve) = repair_bench_chop(&truth, &judged, d);
    println!(
        "seed 34's chop over the bifurcation: {hd:.2}h, {:+.1}% in D",
        100.0 * ve
    );
    assert_eq!(done.report.regions[0].fill, Some("stump"));
    assert!(done.report.parameters.stitched);
    assert!(
        done.report
            .notices
            .iter()
            .any(|n| n.contains("a vessel stops inside it") && n.contains("not restored")),
        "{:?}",
        done.report.notices
    );
}

/// The coronary's bend chop in `benches/repair_real`'s draw of seed 34: the hole takes the inner
/// side of a 48° bend, where the wall folds into a crease. The cubic between the anchors cut the
/// bend's corner so near the hole's cap that no section of its middle read the far wall, and
/// the tube overfilled the crease: 1.91h / +10.2% in D (MeshLib 1.17h). The coronary's sections
/// are round, so the curve is now moved onto the centre of half a section of intact wall, in
/// five passes (`guided::ROUND_SECTION`).
#[test]
fn a_hole_inside_the_coronarys_bend_does_not_fill_its_crease() {
    let d = Ball {
        center: Point3::new(27.259186240369914, -26.743708474649445, 61.588902951149606),
        radius: 1.6564773312272627,
    };
    let what = "seed 34's coronary bend chop";
    check_bench_chop("coronary_stenosis_xray.stl", d, "through", 1.5, 0.07, what);
}

/// End bites of the aneurysm in `benches/repair_real --end-bites` (../shared/data/real; the chop:
/// every triangle with a corner in a ball of 1.5 local radii, the largest piece kept) that take
/// its short ICA branch whole, from its open end to past the junction or to the parent beside
/// it, and leave an arc of the end's rim on the hole's. No anchor leads to that branch: the
/// others were bridged (or passed through D) without it. Its cut end is now read off the hole's
/// rim and it joins the junction, or the parent as a side branch, from there.
#[test]
fn a_branch_bitten_off_with_its_open_end_is_restored_to_its_cut() {
    let Some(dir) = common::real_dir() else {
        return;
    };
    let truth = common::read_real(&dir, "ica_aneurysm_c0015.stl");
    // Judged in D against the truth with its open ends capped flat, as the benchmark judges it.
    let (judged, _) = vesselmsr::mesh::cap::cap_holes(&truth, &Default::default()).unwrap();
    // (region D of the benchmark, Hausdorff and volume bounds in D): seed 21's bite #1, measured
    // there 6.62h / −1.3% (6.43h / −1.9% with the junction branches' equal Hermite tangents,
    // `guided::JUNCTION_TANGENTS`; 6.37h / −1.6% with the wall chart's Laplacian isotropic too;
    // 26.93h / −34.7% bridged past the branch, with a speck of the grid as a second piece); seed
    // 22's bite #2, 4.79h / +6.9% (4.79h / +6.3% with equal tangents; 4.43h / +6.2% isotropic
    // too; 9.99h / −4.7%, the parent through D alone).
    let bites = [
        (
            [33.39946137282439, 31.517140147669764, 39.515266094672796],
            3.13744758988492,
            8.0,
            0.05,
        ),
        (
            [32.72218480557267, 32.62312795166795, 40.332934671623875],
            2.526886191649525,
            5.0,
            0.08,
        ),
    ];
    for (centre, radius, max_h, max_ve) in bites {
        let d = Ball {
            center: Point3::from(centre),
            radius,
        };
        let (done, hd, ve) = repair_bench_chop(&truth, &judged, d);
        let p = &done.report.parameters;
        assert_eq!(done.report.regions.len(), 1);
        assert_eq!(done.report.regions[0].fill, Some("junction"));
        assert!(p.stitched, "{:?}", p.fallback);
        assert!(mesh_info(&done.mesh).watertight);
        assert_eq!(connected_components(&done.mesh).0, 1);
        println!(
            "bitten ICA end at {centre:?}: {hd:.2}h, {:+.1}% in D",
            100.0 * ve
        );
        assert!(hd <= max_h && ve.abs() <= max_ve, "{hd}h {ve}");
    }
}
