//! Text on figures, with no system font, fontconfig or FreeType: the typeface Noto Sans Regular
//! from the `notosans` crate is embedded in the binary (SIL Open Font License 1.1 as the crate
//! distributes it, Apache-2.0 by the font's own name table; the notice and licence text are in
//! `src/report/NOTO_SANS_LICENSE.txt`). Free text (titles, colour-bar labels, panel notes) is laid out and rasterised here
//! with `ab_glyph` (advances, kerning, side bearings, anti-aliased coverage blended over the
//! image); chart axes go through `plotters`, for which the same font is registered once under
//! the family name "sans-serif". Numbers on figures are written by [`format_value`].

use super::image::RgbImage;
use crate::{Error, Result};
use ab_glyph::{point, Font, FontRef, PxScale, ScaleFont};
use std::sync::OnceLock;

/// The family name the embedded font is registered under with plotters.
pub(crate) const FAMILY: &str = "sans-serif";

/// The embedded font, parsed once.
fn font() -> Result<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(notosans::REGULAR_TTF).ok())
        .as_ref()
        .ok_or_else(|| Error::Geometry("figure text: the embedded font could not be read".into()))
}

/// Registers the embedded font with plotters (once per process).
pub(crate) fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(
            FAMILY,
            plotters::style::FontStyle::Normal,
            notosans::REGULAR_TTF,
        )
        .is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Geometry(
            "figure text: the embedded font could not be registered".into(),
        ))
    }
}

/// A plotters drawing error as a library error.
pub(crate) fn drawing_error(e: impl std::fmt::Display) -> Error {
    Error::Geometry(format!("figure drawing failed: {e}"))
}

/// Horizontal placement of a text relative to its anchor point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum HAlign {
    Left,
    Center,
    Right,
}

/// The advance width in pixels of `text` at `size` pixels (0 if the font is unusable).
pub(crate) fn text_width(text: &str, size: f64) -> f64 {
    let Ok(font) = font() else {
        return 0.0;
    };
    let scaled = font.as_scaled(PxScale::from(size as f32));
    let mut width = 0.0f32;
    let mut prev = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = prev {
            width += scaled.kern(p, id);
        }
        width += scaled.h_advance(id);
        prev = Some(id);
    }
    width as f64
}

/// Draws `text` of `size` pixels (the font's ascent-to-descent height) in `color` with the top
/// of the line at row `y`, anchored at column `x` as `align` says; anti-aliased, blended over
/// the image, clipped at its edges.
pub(crate) fn draw_text(
    image: &mut RgbImage,
    text: &str,
    x: i32,
    y: i32,
    size: f64,
    color: [u8; 3],
    align: HAlign,
) -> Result<()> {
    let font = font()?;
    if !(size.is_finite() && size > 0.0) {
        return Ok(());
    }
    let scaled = font.as_scaled(PxScale::from(size as f32));
    let width = text_width(text, size) as f32;
    let mut caret = x as f32
        - match align {
            HAlign::Left => 0.0,
            HAlign::Center => 0.5 * width,
            HAlign::Right => width,
        };
    let baseline = y as f32 + scaled.ascent();
    let (w, h) = (image.width as i64, image.height as i64);
    let mut prev = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = prev {
            caret += scaled.kern(p, id);
        }
        let glyph = id.with_scale_and_position(scaled.scale(), point(caret, baseline));
        if let Some(outline) = scaled.outline_glyph(glyph) {
            let bounds = outline.px_bounds();
            outline.draw(|gx, gy, coverage| {
                let px = bounds.min.x as i64 + gx as i64;
                let py = bounds.min.y as i64 + gy as i64;
                if px < 0 || py < 0 || px >= w || py >= h {
                    return;
                }
                let a = coverage.clamp(0.0, 1.0);
                let pixel = &mut image.pixels[(py * w + px) as usize];
                for k in 0..3 {
                    let mixed = pixel[k] as f32 * (1.0 - a) + color[k] as f32 * a;
                    pixel[k] = mixed.round().clamp(0.0, 255.0) as u8;
                }
            });
        }
        caret += scaled.h_advance(id);
        prev = Some(id);
    }
    Ok(())
}

/// A figure written on a picture: 4 significant digits, in exponent form below 0.01 or from a
/// million on (a vessel in metres has volumes of some 1e-6 m³, which one decimal shows as 0.0).
pub(crate) fn format_figure(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let magnitude = v.abs().log10().floor();
    if !(-2.0..6.0).contains(&magnitude) {
        return format!("{v:.3e}");
    }
    let decimals = (3.0 - magnitude).max(0.0) as usize;
    format!("{v:.decimals$}")
}

/// A short decimal form of a tick value (3 significant digits, no "-0").
pub(crate) fn format_value(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_nan() { "NaN".into() } else { "0".into() };
    }
    let digits = (2 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.digits$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_keep_four_significant_digits() {
        assert_eq!(format_figure(11779.93), "11780");
        assert_eq!(format_figure(945.84), "945.8");
        assert_eq!(format_figure(0.25), "0.2500");
        assert_eq!(format_figure(1.2345e-6), "1.234e-6");
        assert_eq!(format_figure(-3.5e-7), "-3.500e-7");
        assert_eq!(format_figure(0.0), "0");
    }
}
