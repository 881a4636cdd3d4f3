//! Test shapes built on `vesselmsr::mesh::primitives`: the cube [lo, hi]³, whole or with one
//! side left open; an octahedron with coordinates f32 cannot hold (for the formats' exactness);
//! a hole punched in a wall, or a chop (its largest piece kept); any mesh as a triangle soup.

use nalgebra::Point3;
use vesselmsr::inpaint::region::Ball;
use vesselmsr::mesh::primitives::box_mesh;
use vesselmsr::mesh::topology::connected_components;
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

/// An octahedron with coordinates that f32 cannot hold exactly (so OBJ/PLY exactness is tested),
/// listed in an order unrelated to first use by the faces.
pub fn odd_octahedron() -> TriMesh {
    let c = [
        [0.1 + 0.2, 1.0 / 3.0, -1e-7],
        [-2.0 / 3.0, 0.7, 12345.678901234567],
        [std::f64::consts::PI, -0.0, 5e-12],
        [1.0, -std::f64::consts::E, 0.3],
        [0.25, 0.5, 2.0f64.sqrt()],
        [-1.1, -2.2, -3.3e5],
    ];
    let vertices = c.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect();
    let faces = vec![
        [4, 0, 1],
        [4, 1, 3],
        [4, 3, 2],
        [4, 2, 0],
        [5, 1, 0],
        [5, 3, 1],
        [5, 2, 3],
        [5, 0, 2],
    ];
    TriMesh::new(vertices, faces)
}

/// `mesh` without the triangles that have a corner `inside` the damage (every piece kept).
pub fn cut_where(mesh: &TriMesh, inside: impl Fn(&Point3<f64>) -> bool) -> TriMesh {
    let mut holed = mesh.clone();
    holed
        .faces
        .retain(|f| !f.iter().any(|&v| inside(&mesh.vertices[v as usize])));
    holed
}

/// `mesh` without the triangles that have a corner within `radius` of `center`: a hole in the
/// wall there.
pub fn punch_hole(mesh: &TriMesh, center: Point3<f64>, radius: f64) -> TriMesh {
    let holed = cut_where(mesh, |p| (p - center).norm() <= radius);
    assert!(holed.num_faces() < mesh.num_faces(), "nothing punched");
    holed
}

/// `mesh` without every triangle that has a vertex in `chop`, its largest piece kept (the chops
/// of `benches/repair_real`).
pub fn chopped(mesh: &TriMesh, chop: &Ball) -> TriMesh {
    let holed = punch_hole(mesh, chop.center, chop.radius);
    let (count, labels) = connected_components(&holed);
    let mut sizes = vec![0usize; count];
    for &l in &labels {
        sizes[l as usize] += 1;
    }
    let big = (0..count).max_by_key(|&c| sizes[c]).unwrap_or(0) as u32;
    let faces = holed
        .faces
        .iter()
        .zip(&labels)
        .filter(|(_, &l)| l == big)
        .map(|(f, _)| *f)
        .collect();
    TriMesh::new(mesh.vertices.clone(), faces)
}

/// `mesh` as a triangle soup: every triangle with its own three corners (no vertex shared).
pub fn soup_of(mesh: &TriMesh) -> TriMesh {
    TriMesh::new(
        mesh.faces
            .iter()
            .flat_map(|f| f.map(|v| mesh.vertices[v as usize]))
            .collect(),
        (0..mesh.num_faces() as u32)
            .map(|f| [3 * f, 3 * f + 1, 3 * f + 2])
            .collect(),
    )
}

/// The signed distance grid φ of `mesh` on `spec` (the default voxelizer), as the decompose
/// tests start from.
pub fn phi_on(mesh: &TriMesh, spec: &vesselmsr::grid::spec::GridSpec) -> vesselmsr::grid::Grid3 {
    vesselmsr::levelset::voxelize::voxelize(
        mesh,
        spec.dims,
        spec.transform,
        &vesselmsr::levelset::voxelize::VoxelizeOptions::default(),
    )
    .unwrap()
}
