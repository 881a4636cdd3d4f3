//! Narrowings found automatically along each branch of a centreline, against a healthy reference
//! diameter (as NASCET compares the narrowest lumen with the normal one).
//!
//! Per branch, on its equivalent-diameter profile (`profile`; points without a section are not
//! used): the points within the branch's median radius of a closed or open end are left out
//! (the wall turns there), the diameters are median-filtered over about one
//! radius, and the healthy reference D_ref(s) = a + b·s is a robust straight-line fit: least
//! squares, refitted on the points within −5%/+30% of the last fit (narrowings and dilations
//! such as aneurysms leave the fit) until the kept set stops changing. A proximal and a distal
//! healthy segment around a lesion thus set its reference, and a tapering vessel keeps its taper.
//! The narrowing along the branch is 1 − D/D_ref; a lesion is a valley of it, deepest first (the
//! run where it exceeds half the valley's peak, then on while it keeps falling away from it), reported with its position (the narrowest point), minimum and
//! reference diameters, diameter stenosis (1 − D_min/D_ref) and area stenosis
//! (1 − A_min/A_ref, A_ref = π D_ref²/4) in percent, and length (that run's arc length).

use super::profile::BranchProfile;
use super::{Centerline, EndKind};
use serde::Serialize;

/// Options of [`find_stenoses`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StenosisFindOptions {
    /// Smallest diameter stenosis reported as a lesion, percent (default 10).
    pub min_degree_pct: f64,
}

impl Default for StenosisFindOptions {
    fn default() -> Self {
        StenosisFindOptions {
            min_degree_pct: 10.0,
        }
    }
}

/// A narrowing found on a branch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Lesion {
    pub branch: usize,
    /// The narrowest point, world units.
    pub position: [f64; 3],
    /// Its arc length along the branch, world units.
    pub s: f64,
    /// Equivalent diameter there, world units.
    pub min_diameter: f64,
    /// Healthy reference diameter there, world units.
    pub reference_diameter: f64,
    /// (1 − min / reference) × 100.
    pub diameter_stenosis_pct: f64,
    /// (1 − area / reference area) × 100.
    pub area_stenosis_pct: f64,
    /// Arc length over which the narrowing exceeds half its largest value, world units.
    pub length: f64,
    /// Inscribed radius at the narrowest point, world units.
    pub inscribed_radius: f64,
}

/// The narrowing figures of one branch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BranchNarrowing {
    pub branch: usize,
    /// Points measured (with a section, away from the ends).
    pub measured: usize,
    /// Reference diameter fit: D_ref(s) = intercept + slope·s (None with too few points).
    pub reference_fit: Option<[f64; 2]>,
    /// Largest (1 − D/D_ref) × 100 over the branch (0 when none narrower than the reference).
    pub max_narrowing_pct: f64,
}

