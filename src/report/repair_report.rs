//! The report of a repair (issue: vessel repair): input and output volumes, and per region D the
//! inpainted volume (output minus input inside D), its fraction of the whole output volume (the
//! paper's Section 4 figure: the share of the recovered vessel that was missing) and the stenosis
//! estimate of [`super::stenosis`] (input against output at the same cross-sections); and the
//! whole report ([`RepairReport`]) that `vesselmsr repair --report` writes as JSON and the Python
//! package returns as a dict.

use super::stenosis::{measure_stenosis_with, volume_in_ball_with, StenosisOptions};
use crate::bvh::{WindingNumber, WindingOptions};
use crate::centerline::healthy::HealthyVessel;
use crate::error::short_number;
use crate::inpaint::guided::{GuideKind, JUNCTION_FILL, STUMP_FILL};
use crate::inpaint::region::Ball;
use crate::mesh::decimate::DecimateReport;
use crate::mesh::info::MeshInfo;
use crate::mesh::measures::signed_volume;
use crate::TriMesh;
use serde::Serialize;

/// The adjacent normal segment of the NASCET figure is measured this many region radii from the
/// region's centre (just outside D, on both sides).
pub const NASCET_OFFSET: f64 = 1.15;

/// One region D of the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegionReport {
    /// Centre, world units.
    pub center: [f64; 3],
    /// Radius, world units.
    pub radius: f64,
    /// Where the region came from (`region`, `regions-file`, `picked point`, `hole`).
    pub source: String,
    /// How it was filled: the `centerline` fill's kind (`through`, `bridge`, `junction`,
    /// `dead-end`, `stump`, `widened`), `axial` where no vessel passes through it on the
    /// centreline, or the method's name (`Repair::region_fill`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fill: Option<&'static str>,
    /// Volume of the output minus that of the input inside D, world units³.
    pub inpainted_volume: f64,
    /// `inpainted_volume` over the whole output volume.
    pub inpainted_fraction: f64,
    /// Volume of the input inside D, world units³: its holes' caps counted only inside the
    /// repaired vessel (what a cap across a crotch holds outside it is left out:
    /// [`discount_cap_outside`]).
    pub input_volume_in_region: f64,
    /// Volume of the output inside D, world units³.
    pub output_volume_in_region: f64,
    /// (1 − min input diameter / healthy diameter) × 100 ("centerline": the local healthy
    /// reference of the input's centreline at the narrowest point, the line between the healthy
    /// lumen on either side; "sections": the output's diameter at the input's narrowest section
    /// in D); None when no cross-section could be taken in D.
    pub diameter_stenosis_pct: Option<f64>,
    /// (1 − min input area / healthy area) × 100, the healthy area as the diameter's.
    pub area_stenosis_pct: Option<f64>,
    /// (1 − min input diameter / normal diameter) × 100: the narrower of the healthy lumens on
    /// either side along the centreline (`stenosis_method` "centerline"; NASCET takes the distal
    /// one, the narrower in a tapering artery), or the input's diameter of the adjacent normal
    /// segments just outside D ("sections").
    pub nascet_stenosis_pct: Option<f64>,
    /// The healthy diameter of the diameter stenosis ("centerline": the local reference) or of
    /// the NASCET figure ("sections"), world units.
    pub reference_diameter: Option<f64>,
    /// How the stenosis was measured: "centerline" (along the input's centreline, independent of
    /// the region's size) or "sections" (across D along the output's local axis, where no
    /// centreline point with a measured section lies in D).
    pub stenosis_method: Option<&'static str>,
    /// Smallest equivalent diameter of the input's lumen in D, world units.
    pub min_input_diameter: Option<f64>,
    /// Equivalent diameter of the output at the same section, world units.
    pub output_diameter_at_min: Option<f64>,
    /// What the repair left of the narrowing: (1 − output diameter at the input's narrowest
    /// section / healthy diameter) × 100 (about 0 when the lumen was restored; negative when the
    /// output is wider than the reference there). None without both diameters.
    pub residual_stenosis_pct: Option<f64>,
    /// Why the stenosis figures are missing, when they are.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stenosis_note: Option<String>,
}

