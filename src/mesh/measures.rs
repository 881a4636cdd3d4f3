//! Geometric measures of a triangle mesh: area, signed enclosed volume (divergence theorem),
//! bounding box, mean edge length, degenerate triangles, Euler characteristic and genus.

use super::TriMesh;

/// Signed enclosed volume by the divergence theorem: Σ a·(b×c)/6 over triangles. Positive when a
/// closed mesh faces outward; only meaningful for closed meshes.
pub fn signed_volume(mesh: &TriMesh) -> f64 {
    // Relative to the first vertex, to keep precision for meshes far from the origin.
    let Some(o) = mesh.vertices.first() else { return 0.0 };
    let mut sum = 0.0;
    for f in 0..mesh.num_faces() {
        let [a, b, c] = mesh.triangle(f);
        sum += (a - o).dot(&(b - o).cross(&(c - o)));
    }
    sum / 6.0
}

/// Aspect ratio of the triangle (a, b, c), normalised so an equilateral triangle gives 1:
/// L_max² · √3 / (4 · area), i.e. the longest edge over the shortest altitude times √3/2.
/// Degenerate triangles give `f64::INFINITY`.
pub fn triangle_aspect_ratio(
    a: &nalgebra::Point3<f64>,
    b: &nalgebra::Point3<f64>,
    c: &nalgebra::Point3<f64>,
) -> f64 {
    let l2 = (b - a)
        .norm_squared()
        .max((c - b).norm_squared())
        .max((a - c).norm_squared());
    let area = 0.5 * (b - a).cross(&(c - a)).norm();
    if area <= 0.0 {
        return f64::INFINITY;
    }
    l2 * 3f64.sqrt() / (4.0 * area)
}
