//! Closest point on the mesh surface to a query point.
//!
//! Point–triangle: the Voronoi-region classification of Ericson, *Real-Time Collision
//! Detection* (2005), §5.1.5, with every division guarded so degenerate (zero-area, collinear or
//! repeated-vertex) triangles fall back to the nearest of their edges instead of producing NaN.
//!
//! Mesh query: branch and bound on the obvhs hierarchy. Nodes are visited nearest box first
//! (depth first, nearer child popped first) and a node is skipped once its box is farther than
//! the best triangle found so far. Box distances are computed in f64 from the padded, outward
//! rounded f32 boxes (see [`super::tri_bvh`]), so culling is conservative; triangle distances
//! are computed in f64 on the original coordinates.

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

use super::MeshBvh;

/// The closest point on a mesh to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    /// The closest point on the surface (world units).
    pub point: Point3<f64>,
    /// Euclidean distance from the query point to `point` (world units). `f64::INFINITY` when
    /// nothing was found (empty mesh).
    pub distance: f64,
    /// Mesh face holding `point`; `u32::MAX` when nothing was found.
    pub face: u32,
    /// Barycentric coordinates of `point` in that face: point = Σᵢ `bary[i]` · corner i.
    pub bary: [f64; 3],
}

impl ClosestPoint {
    /// The answer for a mesh without triangles: infinite distance, face `u32::MAX`, and the query
    /// point itself standing in for the point.
    pub fn none(p: &Point3<f64>) -> Self {
        ClosestPoint {
            point: *p,
            distance: f64::INFINITY,
            face: u32::MAX,
            bary: [0.0; 3],
        }
    }

    /// Whether a face was found.
    pub fn is_found(&self) -> bool {
        self.face != u32::MAX
    }
}

