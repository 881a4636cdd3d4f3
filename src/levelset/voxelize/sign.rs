//! Signs at every node from few winding-number evaluations.
//!
//! The sign is inside iff |w| ≥ ½ for the generalized winding number w. On a closed surface w
//! is an integer off the triangles, the signed number of crossings of any ray to infinity, which
//! is what is evaluated there (exact, and no hierarchy of expansions to build). Otherwise the
//! fast w is evaluated, and where it (β of
//! the options, default 2: error up to about 1e-2) comes within 0.02 of ±½ — only across open
//! ends, on the surface |w| = ½ that closes them — it is evaluated again with β = 8 (error about
//! 2e-5), so the sign there is that of the exact w but for the thinnest of margins. Evaluating w at every
//! node is too slow (a 256³ grid has 16.7 M nodes), so it is evaluated at *seeds* and carried to
//! the other nodes along grid edges that provably do not cross the surface:
//!
//! * An edge a–b of length h crosses no triangle when d(a) + d(b) > h (d = distance to the mesh;
//!   a crossing point x would give d(a) + d(b) ≤ |a − x| + |x − b| = h). Off the surface w is
//!   continuous (harmonic), so for a closed mesh — where w is an integer — both ends have the same
//!   w. Every edge touching a node outside the band (d > band ≥ h) is such an edge.
//! * Seeds: the nodes of a coarse lattice (every `stride`-th node along each axis) and the band
//!   nodes with no crossing-free edge at all (those closest to the surface, about d < 0.2 h).
//!   For an open surface, also every node within one voxel of it (`near`): w is not constant
//!   along the surface there (next to an open end, a thin sheet of nodes hugging the inner wall
//!   can be inside while the lumen's centre at the same level is not yet), and nodes that close
//!   are joined along the surface by no crossing-free edge that could carry the news. Every
//!   node left unevaluated is then farther than h from the surface, so all its edges are
//!   crossing-free.
//! * A breadth-first flood from the seeds over crossing-free edges, run by spans of grid rows
//!   (see `SpanFlood`), gives every other node the sign of a seed joined to it; a node the flood
//!   never reaches (a pocket without a seed) is evaluated and flooded from in turn.
//! * Fronts (open meshes only; on a closed one every seed is exact and w is constant along
//!   crossing-free edges): for an open mesh w is not piecewise constant, and |w| = ½ on a "virtual cap" spanning
//!   each hole, away from the triangles. Wherever a crossing-free edge joins nodes of opposite
//!   signs, each unevaluated end is evaluated; a node whose sign changes makes its disagreeing
//!   unevaluated neighbours the next front; repeat until no front is left. At the end every
//!   crossing-free edge with a sign change has both ends evaluated, so the sign boundary sits
//!   where w says it is. Only a region of one sign lying entirely among unevaluated nodes could
//!   be missed; w being harmonic off the surface, such a region reaches the surface or the grid's
//!   border, so it would have to slip between the evaluated nodes there.

use rayon::prelude::*;
use std::collections::VecDeque;
use std::ops::RangeInclusive;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

use super::{Layout, ASSIGNED, EVAL, NEG, QUEUED};
use crate::bvh::brute::winding_number_exact;
use crate::bvh::{MeshBvh, WindingNumber, WindingOptions};
use crate::TriMesh;
use nalgebra::Point3;

/// How w is evaluated at a node.
pub(super) enum SignSource<'a> {
    /// A closed surface (every edge used as often in each direction): w is the signed count of
    /// ray crossings, exact and cheap (`MeshBvh::winding_number_by_rays`); the exact sum over
    /// the triangles where no ray gives a clean count (a node on the surface).
    Rays { bvh: MeshBvh, mesh: &'a TriMesh },
    /// Any surface: the fast winding number, refined near ±½ (see the module docs).
    Winding(WindingNumber),
}

impl SignSource<'_> {
    /// The triangle hierarchy.
    pub(super) fn bvh(&self) -> &MeshBvh {
        match self {
            SignSource::Rays { bvh, .. } => bvh,
            SignSource::Winding(wn) => wn.bvh(),
        }
    }
}

/// Counts of winding-number evaluations, for the report.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct SignCounts {
    pub seeds: usize,
    pub pockets: usize,
    pub fronts: usize,
    pub front_rounds: usize,
    pub refined: usize,
}

/// Fast winding numbers closer than this to ±½ are evaluated again with β = [`REFINE_BETA`]: the
/// largest error of β = 2 on the project's real meshes is about 1e-2.
const REFINE_MARGIN: f64 = 0.02;

/// Accuracy of the second evaluation (largest error about 2e-5 on the real meshes).
const REFINE_BETA: f64 = 8.0;

