//! Synthetic damaged vessels with known ground truth, for testing the inpainting of paper
//! Section 4 (Algorithm 4): an intact vessel (the truth), the same vessel damaged inside a known
//! region D (balls), and D itself.
//!
//! Both surfaces are the zero level set of an analytic function φ (negative inside, a signed
//! distance or close to one near the surface) sampled on a grid of voxel h = radius /
//! voxels_per_radius and meshed by marching cubes ([`crate::levelset::marching_cubes`]), so they
//! are closed, manifold and outward. Vessels are capped tubes (the tube's distance intersected
//! with its end planes: flat caps). The damage is built as a segmentation would show it, so the
//! damaged mesh is closed too:
//! - `tube`: a straight tube of length 10R; damaged: a ball of radius 1.2R centred on the wall
//!   carved out (max(φ, −φ_ball)), a dent.
//! - `curved`: a circular-arc tube (bend radius 4R, 120°); damaged: a slab of width 1.5R across
//!   the middle removed, leaving two pieces.
//! - `bifurcation`: a Y (parent of radius R, two daughters of radius 0.8R, 60° apart), capsules
//!   joined by a smooth minimum near the carina; damaged: a ball of radius 0.8R at the carina
//!   carved out.
//! - `stenosis`: truth the straight tube; damaged: a smooth 50% diameter narrowing with the
//!   gaussian profile r(z) = R(1 − 0.5 exp(−z²/(2σ²))), σ = 1.2R, whose φ is
//!   (ρ − r(z))·cos(atan r'(z)) (first order accurate distance to a surface of revolution).
//! - `occlusion`: truth the straight tube; damaged: a slab of width R across it removed (a full
//!   gap, both sides capped).
//!
//! The seed moves and tilts the damage a little (a splitmix64 stream, so the phantom of a seed is
//! the same on every machine). The regions D cover the damage with a margin of about R.

use super::region::Ball;
use crate::grid::{Grid3, GridTransform};
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::mesh::info::mesh_info;
use crate::{Error, Result, TriMesh};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;

/// Empty voxels kept between the vessel's bounding box and the grid border (voxels).
pub const MARGIN_VOXELS: usize = 4;

/// Largest grid (nodes) a phantom may use.
const MAX_NODES: usize = 1 << 28;

/// The kinds of phantom.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PhantomKind {
    /// A straight tube with a patch of wall chopped off.
    Tube,
    /// A circular-arc tube with a section removed across the whole diameter.
    Curved,
    /// A Y-shaped bifurcation with the wall chopped at the carina.
    Bifurcation,
    /// A straight tube with a smooth 50% diameter narrowing (truth: the normal tube).
    Stenosis,
    /// A straight tube with a short full gap (truth: the normal tube).
    Occlusion,
}

impl PhantomKind {
    /// Every kind, in the order the CLI lists them.
    pub const ALL: [PhantomKind; 5] = [
        PhantomKind::Tube,
        PhantomKind::Curved,
        PhantomKind::Bifurcation,
        PhantomKind::Stenosis,
        PhantomKind::Occlusion,
    ];

    /// The kind's name as the CLI spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            PhantomKind::Tube => "tube",
            PhantomKind::Curved => "curved",
            PhantomKind::Bifurcation => "bifurcation",
            PhantomKind::Stenosis => "stenosis",
            PhantomKind::Occlusion => "occlusion",
        }
    }
}

impl fmt::Display for PhantomKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for PhantomKind {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        PhantomKind::ALL
            .iter()
            .copied()
            .find(|k| k.as_str() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = PhantomKind::ALL.iter().map(|k| k.as_str()).collect();
                Error::Geometry(format!(
                    "unknown phantom kind {s:?} (expected one of {})",
                    names.join(", ")
                ))
            })
    }
}

/// Options of [`make_phantom`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhantomOptions {
    /// Seed of the small random moves and tilts of the damage.
    pub seed: u64,
    /// Vessel radius R (of the parent vessel for a bifurcation), world units (> 0). The default
    /// 3.0 is a 6 mm vessel when the units are mm.
    pub radius: f64,
    /// Grid resolution: voxels per radius, so the voxel is h = radius / voxels_per_radius
    /// (world units). In [2, 64].
    pub voxels_per_radius: f64,
}

impl Default for PhantomOptions {
    fn default() -> Self {
        PhantomOptions {
            seed: 1,
            radius: 3.0,
            voxels_per_radius: 8.0,
        }
    }
}

