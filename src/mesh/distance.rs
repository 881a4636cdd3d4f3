//! Surface-to-surface distances for `compare`: dense area-weighted samples on both surfaces,
//! closest points on the other surface by BVH, and from them the symmetric Hausdorff distance and
//! the mean and RMS surface distances.
//!
//! Samples are deterministic: the k-th of n samples picks its triangle by inverting the cumulative
//! area at (k + ½)/n (stratified in area) and its position in the triangle from the additive
//! recurrence of the plastic number (the R2 low-discrepancy sequence), folded into the triangle.
//! The Hausdorff distance also takes every vertex of both meshes into account, where maxima of
//! piecewise-linear surfaces usually sit, and is then refined to within [`HAUSDORFF_TOLERANCE`]
//! of the finer mesh's mean edge: the distance to a surface is 1-Lipschitz, so on a triangle with
//! centroid g and corners within r of it no point is farther than d(g) + r, nor farther from a
//! face of the other mesh than its corners are (the distance to one triangle is convex), which
//! bounds it where the two surfaces run parallel; every triangle whose bound passes the largest
//! distance found is split in four, its parts' corners and centroids measured, and so on (branch
//! and bound, at most [`HAUSDORFF_FACE_BUDGET`] points per face). Without it the
//! figure is the largest of the samples taken, which moved by 0.15h on a real vessel's
//! reconstruction when the sample count changed by 0.5%.

use super::measures::mean_edge_length;
use super::TriMesh;
use crate::bvh::{closest_point_on_triangle, ClosestPoint, MeshBvh};
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

/// The Hausdorff distances are refined to within this fraction of the finer mesh's mean edge.
pub const HAUSDORFF_TOLERANCE: f64 = 0.01;

/// At most this many points are measured per triangle while refining (a guard: the bound
/// usually closes after a few splits, on the few triangles near the largest distance).
pub const HAUSDORFF_FACE_BUDGET: usize = 1024;

/// Distances between surfaces A and B, in the meshes' own units.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct SurfaceDistance {
    /// Symmetric Hausdorff distance: max(max_A d(·, B), max_B d(·, A)).
    pub hausdorff: f64,
    /// Largest distance from A to B (samples and vertices, refined; see the module doc).
    pub max_a_to_b: f64,
    /// Largest distance from B to A (likewise).
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

/// The largest distance from the surface `from` to `to_mesh` (`to` its hierarchy), at least
/// `lower` (a distance already found), to within `tol` (world units) unless a triangle's budget
/// runs out: branch and bound on the triangles of `from` (see the module doc).
fn refine_directed_max(
    from: &TriMesh,
    to_mesh: &TriMesh,
    to: &MeshBvh,
    lower: f64,
    tol: f64,
) -> f64 {
    if !lower.is_finite() || tol <= 0.0 {
        return lower;
    }
    (0..from.num_faces())
        .into_par_iter()
        .map(|f| {
            let mut best = lower;
            let mut stack = vec![from.triangle(f)];
            let mut measured = 0;
            while let Some(tri) = stack.pop() {
                let [a, b, c] = tri;
                let g = Point3::from((a.coords + b.coords + c.coords) / 3.0);
                let near = [a, b, c, g].map(|p| to.closest_point(&p));
                measured += 4;
                best = near.iter().fold(best, |m, q| m.max(q.distance));
                let upper = triangle_upper_bound(&tri, &g, near[3].distance, &near, to_mesh);
                if upper > best + tol && measured < HAUSDORFF_FACE_BUDGET {
                    let (ab, bc, ca) = (
                        Point3::from((a.coords + b.coords) / 2.0),
                        Point3::from((b.coords + c.coords) / 2.0),
                        Point3::from((c.coords + a.coords) / 2.0),
                    );
                    stack.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
                }
            }
            best
        })
        .reduce(|| lower, f64::max)
}

