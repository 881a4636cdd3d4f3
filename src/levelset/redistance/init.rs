//! Sub-voxel initialisation of the redistancer. Finds the interface nodes (a 6-neighbour of the
//! other sign, or φ = 0) and gives each a second-order patch of the interface: the nearest
//! linearly interpolated crossing on its grid edges, and there the unit normal and the shape
//! operator (second fundamental form) of the level set, from central differences of φ at the
//! two ends of the edge interpolated to the crossing, as principal curvatures and directions.
//! Interpolating to the crossing cancels the first-order error a φ that is not a distance (say
//! d·g with g > 0) has off the interface, since ∇(d·g) = g∇d and P·∇²(d·g)·P = g·P·∇²d·P where
//! d = 0 (P: projection on the tangent plane). The distance of a point to a patch is the plane
//! distance corrected along each principal direction by the osculating circle there (see
//! [`patch_distance`]). Neighbours that are ±∞ are ignored (one-sided differences, or a plane
//! patch, instead).

use crate::grid::Grid3;
use crate::{Error, Result};
use rayon::prelude::*;

/// The frozen interface nodes, in flat-index order, all in voxel units.
pub(super) struct Seeds {
    /// Flat node index of each interface node.
    pub node: Vec<usize>,
    /// Distance to its patch, voxels (≤ 1).
    pub dist: Vec<f32>,
    /// The patch of the interface it was measured to.
    pub patch: Vec<Patch>,
}

impl Seeds {
    pub fn len(&self) -> usize {
        self.node.len()
    }
}

/// A second-order patch of the interface around one of its points (one cache line).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub(super) struct Patch {
    /// The point of the interface: `base + off` in voxel-index coordinates, `base` the interface
    /// node's (i, j, k) as exact f32 integers, so distances from other nodes are formed from
    /// exact integer differences plus a small offset.
    pub base: [f32; 3],
    pub off: [f32; 3],
    /// Unit normal there (toward φ > 0); zero when unknown, and then the patch is the point.
    pub normal: [f32; 3],
    /// Principal direction (unit, tangent) of the principal curvature farther from 0.
    pub principal: [f32; 3],
    /// That curvature, then the other one (per voxel, clamped to ±[`MAX_CURVATURE`]): positive
    /// where the interface curves away from the normal, as a sphere seen from outside.
    pub kappa: [f32; 2],
}

impl Patch {
    /// The point, voxel-index coordinates.
    pub fn point(&self) -> [f64; 3] {
        std::array::from_fn(|c| self.base[c] as f64 + self.off[c] as f64)
    }
}

/// Largest curvature a patch is given, per voxel: a radius of curvature under one voxel is
/// not resolved by the grid, and a kink of φ (an edge of a box, the seam between two shapes)
/// shows up in the finite differences as a huge curvature that must not bend the patch.
const MAX_CURVATURE: f64 = 1.0;

/// How far toward its centre of curvature a point may be (as a fraction of the radius) before
/// the curvature is reduced (see [`circle_correction`]).
const FOCAL_LIMIT: f32 = 0.9;

/// Signed distance from (a along the normal, τ along the plane) to the circle of curvature κ
/// tangent to the plane at the origin, minus a: (κ(a² + τ²) + a − a·s)/(s + 1) with
/// s = √((1 + κa)² + κ²τ²). Exact for any κ (0: a plane) and on both sides of the focal point.
#[inline]
fn circle_correction(kappa: f32, tau: f32, a: f32) -> f32 {
    // On the concave side, keep x short of the centre of curvature: past it the circle would
    // measure to its far side, and there a small error of κ (from finite differences) makes a
    // large error of the distance. Deeper than ¾ of the radius, the radius is taken as 4/3 of
    // the depth.
    let kappa = if kappa * a < -FOCAL_LIMIT {
        -FOCAL_LIMIT / a
    } else {
        kappa
    };
    let q = 1.0 + kappa * a;
    let s = (q * q + kappa * kappa * tau * tau).sqrt();
    (kappa * (a * a + tau * tau) + a - a * s) / (s + 1.0)
}

