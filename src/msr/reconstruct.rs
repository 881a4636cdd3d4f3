//! Reconstruction (IMST) by the level set (paper Definition 2.1(4)): from φ_i, whose zero level
//! set is S_i, and the details W_i at the samples X_i ∈ S_i, the level set φ_{i−1} of S_{i−1}.
//!
//! φ is advected back along the details in one semi-Lagrangian step: a point x of S_{i−1} came
//! from y = x + W(x) on S_i, so φ_{i−1}(x) = φ_i(y). W at a node comes either from W_i extended
//! around S_i constant along normals ([`super::extend`]), y then found by fixed-point iteration
//! of y = x + W̃(y) from y₀ = x + W̃(x) (the paper's way), or, by default, from the samples'
//! own positions on S_{i−1}, X_{i−1} = X_i − W_i, looked up around x ([`Departure`]). Nodes
//! outside the band keep φ_i; the result is redistanced (closest-point transform,
//! [`RedistanceScheme::ClosestPointTransform`]). (The reconstruction by vertices needs none of
//! this: [`super::Msr::mesh_at`].)

use super::extend::{extend_to_band, ExtendFrom, NodeField, SampleIndex};
use crate::grid::Grid3;
use crate::levelset::redistance::{redistance, RedistanceOptions, RedistanceScheme};
use crate::levelset::speck::{clear_specks, SPECK};
use crate::Result;
use nalgebra::{Point3, Vector3, Vector4};
use rayon::prelude::*;

/// Radius of the tangent disc each sample stands for (voxels): about half the spacing of the
/// samples.
const DISC_RADIUS: f64 = 0.5;
/// Scale of the soft minimum over the discs (voxels): a disc this much farther than the nearest
/// weighs e⁻¹ of it.
const DISC_SOFTNESS: f64 = 0.1;
/// A node takes tangent planes only if its nearest discs' samples are at most this many voxels
/// off their normal lines through it.
const LATERAL_REACH: f64 = 1.5;
/// Spread σ of the weights of the tangent planes (voxels): a sample whose squared distance to
/// the node exceeds the nearest's by σ² weighs e^(−1/2) of it.
const PLANE_SPREAD: f64 = 0.25;

/// A sample whose normal line passes this near a node (voxels), and which is no farther from it
/// than the nearest sample by more than the coverage, is the node's foot point, whose plane
/// gives the node its distance alone (no average, no clamp). The decomposition's samples for
/// misread nodes are such ([`super::misread`]); another sample passes this near a node by
/// chance only, and its plane is then as good a distance.
const FOOT_LATERAL: f64 = 0.01;

/// A node farther than this (voxels) beyond the largest detail of the samples around it from
/// S_i keeps φ_i. On the cortex's five levels no node farther than half a voxel beyond it takes
/// the other side from the planes, so such a node, and its neighbours a voxel nearer, keep
/// their side, and the zero crossings and the values next to them are the planes' as before
/// (measured: the same signs and the same values at every node next to a crossing; only the
/// distances the redistancer measures farther out move, through its curvature estimates at the
/// crossings, which read a node or two beyond them). It halves the nodes that query the planes.
const SURE_SIDE: f64 = 1.5;

/// Samples whose normal makes a larger angle than this (cosine) with the nearest sample's lie on
/// another sheet of the surface (the far bank of a crease) and give a node no plane.
const SAME_SHEET: f64 = 0.0;