/// An upper bound of the distance from any point of the triangle `tri` (centroid `g`, at
/// `dg` from the surface) to `to_mesh`: the smaller of dg + (the largest corner distance from g)
/// — the distance is 1-Lipschitz — and, for each face of `to_mesh` nearest to a corner or the
/// centroid (`near`), the largest distance from the triangle's corners to that face (the
/// distance to one triangle is convex, so its maximum over `tri` is at a corner): tight where
/// the two surfaces run parallel, where the first bound alone never closes.
fn triangle_upper_bound(
    tri: &[Point3<f64>; 3],
    g: &Point3<f64>,
    dg: f64,
    near: &[ClosestPoint; 4],
    to_mesh: &TriMesh,
) -> f64 {
    let r = tri.iter().map(|p| (p - g).norm()).fold(0.0, f64::max);
    near.iter()
        .filter(|q| (q.face as usize) < to_mesh.num_faces())
        .map(|q| {
            let [ta, tb, tc] = to_mesh.triangle(q.face as usize);
            tri.iter()
                .map(|p| (p - closest_point_on_triangle(p, &ta, &tb, &tc).0).norm())
                .fold(0.0, f64::max)
        })
        .fold(dg + r, f64::min)
}

/// Symmetric surface distances between `a` and `b` (see [`SurfaceDistance`]).
pub fn surface_distance(
    a: &TriMesh,
    b: &TriMesh,
    opts: &SurfaceDistanceOptions,
) -> SurfaceDistance {
    let (bvh_a, bvh_b) = rayon::join(|| MeshBvh::new(a), || MeshBvh::new(b));
    let edge = [a, b]
        .map(mean_edge_length)
        .into_iter()
        .filter(|e| *e > 0.0 && e.is_finite())
        .fold(f64::INFINITY, f64::min);
    let tol = if edge.is_finite() {
        HAUSDORFF_TOLERANCE * edge
    } else {
        0.0
    };
    let directed = |from: &TriMesh, to_mesh: &TriMesh, to: &MeshBvh| -> (f64, f64, f64) {
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
        let max = refine_directed_max(from, to_mesh, to, max, tol);
        (
            max,
            dists.iter().sum::<f64>(),
            dists.iter().map(|d| d * d).sum::<f64>(),
        )
    };
    let (ab, ba) = rayon::join(|| directed(a, b, &bvh_b), || directed(b, a, &bvh_a));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A triangle of about 10 across and, as the other surface, three small triangles at its
    /// corners: the farthest point of the large one lies inside it, far from every vertex.
    fn corners() -> (TriMesh, TriMesh) {
        let big = TriMesh::new(
            vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(10.0, 0.0, 0.0),
                Point3::new(3.0, 8.0, 0.0),
            ],
            vec![[0, 1, 2]],
        );
        let mut vertices = Vec::new();
        let mut faces = Vec::new();
        for (c, a, b) in [
            ([0.0, 0.0], [0.5, 0.0], [0.0, 0.5]),
            ([10.0, 0.0], [-0.5, 0.0], [0.0, 0.5]),
            ([3.0, 8.0], [0.5, -0.5], [-0.2, -0.5]),
        ] {
            let k = vertices.len() as u32;
            let p = Point3::new(c[0], c[1], 0.0);
            vertices.extend([
                p,
                p + Vector3::new(a[0], a[1], 0.0),
                p + Vector3::new(b[0], b[1], 0.0),
            ]);
            faces.push([k, k + 1, k + 2]);
        }
        (big, TriMesh::new(vertices, faces))
    }

    use nalgebra::Vector3;

    #[test]
    fn the_hausdorff_distance_is_refined_to_the_true_maximum() {
        let (big, small) = corners();
        // Brute force: the largest distance over a fine barycentric lattice of the big triangle.
        let bvh = MeshBvh::new(&small);
        let n = 1500;
        let brute = (0..=n)
            .into_par_iter()
            .map(|i| {
                (0..=n - i)
                    .map(|j| {
                        let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                        let p = Point3::new(10.0 * u + 3.0 * v, 8.0 * v, 0.0);
                        bvh.closest_point(&p).distance
                    })
                    .fold(0.0, f64::max)
            })
            .reduce(|| 0.0, f64::max);
        // The small triangles' mean edge is 0.57: the refinement closes to 0.006.
        let tol = HAUSDORFF_TOLERANCE * mean_edge_length(&small);
        for samples in [3, 20, 10_000] {
            let d = surface_distance(&big, &small, &SurfaceDistanceOptions { samples });
            assert!(
                (d.max_a_to_b - brute).abs() <= tol + 20.0 / n as f64,
                "{samples} samples: {} against {brute}",
                d.max_a_to_b
            );
        }
        // What the samples and the vertices alone reach with few samples: well short of it.
        let sampled = sample_surface(&big, 3)
            .iter()
            .map(|p| bvh.closest_point(p).distance)
            .fold(0.0, f64::max);
        assert!(sampled < brute - 0.5, "{sampled} against {brute}");
    }
}
