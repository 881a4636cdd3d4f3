//! `vesselmsr repair MESH -o OUT (--region x,y,z,r | --regions FILE | --holes)`: inpaint the
//! damaged regions D of a vessel (paper Section 4, Algorithm 4; see [`crate::inpaint::repair`]),
//! write the repaired watertight mesh, and report the inpainted volume and the stenosis per region.

use super::message::short_number;
use super::outputs::Outputs;
use super::region_limits::check_regions;
use super::repair_budget;
use super::{print_json, progress, Context};
use crate::centerline::healthy::HealthyVessel;
use crate::centerline::stenosis::StenosisFindOptions;
use crate::centerline::{compute_centerline, CenterlineOptions};
use crate::inpaint::guided::GuideKind;
use crate::inpaint::holes::{classify_loops, hole_regions, LoopKind, LoopOptions};
use crate::inpaint::region::{parse_ball, read_regions, Ball};
use crate::inpaint::repair::{repair_with_centerline, InpaintMethod, Repair, RepairOptions};
use crate::io::{read_mesh, write_atomic, write_mesh, MeshFormat};
use crate::mesh::cap::{cap_holes, CapOptions};
use crate::mesh::decimate::{decimate_mesh, DecimateOptions, DecimateReport};
use crate::mesh::info::mesh_info;
use crate::mesh::orient::orient_outward;
use crate::mesh::topology::EdgeMap;
use crate::mesh::units::{check_vessel_scale, VesselScaleOptions};
use crate::report::repair_picture::{render_repair, RepairPictureOptions};
use crate::report::repair_report::{
    region_reports, surface_measures, RegionReport, SurfaceMeasures,
};
use crate::report::text::format_figure;
use crate::TriMesh;
use anyhow::Context as _;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The source of a region from `--stenoses` (the report's `source`).
const DETECTED_STENOSIS: &str = "detected stenosis";

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
    /// reference there; else the local radius).
    #[arg(long, value_name = "FILE")]
    pub regions: Option<PathBuf>,
    /// Every boundary loop of the input that is not an open vessel end (a near-planar loop across
    /// the vessel) becomes a region.
    #[arg(long)]
    pub holes: bool,
    /// Also repair every narrowing the centreline finds of at least P% stenosis against the
    /// normal lumen beyond it (NASCET; default 20): a ball on the centreline at the narrowest point, 1.5 healthy radii or the
    /// lesion's width at half depth plus one healthy radius, the larger.
    #[arg(long, value_name = "P", num_args = 0..=1, default_missing_value = "20")]
    pub stenoses: Option<f64>,
    /// Voxel size h of the grid around D, world units (default: the voxelize rule on the whole
    /// mesh, min(mean edge / 2, longest side / 256)).
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

#[derive(Serialize)]
struct MeshPart {
    path: String,
    #[serde(flatten)]
    measures: SurfaceMeasures,
}

#[derive(Serialize)]
struct LoopReport {
    kind: &'static str,
    center: [f64; 3],
    radius: f64,
    planarity: f64,
}

#[derive(Serialize)]
struct Parameters {
    method: &'static str,
    voxel: f64,
    grid_dims: [usize; 3],
    radius_estimate: f64,
    c: f64,
    time: f64,
    epsilon: f64,
    keep_outside: bool,
    open_ends: bool,
    stitched: bool,
    junctions: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    fallback: Option<String>,
    axes: Vec<[f64; 3]>,
    /// The centreline fill's curves, by kind.
    guides: Vec<GuideKind>,
}

#[derive(Serialize)]
pub(super) struct Report {
    units: String,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    notices: Vec<String>,
    input: MeshPart,
    input_capped: bool,
    output: MeshPart,
    regions: Vec<RegionReport>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    loops: Vec<LoopReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    decimate: Option<DecimateReport>,
    watertight: bool,
    iterations: usize,
    converged: bool,
    parameters: Parameters,
    timings: serde_json::Map<String, serde_json::Value>,
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

/// The whole `repair` command but the printing: reads, repairs, writes the outputs and returns
/// the report (also for `batch`).
pub(super) fn repair_file(ctx: &Context, args: &RepairArgs) -> anyhow::Result<Report> {
    let start = Instant::now();
    MeshFormat::from_path(&args.output)?;
    let targets: Vec<&Path> = std::iter::once(&args.output)
        .chain(&args.report)
        .chain(&args.picture)
        .map(|p| &**p)
        .collect();
    let mut outputs = Outputs::new(&targets, &[])?;
    let method: InpaintMethod = args.method.parse()?;
    for (name, v) in [
        ("-c/--speed", args.speed),
        ("--time", args.time),
        ("--epsilon", args.epsilon),
    ] {
        if let Some(v) = v {
            anyhow::ensure!(v.is_finite() && v > 0.0, "{name} must be > 0, got {v}");
        }
    }
    if let Some(v) = args.decimate {
        anyhow::ensure!(
            v.is_finite() && v > 0.0,
            "--decimate must be a positive number of voxels, got {v}"
        );
    }
    if let Some(v) = args.voxel {
        anyhow::ensure!(
            v.is_finite() && v > 0.0,
            "--voxel must be a positive length, got {v}"
        );
    }
    anyhow::ensure!(
        !args.region.is_empty() || args.regions.is_some() || args.holes || args.stenoses.is_some(),
        "no region to repair: give --region x,y,z,r, --regions FILE.json, --holes or --stenoses"
    );
    if let Some(p) = args.stenoses {
        anyhow::ensure!(
            p.is_finite() && (0.0..100.0).contains(&p),
            "--stenoses must be a percentage from 0 to below 100, got {p}"
        );
    }
    let mut balls: Vec<Ball> = Vec::new();
    let mut sources: Vec<String> = Vec::new();
    for text in &args.region {
        balls.push(parse_ball(text)?);
        sources.push("region".into());
    }
    let mesh = read_mesh(&args.mesh)?;
    let read_secs = start.elapsed().as_secs_f64();
    let mut notices = Vec::new();
    if let Some(n) = check_vessel_scale(&mesh, &args.units, &VesselScaleOptions::default()) {
        notices.push(n);
    }
    // The input's centreline: healthy radii for picked points, detected narrowings, and the
    // stenosis measured along it in the report.
    let centerline_start = Instant::now();
    let healthy = match compute_centerline(&mesh, &CenterlineOptions::default()) {
        Ok((cl, _)) => Some(HealthyVessel::new(
            &mesh,
            cl,
            &StenosisFindOptions::default(),
        )),
        Err(e) => {
            ctx.notice(&format!(
                "{}: no centreline ({e}); regions are sized and measured without it",
                args.mesh.display()
            ));
            None
        }
    };
    let centerline_secs = centerline_start.elapsed().as_secs_f64();
    if let Some(path) = &args.regions {
        let radius = |p: &nalgebra::Point3<f64>| healthy.as_ref().and_then(|h| h.healthy_radius(p));
        for b in read_regions(path, &mesh, &radius)? {
            balls.push(b);
            sources.push(format!("regions file {}", path.display()));
        }
    }
    if let Some(p) = args.stenoses {
        let found = healthy
            .as_ref()
            .map(|h| h.lesion_regions(p))
            .unwrap_or_default();
        if found.is_empty() {
            notices.push(format!("no narrowing of {p}% or more found"));
        }
        for b in found {
            balls.push(b);
            sources.push(DETECTED_STENOSIS.into());
        }
    }
    let mut loops = Vec::new();
    if args.holes {
        let infos = classify_loops(&mesh, &LoopOptions::default());
        if infos.iter().any(|l| l.kind == LoopKind::Hole) {
            let (holes, _) = hole_regions(&mesh, &LoopOptions::default())
                .with_context(|| format!("{}: --holes", args.mesh.display()))?;
            for b in holes {
                balls.push(b);
                sources.push("hole".into());
            }
        } else {
            notices.push(if infos.is_empty() {
                "no holes found (the mesh is closed): nothing to inpaint".to_string()
            } else {
                format!(
                    "no holes found ({} boundary loop(s), all open vessel ends): nothing to inpaint{}",
                    infos.len(),
                    if args.open_ends { "" } else { "; the ends are capped" }
                )
            });
        }
        loops = infos
            .iter()
            .map(|l| LoopReport {
                kind: match l.kind {
                    LoopKind::End => "open vessel end",
                    LoopKind::Hole => "hole",
                },
                center: [l.center.x, l.center.y, l.center.z],
                radius: l.radius,
                planarity: l.planarity,
            })
            .collect();
    }
    // Asked to find holes or narrowings and none found: the mesh is written as it is (ends
    // capped), with a report saying so, exit 0 (a script over a cohort goes on).
    let nothing_to_do = (args.holes || args.stenoses.is_some()) && balls.is_empty();
    if nothing_to_do && args.picture.is_some() {
        notices.push("no picture written: nothing was inpainted".into());
    }
    if !nothing_to_do {
        let mesh_name = args.mesh.display().to_string();
        check_regions(ctx, &mesh, &mesh_name, &mut balls, &mut sources)?;
    }
    for n in &notices {
        ctx.notice(&format!("{}: {n}", args.mesh.display()));
    }
    let opts = RepairOptions {
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
        intact_lumen: sources.iter().map(|s| s == DETECTED_STENOSIS).collect(),
        ..RepairOptions::default()
    };
    repair_budget::check(&mesh, &balls, &opts, ctx.max_memory)
        .with_context(|| args.mesh.display().to_string())?;
    let bar = progress::spinner(ctx.quiet, "repairing");
    let mut result = if nothing_to_do {
        unrepaired(&mesh, &opts)
    } else {
        repair_with_centerline(
            &mesh,
            &balls,
            &opts,
            healthy.as_ref().map(|h| &h.centerline),
        )
    }
    .with_context(|| format!("{}: repair failed", args.mesh.display()))?;
    let decimate = match args.decimate {
        Some(voxels) if result.voxel > 0.0 => {
            bar.set_message("decimating");
            let (lean, done) = decimate_mesh(
                &result.mesh,
                &DecimateOptions {
                    max_distance: voxels * result.voxel,
                    ..DecimateOptions::default()
                },
            );
            result.mesh = lean;
            Some(done)
        }
        _ => None,
    };
    bar.set_message("measuring");
    let measure_start = Instant::now();
    let regions = region_reports(
        &result.closed_input,
        &result.mesh,
        &balls,
        &sources,
        healthy.as_ref(),
    );
    let info = mesh_info(&result.mesh);
    let input_info = mesh_info(&result.closed_input);
    let measure_secs = measure_start.elapsed().as_secs_f64();
    let mut timings = serde_json::Map::new();
    timings.insert("read".into(), read_secs.into());
    timings.insert("centerline".into(), centerline_secs.into());
    for (name, secs) in &result.timings {
        timings.insert(name.clone(), (*secs).into());
    }
    timings.insert("report".into(), measure_secs.into());
    notices.extend(result.notices.iter().cloned());
    let report = Report {
        units: args.units.clone(),
        notices,
        input: MeshPart {
            path: args.mesh.display().to_string(),
            measures: surface_measures(&input_info),
        },
        input_capped: result.closed_input.num_faces() != mesh.num_faces(),
        output: MeshPart {
            path: args.output.display().to_string(),
            measures: surface_measures(&info),
        },
        regions,
        loops,
        decimate,
        watertight: info.watertight,
        iterations: result.iterations,
        converged: result.converged,
        parameters: Parameters {
            method: method.as_str(),
            voxel: result.voxel,
            grid_dims: result.grid_dims,
            radius_estimate: result.radius_estimate,
            c: result.speed,
            time: result.time,
            epsilon: result.epsilon,
            keep_outside: opts.keep_outside,
            open_ends: opts.open_ends,
            stitched: result.stitched,
            junctions: result.junctions,
            fallback: result.fallback.clone(),
            axes: result.axes.clone(),
            guides: result.guides.clone(),
        },
        timings,
    };
    anyhow::ensure!(
        info.watertight || args.open_ends,
        "{}: the repaired mesh is not watertight ({}); nothing written",
        args.mesh.display(),
        info.leaks().join(", ")
    );
    let text = serde_json::to_string_pretty(&report)?;
    outputs.write(&args.output, |p| write_mesh(p, &result.mesh))?;
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
            added_distance: 0.5 * result.voxel,
            unit: args.units.clone(),
            figures: picture_figures(&report),
            ..RepairPictureOptions::default()
        };
        outputs.write(path, |p| {
            render_repair(&mesh, &result.mesh, &balls, p, &opts)
        })?;
    }
    outputs.commit()?;
    bar.finish_and_clear();
    for n in &result.notices {
        ctx.notice(&format!("{}: {n}", args.mesh.display()));
    }
    if let Some(why) = &result.fallback {
        ctx.notice(&format!(
            "the patch could not be stitched into the kept triangles ({why}); the whole vessel was re-meshed"
        ));
    }
    Ok(report)
}

