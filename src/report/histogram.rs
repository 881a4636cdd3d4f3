//! Histograms of the scalar detail w_i per level as small multiples in a grid, the picture of
//! Figure 2 of Dong, Chien, Shen and Osher (the details concentrate at 0, more so at later
//! levels). Drawn with `plotters` on its bitmap backend into an [`RgbImage`]: one panel per
//! level with its label as caption, ticks and axis labels (values in units of the voxel size h,
//! sample counts), a shared value range (symmetric about 0, with an odd number of bins so one
//! bin is centred on 0) and, by default, a shared count axis, so that panels compare at a
//! glance. Each panel also states the number of samples, mean |w| and the fraction of
//! |w| below a threshold (the sparsity).

use super::colormap::quantile;
use super::image::RgbImage;
use super::text::{
    draw_text, drawing_error, ensure_font, format_value, text_width, HAlign, FAMILY,
};
use crate::{Error, Result};
use plotters::prelude::*;

/// Colour of the bars.
pub const BAR_COLOR: [u8; 3] = [52, 101, 164];

/// Counts of values in equal bins over [lo, hi].
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    pub lo: f64,
    pub hi: f64,
    /// Count per bin; bin i covers [lo + i·Δ, lo + (i+1)·Δ), the last one includes `hi`.
    pub counts: Vec<u64>,
    /// Finite values below `lo`.
    pub below: u64,
    /// Finite values above `hi`.
    pub above: u64,
    /// NaN and infinite values (not counted anywhere else).
    pub not_finite: u64,
}

impl Histogram {
    /// Width Δ of one bin.
    pub fn bin_width(&self) -> f64 {
        (self.hi - self.lo) / self.counts.len() as f64
    }

    /// Centre of bin `i`.
    pub fn bin_center(&self, i: usize) -> f64 {
        self.lo + (i as f64 + 0.5) * self.bin_width()
    }

    /// The index of the fullest bin (the first of equals), `None` if every bin is empty.
    pub fn tallest(&self) -> Option<usize> {
        let max = *self.counts.iter().max()?;
        (max > 0).then(|| self.counts.iter().position(|&c| c == max).unwrap_or(0))
    }
}

/// Counts `values` in `bins` equal bins over [lo, hi] (at least one bin; an empty or reversed
/// range becomes the unit range about `lo`).
pub fn histogram(values: &[f64], lo: f64, hi: f64, bins: usize) -> Histogram {
    let bins = bins.max(1);
    let (lo, hi) = if lo.is_finite() && hi.is_finite() && hi > lo {
        (lo, hi)
    } else if lo.is_finite() {
        (lo - 0.5, lo + 0.5)
    } else {
        (-0.5, 0.5)
    };
    let mut h = Histogram {
        lo,
        hi,
        counts: vec![0; bins],
        below: 0,
        above: 0,
        not_finite: 0,
    };
    for &v in values {
        if !v.is_finite() {
            h.not_finite += 1;
        } else if v < lo {
            h.below += 1;
        } else if v > hi {
            h.above += 1;
        } else {
            let i = (((v - lo) / (hi - lo)) * bins as f64) as usize;
            h.counts[i.min(bins - 1)] += 1;
        }
    }
    h
}

/// How the histogram grid is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct HistogramOptions {
    /// Width of one panel in pixels.
    pub panel_width: u32,
    /// Height of one panel in pixels.
    pub panel_height: u32,
    /// Panels per row (the paper's Figure 2 has its 5 levels in one row).
    pub columns: usize,
    /// Number of bins; an odd number puts one bin centred on 0.
    pub bins: usize,
    /// The unit the values are shown in, in the values' own (world) units: the voxel size h, so
    /// the axis reads w / h. 1 shows the raw values.
    pub unit: f64,
    /// Name of the unit for the axis label ("h"); empty for raw values.
    pub unit_name: String,
    /// Half-width of the value axis, in `unit`s (the axis is [−a, a]); `None` takes the 99.5th
    /// percentile of |w| over all levels, rounded up to 1, 2, 2.5 or 5 times a power of ten.
    /// Values beyond it are counted and reported in the panel, not drawn.
    pub half_range: Option<f64>,
    /// One count axis for all panels (true) or one per panel.
    pub shared_counts: bool,
    /// The sparsity threshold in `unit`s: each panel states the fraction of |w| below it.
    pub sparse_threshold: f64,
}

