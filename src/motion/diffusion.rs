//! Heat diffusion on a grid: u_t = Δu for a time t (world units, length²) is the convolution with
//! the Gaussian of σ = √(2t) (the diffusion step of threshold dynamics, paper Section 3,
//! Algorithms 2 and 3; Merriman, Bence, Osher 1992).
//!
//! The Gaussian is separable: one 1-D filter along x, y and z in turn, each run in parallel
//! (rayon) over bundles of lines laid side by side in memory (x-contiguous rows for the y and z
//! passes), so the inner loops run over contiguous memory and vectorise.
//!
//! **Boundary.** Neumann, by mirror extension about the half-voxel faces around the boundary
//! nodes (… c b a | a b c …, scipy.ndimage's `mode="reflect"`): the domain does not shrink, the
//! filter is exact on constant fields (its weights sum to 1) and, being symmetric and doubly
//! stochastic, it conserves Σu exactly — the discrete volume a volume-preserving flow thresholds
//! against. A linear field is preserved at nodes farther than the kernel's reach from the
//! boundary; near it the mirror bends it (the reflected field is even about the face).
//!
//! **Kernels.**
//! * [`DiffusionKernel::Truncated`]: the sampled Gaussian e^(−x²/2σ²), cut at r = ⌊ρσ + ½⌋
//!   nodes (ρ = `radius_sigmas`, the rule of scipy's `gaussian_filter` with `truncate = ρ`) and
//!   normalised; cost ∝ r per node and pass, accumulated in f32.
//! * [`DiffusionKernel::Recursive`]: the third-order recursive Gaussian of Young and van Vliet
//!   (1995, "Recursive implementation of the Gaussian filter", Signal Processing 44): a causal
//!   and an anticausal all-pole pass, cost independent of σ. Its shape parameter q is solved so
//!   that the filter's variance is exactly σ² (closed form of the variance of an all-pole
//!   filter) rather than taken from the paper's fitted formula. The mirror boundary is exact: the
//!   mirrored line is periodic of period 2n, and each pass starts from its periodic steady state,
//!   (I − A^2n)⁻¹ times the state reached from rest (A: the pass's companion matrix). Accumulated
//!   in f64.
//! * [`DiffusionKernel::Auto`] (default): truncated up to σ = [`AUTO_RECURSIVE_FROM_SIGMA`]
//!   voxels, recursive beyond, from measured cost and accuracy (see the constant).

use crate::grid::{Grid3, SubBox};
use crate::{Error, Result};
use rayon::prelude::*;

/// Default truncation radius of [`DiffusionKernel::Truncated`], in σ (scipy's default too).
pub const DEFAULT_RADIUS_SIGMAS: f64 = 4.0;

/// [`DiffusionKernel::Auto`] uses the truncated kernel (ρ = 4) below this σ, in voxels, and the
/// recursive filter from it on.
pub const AUTO_RECURSIVE_FROM_SIGMA: f64 = 6.0;

/// Below this σ (voxels) the recursive filter is not used (its approximation of the Gaussian
/// degrades): [`DiffusionKernel::Recursive`] falls back to the truncated kernel (ρ = 4).
pub const RECURSIVE_MIN_SIGMA: f64 = 1.0;

/// Lines filtered together by the recursive x pass.
const X_BUNDLE: usize = 8;
/// Nodes of a slab processed together by the truncated z pass.
const Z_TILE: usize = 1024;

/// How the Gaussian is applied.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum DiffusionKernel {
    /// Truncated kernel for small σ, recursive filter for large σ (see
    /// [`AUTO_RECURSIVE_FROM_SIGMA`]).
    #[default]
    Auto,
    /// Sampled Gaussian cut at ⌊radius_sigmas·σ + ½⌋ nodes on each side (in σ, so
    /// independent of the voxel size), normalised to sum 1. Cost grows with σ.
    Truncated {
        /// Half-width of the kernel in standard deviations (4 matches scipy's default).
        radius_sigmas: f64,
    },
    /// Young–van Vliet third-order recursive filter with exact variance: cost independent of σ.
    /// Falls back to the truncated kernel below σ = [`RECURSIVE_MIN_SIGMA`] voxels.
    Recursive,
}

