//! Narrowings found automatically along each branch of a centreline, against the healthy lumen
//! on either side of them (as NASCET and ECST compare the narrowest lumen with the normal one).
//!
//! Per branch, on its equivalent-diameter profile (`profile`; points without a section are not
//! used): the points within the branch's median radius of a closed or open end are left out
//! (the wall turns there), and the diameters are median-filtered over about one radius. At each
//! point the healthy lumen beyond it on each side (its *shoulder*) is the widest filtered
//! diameter met going outward, up to where the diameter falls 3% below it again (the nearest
//! healthy lumen, not a farther bulge), levels off after rising 5% from the point (under 1%
//! more over the next median radius: the lumen beside a lesion, not the widest one up the
//! vessel's taper or flare beyond it), rises slowest before quickening again (the lesion's
//! flank meeting a bulb's flare, see `QUICKEN`), or [`SHOULDER_REACH`] median diameters of
//! arc. A side whose reach runs past the measured points while the diameter is still rising
//! towards them (a junction's unmeasured flare, a branch end next to the lesion) has no known
//! shoulder; the other side's is used.
//! Two references follow from the shoulders:
//! - the *local* reference: the straight line between the two shoulders, read at the point —
//!   the vessel's own diameter there had it not narrowed (ECST's estimate of the original
//!   lumen), which keeps a tapering vessel's taper; the diameter stenosis is against it;
//! - the *normal* reference: the narrower shoulder. NASCET takes the normal lumen distal to the
//!   lesion, the narrower one in an artery that tapers downstream (which way the blood flows is
//!   not in a mesh); a dip before a widening (a bulb, a junction's flare, a taper) is not a
//!   narrowing against it, so lesions are found against this one.
//!
//! A lesion is a valley of the narrowing against the normal reference at least
//! [`StenosisFindOptions::min_degree_pct`] deep, deepest first (the points between its two
//! shoulders are then taken), reported with its position (the narrowest point: among the
//! sections the median filter read at the valley, the one narrowest against its local reference,
//! unfiltered, as the repair report takes it; the filter raises a short lesion's floor, a 50%
//! narrowing of σ = 0.6 radii read 43.9% from it and the stenosis phantom 48.3%), minimum and
//! local reference diameters, diameter stenosis (1 − D_min/D_ref) and area stenosis
//! (1 − A_min/A_ref, A_ref = π D_ref²/4) in percent, the NASCET-style degree against the normal
//! reference, and length (the arc length over which it is narrower than the local reference
//! line by more than half its depth).

use super::profile::BranchProfile;
use super::{Centerline, EndKind};
use serde::Serialize;

/// Each side's shoulder is looked for within this many of the branch's median diameters of arc.
pub const SHOULDER_REACH: f64 = 4.0;

/// A side's shoulder may be where the lumen levels off once it has risen this fraction above
/// the point's own diameter (a flat-bottomed lesion's floor is not a shoulder).
const RISEN: f64 = 0.05;
/// Levelled off: the diameter rises less than this fraction over the next median radius of arc.
/// On a Gaussian narrowing of σ = 1.2 radii that is 2.8σ out, where the lumen is 1% short of
/// the healthy one (1.5% stopped at 2.6σ, 1.6% short, and read the bench's aortas' 50%
/// stenoses as 45.1–45.4%).
const LEVEL_RISE: f64 = 0.01;
/// The rise over half a radius has slowed when it is this much below the steepest met going
/// out (the lesion's flank), and quickens again (a flare beyond the lesion) when it is this
/// much, and half as much again, above the slowest since: twice `LEVEL_RISE`, well above the
/// filtered profile's noise. (Half the flank's steepest, tried first, missed the slowing seen
/// from a point up the flank, where the steepest part is behind.)
const QUICKEN: f64 = 0.02;

