//! `vesselmsr decompose MESH -o MSR.npz [--levels N] [--time T] [--velocity …] [--c C] [--dt DT]
//! [grid flags] [--levels-dir DIR] [--figures DIR] [--measure-rebuilds [SAMPLES]]`: the
//! multiscale representation of a mesh (paper Algorithm 1, [`crate::msr::decompose`]) written
//! as one `.npz` archive.
//!
//! The mesh is voxelized, the grid padded for the motion (as `evolve` does), and the levels
//! t_i = i·T/N computed by the chosen motion (default `vpmcf`, the paper's Figure 1). Optional
//! outputs for looking at the result: `--levels-dir` writes every scale S_0..S_N as PLY, VTP or
//! VTK (`--levels-format`; S_k, k ≥ 1, with the per-vertex scalar `detail` = w_k, for ParaView or MeshLab), `--figures` the
//! detail histograms per level (the paper's Figure 2) and a strip of S_0..S_N coloured by w_k
//! (its Figure 1); `--measure-rebuilds` the paper's Figure 1 measure of the level-set
//! reconstruction, each S_{i−1} against its rebuild from the exact φ_i
//! ([`crate::msr::fidelity`]). Everything is computed before anything is written, so a failure
//! leaves no output.

use super::evolve::{pad_for_motion, MotionRoom, VelocityName};
use super::grid_args::{load_and_voxelize, GridArgs, Voxelized};
use super::outputs::Outputs;
use super::{print_json, Context};
use crate::grid::spec::grid_memory_bytes;
use crate::grid::spec::GridJson;
use crate::io::write_mesh_with_scalars;
use crate::mesh::distance::SurfaceDistanceOptions;
use crate::motion::Velocity;
use crate::msr::archive::write_msr;
use crate::msr::decompose::{decompose, level_schedule, DecomposeOptions};
use crate::msr::fidelity::measure_level_rebuilds;
use crate::report::{
    histogram_grid, render_strip, write_png, Camera, HistogramOptions, Panel, RgbImage,
    StripOptions,
};
use crate::TriMesh;
use clap::ValueEnum;
use indicatif::ProgressStyle;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, clap::Args)]
pub struct DecomposeArgs {
    /// Input mesh (.stl, .obj, .ply, .vtp or .vtk).
    pub mesh: PathBuf,
    /// Output archive (.npz; numpy's `np.load` opens it).
    #[arg(short, long, value_name = "MSR.npz")]
    pub output: PathBuf,
    /// Number of levels N.
    #[arg(long, value_name = "N", default_value_t = 5)]
    pub levels: usize,
    /// Total time T, in the mesh's length² (default N·4h², h the voxel size: each level smooths
    /// away features of about 2h more radius).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// The motion between levels.
    #[arg(long, value_enum, default_value_t = VelocityName::Vpmcf)]
    pub velocity: VelocityName,
    /// Speed of `expand` and `inpaint`, in the mesh's length per unit time (default 0).
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub c: Option<f64>,
    /// Largest time step, in the mesh's length² (default 2h²); each level takes a whole number
    /// of equal steps.
    #[arg(long, value_name = "DT", allow_negative_numbers = true)]
    pub dt: Option<f64>,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Write each scale S_0..S_N as DIR/level_K.ply (S_K, K ≥ 1, with the per-vertex scalar
    /// `detail` = w_K; see --levels-format).
    #[arg(long, value_name = "DIR")]
    pub levels_dir: Option<PathBuf>,
    /// File format of the --levels-dir scales: ply (for MeshLab), vtp (VTK XML PolyData, for
    /// ParaView and 3D Slicer) or vtk (legacy VTK); the detail is a point-data array in the last
    /// two.
    #[arg(long, value_name = "EXT", default_value = "ply")]
    pub levels_format: String,
    /// Write DIR/details_histograms.png (w_i in units of h, one panel per level) and
    /// DIR/levels_strip.png (S_0..S_N coloured by w_i).
    #[arg(long, value_name = "DIR")]
    pub figures: Option<PathBuf>,
    /// Also measure, per level, the level-set reconstruction of S_{i−1} from the exact φ_i in
    /// one step (the paper's Figure 1 measure): the Hausdorff and mean distances between the
    /// two zero level sets, from SAMPLES area samples per surface (default 1000000) and every
    /// vertex. Keeps every level's grid in memory.
    #[arg(long, value_name = "SAMPLES", num_args = 0..=1, default_missing_value = "1000000")]
    pub measure_rebuilds: Option<usize>,
}

#[derive(serde::Serialize)]
struct LevelJson {
    level: usize,
    /// t_i, length².
    time: f64,
    samples: usize,
    /// Mean |w_i|, in units of h.
    mean_abs_detail: f64,
    /// Fraction of |w_i| < 0.1h.
    sparse_fraction: f64,
    /// Samples whose projection did not converge.
    unconverged: usize,
    volume: f64,
    area: f64,
    /// Mean |κ| at the samples, in units of 1/h (decreasing as the levels get smoother).
    mean_abs_curvature: f64,
    /// With `--measure-rebuilds`: Hausdorff(S_{i−1}, S̃_{i−1}), S̃_{i−1} rebuilt from φ_i, in h.
    #[serde(skip_serializing_if = "Option::is_none")]
    rebuild_hausdorff_h: Option<f64>,
    /// With `--measure-rebuilds`: their mean distance, in h.
    #[serde(skip_serializing_if = "Option::is_none")]
    rebuild_mean_h: Option<f64>,
}

#[derive(serde::Serialize)]
struct Timings {
    read: f64,
    voxelize: f64,
    decompose: f64,
    write: f64,
}

#[derive(serde::Serialize)]
struct DecomposeOutput {
    voxel: f64,
    velocity: &'static str,
    c: Option<f64>,
    time: f64,
    dt: f64,
    steps_per_level: usize,
    grid: GridJson,
    vertices: usize,
    samples: usize,
    levels: Vec<LevelJson>,
    output: String,
    files: Vec<String>,
    timings: Timings,
}

/// f32 grids of the padded grid `decompose` holds at once: the motion's, φ_0 and φ_T.
const DECOMPOSE_GRIDS: usize = 6;

/// The name of a velocity on the command line.
pub(super) fn velocity_name(v: VelocityName) -> String {
    v.to_possible_value()
        .map_or_else(String::new, |p| p.get_name().to_string())
}

pub fn run(ctx: &Context, args: &DecomposeArgs) -> anyhow::Result<()> {
    let is_npz = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npz"));
    anyhow::ensure!(
        is_npz,
        "{}: the archive must be a .npz file",
        args.output.display()
    );
    let levels_ext = args.levels_format.to_ascii_lowercase();
    anyhow::ensure!(
        matches!(levels_ext.as_str(), "ply" | "vtp" | "vtk"),
        "--levels-format must be ply, vtp or vtk, got {:?}",
        args.levels_format
    );
    let dirs: Vec<&Path> = args
        .levels_dir
        .iter()
        .chain(&args.figures)
        .map(|p| &**p)
        .collect();
    let mut outputs = Outputs::new(&[&args.output], &dirs)?;
    let velocity = Velocity::from_name(&velocity_name(args.velocity), args.c)?;
    if args.measure_rebuilds == Some(0) {
        anyhow::bail!("--measure-rebuilds needs at least 1 sample per surface");
    }
    if let Some(samples) = args.measure_rebuilds {
        super::budget::check_samples("--measure-rebuilds", samples, ctx.max_memory)?;
    }
    let mut opts = DecomposeOptions {
        levels: args.levels,
        time: args.time,
        velocity,
        dt: args.dt,
        keep_level_sets: args.measure_rebuilds.is_some(),
        ..Default::default()
    };
    // The level count is checked before any work (the rest of the schedule needs h).
    if args.levels == 0 {
        level_schedule(&opts, 1.0).map_err(|e| anyhow::anyhow!("{}: {e}", args.mesh.display()))?;
    }
    let grid_opts = args.grid.options(ctx);
    let Voxelized {
        mesh,
        mut spec,
        phi,
        read_s,
        voxelize_s,
        bar,
        ..
    } = load_and_voxelize(ctx, &args.mesh, &args.grid)?;
    let h = spec.voxel();
    let (time, dt, steps) =
        level_schedule(&opts, h).map_err(|e| anyhow::anyhow!("{}: {e}", args.mesh.display()))?;
    opts.time = Some(time);
    let phi = pad_for_motion(
        &args.mesh,
        &mut spec,
        phi,
        &grid_opts,
        &MotionRoom {
            velocity,
            time,
            step: dt,
        },
        &opts.flow,
        "decomposing",
    )?;
    // The motion's grids, φ_0 and φ_T beside them, and every level's with --measure-rebuilds.
    let kept = if opts.keep_level_sets {
        args.levels.saturating_add(1)
    } else {
        0
    };
    let held = DECOMPOSE_GRIDS.saturating_add(kept);
    let [nx, ny, nz] = spec.dims;
    super::budget::check(
        &format!(
            "{}: decomposing on a {nx}×{ny}×{nz} grid ({held} grids)",
            args.mesh.display()
        ),
        grid_memory_bytes(spec.dims, held),
        ctx.max_memory,
        "use a coarser --voxel, fewer --levels, or ",
    )?;

    if !bar.is_hidden() {
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} {msg} [{bar:30}] {pos}/{len} steps ({elapsed})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.set_length((args.levels * steps) as u64);
    }
    bar.set_message(format!("decomposing ({velocity})"));
    let t = Instant::now();
    let levels = args.levels;
    let d = decompose(&mesh, phi, &opts, |level, _| {
        bar.set_message(format!("decomposing ({velocity}), level {level}/{levels}"));
        bar.inc(1);
    })
    .map_err(|e| anyhow::anyhow!("{}: {e}", args.mesh.display()))?;
    let decompose_s = t.elapsed().as_secs_f64();
    let msr = &d.msr;

