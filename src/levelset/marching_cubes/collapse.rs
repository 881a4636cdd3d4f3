//! Removal of the slivers of marching cubes by collapsing short edges, keeping the surface a
//! closed, consistently oriented 2-manifold.
//!
//! A mesh edge shorter than a fraction of the voxel joins two crossings near one grid node (two
//! points on distinct grid edges that are that close must both lie near the node the edges
//! share), so only vertices flagged near a node are candidates. Each candidate edge (a, b),
//! shortest first, is collapsed by merging one endpoint into the other (a half-edge collapse:
//! the kept vertex does not move, so every vertex stays on the interpolated level set). A
//! collapse is made only when
//! - the link condition holds: the vertices adjacent to both a and b are exactly the two
//!   opposite the edge, and the four do not bound a tetrahedron (Dey, Edelsbrunner, Guha and
//!   Nekhayev, "Topology preserving edge contraction", 1999): then the result is again a closed
//!   2-manifold with the same topology;
//! - no triangle that survives flips (its normal keeps a positive dot product with the old one)
//!   or drops below a tiny area;
//! - the smallest angle around does not get worse, except for a new needle that still has a
//!   short edge (its own collapse comes later); caps (an angle above 150°) never pass;
//! - no grid node changes side: moving the removed vertex straight to the kept one sweeps each
//!   triangle of its star through a thin tetrahedron, and no grid node may lie in one (or on a
//!   new triangle). The surface therefore still separates the inside nodes (φ < 0) from the
//!   outside ones, as the marching cubes' surface does.
//!
//! The vertex nearer its grid node is merged into the other; if that is refused the other way
//! is tried. The two triangles on the edge disappear; the caller drops them and the merged
//! vertices. Each collapse only touches the cubes around one node, so the extractor runs this
//! per slab of z-layers in parallel, then once more for the nodes on the layers slabs share.

use crate::bvh::closest_point_on_triangle;
use nalgebra::Point3;

pub(super) struct CollapseParams {
    /// Edges shorter than this (world units) are collapsed.
    pub max_length: f64,
    /// Voxel size (world units): sets the area floor.
    pub voxel: f64,
    /// Grid origin (world units): where the grid nodes are.
    pub origin: [f64; 3],
}

/// A surviving triangle must keep twice its area above this times h².
const MIN_DOUBLE_AREA_REL: f64 = 1e-9;
/// A new triangle must stay at least this times h from every grid node.
const NODE_CLEARANCE_REL: f64 = 1e-6;
/// A new triangle with a short edge may be worse than the old ones only when no angle of it
/// exceeds 150° (a needle, which a later collapse removes, not a cap): cos 150°.
const NEEDLE_MAX_ANGLE_COS: f64 = -0.866_025_403_784_438_6;
/// A tetrahedron whose volume is below this times the product of its edges from one corner is
/// treated as flat.
const FLAT_REL: f64 = 1e-9;
/// Marks a removed face.
pub(super) const DEAD: u32 = u32::MAX;
const NONE: u32 = u32::MAX;