/// Options of [`find_stenoses`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StenosisFindOptions {
    /// Smallest NASCET-style stenosis (against the narrower shoulder) reported as a lesion,
    /// percent (default 10).
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
    /// Local healthy reference diameter there (the line between the shoulders), world units.
    pub reference_diameter: f64,
    /// (1 − min / reference) × 100.
    pub diameter_stenosis_pct: f64,
    /// (1 − area / reference area) × 100.
    pub area_stenosis_pct: f64,
    /// The normal lumen beyond the lesion (the narrower shoulder), world units.
    pub normal_diameter: f64,
    /// (1 − min / normal) × 100, as NASCET.
    pub nascet_stenosis_pct: f64,
    /// Arc length over which the narrowing exceeds half its largest value, world units.
    pub length: f64,
    /// Inscribed radius at the narrowest point, world units.
    pub inscribed_radius: f64,
}

/// The healthy references at one profile point (see the module doc), world units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Reference {
    /// The line between the shoulders read at the point.
    pub local: f64,
    /// The narrower shoulder.
    pub normal: f64,
    /// The shoulders on the side of the branch's start and of its end (None: not known).
    pub shoulders: [Option<Shoulder>; 2],
}

/// A shoulder: the healthy lumen beside a point (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Shoulder {
    /// Its index among the branch's profile points.
    pub point: usize,
    /// Its arc length from the branch's first point, world units.
    pub s: f64,
    /// Its (median-filtered) equivalent diameter, world units.
    pub diameter: f64,
}

/// The narrowing figures of one branch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BranchNarrowing {
    pub branch: usize,
    /// Points measured (with a section, away from the ends).
    pub measured: usize,
    /// The references at every profile point (None where it is not measured or no shoulder is
    /// known).
    #[serde(skip)]
    pub reference: Vec<Option<Reference>>,
    /// Largest (1 − D/D_normal) × 100 over the branch (0 when none narrower than its normal
    /// reference).
    pub max_narrowing_pct: f64,
}

/// The filtered profile of one branch: measured point indices, arc lengths, diameters.
struct Filtered {
    idx: Vec<usize>,
    s: Vec<f64>,
    d: Vec<f64>,
    /// The unfiltered diameters.
    raw: Vec<f64>,
    /// The median filter's half width, in points.
    half: usize,
}

/// Shoulders of point `k` of (s, d): on each side, the widest point met going outward before
/// the diameter falls 3% below it again or `reach` of arc is passed (the nearest of equal
/// ones); None for a side cut short by the measured points while the diameter still rises
/// towards their edge (both kept when both are so: the best there is), so never both None.
fn shoulders(s: &[f64], d: &[f64], k: usize, reach: f64) -> (Option<usize>, Option<usize>) {
    // One median radius of arc (`reach` is SHOULDER_REACH median diameters).
    let radius = reach / (2.0 * SHOULDER_REACH);
    let side = |edge: usize| -> (usize, bool) {
        // The m-th point from k towards `edge`.
        let at = |m: usize| if edge < k { k - m } else { k + m };
        let len = k.abs_diff(edge);
        let mut best = k;
        // The points after the m-th within `window` of arc of it.
        let ahead = move |m: usize, window: f64| {
            let j = at(m);
            (m + 1..=len)
                .map(at)
                .take_while(move |&a| (s[a] - s[j]).abs() <= window)
        };
        // The relative rise over the next half radius from the m-th point (None where the
        // measured points stop short of 3/4 of it).
        let rise_ahead = |m: usize| -> Option<f64> {
            let (j, last) = (at(m), ahead(m, 0.5 * radius).last()?);
            ((s[at(len)] - s[j]).abs() >= 0.375 * radius).then(|| d[last] / d[j] - 1.0)
        };
        // The steepest rise met going out (the lesion's flank), and the slowest since, once
        // risen (point, rise).
        let mut steepest = 0.0_f64;
        let mut slowest: Option<(usize, f64)> = None;
        for m in 1..=len {
            let j = at(m);
            // Past the reach, or past the shoulder: fallen 3% below the widest so far (the
            // nearest healthy lumen, not a farther bulge of the vessel's natural variation).
            if (s[j] - s[k]).abs() > reach || (best != k && d[j] < 0.97 * d[best]) {
                return (best, true);
            }
            if d[j] > d[best] {
                best = j;
            }
            // Or levelled off: risen from the throat, and no longer rising (under
            // LEVEL_RISE over the next radius of arc, all of it measured). A vessel that
            // tapers or flares beyond its lesion's rim rises on, and the widest lumen met up
            // the taper, a reach away, is not the lumen beside the lesion.
            let risen = d[best] >= (1.0 + RISEN) * d[k];
            if risen {
                let covered = ahead(m, radius)
                    .last()
                    .is_some_and(|a| (s[a] - s[j]).abs() >= 0.75 * radius);
                if covered && ahead(m, radius).all(|a| d[a] < (1.0 + LEVEL_RISE) * d[best]) {
                    return (best, true);
                }
            }
            // Or where the rise, having slowed by QUICKEN from the flank's, quickens again (by
            // half and by QUICKEN at least): the flank has met a flare beyond the lesion
            // without levelling off, and the lumen beside the lesion is where it rose slowest.
            // A lesion's tail alone only slows outward.
            if let Some(rise) = rise_ahead(m) {
                if let Some((at_slowest, lo)) = slowest {
                    if risen && lo + QUICKEN <= steepest && rise >= (1.5 * lo).max(lo + QUICKEN) {
                        return (at_slowest, true);
                    }
                }
                if rise > steepest {
                    // Still on the flank, quickening towards its steepest.
                    steepest = rise;
                    slowest = None;
                } else if risen && slowest.map_or(true, |(_, lo)| rise < lo) {
                    slowest = Some((j, rise));
                }
            }
        }
        // Cut short by the edge: unknown when the widest lies within a quarter of the reach of
        // the edge and the diameter still rises into the edge (by 3% over the last radius).
        let near_edge = |j: usize| (s[j] - s[edge]).abs() <= 0.25 * reach;
        let inner = (0..s.len())
            .filter(|&j| (s[j] - s[edge]).abs() <= radius)
            .max_by(|&a, &b| (s[a] - s[edge]).abs().total_cmp(&(s[b] - s[edge]).abs()))
            .unwrap_or(edge);
        (
            best,
            best == k || !near_edge(best) || d[edge] <= 1.03 * d[inner],
        )
    };
    let (left, lk) = side(0);
    let (right, rk) = side(s.len() - 1);
    if !lk && !rk {
        return (Some(left), Some(right));
    }
    (lk.then_some(left), rk.then_some(right))
}

