//! Sampling a [`Grid3`] at world points: trilinear and tricubic interpolation, each with its
//! gradient (world units: value per world length).
//!
//! **Domain.** A grid covers the closed box of its nodes, `origin + voxel·[0, n−1]` per axis. A
//! point outside it gives `None` (so does a NaN coordinate); a point within 1e-9 voxel of the box
//! (round-off from computing node positions) is taken as on it. An axis of a single node is
//! constant along that axis.
//!
//! **Trilinear.** The usual interpolation between the 8 nodes of the cell holding the point:
//! exact on fields linear in each coordinate, C⁰ across cell faces, value error O(h²), gradient
//! error O(h). The gradient is the derivative of the interpolant inside the cell (a point on a
//! cell face takes the cell on its high side, except on the grid's high face).
//!
//! **Tricubic.** The tensor product of Catmull-Rom splines, i.e. Keys' cubic convolution
//! (R. Keys, "Cubic convolution interpolation for digital image processing", IEEE Trans. ASSP 29,
//! 1981) with a = −1/2, on the 4×4×4 nodes around the cell. Chosen over the cubic B-spline because
//! it interpolates the nodes (φ at a node is the stored φ, no prefilter pass or second grid) and
//! still has a continuous gradient: it is C¹, reproduces polynomials of degree ≤ 2 in each
//! coordinate exactly (value and gradient), and converges as O(h³) in value and O(h²) in gradient
//! on smooth fields. **Borders:** the stencil's node beyond the grid is a ghost extrapolated
//! quadratically from the three nearest nodes (f₋₁ = 3f₀ − 3f₁ + f₂; linearly on an axis of two
//! nodes), so the border cells keep quadratic exactness and C¹ continuity; their derivative at the
//! border node is the one-sided second-order difference (−3f₀ + 4f₁ − f₂)/2.

use super::Grid3;
use nalgebra::{Point3, Vector3};

/// Distance beyond the node box, in voxels, still taken as on the box.
const EDGE_TOLERANCE: f64 = 1e-9;

impl Grid3 {
    /// Continuous index of `p`, or None outside the node box (or NaN).
    #[inline]
    fn continuous_index(&self, p: &Point3<f64>) -> Option<[f64; 3]> {
        let u = self.transform().world_to_index(p);
        let dims = self.dims();
        let mut out = [0.0; 3];
        for a in 0..3 {
            let top = (dims[a] - 1) as f64;
            // Written so that NaN fails the test.
            if !(u[a] >= -EDGE_TOLERANCE && u[a] <= top + EDGE_TOLERANCE) {
                return None;
            }
            out[a] = u[a].clamp(0.0, top);
        }
        Some(out)
    }

    /// Whether `p` lies in the box spanned by the nodes (where sampling gives a value).
    pub fn contains_point(&self, p: &Point3<f64>) -> bool {
        self.continuous_index(p).is_some()
    }

    /// Trilinear interpolation at `p`; None outside the node box.
    #[inline]
    pub fn sample_trilinear(&self, p: &Point3<f64>) -> Option<f64> {
        let u = self.continuous_index(p)?;
        Some(trilinear_value(&self.cell_corners(u)))
    }

    /// Gradient (world units) of the trilinear interpolant at `p`; None outside the node box.
    #[inline]
    pub fn gradient_trilinear(&self, p: &Point3<f64>) -> Option<Vector3<f64>> {
        self.sample_trilinear_with_gradient(p).map(|(_, g)| g)
    }