/// Measures of one closed surface.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceMeasures {
    /// Enclosed volume, world units³ (of the capped surface when ends were capped).
    pub volume: f64,
    /// Connected components.
    pub components: usize,
    /// Boundary edges (0: closed).
    pub boundary_edges: usize,
}

/// The input or the output of a repair: its file, when there is one, and its measures.
#[derive(Debug, Clone, Serialize)]
pub struct MeshPart {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<String>,
    #[serde(flatten)]
    pub measures: SurfaceMeasures,
}

/// A boundary loop of the input (`--holes`): its kind (`open vessel end`, `hole` or `cut end`,
/// a side of a gap the damage cut through the vessel) and shape.
#[derive(Debug, Clone, Serialize)]
pub struct LoopReport {
    pub kind: &'static str,
    pub center: [f64; 3],
    pub radius: f64,
    pub planarity: f64,
}

/// The parameters a repair used (given or defaulted), and how it went.
#[derive(Debug, Clone, Serialize)]
pub struct RepairParameters {
    pub method: &'static str,
    pub voxel: f64,
    pub grid_dims: [usize; 3],
    /// Voxel of the grid the stitched patch was meshed on (`voxel` or twice it), world units;
    /// `voxel` where the whole vessel was re-meshed.
    pub patch_voxel: f64,
    pub radius_estimate: f64,
    pub c: f64,
    pub time: f64,
    pub epsilon: f64,
    pub keep_outside: bool,
    pub open_ends: bool,
    pub stitched: bool,
    /// How far beyond D the patch was stitched, world units (0: at D; see `Repair::stitch_beyond`).
    pub stitch_beyond: f64,
    pub junctions: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fallback: Option<String>,
    pub axes: Vec<[f64; 3]>,
    /// The centreline fill's curves, by kind.
    pub guides: Vec<GuideKind>,
}

/// The whole report of a repair (`repair --report R.json`; the keys are in the README).
#[derive(Debug, Clone, Serialize)]
pub struct RepairReport {
    pub units: String,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notices: Vec<String>,
    pub input: MeshPart,
    pub input_capped: bool,
    pub output: MeshPart,
    pub regions: Vec<RegionReport>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub loops: Vec<LoopReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decimate: Option<DecimateReport>,
    pub watertight: bool,
    pub iterations: usize,
    pub converged: bool,
    pub parameters: RepairParameters,
    /// Seconds per phase (`centerline` may overlap `cap` and `voxelize`: it is traced meanwhile
    /// unless the regions are read on it).
    pub timings: serde_json::Map<String, serde_json::Value>,
}

/// The measures of the report, from the mesh's [`MeshInfo`].
pub fn surface_measures(info: &MeshInfo) -> SurfaceMeasures {
    SurfaceMeasures {
        volume: info.signed_volume,
        components: info.components,
        boundary_edges: info.boundary_edges,
    }
}

/// The source of a region that `repair --stenoses` placed on a narrowing the centreline found.
pub const DETECTED_STENOSIS: &str = "detected stenosis";
/// The source of a narrowing's region chosen by a point picked on it (a regions file).
pub const PICKED_STENOSIS: &str = "picked stenosis";

/// A narrowing's region whose output is still narrowed by this much or more (`residual_stenosis_pct`)
/// was not restored: the repair says so in a notice (the threshold of a narrowing worth
/// repairing, as a picked point takes it).
pub const UNRESTORED_NARROWING_PCT: f64 = crate::inpaint::pipeline::PICKED_STENOSIS_MIN_PCT;

/// (1 − output / healthy diameter) × 100.
fn residual_pct(output: f64, healthy: f64) -> f64 {
    (1.0 - output / healthy) * 100.0
}

/// "region K (x, y, z)": how the notices name a region (`k` counts regions from 1).
fn region_label(k: usize, region: &RegionReport) -> String {
    let [x, y, z] = region.center.map(short_number);
    format!("region {k} ({x}, {y}, {z})")
}