/// Collapses the short edges between `candidates` (vertex indices) in place; returns the
/// vertices merged away (no face uses them any more). The faces must form a closed, consistently
/// oriented 2-manifold around the candidates (marching cubes' do). Removed faces become
/// `[DEAD; 3]`: the caller compacts.
pub(super) fn collapse_short_edges(
    vertices: &[Point3<f64>],
    faces: &mut [[u32; 3]],
    candidates: &[u32],
    params: &CollapseParams,
) -> Vec<u32> {
    let nv = vertices.len();
    let mut slot = vec![NONE; nv];
    for (s, &v) in candidates.iter().enumerate() {
        slot[v as usize] = s as u32;
    }
    let nc = candidates.len();

    // Faces around each candidate (CSR), and the short candidate edges (once per edge: the
    // directed use with a < b; a closed oriented mesh has exactly one).
    let mut count = vec![0u32; nc + 1];
    let mut edges: Vec<(f64, u32, u32)> = Vec::new();
    let max2 = params.max_length * params.max_length;
    for f in faces.iter() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let sa = slot[a as usize];
            if sa != NONE {
                count[sa as usize + 1] += 1;
                if a < b && slot[b as usize] != NONE {
                    let d2 = (vertices[a as usize] - vertices[b as usize]).norm_squared();
                    if d2 < max2 {
                        edges.push((d2, a, b));
                    }
                }
            }
        }
    }
    if edges.is_empty() {
        return Vec::new();
    }
    for s in 0..nc {
        count[s + 1] += count[s];
    }
    let start = count;
    let mut fill = start.clone();
    let mut lists = vec![0u32; start[nc] as usize];
    for (fi, f) in faces.iter().enumerate() {
        for &v in f {
            let s = slot[v as usize];
            if s != NONE {
                lists[fill[s as usize] as usize] = fi as u32;
                fill[s as usize] += 1;
            }
        }
    }
    edges.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));

    let mut state = State {
        faces,
        vertices,
        slot,
        start,
        lists,
        merged_into: vec![NONE; nc],
        next_member: vec![NONE; nc],
        last_member: (0..nc as u32).collect(),
        min_double_area: MIN_DOUBLE_AREA_REL * params.voxel * params.voxel,
        max_length: params.max_length,
        origin: params.origin,
        voxel: params.voxel,
        around_a: Vec::new(),
        around_b: Vec::new(),
        scratch: Scratch::default(),
    };
    let node_distance = |v: u32| -> f64 {
        let p = state.vertices[v as usize];
        let g = [0, 1, 2].map(|i| (p[i] - params.origin[i]) / params.voxel);
        let r = g.map(|x| x - x.round());
        (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt()
    };
    let mut merged = Vec::new();
    for &(_, u, v) in &edges {
        let (a, b) = (state.find(u), state.find(v));
        if a == b
            || (state.vertices[a as usize] - state.vertices[b as usize]).norm_squared() >= max2
        {
            continue;
        }
        let (first, second) = if node_distance(a) <= node_distance(b) {
            (a, b)
        } else {
            (b, a)
        };
        if state.try_collapse(first, second) {
            merged.push(first);
        } else if state.try_collapse(second, first) {
            merged.push(second);
        }
    }
    merged
}

/// Reused buffers of the collapse checks.
#[derive(Default)]
struct Scratch {
    na: Vec<u32>,
    nb: Vec<u32>,
    old: Vec<[Point3<f64>; 3]>,
    new: Vec<[Point3<f64>; 3]>,
    moving: Vec<[Point3<f64>; 3]>,
}

struct State<'m> {
    faces: &'m mut [[u32; 3]],
    vertices: &'m [Point3<f64>],
    /// Candidate slot of each vertex (NONE for the others).
    slot: Vec<u32>,
    /// CSR of the faces around each candidate at the start.
    start: Vec<u32>,
    lists: Vec<u32>,
    /// Per slot: the vertex it was merged into (NONE while alive).
    merged_into: Vec<u32>,
    /// Per slot: the next slot whose face list belongs to the same surviving vertex.
    next_member: Vec<u32>,
    last_member: Vec<u32>,
    min_double_area: f64,
    max_length: f64,
    origin: [f64; 3],
    voxel: f64,
    around_a: Vec<u32>,
    around_b: Vec<u32>,
    scratch: Scratch,
}

