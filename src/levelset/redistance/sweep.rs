//! The Gauss–Seidel sweeps of the redistancer, in the 8 alternating orders, outward from the
//! frozen interface nodes, and the write-back of the signed result.
//!
//! Each sweep visits the rows of x in its order (k-major over the (y, z) plane, both in the
//! sweep's direction), and each row along x in the sweep's direction. For threads, the (y, z)
//! plane is cut into tiles of [`TILE`]×[`TILE`] rows; tile (a, b) (in sweep order) lies on the
//! tile plane a + 2b, the 8 tiles around a tile lie on other planes, so the tiles of one plane
//! run in parallel and every row still sees exactly the rows the sequential order would have
//! updated before it: the result does not depend on the number of threads.
//!
//! Values live in atomics (relaxed loads and stores, plain moves) so that the tiles can share
//! the arrays without `unsafe`. Per node: `val`, f32 bits of the distance (Godunov) or of the
//! squared distance to the carried crossing point (closest point), in voxels, the sign bit
//! marking a frozen interface node; `ids` (closest point): the interface node carried. Per row:
//! the sweep that last changed it, the sweep(s) that last visited it, and the span of its nodes
//! that hold a value. A row is visited only if a row it reads changed since it last read that
//! row (Godunov reads the 4 face rows whatever the order; the closest-point scheme reads its
//! upwind rows, so it keeps one stamp per axis and side), and only the span of the rows read,
//! widened by one, is walked, plus whatever the sweep carries on along x.

use super::init::{patch_distance, Patch, Seeds};
use super::{RedistanceOptions, RedistanceScheme};
use crate::grid::Grid3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering::Relaxed};

/// 1/√3, the least a Godunov update can add to the smallest neighbour.
const FRAC_1_SQRT_3: f32 = 0.577_350_26;
/// Sign bit of `val`: a frozen interface node.
const FROZEN: u32 = 0x8000_0000;
/// Rows per side of a tile of the (y, z) plane (the unit of parallel work).
const TILE: usize = 8;
/// An empty span of a row.
const EMPTY_SPAN: u64 = u32::MAX as u64;
/// Most disjoint spans kept per row, ascending (a row through a closed surface holds a band
/// piece on each side; more pieces are joined across their smallest gaps).
const SPANS: usize = 2;
/// Most runs of nodes one row visit walks: the spans of the (at most 5) rows it reads.
const RUNS: usize = 5 * SPANS;
/// Most stretches of changed nodes one row visit reports (more are joined to the last).
const STRETCHES: usize = 8;
/// Changed nodes more than this many nodes apart start a new stretch: a run that crosses a
/// gap between band pieces must not record the gap as holding values.
const GAP: usize = 4;

/// The 8 sweep orders (ascending along x, y, z?), each differing from the next in one axis.
const ORDERS: [[bool; 3]; 8] = [
    [true, true, true],
    [false, true, true],
    [false, false, true],
    [true, false, true],
    [true, false, false],
    [false, false, false],
    [false, true, false],
    [true, true, false],
];

struct Sweeper<'a> {
    dims: [usize; 3],
    scheme: RedistanceScheme,
    val: Vec<AtomicU32>,
    ids: Vec<AtomicU32>,
    /// Closest point: each interface node's crossing point, absolute voxel coordinates (x, y,
    /// z, 0), for the nearest-point search, and last a sentinel at infinity: the id of nodes
    /// no interface node reached yet.
    point: Vec<[f32; 4]>,
    patch: &'a [Patch],
    /// Starting value of nodes that are not frozen (Godunov: the band, or ∞).
    far: f32,
    /// Closest point: largest squared distance to a crossing point kept ((band + 2)², voxels²;
    /// ∞ without a band).
    limit2: f32,
    /// Godunov: smallest decrease that counts as a change (voxels).
    tolerance: f32,
    /// Per row (j + ny·k), stamps (sweep s stamps s + 1; 1 marks the rows of the interface
    /// nodes; 0: never): Godunov, the last visit; closest point, 6 per row, the last visit that
    /// read the row's x, y and z neighbours from the low or the high side.
    visited: Vec<AtomicU32>,
    /// Per row: the stamp of its last change.
    changed: Vec<AtomicU32>,
    /// Per row, [`SPANS`] slots (row r: r·SPANS..): disjoint, ascending spans lo | hi << 32
    /// (lo > hi: empty, after the others); every node that holds a value lies in one of them.
    span: Vec<AtomicU64>,
}

