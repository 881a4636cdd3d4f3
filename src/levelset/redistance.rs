//! Redistancing: rebuilds φ as the signed distance to its own zero level set, keeping the sign of
//! every node, by the fast sweeping method (Gauss–Seidel sweeps in the 8 alternating orders of
//! Zhao 2005, "A fast sweeping method for Eikonal equations", Math. Comp. 74; Tsai, Cheng, Osher,
//! Zhao 2003, "Fast sweeping algorithms for a class of Hamilton–Jacobi equations", SIAM J. Numer.
//! Anal. 41 — the [TCOZ] the paper calls after every motion step).
//!
//! 1. **Sub-voxel initialisation** (`init`): every node with a 6-neighbour of the other sign (or
//!    with φ = 0) is an interface node. Its distance is |φ|/|∇φ| with ∇φ estimated per axis by
//!    the one-sided difference across the sign change (the linear interpolation of the crossing
//!    along that edge; the nearer crossing when both sides change sign) and by central differences
//!    along axes without a crossing. This is exact for a planar interface whatever the scaling of
//!    φ, and the linearly interpolated crossings along the grid edges stay where they were (up to
//!    the curvature of the interface within a voxel). Interface nodes are then frozen.
//! 2. **Sweeping** (`sweep`), outward from the frozen nodes on both sides at once (a node that is
//!    not frozen has only neighbours of its own sign), in one of two schemes:
//!    * [`RedistanceScheme::ClosestPoint`] (default): each frozen node also stores the foot of its
//!      distance on the local linear interface, x − φ∇φ/|∇φ|²; the sweeps carry the nearest such
//!      point from neighbour to neighbour and φ is the Euclidean distance to it (the
//!      closest-point sweeping of Tsai 2002, "Rapid and accurate computation of the distance
//!      function using grids", J. Comput. Phys. 178). |∇φ| = 1 up to the sampling of the
//!      interface, away from the medial axis.
//!    * [`RedistanceScheme::Godunov`]: the first-order Godunov upwind discretisation of |∇φ| = 1
//!      (the 1-, 2- and 3-neighbour cases) of [TCOZ]/Zhao 2005. Its viscosity error makes φ grow
//!      slightly faster than the distance near curved interfaces (|∇φ| − 1 ≈ h·κ/2 along
//!      diagonals), which the closest-point scheme does not have.
//!
//! The sweeps of one direction are Gauss–Seidel over rows of x; rows on one anti-diagonal of the
//! (y, z) plane depend on none of each other and run in parallel (rayon), so the result is the
//! same as the sequential sweep, bit for bit, on any number of threads (the row-level form of the
//! parallel fast sweeping of Detrixhe, Gibou, Min 2013). Rows none of whose neighbours changed
//! since their last visit are skipped (a row-level form of the locking of Bak, McLaughlin, Renzi
//! 2010), and the sweeping stops after the first sweep that changes nothing.

mod init;
mod sweep;

use crate::grid::Grid3;
use crate::{Error, Result};

/// How the sweeps propagate the distance from the interface nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RedistanceScheme {
    /// Carry the nearest interface point (closest-point sweeping, Tsai 2002): Euclidean distance
    /// to the locally linear interface; |∇φ| = 1 up to the interface sampling.
    #[default]
    ClosestPoint,
    /// First-order Godunov upwind update of |∇φ| = 1 (Zhao 2005, [TCOZ]); overestimates the
    /// distance slightly near curved interfaces.
    Godunov,
}

