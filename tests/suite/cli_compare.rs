//! `compare`: analytic distances between concentric spheres, zero for a mesh against itself, and
//! the volumes' relative difference.

use crate::common;
use common::*;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

/// A UV sphere of radius `r` as OBJ text (outward), with `n` segments around and n/2 from pole to pole.
fn uv_sphere_obj(r: f64, n: usize) -> String {
    let rings = n / 2;
    let mut s = String::new();
    writeln!(s, "v 0 0 {r}").unwrap();
    for i in 1..rings {
        let theta = PI * i as f64 / rings as f64;
        for j in 0..n {
            let phi = 2.0 * PI * j as f64 / n as f64;
            writeln!(
                s,
                "v {} {} {}",
                r * theta.sin() * phi.cos(),
                r * theta.sin() * phi.sin(),
                r * theta.cos()
            )
            .unwrap();
        }
    }
    writeln!(s, "v 0 0 {}", -r).unwrap();
    let idx = |i: usize, j: usize| 2 + (i - 1) * n + (j % n); // 1-based ring i ≥ 1
    let south = 2 + (rings - 1) * n;
    for j in 0..n {
        writeln!(s, "f 1 {} {}", idx(1, j), idx(1, j + 1)).unwrap();
        writeln!(
            s,
            "f {south} {} {}",
            idx(rings - 1, j + 1),
            idx(rings - 1, j)
        )
        .unwrap();
    }
    for i in 1..rings - 1 {
        for j in 0..n {
            writeln!(
                s,
                "f {} {} {} {}",
                idx(i, j),
                idx(i + 1, j),
                idx(i + 1, j + 1),
                idx(i, j + 1)
            )
            .unwrap();
        }
    }
    s
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn concentric_spheres_are_half_a_unit_apart() {
    let tmp = tempfile::tempdir().unwrap();
    let a = write(tmp.path(), "a.obj", &uv_sphere_obj(10.0, 256));
    let b = write(tmp.path(), "b.obj", &uv_sphere_obj(10.5, 256));
    let out = vesselmsr_json(&["compare", "--json", &a, &b]);
    println!("{out}");
    let get = |k: &str| out[k].as_f64().unwrap();
    // Same tessellation scaled: distances are 0.5 up to the chord error (r·(π/256)²/2 ≈ 8e-4).
    assert!(
        (get("hausdorff") - 0.5).abs() < 2e-3,
        "hausdorff {}",
        get("hausdorff")
    );
    assert!(
        (get("mean_distance") - 0.5).abs() < 2e-3,
        "mean {}",
        get("mean_distance")
    );
    assert!(
        (get("rms_distance") - 0.5).abs() < 2e-3,
        "rms {}",
        get("rms_distance")
    );
    assert!(get("mean_distance") <= get("rms_distance") && get("rms_distance") <= get("hausdorff"));
    let expected = 1.05f64.powi(3) - 1.0; // same tessellation, scaled by 1.05
    assert!(
        (get("volume_rel_diff") - expected).abs() < 1e-9,
        "volume_rel_diff {}",
        get("volume_rel_diff")
    );
    assert!((get("volume_a") - 4.0 / 3.0 * PI * 1000.0).abs() / (4.0 / 3.0 * PI * 1000.0) < 1e-3);
}

#[test]
fn a_mesh_is_at_distance_zero_from_itself() {
    let a = data_dir().join("cortex_rh_pial_fsaverage5.stl");
    let a = a.to_str().unwrap();
    let out = vesselmsr_json(&["compare", "--json", "--samples", "20000", a, a]);
    for k in [
        "hausdorff",
        "mean_distance",
        "rms_distance",
        "volume_rel_diff",
    ] {
        assert!(out[k].as_f64().unwrap().abs() < 1e-9, "{k}: {}", out[k]);
    }
    assert_eq!(out["samples_per_surface"], 20000);
}

#[test]
fn open_meshes_have_no_volume() {
    let a = data_dir().join("aorta_abdominal_open_ends.stl");
    let a = a.to_str().unwrap();
    let out = vesselmsr_json(&["compare", "--json", "--samples", "1000", a, a]);
    assert!(
        out["volume_a"].is_null() && out["volume_rel_diff"].is_null(),
        "{out}"
    );
    let text = vesselmsr(&["compare", "--samples", "1000", a, a]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("not watertight"));
}

#[test]
fn hausdorff_brackets_libigl_on_a_capped_aorta() {
    // libigl's hausdorff measures vertices against the other mesh's triangles, a lower bound of
    // the surface Hausdorff distance; ours adds dense samples, so it lies between that bound and
    // the bound plus one mean edge.
    let oracle = oracle();
    let tmp = tempfile::tempdir().unwrap();
    let open = data_dir().join("aorta_abdominal_open_ends.stl");
    let capped = tmp.path().join("capped.stl");
    let (o, c) = (open.to_str().unwrap(), capped.to_str().unwrap());
    vesselmsr_json(&["cap", "--json", o, "-o", c]);
    let ours = vesselmsr_json(&["compare", "--json", o, c]);
    let theirs = oracle.run(&[&"hausdorff", &open, &capped]);
    let edge = vesselmsr_json(&["info", "--json", o])["mean_edge"]
        .as_f64()
        .unwrap();
    let (h, h_igl) = (
        ours["hausdorff"].as_f64().unwrap(),
        theirs["hausdorff"].as_f64().unwrap(),
    );
    println!(
        "hausdorff open vs capped aorta: ours {h}, libigl (vertex bound) {h_igl}, mean edge {edge}"
    );
    assert!(
        h >= h_igl * (1.0 - 1e-9),
        "ours {h} below libigl's lower bound {h_igl}"
    );
    assert!(
        h <= h_igl + edge,
        "ours {h} exceeds libigl's bound {h_igl} by more than a mean edge"
    );
}

#[test]
fn meshes_in_different_units_get_a_notice() {
    let Some(dir) = real_dir() else { return };
    let metres = dir.join("carotid_bifurcation.stl");
    let mm = data_dir().join("aorta_abdominal_open_ends.stl");
    let out = vesselmsr(&[
        "compare",
        "--samples",
        "100",
        metres.to_str().unwrap(),
        mm.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("same units"), "no units notice: {stderr}");
    let same = vesselmsr(&[
        "compare",
        "--samples",
        "100",
        mm.to_str().unwrap(),
        mm.to_str().unwrap(),
    ]);
    assert!(!String::from_utf8_lossy(&same.stderr).contains("same units"));
}
