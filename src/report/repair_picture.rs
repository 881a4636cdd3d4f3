//! The before/after picture of a repair (issue 6, point 4; `--picture P.png`): two panels side
//! by side, "input" and "repaired", drawn with one camera, as in Figure 3 of Dong, Chien, Shen
//! and Osher (row 1: the vessel before inpainting with the regions marked by red circles; row 3:
//! the inpainted regions shown in red).
//!
//! - Framing: the context box is the bounding box of the balls of D grown ×[`CONTEXT_GROWTH`]
//!   about its centre; only the triangles whose centroid lies in it (or that touch D) are drawn,
//!   so the rest of a large vessel tree neither hides D nor shrinks it to a dot. The camera is
//!   orthographic and fitted to what is drawn (both meshes and the balls' discs), one scale for
//!   both panels.
//! - View direction ([`repair_view`]): perpendicular to the vessel, D face on. From the
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
//!   made orthogonal to the axis, from the side where D's centroid is nearer.
//! - Drawing: a z-buffered scan conversion with 2×2 supersampling, two-sided Lambert shading
//!   plus ambient (as [`super::render`]), but with one colour per triangle: grey surfaces, the
//!   repaired mesh's triangles in D (a corner in some ball) red, the input's tinted light red,
//!   and each ball's outline (its orthographic projection, a circle) in dark red on the input.
//!
//! Sizes are in pixels; world units are those of the meshes (never assumed to be mm).

use super::image::{write_png, RgbImage};
use super::raster::{vertex_normals, Lighting, ZBuffer};
use super::text::{draw_text, HAlign};
use crate::inpaint::region::Ball;
use crate::{Error, Result, TriMesh};
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use std::path::Path;

/// Factor by which the bounding box of the balls is grown (about its centre) into the context
/// box that is drawn.
pub const CONTEXT_GROWTH: f64 = 2.5;
/// Colour of surfaces outside D.
pub const SURFACE_GREY: [u8; 3] = [200, 200, 200];
/// Colour of the repaired mesh's triangles in D.
pub const REPAIRED_RED: [u8; 3] = [220, 40, 35];
/// Colour of the input mesh's triangles in D.
pub const INPUT_TINT: [u8; 3] = [245, 175, 165];
/// Colour of the balls' outlines on the input panel.
pub const OUTLINE_RED: [u8; 3] = [170, 10, 10];
/// Colour of the pixels no surface covers.
pub const BACKGROUND: [u8; 3] = [255, 255, 255];

/// Largest accepted width or height, pixels.
const MAX_SIDE: u32 = 4096;
/// Smallest accepted width or height, pixels.
const MIN_SIDE: u32 = 32;
/// Pixels between the two panels.
const GAP: u32 = 8;
/// Blank border of each panel, as a fraction of its width and height.
const MARGIN: f64 = 0.04;
/// Direction towards the light in the camera's frame (x right, y up, z towards the viewer).
const LIGHT: [f64; 3] = [-0.35, 0.45, 0.82];
/// Ambient part of the lighting; the rest is Lambertian.
const AMBIENT: f64 = 0.3;

/// Size of the picture.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RepairPictureOptions {
    /// Width of the whole picture (both panels), pixels, in [32, 4096].
    pub width: u32,
    /// Height of the whole picture (titles and panels), pixels, in [32, 4096].
    pub height: u32,
}

impl Default for RepairPictureOptions {
    fn default() -> Self {
        RepairPictureOptions {
            width: 1200,
            height: 600,
        }
    }
}

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

/// One panel's triangles: the face indices to draw and their colours.
struct Scene<'a> {
    mesh: &'a TriMesh,
    faces: Vec<([u32; 3], [u8; 3])>,
}

