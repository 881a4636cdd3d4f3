//! The report of a repair (issue: vessel repair): input and output volumes, and per region D the
//! inpainted volume (output minus input inside D), its fraction of the whole output volume (the
//! paper's Section 4 figure: the share of the recovered vessel that was missing) and the stenosis
//! estimate of [`super::stenosis`] (input against output at the same cross-sections).

use super::stenosis::{measure_stenosis_with, volume_in_ball_with, StenosisOptions};
use crate::bvh::{WindingNumber, WindingOptions};
use crate::inpaint::region::Ball;
use crate::mesh::info::MeshInfo;
use crate::mesh::measures::signed_volume;
use crate::TriMesh;
use serde::Serialize;

/// The adjacent normal segment of the NASCET figure is measured this many region radii from the
/// region's centre (just outside D, on both sides).
pub const NASCET_OFFSET: f64 = 1.15;

/// One region D of the report.
#[derive(Debug, Clone, Serialize)]
pub struct RegionReport {
    /// Centre, world units.
    pub center: [f64; 3],
    /// Radius, world units.
    pub radius: f64,
    /// Where the region came from (`region`, `regions-file`, `picked point`, `hole`).
    pub source: String,
    /// Volume of the output minus that of the input inside D, world units³.
    pub inpainted_volume: f64,
    /// `inpainted_volume` over the whole output volume.
    pub inpainted_fraction: f64,
    /// Volume of the input inside D, world units³.
    pub input_volume_in_region: f64,
    /// Volume of the output inside D, world units³.
    pub output_volume_in_region: f64,
    /// (1 − min input diameter / output diameter at that section) × 100; None when no
    /// cross-section of the vessel could be taken in D.
    pub diameter_stenosis_pct: Option<f64>,
    /// (1 − min input area / output area at that section) × 100.
    pub area_stenosis_pct: Option<f64>,
    /// (1 − min input diameter / diameter of the adjacent normal segment outside D) × 100.
    pub nascet_stenosis_pct: Option<f64>,
    /// Smallest equivalent diameter of the input's lumen in D, world units.
    pub min_input_diameter: Option<f64>,
    /// Equivalent diameter of the output at the same section, world units.
    pub output_diameter_at_min: Option<f64>,
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

/// The measures of the report, from the mesh's [`MeshInfo`].
pub fn surface_measures(info: &MeshInfo) -> SurfaceMeasures {
    SurfaceMeasures {
        volume: info.signed_volume,
        components: info.components,
        boundary_edges: info.boundary_edges,
    }
}

/// The per-region figures for `balls` (with their `sources`), `input` being the measured input
/// (capped) and `output` the repaired mesh.
pub fn region_reports(
    input: &TriMesh,
    output: &TriMesh,
    balls: &[Ball],
    sources: &[String],
) -> Vec<RegionReport> {
    let opts = WindingOptions::default();
    let win_in = WindingNumber::new(input, opts);
    let win_out = WindingNumber::new(output, opts);
    let total = signed_volume(output);
    balls
        .iter()
        .enumerate()
        .map(|(k, ball)| {
            let vin = volume_in_ball_with(input, &win_in, ball);
            let vout = volume_in_ball_with(output, &win_out, ball);
            let stenosis = measure_stenosis_with(
                input,
                &win_in,
                output,
                &win_out,
                ball,
                &StenosisOptions {
                    normal_offset: NASCET_OFFSET,
                    ..StenosisOptions::default()
                },
            );
            let (s, note) = match stenosis {
                Ok(s) => (Some(s), None),
                Err(e) => (None, Some(e.to_string())),
            };
            RegionReport {
                center: [ball.center.x, ball.center.y, ball.center.z],
                radius: ball.radius,
                source: sources.get(k).cloned().unwrap_or_else(|| "region".into()),
                inpainted_volume: vout - vin,
                inpainted_fraction: if total > 0.0 {
                    (vout - vin) / total
                } else {
                    0.0
                },
                input_volume_in_region: vin,
                output_volume_in_region: vout,
                diameter_stenosis_pct: s.as_ref().map(|s| s.diameter_stenosis_pct),
                area_stenosis_pct: s.as_ref().map(|s| s.area_stenosis_pct),
                nascet_stenosis_pct: s.as_ref().and_then(|s| s.nascet_stenosis_pct),
                min_input_diameter: s.as_ref().map(|s| s.min_input_diameter),
                output_diameter_at_min: s.as_ref().map(|s| s.output_diameter_at_min),
                stenosis_note: note,
            }
        })
        .collect()
}