    /// Trilinear value and gradient (world units) at `p`; None outside the node box.
    #[inline]
    pub fn sample_trilinear_with_gradient(&self, p: &Point3<f64>) -> Option<(f64, Vector3<f64>)> {
        let u = self.continuous_index(p)?;
        let c = self.cell_corners(u);
        let f = &c.f;
        let [tx, ty, tz] = c.t;
        let (sx, sy, sz) = (1.0 - tx, 1.0 - ty, 1.0 - tz);
        let value = trilinear_value(&c);
        let dx = sz * (sy * (f[1] - f[0]) + ty * (f[3] - f[2]))
            + tz * (sy * (f[5] - f[4]) + ty * (f[7] - f[6]));
        let dy = sz * (sx * (f[2] - f[0]) + tx * (f[3] - f[1]))
            + tz * (sx * (f[6] - f[4]) + tx * (f[7] - f[5]));
        let dz = sy * (sx * (f[4] - f[0]) + tx * (f[5] - f[1]))
            + ty * (sx * (f[6] - f[2]) + tx * (f[7] - f[3]));
        Some((value, Vector3::new(dx, dy, dz) / self.voxel()))
    }

    /// Tricubic (Catmull-Rom) interpolation at `p`; None outside the node box.
    #[inline]
    pub fn sample_tricubic(&self, p: &Point3<f64>) -> Option<f64> {
        let u = self.continuous_index(p)?;
        Some(self.tricubic::<false>(u).0)
    }

    /// Gradient (world units) of the tricubic interpolant at `p`; None outside the node box.
    #[inline]
    pub fn gradient_tricubic(&self, p: &Point3<f64>) -> Option<Vector3<f64>> {
        self.sample_tricubic_with_gradient(p).map(|(_, g)| g)
    }

    /// Tricubic value and gradient (world units) at `p`; None outside the node box.
    #[inline]
    pub fn sample_tricubic_with_gradient(&self, p: &Point3<f64>) -> Option<(f64, Vector3<f64>)> {
        let u = self.continuous_index(p)?;
        let (value, g) = self.tricubic::<true>(u);
        Some((value, Vector3::from(g) / self.voxel()))
    }

    /// The 8 corner values of the cell holding the (in-range) continuous index `u`, and the
    /// fractional position in it.
    #[inline]
    fn cell_corners(&self, u: [f64; 3]) -> Corners {
        let dims = self.dims();
        let mut lo = [0usize; 3];
        let mut step = [0usize; 3];
        let mut t = [0.0; 3];
        let strides = [1, dims[0], dims[0] * dims[1]];
        for a in 0..3 {
            if dims[a] > 1 {
                let i = (u[a] as usize).min(dims[a] - 2);
                lo[a] = i;
                t[a] = u[a] - i as f64;
                step[a] = strides[a];
            }
        }
        let base = self.index(lo[0], lo[1], lo[2]);
        let data = self.data();
        let mut f = [0.0; 8];
        for (corner, value) in f.iter_mut().enumerate() {
            let offset = (corner & 1) * step[0]
                + ((corner >> 1) & 1) * step[1]
                + ((corner >> 2) & 1) * step[2];
            *value = data[base + offset] as f64;
        }
        Corners { f, t }
    }

    /// Tricubic value and (when `GRAD`) index-space gradient at the in-range continuous index.
    #[inline]
    fn tricubic<const GRAD: bool>(&self, u: [f64; 3]) -> (f64, [f64; 3]) {
        let dims = self.dims();
        let sx = Stencil::new(u[0], dims[0]);
        let sy = Stencil::new(u[1], dims[1]);
        let sz = Stencil::new(u[2], dims[2]);
        let data = self.data();
        let (nx, ny) = (dims[0], dims[1]);
        let mut value = 0.0;
        let mut g = [0.0; 3];
        for c in 0..4 {
            if sz.w[c] == 0.0 && (!GRAD || sz.dw[c] == 0.0) {
                continue;
            }
            for b in 0..4 {
                if sy.w[b] == 0.0 && (!GRAD || sy.dw[b] == 0.0) {
                    continue;
                }
                let row = &data[nx * (sy.idx[b] + ny * sz.idx[c])..][..nx];
                let mut fx = 0.0;
                let mut dfx = 0.0;
                for a in 0..4 {
                    let f = row[sx.idx[a]] as f64;
                    fx += sx.w[a] * f;
                    if GRAD {
                        dfx += sx.dw[a] * f;
                    }
                }
                value += sz.w[c] * sy.w[b] * fx;
                if GRAD {
                    g[0] += sz.w[c] * sy.w[b] * dfx;
                    g[1] += sz.w[c] * sy.dw[b] * fx;
                    g[2] += sz.dw[c] * sy.w[b] * fx;
                }
            }
        }
        (value, g)
    }
}

