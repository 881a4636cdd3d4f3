//! Threshold dynamics on a signed distance function: the level-set motions φ_t + v_n|∇φ| = 0
//! of the paper (Section 3, Algorithms 2 and 3; eq. 4.2 for inpainting) stepped by diffusion,
//! thresholding and redistancing, one [`Flow::step`] at a time.
//!
//! **Why a signed distance function instead of the indicator.** The paper's algorithms (after
//! Merriman, Bence and Osher) diffuse the characteristic function χ of the inside for Δt and
//! threshold it. On a grid that pins the interface when √(2Δt) is below the voxel size h: the
//! diffused indicator then barely changes at the nodes, and the thresholded set is the old one.
//! Here the field diffused is φ itself, a signed distance function (Esedoglu, Ruuth and Tsai,
//! "Diffusion generated motion using signed distance functions", J. Comput. Phys. 229, 2010):
//! the heat flow gives φ̃ = φ + Δt·Δφ + O(Δt²), and Δφ is the mean curvature κ of the level set
//! through each point, so the zero level set of φ̃ has moved by −Δt·κ: mean curvature motion to
//! first order (a sphere's zero crossing moves from R to r with r + 2Δt/r = R exactly, for
//! √(2Δt) ≪ R). φ̃ carries the interface at sub-voxel precision, so thresholding it at 0 (the
//! equivalent of χ̄ > ½) is the "sub-voxel indicator" the issue asks for, and the redistancer
//! (`levelset::redistance`, distances to sub-voxel patches of the interface: by default the
//! closest-point transform, [`FlowOptions::redistance`])
//! rebuilds φ without moving its zero level set: nothing pins, whatever Δt/h².
//!
//! **The four velocities** ([`Velocity`]):
//! * `mcf` (v = −κ): φ ← redistance(G_Δt ∗ φ). The threshold is 0.
//! * `vpmcf` (v = κ_a − κ, Algorithm 3, Ruuth and Wetton): after the diffusion, the shift λ is
//!   found for which {φ̃ − λ < 0} has the volume the flow started with (sub-voxel estimate of
//!   `volume`; the target is fixed at the first step, so the volume does not drift), then
//!   φ ← redistance(φ̃ − λ). λ/Δt is the average curvature κ_a of the step.
//! * `expand` (v = c, Algorithm 2): for a signed distance function the exact step is the
//!   Huygens construction φ ← φ − cΔt (the set grown by cΔt), then redistance. Algorithm 2
//!   realises it by thresholding the diffused indicator below ½, which also adds a curvature
//!   motion of the size of the diffusion; the signed distance does without the diffusion.
//! * `inpaint` (v = c + κ_a − κ, eq. 4.2): the `expand` step, then the `vpmcf` step keeping the
//!   grown volume (Lie splitting; the two commute on a sphere, where κ_a = κ).
//!
//! **Second order.** Thresholding the diffused φ is first order in Δt (the curvature is taken
//! at the new surface, and the diffusion adds a term that is no part of the motion); by default
//! ([`FlowOptions::second_order`]) the diffused φ is corrected near the surface by the
//! trapezoidal rule and for the remaining umbilic defect (see `flow/second_order.rs`).
//!
//! **Valid range of Δt/h²** (measured, see tests/suite/motion_flows.rs; h the voxel):
//! * Lower limit 0.25h² (σ = √(2Δt) ≥ 0.7h), which [`Flow::step`] enforces: below it the
//!   Gaussian sampled on the grid has less variance than the heat kernel (0.2% less at
//!   σ = 0.7h, 30% at 0.45h), so the surface moves too slowly (a sphere shrinking from 24h to
//!   12h in steps of 0.1h² ends 4.5h too large). Each redistance moves the surface by about
//!   10⁻³h or less, a noise that stays below the scheme's own error from 0.25h² up: a sphere of
//!   24h follows r² = R² − 4t within 0.04h at 0.25h², 0.002h at 0.5h² and 2h².
//! * No sharp upper limit: a sphere of 24h stays within 0.01h of r² = R² − 4t down to half its
//!   radius at Δt = 8h² and within 0.03h at 32h², a cylinder of 16h within 0.09h of
//!   r² = R² − 2t at 8h². What bounds Δt is the smallest feature to be followed: σ should stay
//!   below about half its radius of curvature (thinner parts vanish within a step or two
//!   instead of shrinking smoothly), and the redistancer's band, so the work per step, grows
//!   as 3σ. Default step of the driver and the CLI: 2h².
//!
//! **Regions.** With [`FlowOptions::region`], only the nodes of that sub-box change: each step
//! extracts the region grown by the band and the diffusion reach, evolves that sub-grid, and
//! writes the region back (the values around it act as fixed data, as inpainting needs).

