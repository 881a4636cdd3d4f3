//! `vesselmsr repair MESH -o OUT (--region x,y,z,r | --regions FILE | --holes)`: inpaint the
//! damaged regions D of a vessel (paper Section 4, Algorithm 4; see [`crate::inpaint::repair`]),
//! write the repaired watertight mesh, and report the inpainted volume and the stenosis per region.

use super::message::short_number;
use super::outputs::Outputs;
use super::{print_json, progress, Context};
use crate::inpaint::pipeline::{repair_vessel, RepairEvent, RepairedVessel, VesselRepair};
use crate::inpaint::region::parse_ball;
use crate::inpaint::repair::{InpaintMethod, RepairOptions};
use crate::io::{read_mesh, write_atomic, write_mesh, MeshFormat};
use crate::report::repair_picture::{render_repair, RepairPictureOptions};
use crate::report::repair_report::RepairReport;
use crate::report::text::format_figure;
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, clap::Args)]
pub struct RepairArgs {
    /// Input mesh (.stl, .obj, .ply, .vtp or .vtk), in any length unit (mm, cm, m): every length
    /// below is in the same unit.
    pub mesh: PathBuf,
    /// Repaired mesh (.stl, .obj, .ply, .vtp or .vtk); written only if the repair succeeds.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// A region D to inpaint: the ball of centre (x, y, z) and radius r, world units. Repeatable.
    #[arg(long, value_name = "x,y,z,r", allow_hyphen_values = true)]
    pub region: Vec<String>,
    /// A JSON regions file: {"regions": [{"center": [x, y, z], "radius": r}, ...], "points":
    /// [[x, y, z], ...]}, or a 3D Slicer markups file (.mrk.json or .fcsv: its control points
    /// are picked points, turned from RAS into the mesh's LPS when stored in RAS); each picked
    /// surface point becomes a ball of 1.5 healthy vessel radii (the centreline's healthy
    /// reference there; else the local radius), or, picked on a narrowing of 20% or more, that
    /// narrowing's region (as --stenoses gives it).
    #[arg(long, value_name = "FILE")]
    pub regions: Option<PathBuf>,
    /// Every boundary loop of the input that is not an open vessel end (a near-planar loop across
    /// the vessel) becomes a region.
    #[arg(long)]
    pub holes: bool,
    /// Also repair every narrowing the centreline finds of at least P% stenosis against the
    /// normal lumen beyond it (NASCET; default 20): a ball on the centreline at the narrowest
    /// point, 1.5 healthy radii or the lesion's width at half depth plus one healthy radius, the
    /// larger.
    #[arg(long, value_name = "P", num_args = 0..=1, default_missing_value = "20")]
    pub stenoses: Option<f64>,
    /// Voxel size h of the grid around D, world units (default: the voxelize rule on the whole
    /// mesh, min(mean edge / 2, longest side / 256); for flow, msr and paper at least an eighth
    /// of the typical vessel radius 2·volume/area).
    #[arg(long, value_name = "H")]
    pub voxel: Option<f64>,
    /// How D is filled: centerline (the vessel continued across D along its centreline, with
    /// its cross-section carried between the intact sections on either side; default), axial
    /// (the vessel carried across D along a straight axis), flow (v = c + κ_a − κ with the data
    /// outside D restored), msr (a coarse level plus the details transferred across D), paper
    /// (Algorithm 4 on the MSR: MST, IMST with viscosity, copy outside D, repeated).
    #[arg(long, default_value = "centerline", value_name = "METHOD")]
    pub method: String,
    /// Growth speed c of v = c + κ_a − κ (flow, msr, paper), 1/length (default: from the vessel
    /// radius R around D: 0.3/R for flow, 1/R otherwise).
    #[arg(
        short = 'c',
        long = "speed",
        value_name = "C",
        allow_hyphen_values = true
    )]
    pub speed: Option<f64>,
    /// Evolution time T of flow, msr and paper, length² (default R² for flow and paper, R²/2 for
    /// msr).
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub time: Option<f64>,
    /// First viscosity ε of paper, length² (default R²/8; divided by 4 every iteration).
    #[arg(long, value_name = "EPS", allow_hyphen_values = true)]
    pub epsilon: Option<f64>,
    /// Most iterations of paper (default 12).
    #[arg(long, value_name = "N")]
    pub max_iterations: Option<usize>,
    /// Re-mesh the whole vessel instead of keeping the input's triangles outside D.
    #[arg(long)]
    pub no_keep_outside: bool,
    /// Keep the input's open vessel ends open (for flow extensions); by default they are capped.
    #[arg(long)]
    pub open_ends: bool,
    /// Simplify the output by quadric edge collapses, its Hausdorff distance to the undecimated
    /// output held within this many voxels (default 0.5); the report measures what is written.
    #[arg(long, value_name = "VOXELS", num_args = 0..=1, default_missing_value = "0.5")]
    pub decimate: Option<f64>,
    /// Write the full report as JSON to this file.
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// Render the input and the repaired vessel around D side by side as a PNG, the inpainted
    /// region in red.
    #[arg(long, value_name = "P.png")]
    pub picture: Option<PathBuf>,
    /// Name of the file's length unit, used in the report (e.g. mm); coordinates are never
    /// rescaled.
    #[arg(long, value_name = "UNIT", default_value = "file units")]
    pub units: String,
}

