//! `vesselmsr evolve` through the CLI: the JSON report (grid, initial measures, one entry per
//! step with volume and area), a watertight output whose volume agrees with the last step's,
//! the motions' effect on volume (mcf shrinks, expand grows by about area·c·T, vpmcf keeps it),
//! and bad input (T or DT ≤ 0, c < 0 for inpaint, c for mcf, a step below 0.25h², a shape that
//! vanishes before T): exit status 2, one line naming the problem, no output.

use crate::common;
use common::*;
use serde_json::Value;
use std::path::Path;

/// `evolve --json` of the aorta at 64 cells along its longest side with `extra` flags.
fn run(out: &Path, extra: &[&str]) -> Value {
    let a = aorta();
    let mut args = vec![
        "--json",
        "evolve",
        &a,
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "64",
    ];
    args.extend_from_slice(extra);
    vesselmsr_json(&args)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

#[test]
fn evolve_mcf_reports_every_step_and_writes_a_watertight_surface() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mcf.ply");
    let report = run(&out, &["--velocity", "mcf", "--time", "8"]);
    let h = f(&report["grid"]["voxel"]);
    assert_eq!(report["velocity"], "mcf");
    assert_eq!(report["time"], 8.0);
    // Default step 2h², as many equal steps as needed.
    let steps = report["steps"].as_array().unwrap();
    let expected = (8.0 / (2.0 * h * h)).ceil() as usize;
    assert_eq!(steps.len(), expected, "h = {h}");
    assert!((f(&report["dt"]) * expected as f64 - 8.0).abs() < 1e-9);
    let mut volume = f(&report["initial"]["volume"]);
    let mut area = f(&report["initial"]["area"]);
    for (k, s) in steps.iter().enumerate() {
        assert_eq!(s["step"], k + 1);
        // Mean curvature flow decreases both volume and area.
        assert!(
            f(&s["volume"]) < volume && f(&s["area"]) < area,
            "step {k}: {s}"
        );
        volume = f(&s["volume"]);
        area = f(&s["area"]);
    }
    assert!((f(&steps.last().unwrap()["time"]) - 8.0).abs() < 1e-9);
    let output = &report["output"];
    assert_eq!(output["watertight"], true);
    assert_eq!(output["orientation"], "outward");
    let mesh_volume = f(&output["volume"]);
    println!("mcf: {expected} steps, volume {volume} (grid) vs {mesh_volume} (mesh), voxel {h}");
    // Both are within O(h²κ) of the true volume, from opposite sides (the smoothed Heaviside
    // over, marching cubes under): about 1% each on the iliac tubes, some 3 voxels thick here.
    assert!((mesh_volume / volume - 1.0).abs() < 0.04);
    for k in ["read", "voxelize", "evolve", "marching_cubes", "write"] {
        assert!(report["timings"][k].as_f64().is_some(), "timing {k}");
    }
    let info = info_json(&out);
    assert_eq!(info["watertight"], true);
    assert_eq!(info["faces"], output["faces"]);
}

#[test]
fn evolve_expand_grows_by_area_times_ct_and_vpmcf_keeps_the_volume() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("expand.stl");
    let (c, t) = (0.5, 2.0);
    let report = run(
        &out,
        &[
            "--velocity",
            "expand",
            "--c",
            "0.5",
            "--time",
            "2",
            "--dt",
            "1",
        ],
    );
    assert_eq!(report["c"], c);
    let v0 = f(&report["initial"]["volume"]);
    let a0 = f(&report["initial"]["area"]);
    let steps = report["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2);
    let v1 = f(&steps[1]["volume"]);
    let a1 = f(&steps[1]["area"]);
    // Growth by d = c·T: ΔV between A0·d and A1·d (the area grows along the way).
    let d = c * t;
    println!("expand by {d}: ΔV {} in [{}, {}]", v1 - v0, a0 * d, a1 * d);
    assert!(v1 - v0 > 0.97 * a0 * d && v1 - v0 < 1.03 * a1 * d);

    let out = tmp.path().join("vpmcf.stl");
    let report = run(&out, &["--velocity", "vpmcf", "--time", "6"]);
    let v0 = f(&report["initial"]["volume"]);
    for s in report["steps"].as_array().unwrap() {
        assert!((f(&s["volume"]) / v0 - 1.0).abs() < 0.005, "{s} vs {v0}");
    }
    let mesh_volume = f(&report["output"]["volume"]);
    println!("vpmcf: volume {v0} at the start, output mesh {mesh_volume}");
    assert!((mesh_volume / v0 - 1.0).abs() < 0.02);
}

#[test]
fn evolve_prints_a_text_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("inpaint.obj");
    let a = aorta();
    let run = vesselmsr(&[
        "evolve",
        &a,
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "48",
        "--velocity",
        "inpaint",
        "--c",
        "0.2",
        "--time",
        "4",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = String::from_utf8_lossy(&run.stdout);
    println!("{text}");
    assert!(text.contains("inpaint (c = 0.2) to t = 4 in"), "{text}");
    assert!(text.contains("watertight"), "{text}");
    assert!(out.exists());
}

#[test]
fn evolve_refuses_bad_input_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out.stl");
    let o = out.to_str().unwrap();
    let a = aorta();
    let base = ["evolve", &a, "-o", o, "--resolution", "48"];
    let with = |extra: &[&'static str]| -> Vec<&str> {
        base.iter().copied().chain(extra.iter().copied()).collect()
    };
    for (extra, word) in [
        (&["--velocity", "mcf", "--time", "0"][..], "positive"),
        (&["--velocity", "mcf", "--time", "-1"], "positive"),
        (
            &["--velocity", "mcf", "--time", "1", "--dt", "0"],
            "positive",
        ),
        (
            &["--velocity", "vpmcf", "--time", "1", "--dt", "-0.5"],
            "positive",
        ),
        (
            &["--velocity", "inpaint", "--c", "-1", "--time", "1"],
            "≥ 0",
        ),
        (
            &["--velocity", "mcf", "--c", "1", "--time", "1"],
            "takes no speed",
        ),
        (
            &["--velocity", "mcf", "--time", "1", "--dt", "0.001"],
            "smallest step",
        ),
        // The aorta's tubes (radius ~5 mm) vanish long before t = 1000 mm².
        (&["--velocity", "mcf", "--time", "1000"], "vanished at t ="),
    ] {
        assert_fails(&with(extra), word, &out);
    }
    // An unknown output format is refused before any work.
    let bad = tmp.path().join("out.xyz");
    assert_fails(
        &[
            "evolve",
            &a,
            "-o",
            bad.to_str().unwrap(),
            "--velocity",
            "mcf",
            "--time",
            "1",
        ],
        "unknown mesh format",
        &bad,
    );
}
