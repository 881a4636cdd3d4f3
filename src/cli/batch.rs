//! `vesselmsr batch MANIFEST.csv|DIR -o OUTDIR [--jobs N] [--command repair|stenosis|remesh]`:
//! every mesh of a cohort through one command, with one summary row per mesh.
//!
//! The meshes are the manifest's `mesh` column (paths relative to the manifest's folder; an
//! optional `id` column names the outputs, else the file stem) or every mesh file of DIR (by
//! extension, sorted by name). Each goes through the single command's own code (`repair --holes`,
//! `stenosis`, `remesh`, their arguments parsed by the same parser with the same defaults), `--jobs`
//! at a time, into OUTDIR/ID.EXT (the mesh, in the input's format unless `--format`) and
//! OUTDIR/ID.report.json (repair's report, stenosis's lesions, remesh's measures). After each
//! mesh, OUTDIR/summary.csv and OUTDIR/summary.json are rewritten (atomically) with every row so
//! far: id, mesh, status (`ok` or `error`), outputs, volumes, the inpainted volume, the
//! stenoses, watertightness, notices, seconds and the error. A run that is stopped can be started again:
//! the rows already in summary.json are kept and their meshes skipped (failed ones too, unless
//! `--retry-failed`). A failing mesh, even one that panics, becomes an error row; the others go
//! on. The exit status is 0 when every row is `ok`, else 2 (after every mesh was tried).

use super::{write_json_file, Cli, Command, Context};
use crate::io::{write_atomic, MeshFormat};
use anyhow::Context as _;
use clap::Parser;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// The command run on every mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BatchCommand {
    /// `repair --holes`: holes inpainted, open ends capped (a mesh without holes is only capped).
    Repair,
    /// `stenosis`: the narrowings along the centreline.
    Stenosis,
    /// `remesh`: the closed, manifold level-set mesh.
    Remesh,
}

#[derive(Debug, clap::Args)]
pub struct BatchArgs {
    /// A manifest CSV with a `mesh` column (paths relative to the manifest's folder) and an
    /// optional `id` column, or a folder: every .stl, .obj, .ply, .vtp and .vtk file in it.
    pub input: PathBuf,
    /// Output folder (created when missing): the outputs, summary.csv and summary.json.
    #[arg(short, long, value_name = "OUTDIR")]
    pub output: PathBuf,
    /// The command run on every mesh.
    #[arg(long, value_enum, default_value = "repair")]
    pub command: BatchCommand,
    /// Meshes processed at once (each also uses the worker threads of --threads).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub jobs: usize,
    /// Format of the output meshes (stl, obj, ply, vtp or vtk; default: the input's).
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    /// Name of the meshes' length unit for repair's report and its plausibility notice (e.g. mm).
    #[arg(long, value_name = "UNIT", default_value = "file units")]
    pub units: String,
    /// Run again the meshes whose row in summary.json is an error (by default every row already
    /// there is skipped).
    #[arg(long)]
    pub retry_failed: bool,
}

/// One mesh of the cohort.
#[derive(Debug, Clone)]
struct Job {
    id: String,
    mesh: PathBuf,
}

/// One row of the summary (summary.csv's columns, in this order).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Row {
    pub id: String,
    pub mesh: String,
    pub command: String,
    /// `ok` or `error`.
    pub status: String,
    /// The output mesh (repair, remesh), empty otherwise.
    pub output: String,
    /// The JSON report written beside it.
    pub report: String,
    /// Enclosed volume of the (capped) input, world units³ (repair).
    pub input_volume: Option<f64>,
    /// Enclosed volume of the output, world units³ (repair, remesh).
    pub output_volume: Option<f64>,
    /// Volume added inside the regions, world units³ (repair).
    pub inpainted_volume: Option<f64>,
    /// Regions inpainted (repair: holes).
    pub regions: Option<usize>,
    /// Narrowings found (stenosis).
    pub stenoses: Option<usize>,
    /// Largest diameter stenosis, percent (stenosis: of the lesions; repair: of the regions).
    pub max_stenosis_pct: Option<f64>,
    /// Whether the output is closed and manifold (repair, remesh).
    pub watertight: Option<bool>,
    /// The command's notices (repair: no holes found, an implausible size for --units), `; `
    /// between them.
    pub notices: String,
    /// Wall time of this mesh, seconds.
    pub seconds: f64,
    /// The error, when `status` is `error`.
    pub error: String,
}