/// A damaged vessel, its intact truth and the region D that holds the damage.
#[derive(Debug, Clone)]
pub struct Phantom {
    /// What was built.
    pub kind: PhantomKind,
    /// The damaged vessel: closed, manifold, outward.
    pub damaged: TriMesh,
    /// The intact vessel: closed, manifold, outward.
    pub truth: TriMesh,
    /// The balls of D (world units): damaged and truth differ only inside them.
    pub regions: Vec<Ball>,
    /// Vessel radius R, world units.
    pub radius: f64,
    /// Voxel h of the grid both meshes were extracted on, world units.
    pub voxel: f64,
    /// Centerlines of the truth, one polyline per branch (world units).
    pub centerlines: Vec<Vec<Point3<f64>>>,
    /// One line saying what was built (shape, sizes, damage).
    pub description: String,
    shape: Shape,
}

impl Phantom {
    /// The analytic φ of the truth at `p` (negative inside; world units, a signed distance or
    /// close to one near the surface), whose zero level set `truth` was extracted from.
    pub fn truth_sdf(&self, p: &Point3<f64>) -> f64 {
        self.shape.truth(p)
    }

    /// The analytic φ of the damaged vessel at `p` (as [`Phantom::truth_sdf`]).
    pub fn damaged_sdf(&self, p: &Point3<f64>) -> f64 {
        self.shape.damaged(p)
    }
}

/// Builds the phantom of `kind` (see the module documentation). Errors when the options are out
/// of range.
pub fn make_phantom(kind: PhantomKind, opts: &PhantomOptions) -> Result<Phantom> {
    let r = opts.radius;
    if !(r.is_finite() && r > 0.0) {
        return Err(Error::Geometry(format!(
            "phantom radius must be positive and finite, got {r}"
        )));
    }
    let vpr = opts.voxels_per_radius;
    if !(vpr.is_finite() && (2.0..=64.0).contains(&vpr)) {
        return Err(Error::Geometry(format!(
            "voxels per radius must be in [2, 64], got {vpr}"
        )));
    }
    let h = r / vpr;
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::Geometry(format!(
            "phantom radius {r} gives no usable voxel size"
        )));
    }
    let mut rng = SplitMix(opts.seed);
    let (shape, regions, centerlines, description) = build(kind, r, &mut rng);
    let grid_box = bounds(&centerlines, r + MARGIN_VOXELS as f64 * h);
    let truth = mesh_of(&grid_box, h, |p| shape.truth(p))?;
    let damaged = mesh_of(&grid_box, h, |p| shape.damaged(p))?;
    Ok(Phantom {
        kind,
        damaged,
        truth,
        regions,
        radius: r,
        voxel: h,
        centerlines,
        description,
        shape,
    })
}

/// The shape of a phantom: its intact body and the damage.
#[derive(Debug, Clone)]
struct Shape {
    body: Body,
    damage: Damage,
}

/// Intact vessels.
#[derive(Debug, Clone)]
enum Body {
    /// Straight tube of radius `r` along z, z ∈ [−half, half].
    Tube { r: f64, half: f64 },
    /// Torus sector about the z axis: centerline radius `bend`, tube radius `r`, polar angle in
    /// [−half_angle, half_angle] (flat caps in the radial planes).
    Arc { r: f64, bend: f64, half_angle: f64 },
    /// Y: parent capsule of radius `r` from (0, 0, −len) to the origin, daughters of radius
    /// `rd` from the origin to len·dᵢ, smooth minimum of width `k`, each end cut flat.
    Y {
        r: f64,
        rd: f64,
        len: f64,
        dirs: [Vector3<f64>; 2],
        k: f64,
    },
}

/// Damage applied to the body.
#[derive(Debug, Clone)]
enum Damage {
    /// The ball carved out.
    Ball(Ball),
    /// The slab |(p − center)·normal| < half_width removed.
    Slab {
        center: Point3<f64>,
        normal: Vector3<f64>,
        half_width: f64,
    },
    /// Straight tube only: the radius becomes r(z) = r·(1 − depth·exp(−(z − z0)²/(2σ²))).
    Narrowing { z0: f64, sigma: f64, depth: f64 },
}

impl Shape {
    fn truth(&self, p: &Point3<f64>) -> f64 {
        self.body.sdf(p)
    }

