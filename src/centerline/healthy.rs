//! The healthy vessel around a damaged region, from the centreline of the damaged input: the
//! healthy radius at a point (to size a region D from it, not from a narrowed lumen), the
//! narrowings the centreline finds (regions D of their own), and the stenosis inside a region
//! measured along the centreline, so that it does not depend on how large the region was drawn.
//!
//! The healthy diameters are the references of `stenosis` at the branch point nearest the point:
//! the *local* one (the line between the healthy lumen on either side, the shoulders, read
//! there) and the *normal* one (the narrower of those two shoulders). Inside a ball D the measured input
//! section along the centreline narrowest against its local reference gives the minimum diameter
//! D_min; the diameter stenosis is 1 − D_min/D_ref and the area stenosis 1 − A_min/(π D_ref²/4)
//! with D_ref the local reference there (ECST's estimate of the original lumen), and the NASCET
//! figure 1 − D_min/D_normal against the normal lumen beyond the lesion. The output's section at
//! the same point and direction is reported beside them (how much of the lumen the repair
//! restored).

use super::profile::{measure_profiles, BranchProfile};
use super::stenosis::{find_stenoses, BranchNarrowing, Lesion, Reference, StenosisFindOptions};
use super::Centerline;
use crate::inpaint::region::Ball;
use crate::report::stenosis::cross_section;
use crate::TriMesh;
use nalgebra::Point3;
use serde::Serialize;

/// A centreline with its diameter profiles and healthy reference lines.
pub struct HealthyVessel {
    pub centerline: Centerline,
    pub profiles: Vec<BranchProfile>,
    pub narrowing: Vec<BranchNarrowing>,
    pub lesions: Vec<Lesion>,
}

/// The stenosis inside one region, along the centreline.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RegionStenosis {
    pub branch: usize,
    /// The narrowest input section's centreline point, world units.
    pub position: [f64; 3],
    /// Equivalent diameter of the input there, world units.
    pub min_input_diameter: f64,
    /// Equivalent diameter of the output at the same section, world units (None: no section).
    pub output_diameter: Option<f64>,
    /// Local healthy reference diameter there, world units.
    pub reference_diameter: f64,
    /// (1 − input / reference diameter) × 100.
    pub diameter_stenosis_pct: f64,
    /// The normal lumen beyond the narrowing (the narrower shoulder), world units.
    pub normal_diameter: f64,
    /// (1 − input / normal diameter) × 100, as NASCET.
    pub nascet_stenosis_pct: f64,
    /// (1 − input area / reference area) × 100.
    pub area_stenosis_pct: f64,
}

impl HealthyVessel {
    /// `centerline` without its diameter profiles: no reference is known, nothing is found
    /// narrowed (for a repair that widens no narrowing, which need not measure them).
    pub fn unmeasured(centerline: Centerline) -> Self {
        HealthyVessel {
            centerline,
            profiles: Vec::new(),
            narrowing: Vec::new(),
            lesions: Vec::new(),
        }
    }

    /// Profiles and reference lines of `centerline` on `mesh` (the input it was traced on).
    pub fn new(mesh: &TriMesh, centerline: Centerline, opts: &StenosisFindOptions) -> Self {
        let profiles = measure_profiles(mesh, &centerline);
        let (lesions, narrowing) = find_stenoses(&centerline, &profiles, opts);
        HealthyVessel {
            centerline,
            profiles,
            narrowing,
            lesions,
        }
    }

    /// The centreline point nearest to `p`: (branch, point index, distance).
    fn nearest(&self, p: &Point3<f64>) -> Option<(usize, usize, f64)> {
        let mut best: Option<(usize, usize, f64)> = None;
        for b in &self.centerline.branches {
            for (i, q) in b.points.iter().enumerate() {
                let d = (q - p).norm();
                if best.is_none_or(|x| d < x.2) {
                    best = Some((b.id, i, d));
                }
            }
        }
        best
    }

