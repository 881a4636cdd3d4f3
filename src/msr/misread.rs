//! Samples added where the level-set reconstruction would misread a level (the paper's "denser
//! samples where needed", Algorithm 1, checked against the reconstruction of Section 2). The
//! decomposition knows both φ_{i−1} and φ_i, so it can ask, node by node near S_{i−1}, what the
//! tangent-plane rebuild ([`super::reconstruct::TangentPlanes::node_value`]) will give from φ_i
//! and the samples of S_{i−1}. Where the cortex folds more tightly than the grid (sub-voxel
//! pockets of S_{i−1} that S_i has smoothed over), the samples placed a quarter voxel apart on
//! the marching-cubes surface ([`super::cover`]) can still leave a node reading the wrong side or
//! a distance off by a third of a voxel; a sample at that node's foot point on S_{i−1} (its
//! Newton projection) gives the rebuild the plane it lacked.

use super::project::{converged_projections, LevelProjectOptions};
use super::reconstruct::{AdvectOptions, TangentPlanes};
use crate::grid::Grid3;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// A node counts as misread when the rebuild's value differs from φ_{i−1} by more than this
/// (voxels), or has the other sign where |φ_{i−1}| exceeds [`SIGN_MARGIN`].
pub const MISREAD_TOLERANCE: f64 = 0.3;

/// Nodes this near S_{i−1} (voxels) may have either sign in the rebuild.
const SIGN_MARGIN: f64 = 0.05;

/// The nodes within one voxel of S_{i−1} (|φ_{i−1}| < h) that the rebuild of φ_{i−1} from
/// `phi` (φ_i) and the samples of S_{i−1} (`previous`, with `normals` n_{i−1} and `details`
/// W_i) misreads, projected onto S_{i−1} (those whose projection converges). With `around`,
/// only the nodes within two voxels of those points are checked (a second round after samples
/// were added there).
#[allow(clippy::too_many_arguments)]
pub fn misread_points(
    previous_phi: &Grid3,
    phi: &Grid3,
    previous: &[Point3<f64>],
    normals: &[Vector3<f64>],
    details: &[Vector3<f64>],
    around: Option<&[Point3<f64>]>,
    advect: &AdvectOptions,
    projection: &LevelProjectOptions,
) -> Vec<Point3<f64>> {
    let h = phi.voxel();
    let planes = TangentPlanes::new(phi, previous, normals, details, advect);
    let check = |n: usize| -> Option<Point3<f64>> {
        let a = previous_phi.data()[n] as f64;
        if a.abs() >= h {
            return None;
        }
        let b = planes.node_value(phi, n) as f64;
        let flipped = (a < 0.0) != (b < 0.0) && a.abs() > SIGN_MARGIN * h;
        if (a - b).abs() > MISREAD_TOLERANCE * h || flipped {
            let [i, j, k] = phi.coords(n);
            Some(phi.world(i, j, k))
        } else {
            None
        }
    };
    let nodes: Vec<Point3<f64>> = match around {
        None => (0..phi.data().len())
            .into_par_iter()
            .filter_map(check)
            .collect(),
        Some(points) => {
            let mut candidates = nodes_near(phi, points, 2);
            candidates.sort_unstable();
            candidates.dedup();
            candidates.into_par_iter().filter_map(check).collect()
        }
    };
    converged_projections(previous_phi, &nodes, projection)
}

/// The nodes of `phi` within `reach` nodes (along each axis) of the node nearest each point.
fn nodes_near(phi: &Grid3, points: &[Point3<f64>], reach: i64) -> Vec<usize> {
    let dims = phi.dims().map(|d| d as i64);
    let mut out = Vec::new();
    for p in points {
        let q = phi.transform().world_to_index(p);
        let c = [0, 1, 2].map(|a| q[a].round() as i64);
        for z in c[2] - reach..=c[2] + reach {
            for y in c[1] - reach..=c[1] + reach {
                for x in c[0] - reach..=c[0] + reach {
                    if x >= 0 && y >= 0 && z >= 0 && x < dims[0] && y < dims[1] && z < dims[2] {
                        out.push((x + dims[0] * (y + dims[1] * z)) as usize);
                    }
                }
            }
        }
    }
    out
}
