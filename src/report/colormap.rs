//! Colour maps for scalar fields on surfaces: a diverging blue–white–red map for signed details
//! (ColorBrewer's 5-class RdBu colours, negative = blue, positive = red, zero = near white) and a
//! sequential map for one-signed values (viridis, sampled at 9 stops). Both interpolate linearly
//! between their stops in sRGB and clamp values outside their range to the end colours.
//!
//! The automatic ranges are robust: the 99th percentile of |w| for the diverging map (symmetric
//! about 0, so zero stays white) and the 1st–99th percentiles for the sequential one, so a few
//! outlying values do not wash out the rest of the picture.

/// Stops of the diverging map at t = −1, −½, 0, ½, 1 (ColorBrewer RdBu, reversed so that
/// negative is blue).
const DIVERGING: [[u8; 3]; 5] = [
    [33, 102, 172],
    [146, 197, 222],
    [247, 247, 247],
    [244, 165, 130],
    [178, 24, 43],
];

/// Stops of the sequential map at t = 0, ⅛, …, 1 (viridis).
const SEQUENTIAL: [[u8; 3]; 9] = [
    [68, 1, 84],
    [71, 45, 123],
    [59, 82, 139],
    [44, 114, 142],
    [33, 145, 140],
    [39, 173, 129],
    [92, 200, 99],
    [170, 220, 50],
    [253, 231, 37],
];

/// The colour given to values that are not numbers (NaN): a neutral grey.
pub const NAN_COLOR: [u8; 3] = [128, 128, 128];

/// Which colour map a scalar field is drawn with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ColorMap {
    /// Blue (negative) – white (zero) – red (positive), for signed details.
    #[default]
    Diverging,
    /// Dark violet (low) to yellow (high), for one-signed values.
    Sequential,
}

/// Piecewise-linear interpolation of `stops` (equally spaced over [0, 1]) at `s`, clamped.
fn interpolate(stops: &[[u8; 3]], s: f64) -> [u8; 3] {
    let n = stops.len() - 1;
    let s = s.clamp(0.0, 1.0) * n as f64;
    let i = (s.floor() as usize).min(n - 1);
    let f = s - i as f64;
    let (a, b) = (stops[i], stops[i + 1]);
    let mix = |k: usize| (a[k] as f64 + (b[k] as f64 - a[k] as f64) * f).round() as u8;
    [mix(0), mix(1), mix(2)]
}

/// The diverging colour of `t` ∈ [−1, 1] (clamped): −1 is dark blue, 0 near white, +1 dark red.
pub fn diverging(t: f64) -> [u8; 3] {
    if t.is_nan() {
        return NAN_COLOR;
    }
    interpolate(&DIVERGING, (t + 1.0) / 2.0)
}

/// The sequential colour of `t` ∈ [0, 1] (clamped): 0 is dark violet, 1 yellow.
pub fn sequential(t: f64) -> [u8; 3] {
    if t.is_nan() {
        return NAN_COLOR;
    }
    interpolate(&SEQUENTIAL, t)
}

/// The `q`-quantile (0 ≤ q ≤ 1, nearest rank) of the finite values of `values`, or `None` when
/// there is none.
pub fn quantile(values: impl IntoIterator<Item = f64>, q: f64) -> Option<f64> {
    let mut v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    let k = ((q.clamp(0.0, 1.0) * (v.len() - 1) as f64).round() as usize).min(v.len() - 1);
    let (_, x, _) = v.select_nth_unstable_by(k, f64::total_cmp);
    Some(*x)
}

impl ColorMap {
    /// The colour of `value` on the range `(lo, hi)`: for the diverging map `lo` goes to blue,
    /// the middle of the range to white and `hi` to red; for the sequential map `lo` to violet
    /// and `hi` to yellow. Values outside the range take the end colours; NaN is grey.
    pub fn color(self, value: f64, (lo, hi): (f64, f64)) -> [u8; 3] {
        let span = hi - lo;
        let s = if span > 0.0 && span.is_finite() {
            (value - lo) / span
        } else {
            // A range of one value: every number is the middle colour (NaN stays NaN: grey).
            if value.is_nan() {
                f64::NAN
            } else {
                0.5
            }
        };
        match self {
            ColorMap::Diverging => diverging(2.0 * s - 1.0),
            ColorMap::Sequential => sequential(s),
        }
    }

    /// The automatic range of `values` for this map: `(−a, a)` with `a` the 99th percentile of
    /// |value| for the diverging map, the 1st and 99th percentiles for the sequential one. NaN
    /// and infinite values are ignored; without finite values, or with a range of zero width, it
    /// falls back to a unit-width range about the values.
    pub fn auto_range(self, values: &[f64]) -> (f64, f64) {
        match self {
            ColorMap::Diverging => {
                let a = quantile(values.iter().map(|v| v.abs()), 0.99).unwrap_or(0.0);
                if a > 0.0 {
                    (-a, a)
                } else {
                    (-1.0, 1.0)
                }
            }
            ColorMap::Sequential => {
                let lo = quantile(values.iter().copied(), 0.01);
                let hi = quantile(values.iter().copied(), 0.99);
                match (lo, hi) {
                    (Some(lo), Some(hi)) if hi > lo => (lo, hi),
                    (Some(lo), _) => (lo - 0.5, lo + 0.5),
                    _ => (0.0, 1.0),
                }
            }
        }
    }
}
