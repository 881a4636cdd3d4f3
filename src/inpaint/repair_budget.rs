//! The memory check of a vessel repair, before any grid is allocated: an upper bound of the grids
//! [`crate::inpaint::repair::repair`] sizes (the sub-box around D, and the lattice of the whole
//! vessel its fallback re-mesh voxelizes), from the same voxel rule and margins, against the
//! budget (`--max-memory`). Refused with one message naming `--voxel`, the regions and
//! `--max-memory`.
//!
//! The margin is `inpaint::repair::region_margin` plus a voxel, the pad of the whole lattice a
//! voxel more than the repair's; the estimate only has to bound them from above.

use super::region::Ball;
use super::repair::{region_margin, RepairOptions};
use crate::budget;
use crate::error::short_number;
use crate::grid::spec::{default_voxel, grid_memory_bytes};
use crate::mesh::measures::{bounding_box, mean_edge_length};
use crate::TriMesh;

/// f32 grids of the sub-box held at once by the fills (φ_0, the fill, its blend weights and
/// depth in D, the flows' scratch grids), rounded up.
const SUB_BOX_GRIDS: usize = 8;
/// f32 grids of the whole vessel's lattice held by the fallback re-mesh (φ and the voxelizer's
/// own), rounded up.
const WHOLE_GRIDS: usize = 3;

/// Refuses a repair of `mesh` in `balls` whose grids would exceed `max_bytes`.
pub fn check(
    mesh: &TriMesh,
    balls: &[Ball],
    opts: &RepairOptions,
    max_bytes: u64,
) -> crate::Result<()> {
    let (lo, hi) = bounding_box(mesh);
    let h = match opts.voxel {
        Some(v) => v,
        None => default_voxel(mean_edge_length(mesh), (hi - lo).max()),
    };
    let rmax = balls.iter().map(|b| b.radius).fold(0.0, f64::max);
    // One voxel more than the repair's own margin.
    let margin = region_margin(opts, balls, h) + h;
    let pad = 5.0 * h + margin + 2.0 * rmax;
    let nodes = |extent: f64| extent / h + 3.0;
    let mut sub = [0.0f64; 3];
    let mut whole = [0.0f64; 3];
    for a in 0..3 {
        let (wlo, whi) = (lo[a] - pad, hi[a] + pad);
        let blo = balls
            .iter()
            .map(|b| b.center[a] - b.radius - margin)
            .fold(f64::INFINITY, f64::min);
        let bhi = balls
            .iter()
            .map(|b| b.center[a] + b.radius + margin)
            .fold(f64::NEG_INFINITY, f64::max);
        sub[a] = nodes((bhi.min(whi) - blo.max(wlo)).max(0.0));
        whole[a] = nodes(whi - wlo);
    }
    let bytes = |dims: [f64; 3], grids: usize| {
        let n = dims.map(|d| {
            if d.is_finite() && d < 1e15 {
                d as usize
            } else {
                usize::MAX
            }
        });
        grid_memory_bytes(n, grids)
    };
    let need = bytes(sub, SUB_BOX_GRIDS).max(bytes(whole, WHOLE_GRIDS));
    let shown = |d: [f64; 3]| d.map(|n| short_number(n.floor())).join("×");
    budget::check(
        &format!(
            "repairing at voxel {} (grids of about {} nodes around D, {} for the whole vessel)",
            short_number(h),
            shown(sub),
            shown(whole)
        ),
        need,
        max_bytes,
        "use a coarser --voxel or smaller regions, or ",
    )
}
