//! Seeded query points and directions around a mesh, for comparing fast queries with brute force
//! or with the oracle.

use nalgebra::{Point3, Vector3};
use rand::rngs::StdRng;
use rand::RngExt;
use vesselmsr::mesh::measures::{bounding_box, mean_edge_length};
use vesselmsr::TriMesh;

/// Length of the bounding-box diagonal: the scale that tolerances on real meshes are relative to.
pub fn bbox_diagonal(mesh: &TriMesh) -> f64 {
    let (lo, hi) = bounding_box(mesh);
    (hi - lo).norm()
}

/// A uniformly distributed unit vector (rejection sampling in the unit ball).
pub fn unit_vector(rng: &mut StdRng) -> Vector3<f64> {
    loop {
        let v = Vector3::from_fn(|_, _| rng.random::<f64>() * 2.0 - 1.0);
        let n = v.norm();
        if n > 1e-3 && n <= 1.0 {
            return v / n;
        }
    }
}

/// `n` query points from `seed`: the even ones uniform in the bounding box grown by 20 %, the odd
/// ones a random surface point (area-weighted) plus a random offset of up to two mean edge
/// lengths, so that both far and near-surface cases are exercised.
pub fn sample_points(mesh: &TriMesh, n: usize, seed: u64) -> Vec<Point3<f64>> {
    let mut rng = super::rng(seed);
    let (lo, hi) = bounding_box(mesh);
    let center = nalgebra::center(&lo, &hi);
    let half = (hi - lo) * 0.6;
    let h = mean_edge_length(mesh);
    let cumulative_area: Vec<f64> = (0..mesh.num_faces())
        .scan(0.0, |total, f| {
            *total += 0.5 * mesh.face_normal_raw(f).norm();
            Some(*total)
        })
        .collect();
    let total = cumulative_area.last().copied().unwrap_or(0.0);
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                let u = Vector3::from_fn(|_, _| rng.random::<f64>() * 2.0 - 1.0);
                center + half.component_mul(&u)
            } else {
                let x = rng.random::<f64>() * total;
                let f = cumulative_area
                    .partition_point(|&s| s < x)
                    .min(mesh.num_faces() - 1);
                let [a, b, c] = mesh.triangle(f);
                let (mut r1, mut r2) = (rng.random::<f64>(), rng.random::<f64>());
                if r1 + r2 > 1.0 {
                    r1 = 1.0 - r1;
                    r2 = 1.0 - r2;
                }
                let s = a + (b - a) * r1 + (c - a) * r2;
                s + unit_vector(&mut rng) * (rng.random::<f64>() * 2.0 * h)
            }
        })
        .collect()
}
