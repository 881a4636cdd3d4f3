//! Diameter profiles along a centreline: at each point of each branch, the inscribed diameter
//! (2 × the maximal inscribed radius) and the equivalent diameter 2√(A/π) of the mesh's
//! cross-section perpendicular to the branch (the lumen area a clinician measures), with the arc
//! length from the branch's start.
//!
//! A section is measured where it is one closed lumen around the point (`report::stenosis::
//! cross_section` encloses it); it is left out (None) next to a junction (within 1.5 inscribed
//! radii, where the plane cuts two lumens) and where the plane runs out through an open end.

use super::{Branch, Centerline, EndKind};
use crate::report::stenosis::cross_section;
use crate::TriMesh;
use rayon::prelude::*;
use serde::Serialize;

/// One point of a branch's profile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProfilePoint {
    /// Arc length from the branch's first point, world units.
    pub s: f64,
    pub position: [f64; 3],
    /// 2 × the maximal inscribed radius, world units.
    pub inscribed_diameter: f64,
    /// 2√(A/π) of the cross-section, world units (None where it is not one lumen).
    pub equivalent_diameter: Option<f64>,
    /// Area of the cross-section, world units² (None with the diameter).
    pub area: Option<f64>,
}

/// The profile of one branch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BranchProfile {
    pub branch: usize,
    pub points: Vec<ProfilePoint>,
}

/// The profiles of every branch of `centerline` on `mesh` (see the module docs).
pub fn measure_profiles(mesh: &TriMesh, centerline: &Centerline) -> Vec<BranchProfile> {
    centerline
        .branches
        .par_iter()
        .map(|b| BranchProfile {
            branch: b.id,
            points: branch_profile(mesh, b),
        })
        .collect()
}

fn branch_profile(mesh: &TriMesh, b: &Branch) -> Vec<ProfilePoint> {
    let n = b.points.len();
    let mut s = 0.0;
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        if i > 0 {
            s += (b.points[i] - b.points[i - 1]).norm();
        }
        let p = b.points[i];
        let near_junction = [(b.start, 0), (b.end, n - 1)].iter().any(|&(kind, k)| {
            kind == EndKind::Junction
                && (p - b.points[k]).norm() < 1.5 * b.radius[k].max(b.radius[i])
        });
        let section = (!near_junction)
            .then(|| cross_section(mesh, &p, &b.tangent[i]))
            .flatten()
            .filter(|c| c.encloses_point);
        out.push(ProfilePoint {
            s,
            position: [p.x, p.y, p.z],
            inscribed_diameter: 2.0 * b.radius[i],
            equivalent_diameter: section.as_ref().map(|c| c.equivalent_diameter),
            area: section.as_ref().map(|c| c.area),
        });
    }
    out
}
