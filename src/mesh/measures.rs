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