pub fn run(ctx: &Context, args: &BatchArgs) -> anyhow::Result<()> {
    anyhow::ensure!(args.jobs >= 1, "--jobs must be at least 1");
    let ext = match &args.format {
        Some(f) => {
            let ext = f.trim_start_matches('.').to_ascii_lowercase();
            MeshFormat::from_path(Path::new(&format!("x.{ext}"))).map_err(|_| {
                anyhow::anyhow!("--format {f:?}: expected stl, obj, ply, vtp or vtk")
            })?;
            Some(ext)
        }
        None => None,
    };
    let jobs = list_jobs(&args.input)?;
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create the output folder", args.output.display()))?;
    let previous = read_previous(&args.output)?;
    let done = |job: &Job| {
        previous
            .iter()
            .find(|r| r.id == job.id && (r.status == "ok" || !args.retry_failed))
    };
    // Rows in manifest order: those kept from the previous run, the others filled in as they end.
    let rows: Mutex<Vec<Option<Row>>> = Mutex::new(jobs.iter().map(|j| done(j).cloned()).collect());
    let todo: Vec<usize> = (0..jobs.len())
        .filter(|&k| done(&jobs[k]).is_none())
        .collect();
    if !ctx.quiet && todo.len() < jobs.len() {
        eprintln!(
            "vesselmsr: batch: {} of {} meshes already in {} (skipped)",
            jobs.len() - todo.len(),
            jobs.len(),
            args.output.join("summary.json").display()
        );
    }
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let worker = || -> anyhow::Result<()> {
        loop {
            let Some(&k) = todo.get(next.fetch_add(1, Ordering::SeqCst)) else {
                return Ok(());
            };
            let row = run_one(&jobs[k], args, ext.as_deref(), ctx.max_memory);
            let n = finished.fetch_add(1, Ordering::SeqCst) + 1;
            if !ctx.quiet {
                eprintln!(
                    "vesselmsr: batch: [{n}/{}] {}: {} ({:.1} s){}",
                    todo.len(),
                    row.id,
                    row.status,
                    row.seconds,
                    if row.error.is_empty() {
                        String::new()
                    } else {
                        format!(": {}", row.error)
                    }
                );
            }
            let mut rows = rows.lock().unwrap_or_else(|e| e.into_inner());
            rows[k] = Some(row);
            write_summaries(&args.output, &rows)?;
        }
    };
    std::thread::scope(|scope| -> anyhow::Result<()> {
        let handles: Vec<_> = (0..args.jobs.min(todo.len().max(1)))
            .map(|_| scope.spawn(worker))
            .collect();
        for h in handles {
            h.join()
                .map_err(|_| anyhow::anyhow!("a batch worker stopped unexpectedly"))??;
        }
        Ok(())
    })?;
    let rows = rows.into_inner().unwrap_or_else(|e| e.into_inner());
    write_summaries(&args.output, &rows)?;
    let rows: Vec<Row> = rows.into_iter().flatten().collect();
    let failed = rows.iter().filter(|r| r.status != "ok").count();
    if ctx.json {
        super::print_json(&rows)?;
    } else {
        println!(
            "{}: {} meshes, {} ok, {failed} failed",
            args.output.join("summary.csv").display(),
            rows.len(),
            rows.len() - failed
        );
    }
    if failed > 0 {
        anyhow::bail!(
            "{failed} of {} meshes failed (see {})",
            rows.len(),
            args.output.join("summary.csv").display()
        );
    }
    Ok(())
}