    fn damaged(&self, p: &Point3<f64>) -> f64 {
        match (&self.damage, &self.body) {
            (Damage::Ball(b), _) => {
                let carve = b.radius - (p - b.center).norm();
                self.body.sdf(p).max(carve)
            }
            (
                Damage::Slab {
                    center,
                    normal,
                    half_width,
                },
                _,
            ) => {
                let carve = half_width - (p - center).dot(normal).abs();
                self.body.sdf(p).max(carve)
            }
            (Damage::Narrowing { z0, sigma, depth }, Body::Tube { r, half }) => {
                let dz = p.z - z0;
                let g = (-dz * dz / (2.0 * sigma * sigma)).exp();
                let radius = r * (1.0 - depth * g);
                let slope = r * depth * g * dz / (sigma * sigma);
                let rho = p.x.hypot(p.y);
                ((rho - radius) / (1.0 + slope * slope).sqrt()).max(p.z.abs() - half)
            }
            (Damage::Narrowing { .. }, _) => self.body.sdf(p),
        }
    }
}

impl Body {
    fn sdf(&self, p: &Point3<f64>) -> f64 {
        match *self {
            Body::Tube { r, half } => capped_cylinder(p.x.hypot(p.y) - r, p.z.abs() - half),
            Body::Arc {
                r,
                bend,
                half_angle,
            } => {
                let rho = p.x.hypot(p.y);
                let tube = (rho - bend).hypot(p.z) - r;
                // Outward normals of the two radial end planes.
                let (s, c) = half_angle.sin_cos();
                let lower = -s * p.x - c * p.y; // plane at −half_angle
                let upper = -s * p.x + c * p.y; // plane at +half_angle
                tube.max(lower).max(upper)
            }
            Body::Y {
                r,
                rd,
                len,
                ref dirs,
                k,
            } => {
                let v = p.coords;
                let parent = capsule(p, &Point3::new(0.0, 0.0, -len), &Point3::origin(), r);
                let d0 = capsule(p, &Point3::origin(), &Point3::from(dirs[0] * len), rd);
                let d1 = capsule(p, &Point3::origin(), &Point3::from(dirs[1] * len), rd);
                let body = smooth_min(smooth_min(parent, d0, k), d1, k);
                let ends = (-len - p.z)
                    .max(v.dot(&dirs[0]) - len)
                    .max(v.dot(&dirs[1]) - len);
                body.max(ends)
            }
        }
    }
}

/// Signed distance of a capped cylinder from the radial offset `a` = ρ − r and axial offset
/// `b` = |z| − half (exact, with sharp rims).
fn capped_cylinder(a: f64, b: f64) -> f64 {
    a.max(b).min(0.0) + a.max(0.0).hypot(b.max(0.0))
}

/// Signed distance to the capsule of radius `r` around the segment [a, b].
fn capsule(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, r: f64) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm() - r
}

/// Polynomial smooth minimum of width `k` (equals min(a, b) when |a − b| ≥ k).
fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    let w = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - w * w * k / 4.0
}

type Built = (Shape, Vec<Ball>, Vec<Vec<Point3<f64>>>, String);

