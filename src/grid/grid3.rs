//! `Grid3`: a dense grid of f32 values stored flat with x fastest (index = i + nx·(j + ny·k)).

use super::GridTransform;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// A dense grid of f32 values with its index↔world transform.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid3 {
    dims: [usize; 3],
    transform: GridTransform,
    data: Vec<f32>,
}

impl Grid3 {
    /// A grid of `dims` nodes filled with `fill`. Errors when a dimension is zero, the node count
    /// overflows, or the voxel size is not positive and finite.
    pub fn new(dims: [usize; 3], transform: GridTransform, fill: f32) -> Result<Self> {
        let len = Self::node_count(dims)?;
        check_voxel(&transform)?;
        Ok(Grid3 {
            dims,
            transform,
            data: vec![fill; len],
        })
    }

    /// A grid over existing values (`data.len()` must equal the node count).
    pub fn from_data(dims: [usize; 3], transform: GridTransform, data: Vec<f32>) -> Result<Self> {
        let len = Self::node_count(dims)?;
        if data.len() != len {
            return Err(Error::Geometry(format!(
                "grid of {}×{}×{} nodes needs {len} values, got {}",
                dims[0],
                dims[1],
                dims[2],
                data.len()
            )));
        }
        check_voxel(&transform)?;
        Ok(Grid3 {
            dims,
            transform,
            data,
        })
    }

    /// Number of nodes of a grid of `dims`, or an error when zero or overflowing.
    pub fn node_count(dims: [usize; 3]) -> Result<usize> {
        let n = dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .filter(|&n| n > 0 && dims.iter().all(|&d| d > 0));
        n.ok_or_else(|| Error::Geometry(format!("invalid grid dimensions {dims:?}")))
    }

    /// Nodes along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The index↔world transform.
    pub fn transform(&self) -> &GridTransform {
        &self.transform
    }

    /// Voxel edge length, world units.
    pub fn voxel(&self) -> f64 {
        self.transform.voxel
    }

    /// The values, x fastest.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// The values, mutable, x fastest.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// Consumes the grid, returning its values.
    pub fn into_data(self) -> Vec<f32> {
        self.data
    }

    /// Flat index of node (i, j, k).
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Node (i, j, k) of a flat index.
    #[inline]
    pub fn coords(&self, index: usize) -> [usize; 3] {
        let i = index % self.dims[0];
        let jk = index / self.dims[0];
        [i, jk % self.dims[1], jk / self.dims[1]]
    }

    /// Value at node (i, j, k).
    #[inline]
    pub fn get(&self, i: usize, j: usize, k: usize) -> f32 {
        self.data[self.index(i, j, k)]
    }

    /// Sets the value at node (i, j, k).
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, k: usize, value: f32) {
        let idx = self.index(i, j, k);
        self.data[idx] = value;
    }

    /// World position of node (i, j, k).
    #[inline]
    pub fn world(&self, i: usize, j: usize, k: usize) -> Point3<f64> {
        self.transform
            .index_to_world(Vector3::new(i as f64, j as f64, k as f64))
    }
}

fn check_voxel(transform: &GridTransform) -> Result<()> {
    if transform.voxel.is_finite() && transform.voxel > 0.0 {
        Ok(())
    } else {
        Err(Error::Geometry(format!(
            "voxel size must be positive and finite, got {}",
            transform.voxel
        )))
    }
}

/// The face neighbours (up to 6) of node `n` of a grid of `dims` (x fastest).
pub fn face_neighbours(dims: [usize; 3], n: usize) -> impl Iterator<Item = usize> {
    let [nx, ny, nz] = dims;
    let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
    let (sy, sz) = (nx, nx * ny);
    [
        (i > 0).then(|| n - 1),
        (i + 1 < nx).then(|| n + 1),
        (j > 0).then(|| n - sy),
        (j + 1 < ny).then(|| n + sy),
        (k > 0).then(|| n - sz),
        (k + 1 < nz).then(|| n + sz),
    ]
    .into_iter()
    .flatten()
}