    /// The healthy references of `branch` at its point `i`, or at its nearest measured point
    /// along the branch where `i` has none (None when the branch has none).
    fn reference_at(&self, branch: usize, i: usize) -> Option<Reference> {
        let refs = &self
            .narrowing
            .iter()
            .find(|n| n.branch == branch)?
            .reference;
        let prof = self.profiles.iter().find(|p| p.branch == branch)?;
        let s = prof.points.get(i)?.s;
        refs.get(i).copied().flatten().or_else(|| {
            refs.iter()
                .zip(&prof.points)
                .filter_map(|(r, p)| r.map(|r| (r, (p.s - s).abs())))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(r, _)| r)
        })
    }

    /// The healthy vessel radius next to the surface point `p`: half the reference diameter at
    /// the nearest centreline point, when `p` lies within twice that radius of it.
    pub fn healthy_radius(&self, p: &Point3<f64>) -> Option<f64> {
        let (b, i, d) = self.nearest(p)?;
        let r = 0.5 * self.reference_at(b, i)?.local;
        (d <= 2.0 * r).then_some(r)
    }

    /// One ball per lesion of at least `min_degree_pct` against the normal lumen beyond it
    /// (NASCET; a dip before a widening is no lesion): on the centreline at the narrowest point,
    /// radius 1.5 healthy radii or the lesion's length (its width at half depth) plus one healthy
    /// radius, the larger: a bell-shaped narrowing is down to a sixteenth of its depth one
    /// half-depth width away from its narrowest point, so the ball reaches healthy wall on both
    /// sides.
    pub fn lesion_regions(&self, min_degree_pct: f64) -> Vec<Ball> {
        self.lesions
            .iter()
            .filter(|l| l.nascet_stenosis_pct >= min_degree_pct)
            .map(lesion_ball)
            .collect()
    }

    /// The region of the lesion of at least `min_degree_pct` (NASCET) whose ball (as
    /// [`Self::lesion_regions`] gives it) holds the surface point `p`, the nearest one's when
    /// several do: a point picked on a narrowing.
    pub fn lesion_region_at(&self, p: &Point3<f64>, min_degree_pct: f64) -> Option<Ball> {
        self.lesion_regions(min_degree_pct)
            .into_iter()
            .filter(|b| b.contains(p))
            .min_by(|a, b| (a.center - p).norm().total_cmp(&(b.center - p).norm()))
    }

    /// The stenosis inside `ball` along the centreline (see the module docs): over the measured
    /// centreline points inside the ball, the one where the input is narrowest against its
    /// healthy reference. None when no measured point lies in the ball.
    pub fn measure_in(&self, output: &TriMesh, ball: &Ball) -> Option<RegionStenosis> {
        let mut best: Option<(f64, usize, usize, f64, Reference)> = None;
        for prof in &self.profiles {
            let b = &self.centerline.branches[prof.branch];
            for (i, pp) in prof.points.iter().enumerate() {
                let Some(d) = pp.equivalent_diameter else {
                    continue;
                };
                if !ball.contains(&b.points[i]) {
                    continue;
                }
                let Some(dref) = self.reference_at(prof.branch, i) else {
                    continue;
                };
                let ratio = d / dref.local;
                if best.is_none_or(|x| ratio < x.0) {
                    best = Some((ratio, prof.branch, i, d, dref));
                }
            }
        }
        let (_, branch, i, dmin, dref) = best?;
        let b = &self.centerline.branches[branch];
        let p = b.points[i];
        let out = cross_section(output, &p, &b.tangent[i]).filter(|c| c.encloses_point);
        let area_in = self.profiles.iter().find(|q| q.branch == branch)?.points[i].area?;
        Some(RegionStenosis {
            branch,
            position: [p.x, p.y, p.z],
            min_input_diameter: dmin,
            output_diameter: out.as_ref().map(|c| c.equivalent_diameter),
            reference_diameter: dref.local,
            diameter_stenosis_pct: (1.0 - dmin / dref.local) * 100.0,
            area_stenosis_pct: (1.0 - area_in / (std::f64::consts::FRAC_PI_4 * dref.local.powi(2)))
                * 100.0,
            normal_diameter: dref.normal,
            nascet_stenosis_pct: (1.0 - dmin / dref.normal) * 100.0,
        })
    }
}

/// The region of one lesion: on the centreline at its narrowest point, radius 1.5 healthy radii
/// or its length plus one healthy radius, the larger ([`HealthyVessel::lesion_regions`]).
fn lesion_ball(l: &Lesion) -> Ball {
    let r = 0.5 * l.reference_diameter;
    Ball {
        center: Point3::from(l.position),
        radius: (1.5 * r).max(l.length + r),
    }
}
