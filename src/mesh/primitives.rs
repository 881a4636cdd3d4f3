//! Analytic test shapes as triangle meshes: icosphere, axis-aligned box, torus and open tube,
//! all outward-facing. They give tests and phantoms shapes with known area, volume, curvature
//! and topology (a sphere under mean curvature flow, a torus of genus 1, a tube with two open
//! ends standing in for a vessel).

use super::TriMesh;
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use std::f64::consts::TAU;

/// Icosahedron subdivided `subdivisions` times (each triangle into four, new vertices pushed to
/// the sphere): 10·4ᵏ + 2 vertices and 20·4ᵏ triangles on the sphere of `radius` (world units)
/// about `center`.
pub fn icosphere(subdivisions: usize, radius: f64, center: Point3<f64>) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut dirs: Vec<Vector3<f64>> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vector3::from(*p).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, dirs: &mut Vec<Vector3<f64>>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                dirs.push((dirs[a as usize] + dirs[b as usize]).normalize());
                (dirs.len() - 1) as u32
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut dirs);
                let bc = midpoint(b, c, &mut dirs);
                let ca = midpoint(c, a, &mut dirs);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    TriMesh::new(dirs.iter().map(|d| center + d * radius).collect(), faces)
}

/// The axis-aligned box [min, max] as 8 vertices and 12 triangles.
pub fn box_mesh(min: Point3<f64>, max: Point3<f64>) -> TriMesh {
    let corner = |i: usize| {
        Point3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    TriMesh::new(
        (0..8).map(corner).collect(),
        quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect(),
    )
}

/// Torus about the z axis through `center`: tube radius `minor` around a circle of radius
/// `major` (world units), `n_major` × `n_minor` quads split into triangles.
pub fn torus(
    major: f64,
    minor: f64,
    n_major: usize,
    n_minor: usize,
    center: Point3<f64>,
) -> TriMesh {
    let mut vertices = Vec::with_capacity(n_major * n_minor);
    for i in 0..n_major {
        let u = TAU * i as f64 / n_major as f64;
        for j in 0..n_minor {
            let w = TAU * j as f64 / n_minor as f64;
            let r = major + minor * w.cos();
            vertices.push(center + Vector3::new(r * u.cos(), r * u.sin(), minor * w.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % n_major) * n_minor + j % n_minor) as u32;
    TriMesh::new(vertices, grid_faces(n_major, n_minor, id))
}

/// Open circular tube (a straight vessel with both ends cut): radius `radius` around the z axis
/// from z = 0 to z = `length` (world units), `rings` rings (≥ 2) of `segments` vertices. Two
/// boundary loops, one per end.
pub fn open_tube(radius: f64, length: f64, segments: usize, rings: usize) -> TriMesh {
    let mut vertices = Vec::with_capacity(segments * rings);
    for j in 0..rings {
        let z = length * j as f64 / (rings.max(2) - 1) as f64;
        for i in 0..segments {
            let th = TAU * i as f64 / segments as f64;
            vertices.push(Point3::new(radius * th.cos(), radius * th.sin(), z));
        }
    }
    let id = |i: usize, j: usize| (j * segments + i % segments) as u32;
    let faces = grid_faces(segments, rings - 1, id);
    TriMesh::new(vertices, faces)
}

/// Two triangles per cell of an `n` × `m` grid whose corners `id(i, j)` (i along the first
/// direction, wrapping is the caller's business), wound so that the first direction × the second
/// points out.
fn grid_faces(n: usize, m: usize, id: impl Fn(usize, usize) -> u32) -> Vec<[u32; 3]> {
    let mut faces = Vec::with_capacity(2 * n * m);
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    faces
}