    // Everything that can fail is computed before the first write.
    let rebuilds = match args.measure_rebuilds {
        Some(samples) => {
            bar.set_message(format!("measuring the rebuild of level 1/{levels}"));
            let measured = measure_level_rebuilds(&d, &SurfaceDistanceOptions { samples }, |i| {
                bar.set_message(format!(
                    "measuring the rebuild of level {}/{levels}",
                    (i + 1).min(levels)
                ));
            })
            .map_err(|e| anyhow::anyhow!("{}: {e}", args.mesh.display()))?;
            Some(measured)
        }
        None => None,
    };
    bar.set_message("preparing the outputs");
    let scales: Vec<TriMesh> = if args.levels_dir.is_some() || args.figures.is_some() {
        (0..=msr.levels()).map(|k| msr.mesh_at(k)).collect()
    } else {
        Vec::new()
    };
    let vertex_details: Vec<&[f64]> = msr
        .normal_details
        .iter()
        .map(|w| &w[..msr.num_vertices])
        .collect();
    let figures = match &args.figures {
        Some(_) => Some(draw_figures(msr, &scales, &vertex_details, h)?),
        None => None,
    };

    let t = Instant::now();
    bar.set_message("writing");
    let mut files = Vec::new();
    outputs.write(&args.output, |p| write_msr(p, msr))?;
    if let Some(dir) = &args.levels_dir {
        outputs.create_dir(dir)?;
        for (k, scale) in scales.iter().enumerate() {
            let path = dir.join(format!("level_{k}.{levels_ext}"));
            let detail: Vec<f32>;
            let scalars: Vec<(&str, &[f32])> = if k == 0 {
                Vec::new()
            } else {
                detail = vertex_details[k - 1].iter().map(|&w| w as f32).collect();
                vec![("detail", &detail[..])]
            };
            outputs.write(&path, |p| write_mesh_with_scalars(p, scale, &scalars))?;
            files.push(path.display().to_string());
        }
    }
    if let (Some(dir), Some((histograms, strip))) = (&args.figures, &figures) {
        outputs.create_dir(dir)?;
        for (name, image) in [
            ("details_histograms.png", histograms),
            ("levels_strip.png", strip),
        ] {
            let path = dir.join(name);
            outputs.write(&path, |p| write_png(p, image))?;
            files.push(path.display().to_string());
        }
    }
    outputs.commit()?;
    let write_s = t.elapsed().as_secs_f64();
    bar.finish_and_clear();

