//! The fill of a narrowing's region (an intact lumen, only narrowed: `--stenoses`, or a point
//! picked on a narrowing): the lesion widened to the healthy lumen, along the input's own
//! centreline, and nothing else in D touched.
//!
//! Paper Section 4 inpaints D so that the shape follows the intact vessel around it; a
//! narrowing's wall is all there, only too close to the axis, so the vessel around it is the
//! healthy lumen on either side of the lesion: the shoulders of `centerline::stenosis` and the
//! straight line between their equivalent diameters (the local reference the report's diameter
//! stenosis is measured against). Per branch of the input's centreline and per run of its points
//! inside the region (grown by the clearance), deepest first, each point narrower than its local
//! reference by 3% or more is a lesion, taken from its left shoulder to its right one (a side
//! without a known shoulder: as far as the lumen stays narrower than the reference) and beyond
//! them, inside the region, as far as the lumen is narrower than the shoulder or not measured (a
//! shoulder read where the sections stop, beside a junction's flare, still lies on the lesion's
//! flank); a point whose shoulders lie on either side of a lesion already taken (a dip between
//! a lesion and a bulb's flare reads one shoulder across the lesion, the other up the bulb) is
//! no lesion of its own. Each lesion's stretch is followed along the centreline, smoothed over
//! about a radius; at each sample the input's wall is read along rays in the section plane (the
//! narrowed lumen's own shape; a ray that ends on another branch leaves the sample out) and
//! scaled about its centroid until its equivalent diameter 2√(A/π) is the line's there
//! (sections already as wide are kept as they are). The tube is cut flat at both ends and
//! united with the input by the caller (`repair`), so the region's other vessels, a junction in
//! it, the shoulders themselves, are the input's.
//!
//! Before this, a narrowing's region was bridged between anchors at its border like a hole
//! (`guided`): where the region reached a junction or a branch's closed end, the anchors lay in
//! the junction's flare or on the end's taper, and the fill filled the carina instead of the
//! lesion (the held-out seed 23 of `benches/repair_real`: the capped aorta's left iliac, 11.4h).

use super::guided::{frames, ray_dirs, read_wall, scaled_section, smooth_path, GuideTube};
use super::region::Ball;
use crate::bvh::MeshBvh;
use crate::centerline::healthy::HealthyVessel;
use nalgebra::Point3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// A stretch is a lesion to widen where its equivalent diameter falls this far below the local
/// reference somewhere (a fraction; the profile's own noise is about 1%).
const LESION_DEPTH: f64 = 0.03;

