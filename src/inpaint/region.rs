//! Regions D to inpaint: balls in world (file) units, and the JSON regions file that lists them.
//!
//! The regions file is `{"regions": [{"center": [x, y, z], "radius": r}, ...],
//! "points": [[x, y, z], ...]}`: balls, and/or points picked on the surface (the paper's
//! interactive strategy, Section 4), from which balls are sized by the local vessel radius.
//! Both keys are optional; at least one region must result.
//!
//! A picked point becomes a ball centred on the surface point nearest to it, of radius
//! [`PICKED_RADIUS_FACTOR`] × the healthy vessel radius there when the caller knows it (the
//! repair gives the centreline's healthy reference, `centerline::healthy`), else the local
//! vessel radius ([`local_vessel_radius`]: half the median length of a fan of inward chords, the
//! ray-cast estimate of the vessel's inscribed radius). A point picked on a narrowing that the
//! caller's centreline finds (the repair: one of 20% or more, within the region `--stenoses`
//! would give it) becomes that narrowing's region: a clinician points at the lesion, and the
//! whole lesion, not a ball of the wall around the click, is widened. Balls also come from the
//! command line (`--region x,y,z,r`, [`parse_ball`]) and are checked against the mesh before
//! use ([`validate_regions`]).

use crate::bvh::MeshBvh;
use crate::io::write_atomic;
use crate::mesh::measures::{area_centroid, bounding_box, signed_volume_about};
use crate::mesh::TriMesh;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A ball of the damaged region D, in world (file) units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball {
    /// Centre, world units.
    pub center: Point3<f64>,
    /// Radius, world units.
    pub radius: f64,
}

impl Ball {
    /// Whether `p` lies in the closed ball.
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        (p - self.center).norm_squared() <= self.radius * self.radius
    }
}

/// How deep `p` lies in the union of `balls`: the largest r − |p − c| (positive inside D, world
/// units), and the index of the ball that gives it. (−∞, 0) without balls.
pub fn deepest_ball(balls: &[Ball], p: &Point3<f64>) -> (f64, usize) {
    let mut best = (f64::NEG_INFINITY, 0);
    for (b, ball) in balls.iter().enumerate() {
        let d = ball.radius - (p - ball.center).norm();
        if d > best.0 {
            best = (d, b);
        }
    }
    best
}

/// How deep `p` lies in the union of `balls` (see [`deepest_ball`]).
pub fn depth_in(balls: &[Ball], p: &Point3<f64>) -> f64 {
    deepest_ball(balls, p).0
}

/// One ball as written in a regions file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BallEntry {
    /// Centre, world units.
    pub center: [f64; 3],
    /// Radius, world units.
    pub radius: f64,
}

/// The contents of a regions file (see the module docs).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionsFile {
    /// Balls, world units.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<BallEntry>,
    /// Points picked on the surface, world units.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<[f64; 3]>,
}

impl From<&Ball> for BallEntry {
    fn from(b: &Ball) -> Self {
        BallEntry {
            center: [b.center.x, b.center.y, b.center.z],
            radius: b.radius,
        }
    }
}

impl From<&BallEntry> for Ball {
    fn from(b: &BallEntry) -> Self {
        Ball {
            center: Point3::from(b.center),
            radius: b.radius,
        }
    }
}

/// Writes `balls` as a regions file at `path` (atomically).
pub fn write_regions(path: &Path, balls: &[Ball]) -> Result<()> {
    let file = RegionsFile {
        regions: balls.iter().map(BallEntry::from).collect(),
        points: Vec::new(),
    };
    let text = serde_json::to_string_pretty(&file)
        .map_err(|e| Error::format(path, format!("cannot encode regions: {e}")))?;
    write_atomic(path, |out| {
        out.write_all(text.as_bytes())
            .and_then(|_| out.write_all(b"\n"))
            .map_err(|e| Error::io(path, e))
    })
}

/// A ball picked by a point has this many times the local vessel radius (world units follow).
pub const PICKED_RADIUS_FACTOR: f64 = 1.5;

/// What the caller knows of the vessel at a picked surface point ([`read_regions`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PickedSite {
    /// The healthy vessel radius there, world units: the ball is [`PICKED_RADIUS_FACTOR`] × it.
    Radius(f64),
    /// The point lies on a narrowing: its region (the one `repair --stenoses` gives it).
    Narrowing(Ball),
}

/// A region read from a regions file: its ball, and whether it is a narrowing's region that a
/// picked point chose (an intact, narrowed lumen: the repair widens it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReadRegion {
    pub ball: Ball,
    pub narrowing: bool,
}