    let out = DecomposeOutput {
        voxel: h,
        velocity: velocity.name(),
        c: velocity.speed(),
        time,
        dt,
        steps_per_level: steps,
        grid: GridJson::of(&spec),
        vertices: msr.num_vertices,
        samples: msr.samples.len(),
        levels: d
            .reports
            .iter()
            .map(|r| LevelJson {
                level: r.level,
                time: r.time,
                samples: r.samples,
                mean_abs_detail: r.mean_abs_detail / h,
                sparse_fraction: r.sparse_fraction,
                unconverged: r.unconverged,
                volume: r.volume,
                area: r.area,
                mean_abs_curvature: r.mean_abs_curvature * h,
                rebuild_hausdorff_h: rebuilds.as_ref().map(|m| m[r.level - 1].hausdorff / h),
                rebuild_mean_h: rebuilds.as_ref().map(|m| m[r.level - 1].mean_distance / h),
            })
            .collect(),
        output: args.output.display().to_string(),
        files,
        timings: Timings {
            read: read_s,
            voxelize: voxelize_s,
            decompose: decompose_s,
            write: write_s,
        },
    };
    if ctx.json {
        return print_json(&out);
    }
    let [nx, ny, nz] = spec.dims;
    println!(
        "{}: {levels} levels of {velocity} to T = {time} ({steps} steps of {dt} per level) on a \
         {nx}×{ny}×{nz} grid, voxel h = {h} (file units); {} samples ({} vertices); decompose \
         {decompose_s:.2} s",
        args.output.display(),
        out.samples,
        out.vertices
    );
    let measured = rebuilds.is_some();
    println!(
        "{:>5}  {:<11}  {:>10}  {:>8}  {:<14}  {:<14}  {:>10}{}",
        "level",
        "t",
        "mean |w|/h",
        "|w|<0.1h",
        "volume",
        "area",
        "mean |κ|·h",
        if measured {
            "  Hausdorff(S_{i-1}, S̃_{i-1} from φ_i)/h, mean/h"
        } else {
            ""
        }
    );
    for l in &out.levels {
        let rebuild = match (l.rebuild_hausdorff_h, l.rebuild_mean_h) {
            (Some(d), Some(m)) => format!("  {d:>38.3}  {m:.4}"),
            _ => String::new(),
        };
        println!(
            "{:>5}  {:<11.5}  {:>10.4}  {:>7.1}%  {:<14.6}  {:<14.6}  {:>10.4}{rebuild}",
            l.level,
            l.time,
            l.mean_abs_detail,
            100.0 * l.sparse_fraction,
            l.volume,
            l.area,
            l.mean_abs_curvature
        );
    }
    for f in &out.files {
        println!("wrote {f}");
    }
    Ok(())
}

