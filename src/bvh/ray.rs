//! Ray casts against the mesh: nearest hit and number of hits.
//!
//! Ray–triangle: the watertight test of Woop, Benthin and Wald, "Watertight ray/triangle
//! intersection", JCGT 2(1), 2013, in f64. The ray is sheared so it runs along +z from the
//! origin; the three 2-D edge functions are then computed from the same products for both
//! triangles sharing an edge, so a ray can never slip between two triangles through their
//! common edge. Both faces count (two-sided).
//!
//! Mesh query: obvhs's own f32 stack traversal of its hierarchy does the culling. The ray is
//! first clipped in f64 against the (padded) root box and restarted from there, so the f32 ray
//! lies within a few diagonals of the local origin; the box padding (see [`super::tri_bvh`])
//! then exceeds every f32 deviation of the ray from its f64 path, including obvhs's clamping of
//! tiny direction components. Hits are computed in f64 with the original origin and direction,
//! and obvhs's `tmax` is only lowered to the best f64 hit plus the padding.

use glam::Vec3A;
use nalgebra::{Point3, Vector3};
use obvhs::bvh2::node::Bvh2Node;
use obvhs::ray::{Ray, RayHit as ObvhsHit};

use super::tri_bvh::f32_up;
use super::MeshBvh;

/// Where a ray first hits the mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Ray parameter of the hit: `point = origin + t · dir` (in units of `|dir|`, so a world
    /// distance only when `dir` has unit length).
    pub t: f64,
    /// Mesh face hit.
    pub face: u32,
    /// Barycentric coordinates of the hit in that face: point = Σᵢ `bary[i]` · corner i.
    pub bary: [f64; 3],
    /// The hit point, `origin + t · dir` (world units).
    pub point: Point3<f64>,
}

/// Intersection of the ray `origin + t·dir`, 0 ≤ t ≤ `t_max`, with the triangle (a, b, c), from
/// either side. Returns the ray parameter and the barycentric coordinates of the hit.
///
/// Watertight (Woop, Benthin, Wald 2013): a ray through a shared edge or vertex hits at least
/// one of the triangles around it. Rays in the triangle's plane (zero determinant) and
/// degenerate triangles miss.
pub fn intersect_ray_triangle(
    origin: &Point3<f64>,
    dir: &Vector3<f64>,
    t_max: f64,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> Option<(f64, [f64; 3])> {
    // Axis of largest |dir| becomes z; the other two keep a right-handed order, swapped when
    // the ray runs along −z so the winding (hence the sign convention) is preserved.
    let kz = dir.iamax();
    let mut kx = (kz + 1) % 3;
    let mut ky = (kx + 1) % 3;
    if dir[kz] < 0.0 {
        std::mem::swap(&mut kx, &mut ky);
    }
    let dz = dir[kz];
    if dz == 0.0 || !dz.is_finite() {
        return None;
    }
    let sx = dir[kx] / dz;
    let sy = dir[ky] / dz;
    let sz = 1.0 / dz;

    let pa = a - origin;
    let pb = b - origin;
    let pc = c - origin;
    // Shear into the ray's frame.
    let ax = pa[kx] - sx * pa[kz];
    let ay = pa[ky] - sy * pa[kz];
    let bx = pb[kx] - sx * pb[kz];
    let by = pb[ky] - sy * pb[kz];
    let cx = pc[kx] - sx * pc[kz];
    let cy = pc[ky] - sy * pc[kz];

    // 2-D edge functions: u weights a, v weights b, w weights c.
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }

    // Scaled hit distance; compare before dividing so t is only formed for hits.
    let tz = u * (sz * pa[kz]) + v * (sz * pb[kz]) + w * (sz * pc[kz]);
    if det > 0.0 {
        if tz < 0.0 || tz > t_max * det {
            return None;
        }
    } else if tz > 0.0 || tz < t_max * det {
        return None;
    }
    let inv = 1.0 / det;
    let t = tz * inv;
    if !(t >= 0.0 && t <= t_max) {
        return None;
    }
    Some((t, [u * inv, v * inv, w * inv]))
}

