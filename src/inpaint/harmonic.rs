//! Harmonic interpolation across the region D: Laplace's equation ∇²u = 0 on the unknown nodes,
//! the known nodes around them as Dirichlet data. This carries the details of the multiscale
//! representation (the field between a coarse level and the data) from the intact neighbourhood
//! across D, the MSR analogue of the framelet-coefficient step of the inpainting scheme of Cai,
//! Chan and Shen that Algorithm 4 of the paper follows (Section 4).
//!
//! Solver: the unknowns start at the mean of their nearest known values (breadth-first layers),
//! then red-black successive over-relaxation with the optimal factor for the region's size.
//! Nodes on the grid's border see only the neighbours they have (a zero-flux border).

use crate::grid::{face_neighbours, Grid3};
use crate::{Error, Result};

/// Options of [`fill_harmonic`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicOptions {
    /// Most sweeps (one sweep = the red and the black half-sweep). Default 2000.
    pub max_sweeps: usize,
    /// Stop when no unknown changes by more than this in a sweep, **in voxels** of the field's
    /// values (which are world lengths here: distances). Default 1e-4.
    pub tolerance: f64,
}

impl Default for HarmonicOptions {
    fn default() -> Self {
        HarmonicOptions {
            max_sweeps: 2000,
            tolerance: 1e-4,
        }
    }
}

/// What [`fill_harmonic`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicReport {
    /// Unknown nodes solved for.
    pub unknowns: usize,
    /// Sweeps made.
    pub sweeps: usize,
    /// Largest change in the last sweep, world units.
    pub last_change: f64,
    /// Whether the change fell below the tolerance.
    pub converged: bool,
}

/// Replaces the values of `field` at the nodes where `unknown` is true by the harmonic function
/// that takes the known values around them. Errors if `unknown` does not match the grid, or if
/// some unknown node has no known node in its connected part (nothing to interpolate from).
pub fn fill_harmonic(
    field: &mut Grid3,
    unknown: &[bool],
    opts: &HarmonicOptions,
) -> Result<HarmonicReport> {
    let [nx, ny, _] = field.dims();
    if unknown.len() != field.data().len() {
        return Err(Error::Geometry(format!(
            "harmonic fill: mask of {} nodes for a grid of {}",
            unknown.len(),
            field.data().len()
        )));
    }
    let cells: Vec<usize> = (0..unknown.len()).filter(|&n| unknown[n]).collect();
    if cells.is_empty() {
        return Ok(HarmonicReport {
            unknowns: 0,
            sweeps: 0,
            last_change: 0.0,
            converged: true,
        });
    }
    let dims = field.dims();
    let sz = nx * ny;
    // Initial guess: breadth-first layers from the known nodes, each node the mean of its
    // already-set neighbours.
    let mut set: Vec<bool> = unknown.iter().map(|&u| !u).collect();
    let data = field.data_mut();
    let mut frontier: Vec<usize> = cells.clone();
    loop {
        let mut next_values = Vec::new();
        let mut waiting = Vec::new();
        for &n in &frontier {
            let (mut sum, mut count) = (0.0f64, 0);
            for m in face_neighbours(dims, n) {
                if set[m] {
                    sum += data[m] as f64;
                    count += 1;
                }
            }
            if count > 0 {
                next_values.push((n, (sum / count as f64) as f32));
            } else {
                waiting.push(n);
            }
        }
        if next_values.is_empty() {
            if waiting.is_empty() {
                break;
            }
            return Err(Error::Geometry(format!(
                "harmonic fill: {} nodes of the region are cut off from every known node",
                waiting.len()
            )));
        }
        for (n, v) in next_values {
            data[n] = v;
            set[n] = true;
        }
        frontier = waiting;
    }
    // Red-black SOR; the optimal factor for a region about `extent` nodes across.
    let extent = {
        let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
        for &n in &cells {
            let c = [n % nx, (n / nx) % ny, n / sz];
            for a in 0..3 {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        (0..3).map(|a| hi[a] + 1 - lo[a]).max().unwrap_or(1) as f64 + 1.0
    };
    let omega = 2.0 / (1.0 + (std::f64::consts::PI / extent).sin());
    let (red, black): (Vec<usize>, Vec<usize>) = cells
        .iter()
        .partition(|&&n| ((n % nx) + (n / nx) % ny + n / sz) % 2 == 0);
    let tolerance = opts.tolerance * field.voxel();
    let data = field.data_mut();
    let mut sweeps = 0;
    let mut last_change = f64::INFINITY;
    while sweeps < opts.max_sweeps {
        sweeps += 1;
        let mut change = 0.0f64;
        for half in [&red, &black] {
            for &n in half.iter() {
                let (mut sum, mut count) = (0.0f64, 0);
                for m in face_neighbours(dims, n) {
                    sum += data[m] as f64;
                    count += 1;
                }
                let old = data[n] as f64;
                let new = old + omega * (sum / count as f64 - old);
                change = change.max((new - old).abs());
                data[n] = new as f32;
            }
        }
        last_change = change;
        if change <= tolerance {
            break;
        }
    }
    Ok(HarmonicReport {
        unknowns: cells.len(),
        sweeps,
        last_change,
        converged: last_change <= tolerance,
    })
}
