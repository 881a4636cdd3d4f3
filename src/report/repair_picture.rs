//! The before/after picture of a repair (issue 6, point 4, and issue 23, point 6; `--picture
//! P.png`): two rows, "input" (the mesh as read, its holes open) and "repaired", each seen in
//! three views with one scale, as in Figure 3 of Dong, Chien, Shen and Osher (row 1: the vessel
//! before inpainting with the regions marked by red circles; row 3: the inpainted regions shown
//! in red); under them the report's figures and a scale bar.
//!
//! - Framing: the context box is the bounding box of the balls of D grown ×[`CONTEXT_GROWTH`]
//!   about its centre; only the triangles whose centroid lies in it (or that touch D) are drawn,
//!   so the rest of a large vessel tree neither hides D nor shrinks it to a dot. The cameras are
//!   orthographic, each fitted to what it shows (both meshes and the balls' discs), one scale
//!   for all six panels (so one scale bar holds for all).
//! - Views: "front" ([`repair_view`]): perpendicular to the vessel, D face on. From the
//!   normal tensor Σ w A n nᵀ of the repaired mesh's triangles in the box, weighted by area A
//!   and by nearness to D, w = exp(−d²/2r²) (d the distance to a ball's centre, r its radius;
//!   the largest over the balls), so that a bend or branch away from D counts little: its
//!   eigenvector of smallest eigenvalue is the vessel's axis (a tube's normals are all
//!   perpendicular to it; for a sheet it is some direction in the sheet), shown to the right.
//!   The camera looks from the balls' centre towards the axis, perpendicular to it: the axis
//!   point is where the triangles' normal lines meet (least squares, same weights; a tube's
//!   all cross its axis), so a wall defect with its ball centred on the wall is seen face on
//!   from outside. All of this is sign-free in the normals: the mesh's orientation does not
//!   matter. When the balls' centre lies on the axis (or there is no ball) the camera looks
//!   along the dominant normal of the triangles in D (of those in the box when D holds none),
//!   made orthogonal to the axis, from the side where D's centroid is nearer. "top": turned a
//!   quarter about the vessel's axis (looking down the front view's up); "oblique": the front
//!   view turned 45° about its up, looking partly along the vessel.
//! - Colours: grey surfaces; red only what the repair added: the repaired mesh's triangles whose
//!   centroid lies farther than `added_distance` (half a voxel from `repair`) from the input
//!   surface, so the kept wall inside D stays grey and a repair that changed nothing shows no
//!   red; each ball's outline (its orthographic projection, a circle) in dark red on the input.
//! - Drawing: a z-buffered scan conversion with 2×2 supersampling, two-sided Lambert shading
//!   plus ambient (as [`super::render`]), one colour per triangle.
//!
//! Sizes are in pixels; world units are those of the meshes, named on the scale bar by
//! `unit` (never assumed to be mm).

use super::image::{write_png, RgbImage};
use super::raster::{Lighting, ZBuffer};
use super::text::{draw_text, text_width, HAlign};
use crate::bvh::MeshBvh;
use crate::inpaint::region::Ball;
use crate::mesh::measures::vertex_normals;
use crate::{Error, Result, TriMesh};
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use std::path::Path;

/// Factor by which the bounding box of the balls is grown (about its centre) into the context
/// box that is drawn.
pub const CONTEXT_GROWTH: f64 = 2.5;
/// Colour of surfaces outside D.
pub const SURFACE_GREY: [u8; 3] = [200, 200, 200];
/// Colour of the triangles the repair added.
pub const REPAIRED_RED: [u8; 3] = [220, 40, 35];
/// Colour of the balls' outlines on the input panel.
pub const OUTLINE_RED: [u8; 3] = [170, 10, 10];
/// Colour of the pixels no surface covers.
pub const BACKGROUND: [u8; 3] = [255, 255, 255];

/// Largest accepted width or height, pixels.
const MAX_SIDE: u32 = 4096;
/// Smallest accepted width or height, pixels.
const MIN_SIDE: u32 = 32;
/// Pixels between the panels.
const GAP: u32 = 8;
/// Blank border of each panel, as a fraction of its width and height.
const MARGIN: f64 = 0.04;
/// Direction towards the light in the camera's frame (x right, y up, z towards the viewer).
const LIGHT: [f64; 3] = [-0.35, 0.45, 0.82];
/// Ambient part of the lighting; the rest is Lambertian.
const AMBIENT: f64 = 0.3;

