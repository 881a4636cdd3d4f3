//! Sample points bucketed by the voxels of a grid, for the nearest-sample queries the MSR makes
//! of every grid node (the extension of the details and the tangent planes of the level-set
//! reconstruction, [`super::extend`], [`super::reconstruct`]). The samples are counting-sorted by
//! voxel into one array (compressed rows: the samples of voxel c are `order[offsets[c] ..
//! offsets[c + 1]]`), so a query reads the few voxels around it, ring by ring, and stops as soon
//! as no unread voxel can hold a nearer sample: exact, as a k-d tree is, and several times
//! faster on samples that lie on a surface a fraction of a voxel apart. Blocks of
//! `BLOCK`³ voxels know their distance (in blocks, 26-connected) to the nearest block with a
//! sample, so a query far from every sample skips the empty rings or answers at once.

use crate::grid::Grid3;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Most neighbours [`VoxelBuckets::nearest`] returns.
pub const MAX_NEAREST: usize = 8;

/// Edge of the blocks of [`VoxelBuckets::block_distance`] (voxels).
const BLOCK: usize = 4;

/// The samples bucketed by voxel (see the module doc).
#[derive(Debug, Clone)]
pub struct VoxelBuckets {
    origin: Point3<f64>,
    h: f64,
    /// Voxels along each axis (nodes − 1, at least 1).
    cells: [usize; 3],
    offsets: Vec<u32>,
    /// Sample indices, voxel by voxel.
    order: Vec<u32>,
    /// Their positions, in the same order (read together).
    sorted: Vec<Point3<f64>>,
    /// Samples outside the grid's box: read by every query.
    outside: Vec<u32>,
    points_outside: Vec<Point3<f64>>,
    /// Blocks of [`BLOCK`]³ voxels along each axis.
    blocks: [usize; 3],
    /// Per block, the Chebyshev distance in blocks to the nearest block holding a sample of the
    /// grid's box (0: it holds one; 255: that far or more, or none at all).
    block_distance: Vec<u8>,
}

/// Up to [`MAX_NEAREST`] (index, squared distance), nearest first.
#[derive(Debug, Clone, Copy)]
pub struct Nearest {
    len: usize,
    items: [(u32, f64); MAX_NEAREST],
}

impl Nearest {
    fn new() -> Self {
        Nearest {
            len: 0,
            items: [(u32::MAX, f64::INFINITY); MAX_NEAREST],
        }
    }

    /// (sample index, squared distance), nearest first.
    pub fn as_slice(&self) -> &[(u32, f64)] {
        &self.items[..self.len]
    }

    /// The squared distance a candidate must beat to enter a list of `k`.
    fn bound(&self, k: usize) -> f64 {
        if self.len < k {
            f64::INFINITY
        } else {
            self.items[k - 1].1
        }
    }

    fn offer(&mut self, k: usize, index: u32, d2: f64) {
        if d2 >= self.bound(k) {
            return;
        }
        let mut at = self.len.min(k - 1);
        while at > 0 && self.items[at - 1].1 > d2 {
            self.items[at] = self.items[at - 1];
            at -= 1;
        }
        self.items[at] = (index, d2);
        self.len = (self.len + 1).min(k);
    }
}

