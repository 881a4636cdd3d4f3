//! The narrow band: every grid node within `band` (world units) of a triangle, and its exact
//! Euclidean distance to the mesh.
//!
//! The triangles are scattered onto the grid: a node can only be within the band of a triangle
//! if it lies in the triangle's bounding box grown by the band and in the slab of half-width
//! `band` about the triangle's plane (each grid row meets that slab in one interval of nodes).
//! At each such node the distance to the triangle is computed in f64 by the hierarchy's own
//! point–triangle routine ([`crate::bvh::closest_point_on_triangle`]) and the smallest is kept, so a band
//! value is the minimum over every triangle within the band: exactly what
//! [`MeshBvh::closest_point_within`]`(p, band)` returns, at a fraction of the cost of one
//! hierarchy query per node (each node meets a few dozen triangles). The work is split over
//! z-layers (one rayon task per layer, writing only its own layer), the triangles being binned by
//! the layers their grown boxes cross.
//!
//! Outside the band, exact distances (when asked for) come from bounded hierarchy queries.

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

use super::{Layout, BAND};
use crate::bvh::{bound_by_triangle, MeshBvh, TrianglePoints};
use crate::TriMesh;

/// A triangle's footprint on the grid: node ranges of its grown box and its plane.
struct Footprint {
    /// The triangle, ready for closest-point queries.
    tri: TrianglePoints,
    /// Inclusive node ranges along x and y.
    i: [usize; 2],
    j: [usize; 2],
    /// Unit normal, plane offset (n·x = c) and half-width of the slab kept about the plane;
    /// `None` for a triangle without area or a sliver, which then covers its whole grown box.
    plane: Option<(Vector3<f64>, f64, f64)>,
    /// A ball holding the triangle: centre (the mean of the corners) and radius, grown by a
    /// billionth (of itself and of the band) so rounding never makes it too small.
    center: Point3<f64>,
    reach: f64,
}

/// Inclusive node range covering world coordinates [lo, hi] along an axis of `n` nodes, or
/// `None` when it misses the grid. Widened by a millionth of a voxel so rounding never drops a
/// candidate (extra candidates cost a query, never a wrong value).
fn node_range(lo: f64, hi: f64, origin: f64, h: f64, n: usize) -> Option<[usize; 2]> {
    let a = ((lo - origin) / h - 1e-6).ceil();
    let b = ((hi - origin) / h + 1e-6).floor();
    // NaN bounds fail `a <= b` and give None.
    if a.partial_cmp(&b).is_none_or(|o| o.is_gt()) || b < 0.0 || a > (n - 1) as f64 {
        return None;
    }
    Some([a.max(0.0) as usize, b.min((n - 1) as f64) as usize])
}