/// Neighbour indices of node `idx` = (i, j, k) along the six axis directions (those inside the
/// grid), passed to `f`.
#[inline]
fn for_neighbours(layout: &Layout, idx: usize, mut f: impl FnMut(usize)) {
    let [nx, ny, nz] = layout.dims;
    let i = idx % nx;
    let jk = idx / nx;
    let j = jk % ny;
    let k = jk / ny;
    let sy = nx;
    let sz = nx * ny;
    if i > 0 {
        f(idx - 1);
    }
    if i + 1 < nx {
        f(idx + 1);
    }
    if j > 0 {
        f(idx - sy);
    }
    if j + 1 < ny {
        f(idx + sy);
    }
    if k > 0 {
        f(idx - sz);
    }
    if k + 1 < nz {
        f(idx + sz);
    }
}

/// Sign bits of every node of `state` from `dist` (distance in the band, +∞ outside). `stride`
/// ≥ 1 is the coarse-lattice spacing in voxels; every node within `near` (world units) of the
/// mesh is a seed too.
pub(super) fn assign_signs(
    source: &SignSource,
    layout: &Layout,
    dist: &[f32],
    state: &mut [u8],
    stride: usize,
    near: f64,
) -> SignCounts {
    let [nx, ny, _] = layout.dims;
    // Crossing-free test with a margin for the f32 rounding of the distances.
    let hf = (layout.h * (1.0 + 1e-5)) as f32;
    let free = |a: usize, b: usize| dist[a] + dist[b] > hf;
    // A fast winding number within REFINE_MARGIN of ±½ is evaluated again more accurately.
    let precise: OnceLock<WindingNumber> = OnceLock::new();
    let refined = AtomicUsize::new(0);
    let fast_inside = |wn: &WindingNumber, p: &Point3<f64>| -> bool {
        let w = wn.winding_number(p).abs();
        if (w - 0.5).abs() >= REFINE_MARGIN || wn.options().beta >= REFINE_BETA {
            return w >= 0.5;
        }
        refined.fetch_add(1, Ordering::Relaxed);
        let precise = precise.get_or_init(|| {
            WindingNumber::from_bvh(
                wn.bvh().clone(),
                WindingOptions {
                    beta: REFINE_BETA,
                    order: 2,
                },
            )
        });
        precise.winding_number(p).abs() >= 0.5
    };
    let inside = |idx: usize| -> bool {
        let [i, j, k] = layout.coords(idx);
        let p = layout.world(i, j, k);
        match source {
            SignSource::Rays { bvh, mesh } => bvh
                .winding_number_by_rays(&p)
                .map_or_else(|| winding_number_exact(mesh, &p).abs() >= 0.5, |w| w != 0),
            SignSource::Winding(wn) => fast_inside(wn, &p),
        }
    };
    let mut counts = SignCounts::default();

    // Seeds: the coarse lattice and the band nodes without a crossing-free edge.
    let layer_len = nx * ny;
    let seeds: Vec<u32> = (0..layout.dims[2])
        .into_par_iter()
        .flat_map_iter(|k| {
            let base = k * layer_len;
            let mut out = Vec::new();
            for j in 0..ny {
                for i in 0..nx {
                    let idx = base + j * nx + i;
                    let lattice = i % stride == 0 && j % stride == 0 && k % stride == 0;
                    let isolated = dist[idx].is_finite()
                        && (dist[idx] as f64 <= near || {
                            let mut any = false;
                            for_neighbours(layout, idx, |b| any |= free(idx, b));
                            !any
                        });
                    if lattice || isolated {
                        out.push(idx as u32);
                    }
                }
            }
            out
        })
        .collect();
    let signs: Vec<bool> = seeds.par_iter().map(|&s| inside(s as usize)).collect();
    counts.seeds = seeds.len();
    for (&s, &neg) in seeds.iter().zip(&signs) {
        state[s as usize] |= EVAL | ASSIGNED | if neg { NEG } else { 0 };
    }

    // Flood from the seeds; pockets without a seed are evaluated and flooded from in turn.
    let mut flood = SpanFlood::new(layout, dist, hf);
    for &s in &seeds {
        flood.seed(state, s as usize);
    }
    flood.run(state);
    for idx in 0..state.len() {
        if state[idx] & ASSIGNED == 0 {
            let neg = inside(idx);
            state[idx] |= EVAL | ASSIGNED | if neg { NEG } else { 0 };
            counts.pockets += 1;
            flood.seed(state, idx);
            flood.run(state);
        }
    }

    debug_assert!(state.iter().all(|s| s & ASSIGNED != 0));
    // Fronts: unevaluated ends of crossing-free edges whose ends disagree. On a closed surface w
    // is an integer, the same at both ends of a crossing-free edge, and every seed's count is
    // exact: there are none to look for.
    if matches!(source, SignSource::Rays { .. }) {
        return counts;
    }
    let state_ro: &[u8] = state;
    let [_, _, nz] = layout.dims;
    let mut front: Vec<u32> = (0..ny * nz)
        .into_par_iter()
        .flat_map_iter(|row| {
            let (j, k) = (row % ny, row / ny);
            let base = row * nx;
            // Row offsets of the ±y and ±z neighbours that exist; ±x handled by i's bounds.
            let across = [
                (j > 0).then(|| base - nx),
                (j + 1 < ny).then(|| base + nx),
                (k > 0).then(|| base - layer_len),
                (k + 1 < nz).then(|| base + layer_len),
            ];
            let differs =
                move |a: usize, b: usize| (state_ro[a] ^ state_ro[b]) & NEG != 0 && free(a, b);
            (0..nx).filter_map(move |i| {
                let a = base + i;
                if state_ro[a] & EVAL != 0 {
                    return None;
                }
                let mut d = (i > 0 && differs(a, a - 1)) || (i + 1 < nx && differs(a, a + 1));
                for other in across.iter().flatten() {
                    d = d || differs(a, other + i);
                }
                d.then_some(a as u32)
            })
        })
        .collect();
    while !front.is_empty() {
        counts.front_rounds += 1;
        counts.fronts += front.len();
        let signs: Vec<bool> = front.par_iter().map(|&a| inside(a as usize)).collect();
        let mut changed = Vec::new();
        for (&a, &neg) in front.iter().zip(&signs) {
            let a = a as usize;
            let was = state[a] & NEG != 0;
            state[a] = (state[a] & !(NEG | QUEUED)) | EVAL | if neg { NEG } else { 0 };
            if was != neg {
                changed.push(a);
            }
        }
        front.clear();
        for &a in &changed {
            for_neighbours(layout, a, |b| {
                let sb = state[b];
                if sb & (EVAL | QUEUED) == 0 && (state[a] ^ sb) & NEG != 0 && free(a, b) {
                    state[b] |= QUEUED;
                    front.push(b as u32);
                }
            });
        }
    }
    counts.refined = refined.into_inner();
    counts
}

