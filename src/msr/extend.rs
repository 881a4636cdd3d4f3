//! Extension of per-sample details to the grid (paper Section 2, the extension of W_i from the
//! sample points to a band around the zero level set, constant along normals, by local search).
//!
//! A node y of the band takes its foot point on the zero level set, f = y − φ(y)∇φ(y)/|∇φ(y)|²
//! (the closest point when φ is a signed distance), and there the mean of the values of the
//! nearest samples (see [`extend_to_band`]). So the value is constant along each normal line, as
//! the paper's extension is. The samples are found through a uniform hash grid.

use crate::grid::Grid3;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::collections::HashMap;

/// Points bucketed in a uniform grid of cubic cells, for radius queries.
pub struct PointIndex<'a> {
    points: &'a [Point3<f64>],
    cell: f64,
    buckets: HashMap<[i64; 3], Vec<u32>>,
}

impl<'a> PointIndex<'a> {
    /// Buckets `points` in cells of edge `cell` (world units, > 0).
    pub fn new(points: &'a [Point3<f64>], cell: f64) -> Self {
        let mut buckets: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            buckets.entry(key(p, cell)).or_default().push(i as u32);
        }
        PointIndex {
            points,
            cell,
            buckets,
        }
    }

    /// Calls `f(index, distance)` for every point within `radius` of `p`.
    pub fn for_each_within(&self, p: &Point3<f64>, radius: f64, mut f: impl FnMut(u32, f64)) {
        let reach = (radius / self.cell).ceil() as i64;
        let c = key(p, self.cell);
        for dz in -reach..=reach {
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    let Some(bucket) = self.buckets.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &i in bucket {
                        let d = (self.points[i as usize] - p).norm();
                        if d <= radius {
                            f(i, d);
                        }
                    }
                }
            }
        }
    }
}

fn key(p: &Point3<f64>, cell: f64) -> [i64; 3] {
    [p.x, p.y, p.z].map(|v| (v / cell).floor() as i64)
}

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

/// Extends `values` (one per point of `points`) to every node with |φ| ≤ `band` (world units).
/// Each node queries around its foot point or itself (`from`) and takes the mean of the values
/// of the samples there, weighted by exp(−(d² − d_min²)/2σ²) with σ = `radius`/2, so the
/// nearest samples dominate; the search radius (`radius` world units at first) doubles until it
/// finds a sample or passes `band` + `radius`. With [`ExtendFrom::FootPoint`] and samples on
/// the zero level set, this is the paper's extension constant along normals.
pub fn extend_to_band(
    phi: &Grid3,
    points: &[Point3<f64>],
    values: &[Vector3<f64>],
    band: f64,
    radius: f64,
    from: ExtendFrom,
) -> NodeField {
    let index = PointIndex::new(points, radius);
    let two_sigma2 = 2.0 * (0.5 * radius).powi(2);
    (0..phi.data().len())
        .into_par_iter()
        .map(|n| {
            let v = phi.data()[n] as f64;
            if v.abs() > band {
                return None;
            }
            let [i, j, k] = phi.coords(n);
            let y = phi.world(i, j, k);
            let query = match from {
                ExtendFrom::Node => y,
                ExtendFrom::FootPoint => {
                    let (value, g) = phi.sample_tricubic_with_gradient(&y)?;
                    let g2 = g.norm_squared();
                    if g2 > 1e-12 {
                        y - value * g / g2
                    } else {
                        y
                    }
                }
            };
            let mut r = radius;
            loop {
                let mut found: Vec<(u32, f64)> = Vec::new();
                index.for_each_within(&query, r, |s, d| found.push((s, d)));
                if let Some(dmin) = found.iter().map(|f| f.1).reduce(f64::min) {
                    let (mut sum, mut weight) = (Vector3::zeros(), 0.0);
                    for (s, d) in found {
                        let w = (-(d * d - dmin * dmin) / two_sigma2).exp();
                        sum += values[s as usize] * w;
                        weight += w;
                    }
                    return Some(sum / weight);
                }
                if r > band + radius {
                    return None;
                }
                r *= 2.0;
            }
        })
        .collect()
}
