//! `vesselmsr remesh MESH -o OUT`: mesh → signed distance grid φ → zero level set by marching
//! cubes (enclosed cavities the input does not have reopened), vertices then projected onto the
//! input and edges split where the surface is still off it: a closed, manifold, outward mesh at
//! the grid's resolution (open ends come out closed, flat, as `cap` closes them); `--decimate`
//! then simplifies it within half a voxel (`mesh::decimate`). The work after voxelization is the
//! library's `levelset::remesh::remesh_levelset`, which the Python package's `remesh` calls too.

use super::grid_args::{load_and_voxelize, GridArgs, Voxelized};
use super::outputs::Outputs;
use super::{print_json, Context};
use crate::io::{write_mesh, MeshFormat};
use crate::levelset::remesh::{
    remesh_levelset, RemeshEvent, RemeshOptions, RemeshReport, Remeshed,
};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, clap::Args)]
pub struct RemeshArgs {
    /// Input mesh (.stl, .obj, .ply, .vtp or .vtk).
    pub mesh: PathBuf,
    /// Output mesh (.stl, .obj, .ply, .vtp or .vtk).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Keep the marching-cubes surface as it is, instead of moving its vertices onto the input
    /// surface (its open ends capped; within one voxel) and splitting the edges whose midpoints
    /// stay farther than 0.05 voxel from it.
    #[arg(long)]
    pub no_project: bool,
    /// Simplify the output by quadric edge collapses, its Hausdorff distance to the undecimated
    /// output held within this many voxels (default 0.5); far fewer triangles.
    #[arg(long, value_name = "VOXELS", num_args = 0..=1, default_missing_value = "0.5")]
    pub decimate: Option<f64>,
}

#[derive(serde::Serialize)]
struct Timings {
    read: f64,
    voxelize: f64,
    marching_cubes: f64,
    project: f64,
    decimate: f64,
    write: f64,
}

#[derive(serde::Serialize)]
pub(super) struct RemeshOutput {
    /// grid, output, cavities_joined, edges_split and decimate (when asked for).
    #[serde(flatten)]
    report: RemeshReport,
    timings: Timings,
}

pub fn run(ctx: &Context, args: &RemeshArgs) -> anyhow::Result<()> {
    let out = remesh_file(ctx, args)?;
    if ctx.json {
        return print_json(&out);
    }
    let [nx, ny, nz] = out.report.grid.dims;
    println!(
        "{}: {nx}×{ny}×{nz} grid, voxel {} (file units)",
        args.output.display(),
        out.report.grid.voxel
    );
    println!("{}", out.report.output);
    Ok(())
}

/// The whole `remesh` command but the printing: reads, re-meshes, writes the output and returns
/// what `--json` prints (also for `batch`).
pub(super) fn remesh_file(ctx: &Context, args: &RemeshArgs) -> anyhow::Result<RemeshOutput> {
    MeshFormat::from_path(&args.output)?;
    if let Some(v) = args.decimate {
        anyhow::ensure!(
            v.is_finite() && v > 0.0,
            "--decimate must be a positive number of voxels, got {v}"
        );
    }
    let mut outputs = Outputs::new(&[&args.output], &[])?;
    // Marching cubes reads φ only next to its zero level set: the narrow band is enough.
    let Voxelized {
        mesh,
        spec,
        phi,
        read_s: read,
        voxelize_s,
        bar,
        ..
    } = load_and_voxelize(ctx, &args.mesh, &args.grid)?;
    let opts = RemeshOptions {
        project: !args.no_project,
        decimate: args.decimate,
        ..RemeshOptions::default()
    };
    let Remeshed {
        mesh: surface,
        report,
        timings,
    } = remesh_levelset(&mesh, &spec, phi, &opts, &mut |event| match event {
        RemeshEvent::Stage(stage) => bar.set_message(stage),
        RemeshEvent::Notice(text) => bar.suspend(|| ctx.notice(text)),
    })?;
    let t = Instant::now();
    outputs.write(&args.output, |p| write_mesh(p, &surface))?;
    outputs.commit()?;
    let write = t.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let out = RemeshOutput {
        report,
        timings: Timings {
            read,
            voxelize: voxelize_s,
            marching_cubes: timings.marching_cubes,
            project: timings.project,
            decimate: timings.decimate,
            write,
        },
    };
    Ok(out)
}
