//! The triangle mesh type: vertex positions in f64 (file units, never rescaled) and triangles as
//! vertex-index triples, counter-clockwise seen from outside when the mesh is oriented outward.

use nalgebra::{Point3, Vector3};

/// An indexed triangle mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions, in the file's own units.
    pub vertices: Vec<Point3<f64>>,
    /// Triangles as indices into `vertices`.
    pub faces: Vec<[u32; 3]>,
}

impl TriMesh {
    /// A mesh from its parts (indices are not checked here; readers validate them).
    pub fn new(vertices: Vec<Point3<f64>>, faces: Vec<[u32; 3]>) -> Self {
        TriMesh { vertices, faces }
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of triangles.
    pub fn num_faces(&self) -> usize {
        self.faces.len()
    }

    /// The three corners of triangle `f`.
    pub fn triangle(&self, f: usize) -> [Point3<f64>; 3] {
        let [a, b, c] = self.faces[f];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// The unnormalised normal (b − a) × (c − a) of triangle `f`: its length is twice the area.
    pub fn face_normal_raw(&self, f: usize) -> Vector3<f64> {
        let [a, b, c] = self.triangle(f);
        (b - a).cross(&(c - a))
    }

    /// Reverses the winding of every triangle (flips all normals).
    pub fn flip_faces(&mut self) {
        for f in &mut self.faces {
            f.swap(1, 2);
        }
    }

    /// Appends `other`'s vertices and triangles (its indices shifted past ours).
    pub fn append(&mut self, other: &TriMesh) {
        let offset = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.faces
            .extend(other.faces.iter().map(|f| f.map(|i| i + offset)));
    }
}