/// Distance (voxels, ≥ 0) from node `x` (voxel-index coordinates, whole numbers) to the
/// interface patch. With v = x − point, a = n·v, t = v − a·n (τ = |t|) and t₁ = v·e₁ along the
/// principal direction of the curvature κ₁ farther from 0 (κ₂ the other): the signed distance
/// a + C(κ₂, τ) + C(κ₁, t₁) − C(κ₂, t₁), C(κ, s) being what the osculating circle of curvature
/// κ in the plane of n and the offset s adds to the plane distance ([`circle_correction`]).
/// That is a sphere of curvature κ₂ plus the excess curvature along e₁: exact for a sphere
/// (any offset), for a cylinder (offsets along the principal directions), to second order
/// otherwise, and well-behaved past focal points (deep inside a tube); the plane distance for a
/// flat patch. Kept no larger than the distance to the patch's point itself (a point of the
/// interface). In f32: x − base is an exact integer difference, so the offset from the point
/// keeps f32 precision relative to itself.
#[inline]
pub(super) fn patch_distance(patch: &Patch, x: [f32; 3]) -> f32 {
    let v0 = (x[0] - patch.base[0]) - patch.off[0];
    let v1 = (x[1] - patch.base[1]) - patch.off[1];
    let v2 = (x[2] - patch.base[2]) - patch.off[2];
    let vv = v0 * v0 + v1 * v1 + v2 * v2;
    let to_point = vv.sqrt();
    let [n0, n1, n2] = patch.normal;
    if n0 == 0.0 && n1 == 0.0 && n2 == 0.0 {
        return to_point;
    }
    let a = v0 * n0 + v1 * n1 + v2 * n2;
    let tau = (vv - a * a).max(0.0).sqrt();
    let [e0, e1, e2] = patch.principal;
    let t1 = v0 * e0 + v1 * e1 + v2 * e2;
    let [k1, k2] = patch.kappa;
    let signed = a + circle_correction(k2, tau, a) + circle_correction(k1, t1, a)
        - circle_correction(k2, t1, a);
    signed.abs().min(to_point)
}

/// One interface node: (flat index, distance, patch).
type Seed = (usize, f32, Patch);

/// Finds the interface nodes of `phi` (no NaN in it) and their patches, in parallel over
/// z-slabs. Errors when there are too many to number with u32 (more than 2³² − 2).
pub(super) fn interface_seeds(phi: &Grid3) -> Result<Seeds> {
    let [nx, ny, nz] = phi.dims();
    let slabs: Vec<Vec<Seed>> = (0..nz)
        .into_par_iter()
        .map(|k| {
            let data = phi.data();
            let mut out = Vec::new();
            for j in 0..ny {
                for i in 0..nx {
                    let idx = phi.index(i, j, k);
                    let p = data[idx];
                    // Quick test: a finite node with φ = 0 or a neighbour of the other sign.
                    let neg = p < 0.0;
                    let other = |q: usize| (data[q] < 0.0) != neg;
                    let candidate = p.is_finite()
                        && (p == 0.0
                            || (i > 0 && other(idx - 1))
                            || (i + 1 < nx && other(idx + 1))
                            || (j > 0 && other(idx - nx))
                            || (j + 1 < ny && other(idx + nx))
                            || (k > 0 && other(idx - nx * ny))
                            || (k + 1 < nz && other(idx + nx * ny)));
                    if candidate {
                        out.extend(node_seed(phi, [i, j, k]));
                    }
                }
            }
            out
        })
        .collect();
    let total: usize = slabs.iter().map(Vec::len).sum();
    if total >= u32::MAX as usize {
        return Err(Error::Geometry(format!(
            "redistance: {total} interface nodes are more than this implementation numbers (2³² − 2)"
        )));
    }
    let mut seeds = Seeds {
        node: Vec::with_capacity(total),
        dist: Vec::with_capacity(total),
        patch: Vec::with_capacity(total),
    };
    for (n, d, p) in slabs.into_iter().flatten() {
        seeds.node.push(n);
        seeds.dist.push(d);
        seeds.patch.push(p);
    }
    Ok(seeds)
}

/// φ at `pos + delta`, if that node exists and is finite.
fn value(phi: &Grid3, pos: [usize; 3], delta: [isize; 3]) -> Option<f64> {
    let dims = phi.dims();
    let mut q = [0usize; 3];
    for c in 0..3 {
        q[c] = pos[c]
            .checked_add_signed(delta[c])
            .filter(|&v| v < dims[c])?;
    }
    let v = phi.get(q[0], q[1], q[2]);
    v.is_finite().then_some(v as f64)
}

fn unit_step(axis: usize, sign: isize) -> [isize; 3] {
    let mut d = [0; 3];
    d[axis] = sign;
    d
}

/// Central-difference ∇φ at `pos` (φ per voxel), one-sided where a neighbour is missing or
/// infinite, 0 along an axis with neither.
fn gradient(phi: &Grid3, pos: [usize; 3], p: f64) -> [f64; 3] {
    std::array::from_fn(|a| {
        let lo = value(phi, pos, unit_step(a, -1));
        let hi = value(phi, pos, unit_step(a, 1));
        match (lo, hi) {
            (Some(lo), Some(hi)) => 0.5 * (hi - lo),
            (Some(lo), None) => p - lo,
            (None, Some(hi)) => hi - p,
            (None, None) => 0.0,
        }
    })
}