impl Default for HistogramOptions {
    fn default() -> Self {
        HistogramOptions {
            panel_width: 320,
            panel_height: 280,
            columns: 5,
            bins: 41,
            unit: 1.0,
            unit_name: "h".to_string(),
            half_range: None,
            shared_counts: true,
            sparse_threshold: 0.1,
        }
    }
}

/// One drawn panel: its label, the histogram of the values in units, and where its plotting
/// area is in the image (pixel columns `x.0..x.1`, rows `y.0..y.1`; x maps linearly from
/// `histogram.lo` to `histogram.hi`, y from the top count down to 0).
#[derive(Clone, Debug, PartialEq)]
pub struct HistogramPanel {
    pub label: String,
    pub histogram: Histogram,
    /// The count at the top of the plotting area.
    pub count_max: f64,
    pub x: (i32, i32),
    pub y: (i32, i32),
}

/// The drawn grid and the layout of its panels.
#[derive(Clone, Debug, PartialEq)]
pub struct HistogramFigure {
    pub image: RgbImage,
    pub panels: Vec<HistogramPanel>,
}

/// `x` rounded up to 1, 2, 2.5 or 5 times a power of ten.
fn nice_ceil(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|&v| v >= x * (1.0 - 1e-12))
        .unwrap_or(10.0 * p)
}

/// Pixel size of the panel notes: line height and the gap kept above the tallest bar.
const NOTE_SIZE: f64 = 13.0;
const NOTE_LINE: i32 = 16;

/// The chart frame of one panel (caption, margins, label areas) on `cell`, scaled to the
/// value axis [−half, half] and the count axis [0, count_max].
fn build_chart<'a, DB: DrawingBackend>(
    cell: &DrawingArea<DB, plotters::coord::Shift>,
    label: &str,
    half: f64,
    count_max: f64,
) -> Result<
    ChartContext<
        'a,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
> {
    ChartBuilder::on(cell)
        .caption(label, (FAMILY, 18))
        .margin(6)
        .margin_right(14)
        .x_label_area_size(40)
        .y_label_area_size(52)
        .build_cartesian_2d(-half..half, 0.0..count_max)
        .map_err(drawing_error)
}

