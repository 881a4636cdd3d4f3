//! The diameter profile picture: one panel per centreline branch, the equivalent diameter
//! (cross-section area) and the inscribed diameter against the arc length, the local healthy
//! reference of the narrowing search dashed, and each lesion marked with its degree. Drawn with
//! `plotters` on its bitmap backend, as the histograms are.

use super::image::RgbImage;
use super::text::{drawing_error, ensure_font, format_value, FAMILY};
use crate::centerline::profile::BranchProfile;
use crate::centerline::stenosis::{BranchNarrowing, Lesion};
use crate::{Error, Result};
use plotters::prelude::*;

const EQUIVALENT: RGBColor = RGBColor(52, 101, 164);
const INSCRIBED: RGBColor = RGBColor(115, 210, 22);
const REFERENCE: RGBColor = RGBColor(120, 120, 120);
const LESION: RGBColor = RGBColor(204, 0, 0);

/// Draws the profiles (see the module docs), two panels to a row, each `panel` pixels, with
/// lengths labelled in `units` (e.g. "mm"; empty for none).
pub fn profile_picture(
    profiles: &[BranchProfile],
    narrowing: &[BranchNarrowing],
    lesions: &[Lesion],
    units: &str,
    panel: (u32, u32),
) -> Result<RgbImage> {
    if profiles.is_empty() {
        return Err(Error::Geometry("profile picture: no branch to draw".into()));
    }
    ensure_font()?;
    let columns = profiles.len().min(2);
    let rows = profiles.len().div_ceil(columns);
    let (w, h) = (panel.0 * columns as u32, panel.1 * rows as u32);
    let mut image = RgbImage::new(w, h, [255, 255, 255]);
    let unit = if units.is_empty() {
        String::new()
    } else {
        format!(" ({units})")
    };
    {
        let root = BitMapBackend::with_buffer(image.as_bytes_mut(), (w, h)).into_drawing_area();
        let cells = root.split_evenly((rows, columns));
        for (prof, cell) in profiles.iter().zip(cells.iter()) {
            let s_max = prof.points.last().map_or(1.0, |p| p.s).max(1e-12);
            let d_max = prof
                .points
                .iter()
                .flat_map(|p| [p.inscribed_diameter, p.equivalent_diameter.unwrap_or(0.0)])
                .fold(0.0, f64::max)
                .max(1e-12)
                * 1.15;
            let mut chart = ChartBuilder::on(cell)
                .caption(format!("branch {}", prof.branch), (FAMILY, 18))
                .margin(6)
                .margin_right(14)
                .x_label_area_size(40)
                .y_label_area_size(56)
                .build_cartesian_2d(0.0..s_max, 0.0..d_max)
                .map_err(drawing_error)?;
            let tick = |v: &f64| format_value(*v);
            chart
                .configure_mesh()
                .x_desc(format!("arc length{unit}"))
                .y_desc(format!("diameter{unit}"))
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .label_style((FAMILY, 13))
                .draw()
                .map_err(drawing_error)?;
            // The equivalent diameter where measured, in runs.
            let mut run = Vec::new();
            let mut runs = Vec::new();
            for p in &prof.points {
                match p.equivalent_diameter {
                    Some(d) => run.push((p.s, d)),
                    None => {
                        if !run.is_empty() {
                            runs.push(std::mem::take(&mut run));
                        }
                    }
                }
            }
            runs.push(run);
            for (k, r) in runs.into_iter().filter(|r| !r.is_empty()).enumerate() {
                let series = chart
                    .draw_series(LineSeries::new(r, EQUIVALENT.stroke_width(2)))
                    .map_err(drawing_error)?;
                if k == 0 {
                    series.label("equivalent").legend(|(x, y)| {
                        PathElement::new([(x, y), (x + 16, y)], EQUIVALENT.stroke_width(2))
                    });
                }
            }
            chart
                .draw_series(LineSeries::new(
                    prof.points.iter().map(|p| (p.s, p.inscribed_diameter)),
                    INSCRIBED.stroke_width(1),
                ))
                .map_err(drawing_error)?
                .label("inscribed")
                .legend(|(x, y)| {
                    PathElement::new([(x, y), (x + 16, y)], INSCRIBED.stroke_width(1))
                });
            let reference: Vec<(f64, f64)> = narrowing
                .iter()
                .find(|n| n.branch == prof.branch)
                .map(|n| {
                    n.reference
                        .iter()
                        .zip(&prof.points)
                        .filter_map(|(r, p)| r.map(|r| (p.s, r.local)))
                        .collect()
                })
                .unwrap_or_default();
            if !reference.is_empty() {
                chart
                    .draw_series(DashedLineSeries::new(
                        reference,
                        6,
                        4,
                        REFERENCE.stroke_width(1),
                    ))
                    .map_err(drawing_error)?
                    .label("reference")
                    .legend(|(x, y)| {
                        PathElement::new([(x, y), (x + 16, y)], REFERENCE.stroke_width(1))
                    });
            }
            for l in lesions.iter().filter(|l| l.branch == prof.branch) {
                chart
                    .draw_series([Circle::new((l.s, l.min_diameter), 4, LESION.filled())])
                    .map_err(drawing_error)?;
                chart
                    .draw_series([Text::new(
                        format!("{:.0}%", l.diameter_stenosis_pct),
                        (l.s, l.min_diameter * 0.8),
                        (FAMILY, 14).into_font().color(&LESION),
                    )])
                    .map_err(drawing_error)?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .label_font((FAMILY, 12))
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK.mix(0.3))
                .draw()
                .map_err(drawing_error)?;
        }
        root.present().map_err(drawing_error)?;
    }
    Ok(image)
}
