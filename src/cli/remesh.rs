//! `vesselmsr remesh MESH -o OUT`: mesh → signed distance grid φ → zero level set by marching
//! cubes, vertices then projected onto the input: a closed, manifold, outward mesh at the
//! grid's resolution (open ends come out closed).

use super::grid_args::{load_and_voxelize, GridArgs, GridJson, Voxelized};
use super::{print_json, Context};
use crate::bvh::MeshBvh;
use crate::io::{write_mesh, MeshFormat};
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::levelset::project::{project_vertices, ProjectOptions};
use crate::mesh::info::{mesh_info, MeshInfo};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, clap::Args)]
pub struct RemeshArgs {
    /// Input mesh (.stl, .obj or .ply).
    pub mesh: PathBuf,
    /// Output mesh (.stl, .obj or .ply).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    #[command(flatten)]
    pub grid: GridArgs,
    /// Keep the marching-cubes vertices where they are, instead of moving them onto the input
    /// surface (within one voxel, away from open ends).
    #[arg(long)]
    pub no_project: bool,
}

#[derive(serde::Serialize)]
struct Timings {
    read: f64,
    voxelize: f64,
    marching_cubes: f64,
    project: f64,
    write: f64,
}

#[derive(serde::Serialize)]
struct RemeshOutput {
    grid: GridJson,
    output: MeshInfo,
    timings: Timings,
}

pub fn run(ctx: &Context, args: &RemeshArgs) -> anyhow::Result<()> {
    MeshFormat::from_path(&args.output)?;
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
    bar.set_message("extracting the surface");
    let t = Instant::now();
    let mut surface = extract_surface(&phi, &ExtractOptions::default())?;
    let mc = t.elapsed().as_secs_f64();
    let t = Instant::now();
    if !args.no_project {
        bar.set_message("projecting onto the input");
        let opts = ProjectOptions {
            max_distance: spec.voxel(),
            ..Default::default()
        };
        project_vertices(&mut surface, &mesh, &MeshBvh::new(&mesh), &opts);
    }
    let project = t.elapsed().as_secs_f64();
    let output = mesh_info(&surface);
    let t = Instant::now();
    write_mesh(&args.output, &surface)?;
    let write = t.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let out = RemeshOutput {
        grid: GridJson::of(&spec),
        output,
        timings: Timings {
            read,
            voxelize: voxelize_s,
            marching_cubes: mc,
            project,
            write,
        },
    };
    if ctx.json {
        return print_json(&out);
    }
    let [nx, ny, nz] = spec.dims;
    println!(
        "{}: {nx}×{ny}×{nz} grid, voxel {} (file units)",
        args.output.display(),
        spec.transform.voxel
    );
    println!("{}", out.output);
    Ok(())
}
