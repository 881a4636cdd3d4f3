//! The multiscale fill of D (`--method msr`): the MSR of the paper (Section 2) with one coarse
//! level, its details carried across D from the intact neighbourhood.
//!
//! 1. Coarse level B: φ_0 evolved by v = c + κ_a − κ (paper, eq. 4.2) for a time T, so that a
//!    narrowing, a gap or a chopped wall are gone from it (the growth c closes them, the curvature
//!    term smooths what is left), redistanced.
//! 2. Details Δ = φ_0 − B, known outside D; inside D replaced by the harmonic function that takes
//!    the known values around it (`harmonic`): the MSR analogue of thresholding the framelet
//!    coefficients in the inpainting scheme of Cai, Chan and Shen that Algorithm 4 follows.
//! 3. ψ = B + Δ̃, blended into φ_0 across ∂D by the caller, redistanced.
//!
//! Measured in ../shared/notes/inpainting.md: a fill by curvature alone removes volume and pinches
//! a narrowing; a coarse base with c > 0 plus transferred details does not.

use super::harmonic::{fill_harmonic, HarmonicOptions, HarmonicReport};
use crate::grid::Grid3;
use crate::levelset::redistance::{redistance, RedistanceOptions};
use crate::motion::flow::FlowOptions;
use crate::motion::{evolve, Velocity};
use crate::Result;
use rayon::prelude::*;

/// Options of [`fill_msr`].
#[derive(Debug, Clone, PartialEq)]
pub struct MsrFillOptions {
    /// Growth speed c of the coarse level, 1/world length (world length per unit time).
    pub speed: f64,
    /// Evolution time T of the coarse level, world length².
    pub time: f64,
    /// Time steps to reach T.
    pub steps: usize,
    /// The harmonic transfer of the details.
    pub harmonic: HarmonicOptions,
}

/// What [`fill_msr`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MsrFillReport {
    /// The harmonic transfer of the details.
    pub harmonic: HarmonicReport,
}

/// The coarse level B of φ_0 (step 1 of the module docs): evolved and fully redistanced.
pub fn coarse_level(phi0: &Grid3, opts: &MsrFillOptions) -> Result<Grid3> {
    let mut base = phi0.clone();
    let dt = opts.time / opts.steps.max(1) as f64;
    evolve(
        &mut base,
        Velocity::Inpaint { c: opts.speed },
        opts.time,
        dt,
        // The sub-box's border cuts the vessel anyway; outside D, φ_0 is restored.
        &FlowOptions {
            allow_border: true,
            ..FlowOptions::default()
        },
        |_| {},
    )?;
    redistance(
        &mut base,
        &RedistanceOptions {
            band: None,
            ..RedistanceOptions::default()
        },
    )?;
    Ok(base)
}

/// The MSR round trip with one coarse level: B = the coarse level of `phi`, Δ = φ − B, then
/// `transfer` changes Δ (the harmonic fill across D here; the viscosity of IMST in Algorithm 4 as
/// written), and B + Δ̃ is returned with what `transfer` reported.
pub fn transfer_details<T>(
    phi: &Grid3,
    opts: &MsrFillOptions,
    transfer: impl FnOnce(&mut Grid3) -> Result<T>,
) -> Result<(Grid3, T)> {
    let base = coarse_level(phi, opts)?;
    let mut detail = phi.clone();
    detail
        .data_mut()
        .par_iter_mut()
        .zip(base.data().par_iter())
        .for_each(|(d, &b)| *d -= b);
    let report = transfer(&mut detail)?;
    let mut psi = base;
    psi.data_mut()
        .par_iter_mut()
        .zip(detail.data().par_iter())
        .for_each(|(p, &d)| *p += d);
    Ok((psi, report))
}

/// ψ = B + Δ̃ (steps 1–3 of the module docs), not yet blended nor redistanced. `phi0` must be a
/// signed distance (not clamped far from the surface: the details compare true distances);
/// `unknown` marks the nodes of D.
pub fn fill_msr(
    phi0: &Grid3,
    unknown: &[bool],
    opts: &MsrFillOptions,
) -> Result<(Grid3, MsrFillReport)> {
    let (psi, harmonic) = transfer_details(phi0, opts, |detail| {
        fill_harmonic(detail, unknown, &opts.harmonic)
    })?;
    Ok((psi, MsrFillReport { harmonic }))
}