impl VoxelBuckets {
    /// Buckets `points` by the voxels of `grid`.
    pub fn new(grid: &Grid3, points: &[Point3<f64>]) -> Self {
        let origin = grid.world(0, 0, 0);
        let h = grid.voxel();
        let cells = grid.dims().map(|d| d.max(2) - 1);
        let total = cells[0] * cells[1] * cells[2];
        let cell_of: Vec<u32> = points
            .par_iter()
            .map(|p| cell_index(&origin, h, cells, p).map_or(u32::MAX, |c| c as u32))
            .collect();
        let mut counts = vec![0u32; total + 1];
        let (mut outside, mut points_outside) = (Vec::new(), Vec::new());
        for (s, (&c, p)) in cell_of.iter().zip(points).enumerate() {
            if c == u32::MAX {
                outside.push(s as u32);
                points_outside.push(*p);
            } else {
                counts[c as usize + 1] += 1;
            }
        }
        for c in 0..total {
            counts[c + 1] += counts[c];
        }
        let offsets = counts.clone();
        let mut fill = counts;
        let inside = offsets[total] as usize;
        let mut order = vec![0u32; inside];
        let mut sorted = vec![Point3::origin(); inside];
        for (s, &c) in cell_of.iter().enumerate() {
            if c == u32::MAX {
                continue;
            }
            let at = fill[c as usize] as usize;
            fill[c as usize] += 1;
            order[at] = s as u32;
            sorted[at] = points[s];
        }
        let (blocks, block_distance) = block_distances(cells, &offsets);
        VoxelBuckets {
            origin,
            h,
            cells,
            offsets,
            order,
            sorted,
            outside,
            points_outside,
            blocks,
            block_distance,
        }
    }

    /// The first ring of [`Self::nearest`]'s search around voxel `a` that may hold a sample of
    /// the grid's box (from the block distances), or `None` when none lies within `reach` voxels
    /// of the point.
    fn first_ring(&self, a: [i64; 3], reach: f64) -> Option<i64> {
        // Clamped onto the grid, a is no farther from any voxel of the grid along any axis.
        let b = [0, 1, 2].map(|i| {
            (a[i].clamp(0, self.cells[i] as i64 - 1) as usize / BLOCK).min(self.blocks[i] - 1)
        });
        let d = self.block_distance[b[0] + self.blocks[0] * (b[1] + self.blocks[1] * b[2])] as i64;
        if d == 0 {
            return Some(0);
        }
        // Every voxel holding a sample lies a Chebyshev distance of at least `gap` voxels from
        // a's block, so from a; ring ρ (voxels a − ρ ..= a + 1 + ρ) reaches ρ + 1 from a, so
        // rings 0 ..= gap − 2 are empty. The point lies within voxels a and a + 1 along each
        // axis, at least gap − 1.5 voxels from those samples.
        let gap = (d - 1) * BLOCK as i64 + 1;
        ((gap as f64 - 1.5) <= reach).then_some(gap - 1)
    }

    /// The `k` (≤ [`MAX_NEAREST`]) samples nearest to `p` within `reach` (world units), nearest
    /// first (exact; ties in the order the samples were given).
    pub fn nearest(&self, p: &Point3<f64>, k: usize, reach: f64) -> Nearest {
        let k = k.clamp(1, MAX_NEAREST);
        let mut best = Nearest::new();
        let reach2 = reach * reach;
        for (&s, q) in self.outside.iter().zip(&self.points_outside) {
            let d2 = (q - p).norm_squared();
            if d2 <= reach2 {
                best.offer(k, s, d2);
            }
        }
        let q: Vector3<f64> = (p - self.origin) / self.h;
        // The search box of ring ρ: voxels a − ρ ..= a + 1 + ρ along each axis, a = ⌊q − ½⌋, so
        // p lies at least ½ + ρ voxels inside it (1 + ρ for a node).
        let a: [i64; 3] = [0, 1, 2].map(|i| (q[i] - 0.5).floor() as i64);
        let Some(first) = self.first_ring(a, reach / self.h) else {
            return best;
        };
        let max_ring = (reach / self.h).ceil() as i64 + 1;
        for ring in first..=max_ring {
            let lo = a.map(|v| v - ring);
            let hi = a.map(|v| v + 1 + ring);
            // Ring 0 is read whole; a later first ring as a shell, the rings inside it empty.
            self.scan_ring(p, lo, hi, ring == 0, k, reach2, &mut best);
            // Every unread voxel is at least this far from p.
            let margin = (0..3)
                .map(|i| (q[i] - lo[i] as f64).min(hi[i] as f64 + 1.0 - q[i]))
                .fold(f64::INFINITY, f64::min)
                * self.h;
            let margin2 = margin * margin;
            if margin2 >= best.bound(k).min(reach2) {
                break;
            }
        }
        best
    }