/// Fills `dist` (one value per node, +∞ on entry) with the exact distance to the mesh at every
/// node within `bw` (world units) of it, and sets [`BAND`] in `state` there. Returns the number
/// of band nodes.
pub(super) fn band_distances(
    bvh: &MeshBvh,
    layout: &Layout,
    bw: f64,
    dist: &mut [f32],
    state: &mut [u8],
) -> usize {
    let [nx, ny, nz] = layout.dims;
    let h = layout.h;
    let o = layout.origin;

    // Footprints and per-layer triangle lists.
    let mut footprints = Vec::with_capacity(bvh.num_triangles());
    let mut layers: Vec<Vec<u32>> = vec![Vec::new(); nz];
    for slot in 0..bvh.num_triangles() {
        let [a, b, c] = bvh.slot_triangle(slot);
        let lo = a.inf(b).inf(c);
        let hi = a.sup(b).sup(c);
        let (Some(i), Some(j), Some(k)) = (
            node_range(lo.x - bw, hi.x + bw, o[0], h, nx),
            node_range(lo.y - bw, hi.y + bw, o[1], h, ny),
            node_range(lo.z - bw, hi.z + bw, o[2], h, nz),
        ) else {
            continue;
        };
        // The plane cut is used only where the normal is accurate (not on slivers, whose whole
        // grown box is kept), with a slab widened by a millionth of band + longest edge.
        let n = (b - a).cross(&(c - a));
        let len = n.norm();
        let long2 = (b - a)
            .norm_squared()
            .max((c - b).norm_squared())
            .max((a - c).norm_squared());
        let plane = (len.is_finite() && len > 1e-6 * long2).then(|| {
            let n = n / len;
            let slab = bw + 1e-6 * (bw + long2.sqrt());
            (n, n.dot(&a.coords), slab)
        });
        let center = Point3::from((a.coords + b.coords + c.coords) / 3.0);
        let radius = [a, b, c]
            .iter()
            .map(|v| (*v - center).norm())
            .fold(0.0, f64::max);
        let reach = radius * (1.0 + 1e-9) + 1e-9 * bw;
        let id = footprints.len() as u32;
        footprints.push(Footprint {
            tri: TrianglePoints::new(a, b, c),
            i,
            j,
            plane,
            center,
            reach,
        });
        for layer in &mut layers[k[0]..=k[1]] {
            layer.push(id);
        }
    }

    let layer_len = nx * ny;
    dist.par_chunks_mut(layer_len)
        .zip(state.par_chunks_mut(layer_len))
        .zip(layers.par_iter())
        .enumerate()
        .map_init(
            || vec![f64::INFINITY; layer_len],
            |d2min, (k, ((dist, state), tris))| {
                let z = o[2] + k as f64 * h;
                for &t in tris {
                    let f = &footprints[t as usize];
                    for jj in f.j[0]..=f.j[1] {
                        let y = o[1] + jj as f64 * h;
                        let Some([i0, i1]) = f.row(y, z, o[0], h, nx) else {
                            continue;
                        };
                        let row = jj * nx;
                        for i in i0..=i1 {
                            let p = layout.world(i, jj, k);
                            let m = &mut d2min[row + i];
                            // The triangle lies in its ball: when the ball is farther than the
                            // nearest triangle so far, so is the triangle (skipped: the minimum
                            // is the same).
                            if *m < f64::INFINITY {
                                let r = f.reach + m.sqrt();
                                if (p - f.center).norm_squared() > r * r {
                                    continue;
                                }
                            }
                            let (x, _) = f.tri.closest_point(&p);
                            let d2 = (p - x).norm_squared();
                            if d2 < *m {
                                *m = d2;
                            }
                        }
                    }
                }
                let bw2 = bw * bw;
                let mut count = 0;
                for ((m, d), s) in d2min.iter_mut().zip(dist.iter_mut()).zip(state.iter_mut()) {
                    if *m <= bw2 {
                        *d = m.sqrt() as f32;
                        *s |= BAND;
                        count += 1;
                    }
                    *m = f64::INFINITY;
                }
                count
            },
        )
        .sum()
}

impl Footprint {
    /// Inclusive range of x nodes of the row (y, z) in the footprint: the grown box's range cut
    /// to the slab about the plane; `None` when empty.
    #[inline]
    fn row(&self, y: f64, z: f64, ox: f64, h: f64, nx: usize) -> Option<[usize; 2]> {
        let Some((n, c, slab)) = self.plane else {
            return Some(self.i);
        };
        let s = n.y * y + n.z * z - c;
        if n.x.abs() < 1e-12 {
            return (s.abs() <= slab).then_some(self.i);
        }
        let xa = (-slab - s) / n.x;
        let xb = (slab - s) / n.x;
        let [a, b] = node_range(xa.min(xb), xa.max(xb), ox, h, nx)?;
        (a <= self.i[1] && b >= self.i[0]).then(|| [a.max(self.i[0]), b.min(self.i[1])])
    }
}

/// Exact distances at every node outside the band (`dist` = +∞ there), row by row. The query is
/// bounded by the distance to the triangle closest to the previous node of the row (or, after a
/// band node, by its distance plus one voxel: distance is 1-Lipschitz), so the branch and bound
/// opens few hierarchy nodes beyond those that could hold a closer triangle.
pub(super) fn far_distances(mesh: &TriMesh, bvh: &MeshBvh, layout: &Layout, dist: &mut [f32]) {
    let [nx, ny, _] = layout.dims;
    let h = layout.h;
    dist.par_chunks_mut(nx).enumerate().for_each(|(row, d)| {
        let (jj, k) = (row % ny, row / ny);
        let mut prev: Option<f64> = None;
        let mut hint: Option<u32> = None;
        for (i, di) in d.iter_mut().enumerate() {
            if di.is_finite() {
                prev = Some(*di as f64);
                hint = None;
                continue;
            }
            let p: Point3<f64> = layout.world(i, jj, k);
            let bound = match (hint, prev) {
                (Some(f), _) => Some(bound_by_triangle(&p, &mesh.triangle(f as usize))),
                (None, Some(pd)) => Some((pd + h) * (1.0 + 1e-6)),
                (None, None) => None,
            };
            let cp = bvh.closest_point_bounded(&p, bound);
            *di = cp.distance as f32;
            prev = Some(cp.distance);
            hint = Some(cp.face);
        }
    });
}
