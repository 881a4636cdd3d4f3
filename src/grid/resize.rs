//! Changing a grid's extent: padding by whole voxels, and sub-boxes of nodes that can be extracted
//! as grids of their own (with their own transform) and written back into the parent; and its
//! resolution: every n-th node as a coarser grid over the same nodes' positions.
//!
//! A [`SubBox`] is a half-open box of node indices, `min ≤ (i, j, k) < max` per axis, like a Rust
//! range. Node (i, j, k) of an extracted grid is node `min + (i, j, k)` of its parent, and both
//! sit at the same world position.

use super::{Grid3, GridTransform};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::ops::Range;

/// Slack of [`SubBox::around_world`], in voxels.
const ROUND_OFF: f64 = 1e-9;

/// A box of node indices `min ≤ (i, j, k) < max` (half-open on each axis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SubBox {
    /// First node on each axis (inclusive).
    pub min: [usize; 3],
    /// One past the last node on each axis (exclusive).
    pub max: [usize; 3],
}

impl SubBox {
    /// The box `min ≤ (i, j, k) < max`.
    pub fn new(min: [usize; 3], max: [usize; 3]) -> SubBox {
        SubBox { min, max }
    }

    /// All the nodes of a grid of `dims`.
    pub fn whole(dims: [usize; 3]) -> SubBox {
        SubBox {
            min: [0; 3],
            max: dims,
        }
    }

    /// Nodes along each axis (0 where `max ≤ min`).
    pub fn dims(&self) -> [usize; 3] {
        [0, 1, 2].map(|a| self.max[a].saturating_sub(self.min[a]))
    }

    /// Number of nodes in the box.
    pub fn node_count(&self) -> usize {
        self.dims().iter().product()
    }

    /// Whether the box holds no node.
    pub fn is_empty(&self) -> bool {
        self.dims().contains(&0)
    }

    /// Whether node `ijk` lies in the box.
    pub fn contains(&self, ijk: [usize; 3]) -> bool {
        (0..3).all(|a| self.min[a] <= ijk[a] && ijk[a] < self.max[a])
    }

    /// Whether the box is non-empty and lies within a grid of `dims`.
    pub fn fits(&self, dims: [usize; 3]) -> bool {
        !self.is_empty() && (0..3).all(|a| self.max[a] <= dims[a])
    }

    /// The nodes in both boxes (possibly empty).
    pub fn intersection(&self, other: &SubBox) -> SubBox {
        SubBox {
            min: [0, 1, 2].map(|a| self.min[a].max(other.min[a])),
            max: [0, 1, 2].map(|a| self.max[a].min(other.max[a])),
        }
    }

    /// The box grown by `n` nodes on every side, clipped to a grid of `dims`.
    pub fn dilate(&self, n: usize, dims: [usize; 3]) -> SubBox {
        SubBox {
            min: [0, 1, 2].map(|a| self.min[a].saturating_sub(n).min(dims[a])),
            max: [0, 1, 2].map(|a| self.max[a].saturating_add(n).min(dims[a])),
        }
    }

    /// The nodes of a grid (`transform`, `dims`) whose positions lie in the closed world box
    /// `[lo, hi]` (give or take 1e-9 voxel, for round-off), clipped to the grid; empty when the
    /// boxes do not meet or a bound is NaN.
    pub fn around_world(
        lo: &Point3<f64>,
        hi: &Point3<f64>,
        transform: &GridTransform,
        dims: [usize; 3],
    ) -> SubBox {
        let a = transform.world_to_index(lo);
        let b = transform.world_to_index(hi);
        let mut min = [0usize; 3];
        let mut max = [0usize; 3];
        for axis in 0..3 {
            let first = (a[axis] - ROUND_OFF).ceil();
            let last = (b[axis] + ROUND_OFF).floor();
            let n = dims[axis] as f64;
            // NaN bounds leave the axis empty (min = max = 0).
            if first <= last && last >= 0.0 && first < n {
                min[axis] = first.max(0.0) as usize;
                max[axis] = ((last + 1.0).min(n)) as usize;
            }
        }
        SubBox { min, max }
    }

    /// The nodes of the box, x fastest (then y, then z).
    pub fn nodes(&self) -> impl Iterator<Item = [usize; 3]> {
        let empty = self.is_empty();
        let (min, max) = (self.min, self.max);
        (min[2]..if empty { min[2] } else { max[2] }).flat_map(move |k| {
            (min[1]..max[1]).flat_map(move |j| (min[0]..max[0]).map(move |i| [i, j, k]))
        })
    }