use super::diffusion::{diffuse, DiffusionOptions};
use super::velocity::Velocity;
use super::volume::{find_volume_shift, measure_shape_in, measure_volume_in};
use crate::grid::{Grid3, SubBox};
use crate::levelset::redistance::{redistance, RedistanceOptions, RedistanceScheme};
use crate::{Error, Result};
use rayon::prelude::*;

mod second_order;

/// Smallest time step, in voxels² (h²): see the module documentation.
pub const MIN_DT_VOXELS2: f64 = 0.25;

/// Options of a [`Flow`].
#[derive(Debug, Clone)]
pub struct FlowOptions {
    /// The heat diffusion of φ (kernel, …).
    pub diffusion: DiffusionOptions,
    /// Half-width of the band of φ the redistancer rebuilds after each step, **in voxels**
    /// (beyond it φ is clamped to ± the band). `None` (default): 3σ/h + |c|Δt/h + 3, so that the
    /// diffusion (σ = √(2Δt)) of the nodes next to the interface sees a true distance up to 3σ
    /// away (clamping beyond moves their values by less than 10⁻³σ, symmetrically on both
    /// sides). Only the box of the nodes within the band is redistanced; the others become
    /// ± the band.
    pub band_voxels: Option<f64>,
    /// The nodes the flow may change (a sub-box of the grid); `None` (default): the whole grid.
    pub region: Option<SubBox>,
    /// Relative error allowed on the volume matched by `vpmcf` and `inpaint` (default 1e-9).
    pub volume_tolerance: f64,
    /// Second order in Δt (default true): threshold the diffused φ corrected by the implicit
    /// trapezoidal rule (the curvature averaged between the old and the new interface) and for
    /// the remaining umbilic defect κ(κ₁ − κ₂)² (see `flow/second_order.rs`). False: the plain
    /// scheme of Esedoglu, Ruuth and Tsai, first order. The correction holds three more grids
    /// during the step.
    pub second_order: bool,
    /// Let the shape reach the border of the grid (default false: a shape that did not touch
    /// the border and reaches it is an error, the grid needing more padding). For a sub-box of a
    /// larger scene whose shape is restored from known data afterwards (the inpainting's coarse
    /// level), where the mirror boundary stands in for what lies beyond.
    pub allow_border: bool,
    /// How φ is redistanced after each step (default
    /// [`RedistanceScheme::ClosestPointTransform`]: the same distances to the interface's
    /// patches as the closest-point sweeps, found without sweeps, at a cost that does not grow
    /// with the band; the decomposition of the cortex runs about 10% faster with it).
    pub redistance: RedistanceScheme,
}

impl Default for FlowOptions {
    fn default() -> Self {
        FlowOptions {
            diffusion: DiffusionOptions::default(),
            band_voxels: None,
            region: None,
            volume_tolerance: 1e-9,
            second_order: true,
            allow_border: false,
            redistance: RedistanceScheme::ClosestPointTransform,
        }
    }
}

impl FlowOptions {
    /// The redistance band for steps of `dt` with `velocity` on a grid of voxel `h`, world units.
    pub fn band_width(&self, velocity: &Velocity, dt: f64, h: f64) -> f64 {
        match self.band_voxels {
            Some(b) => b * h,
            None => {
                let sigma = if velocity.has_curvature() {
                    (2.0 * dt).sqrt()
                } else {
                    0.0
                };
                let growth = velocity.speed().map_or(0.0, |c| c.abs() * dt);
                3.0 * sigma + growth + 3.0 * h
            }
        }
    }
}

/// What one [`Flow::step`] did, and the shape after it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct StepReport {
    /// Steps taken so far (1 after the first).
    pub step: usize,
    /// Time after the step, world length².
    pub time: f64,
    /// Length of the step, world length².
    pub dt: f64,
    /// Sub-voxel volume of {φ < 0} after the step (within the region, when there is one), world
    /// units³.
    pub volume: f64,
    /// Area estimate of the zero level set after the step (within the region), world units².
    pub area: f64,
    /// Threshold shift λ of `vpmcf` and `inpaint` (world units; λ/Δt is the step's average
    /// curvature κ_a); 0 for the others.
    pub shift: f64,
}

/// A level-set motion stepped by threshold dynamics on a signed distance function (see the
/// module documentation).
#[derive(Debug, Clone)]
pub struct Flow {
    velocity: Velocity,
    dt: f64,
    opts: FlowOptions,
    time: f64,
    steps: usize,
    target_volume: Option<f64>,
}

