//! Decomposition (MST, paper Algorithm 1): from a mesh and its signed distance grid φ_0, the
//! multiscale representation {W_1..W_N, φ_T}.
//!
//! The samples X_0 are the mesh vertices plus lattice points where the mesh is coarser than
//! `sample_spacing` voxels ([`super::sample`]), snapped onto the zero level set S_0 of φ_0 (the
//! snap is kept, so the input comes back exactly). The levels are t_i = i·T/N. Before each
//! level, the surface S_{i−1} gets new samples where it has none within `cover_radius` voxels
//! ([`super::cover`]: the paper's "denser samples where needed"). For each level, φ is evolved
//! from t_{i−1} to t_i by the chosen [`Velocity`] (threshold dynamics, [`crate::motion`]; the
//! flow keeps φ a signed distance within its band, and φ is redistanced farther, as far as the
//! farthest sample, only when a sample lies near the band's edge or beyond, so the projection
//! always sees a true distance however far the samples must travel), and X_{i−1} is projected
//! orthogonally onto its zero level set by Newton steps ([`super::project`]): X_i,
//! W_i = X_i − X_{i−1}, and the scalar detail w_i = W_i·n_i with n_i = ∇φ(t_i)/|∇φ(t_i)| at
//! X_i (positive outward). Then, where the level-set rebuild of φ_{i−1} from φ_i and these
//! samples would misread a node near S_{i−1}, a sample is added at that node's foot point on
//! S_{i−1} ([`super::misread`], `misread_rounds` rounds).

use super::cover::cover_gaps;
use super::misread::misread_points;
use super::project::{project_to_zero_level, LevelProjectOptions, Projected};
use super::reconstruct::AdvectOptions;
use super::rescue::rescue_unconverged;
use super::sample::sample_for_spacing;
use super::{Msr, MsrParams};
use crate::grid::Grid3;
use crate::levelset::redistance::{redistance, RedistanceOptions};
use crate::levelset::speck::{clear_specks, SPECK};
use crate::motion::evolve::step_count;
use crate::motion::flow::{Flow, FlowOptions, StepReport, MIN_DT_VOXELS2};
use crate::motion::velocity::Velocity;
use crate::{Error, Result, TriMesh};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Options of [`decompose`].
#[derive(Debug, Clone)]
pub struct DecomposeOptions {
    /// Number of levels N.
    pub levels: usize,
    /// Total time T, world length²; `None`: N·(2h)² — each level then smooths away features of
    /// about 2h more radius (a sphere of radius ρ vanishes under mean curvature flow at ρ²/4).
    pub time: Option<f64>,
    /// The motion between levels (the paper's Figure 1 uses `vpmcf`).
    pub velocity: Velocity,
    /// Time step, world length²; `None`: 2h², or less so that each level has a whole number of
    /// equal steps.
    pub dt: Option<f64>,
    /// Largest distance between samples on the input (voxels).
    pub sample_spacing: f64,
    /// Before each level, every point of S_{i−1} (the vertices of its marching-cubes surface)
    /// with no sample within this distance (voxels) gets one; `None`: no new samples.
    pub cover_radius: Option<f64>,
    /// After each level, rounds of samples added on S_{i−1} at the nodes near it that the
    /// level-set rebuild (`rebuild_from_tangent_planes` with `AdvectOptions::default()`) would
    /// misread ([`super::misread`]: a node's value, or a grid face's decider; the second and
    /// later rounds check only around the nodes found before); 0: none.
    pub misread_rounds: usize,
    /// Newton projection onto each level set.
    pub projection: LevelProjectOptions,
    /// The flow's own options.
    pub flow: FlowOptions,
    /// Keep φ(t_i) of every level in [`Decomposition::level_sets`] (for measuring the
    /// reconstruction; costs one grid per level).
    pub keep_level_sets: bool,
}

impl Default for DecomposeOptions {
    fn default() -> Self {
        DecomposeOptions {
            levels: 5,
            time: None,
            velocity: Velocity::VolumePreserving,
            dt: None,
            sample_spacing: 1.0,
            cover_radius: Some(0.25),
            misread_rounds: 2,
            projection: LevelProjectOptions::default(),
            flow: FlowOptions::default(),
            keep_level_sets: false,
        }
    }
}

