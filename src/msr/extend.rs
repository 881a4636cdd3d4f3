//! Extension of per-sample details to the grid (paper Section 2, the extension of W_i from the
//! sample points to a band around the zero level set, constant along normals, by local search).
//!
//! A node y of the band takes its foot point on the zero level set, f = y − φ(y)∇φ(y)/|∇φ(y)|²
//! (the closest point when φ is a signed distance), and there the mean of the values of the
//! nearest samples (see [`extend_to_band`]). So the value is constant along each normal line, as
//! the paper's extension is. The samples are found through a [`SampleIndex`].

use super::buckets::VoxelBuckets;
use crate::grid::Grid3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::num::NonZero;

/// A vector field on the nodes of a grid: `None` where it was not extended.
pub type NodeField = Vec<Option<Vector3<f64>>>;

/// Where a node looks for the samples whose values it takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ExtendFrom {
    /// Around its foot point on the zero level set of φ: constant along normals (the paper).
    #[default]
    FootPoint,
    /// Around the node itself (the samples then need not lie on φ's zero level set).
    Node,
}

/// Samples each node takes its value from (the nearest ones).
const NEAREST: usize = 8;

/// Largest reach (voxels) searched through [`VoxelBuckets`]; a farther one through a k-d tree,
/// whose cost does not grow with the distance to the nearest sample as the buckets' rings do.
const BUCKETS_REACH: f64 = 6.0;

/// Extends `values` (one per point of `points`) to every node with |φ| ≤ `band` (world units).
/// Each node queries around its foot point or itself (`from`), finds its `NEAREST` samples
/// ([`SampleIndex`]) and takes the mean of their values weighted by exp(−(d² − d_min²)/2σ²), σ =
/// `radius`/2, so the nearest samples dominate and farther ones only smooth ties. A node whose
/// nearest sample is farther than `band` + `radius` gets `None`. With [`ExtendFrom::FootPoint`]
/// and samples on the zero level set, this is the paper's extension constant along normals.
pub fn extend_to_band(
    phi: &Grid3,
    points: &[Point3<f64>],
    values: &[Vector3<f64>],
    band: f64,
    radius: f64,
    from: ExtendFrom,
) -> NodeField {
    weighted_nearest(phi, points, band, radius, band + radius, from, |s, _| {
        values[s]
    })
}

/// The weighted mean over the nearest samples of `value(sample, query point)`, at every node
/// with |φ| ≤ `band` whose nearest sample is within `reach` (world units) of its query point
/// (the machinery of [`extend_to_band`], for any value that can be averaged). A small `reach`
/// makes the queries of far nodes stop early.
pub fn weighted_nearest<T>(
    phi: &Grid3,
    points: &[Point3<f64>],
    band: f64,
    radius: f64,
    reach: f64,
    from: ExtendFrom,
    value: impl Fn(usize, &Point3<f64>) -> T + Sync,
) -> Vec<Option<T>>
where
    T: Copy + Send + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    let two_sigma2 = 2.0 * (0.5 * radius).powi(2);
    reduce_nearest(phi, points, band, reach, from, |y, found| {
        let d2min = found.first()?.1;
        let mut sum: Option<T> = None;
        let mut weight = 0.0;
        for &(s, d2) in found {
            let w = (-(d2 - d2min) / two_sigma2).exp();
            let term = value(s, y) * w;
            sum = Some(match sum {
                Some(acc) => acc + term,
                None => term,
            });
            weight += w;
        }
        sum.map(|acc| acc * (1.0 / weight))
    })
}

/// At every node with |φ| ≤ `band` whose nearest sample is within `reach` (world units) of its
/// query point (`from`): `reduce(node, nearest)` over its `NEAREST` nearest samples, given as
/// (index, squared distance to the query point), nearest first and all within `reach`.
pub fn reduce_nearest<T>(
    phi: &Grid3,
    points: &[Point3<f64>],
    band: f64,
    reach: f64,
    from: ExtendFrom,
    reduce: impl Fn(&Point3<f64>, &[(usize, f64)]) -> Option<T> + Sync,
) -> Vec<Option<T>>
where
    T: Send,
{
    let Some(index) = SampleIndex::new(phi, points, reach) else {
        return (0..phi.data().len()).map(|_| None).collect();
    };
    (0..phi.data().len())
        .into_par_iter()
        .map(|n| {
            let v = phi.data()[n] as f64;
            if v.abs() > band {
                return None;
            }
            let [i, j, kk] = phi.coords(n);
            let y = phi.world(i, j, kk);
            let found = match from {
                ExtendFrom::Node => index.nearest_to_node(&y),
                ExtendFrom::FootPoint => {
                    let (value, g) = phi.sample_tricubic_with_gradient(&y)?;
                    let g2 = g.norm_squared();
                    let foot = if g2 > 1e-12 { y - value * g / g2 } else { y };
                    index.nearest(&foot)
                }
            };
            if found.is_empty() {
                return None;
            }
            reduce(&y, &found)
        })
        .collect()
}

