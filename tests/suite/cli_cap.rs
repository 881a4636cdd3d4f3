//! `cap` on the six real meshes: the result is accepted by manifold3d (status NoError), faces
//! outward, is one component, has no cap triangle with aspect ratio over 10, and its volume as
//! `info` measures it equals pymeshlab's within 1e-6 relative. Also the three output formats.

use crate::common;
use common::*;
use serde_json::Value;
use std::path::Path;

/// `vesselmsr cap --json <flags> <input> -o <output>`, its report parsed.
fn cap_json(input: &Path, output: &Path, flags: &[&str]) -> Value {
    let mut args = vec!["cap", "--json"];
    args.extend_from_slice(flags);
    args.extend([input.to_str().unwrap(), "-o", output.to_str().unwrap()]);
    vesselmsr_json(&args)
}

#[test]
fn cap_real_meshes_is_watertight_outward_and_well_shaped() {
    let Some(dir) = real_dir() else { return };
    let oracle = oracle();
    let tmp = tempfile::tempdir().unwrap();
    for (file, _, _, loops, _) in REAL_MESHES {
        let input = dir.join(file);
        let output = tmp.path().join(file);
        let report = cap_json(&input, &output, &[]);
        let cap = &report["cap"];
        println!("{file}: {cap}");
        assert_eq!(cap["loops_capped"], loops, "{file} loops capped");
        let aspect = cap["max_cap_aspect_ratio"].as_f64().unwrap_or(0.0);
        assert!(aspect <= 10.0, "{file}: cap aspect ratio {aspect}");
        // What was written, read back.
        let info = info_json(&output);
        assert_eq!(info["watertight"], true, "{file}: {info}");
        assert_eq!(info["orientation"], "outward", "{file}");
        assert_eq!(info["components"], 1, "{file}");
        assert_eq!(info["boundary_loops"], 0, "{file}");
        let reference = oracle.check(&output);
        println!("{file}: oracle {reference}");
        assert_eq!(
            reference["manifold_status"], "NoError",
            "{file}: manifold3d verdict"
        );
        assert_matches_pymeshlab(
            &format!("{file}: capped volume"),
            info["volume"].as_f64().unwrap(),
            reference["pymeshlab_volume"].as_f64().unwrap(),
        );
        assert!(
            info["signed_volume"].as_f64().unwrap() > 0.0,
            "{file}: outward means positive volume"
        );
    }
}

#[test]
fn cap_flips_inward_input_unless_told_not_to() {
    let Some(dir) = real_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let input = dir.join("aorta_abdominal_capped.stl");
    let out = tmp.path().join("kept.stl");
    let report = cap_json(&input, &out, &["--no-orient"]);
    assert_eq!(report["input"]["orientation"], "inward");
    assert_eq!(report["output"]["orientation"], "inward");
    assert_eq!(report["cap"]["flipped"], false);
    let out2 = tmp.path().join("flipped.stl");
    let report = cap_json(&input, &out2, &[]);
    assert_eq!(report["output"]["orientation"], "outward");
    assert_eq!(report["cap"]["flipped"], true);
}

#[test]
fn cap_writes_every_format() {
    let input = data_dir().join("aorta_abdominal_open_ends.stl");
    let tmp = tempfile::tempdir().unwrap();
    for ext in ["stl", "obj", "ply", "PLY"] {
        let out = tmp.path().join(format!("capped.{ext}"));
        let report = cap_json(&input, &out, &[]);
        let info = info_json(&out);
        assert_eq!(info["watertight"], true, "{ext}");
        assert_eq!(info["faces"], report["output"]["faces"], "{ext}");
        assert_eq!(info["vertices"], report["output"]["vertices"], "{ext}");
    }
}