/// Size and captions of the picture.
#[derive(Clone, Debug, PartialEq)]
pub struct RepairPictureOptions {
    /// Width of the whole picture, pixels, in [32, 4096].
    pub width: u32,
    /// Height of the whole picture (titles, panels, figures), pixels, in [32, 4096].
    pub height: u32,
    /// A repaired triangle whose centroid is farther than this from the input surface was
    /// added by the repair and is drawn red (world units; `repair` gives half its voxel). At
    /// 0, anything farther than a millionth of the context box's diagonal.
    pub added_distance: f64,
    /// Name of the world unit on the scale bar ("mm"); empty: "units".
    pub unit: String,
    /// Lines of the report's figures written under the panels.
    pub figures: Vec<String>,
}

impl Default for RepairPictureOptions {
    fn default() -> Self {
        RepairPictureOptions {
            width: 1200,
            height: 800,
            added_distance: 0.0,
            unit: String::new(),
            figures: Vec::new(),
        }
    }
}

/// The views of each row, left to right (see the module docs).
pub const VIEW_NAMES: [&str; 3] = ["front", "top", "oblique"];
/// The rows, top to bottom.
pub const ROW_NAMES: [&str; 2] = ["input", "repaired"];

/// The camera of a repair picture: the context box and the view (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RepairView {
    /// Lower corner of the context box, world units.
    pub min: Point3<f64>,
    /// Upper corner of the context box, world units.
    pub max: Point3<f64>,
    /// Unit direction the camera looks along (from the viewer into the scene).
    pub view: Vector3<f64>,
    /// Unit direction shown upwards, orthogonal to `view`.
    pub up: Vector3<f64>,
    /// Unit direction shown to the right: `view` × `up`.
    pub right: Vector3<f64>,
}

impl RepairView {
    /// Whether `p` lies in the context box (closed).
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        (0..3).all(|k| p[k] >= self.min[k] && p[k] <= self.max[k])
    }
}

/// Whether a ball can be drawn: finite centre, finite radius ≥ 0.
fn usable(ball: &Ball) -> bool {
    ball.center.iter().all(|c| c.is_finite()) && ball.radius.is_finite() && ball.radius >= 0.0
}

/// Bounding box of the finite vertices used by faces whose indices are in range.
fn used_bounds(mesh: &TriMesh) -> Option<(Point3<f64>, Point3<f64>)> {
    let n = mesh.vertices.len();
    let mut b: Option<(Point3<f64>, Point3<f64>)> = None;
    for face in mesh
        .faces
        .iter()
        .filter(|f| f.iter().all(|&i| (i as usize) < n))
    {
        for &i in face {
            let p = mesh.vertices[i as usize];
            if p.iter().all(|c| c.is_finite()) {
                b = Some(match b {
                    None => (p, p),
                    Some((lo, hi)) => (lo.inf(&p), hi.sup(&p)),
                });
            }
        }
    }
    b
}

/// The context box: the balls' bounding box grown ×[`CONTEXT_GROWTH`] about its centre; without
/// usable balls (or with balls of radius 0 only) the bounding box of `after`, else the box
/// [−1, 1]³.
fn context_box(after: &TriMesh, balls: &[Ball]) -> (Point3<f64>, Point3<f64>) {
    let mut b: Option<(Point3<f64>, Point3<f64>)> = None;
    for ball in balls.iter().filter(|b| usable(b)) {
        let r = Vector3::repeat(ball.radius);
        let (lo, hi) = (ball.center - r, ball.center + r);
        b = Some(match b {
            None => (lo, hi),
            Some((a, z)) => (a.inf(&lo), z.sup(&hi)),
        });
    }
    if let Some((lo, hi)) = b {
        let (c, half) = (nalgebra::center(&lo, &hi), 0.5 * (hi - lo));
        if half.max() > 0.0 && half.iter().all(|h| h.is_finite()) {
            let half = half * CONTEXT_GROWTH;
            return (c - half, c + half);
        }
    }
    used_bounds(after).unwrap_or((Point3::from([-1.0; 3]), Point3::from([1.0; 3])))
}

