//! `vesselmsr remesh MESH -o OUT`: mesh → signed distance grid φ → zero level set by marching
//! cubes (enclosed cavities the input does not have reopened), vertices then projected onto the
//! input and edges split where the surface is still off it: a closed, manifold, outward mesh at
//! the grid's resolution (open ends come out closed); `--decimate` then simplifies it within half
//! a voxel (`mesh::decimate`).

use super::grid_args::{load_and_voxelize, GridArgs, GridJson, Voxelized};
use super::outputs::Outputs;
use super::{print_json, Context};
use crate::bvh::MeshBvh;
use crate::io::{write_mesh, MeshFormat};
use crate::levelset::cavity::{extract_joining_cavities, find_cavities, CavityOptions};
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::levelset::project::{project_vertices, ProjectOptions};
use crate::levelset::refine::{refine_to_surface, remesh_refine_options, RefineReport};
use crate::mesh::decimate::{decimate_mesh, DecimateOptions, DecimateReport};
use crate::mesh::info::{mesh_info, MeshInfo};
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
    /// surface (within one voxel, away from open ends) and splitting the edges whose midpoints
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
    grid: GridJson,
    output: MeshInfo,
    /// Enclosed cavities of the extraction reopened to the outside (folds narrower than h).
    cavities_joined: usize,
    /// Edges split to bring the surface within 0.05 voxel of the input.
    edges_split: usize,
    /// The simplification of `--decimate`.
    #[serde(skip_serializing_if = "Option::is_none")]
    decimate: Option<DecimateReport>,
    timings: Timings,
}

pub fn run(ctx: &Context, args: &RemeshArgs) -> anyhow::Result<()> {
    let out = remesh_file(ctx, args)?;
    if ctx.json {
        return print_json(&out);
    }
    let [nx, ny, nz] = out.grid.dims;
    println!(
        "{}: {nx}×{ny}×{nz} grid, voxel {} (file units)",
        args.output.display(),
        out.grid.voxel
    );
    println!("{}", out.output);
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
        mut phi,
        read_s: read,
        voxelize_s,
        bar,
        ..
    } = load_and_voxelize(ctx, &args.mesh, &args.grid)?;
    bar.set_message("extracting the surface");
    let t = Instant::now();
    // A fold narrower than the voxel can enclose a bubble of outside the input does not have:
    // reopen it (only when the input has no cavity of its own).
    let extract = ExtractOptions::default();
    let (mut surface, cavities_joined) = if find_cavities(&mesh).is_empty() {
        extract_joining_cavities(&mut phi, &extract, &CavityOptions::default())?
    } else {
        (extract_surface(&phi, &extract)?, 0)
    };
    if cavities_joined > 0 {
        bar.suspend(|| {
            ctx.notice(&format!(
                "reopened {cavities_joined} fold(s) of the input that closed into an enclosed \
                 cavity at this voxel size"
            ))
        });
    }
    let mc = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut refined = RefineReport::default();
    if !args.no_project {
        bar.set_message("projecting onto the input");
        let opts = ProjectOptions {
            max_distance: spec.voxel(),
            ..Default::default()
        };
        let bvh = MeshBvh::new(&mesh);
        project_vertices(&mut surface, &mesh, &bvh, &opts);
        bar.set_message("refining towards the input");
        refined = refine_to_surface(
            &mut surface,
            &mesh,
            &bvh,
            &remesh_refine_options(spec.voxel()),
        );
    }
    let project = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let decimate = args.decimate.map(|voxels| {
        bar.set_message("decimating");
        let opts = DecimateOptions {
            max_distance: voxels * spec.voxel(),
            ..DecimateOptions::default()
        };
        let (lean, report) = decimate_mesh(&surface, &opts);
        surface = lean;
        report
    });
    let decimate_s = t.elapsed().as_secs_f64();
    let output = mesh_info(&surface);
    let t = Instant::now();
    outputs.write(&args.output, |p| write_mesh(p, &surface))?;
    outputs.commit()?;
    let write = t.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let out = RemeshOutput {
        grid: GridJson::of(&spec),
        output,
        cavities_joined,
        edges_split: refined.edges_split,
        decimate,
        timings: Timings {
            read,
            voxelize: voxelize_s,
            marching_cubes: mc,
            project,
            decimate: decimate_s,
            write,
        },
    };
    Ok(out)
}