/// `num / den` clamped to [0, 1], or 0 when `den` is not positive (a degenerate edge: its start).
fn unit_fraction(num: f64, den: f64) -> f64 {
    if den > 0.0 {
        (num / den).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Closest point to `p` on the segment a–b, with its parameter along a→b in [0, 1].
fn closest_on_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> (Point3<f64>, f64) {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let s = unit_fraction((p - a).dot(&ab), len2);
    (a + ab * s, s)
}

/// Nearest of the three edges: the fallback for degenerate triangles.
fn closest_on_edges(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> (Point3<f64>, [f64; 3]) {
    let (qab, s) = closest_on_segment(p, a, b);
    let (qbc, t) = closest_on_segment(p, b, c);
    let (qca, u) = closest_on_segment(p, c, a);
    let dab = (p - qab).norm_squared();
    let dbc = (p - qbc).norm_squared();
    let dca = (p - qca).norm_squared();
    if dab <= dbc && dab <= dca {
        (qab, [1.0 - s, s, 0.0])
    } else if dbc <= dca {
        (qbc, [0.0, 1.0 - t, t])
    } else {
        (qca, [u, 0.0, 1.0 - u])
    }
}

/// Closest point to `p` on the triangle (a, b, c) and its barycentric coordinates
/// `[u, v, w]` (point = u·a + v·b + w·c, all in [0, 1], summing to 1).
///
/// Classifies `p` into the triangle's vertex, edge or face Voronoi regions from six dot products
/// (Ericson 2005, §5.1.5). Degenerate triangles never give NaN: the face region of a triangle
/// without area is replaced by the nearest edge, and zero-length edges by their endpoint.
pub fn closest_point_on_triangle(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> (Point3<f64>, [f64; 3]) {
    TrianglePoints::new(a, b, c).closest_point(p)
}

/// A triangle with what the closest-point query derives from its corners alone, for many
/// queries against one triangle ([`closest_point_on_triangle`] is the one-off form: the same
/// answer, bit for bit).
#[derive(Debug, Clone, Copy)]
pub struct TrianglePoints {
    a: Point3<f64>,
    b: Point3<f64>,
    c: Point3<f64>,
    ab: Vector3<f64>,
    ac: Vector3<f64>,
    /// No area (or NaN): the nearest edge.
    degenerate: bool,
    /// A sliver: the nearer of the region answer and the nearest edge.
    sliver: bool,
}

impl TrianglePoints {
    /// The triangle (a, b, c).
    pub fn new(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> Self {
        let ab: Vector3<f64> = b - a;
        let ac: Vector3<f64> = c - a;
        let (ab2, ac2, abac) = (ab.norm_squared(), ac.norm_squared(), ab.dot(&ac));
        let gram = ab2 * ac2 - abac * abac;
        let degenerate = gram.is_nan() || gram <= 0.0;
        TrianglePoints {
            a: *a,
            b: *b,
            c: *c,
            ab,
            ac,
            degenerate,
            sliver: !degenerate && gram < SLIVER * ab2 * ac2,
        }
    }

    /// [`closest_point_on_triangle`] of `p` on this triangle.
    #[inline]
    pub fn closest_point(&self, p: &Point3<f64>) -> (Point3<f64>, [f64; 3]) {
        let (a, b, c) = (&self.a, &self.b, &self.c);
        // The region tests assume a proper triangle. Without area (collinear corners, a
        // zero-length edge) the closest point is on an edge. On a sliver (sin² of the angle at
        // a below SLIVER) rounding can misclassify the regions; every candidate lies on the
        // triangle, so the nearer of the region answer and the nearest edge is then taken.
        if self.degenerate {
            return closest_on_edges(p, a, b, c);
        }
        let region = closest_by_regions(p, a, b, c, &self.ab, &self.ac);
        if self.sliver {
            let edge = closest_on_edges(p, a, b, c);
            if (p - edge.0).norm_squared() < (p - region.0).norm_squared() {
                return edge;
            }
        }
        region
    }
}

/// Ericson's region classification proper (the triangle has area).
fn closest_by_regions(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
    ab: &Vector3<f64>,
    ac: &Vector3<f64>,
) -> (Point3<f64>, [f64; 3]) {
    // Vertex region of a.
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, [1.0, 0.0, 0.0]);
    }

    // Vertex region of b.
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, [0.0, 1.0, 0.0]);
    }

    // Edge region ab (d1 − d3 = |ab|²).
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = unit_fraction(d1, d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }

    // Vertex region of c.
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, [0.0, 0.0, 1.0]);
    }

    // Edge region ac (d2 − d6 = |ac|²).
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = unit_fraction(d2, d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }

    // Edge region bc ((d4 − d3) + (d5 − d6) = |bc|²).
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = unit_fraction(d4 - d3, (d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }

    // Face region: va, vb, vc are the barycentric coordinates scaled by their sum (= |ab × ac|²
    // in exact arithmetic). Rounding can only push one slightly below 0 near an edge: the
    // nearest edge is then the answer.
    let den = va + vb + vc;
    if den.is_nan() || den <= 0.0 || va < 0.0 || vb < 0.0 || vc < 0.0 {
        return closest_on_edges(p, a, b, c);
    }
    let v = vb / den;
    let w = vc / den;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// A bound on the distance from `p` to a mesh holding the triangle `tri`: the distance to that
/// triangle, grown by a billionth so rounding never makes it too small (for
/// [`MeshBvh::closest_point_bounded`]).
pub fn bound_by_triangle(p: &Point3<f64>, tri: &[Point3<f64>; 3]) -> f64 {
    let [a, b, c] = tri;
    (p - closest_point_on_triangle(p, a, b, c).0).norm() * (1.0 + 1e-9)
}

/// sin² of the angle at the first corner below which a triangle is also checked against its edges.
const SLIVER: f64 = 1e-6;

impl MeshBvh {
    /// Closest point on the mesh to `p`. On a mesh without triangles the answer has
    /// `distance = f64::INFINITY` and `face = u32::MAX` (see [`ClosestPoint::none`]).
    pub fn closest_point(&self, p: &Point3<f64>) -> ClosestPoint {
        self.closest_point_within(p, f64::INFINITY)
            .unwrap_or_else(|| ClosestPoint::none(p))
    }

    /// Closest point on the mesh to `p` if it lies within `max_dist` (world units, inclusive);
    /// `None` otherwise. Cheaper than [`MeshBvh::closest_point`] for small `max_dist`, since
    /// nodes farther than `max_dist` are never opened (narrow-band queries).
    pub fn closest_point_within(&self, p: &Point3<f64>, max_dist: f64) -> Option<ClosestPoint> {
        if self.is_empty() || max_dist.is_nan() || max_dist < 0.0 {
            return None;
        }
        let q = [
            p.x - self.origin.x,
            p.y - self.origin.y,
            p.z - self.origin.z,
        ];
        let box_d2 = |node: usize| -> f64 {
            let (lo, hi) = self.node_box_local(node);
            let mut d2 = 0.0;
            for k in 0..3 {
                let e = (lo[k] - q[k]).max(q[k] - hi[k]).max(0.0);
                d2 += e * e;
            }
            d2
        };

        // Best squared distance so far; starts at the bound so farther nodes are never opened.
        let mut best_d2 = max_dist * max_dist;
        let mut best: Option<(usize, Point3<f64>, [f64; 3], f64)> = None;

        let nodes = &self.bvh.nodes;
        let mut stack: Vec<(u32, f64)> = Vec::with_capacity(64);
        let root_d2 = box_d2(0);
        if root_d2 <= best_d2 {
            stack.push((0, root_d2));
        }
        while let Some((ni, nd2)) = stack.pop() {
            if nd2 > best_d2 {
                continue;
            }
            let node = &nodes[ni as usize];
            if node.is_leaf() {
                let start = node.first_index as usize;
                for slot in start..start + node.prim_count as usize {
                    let [a, b, c] = &self.tris[slot];
                    let (x, bary) = closest_point_on_triangle(p, a, b, c);
                    let d2 = (p - x).norm_squared();
                    if d2 < best_d2 || (best.is_none() && d2 <= best_d2) {
                        best_d2 = d2;
                        best = Some((slot, x, bary, d2));
                    }
                }
            } else {
                let l = node.first_index;
                let r = l + 1;
                let dl = box_d2(l as usize);
                let dr = box_d2(r as usize);
                // Push the farther child first so the nearer one is opened next.
                let (near, dn, far, df) = if dl <= dr {
                    (l, dl, r, dr)
                } else {
                    (r, dr, l, dl)
                };
                if df <= best_d2 {
                    stack.push((far, df));
                }
                if dn <= best_d2 {
                    stack.push((near, dn));
                }
            }
        }

        best.map(|(slot, point, bary, d2)| ClosestPoint {
            point,
            distance: d2.sqrt(),
            face: self.face_ids[slot],
            bary,
        })
    }

    /// [`MeshBvh::closest_point`] with a bound on its distance known beforehand (world units;
    /// `None`: no bound): the same answer, found opening fewer boxes when the bound is tight, as
    /// the distance to a neighbouring query's nearest triangle is ([`bound_by_triangle`]).
    pub fn closest_point_bounded(&self, p: &Point3<f64>, bound: Option<f64>) -> ClosestPoint {
        bound
            .and_then(|r| self.closest_point_within(p, r))
            .unwrap_or_else(|| self.closest_point(p))
    }

    /// [`MeshBvh::closest_point`] for many points, in parallel (rayon).
    pub fn closest_points(&self, ps: &[Point3<f64>]) -> Vec<ClosestPoint> {
        ps.par_iter().map(|p| self.closest_point(p)).collect()
    }

    /// [`MeshBvh::closest_point_within`] for many points, in parallel (rayon).
    pub fn closest_points_within(
        &self,
        ps: &[Point3<f64>],
        max_dist: f64,
    ) -> Vec<Option<ClosestPoint>> {
        ps.par_iter()
            .map(|p| self.closest_point_within(p, max_dist))
            .collect()
    }
}
