//! The level-set commands through the CLI: `remesh` (JSON keys, watertight output, the grid
//! flags) and `voxelize` (.npy with its sidecar, .vti), and their bad input: a grid over the
//! memory limit, a voxel size ≤ 0 or larger than the mesh, a mesh with no inside, an unknown
//! output format — exit status 2, one line naming the problem, no output.

mod common;
use common::*;
use std::path::Path;

fn aorta() -> String {
    data_dir()
        .join("aorta_abdominal_open_ends.stl")
        .to_string_lossy()
        .into_owned()
}

#[test]
fn remesh_json_reports_grid_output_and_timings() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("remeshed.stl");
    let report = vesselmsr_json(&[
        "--json",
        "remesh",
        &aorta(),
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "96",
    ]);
    let dims: Vec<u64> = report["grid"]["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap())
        .collect();
    assert_eq!(dims.len(), 3);
    // 96 cells along the longest axis (y for this aorta), plus padding on both sides.
    assert!(dims[1] >= 97 && dims[1] <= 97 + 2 * 8, "{dims:?}");
    assert!(report["grid"]["voxel"].as_f64().unwrap() > 0.0);
    assert_eq!(report["grid"]["origin"].as_array().unwrap().len(), 3);
    assert_eq!(report["output"]["watertight"], true);
    assert_eq!(report["output"]["orientation"], "outward");
    assert_eq!(report["output"]["components"], 1);
    for k in ["read", "voxelize", "marching_cubes", "project", "write"] {
        assert!(report["timings"][k].as_f64().is_some(), "timing {k}");
    }
    let info = vesselmsr_json(&["info", "--json", out.to_str().unwrap()]);
    assert_eq!(info["watertight"], true);
    assert_eq!(info["faces"], report["output"]["faces"]);
}

fn assert_fails(args: &[&str], word: &str, output: &Path) {
    let run = vesselmsr(args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
    assert!(
        stderr.contains(word),
        "{args:?}: message lacks {word:?}: {stderr}"
    );
    assert!(!output.exists(), "{args:?} left an output");
    println!("{args:?} -> {}", stderr.trim_end());
}

#[test]
fn remesh_refuses_bad_grids_and_meshes_without_inside() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out.ply");
    let o = out.to_str().unwrap();
    let a = aorta();
    assert_fails(
        &[
            "remesh",
            &a,
            "-o",
            o,
            "--resolution",
            "4000",
            "--max-memory",
            "64M",
        ],
        "--max-memory",
        &out,
    );
    assert_fails(&["remesh", &a, "-o", o, "--voxel=-1"], "voxel", &out);
    assert_fails(&["remesh", &a, "-o", o, "--voxel", "1000"], "voxel", &out);
    assert_fails(
        &["remesh", &a, "-o", o, "--resolution", "0"],
        "resolution",
        &out,
    );
    assert_fails(
        &[
            "remesh",
            &a,
            "-o",
            &tmp.path().join("out.xyz").to_string_lossy(),
            "--resolution",
            "32",
        ],
        "format",
        &tmp.path().join("out.xyz"),
    );
    // A flat disc (a fan of triangles in one plane) encloses nothing.
    let disc = tmp.path().join("disc.obj");
    let mut text = String::from("v 0 0 0\n");
    for k in 0..16 {
        let t = std::f64::consts::TAU * k as f64 / 16.0;
        text += &format!("v {} {} 0\n", t.cos(), t.sin());
    }
    for k in 0..16 {
        text += &format!("f 1 {} {}\n", 2 + k, 2 + (k + 1) % 16);
    }
    std::fs::write(&disc, text).unwrap();
    assert_fails(
        &["remesh", disc.to_str().unwrap(), "-o", o],
        "encloses no volume",
        &out,
    );
}