/// Lesions of every branch (sorted by degree, largest first) and each branch's figures.
pub fn find_stenoses(
    centerline: &Centerline,
    profiles: &[BranchProfile],
    opts: &StenosisFindOptions,
) -> (Vec<Lesion>, Vec<BranchNarrowing>) {
    let mut lesions = Vec::new();
    let mut figures = Vec::new();
    for prof in profiles {
        let b = &centerline.branches[prof.branch];
        let n = prof.points.len();
        let total = prof.points.last().map_or(0.0, |p| p.s);
        // Points away from the closed and open ends (by the branch's median radius), with a
        // section.
        let median_radius = {
            let mut r = b.radius.clone();
            r.sort_by(f64::total_cmp);
            r.get(r.len() / 2).copied().unwrap_or(0.0)
        };
        let idx: Vec<usize> = (0..n)
            .filter(|&i| {
                let p = &prof.points[i];
                let near = |kind: EndKind, d: f64| kind != EndKind::Junction && d < median_radius;
                p.equivalent_diameter.is_some() && !near(b.start, p.s) && !near(b.end, total - p.s)
            })
            .collect();
        let mut fig = BranchNarrowing {
            branch: prof.branch,
            measured: idx.len(),
            reference_fit: None,
            max_narrowing_pct: 0.0,
        };
        if idx.len() < 5 {
            figures.push(fig);
            continue;
        }
        let s: Vec<f64> = idx.iter().map(|&i| prof.points[i].s).collect();
        let raw: Vec<f64> = idx
            .iter()
            .map(|&i| prof.points[i].equivalent_diameter.unwrap_or(0.0))
            .collect();
        // Median filter over about one radius of arc.
        let spacing = (s[s.len() - 1] - s[0]) / (s.len() - 1).max(1) as f64;
        let median_r = {
            let mut r: Vec<f64> = raw.iter().map(|d| 0.5 * d).collect();
            r.sort_by(f64::total_cmp);
            r[r.len() / 2]
        };
        let half = ((0.5 * median_r / spacing.max(1e-300)).round() as usize).min(10);
        let d: Vec<f64> = (0..raw.len())
            .map(|k| {
                let lo = k.saturating_sub(half);
                let hi = (k + half + 1).min(raw.len());
                let mut w: Vec<f64> = raw[lo..hi].to_vec();
                w.sort_by(f64::total_cmp);
                w[w.len() / 2]
            })
            .collect();
        let Some([a, slope]) = robust_line(&s, &d) else {
            figures.push(fig);
            continue;
        };
        fig.reference_fit = Some([a, slope]);
        let narrowing: Vec<f64> = s
            .iter()
            .zip(&d)
            .map(|(&si, &di)| {
                let r = a + slope * si;
                if r > 0.0 {
                    1.0 - di / r
                } else {
                    0.0
                }
            })
            .collect();
        fig.max_narrowing_pct = narrowing.iter().cloned().fold(0.0, f64::max) * 100.0;
        figures.push(fig);

        // Lesions: runs above half their own peak, from the deepest down.
        let mut used = vec![false; narrowing.len()];
        while let Some((k, &peak)) = narrowing
            .iter()
            .enumerate()
            .filter(|(k, _)| !used[*k])
            .max_by(|a, b| a.1.total_cmp(b.1))
        {
            if peak * 100.0 < opts.min_degree_pct {
                break;
            }
            let mut lo = k;
            while lo > 0 && narrowing[lo - 1] > 0.5 * peak && !used[lo - 1] {
                lo -= 1;
            }
            let mut hi = k;
            while hi + 1 < narrowing.len() && narrowing[hi + 1] > 0.5 * peak && !used[hi + 1] {
                hi += 1;
            }
            // The whole valley is this lesion's: on from the half-peak run while the narrowing
            // keeps falling away from the peak.
            let (mut vlo, mut vhi) = (lo, hi);
            while vlo > 0 && !used[vlo - 1] && narrowing[vlo - 1] <= narrowing[vlo] {
                vlo -= 1;
            }
            while vhi + 1 < narrowing.len()
                && !used[vhi + 1]
                && narrowing[vhi + 1] <= narrowing[vhi]
            {
                vhi += 1;
            }
            for u in used.iter_mut().take(vhi + 1).skip(vlo) {
                *u = true;
            }
            let i = idx[k];
            let p = &prof.points[i];
            let dref = a + slope * s[k];
            let dmin = d[k];
            lesions.push(Lesion {
                branch: prof.branch,
                position: p.position,
                s: p.s,
                min_diameter: dmin,
                reference_diameter: dref,
                diameter_stenosis_pct: (1.0 - dmin / dref) * 100.0,
                area_stenosis_pct: (1.0 - (dmin / dref).powi(2)) * 100.0,
                length: s[hi] - s[lo],
                inscribed_radius: 0.5 * p.inscribed_diameter,
            });
        }
    }
    lesions.sort_by(|a, b| b.diameter_stenosis_pct.total_cmp(&a.diameter_stenosis_pct));
    (lesions, figures)
}

/// Least-squares line through (x, y), refitted on the points within −5% / +30% of the last fit
/// until the kept set stops changing (at most 20 rounds); None with fewer than 3 points kept or
/// all x equal.
pub fn robust_line(x: &[f64], y: &[f64]) -> Option<[f64; 2]> {
    let mut keep = vec![true; x.len()];
    let mut fit = None;
    for _ in 0..20 {
        let f = line_fit(x, y, &keep)?;
        let next: Vec<bool> = x
            .iter()
            .zip(y)
            .map(|(&xi, &yi)| {
                let r = f[0] + f[1] * xi;
                yi >= 0.95 * r && yi <= 1.3 * r
            })
            .collect();
        fit = Some(f);
        if next == keep || next.iter().filter(|&&k| k).count() < 3 {
            break;
        }
        keep = next;
    }
    fit
}

fn line_fit(x: &[f64], y: &[f64], keep: &[bool]) -> Option<[f64; 2]> {
    let (mut n, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for ((&xi, &yi), &k) in x.iter().zip(y).zip(keep) {
        if k {
            n += 1.0;
            sx += xi;
            sy += yi;
            sxx += xi * xi;
            sxy += xi * yi;
        }
    }
    if n < 3.0 {
        return None;
    }
    let det = n * sxx - sx * sx;
    if det.abs() <= 1e-12 * (n * sxx).abs().max(1e-300) {
        return Some([sy / n, 0.0]);
    }
    let slope = (n * sxy - sx * sy) / det;
    Some([(sy - slope * sx) / n, slope])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robust_line_ignores_a_narrowing_and_a_dilation() {
        let x: Vec<f64> = (0..100).map(|i| i as f64).collect();
        let y: Vec<f64> = x
            .iter()
            .map(|&s| {
                let healthy = 6.0 - 0.01 * s;
                if (40.0..50.0).contains(&s) {
                    healthy * 0.5
                } else if (70.0..75.0).contains(&s) {
                    healthy * 1.8
                } else {
                    healthy
                }
            })
            .collect();
        let [a, b] = robust_line(&x, &y).unwrap();
        assert!((a - 6.0).abs() < 1e-9 && (b + 0.01).abs() < 1e-9, "{a} {b}");
    }
}