/// Sweeps from the frozen `seeds` until a sweep changes nothing (or `opts.max_sweeps`), then
/// writes sign·min(distance, band) into `phi` (world units). Returns (sweeps run, converged).
pub(super) fn sweep_distance(
    phi: &mut Grid3,
    seeds: &Seeds,
    band_vox: Option<f64>,
    opts: &RedistanceOptions,
) -> (usize, bool) {
    let [nx, ny, nz] = phi.dims();
    let n = nx * ny * nz;
    let closest = opts.scheme == RedistanceScheme::ClosestPoint;
    // Godunov values never rise above their start, so starting at the band stops the sweeps
    // there.
    let far = match band_vox {
        Some(b) if !closest => b as f32,
        _ => f32::INFINITY,
    };
    let filled = |len: usize, value: u32| {
        let mut v = Vec::with_capacity(len);
        v.resize_with(len, || AtomicU32::new(value));
        v
    };
    let val = filled(n, far.to_bits());
    // No interface node reached yet: the sentinel after the last one, a point at infinity.
    let none = seeds.len() as u32;
    let ids = if closest { filled(n, none) } else { Vec::new() };
    let rows = ny * nz;
    // Closest point: one stamp per axis and side the row was last read from (see `row`).
    let slots = if closest { 6 * rows } else { rows };
    let visited = filled(slots, 0);
    let changed = filled(rows, 0);
    let span: Vec<AtomicU64> = (0..SPANS * rows)
        .map(|_| AtomicU64::new(EMPTY_SPAN))
        .collect();
    for (s, (&node, &d)) in seeds.node.iter().zip(&seeds.dist).enumerate() {
        let stored = if closest {
            ids[node].store(s as u32, Relaxed);
            d * d
        } else {
            d
        };
        val[node].store(stored.to_bits() | FROZEN, Relaxed);
        let (r, i) = (node / nx, (node % nx) as u64);
        changed[r].store(1, Relaxed);
        add_span(&span[SPANS * r..SPANS * (r + 1)], i, i);
    }
    let point = if closest {
        let mut point: Vec<[f32; 4]> = seeds
            .patch
            .par_iter()
            .map(|p| {
                let a = p.point();
                [a[0] as f32, a[1] as f32, a[2] as f32, 0.0]
            })
            .collect();
        point.push([f32::INFINITY, f32::INFINITY, f32::INFINITY, 0.0]);
        point
    } else {
        Vec::new()
    };
    let sweeper = Sweeper {
        dims: [nx, ny, nz],
        scheme: opts.scheme,
        val,
        ids,
        point,
        patch: &seeds.patch,
        far,
        // Crossing points a little beyond the band still serve nodes inside it (a patch can be
        // nearer than its point): keep two voxels more than the band.
        limit2: band_vox.map_or(f32::INFINITY, |b| ((b + 2.0) * (b + 2.0)) as f32),
        tolerance: opts.tolerance as f32,
        visited,
        changed,
        span,
    };
    let (sweeps, converged) = sweeper.run(opts.max_sweeps);
    sweeper.write_back(phi, band_vox.map_or(f64::INFINITY, |b| b * phi.voxel()));
    (sweeps, converged)
}

