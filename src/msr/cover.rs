//! Denser samples where a level needs them (paper Algorithm 1: "the sample points, plus denser
//! samples where needed"). The samples of scale i are those of scale i−1 projected onto S_i, and
//! orthogonal projection is not onto: where S_i bulges past S_{i−1} or a fold of S_{i−1} closes,
//! patches of S_i are left with no sample near them, and the level-set reconstruction has nothing
//! there to rebuild S_i from. The gaps are found among the vertices of the marching-cubes surface
//! of φ (a point every fraction of a voxel on the zero level set): a vertex with no sample within
//! the covering radius becomes a new sample, Newton-projected onto the zero level set, and covers
//! its neighbourhood in turn (greedy, in vertex order, so the result is deterministic).

use super::project::{project_to_zero_level, LevelProjectOptions};
use crate::grid::Grid3;
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::Result;
use foldhash::fast::FixedState;
use nalgebra::Point3;
use std::collections::HashMap;

/// New samples on the zero level set of `phi` so that every vertex of its marching-cubes surface
/// has a sample (of `samples` or of the new ones) within `radius` (world units). The new
/// samples are projected with `projection`; those that do not converge are dropped.
pub fn cover_gaps(
    phi: &Grid3,
    samples: &[Point3<f64>],
    radius: f64,
    projection: &LevelProjectOptions,
) -> Result<Vec<Point3<f64>>> {
    let surface = extract_surface(phi, &ExtractOptions::default())?;
    let mut hash = PointHash::new(radius, samples.len() + surface.vertices.len());
    for p in samples {
        hash.insert(*p);
    }
    let mut candidates = Vec::new();
    for v in &surface.vertices {
        if !hash.has_within(v, radius) {
            hash.insert(*v);
            candidates.push(*v);
        }
    }
    Ok(project_to_zero_level(phi, &candidates, projection)
        .into_iter()
        .filter(|p| p.converged)
        .map(|p| p.point)
        .collect())
}

/// Points bucketed in cubic cells of edge `cell` (world units): each occupied cell holds the
/// head of a chain through the points it contains.
struct PointHash {
    cell: f64,
    heads: HashMap<[i64; 3], u32, FixedState>,
    points: Vec<Point3<f64>>,
    next: Vec<u32>,
}

/// The end of a chain.
const NONE: u32 = u32::MAX;

impl PointHash {
    fn new(cell: f64, capacity: usize) -> Self {
        PointHash {
            cell,
            heads: HashMap::with_capacity_and_hasher(capacity, FixedState::default()),
            points: Vec::with_capacity(capacity),
            next: Vec::with_capacity(capacity),
        }
    }

    fn key(&self, p: &Point3<f64>) -> [i64; 3] {
        [0, 1, 2].map(|a| (p[a] / self.cell).floor() as i64)
    }

    fn insert(&mut self, p: Point3<f64>) {
        let k = self.key(&p);
        let index = self.points.len() as u32;
        self.points.push(p);
        self.next.push(self.heads.insert(k, index).unwrap_or(NONE));
    }

    /// Whether a stored point lies within `r` ≤ `cell` of `p`.
    fn has_within(&self, p: &Point3<f64>, r: f64) -> bool {
        let [x, y, z] = self.key(p);
        let r2 = r * r;
        (-1..=1).any(|dz| {
            (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let mut at = self.heads.get(&[x + dx, y + dy, z + dz]).copied();
                    while let Some(i) = at.filter(|&i| i != NONE) {
                        if (self.points[i as usize] - p).norm_squared() <= r2 {
                            return true;
                        }
                        at = Some(self.next[i as usize]);
                    }
                    false
                })
            })
        })
    }
}