/// Options of [`diffuse`] and [`diffuse_in_box`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DiffusionOptions {
    /// The kernel (default: [`DiffusionKernel::Auto`]).
    pub kernel: DiffusionKernel,
}

/// σ of the Gaussian that solves the heat equation for `time` (world units: σ = √(2·time)).
pub fn diffusion_sigma(time: f64) -> f64 {
    (2.0 * time).sqrt()
}

/// Heat equation u_t = Δu for `time` (world units, length²), i.e. Gaussian blur of σ = √(2·time)
/// world units. Neumann (mirror) boundary: the domain does not shrink; exact on constant fields
/// (weights sum to 1). Errors when `time` is not positive and finite, or the kernel's radius is
/// not.
pub fn diffuse(grid: &mut Grid3, time: f64, opts: &DiffusionOptions) -> Result<()> {
    let plan = Plan::new(time, grid.voxel(), opts)?;
    let dims = grid.dims();
    match plan {
        Plan::Identity => {}
        Plan::Truncated(w) => {
            xy_truncated(grid.data_mut(), dims, &w);
            if dims[2] > 1 {
                let out = z_truncated(grid.data(), dims, &w);
                *grid = Grid3::from_data(dims, *grid.transform(), out)?;
            }
        }
        Plan::Recursive(iir) => {
            xy_recursive(grid.data_mut(), dims, &iir);
            if dims[2] > 1 {
                z_recursive(grid.data_mut(), dims, &iir);
            }
        }
    }
    Ok(())
}

/// Same as [`diffuse`], restricted to a sub-box of the grid (mirror boundary at the sub-box
/// faces); nodes outside are untouched. Errors as [`diffuse`], and when the box is empty or does
/// not fit in the grid.
pub fn diffuse_in_box(
    grid: &mut Grid3,
    sub_box: &SubBox,
    time: f64,
    opts: &DiffusionOptions,
) -> Result<()> {
    // Check the arguments before copying anything.
    Plan::new(time, grid.voxel(), opts)?;
    let mut sub = grid.extract(sub_box)?;
    diffuse(&mut sub, time, opts)?;
    grid.write_back(sub_box, &sub)
}

/// What [`diffuse`] does for one call.
enum Plan {
    /// σ so small that the truncated kernel is the single weight 1.
    Identity,
    /// Half of a symmetric kernel: w[0] at the centre, w[t] at ±t.
    Truncated(Vec<f32>),
    Recursive(Iir),
}

impl Plan {
    fn new(time: f64, voxel: f64, opts: &DiffusionOptions) -> Result<Plan> {
        if !(time.is_finite() && time > 0.0) {
            return Err(Error::Geometry(format!(
                "diffusion time must be positive and finite (world units, length²), got {time}"
            )));
        }
        let sigma = diffusion_sigma(time) / voxel;
        if !sigma.is_finite() {
            return Err(Error::Geometry(format!(
                "diffusion time {time} on voxels of {voxel} gives σ = {sigma} voxels"
            )));
        }
        let truncated = |radius_sigmas: f64| -> Result<Plan> {
            if !(radius_sigmas.is_finite() && radius_sigmas > 0.0) {
                return Err(Error::Geometry(format!(
                    "kernel radius must be positive and finite (in σ), got {radius_sigmas}"
                )));
            }
            let w = truncated_weights(sigma, radius_sigmas);
            Ok(if w.len() == 1 {
                Plan::Identity
            } else {
                Plan::Truncated(w)
            })
        };
        match opts.kernel {
            DiffusionKernel::Truncated { radius_sigmas } => truncated(radius_sigmas),
            DiffusionKernel::Auto if sigma < AUTO_RECURSIVE_FROM_SIGMA => {
                truncated(DEFAULT_RADIUS_SIGMAS)
            }
            DiffusionKernel::Recursive if sigma < RECURSIVE_MIN_SIGMA => {
                truncated(DEFAULT_RADIUS_SIGMAS)
            }
            DiffusionKernel::Auto | DiffusionKernel::Recursive => {
                Ok(Plan::Recursive(Iir::new(sigma)))
            }
        }
    }
}

