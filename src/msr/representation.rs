//! The multiscale representation as data: sample points X_N at the coarsest scale, the details
//! W_1..W_N (displacements of every sample from scale i−1 to scale i, paper Algorithm 1), their
//! normal components w_i = W_i·n (positive outward), the scale times t_0..t_N, the level set
//! φ_T of the coarsest shape, and the parameters used. Reconstruction by vertices (the paper's
//! Remark 2.2(4)) is exact: since W_i = X_i − X_{i−1}, X_k = X_N − Σ_{i=k+1}^{N} W_i, and the
//! input is X_0 less the snap of each input sample onto the zero level set of φ_0.
//!
//! Two kinds of samples: those of the input (its vertices, then extra points on its triangles),
//! which start on the mesh and are snapped onto S_0 = {φ_0 = 0} (the level set the
//! decomposition and the level-set reconstruction work with, which differs from the mesh by a
//! fraction of a voxel where the mesh has features finer than the grid); and samples added on
//! S_b where the samples carried from the levels before left gaps (born at level b, with no
//! detail before: W_i = 0 and n_i = 0 for i ≤ b, resp. i < b).

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
    /// For each input sample (the first `snap.len()` = `num_vertices + extra_face.len()`
    /// samples): X_0 − its position on the input mesh.
    pub snap: Vec<Vector3<f64>>,
    /// For every sample: the level at which it joined (0 for the input's; see the module doc).
    pub born: Vec<u32>,
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

    /// X_k, the samples at scale k (on S_k; 0 = the finest, N = the coarsest):
    /// X_N − Σ_{i=k+1}^{N} W_i. A sample born after k is at its position at birth.
    pub fn samples_at(&self, k: usize) -> Vec<Point3<f64>> {
        let mut x = self.samples.clone();
        for w in self.details.iter().skip(k) {
            for (p, d) in x.iter_mut().zip(w) {
                *p -= d;
            }
        }
        x
    }

    /// The input samples where they were on the input mesh (X_0 less the snap): its vertices,
    /// then the extra points on its triangles.
    pub fn input_samples(&self) -> Vec<Point3<f64>> {
        let mut x = self.samples_at(0);
        x.truncate(self.snap.len());
        for (p, s) in x.iter_mut().zip(&self.snap) {
            *p -= s;
        }
        x
    }

    /// S_k as a mesh: the original triangles on the vertex samples of scale k; for k = 0 the
    /// input mesh itself (X_0 less the snap).
    pub fn mesh_at(&self, k: usize) -> TriMesh {
        let mut x = if k == 0 {
            self.input_samples()
        } else {
            self.samples_at(k)
        };
        x.truncate(self.num_vertices);
        TriMesh::new(x, self.faces.clone())
    }

    /// What the level-set reconstruction of S_{i−1} from S_i reads (1 ≤ i ≤ N): the samples
    /// that exist at level i − 1, as (X_{i−1}, n_{i−1}, W_i).
    pub fn level_data(&self, i: usize) -> LevelData {
        let x = self.samples_at(i - 1);
        let mut out = LevelData::default();
        for (k, p) in x.iter().enumerate() {
            if self.exists_before(k, i) {
                out.points.push(*p);
                out.normals.push(self.normals[i - 1][k]);
                out.details.push(self.details[i - 1][k]);
            }
        }
        out
    }

    /// φ of level i − 1 rebuilt from `above`, φ of level i, by level i's details: the
    /// level-set IMST step ([`super::reconstruct::rebuild_from_tangent_planes`] with the
    /// default options), as `vesselmsr reconstruct --method levelset` takes it.
    pub fn rebuild_level(&self, above: &Grid3, i: usize) -> crate::Result<Grid3> {
        let data = self.level_data(i);
        super::reconstruct::rebuild_from_tangent_planes(
            above,
            &data.points,
            &data.normals,
            &data.details,
            &super::reconstruct::AdvectOptions::default(),
        )
    }

    /// The normal details w_i of the samples that exist at level i − 1 (1 ≤ i ≤ N).
    pub fn level_normal_details(&self, i: usize) -> Vec<f64> {
        (self.normal_details[i - 1].iter().enumerate())
            .filter(|&(k, _)| self.exists_before(k, i))
            .map(|(_, w)| *w)
            .collect()
    }

    /// The longest detail vector |W_i| over every level and sample (world units; 0 without
    /// levels).
    pub fn largest_detail(&self) -> f64 {
        self.details
            .iter()
            .flatten()
            .map(|w| w.norm())
            .fold(0.0, f64::max)
    }

    /// Whether sample `k` exists at level i − 1 (it was born there or before).
    fn exists_before(&self, k: usize, i: usize) -> bool {
        (self.born[k] as usize) < i
    }
}

/// The samples of one level of an [`Msr`] ([`Msr::level_data`]).
#[derive(Debug, Clone, Default)]
pub struct LevelData {
    /// X_{i−1}.
    pub points: Vec<Point3<f64>>,
    /// n_{i−1}.
    pub normals: Vec<Vector3<f64>>,
    /// W_i = X_i − X_{i−1}.
    pub details: Vec<Vector3<f64>>,
}