/// The samples of a level, indexed for the queries of the nodes of one grid: the `NEAREST`
/// samples within `reach` (world units) of a point, through [`VoxelBuckets`] for a reach of up
/// to `BUCKETS_REACH` voxels (the tangent planes' few voxels), else through a k-d tree
/// (kiddo) with a coarse occupancy grid that answers "none" at once for the nodes far from
/// every sample (the buckets' block distances do that themselves).
pub struct SampleIndex {
    search: Search,
    reach: f64,
}

enum Search {
    Buckets(VoxelBuckets),
    Tree(ImmutableKdTree<f64, 3>, NearSamples),
}

impl SampleIndex {
    /// `None` when there are no samples.
    pub fn new(phi: &Grid3, points: &[Point3<f64>], reach: f64) -> Option<Self> {
        if points.is_empty() {
            return None;
        }
        let search = if reach <= BUCKETS_REACH * phi.voxel() {
            Search::Buckets(VoxelBuckets::new(phi, points))
        } else {
            let coords: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
            Search::Tree(
                ImmutableKdTree::new_from_slice(&coords).ok()?,
                NearSamples::new(phi, points, reach),
            )
        };
        Some(SampleIndex { search, reach })
    }

    /// The nearest samples within reach of `query` (anywhere), as (index, squared distance),
    /// nearest first.
    pub fn nearest(&self, query: &Point3<f64>) -> Vec<(usize, f64)> {
        match &self.search {
            Search::Buckets(buckets) => buckets
                .nearest(query, NEAREST, self.reach)
                .as_slice()
                .iter()
                .map(|&(s, d2)| (s as usize, d2))
                .collect(),
            Search::Tree(tree, _) => {
                let reach2 = self.reach * self.reach;
                let k = NonZero::new(NEAREST.min(tree.size())).expect("k ≥ 1");
                tree.query(&[query.x, query.y, query.z])
                    .nearest_n::<SquaredEuclidean<f64>>(k)
                    .within(reach2)
                    .execute()
                    .into_iter()
                    .filter(|f| f.distance <= reach2)
                    .map(|f| (f.item as usize, f.distance))
                    .collect()
            }
        }
    }

    /// [`Self::nearest`] for a point inside the grid's box (a node), skipping the tree's search
    /// where its occupancy grid has no sample.
    pub fn nearest_to_node(&self, y: &Point3<f64>) -> Vec<(usize, f64)> {
        match &self.search {
            Search::Tree(_, near) if !near.may_have(y) => Vec::new(),
            _ => self.nearest(y),
        }
    }
}

/// A coarse occupancy grid of the samples (cells of edge `reach`, dilated by one cell): a point
/// whose cell is empty has no sample within `reach`, so its search can be skipped.
struct NearSamples {
    origin: Point3<f64>,
    cell: f64,
    dims: [usize; 3],
    occupied: Vec<bool>,
}

impl NearSamples {
    fn new(phi: &Grid3, points: &[Point3<f64>], reach: f64) -> Self {
        let origin = phi.transform().index_to_world(Vector3::zeros());
        let extent = phi.dims().map(|d| (d.max(1) - 1) as f64 * phi.voxel());
        let cell = reach.max(phi.voxel());
        let dims = extent.map(|e| (e / cell).floor() as usize + 1);
        let mut occupied = vec![false; dims[0] * dims[1] * dims[2]];
        let key = |p: &Point3<f64>| -> Option<[usize; 3]> {
            let mut k = [0usize; 3];
            for a in 0..3 {
                let c = ((p[a] - origin[a]) / cell).floor();
                if !(c >= -1.0 && c <= dims[a] as f64) {
                    return None;
                }
                k[a] = c.clamp(0.0, (dims[a] - 1) as f64) as usize;
            }
            Some(k)
        };
        for p in points {
            if let Some([x, y, z]) = key(p) {
                occupied[x + dims[0] * (y + dims[1] * z)] = true;
            }
        }
        // Dilated by one cell (the 26 neighbours), one axis at a time.
        let stride = [1, dims[0], dims[0] * dims[1]];
        for a in 0..3 {
            let src = occupied.clone();
            occupied.par_iter_mut().enumerate().for_each(|(n, v)| {
                let c = (n / stride[a]) % dims[a];
                *v = src[n]
                    || (c > 0 && src[n - stride[a]])
                    || (c + 1 < dims[a] && src[n + stride[a]]);
            });
        }
        NearSamples {
            origin,
            cell,
            dims,
            occupied,
        }
    }

    /// Whether a sample may lie within `reach` of `p` (p inside the grid's box).
    fn may_have(&self, p: &Point3<f64>) -> bool {
        let mut k = [0usize; 3];
        for a in 0..3 {
            let c = ((p[a] - self.origin[a]) / self.cell).floor();
            k[a] = c.clamp(0.0, (self.dims[a] - 1) as f64) as usize;
        }
        self.occupied[k[0] + self.dims[0] * (k[1] + self.dims[1] * k[2])]
    }
}