/// Breadth-first flood over crossing-free edges, run by spans: maximal runs of a grid row joined
/// by crossing-free x-edges, all given the sign of the node they grew from. A popped span scans
/// the four rows beside it (±y, ±z) over its own x-range; an unassigned node there behind a
/// crossing-free edge takes the span's sign and grows into a new span. Every node is assigned once
/// and read from at most five spans, with no division per node, which is what makes it several
/// times faster than a node-by-node queue over the mostly empty grid around a thin vessel.
struct SpanFlood<'a> {
    layout: &'a Layout,
    dist: &'a [f32],
    /// Crossing-free threshold: an edge a–b crosses no triangle when d(a) + d(b) > hf.
    hf: f32,
    /// Spans waiting to scan their neighbour rows: first and last node index (same row).
    queue: VecDeque<(u32, u32)>,
}

impl<'a> SpanFlood<'a> {
    fn new(layout: &'a Layout, dist: &'a [f32], hf: f32) -> Self {
        SpanFlood {
            layout,
            dist,
            hf,
            queue: VecDeque::new(),
        }
    }

    #[inline]
    fn free(&self, a: usize, b: usize) -> bool {
        self.dist[a] + self.dist[b] > self.hf
    }

    /// Grows the span through assigned node `a` over the unassigned nodes of its row joined to
    /// it by crossing-free edges (they take a's sign), and queues it.
    fn seed(&mut self, state: &mut [u8], a: usize) {
        let span = self.grow(state, a);
        self.queue
            .push_back((*span.start() as u32, *span.end() as u32));
    }

    fn grow(&self, state: &mut [u8], a: usize) -> RangeInclusive<usize> {
        let nx = self.layout.dims[0];
        let row = a - a % nx;
        let mark = ASSIGNED | (state[a] & NEG);
        let mut lo = a;
        while lo > row && state[lo - 1] & ASSIGNED == 0 && self.free(lo, lo - 1) {
            lo -= 1;
            state[lo] |= mark;
        }
        let mut hi = a;
        while hi + 1 < row + nx && state[hi + 1] & ASSIGNED == 0 && self.free(hi, hi + 1) {
            hi += 1;
            state[hi] |= mark;
        }
        lo..=hi
    }

    /// Floods until no span is waiting.
    fn run(&mut self, state: &mut [u8]) {
        let [nx, ny, nz] = self.layout.dims;
        let sz = nx * ny;
        while let Some((lo, hi)) = self.queue.pop_front() {
            let (lo, hi) = (lo as usize, hi as usize);
            let jk = lo / nx;
            let (j, k) = (jk % ny, jk / ny);
            let offsets = [
                (j > 0).then(|| -(nx as isize)),
                (j + 1 < ny).then_some(nx as isize),
                (k > 0).then(|| -(sz as isize)),
                (k + 1 < nz).then_some(sz as isize),
            ];
            for off in offsets.into_iter().flatten() {
                let mut a = lo;
                while a <= hi {
                    let b = a.wrapping_add_signed(off);
                    if state[b] & ASSIGNED == 0 && self.free(a, b) {
                        state[b] |= ASSIGNED | (state[a] & NEG);
                        let span = self.grow(state, b);
                        // The new span's nodes right of b are assigned now: skip past them.
                        let end = span.end().wrapping_add_signed(-off);
                        self.queue
                            .push_back((*span.start() as u32, *span.end() as u32));
                        a = end.max(a) + 1;
                    } else {
                        a += 1;
                    }
                }
            }
        }
    }
}