/// Adds lo..=hi to the spans of a row (its [`SPANS`] slots): spans that overlap or touch are
/// joined, and when more than [`SPANS`] remain, the two with the smallest gap between them.
fn add_span(slots: &[AtomicU64], lo: u64, hi: u64) {
    let mut cur = [(0u64, 0u64); SPANS + 1];
    let mut n = 0;
    let mut placed = false;
    for slot in slots {
        let p = slot.load(Relaxed);
        let (a, b) = (p & 0xffff_ffff, p >> 32);
        if a > b {
            break;
        }
        if a <= lo && hi <= b {
            // Already covered: nothing to store.
            return;
        }
        if !placed && lo < a {
            cur[n] = (lo, hi);
            n += 1;
            placed = true;
        }
        cur[n] = (a, b);
        n += 1;
    }
    if !placed {
        cur[n] = (lo, hi);
        n += 1;
    }
    let mut m = 0;
    for t in 1..n {
        if cur[t].0 <= cur[m].1 + 1 {
            cur[m].1 = cur[m].1.max(cur[t].1);
        } else {
            m += 1;
            cur[m] = cur[t];
        }
    }
    let mut n = m + 1;
    if n > SPANS {
        let g = (0..n - 1)
            .min_by_key(|&t| cur[t + 1].0 - cur[t].1)
            .unwrap_or(0);
        cur[g].1 = cur[g + 1].1;
        cur.copy_within(g + 2..n, g + 1);
        n -= 1;
    }
    for (t, slot) in slots.iter().enumerate() {
        let packed = if t < n {
            cur[t].0 | cur[t].1 << 32
        } else {
            EMPTY_SPAN
        };
        slot.store(packed, Relaxed);
    }
}

