//! The level-set commands through the CLI: `remesh` (JSON keys, watertight output, the grid
//! flags) and `voxelize` (.npy with its sidecar, .vti, .nrrd), and their bad input: a grid over the
//! memory limit, a voxel size ≤ 0 or larger than the mesh, a mesh with no inside, an unknown
//! output format — exit status 2, one line naming the problem, no output.

use crate::common;
use common::*;
use std::path::Path;

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

#[test]
fn voxelize_writes_a_signed_distance_grid_as_npy_vti_and_nrrd() {
    use rand::RngExt;
    use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
    let tmp = tempfile::tempdir().unwrap();
    let npy = tmp.path().join("phi.npy");
    let vti = tmp.path().join("phi.VTI");
    let nrrd = tmp.path().join("phi.nrrd");
    let report = vesselmsr_json(&[
        "--json",
        "voxelize",
        &aorta(),
        "-o",
        npy.to_str().unwrap(),
        "--resolution",
        "80",
    ]);
    for other in [&vti, &nrrd] {
        vesselmsr_json(&[
            "--json",
            "voxelize",
            &aorta(),
            "-o",
            other.to_str().unwrap(),
            "--resolution",
            "80",
        ]);
    }
    let phi = vesselmsr::io::read_npy(&npy).unwrap();
    assert_eq!(
        phi,
        vesselmsr::io::read_vti(&vti).unwrap(),
        "the formats hold the same grid"
    );
    assert_eq!(phi, vesselmsr::io::read_nrrd(&nrrd).unwrap());
    let dims: Vec<usize> = report["grid"]["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(phi.dims().to_vec(), dims);
    assert_eq!(phi.voxel(), report["grid"]["voxel"].as_f64().unwrap());
    let inside = phi.data().iter().filter(|&&v| v < 0.0).count();
    assert_eq!(inside as u64, report["inside_nodes"].as_u64().unwrap());

    // In the band |φ| is the exact distance to the triangles, and the sign is the winding
    // number's (checked where |w| is not within 0.05 of ½, i.e. away from open ends).
    let mesh = vesselmsr::io::read_mesh(Path::new(&aorta())).unwrap();
    let bvh = MeshBvh::new(&mesh);
    let wn = WindingNumber::new(&mesh, WindingOptions::default());
    let h = phi.voxel();
    let mut rng = rng(5);
    let (mut worst_band, mut checked) = (0.0f64, 0);
    for _ in 0..4000 {
        let [nx, ny, nz] = phi.dims();
        let (i, j, k) = (
            rng.random_range(0..nx),
            rng.random_range(0..ny),
            rng.random_range(0..nz),
        );
        let (p, value) = (phi.world(i, j, k), phi.get(i, j, k) as f64);
        let d = bvh.closest_point(&p).distance;
        if d < 2.5 * h {
            worst_band = worst_band.max((value.abs() - d).abs() / h);
            checked += 1;
            if (wn.winding_number(&p).abs() - 0.5).abs() > 0.05 {
                assert_eq!(
                    value < 0.0,
                    wn.is_inside(&p) || wn.winding_number(&p) <= -0.5,
                    "sign at {p:?}"
                );
            }
        }
    }
    println!("{checked} band nodes: max ||φ| − d| = {worst_band:.2e} h");
    assert!(
        checked > 50 && worst_band < 1e-4,
        "band values differ from exact distances by {worst_band} h"
    );
}

#[test]
fn voxelize_refuses_unknown_grid_formats() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("phi.nii");
    assert_fails(
        &[
            "voxelize",
            &aorta(),
            "-o",
            out.to_str().unwrap(),
            "--resolution",
            "32",
        ],
        ".npy, .vti or .nrrd",
        &out,
    );
}