/// The narrowing tubes of the region `balls` (grown by `grow`, world units), read with `rays`
/// rays per section, `spacing` apart along the curve (world units); None when no stretch of the
/// input's centreline in the region is narrower than its healthy reference.
pub fn plan_widening(
    bvh: &MeshBvh,
    healthy: &HealthyVessel,
    balls: &[Ball],
    grow: f64,
    rays: usize,
    spacing: f64,
) -> Option<Vec<GuideTube>> {
    let centerline = &healthy.centerline;
    let in_e = |p: &Point3<f64>| {
        balls
            .iter()
            .any(|b| (p - b.center).norm() < b.radius + grow)
    };
    let mut tubes = Vec::new();
    for (bi, br) in centerline.branches.iter().enumerate() {
        let (Some(refs), Some(profile)) = (
            healthy.narrowing.iter().find(|n| n.branch == bi),
            healthy.profiles.iter().find(|p| p.branch == bi),
        ) else {
            continue;
        };
        let n = br
            .points
            .len()
            .min(refs.reference.len())
            .min(profile.points.len());
        // Input diameter over the local reference, where both are known.
        let ratio: Vec<Option<f64>> = (0..n)
            .map(|i| {
                let d = profile.points[i].equivalent_diameter?;
                let r = refs.reference[i]?.local;
                (r > 0.0).then(|| d / r)
            })
            .collect();
        let mut i = 0;
        while i < n {
            if !in_e(&br.points[i]) {
                i += 1;
                continue;
            }
            let start = i;
            while i < n && in_e(&br.points[i]) {
                i += 1;
            }
            let run = start..i;
            // Lesions in the run, deepest first: each from its shoulder to its shoulder.
            let mut done = vec![false; n];
            // The throats of the lesions taken so far.
            let mut throats: Vec<usize> = Vec::new();
            while let Some(k) = run
                .clone()
                .filter(|&k| !done[k] && ratio[k].is_some_and(|q| q < 1.0 - LESION_DEPTH))
                .min_by(|&p, &q| ratio[p].unwrap_or(1.0).total_cmp(&ratio[q].unwrap_or(1.0)))
            {
                let Some(reference) = refs.reference[k] else {
                    break;
                };
                let [left, right] = reference.shoulders;
                // A point whose shoulders lie on either side of a lesion already taken (a dip
                // between that lesion and a bulb's flare: its walk outward crossed the lesion's
                // throat before it rose) has its healthy line read across that lesion, not
                // beside it.
                let span = left.map_or(run.start, |l| l.point)..=right.map_or(run.end, |r| r.point);
                if throats.iter().any(|t| span.contains(t)) {
                    done[k] = true;
                    continue;
                }
                throats.push(k);
                // The healthy lumen: the straight line between the shoulders (one alone: its
                // diameter all along), read at each point's arc length.
                let line = |j: usize| {
                    let sj = profile.points[j].s;
                    match (left, right) {
                        (Some(l), Some(r)) if r.s > l.s => {
                            l.diameter
                                + (r.diameter - l.diameter)
                                    * ((sj - l.s) / (r.s - l.s)).clamp(0.0, 1.0)
                        }
                        (Some(x), _) | (None, Some(x)) => x.diameter,
                        (None, None) => reference.local,
                    }
                };
                // A side without a known shoulder: as far as the lumen stays narrower.
                let narrower = |j: usize| ratio[j].is_some_and(|q| q < 1.0);
                let a = left.map_or_else(
                    || {
                        let mut a = k;
                        while a > run.start && narrower(a - 1) {
                            a -= 1;
                        }
                        a
                    },
                    |l| l.point.min(k),
                );
                let b = right.map_or_else(
                    || {
                        let mut b = k;
                        while b + 1 < run.end && narrower(b + 1) {
                            b += 1;
                        }
                        b
                    },
                    |r| r.point.max(k).min(n - 1),
                );
                // Beyond a shoulder, inside the region, as far as the lumen is narrower than
                // the shoulder (a shoulder read where the sections stop, next to a junction's
                // flare, is still on the lesion's flank).
                let below = |j: usize| {
                    profile.points[j]
                        .equivalent_diameter
                        .is_none_or(|d| d < line(j))
                };
                let (mut a, mut b) = (a, b);
                while a > run.start && below(a - 1) {
                    a -= 1;
                }
                while b + 1 < run.end && below(b + 1) {
                    b += 1;
                }
                for d in done.iter_mut().take(b + 1).skip(a) {
                    *d = true;
                }
                if b - a < 2 {
                    continue;
                }
                let target: Vec<f64> = (a..=b).map(line).collect();
                if let Some(tube) = widen_stretch(bvh, centerline, bi, a, &target, rays, spacing) {
                    tubes.push(tube);
                }
            }
        }
    }
    (!tubes.is_empty()).then_some(tubes)
}

/// The tube along branch `bi`'s points `a..a + target.len()`, each section widened to its
/// `target` equivalent diameter.
fn widen_stretch(
    bvh: &MeshBvh,
    centerline: &crate::centerline::Centerline,
    bi: usize,
    a: usize,
    target: &[f64],
    rays: usize,
    spacing: f64,
) -> Option<GuideTube> {
    let br = &centerline.branches[bi];
    let stretch = &br.points[a..a + target.len()];
    let radius = 0.5 * target.iter().fold(f64::INFINITY, |m, &t| m.min(t));
    let points = smooth_path(stretch, radius, spacing);
    if points.len() < 2 {
        return None;
    }
    let fr = frames(&points, &br.tangent[a]);
    let sections: Vec<Option<Vec<f64>>> = points
        .par_iter()
        .zip(&fr)
        .map(|(c, f)| {
            let k = nearest(stretch, c);
            widened_section(bvh, centerline, bi, c, f, target[k], rays)
        })
        .collect();
    let radii = bridge_missing(&sections)?;
    Some(GuideTube::from_radii(points, fr, radii, rays))
}