/// Options of [`advect_back`].
#[derive(Debug, Clone, Copy)]
pub struct AdvectOptions {
    /// Fixed-point iterations for the departure point y = x + W̃(y).
    pub fixed_point_iterations: usize,
    /// Search radius of the extension around each foot point (voxels).
    pub extension_radius: f64,
    /// Band beyond the largest detail where φ is advected (voxels).
    pub band_margin: f64,
    /// How the details reach the grid nodes: [`Departure::FootPoint`] extends W_i from the
    /// samples X_i on S_i constant along normals and solves y = x + W̃(y) (the paper);
    /// [`Departure::Arrival`] looks W_i up around the node among the samples' positions
    /// X_{i−1} = X_i − W_i on S_{i−1} (the same data), which keeps the two banks of a fold that
    /// S_i has smoothed over apart.
    pub departure: Departure,
    /// Every point of S_{i−1} has a sample within about this distance (voxels). Default: the
    /// decomposition's [`super::decompose::DecomposeOptions::cover_radius`] (samples a quarter
    /// voxel around each vertex of the marching-cubes surface); samples spaced s apart and no
    /// more cover s/2. [`rebuild_from_tangent_planes`] keeps each node's value no nearer to zero
    /// than its nearest sample's distance less this.
    pub coverage: f64,
}

/// See [`AdvectOptions::departure`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Departure {
    FootPoint,
    #[default]
    Arrival,
}

impl Default for AdvectOptions {
    fn default() -> Self {
        AdvectOptions {
            fixed_point_iterations: 6,
            extension_radius: 1.5,
            band_margin: 2.0,
            departure: Departure::default(),
            coverage: 0.25,
        }
    }
}

/// φ_{i−1} from φ_i and the details `details` at the samples `samples` (see the module doc).
pub fn advect_back(
    phi: &Grid3,
    samples: &[Point3<f64>],
    details: &[Vector3<f64>],
    opts: &AdvectOptions,
) -> Result<Grid3> {
    let h = phi.voxel();
    let largest = details.iter().map(|w| w.norm()).fold(0.0, f64::max);
    let band = largest + opts.band_margin * h;
    let radius = opts.extension_radius * h;
    let previous: Vec<Point3<f64>>;
    let field = match opts.departure {
        Departure::FootPoint => extend_to_band(
            phi,
            samples,
            details,
            band + largest,
            radius,
            ExtendFrom::FootPoint,
        ),
        Departure::Arrival => {
            previous = samples.iter().zip(details).map(|(x, w)| x - w).collect();
            extend_to_band(phi, &previous, details, band, radius, ExtendFrom::Node)
        }
    };
    let iterations = match opts.departure {
        Departure::FootPoint => opts.fixed_point_iterations,
        Departure::Arrival => 0,
    };
    let mut out = phi.clone();
    let values: Vec<f32> = (0..phi.data().len())
        .into_par_iter()
        .map(|n| {
            let v = phi.data()[n];
            if (v as f64).abs() > band {
                return v;
            }
            let [i, j, k] = phi.coords(n);
            let x = phi.world(i, j, k);
            let Some(w0) = field[n] else {
                return v;
            };
            let mut y = x + w0;
            for _ in 0..iterations {
                match sample_field(phi, &field, &y) {
                    Some(w) => y = x + w,
                    None => break,
                }
            }
            phi.sample_tricubic(&y).map_or(v, |p| p as f32)
        })
        .collect();
    out.data_mut().copy_from_slice(&values);
    redistance(
        &mut out,
        &RedistanceOptions {
            scheme: RedistanceScheme::ClosestPointTransform,
            ..RedistanceOptions::default()
        },
    )?;
    Ok(out)
}

