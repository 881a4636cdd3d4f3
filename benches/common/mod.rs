//! Shared plumbing of the benchmarks: median wall-time timing, and the Python reference oracle
//! (reference/oracle.py, run with $VESSELMSR_PYTHON or reference/.venv) with the files it reads
//! and writes. A benchmark uses it with `mod common;`; the figures each prints stay in the bench.
#![allow(dead_code)]

pub mod surface;

use nalgebra::Point3;
use serde_json::Value;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// The real vessels of ../shared/data/real that the benches damage and repair: every mesh there
/// but the cortex.
pub const REAL_VESSELS: [&str; 5] = [
    "aorta_abdominal_capped.stl",
    "aorta_abdominal_open_ends.stl",
    "carotid_bifurcation.stl",
    "ica_aneurysm_c0015.stl",
    "coronary_stenosis_xray.stl",
];

/// The project root (where reference/ and data/ are).
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Median wall time of `f` and its last result: at least `min_runs` runs, more while the total
/// stays under `budget` and the count under `max_runs`. Results are dropped outside the timing.
pub fn time_median<T>(
    min_runs: usize,
    max_runs: usize,
    budget: Duration,
    mut f: impl FnMut() -> T,
) -> (Duration, T) {
    time_median_with_setup(min_runs, max_runs, budget, || (), |()| f())
}

/// [`time_median`] where each run first calls `setup` (not timed) and `f` consumes its output.
pub fn time_median_with_setup<S, T>(
    min_runs: usize,
    max_runs: usize,
    budget: Duration,
    mut setup: impl FnMut() -> S,
    mut f: impl FnMut(S) -> T,
) -> (Duration, T) {
    assert!(min_runs > 0, "at least one run");
    let mut times = Vec::new();
    let mut last = None;
    let start = Instant::now();
    while times.len() < min_runs || (start.elapsed() < budget && times.len() < max_runs) {
        let input = setup();
        let t = Instant::now();
        let result = std::hint::black_box(f(input));
        times.push(t.elapsed());
        last = Some(result);
    }
    times.sort();
    (times[times.len() / 2], last.expect("at least one run"))
}

/// The Python reference oracle.
pub struct Reference {
    python: PathBuf,
    script: PathBuf,
}

impl Reference {
    /// The oracle, when its Python ($VESSELMSR_PYTHON, else reference/.venv/bin/python) exists.
    pub fn find() -> Option<Reference> {
        let python = std::env::var_os("VESSELMSR_PYTHON")
            .map(PathBuf::from)
            .unwrap_or_else(|| root().join("reference/.venv/bin/python"));
        python.exists().then(|| Reference {
            python,
            script: root().join("reference/oracle.py"),
        })
    }

    /// The Python that runs the oracle (e.g. for `python -m pip` or another script).
    pub fn python(&self) -> &Path {
        &self.python
    }

    /// The same Python running another script of `reference/` (e.g. `msr.py`).
    pub fn with_script(&self, name: &str) -> Reference {
        Reference {
            python: self.python.clone(),
            script: root().join("reference").join(name),
        }
    }

    /// [`Reference::find`], printing a notice that `what` is skipped when the oracle is missing.
    pub fn find_or_notice(what: &str) -> Option<Reference> {
        let reference = Reference::find();
        if reference.is_none() {
            println!("notice: reference/.venv not found: {what} skipped (bash tests/run_all.sh creates it)");
        }
        reference
    }

    /// Runs `oracle.py ARGS...` and parses the JSON line it prints; None (with the oracle's
    /// stderr printed) when it fails.
    pub fn run(&self, args: &[&OsStr]) -> Option<Value> {
        let out = Command::new(&self.python)
            .arg(&self.script)
            .args(args)
            .output()
            .ok()?;
        if !out.status.success() {
            eprintln!("reference failed: {}", String::from_utf8_lossy(&out.stderr));
            return None;
        }
        serde_json::from_slice(&out.stdout).ok()
    }

    /// The oracle's own timing of one run ("seconds": the computation only, not Python start-up
    /// or loading).
    pub fn seconds(&self, args: &[&OsStr]) -> Option<f64> {
        seconds(&self.run(args)?)
    }

    /// The answer of the fastest of `runs` runs (by "seconds"; the first on a tie), or None when
    /// any run fails.
    pub fn best_of(&self, runs: usize, args: &[&OsStr]) -> Option<Value> {
        let mut best: Option<(f64, Value)> = None;
        for _ in 0..runs {
            let v = self.run(args)?;
            let s = seconds(&v)?;
            if best.as_ref().is_none_or(|(b, _)| s < *b) {
                best = Some((s, v));
            }
        }
        best.map(|(_, v)| v)
    }
}

/// The "seconds" of an oracle answer.
pub fn seconds(answer: &Value) -> Option<f64> {
    answer["seconds"].as_f64()
}

/// Writes `points` as little-endian f64 triples to `dir`/points.f64 (the oracle's query input).
pub fn write_points(dir: &Path, points: &[Point3<f64>]) -> Option<PathBuf> {
    let path = dir.join("points.f64");
    let bytes: Vec<u8> = points
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .flat_map(f64::to_le_bytes)
        .collect();
    std::fs::write(&path, bytes).ok()?;
    Some(path)
}

/// Reads a file of little-endian f64 values (an oracle output).
pub fn read_f64s(path: &Path) -> Option<Vec<f64>> {
    Some(
        std::fs::read(path)
            .ok()?
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect(),
    )
}

/// The machine's load averages (1, 5, 15 minutes) for the bench's header; "unknown" without
/// /proc/loadavg.
pub fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}
