//! Shared helpers of the integration tests: where the real meshes are, the CLI binary, the
//! Python reference oracle (reference/oracle.py) run in the project's virtual environment, seeded
//! query points (points.rs), test shapes built on the library primitives (shapes.rs),
//! hand-made mesh files (files.rs) and measures of a repair inside its region (in_region.rs).
//! A test module uses them with `use crate::common;` (and `use common::*;`), tests/suite/main.rs
//! declaring this module once for every test module.

mod files;
mod in_region;
mod points;
mod shapes;

pub use {files::*, in_region::*, points::*, shapes::*};

use nalgebra::Point3;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use vesselmsr::TriMesh;

/// The six real meshes of ../shared/data/real with the counts its SOURCES.md gives:
/// (file, vertices, faces, boundary loops, closed).
pub const REAL_MESHES: [(&str, usize, usize, usize, bool); 6] = [
    ("aorta_abdominal_open_ends.stl", 6068, 11887, 3, false),
    ("aorta_abdominal_capped.stl", 6468, 12932, 0, true),
    ("carotid_bifurcation.stl", 5829, 11594, 3, false),
    ("ica_aneurysm_c0015.stl", 3862, 7485, 3, false),
    ("coronary_stenosis_xray.stl", 3232, 6400, 2, false),
    ("cortex_rh_pial_fsaverage5.stl", 10242, 20480, 0, true),
];

/// The folder of real meshes, or None (with the notice of [`skip`]) when ../shared is absent.
pub fn real_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/real");
    if dir.is_dir() {
        Some(dir)
    } else {
        skip("../shared/data/real not found");
        None
    }
}

/// Says that the running test skips its checks (or part of them) for `reason`: prints
/// "skipping: {reason}" and, when $VESSELMSR_SKIPPED names a file (tests/run_all.sh sets it and
/// lists the file in its summary), appends the line "{test}: {reason}" to it, the test by its
/// path, whose first part is its file (`io_formats::real_meshes_…` is in tests/suite/io_formats.rs).
pub fn skip(reason: &str) {
    use std::io::Write;
    println!("skipping: {reason}");
    let Some(path) = std::env::var_os("VESSELMSR_SKIPPED") else {
        return;
    };
    // libtest runs each test on a thread named after it (its path in the test binary).
    let test = std::thread::current().name().unwrap_or("?").to_string();
    let line = format!("{test}: {reason}\n");
    // One short write in append mode: lines of tests running at once do not mix.
    let written = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .and_then(|mut f| f.write_all(line.as_bytes()));
    if let Err(e) = written {
        println!(
            "could not record the skip in {}: {e}",
            Path::new(&path).display()
        );
    }
}

/// The six real meshes of [`REAL_MESHES`] as (file name, mesh), or None (with the notice of
/// [`real_dir`]) when ../shared is absent.
pub fn real_meshes() -> Option<Vec<(String, TriMesh)>> {
    let dir = real_dir()?;
    Some(
        REAL_MESHES
            .iter()
            .map(|&(file, ..)| (file.to_string(), read_real(&dir, file)))
            .collect(),
    )
}

