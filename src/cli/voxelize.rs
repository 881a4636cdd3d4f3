//! `vesselmsr voxelize MESH -o PHI.npy|PHI.vti|PHI.nrrd`: the signed distance grid φ of a mesh (negative
//! inside), exact near the surface and redistanced by fast sweeping elsewhere.

use super::grid_args::{load_and_voxelize, GridArgs, Voxelized};
use super::outputs::Outputs;
use super::{print_json, Context};
use crate::grid::spec::GridJson;
use crate::io::{write_npy, write_nrrd, write_vti};
use crate::levelset::redistance::{redistance, RedistanceOptions};
use crate::levelset::voxelize::VoxelizeOptions;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, clap::Args)]
pub struct VoxelizeArgs {
    /// Input mesh (.stl, .obj, .ply, .vtp or .vtk).
    pub mesh: PathBuf,
    /// Output grid: .npy (NumPy, with a .npy.json sidecar holding the transform), .vti (VTK
    /// ImageData, for ParaView) or .nrrd (NRRD, for 3D Slicer and ITK).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    #[command(flatten)]
    pub grid: GridArgs,
}

enum GridFormat {
    Npy,
    Vti,
    Nrrd,
}

fn grid_format(path: &Path) -> anyhow::Result<GridFormat> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("npy") => Ok(GridFormat::Npy),
        Some("vti") => Ok(GridFormat::Vti),
        Some("nrrd") => Ok(GridFormat::Nrrd),
        _ => anyhow::bail!(
            "{}: unknown grid format (expected extension .npy, .vti or .nrrd)",
            path.display()
        ),
    }
}

#[derive(serde::Serialize)]
struct Timings {
    read: f64,
    voxelize: f64,
    redistance: f64,
    write: f64,
}

#[derive(serde::Serialize)]
struct VoxelizeOutput {
    grid: GridJson,
    inside_nodes: usize,
    band_nodes: usize,
    estimated_bytes: u64,
    timings: Timings,
}

pub fn run(ctx: &Context, args: &VoxelizeArgs) -> anyhow::Result<()> {
    let format = grid_format(&args.output)?;
    let mut outputs = Outputs::new(&[&args.output], &[])?;
    let Voxelized {
        spec,
        mut phi,
        report,
        read_s: read,
        voxelize_s,
        bar,
        ..
    } = load_and_voxelize(ctx, &args.mesh, &args.grid)?;
    bar.set_message("redistancing");
    let t = Instant::now();
    // Fast sweeping fills the values beyond the band; the band keeps voxelize's exact
    // distances (the redistancer's sub-voxel patches are close, but these are exact).
    let exact = phi.data().to_vec();
    redistance(&mut phi, &RedistanceOptions::default())?;
    let band = (VoxelizeOptions::default().band * spec.voxel()) as f32;
    for (value, &e) in phi.data_mut().iter_mut().zip(&exact) {
        if e.abs() < band {
            *value = e;
        }
    }
    let redistance_s = t.elapsed().as_secs_f64();
    bar.set_message("writing");
    let t = Instant::now();
    // The .npy sidecar lands beside its array in the staging folder and is committed with it.
    outputs.write(&args.output, |p| match format {
        GridFormat::Npy => write_npy(p, &phi),
        GridFormat::Vti => write_vti(p, &phi),
        GridFormat::Nrrd => write_nrrd(p, &phi),
    })?;
    outputs.commit()?;
    let write = t.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let out = VoxelizeOutput {
        grid: GridJson::of(&spec),
        inside_nodes: report.inside_nodes,
        band_nodes: report.band_nodes,
        estimated_bytes: spec.estimated_bytes,
        timings: Timings {
            read,
            voxelize: voxelize_s,
            redistance: redistance_s,
            write,
        },
    };
    if ctx.json {
        return print_json(&out);
    }
    let [nx, ny, nz] = spec.dims;
    println!(
        "{}: {nx}×{ny}×{nz} grid, voxel {} (file units), {} nodes inside",
        args.output.display(),
        spec.transform.voxel,
        report.inside_nodes
    );
    println!("voxelize {voxelize_s:.2} s, redistance {redistance_s:.2} s, write {write:.2} s");
    Ok(())
}
