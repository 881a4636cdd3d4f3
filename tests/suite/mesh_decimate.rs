//! `--decimate` (issue 23): `remesh --decimate` on the shipped aorta gives fewer triangles than
//! the input, watertight (manifold3d agrees) and outward, on vertices of the undecimated output,
//! within 0.5h of it by our own measure and the report's; `repair --decimate` stays watertight
//! and within its bound. The slow study (tests/run_slow.sh) does every shared vessel: faces
//! within 2× the input's, within 0.5h of the undecimated output, within 0.6h of the input (with
//! its open ends capped, as the remesh closes them; also asserted on the shipped open aorta).

use crate::common;

use common::{data_dir, oracle, real_dir, vesselmsr, vesselmsr_json};
use serde_json::Value;
use std::path::Path;
use vesselmsr::io::read_mesh;
use vesselmsr::mesh::distance::{surface_distance, SurfaceDistanceOptions};
use vesselmsr::mesh::info::mesh_info;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Remeshes `input` into `dir` with and without `--decimate`: (report of the decimated run,
/// decimated path, undecimated path).
fn remesh_both(dir: &Path, input: &Path) -> (Value, std::path::PathBuf, std::path::PathBuf) {
    let (lean, full) = (dir.join("lean.stl"), dir.join("full.stl"));
    let r = vesselmsr_json(&["remesh", s(input), "-o", s(&lean), "--decimate", "--json"]);
    assert!(vesselmsr(&["remesh", s(input), "-o", s(&full), "-q"])
        .status
        .success());
    (r, lean, full)
}

/// Hausdorff distance between two mesh files, world units.
fn hausdorff(a: &Path, b: &Path) -> f64 {
    surface_distance(
        &read_mesh(a).unwrap(),
        &read_mesh(b).unwrap(),
        &SurfaceDistanceOptions { samples: 400_000 },
    )
    .hausdorff
}

#[test]
fn remesh_decimate_on_the_shipped_aorta() {
    let dir = tempfile::tempdir().unwrap();
    let input = data_dir().join("aorta_abdominal_open_ends.stl");
    let (r, lean, full) = remesh_both(dir.path(), &input);
    let h = r["grid"]["voxel"].as_f64().unwrap();
    let d = &r["decimate"];
    let (before, after) = (
        d["faces_before"].as_u64().unwrap(),
        d["faces_after"].as_u64().unwrap(),
    );
    let ours = hausdorff(&full, &lean);
    println!(
        "aorta: {before} -> {after} faces (input 11887), report {:.3}h, measured {:.3}h",
        d["hausdorff"].as_f64().unwrap() / h,
        ours / h
    );
    assert_eq!(d["simplified"], true);
    assert!(after < 11887 && after * 5 < before);
    assert!(d["hausdorff"].as_f64().unwrap() <= 0.5 * h);
    // Other samples than the check's: a little slack for what neither set saw.
    assert!(ours <= 0.52 * h, "{ours}");
    // The bound to the input (its open ends capped, as the remesh closes them): the
    // rims come out sharp (marching cubes alone left them 0.82h off).
    let capped = dir.path().join("capped.stl");
    assert!(vesselmsr(&["cap", s(&input), "-o", s(&capped), "-q"])
        .status
        .success());
    let to_input = hausdorff(&capped, &lean);
    println!("aorta: to the capped input {:.3}h", to_input / h);
    assert!(to_input <= 0.6 * h, "{}h", to_input / h);
    let mesh = read_mesh(&lean).unwrap();
    let info = mesh_info(&mesh);
    assert!(info.watertight);
    assert_eq!(serde_json::to_value(info.orientation).unwrap(), "outward");
    assert_eq!(r["output"]["faces"].as_u64().unwrap(), after);
    let check = oracle().check(&lean);
    assert_eq!(check["manifold_status"], "NoError", "{check}");
    // Collapses move no vertex: every vertex is one of the undecimated output's (to f32 STL).
    let full_mesh = read_mesh(&full).unwrap();
    let kept: std::collections::HashSet<[u64; 3]> = full_mesh
        .vertices
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect();
    assert!(mesh.vertices.iter().all(|p| kept.contains(&[
        p.x.to_bits(),
        p.y.to_bits(),
        p.z.to_bits()
    ])));
}

#[test]
fn repair_decimate_stays_watertight() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (damaged, _, regions) = common::phantom("occlusion", d);
    let out = d.join("o.stl");
    let r = vesselmsr_json(&[
        "repair",
        s(&damaged),
        "--regions",
        s(&regions),
        "-o",
        s(&out),
        "--decimate",
        "--json",
        "-q",
    ]);
    let h = r["parameters"]["voxel"].as_f64().unwrap();
    let dec = &r["decimate"];
    println!("{dec}");
    assert_eq!(dec["simplified"], true);
    assert!(dec["hausdorff"].as_f64().unwrap() <= 0.5 * h);
    assert!(dec["faces_after"].as_u64() < dec["faces_before"].as_u64());
    assert_eq!(r["watertight"], true);
    assert!(mesh_info(&read_mesh(&out).unwrap()).watertight);
}

mod slow {
    use super::*;

    /// The acceptance figures on every shared vessel (printed for the notes).
    #[test]
    #[ignore = "slow: run by tests/run_slow.sh"]
    fn remesh_decimate_on_the_shared_vessels() {
        let Some(real) = real_dir() else {
            return;
        };
        for (file, _, faces, _, _) in common::REAL_MESHES {
            if file.starts_with("cortex") {
                continue;
            }
            let dir = tempfile::tempdir().unwrap();
            let input = real.join(file);
            let (r, lean, full) = remesh_both(dir.path(), &input);
            let h = r["grid"]["voxel"].as_f64().unwrap();
            let after = r["decimate"]["faces_after"].as_u64().unwrap() as usize;
            // The input with its open ends capped: the surface both remeshes follow.
            let capped = dir.path().join("capped.stl");
            assert!(vesselmsr(&["cap", s(&input), "-o", s(&capped), "-q"])
                .status
                .success());
            let (to_full, lean_to_input, full_to_input) = (
                hausdorff(&full, &lean) / h,
                hausdorff(&capped, &lean) / h,
                hausdorff(&capped, &full) / h,
            );
            println!(
                "{file}: {faces} input faces, {after} decimated; Hausdorff to the undecimated \
                 {to_full:.3}h, to the (capped) input {lean_to_input:.3}h (undecimated \
                 {full_to_input:.3}h)"
            );
            assert!(after <= 2 * faces);
            assert!(to_full <= 0.52, "{file}");
            assert!(lean_to_input <= 0.6, "{file}: {lean_to_input}h");
        }
    }
}