/// The sections' radii in order, each missing one (None) interpolated ray by ray between the
/// nearest sections on either side (copied from the one side at the ends); None when every
/// section is missing. (A missing section once became a section of radius 0, and the tube was
/// pinched there: a groove in the widened lumen, as deep as the narrowing.)
fn bridge_missing(sections: &[Option<Vec<f64>>]) -> Option<Vec<f64>> {
    let known: Vec<usize> = (0..sections.len())
        .filter(|&i| sections[i].is_some())
        .collect();
    let (&first, &last) = (known.first()?, known.last()?);
    // known[next] is the first known section after the current one.
    let mut next: usize = 0;
    let mut out = Vec::new();
    for (i, section) in sections.iter().enumerate() {
        if let Some(s) = section {
            out.extend_from_slice(s);
            next += 1;
            continue;
        }
        let p = if next == 0 { first } else { known[next - 1] };
        let q = known.get(next).copied().unwrap_or(last);
        let (sp, sq) = (sections[p].as_deref()?, sections[q].as_deref()?);
        let w = if q > p {
            (i as f64 - p as f64) / (q - p) as f64
        } else {
            0.0
        };
        out.extend(sp.iter().zip(sq).map(|(x, y)| x + (y - x) * w));
    }
    Some(out)
}

/// Index of the point of `pts` nearest to `p`.
fn nearest(pts: &[Point3<f64>], p: &Point3<f64>) -> usize {
    (0..pts.len())
        .min_by(|&i, &j| (pts[i] - p).norm().total_cmp(&(pts[j] - p).norm()))
        .unwrap_or(0)
}

/// The section at curve point `c` (frame `f`): the input's wall along `rays` rays in the section
/// plane (on branch `bi`), scaled about its centroid to the equivalent diameter `target` when
/// narrower, as distances from `c` along the same rays. None when a ray misses the wall or ends
/// on another branch.
fn widened_section(
    bvh: &MeshBvh,
    centerline: &crate::centerline::Centerline,
    bi: usize,
    c: &Point3<f64>,
    f: &[nalgebra::Vector3<f64>; 3],
    target: f64,
    rays: usize,
) -> Option<Vec<f64>> {
    let dirs = ray_dirs(rays);
    let wall = read_wall(
        bvh,
        centerline,
        c,
        f,
        &dirs,
        &[bi],
        |_| target,
        |_| 0.5 * target,
    )?;
    // Area and centroid of the wall's polygon (shoelace).
    let (mut area2, mut gx, mut gy) = (0.0, 0.0, 0.0);
    for j in 0..rays {
        let (p, q) = (wall[j], wall[(j + 1) % rays]);
        let cross = p.0 * q.1 - q.0 * p.1;
        area2 += cross;
        gx += (p.0 + q.0) * cross;
        gy += (p.1 + q.1) * cross;
    }
    if !(area2 > 0.0) {
        return None;
    }
    let (gx, gy) = (gx / (3.0 * area2), gy / (3.0 * area2));
    let diameter = 2.0 * (0.5 * area2 / PI).sqrt();
    let k = target / diameter;
    if k <= 1.0 {
        return Some(wall.iter().map(|w| w.0.hypot(w.1)).collect());
    }
    scaled_section(&wall, (gx, gy), k, &dirs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_section_is_bridged_from_its_neighbours() {
        let s = |r: f64| Some(vec![r, 2.0 * r]);
        let got = bridge_missing(&[None, s(1.0), None, None, s(4.0), None]).unwrap();
        assert_eq!(
            got,
            [1.0, 2.0, 1.0, 2.0, 2.0, 4.0, 3.0, 6.0, 4.0, 8.0, 4.0, 8.0]
        );
        assert_eq!(bridge_missing(&[s(1.0)]).unwrap(), [1.0, 2.0]);
        assert!(bridge_missing(&[None, None]).is_none());
    }
}
