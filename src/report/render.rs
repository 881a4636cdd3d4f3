//! A small software rasteriser for figures of surfaces, with no display and no GPU: a triangle
//! mesh, optionally coloured by a per-vertex scalar, is projected by an orthographic camera
//! that fits the mesh's bounding box into the image with a margin, scan-converted with a
//! z-buffer (edge functions, barycentric interpolation at pixel centres), and shaded by
//! Lambert's cosine law plus an ambient term, two-sided (a normal facing away from the viewer is
//! flipped), with the vertex normals (area-weighted face normals) interpolated per pixel.
//! Optional 2×2 supersampling (rendering at twice the size and averaging) smooths the edges.
//!
//! Scalars are interpolated across each triangle before the colour map is applied (as ParaView
//! does by default), so a diverging field crossing zero inside a triangle shows its white line.
//! [`render_strip`] puts several surfaces side by side with one shared camera scale and one
//! shared colour range, as in the first two rows of Figure 1 of Dong, Chien, Shen and Osher
//! (the scales S_0 … S_N, coloured by the detail w_i).

use super::colormap::ColorMap;
use super::image::RgbImage;
use super::raster::{Lighting, ZBuffer};
use super::text::{draw_text, format_value, text_width, HAlign};
use crate::mesh::measures::vertex_normals;
use crate::{Error, Result, TriMesh};
use nalgebra::{Point3, Vector3};

/// An orthographic camera: the direction it looks along and the world direction shown upwards.
/// Neither needs to be a unit vector; `up` need not be orthogonal to `view` (only its part
/// orthogonal to `view` counts).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The direction the camera looks along (from the viewer into the scene).
    pub view: Vector3<f64>,
    /// The world direction that points up in the image.
    pub up: Vector3<f64>,
}

impl Default for Camera {
    /// Looking along −y with z up: a vessel lying along z is shown upright, seen from +y.
    fn default() -> Self {
        Camera {
            view: Vector3::new(0.0, -1.0, 0.0),
            up: Vector3::new(0.0, 0.0, 1.0),
        }
    }
}

/// The camera's orthonormal frame: `right`, `up`, and `view` (into the scene); right × up = −view.
#[derive(Clone, Copy, Debug)]
struct Frame {
    right: Vector3<f64>,
    up: Vector3<f64>,
    view: Vector3<f64>,
}

impl Camera {
    /// A camera looking along the shortest side of the mesh's bounding box (towards −axis, so
    /// from the +axis side), which shows the largest silhouette; up is z, or y when z is the
    /// shortest side. An empty mesh gets the default camera.
    pub fn along_shortest_axis(mesh: &TriMesh) -> Camera {
        let Some((min, max)) = finite_bounds(mesh) else {
            return Camera::default();
        };
        let extent = max - min;
        let shortest = (0..3)
            .min_by(|&a, &b| extent[a].total_cmp(&extent[b]))
            .unwrap_or(1);
        let mut view = Vector3::zeros();
        view[shortest] = -1.0;
        let up = if shortest == 2 {
            Vector3::new(0.0, 1.0, 0.0)
        } else {
            Vector3::new(0.0, 0.0, 1.0)
        };
        Camera { view, up }
    }

    /// The orthonormal frame; a zero or non-finite `view` falls back to the default, an `up`
    /// parallel to `view` to the world axis most orthogonal to `view`.
    fn frame(&self) -> Frame {
        let view = match self.view.try_normalize(1e-300) {
            Some(v) if v.iter().all(|c| c.is_finite()) => v,
            _ => Camera::default().view,
        };
        let orthogonal = |u: Vector3<f64>| {
            let u = u - view * u.dot(&view);
            u.try_normalize(1e-9 * u.norm().max(1e-300))
                .filter(|u| u.iter().all(|c| c.is_finite()) && u.norm() > 0.5)
        };
        let up = orthogonal(self.up).unwrap_or_else(|| {
            let axis = (0..3)
                .min_by(|&a, &b| view[a].abs().total_cmp(&view[b].abs()))
                .unwrap_or(2);
            let mut e = Vector3::zeros();
            e[axis] = 1.0;
            orthogonal(e).unwrap_or(Vector3::new(0.0, 0.0, 1.0))
        });
        Frame {
            right: view.cross(&up),
            up,
            view,
        }
    }
}

