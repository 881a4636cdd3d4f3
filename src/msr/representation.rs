//! The multiscale representation as data: sample points X_N at the coarsest scale, the details
//! W_1..W_N (displacements of every sample from scale i−1 to scale i, paper Algorithm 1), their
//! normal components w_i = W_i·n (positive outward), the scale times t_0..t_N, the level set
//! φ_T of the coarsest shape, and the parameters used. Reconstruction by vertices (the paper's
//! Remark 2.2(4)) is exact: since W_i = X_i − X_{i−1}, X_k = X_N − Σ_{i=k+1}^{N} W_i.

use crate::grid::Grid3;
use crate::TriMesh;
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// The parameters a representation was made with (stored in its archive).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MsrParams {
    /// The motion between scales: "mcf", "vpmcf", "expand" or "inpaint".
    pub velocity: String,
    /// Constant normal speed c of "expand"/"inpaint" (world units per unit time).
    pub c: f64,
    /// Total time T (world units, length²).
    pub time: f64,
    /// Number of levels N.
    pub levels: usize,
    /// Time step of the motion (world units, length²).
    pub dt: f64,
    /// Voxel size h of φ (world units).
    pub voxel: f64,
    /// Newton projection onto each zero level set stops within this distance (voxels).
    pub projection_tolerance_voxels: f64,
    /// The program that wrote the representation and its version.
    pub software: String,
}

/// A multiscale representation (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct Msr {
    /// Triangles of the original mesh; its vertices are samples `0..num_vertices`.
    pub faces: Vec<[u32; 3]>,
    /// Number of samples that are vertices of the original mesh.
    pub num_vertices: usize,
    /// For each extra sample (`num_vertices..`): the original face it was sampled on.
    pub extra_face: Vec<u32>,
    /// ... and its barycentric coordinates in that face.
    pub extra_bary: Vec<[f64; 3]>,
    /// X_N: every sample at the coarsest scale.
    pub samples: Vec<Point3<f64>>,
    /// `details[i − 1]` = W_i = X_i − X_{i−1}, one vector per sample.
    pub details: Vec<Vec<Vector3<f64>>>,
    /// `normal_details[i − 1]` = w_i = W_i·n_i (n_i the outward normal of φ(t_i) at X_i).
    pub normal_details: Vec<Vec<f64>>,
    /// `normals[i]` = n_i, the outward unit normal of S_i at each sample X_i (i = 0..=N), from
    /// ∇φ(t_i): what the level-set reconstruction orients each sample's tangent plane by.
    pub normals: Vec<Vec<Vector3<f64>>>,
    /// t_0 = 0 < t_1 < … < t_N = T.
    pub times: Vec<f64>,
    /// φ(t_N), the coarsest shape.
    pub phi: Grid3,
    /// How it was made.
    pub params: MsrParams,
}

impl Msr {
    /// Number of levels N.
    pub fn levels(&self) -> usize {
        self.details.len()
    }

    /// X_k, the samples at scale k (0 = the input, N = the coarsest): X_N − Σ_{i=k+1}^{N} W_i.
    pub fn samples_at(&self, k: usize) -> Vec<Point3<f64>> {
        let mut x = self.samples.clone();
        for w in self.details.iter().skip(k) {
            for (p, d) in x.iter_mut().zip(w) {
                *p -= d;
            }
        }
        x
    }

    /// S_k as a mesh: the original triangles on the vertex samples of scale k.
    pub fn mesh_at(&self, k: usize) -> TriMesh {
        let mut x = self.samples_at(k);
        x.truncate(self.num_vertices);
        TriMesh::new(x, self.faces.clone())
    }
}