/// The trilinear interpolant of a cell's corners at its fractional position.
#[inline]
fn trilinear_value(c: &Corners) -> f64 {
    let f = &c.f;
    let [tx, ty, tz] = c.t;
    let (sx, sy, sz) = (1.0 - tx, 1.0 - ty, 1.0 - tz);
    sz * (sy * (sx * f[0] + tx * f[1]) + ty * (sx * f[2] + tx * f[3]))
        + tz * (sy * (sx * f[4] + tx * f[5]) + ty * (sx * f[6] + tx * f[7]))
}

/// Corner values of a cell (x bit 1, y bit 2, z bit 4) and the position in it.
struct Corners {
    f: [f64; 8],
    t: [f64; 3],
}

/// One axis of the tricubic stencil: four node indices with the Catmull-Rom weights and their
/// derivatives, ghosts beyond the border already folded into real nodes. Unused slots have
/// weight 0 and a valid index.
struct Stencil {
    idx: [usize; 4],
    w: [f64; 4],
    dw: [f64; 4],
}

impl Stencil {
    #[inline]
    fn new(u: f64, n: usize) -> Stencil {
        if n == 1 {
            return Stencil {
                idx: [0; 4],
                w: [1.0, 0.0, 0.0, 0.0],
                dw: [0.0; 4],
            };
        }
        let i0 = (u as usize).min(n - 2);
        let t = u - i0 as f64;
        let (t2, t3) = (t * t, t * t * t);
        // Catmull-Rom weights of nodes i0−1, i0, i0+1, i0+2, and their derivatives in t.
        let cw = [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ];
        let cdw = [
            0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
            0.5 * (9.0 * t2 - 10.0 * t),
            0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
            0.5 * (3.0 * t2 - 2.0 * t),
        ];
        let interior = i0 >= 1 && i0 + 2 < n;
        if interior {
            let b = i0 - 1;
            return Stencil {
                idx: [b, b + 1, b + 2, b + 3],
                w: cw,
                dw: cdw,
            };
        }
        // Border: slots cover nodes b..b+3 (clamped to the grid); ghosts fold into real nodes.
        let b = (i0 as isize - 1).clamp(0, n.saturating_sub(4) as isize) as usize;
        let mut w = [0.0; 4];
        let mut dw = [0.0; 4];
        let mut add = |node: usize, coef: f64, s: usize| {
            w[node - b] += coef * cw[s];
            dw[node - b] += coef * cdw[s];
        };
        for s in 0..4 {
            let m = i0 as isize + s as isize - 1;
            if m >= 0 && (m as usize) < n {
                add(m as usize, 1.0, s);
            } else if m < 0 {
                // Ghost node −1.
                if n >= 3 {
                    add(0, 3.0, s);
                    add(1, -3.0, s);
                    add(2, 1.0, s);
                } else {
                    add(0, 2.0, s);
                    add(1, -1.0, s);
                }
            } else if n >= 3 {
                // Ghost node n.
                add(n - 1, 3.0, s);
                add(n - 2, -3.0, s);
                add(n - 3, 1.0, s);
            } else {
                add(n - 1, 2.0, s);
                add(n - 2, -1.0, s);
            }
        }
        Stencil {
            idx: [0, 1, 2, 3].map(|s| (b + s).min(n - 1)),
            w,
            dw,
        }
    }
}