/// Central-difference ∇²φ at `pos` (xx, yy, zz, xy, xz, yz), or None when one of the 18
/// neighbours it needs is missing or infinite. Along an axis of one node φ counts as constant
/// (a 2-D grid).
fn hessian(phi: &Grid3, pos: [usize; 3], p: f64) -> Option<[f64; 6]> {
    let flat = phi.dims().map(|d| d == 1);
    let mut h = [0.0; 6];
    for (a, slot) in h.iter_mut().take(3).enumerate() {
        if !flat[a] {
            *slot =
                value(phi, pos, unit_step(a, 1))? - 2.0 * p + value(phi, pos, unit_step(a, -1))?;
        }
    }
    for (slot, (a, b)) in [(3, (0, 1)), (4, (0, 2)), (5, (1, 2))] {
        if flat[a] || flat[b] {
            continue;
        }
        let at = |sa: isize, sb: isize| {
            let mut d = [0; 3];
            d[a] = sa;
            d[b] = sb;
            value(phi, pos, d)
        };
        h[slot] = 0.25 * (at(1, 1)? - at(1, -1)? - at(-1, 1)? + at(-1, -1)?);
    }
    Some(h)
}

/// The seed of node `pos`, or None when it is not an interface node.
///
/// The nearest crossing along the 6 grid edges (fraction θ of the edge from p toward q) is the
/// sample; gradient and Hessian there are (1 − θ)·(value at p) + θ·(value at q). The node's
/// distance is its distance to that patch. p and q get the same patch when both pick their
/// common edge.
fn node_seed(phi: &Grid3, pos: [usize; 3]) -> Option<Seed> {
    let p = phi.get(pos[0], pos[1], pos[2]);
    if !p.is_finite() {
        return None;
    }
    let idx = phi.index(pos[0], pos[1], pos[2]);
    let base = pos.map(|c| c as f32);
    let inside = p < 0.0;
    let p = p as f64;
    // Nearest crossing: (θ, axis, ±1 toward q, φ(q)); θ = 0 when φ = 0 here.
    let mut nearest: Option<(f64, usize, isize, f64)> = None;
    if p == 0.0 {
        nearest = Some((0.0, 0, 1, value(phi, pos, [1, 0, 0]).unwrap_or(0.0)));
    } else {
        for axis in 0..3 {
            for sign in [-1, 1] {
                let q = value(phi, pos, unit_step(axis, sign)).filter(|&q| (q < 0.0) != inside);
                if let Some(q) = q {
                    let theta = p / (p - q);
                    if nearest.is_none_or(|(t, ..)| theta < t) {
                        nearest = Some((theta, axis, sign, q));
                    }
                }
            }
        }
    }
    let (theta, axis, sign, q) = nearest?;
    let theta = if theta > 0.0 {
        // The cubic through φ one node before p and one after q places the crossing to
        // fourth order where φ is smooth; the linear fraction where that stencil is missing.
        let before = value(phi, pos, unit_step(axis, -sign));
        let after = value(phi, pos, unit_step(axis, 2 * sign));
        refine_crossing(before, p, q, after, theta)
    } else {
        theta
    };
    let qpos = pos.map(|c| c as isize);
    let mut qpos = qpos;
    qpos[axis] += sign;
    let qpos = qpos.map(|c| c as usize);
    // Ends of the edge: p, and q when the crossing is not at p itself.
    let other = (theta > 0.0 && qpos[axis] < phi.dims()[axis]).then_some((qpos, q));
    let mix = |a: &[f64], b: Option<&[f64]>| -> Vec<f64> {
        match b {
            Some(b) => a
                .iter()
                .zip(b)
                .map(|(x, y)| (1.0 - theta) * x + theta * y)
                .collect(),
            None => a.to_vec(),
        }
    };
    let gp = gradient(phi, pos, p);
    let gq = other.map(|(qpos, q)| gradient(phi, qpos, q));
    let g = mix(&gp, gq.as_ref().map(|g| &g[..]));
    let hp = hessian(phi, pos, p);
    let hq = other.map(|(qpos, q)| hessian(phi, qpos, q));
    let hess = match (hp, hq) {
        (Some(hp), Some(Some(hq))) => Some(mix(&hp, Some(&hq))),
        (Some(hp), None) => Some(hp.to_vec()),
        _ => None,
    };
    let glen = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    // Sign change along the edge, as φ per voxel along +axis (0 when φ = 0 here).
    let along = (q - p) * sign as f64;
    let trusted = glen > 0.0 && glen.is_finite() && (p == 0.0 || g[axis] * along > 0.0);
    let normal: [f64; 3] = if trusted {
        std::array::from_fn(|c| g[c] / glen)
    } else if p != 0.0 {
        // The interpolated gradient vanishes or contradicts the sign change: the edge's own
        // direction, and a plane patch.
        unit_step(axis, along.signum() as isize).map(|c| c as f64)
    } else {
        [0.0; 3]
    };
    let (principal, kappa) = match hess {
        Some(h) if trusted => principal_curvatures(&h, &normal, glen),
        _ => (tangent_basis(&normal).0, [0.0; 2]),
    };
    let mut off = [0.0f32; 3];
    off[axis] = (theta * sign as f64) as f32;
    let patch = Patch {
        base,
        off,
        normal: normal.map(|c| c as f32),
        principal: principal.map(|c| c as f32),
        kappa: kappa.map(|c| c.clamp(-MAX_CURVATURE, MAX_CURVATURE) as f32),
    };
    let dist = patch_distance(&patch, base).min(1.0);
    Some((idx, dist, patch))
}