/// φ_{i−1} from φ_i and the samples of S_{i−1} (X_{i−1}, with their outward normals n_{i−1} and
/// the details W_i that took them to S_i): near the samples, each node takes its signed distance
/// n·(x − X) to the tangent planes of its nearest samples (the semi-Lagrangian step φ_i(y) of
/// [`advect_back`] carried with the rotation of the sample's frame from n_i to n_{i−1}, which to
/// first order is exactly that distance), averaged with weights that fall fast with the
/// distance to the sample (Gaussian, σ = a quarter voxel beyond the nearest), so each node
/// follows its own sheet where two sheets of S_{i−1} lie close, as the banks of a narrow sulcus
/// do; elsewhere the side comes from φ_i, at least `band_margin` voxels from the surface; then
/// the redistance (closest-point transform) of a band, the nodes next to the zero level set
/// keeping the planes' values.
///
/// The value is kept within what the samples allow: no farther from S_{i−1} than the nearest
/// sample, d_min, and no nearer than d_min − `coverage` (every point of S_{i−1} has a sample
/// within `coverage`), so a plane seen far from its sample, where the surface has curved away,
/// cannot put a zero crossing where no sample is. A sample whose normal line passes through the
/// node (within `FOOT_LATERAL`, a hundredth of a voxel) is the node's foot point: its plane is
/// seen where it was taken, so the node takes its distance alone, as it is (the decomposition
/// places such samples where this rebuild would otherwise misread S_{i−1}, [`super::misread`]).
/// Where S_i has closed a fold of S_{i−1} (a sulcus smoothed over), this keeps the fold's
/// walls apart, which the plain translation of [`advect_back`] cannot.
pub fn rebuild_from_tangent_planes(
    phi: &Grid3,
    previous: &[Point3<f64>],
    normals: &[Vector3<f64>],
    details: &[Vector3<f64>],
    opts: &AdvectOptions,
) -> Result<Grid3> {
    let planes = TangentPlanes::new(phi, previous, normals, details, opts);
    let mut out = phi.clone();
    let values: Vec<f32> = (0..phi.data().len())
        .into_par_iter()
        .map(|n| planes.node_value(phi, n))
        .collect();
    out.data_mut().copy_from_slice(&values);
    clear_specks(&mut out, SPECK);
    // A band is enough for marching cubes and for the next level's rebuild, which reads φ's sign
    // beyond `near` and takes distances only near the samples. The nodes next to the zero level
    // set keep the planes' distances: the redistancer would measure them again to its own
    // patches of the interface, which in creases move the crossings by a fifth of a voxel.
    redistance(
        &mut out,
        &RedistanceOptions {
            band: Some(planes.reach + phi.voxel()),
            keep_interface: true,
            scheme: RedistanceScheme::ClosestPointTransform,
            ..RedistanceOptions::default()
        },
    )?;
    Ok(out)
}

/// The samples of S_{i−1} as [`rebuild_from_tangent_planes`] reads them: what it gives each node
/// before the redistance ([`TangentPlanes::node_value`]; public so that a node's value can be
/// inspected where the rebuild misreads S_{i−1}).
pub struct TangentPlanes<'a> {
    previous: &'a [Point3<f64>],
    normals: &'a [Vector3<f64>],
    details: &'a [Vector3<f64>],
    index: Option<SampleIndex>,
    /// |φ_i| beyond which a node keeps φ_i (world units).
    band: f64,
    /// The largest detail among the samples within reach of each part of the grid.
    moved: BlockMax,
    /// Distance from the surface inside which φ_i gives only the side (world units).
    near: f64,
    /// Farthest a node may be from its samples and still take their planes.
    reach: f64,
    disc: f64,
    softness: f64,
    lateral_reach: f64,
    two_sigma2: f64,
    coverage: f64,
    foot_lateral: f64,
    h: f64,
}

impl<'a> TangentPlanes<'a> {
    /// The samples X_{i−1} (`previous`, with their outward normals n_{i−1} and the details W_i),
    /// indexed for the nodes of φ_i's grid.
    pub fn new(
        phi: &Grid3,
        previous: &'a [Point3<f64>],
        normals: &'a [Vector3<f64>],
        details: &'a [Vector3<f64>],
        opts: &AdvectOptions,
    ) -> Self {
        let h = phi.voxel();
        let largest = details.iter().map(|w| w.norm()).fold(0.0, f64::max);
        let near = opts.band_margin * h;
        let reach = near + 2.0 * h;
        TangentPlanes {
            previous,
            normals,
            details,
            index: SampleIndex::new(phi, previous, reach),
            band: largest + near,
            moved: BlockMax::new(phi, previous, details, reach),
            near,
            reach,
            // Each sample stands for a small disc of S_{i−1} (its tangent plane within
            // DISC_RADIUS voxels of it): the distance to the nearest disc and the node's lateral
            // offset from it decide whether the planes are trusted at all.
            disc: DISC_RADIUS * h,
            softness: DISC_SOFTNESS * h,
            lateral_reach: LATERAL_REACH * h,
            two_sigma2: 2.0 * (PLANE_SPREAD * h).powi(2),
            coverage: opts.coverage * h,
            foot_lateral: FOOT_LATERAL * h,
            h,
        }
    }