/// Per-level figures of a decomposition.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LevelReport {
    /// Level i (1..=N).
    pub level: usize,
    /// t_i, world length².
    pub time: f64,
    /// Number of samples.
    pub samples: usize,
    /// Mean |w_i|, world units.
    pub mean_abs_detail: f64,
    /// Fraction of samples with |w_i| < 0.1h.
    pub sparse_fraction: f64,
    /// Samples whose Newton projection did not reach the tolerance (they keep the best point).
    pub unconverged: usize,
    /// Sub-voxel volume of {φ(t_i) < 0}, world units³.
    pub volume: f64,
    /// Area of the zero level set of φ(t_i), world units².
    pub area: f64,
    /// Mean |κ| (κ the sum of the principal curvatures, ∇·(∇φ/|∇φ|)) of φ(t_i) at the samples
    /// X_i, 1/world units: decreasing level by level as the shape gets smoother.
    pub mean_abs_curvature: f64,
}

/// The result of [`decompose`].
#[derive(Debug, Clone)]
pub struct Decomposition {
    pub msr: Msr,
    /// Levels 1..=N.
    pub reports: Vec<LevelReport>,
    /// φ(t_0) .. φ(t_N) when [`DecomposeOptions::keep_level_sets`] is set, else empty.
    pub level_sets: Vec<Grid3>,
}

/// The resolved time, step and steps per level for `opts` on a grid of voxel `h`.
pub fn level_schedule(opts: &DecomposeOptions, h: f64) -> Result<(f64, f64, usize)> {
    if opts.levels == 0 {
        return Err(Error::Geometry(
            "the number of levels must be at least 1".into(),
        ));
    }
    let time = opts.time.unwrap_or(opts.levels as f64 * 4.0 * h * h);
    if !(time.is_finite() && time > 0.0) {
        return Err(Error::Geometry(format!(
            "the decomposition time must be positive and finite (world length²), got {time}"
        )));
    }
    let per_level = time / opts.levels as f64;
    let dt = opts.dt.unwrap_or(2.0 * h * h);
    let steps = step_count(per_level, dt)?;
    // Below the flow's smallest step per level the motion is within the redistancer's noise.
    let min_level = MIN_DT_VOXELS2 * h * h;
    if per_level < min_level {
        return Err(Error::Geometry(format!(
            "{} levels in a time of {time:.4e} leave {per_level:.3e} per level, less than \
             {MIN_DT_VOXELS2} h² = {min_level:.3e} (h = {h:.4e}): use fewer levels or a longer --time",
            opts.levels
        )));
    }
    Ok((time, per_level / steps as f64, steps))
}

