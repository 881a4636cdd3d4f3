//! Regions D to inpaint: balls in world (file) units, and the JSON regions file that lists them.
//!
//! The regions file is `{"regions": [{"center": [x, y, z], "radius": r}, ...],
//! "points": [[x, y, z], ...]}`: balls, and/or points picked on the surface (the paper's
//! interactive strategy, Section 4), from which balls are sized by the local vessel radius.
//! Both keys are optional; at least one region must result.

use crate::io::write_atomic;
use crate::{Error, Result};
use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A ball of the damaged region D, in world (file) units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball {
    /// Centre, world units.
    pub center: Point3<f64>,
    /// Radius, world units.
    pub radius: f64,
}

impl Ball {
    /// Whether `p` lies in the closed ball.
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        (p - self.center).norm_squared() <= self.radius * self.radius
    }
}

/// One ball as written in a regions file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BallEntry {
    /// Centre, world units.
    pub center: [f64; 3],
    /// Radius, world units.
    pub radius: f64,
}

/// The contents of a regions file (see the module docs).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RegionsFile {
    /// Balls, world units.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<BallEntry>,
    /// Points picked on the surface, world units.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<[f64; 3]>,
}

impl From<&Ball> for BallEntry {
    fn from(b: &Ball) -> Self {
        BallEntry {
            center: [b.center.x, b.center.y, b.center.z],
            radius: b.radius,
        }
    }
}

impl From<&BallEntry> for Ball {
    fn from(b: &BallEntry) -> Self {
        Ball {
            center: Point3::from(b.center),
            radius: b.radius,
        }
    }
}

/// Writes `balls` as a regions file at `path` (atomically).
pub fn write_regions(path: &Path, balls: &[Ball]) -> Result<()> {
    let file = RegionsFile {
        regions: balls.iter().map(BallEntry::from).collect(),
        points: Vec::new(),
    };
    let text = serde_json::to_string_pretty(&file)
        .map_err(|e| Error::format(path, format!("cannot encode regions: {e}")))?;
    write_atomic(path, |out| {
        out.write_all(text.as_bytes())
            .and_then(|_| out.write_all(b"\n"))
            .map_err(|e| Error::io(path, e))
    })
}