/// The outcome of `--holes` on a mesh without holes: the input, its open ends capped unless
/// they are kept open, outward; nothing inpainted.
fn unrepaired(mesh: &TriMesh, opts: &RepairOptions) -> crate::Result<Repair> {
    let start = Instant::now();
    let closed_input = if opts.open_ends || EdgeMap::new(mesh).boundary_edges() == 0 {
        mesh.clone()
    } else {
        cap_holes(mesh, &CapOptions::default())?.0
    };
    let mut output = closed_input.clone();
    if !opts.open_ends {
        orient_outward(&mut output);
    }
    Ok(Repair {
        mesh: output,
        closed_input,
        voxel: 0.0,
        grid_dims: [0; 3],
        radius_estimate: 0.0,
        speed: 0.0,
        time: 0.0,
        epsilon: 0.0,
        axes: Vec::new(),
        junctions: 0,
        iterations: 0,
        converged: true,
        stitched: false,
        fallback: None,
        guides: Vec::new(),
        notices: Vec::new(),
        timings: vec![("cap".into(), start.elapsed().as_secs_f64())],
    })
}

/// The report's figures written on the picture: volumes, what was inpainted, the stenosis,
/// watertightness and the method.
fn picture_figures(r: &Report) -> Vec<String> {
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

fn print_summary(r: &Report, secs: f64) {
    let u = &r.units;
    // Six significant digits (exponent form when tiny): a vessel in metres has volumes of some
    // 1e-6 m³ and radii of 1e-3 m, which fixed decimals print as 0.0000.
    let n = short_number;
    let v = |x: f64| format!("{} {u}³", n(x));
    println!(
        "input   {}: volume {}{}",
        r.input.path,
        v(r.input.measures.volume),
        if r.input_capped {
            " (open ends capped)"
        } else {
            ""
        }
    );
    println!(
        "output  {}: volume {}, {}, {} component(s), {}",
        r.output.path,
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
            "region {} ({}, {}, {}) radius {}: inpainted {} ({:.2}% of the output); stenosis: diameter {}, area {}, NASCET {}",
            k + 1,
            n(g.center[0]),
            n(g.center[1]),
            n(g.center[2]),
            n(g.radius),
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
    println!(
        "method {}, voxel {} {u}, vessel radius ≈ {} {u}, {} iteration(s){}, {:.1} s",
        r.parameters.method,
        n(r.parameters.voxel),
        n(r.parameters.radius_estimate),
        r.iterations,
        if r.converged { "" } else { " (not converged)" },
        secs
    );
}