/// Reads `file` of the real-mesh folder `dir`, panicking with the path when it cannot.
pub fn read_real(dir: &Path, file: &str) -> TriMesh {
    let path = dir.join(file);
    vesselmsr::io::read_mesh(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Relative difference |a − b| / |b| (b = 0 counts as the smallest positive number).
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

/// Asserts that `ours` equals pymeshlab's `theirs` within 1e-6 relative, printing both as
/// "{what} ours vs pymeshlab theirs (rel …)".
pub fn assert_matches_pymeshlab(what: &str, ours: f64, theirs: f64) {
    let r = rel(ours, theirs);
    println!("{what} {ours} vs pymeshlab {theirs} (rel {r:.2e})");
    assert!(r < 1e-6, "{what} {ours} vs pymeshlab {theirs}");
}

/// The project's shipped sample folder.
pub fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data")
}

/// Runs the vesselmsr binary with `args`.
pub fn vesselmsr(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vesselmsr"))
        .args(args)
        .output()
        .expect("the vesselmsr binary runs")
}

/// The shipped open-ended aorta (data/), as a command-line argument.
pub fn aorta() -> String {
    data_dir()
        .join("aorta_abdominal_open_ends.stl")
        .to_string_lossy()
        .into_owned()
}

/// Writes the `kind` phantom (tube, curved, bifurcation, stenosis, occlusion) into `dir` by the
/// CLI: (damaged, truth, regions file).
pub fn phantom(kind: &str, dir: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let files = (
        dir.join(format!("{kind}.stl")),
        dir.join(format!("{kind}_truth.stl")),
        dir.join(format!("{kind}_regions.json")),
    );
    let path = |p: &PathBuf| p.to_str().unwrap().to_string();
    let (damaged, truth, regions) = (path(&files.0), path(&files.1), path(&files.2));
    let args = [
        "phantom",
        kind,
        "-o",
        &damaged,
        "--truth",
        &truth,
        "--regions-out",
        &regions,
        "-q",
    ];
    let out = vesselmsr(&args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    files
}

/// Runs the CLI with `args` and checks it failed as bad input must: exit status 2, one line on
/// stderr containing `word`, and no `output` left behind.
pub fn assert_fails(args: &[&str], word: &str, output: &Path) {
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

/// Runs the binary, asserts success and parses its stdout as JSON.
pub fn vesselmsr_json(args: &[&str]) -> Value {
    let out = vesselmsr(args);
    assert!(
        out.status.success(),
        "vesselmsr {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

/// The `kind` of every boundary loop a repair report lists (`hole`, `open vessel end`, ...).
pub fn loop_kinds(report: &Value) -> Vec<&str> {
    report["loops"]
        .as_array()
        .expect("the report lists the loops")
        .iter()
        .map(|l| l["kind"].as_str().expect("a loop's kind"))
        .collect()
}

/// `vesselmsr info --json <path>`, parsed.
pub fn info_json(path: &Path) -> Value {
    vesselmsr_json(&["info", "--json", path.to_str().unwrap()])
}

/// The Python reference oracle.
pub struct Oracle {
    python: PathBuf,
    script: PathBuf,
}

/// The oracle's Python, from $VESSELMSR_PYTHON or reference/.venv. Panics with instructions when
/// neither exists: the oracle tests are part of the suite, `bash tests/run_all.sh` creates the venv.
pub fn python() -> PathBuf {
    let python = std::env::var_os("VESSELMSR_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("reference/.venv/bin/python")
        });
    assert!(
        python.exists(),
        "the Python reference oracle is not installed ({}): run `bash tests/run_all.sh`, which creates it",
        python.display()
    );
    python
}

/// The oracle, run with [`python`] (which panics with instructions when it is missing).
pub fn oracle() -> Oracle {
    Oracle {
        python: python(),
        script: Path::new(env!("CARGO_MANIFEST_DIR")).join("reference/oracle.py"),
    }
}

impl Oracle {
    /// Runs an oracle command and returns its JSON answer.
    pub fn run(&self, args: &[&dyn AsRef<std::ffi::OsStr>]) -> Value {
        let out = Command::new(&self.python)
            .arg(&self.script)
            .args(args.iter().map(|a| a.as_ref()))
            .output()
            .expect("python runs");
        assert!(
            out.status.success(),
            "oracle {:?} failed: {}",
            args.iter()
                .map(|a| a.as_ref().to_string_lossy().into_owned())
                .collect::<Vec<_>>(),
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("oracle prints JSON")
    }

    /// manifold3d / pymeshlab verdict and measures of a mesh file.
    pub fn check(&self, mesh: &Path) -> Value {
        self.run(&[&"check", &mesh])
    }

    /// A per-point query (`closest`, `signed_distance`, `winding`) with `width` values per point.
    pub fn query(
        &self,
        command: &str,
        mesh: &Path,
        points: &[Point3<f64>],
        width: usize,
    ) -> (Vec<f64>, Value) {
        let dir = tempfile::tempdir().unwrap();
        let (input, output) = (dir.path().join("points.f64"), dir.path().join("out.f64"));
        let bytes: Vec<u8> = points
            .iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .flat_map(f64::to_le_bytes)
            .collect();
        std::fs::write(&input, bytes).unwrap();
        let answer = self.run(&[&command, &mesh, &input, &output]);
        let raw = std::fs::read(&output).unwrap();
        let values: Vec<f64> = raw
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(
            values.len(),
            points.len() * width,
            "oracle {command} output length"
        );
        (values, answer)
    }
}

/// A seeded generator for reproducible test points.
pub fn rng(seed: u64) -> rand::rngs::StdRng {
    rand::SeedableRng::seed_from_u64(seed)
}

/// Runs `script` with the oracle's Python and `args`, returning its stdout parsed as JSON.
pub fn run_python(script: &str, args: &[&dyn AsRef<std::ffi::OsStr>]) -> Value {
    let out = Command::new(python())
        .arg("-c")
        .arg(script)
        .args(args.iter().map(|a| a.as_ref()))
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "python failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("python prints JSON")
}