/// Decomposes `mesh`, whose signed distance grid is `phi` (negative inside), into its multiscale
/// representation (see the module doc). `progress(level, step)` is called after every flow step.
///
/// Errors: invalid options ([`level_schedule`]), and the flow's errors — among them the shape
/// vanishing before T (the message gives the time).
pub fn decompose(
    mesh: &TriMesh,
    mut phi: Grid3,
    opts: &DecomposeOptions,
    mut progress: impl FnMut(usize, &StepReport),
) -> Result<Decomposition> {
    let h = phi.voxel();
    let (time, dt, steps_per_level) = level_schedule(opts, h)?;
    let samples = sample_for_spacing(mesh, opts.sample_spacing * h);
    let redistance_opts = RedistanceOptions {
        scheme: opts.flow.redistance,
        ..RedistanceOptions::default()
    };
    redistance(&mut phi, &redistance_opts)?;
    clear_specks(&mut phi, SPECK);
    let mut level_sets = Vec::new();
    if opts.keep_level_sets {
        level_sets.push(phi.clone());
    }
    let mut flow = Flow::new(opts.velocity, dt, opts.flow.clone())?;
    let band = opts.flow.band_width(&opts.velocity, dt, h);
    let x: Vec<Point3<f64>> = project_with_rescue(&phi, &samples.points, &opts.projection)?
        .iter()
        .map(|p| p.point)
        .collect();
    let snap: Vec<Vector3<f64>> = x.iter().zip(&samples.points).map(|(a, b)| a - b).collect();
    let mut tracks = Tracks {
        born: vec![0u32; x.len()],
        normals: vec![outward_normals(&phi, &x)],
        x,
        details: Vec::with_capacity(opts.levels),
        normal_details: Vec::with_capacity(opts.levels),
    };
    let mut reports = Vec::with_capacity(opts.levels);
    let mut times = vec![0.0];
    for level in 1..=opts.levels {
        if let Some(radius) = opts.cover_radius {
            let new = cover_gaps(&phi, &tracks.x, radius * h, &opts.projection)?;
            let normals = outward_normals(&phi, &new);
            tracks.append(new, normals, level - 1);
        }
        let previous_phi = (opts.misread_rounds > 0).then(|| phi.clone());
        let mut last = None;
        for _ in 0..steps_per_level {
            let r = flow.step(&mut phi)?;
            progress(level, &r);
            last = Some(r);
        }
        let last = last.expect("at least one step per level");
        // S_i as measured and rebuilt: without specks (neither side could say where they are).
        clear_specks(&mut phi, SPECK);
        // The flow leaves φ a signed distance within its band; samples near its edge or beyond
        // need it redistanced as far as they are (the tricubic stencil reaches 2 voxels out).
        let farthest = tracks
            .x
            .par_iter()
            .map(|p| phi.sample_trilinear(p).map_or(f64::INFINITY, f64::abs))
            .reduce(|| 0.0, f64::max);
        if farthest > band - 3.0 * h {
            redistance(
                &mut phi,
                &RedistanceOptions {
                    band: Some(farthest + 3.0 * h),
                    ..redistance_opts.clone()
                },
            )?;
        }
        let projected = project_with_rescue(&phi, &tracks.x, &opts.projection)?;
        let mut unconverged = projected.iter().filter(|p| !p.converged).count();
        let mut next: Vec<Point3<f64>> = projected.iter().map(|p| p.point).collect();
        let mut w: Vec<Vector3<f64>> = next.iter().zip(&tracks.x).map(|(a, b)| a - b).collect();
        if let Some(previous_phi) = &previous_phi {
            let mut found: Option<Vec<usize>> = None;
            for _ in 0..opts.misread_rounds {
                let misread = misread_points(
                    previous_phi,
                    &phi,
                    &tracks.x,
                    tracks.normals.last().expect("n_{i-1} is set"),
                    &w,
                    found.as_deref(),
                    &AdvectOptions::default(),
                    &opts.projection,
                );
                if misread.is_empty() {
                    break;
                }
                let new: Vec<Point3<f64>> = misread.iter().map(|m| m.point).collect();
                let arrived = project_with_rescue(&phi, &new, &opts.projection)?;
                unconverged += arrived.iter().filter(|p| !p.converged).count();
                w.extend(arrived.iter().zip(&new).map(|(a, b)| a.point - b));
                next.extend(arrived.iter().map(|p| p.point));
                tracks.append(new, misread.iter().map(|m| m.normal).collect(), level - 1);
                let nodes = found.get_or_insert_with(Vec::new);
                nodes.extend(misread.iter().map(|m| m.node));
                nodes.sort_unstable();
            }
        }
        let n_i = outward_normals(&phi, &next);
        let wn: Vec<f64> = n_i.iter().zip(&w).map(|(n, d)| d.dot(n)).collect();
        tracks.normals.push(n_i);
        let mean_abs = wn.iter().map(|v| v.abs()).sum::<f64>() / wn.len().max(1) as f64;
        let sparse =
            wn.iter().filter(|v| v.abs() < 0.1 * h).count() as f64 / wn.len().max(1) as f64;
        reports.push(LevelReport {
            level,
            time: last.time,
            samples: tracks.x.len(),
            mean_abs_detail: mean_abs,
            sparse_fraction: sparse,
            unconverged,
            volume: last.volume,
            area: last.area,
            mean_abs_curvature: mean_abs_curvature(&phi, &next),
        });
        times.push(level as f64 * time / opts.levels as f64);
        tracks.details.push(w);
        tracks.normal_details.push(wn);
        tracks.x = next;
        if opts.keep_level_sets {
            level_sets.push(phi.clone());
        }
    }
    let msr = Msr {
        faces: mesh.faces.clone(),
        num_vertices: samples.num_vertices,
        extra_face: samples.extra_face,
        extra_bary: samples.extra_bary,
        snap,
        born: tracks.born,
        samples: tracks.x,
        details: tracks.details,
        normal_details: tracks.normal_details,
        normals: tracks.normals,
        times,
        phi,
        params: MsrParams {
            velocity: opts.velocity.name().into(),
            c: opts.velocity.speed().unwrap_or(0.0),
            time,
            levels: opts.levels,
            dt,
            voxel: h,
            projection_tolerance_voxels: opts.projection.tolerance,
            software: format!("vesselmsr {}", env!("CARGO_PKG_VERSION")),
        },
    };
    Ok(Decomposition {
        msr,
        reports,
        level_sets,
    })
}