/// How a surface is drawn. Sizes are in pixels; the camera scale is chosen by fitting the mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Orthographic camera (only the directions; position and scale fit the mesh).
    pub camera: Camera,
    /// Blank border on each side, as a fraction of the image's width and height (0 ≤ margin < 0.5).
    pub margin: f64,
    /// Render at 2×2 the size and average each 2×2 block, for smooth edges.
    pub supersample: bool,
    /// Colour of the pixels the surface does not cover.
    pub background: [u8; 3],
    /// Colour of the surface when no scalar is given.
    pub surface_color: [u8; 3],
    /// Colour map for the scalar.
    pub colormap: ColorMap,
    /// Scalar range mapped onto the colour map (lo, hi), in the scalar's units; `None` picks it
    /// with [`ColorMap::auto_range`] (symmetric 99th percentile of |w| for the diverging map).
    pub range: Option<(f64, f64)>,
    /// Direction towards the light in the camera's frame: x right, y up, z towards the viewer.
    pub light: Vector3<f64>,
    /// Ambient part of the lighting, 0 ≤ ambient ≤ 1; the rest is Lambertian.
    pub ambient: f64,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 480,
            height: 480,
            camera: Camera::default(),
            margin: 0.05,
            supersample: true,
            background: [255, 255, 255],
            surface_color: [200, 200, 200],
            colormap: ColorMap::Diverging,
            range: None,
            light: Vector3::new(-0.35, 0.45, 0.82),
            ambient: 0.3,
        }
    }
}

/// One surface of a strip, with its optional per-vertex scalar and title.
#[derive(Clone, Copy, Debug)]
pub struct Panel<'a> {
    pub mesh: &'a TriMesh,
    /// One value per vertex of `mesh`, or `None` for a plain surface.
    pub scalars: Option<&'a [f64]>,
    /// Text above the panel (e.g. "S_2"); empty for none.
    pub title: &'a str,
}

/// How a strip of panels is laid out; each panel is drawn with `panel` (its width and height
/// are those of one panel, its camera and colour map are shared by all).
#[derive(Clone, Debug, PartialEq)]
pub struct StripOptions {
    pub panel: RenderOptions,
    /// Pixels between neighbouring panels.
    pub gap: u32,
    /// Height in pixels of the band above the panels that holds their titles (0: no titles).
    pub title_height: u32,
    /// Caption of the colour bar drawn under the panels (e.g. "detail w / h"); `None` for no
    /// colour bar. Drawn only when some panel has a scalar.
    pub colorbar: Option<String>,
}

impl Default for StripOptions {
    fn default() -> Self {
        StripOptions {
            panel: RenderOptions {
                width: 320,
                height: 400,
                ..RenderOptions::default()
            },
            gap: 8,
            title_height: 28,
            colorbar: Some("detail w".to_string()),
        }
    }
}

/// Bounding box of the finite vertices used by in-range faces, or `None` if there is none.
fn finite_bounds(mesh: &TriMesh) -> Option<(Point3<f64>, Point3<f64>)> {
    let mut min = Point3::from([f64::INFINITY; 3]);
    let mut max = Point3::from([f64::NEG_INFINITY; 3]);
    let mut any = false;
    for_each_used_vertex(mesh, |p| {
        any = true;
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    });
    any.then_some((min, max))
}

/// Calls `f` on every finite vertex of every face whose three indices are in range (a vertex
/// shared by several faces is visited several times).
fn for_each_used_vertex(mesh: &TriMesh, mut f: impl FnMut(&Point3<f64>)) {
    let n = mesh.vertices.len();
    for face in &mesh.faces {
        if face.iter().all(|&i| (i as usize) < n) {
            for &i in face {
                let p = &mesh.vertices[i as usize];
                if p.iter().all(|c| c.is_finite()) {
                    f(p);
                }
            }
        }
    }
}

/// The extent of the mesh in the camera's image plane: (min right, max right, min up, max up).
fn projected_bounds(mesh: &TriMesh, frame: &Frame) -> Option<[f64; 4]> {
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut any = false;
    for_each_used_vertex(mesh, |p| {
        any = true;
        let (r, u) = (frame.right.dot(&p.coords), frame.up.dot(&p.coords));
        b = [b[0].min(r), b[1].max(r), b[2].min(u), b[3].max(u)];
    });
    any.then_some(b)
}

/// Pixels per world unit that fit `bounds` into `width × height` less the margin.
fn fit_scale(bounds: &[f64; 4], width: u32, height: u32, margin: f64) -> f64 {
    let margin = if margin.is_finite() {
        margin.clamp(0.0, 0.49)
    } else {
        0.0
    };
    let usable_w = width as f64 * (1.0 - 2.0 * margin);
    let usable_h = height as f64 * (1.0 - 2.0 * margin);
    let (ew, eh) = (bounds[1] - bounds[0], bounds[3] - bounds[2]);
    let sw = if ew > 0.0 {
        usable_w / ew
    } else {
        f64::INFINITY
    };
    let sh = if eh > 0.0 {
        usable_h / eh
    } else {
        f64::INFINITY
    };
    let s = sw.min(sh);
    if s.is_finite() && s > 0.0 {
        s
    } else {
        1.0
    }
}