impl Sweeper<'_> {
    fn run(&self, max_sweeps: usize) -> (usize, bool) {
        let [_, ny, nz] = self.dims;
        let (ty, tz) = (ny.div_ceil(TILE), nz.div_ceil(TILE));
        let parallel = rayon::current_num_threads() > 1 && ty * tz > 1;
        for s in 1..=max_sweeps {
            let order = ORDERS[(s - 1) % 8];
            let any = AtomicBool::new(false);
            // Stamps: 1 marks the rows of the interface nodes, sweep s stamps s + 1.
            let stamp = s as u32 + 1;
            let tile = |a: usize, b: usize| {
                // Rows of tile (a, b) in sweep order, k-major: (jj, kk) counted along the sweep.
                let mut changed = false;
                for kk in b * TILE..((b + 1) * TILE).min(nz) {
                    for jj in a * TILE..((a + 1) * TILE).min(ny) {
                        let j = if order[1] { jj } else { ny - 1 - jj };
                        let k = if order[2] { kk } else { nz - 1 - kk };
                        changed |= self.row(j, k, order, stamp);
                    }
                }
                if changed {
                    any.store(true, Relaxed);
                }
            };
            for t in 0..ty + 2 * tz - 2 {
                // Tiles (a, b) with a + 2b = t, 0 ≤ a < ty, 0 ≤ b < tz.
                let lo = (t + 1).saturating_sub(ty).div_ceil(2);
                let hi = (t / 2).min(tz - 1);
                if parallel && hi > lo {
                    (lo..hi + 1)
                        .into_par_iter()
                        .for_each(|b| tile(t - 2 * b, b));
                } else {
                    (lo..=hi).for_each(|b| tile(t - 2 * b, b));
                }
            }
            if !any.load(Relaxed) {
                return (s, true);
            }
        }
        (max_sweeps, false)
    }

    /// Sweeps row (j, k) along x unless none of the rows it reads changed since it last read
    /// them; true when a value changed (by more than the tolerance, for Godunov).
    fn row(&self, j: usize, k: usize, order: [bool; 3], stamp: u32) -> bool {
        let [nx, ny, nz] = self.dims;
        let r = j + ny * k;
        let (y_up, z_up) = (
            if order[1] {
                j.checked_sub(1)
            } else {
                (j + 1 < ny).then_some(j + 1)
            },
            if order[2] {
                k.checked_sub(1)
            } else {
                (k + 1 < nz).then_some(k + 1)
            },
        );
        let y_up = y_up.map(|jj| jj + ny * k);
        let z_up = z_up.map(|kk| j + ny * kk);
        // The runs of nodes that can change: the spans of the rows read, widened by one.
        let mut runs = [(0usize, 0usize); RUNS];
        let mut count = 0;
        let mut take_span = |q: usize| {
            for slot in &self.span[SPANS * q..SPANS * (q + 1)] {
                let s = slot.load(Relaxed);
                let (a, b) = ((s & 0xffff_ffff) as usize, (s >> 32) as usize);
                if a > b {
                    break;
                }
                runs[count] = (a.saturating_sub(1), (b + 1).min(nx - 1));
                count += 1;
            }
        };
        let changed_at = |q: usize| self.changed[q].load(Relaxed);
        match self.scheme {
            RedistanceScheme::Godunov => {
                // The update reads both neighbours along each axis whatever the order: the row
                // can change only if it or one of its 4 face rows changed since its last visit
                // (in that sweep or after it).
                let faces = [
                    Some(r),
                    j.checked_sub(1).map(|jj| jj + ny * k),
                    (j + 1 < ny).then(|| r + 1),
                    k.checked_sub(1).map(|kk| j + ny * kk),
                    (k + 1 < nz).then(|| r + ny),
                ];
                let mut last = 0;
                for q in faces.into_iter().flatten() {
                    last = last.max(changed_at(q));
                    take_span(q);
                }
                if last == 0 || last < self.visited[r].load(Relaxed) {
                    return false;
                }
                self.visited[r].store(stamp, Relaxed);
            }
            // (The transform does not sweep: never here.)
            RedistanceScheme::ClosestPoint | RedistanceScheme::ClosestPointTransform => {
                // A node reads only its 3 upwind face neighbours, which depend on the order: the
                // row is worth a visit if its own row, its upwind y row or its upwind z row
                // changed since the last visit that read them from the same side.
                let slot = |axis: usize| 6 * r + 2 * axis + usize::from(order[axis]);
                let mut fresh = false;
                for (axis, q) in [(0, Some(r)), (1, y_up), (2, z_up)] {
                    if let Some(q) = q {
                        fresh |= changed_at(q) > self.visited[slot(axis)].load(Relaxed);
                        take_span(q);
                    }
                }
                if let (Some(qy), Some(_)) = (y_up, z_up) {
                    // The diagonal row, read when the y and z sides both match.
                    // Summed before subtracting: the z offset may be negative (no overflow in debug builds).
                    let q = qy + z_up.unwrap() - r;
                    let seen = self.visited[slot(1)]
                        .load(Relaxed)
                        .min(self.visited[slot(2)].load(Relaxed));
                    fresh |= changed_at(q) > seen;
                    take_span(q);
                }
                if !fresh {
                    return false;
                }
                for axis in 0..3 {
                    self.visited[slot(axis)].store(stamp, Relaxed);
                }
            }
        }
        if count == 0 {
            return false;
        }
        let runs = merge_runs(&mut runs[..count]);
        let (changed, out, outs) = match self.scheme {
            RedistanceScheme::Godunov => self.godunov_row(j, k, order[0], runs),
            RedistanceScheme::ClosestPoint | RedistanceScheme::ClosestPointTransform => {
                self.closest_point_row(j, k, order, runs)
            }
        };
        let slots = &self.span[SPANS * r..SPANS * (r + 1)];
        for &(lo, hi) in &out[..outs] {
            add_span(slots, lo as u64, hi as u64);
        }
        if changed {
            self.changed[r].store(stamp, Relaxed);
        }
        changed
    }

    /// The nodes of a row visited in sweep direction, run by run (`runs`: disjoint, ascending):
    /// from the first node of each run not visited yet, past its last one for as long as the
    /// previous node changed (the sweep carries values along x). `visit` is told whether the
    /// node starts a new stretch (its upwind x neighbour was not just visited). Returns the
    /// stretches of the nodes for which `visit` said true (more than [`GAP`] nodes apart:
    /// separate stretches, at most [`STRETCHES`]) and their count.
    #[inline(always)]
    fn walk(
        nx: usize,
        ascending: bool,
        runs: &[(usize, usize)],
        mut visit: impl FnMut(usize, bool) -> bool,
    ) -> ([(usize, usize); STRETCHES], usize) {
        let mut out = [(0usize, 0usize); STRETCHES];
        let mut outs = 0;
        // The stretch being grown (lo > hi: none yet).
        let (mut cur_lo, mut cur_hi) = (usize::MAX, 0usize);
        let step: isize = if ascending { 1 } else { -1 };
        // The next node in sweep order not visited yet.
        let mut next: isize = if ascending { 0 } else { nx as isize - 1 };
        for t in 0..runs.len() {
            let (lo, hi) = runs[if ascending { t } else { runs.len() - 1 - t }];
            let (start, stop) = if ascending {
                ((lo as isize).max(next), hi as isize)
            } else {
                ((hi as isize).min(next), lo as isize)
            };
            if (start - stop) * step > 0 {
                continue;
            }
            let mut i = start;
            let mut first = true;
            loop {
                let changed = visit(i as usize, first);
                first = false;
                if changed {
                    let u = i as usize;
                    if cur_lo > cur_hi {
                        (cur_lo, cur_hi) = (u, u);
                    } else if u + GAP >= cur_lo && u <= cur_hi + GAP {
                        (cur_lo, cur_hi) = (cur_lo.min(u), cur_hi.max(u));
                    } else {
                        if outs == STRETCHES {
                            let last = &mut out[STRETCHES - 1];
                            *last = (last.0.min(cur_lo), last.1.max(cur_hi));
                        } else {
                            out[outs] = (cur_lo, cur_hi);
                            outs += 1;
                        }
                        (cur_lo, cur_hi) = (u, u);
                    }
                }
                if (i - stop) * step >= 0 && !changed {
                    break;
                }
                i += step;
                if i < 0 || i >= nx as isize {
                    break;
                }
            }
            next = i + step;
        }
        if cur_lo <= cur_hi {
            if outs == STRETCHES {
                let last = &mut out[STRETCHES - 1];
                *last = (last.0.min(cur_lo), last.1.max(cur_hi));
            } else {
                out[outs] = (cur_lo, cur_hi);
                outs += 1;
            }
        }
        (out, outs)
    }

    /// One Godunov pass along row (j, k) over `runs` (and on while values change): returns
    /// (changed beyond tolerance, spans of the nodes that got a value below the start, count).
    fn godunov_row(
        &self,
        j: usize,
        k: usize,
        ascending: bool,
        runs: &[(usize, usize)],
    ) -> (bool, [(usize, usize); STRETCHES], usize) {
        let [nx, ny, nz] = self.dims;
        let base = nx * (j + ny * k);
        let rows = [
            (j > 0).then(|| base - nx),
            (j + 1 < ny).then(|| base + nx),
            (k > 0).then(|| base - nx * ny),
            (k + 1 < nz).then(|| base + nx * ny),
        ];
        let magnitude = |q: usize| f32::from_bits(self.val[q].load(Relaxed) & !FROZEN);
        let pair = |a: Option<usize>, b: Option<usize>, i: usize| {
            let x = a.map_or(f32::INFINITY, |r| magnitude(r + i));
            let y = b.map_or(f32::INFINITY, |r| magnitude(r + i));
            x.min(y)
        };
        let mut changed = false;
        let (out, outs) = Self::walk(nx, ascending, runs, |i, _| {
            let idx = base + i;
            let bits = self.val[idx].load(Relaxed);
            if bits & FROZEN != 0 {
                return false;
            }
            let old = f32::from_bits(bits);
            let left = if i > 0 {
                magnitude(idx - 1)
            } else {
                f32::INFINITY
            };
            let right = if i + 1 < nx {
                magnitude(idx + 1)
            } else {
                f32::INFINITY
            };
            let ax = left.min(right);
            let ay = pair(rows[0], rows[1], i);
            let az = pair(rows[2], rows[3], i);
            // Sort a ≤ b ≤ c.
            let (a, b) = (ax.min(ay), ax.max(ay));
            let (b, c) = (b.min(az), b.max(az));
            let (a, b) = (a.min(b), a.max(b));
            // The update is at least a + 1/√3 (a = b = c): nothing to gain otherwise.
            if a + FRAC_1_SQRT_3 >= old {
                return false;
            }
            let new = godunov(a, b, c);
            if new < old {
                self.val[idx].store(new.to_bits(), Relaxed);
                let big = old - new > self.tolerance;
                changed |= big;
                // A first value always counts (it widens the span).
                return big || old == self.far;
            }
            false
        });
        (changed, out, outs)
    }

    /// One closest-point pass along row (j, k) over `runs` (and on while values change): each
    /// node that is not frozen takes, among its own interface node and those carried by its 7
    /// upwind neighbours in this sweep order (±1 or 0 along each axis, toward where the sweep
    /// comes from), the one whose crossing point is nearest. Returns (changed, spans of the
    /// changed nodes, count).
    fn closest_point_row(
        &self,
        j: usize,
        k: usize,
        order: [bool; 3],
        runs: &[(usize, usize)],
    ) -> (bool, [(usize, usize); STRETCHES], usize) {
        let [nx, ny, nz] = self.dims;
        let base = nx * (j + ny * k);
        // Upwind steps as flat-index offsets; 0 where the neighbour is off the grid, which
        // offers the node's own interface node (nothing new).
        let dy: isize = match order[1] {
            true if j > 0 => -(nx as isize),
            false if j + 1 < ny => nx as isize,
            _ => 0,
        };
        let dz: isize = match order[2] {
            true if k > 0 => -((nx * ny) as isize),
            false if k + 1 < nz => (nx * ny) as isize,
            _ => 0,
        };
        let dx: isize = if order[0] { -1 } else { 1 };
        let first = if order[0] { 0 } else { nx - 1 };
        // The 6 candidates besides the x neighbour: y, z, yz, xy, xz, xyz; the first node of the
        // row has no x neighbour (its x-diagonal candidates fall back to y, z, yz).
        let offsets = [dy, dz, dy + dz, dx + dy, dx + dz, dx + dy + dz];
        let offsets_first = [dy, dz, dy + dz, dy, dz, dy + dz];
        let (y, z) = (j as f32, k as f32);
        let (ids, val, point) = (&self.ids[..], &self.val[..], &self.point[..]);
        let limit2 = self.limit2;
        // The id the previous node (upwind along x) ended with, carried in a register;
        // u32::MAX at the start of each stretch.
        let mut prev = u32::MAX;
        let (out, outs) = Self::walk(nx, order[0], runs, |i, fresh| {
            if fresh {
                prev = u32::MAX;
            }
            let idx = base + i;
            let bits = val[idx].load(Relaxed);
            let own = ids[idx].load(Relaxed);
            let cx = if prev != u32::MAX {
                prev
            } else if i == first {
                own
            } else {
                ids[idx.wrapping_add_signed(-dx)].load(Relaxed)
            };
            if bits & FROZEN != 0 {
                prev = own;
                return false;
            }
            let o = if i == first { &offsets_first } else { &offsets };
            let at = |d: isize| ids[idx.wrapping_add_signed(d)].load(Relaxed);
            // (Written out: array::map is not inlined here.)
            let c = [at(o[0]), at(o[1]), at(o[2]), at(o[3]), at(o[4]), at(o[5])];
            let differ = (cx ^ own)
                | (c[0] ^ own)
                | (c[1] ^ own)
                | (c[2] ^ own)
                | (c[3] ^ own)
                | (c[4] ^ own)
                | (c[5] ^ own);
            if differ == 0 {
                prev = own;
                return false;
            }
            let x = i as f32;
            let dist2 = |id: u32| {
                let p = &point[id as usize];
                let (ex, ey, ez) = (x - p[0], y - p[1], z - p[2]);
                ex * ex + ey * ey + ez * ez
            };
            let pick = |(da, ia): (f32, u32), (db, ib): (f32, u32)| {
                if db < da {
                    (db, ib)
                } else {
                    (da, ia)
                }
            };
            // The other candidates do not depend on the previous node: settle them first, so
            // the chain from node to node is only the x candidate. Only candidates that differ
            // from the node's own and from the one before in the list are measured.
            let mut across = (f32::from_bits(bits), own);
            let mut last = own;
            for id in c {
                if id != own && id != last {
                    across = pick(across, (dist2(id), id));
                    last = id;
                }
            }
            let (best, best_id) = if cx == across.1 || cx == own {
                across
            } else {
                pick(across, (dist2(cx), cx))
            };
            if best_id != own && best <= limit2 {
                ids[idx].store(best_id, Relaxed);
                val[idx].store(best.to_bits(), Relaxed);
                prev = best_id;
                return true;
            }
            prev = own;
            false
        });
        (outs > 0, out, outs)
    }

    /// φ ← sign(φ)·min(distance·h, band), in parallel over rows. The closest-point scheme
    /// measures each node to the patch of the interface node whose crossing point it found
    /// nearest.
    fn write_back(&self, phi: &mut Grid3, band: f64) {
        let [nx, ny, _] = self.dims;
        let h = phi.voxel();
        let closest = self.scheme == RedistanceScheme::ClosestPoint;
        phi.data_mut()
            .par_chunks_mut(nx)
            .enumerate()
            .for_each(|(r, row)| {
                let (y, z) = ((r % ny) as f32, (r / ny) as f32);
                for (i, v) in row.iter_mut().enumerate() {
                    let idx = r * nx + i;
                    let bits = self.val[idx].load(Relaxed);
                    let stored = f32::from_bits(bits & !FROZEN);
                    let d = if !closest {
                        stored
                    } else if bits & FROZEN != 0 {
                        stored.sqrt()
                    } else {
                        match self.patch.get(self.ids[idx].load(Relaxed) as usize) {
                            Some(patch) => patch_distance(patch, [i as f32, y, z]),
                            None => f32::INFINITY,
                        }
                    };
                    let w = (d as f64 * h).min(band) as f32;
                    *v = if *v < 0.0 { -w } else { w };
                }
            });
    }
}