/// Reflects index `i` into 0..n about the half-voxel faces (period 2n).
#[inline]
fn reflect(i: isize, n: usize) -> usize {
    let m = i.rem_euclid(2 * n as isize) as usize;
    if m < n {
        m
    } else {
        2 * n - 1 - m
    }
}

// ------------------------------------------------------------------------------------------
// Truncated kernel
// ------------------------------------------------------------------------------------------

/// w[0..=r] of the normalised sampled Gaussian of `sigma` voxels cut at r = ⌊ρσ + ½⌋.
fn truncated_weights(sigma: f64, radius_sigmas: f64) -> Vec<f32> {
    // Bounded so a huge σ cannot ask for an absurd allocation; far beyond any grid anyway.
    let r = (radius_sigmas * sigma + 0.5).floor().min(1e7) as usize;
    let w: Vec<f64> = (0..=r)
        .map(|t| (-0.5 * (t as f64 / sigma).powi(2)).exp())
        .collect();
    let sum = w[0] + 2.0 * w[1..].iter().sum::<f64>();
    w.iter().map(|&v| (v / sum) as f32).collect()
}

/// out = w0·centre.
#[inline]
fn scale_into(out: &mut [f32], w0: f32, centre: &[f32]) {
    for (o, &c) in out.iter_mut().zip(centre) {
        *o = w0 * c;
    }
}

/// out += w·(a + b).
#[inline]
fn add_pair(out: &mut [f32], w: f32, a: &[f32], b: &[f32]) {
    for ((o, &x), &y) in out.iter_mut().zip(a).zip(b) {
        *o += w * (x + y);
    }
}

/// The x and y passes of the truncated kernel, in place, slab (fixed z) by slab in parallel.
fn xy_truncated(data: &mut [f32], dims: [usize; 3], w: &[f32]) {
    let [nx, ny, _] = dims;
    let r = w.len() - 1;
    data.par_chunks_mut(nx * ny).for_each_init(
        || (Vec::new(), Vec::new()),
        |(scratch, padded): &mut (Vec<f32>, Vec<f32>), slab| {
            if ny > 1 {
                scratch.clear();
                scratch.extend_from_slice(slab);
                let row = |j: isize| &scratch[reflect(j, ny) * nx..][..nx];
                for (j, out) in slab.chunks_exact_mut(nx).enumerate() {
                    let j = j as isize;
                    scale_into(out, w[0], row(j));
                    for (t, &wt) in w.iter().enumerate().skip(1) {
                        add_pair(out, wt, row(j - t as isize), row(j + t as isize));
                    }
                }
            }
            if nx > 1 {
                for out in slab.chunks_exact_mut(nx) {
                    padded.clear();
                    padded
                        .extend((0..nx + 2 * r).map(|p| out[reflect(p as isize - r as isize, nx)]));
                    scale_into(out, w[0], &padded[r..r + nx]);
                    for (t, &wt) in w.iter().enumerate().skip(1) {
                        add_pair(
                            out,
                            wt,
                            &padded[r - t..r - t + nx],
                            &padded[r + t..r + t + nx],
                        );
                    }
                }
            }
        },
    );
}