/// The part of a ray inside the padded root box. `s` is the distance along the ray from its
/// origin in world units (s = t·|dir|); the segment is [s_start, s_end].
struct Clipped {
    /// The point at s_start, in the local frame of the node boxes.
    start_local: Vector3<f64>,
    /// dir / |dir|.
    unit: Vector3<f64>,
    /// |dir|.
    len: f64,
    s_start: f64,
    s_end: f64,
}

impl MeshBvh {
    /// Clips `origin + t·dir`, 0 ≤ t ≤ `t_max`, to the padded root box; `None` if it misses the
    /// box or the input is not a usable ray (non-finite values, zero direction, negative or NaN
    /// `t_max`).
    fn clip_ray(&self, origin: &Point3<f64>, dir: &Vector3<f64>, t_max: f64) -> Option<Clipped> {
        if self.is_empty() || t_max.is_nan() || t_max < 0.0 {
            return None;
        }
        if !origin.iter().all(|c| c.is_finite()) || !dir.iter().all(|c| c.is_finite()) {
            return None;
        }
        let len = dir.norm();
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        let unit = dir / len;
        let o = origin.coords - self.origin;
        let (lo, hi) = self.node_box_local(0);
        let mut s0 = 0.0f64;
        let mut s1 = t_max * len;
        for k in 0..3 {
            if unit[k] == 0.0 {
                if o[k] < lo[k] || o[k] > hi[k] {
                    return None;
                }
            } else {
                let ta = (lo[k] - o[k]) / unit[k];
                let tb = (hi[k] - o[k]) / unit[k];
                s0 = s0.max(ta.min(tb));
                s1 = s1.min(ta.max(tb));
            }
        }
        if s0.is_nan() || s1.is_nan() || s0 > s1 {
            return None;
        }
        // Back off by the padding so rounding in this clip cannot start past a hit.
        let s_start = (s0 - self.pad).max(0.0);
        Some(Clipped {
            start_local: o + unit * s_start,
            unit,
            len,
            s_start,
            s_end: s1,
        })
    }

    /// Runs obvhs's traversal over the clipped ray. `visit(slot, &mut tmax_world)` is called for
    /// every triangle slot in a leaf the ray reaches; it may lower the world-distance bound, which
    /// is passed back to obvhs (plus the padding) to cull farther nodes.
    fn traverse_ray(&self, clip: &Clipped, mut visit: impl FnMut(usize, &mut f64)) {
        let o32 = Vec3A::new(
            clip.start_local.x as f32,
            clip.start_local.y as f32,
            clip.start_local.z as f32,
        );
        let d32 = Vec3A::new(clip.unit.x as f32, clip.unit.y as f32, clip.unit.z as f32);
        let span = clip.s_end - clip.s_start;
        let ray = Ray::new(o32, d32, 0.0, f32_up(span + 2.0 * self.pad));
        let pad = self.pad;
        let s_start = clip.s_start;
        let mut bound = f64::INFINITY;
        let mut hit = ObvhsHit::none();
        let leaf = |node: &Bvh2Node, ray: &mut Ray, _hit: &mut ObvhsHit| {
            let start = node.first_index as usize;
            for slot in start..start + node.prim_count as usize {
                let before = bound;
                visit(slot, &mut bound);
                if bound < before {
                    let cull = f32_up(bound - s_start + 2.0 * pad);
                    if cull < ray.tmax {
                        ray.tmax = cull;
                    }
                }
            }
            true
        };
        obvhs::fast_stack!(u32, (96, 192), self.bvh.max_depth, stack, {
            self.bvh
                .ray_traverse_dynamic(&mut stack, ray, &mut hit, leaf)
        });
    }

    /// Nearest hit of the ray `origin + t·dir` with 0 ≤ t ≤ `t_max` (t in units of `|dir|`;
    /// pass `f64::INFINITY` for an unbounded ray). Both sides of every triangle count. `None` if
    /// the ray misses, or if the input is unusable (non-finite values, zero direction).
    pub fn cast_ray(&self, origin: &Point3<f64>, dir: &Vector3<f64>, t_max: f64) -> Option<RayHit> {
        let clip = self.clip_ray(origin, dir, t_max)?;
        let mut best: Option<(f64, usize, [f64; 3])> = None;
        let len = clip.len;
        self.traverse_ray(&clip, |slot, bound| {
            let [a, b, c] = &self.tris[slot];
            let limit = best.map_or(t_max, |(t, _, _)| t);
            if let Some((t, bary)) = intersect_ray_triangle(origin, dir, limit, a, b, c) {
                let better = match best {
                    None => true,
                    // Equal parameters (a shared edge or vertex): keep the lower face index, so
                    // the answer does not depend on the traversal order.
                    Some((bt, bs, _)) => {
                        t < bt || (t == bt && self.face_ids[slot] < self.face_ids[bs])
                    }
                };
                if better {
                    best = Some((t, slot, bary));
                    *bound = t * len;
                }
            }
        });
        best.map(|(t, slot, bary)| RayHit {
            t,
            face: self.face_ids[slot],
            bary,
            point: origin + dir * t,
        })
    }