/// Parses a command-line ball `x,y,z,r` (world units): four finite numbers, r > 0.
pub fn parse_ball(text: &str) -> Result<Ball> {
    let bad = |why: &str| Error::Geometry(format!("--region {text:?}: {why}"));
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 4 {
        return Err(bad("expected x,y,z,r (four comma-separated numbers)"));
    }
    let mut v = [0.0f64; 4];
    for (k, part) in parts.iter().enumerate() {
        v[k] = part
            .parse::<f64>()
            .map_err(|_| bad(&format!("expected x,y,z,r; {part:?} is not a number")))?;
        if !v[k].is_finite() {
            return Err(bad(&format!("expected x,y,z,r; {part:?} is not finite")));
        }
    }
    if v[3] <= 0.0 {
        return Err(bad("radius must be > 0"));
    }
    Ok(Ball {
        center: Point3::new(v[0], v[1], v[2]),
        radius: v[3],
    })
}

/// Tilt of the side rays of the chord fan from the inward normal, radians (about 12°).
const FAN_TILT: f64 = 0.21;
/// Number of side rays of the chord fan (around the central one).
const FAN_RAYS: usize = 8;

/// Estimated vessel radius (world units) at the surface point nearest to `p`: half the median
/// length of the chords cast from there into the vessel, along the inward face normal and a fan of
/// rays tilted about 12° around it (on a straight tube of radius r this is r within 2%).
///
/// "Inward" follows the mesh orientation (the sign of its volume about its area centroid); when
/// fewer than half of the rays hit in that direction the opposite one is tried, so inward-facing
/// meshes work too. `None` for an empty mesh, a degenerate face at `p`, a non-finite `p`, or when
/// no chord closes in either direction.
pub fn local_vessel_radius(mesh: &TriMesh, bvh: &MeshBvh, p: &Point3<f64>) -> Option<f64> {
    if !p.iter().all(|c| c.is_finite()) || bvh.is_empty() {
        return None;
    }
    let cp = bvh.closest_point(p);
    if !cp.is_found() {
        return None;
    }
    let n = mesh.face_normal_raw(cp.face as usize);
    let n = n.try_normalize(0.0)?;
    let [lo, hi] = bvh.bounding_box()?;
    let diag = (hi - lo).norm();
    let outward = signed_volume_about(mesh, &area_centroid(mesh)) >= 0.0;
    let first = if outward { -n } else { n };
    for inward in [first, -first] {
        let chords = chord_fan(bvh, &cp.point, &inward, diag);
        if chords.len() * 2 > FAN_RAYS + 1 {
            return Some(0.5 * median(chords));
        }
    }
    None
}

/// Lengths of the chords from surface point `s` into direction `inward` and the tilted fan around
/// it (hits only). Hits closer than a tiny fraction of the mesh diagonal (the faces around `s`)
/// are stepped over.
fn chord_fan(bvh: &MeshBvh, s: &Point3<f64>, inward: &Vector3<f64>, diag: f64) -> Vec<f64> {
    // Two unit vectors spanning the plane perpendicular to `inward`.
    let helper = if inward.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = inward.cross(&helper).normalize();
    let w = inward.cross(&u);
    let skip = 1e-7 * diag.max(f64::MIN_POSITIVE);
    let mut dirs = vec![*inward];
    for k in 0..FAN_RAYS {
        let phi = std::f64::consts::TAU * k as f64 / FAN_RAYS as f64;
        let side = u * phi.cos() + w * phi.sin();
        dirs.push(inward * FAN_TILT.cos() + side * FAN_TILT.sin());
    }
    dirs.iter()
        .filter_map(|d| {
            let mut start = 0.0;
            for _ in 0..8 {
                let origin = s + d * (start + skip);
                let hit = bvh.cast_ray(&origin, d, f64::INFINITY)?;
                let t = start + skip + hit.t;
                if t > 1e-5 * diag {
                    return Some(t);
                }
                start = t;
            }
            None
        })
        .collect()
}