/// The samples' bookkeeping while the levels are built: X_{i−1}, the normals n_0..n_{i−1}, the
/// details of the levels done and each sample's birth level.
struct Tracks {
    x: Vec<Point3<f64>>,
    normals: Vec<Vec<Vector3<f64>>>,
    details: Vec<Vec<Vector3<f64>>>,
    normal_details: Vec<Vec<f64>>,
    born: Vec<u32>,
}

impl Tracks {
    /// Adds `new` samples of S_{born} with their `normals` at that level (zero normals and
    /// details before it).
    fn append(&mut self, new: Vec<Point3<f64>>, normals: Vec<Vector3<f64>>, born: usize) {
        let total = self.x.len() + new.len();
        self.normals.last_mut().expect("n_0 is set").extend(normals);
        for n in self.normals.iter_mut().rev().skip(1) {
            n.resize(total, Vector3::zeros());
        }
        for w in self.details.iter_mut() {
            w.resize(total, Vector3::zeros());
        }
        for w in self.normal_details.iter_mut() {
            w.resize(total, 0.0);
        }
        self.born.resize(total, born as u32);
        self.x.extend(new);
    }
}

/// The Newton projections of `points` onto the zero level set of `phi`, those that stall
/// restarted from the marching-cubes surface ([`rescue_unconverged`]).
fn project_with_rescue(
    phi: &Grid3,
    points: &[Point3<f64>],
    opts: &LevelProjectOptions,
) -> Result<Vec<Projected>> {
    let mut projected = project_to_zero_level(phi, points, opts);
    rescue_unconverged(phi, points, &mut projected, opts)?;
    Ok(projected)
}

/// Unit outward normals ∇φ/|∇φ| (tricubic) at `points`; zero where the gradient vanishes or the
/// point is off the grid.
fn outward_normals(phi: &Grid3, points: &[Point3<f64>]) -> Vec<Vector3<f64>> {
    points.par_iter().map(|p| outward_normal(phi, p)).collect()
}

/// [`outward_normals`] at one point.
pub(super) fn outward_normal(phi: &Grid3, p: &Point3<f64>) -> Vector3<f64> {
    unit_normal(phi, p).unwrap_or_else(Vector3::zeros)
}

/// Mean |∇·(∇φ/|∇φ|)| at `points` (central differences of the tricubic unit normal, step h/2);
/// points where it cannot be evaluated are skipped.
pub fn mean_abs_curvature(phi: &Grid3, points: &[Point3<f64>]) -> f64 {
    let d = 0.5 * phi.voxel();
    let (sum, count) = points
        .par_iter()
        .filter_map(|p| {
            let mut div = 0.0;
            for a in 0..3 {
                let mut e = Vector3::zeros();
                e[a] = d;
                div +=
                    (unit_normal(phi, &(p + e))?[a] - unit_normal(phi, &(p - e))?[a]) / (2.0 * d);
            }
            Some(div.abs())
        })
        .fold(|| (0.0, 0usize), |(s, c), k| (s + k, c + 1))
        .reduce(|| (0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    sum / count.max(1) as f64
}

/// ∇φ/|∇φ| of the tricubic interpolant at `p`; None off the grid or where the gradient vanishes.
pub(super) fn unit_normal(phi: &Grid3, p: &Point3<f64>) -> Option<Vector3<f64>> {
    phi.gradient_tricubic(p)
        .and_then(|g| g.try_normalize(1e-12))
}
