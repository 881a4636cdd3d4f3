//! The second-order (trapezoidal) correction of a diffusion step of a signed distance function.
//!
//! Diffusing a signed distance function φ for Δt gives u = φ + δ with δ ≈ Δt·κ, κ the mean
//! curvature of the level set of φ through each point. Thresholding u at 0 puts the new
//! interface where φ = −δ(x): the curvature is taken at the new position x, an implicit Euler
//! step of the motion (a sphere shrinks by 2Δt²/r³ too much per step). Taking the mean of the
//! curvature at x and at its closest point π(x) = x − φ(x)∇φ(x) on the old interface, i.e.
//! thresholding
//!
//!   ψ(x) = φ(x) + ½(δ(x) + δ(π(x))) = u(x) + ½(δ(π(x)) − δ(x)),
//!
//! is the implicit trapezoidal rule, second order in Δt. δ(π(x)) is interpolated trilinearly
//! (δ is smooth: its interpolation error is O(h²Δtκ³)), ∇φ by central differences. Only nodes
//! within a few voxels of the interface are corrected: the others only pass their sign to the
//! redistancer, and the correction (O(Δt²κ³)) cannot change it there.

use crate::grid::Grid3;
use rayon::prelude::*;

/// Half-width, in voxels, of the band of nodes corrected (the redistancer's interface patches
/// read φ up to two nodes away from a sign change).
const CORRECTED_BAND_VOXELS: f64 = 4.0;

/// Replaces `u` (φ diffused) by ψ = u + ½(δ(π(x)) − δ(x)) near the zero level set, where
/// `delta` holds δ = u − φ on the same grid (see the module documentation).
pub(super) fn correct(u: &mut Grid3, delta: &Grid3) {
    let dims = u.dims();
    let h = u.voxel();
    let [nx, ny, _] = dims;
    let layer = nx * ny;
    let max_delta = delta
        .data()
        .par_iter()
        .map(|d| d.abs())
        .reduce(|| 0.0f32, f32::max) as f64;
    let window = (CORRECTED_BAND_VOXELS * h + max_delta) as f32;
    let src = u.data().to_vec();
    let d = delta.data();
    // φ = u − δ at a flat index.
    let phi_at = |idx: usize| (src[idx] - d[idx]) as f64;
    u.data_mut()
        .par_chunks_mut(layer)
        .enumerate()
        .for_each(|(k, out)| {
            for j in 0..ny {
                for i in 0..nx {
                    let idx = i + nx * (j + ny * k);
                    if src[idx].abs() >= window {
                        continue;
                    }
                    let strides = [1, nx, layer];
                    let at = [i, j, k];
                    let mut grad = [0.0f64; 3];
                    for a in 0..3 {
                        let (lo, hi, span) = match (at[a] > 0, at[a] + 1 < dims[a]) {
                            (true, true) => (idx - strides[a], idx + strides[a], 2.0),
                            (false, true) => (idx, idx + strides[a], 1.0),
                            (true, false) => (idx - strides[a], idx, 1.0),
                            (false, false) => (idx, idx, 1.0),
                        };
                        grad[a] = (phi_at(hi) - phi_at(lo)) / (span * h);
                    }
                    let norm = (grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]).sqrt();
                    if !(norm > 0.5) {
                        // Near a kink of φ (medial axis): no reliable closest point.
                        continue;
                    }
                    let phi = phi_at(idx);
                    let p = delta.world(i, j, k)
                        - nalgebra::Vector3::from(grad) * (phi / (norm * norm));
                    if let Some(dp) = delta.sample_trilinear(&p) {
                        out[idx - layer * k] =
                            (src[idx] as f64 + 0.5 * (dp - d[idx] as f64)) as f32;
                    }
                }
            }
        });
}
