//! Centerline benchmark (issue 20, "Speed"): the whole command the user waits for,
//! `vesselmsr centerline MESH -o CL.json` (the release binary: start-up, reading, the grid, the
//! skeleton, the JSON), against the independent Python route `reference/centerline.py MESH -o
//! REF.json` (libigl winding-number mask, kimimaro TEASAR skeleton, trimesh sections; its own
//! Python start-up and imports included), on each real vessel of ../shared/data/real (all but the
//! cortex; skipped with a notice when ../shared is absent), both on the same grid: ours at its
//! default voxel, the reference given that voxel (`--voxel`, read from our JSON).
//!
//! Per mesh, 3 rounds of one run of each, interleaved (ours, then the reference), so that both
//! sides of a round run under the same load; the figure of each side is its best wall time of
//! the 3, and ratio = reference / ours. Then `reference/centerline.py --compare` on the two JSON
//! files of the last round: branches, junctions and endpoints (ours / reference), total
//! lengths, the symmetric Hausdorff and mean distances between the two sets of branch polylines
//! (resampled every h/4) and the mean |radius difference| of our points against the nearest
//! reference point, in units of our voxel h. Acceptance (issue 20): each vessel in < 2 s on
//! this 2-core machine, >= 10× faster than the reference.
//!
//! Measured 2026-12-04 (load 1.3–1.8), after the open ends are closed by centroid fans for the
//! grid's signs (exact ray crossings instead of the open mesh's winding numbers, and the grid
//! sized on the true enclosed volume) and the sign flood runs by row spans:
//!
//! | mesh | ours s | reference s | ratio | branches | junctions | endpoints | length ours/ref | Hausdorff h | mean h | abs dr h |
//! |---|---|---|---|---|---|---|---|---|---|---|
//! | aorta_abdominal_open_ends | 0.15 | 2.27 | 15.4 | 3/3 | 1/1 | 3/3 | 118.5/119.4 | 3.17 | 0.26 | 0.07 |
//! | aorta_abdominal_capped | 0.18 | 2.63 | 14.6 | 3/5 | 1/2 | 3/4 | 127.4/140.0 | 12.84 | 0.75 | 0.20 |
//! | carotid_bifurcation | 0.19 | 3.18 | 16.8 | 3/3 | 1/1 | 3/3 | 0.1031/0.1028 | 1.77 | 0.13 | 0.03 |
//! | ica_aneurysm_c0015 | 0.11 | 1.82 | 17.0 | 3/3 | 1/1 | 3/3 | 22.96/23.40 | 1.86 | 0.26 | 0.11 |
//! | coronary_stenosis_xray | 0.21 | 3.31 | 16.0 | 1/1 | 0/0 | 2/2 | 72.70/72.63 | 0.85 | 0.07 | 0.02 |
//!
//! Every vessel under 2 s and at least 14.6× faster than the reference (acceptance: >= 10×).
//! Under load 5 (three other builds) the same code gave ratios 11.8–16.2.
//!
//! Measured 2026-12-03 at a5e57df (our centreline grid coarsened to a tenth of the typical vessel
//! radius; the reference on the same grid), load 0.2–0.7 (a quiet machine):
//!
//! | mesh | ours s | reference s | ratio | branches | junctions | endpoints | length ours/ref | Hausdorff h | mean h | abs dr h |
//! |---|---|---|---|---|---|---|---|---|---|---|
//! | aorta_abdominal_open_ends | 0.41 | 3.38 | 8.3 | 3/3 | 1/1 | 3/3 | 118.8/119.7 | 3.45 | 0.27 | 0.09 |
//! | aorta_abdominal_capped | 0.15 | 2.27 | 14.7 | 3/5 | 1/2 | 3/4 | 127.4/140.0 | 12.84 | 0.75 | 0.20 |
//! | carotid_bifurcation | 0.30 | 3.35 | 11.0 | 3/3 | 1/1 | 3/3 | 0.1035/0.1039 | 2.58 | 0.15 | 0.03 |
//! | ica_aneurysm_c0015 | 0.17 | 2.26 | 13.0 | 3/3 | 1/1 | 3/3 | 22.85/23.47 | 2.03 | 0.25 | 0.06 |
//! | coronary_stenosis_xray | 0.41 | 2.89 | 7.1 | 1/1 | 0/0 | 2/2 | 72.67/72.63 | 0.57 | 0.07 | 0.01 |
//!
//! Under load 3 the same code gave ours 0.15–0.53 s and ratios 7.5, 12.7, 7.8, 10.2, 7.9. So every
//! vessel takes well under 2 s, but the >= 10x asked holds on three of five: on the open aorta and
//! the coronary ours spends most of its time in the voxelizer's serial sign flood over a grid that
//! is mostly outside the thin vessel (perf: 38% of the coronary's run). On the capped aorta the
//! reference finds two extra short branches at the flat caps' corners (5 against our 3), hence
//! its Hausdorff distance.
//! Earlier figures (load ~5, main at f84a2d5, our grid at the project's default voxel, the
//! reference at its own): ours 0.73–3.36 s, ratios 5.2–11.9.
//!
//! Run: `cargo bench --bench centerline` (the reference needs reference/.venv, which
//! `bash tests/run_all.sh` creates, or $VESSELMSR_PYTHON).