impl State<'_> {
    /// The surviving vertex that `v` was merged into (itself when alive).
    fn find(&mut self, mut v: u32) -> u32 {
        let root = {
            let mut r = v;
            loop {
                let m = self.merged_into[self.slot[r as usize] as usize];
                if m == NONE {
                    break r;
                }
                r = m;
            }
        };
        while v != root {
            let s = self.slot[v as usize] as usize;
            v = std::mem::replace(&mut self.merged_into[s], root);
        }
        root
    }

    /// The live faces around the surviving candidate `v`.
    fn faces_around(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        let mut s = self.slot[v as usize];
        while s != NONE {
            let (lo, hi) = (self.start[s as usize], self.start[s as usize + 1]);
            for &f in &self.lists[lo as usize..hi as usize] {
                let face = self.faces[f as usize];
                if face[0] != DEAD && face.contains(&v) {
                    out.push(f);
                }
            }
            s = self.next_member[s as usize];
        }
    }

    /// Merges `a` into `b` if that keeps a closed manifold without flipped or vanishing
    /// triangles.
    fn try_collapse(&mut self, a: u32, b: u32) -> bool {
        let mut around_a = std::mem::take(&mut self.around_a);
        let mut around_b = std::mem::take(&mut self.around_b);
        self.faces_around(a, &mut around_a);
        self.faces_around(b, &mut around_b);
        let mut scratch = std::mem::take(&mut self.scratch);
        let ok = self.collapsible(a, b, &around_a, &around_b, &mut scratch);
        self.scratch = scratch;
        if ok {
            for &f in &around_a {
                let face = &mut self.faces[f as usize];
                if face.contains(&b) {
                    *face = [DEAD; 3];
                } else {
                    for v in face.iter_mut() {
                        if *v == a {
                            *v = b;
                        }
                    }
                }
            }
            let (sa, sb) = (self.slot[a as usize], self.slot[b as usize]);
            self.merged_into[sa as usize] = b;
            let tail = self.last_member[sb as usize];
            self.next_member[tail as usize] = sa;
            self.last_member[sb as usize] = self.last_member[sa as usize];
        }
        self.around_a = around_a;
        self.around_b = around_b;
        ok
    }

    fn collapsible(
        &self,
        a: u32,
        b: u32,
        around_a: &[u32],
        around_b: &[u32],
        scratch: &mut Scratch,
    ) -> bool {
        // The two triangles on edge (a, b) and their opposite vertices.
        let mut opposite = [NONE; 2];
        let mut n_edge = 0;
        for &f in around_a {
            let face = self.faces[f as usize];
            if face.contains(&b) {
                if n_edge == 2 {
                    return false;
                }
                opposite[n_edge] = *face.iter().find(|&&v| v != a && v != b).unwrap_or(&NONE);
                n_edge += 1;
            }
        }
        if n_edge != 2 || opposite[0] == opposite[1] {
            return false;
        }
        // Link condition: the common neighbours of a and b are exactly the two opposite vertices.
        let neighbours = |faces: &[u32], centre: u32, n: &mut Vec<u32>| {
            n.clear();
            n.extend(
                faces
                    .iter()
                    .flat_map(|&f| self.faces[f as usize])
                    .filter(|&v| v != centre),
            );
            n.sort_unstable();
            n.dedup();
        };
        let Scratch {
            na,
            nb,
            old,
            new,
            moving,
        } = scratch;
        neighbours(around_a, a, na);
        neighbours(around_b, b, nb);
        let common = na
            .iter()
            .filter(|&&v| v != b && nb.binary_search(&v).is_ok())
            .count();
        if common != 2 {
            return false;
        }
        // Not a tetrahedron: a and b must not both have a triangle with both opposite vertices.
        let has_opposite_edge = |faces: &[u32]| {
            faces.iter().any(|&f| {
                let face = self.faces[f as usize];
                face.contains(&opposite[0]) && face.contains(&opposite[1])
            })
        };
        if has_opposite_edge(around_a) && has_opposite_edge(around_b) {
            return false;
        }
        // Geometry: the triangles that stay keep their orientation and some area.
        let pb = self.vertices[b as usize];
        old.clear();
        new.clear();
        moving.clear();
        for &f in around_a {
            let face = self.faces[f as usize];
            let p = face.map(|v| self.vertices[v as usize]);
            old.push(p);
            if face.contains(&b) {
                continue;
            }
            moving.push(p);
            let q = face.map(|v| {
                if v == a {
                    pb
                } else {
                    self.vertices[v as usize]
                }
            });
            let n_old = (p[1] - p[0]).cross(&(p[2] - p[0]));
            let n_new = (q[1] - q[0]).cross(&(q[2] - q[0]));
            if n_new.norm() <= self.min_double_area || n_new.dot(&n_old) <= 0.0 {
                return false;
            }
            new.push(q);
        }
        // The smallest angle around does not get worse (the triangles on the short edge, which
        // disappear, hold the smallest angles as a rule). A new triangle with a short edge may
        // be worse for now if it is a needle (no angle above 150°): collapsing that edge later
        // removes it; a cap (an angle near 180°) would stay.
        let max2 = self.max_length * self.max_length;
        let worst_old = old
            .iter()
            .map(smallest_angle_cos)
            .fold(f64::NEG_INFINITY, f64::max);
        let worse = new.iter().any(|t| {
            if smallest_angle_cos(t) <= worst_old {
                return false;
            }
            let shortest = (0..3)
                .map(|i| (t[(i + 1) % 3] - t[i]).norm_squared())
                .fold(f64::INFINITY, f64::min);
            !(shortest < max2 && largest_angle_cos(t) >= NEEDLE_MAX_ANGLE_COS)
        });
        if worse {
            return false;
        }
        // No grid node is swept: moving a straight to b sweeps each triangle t of its star that
        // stays through the tetrahedron conv(t ∪ {b}) (the two on the edge shrink within their
        // own planes). A node outside them cannot change side; one on their boundary (on a new
        // triangle) is refused too. The nodes tried are those in each tetrahedron's box, grown
        // a little because vertices often lie exactly on grid planes, where rounding could drop
        // a node.
        let tol = NODE_CLEARANCE_REL * self.voxel;
        for t in moving.iter() {
            let lo = t[0].inf(&t[1]).inf(&t[2]).inf(&pb);
            let hi = t[0].sup(&t[1]).sup(&t[2]).sup(&pb);
            let range = |i: usize| {
                let g = |x: f64| (x - self.origin[i]) / self.voxel;
                (
                    (g(lo[i]) - 1e-6).ceil() as i64,
                    (g(hi[i]) + 1e-6).floor() as i64,
                )
            };
            let (rx, ry, rz) = (range(0), range(1), range(2));
            for k in rz.0..=rz.1 {
                for j in ry.0..=ry.1 {
                    for i in rx.0..=rx.1 {
                        let node = Point3::new(
                            self.origin[0] + self.voxel * i as f64,
                            self.origin[1] + self.voxel * j as f64,
                            self.origin[2] + self.voxel * k as f64,
                        );
                        if in_tetrahedron(&node, t, &pb, tol) {
                            return false;
                        }
                    }
                }
            }
        }
        true
    }
}

