//! Collapse of degenerate rim edges before capping. A rim edge far shorter than its neighbours
//! (two rim vertices a float rounding apart, as left by cutting or format conversion) forces a
//! cap triangle of huge aspect ratio whatever the cap, since a triangle on an edge of length e
//! whose longest edge is L has aspect ratio at least (√3/2)·L/e. Such an edge is removed by
//! merging its second vertex into its first (a boundary edge collapse): the mesh's sliver
//! triangle on that edge disappears and the other triangles of the merged vertex move by less
//! than the edge length. Collapses that would break manifoldness (link condition) or flip a
//! triangle are skipped.
//!
//! Likewise an *ear* of a loop: a triangle A B C of the mesh whose two edges A → B and B → C are
//! both on the rim, with B, its only triangle's corner, within the same fraction of the target
//! edge length of the line A C (three rim points of a clipped end, nearly in a row, as the ICA
//! of `benches/repair_real`'s aneurysm has 13 of, of 10⁻⁷ mm²). The cap covers the polygon
//! through B, so over the ear's sliver the mesh would hold two sheets, overlapping (MeshLib's
//! `findSelfCollidingTriangles` found 9 colliding pairs on that ICA capped): the ear is cut off
//! (the triangle removed, the rim running A → C) before the cap is made.

use nalgebra::Point3;
use std::collections::{HashMap, HashSet};

/// The input's triangles under edge collapses.
pub(super) struct Working {
    pub faces: Vec<[u32; 3]>,
    pub alive: Vec<bool>,
    /// Triangles of each vertex (alive ones; kept up to date).
    inc: Vec<Vec<u32>>,
}

impl Working {
    pub fn new(num_vertices: usize, faces: &[[u32; 3]]) -> Self {
        let mut inc = vec![Vec::new(); num_vertices];
        for (f, t) in faces.iter().enumerate() {
            for &v in t {
                if !inc[v as usize].contains(&(f as u32)) {
                    inc[v as usize].push(f as u32);
                }
            }
        }
        Working {
            faces: faces.to_vec(),
            alive: vec![true; faces.len()],
            inc,
        }
    }

    fn neighbours(&self, v: u32) -> HashSet<u32> {
        let mut s = HashSet::new();
        for &f in &self.inc[v as usize] {
            for &w in &self.faces[f as usize] {
                if w != v {
                    s.insert(w);
                }
            }
        }
        s
    }

    /// Removes triangle `f` (from its vertices' lists too).
    fn remove(&mut self, f: u32) {
        self.alive[f as usize] = false;
        for v in self.faces[f as usize] {
            self.inc[v as usize].retain(|&g| g != f);
        }
    }

    /// Merges vertex `b` into `a` across the rim edge a → b if that is safe; returns the removed
    /// triangle.
    fn collapse(&mut self, vertices: &[Point3<f64>], a: u32, b: u32) -> Option<usize> {
        // The one triangle holding a → b.
        let holder = self.inc[a as usize].iter().copied().find(|&f| {
            let t = self.faces[f as usize];
            (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b)
        });
        let f = holder?;
        let t = self.faces[f as usize];
        let &w = t.iter().find(|&&v| v != a && v != b)?;
        // Link condition for a boundary edge: a and b share exactly the neighbour w.
        let common: Vec<u32> = self
            .neighbours(a)
            .intersection(&self.neighbours(b))
            .copied()
            .collect();
        if common != [w] {
            return None;
        }
        // No other triangle of b may flip or degenerate when b moves onto a.
        let pa = vertices[a as usize];
        for &g in &self.inc[b as usize] {
            if g == f {
                continue;
            }
            let t = self.faces[g as usize];
            let p = |v: u32, moved: bool| {
                if moved && v == b {
                    pa
                } else {
                    vertices[v as usize]
                }
            };
            let normal = |moved: bool| {
                let (x, y, z) = (p(t[0], moved), p(t[1], moved), p(t[2], moved));
                (y - x).cross(&(z - x))
            };
            let (before, after) = (normal(false), normal(true));
            let agree = after.dot(&before);
            if agree.is_nan() || agree <= 0.0 || after.norm() <= 1e-6 * before.norm() {
                return None;
            }
        }
        self.remove(f);
        let moved: Vec<u32> = std::mem::take(&mut self.inc[b as usize]);
        for g in moved {
            for v in self.faces[g as usize].iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
            self.inc[a as usize].push(g);
        }
        Some(f as usize)
    }
}