mod common;

use common::{load, Reference};
use serde_json::Value;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Real vessels timed (file names in ../shared/data/real): every one but the cortex.
const MESHES: [&str; 5] = [
    "aorta_abdominal_open_ends.stl",
    "aorta_abdominal_capped.stl",
    "carotid_bifurcation.stl",
    "ica_aneurysm_c0015.stl",
    "coronary_stenosis_xray.stl",
];

/// Rounds per mesh; each side's figure is its best wall time.
const ROUNDS: usize = 3;

/// One timed run: wall seconds, or the failure (exit status and the last line of stderr).
fn timed(cmd: &mut Command) -> Result<f64, String> {
    let t = Instant::now();
    let out = cmd.output().map_err(|e| format!("cannot start: {e}"))?;
    let secs = t.elapsed().as_secs_f64();
    if out.status.success() {
        Ok(secs)
    } else {
        let err = String::from_utf8_lossy(&out.stderr);
        Err(format!(
            "{}: {}",
            out.status,
            err.lines().last().unwrap_or("(no message)")
        ))
    }
}

fn ours(mesh: &Path, out: &Path) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_vesselmsr"));
    cmd.arg("centerline").arg(mesh).arg("-o").arg(out);
    cmd
}

fn reference_cmd(python: &Path, mesh: &Path, out: &Path, voxel: Option<f64>) -> Command {
    let mut cmd = Command::new(python);
    cmd.arg(common::root().join("reference/centerline.py"))
        .arg(mesh)
        .arg("-o")
        .arg(out);
    if let Some(h) = voxel {
        cmd.arg("--voxel").arg(format!("{h:e}"));
    }
    cmd
}

/// The voxel our centreline was traced on (from its JSON), so the reference works on the same
/// grid.
fn our_voxel(json: &Path) -> Option<f64> {
    let v: Value = serde_json::from_slice(&std::fs::read(json).ok()?).ok()?;
    v["voxel"].as_f64()
}