/// Area-weighted moments of a set of triangles (n the unit normal, A the area, c the
/// centroid of a triangle, all sums divided by Σ A).
#[derive(Clone, Copy, Debug)]
struct Patch {
    /// Normal tensor Σ A n nᵀ / Σ A.
    tensor: Matrix3<f64>,
    /// Area centroid Σ A c / Σ A.
    centroid: Point3<f64>,
    /// Σ A (I − n nᵀ) c / Σ A, the right-hand side of the least-squares meeting point of the
    /// normal lines.
    lines: Vector3<f64>,
}

impl Patch {
    /// The point nearest (least squares, weighted) to all the triangles' normal lines:
    /// on the axis of a tube (its normal lines all cross the axis), at the centroid's position
    /// along the axis. It solves M x = Σ A (I − n nᵀ) c / Σ A with M = I − tensor in M's
    /// eigenbasis; along eigenvectors whose eigenvalue is below [`LINES_DETERMINE`] (a sheet's
    /// normal, which its parallel normal lines leave undetermined) x keeps the centroid's
    /// coordinate.
    fn axis_point(&self) -> Option<Point3<f64>> {
        let eig = SymmetricEigen::new(Matrix3::identity() - self.tensor);
        let residual = self.lines - (Matrix3::identity() - self.tensor) * self.centroid.coords;
        let mut x = self.centroid.coords;
        for k in 0..3 {
            let mu = eig.eigenvalues[k];
            if mu > LINES_DETERMINE {
                let e = eig.eigenvectors.column(k);
                x += e * (e.dot(&residual) / mu);
            }
        }
        x.iter().all(|c| c.is_finite()).then_some(Point3::from(x))
    }
}

/// Eigenvalue of I − Σ A n nᵀ / Σ A below which the normal lines are taken to leave a direction
/// undetermined (a tube's cross-section plane has ½, its axis 1, a sheet's normal 0).
const LINES_DETERMINE: f64 = 0.1;

/// The moments of the faces of `mesh`, each area weighted also by `weight` of its corners
/// (0 leaves the face out); `None` when the weights leave no area.
fn patch(mesh: &TriMesh, mut weight: impl FnMut(&[Point3<f64>; 3]) -> f64) -> Option<Patch> {
    let n = mesh.vertices.len();
    let (mut tensor, mut centroid, mut lines, mut total) =
        (Matrix3::zeros(), Vector3::zeros(), Vector3::zeros(), 0.0);
    for f in &mesh.faces {
        if !f.iter().all(|&i| (i as usize) < n) {
            continue;
        }
        let corners = f.map(|i| mesh.vertices[i as usize]);
        if !corners.iter().all(|p| p.iter().all(|c| c.is_finite())) {
            continue;
        }
        let w = weight(&corners);
        if !(w > 0.0 && w.is_finite()) {
            continue;
        }
        let [a, b, c] = corners;
        let cross = (b - a).cross(&(c - a));
        let raw = 0.5 * cross.norm();
        if !(raw > 0.0 && raw.is_finite()) {
            continue;
        }
        let unit = cross / (2.0 * raw);
        let area = raw * w;
        let nn = unit * unit.transpose();
        let mid = (a.coords + b.coords + c.coords) / 3.0;
        tensor += nn * area;
        centroid += mid * area;
        lines += (Matrix3::identity() - nn) * mid * area;
        total += area;
    }
    (total > 0.0).then(|| Patch {
        tensor: tensor / total,
        centroid: Point3::from(centroid / total),
        lines: lines / total,
    })
}