/// The z pass of the truncated kernel, out of place. Each task owns a run of output slabs and
/// walks them tile by tile, so the input tiles it reads stay in cache across its slabs.
fn z_truncated(src: &[f32], dims: [usize; 3], w: &[f32]) -> Vec<f32> {
    let [nx, ny, nz] = dims;
    let slab = nx * ny;
    let mut out = vec![0.0f32; src.len()];
    let per_task = (nz / (4 * rayon::current_num_threads())).clamp(1, 32);
    out.par_chunks_mut(slab * per_task)
        .enumerate()
        .for_each(|(c, chunk)| {
            let k0 = c * per_task;
            for t0 in (0..slab).step_by(Z_TILE) {
                let t1 = (t0 + Z_TILE).min(slab);
                let tile = |k: isize| &src[reflect(k, nz) * slab..][t0..t1];
                for (kk, out_slab) in chunk.chunks_exact_mut(slab).enumerate() {
                    let k = (k0 + kk) as isize;
                    let out = &mut out_slab[t0..t1];
                    scale_into(out, w[0], tile(k));
                    for (t, &wt) in w.iter().enumerate().skip(1) {
                        add_pair(out, wt, tile(k - t as isize), tile(k + t as isize));
                    }
                }
            }
        });
    out
}

// ------------------------------------------------------------------------------------------
// Recursive filter (Young–van Vliet 1995, variance solved exactly)
// ------------------------------------------------------------------------------------------

/// A causal pass y[i] = gain·x[i] + a1·y[i−1] + a2·y[i−2] + a3·y[i−3], run forward then backward.
#[derive(Debug, Clone, Copy)]
struct Iir {
    a: [f64; 3],
    gain: f64,
}

impl Iir {
    /// The Young–van Vliet coefficients of shape parameter `q`.
    fn of_q(q: f64) -> Iir {
        let (q2, q3) = (q * q, q * q * q);
        let b0 = 1.57825 + 2.44413 * q + 1.4281 * q2 + 0.422205 * q3;
        let b1 = 2.44413 * q + 2.85619 * q2 + 1.26661 * q3;
        let b2 = -(1.4281 * q2 + 1.26661 * q3);
        let b3 = 0.422205 * q3;
        let a = [b1 / b0, b2 / b0, b3 / b0];
        Iir {
            a,
            gain: 1.0 - a.iter().sum::<f64>(),
        }
    }

    /// Variance of the forward–backward filter: twice that of the causal impulse response
    /// h = gain/(1 − Σ a_k z^−k), whose cumulants follow from ln H(e^−s) at s = 0.
    fn variance(&self) -> f64 {
        let [a1, a2, a3] = self.a;
        let d1 = 1.0 - a1 - a2 - a3;
        let s1 = a1 + 2.0 * a2 + 3.0 * a3;
        let s2 = a1 + 4.0 * a2 + 9.0 * a3;
        2.0 * (s2 * d1 + s1 * s1) / (d1 * d1)
    }

    /// The filter of variance `sigma`² (voxels), q found by bisection (the variance grows with q).
    fn new(sigma: f64) -> Iir {
        let target = sigma * sigma;
        let (mut lo, mut hi) = (1e-3, 1.0);
        while Iir::of_q(hi).variance() < target {
            hi *= 2.0;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if Iir::of_q(mid).variance() < target {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-15 * hi {
                break;
            }
        }
        Iir::of_q(0.5 * (lo + hi))
    }

    /// (I − A^period)⁻¹ with A the companion matrix of the pass: maps the state reached from rest
    /// after one period to the periodic steady state.
    fn periodic_start(&self, period: usize) -> [[f64; 3]; 3] {
        let [a1, a2, a3] = self.a;
        let a = [[a1, a2, a3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let p = mat_pow(a, period);
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = f64::from(u8::from(i == j)) - p[i][j];
            }
        }
        mat_inv(m)
    }
}

fn mat_mul(x: [[f64; 3]; 3], y: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut z = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            z[i][j] = (0..3).map(|k| x[i][k] * y[k][j]).sum();
        }
    }
    z
}

fn mat_pow(mut x: [[f64; 3]; 3], mut e: usize) -> [[f64; 3]; 3] {
    let mut r = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    while e > 0 {
        if e & 1 == 1 {
            r = mat_mul(r, x);
        }
        x = mat_mul(x, x);
        e >>= 1;
    }
    r
}

fn mat_inv(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            inv[i][j] = c(j, i) / det;
        }
    }
    inv
}

