//! Surface-to-surface distances for `compare`: dense area-weighted samples on both surfaces,
//! closest points on the other surface by BVH, and from them the symmetric Hausdorff distance and
//! the mean and RMS surface distances.
//!
//! Samples are deterministic: the k-th of n samples picks its triangle by inverting the cumulative
//! area at (k + ½)/n (stratified in area) and its position in the triangle from the additive
//! recurrence of the plastic number (the R2 low-discrepancy sequence), folded into the triangle.
//! The Hausdorff distance also takes every vertex of both meshes into account, where maxima of
//! piecewise-linear surfaces usually sit.

use super::TriMesh;
use crate::bvh::MeshBvh;
use nalgebra::Point3;
use rayon::prelude::*;

/// Options for [`surface_distance`].
#[derive(Debug, Clone)]
pub struct SurfaceDistanceOptions {
    /// Area-weighted samples per surface (a count, not a density).
    pub samples: usize,
}

impl Default for SurfaceDistanceOptions {
    fn default() -> Self {
        SurfaceDistanceOptions { samples: 200_000 }
    }
}

/// Distances between surfaces A and B, in the meshes' own units.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct SurfaceDistance {
    /// Symmetric Hausdorff distance: max(max_A d(·, B), max_B d(·, A)).
    pub hausdorff: f64,
    /// Largest distance from A (samples and vertices) to B.
    pub max_a_to_b: f64,
    /// Largest distance from B (samples and vertices) to A.
    pub max_b_to_a: f64,
    /// Mean distance over the area-weighted samples of both surfaces.
    pub mean_distance: f64,
    /// Root mean square distance over the area-weighted samples of both surfaces.
    pub rms_distance: f64,
    /// Area-weighted samples taken on each surface.
    pub samples_per_surface: usize,
}

/// `n` deterministic area-weighted sample points on the surface (see the module doc).
/// Returns no points for a mesh of zero area.
pub fn sample_surface(mesh: &TriMesh, n: usize) -> Vec<Point3<f64>> {
    let mut cumulative = Vec::with_capacity(mesh.num_faces());
    let mut total = 0.0;
    for f in 0..mesh.num_faces() {
        total += 0.5 * mesh.face_normal_raw(f).norm();
        cumulative.push(total);
    }
    if total <= 0.0 || !total.is_finite() {
        return Vec::new();
    }
    // Additive recurrence of the plastic number ρ (ρ³ = ρ + 1): the R2 sequence.
    let rho = 1.324_717_957_244_746_f64;
    let (a1, a2) = (1.0 / rho, 1.0 / (rho * rho));
    (0..n)
        .into_par_iter()
        .map(|k| {
            let target = (k as f64 + 0.5) / n as f64 * total;
            let f = cumulative
                .partition_point(|&c| c < target)
                .min(mesh.num_faces() - 1);
            let (mut u, mut v) = ((0.5 + a1 * k as f64).fract(), (0.5 + a2 * k as f64).fract());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let [a, b, c] = mesh.triangle(f);
            a + (b - a) * u + (c - a) * v
        })
        .collect()
}

/// Symmetric surface distances between `a` and `b` (see [`SurfaceDistance`]).
pub fn surface_distance(
    a: &TriMesh,
    b: &TriMesh,
    opts: &SurfaceDistanceOptions,
) -> SurfaceDistance {
    let (bvh_a, bvh_b) = rayon::join(|| MeshBvh::new(a), || MeshBvh::new(b));
    let directed = |from: &TriMesh, to: &MeshBvh| -> (f64, f64, f64) {
        let samples = sample_surface(from, opts.samples);
        let dists: Vec<f64> = samples
            .par_iter()
            .map(|p| to.closest_point(p).distance)
            .collect();
        let vertex_max = from
            .vertices
            .par_iter()
            .map(|p| to.closest_point(p).distance)
            .reduce(|| 0.0, f64::max);
        let max = dists.iter().copied().fold(vertex_max, f64::max);
        (
            max,
            dists.iter().sum::<f64>(),
            dists.iter().map(|d| d * d).sum::<f64>(),
        )
    };
    let (ab, ba) = rayon::join(|| directed(a, &bvh_b), || directed(b, &bvh_a));
    let n = (2 * opts.samples).max(1) as f64;
    SurfaceDistance {
        hausdorff: ab.0.max(ba.0),
        max_a_to_b: ab.0,
        max_b_to_a: ba.0,
        mean_distance: (ab.1 + ba.1) / n,
        rms_distance: ((ab.2 + ba.2) / n).sqrt(),
        samples_per_surface: opts.samples,
    }
}
