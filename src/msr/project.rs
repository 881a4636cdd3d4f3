//! Orthogonal projection of points onto the zero level set of φ by Newton steps on the tricubic
//! interpolant (paper Algorithm 1, step 3: X_i is X_{i−1} projected onto {φ(t_i) = 0}):
//! x ← x − φ(x) ∇φ(x) / |∇φ(x)|², until |φ(x)| is below the tolerance. For a signed distance
//! function the first step already lands on the closest point of the level set; later steps
//! correct the interpolation's curvature. A step is limited to `max_step` voxels, so a point
//! whose gradient vanishes (a medial axis) cannot jump across the shape.

use crate::grid::Grid3;
use nalgebra::Point3;
use rayon::prelude::*;

/// Options of [`project_to_zero_level`].
#[derive(Debug, Clone, Copy)]
pub struct LevelProjectOptions {
    /// Stop when |φ| is below this (voxels).
    pub tolerance: f64,
    /// Newton steps at most.
    pub max_iterations: usize,
    /// Longest single step (voxels).
    pub max_step: f64,
}

impl Default for LevelProjectOptions {
    fn default() -> Self {
        LevelProjectOptions {
            tolerance: 1e-3,
            max_iterations: 30,
            max_step: 2.0,
        }
    }
}

/// The projection of one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projected {
    /// Where it ended.
    pub point: Point3<f64>,
    /// |φ| there (world units).
    pub residual: f64,
    /// Whether |φ| fell below the tolerance.
    pub converged: bool,
}

/// Projects every point of `points` onto the zero level set of `phi` (in parallel).
pub fn project_to_zero_level(
    phi: &Grid3,
    points: &[Point3<f64>],
    opts: &LevelProjectOptions,
) -> Vec<Projected> {
    points
        .par_iter()
        .map(|p| project_one(phi, p, opts))
        .collect()
}

fn project_one(phi: &Grid3, p: &Point3<f64>, opts: &LevelProjectOptions) -> Projected {
    let h = phi.voxel();
    let tol = opts.tolerance * h;
    let max_step = opts.max_step * h;
    let mut x = *p;
    let mut best = Projected {
        point: x,
        residual: f64::INFINITY,
        converged: false,
    };
    for _ in 0..=opts.max_iterations {
        let Some((v, g)) = phi.sample_tricubic_with_gradient(&x) else {
            break;
        };
        if v.abs() < best.residual {
            best = Projected {
                point: x,
                residual: v.abs(),
                converged: v.abs() <= tol,
            };
        }
        if v.abs() <= tol {
            break;
        }
        let g2 = g.norm_squared();
        // Also stops on a NaN gradient.
        if g2.is_nan() || g2 <= 1e-12 {
            break;
        }
        let mut step = -v * g / g2;
        let len = step.norm();
        if len > max_step {
            step *= max_step / len;
        }
        x += step;
    }
    best
}