/// The recursive filter along one axis of length `n` ≥ 2, for bundles of `lanes` lines stored
/// position-major (`buf[q·lanes + l]`, 2n positions: the line then its mirror image).
struct Bundle<'a> {
    iir: &'a Iir,
    start: [[f64; 3]; 3],
    n: usize,
    lanes: usize,
}

impl<'a> Bundle<'a> {
    fn new(iir: &'a Iir, n: usize, lanes: usize) -> Self {
        Bundle {
            iir,
            start: iir.periodic_start(2 * n),
            n,
            lanes,
        }
    }

    /// Filters the lines whose values fill positions 0..n of `buf` (len 2n·lanes); the result
    /// replaces them. `state` is scratch.
    fn filter(&self, buf: &mut [f64], state: &mut Vec<f64>) {
        let (n, l) = (self.n, self.lanes);
        let p = 2 * n;
        debug_assert_eq!(buf.len(), p * l);
        // Mirror image: position n + m holds position n − 1 − m.
        let (line, mirror) = buf.split_at_mut(n * l);
        for (m, row) in mirror.chunks_exact_mut(l).enumerate() {
            row.copy_from_slice(&line[(n - 1 - m) * l..][..l]);
        }
        state.clear();
        state.resize(3 * l, 0.0);
        let [a1, a2, a3] = self.iir.a;
        let g = self.iir.gain;

        // Causal pass from rest.
        for q in 0..p {
            let (before, cur) = buf.split_at_mut(q * l);
            let cur = &mut cur[..l];
            let prev = |k: usize| (q >= k).then(|| &before[(q - k) * l..][..l]);
            match (prev(1), prev(2), prev(3)) {
                (Some(y1), Some(y2), Some(y3)) => {
                    for (((y, &u1), &u2), &u3) in cur.iter_mut().zip(y1).zip(y2).zip(y3) {
                        *y = g * *y + a1 * u1 + a2 * u2 + a3 * u3;
                    }
                }
                (y1, y2, _) => {
                    for (i, y) in cur.iter_mut().enumerate() {
                        let u1 = y1.map_or(0.0, |r| r[i]);
                        let u2 = y2.map_or(0.0, |r| r[i]);
                        *y = g * *y + a1 * u1 + a2 * u2;
                    }
                }
            }
        }
        // Periodic start state (y[−1], y[−2], y[−3]) and the homogeneous correction.
        self.steady_state(buf, [p - 1, p - 2, p - 3], state);
        self.correct(buf, 0..p, state);

        // Anticausal pass from rest: z[q] = g·y[q] + a1·z[q+1] + a2·z[q+2] + a3·z[q+3].
        for q in (0..p).rev() {
            let (cur, after) = buf.split_at_mut((q + 1) * l);
            let cur = &mut cur[q * l..];
            let next = |k: usize| (q + k < p).then(|| &after[(k - 1) * l..][..l]);
            match (next(1), next(2), next(3)) {
                (Some(z1), Some(z2), Some(z3)) => {
                    for (((z, &u1), &u2), &u3) in cur.iter_mut().zip(z1).zip(z2).zip(z3) {
                        *z = g * *z + a1 * u1 + a2 * u2 + a3 * u3;
                    }
                }
                (z1, z2, _) => {
                    for (i, z) in cur.iter_mut().enumerate() {
                        let u1 = z1.map_or(0.0, |r| r[i]);
                        let u2 = z2.map_or(0.0, |r| r[i]);
                        *z = g * *z + a1 * u1 + a2 * u2;
                    }
                }
            }
        }
        self.steady_state(buf, [0, 1, 2], state);
        self.correct(buf, (0..p).rev(), state);
    }

    /// state ← start · (rows `at` of buf): the periodic steady state, per lane.
    fn steady_state(&self, buf: &[f64], at: [usize; 3], state: &mut [f64]) {
        let l = self.lanes;
        let r = at.map(|q| &buf[q * l..][..l]);
        let m = &self.start;
        for (s, mi) in state.chunks_exact_mut(l).zip(m) {
            for (i, v) in s.iter_mut().enumerate() {
                *v = mi[0] * r[0][i] + mi[1] * r[1][i] + mi[2] * r[2][i];
            }
        }
    }

