//! The centreline picture: the mesh's vertices in light grey seen along each axis (three
//! panels: x–y, x–z, y–z, equal scales), each branch as a coloured polyline with its id, the
//! junctions as black dots, the open ends as red triangles and the closed ends as blue crosses.
//! A quick look that needs no viewer (the `.vtp` is for ParaView and 3D Slicer).

use super::image::RgbImage;
use super::text::{drawing_error, ensure_font, format_value, FAMILY};
use crate::centerline::Centerline;
use crate::{Error, Result, TriMesh};
use plotters::prelude::*;

const MESH: RGBColor = RGBColor(205, 205, 205);
const OPEN_END: RGBColor = RGBColor(204, 0, 0);
const CLOSED_END: RGBColor = RGBColor(32, 74, 135);
/// Branch colours, in turn.
const BRANCH: [RGBColor; 6] = [
    RGBColor(52, 101, 164),
    RGBColor(245, 121, 0),
    RGBColor(78, 154, 6),
    RGBColor(117, 80, 123),
    RGBColor(193, 125, 17),
    RGBColor(6, 152, 154),
];

/// Draws `centerline` over `mesh` (see the module docs), each panel `panel` pixels.
pub fn centerline_picture(
    mesh: &TriMesh,
    centerline: &Centerline,
    panel: (u32, u32),
) -> Result<RgbImage> {
    if mesh.vertices.is_empty() {
        return Err(Error::Geometry(
            "centreline picture: the mesh has no vertex".into(),
        ));
    }
    ensure_font()?;
    let (w, h) = (panel.0 * 3, panel.1);
    let mut image = RgbImage::new(w, h, [255, 255, 255]);
    // One scale for the three panels: the largest extent, centred per axis.
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in &mesh.vertices {
        for a in 0..3 {
            lo[a] = lo[a].min(v[a]);
            hi[a] = hi[a].max(v[a]);
        }
    }
    let half = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max) * 0.55;
    let range = |a: usize| {
        let c = 0.5 * (lo[a] + hi[a]);
        (c - half)..(c + half)
    };
    let names = ["x", "y", "z"];
    {
        let root = BitMapBackend::with_buffer(image.as_bytes_mut(), (w, h)).into_drawing_area();
        let cells = root.split_evenly((1, 3));
        for ((a, b), cell) in [(0usize, 1usize), (0, 2), (1, 2)]
            .into_iter()
            .zip(cells.iter())
        {
            let mut chart = ChartBuilder::on(cell)
                .caption(format!("{}–{}", names[a], names[b]), (FAMILY, 16))
                .margin(6)
                .x_label_area_size(30)
                .y_label_area_size(48)
                .build_cartesian_2d(range(a), range(b))
                .map_err(drawing_error)?;
            let tick = |v: &f64| format_value(*v);
            chart
                .configure_mesh()
                .disable_mesh()
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .label_style((FAMILY, 11))
                .draw()
                .map_err(drawing_error)?;
            let step = (mesh.vertices.len() / 20_000).max(1);
            chart
                .draw_series(
                    mesh.vertices
                        .iter()
                        .step_by(step)
                        .map(|v| Pixel::new((v[a], v[b]), MESH)),
                )
                .map_err(drawing_error)?;
            for br in &centerline.branches {
                let color = BRANCH[br.id % BRANCH.len()];
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        br.points.iter().map(|p| (p[a], p[b])).collect::<Vec<_>>(),
                        color.stroke_width(2),
                    )))
                    .map_err(drawing_error)?;
                let mid = br.points[br.points.len() / 2];
                chart
                    .draw_series(std::iter::once(Text::new(
                        br.id.to_string(),
                        (mid[a], mid[b]),
                        (FAMILY, 13).into_font().color(&color),
                    )))
                    .map_err(drawing_error)?;
            }
            chart
                .draw_series(
                    centerline
                        .junctions
                        .iter()
                        .map(|j| Circle::new((j.position[a], j.position[b]), 4, BLACK.filled())),
                )
                .map_err(drawing_error)?;
            for e in &centerline.endpoints {
                let at = (e.position[a], e.position[b]);
                if e.open_end {
                    chart
                        .draw_series(std::iter::once(TriangleMarker::new(
                            at,
                            6,
                            OPEN_END.filled(),
                        )))
                        .map_err(drawing_error)?;
                } else {
                    chart
                        .draw_series(std::iter::once(Cross::new(
                            at,
                            5,
                            CLOSED_END.stroke_width(2),
                        )))
                        .map_err(drawing_error)?;
                }
            }
        }
        root.present().map_err(drawing_error)?;
    }
    Ok(image)
}
