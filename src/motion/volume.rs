//! Sub-voxel measures of the region {φ < 0} of a signed distance grid, and the threshold shift
//! that gives it a prescribed volume (step 3 of the paper's Algorithm 3, after Ruuth and Wetton).
//!
//! * **Volume**: every node counts for the fraction H_ε(φ) of its voxel (h³), H_ε the smoothed
//!   Heaviside of half-width ε = h whose derivative is the cosine delta below:
//!   H_ε(φ) = ½(1 − φ/ε − sin(πφ/ε)/π) for |φ| < ε, 1 inside, 0 outside. Being smooth, its sum
//!   over the nodes hardly depends on where the surface sits between them: on spheres of 10
//!   voxels at random offsets it varies by 2·10⁻⁵ (relative), against 5·10⁻⁴ for the linear
//!   ramp clamp(½ − φ/h, 0, 1). Its bias is smooth too: for a signed distance function the
//!   estimate is V + m·∫κ dA with m = (1/6 − 1/π²)ε² ≈ 0.065h², i.e. +0.39h²/R² relative on a
//!   sphere of radius R (7·10⁻⁴ at R = 24h), and it changes only as the integral of the mean
//!   curvature does. So the estimate is consistent from step to step, which is what the
//!   volume-preserving flows need, and it is a smooth, increasing function of a shift λ of φ.
//! * **Area**: Σ δ_ε(φ)·h³ with the cosine delta δ_ε(φ) = (1 + cos(πφ/ε))/(2ε) for |φ| < ε,
//!   ε = 1.5h (the smoothed delta of Osher and Fedkiw's level-set book); for a signed distance
//!   function it is a first-order estimate (about 1% on a sphere of 12 voxels of radius).
//! * **Volume shift**: the λ for which {φ − λ < 0} has the target volume, by a safeguarded
//!   Newton iteration (the slope of the volume in λ is the area estimate), over the nodes near
//!   the interface gathered once.
//!
//! All three work on a [`SubBox`] of the grid (the whole grid or the region a flow may change)
//! and run in parallel over z-layers (rayon).

use crate::grid::{Grid3, SubBox};
use crate::{Error, Result};
use rayon::prelude::*;

/// Half-width of the smoothed delta of the area estimate, in voxels.
const DELTA_WIDTH_VOXELS: f64 = 1.5;

/// Half-width of the smoothed Heaviside of the volume estimate, in voxels.
const HEAVISIDE_WIDTH_VOXELS: f64 = 1.0;

/// Fraction of a node's voxel inside, H_ε(φ) with φ in voxels, and its derivative −dH/dφ.
#[inline]
fn inside_fraction(phi_vox: f64) -> (f64, f64) {
    let e = HEAVISIDE_WIDTH_VOXELS;
    if phi_vox <= -e {
        (1.0, 0.0)
    } else if phi_vox >= e {
        (0.0, 0.0)
    } else {
        let a = std::f64::consts::PI * phi_vox / e;
        (
            0.5 * (1.0 - phi_vox / e - a.sin() / std::f64::consts::PI),
            (1.0 + a.cos()) / (2.0 * e),
        )
    }
}

fn check_region(phi: &Grid3, region: &SubBox) -> Result<()> {
    if region.fits(phi.dims()) {
        Ok(())
    } else {
        Err(Error::Geometry(format!(
            "region {:?}..{:?} is empty or outside the grid of {:?} nodes",
            region.min,
            region.max,
            phi.dims()
        )))
    }
}

/// Sub-voxel volume of {φ < 0} (world units³) over the whole grid; see the module documentation.
/// φ must be a signed distance function near its zero level set.
pub fn measure_volume(phi: &Grid3) -> f64 {
    measure_volume_in(phi, &phi.whole_box()).unwrap_or(0.0)
}

/// [`measure_volume`] over the nodes of `region` only. Errors when the region does not fit.
pub fn measure_volume_in(phi: &Grid3, region: &SubBox) -> Result<f64> {
    measure_shape_in(phi, region).map(|(volume, _)| volume)
}

/// Area estimate of the zero level set (world units²) over the whole grid; see the module
/// documentation. φ must be a signed distance function near its zero level set.
pub fn measure_area(phi: &Grid3) -> f64 {
    measure_area_in(phi, &phi.whole_box()).unwrap_or(0.0)
}

/// [`measure_area`] over the nodes of `region` only. Errors when the region does not fit.
pub fn measure_area_in(phi: &Grid3, region: &SubBox) -> Result<f64> {
    measure_shape_in(phi, region).map(|(_, area)| area)
}