/// The detail histograms per level and the strip of S_0..S_N coloured by w_k / h (one camera,
/// along the shortest side of S_0).
fn draw_figures(
    msr: &crate::msr::Msr,
    scales: &[TriMesh],
    vertex_details: &[&[f64]],
    h: f64,
) -> anyhow::Result<(RgbImage, RgbImage)> {
    let levels: Vec<(String, Vec<f64>)> = (1..=msr.levels())
        .map(|i| (format!("level {i}"), msr.level_normal_details(i)))
        .collect();
    let histograms = histogram_grid(
        &levels,
        &HistogramOptions {
            unit: h,
            columns: levels.len().min(5),
            ..Default::default()
        },
    )?
    .image;
    let in_h: Vec<Vec<f64>> = vertex_details
        .iter()
        .map(|w| w.iter().map(|x| x / h).collect())
        .collect();
    let titles: Vec<String> = (0..scales.len()).map(|k| format!("S_{k}")).collect();
    let panels: Vec<Panel> = scales
        .iter()
        .enumerate()
        .map(|(k, mesh)| Panel {
            mesh,
            scalars: k.checked_sub(1).map(|i| &in_h[i][..]),
            title: &titles[k],
        })
        .collect();
    let mut strip_opts = StripOptions {
        colorbar: Some("detail w / h".to_string()),
        ..Default::default()
    };
    strip_opts.panel.camera = scales
        .first()
        .map_or_else(Camera::default, Camera::along_shortest_axis);
    let strip = render_strip(&panels, &strip_opts)?;
    Ok((histograms, strip))
}
