//! `vesselmsr evolve MESH -o OUT --velocity mcf|vpmcf|expand|inpaint [--c C] --time T [--dt DT]`:
//! voxelize the mesh, evolve its signed distance function by threshold dynamics
//! (`motion::evolve`) up to time T, and write the zero level set (marching cubes) of the result.
//!
//! Units are the mesh's: T and DT in length², C in length per unit time (1/length), so `expand`
//! moves the surface by C·T. The default step is 2h² (h the voxel): on a sphere of 24 voxels of
//! radius, mean curvature flow then stays within 0.01 voxel of r² = R² − 4t. The grid gets, beyond
//! the usual padding, room for the growth C·T and the diffusion's reach 4√(2·DT), and for the
//! curvature flows that can move outward (`vpmcf`, `inpaint`) the distance 2√T a sphere's surface
//! travels under mean curvature flow in time T. Nothing is written when the evolution fails (e.g.
//! the shape vanishes before T).

use super::grid_args::{load_and_voxelize, GridArgs, Voxelized};
use super::outputs::Outputs;
use super::{print_json, Context};
use crate::grid::spec::GridJson;
use crate::grid::spec::{format_bytes, grid_memory_bytes, GridOptions};
use crate::grid::{Grid3, GridSpec};
use crate::io::{write_mesh, MeshFormat};
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::mesh::info::{mesh_info, MeshInfo};
use crate::motion::volume::{measure_area, measure_volume};
use crate::motion::{evolve, step_count, FlowOptions, StepReport, Velocity};
use indicatif::ProgressStyle;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Default time step, in voxels² (h²).
pub const DEFAULT_DT_VOXELS2: f64 = 2.0;

/// f32-sized arrays per node held during a step, for the memory estimate: φ, its copy for the
/// second-order correction, and the redistancer's two work arrays (over the band's box).
const GRIDS_HELD: usize = 4;

/// The velocities on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum VelocityName {
    /// Mean curvature flow, v = −κ.
    Mcf,
    /// Volume-preserving mean curvature flow, v = κ_a − κ.
    Vpmcf,
    /// Constant normal speed, v = c.
    Expand,
    /// Inpainting motion, v = c + κ_a − κ (c ≥ 0).
    Inpaint,
}

#[derive(Debug, clap::Args)]
pub struct EvolveArgs {
    /// Input mesh (.stl, .obj, .ply, .vtp or .vtk).
    pub mesh: PathBuf,
    /// Output mesh (.stl, .obj, .ply, .vtp or .vtk): the evolved surface.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Normal velocity of the motion.
    #[arg(long, value_enum)]
    pub velocity: VelocityName,
    /// Speed of `expand` and `inpaint`, in the mesh's length per unit time (default 0).
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub c: Option<f64>,
    /// Final time, in the mesh's length² (mean curvature flow shrinks a sphere as r² = R² − 4t).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub time: f64,
    /// Largest time step, in the mesh's length² (default 2h², h the voxel size); the run takes
    /// ⌈T/DT⌉ equal steps.
    #[arg(long, value_name = "DT", allow_negative_numbers = true)]
    pub dt: Option<f64>,
    #[command(flatten)]
    pub grid: GridArgs,
}

#[derive(serde::Serialize)]
struct Timings {
    read: f64,
    voxelize: f64,
    evolve: f64,
    marching_cubes: f64,
    write: f64,
}

#[derive(serde::Serialize)]
struct Initial {
    volume: f64,
    area: f64,
}

#[derive(serde::Serialize)]
struct EvolveOutput {
    velocity: &'static str,
    c: Option<f64>,
    time: f64,
    dt: f64,
    grid: GridJson,
    initial: Initial,
    steps: Vec<StepReport>,
    output: MeshInfo,
    timings: Timings,
}

/// A motion a grid must have room for: its velocity, final time and step (world length²).
pub(super) struct MotionRoom {
    pub velocity: Velocity,
    pub time: f64,
    pub step: f64,
}