/// [`measure_volume_in`] and [`measure_area_in`] in one pass: (volume, area).
pub fn measure_shape_in(phi: &Grid3, region: &SubBox) -> Result<(f64, f64)> {
    check_region(phi, region)?;
    let h = phi.voxel();
    let inv_h = 1.0 / h;
    let eps = DELTA_WIDTH_VOXELS;
    let dims = phi.dims();
    let data = phi.data();
    let (volume, area) = (region.min[2]..region.max[2])
        .into_par_iter()
        .map(|k| {
            let layer = SubBox::new(
                [region.min[0], region.min[1], k],
                [region.max[0], region.max[1], k + 1],
            );
            let mut acc = (0.0f64, 0.0f64);
            for (_, _, row) in layer.rows(dims) {
                for &v in &data[row] {
                    let x = v as f64 * inv_h;
                    acc.0 += inside_fraction(x).0;
                    if x.abs() < eps {
                        acc.1 += (1.0 + (std::f64::consts::PI * x / eps).cos()) / (2.0 * eps);
                    }
                }
            }
            acc
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold((0.0, 0.0), add_pairs);
    Ok((volume * h * h * h, area * h * h))
}

/// Sum of two pairs. The parallel parts of a sum (a layer, a fixed chunk) are collected in order
/// and added in that order, never by rayon's `reduce`, whose tree follows the thread split: the
/// result is then the same bits for every thread count.
fn add_pairs(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 + b.0, a.1 + b.1)
}

/// The nodes near the interface, for evaluating the volume of {φ < λ} at many λ.
struct NearInterface {
    /// φ/h of the nodes with |φ/h| < window.
    values: Vec<f32>,
    /// Nodes with φ/h ≤ −window (wholly inside for |λ/h| ≤ window − ε).
    inside: usize,
}

impl NearInterface {
    fn gather(phi: &Grid3, region: &SubBox, window: f64) -> NearInterface {
        let dims = phi.dims();
        let data = phi.data();
        let inv_h = 1.0 / phi.voxel();
        let parts: Vec<(Vec<f32>, usize)> = (region.min[2]..region.max[2])
            .into_par_iter()
            .map(|k| {
                let layer = SubBox::new(
                    [region.min[0], region.min[1], k],
                    [region.max[0], region.max[1], k + 1],
                );
                let mut values = Vec::new();
                let mut inside = 0usize;
                for (_, _, row) in layer.rows(dims) {
                    for &v in &data[row] {
                        let x = v as f64 * inv_h;
                        if x <= -window {
                            inside += 1;
                        } else if x < window {
                            values.push(x as f32);
                        }
                    }
                }
                (values, inside)
            })
            .collect();
        let inside = parts.iter().map(|p| p.1).sum();
        let values = parts.into_iter().flat_map(|p| p.0).collect();
        NearInterface { values, inside }
    }

    /// Volume of {φ − λ < 0} in voxels³ and its derivative in λ (voxels²), λ in voxels with
    /// |λ| ≤ window − ε.
    fn volume(&self, lambda: f64) -> (f64, f64) {
        let (sum, slope) = self
            .values
            .par_chunks(1 << 14)
            .map(|chunk| {
                chunk.iter().fold((0.0, 0.0), |(s, d), &x| {
                    let (f, df) = inside_fraction(x as f64 - lambda);
                    (s + f, d + df)
                })
            })
            .collect::<Vec<_>>()
            .into_iter()
            .fold((0.0, 0.0), add_pairs);
        (self.inside as f64 + sum, slope)
    }
}

/// The shift λ (world units) for which {φ − λ < 0} has the sub-voxel volume `target` (world
/// units³, as [`measure_volume_in`] measures it) over the nodes of `region`, found to a relative
/// volume error of `tolerance` (or to 10⁻⁹ voxel in λ). λ > 0 grows the region. Errors when the
/// region does not fit, when `target` is not positive and finite, or when no shift reaches it
/// (the target is more than the region's whole volume).
pub fn find_volume_shift(phi: &Grid3, region: &SubBox, target: f64, tolerance: f64) -> Result<f64> {
    check_region(phi, region)?;
    let h = phi.voxel();
    let capacity = region.node_count() as f64 * h * h * h;
    if !(target.is_finite() && target > 0.0 && target < capacity) {
        return Err(Error::Geometry(format!(
            "no threshold gives the volume {target}: it must be positive and below the \
             region's {capacity}"
        )));
    }
    let goal = target / (h * h * h);
    let tol = (tolerance.max(0.0) * goal).max(1e-12 * goal);
    let dims = region.dims();
    let span = dims[0].max(dims[1]).max(dims[2]) as f64 + 2.0;
    let mut window = 4.0f64;
    loop {
        let near = NearInterface::gather(phi, region, window);
        let reach = window - HEAVISIDE_WIDTH_VOXELS;
        let (v_lo, _) = near.volume(-reach);
        let (v_hi, _) = near.volume(reach);
        if goal < v_lo || goal > v_hi {
            if window > span {
                return Err(Error::Geometry(format!(
                    "no threshold gives the volume {target} (the region holds {} to {})",
                    v_lo * h * h * h,
                    v_hi * h * h * h
                )));
            }
            window *= 4.0;
            continue;
        }
        let (mut lo, mut hi) = (-reach, reach);
        let mut lambda = 0.0f64.clamp(lo, hi);
        for _ in 0..200 {
            let (v, slope) = near.volume(lambda);
            let err = v - goal;
            if err.abs() <= tol {
                return Ok(lambda * h);
            }
            if err < 0.0 {
                lo = lambda;
            } else {
                hi = lambda;
            }
            if hi - lo < 1e-9 {
                return Ok(0.5 * (lo + hi) * h);
            }
            let newton = lambda - err / slope;
            lambda = if slope > 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
        }
        return Ok(lambda * h);
    }
}
