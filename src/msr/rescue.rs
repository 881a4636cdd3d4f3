//! A second chance for the samples whose Newton projection onto a zero level set did not
//! converge (paper Algorithm 1, step 3). Newton steps stall where ∇φ nearly vanishes — on the
//! medial axis of a thin fold — and leave the sample off the surface, with a wrong normal that
//! then spoils the reconstruction of the next level. Such a sample restarts from its closest point
//! on the marching-cubes surface of φ (found with the BVH), which lies within a fraction of a
//! voxel of the zero level set, and Newton polishes it from there.

use super::project::{project_to_zero_level, LevelProjectOptions, Projected};
use crate::bvh::MeshBvh;
use crate::grid::Grid3;
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::Result;
use nalgebra::Point3;

/// Re-projects every unconverged entry of `projected` (the projections of `points` onto the zero
/// level set of `phi`) from its closest point on the marching-cubes surface of `phi`; an entry
/// is replaced only when its residual falls. Returns how many were rescued (now converged).
pub fn rescue_unconverged(
    phi: &Grid3,
    points: &[Point3<f64>],
    projected: &mut [Projected],
    opts: &LevelProjectOptions,
) -> Result<usize> {
    let failed: Vec<usize> = (0..projected.len())
        .filter(|&k| !projected[k].converged)
        .collect();
    if failed.is_empty() {
        return Ok(0);
    }
    let surface = extract_surface(phi, &ExtractOptions::default())?;
    if surface.faces.is_empty() {
        return Ok(0);
    }
    let bvh = MeshBvh::new(&surface);
    let starts: Vec<Point3<f64>> = failed
        .iter()
        .map(|&k| bvh.closest_point(&points[k]).point)
        .collect();
    let mut rescued = 0;
    for (&k, again) in failed.iter().zip(project_to_zero_level(phi, &starts, opts)) {
        if again.residual < projected[k].residual {
            rescued += usize::from(again.converged);
            projected[k] = again;
        }
    }
    Ok(rescued)
}