    /// Adds to the rows of buf, in `order`, the free response of the pass started from `state`
    /// (three rows: the last, second last and third last outputs before the first row).
    fn correct(&self, buf: &mut [f64], order: impl Iterator<Item = usize>, state: &mut [f64]) {
        let l = self.lanes;
        let [a1, a2, a3] = self.iir.a;
        // Rotating roles: newest, middle, oldest.
        let mut roles = [0usize, 1, 2];
        for q in order {
            let row = &mut buf[q * l..][..l];
            let [h1, h2, h3] = roles;
            for (i, y) in row.iter_mut().enumerate() {
                let v = a1 * state[h1 * l + i] + a2 * state[h2 * l + i] + a3 * state[h3 * l + i];
                state[h3 * l + i] = v;
                *y += v;
            }
            roles = [h3, h1, h2];
        }
    }
}

/// The x and y passes of the recursive filter, in place, slab by slab in parallel.
fn xy_recursive(data: &mut [f32], dims: [usize; 3], iir: &Iir) {
    let [nx, ny, _] = dims;
    let bx = (nx > 1).then(|| Bundle::new(iir, nx, X_BUNDLE));
    let by = (ny > 1).then(|| Bundle::new(iir, ny, nx));
    data.par_chunks_mut(nx * ny).for_each_init(
        || (Vec::new(), Vec::new()),
        |(buf, state): &mut (Vec<f64>, Vec<f64>), slab| {
            if let Some(by) = &by {
                buf.clear();
                buf.extend(slab.iter().map(|&v| f64::from(v)));
                buf.resize(2 * ny * nx, 0.0);
                by.filter(buf, state);
                for (o, &v) in slab.iter_mut().zip(buf.iter()) {
                    *o = v as f32;
                }
            }
            if let Some(bx) = &bx {
                for rows in slab.chunks_mut(nx * X_BUNDLE) {
                    let lanes = rows.len() / nx;
                    buf.clear();
                    buf.resize(2 * nx * X_BUNDLE, 0.0);
                    for (lane, row) in rows.chunks_exact(nx).enumerate() {
                        for (i, &v) in row.iter().enumerate() {
                            buf[i * X_BUNDLE + lane] = f64::from(v);
                        }
                    }
                    // Unused lanes of the last bundle filter zeros.
                    bx.filter(buf, state);
                    for (lane, row) in rows.chunks_exact_mut(nx).enumerate().take(lanes) {
                        for (i, v) in row.iter_mut().enumerate() {
                            *v = buf[i * X_BUNDLE + lane] as f32;
                        }
                    }
                }
            }
        },
    );
}

/// The z pass of the recursive filter, in place: each task filters the nodes of one row j
/// through all slabs (x-contiguous reads), then the results are written back slab by slab.
fn z_recursive(data: &mut [f32], dims: [usize; 3], iir: &Iir) {
    let [nx, ny, nz] = dims;
    let slab = nx * ny;
    let bz = Bundle::new(iir, nz, nx);
    let src: &[f32] = data;
    let columns: Vec<Vec<f32>> = (0..ny)
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(buf, state): &mut (Vec<f64>, Vec<f64>), j| {
                buf.clear();
                for k in 0..nz {
                    buf.extend(src[k * slab + j * nx..][..nx].iter().map(|&v| f64::from(v)));
                }
                buf.resize(2 * nz * nx, 0.0);
                bz.filter(buf, state);
                buf[..nz * nx].iter().map(|&v| v as f32).collect()
            },
        )
        .collect();
    data.par_chunks_mut(slab).enumerate().for_each(|(k, out)| {
        for (row, column) in out.chunks_exact_mut(nx).zip(&columns) {
            row.copy_from_slice(&column[k * nx..][..nx]);
        }
    });
}