/// Eigenvectors of a symmetric 3×3 matrix, ordered by increasing eigenvalue.
fn sorted_eigenvectors(m: Matrix3<f64>) -> Option<[Vector3<f64>; 3]> {
    let eig = SymmetricEigen::new(m);
    if !eig.eigenvalues.iter().all(|l| l.is_finite()) {
        return None;
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    Some(order.map(|k| eig.eigenvectors.column(k).into_owned()))
}

/// The camera of the repair picture of `after` with regions `balls` (see the module docs): the
/// context box, and the view from the normals of `after`'s triangles in the box, weighted by
/// nearness to D (the vessel's axis and the point on it facing D). With no surface in the box it looks along −y with z
/// up.
pub fn repair_view(after: &TriMesh, balls: &[Ball]) -> RepairView {
    let (min, max) = context_box(after, balls);
    let mut view = RepairView {
        min,
        max,
        view: Vector3::new(0.0, -1.0, 0.0),
        up: Vector3::new(0.0, 0.0, 1.0),
        right: Vector3::new(1.0, 0.0, 0.0),
    };
    let boxed = view;
    let balls: Vec<&Ball> = balls.iter().filter(|b| usable(b)).collect();
    // The box's triangles, weighted by nearness to D: exp(−d²/2r²) with d the distance to the
    // centre of a ball of radius r > 0 (the largest over the balls).
    let near = |p: &Point3<f64>| {
        let weights = balls
            .iter()
            .filter(|b| b.radius > 0.0)
            .map(|b| (-(p - b.center).norm_squared() / (2.0 * b.radius * b.radius)).exp());
        weights.fold(None, |m: Option<f64>, w| Some(m.map_or(w, |m| m.max(w))))
    };
    let Some(context) = patch(after, |[a, b, c]| {
        let mid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
        if boxed.contains(&mid) {
            near(&mid).unwrap_or(1.0)
        } else {
            0.0
        }
    }) else {
        return view;
    };
    let Some([axis, _, box_normal]) = sorted_eigenvectors(context.tensor) else {
        return view;
    };
    let across = |v: Vector3<f64>| v - axis * axis.dot(&v);
    // From the vessel's axis towards the balls' centre: the side D is on.
    let size = (max - min).norm();
    let from_axis = context.axis_point().and_then(|x| {
        let centre =
            balls.iter().map(|b| b.center.coords).sum::<Vector3<f64>>() / balls.len().max(1) as f64;
        (!balls.is_empty())
            .then(|| across(centre - x.coords))
            .and_then(|v| v.try_normalize(1e-6 * size))
    });
    let d = match from_axis {
        Some(v) => -v,
        None => {
            // The balls' centre on the axis (or no ball): the dominant normal of D's triangles
            // (of the box's without any), from the side where D's centroid is nearer.
            let d_part = patch(after, |corners| {
                let touches = corners.iter().any(|p| balls.iter().any(|b| b.contains(p)));
                if touches {
                    1.0
                } else {
                    0.0
                }
            });
            let facing = d_part
                .and_then(|p| sorted_eigenvectors(p.tensor))
                .and_then(|[_, _, m]| across(m).try_normalize(1e-6))
                .unwrap_or(box_normal);
            let towards = d_part.map_or(0.0, |p| facing.dot(&(p.centroid - context.centroid)));
            if towards > 0.0 {
                -facing
            } else if towards < 0.0 {
                facing
            } else {
                with_largest_component_negative(facing)
            }
        }
    };
    let right = (axis - d * d.dot(&axis))
        .try_normalize(1e-9)
        .map(|r| -with_largest_component_negative(r));
    let Some(right) = right else {
        return view;
    };
    view.view = d;
    view.right = right;
    view.up = right.cross(&d);
    view
}

/// `v` or −`v`, whichever has its largest-magnitude component negative (a deterministic sign).
fn with_largest_component_negative(v: Vector3<f64>) -> Vector3<f64> {
    let k = (0..3)
        .max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
        .unwrap_or(0);
    if v[k] > 0.0 {
        -v
    } else {
        v
    }
}

/// One row's triangles: the face indices to draw and their colours.
struct Scene<'a> {
    mesh: &'a TriMesh,
    faces: Vec<([u32; 3], [u8; 3])>,
}

/// Faces of `mesh` with indices in range and finite corners.
fn drawable<'a>(mesh: &'a TriMesh) -> impl Iterator<Item = &'a [u32; 3]> + 'a {
    let n = mesh.vertices.len();
    mesh.faces.iter().filter(move |f| {
        f.iter()
            .all(|&i| (i as usize) < n && mesh.vertices[i as usize].iter().all(|c| c.is_finite()))
    })
}

fn centroid(mesh: &TriMesh, f: &[u32; 3]) -> Point3<f64> {
    let [a, b, c] = f.map(|i| mesh.vertices[i as usize].coords);
    Point3::from((a + b + c) / 3.0)
}