/// Whether `p` lies in the closed tetrahedron (t[0], t[1], t[2], d), or within `tol` of it when
/// it is flat.
fn in_tetrahedron(p: &Point3<f64>, t: &[Point3<f64>; 3], d: &Point3<f64>, tol: f64) -> bool {
    let lo = t[0].inf(&t[1]).inf(&t[2]).inf(d);
    let hi = t[0].sup(&t[1]).sup(&t[2]).sup(d);
    if (0..3).any(|i| p[i] < lo[i] - tol || p[i] > hi[i] + tol) {
        return false;
    }
    let (e1, e2, e3, q) = (t[1] - t[0], t[2] - t[0], d - t[0], p - t[0]);
    let det = e1.dot(&e2.cross(&e3));
    if det.abs() > FLAT_REL * e1.norm() * e2.norm() * e3.norm() {
        // Barycentric coordinates by Cramer's rule, with a hair of slack on the closed side.
        let l1 = q.dot(&e2.cross(&e3)) / det;
        let l2 = e1.dot(&q.cross(&e3)) / det;
        let l3 = e1.dot(&e2.cross(&q)) / det;
        let eps = 1e-9;
        return l1 >= -eps && l2 >= -eps && l3 >= -eps && l1 + l2 + l3 <= 1.0 + eps;
    }
    // Flat: near any of its four faces.
    let near = |a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>| {
        (closest_point_on_triangle(p, a, b, c).0 - p).norm() <= tol
    };
    near(&t[0], &t[1], &t[2])
        || near(&t[0], &t[1], d)
        || near(&t[1], &t[2], d)
        || near(&t[2], &t[0], d)
}

/// The cosine of the smallest angle of a triangle (the angle opposite its shortest side): the
/// larger, the worse the triangle.
fn smallest_angle_cos(t: &[Point3<f64>; 3]) -> f64 {
    angle_cos(t, |x, y| x < y)
}

/// The cosine of the largest angle of a triangle (opposite its longest side).
fn largest_angle_cos(t: &[Point3<f64>; 3]) -> f64 {
    angle_cos(t, |x, y| x > y)
}

/// The cosine of the angle opposite the side that `pick` prefers (by squared length).
#[inline]
fn angle_cos(t: &[Point3<f64>; 3], pick: impl Fn(f64, f64) -> bool) -> f64 {
    let sides = [
        (t[2] - t[1]).norm_squared(),
        (t[0] - t[2]).norm_squared(),
        (t[1] - t[0]).norm_squared(),
    ];
    let mut k = 0;
    for i in 1..3 {
        if pick(sides[i], sides[k]) {
            k = i;
        }
    }
    // The angle at corner k, between the two sides that meet there.
    let (u, v) = (t[(k + 1) % 3] - t[k], t[(k + 2) % 3] - t[k]);
    let (a, b) = (sides[(k + 2) % 3], sides[(k + 1) % 3]);
    u.dot(&v) / (a * b).sqrt().max(f64::MIN_POSITIVE)
}