/// Sorts `runs` by start and joins those that overlap or touch, in place: returns the disjoint,
/// ascending runs.
fn merge_runs(runs: &mut [(usize, usize)]) -> &[(usize, usize)] {
    for t in 1..runs.len() {
        let mut u = t;
        while u > 0 && runs[u - 1].0 > runs[u].0 {
            runs.swap(u - 1, u);
            u -= 1;
        }
    }
    let mut m = 0;
    for t in 1..runs.len() {
        if runs[t].0 <= runs[m].1 + 1 {
            runs[m].1 = runs[m].1.max(runs[t].1);
        } else {
            m += 1;
            runs[m] = runs[t];
        }
    }
    &runs[..m + 1]
}

/// The Godunov upwind solution of |∇u| = 1 (unit spacing) from the smallest neighbour values
/// along each axis, sorted a ≤ b ≤ c: one, two or three axes take part, the first case whose
/// solution does not exceed the next neighbour value. Solved for u − a, from b − a and c − a,
/// so that distances of hundreds of voxels keep the precision of the small differences (the
/// direct form loses it to cancellation, and the sweeps would then ratchet down on the noise).
#[inline]
fn godunov(a: f32, b: f32, c: f32) -> f32 {
    let (b, c) = (b - a, c - a);
    if b >= 1.0 {
        return a + 1.0;
    }
    let u = 0.5 * (b + (2.0 - b * b).sqrt());
    if u <= c {
        return a + u;
    }
    let s = b + c;
    let q = s * s - 3.0 * (b * b + c * c - 1.0);
    a + (s + q.max(0.0).sqrt()) / 3.0
}