/// The triangles of `mesh` that are drawn: centroid in the context box, or a corner in D.
fn shown(mesh: &TriMesh, view: &RepairView, balls: &[&Ball]) -> Vec<[u32; 3]> {
    drawable(mesh)
        .filter(|f| {
            view.contains(&centroid(mesh, f))
                || f.iter()
                    .any(|&i| balls.iter().any(|b| b.contains(&mesh.vertices[i as usize])))
        })
        .copied()
        .collect()
}

/// The input's row: its shown triangles, grey.
fn input_scene<'a>(mesh: &'a TriMesh, view: &RepairView, balls: &[&Ball]) -> Scene<'a> {
    let faces = shown(mesh, view, balls)
        .into_iter()
        .map(|f| (f, SURFACE_GREY))
        .collect();
    Scene { mesh, faces }
}

/// The repaired row: its shown triangles, red where the centroid lies farther than `reach`
/// from the input's shown triangles (and those within `reach` of the box), else grey.
fn repaired_scene<'a>(
    after: &'a TriMesh,
    before: &TriMesh,
    view: &RepairView,
    balls: &[&Ball],
    reach: f64,
) -> Scene<'a> {
    let grown = RepairView {
        min: view.min - Vector3::repeat(reach),
        max: view.max + Vector3::repeat(reach),
        ..*view
    };
    // The input near what is drawn: a triangle of the input that could be within `reach` of a
    // shown centroid has a corner in the grown box or in D, or is as large as the box.
    let near: Vec<[u32; 3]> = drawable(before)
        .filter(|f| {
            f.iter().any(|&i| {
                let p = &before.vertices[i as usize];
                grown.contains(p) || balls.iter().any(|b| b.contains(p))
            }) || grown.contains(&centroid(before, f))
        })
        .copied()
        .collect();
    let bvh = MeshBvh::new(&TriMesh::new(before.vertices.clone(), near));
    let faces = shown(after, view, balls)
        .into_par_iter()
        .map(|f| {
            let added = bvh
                .closest_point_within(&centroid(after, &f), reach)
                .is_none();
            (f, if added { REPAIRED_RED } else { SURFACE_GREY })
        })
        .collect();
    Scene { mesh: after, faces }
}

/// One camera: its directions, the image-plane centre (right, up coordinates) and pixels per
/// world unit, shared by a panel of each row.
#[derive(Clone, Copy, Debug)]
struct Projection {
    right: Vector3<f64>,
    up: Vector3<f64>,
    view: Vector3<f64>,
    centre: [f64; 2],
    scale: f64,
}

impl Projection {
    /// Panel pixel coordinates (x right, y down) and depth of `p`, for a panel of `w × h` pixels
    /// drawn at `ss`× resolution.
    fn project(&self, p: &Point3<f64>, w: f64, h: f64, ss: f64) -> [f64; 3] {
        let s = self.scale * ss;
        [
            0.5 * w * ss + s * (self.right.dot(&p.coords) - self.centre[0]),
            0.5 * h * ss - s * (self.up.dot(&p.coords) - self.centre[1]),
            self.view.dot(&p.coords),
        ]
    }
}

/// The three cameras (front, top, oblique; see the module docs) of `view`.
fn cameras(view: &RepairView) -> [(Vector3<f64>, Vector3<f64>, Vector3<f64>); 3] {
    let (d, u, r) = (view.view, view.up, view.right);
    // (view, up, right) with right = view × up (r = d × u, so r × u = −d).
    let h = std::f64::consts::FRAC_1_SQRT_2;
    [(d, u, r), (-u, d, r), ((d + r) * h, u, (r - d) * h)]
}

