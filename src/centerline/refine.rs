//! From a branch of grid nodes to a smooth sub-voxel curve with radii and tangents.
//!
//! 1. The nodes' positions are resampled every `spacing` along the polyline and smoothed by a
//!    gaussian along the arc length (the ends are kept; beyond them the curve is continued by
//!    point reflection, so a straight end stays straight).
//! 2. A terminal end that is not an open vessel end is trimmed where its inscribed radius falls
//!    below 95% of the vessel's just before it (TEASAR's last steps run from the axis to the
//!    farthest corner of a blunt end, where the wall is near) and continued straight along its
//!    tangent until it meets the wall (φ = 0): the centreline ends where the vessel does.
//! 3. Centring: each point moves to the centroid of the mesh's cross-section perpendicular to
//!    the curve (exact on circular sections, bent or not), where that section is one lumen around
//!    the point: it encloses it, its equivalent radius is 0.75–1.6 times the inscribed radius,
//!    and the move is under half that radius; within 1.5 radii of a junction (where the section
//!    cuts two lumens) points are not moved. The curve is then smoothed again.
//! 4. Radius: the maximal inscribed radius at each point, its exact distance to the mesh (at an
//!    open end, to the rim: the radius does not fall where the winding number closes the end);
//!    tangent: the unit central difference.

use super::graph::EndKind;
use crate::bvh::MeshBvh;
use crate::grid::Grid3;
use crate::report::stenosis::cross_section;
use crate::TriMesh;
use nalgebra::{Point3, Vector3};

/// Options of [`refine_branch`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineOptions {
    /// Spacing of the output points, **in voxels** (default 1).
    pub spacing_voxels: f64,
    /// Gaussian width of the first smoothing, **in voxels** (default 2).
    pub smooth_voxels: f64,
    /// Whether to centre the points on the mesh's cross-sections (default true).
    pub centre_on_sections: bool,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            spacing_voxels: 1.0,
            smooth_voxels: 2.0,
            centre_on_sections: true,
        }
    }
}

/// A refined branch.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    pub points: Vec<Point3<f64>>,
    pub radius: Vec<f64>,
    pub tangent: Vec<Vector3<f64>>,
}

/// Refines one branch (see the module docs). `points` are its nodes' world positions, `ends`
/// the kinds of its first and last point; `open_end_points` gives, for an open end, the end
/// loop's centre, appended as the branch's end point. Radii are exact distances to the mesh
/// (`bvh`, the hierarchy of `mesh`).
pub fn refine_branch(
    phi: &Grid3,
    mesh: &TriMesh,
    bvh: &MeshBvh,
    points: &[Point3<f64>],
    ends: [EndKind; 2],
    open_end_points: [Option<Point3<f64>>; 2],
    opts: &RefineOptions,
) -> Curve {
    let h = phi.voxel();
    let spacing = opts.spacing_voxels * h;
    let mut pts = resample(points, spacing);
    pts = smooth(&pts, opts.smooth_voxels * h / spacing);

    // Blunt ends: trim the corner run and continue along the axis to the wall.
    for (side, kind) in ends.iter().enumerate() {
        if *kind != EndKind::End || pts.len() < 3 {
            continue;
        }
        // trim_and_extend works on the last point: bring the first one there.
        if side == 0 {
            pts.reverse();
        }
        trim_and_extend(phi, bvh, &mut pts, spacing);
        if side == 0 {
            pts.reverse();
        }
    }
    if opts.centre_on_sections && pts.len() >= 3 {
        let n = pts.len();
        let junction_zone = |i: usize| {
            (0..2).any(|side| {
                if ends[side] != EndKind::Junction {
                    return false;
                }
                let j = if side == 0 { pts[0] } else { pts[n - 1] };
                (pts[i] - j).norm() < 1.5 * bvh.closest_point(&j).distance.max(h)
            })
        };
        let tangents = tangents(&pts);
        let moved: Vec<Point3<f64>> = (0..n)
            .map(|i| {
                if i == 0 || i == n - 1 || junction_zone(i) {
                    return pts[i];
                }
                let r = bvh.closest_point(&pts[i]).distance;
                match cross_section(mesh, &pts[i], &tangents[i]) {
                    Some(s) => {
                        let req = 0.5 * s.equivalent_diameter;
                        let ok = s.encloses_point
                            && req >= 0.75 * r
                            && req <= 1.6 * r
                            && (s.centroid - pts[i]).norm() < 0.5 * r;
                        if ok {
                            s.centroid
                        } else {
                            pts[i]
                        }
                    }
                    None => pts[i],
                }
            })
            .collect();
        pts = smooth(&moved, 1.0 * h / spacing);
    }
    // Open ends: the loop's centre closes the branch.
    if let Some(c) = open_end_points[1] {
        if pts.last().is_some_and(|p| (p - c).norm() > 0.25 * h) {
            pts.push(c);
        }
    }
    if let Some(c) = open_end_points[0] {
        if pts.first().is_some_and(|p| (p - c).norm() > 0.25 * h) {
            pts.insert(0, c);
        }
    }
    let radius = pts.iter().map(|p| bvh.closest_point(p).distance).collect();
    let tangent = tangents(&pts);
    Curve {
        points: pts,
        radius,
        tangent,
    }
}