pub fn run(ctx: &Context, args: &RepairArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let report = repair_file(ctx, args)?;
    if ctx.json {
        return print_json(&report);
    }
    print_summary(&report, start.elapsed().as_secs_f64());
    Ok(())
}

/// The whole `repair` command but the printing: reads, repairs (the library's
/// [`repair_vessel`], which the Python package calls too), writes the outputs and returns the
/// report (also for `batch`).
pub(super) fn repair_file(ctx: &Context, args: &RepairArgs) -> anyhow::Result<RepairReport> {
    let start = Instant::now();
    MeshFormat::from_path(&args.output)?;
    let targets: Vec<&Path> = std::iter::once(&args.output)
        .chain(&args.report)
        .chain(&args.picture)
        .map(|p| &**p)
        .collect();
    let mut outputs = Outputs::new(&targets, &[])?;
    let method: InpaintMethod = args.method.parse()?;
    let mut request = VesselRepair {
        balls: Vec::new(),
        regions_file: args.regions.clone(),
        holes: args.holes,
        stenoses: args.stenoses,
        decimate: args.decimate,
        units: args.units.clone(),
        options: RepairOptions {
            method,
            voxel: args.voxel,
            keep_outside: !args.no_keep_outside,
            open_ends: args.open_ends,
            speed: args.speed,
            time: args.time,
            epsilon: args.epsilon,
            max_iterations: args
                .max_iterations
                .unwrap_or(RepairOptions::default().max_iterations),
            ..RepairOptions::default()
        },
        max_memory: ctx.max_memory,
        input_path: Some(args.mesh.display().to_string()),
        output_path: Some(args.output.display().to_string()),
    };
    for text in &args.region {
        request.balls.push(parse_ball(text)?);
    }
    // The options before the mesh is read, in the flags' names.
    request.validate().map_err(flag_error)?;
    let mesh = read_mesh(&args.mesh)?;
    let read_secs = start.elapsed().as_secs_f64();
    let mut bar: Option<ProgressBar> = None;
    let repaired = repair_vessel(&mesh, &request, &mut |event| match event {
        RepairEvent::Notice(text) => ctx.notice(text),
        RepairEvent::Stage(stage) => match &bar {
            Some(b) => b.set_message(stage),
            None => bar = Some(progress::spinner(ctx.quiet, stage)),
        },
    })
    .map_err(flag_error)?;
    let RepairedVessel {
        mesh: repaired_mesh,
        mut report,
        balls,
        repair_notices,
    } = repaired;
    report.timings.insert("read".into(), read_secs.into());
    if balls.is_empty() && args.picture.is_some() {
        let n = "no picture written: nothing was inpainted";
        ctx.notice(&format!("{}: {n}", args.mesh.display()));
        report.notices.push(n.into());
    }
    let text = serde_json::to_string_pretty(&report)?;
    outputs.write(&args.output, |p| write_mesh(p, &repaired_mesh))?;
    if let Some(path) = &args.report {
        outputs.write(path, |path| {
            write_atomic(path, |out| {
                out.write_all(text.as_bytes())
                    .and_then(|_| out.write_all(b"\n"))
                    .map_err(|e| crate::Error::io(path, e))
            })
        })?;
    }
    if let Some(path) = args.picture.as_ref().filter(|_| !balls.is_empty()) {
        // The input as it was, its holes open.
        let opts = RepairPictureOptions {
            added_distance: 0.5 * report.parameters.voxel,
            unit: args.units.clone(),
            figures: picture_figures(&report),
            ..RepairPictureOptions::default()
        };
        outputs.write(path, |p| {
            render_repair(&mesh, &repaired_mesh, &balls, p, &opts)
        })?;
    }
    outputs.commit()?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    for n in &repair_notices {
        ctx.notice(&format!("{}: {n}", args.mesh.display()));
    }
    if let Some(why) = &report.parameters.fallback {
        ctx.notice(&format!(
            "the patch could not be stitched into the kept triangles ({why}); the whole vessel was re-meshed"
        ));
    }
    Ok(report)
}