/// The shape, regions, centerlines and description of `kind` at radius `r`.
fn build(kind: PhantomKind, r: f64, rng: &mut SplitMix) -> Built {
    let half = 5.0 * r;
    let straight = || {
        vec![line(
            Point3::new(0.0, 0.0, -half),
            Point3::new(0.0, 0.0, half),
        )]
    };
    let tube = Body::Tube { r, half };
    let z = Vector3::z();
    match kind {
        PhantomKind::Tube => {
            let angle = 2.0 * PI * rng.uniform();
            let center = Point3::new(r * angle.cos(), r * angle.sin(), 0.5 * r * rng.symmetric());
            let ball = Ball {
                center,
                radius: 1.2 * r,
            };
            let description = format!(
                "straight tube radius {} length {}; wall chopped by a ball of radius {} centred \
                 on the wall at {}",
                fmt_len(r),
                fmt_len(2.0 * half),
                fmt_len(ball.radius),
                fmt_point(&center)
            );
            let region = Ball {
                center,
                radius: ball.radius + r,
            };
            let shape = Shape {
                body: tube,
                damage: Damage::Ball(ball),
            };
            (shape, vec![region], straight(), description)
        }
        PhantomKind::Curved => {
            let (bend, half_angle) = (4.0 * r, PI / 3.0);
            let theta = 5f64.to_radians() * rng.symmetric();
            let center = Point3::new(bend * theta.cos(), bend * theta.sin(), 0.0);
            let tangent = Vector3::new(-theta.sin(), theta.cos(), 0.0);
            let (normal, tilt) = tilted(&tangent, 10f64.to_radians(), rng);
            let gap = 1.5 * r;
            let region = slab_region(&center, r, gap, tilt);
            let n = 25;
            let arc = (0..=n)
                .map(|i| {
                    let t = -half_angle + 2.0 * half_angle * i as f64 / n as f64;
                    Point3::new(bend * t.cos(), bend * t.sin(), 0.0)
                })
                .collect();
            let description = format!(
                "circular-arc tube radius {}, bend radius {}, 120°; a slab of width {} removed \
                 across it at {} (tilted {:.1}°)",
                fmt_len(r),
                fmt_len(bend),
                fmt_len(gap),
                fmt_point(&center),
                tilt.to_degrees()
            );
            let shape = Shape {
                body: Body::Arc {
                    r,
                    bend,
                    half_angle,
                },
                damage: Damage::Slab {
                    center,
                    normal,
                    half_width: gap / 2.0,
                },
            };
            (shape, vec![region], vec![arc], description)
        }
        PhantomKind::Bifurcation => {
            let (rd, len, a) = (0.8 * r, 5.0 * r, 30f64.to_radians());
            let dirs = [
                Vector3::new(a.sin(), 0.0, a.cos()),
                Vector3::new(-a.sin(), 0.0, a.cos()),
            ];
            let body = Body::Y {
                r,
                rd,
                len,
                dirs,
                k: 0.5 * r,
            };
            // The carina: where a ray from the junction between the daughters leaves the body.
            let beta = 15f64.to_radians() * rng.symmetric();
            let ray = Vector3::new(0.0, beta.sin(), beta.cos());
            let center = surface_on_ray(&body, &ray, 4.0 * r);
            let ball = Ball { center, radius: rd };
            let region = Ball {
                center,
                radius: ball.radius + r,
            };
            let origin = Point3::origin();
            let centerlines = vec![
                line(Point3::new(0.0, 0.0, -len), origin),
                line(origin, Point3::from(dirs[0] * len)),
                line(origin, Point3::from(dirs[1] * len)),
            ];
            let description = format!(
                "bifurcation: parent radius {} length {}, daughters radius {} length {} at ±30°; \
                 wall chopped by a ball of radius {} at the carina {}",
                fmt_len(r),
                fmt_len(len),
                fmt_len(rd),
                fmt_len(len),
                fmt_len(rd),
                fmt_point(&center)
            );
            let shape = Shape {
                body,
                damage: Damage::Ball(ball),
            };
            (shape, vec![region], centerlines, description)
        }
        PhantomKind::Stenosis => {
            let sigma = 1.2 * r;
            let z0 = 0.5 * r * rng.symmetric();
            let region = Ball {
                center: Point3::new(0.0, 0.0, z0),
                radius: 3.0 * sigma,
            };
            let description = format!(
                "straight tube radius {} length {}; 50% diameter stenosis (gaussian, σ = {}) with \
                 its throat at z = {z0:.4}",
                fmt_len(r),
                fmt_len(2.0 * half),
                fmt_len(sigma)
            );
            let shape = Shape {
                body: tube,
                damage: Damage::Narrowing {
                    z0,
                    sigma,
                    depth: 0.5,
                },
            };
            (shape, vec![region], straight(), description)
        }
        PhantomKind::Occlusion => {
            let center = Point3::new(0.0, 0.0, 0.5 * r * rng.symmetric());
            let (normal, tilt) = tilted(&z, 10f64.to_radians(), rng);
            let gap = r;
            let region = slab_region(&center, r, gap, tilt);
            let description = format!(
                "straight tube radius {} length {}; occluded: a gap of {} across it at {} \
                 (tilted {:.1}°)",
                fmt_len(r),
                fmt_len(2.0 * half),
                fmt_len(gap),
                fmt_point(&center),
                tilt.to_degrees()
            );
            let shape = Shape {
                body: tube,
                damage: Damage::Slab {
                    center,
                    normal,
                    half_width: gap / 2.0,
                },
            };
            (shape, vec![region], straight(), description)
        }
    }
}

