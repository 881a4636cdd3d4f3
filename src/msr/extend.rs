//! Extension of per-sample details to the grid (paper Section 2, the extension of W_i from the
//! sample points to a band around the zero level set, constant along normals, by local search).
//!
//! A node y of the band takes its foot point on the zero level set, f = y − φ(y)∇φ(y)/|∇φ(y)|²
//! (the closest point when φ is a signed distance), and there the mean of the values of the
//! samples within `radius` of f, weighted by a Gaussian of the distance (σ = radius/2). So the
//! value is constant along each normal line, as the paper's extension is. The samples are found
//! through a uniform hash grid of cell `radius`.

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

/// Extends `values` (one per point of `points`, which lie on the zero level set of `phi`) to
/// every node with |φ| ≤ `band` (world units), constant along normals (see the module doc);
/// `radius` (world units) is the search radius around each foot point, doubled up to three times
/// where it finds no sample.
pub fn extend_along_normals(
    phi: &Grid3,
    points: &[Point3<f64>],
    values: &[Vector3<f64>],
    band: f64,
    radius: f64,
) -> NodeField {
    let index = PointIndex::new(points, radius);
    let sigma2 = (0.5 * radius).powi(2);
    (0..phi.data().len())
        .into_par_iter()
        .map(|n| {
            let v = phi.data()[n] as f64;
            if v.abs() > band {
                return None;
            }
            let [i, j, k] = phi.coords(n);
            let y = phi.world(i, j, k);
            let (value, g) = phi.sample_tricubic_with_gradient(&y)?;
            let g2 = g.norm_squared();
            let foot = if g2 > 1e-12 { y - value * g / g2 } else { y };
            let mut r = radius;
            for _ in 0..4 {
                let (mut sum, mut weight) = (Vector3::zeros(), 0.0);
                index.for_each_within(&foot, r, |s, d| {
                    let w = (-d * d / (2.0 * sigma2 * (r / radius).powi(2))).exp();
                    sum += values[s as usize] * w;
                    weight += w;
                });
                if weight > 0.0 {
                    return Some(sum / weight);
                }
                r *= 2.0;
            }
            None
        })
        .collect()
}
