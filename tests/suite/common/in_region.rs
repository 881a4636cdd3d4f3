//! Measures of a repaired surface against its truth inside the region D (union of balls).

use nalgebra::Point3;
use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::inpaint::checks::faces_not_facing_out;
use vesselmsr::inpaint::region::Ball;
use vesselmsr::mesh::distance::sample_surface;
use vesselmsr::report::stenosis::volume_in_ball;
use vesselmsr::TriMesh;

pub fn in_regions(balls: &[Ball], p: &Point3<f64>) -> bool {
    balls.iter().any(|b| b.contains(p))
}

/// Symmetric Hausdorff distance between the parts of `a` and `b` inside D (area samples of each
/// inside D against the whole other surface).
pub fn hausdorff_in(a: &TriMesh, b: &TriMesh, balls: &[Ball]) -> f64 {
    let one_way = |x: &TriMesh, y: &TriMesh| {
        let bvh = MeshBvh::new(y);
        sample_surface(x, 60_000)
            .iter()
            .chain(&x.vertices)
            .filter(|p| in_regions(balls, p))
            .map(|p| (p - bvh.closest_point(p).point).norm())
            .fold(0.0, f64::max)
    };
    one_way(a, b).max(one_way(b, a))
}

/// (Output − truth) volume inside D over the truth's volume inside D.
pub fn volume_error_in(output: &TriMesh, truth: &TriMesh, balls: &[Ball]) -> f64 {
    let (o, t): (f64, f64) = balls
        .iter()
        .map(|b| (volume_in_ball(output, b), volume_in_ball(truth, b)))
        .fold((0.0, 0.0), |s, v| (s.0 + v.0, s.1 + v.1));
    (o - t) / t
}

/// The faces of `mesh` with a vertex in D grown by `reach` that do not separate inside (behind)
/// from outside (in front), probed by the winding number `eps` off their centroid: a slit, fin
/// or pocket inside the solid has inside on both sides. Returns (wrong, probed).
pub fn one_sided_faces_near(
    mesh: &TriMesh,
    balls: &[Ball],
    reach: f64,
    eps: f64,
) -> (usize, usize) {
    let grown: Vec<Ball> = balls
        .iter()
        .map(|b| Ball {
            center: b.center,
            radius: b.radius + reach,
        })
        .collect();
    let winding = WindingNumber::new(mesh, WindingOptions::default());
    let v = &mesh.vertices;
    let near: Vec<usize> = (0..mesh.faces.len())
        .filter(|&f| {
            mesh.faces[f]
                .iter()
                .any(|&k| in_regions(&grown, &v[k as usize]))
        })
        .collect();
    (faces_not_facing_out(mesh, &winding, &near, eps), near.len())
}
