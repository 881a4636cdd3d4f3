//! The region D on a grid (paper, Algorithm 4: "copy φ_0 outside D"): how deep each node lies
//! inside the union of balls, which nodes are unknown, and the weight that blends the inpainted
//! field into the known one over a band inside ∂D so that no seam appears at the boundary.

use super::region::{depth_in, Ball};
use crate::grid::Grid3;
use rayon::prelude::*;

/// Depth of every node of `grid` inside the union of `balls`, world units: the largest
/// r − |x − c| over the balls (positive inside D, negative outside).
pub fn region_depth(grid: &Grid3, balls: &[Ball]) -> Vec<f32> {
    let [nx, ny, _] = grid.dims();
    let t = *grid.transform();
    let mut depth = vec![f32::NEG_INFINITY; grid.data().len()];
    depth
        .par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, slab)| {
            for j in 0..ny {
                for i in 0..nx {
                    let p = t.index_to_world(nalgebra::Vector3::new(i as f64, j as f64, k as f64));
                    slab[i + nx * j] = depth_in(balls, &p) as f32;
                }
            }
        });
    depth
}

/// The unknown nodes: those strictly inside D.
pub fn region_mask(depth: &[f32]) -> Vec<bool> {
    depth.par_iter().map(|&d| d > 0.0).collect()
}

/// Blend weight of the inpainted field: 0 outside D and on ∂D, rising smoothly (a cubic
/// smoothstep) to 1 at `band` (world units) inside D.
pub fn blend_weights(depth: &[f32], band: f64) -> Vec<f32> {
    let band = band.max(f64::MIN_POSITIVE) as f32;
    depth
        .par_iter()
        .map(|&d| {
            let s = (d / band).clamp(0.0, 1.0);
            s * s * (3.0 - 2.0 * s)
        })
        .collect()
}

/// ψ ← w ψ + (1 − w) φ_0 at every node: the known data outside D, the inpainted field deep in D.
pub fn blend_known(psi: &mut Grid3, phi0: &Grid3, weights: &[f32]) {
    psi.data_mut()
        .par_iter_mut()
        .zip(phi0.data().par_iter())
        .zip(weights.par_iter())
        .for_each(|((p, &k), &w)| *p = w * *p + (1.0 - w) * k);
}