/// The triangles of `mesh` that are drawn (centroid in the context box, or a corner in D), in
/// `in_d` when a corner is in some ball, else in grey. Faces with out-of-range indices or
/// non-finite corners are left out.
fn scene<'a>(mesh: &'a TriMesh, view: &RepairView, balls: &[Ball], in_d: [u8; 3]) -> Scene<'a> {
    let n = mesh.vertices.len();
    let balls: Vec<&Ball> = balls.iter().filter(|b| usable(b)).collect();
    let in_ball: Vec<bool> = mesh
        .vertices
        .iter()
        .map(|p| balls.iter().any(|b| b.contains(p)))
        .collect();
    let faces = mesh
        .faces
        .iter()
        .filter(|f| {
            f.iter().all(|&i| {
                (i as usize) < n && mesh.vertices[i as usize].iter().all(|c| c.is_finite())
            })
        })
        .filter_map(|f| {
            let touches_d = f.iter().any(|&i| in_ball[i as usize]);
            let [a, b, c] = f.map(|i| mesh.vertices[i as usize].coords);
            let centroid = Point3::from((a + b + c) / 3.0);
            (touches_d || view.contains(&centroid))
                .then_some((*f, if touches_d { in_d } else { SURFACE_GREY }))
        })
        .collect();
    Scene { mesh, faces }
}

/// The orthographic projection shared by both panels: image-plane centre (right, up
/// coordinates) and pixels per world unit, for a panel of `width × height`.
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

/// Fits the drawn triangles of both scenes and the balls' discs into a `w × h` panel.
fn fit(view: &RepairView, scenes: &[&Scene], balls: &[Ball], w: u32, h: u32) -> Projection {
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let add = |b: &mut [f64; 4], p: &Point3<f64>, r: f64| {
        let (x, y) = (view.right.dot(&p.coords), view.up.dot(&p.coords));
        *b = [
            b[0].min(x - r),
            b[1].max(x + r),
            b[2].min(y - r),
            b[3].max(y + r),
        ];
    };
    for s in scenes {
        for (f, _) in &s.faces {
            for &i in f {
                add(&mut b, &s.mesh.vertices[i as usize], 0.0);
            }
        }
    }
    for ball in balls.iter().filter(|b| usable(b)) {
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
    Projection {
        right: view.right,
        up: view.up,
        view: view.view,
        centre: [0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3])],
        scale: if s.is_finite() && s > 0.0 { s } else { 1.0 },
    }
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

/// Where the two panels lie in a picture of size `opts`: `[x, y, width, height]` in pixels of
/// the "input" panel and of the "repaired" one. The titles take the top 7% of the height
/// (16 to 64 pixels), the panels the rest, each (width − 8) / 2 wide, 8 pixels apart.
pub fn panel_layout(opts: &RepairPictureOptions) -> [[u32; 4]; 2] {
    let title_h = (opts.height as f64 * 0.07).clamp(16.0, 64.0) as u32;
    let title_h = title_h.min(opts.height / 2);
    let panel_w = opts.width.saturating_sub(GAP) / 2;
    let panel_h = opts.height - title_h;
    [
        [0, title_h, panel_w, panel_h],
        [opts.width - panel_w, title_h, panel_w, panel_h],
    ]
}

/// The before/after picture as an image (see the module docs): panel "input" (`before`, its
/// triangles in D tinted light red, the balls outlined) on the left, panel "repaired" (`after`,
/// its triangles in D red) on the right, one camera ([`repair_view`] of `after`). Meshes with
/// nothing in the context box give blank panels. Fails when the size is out of range.
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
    let [[_, title_h, panel_w, panel_h], [right_x, _, _, _]] = panel_layout(opts);

    let view = repair_view(after, balls);
    let input = scene(before, &view, balls, INPUT_TINT);
    let repaired = scene(after, &view, balls, REPAIRED_RED);
    let proj = fit(&view, &[&input, &repaired], balls, panel_w, panel_h);

    let mut image = RgbImage::new(width, height, BACKGROUND);
    let mut left = draw_scene(&input, &proj, panel_w, panel_h);
    for ball in balls.iter().filter(|b| usable(b)) {
        let [cx, cy, _] = proj.project(&ball.center, panel_w as f64, panel_h as f64, 1.0);
        draw_circle(&mut left, cx, cy, ball.radius * proj.scale, OUTLINE_RED);
    }
    let right = draw_scene(&repaired, &proj, panel_w, panel_h);
    image.blit(&left, 0, title_h as i64);
    image.blit(&right, right_x as i64, title_h as i64);
    let size = title_h as f64 * 0.7;
    for (title, x) in [("input", panel_w / 2), ("repaired", right_x + panel_w / 2)] {
        draw_text(
            &mut image,
            title,
            x as i32,
            ((title_h as f64 - size) / 2.0) as i32,
            size,
            [0, 0, 0],
            HAlign::Center,
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