    fn scan_voxel(&self, c: usize, p: &Point3<f64>, k: usize, reach2: f64, best: &mut Nearest) {
        for at in self.offsets[c] as usize..self.offsets[c + 1] as usize {
            let d2 = (self.sorted[at] - p).norm_squared();
            if d2 <= reach2 {
                best.offer(k, self.order[at], d2);
            }
        }
    }

    fn flat(&self, x: i64, y: i64, z: i64) -> usize {
        x as usize + self.cells[0] * (y as usize + self.cells[1] * z as usize)
    }

    /// Offers to `best` the samples of the voxels of the box lo..=hi that are on its surface
    /// (all of them when `whole`), clipped to the grid.
    #[allow(clippy::too_many_arguments)]
    fn scan_ring(
        &self,
        p: &Point3<f64>,
        lo: [i64; 3],
        hi: [i64; 3],
        whole: bool,
        k: usize,
        reach2: f64,
        best: &mut Nearest,
    ) {
        let clip_lo = [0, 1, 2].map(|i| lo[i].max(0));
        let clip_hi = [0, 1, 2].map(|i| hi[i].min(self.cells[i] as i64 - 1));
        for z in clip_lo[2]..=clip_hi[2] {
            let z_face = z == lo[2] || z == hi[2];
            for y in clip_lo[1]..=clip_hi[1] {
                let face = whole || z_face || y == lo[1] || y == hi[1];
                if face {
                    for x in clip_lo[0]..=clip_hi[0] {
                        self.scan_voxel(self.flat(x, y, z), p, k, reach2, best);
                    }
                } else {
                    // Inside the box's shell only its two x ends are on the ring.
                    for x in [lo[0], hi[0]] {
                        if (clip_lo[0]..=clip_hi[0]).contains(&x) {
                            self.scan_voxel(self.flat(x, y, z), p, k, reach2, best);
                        }
                    }
                }
            }
        }
    }
}

/// The blocks of [`BLOCK`]³ voxels covering `cells` voxels, and per block (x fastest) the
/// Chebyshev distance in blocks to the nearest block with a sample (`offsets` as in
/// [`VoxelBuckets`]), by breadth-first search over the 26 neighbours, capped at 255.
fn block_distances(cells: [usize; 3], offsets: &[u32]) -> ([usize; 3], Vec<u8>) {
    let blocks = cells.map(|c| c.div_ceil(BLOCK));
    let mut distance = vec![u8::MAX; blocks[0] * blocks[1] * blocks[2]];
    let flat = |b: [usize; 3]| b[0] + blocks[0] * (b[1] + blocks[1] * b[2]);
    let mut front = Vec::new();
    for z in 0..cells[2] {
        for y in 0..cells[1] {
            let row = cells[0] * (y + cells[1] * z);
            for x in 0..cells[0] {
                if offsets[row + x + 1] > offsets[row + x] {
                    let b = flat([x / BLOCK, y / BLOCK, z / BLOCK]);
                    if distance[b] != 0 {
                        distance[b] = 0;
                        front.push(b);
                    }
                }
            }
        }
    }
    for d in 1..u8::MAX {
        let mut next = Vec::new();
        for &b in &front {
            let c = [
                b % blocks[0],
                (b / blocks[0]) % blocks[1],
                b / (blocks[0] * blocks[1]),
            ];
            for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let n = [c[0] as i64 + dx, c[1] as i64 + dy, c[2] as i64 + dz];
                        if (0..3).any(|i| n[i] < 0 || n[i] >= blocks[i] as i64) {
                            continue;
                        }
                        let m = flat(n.map(|v| v as usize));
                        if distance[m] == u8::MAX {
                            distance[m] = d;
                            next.push(m);
                        }
                    }
                }
            }
        }
        if next.is_empty() {
            break;
        }
        front = next;
    }
    (blocks, distance)
}