/// Pads `phi` (and updates `spec` to match) so that, beyond the padding `grid_opts` already gave
/// it, the grid has room for the motion: the growth C·T, the diffusion's reach 4√(2·step) for the
/// curvature motions, and 2√T for those that can move outward (`vpmcf`, `inpaint`), plus two
/// voxels. New nodes get φ = the flow's redistance band (outside). Refuses, naming `mesh_path`
/// and `what` (e.g. "evolving"), a padded grid whose `GRIDS_HELD` grids exceed the memory limit.
pub(super) fn pad_for_motion(
    mesh_path: &Path,
    spec: &mut GridSpec,
    phi: Grid3,
    grid_opts: &GridOptions,
    motion: &MotionRoom,
    flow: &FlowOptions,
    what: &str,
) -> anyhow::Result<Grid3> {
    let h = spec.voxel();
    let velocity = motion.velocity;
    let growth = velocity.speed().map_or(0.0, |c| c.max(0.0) * motion.time);
    let outward = if velocity.preserves_volume() {
        2.0 * motion.time.sqrt()
    } else {
        0.0
    };
    let reach = if velocity.has_curvature() {
        4.0 * (2.0 * motion.step).sqrt()
    } else {
        0.0
    };
    let needed = ((growth + outward + reach) / h + 2.0).ceil();
    let have = grid_opts.padding_voxels as f64;
    let extra = (needed - have).max(0.0);
    if extra <= 0.0 {
        return Ok(phi);
    }
    let dims = spec.dims.map(|d| d as f64 + 2.0 * extra);
    let bytes = grid_memory_bytes(spec.dims, GRIDS_HELD) as f64 * (dims[0] * dims[1] * dims[2])
        / spec.node_count() as f64;
    if bytes > grid_opts.max_memory_bytes as f64 {
        anyhow::bail!(
            "{}: {what} needs a grid of {}×{}×{} nodes (padded by {extra} voxels for the \
             motion), about {} for {GRIDS_HELD} grids, more than the {} limit: use a \
             coarser --voxel, a shorter --time, or raise --max-memory",
            mesh_path.display(),
            dims[0],
            dims[1],
            dims[2],
            format_bytes(bytes as u64),
            format_bytes(grid_opts.max_memory_bytes)
        );
    }
    let fill = flow.band_width(&velocity, motion.step, h) as f32;
    let phi = phi.pad(extra as usize, fill)?;
    spec.dims = phi.dims();
    spec.transform = *phi.transform();
    Ok(phi)
}

pub fn run(ctx: &Context, args: &EvolveArgs) -> anyhow::Result<()> {
    MeshFormat::from_path(&args.output)?;
    let mut outputs = Outputs::new(&[&args.output], &[])?;
    let name = match args.velocity {
        VelocityName::Mcf => "mcf",
        VelocityName::Vpmcf => "vpmcf",
        VelocityName::Expand => "expand",
        VelocityName::Inpaint => "inpaint",
    };
    let velocity = Velocity::from_name(name, args.c)?;
    // T and DT are checked before any work (DT's default needs the voxel size).
    step_count(args.time, args.dt.unwrap_or(args.time))
        .map_err(|e| anyhow::anyhow!("--time/--dt: {e}"))?;
    let grid_opts = args.grid.options(ctx);
    let Voxelized {
        mut spec,
        mut phi,
        read_s: read,
        voxelize_s,
        bar,
        ..
    } = load_and_voxelize(ctx, &args.mesh, &args.grid)?;
    let h = spec.voxel();
    let dt = args.dt.unwrap_or(DEFAULT_DT_VOXELS2 * h * h);
    let steps = step_count(args.time, dt)?;
    let step = args.time / steps as f64;
    let opts = FlowOptions::default();

    phi = pad_for_motion(
        &args.mesh,
        &mut spec,
        phi,
        &grid_opts,
        &MotionRoom {
            velocity,
            time: args.time,
            step,
        },
        &opts,
        "evolving",
    )?;
    let initial = Initial {
        volume: measure_volume(&phi),
        area: measure_area(&phi),
    };

    if !bar.is_hidden() {
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} {msg} [{bar:30}] {pos}/{len} steps ({elapsed})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.set_length(steps as u64);
    }
    bar.set_message(format!("evolving ({velocity})"));
    let t = Instant::now();
    let reports = evolve(&mut phi, velocity, args.time, dt, &opts, |_| bar.inc(1))
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.mesh.display()))?;
    let evolve_s = t.elapsed().as_secs_f64();

    bar.set_message("extracting the surface");
    let t = Instant::now();
    let surface = extract_surface(&phi, &ExtractOptions::default())?;
    let mc = t.elapsed().as_secs_f64();
    let output = mesh_info(&surface);
    let t = Instant::now();
    outputs.write(&args.output, |p| write_mesh(p, &surface))?;
    outputs.commit()?;
    let write = t.elapsed().as_secs_f64();
    bar.finish_and_clear();

    let out = EvolveOutput {
        velocity: velocity.name(),
        c: velocity.speed(),
        time: args.time,
        dt: step,
        grid: GridJson::of(&spec),
        initial,
        steps: reports,
        output,
        timings: Timings {
            read,
            voxelize: voxelize_s,
            evolve: evolve_s,
            marching_cubes: mc,
            write,
        },
    };
    if ctx.json {
        return print_json(&out);
    }
    let [nx, ny, nz] = spec.dims;
    let last = out.steps.last();
    println!(
        "{}: {velocity} to t = {} in {steps} steps of {step} on a {nx}×{ny}×{nz} grid, voxel {h} \
         (file units)",
        args.output.display(),
        args.time
    );
    println!(
        "volume {:.6} -> {:.6}, area {:.6} -> {:.6} (sub-voxel estimates); evolve {evolve_s:.2} s",
        out.initial.volume,
        last.map_or(out.initial.volume, |r| r.volume),
        out.initial.area,
        last.map_or(out.initial.area, |r| r.area)
    );
    println!("{}", out.output);
    Ok(())
}