/// The ball covering a slab of width `gap` through a tube of radius `r` (slab centre on the
/// axis, slab tilted by `tilt` from perpendicular), with a margin of `r`.
fn slab_region(center: &Point3<f64>, r: f64, gap: f64, tilt: f64) -> Ball {
    let reach = gap / 2.0 + r * tilt.tan();
    Ball {
        center: *center,
        radius: r.hypot(reach) + r,
    }
}

/// `axis` tilted by a random angle up to `max_tilt` towards a random direction; also the angle.
fn tilted(axis: &Vector3<f64>, max_tilt: f64, rng: &mut SplitMix) -> (Vector3<f64>, f64) {
    let helper = if axis.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = axis.cross(&helper).normalize();
    let v = axis.cross(&u);
    let psi = 2.0 * PI * rng.uniform();
    let tilt = max_tilt * rng.uniform();
    let normal = axis * tilt.cos() + (u * psi.cos() + v * psi.sin()) * tilt.sin();
    (normal, tilt)
}

/// Where the ray from the origin (inside `body`) along the unit `dir` crosses the surface, found
/// by bisection on [0, t_out] (the end must be outside).
fn surface_on_ray(body: &Body, dir: &Vector3<f64>, t_out: f64) -> Point3<f64> {
    let (mut lo, mut hi) = (0.0, t_out);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if body.sdf(&Point3::from(dir * mid)) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Point3::from(dir * (0.5 * (lo + hi)))
}

/// The segment [a, b] as a polyline of 11 points.
fn line(a: Point3<f64>, b: Point3<f64>) -> Vec<Point3<f64>> {
    (0..=10).map(|i| a + (b - a) * (i as f64 / 10.0)).collect()
}

/// A length for a description: at most six decimals, no float noise (3.6, not 3.5999999999999996).
fn fmt_len(x: f64) -> String {
    format!("{}", (x * 1e6).round() / 1e6)
}

fn fmt_point(p: &Point3<f64>) -> String {
    format!("({:.4}, {:.4}, {:.4})", p.x, p.y, p.z)
}

/// The bounding box of the polylines grown by `pad` on every side.
fn bounds(lines: &[Vec<Point3<f64>>], pad: f64) -> [Point3<f64>; 2] {
    let mut lo = Point3::from([f64::INFINITY; 3]);
    let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
    for p in lines.iter().flatten() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let pad = Vector3::from([pad; 3]);
    [lo - pad, hi + pad]
}

/// The zero level set of `sdf` sampled with voxel `h` on the box.
fn mesh_of(
    grid_box: &[Point3<f64>; 2],
    h: f64,
    sdf: impl Fn(&Point3<f64>) -> f64 + Sync,
) -> Result<TriMesh> {
    let [lo, hi] = grid_box;
    let mut dims = [0usize; 3];
    for a in 0..3 {
        let n = ((hi[a] - lo[a]) / h).ceil() + 1.0;
        if !(n.is_finite() && n <= MAX_NODES as f64) {
            return Err(Error::Geometry(format!(
                "phantom grid too large ({n} nodes along an axis)"
            )));
        }
        dims[a] = n as usize;
    }
    let count = Grid3::node_count(dims)?;
    if count > MAX_NODES {
        return Err(Error::Geometry(format!(
            "phantom grid of {}×{}×{} nodes is too large",
            dims[0], dims[1], dims[2]
        )));
    }
    let transform = GridTransform::new(*lo, h);
    let mut data = vec![0f32; count];
    let layer = dims[0] * dims[1];
    data.par_chunks_mut(layer).enumerate().for_each(|(k, out)| {
        for (idx, value) in out.iter_mut().enumerate() {
            let (i, j) = (idx % dims[0], idx / dims[0]);
            let p = transform.index_to_world(Vector3::new(i as f64, j as f64, k as f64));
            *value = sdf(&p) as f32;
        }
    });
    let phi = Grid3::from_data(dims, transform, data)?;
    let mesh = extract_surface(&phi, &ExtractOptions::default())?;
    let info = mesh_info(&mesh);
    if !info.watertight {
        return Err(Error::Geometry(format!(
            "phantom surface is not watertight: {}",
            info.leaks().join(", ")
        )));
    }
    Ok(mesh)
}

/// splitmix64 (Steele, Lea, Flood 2014): a small, fixed random stream (the same on every
/// machine) for the damage jitter; the seed is the state.
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [−1, 1).
    fn symmetric(&mut self) -> f64 {
        2.0 * self.uniform() - 1.0
    }
}