/// The voxel of `p`, or None outside the grid's box.
fn cell_index(origin: &Point3<f64>, h: f64, cells: [usize; 3], p: &Point3<f64>) -> Option<usize> {
    let mut c = [0usize; 3];
    for a in 0..3 {
        let v = ((p[a] - origin[a]) / h).floor();
        if !(v >= 0.0 && v < cells[a] as f64) {
            return None;
        }
        c[a] = v as usize;
    }
    Some(c[0] + cells[0] * (c[1] + cells[1] * c[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridTransform;

    /// Brute force: the k nearest within reach by a scan of every sample.
    fn scan(points: &[Point3<f64>], p: &Point3<f64>, k: usize, reach: f64) -> Vec<(u32, f64)> {
        let mut all: Vec<(u32, f64)> = points
            .iter()
            .enumerate()
            .map(|(s, q)| (s as u32, (q - p).norm_squared()))
            .filter(|&(_, d2)| d2 <= reach * reach)
            .collect();
        all.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        all.truncate(k);
        all
    }

    #[test]
    fn nearest_equals_a_scan() {
        let h = 0.5;
        let transform = GridTransform::new(Point3::new(-3.0, -2.0, -4.0), h);
        let grid = Grid3::new([13, 11, 17], transform, 0.0).unwrap();
        // Points on a sphere (dense, like samples on a surface), a few outside the box.
        let mut points = Vec::new();
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..3000 {
            let (u, v) = (2.0 * next() - 1.0, std::f64::consts::TAU * next());
            let s = (1.0 - u * u).sqrt();
            points.push(Point3::new(
                0.3 + 2.0 * s * v.cos(),
                0.4 + 2.0 * s * v.sin(),
                2.0 * u,
            ));
        }
        points.push(Point3::new(-3.5, 0.0, 0.0));
        points.push(Point3::new(10.0, 10.0, 10.0));
        let buckets = VoxelBuckets::new(&grid, &points);
        let mut checked = 0;
        for z in 0..17 {
            for y in 0..11 {
                for x in 0..13 {
                    let node = grid.world(x, y, z);
                    let off = Vector3::new(0.37 * h, -0.21 * h, 0.05 * h) * (x % 3) as f64;
                    for p in [node, node + off] {
                        for (k, reach) in [(8, 2.0), (3, 0.6), (1, 5.0)] {
                            let got: Vec<(u32, f64)> =
                                buckets.nearest(&p, k, reach).as_slice().to_vec();
                            let want = scan(&points, &p, k, reach);
                            assert_eq!(got.len(), want.len(), "at {p:?}");
                            for (g, w) in got.iter().zip(&want) {
                                assert_eq!(g.1, w.1, "at {p:?}");
                            }
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 10_000);
    }

    #[test]
    fn far_queries_equal_a_scan() {
        // A small cluster in one corner of a large grid: most queries are many blocks from every
        // sample, where the block distances skip rings or answer at once.
        let h = 1.0;
        let transform = GridTransform::new(Point3::new(0.0, 0.0, 0.0), h);
        let grid = Grid3::new([41, 37, 45], transform, 0.0).unwrap();
        let points: Vec<Point3<f64>> = (0..50)
            .map(|s| {
                let t = s as f64 * 0.37;
                Point3::new(3.0 + t.sin() * 1.3, 4.5 + t.cos(), 2.0 + 0.05 * s as f64)
            })
            .chain([Point3::new(-6.0, 20.0, 20.0)])
            .collect();
        let buckets = VoxelBuckets::new(&grid, &points);
        let mut found = 0;
        for z in (0..45).step_by(2) {
            for y in (0..37).step_by(3) {
                for x in 0..41 {
                    let p = grid.world(x, y, z) + Vector3::new(0.3, 0.1, -0.2);
                    for (k, reach) in [(8, 3.0), (2, 9.5), (1, 30.0), (8, 60.0)] {
                        let got = buckets.nearest(&p, k, reach).as_slice().to_vec();
                        let want = scan(&points, &p, k, reach);
                        assert_eq!(got.len(), want.len(), "at {p:?}, reach {reach}");
                        for (g, w) in got.iter().zip(&want) {
                            assert_eq!(g.1, w.1, "at {p:?}, reach {reach}");
                        }
                        found += got.len();
                    }
                }
            }
        }
        assert!(found > 1000);
    }
}
