//! `vesselmsr centerline MESH -o CL.json|CL.vtp`: the centreline graph of a vessel mesh (points,
//! inscribed radius, tangent, branch ids, junctions, endpoints), as JSON or as VTK PolyData
//! (one polyline per branch, for ParaView and 3D Slicer).

use super::grid_args::GridArgs;
use super::outputs::Outputs;
use super::{print_json, progress, Context};
use crate::centerline::extract::CenterlineTimings;
use crate::centerline::{compute_centerline, Centerline, CenterlineOptions};
use crate::io::{read_centerline_json, read_mesh, write_centerline_json, write_centerline_vtp};
use crate::report::centerline_plot::centerline_picture;
use crate::report::image::write_png;
use crate::TriMesh;
use anyhow::Context as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, clap::Args)]
pub struct CenterlineArgs {
    /// Input mesh (.stl, .obj, .ply, .vtp or .vtk), closed or with open vessel ends.
    pub mesh: PathBuf,
    /// Output: .json (every point, radius, tangent, branch, junction, endpoint) or .vtp.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also draw the centreline over the mesh (PNG): three views along the axes.
    #[arg(long, value_name = "CL.png")]
    pub picture: Option<PathBuf>,
    #[command(flatten)]
    pub grid: GridArgs,
}

/// What `--json` prints: the centreline without its points, and where it went.
#[derive(serde::Serialize)]
struct Summary<'a> {
    mesh: &'a Path,
    voxel: f64,
    components: usize,
    total_length: f64,
    branches: Vec<BranchSummary>,
    junctions: &'a [crate::centerline::Junction],
    endpoints: &'a [crate::centerline::Endpoint],
    notices: &'a [String],
    output: Option<&'a Path>,
    timings: Timings,
}

#[derive(serde::Serialize)]
struct BranchSummary {
    id: usize,
    component: usize,
    length: f64,
    points: usize,
    mean_radius: f64,
    min_radius: f64,
    start: crate::centerline::EndKind,
    end: crate::centerline::EndKind,
}

#[derive(serde::Serialize)]
struct Timings {
    read: f64,
    #[serde(flatten)]
    steps: CenterlineTimings,
    write: f64,
    total: f64,
}

/// The output file's format, by extension.
enum Format {
    Json,
    Vtp,
}

fn output_format(path: &Path) -> anyhow::Result<Format> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("json") => Ok(Format::Json),
        Some("vtp") => Ok(Format::Vtp),
        _ => anyhow::bail!(
            "{}: unknown centreline format (expected extension .json or .vtp)",
            path.display()
        ),
    }
}

/// Where `profile` and `stenosis` get their centreline: a file, or computed from the mesh.
#[derive(Debug, clap::Args)]
pub struct CenterlineSource {
    /// Input mesh (.stl, .obj, .ply, .vtp or .vtk).
    pub mesh: PathBuf,
    /// A centreline written by `vesselmsr centerline -o CL.json` (default: computed).
    #[arg(long, value_name = "CL.json")]
    pub centerline: Option<PathBuf>,
    #[command(flatten)]
    pub grid: GridArgs,
}

/// The mesh and its centreline, read from `--centerline` or computed (notices printed).
pub fn centerline_for(
    ctx: &Context,
    src: &CenterlineSource,
) -> anyhow::Result<(TriMesh, Centerline)> {
    match &src.centerline {
        Some(path) => Ok((read_mesh(&src.mesh)?, read_centerline_json(path)?)),
        None => {
            let (mesh, cl, _, _) = load_centerline(ctx, &src.mesh, &src.grid)?;
            print_notices(ctx, &src.mesh, &cl);
            Ok((mesh, cl))
        }
    }
}

/// Reads a mesh and computes its centreline with the grid flags, errors naming the file.
pub fn load_centerline(
    ctx: &Context,
    mesh_path: &Path,
    grid: &GridArgs,
) -> anyhow::Result<(TriMesh, Centerline, CenterlineTimings, f64)> {
    let t = Instant::now();
    let mesh = read_mesh(mesh_path)?;
    let read_s = t.elapsed().as_secs_f64();
    let opts = CenterlineOptions {
        grid: grid.options(ctx),
        ..CenterlineOptions::default()
    };
    let (cl, timings) =
        compute_centerline(&mesh, &opts).with_context(|| format!("{}", mesh_path.display()))?;
    Ok((mesh, cl, timings, read_s))
}

/// Prints the centreline's notices on stderr (unless quiet).
pub fn print_notices(ctx: &Context, mesh_path: &Path, cl: &Centerline) {
    for n in &cl.notices {
        ctx.notice(&format!("{}: {n}", mesh_path.display()));
    }
}

pub fn run(ctx: &Context, args: &CenterlineArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let format = args.output.as_deref().map(output_format).transpose()?;
    let targets: Vec<&Path> = args
        .output
        .iter()
        .chain(&args.picture)
        .map(|p| &**p)
        .collect();
    let mut outputs = Outputs::new(&targets, &[])?;
    let bar = progress::spinner(ctx.quiet, "tracing the centreline");
    let (mesh, cl, steps, read_s) = load_centerline(ctx, &args.mesh, &args.grid)?;
    let picture = match &args.picture {
        Some(_) => Some(centerline_picture(&mesh, &cl, (480, 480))?),
        None => None,
    };
    bar.finish_and_clear();
    print_notices(ctx, &args.mesh, &cl);
    let t = Instant::now();
    if let (Some(path), Some(format)) = (&args.output, format) {
        outputs.write(path, |p| match format {
            Format::Json => write_centerline_json(p, &cl),
            Format::Vtp => write_centerline_vtp(p, &cl),
        })?;
    }
    if let (Some(path), Some(image)) = (&args.picture, &picture) {
        outputs.write(path, |p| write_png(p, image))?;
    }
    outputs.commit()?;
    let write_s = t.elapsed().as_secs_f64();
    let summary = Summary {
        mesh: &args.mesh,
        voxel: cl.voxel,
        components: cl.components,
        total_length: cl.total_length(),
        branches: cl
            .branches
            .iter()
            .map(|b| BranchSummary {
                id: b.id,
                component: b.component,
                length: b.length,
                points: b.points.len(),
                mean_radius: b.radius.iter().sum::<f64>() / b.radius.len().max(1) as f64,
                min_radius: b.radius.iter().cloned().fold(f64::INFINITY, f64::min),
                start: b.start,
                end: b.end,
            })
            .collect(),
        junctions: &cl.junctions,
        endpoints: &cl.endpoints,
        notices: &cl.notices,
        output: args.output.as_deref(),
        timings: Timings {
            read: read_s,
            steps,
            write: write_s,
            total: start.elapsed().as_secs_f64(),
        },
    };
    if ctx.json {
        return print_json(&summary);
    }
    println!("{}", args.mesh.display());
    println!(
        "{} component(s), {} branch(es), {} junction(s), {} endpoint(s) ({} open), total length {:.4}, voxel {:.4}",
        cl.components,
        cl.branches.len(),
        cl.junctions.len(),
        cl.endpoints.len(),
        cl.endpoints.iter().filter(|e| e.open_end).count(),
        cl.total_length(),
        cl.voxel
    );
    for b in &summary.branches {
        println!(
            "  branch {:>3}: length {:>10.4}  radius mean {:.4} min {:.4}  {:?} -> {:?}",
            b.id, b.length, b.mean_radius, b.min_radius, b.start, b.end
        );
    }
    for p in args.output.iter().chain(&args.picture) {
        println!("wrote {}", p.display());
    }
    Ok(())
}