/// Collapses, in the loop `lp` (rim half-edges lp[i] → lp[i+1]), every rim edge shorter than
/// `min_len` (world units) whose collapse is safe, shortest first, keeping at least 3 vertices.
/// Vertices in `shared` (on several loops, or twice on one) are left alone. Returns the merged
/// pairs [kept, removed] and the indices of the removed triangles.
pub(super) fn collapse_short_rim_edges(
    vertices: &[Point3<f64>],
    work: &mut Working,
    lp: &mut Vec<u32>,
    min_len: f64,
    shared: &HashMap<u32, usize>,
) -> (Vec<[u32; 2]>, Vec<usize>) {
    let mut merged = Vec::new();
    let mut removed = Vec::new();
    let mut refused: HashSet<(u32, u32)> = HashSet::new();
    loop {
        let n = lp.len();
        if n <= 3 {
            break;
        }
        let len = |i: usize| (vertices[lp[(i + 1) % n] as usize] - vertices[lp[i] as usize]).norm();
        let cand = (0..n)
            .filter(|&i| {
                let (a, b) = (lp[i], lp[(i + 1) % n]);
                len(i) < min_len
                    && !refused.contains(&(a, b))
                    && shared.get(&a).is_none_or(|&c| c <= 1)
                    && shared.get(&b).is_none_or(|&c| c <= 1)
            })
            .min_by(|&i, &j| len(i).total_cmp(&len(j)));
        let Some(i) = cand else { break };
        let (a, b) = (lp[i], lp[(i + 1) % n]);
        if let Some(f) = work.collapse(vertices, a, b) {
            removed.push(f);
            merged.push([a, b]);
            lp.remove((i + 1) % n);
        } else {
            refused.insert((a, b));
        }
    }
    (merged, removed)
}

/// Cuts off, in the loop `lp`, every ear (see the module docs) whose tip B lies within
/// `max_height` (world units) of the line through its neighbours A and C and is on no other
/// triangle, keeping at least 3 vertices. Vertices in `shared` are left alone. Returns the
/// removed triangles.
pub(super) fn cut_sliver_ears(
    vertices: &[Point3<f64>],
    work: &mut Working,
    lp: &mut Vec<u32>,
    max_height: f64,
    shared: &HashMap<u32, usize>,
) -> Vec<usize> {
    let mut removed = Vec::new();
    let mut i = 0;
    while lp.len() > 3 && i < lp.len() {
        let n = lp.len();
        let (a, b, c) = (lp[(i + n - 1) % n], lp[i], lp[(i + 1) % n]);
        let ear = match work.inc[b as usize].as_slice() {
            [f] => {
                let t = work.faces[*f as usize];
                let holds = |p: u32, q: u32| (0..3).any(|k| t[k] == p && t[(k + 1) % 3] == q);
                ((holds(a, b) && holds(b, c)) || (holds(c, b) && holds(b, a))).then_some(*f)
            }
            _ => None,
        };
        let sliver = || {
            let (pa, pb, pc) = (
                vertices[a as usize],
                vertices[b as usize],
                vertices[c as usize],
            );
            let ac = pc - pa;
            let len = ac.norm();
            len > 0.0 && (pb - pa).cross(&ac).norm() / len <= max_height
        };
        match ear {
            Some(f) if shared.get(&b).is_none_or(|&k| k <= 1) && sliver() => {
                work.remove(f);
                removed.push(f as usize);
                lp.remove(i);
                // The new corner at A may be an ear in its turn.
                i = i.saturating_sub(1);
            }
            _ => i += 1,
        }
    }
    removed
}