/// Checks that `scalars` has one value per vertex.
fn check_scalars(mesh: &TriMesh, scalars: Option<&[f64]>) -> Result<()> {
    match scalars {
        Some(s) if s.len() != mesh.num_vertices() => Err(Error::InvalidMesh(format!(
            "the scalar field has {} values for {} vertices",
            s.len(),
            mesh.num_vertices()
        ))),
        _ => Ok(()),
    }
}

/// Renders `mesh` into a `width × height` image (see the module doc), coloured by `scalars`
/// (one value per vertex) when given, otherwise in `surface_color`. The camera is fitted to the
/// mesh's bounding box. Faces with out-of-range indices or non-finite corners are skipped; a
/// mesh with nothing to draw gives a blank image. Fails only if `scalars` has the wrong length.
pub fn render_mesh(
    mesh: &TriMesh,
    scalars: Option<&[f64]>,
    opts: &RenderOptions,
) -> Result<RgbImage> {
    check_scalars(mesh, scalars)?;
    let frame = opts.camera.frame();
    let range = scalars.map(|s| opts.range.unwrap_or_else(|| opts.colormap.auto_range(s)));
    let Some(bounds) = projected_bounds(mesh, &frame) else {
        return Ok(RgbImage::new(opts.width, opts.height, opts.background));
    };
    let scale = fit_scale(&bounds, opts.width, opts.height, opts.margin);
    Ok(rasterize(
        mesh, scalars, range, &frame, &bounds, scale, opts,
    ))
}

/// Renders the panels side by side, left to right, with one camera scale for all (the largest
/// that fits every panel), each panel centred in its cell, titles above and a colour bar below.
/// The scalar range is `opts.panel.range` or the automatic range of all panels' scalars
/// together, so equal colours mean equal values across the strip. Fails if a panel's scalar
/// field has the wrong length.
pub fn render_strip(panels: &[Panel], opts: &StripOptions) -> Result<RgbImage> {
    let p = &opts.panel;
    for panel in panels {
        check_scalars(panel.mesh, panel.scalars)?;
    }
    let frame = p.camera.frame();
    let all: Vec<f64> = panels
        .iter()
        .filter_map(|q| q.scalars)
        .flatten()
        .copied()
        .collect();
    let has_scalars = panels.iter().any(|q| q.scalars.is_some());
    let range = p.range.unwrap_or_else(|| p.colormap.auto_range(&all));
    let bounds: Vec<Option<[f64; 4]>> = panels
        .iter()
        .map(|q| projected_bounds(q.mesh, &frame))
        .collect();
    let scale = bounds
        .iter()
        .flatten()
        .map(|b| fit_scale(b, p.width, p.height, p.margin))
        .fold(f64::INFINITY, f64::min);

    let n = panels.len() as u32;
    let width = (n * p.width + n.saturating_sub(1) * opts.gap).max(1);
    let bar = has_scalars && opts.colorbar.is_some();
    let bar_height = if bar { 64 } else { 0 };
    let height = opts.title_height + p.height + bar_height;
    let mut image = RgbImage::new(width, height, p.background);
    for (i, (panel, b)) in panels.iter().zip(&bounds).enumerate() {
        let x = i as u32 * (p.width + opts.gap);
        let tile = match b {
            Some(b) => rasterize(
                panel.mesh,
                panel.scalars,
                panel.scalars.map(|_| range),
                &frame,
                b,
                scale,
                p,
            ),
            None => RgbImage::new(p.width, p.height, p.background),
        };
        image.blit(&tile, x as i64, opts.title_height as i64);
        if opts.title_height > 0 && !panel.title.is_empty() {
            let size = (opts.title_height as f64 * 0.7).clamp(8.0, 40.0);
            draw_text(
                &mut image,
                panel.title,
                (x + p.width / 2) as i32,
                ((opts.title_height as f64 - size) / 2.0) as i32,
                size,
                [0, 0, 0],
                HAlign::Center,
            )?;
        }
    }
    if bar {
        let caption = opts.colorbar.as_deref().unwrap_or("");
        draw_colorbar(
            &mut image,
            opts.title_height + p.height,
            p.colormap,
            range,
            caption,
        )?;
    }
    Ok(image)
}