/// The reference's Python, as `common::Reference::find` chooses it.
fn python() -> Option<PathBuf> {
    let python = std::env::var_os("VESSELMSR_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| common::root().join("reference/.venv/bin/python"));
    python.exists().then_some(python)
}

fn best(times: &[Result<f64, String>]) -> Result<f64, String> {
    let ok: Vec<f64> = times
        .iter()
        .filter_map(|t| t.as_ref().ok().copied())
        .collect();
    if ok.is_empty() {
        Err(times
            .iter()
            .find_map(|t| t.as_ref().err().cloned())
            .unwrap_or_default())
    } else {
        Ok(ok.into_iter().fold(f64::INFINITY, f64::min))
    }
}

fn fmt_secs(t: &Result<f64, String>) -> String {
    match t {
        Ok(s) => format!("{s:.2}"),
        Err(_) => "failed".into(),
    }
}

fn with_unit(t: &Result<f64, String>) -> String {
    match t {
        Ok(s) => format!("{s:.2} s"),
        Err(_) => "failed".into(),
    }
}

fn num(v: &Value, key: &str, digits: usize) -> String {
    match &v[key] {
        Value::Number(n) => match n.as_i64() {
            Some(i) => i.to_string(),
            None => format!("{:.*}", digits, n.as_f64().unwrap_or(f64::NAN)),
        },
        _ => "-".into(),
    }
}

fn main() {
    let start = Instant::now();
    println!(
        "vesselmsr centerline benchmark: whole commands, best of {ROUNDS} interleaved rounds (load {}; the machine is shared: timings vary)",
        load()
    );
    println!("reproduce: cargo bench --bench centerline");
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real"));
    if !dir.is_dir() {
        println!("notice: ../shared/data/real not found: centerline benchmark skipped");
        return;
    }
    let python = python();
    let compare = Reference::find().map(|r| r.with_script("centerline.py"));
    if python.is_none() {
        println!("notice: reference/.venv not found: the reference is skipped (bash tests/run_all.sh creates it)");
    }
    let tmp = tempfile::tempdir().expect("temporary directory");
    let mut rows = Vec::new();
    for name in MESHES {
        let mesh = dir.join(name);
        if !mesh.is_file() {
            println!("notice: {} not found: skipped", mesh.display());
            continue;
        }
        let ours_json = tmp.path().join("ours.json");
        let ref_json = tmp.path().join("ref.json");
        let _ = std::fs::remove_file(&ours_json);
        let _ = std::fs::remove_file(&ref_json);
        let mut ours_times = Vec::new();
        let mut ref_times = Vec::new();
        for _ in 0..ROUNDS {
            ours_times.push(timed(&mut ours(&mesh, &ours_json)));
            if let Some(py) = &python {
                let voxel = our_voxel(&ours_json);
                ref_times.push(timed(&mut reference_cmd(py, &mesh, &ref_json, voxel)));
            }
        }
        let o = best(&ours_times);
        let r = if python.is_some() {
            best(&ref_times)
        } else {
            Err("no reference/.venv".into())
        };
        for (side, t) in [("ours", &o), ("reference", &r)] {
            if let Err(e) = t {
                println!("{name}: {side} failed: {e}");
            }
        }
        let figures = match (&o, &r, &compare) {
            (Ok(_), Ok(_), Some(c)) => c.run(&[
                OsStr::new("--compare"),
                ours_json.as_os_str(),
                ref_json.as_os_str(),
            ]),
            _ => None,
        }
        .unwrap_or(Value::Null);
        println!(
            "{name}: ours {}, reference {} (rounds: ours {:?}, reference {:?})",
            with_unit(&o),
            with_unit(&r),
            ours_times.iter().map(fmt_secs).collect::<Vec<_>>(),
            ref_times.iter().map(fmt_secs).collect::<Vec<_>>()
        );
        rows.push((name, o, r, figures));
    }
    println!();
    println!(
        "{:<30} {:>7} {:>7} {:>6} | {:>9} {:>9} {:>9} {:>15} {:>7} {:>7} {:>7}",
        "mesh",
        "ours s",
        "ref s",
        "ratio",
        "branches",
        "junctions",
        "endpoints",
        "length ours/ref",
        "Haus h",
        "mean h",
        "|dr| h"
    );
    for (name, o, r, f) in &rows {
        let ratio = match (o, r) {
            (Ok(o), Ok(r)) => format!("{:.1}", r / o),
            _ => "-".into(),
        };
        let pair = |key: &str| {
            format!(
                "{}/{}",
                num(f, &format!("{key}_ours"), 0),
                num(f, &format!("{key}_ref"), 0)
            )
        };
        let lengths = match (f["length_ours"].as_f64(), f["length_ref"].as_f64()) {
            (Some(a), Some(b)) => format!("{}/{}", sig(a), sig(b)),
            _ => "-".into(),
        };
        println!(
            "{:<30} {:>7} {:>7} {:>6} | {:>9} {:>9} {:>9} {:>15} {:>7} {:>7} {:>7}",
            name.trim_end_matches(".stl"),
            fmt_secs(o),
            fmt_secs(r),
            ratio,
            pair("branches"),
            pair("junctions"),
            pair("endpoints"),
            lengths,
            num(f, "hausdorff_h", 2),
            num(f, "mean_h", 2),
            num(f, "mean_abs_radius_diff_h", 2),
        );
    }
    println!(
        "\nbenchmark took {:.1} s; load now {}",
        start.elapsed().as_secs_f64(),
        load()
    );
}

/// Four significant digits (the meshes' units differ: the carotid is in metres).
fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = (3 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
}
