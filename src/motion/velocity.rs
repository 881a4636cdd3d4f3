//! The normal velocities v_n of the level-set motion φ_t + v_n |∇φ| = 0 that the threshold
//! dynamics of [`super::flow`] solve (paper, eq. 1.1 with the velocities of eq. 1.2 and eq. 4.2).
//!
//! Conventions: φ < 0 inside, κ = ∇·(∇φ/|∇φ|) is the mean curvature as the sum of the principal
//! curvatures (2/R on a sphere of radius R), v_n > 0 moves the surface outward. Time is in world
//! length² (the heat equation u_t = Δu has no diffusion constant), so a speed c is in world
//! length per unit time, i.e. 1/length, and moves the surface by c·t.

use crate::{Error, Result};
use std::fmt;

/// A normal velocity of the level-set motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Velocity {
    /// `mcf`: mean curvature flow, v_n = −κ (a sphere shrinks as r² = R² − 4t).
    MeanCurvature,
    /// `vpmcf`: volume-preserving mean curvature flow, v_n = κ_a − κ with κ_a the area-weighted
    /// mean of κ (paper, Algorithm 3, after Ruuth and Wetton).
    VolumePreserving,
    /// `expand`: motion at constant normal speed, v_n = c (paper, Algorithm 2); c < 0 shrinks.
    Expand {
        /// Speed, world length per unit time.
        c: f64,
    },
    /// `inpaint`: v_n = c + κ_a − κ (paper, eq. 4.2), the volume-preserving flow plus a growth
    /// at speed c ≥ 0.
    Inpaint {
        /// Speed, world length per unit time (≥ 0).
        c: f64,
    },
}

impl Velocity {
    /// The velocity named `name` (`mcf`, `vpmcf`, `expand`, `inpaint`) with speed `c` (used by
    /// `expand` and `inpaint` only; `None` is 0). Errors on another name, or a `c` that the
    /// velocity does not take, is not finite, or is negative for `inpaint`.
    pub fn from_name(name: &str, c: Option<f64>) -> Result<Velocity> {
        let velocity = match name {
            "mcf" => Velocity::MeanCurvature,
            "vpmcf" => Velocity::VolumePreserving,
            "expand" => Velocity::Expand {
                c: c.unwrap_or(0.0),
            },
            "inpaint" => Velocity::Inpaint {
                c: c.unwrap_or(0.0),
            },
            _ => {
                return Err(Error::Geometry(format!(
                    "unknown velocity '{name}' (expected mcf, vpmcf, expand or inpaint)"
                )))
            }
        };
        if c.is_some() && velocity.speed().is_none() {
            return Err(Error::Geometry(format!(
                "velocity {name} takes no speed c (only expand and inpaint do)"
            )));
        }
        velocity.validate()?;
        Ok(velocity)
    }

    /// The constant speed c of `expand` and `inpaint`, None for the others.
    pub fn speed(&self) -> Option<f64> {
        match *self {
            Velocity::Expand { c } | Velocity::Inpaint { c } => Some(c),
            _ => None,
        }
    }

    /// The short name used on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Velocity::MeanCurvature => "mcf",
            Velocity::VolumePreserving => "vpmcf",
            Velocity::Expand { .. } => "expand",
            Velocity::Inpaint { .. } => "inpaint",
        }
    }

    /// Whether the motion contains the curvature term (all but `expand`): those steps diffuse φ.
    pub fn has_curvature(&self) -> bool {
        !matches!(self, Velocity::Expand { .. })
    }

    /// Whether the step keeps the enclosed volume fixed before the growth term (`vpmcf`,
    /// `inpaint`): those steps search the threshold shift λ.
    pub fn preserves_volume(&self) -> bool {
        matches!(self, Velocity::VolumePreserving | Velocity::Inpaint { .. })
    }

    /// Checks the speed: finite, and ≥ 0 for `inpaint`.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Velocity::Expand { c } if !c.is_finite() => Err(Error::Geometry(format!(
                "expand: the speed c must be finite, got {c}"
            ))),
            Velocity::Inpaint { c } if !(c.is_finite() && c >= 0.0) => {
                Err(Error::Geometry(format!(
                    "inpaint: the speed c must be finite and ≥ 0 (the inpainting motion grows \
                     the shape), got {c}"
                )))
            }
            _ => Ok(()),
        }
    }
}

impl fmt::Display for Velocity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.speed() {
            Some(c) => write!(f, "{} (c = {c})", self.name()),
            None => f.write_str(self.name()),
        }
    }
}