/// The notice for a narrowing's region (by its `source`) that the repair did not widen: the
/// output still narrowed by [`UNRESTORED_NARROWING_PCT`] or more at the input's narrowest
/// section. `k` counts regions from 1.
pub fn unrestored_narrowing(k: usize, region: &RegionReport) -> Option<String> {
    let residual = region.residual_stenosis_pct?;
    if !(is_stenosis_source(&region.source) && residual >= UNRESTORED_NARROWING_PCT) {
        return None;
    }
    let d = |v: Option<f64>| v.map_or("?".into(), short_number);
    Some(format!(
        "{}: narrowing not restored: the output is still {residual:.0}% \
         narrower than the healthy lumen at the throat (diameter {} against {}); check the \
         picture, or give the region with --region",
        region_label(k, region),
        d(region.output_diameter_at_min),
        d(region.reference_diameter),
    ))
}

/// Takes `outside` off the input's volume in region `k` (counted from 1): the capped input's
/// volume there that only a hole's cap held, outside the repaired vessel (`Repair::cap_outside`,
/// world units³), so that the inpainted volume counts from the input's own wall; `output_volume`
/// is the whole output's, for the fraction. The notice saying so when `outside` is more than a
/// thousandth of the region's ball (a cap across a bifurcation's crotch).
pub fn discount_cap_outside(
    k: usize,
    region: &mut RegionReport,
    outside: f64,
    output_volume: f64,
) -> Option<String> {
    if !(outside > 0.0 && outside.is_finite()) {
        return None;
    }
    region.input_volume_in_region -= outside;
    region.inpainted_volume += outside;
    if output_volume > 0.0 {
        region.inpainted_fraction = region.inpainted_volume / output_volume;
    }
    let ball = 4.0 / 3.0 * std::f64::consts::PI * region.radius.powi(3);
    if outside <= 1e-3 * ball {
        return None;
    }
    Some(format!(
        "{}: the hole's cap crossed space outside the vessel (a crotch \
         between branches): {} (the mesh's units³) of the capped input there was not kept, and \
         the input's volume in the region is counted without it",
        region_label(k, region),
        short_number(outside)
    ))
}

/// The notice for a region filled as a junction (`fill` [`JUNCTION_FILL`]): the branches are continued
/// to a junction point that the fill places, so the shape of the carina and the flare inside D
/// is an estimate. Such fills are the least accurate of the repair: on the real damage of
/// `benches/repair_real` (seeds 21–33), 33 of the 52 regions filled as a junction end beyond 3
/// voxels of the truth, against 16 of the 271 others (seeds 21–23: 7 of 14, 2 of 61). `k`
/// counts regions from 1.
pub fn modelled_junction(k: usize, region: &RegionReport) -> Option<String> {
    if region.fill != Some(JUNCTION_FILL) {
        return None;
    }
    Some(format!(
        "{} spans a junction: its branches are continued to a modelled \
         junction, so the carina and the flare inside it are estimated, not measured; check the \
         picture",
        region_label(k, region)
    ))
}

/// The notice for a region where a vessel stops with nothing found beyond it (`fill`
/// [`STUMP_FILL`]): it is capped round where its damaged centreline stops, and whatever the
/// damage took beyond it is not restored. On `benches/repair_real` (seeds 21–35) the one such
/// region is seed 34's chop over the capped aorta's bifurcation, whose iliacs the chop cut off
/// (99h in D: the input holds nothing of them). `k` counts regions from 1.
pub fn stopped_vessel(k: usize, region: &RegionReport) -> Option<String> {
    if region.fill != Some(STUMP_FILL) {
        return None;
    }
    Some(format!(
        "{}: a vessel stops inside it with no end found beyond (no open \
         end, cut plane or intact closed end): it is capped round there; if the damage took its \
         continuation (a branch, a bifurcation), that is not restored; check the picture",
        region_label(k, region)
    ))
}

/// Whether a region of this source is a narrowing's (an intact, narrowed lumen, measured at
/// its own narrowest point).
pub fn is_stenosis_source(source: &str) -> bool {
    source == DETECTED_STENOSIS || source == PICKED_STENOSIS
}