impl Flow {
    /// A flow of `velocity` in steps of `dt` (world length²) from t = 0. Errors when `dt` is not
    /// positive and finite, the velocity's speed is invalid (see [`Velocity::validate`]), or an
    /// option is out of range.
    pub fn new(velocity: Velocity, dt: f64, opts: FlowOptions) -> Result<Flow> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::Geometry(format!(
                "the time step must be positive and finite (world length²), got {dt}"
            )));
        }
        velocity.validate()?;
        if let Some(b) = opts.band_voxels {
            if !(b.is_finite() && b >= 2.0) {
                return Err(Error::Geometry(format!(
                    "the redistance band must be at least 2 voxels, got {b}"
                )));
            }
        }
        if !(opts.volume_tolerance >= 0.0 && opts.volume_tolerance < 1.0) {
            return Err(Error::Geometry(format!(
                "the volume tolerance must be in [0, 1), got {}",
                opts.volume_tolerance
            )));
        }
        Ok(Flow {
            velocity,
            dt,
            opts,
            time: 0.0,
            steps: 0,
            target_volume: None,
        })
    }

    /// The velocity.
    pub fn velocity(&self) -> Velocity {
        self.velocity
    }

    /// The time step, world length².
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Time reached, world length².
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The volume `vpmcf` keeps (world units³): the volume of φ at the first step, None before.
    pub fn target_volume(&self) -> Option<f64> {
        self.target_volume
    }

    /// The options.
    pub fn options(&self) -> &FlowOptions {
        &self.opts
    }

    /// Advances `phi` (a signed distance function within the band, negative inside) by one step
    /// of Δt. Errors on NaN in φ, a region that does not fit the grid, when the shape vanishes
    /// (no node left inside: the message gives the time), fills the grid, or newly reaches the
    /// grid's border (the grid needs more padding). After an error `phi` holds the state the
    /// step reached.
    pub fn step(&mut self, phi: &mut Grid3) -> Result<StepReport> {
        let dims = phi.dims();
        let h = phi.voxel();
        let dt = self.dt;
        if self.velocity.has_curvature() && dt < MIN_DT_VOXELS2 * h * h {
            return Err(Error::Geometry(format!(
                "the time step {dt} is below {MIN_DT_VOXELS2}h² = {} (h = {h}): the Gaussian on \
                 the grid no longer has the heat kernel's variance there and the surface would \
                 move too slowly; take larger steps (or a finer grid)",
                MIN_DT_VOXELS2 * h * h
            )));
        }
        let band = self.opts.band_width(&self.velocity, dt, h);
        // A shape that reaches the border must not have touched it before (scanned only when
        // that is an error).
        let watch_border = !self.opts.allow_border && !border_inside(phi);
        let (shift, volume, area) = match self.opts.region {
            None => {
                let region = phi.whole_box();
                self.advance(phi, &region, band)?
            }
            Some(region) => {
                if !region.fits(dims) {
                    return Err(Error::Geometry(format!(
                        "flow region {:?}..{:?} is empty or outside the grid of {dims:?} nodes",
                        region.min, region.max
                    )));
                }
                let reach = if self.velocity.has_curvature() {
                    4.0 * (2.0 * dt).sqrt()
                } else {
                    0.0
                };
                let margin = ((band + reach) / h).ceil() as usize + 2;
                let work_box = region.dilate(margin, dims);
                let mut work = phi.extract(&work_box)?;
                let local = SubBox::new(
                    [0, 1, 2].map(|a| region.min[a] - work_box.min[a]),
                    [0, 1, 2].map(|a| region.max[a] - work_box.min[a]),
                );
                let out = self.advance(&mut work, &local, band)?;
                phi.write_back(&region, &work.extract(&local)?)?;
                out
            }
        };
        let t0 = self.time;
        self.time += dt;
        self.steps += 1;
        let (inside, nodes) = phi
            .data()
            .par_chunks(1 << 16)
            .map(|c| (c.iter().filter(|&&v| v < 0.0).count(), c.len()))
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        if inside == 0 {
            return Err(Error::Geometry(format!(
                "{}: the shape vanished at t = {} (no node left inside after step {}, from \
                 t = {t0}; time in world length²)",
                self.velocity.name(),
                self.time,
                self.steps
            )));
        }
        if inside == nodes {
            return Err(Error::Geometry(format!(
                "{}: the shape filled the whole grid at t = {} (world length²)",
                self.velocity.name(),
                self.time
            )));
        }
        if watch_border && border_inside(phi) {
            return Err(Error::Geometry(format!(
                "{}: the shape reached the border of the grid at t = {} (world length²): the \
                 grid needs more padding",
                self.velocity.name(),
                self.time
            )));
        }
        Ok(StepReport {
            step: self.steps,
            time: self.time,
            dt,
            volume,
            area,
            shift,
        })
    }

    /// One step on `grid`, whose nodes in `region` are the ones that count; returns the shift,
    /// the volume and the area in the region.
    fn advance(&mut self, grid: &mut Grid3, region: &SubBox, band: f64) -> Result<(f64, f64, f64)> {
        let dt = self.dt;
        if let Some(c) = self.velocity.speed() {
            let d = (c * dt) as f32;
            grid.data_mut().par_iter_mut().for_each(|v| *v -= d);
        }
        let mut shift = 0.0;
        if self.velocity.has_curvature() {
            let target = if self.velocity.preserves_volume() {
                let before = measure_volume_in(grid, region)?;
                Some(match self.velocity {
                    // vpmcf keeps the volume it started with, so it does not drift.
                    Velocity::VolumePreserving => *self.target_volume.get_or_insert(before),
                    _ => before,
                })
            } else {
                None
            };
            if self.opts.second_order {
                let phi = grid.clone();
                diffuse(grid, dt, &self.opts.diffusion)?;
                second_order::correct(grid, &phi, dt);
            } else {
                diffuse(grid, dt, &self.opts.diffusion)?;
            }
            if let Some(target) = target {
                shift = find_volume_shift(grid, region, target, self.opts.volume_tolerance)?;
                let s = shift as f32;
                grid.data_mut().par_iter_mut().for_each(|v| *v -= s);
            }
        }
        redistance_within(grid, band, self.opts.redistance)?;
        let (volume, area) = measure_shape_in(grid, region)?;
        Ok((shift, volume, area))
    }
}

