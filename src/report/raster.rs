//! The z-buffered triangle rasteriser shared by the figures (`render`) and the repair picture
//! (`repair_picture`): screen-space triangles (x right, y down, in pixels of a supersampled
//! buffer, plus depth along the view), Gouraud-interpolated normals lit by one directional light
//! with an ambient term and two-sided shading, and a box-filter downsample to the final image.

use super::image::RgbImage;
use nalgebra::Vector3;

/// The lighting of a scene: view direction (into the screen), light direction, ambient share.
pub(super) struct Lighting {
    pub view: Vector3<f64>,
    pub light: Vector3<f64>,
    pub ambient: f64,
}

/// A colour and depth buffer of `width × height` pixels.
pub(super) struct ZBuffer {
    pub width: usize,
    pub height: usize,
    depth: Vec<f64>,
    color: Vec<[f32; 3]>,
}

impl ZBuffer {
    /// A buffer cleared to `background`.
    pub fn new(width: usize, height: usize, background: [u8; 3]) -> Self {
        ZBuffer {
            width,
            height,
            depth: vec![f64::INFINITY; width * height],
            color: vec![background.map(|c| c as f32); width * height],
        }
    }

    /// Draws the triangle with screen points `p` (x, y, depth), vertex normals `normals` and
    /// unit face normal `face_normal`; `base` gives the unshaded colour at barycentric
    /// coordinates (b0, b1, b2). Degenerate or off-screen triangles draw nothing.
    pub fn triangle(
        &mut self,
        p: [[f64; 3]; 3],
        normals: [Vector3<f64>; 3],
        face_normal: Vector3<f64>,
        lighting: &Lighting,
        base: impl Fn(f64, f64, f64) -> [f32; 3],
    ) {
        let [p0, p1, p2] = p;
        let edge = |a: [f64; 3], b: [f64; 3], x: f64, y: f64| {
            (b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])
        };
        let area = edge(p0, p1, p2[0], p2[1]);
        if !area.is_finite() || area.abs() < 1e-12 {
            return;
        }
        // Pixels whose centres (x + ½, y + ½) can lie in the triangle.
        let x0 = (p0[0].min(p1[0]).min(p2[0]) - 0.5).ceil().max(0.0);
        let x1 = (p0[0].max(p1[0]).max(p2[0]) - 0.5)
            .floor()
            .min(self.width as f64 - 1.0);
        let y0 = (p0[1].min(p1[1]).min(p2[1]) - 0.5).ceil().max(0.0);
        let y1 = (p0[1].max(p1[1]).max(p2[1]) - 0.5)
            .floor()
            .min(self.height as f64 - 1.0);
        if x0 > x1 || y0 > y1 {
            return;
        }
        let ambient = lighting.ambient;
        for py in y0 as usize..=y1 as usize {
            let y = py as f64 + 0.5;
            for px in x0 as usize..=x1 as usize {
                let x = px as f64 + 0.5;
                let b0 = edge(p1, p2, x, y) / area;
                let b1 = edge(p2, p0, x, y) / area;
                let b2 = edge(p0, p1, x, y) / area;
                if b0 < 0.0 || b1 < 0.0 || b2 < 0.0 {
                    continue;
                }
                let d = b0 * p0[2] + b1 * p1[2] + b2 * p2[2];
                let k = py * self.width + px;
                if d >= self.depth[k] {
                    continue;
                }
                self.depth[k] = d;
                let mut nrm = (normals[0] * b0 + normals[1] * b1 + normals[2] * b2)
                    .try_normalize(1e-6)
                    .unwrap_or(face_normal);
                if nrm.dot(&lighting.view) > 0.0 {
                    nrm = -nrm;
                }
                let shade = (ambient + (1.0 - ambient) * nrm.dot(&lighting.light).max(0.0)) as f32;
                self.color[k] = base(b0, b1, b2).map(|c| c * shade);
            }
        }
    }

    /// The image of `width / factor × height / factor` pixels, each the mean of its
    /// `factor × factor` block.
    pub fn downsample(&self, factor: usize, background: [u8; 3]) -> RgbImage {
        let (w, h) = (self.width / factor, self.height / factor);
        let mut image = RgbImage::new(w as u32, h as u32, background);
        let norm = 1.0 / (factor * factor) as f32;
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0f32; 3];
                for dy in 0..factor {
                    for dx in 0..factor {
                        let c = self.color[(y * factor + dy) * self.width + x * factor + dx];
                        for k in 0..3 {
                            sum[k] += c[k];
                        }
                    }
                }
                image.pixels[y * w + x] = sum.map(|s| (s * norm).round().clamp(0.0, 255.0) as u8);
            }
        }
        image
    }
}
