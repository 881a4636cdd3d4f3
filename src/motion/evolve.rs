//! The time-stepping driver of the level-set motions: redistance φ once, then take equal
//! [`Flow`] steps up to the final time, reporting each step to a callback (the CLI's progress
//! bar and its per-step JSON).

use super::flow::{Flow, FlowOptions, StepReport, MIN_DT_VOXELS2};
use super::velocity::Velocity;
use crate::grid::Grid3;
use crate::levelset::redistance::{redistance, RedistanceOptions};
use crate::{Error, Result};

/// Number of equal steps of at most `dt` that make up `total_time` (both world length²): ⌈T/Δt⌉,
/// give or take 10⁻⁹ for round-off. Errors when either is not positive and finite, or the count
/// does not fit in usize.
pub fn step_count(total_time: f64, dt: f64) -> Result<usize> {
    if !(total_time.is_finite() && total_time > 0.0) {
        return Err(Error::Geometry(format!(
            "the evolution time must be positive and finite (world length²), got {total_time}"
        )));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(Error::Geometry(format!(
            "the time step must be positive and finite (world length²), got {dt}"
        )));
    }
    let n = (total_time / dt * (1.0 - 1e-9)).ceil().max(1.0);
    if n >= 1e15 {
        return Err(Error::Geometry(format!(
            "{n} steps of {dt} to reach {total_time} are too many"
        )));
    }
    Ok(n as usize)
}

/// Evolves `phi` (negative inside) by `velocity` up to `total_time` (world length²), in
/// [`step_count`] equal steps of at most `dt`, and returns the reports of all steps. Without a
/// region φ is first redistanced within the flow's band (so a clamped voxelization is a valid
/// start; with [`FlowOptions::region`] φ must already be a signed distance, as nodes outside the
/// region never change), then stepped by [`Flow::step`]; `progress` sees every step's report as
/// it is done.
///
/// Errors: `total_time` or `dt` not positive and finite, steps below [`MIN_DT_VOXELS2`]·h² for
/// the curvature flows, an invalid velocity or option, NaN in
/// φ, no node inside at the start, and the errors of [`Flow::step`] — among them the shape
/// vanishing before `total_time` (e.g. a small shape under `mcf`), whose message gives the time.
/// `phi` then holds the last state reached, which the caller should not use as a result.
pub fn evolve(
    phi: &mut Grid3,
    velocity: Velocity,
    total_time: f64,
    dt: f64,
    opts: &FlowOptions,
    mut progress: impl FnMut(&StepReport),
) -> Result<Vec<StepReport>> {
    let n = step_count(total_time, dt)?;
    let step = total_time / n as f64;
    let mut flow = Flow::new(velocity, step, opts.clone())?;
    let h = phi.voxel();
    if velocity.has_curvature() && step < MIN_DT_VOXELS2 * h * h {
        return Err(Error::Geometry(format!(
            "{}: steps of {step} are below the smallest step {MIN_DT_VOXELS2}h² = {} of the \
             curvature flows (h = {h}){}",
            velocity.name(),
            MIN_DT_VOXELS2 * h * h,
            if total_time < MIN_DT_VOXELS2 * h * h {
                ": the final time is shorter than one such step"
            } else {
                ": give a larger step"
            }
        )));
    }
    if opts.region.is_none() {
        let band = opts.band_width(&velocity, step, phi.voxel());
        redistance(
            phi,
            &RedistanceOptions {
                band: Some(band),
                ..RedistanceOptions::default()
            },
        )?;
    }
    let inside = phi.data().iter().any(|&v| v < 0.0);
    let outside = phi.data().iter().any(|&v| v >= 0.0);
    if !(inside && outside) {
        return Err(Error::Geometry(
            "nothing to evolve: φ has no zero level set (no node inside, or every node)".into(),
        ));
    }
    let mut reports = Vec::with_capacity(n);
    for _ in 0..n {
        let r = flow.step(phi).map_err(|e| {
            Error::Geometry(format!("{e}; stopped before the final time {total_time}"))
        })?;
        progress(&r);
        reports.push(r);
    }
    Ok(reports)
}