/// Draws one histogram per level (`(label, values)`, values in world units) as small multiples,
/// `opts.columns` to a row. The count axis leaves room above the tallest bar for the panel's
/// notes. Fails if there is no level or the unit is not a positive number.
pub fn histogram_grid(
    levels: &[(String, Vec<f64>)],
    opts: &HistogramOptions,
) -> Result<HistogramFigure> {
    if levels.is_empty() {
        return Err(Error::Geometry("histogram grid: no level to draw".into()));
    }
    if !(opts.unit.is_finite() && opts.unit > 0.0) {
        return Err(Error::Geometry(format!(
            "histogram grid: the unit must be a positive length, got {}",
            opts.unit
        )));
    }
    ensure_font()?;
    let scaled: Vec<Vec<f64>> = levels
        .iter()
        .map(|(_, v)| v.iter().map(|x| x / opts.unit).collect())
        .collect();
    let half = match opts.half_range {
        Some(a) if a.is_finite() && a > 0.0 => a,
        _ => nice_ceil(quantile(scaled.iter().flatten().map(|v| v.abs()), 0.995).unwrap_or(1.0)),
    };
    let hists: Vec<Histogram> = scaled
        .iter()
        .map(|v| histogram(v, -half, half, opts.bins))
        .collect();
    let unit = if opts.unit_name.is_empty() {
        String::new()
    } else {
        format!(" {}", opts.unit_name)
    };
    let notes: Vec<Vec<String>> = scaled
        .iter()
        .zip(&hists)
        .map(|(values, hist)| {
            let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
            let n = finite.len();
            let mean_abs = finite.iter().map(|v| v.abs()).sum::<f64>() / n.max(1) as f64;
            let sparse = finite
                .iter()
                .filter(|v| v.abs() < opts.sparse_threshold)
                .count() as f64
                / n.max(1) as f64;
            let mut lines = vec![
                format!("n = {n}"),
                format!("mean |w| = {}{unit}", format_value(mean_abs)),
                format!(
                    "|w| < {}{unit}: {:.0}%",
                    format_value(opts.sparse_threshold),
                    100.0 * sparse
                ),
            ];
            let beyond = hist.below + hist.above;
            if beyond > 0 {
                lines.push(format!("{beyond} beyond ±{}", format_value(half)));
            }
            lines
        })
        .collect();

    let columns = opts.columns.clamp(1, levels.len());
    let rows = levels.len().div_ceil(columns);
    let (cell_w, cell_h) = (opts.panel_width.max(120), opts.panel_height.max(120));
    let (width, height) = (cell_w * columns as u32, cell_h * rows as u32);

    // The plotting area's height, from the same frame drawn on a scratch cell: the count axis
    // is stretched so the tallest bar stays below the notes.
    let plot_h = {
        let mut scratch = vec![255u8; cell_w as usize * cell_h as usize * 3];
        let area = BitMapBackend::with_buffer(&mut scratch, (cell_w, cell_h)).into_drawing_area();
        let chart = build_chart(&area, "level", 1.0, 1.0)?;
        let (_, yr) = chart.plotting_area().get_pixel_range();
        (yr.end - yr.start).max(1) as f64
    };
    let top = |h: &Histogram, lines: usize| {
        let reserve = (NOTE_LINE as f64 * lines as f64 + 8.0).min(0.6 * plot_h);
        (*h.counts.iter().max().unwrap_or(&0)).max(1) as f64 * plot_h / (plot_h - reserve)
    };
    let max_lines = notes.iter().map(Vec::len).max().unwrap_or(0);
    let shared_top = hists.iter().map(|h| top(h, max_lines)).fold(1.0, f64::max);

    let mut image = RgbImage::new(width, height, [255, 255, 255]);
    let x_desc = if opts.unit_name.is_empty() {
        "w".to_string()
    } else {
        format!("w / {}", opts.unit_name)
    };
    let mut panels = Vec::with_capacity(levels.len());
    {
        let root =
            BitMapBackend::with_buffer(image.as_bytes_mut(), (width, height)).into_drawing_area();
        let cells = root.split_evenly((rows, columns));
        for (((label, _), hist), (cell, lines)) in
            levels.iter().zip(hists).zip(cells.iter().zip(&notes))
        {
            let count_max = if opts.shared_counts {
                shared_top
            } else {
                top(&hist, lines.len())
            };
            let mut chart = build_chart(cell, label, half, count_max)?;
            let tick = |v: &f64| format_value(*v);
            let count_tick = |v: &f64| format!("{:.0}", v);
            chart
                .configure_mesh()
                .disable_x_mesh()
                .y_max_light_lines(1)
                .light_line_style(RGBColor(238, 238, 238))
                .bold_line_style(RGBColor(215, 215, 215))
                .x_labels(5)
                .y_labels(5)
                .x_label_formatter(&tick)
                .y_label_formatter(&count_tick)
                .label_style((FAMILY, 13))
                .axis_desc_style((FAMILY, 14))
                .x_desc(x_desc.as_str())
                .y_desc("count")
                .draw()
                .map_err(drawing_error)?;
            let bar = RGBColor(BAR_COLOR[0], BAR_COLOR[1], BAR_COLOR[2]);
            chart
                .draw_series(hist.counts.iter().enumerate().filter(|(_, &c)| c > 0).map(
                    |(i, &c)| {
                        let x0 = hist.lo + i as f64 * hist.bin_width();
                        let x1 = x0 + hist.bin_width();
                        Rectangle::new([(x0, 0.0), (x1, c as f64)], bar.filled())
                    },
                ))
                .map_err(drawing_error)?;
            let (xr, yr) = chart.plotting_area().get_pixel_range();
            panels.push(HistogramPanel {
                label: label.clone(),
                histogram: hist,
                count_max,
                x: (xr.start, xr.end),
                y: (yr.start, yr.end),
            });
        }
        root.present().map_err(drawing_error)?;
    }
    for (panel, lines) in panels.iter().zip(&notes) {
        for (k, line) in lines.iter().enumerate() {
            // A white backdrop keeps grid lines from crossing the text.
            let (x, y) = (panel.x.1 - 4, panel.y.0 + 4 + NOTE_LINE * k as i32);
            let w = text_width(line, NOTE_SIZE).ceil() as i64;
            image.fill_rect(
                x as i64 - w - 2,
                y as i64,
                w + 6,
                NOTE_LINE as i64,
                [255; 3],
            );
            draw_text(
                &mut image,
                line,
                x,
                y,
                NOTE_SIZE,
                [40, 40, 40],
                HAlign::Right,
            )?;
        }
    }
    Ok(HistogramFigure { image, panels })
}
