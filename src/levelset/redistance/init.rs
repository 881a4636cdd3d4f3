//! Sub-voxel initialisation of the redistancer. Finds the interface nodes (a 6-neighbour of the
//! other sign, or φ = 0) and gives each a second-order patch of the interface: the nearest
//! linearly interpolated crossing on its grid edges, and there the unit normal and the shape
//! operator (second fundamental form) of the level set, from central differences of φ at the
//! two ends of the edge interpolated to the crossing. Interpolating to the crossing cancels the
//! first-order error a φ that is not a distance (say d·g with g > 0) has off the interface, since
//! ∇(d·g) = g∇d and P·∇²(d·g)·P = g·P·∇²d·P where d = 0 (P: projection on the tangent plane).
//! The distance of a point to the patch is the plane distance plus the quadratic correction of
//! the osculating paraboloid (exact to second order for a sphere), kept between the plane
//! distance's sign and the distance to the crossing point itself. Neighbours that are ±∞ are
//! ignored (one-sided differences, or a plane patch, instead).

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
    /// Shape operator P·∇²φ·P/|∇φ| (xx, yy, zz, xy, xz, yz; per voxel): positive where the
    /// interface curves away from the normal, as a sphere seen from outside.
    pub shape: [f32; 6],
}

impl Patch {
    /// The point, voxel-index coordinates.
    pub fn point(&self) -> [f64; 3] {
        std::array::from_fn(|c| self.base[c] as f64 + self.off[c] as f64)
    }
}

/// Distance (voxels, ≥ 0) from node `x` (voxel-index coordinates, whole numbers) to the
/// interface patch: the plane distance a plus ½·tᵀSt/(1 + a·κ_t) (t: the offset along the
/// plane, κ_t = tᵀSt/|t|²: the osculating paraboloid, exact to second order for a sphere), kept
/// on the side of a and no farther than the patch's point itself. In f32: x − base is an exact
/// integer difference, so the offset from the point keeps f32 precision relative to itself.
#[inline]
pub(super) fn patch_distance(patch: &Patch, x: [f32; 3]) -> f32 {
    let v0 = (x[0] - patch.base[0]) - patch.off[0];
    let v1 = (x[1] - patch.base[1]) - patch.off[1];
    let v2 = (x[2] - patch.base[2]) - patch.off[2];
    let vv = v0 * v0 + v1 * v1 + v2 * v2;
    let [n0, n1, n2] = patch.normal;
    let a = v0 * n0 + v1 * n1 + v2 * n2;
    if n0 == 0.0 && n1 == 0.0 && n2 == 0.0 {
        return vv.sqrt();
    }
    let (t0, t1, t2) = (v0 - a * n0, v1 - a * n1, v2 - a * n2);
    let [sxx, syy, szz, sxy, sxz, syz] = patch.shape;
    let tst = sxx * t0 * t0
        + syy * t1 * t1
        + szz * t2 * t2
        + 2.0 * (sxy * t0 * t1 + sxz * t0 * t2 + syz * t1 * t2);
    let tt = t0 * t0 + t1 * t1 + t2 * t2;
    let mut est = a;
    if tt > 0.0 {
        // Near a focal point (1 + a·κ_t → 0) the paraboloid says little: damp it.
        let den = (1.0 + a * tst / tt).max(0.5);
        est += 0.5 * tst / den;
    }
    if est * a < 0.0 {
        est = 0.0;
    }
    est.abs().min(vv.sqrt())
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
/// neighbours it needs is missing or infinite.
fn hessian(phi: &Grid3, pos: [usize; 3], p: f64) -> Option<[f64; 6]> {
    let mut h = [0.0; 6];
    for (a, slot) in h.iter_mut().take(3).enumerate() {
        *slot = value(phi, pos, unit_step(a, 1))? - 2.0 * p + value(phi, pos, unit_step(a, -1))?;
    }
    for (slot, (a, b)) in [(3, (0, 1)), (4, (0, 2)), (5, (1, 2))] {
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
    let normal: [f64; 3] = if glen > 0.0 && glen.is_finite() && (p == 0.0 || g[axis] * along > 0.0)
    {
        std::array::from_fn(|c| g[c] / glen)
    } else if p != 0.0 {
        // The interpolated gradient vanishes or contradicts the sign change: the edge's own
        // direction, and a plane patch.
        unit_step(axis, along.signum() as isize).map(|c| c as f64)
    } else {
        [0.0; 3]
    };
    let shape = match hess {
        Some(h) if normal != [0.0; 3] && glen > 0.0 && glen.is_finite() => {
            tangential(&h, &normal).map(|c| (c / glen) as f32)
        }
        _ => [0.0; 6],
    };
    let mut off = [0.0f32; 3];
    off[axis] = (theta * sign as f64) as f32;
    let patch = Patch {
        base,
        off,
        normal: normal.map(|c| c as f32),
        shape,
    };
    let dist = patch_distance(&patch, base).min(1.0);
    Some((idx, dist, patch))
}

/// P·H·P with P = I − n·nᵀ (symmetric, as xx, yy, zz, xy, xz, yz).
fn tangential(h: &[f64], n: &[f64; 3]) -> [f64; 6] {
    let m = [[h[0], h[3], h[4]], [h[3], h[1], h[5]], [h[4], h[5], h[2]]];
    let p: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| f64::from(i == j) - n[i] * n[j]));
    let mut pm = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            pm[i][j] = (0..3).map(|k| p[i][k] * m[k][j]).sum();
        }
    }
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = (0..3).map(|k| pm[i][k] * p[k][j]).sum();
        }
    }
    [
        out[0][0], out[1][1], out[2][2], out[0][1], out[0][2], out[1][2],
    ]
}
