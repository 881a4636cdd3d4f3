//! The `vesselmsr` command-line interface: argument parsing (clap), the global flags (`--quiet`,
//! `--threads`, `--json`, `--max-memory`), and one file per command. Errors are printed as one
//! line on stderr with exit status 2 (`message`); outputs are only written when the whole command
//! succeeded (`outputs`); the memory budget is `budget`.

mod batch;
mod cap;
mod centerline;
mod compare;
mod decompose;
mod evolve;
mod grid_args;
mod info;
mod message;
mod outputs;
mod phantom;
mod profile;
mod progress;
mod reconstruct;
mod remesh;
mod repair;
mod stenosis;
mod voxelize;

use crate::budget;
use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// Repairs triangulated blood-vessel surfaces (level-set multiscale representation).
#[derive(Debug, Parser)]
#[command(name = "vesselmsr", version, about, long_about = None)]
pub struct Cli {
    /// No progress bars and no notices on stderr (errors are still printed).
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Worker threads for parallel work (default: one per core; at most 4 per core).
    #[arg(long, global = true, value_name = "N")]
    pub threads: Option<usize>,
    /// Refuse work whose memory estimate (grids, sample sets, archive members) exceeds this,
    /// e.g. 8G, 512M, bytes (default: half the machine's memory, within the address-space limit).
    #[arg(long, global = true, value_name = "SIZE")]
    pub max_memory: Option<String>,
    /// Print results as JSON on stdout instead of text.
    #[arg(long, global = true)]
    pub json: bool,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Validate a mesh and print its measures (counts, boundary loops, watertightness, orientation,
    /// volume, area, bounding box, mean edge length, genus).
    Info {
        /// Input mesh (.stl, .obj, .ply, .vtp or .vtk).
        mesh: PathBuf,
    },
    /// Close every boundary loop (open vessel ends, holes) with refined planar caps and write a
    /// watertight, outward-oriented mesh.
    Cap(cap::CapArgs),
    /// Centreline graph of a vessel mesh: branches with their maximal inscribed radius and
    /// tangent, junctions and endpoints, written as .json or .vtp.
    Centerline(centerline::CenterlineArgs),
    /// Distances between two surfaces (Hausdorff, mean, RMS) and their volumes.
    Compare(compare::CompareArgs),
    /// Signed distance grid φ of a mesh (negative inside), written as .npy (+ .npy.json sidecar)
    /// or .vti or .nrrd.
    Voxelize(voxelize::VoxelizeArgs),
    /// Mesh → signed distance grid → marching cubes: a closed, manifold, outward mesh.
    Remesh(remesh::RemeshArgs),
    /// Evolve a surface by a level-set motion (mean curvature, volume-preserving, constant speed,
    /// inpainting) solved by threshold dynamics; writes the evolved surface.
    Evolve(evolve::EvolveArgs),
    /// Multiscale representation of a surface (levels of a curvature motion and the details
    /// between them) written as one .npz archive; optionally every level as PLY and figures.
    Decompose(decompose::DecomposeArgs),
    /// Rebuild a level of a multiscale representation archive, exactly from its tracked vertices
    /// or by advecting its coarsest level set back along the details.
    Reconstruct(reconstruct::ReconstructArgs),
    /// Repair damaged regions of a vessel (chopped wall, hole, narrowing, occlusion) by
    /// inpainting; writes a watertight mesh and reports the inpainted volume and stenosis.
    Repair(repair::RepairArgs),
    /// Equivalent (cross-section) and inscribed diameters along every centreline branch, as CSV
    /// and optionally a plot.
    Profile(profile::ProfileArgs),
    /// Narrowings found automatically along every centreline branch against the healthy
    /// diameter: position, minimum and reference diameter, diameter and area stenosis, length.
    Stenosis(stenosis::StenosisArgs),
    /// Synthetic damaged vessel (tube, curved, bifurcation, stenosis or occlusion) with its
    /// intact truth and the regions D covering the damage: test data for inpainting.
    Phantom(phantom::PhantomArgs),
    /// Every mesh of a cohort (a manifest CSV or a folder) through repair --holes, stenosis or
    /// remesh, resumable, with one summary row per mesh in OUTDIR/summary.csv and summary.json.
    Batch(batch::BatchArgs),
}

/// Global settings every command sees.
pub struct Context {
    pub quiet: bool,
    pub json: bool,
    /// The memory budget, bytes (`--max-memory`).
    pub max_memory: u64,
}

impl Context {
    /// Prints a notice on stderr (one clean line, see `message`) unless `--quiet`.
    pub fn notice(&self, text: &str) {
        if !self.quiet {
            eprintln!("vesselmsr: notice: {}", message::clean(text));
        }
    }
}

/// Parses the command line, runs the command and returns the process exit status.
pub fn run() -> i32 {
    outputs::install_signal_cleanup();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if e.use_stderr() => {
            eprintln!("vesselmsr: error: {}", message::usage_error_line(&e));
            return 2;
        }
        Err(e) => {
            // --help and --version.
            let _ = e.print();
            return 0;
        }
    };
    match execute(cli) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("vesselmsr: error: {}", message::error_line(&e));
            2
        }
    }
}

fn execute(cli: Cli) -> anyhow::Result<()> {
    let max_memory = budget::max_memory(cli.max_memory.as_deref())?;
    let ctx = Context {
        quiet: cli.quiet,
        json: cli.json,
        max_memory,
    };
    if let Some(n) = cli.threads {
        anyhow::ensure!(n >= 1, "--threads must be at least 1");
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        let most = MAX_THREADS_PER_CORE * cores;
        if n > most {
            ctx.notice(&format!(
                "--threads {n} capped to {most} ({MAX_THREADS_PER_CORE} per core, {cores} cores)"
            ));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.min(most))
            .build_global()?;
    }
    match cli.command {
        Command::Info { mesh } => info::run(&ctx, &mesh),
        Command::Cap(args) => cap::run(&ctx, &args),
        Command::Centerline(args) => centerline::run(&ctx, &args),
        Command::Compare(args) => compare::run(&ctx, &args),
        Command::Voxelize(args) => voxelize::run(&ctx, &args),
        Command::Remesh(args) => remesh::run(&ctx, &args),
        Command::Evolve(args) => evolve::run(&ctx, &args),
        Command::Decompose(args) => decompose::run(&ctx, &args),
        Command::Reconstruct(args) => reconstruct::run(&ctx, &args),
        Command::Repair(args) => repair::run(&ctx, &args),
        Command::Phantom(args) => phantom::run(&ctx, &args),
        Command::Profile(args) => profile::run(&ctx, &args),
        Command::Stenosis(args) => stenosis::run(&ctx, &args),
        Command::Batch(args) => batch::run(&ctx, &args),
    }
}

/// Most worker threads per core `--threads` gives (more only cost memory and start-up time).
const MAX_THREADS_PER_CORE: usize = 4;

/// Writes a value as pretty JSON to `path` (atomically).
fn write_json_file<T: serde::Serialize>(path: &std::path::Path, value: &T) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    crate::io::write_atomic(path, |out| {
        out.write_all(text.as_bytes())
            .and_then(|_| out.write_all(b"\n"))
            .map_err(|e| crate::Error::io(path, e))
    })?;
    Ok(())
}

/// Prints a value as pretty JSON on stdout.
fn print_json<T: serde::Serialize>(value: &T) -> anyhow::Result<()> {
    println!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}