/// The meshes of a manifest CSV or a folder, with unique ids.
fn list_jobs(input: &Path) -> anyhow::Result<Vec<Job>> {
    let mut jobs = Vec::new();
    if input.is_dir() {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(input)
            .with_context(|| format!("{}", input.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && MeshFormat::from_path(p).is_ok())
            .collect();
        paths.sort();
        for mesh in paths {
            jobs.push(Job {
                id: stem(&mesh),
                mesh,
            });
        }
    } else {
        let base = input.parent().unwrap_or(Path::new("."));
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_path(input)
            .with_context(|| format!("{}: cannot read the manifest", input.display()))?;
        let headers = reader
            .headers()
            .with_context(|| format!("{}: not a CSV manifest", input.display()))?
            .clone();
        let column = |name: &str| headers.iter().position(|h| h.eq_ignore_ascii_case(name));
        let mesh_col = column("mesh").ok_or_else(|| {
            anyhow::anyhow!(
                "{}: the manifest has no `mesh` column (columns: {})",
                input.display(),
                headers.iter().collect::<Vec<_>>().join(", ")
            )
        })?;
        let id_col = column("id");
        for (n, record) in reader.records().enumerate() {
            let record = record.with_context(|| format!("{}: row {}", input.display(), n + 2))?;
            let path = record.get(mesh_col).unwrap_or("");
            anyhow::ensure!(
                !path.is_empty(),
                "{}: row {}: empty `mesh`",
                input.display(),
                n + 2
            );
            let mesh = base.join(path);
            let id = id_col
                .and_then(|c| record.get(c))
                .filter(|s| !s.is_empty())
                .map_or_else(|| stem(&mesh), str::to_string);
            jobs.push(Job { id, mesh });
        }
    }
    anyhow::ensure!(
        !jobs.is_empty(),
        "{}: no mesh to process (a folder of .stl, .obj, .ply, .vtp or .vtk files, or a CSV with a `mesh` column)",
        input.display()
    );
    // Unique ids, deterministic for a given manifest (resuming relies on it): a repeated id
    // gets _2, _3, ….
    let mut seen = std::collections::HashSet::new();
    for job in &mut jobs {
        anyhow::ensure!(
            !job.id.contains(['/', '\\']) && job.id != "." && job.id != "..",
            "{}: id {:?} is not a file name",
            input.display(),
            job.id
        );
        let base = job.id.clone();
        let mut k = 1;
        while !seen.insert(job.id.clone()) {
            k += 1;
            job.id = format!("{base}_{k}");
        }
    }
    Ok(jobs)
}

/// The file name without its mesh extension.
fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".into())
}

/// The rows of a previous run's summary.json in `dir` (none when absent).
fn read_previous(dir: &Path) -> anyhow::Result<Vec<Row>> {
    let path = dir.join("summary.json");
    match std::fs::read(&path) {
        Ok(bytes) => serde_json::from_slice(&bytes).with_context(|| {
            format!(
                "{}: not a batch summary (remove it to start afresh)",
                path.display()
            )
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(crate::Error::io(&path, e).into()),
    }
}

/// Rewrites summary.csv and summary.json of `dir` with the finished rows (atomically; there is
/// at least one).
fn write_summaries(dir: &Path, rows: &[Option<Row>]) -> anyhow::Result<()> {
    let rows: Vec<&Row> = rows.iter().flatten().collect();
    write_json_file(&dir.join("summary.json"), &rows)?;
    let mut csv_text = csv::Writer::from_writer(Vec::new());
    for row in &rows {
        csv_text.serialize(row)?;
    }
    let bytes = csv_text.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?;
    let path = dir.join("summary.csv");
    write_atomic(&path, |out| {
        out.write_all(&bytes)
            .map_err(|e| crate::Error::io(&path, e))
    })?;
    Ok(())
}

/// Runs the command on one mesh; any error, or a panic, becomes an error row (without figures).
fn run_one(job: &Job, args: &BatchArgs, ext: Option<&str>, max_memory: u64) -> Row {
    let start = Instant::now();
    let base = Row {
        id: job.id.clone(),
        mesh: job.mesh.display().to_string(),
        command: format!("{:?}", args.command).to_lowercase(),
        ..Row::default()
    };
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut row = base.clone();
        run_command(job, args, ext, max_memory, &mut row).map(|()| row)
    }));
    let failed = |error: String| Row {
        status: "error".into(),
        error,
        ..base.clone()
    };
    let row = match outcome {
        Ok(Ok(row)) => Row {
            status: "ok".into(),
            ..row
        },
        Ok(Err(e)) => failed(super::message::error_line(&e)),
        Err(panic) => failed(format!(
            "internal error: {}",
            panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default()
        )),
    };
    Row {
        seconds: start.elapsed().as_secs_f64(),
        ..row
    }
}

