//! The sample points of a decomposition (paper Algorithm 1, X_0): every vertex of the mesh, and
//! where the mesh is coarser than the grid, extra points on its triangles so that no point of
//! the surface is farther than about one voxel from a sample. A triangle whose longest edge
//! exceeds the spacing s gets the interior points of the barycentric lattice of step 1/m,
//! m = ⌈longest edge / s⌉; an edge longer than s gets ⌈length / s⌉ − 1 evenly spaced points,
//! once for both of its triangles. Each extra sample records its face and barycentric
//! coordinates, so it can be placed again on the original surface.

use crate::mesh::topology::EdgeMap;
use crate::TriMesh;
use nalgebra::Point3;

/// Samples of a surface: the mesh vertices first, then the extra points.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceSamples {
    /// All sample positions (vertices first).
    pub points: Vec<Point3<f64>>,
    /// Number of leading samples that are mesh vertices.
    pub num_vertices: usize,
    /// Face of each extra sample.
    pub extra_face: Vec<u32>,
    /// Barycentric coordinates of each extra sample in its face.
    pub extra_bary: Vec<[f64; 3]>,
}

/// Samples `mesh` with spacing at most `spacing` (world units; the decomposition uses one voxel).
pub fn sample_for_spacing(mesh: &TriMesh, spacing: f64) -> SurfaceSamples {
    let mut s = SurfaceSamples {
        points: mesh.vertices.clone(),
        num_vertices: mesh.num_vertices(),
        extra_face: Vec::new(),
        extra_bary: Vec::new(),
    };
    if !(spacing > 0.0 && spacing.is_finite()) {
        return s;
    }
    let push = |s: &mut SurfaceSamples, f: usize, bary: [f64; 3]| {
        let [a, b, c] = mesh.triangle(f);
        s.points.push(Point3::from(
            a.coords * bary[0] + b.coords * bary[1] + c.coords * bary[2],
        ));
        s.extra_face.push(f as u32);
        s.extra_bary.push(bary);
    };
    // Edge points, once per edge (on the first face using it).
    let map = EdgeMap::new(mesh);
    for e in 0..map.num_edges() {
        let [u, v] = map.edges()[e];
        let len = (mesh.vertices[v as usize] - mesh.vertices[u as usize]).norm();
        let m = (len / spacing).ceil() as usize;
        if m < 2 {
            continue;
        }
        let first = map.uses(e)[0];
        let (f, k) = (first.face as usize, first.slot as usize);
        // The face runs corner k → k+1 along this edge.
        for t in 1..m {
            let x = t as f64 / m as f64;
            let mut bary = [0.0; 3];
            bary[k] = 1.0 - x;
            bary[(k + 1) % 3] = x;
            push(&mut s, f, bary);
        }
    }
    // Interior lattice points.
    for f in 0..mesh.num_faces() {
        let [a, b, c] = mesh.triangle(f);
        let longest = (b - a).norm().max((c - b).norm()).max((a - c).norm());
        let m = (longest / spacing).ceil() as usize;
        for i in 1..m {
            for j in 1..m - i {
                let (x, y) = (i as f64 / m as f64, j as f64 / m as f64);
                push(&mut s, f, [1.0 - x - y, x, y]);
            }
        }
    }
    s
}
