//! The grid flags shared by the level-set commands (`voxelize`, `remesh`): voxel size or
//! resolution, and the memory limit.

use crate::grid::spec::{parse_memory_size, GridOptions, DEFAULT_MAX_MEMORY_BYTES};

#[derive(Debug, Clone, clap::Args)]
pub struct GridArgs {
    /// Voxel edge length, in the mesh's own units (default: min(mean edge / 2, longest extent
    /// / 256)).
    #[arg(long, value_name = "H", conflicts_with = "resolution")]
    pub voxel: Option<f64>,
    /// Cells along the longest axis of the mesh's bounding box (instead of --voxel).
    #[arg(long, value_name = "N")]
    pub resolution: Option<usize>,
    /// Refuse grids whose memory estimate exceeds this (e.g. 8G, 512M, bytes).
    #[arg(long, value_name = "SIZE")]
    pub max_memory: Option<String>,
}

impl GridArgs {
    /// The grid options these flags ask for.
    pub fn options(&self) -> anyhow::Result<GridOptions> {
        let max_memory_bytes = match &self.max_memory {
            Some(text) => parse_memory_size(text)?,
            None => DEFAULT_MAX_MEMORY_BYTES,
        };
        Ok(GridOptions {
            voxel: self.voxel,
            resolution: self.resolution,
            max_memory_bytes,
            ..GridOptions::default()
        })
    }
}

/// The grid layout as the JSON outputs print it.
#[derive(serde::Serialize)]
pub struct GridJson {
    pub dims: [usize; 3],
    pub voxel: f64,
    pub origin: [f64; 3],
}

impl GridJson {
    pub fn of(spec: &crate::grid::GridSpec) -> Self {
        GridJson {
            dims: spec.dims,
            voxel: spec.transform.voxel,
            origin: spec.transform.origin,
        }
    }
}