    /// The winding number at `p` of a closed surface (every edge used as often in each
    /// direction), as the signed number of crossings of a ray from `p` to infinity: +1 where the ray leaves through a face's front (its normal (b − a) × (c − a)
    /// points along the ray), −1 where it enters. For such a surface this equals the generalized
    /// winding number off the triangles, exactly: 1 inside an outward surface, −1 inside an
    /// inward one, 0 outside, more where components overlap. A ray that passes within a hair of
    /// an edge or vertex (where the watertight test may count a crossing twice), grazes a face,
    /// or starts on a triangle is not trusted; the next of a few fixed directions is tried.
    /// `None` when none gives a clean count (`p` on the surface, in practice).
    /// Meaningless for an open surface (the count then depends on the direction).
    pub fn winding_number_by_rays(&self, p: &Point3<f64>) -> Option<i64> {
        // Directions with no simple relation to the axes or to each other.
        const DIRECTIONS: [[f64; 3]; 6] = [
            [0.5377, 0.6523, 0.5339],
            [-0.7183, 0.3167, 0.6196],
            [0.2113, -0.8409, 0.4982],
            [-0.4431, -0.5186, -0.7313],
            [0.8867, -0.1249, -0.4452],
            [-0.1541, 0.9237, -0.3508],
        ];
        // Barycentric coordinates below this count as on an edge; normal·direction below this
        // (relative to the face's size) as grazing.
        const HAIR: f64 = 1e-9;
        if self.is_empty() || !p.iter().all(|c| c.is_finite()) {
            return None;
        }
        let scale = (self.bbox[1] - self.bbox[0]).norm();
        'directions: for d in DIRECTIONS {
            let dir = Vector3::from(d);
            let Some(clip) = self.clip_ray(p, &dir, f64::INFINITY) else {
                // The ray misses the whole hierarchy: p is outside its box.
                return Some(0);
            };
            let mut count = 0i64;
            let mut clean = true;
            self.traverse_ray(&clip, |slot, _| {
                if !clean {
                    return;
                }
                let [a, b, c] = &self.tris[slot];
                if let Some((t, bary)) = intersect_ray_triangle(p, &dir, f64::INFINITY, a, b, c) {
                    let normal = (b - a).cross(&(c - a));
                    let facing = normal.dot(&dir);
                    if bary.iter().any(|&w| w < HAIR)
                        || facing.abs() < HAIR * normal.norm()
                        || t * dir.norm() < HAIR * scale
                    {
                        clean = false;
                    } else {
                        count += if facing > 0.0 { 1 } else { -1 };
                    }
                }
            });
            if !clean {
                continue 'directions;
            }
            return Some(count);
        }
        None
    }

    /// Number of triangles the ray `origin + t·dir`, 0 ≤ t ≤ `t_max`, crosses (both sides count).
    /// From a point off a closed, consistently oriented mesh, the parity of this count to
    /// infinity tells inside (odd) from outside (even), unless the ray passes exactly through an
    /// edge or vertex, where the watertight test may count both neighbours.
    pub fn count_ray_hits(&self, origin: &Point3<f64>, dir: &Vector3<f64>, t_max: f64) -> usize {
        let Some(clip) = self.clip_ray(origin, dir, t_max) else {
            return 0;
        };
        let mut n = 0;
        self.traverse_ray(&clip, |slot, _| {
            let [a, b, c] = &self.tris[slot];
            if intersect_ray_triangle(origin, dir, t_max, a, b, c).is_some() {
                n += 1;
            }
        });
        n
    }
}