    /// The box's rows along x in a grid of `dims`: `(j, k, flat index range)`, y then z. The box
    /// must fit the grid (see [`SubBox::fits`]); rows of an empty box are none.
    pub fn rows(&self, dims: [usize; 3]) -> impl Iterator<Item = (usize, usize, Range<usize>)> {
        let (min, max) = (self.min, self.max);
        let empty = self.is_empty();
        (min[2]..if empty { min[2] } else { max[2] }).flat_map(move |k| {
            (min[1]..max[1]).map(move |j| {
                let start = min[0] + dims[0] * (j + dims[1] * k);
                (j, k, start..start + (max[0] - min[0]))
            })
        })
    }
}

impl Grid3 {
    /// All the nodes of this grid as a [`SubBox`].
    pub fn whole_box(&self) -> SubBox {
        SubBox::whole(self.dims())
    }

    /// A copy grown by `n` nodes on every side, the new nodes set to `fill`; node (i, j, k) of
    /// this grid is node (i + n, j + n, k + n) of the result, whose origin is shifted by −n·h so
    /// every old node keeps its world position. Errors when the grown grid's size overflows.
    pub fn pad(&self, n: usize, fill: f32) -> Result<Grid3> {
        let dims = self.dims();
        let grown = dims
            .iter()
            .map(|&d| n.checked_mul(2).and_then(|m| m.checked_add(d)))
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| Error::Geometry(format!("padding {dims:?} by {n} overflows")))?;
        let new_dims = [grown[0], grown[1], grown[2]];
        let origin = self
            .transform()
            .index_to_world(Vector3::from_element(-(n as f64)));
        let transform = GridTransform::new(origin, self.voxel());
        let mut out = Grid3::new(new_dims, transform, fill)?;
        out.write_back(&SubBox::new([n; 3], [0, 1, 2].map(|a| n + dims[a])), self)?;
        Ok(out)
    }

    /// The nodes of `sub_box` as a grid of their own, whose node (0, 0, 0) sits where node
    /// `sub_box.min` of this grid does (same voxel size). Errors when the box is empty or does
    /// not fit in this grid.
    pub fn extract(&self, sub_box: &SubBox) -> Result<Grid3> {
        self.check_box(sub_box)?;
        let [i, j, k] = sub_box.min;
        let transform = GridTransform::new(self.world(i, j, k), self.voxel());
        let mut data = Vec::with_capacity(sub_box.node_count());
        for (_, _, row) in sub_box.rows(self.dims()) {
            data.extend_from_slice(&self.data()[row]);
        }
        Grid3::from_data(sub_box.dims(), transform, data)
    }

    /// Copies the values of `sub` (typically a grid [`Grid3::extract`]ed with the same box and
    /// since modified) into the nodes of `sub_box`. Errors when the box is empty, does not fit in
    /// this grid, or has not the dimensions of `sub`. Transforms are not compared.
    pub fn write_back(&mut self, sub_box: &SubBox, sub: &Grid3) -> Result<()> {
        self.check_box(sub_box)?;
        if sub.dims() != sub_box.dims() {
            return Err(Error::Geometry(format!(
                "a grid of {:?} nodes cannot be written into a sub-box of {:?} nodes",
                sub.dims(),
                sub_box.dims()
            )));
        }
        let row_len = sub_box.dims()[0];
        let dims = self.dims();
        let src = sub.data().chunks_exact(row_len);
        for ((_, _, row), values) in sub_box.rows(dims).zip(src) {
            self.data_mut()[row].copy_from_slice(values);
        }
        Ok(())
    }

    /// Every `stride`-th node on each axis, from node (0, 0, 0), as a grid of its own: voxel
    /// `stride` times this grid's, node (i, j, k) where this grid's (stride·i, stride·j,
    /// stride·k) is, with its value (no filtering: a signed distance's nodes are samples of the
    /// same field). (n − 1)/stride + 1 nodes on an axis of n. Errors when `stride` is 0; a stride
    /// of 1 gives a copy.
    pub fn subsample(&self, stride: usize) -> Result<Grid3> {
        if stride == 0 {
            return Err(Error::Geometry(
                "a grid cannot be subsampled with a stride of 0".into(),
            ));
        }
        let [nx, ny, nz] = self.dims();
        let dims = [nx, ny, nz].map(|n| (n - 1) / stride + 1);
        let mut data = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                let row = self.index(0, j * stride, k * stride);
                data.extend(self.data()[row..row + nx].iter().step_by(stride));
            }
        }
        let transform = GridTransform::new(self.world(0, 0, 0), self.voxel() * stride as f64);
        Grid3::from_data(dims, transform, data)
    }

    fn check_box(&self, sub_box: &SubBox) -> Result<()> {
        if sub_box.fits(self.dims()) {
            Ok(())
        } else {
            Err(Error::Geometry(format!(
                "sub-box {:?}..{:?} is empty or outside the grid of {:?} nodes",
                sub_box.min,
                sub_box.max,
                self.dims()
            )))
        }
    }
}