/// Runs the command on `job` through the single command's code, writing its outputs and
/// filling the row's figures.
fn run_command(
    job: &Job,
    args: &BatchArgs,
    ext: Option<&str>,
    max_memory: u64,
    row: &mut Row,
) -> anyhow::Result<()> {
    let ext = match ext {
        Some(e) => e.to_string(),
        None => {
            MeshFormat::from_path(&job.mesh)?;
            job.mesh
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default()
        }
    };
    let output = args.output.join(format!("{}.{ext}", job.id));
    let report = args.output.join(format!("{}.report.json", job.id));
    let (mesh, output_s, report_s) = (job.mesh.as_os_str(), output.as_os_str(), report.as_os_str());
    // The single command's own parser, so its defaults are the batch's.
    let line: Vec<&std::ffi::OsStr> = match args.command {
        BatchCommand::Repair => vec![
            "repair".as_ref(),
            mesh,
            "--holes".as_ref(),
            "-o".as_ref(),
            output_s,
            "--report".as_ref(),
            report_s,
            "--units".as_ref(),
            args.units.as_ref(),
        ],
        BatchCommand::Stenosis => vec!["stenosis".as_ref(), mesh],
        BatchCommand::Remesh => vec!["remesh".as_ref(), mesh, "-o".as_ref(), output_s],
    };
    let cli = Cli::try_parse_from(std::iter::once("vesselmsr".as_ref()).chain(line))
        .map_err(|e| anyhow::anyhow!("{}", e.to_string().trim()))?;
    let ctx = Context {
        quiet: true,
        json: false,
        max_memory,
    };
    let f = |v: &Value| v.as_f64();
    match cli.command {
        Command::Repair(a) => {
            let r = serde_json::to_value(super::repair::repair_file(&ctx, &a)?)?;
            let regions = r["regions"].as_array().cloned().unwrap_or_default();
            row.output = output.display().to_string();
            row.report = report.display().to_string();
            row.input_volume = f(&r["input"]["volume"]);
            row.output_volume = f(&r["output"]["volume"]);
            row.inpainted_volume = Some(
                regions
                    .iter()
                    .filter_map(|g| f(&g["inpainted_volume"]))
                    .fold(0.0, |a, b| a + b),
            );
            row.notices = r["notices"]
                .as_array()
                .map(|n| {
                    n.iter()
                        .filter_map(Value::as_str)
                        .collect::<Vec<_>>()
                        .join("; ")
                })
                .unwrap_or_default();
            row.regions = Some(regions.len());
            row.max_stenosis_pct = regions
                .iter()
                .filter_map(|g| f(&g["diameter_stenosis_pct"]))
                .reduce(f64::max);
            row.watertight = r["watertight"].as_bool();
        }
        Command::Stenosis(a) => {
            let found = super::stenosis::find_in_file(&ctx, &a)?;
            write_json_file(&report, &found)?;
            row.report = report.display().to_string();
            row.stenoses = Some(found.lesions.len());
            row.max_stenosis_pct = found
                .lesions
                .iter()
                .map(|l| l.diameter_stenosis_pct)
                .reduce(f64::max);
        }
        Command::Remesh(a) => {
            let out = serde_json::to_value(super::remesh::remesh_file(&ctx, &a)?)?;
            write_json_file(&report, &out)?;
            row.output = output.display().to_string();
            row.report = report.display().to_string();
            row.output_volume = f(&out["output"]["volume"]);
            row.watertight = out["output"]["watertight"].as_bool();
        }
        _ => anyhow::bail!("unsupported batch command"),
    }
    Ok(())
}