/// Median of a non-empty list (mean of the two middle values for an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// Reads a regions file (see the module docs; or a 3D Slicer markups file, `.mrk.json` or
/// `.fcsv`, whose points are picked points: [`crate::io::read_markups`]) for `mesh`: its balls first, then one ball per
/// picked point, centred on the surface point nearest to it with radius [`PICKED_RADIUS_FACTOR`]
/// × the radius `site(point)` gives, or × [`local_vessel_radius`] there where it gives None; a
/// point that `site` finds on a narrowing becomes that narrowing's region instead. Unknown
/// keys, malformed JSON, a point where no vessel radius can be estimated and a file listing no
/// region at all are errors naming the file.
pub fn read_regions(
    path: &Path,
    mesh: &TriMesh,
    site: &dyn Fn(&Point3<f64>) -> Option<PickedSite>,
) -> Result<Vec<ReadRegion>> {
    // A 3D Slicer markups file (.mrk.json, .fcsv) lists picked points only.
    let file = if crate::io::is_markups_path(path) {
        let points = crate::io::read_markups(path)?;
        RegionsFile {
            points: points.iter().map(|p| [p.x, p.y, p.z]).collect(),
            ..RegionsFile::default()
        }
    } else {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        serde_json::from_str(&text)
            .map_err(|e| Error::format(path, format!("not a regions file: {e}")))?
    };
    if file.regions.is_empty() && file.points.is_empty() {
        return Err(Error::format(
            path,
            "no regions (neither \"regions\" nor \"points\" lists anything)",
        ));
    }
    let mut balls: Vec<ReadRegion> = (file.regions.iter())
        .map(|r| ReadRegion {
            ball: Ball::from(r),
            narrowing: false,
        })
        .collect();
    if !file.points.is_empty() {
        let bvh = MeshBvh::new(mesh);
        if bvh.is_empty() {
            return Err(Error::format(
                path,
                "picked points need a mesh with triangles",
            ));
        }
        for (k, q) in file.points.iter().enumerate() {
            let q = Point3::from(*q);
            let snapped = bvh.closest_point(&q).point;
            let healthy = match site(&snapped) {
                Some(PickedSite::Narrowing(ball)) => {
                    balls.push(ReadRegion {
                        ball,
                        narrowing: true,
                    });
                    continue;
                }
                Some(PickedSite::Radius(r)) => Some(r),
                None => None,
            };
            let r = healthy
                .or_else(|| local_vessel_radius(mesh, &bvh, &snapped))
                .ok_or_else(|| {
                    Error::format(
                        path,
                        format!(
                            "point {} ({}, {}, {}): cannot estimate the vessel radius there",
                            k + 1,
                            q.x,
                            q.y,
                            q.z
                        ),
                    )
                })?;
            balls.push(ReadRegion {
                ball: Ball {
                    center: snapped,
                    radius: PICKED_RADIUS_FACTOR * r,
                },
                narrowing: false,
            });
        }
    }
    Ok(balls)
}

/// Checks that every ball can be a damaged region of `mesh`: a finite centre, a positive finite
/// radius, a centre within the mesh's bounding box grown by the radius, and at least one surface
/// point inside the ball. Errors name the region (1-based) and its centre. No balls at all is an
/// error too.
pub fn validate_regions(mesh: &TriMesh, balls: &[Ball]) -> Result<()> {
    if balls.is_empty() {
        return Err(Error::Geometry("no regions".into()));
    }
    if mesh.faces.is_empty() {
        return Err(Error::InvalidMesh(
            "regions need a mesh with triangles".into(),
        ));
    }
    let (lo, hi) = bounding_box(mesh);
    let bvh = MeshBvh::new(mesh);
    for (k, b) in balls.iter().enumerate() {
        let c = b.center;
        let name = format!("region {} (centre {}, {}, {})", k + 1, c.x, c.y, c.z);
        let fail = |why: String| Err(Error::Geometry(format!("{name}: {why}")));
        if !c.iter().all(|v| v.is_finite()) {
            return fail("centre is not finite".into());
        }
        if !b.radius.is_finite() {
            return fail(format!("radius {} is not finite", b.radius));
        }
        if b.radius <= 0.0 {
            return fail(format!("radius must be > 0 (got {})", b.radius));
        }
        let r = Vector3::repeat(b.radius);
        let (glo, ghi) = (lo - r, hi + r);
        if (0..3).any(|i| c[i] < glo[i] || c[i] > ghi[i]) {
            return fail(format!(
                "centre lies outside the mesh's bounding box ({}, {}, {})–({}, {}, {}) grown by the radius {}",
                lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, b.radius
            ));
        }
        if bvh.closest_point_within(&c, b.radius).is_none() {
            let d = bvh.closest_point(&c).distance;
            return fail(format!(
                "ball of radius {} touches no surface (nearest surface point is {} away)",
                b.radius, d
            ));
        }
    }
    Ok(())
}