/// The references at point `k` of (s, d) from its shoulders (`idx`: the profile point of each
/// of (s, d)'s).
fn reference_at(s: &[f64], d: &[f64], idx: &[usize], k: usize, reach: f64) -> Reference {
    let found = shoulders(s, d, k, reach);
    let shoulder = |j: Option<usize>| {
        j.map(|j| Shoulder {
            point: idx[j],
            s: s[j],
            diameter: d[j],
        })
    };
    let shoulders = [shoulder(found.0), shoulder(found.1)];
    match found {
        (Some(l), Some(r)) => {
            let local = if s[r] > s[l] {
                d[l] + (d[r] - d[l]) * (s[k] - s[l]) / (s[r] - s[l])
            } else {
                d[k]
            };
            Reference {
                local,
                normal: d[l].min(d[r]),
                shoulders,
            }
        }
        (Some(j), None) | (None, Some(j)) => Reference {
            local: d[j],
            normal: d[j],
            shoulders,
        },
        // Not returned by `shoulders`; the point is then its own reference.
        (None, None) => Reference {
            local: d[k],
            normal: d[k],
            shoulders,
        },
    }
}

/// The measured points of a branch's profile, away from its closed and open ends (by the
/// branch's median radius), with their diameters median-filtered over about one radius; None
/// with fewer than 5.
fn filtered_profile(centerline: &Centerline, prof: &BranchProfile) -> Option<Filtered> {
    let b = &centerline.branches[prof.branch];
    let total = prof.points.last().map_or(0.0, |p| p.s);
    let median_radius = median(b.radius.clone());
    let idx: Vec<usize> = (0..prof.points.len())
        .filter(|&i| {
            let p = &prof.points[i];
            let near = |kind: EndKind, d: f64| kind != EndKind::Junction && d < median_radius;
            p.equivalent_diameter.is_some() && !near(b.start, p.s) && !near(b.end, total - p.s)
        })
        .collect();
    if idx.len() < 5 {
        return None;
    }
    let s: Vec<f64> = idx.iter().map(|&i| prof.points[i].s).collect();
    let raw: Vec<f64> = idx
        .iter()
        .map(|&i| prof.points[i].equivalent_diameter.unwrap_or(0.0))
        .collect();
    let spacing = (s[s.len() - 1] - s[0]) / (s.len() - 1).max(1) as f64;
    let median_r = 0.5 * median(raw.clone());
    let half = ((0.5 * median_r / spacing.max(1e-300)).round() as usize).min(10);
    let d = (0..raw.len())
        .map(|k| median(raw[k.saturating_sub(half)..(k + half + 1).min(raw.len())].to_vec()))
        .collect();
    Some(Filtered {
        idx,
        s,
        d,
        raw,
        half,
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
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
        let mut fig = BranchNarrowing {
            branch: prof.branch,
            measured: 0,
            reference: vec![None; prof.points.len()],
            max_narrowing_pct: 0.0,
        };
        let Some(Filtered {
            idx,
            s,
            d,
            raw,
            half,
        }) = filtered_profile(centerline, prof)
        else {
            fig.measured = prof
                .points
                .iter()
                .filter(|p| p.equivalent_diameter.is_some())
                .count();
            figures.push(fig);
            continue;
        };
        fig.measured = idx.len();
        let reach = SHOULDER_REACH * median(d.clone());
        let refs: Vec<Reference> = (0..d.len())
            .map(|k| reference_at(&s, &d, &idx, k, reach))
            .collect();
        for (k, r) in refs.iter().enumerate() {
            fig.reference[idx[k]] = Some(*r);
        }
        // Narrowing against the normal reference (the narrower shoulder).
        let narrowing: Vec<f64> = refs
            .iter()
            .zip(&d)
            .map(|(r, &di)| (1.0 - di / r.normal).max(0.0))
            .collect();
        fig.max_narrowing_pct = narrowing.iter().cloned().fold(0.0, f64::max) * 100.0;
        figures.push(fig);

        // Lesions, from the deepest down: the points between a lesion's shoulders are its own.
        let mut used = vec![false; narrowing.len()];
        while let Some((k, &peak)) = narrowing
            .iter()
            .enumerate()
            .filter(|(k, _)| !used[*k])
            .max_by(|a, b| a.1.total_cmp(b.1))
        {
            if peak * 100.0 < opts.min_degree_pct || peak <= 0.0 {
                break;
            }
            let r = refs[k];
            let (l, h) = shoulders(&s, &d, k, reach);
            let (lo, hi) = (l.unwrap_or(0), h.unwrap_or(d.len() - 1));
            for u in used.iter_mut().take(hi + 1).skip(lo) {
                *u = true;
            }
            // The width at half depth, against this lesion's local reference line.
            let line = |j: usize| match (l, h) {
                (Some(l), Some(h)) if s[h] > s[l] => {
                    d[l] + (d[h] - d[l]) * (s[j] - s[l]) / (s[h] - s[l])
                }
                _ => r.local,
            };
            let depth = 1.0 - d[k] / r.local;
            let deep = |j: usize| 1.0 - d[j] / line(j) > 0.5 * depth;
            let mut a = k;
            while a > lo && deep(a - 1) {
                a -= 1;
            }
            let mut b = k;
            while b < hi && deep(b + 1) {
                b += 1;
            }
            // The figures read the narrowest measured section, not the filtered profile: the
            // median over a radius of arc that finds the lesion raises a short lesion's floor
            // (on a V-shaped profile it reads the diameter a quarter of the window out). Among
            // the sections the filter read at k, the one narrowest against its local reference,
            // as the repair report's `HealthyReference::measure_in` takes it.
            let (w0, w1) = (k.saturating_sub(half), (k + half).min(d.len() - 1));
            let km = (w0..=w1)
                .min_by(|&a, &b| (raw[a] / refs[a].local).total_cmp(&(raw[b] / refs[b].local)))
                .unwrap_or(k);
            let (p, rm, dmin) = (&prof.points[idx[km]], refs[km], raw[km]);
            lesions.push(Lesion {
                branch: prof.branch,
                position: p.position,
                s: p.s,
                min_diameter: dmin,
                reference_diameter: rm.local,
                diameter_stenosis_pct: (1.0 - dmin / rm.local) * 100.0,
                area_stenosis_pct: (1.0 - (dmin / rm.local).powi(2)) * 100.0,
                normal_diameter: rm.normal,
                nascet_stenosis_pct: (1.0 - dmin / rm.normal) * 100.0,
                length: s[b] - s[a],
                inscribed_radius: 0.5 * p.inscribed_diameter,
            });
        }
    }
    lesions.sort_by(|a, b| b.nascet_stenosis_pct.total_cmp(&a.nascet_stenosis_pct));
    (lesions, figures)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tapering profile with a 50% narrowing, a dilation and a step down (a bulb's end).
    fn profile(step: bool) -> (Vec<f64>, Vec<f64>) {
        let s: Vec<f64> = (0..200).map(|i| i as f64 * 0.5).collect();
        let d = s
            .iter()
            .map(|&x| {
                let healthy = 6.0 - 0.02 * x + if step && x > 60.0 { 3.0 } else { 0.0 };
                let narrow = 1.0 - 0.5 * (-(x - 30.0).powi(2) / (2.0 * 9.0)).exp();
                let wide = 1.0 + 0.8 * (-(x - 80.0).powi(2) / 8.0).exp();
                healthy * narrow * wide
            })
            .collect();
        (s, d)
    }

    #[test]
    fn shoulders_give_the_local_and_normal_references() {
        let (s, d) = profile(false);
        let idx: Vec<usize> = (0..s.len()).collect();
        let r = reference_at(&s, &d, &idx, 60, 24.0);
        let healthy = 6.0 - 0.02 * 30.0;
        assert!(
            (r.local - healthy).abs() < 0.02 * healthy,
            "{r:?} {healthy}"
        );
        assert!(r.normal < r.local && r.normal > 0.93 * healthy, "{r:?}");
        assert!((d[60] / r.local - 0.5).abs() < 0.02);
        // The shoulders bracket the throat (σ = 3: beyond 2σ on either side), and the local
        // reference is the line between them.
        let [Some(left), Some(right)] = r.shoulders else {
            panic!("both shoulders: {r:?}");
        };
        assert!(left.s < 24.0 && right.s > 36.0, "{r:?}");
        assert_eq!(
            (d[left.point], d[right.point]),
            (left.diameter, right.diameter)
        );
        let line =
            left.diameter + (right.diameter - left.diameter) * (30.0 - left.s) / (right.s - left.s);
        assert!((line - r.local).abs() < 1e-12, "{line} {r:?}");
        // A healthy point is its own reference on a taper.
        let r = reference_at(&s, &d, &idx, 190, 24.0);
        assert!((1.0 - d[190] / r.normal).abs() < 0.01, "{r:?} {}", d[190]);
    }

    #[test]
    fn a_dip_before_a_widening_is_no_narrowing_against_the_normal_lumen() {
        // Flat at 6, a 5% dip, then up to 9: against the line between the shoulders (where
        // the dip levels off on the left, the top of the rise on the right) the dip looks like
        // 14%; against the narrower shoulder it is 5%.
        let s: Vec<f64> = (0..120).map(|i| i as f64 * 0.5).collect();
        let d: Vec<f64> = s
            .iter()
            .map(|&x| {
                let base = if x < 30.0 {
                    6.0
                } else {
                    6.0 + 3.0 * ((x - 30.0) / 10.0).min(1.0)
                };
                base * (1.0 - 0.05 * (-(x - 28.0).powi(2) / 4.0).exp())
            })
            .collect();
        let k = 56;
        let idx: Vec<usize> = (0..s.len()).collect();
        let r = reference_at(&s, &d, &idx, k, 24.0);
        assert!((1.0 - d[k] / r.normal) < 0.06, "{r:?} {}", d[k]);
        assert!((1.0 - d[k] / r.local) > 0.12, "{r:?} {}", d[k]);
    }

    #[test]
    fn the_shoulder_is_where_the_lumen_levels_off_not_up_a_taper_beyond() {
        // A 50% narrowing (σ = 1.2) in a stretch of diameter 2, the vessel widening steeply
        // (0.1 a unit) from 6 units before the throat on: the lumen beside the lesion is 2.
        let s: Vec<f64> = (0..160).map(|i| i as f64 * 0.25).collect();
        let d: Vec<f64> = s
            .iter()
            .map(|&x| {
                let healthy = 2.0 + 0.1 * (24.0 - x).max(0.0);
                healthy * (1.0 - 0.5 * (-(x - 30.0).powi(2) / (2.0 * 1.44)).exp())
            })
            .collect();
        let k = 120;
        let idx: Vec<usize> = (0..s.len()).collect();
        // Reach: 4 median diameters, as find_stenoses takes it.
        let r = reference_at(&s, &d, &idx, k, 8.0);
        let [Some(left), Some(right)] = r.shoulders else {
            panic!("both shoulders: {r:?}");
        };
        assert!(left.s > 24.0 && right.s < 36.0, "{r:?}");
        let pct = (1.0 - d[k] / r.local) * 100.0;
        assert!((pct - 50.0).abs() < 1.5, "{pct} {r:?}");
        assert!((r.normal - 2.0).abs() < 0.04, "{r:?}");
        // Before the lumen has risen from the throat, a level stretch is no shoulder: a
        // flat-bottomed narrowing to 1 over 26–34 is measured against the lumen of 2 beside it.
        let d: Vec<f64> = s
            .iter()
            .map(|&x| 2.0 - 0.5 * (((x - 26.0) * 2.0).tanh() - ((x - 34.0) * 2.0).tanh()))
            .collect();
        let r = reference_at(&s, &d, &idx, k, 8.0);
        assert!(
            (r.local - 2.0).abs() < 0.02 && (r.normal - 2.0).abs() < 0.02,
            "{r:?}"
        );
    }

    #[test]
    fn the_shoulder_before_a_bulb_is_where_the_flank_meets_its_flare() {
        // A 50% narrowing (σ = 1.2) in a stretch of diameter 2 whose lumen doubles over 4 units
        // (a carotid bulb) starting `gap` units past the throat: the lumen beside the lesion is
        // 2, not the bulb's 4. With a gap of 4 the lumen levels off for under a radius (1 unit)
        // before the bulb; with 3 the lesion's tail runs into the flare without levelling.
        // Either way the lumen rises on within every radius, so the level-off rule alone took
        // the bulb for the shoulder (local references 2.59 and 2.65).
        let s: Vec<f64> = (0..200).map(|i| i as f64 * 0.2).collect();
        let idx: Vec<usize> = (0..s.len()).collect();
        for gap in [4.0, 3.0] {
            let d: Vec<f64> = s
                .iter()
                .map(|&x| {
                    let t = ((x - 20.0 - gap) / 4.0).clamp(0.0, 1.0);
                    let healthy = 2.0 + 2.0 * t * t * (3.0 - 2.0 * t);
                    healthy * (1.0 - 0.5 * (-(x - 20.0).powi(2) / (2.0 * 1.44)).exp())
                })
                .collect();
            let k = 100;
            let r = reference_at(&s, &d, &idx, k, 8.0);
            let [Some(_), Some(right)] = r.shoulders else {
                panic!("gap {gap}: both shoulders: {r:?}");
            };
            assert!(right.diameter < 2.1, "gap {gap}: {r:?}");
            let pct = (1.0 - d[k] / r.local) * 100.0;
            assert!((pct - 50.0).abs() < 3.0, "gap {gap}: {pct} {r:?}");
        }
    }

    #[test]
    fn a_side_cut_short_while_rising_is_unknown() {
        // The profile starts inside a narrowing (a junction's unmeasured flare beyond): the left
        // side rises into its edge, so only the right shoulder is known.
        let (s, d) = profile(false);
        let (s, d) = (s[50..].to_vec(), d[50..].to_vec());
        let k = 10; // x = 30
        let (l, r) = shoulders(&s, &d, k, 24.0);
        assert_eq!(l, None);
        assert!(r.is_some());
        let idx: Vec<usize> = (0..s.len()).collect();
        let rf = reference_at(&s, &d, &idx, k, 24.0);
        assert!((d[k] / rf.local - 0.5).abs() < 0.05, "{rf:?}");
    }
}