/// Options of [`redistance`].
#[derive(Debug, Clone, PartialEq)]
pub struct RedistanceOptions {
    /// Half-width of the band, world units (> 0). `Some(w)`: the sweeps stop at distance `w` and
    /// every value beyond it becomes ±w, so the work scales with the band, not the grid.
    /// `None` (default): the whole grid.
    pub band: Option<f64>,
    /// The scheme of the sweeps (default: closest point).
    pub scheme: RedistanceScheme,
    /// Most sweeps (each in one of the 8 orders; default 64 = 8 rounds). The sweeping usually
    /// stops on its own after 9–17; when it reaches this limit [`RedistanceReport::converged`]
    /// is false and nodes the sweeps have not reached yet are ±∞ (±band). The Godunov values
    /// only decrease from sweep to sweep, so they are then upper bounds of the converged ones.
    pub max_sweeps: usize,
    /// Godunov scheme: a decrease smaller than this, in voxels, does not count as a change when
    /// deciding convergence (default 1e-4). The closest-point scheme converges exactly.
    pub tolerance: f64,
}

impl Default for RedistanceOptions {
    fn default() -> Self {
        RedistanceOptions {
            band: None,
            scheme: RedistanceScheme::ClosestPoint,
            max_sweeps: 64,
            tolerance: 1e-4,
        }
    }
}

/// What [`redistance`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RedistanceReport {
    /// Frozen nodes next to the interface (a sign change along a grid edge, or φ = 0). Zero means
    /// φ had one sign everywhere: see [`redistance`].
    pub interface_nodes: usize,
    /// Sweeps run, counting the last one that changed nothing.
    pub sweeps: usize,
    /// Whether the last sweep changed nothing (false: `max_sweeps` was reached first).
    pub converged: bool,
}

/// Rebuilds `phi` as the signed distance (world units) to its zero level set, in place.
///
/// The sign of every node is kept (φ < 0 inside; a node with φ = 0 lies on the interface and
/// gets 0). Nodes next to a sign change get their sub-voxel distance to the linearly
/// reconstructed interface and are not moved by the sweeps, so the zero level set stays where it
/// was. With a band, every |φ| beyond it becomes the band width.
///
/// Special cases (no error): when φ has one sign everywhere (a grid of one node, no interface,
/// all inside or all outside) there is nothing to measure from and every node becomes ±band, or
/// ±∞ without a band (the distance to an empty set), with its sign; the report says
/// `interface_nodes: 0`. ±∞ in the input is accepted as "far on that side": such nodes are not
/// frozen and get their distance from the sweeps (an edge between ±∞ and a finite value of the
/// other sign has no crossing position and seeds nothing).
///
/// Errors: a NaN in φ, a band that is not positive and finite, or more than 2³² − 2 interface
/// nodes.
pub fn redistance(phi: &mut Grid3, opts: &RedistanceOptions) -> Result<RedistanceReport> {
    if let Some(band) = opts.band {
        if !(band.is_finite() && band > 0.0) {
            return Err(Error::Geometry(format!(
                "redistance band must be positive and finite (world units), got {band}"
            )));
        }
    }
    if opts.tolerance.is_nan() || opts.tolerance < 0.0 {
        return Err(Error::Geometry(format!(
            "redistance tolerance must be non-negative, got {}",
            opts.tolerance
        )));
    }
    if let Some(i) = phi.data().iter().position(|v| v.is_nan()) {
        let [x, y, z] = phi.coords(i);
        return Err(Error::Geometry(format!(
            "redistance: φ is NaN at node ({x}, {y}, {z})"
        )));
    }
    let h = phi.voxel();
    // The band in voxels; the sweeps work in voxel units.
    let band_vox = opts.band.map(|b| b / h);
    let seeds = init::interface_seeds(phi)?;
    let interface_nodes = seeds.len();
    let (sweeps, converged) = if interface_nodes == 0 {
        let far = opts.band.map_or(f32::INFINITY, |b| b as f32);
        for v in phi.data_mut() {
            *v = if *v < 0.0 { -far } else { far };
        }
        (0, true)
    } else {
        sweep::sweep_distance(phi, &seeds, band_vox, opts)
    };
    Ok(RedistanceReport {
        interface_nodes,
        sweeps,
        converged,
    })
}