/// Fits the drawn triangles of both scenes and the balls' discs, seen by each camera, into a
/// `w × h` panel: each camera centred on what it sees, all with the smallest of their scales.
fn fit(view: &RepairView, scenes: &[&Scene], balls: &[&Ball], w: u32, h: u32) -> [Projection; 3] {
    let fitted = cameras(view).map(|(v, u, r)| {
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let add = |b: &mut [f64; 4], p: &Point3<f64>, rad: f64| {
            let (x, y) = (r.dot(&p.coords), u.dot(&p.coords));
            *b = [
                b[0].min(x - rad),
                b[1].max(x + rad),
                b[2].min(y - rad),
                b[3].max(y + rad),
            ];
        };
        for s in scenes {
            for (f, _) in &s.faces {
                for &i in f {
                    add(&mut b, &s.mesh.vertices[i as usize], 0.0);
                }
            }
        }
        for ball in balls {
            add(&mut b, &ball.center, ball.radius);
        }
        if !b.iter().all(|v| v.is_finite()) {
            // Nothing to draw: frame the context box.
            for k in 0..8 {
                let p = Point3::new(
                    if k & 1 == 0 { view.min.x } else { view.max.x },
                    if k & 2 == 0 { view.min.y } else { view.max.y },
                    if k & 4 == 0 { view.min.z } else { view.max.z },
                );
                add(&mut b, &p, 0.0);
            }
        }
        let (ew, eh) = (b[1] - b[0], b[3] - b[2]);
        let usable_w = w as f64 * (1.0 - 2.0 * MARGIN);
        let usable_h = h as f64 * (1.0 - 2.0 * MARGIN);
        let s = (if ew > 0.0 {
            usable_w / ew
        } else {
            f64::INFINITY
        })
        .min(if eh > 0.0 {
            usable_h / eh
        } else {
            f64::INFINITY
        });
        (v, u, r, [0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3])], s)
    });
    let scale = fitted
        .iter()
        .map(|f| f.4)
        .filter(|s| s.is_finite() && *s > 0.0)
        .fold(f64::INFINITY, f64::min);
    let scale = if scale.is_finite() { scale } else { 1.0 };
    fitted.map(|(view, up, right, centre, _)| Projection {
        right,
        up,
        view,
        centre,
        scale,
    })
}

/// Draws a scene into a `w × h` panel: z-buffer, 2×2 supersampling, two-sided Lambert shading
/// with interpolated area-weighted vertex normals, one base colour per triangle.
fn draw_scene(scene: &Scene, proj: &Projection, w: u32, h: u32) -> RgbImage {
    const SS: usize = 2;
    let mesh = scene.mesh;
    let normals = vertex_normals(mesh, scene.faces.iter().map(|(f, _)| f));
    let lighting = Lighting {
        view: proj.view,
        light: (proj.right * LIGHT[0] + proj.up * LIGHT[1] - proj.view * LIGHT[2]).normalize(),
        ambient: AMBIENT,
    };
    let mut buffer = ZBuffer::new(w as usize * SS, h as usize * SS, BACKGROUND);
    for (f, base) in &scene.faces {
        let [i0, i1, i2] = f.map(|i| i as usize);
        let p =
            [i0, i1, i2].map(|i| proj.project(&mesh.vertices[i], w as f64, h as f64, SS as f64));
        let Some(face_normal) = unit_normal(mesh, f) else {
            continue;
        };
        let base = base.map(|c| c as f32);
        buffer.triangle(
            p,
            [normals[i0], normals[i1], normals[i2]],
            face_normal,
            &lighting,
            |_, _, _| base,
        );
    }
    buffer.downsample(SS, BACKGROUND)
}

/// Unit normal of face `f` of `mesh`, or `None` for a degenerate face.
fn unit_normal(mesh: &TriMesh, f: &[u32; 3]) -> Option<Vector3<f64>> {
    let [a, b, c] = f.map(|i| mesh.vertices[i as usize]);
    (b - a)
        .cross(&(c - a))
        .try_normalize(0.0)
        .filter(|n| n.iter().all(|c| c.is_finite()))
}

