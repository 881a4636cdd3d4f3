//! The grid flags shared by the level-set commands (`voxelize`, `remesh`): voxel size or
//! resolution (the memory limit is the global `--max-memory`, see `budget`); and the first steps
//! both commands take with them (read the mesh, size its grid, voxelize it).

use super::{progress, Context};
use crate::grid::spec::GridOptions;
use crate::grid::{grid_for_mesh, Grid3, GridSpec};
use crate::io::read_mesh;
use crate::levelset::voxelize::{voxelize_with_report, VoxelizeOptions, VoxelizeReport};
use crate::TriMesh;
use indicatif::ProgressBar;
use std::path::Path;
use std::time::Instant;

#[derive(Debug, Clone, clap::Args)]
pub struct GridArgs {
    /// Voxel edge length, in the mesh's own units (default: min(mean edge / 2, longest extent
    /// / 256)).
    #[arg(long, value_name = "H", conflicts_with = "resolution")]
    pub voxel: Option<f64>,
    /// Cells along the longest axis of the mesh's bounding box (instead of --voxel).
    #[arg(long, value_name = "N")]
    pub resolution: Option<usize>,
}

impl GridArgs {
    /// The grid options these flags ask for, within the memory budget of `ctx`.
    pub fn options(&self, ctx: &Context) -> GridOptions {
        GridOptions {
            voxel: self.voxel,
            resolution: self.resolution,
            max_memory_bytes: ctx.max_memory,
            ..GridOptions::default()
        }
    }
}

/// A mesh read and voxelized on the grid its flags ask for, with the spinner still running.
pub struct Voxelized {
    pub mesh: TriMesh,
    pub spec: GridSpec,
    /// φ from `voxelize` with the default options (exact within the band, clamped beyond).
    pub phi: Grid3,
    pub report: VoxelizeReport,
    /// Seconds spent reading the mesh.
    pub read_s: f64,
    /// Seconds spent voxelizing.
    pub voxelize_s: f64,
    /// The "voxelizing" spinner, for the caller's next steps.
    pub bar: ProgressBar,
}

/// Reads `mesh_path`, sizes its grid from `grid` (errors name the file) and voxelizes it under a
/// "voxelizing" spinner, timing the read and the voxelization.
pub fn load_and_voxelize(
    ctx: &Context,
    mesh_path: &Path,
    grid: &GridArgs,
) -> anyhow::Result<Voxelized> {
    let grid_opts = grid.options(ctx);
    let t = Instant::now();
    let mesh = read_mesh(mesh_path)?;
    let read_s = t.elapsed().as_secs_f64();
    let spec = grid_for_mesh(&mesh, &grid_opts)
        .map_err(|e| anyhow::anyhow!("{}: {e}", mesh_path.display()))?;
    let bar = progress::spinner(ctx.quiet, "voxelizing");
    let t = Instant::now();
    let (phi, report) = voxelize_with_report(
        &mesh,
        spec.dims,
        spec.transform,
        &VoxelizeOptions::default(),
    )
    .map_err(|e| anyhow::anyhow!("{}: {e}", mesh_path.display()))?;
    let voxelize_s = t.elapsed().as_secs_f64();
    Ok(Voxelized {
        mesh,
        spec,
        phi,
        report,
        read_s,
        voxelize_s,
        bar,
    })
}