/// A surface's fast winding number (`WindingOptions::SIDES`) and the volume it holds in each
/// ball of D ([`volume_in_ball_with`] with that winding number), measured once: the repair's
/// self-checks measure them, and the report reads them instead of measuring them again.
#[derive(Debug, Clone)]
pub struct Measured {
    pub winding: WindingNumber,
    pub volumes: Vec<f64>,
}

impl Measured {
    /// `mesh`'s winding number and its volume in each of `balls`.
    pub fn new(mesh: &TriMesh, balls: &[Ball]) -> Self {
        let winding = WindingNumber::new(mesh, WindingOptions::SIDES);
        Measured {
            volumes: balls
                .iter()
                .map(|b| volume_in_ball_with(mesh, &winding, b))
                .collect(),
            winding,
        }
    }
}

/// The per-region figures for `balls` (with their `sources`), `input` being the measured input
/// (capped) and `output` the repaired mesh; the stenosis along `healthy` (the input's centreline)
/// where it has measured points in the region, else across the region's sections. `measured`:
/// the input's and output's winding numbers and volumes in `balls` when already measured.
pub fn region_reports(
    input: &TriMesh,
    output: &TriMesh,
    balls: &[Ball],
    sources: &[String],
    healthy: Option<&HealthyVessel>,
    measured: Option<[&Measured; 2]>,
) -> Vec<RegionReport> {
    let built;
    let [m_in, m_out] = match measured {
        Some(m) if m.iter().all(|m| m.volumes.len() == balls.len()) => m,
        _ => {
            built = [input, output].map(|m| Measured::new(m, balls));
            [&built[0], &built[1]]
        }
    };
    let (win_in, win_out) = (&m_in.winding, &m_out.winding);
    let total = signed_volume(output);
    balls
        .iter()
        .enumerate()
        .map(|(k, ball)| {
            let (vin, vout) = (m_in.volumes[k], m_out.volumes[k]);
            // A narrowing's region (found by `--stenoses` or picked) is measured at its own
            // narrowest point, the ball's centre (within a third of the ball's radius, half a
            // healthy radius at least), not at the deepest narrowing the ball reaches: its ball
            // (a healthy radius beyond the lesion's width) can hold a neighbouring lesion's
            // throat.
            let detected = sources.get(k).is_some_and(|s| is_stenosis_source(s));
            let probe = Ball {
                radius: if detected {
                    ball.radius / 3.0
                } else {
                    ball.radius
                },
                ..*ball
            };
            let along = healthy.and_then(|h| h.measure_in(output, &probe));
            let mut report = RegionReport {
                center: [ball.center.x, ball.center.y, ball.center.z],
                radius: ball.radius,
                source: sources.get(k).cloned().unwrap_or_else(|| "region".into()),
                fill: None,
                inpainted_volume: vout - vin,
                inpainted_fraction: if total > 0.0 {
                    (vout - vin) / total
                } else {
                    0.0
                },
                input_volume_in_region: vin,
                output_volume_in_region: vout,
                diameter_stenosis_pct: None,
                area_stenosis_pct: None,
                nascet_stenosis_pct: None,
                reference_diameter: None,
                stenosis_method: None,
                min_input_diameter: None,
                output_diameter_at_min: None,
                residual_stenosis_pct: None,
                stenosis_note: None,
            };
            if let Some(a) = along {
                report.diameter_stenosis_pct = Some(a.diameter_stenosis_pct);
                report.area_stenosis_pct = Some(a.area_stenosis_pct);
                report.nascet_stenosis_pct = Some(a.nascet_stenosis_pct);
                report.reference_diameter = Some(a.reference_diameter);
                report.stenosis_method = Some("centerline");
                report.min_input_diameter = Some(a.min_input_diameter);
                report.output_diameter_at_min = a.output_diameter;
                report.residual_stenosis_pct = a
                    .output_diameter
                    .map(|o| residual_pct(o, a.reference_diameter));
                return report;
            }
            let stenosis = measure_stenosis_with(
                input,
                win_in,
                output,
                win_out,
                ball,
                &StenosisOptions {
                    normal_offset: NASCET_OFFSET,
                    ..StenosisOptions::default()
                },
            );
            match stenosis {
                Ok(s) => {
                    report.diameter_stenosis_pct = Some(s.diameter_stenosis_pct);
                    report.area_stenosis_pct = Some(s.area_stenosis_pct);
                    report.nascet_stenosis_pct = s.nascet_stenosis_pct;
                    report.reference_diameter = s.normal_diameter;
                    report.stenosis_method = Some("sections");
                    report.min_input_diameter = Some(s.min_input_diameter);
                    report.output_diameter_at_min = Some(s.output_diameter_at_min);
                    report.residual_stenosis_pct = s
                        .normal_diameter
                        .map(|d| residual_pct(s.output_diameter_at_min, d));
                }
                Err(e) => report.stenosis_note = Some(e.to_string()),
            }
            report
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn narrowing(source: &str, output: f64, healthy: f64) -> RegionReport {
        RegionReport {
            center: [1.0, 2.0, 3.0],
            radius: 4.0,
            source: source.into(),
            fill: None,
            inpainted_volume: 0.0,
            inpainted_fraction: 0.0,
            input_volume_in_region: 0.0,
            output_volume_in_region: 0.0,
            diameter_stenosis_pct: Some(50.0),
            area_stenosis_pct: Some(75.0),
            nascet_stenosis_pct: Some(50.0),
            reference_diameter: Some(healthy),
            stenosis_method: Some("centerline"),
            min_input_diameter: Some(0.5 * healthy),
            output_diameter_at_min: Some(output),
            residual_stenosis_pct: Some(residual_pct(output, healthy)),
            stenosis_note: None,
        }
    }

    #[test]
    fn a_narrowing_left_narrowed_gets_a_notice() {
        // The capped aorta's narrowing of the held-out seed 23 (repair_real): 4.69 against 8.64.
        let left = narrowing(PICKED_STENOSIS, 4.69, 8.64);
        assert!((left.residual_stenosis_pct.unwrap() - 45.7).abs() < 0.1);
        let n = unrestored_narrowing(2, &left).expect("a notice");
        assert!(
            n.starts_with("region 2 (1, 2, 3): narrowing not restored"),
            "{n}"
        );
        assert!(n.contains("46%") && n.contains("4.69 against 8.64"), "{n}");
        assert!(n.len() < 300, "{} characters", n.len());
        // Restored (the bench's seed 21: 8.742 against 8.749), or just under the threshold.
        assert!(unrestored_narrowing(1, &narrowing(DETECTED_STENOSIS, 8.742, 8.749)).is_none());
        assert!(unrestored_narrowing(1, &narrowing(DETECTED_STENOSIS, 8.1, 10.0)).is_none());
        assert!(unrestored_narrowing(1, &narrowing(DETECTED_STENOSIS, 7.9, 10.0)).is_some());
        // A chop's region is no narrowing: its sections say nothing of a lesion.
        assert!(unrestored_narrowing(1, &narrowing("hole", 4.69, 8.64)).is_none());
    }

    #[test]
    fn a_vessel_stopping_in_a_region_gets_a_notice() {
        let mut region = narrowing("hole", 9.0, 9.0);
        region.fill = Some("dead-end");
        assert!(stopped_vessel(1, &region).is_none());
        region.fill = Some(STUMP_FILL);
        let n = stopped_vessel(2, &region).expect("a notice");
        assert!(n.starts_with("region 2 ("), "{n}");
        assert!(
            n.contains("stops inside it") && n.contains("not restored"),
            "{n}"
        );
        assert!(n.chars().count() <= 300, "{} characters", n.chars().count());
    }

    #[test]
    fn a_region_filled_as_a_junction_gets_a_notice() {
        let mut region = narrowing("hole", 9.0, 9.0);
        assert!(modelled_junction(1, &region).is_none(), "no fill given");
        region.fill = Some("through");
        assert!(modelled_junction(1, &region).is_none());
        region.fill = Some("junction");
        let n = modelled_junction(3, &region).expect("a notice");
        assert!(n.starts_with("region 3 ("), "{n}");
        assert!(
            n.contains("spans a junction") && n.contains("estimated"),
            "{n}"
        );
        assert!(n.chars().count() <= 300, "{} characters", n.chars().count());
    }
}