/// A library error with the option named as its flag (`voxel` → `--voxel`).
fn flag_error(e: crate::Error) -> anyhow::Error {
    match e {
        crate::Error::BadOption {
            option: "regions", ..
        } => anyhow::anyhow!(
            "no region to repair: give --region x,y,z,r, --regions FILE.json, --holes or --stenoses"
        ),
        crate::Error::BadOption { option, problem } => {
            let flag = match option {
                "speed" => "-c/--speed".to_string(),
                other => format!("--{}", other.replace('_', "-")),
            };
            anyhow::anyhow!("{flag} {problem}")
        }
        e => e.into(),
    }
}

/// The report's figures written on the picture: volumes, what was inpainted, the stenosis,
/// watertightness and the method.
fn picture_figures(r: &RepairReport) -> Vec<String> {
    let u = &r.units;
    let inpainted: f64 = r.regions.iter().map(|g| g.inpainted_volume).sum();
    let stenosis = r
        .regions
        .iter()
        .filter_map(|g| g.diameter_stenosis_pct)
        .fold(None, |m: Option<f64>, p| Some(m.map_or(p, |m| m.max(p))));
    vec![
        format!(
            "input volume {} {u}³{}   output volume {} {u}³   inpainted {} {u}³",
            format_figure(r.input.measures.volume),
            if r.input_capped { " (ends capped)" } else { "" },
            format_figure(r.output.measures.volume),
            format_figure(inpainted)
        ),
        format!(
            "stenosis (diameter) {}   watertight {}   method {}{}",
            stenosis.map_or("n/a".to_string(), |p| format!("{p:.0}%")),
            if r.watertight { "yes" } else { "no" },
            r.parameters.method,
            if r.parameters.stitched {
                ", stitched"
            } else {
                ", whole vessel re-meshed"
            }
        ),
    ]
}

fn print_summary(r: &RepairReport, secs: f64) {
    let u = &r.units;
    // Six significant digits (exponent form when tiny): a vessel in metres has volumes of some
    // 1e-6 m³ and radii of 1e-3 m, which fixed decimals print as 0.0000.
    let n = short_number;
    let v = |x: f64| format!("{} {u}³", n(x));
    println!(
        "input   {}: volume {}{}",
        r.input.path.as_deref().unwrap_or("-"),
        v(r.input.measures.volume),
        if r.input_capped {
            " (open ends capped)"
        } else {
            ""
        }
    );
    println!(
        "output  {}: volume {}, {}, {} component(s), {}",
        r.output.path.as_deref().unwrap_or("-"),
        v(r.output.measures.volume),
        if r.watertight {
            "watertight"
        } else {
            "NOT watertight"
        },
        r.output.measures.components,
        if r.parameters.stitched {
            "new patch stitched into the original triangles outside D"
        } else {
            "whole vessel re-meshed"
        }
    );
    for (k, g) in r.regions.iter().enumerate() {
        let pct = |p: Option<f64>| p.map_or("n/a".to_string(), |p| format!("{p:.1}%"));
        println!(
            "region {} ({}, {}, {}) radius {}{}: inpainted {} ({:.2}% of the output); stenosis: diameter {}, area {}, NASCET {}",
            k + 1,
            n(g.center[0]),
            n(g.center[1]),
            n(g.center[2]),
            n(g.radius),
            g.fill.map_or(String::new(), |f| format!(", filled {f}")),
            v(g.inpainted_volume),
            100.0 * g.inpainted_fraction,
            pct(g.diameter_stenosis_pct),
            pct(g.area_stenosis_pct),
            pct(g.nascet_stenosis_pct)
        );
    }
    for l in &r.loops {
        println!(
            "loop at ({}, {}, {}) radius {}: {}",
            n(l.center[0]),
            n(l.center[1]),
            n(l.center[2]),
            n(l.radius),
            l.kind
        );
    }
    // The stitched patch is meshed at twice the voxel on wide vessels (`patch_stride`).
    let patch = if r.parameters.patch_voxel > r.parameters.voxel {
        format!(" (the patch meshed at {} {u})", n(r.parameters.patch_voxel))
    } else {
        String::new()
    };
    println!(
        "method {}, voxel {} {u}{patch}, vessel radius ≈ {} {u}, {} iteration(s){}, {:.1} s",
        r.parameters.method,
        n(r.parameters.voxel),
        n(r.parameters.radius_estimate),
        r.iterations,
        if r.converged { "" } else { " (not converged)" },
        secs
    );
}