/// Draws a horizontal colour bar, centred, just below row `top`, with the range's end values and
/// middle written under it and `caption` to its left.
fn draw_colorbar(
    image: &mut RgbImage,
    top: u32,
    map: ColorMap,
    (lo, hi): (f64, f64),
    caption: &str,
) -> Result<()> {
    let bar_w = (image.width as f64 * 0.5).clamp(60.0, 600.0) as i64;
    let bar_h = 14i64;
    let x0 = (image.width as i64 - bar_w) / 2;
    let y0 = top as i64 + 8;
    for i in 0..bar_w {
        let v = lo + (hi - lo) * (i as f64 + 0.5) / bar_w as f64;
        image.fill_rect(x0 + i, y0, 1, bar_h, map.color(v, (lo, hi)));
    }
    let frame = [90, 90, 90];
    image.fill_rect(x0 - 1, y0 - 1, bar_w + 2, 1, frame);
    image.fill_rect(x0 - 1, y0 + bar_h, bar_w + 2, 1, frame);
    image.fill_rect(x0 - 1, y0 - 1, 1, bar_h + 2, frame);
    image.fill_rect(x0 + bar_w, y0 - 1, 1, bar_h + 2, frame);
    let size = 15.0;
    let ty = (y0 + bar_h + 4) as i32;
    let mid = 0.5 * (lo + hi);
    for (v, x) in [(lo, x0), (mid, x0 + bar_w / 2), (hi, x0 + bar_w)] {
        image.fill_rect(x, y0 + bar_h, 1, 4, frame);
        draw_text(
            image,
            &format_value(v),
            x as i32,
            ty,
            size,
            [0, 0, 0],
            HAlign::Center,
        )?;
    }
    if !caption.is_empty() {
        let w = text_width(caption, size);
        let cx = (x0 - 12 - w as i64).max(2) as i32;
        draw_text(
            image,
            caption,
            cx,
            (y0 - 1) as i32,
            size,
            [0, 0, 0],
            HAlign::Left,
        )?;
    }
    Ok(())
}

/// Scan-converts the mesh with the given frame, image-plane `bounds` (whose centre goes to the
/// image centre) and `scale` (pixels per world unit).
fn rasterize(
    mesh: &TriMesh,
    scalars: Option<&[f64]>,
    range: Option<(f64, f64)>,
    frame: &Frame,
    bounds: &[f64; 4],
    scale: f64,
    opts: &RenderOptions,
) -> RgbImage {
    let ss: usize = if opts.supersample { 2 } else { 1 };
    let (w, h) = (opts.width as usize * ss, opts.height as usize * ss);
    let scale = scale * ss as f64;
    let (cr, cu) = (0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]));
    let n = mesh.vertices.len();
    let valid = |f: &[u32; 3]| {
        f.iter().all(|&i| (i as usize) < n)
            && f.iter()
                .all(|&i| mesh.vertices[i as usize].iter().all(|c| c.is_finite()))
    };

    // Screen position (x right, y down, pixel units) and depth (along the view) of each vertex.
    let screen: Vec<[f64; 3]> = mesh
        .vertices
        .iter()
        .map(|p| {
            [
                0.5 * w as f64 + scale * (frame.right.dot(&p.coords) - cr),
                0.5 * h as f64 - scale * (frame.up.dot(&p.coords) - cu),
                frame.view.dot(&p.coords),
            ]
        })
        .collect();
    let normals = vertex_normals(mesh, mesh.faces.iter().filter(|f| valid(f)));
    let light = {
        let l = opts.light;
        let l = frame.right * l.x + frame.up * l.y - frame.view * l.z;
        l.try_normalize(0.0).unwrap_or(-frame.view)
    };
    let lighting = Lighting {
        view: frame.view,
        light,
        ambient: if opts.ambient.is_finite() {
            opts.ambient.clamp(0.0, 1.0)
        } else {
            0.3
        },
    };
    let base = opts.surface_color.map(|c| c as f32);
    let mut buffer = ZBuffer::new(w, h, opts.background);
    for f in mesh.faces.iter().filter(|f| valid(f)) {
        let [i0, i1, i2] = f.map(|i| i as usize);
        let face_normal = {
            let [a, b, c] = f.map(|i| mesh.vertices[i as usize]);
            (b - a).cross(&(c - a)).try_normalize(0.0)
        };
        let Some(face_normal) = face_normal else {
            continue;
        };
        buffer.triangle(
            [screen[i0], screen[i1], screen[i2]],
            [normals[i0], normals[i1], normals[i2]],
            face_normal,
            &lighting,
            |b0, b1, b2| match (scalars, range) {
                (Some(s), Some(range)) => opts
                    .colormap
                    .color(b0 * s[i0] + b1 * s[i1] + b2 * s[i2], range)
                    .map(|c| c as f32),
                _ => base,
            },
        );
    }
    buffer.downsample(ss, opts.background)
}