    /// The value of node `n` of `phi` (φ_i) before the redistance: φ_i where the node is
    /// farther from S_i than the samples around it moved, by `SURE_SIDE` (1.5) voxels; nearer, the
    /// tangent planes' distance near the samples, else the side φ_i gives at least `near` from
    /// the surface, else φ_i.
    pub fn node_value(&self, phi: &Grid3, n: usize) -> f32 {
        let v = phi.data()[n];
        if (v.abs() as f64) > self.band {
            return v;
        }
        let [i, j, k] = phi.coords(n);
        let x = phi.world(i, j, k);
        // Farther from S_i than any sample around moved (plus a margin), the node is on φ_i's
        // side of S_{i−1} too, and not next to its zero crossing: the redistance keeps its
        // sign and measures its distance again, so its planes are not needed. (This also
        // keeps φ_i wherever no plane could be taken: those lie within `near` + min(moved, 2h)
        // of a disc, so within that plus the disc and the sample's own detail of S_i.)
        let w = self.moved.at(&x);
        if (v.abs() as f64) > w + SURE_SIDE * self.h {
            return v;
        }
        match self.planes(&x) {
            // Tangent planes only where φ_i cannot be trusted for the side — within the
            // distance the nearby samples moved (counted up to 2h), plus a margin — and only
            // where the nearest disc is one whose normal line passes near the node.
            Some(f) if f.y <= self.near + f.w.min(2.0 * self.h) && f.z <= self.lateral_reach => {
                f.x as f32
            }
            // Beyond: the side φ_i gives, at least `near` from the surface.
            _ if (v.abs() as f64) < self.near => (self.near as f32).copysign(v),
            _ => v,
        }
    }

    /// At `x`: (plane value, distance to the nearest disc, lateral offset, how far the samples
    /// moved); `None` with no sample within reach.
    fn planes(&self, x: &Point3<f64>) -> Option<Vector4<f64>> {
        let found = self.index.as_ref()?.nearest_to_node(x);
        let d2min = found.first()?.1;
        let d_min = d2min.sqrt();
        let mut best = f64::INFINITY;
        let per: Vec<(f64, f64, f64)> = found
            .iter()
            .map(|&(s, d2)| {
                let along = self.normals[s].dot(&(x - self.previous[s]));
                let lateral = (d2 - along * along).max(0.0).sqrt();
                let to_disc = along.hypot((lateral - self.disc).max(0.0));
                best = best.min(to_disc);
                (to_disc, along, lateral)
            })
            .collect();
        let (mut weight, mut lateral, mut moved) = (0.0, 0.0, 0.0);
        let (mut plane, mut plane_weight) = (0.0, 0.0);
        let mut foot: Option<(f64, f64)> = None;
        let sheet = self.normals[found[0].0];
        for (&(s, d2), &(to_disc, along, lat)) in found.iter().zip(&per) {
            let w = (-(to_disc - best) / self.softness).exp();
            lateral += w * lat;
            moved += w * self.details[s].norm();
            weight += w;
            if self.normals[s].dot(&sheet) < SAME_SHEET {
                continue;
            }
            let wp = (-(d2 - d2min) / self.two_sigma2).exp();
            plane += wp * along;
            plane_weight += wp;
            if lat < self.foot_lateral
                && d2.sqrt() <= d_min + self.coverage
                && foot.is_none_or(|(l, _)| lat < l)
            {
                foot = Some((lat, along));
            }
        }
        let value = match foot {
            // A sample whose normal line passes through the node is its foot point: its plane
            // gives the node's distance as it is, with no average and no clamp.
            Some((_, along)) => along,
            None => {
                let value = plane / plane_weight;
                value
                    .abs()
                    .clamp((d_min - self.coverage).max(0.0), d_min)
                    .copysign(value)
            }
        };
        Some(Vector4::new(value, best, lateral / weight, moved / weight))
    }
}