/// Redistances `grid` within `band` (world units), working on the box of the nodes where
/// |φ| < band only: outside it, φ (1-Lipschitz: a diffused or shifted signed distance) is at
/// least the band away from its zero level set, so those nodes become ±band, as the
/// redistancer would set them, without its per-node costs over the whole grid.
fn redistance_within(grid: &mut Grid3, band: f64, scheme: RedistanceScheme) -> Result<()> {
    let opts = RedistanceOptions {
        band: Some(band),
        scheme,
        ..RedistanceOptions::default()
    };
    let dims = grid.dims();
    let w = band as f32;
    let [nx, ny, _] = dims;
    // Bounding box of the band, by z-layer.
    let boxes: Vec<Option<([usize; 3], [usize; 3])>> = grid
        .data()
        .par_chunks(nx * ny)
        .enumerate()
        .map(|(k, layer)| {
            let mut lo = [usize::MAX; 3];
            let mut hi = [0usize; 3];
            for (r, row) in layer.chunks_exact(nx).enumerate() {
                let first = row.iter().position(|v| v.abs() < w);
                if let Some(first) = first {
                    let last = row.iter().rposition(|v| v.abs() < w).unwrap_or(first);
                    lo = [lo[0].min(first), lo[1].min(r), k];
                    hi = [hi[0].max(last + 1), hi[1].max(r + 1), k + 1];
                }
            }
            (lo[0] != usize::MAX).then_some((lo, hi))
        })
        .collect();
    let Some((lo, hi)) = boxes.into_iter().flatten().reduce(|a, b| {
        (
            [0, 1, 2].map(|i| a.0[i].min(b.0[i])),
            [0, 1, 2].map(|i| a.1[i].max(b.1[i])),
        )
    }) else {
        // No node within the band: one sign everywhere (the redistancer's special case).
        redistance(grid, &opts)?;
        return Ok(());
    };
    // One node of margin, so the band's edge nodes are not on the sub-grid's border.
    let sub_box = SubBox::new(lo, hi).dilate(1, dims);
    if sub_box.node_count() * 10 > 8 * grid.data().len() {
        redistance(grid, &opts)?;
        return Ok(());
    }
    let mut sub = grid.extract(&sub_box)?;
    redistance(&mut sub, &opts)?;
    grid.data_mut()
        .par_iter_mut()
        .for_each(|v| *v = if *v < 0.0 { -w } else { w });
    grid.write_back(&sub_box, &sub)
}

/// Whether a node on the grid's outer faces is inside (φ < 0).
fn border_inside(phi: &Grid3) -> bool {
    let [nx, ny, nz] = phi.dims();
    let faces = [
        SubBox::new([0, 0, 0], [1, ny, nz]),
        SubBox::new([nx - 1, 0, 0], [nx, ny, nz]),
        SubBox::new([0, 0, 0], [nx, 1, nz]),
        SubBox::new([0, ny - 1, 0], [nx, ny, nz]),
        SubBox::new([0, 0, 0], [nx, ny, 1]),
        SubBox::new([0, 0, nz - 1], [nx, ny, nz]),
    ];
    faces.iter().any(|f| {
        f.rows(phi.dims())
            .any(|(_, _, row)| phi.data()[row].iter().any(|&v| v < 0.0))
    })
}
