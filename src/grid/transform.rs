//! The index↔world transform of a grid: node (i, j, k) sits at `origin + voxel · (i, j, k)`
//! (world units; the voxel is a cube of side `voxel`).

use nalgebra::{Point3, Vector3};

/// Maps grid indices to world positions and back.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GridTransform {
    /// World position of node (0, 0, 0).
    pub origin: [f64; 3],
    /// Edge length of a voxel, in world units (> 0).
    pub voxel: f64,
}

impl GridTransform {
    /// A transform with node (0, 0, 0) at `origin` and voxel size `voxel` (world units).
    pub fn new(origin: Point3<f64>, voxel: f64) -> Self {
        GridTransform {
            origin: origin.into(),
            voxel,
        }
    }

    /// World position of the (possibly fractional) index `ijk`.
    pub fn index_to_world(&self, ijk: Vector3<f64>) -> Point3<f64> {
        Point3::from(self.origin) + ijk * self.voxel
    }

    /// Continuous index of the world position `p`.
    pub fn world_to_index(&self, p: &Point3<f64>) -> Vector3<f64> {
        (p - Point3::from(self.origin)) / self.voxel
    }
}