/// The root in [0, 1] of the cubic through (−1, f₋), (0, f₀), (1, f₁), (2, f₂) (f₀, f₁ of
/// opposite signs) by Newton's method from the linear root `theta`; `theta` itself when a
/// value is missing or the iteration leaves the edge.
fn refine_crossing(before: Option<f64>, f0: f64, f1: f64, after: Option<f64>, theta: f64) -> f64 {
    let (Some(fm), Some(f2)) = (before, after) else {
        return theta;
    };
    // Newton form of the interpolating cubic in t.
    let d1 = f1 - f0;
    let d2 = 0.5 * (f1 - 2.0 * f0 + fm); // second divided difference on −1, 0, 1
    let d3 = (f2 - 3.0 * f1 + 3.0 * f0 - fm) / 6.0; // third on −1, 0, 1, 2
                                                    // c(t) = f0 + d1·t + d2·t(t − 1) + d3·(t + 1)t(t − 1)
    let c = |t: f64| f0 + d1 * t + d2 * t * (t - 1.0) + d3 * (t * t * t - t);
    let dc = |t: f64| d1 + d2 * (2.0 * t - 1.0) + d3 * (3.0 * t * t - 1.0);
    let mut t = theta;
    for _ in 0..4 {
        let slope = dc(t);
        if slope == 0.0 || !slope.is_finite() {
            return theta;
        }
        t -= c(t) / slope;
    }
    if t.is_finite() && (0.0..=1.0).contains(&t) && (t - theta).abs() < 0.5 {
        t
    } else {
        theta
    }
}

/// Two unit vectors completing the unit `n` (or any unit vector, for n = 0) to an orthonormal
/// frame.
fn tangent_basis(n: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
    let cross = |a: &[f64; 3], b: &[f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    // The axis least aligned with n.
    let axis = (0..3)
        .min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .unwrap_or(0);
    let b1 = cross(n, &unit_step(axis, 1).map(|c| c as f64));
    let b1 = unit(b1).unwrap_or([1.0, 0.0, 0.0]);
    (b1, cross(n, &b1))
}

/// Principal direction of the principal curvature farther from 0, that curvature and the other
/// one, of the level set with unit normal `n`, from the Hessian `h` (xx, yy, zz, xy, xz, yz)
/// and |∇φ| = `glen`: the eigen-pairs of the shape operator bᵢᵀ·H·bⱼ/|∇φ| in a tangent frame
/// (b₁, b₂).
fn principal_curvatures(h: &[f64], n: &[f64; 3], glen: f64) -> ([f64; 3], [f64; 2]) {
    let m = [[h[0], h[3], h[4]], [h[3], h[1], h[5]], [h[4], h[5], h[2]]];
    let (b1, b2) = tangent_basis(n);
    let form = |u: &[f64; 3], w: &[f64; 3]| {
        let mut s = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                s += u[i] * m[i][j] * w[j];
            }
        }
        s / glen
    };
    let (m11, m12, m22) = (form(&b1, &b1), form(&b1, &b2), form(&b2, &b2));
    let mean = 0.5 * (m11 + m22);
    let spread = (0.25 * (m11 - m22) * (m11 - m22) + m12 * m12).sqrt();
    // Direction of the larger eigenvalue; the smaller one's is a quarter turn on.
    let mut angle = 0.5 * (2.0 * m12).atan2(m11 - m22);
    let (mut big, mut small) = (mean + spread, mean - spread);
    if small.abs() > big.abs() {
        std::mem::swap(&mut big, &mut small);
        angle += std::f64::consts::FRAC_PI_2;
    }
    let (c, s) = (angle.cos(), angle.sin());
    let e1 = std::array::from_fn(|i| c * b1[i] + s * b2[i]);
    (e1, [big, small])
}

fn unit(g: [f64; 3]) -> Option<[f64; 3]> {
    let len = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    (len > 0.0 && len.is_finite()).then(|| g.map(|c| c / len))
}