/// The largest |W| of the samples in blocks of the grid, each block's value the largest within
/// `reach` of any point of it (the blocks around it taken in).
struct BlockMax {
    origin: Point3<f64>,
    block: f64,
    dims: [usize; 3],
    values: Vec<f64>,
}

impl BlockMax {
    fn new(phi: &Grid3, points: &[Point3<f64>], details: &[Vector3<f64>], reach: f64) -> Self {
        let origin = phi.world(0, 0, 0);
        let block = 2.0 * phi.voxel();
        let extent = phi.dims().map(|d| (d.max(1) - 1) as f64 * phi.voxel());
        let dims = extent.map(|e| (e / block).floor() as usize + 1);
        let key = |p: &Point3<f64>| -> [usize; 3] {
            [0, 1, 2].map(|a| {
                ((p[a] - origin[a]) / block)
                    .floor()
                    .clamp(0.0, (dims[a] - 1) as f64) as usize
            })
        };
        let mut own = vec![0.0f64; dims[0] * dims[1] * dims[2]];
        for (p, w) in points.iter().zip(details) {
            let [x, y, z] = key(p);
            let c = &mut own[x + dims[0] * (y + dims[1] * z)];
            *c = c.max(w.norm());
        }
        // Dilate by the blocks within reach, one axis at a time.
        let r = (reach / block).ceil() as usize;
        let stride = [1, dims[0], dims[0] * dims[1]];
        let mut values = own;
        for a in 0..3 {
            let src = values.clone();
            for (n, v) in values.iter_mut().enumerate() {
                let c = (n / stride[a]) % dims[a];
                let lo = c.saturating_sub(r);
                let hi = (c + r).min(dims[a] - 1);
                let base = n - c * stride[a];
                *v = (lo..=hi)
                    .map(|t| src[base + t * stride[a]])
                    .fold(0.0, f64::max);
            }
        }
        BlockMax {
            origin,
            block,
            dims,
            values,
        }
    }

    fn at(&self, p: &Point3<f64>) -> f64 {
        let k = [0, 1, 2].map(|a| {
            ((p[a] - self.origin[a]) / self.block)
                .floor()
                .clamp(0.0, (self.dims[a] - 1) as f64) as usize
        });
        self.values[k[0] + self.dims[0] * (k[1] + self.dims[1] * k[2])]
    }
}

/// Trilinear interpolation of `field` at `p`, over the corners where it is defined.
fn sample_field(phi: &Grid3, field: &NodeField, p: &Point3<f64>) -> Option<Vector3<f64>> {
    let q = phi.transform().world_to_index(p);
    let dims = phi.dims();
    let mut base = [0usize; 3];
    let mut t = [0.0; 3];
    for a in 0..3 {
        if !(q[a] >= 0.0 && q[a] <= (dims[a] - 1) as f64) {
            return None;
        }
        base[a] = (q[a].floor() as usize).min(dims[a].saturating_sub(2));
        t[a] = q[a] - base[a] as f64;
    }
    let (mut sum, mut weight) = (Vector3::zeros(), 0.0);
    for c in 0..8 {
        let o = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
        let w: f64 = (0..3)
            .map(|a| if o[a] == 1 { t[a] } else { 1.0 - t[a] })
            .product();
        if let Some(v) = field[phi.index(base[0] + o[0], base[1] + o[1], base[2] + o[2])] {
            sum += v * w;
            weight += w;
        }
    }
    (weight > 1e-9).then(|| sum / weight)
}