/// Blends an anti-aliased circle outline (line width about 2 px) of `radius` pixels about
/// (`cx`, `cy`) over the image.
fn draw_circle(image: &mut RgbImage, cx: f64, cy: f64, radius: f64, color: [u8; 3]) {
    const HALF_WIDTH: f64 = 1.0;
    if !(cx.is_finite() && cy.is_finite() && radius.is_finite()) {
        return;
    }
    let reach = radius + HALF_WIDTH + 1.0;
    let x0 = (cx - reach).floor().max(0.0);
    let x1 = (cx + reach).ceil().min(image.width as f64 - 1.0);
    let y0 = (cy - reach).floor().max(0.0);
    let y1 = (cy + reach).ceil().min(image.height as f64 - 1.0);
    if x0 > x1 || y0 > y1 {
        return;
    }
    for py in y0 as u32..=y1 as u32 {
        for px in x0 as u32..=x1 as u32 {
            let r = ((px as f64 + 0.5 - cx).powi(2) + (py as f64 + 0.5 - cy).powi(2)).sqrt();
            let a = (HALF_WIDTH + 0.5 - (r - radius).abs()).clamp(0.0, 1.0);
            if a > 0.0 {
                if let Some(p) = image.get(px, py) {
                    let mixed = [0, 1, 2]
                        .map(|k| (p[k] as f64 * (1.0 - a) + color[k] as f64 * a).round() as u8);
                    image.set(px, py, mixed);
                }
            }
        }
    }
}

/// Where the parts of a picture of size `opts` lie, `[x, y, width, height]` in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PictureLayout {
    /// `panels[row][view]`: rows input, repaired ([`ROW_NAMES`]); views front, top, oblique
    /// ([`VIEW_NAMES`]).
    pub panels: [[[u32; 4]; 3]; 2],
    /// The strip under the panels with the figures and the scale bar.
    pub caption: [u32; 4],
    /// Height of a line of text, pixels.
    pub line: u32,
}

/// The layout of a picture of size `opts`: a title line (the views' names), two rows of three
/// panels 8 pixels apart, each row's name in its first panel's corner, and a caption strip of
/// one line per figure line plus the scale bar's (a line is 3% of the height, 12 to 40 pixels).
pub fn picture_layout(opts: &RepairPictureOptions) -> PictureLayout {
    let line = ((opts.height as f64 * 0.03).clamp(12.0, 40.0) as u32).min(opts.height / 8);
    let title = line + line / 2;
    let lines = opts.figures.len() as u32 + 1;
    let caption_h = (lines * line + line / 2).min(opts.height / 3);
    let rows_h = opts.height.saturating_sub(title + caption_h);
    let panel_h = rows_h.saturating_sub(GAP) / 2;
    let panel_w = opts.width.saturating_sub(2 * GAP) / 3;
    let mut panels = [[[0; 4]; 3]; 2];
    for (r, row) in panels.iter_mut().enumerate() {
        for (c, p) in row.iter_mut().enumerate() {
            *p = [
                c as u32 * (panel_w + GAP),
                title + r as u32 * (panel_h + GAP),
                panel_w,
                panel_h,
            ];
        }
    }
    PictureLayout {
        panels,
        caption: [0, opts.height - caption_h, opts.width, caption_h],
        line,
    }
}

/// The largest 1, 2 or 5 × 10^k not above `x` (x > 0, finite).
fn round_length(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * p)
        .find(|&v| v <= x)
        .unwrap_or(p)
}

/// Draws a black bar `length` pixels long ending at column `x1` on row `y`, with end ticks.
fn draw_bar(image: &mut RgbImage, x1: u32, y: u32, length: u32) {
    let x0 = x1.saturating_sub(length);
    for x in x0..=x1 {
        for dy in 0..3 {
            image.set(x, y + dy, [0, 0, 0]);
        }
    }
    for x in [x0, x1] {
        for yy in y.saturating_sub(5)..y + 8 {
            image.set(x, yy, [0, 0, 0]);
        }
    }
}

