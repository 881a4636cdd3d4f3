//! Brute-force references for the hierarchy queries: every triangle is visited, in f64. Slow
//! (linear in the number of triangles per query) and meant for tests, oracles and benchmarks.
//!
//! The ray references use Möller and Trumbore, "Fast, minimum storage ray/triangle
//! intersection", J. Graphics Tools 2(1), 1997, an independent method from the watertight test
//! that [`crate::bvh::MeshBvh::cast_ray`] uses.

use nalgebra::{Point3, Vector3};

use super::closest::closest_point_on_triangle;
use super::winding::solid_angle;
use super::{ClosestPoint, RayHit};
use crate::TriMesh;

/// Corners of face `f`, or `None` if an index is out of range.
fn corners(mesh: &TriMesh, f: usize) -> Option<[Point3<f64>; 3]> {
    let [a, b, c] = mesh.faces[f];
    let v = &mesh.vertices;
    Some([
        *v.get(a as usize)?,
        *v.get(b as usize)?,
        *v.get(c as usize)?,
    ])
}

/// Closest point on the mesh to `p`, by testing every face (lowest face index on ties).
/// [`ClosestPoint::none`] for a mesh without faces.
pub fn closest_point_brute(mesh: &TriMesh, p: &Point3<f64>) -> ClosestPoint {
    let mut best = ClosestPoint::none(p);
    let mut best_d2 = f64::INFINITY;
    for f in 0..mesh.num_faces() {
        let Some([a, b, c]) = corners(mesh, f) else {
            continue;
        };
        let (x, bary) = closest_point_on_triangle(p, &a, &b, &c);
        let d2 = (p - x).norm_squared();
        if d2 < best_d2 {
            best_d2 = d2;
            best = ClosestPoint {
                point: x,
                distance: d2.sqrt(),
                face: f as u32,
                bary,
            };
        }
    }
    best
}

/// Generalized winding number at `p`: (1/4π) times the sum of the signed solid angles of all
/// faces (Van Oosterom and Strackee 1983), with no approximation.
pub fn winding_number_exact(mesh: &TriMesh, p: &Point3<f64>) -> f64 {
    let mut sum = 0.0;
    for f in 0..mesh.num_faces() {
        if let Some([a, b, c]) = corners(mesh, f) {
            sum += solid_angle(p, &a, &b, &c);
        }
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// Möller–Trumbore intersection of `origin + t·dir`, 0 ≤ t ≤ `t_max`, with (a, b, c), two-sided:
/// the ray parameter and barycentric coordinates of the hit.
pub fn intersect_ray_triangle_mt(
    origin: &Point3<f64>,
    dir: &Vector3<f64>,
    t_max: f64,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> Option<(f64, [f64; 3])> {
    let e1 = b - a;
    let e2 = c - a;
    let pv = dir.cross(&e2);
    let det = e1.dot(&pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = origin - a;
    let u = tv.dot(&pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(&e1);
    let v = dir.dot(&qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(&qv) * inv;
    if !(t >= 0.0 && t <= t_max) {
        return None;
    }
    Some((t, [1.0 - u - v, u, v]))
}

/// Nearest hit of `origin + t·dir`, 0 ≤ t ≤ `t_max`, testing every face (Möller–Trumbore,
/// two-sided; lowest face index on ties).
pub fn cast_ray_brute(
    mesh: &TriMesh,
    origin: &Point3<f64>,
    dir: &Vector3<f64>,
    t_max: f64,
) -> Option<RayHit> {
    let mut best: Option<RayHit> = None;
    for f in 0..mesh.num_faces() {
        let Some([a, b, c]) = corners(mesh, f) else {
            continue;
        };
        if let Some((t, bary)) = intersect_ray_triangle_mt(origin, dir, t_max, &a, &b, &c) {
            if best.is_none_or(|h| t < h.t) {
                best = Some(RayHit {
                    t,
                    face: f as u32,
                    bary,
                    point: origin + dir * t,
                });
            }
        }
    }
    best
}

/// Number of faces hit by `origin + t·dir`, 0 ≤ t ≤ `t_max` (Möller–Trumbore, two-sided).
pub fn count_ray_hits_brute(
    mesh: &TriMesh,
    origin: &Point3<f64>,
    dir: &Vector3<f64>,
    t_max: f64,
) -> usize {
    (0..mesh.num_faces())
        .filter_map(|f| corners(mesh, f))
        .filter(|[a, b, c]| intersect_ray_triangle_mt(origin, dir, t_max, a, b, c).is_some())
        .count()
}
