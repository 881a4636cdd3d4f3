//! Test shapes built on `vesselmsr::mesh::primitives`: the cube [lo, hi]³, whole or with one
//! side left open.

use nalgebra::Point3;
use vesselmsr::mesh::primitives::box_mesh;
use vesselmsr::TriMesh;

/// The axis-aligned cube [lo, hi]³: 8 vertices, 12 outward triangles.
pub fn cube(lo: f64, hi: f64) -> TriMesh {
    box_mesh(Point3::from([lo; 3]), Point3::from([hi; 3]))
}

/// The cube [lo, hi]³ without the two triangles of one side, numbered −x, +x, −y, +y, −z, +z
/// (side 5 is the top, z = hi): an open box with one square boundary loop.
pub fn cube_without_side(lo: f64, hi: f64, side: usize) -> TriMesh {
    let (axis, at) = (side / 2, [lo, hi][side % 2]);
    let mut mesh = cube(lo, hi);
    let before = mesh.num_faces();
    let vertices = &mesh.vertices;
    mesh.faces
        .retain(|f| !f.iter().all(|&v| vertices[v as usize][axis] == at));
    assert_eq!(mesh.num_faces(), before - 2, "side {side} of the cube");
    mesh
}