/// Points every `spacing` along the polyline (its two ends kept).
pub fn resample(points: &[Point3<f64>], spacing: f64) -> Vec<Point3<f64>> {
    if points.len() < 2 {
        return points.to_vec();
    }
    let mut cum = vec![0.0];
    for w in points.windows(2) {
        cum.push(cum.last().unwrap() + (w[1] - w[0]).norm());
    }
    let total = *cum.last().unwrap();
    let n = ((total / spacing).round() as usize).max(1);
    let mut out = Vec::with_capacity(n + 1);
    let mut seg = 0;
    for k in 0..=n {
        let s = total * k as f64 / n as f64;
        while seg + 2 < cum.len() && cum[seg + 1] < s {
            seg += 1;
        }
        let len = cum[seg + 1] - cum[seg];
        let t = if len > 0.0 {
            ((s - cum[seg]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(points[seg] + (points[seg + 1] - points[seg]) * t);
    }
    out
}

/// Gaussian smoothing of evenly spaced points, width `sigma` in points; the ends are kept and
/// the curve is continued beyond them by point reflection.
pub fn smooth(points: &[Point3<f64>], sigma: f64) -> Vec<Point3<f64>> {
    let n = points.len();
    if n < 3 || sigma <= 0.0 {
        return points.to_vec();
    }
    let half = (3.0 * sigma).ceil() as isize;
    let weights: Vec<f64> = (-half..=half)
        .map(|k| (-(k as f64).powi(2) / (2.0 * sigma * sigma)).exp())
        .collect();
    let at = |i: isize| -> Point3<f64> {
        let last = n as isize - 1;
        if i < 0 {
            let m = (-i).min(last) as usize;
            Point3::from(2.0 * points[0].coords - points[m].coords)
        } else if i > last {
            let m = (2 * last - i).max(0) as usize;
            Point3::from(2.0 * points[n - 1].coords - points[m].coords)
        } else {
            points[i as usize]
        }
    };
    (0..n)
        .map(|i| {
            if i == 0 || i == n - 1 {
                return points[i];
            }
            let mut acc = Vector3::zeros();
            let mut wsum = 0.0;
            for (w, k) in weights.iter().zip(-half..=half) {
                acc += at(i as isize + k).coords * *w;
                wsum += w;
            }
            Point3::from(acc / wsum)
        })
        .collect()
}

/// Unit tangents by central differences (one-sided at the ends).
pub fn tangents(points: &[Point3<f64>]) -> Vec<Vector3<f64>> {
    let n = points.len();
    (0..n)
        .map(|i| {
            let a = points[i.saturating_sub(2)];
            let b = points[(i + 2).min(n - 1)];
            (b - a).try_normalize(0.0).unwrap_or_else(Vector3::x)
        })
        .collect()
}

/// Trims the end of `pts` where the inscribed radius falls below 95% of the vessel's radius just
/// before it (the largest within 3 radii of arc; never more than 2.5 radii or half the curve),
/// and continues the curve straight along the tangent of the next radius of it, every
/// `spacing`, while it stays inside (φ < 0).
fn trim_and_extend(phi: &Grid3, bvh: &MeshBvh, pts: &mut Vec<Point3<f64>>, spacing: f64) {
    let n = pts.len();
    let total: f64 = pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let radius: Vec<f64> = pts.iter().map(|p| bvh.closest_point(p).distance).collect();
    let mut vessel: f64 = 0.0;
    let mut s = 0.0;
    for i in (1..n).rev() {
        vessel = vessel.max(radius[i]);
        s += (pts[i] - pts[i - 1]).norm();
        if s > 3.0 * vessel.max(spacing) || s > 0.5 * total {
            break;
        }
    }
    let limit = (2.5 * vessel).min(0.5 * total);
    let mut s = 0.0;
    while pts.len() > 2 {
        let m = pts.len();
        let step = (pts[m - 1] - pts[m - 2]).norm();
        if radius[m - 1] >= 0.95 * vessel || s + step > limit {
            break;
        }
        s += step;
        pts.pop();
    }
    let m = pts.len();
    let back = ((vessel / spacing).ceil() as usize).clamp(1, m - 1);
    let Some(dir) = (pts[m - 1] - pts[m - 1 - back]).try_normalize(0.0) else {
        return;
    };
    let mut p = pts[m - 1];
    let steps = (4.0 * vessel / spacing).ceil() as usize + 4;
    for _ in 0..steps {
        let q = p + dir * spacing;
        match phi.sample_tricubic(&q) {
            Some(v) if v < 0.0 => {
                pts.push(q);
                p = q;
            }
            Some(v) => {
                // Last partial step to the wall.
                let v0 = phi.sample_tricubic(&p).unwrap_or(0.0);
                let t = if v - v0 != 0.0 {
                    (-v0 / (v - v0)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                if t > 0.1 {
                    pts.push(p + dir * (spacing * t));
                }
                break;
            }
            None => break,
        }
    }
}