/// The before/after picture as an image (see the module docs): the "input" row (`before` as
/// read, grey, the balls outlined) above the "repaired" row (`after`, what the repair added
/// red), each in the front, top and oblique views of [`repair_view`] of `after`, one scale; under
/// them `opts.figures` and a scale bar in `opts.unit`. Meshes with nothing in the context box
/// give blank panels. Fails when the size is out of range.
pub fn repair_picture(
    before: &TriMesh,
    after: &TriMesh,
    balls: &[Ball],
    opts: &RepairPictureOptions,
) -> Result<RgbImage> {
    let (width, height) = (opts.width, opts.height);
    for (name, v) in [("width", width), ("height", height)] {
        if !(MIN_SIDE..=MAX_SIDE).contains(&v) {
            return Err(Error::Geometry(format!(
                "repair picture {name} must be in [{MIN_SIDE}, {MAX_SIDE}] pixels, got {v}"
            )));
        }
    }
    let layout = picture_layout(opts);
    let [_, _, panel_w, panel_h] = layout.panels[0][0];
    let mut image = RgbImage::new(width, height, BACKGROUND);
    let size = layout.line as f64 * 0.8;
    for (c, name) in VIEW_NAMES.iter().enumerate() {
        let [x, _, w, _] = layout.panels[0][c];
        draw_text(
            &mut image,
            name,
            (x + w / 2) as i32,
            (layout.line / 4) as i32,
            size,
            [0, 0, 0],
            HAlign::Center,
        )?;
    }
    if panel_w < 8 || panel_h < 8 {
        return Ok(image);
    }

    let view = repair_view(after, balls);
    let usable: Vec<&Ball> = balls.iter().filter(|b| usable(b)).collect();
    let diagonal = (view.max - view.min).norm();
    let reach = if opts.added_distance > 0.0 && opts.added_distance.is_finite() {
        opts.added_distance
    } else {
        1e-6 * diagonal
    };
    let input = input_scene(before, &view, &usable);
    let repaired = repaired_scene(after, before, &view, &usable, reach);
    let projections = fit(&view, &[&input, &repaired], &usable, panel_w, panel_h);

    // The six panels drawn in parallel (the rasteriser is most of the picture's time).
    let scenes = [&input, &repaired];
    let panels: Vec<RgbImage> = (0..6)
        .into_par_iter()
        .map(|k| {
            let (r, proj) = (k / 3, &projections[k % 3]);
            let mut panel = draw_scene(scenes[r], proj, panel_w, panel_h);
            if r == 0 {
                for ball in &usable {
                    let [cx, cy, _] =
                        proj.project(&ball.center, panel_w as f64, panel_h as f64, 1.0);
                    draw_circle(&mut panel, cx, cy, ball.radius * proj.scale, OUTLINE_RED);
                }
            }
            panel
        })
        .collect();
    for (k, panel) in panels.iter().enumerate() {
        let [x, y, _, _] = layout.panels[k / 3][k % 3];
        image.blit(panel, x as i64, y as i64);
    }
    for (r, name) in ROW_NAMES.iter().enumerate() {
        let [x, y, _, _] = layout.panels[r][0];
        draw_text(
            &mut image,
            name,
            (x + 6) as i32,
            (y + 4) as i32,
            size,
            [0, 0, 0],
            HAlign::Left,
        )?;
    }

    // The figures, then the scale bar: a round length near a quarter of a panel's width.
    let [cx, cy, cw, _] = layout.caption;
    let line = layout.line;
    for (k, text) in opts.figures.iter().enumerate() {
        draw_text(
            &mut image,
            text,
            (cx + 8) as i32,
            (cy + line / 4 + k as u32 * line) as i32,
            size,
            [0, 0, 0],
            HAlign::Left,
        )?;
    }
    let scale = projections[0].scale;
    let world = panel_w as f64 / 4.0 / scale;
    if world.is_finite() && world > 0.0 {
        let length = round_length(world);
        let px = (length * scale).round() as u32;
        let unit = if opts.unit.is_empty() {
            "units"
        } else {
            &opts.unit
        };
        let y = cy + line / 4 + opts.figures.len() as u32 * line;
        let x1 = cx + cw.saturating_sub(16);
        let label = format!("{length} {unit}");
        let label_w = text_width(&label, size).ceil() as u32;
        draw_bar(&mut image, x1, y + line / 2, px);
        draw_text(
            &mut image,
            &label,
            x1.saturating_sub(px + 12 + label_w) as i32,
            y as i32,
            size,
            [0, 0, 0],
            HAlign::Left,
        )?;
    }
    Ok(image)
}

/// Writes the before/after picture of a repair ([`repair_picture`]) to `path` as a PNG,
/// atomically: on any error nothing is left at `path`.
pub fn render_repair(
    before: &TriMesh,
    after: &TriMesh,
    balls: &[Ball],
    path: &Path,
    opts: &RepairPictureOptions,
) -> Result<()> {
    let image = repair_picture(before, after, balls, opts).map_err(|e| match e {
        Error::Geometry(m) => Error::format(path, m),
        other => other,
    })?;
    write_png(path, &image)
}
