//! Reconstruction (IMST) by the level set (paper Definition 2.1(4)): from φ_i, whose zero level
//! set is S_i, and the details W_i at the samples X_i ∈ S_i, the level set φ_{i−1} of S_{i−1}.
//!
//! W_i is extended to a band around S_i constant along normals ([`super::extend`]); then φ is
//! advected back along the extended field in one semi-Lagrangian step: a point x of S_{i−1}
//! came from y = x + W̃(y) on S_i, so φ_{i−1}(x) = φ_i(y), with y found by fixed-point iteration
//! from y₀ = x + W̃(x) (the field is smooth on the scale of its displacements, so a few
//! iterations converge). Nodes outside the band keep φ_i; the result is redistanced by fast
//! sweeping. (The reconstruction by vertices needs none of this: [`super::Msr::mesh_at`].)

use super::extend::{extend_along_normals, NodeField};
use crate::grid::Grid3;
use crate::levelset::redistance::{redistance, RedistanceOptions};
use crate::Result;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Options of [`advect_back`].
#[derive(Debug, Clone, Copy)]
pub struct AdvectOptions {
    /// Fixed-point iterations for the departure point y = x + W̃(y).
    pub fixed_point_iterations: usize,
    /// Search radius of the extension around each foot point (voxels).
    pub extension_radius: f64,
    /// Band beyond the largest detail where φ is advected (voxels).
    pub band_margin: f64,
}

impl Default for AdvectOptions {
    fn default() -> Self {
        AdvectOptions {
            fixed_point_iterations: 6,
            extension_radius: 1.5,
            band_margin: 3.0,
        }
    }
}

/// φ_{i−1} from φ_i and the details `details` at the samples `samples` (see the module doc).
pub fn advect_back(
    phi: &Grid3,
    samples: &[Point3<f64>],
    details: &[Vector3<f64>],
    opts: &AdvectOptions,
) -> Result<Grid3> {
    let h = phi.voxel();
    let largest = details.iter().map(|w| w.norm()).fold(0.0, f64::max);
    let band = largest + opts.band_margin * h;
    let field = extend_along_normals(
        phi,
        samples,
        details,
        band + largest,
        opts.extension_radius * h,
    );
    let mut out = phi.clone();
    let values: Vec<f32> = (0..phi.data().len())
        .into_par_iter()
        .map(|n| {
            let v = phi.data()[n];
            if (v as f64).abs() > band {
                return v;
            }
            let [i, j, k] = phi.coords(n);
            let x = phi.world(i, j, k);
            let Some(w0) = field[n] else {
                return v;
            };
            let mut y = x + w0;
            for _ in 0..opts.fixed_point_iterations {
                match sample_field(phi, &field, &y) {
                    Some(w) => y = x + w,
                    None => break,
                }
            }
            phi.sample_tricubic(&y).map_or(v, |p| p as f32)
        })
        .collect();
    out.data_mut().copy_from_slice(&values);
    redistance(&mut out, &RedistanceOptions::default())?;
    Ok(out)
}

/// Trilinear interpolation of `field` at `p`, over the corners where it is defined.
fn sample_field(phi: &Grid3, field: &NodeField, p: &Point3<f64>) -> Option<Vector3<f64>> {
    let q = phi.transform().world_to_index(p);
    let dims = phi.dims();
    let mut base = [0usize; 3];
    let mut t = [0.0; 3];
    for a in 0..3 {
        if !(q[a] >= 0.0 && q[a] <= (dims[a] - 1) as f64) {
            return None;
        }
        base[a] = (q[a].floor() as usize).min(dims[a].saturating_sub(2));
        t[a] = q[a] - base[a] as f64;
    }
    let (mut sum, mut weight) = (Vector3::zeros(), 0.0);
    for c in 0..8 {
        let o = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
        let w: f64 = (0..3)
            .map(|a| if o[a] == 1 { t[a] } else { 1.0 - t[a] })
            .product();
        if let Some(v) = field[phi.index(base[0] + o[0], base[1] + o[1], base[2] + o[2])] {
            sum += v * w;
            weight += w;
        }
    }
    (weight > 1e-9).then(|| sum / weight)
}
