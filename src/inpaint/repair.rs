//! Vessel repair (paper Section 4, Algorithm 4): the damaged regions D of a mesh are inpainted on a
//! grid around D only, and the result is meshed and stitched into the original triangles.
//!
//! 1. Close the input's open vessel ends (unless kept open), size the voxel h (the project's
//!    default rule on the whole mesh, for the curvature motions no finer than an eighth of the
//!    vessel's radius, or given), and take a sub-box around D with a margin:
//!    the cost follows the size of D, not of the vessel tree.
//! 2. φ_0: signed distance of the (closed) input on the sub-box (winding-number sign, so holes
//!    are tolerated), redistanced so that the fills compare true distances: over the whole
//!    sub-box for the flows (closest-point sweeps), within 3 voxels of the regions' box for the
//!    axial fill (which reads φ_0 only near ∂D; by the closest-point transform, which finds the
//!    nearest crossing exactly and in a fixed number of passes).
//! 3. Fill D by one of the methods ([`InpaintMethod`]), unite it with the input (min(ψ, φ_0):
//!    the damage is missing volume, so nothing the input has is taken away), blend the result
//!    into φ_0 over a band inside ∂D (no seam) and, in a ball around a hole, over the intact
//!    wall beside the hole (`known_wall`: only the hole's cap is unknown there), remove pieces that float in D or voids sealed in
//!    it (`topology`), redistance near the surface (not after the axial fill, whose values are
//!    distances already).
//! 4. Mesh: marching cubes of the filled φ (closed specks smaller than a cell dropped; a patch
//!    with more handles than the input's genus has a tunnel through the vessel, and step 3's
//!    field is closed in D by the smallest radius that removes it, `tunnel`); with
//!    `keep_outside`, stitch the part deep in D into the input's triangles outside D, and when
//!    that fails at every cut depth, once more `STITCH_BEYOND_VOXELS` beyond D; when that fails
//!    too (or without `keep_outside`), re-mesh the whole vessel with the filled sub-box. The
//!    stitched surface is checked first (`checks`: no face inside the solid, no long stitch
//!    edges, no more pieces than the input, outward, no volume lost in D); a failed check counts
//!    as a failed stitch, and the reason of a whole re-mesh is in `Repair::fallback`. Check that
//!    the output is closed where the input was.

use super::axial::fill_axial;
use super::axis::{branch_crossings, estimate_axis, fit_cylinder};
use super::checks::RepairChecks;
use super::guided::{fill_guided, plan_guides, GuideKind, GuideOptions, HoleCaps, JUNCTION_FILL};
use super::junction::{fill_junction, Branch};
use super::known_wall::{
    cap_only_nodes, hole_balls, hole_rims, keep_known_wall, rim_points, HoleWall,
};
use super::mask::{blend_known, blend_weights, region_depth, region_mask};
use super::msr_fill::{fill_msr, MsrFillOptions};
use super::paper::{fill_paper, PaperOptions, DT_VOXELS2};
use super::region::{deepest_ball, Ball};
use super::shave::shave_bumps;
use super::stitch::{cut_out, stitch_patch_checked, without_specks, CutOut};
use super::topology::remove_islands;
use super::tunnel::{close_inside, closing_radii};
use crate::bvh::{bound_by_triangle, MeshBvh};
use crate::centerline::healthy::HealthyVessel;
use crate::centerline::stenosis::StenosisFindOptions;
use crate::centerline::{compute_centerline, CenterlineOptions};
use crate::grid::{spec::default_voxel, Grid3, GridTransform, SubBox};
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::levelset::redistance::{redistance, RedistanceOptions, RedistanceScheme};
use crate::levelset::voxelize::{voxelize, VoxelizeOptions};
use crate::mesh::cap::{cap_holes, CapOptions};
use crate::mesh::measures::{bounding_box, genus, handles, mean_edge_length};
use crate::mesh::orient::orient_outward;
use crate::mesh::topology::EdgeMap;
use crate::mesh::units::typical_vessel_radius;
use crate::motion::{Flow, FlowOptions, Velocity};
use crate::report::repair_report::Measured;
use crate::{Error, Result, TriMesh};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::fmt;
use std::str::FromStr;
use std::time::Instant;

/// How D is filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InpaintMethod {
    /// `centerline`: the vessel continued across D along its centreline, with its cross-section
    /// interpolated between the intact sections on either side (`guided`); regions no vessel
    /// passes through fall back to `axial`.
    Centerline,
    /// `axial`: φ_0 carried across D along a straight vessel axis (`axial`); also the fallback of
    /// `centerline` where no vessel passes through D.
    Axial,
    /// `msr`: one coarse level of v = c + κ_a − κ plus the details transferred harmonically
    /// (`msr_fill`).
    Msr,
    /// `flow`: v = c + κ_a − κ (eq. 4.2) run on φ with φ_0 restored outside D after every step:
    /// the fill relaxes to a surface of constant mean curvature matching the intact wall.
    Flow,
    /// `paper`: Algorithm 4 on the MSR of `msr` (`paper`): repeat { MST with v = c + κ_a − κ,
    /// IMST with viscosity ε (eq. 4.1; the intact wall's details carried across D), copy φ_0
    /// outside D, ε ← ε/4 } until the zero level set in D stops moving.
    Paper,
}

impl InpaintMethod {
    /// Every method, default first.
    pub const ALL: [InpaintMethod; 5] = [
        InpaintMethod::Centerline,
        InpaintMethod::Axial,
        InpaintMethod::Flow,
        InpaintMethod::Msr,
        InpaintMethod::Paper,
    ];

    /// Whether the method runs a curvature motion on φ (flow, msr, paper): it may grow the shape
    /// by up to c·T, evolves the whole sub-box, and works at its own default voxel.
    pub fn is_motion(self) -> bool {
        matches!(
            self,
            InpaintMethod::Flow | InpaintMethod::Msr | InpaintMethod::Paper
        )
    }

    /// The name used on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            InpaintMethod::Centerline => "centerline",
            InpaintMethod::Axial => "axial",
            InpaintMethod::Msr => "msr",
            InpaintMethod::Flow => "flow",
            InpaintMethod::Paper => "paper",
        }
    }
}

impl fmt::Display for InpaintMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for InpaintMethod {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        InpaintMethod::ALL
            .into_iter()
            .find(|m| m.as_str() == s)
            .ok_or_else(|| {
                Error::Geometry(format!(
                    "unknown inpainting method '{s}' (expected centerline, axial, flow, msr or paper)"
                ))
            })
    }
}

/// Options of [`repair`]. Lengths in world (file) units unless a field says voxels; the
/// defaults of c, T and ε scale with the vessel radius R estimated around D.
#[derive(Debug, Clone, PartialEq)]
pub struct RepairOptions {
    /// The fill (default [`InpaintMethod::Centerline`]).
    pub method: InpaintMethod,
    /// Voxel h, world units; `None`: the default rule on the whole input mesh (for the
    /// curvature motions at least [`MOTION_VOXELS_PER_RADIUS`]⁻¹ of the typical vessel radius).
    pub voxel: Option<f64>,
    /// Keep the input's triangles outside D and stitch the patch to them (default true).
    pub keep_outside: bool,
    /// Leave the input's open vessel ends open (default false: they are capped).
    pub open_ends: bool,
    /// Growth speed c of v = c + κ_a − κ (`flow`, `msr`, `paper`), 1/world length; default
    /// 0.3/R for `flow`, 1/R otherwise.
    pub speed: Option<f64>,
    /// Evolution time T of the coarse level, world length²; default R² for `flow` and `paper`,
    /// R²/2 for `msr`.
    pub time: Option<f64>,
    /// Time steps of the coarse level (default 4).
    pub steps: usize,
    /// Steps of `flow` (default 20).
    pub flow_steps: usize,
    /// First viscosity ε of `paper`, world length²; default R²/8.
    pub epsilon: Option<f64>,
    /// Most iterations of `paper` (default 12).
    pub max_iterations: usize,
    /// `paper` stops when the zero level set in D moves less than this, **in voxels** (default 0.1).
    pub tolerance_voxels: f64,
    /// Width of the band inside ∂D over which the fill is blended into φ_0, **in voxels**
    /// (default 2).
    pub blend_voxels: f64,
    /// Per region (in the order of the balls): its lumen is intact, only narrowed (a narrowing
    /// found along the centreline), so the input's centreline through it is the vessel's own
    /// and the `centerline` fill may follow it where it winds; missing entries: not intact
    /// (a hole's or a chop's centreline runs through a cap or a gap). Default empty.
    pub intact_lumen: Vec<bool>,
    /// The memory budget (bytes) the grids are checked against again when they must be sized
    /// a second time (c given without T: the margin for the growth c·T is known only once R
    /// is; see [`region_margin`]). `None`: not checked (the caller checked
    /// [`super::repair_budget::check`] once, as the pipeline does before the first sizing).
    pub max_memory: Option<u64>,
}

impl Default for RepairOptions {
    fn default() -> Self {
        RepairOptions {
            method: InpaintMethod::Centerline,
            voxel: None,
            keep_outside: true,
            open_ends: false,
            speed: None,
            time: None,
            steps: 4,
            flow_steps: 20,
            epsilon: None,
            max_iterations: 12,
            tolerance_voxels: 0.1,
            blend_voxels: 2.0,
            intact_lumen: Vec::new(),
            max_memory: None,
        }
    }
}

/// What [`repair`] produced and did.
#[derive(Debug, Clone)]
pub struct Repair {
    /// The repaired, closed (except kept open ends), outward mesh.
    pub mesh: TriMesh,
    /// The input as measured: capped unless the ends are kept open.
    pub closed_input: TriMesh,
    /// Voxel h, world units.
    pub voxel: f64,
    /// Nodes of the sub-box grid.
    pub grid_dims: [usize; 3],
    /// Voxel of the grid the patch was meshed on (h or 2h: [`patch_stride`]), world units; the
    /// whole-vessel re-mesh is meshed at h.
    pub patch_voxel: f64,
    /// Vessel radius R estimated around D (largest inside distance near ∂D), world units.
    pub radius_estimate: f64,
    /// Speed c used (`flow`, `msr`, `paper`; the others use none), 1/world length.
    pub speed: f64,
    /// Time T of the coarse level used (`flow`, `msr`, `paper`), world length².
    pub time: f64,
    /// First viscosity ε of `paper`, world length².
    pub epsilon: f64,
    /// The vessel axis used for each region (`axial`).
    pub axes: Vec<[f64; 3]>,
    /// Regions filled as junctions (`axial`: three or more branches cross the ball).
    pub junctions: usize,
    /// Iterations of the fill (1 for `axial` and `msr`).
    pub iterations: usize,
    /// Whether the fill converged (always for the one-shot fills).
    pub converged: bool,
    /// Whether the patch was stitched into the kept triangles (false: whole re-mesh).
    pub stitched: bool,
    /// How far beyond ∂D the patch was stitched, world units: 0, or `STITCH_BEYOND_VOXELS`
    /// voxels where it could not be stitched at ∂D (the input's surface re-meshed between).
    pub stitch_beyond: f64,
    /// Why the stitch was not used, when it was not.
    pub fallback: Option<String>,
    /// The curves of the `centerline` fill, by kind (a vessel through D, a gap bridged, a
    /// junction branch, a dead end, a widened narrowing).
    pub guides: Vec<GuideKind>,
    /// How each ball of D was filled: for `centerline`, its group's kind
    /// ([`GuideKind::region_fill`]: `through`, `bridge`, `junction`, `dead-end`, `stump`,
    /// `widened`) or `axial` where no vessel passes through it on the centreline; otherwise the
    /// method's name.
    pub region_fill: Vec<&'static str>,
    /// One-line notices (regions filled another way than asked, and why).
    pub notices: Vec<String>,
    /// Seconds per phase.
    pub timings: Vec<(String, f64)>,
    /// The fast winding numbers (`WindingOptions::SIDES`) of `closed_input` and `mesh` and their
    /// volumes in each ball, which the self-checks measured, for the report to read; `None` where
    /// no check ran (re-meshed whole, ends kept open).
    pub measured: Option<(Measured, Measured)>,
    /// Per ball of D, the volume of the capped input that lies outside the repaired vessel, held
    /// only by a hole's cap (a cap across a bifurcation's crotch; `known_wall::cap_only_nodes`),
    /// estimated by the fill grid's cells, world units³: the repair does not keep it, and the
    /// input's volume in D is counted without it.
    pub cap_outside: Vec<f64>,
}

/// The default voxel of the curvature-motion methods (flow, msr, paper): the typical vessel
/// radius (2·volume/area) over this. At the rule's voxel, R/25 on the phantoms (R = 3), they
/// took 10–120 s a phantom, paper 1,100 s on the stenosis one (12 rounds, not converged).
pub const MOTION_VOXELS_PER_RADIUS: f64 = 8.0;

/// Where D only grazes the input's surface (a ball on one wall reaching just past another
/// wall, or another branch), the input's triangles are kept: a connected piece of the faces D
/// reaches that lies within this depth inside ∂D throughout (voxels) is not cut out. The patch,
/// cut deeper than that, has no loop there to meet such a hole, and the stitch used to fail for
/// it and re-mesh the whole vessel (the open aorta's chop 2 of benches/repair_real seed 25).
const GRAZE_VOXELS: f64 = 1.0;

/// Sub-box margin around D beyond the balls, in voxels (the fills that grow the shape add half
/// the largest radius and their growth c·T).
const MARGIN_VOXELS: f64 = 6.0;
/// Margin around the regions' box within which φ_0 is redistanced for the axial fill (voxels):
/// its lines leave D within √3 voxels of ∂D, and the blend reaches 2 voxels into D.
const AXIAL_CORE_VOXELS: f64 = 3.0;

/// Time of the step that shaves a junction fill's bumps ([`shave_bumps`]), in units of R² (R the
/// vessel radius around D): a tube of radius R goes in by 1% of it. On the 30 junction chops of
/// `benches/repair_real` (seeds 21–27; Hausdorff distance in D to the truth, in voxels):
/// chosen on those of seeds 21–23 (14: 0.005 R², 0.01, 0.015, 0.02 gave medians 3.73 → 3.51,
/// 3.34, 3.15, 3.15h, 5 closer and 2 farther each, the aneurysm's), then seeds 24–27 (16):
/// median 4.29 → 3.96h, mean 4.71 → 4.41h, 13 closer, 2 farther; the volume error in D over the
/// 30: mean +1.26% → +0.23%, mean |error| 4.58% → 4.25%.
const JUNCTION_SHAVE_R2: f64 = 0.01;
/// The depths, in voxels inside ∂D, at which the patch is cut to be stitched (tried in turn): a
/// voxel or more leaves room for the zipper; the shallow ones, last, follow ∂D where the surface
/// grazes it and a deeper cut would merge the patch's loops (see `stitch`).
const STITCH_MARGINS_VOXELS: [f64; 8] = [1.5, 1.0, 0.75, 2.5, 3.5, 0.5, 0.25, 0.0];

/// Where the patch cannot be stitched at ∂D at any cut depth, it is stitched this many voxels
/// beyond it (D grown by as much, well within the fill's grid, MARGIN_VOXELS beyond D, where the
/// fill is the input's φ_0) before the whole vessel is re-meshed. A bifurcation's crotch that
/// touches ∂D is the case: the input's, cut there, leaves the two daughters' holes joined at a
/// vertex, while the patch's crotch, a fraction of a voxel out of D, joins their loops into one
/// ("3 holes around D but 2 patch loops": the capped aorta's junction chops of
/// `benches/repair_real` seeds 26 and 27, which took 2.3 and 1.6 s re-meshed whole).
const STITCH_BEYOND_VOXELS: f64 = 2.0;

/// The patch is meshed on every other node of the fill's grid (twice the voxel) where the vessel
/// around D is this many voxels in radius or more (R from [`Repair::radius_estimate`]) and twice
/// the voxel is no longer than the input's mean edge (see [`patch_stride`]).
const PATCH_COARSE_RADIUS_VOXELS: f64 = 12.0;

/// Every how many nodes of the fill's grid (voxel `h`) its surface is meshed for the patch: 2
/// where the vessel's radius `r` is `PATCH_COARSE_RADIUS_VOXELS` voxels or more and 2h is no
/// longer than the input's `mean_edge` (the default voxel is half of it), else 1. The fill itself
/// needs the fine grid (its tubes, a junction's shave); its surface does not always, nor does
/// what follows the fill node by node (the known wall, the union, the blend and the islands run
/// on the patch's nodes only: `finish_fill`). At the default voxel the patch was four times as
/// dense as the input (on the aneurysm's slowest chop of `benches/repair_real`, 55,000 of the
/// output's 64,000 triangles), and what is done with it (the stitch, the self-checks' and the
/// report's winding numbers, the picture) scales with it. Measured on the 105 chops of that
/// bench's seeds 21–27 with every patch meshed at 2h: the volume in D 0.0–0.1% lower at R ≥ 22h,
/// 0.2–0.4% at 12–16h, 0.4–1.0% at 8–10h and 0.8–2.2% at 4–7h (chords across a curved wall), the
/// Hausdorff distance within 0.13h of the fine patch's from 12h up (+0.18h at most below).
pub fn patch_stride(r: f64, h: f64, mean_edge: f64) -> usize {
    let coarse = 2.0 * h;
    if r >= PATCH_COARSE_RADIUS_VOXELS * h && coarse <= mean_edge * (1.0 + 1e-9) {
        2
    } else {
        1
    }
}

/// The sub-box's margin beyond the balls, world units, at voxel `h`: a few voxels, and for the
/// fills that grow the shape (msr, paper, flow), which move it by up to c·T, room for that too
/// (`growth_allowance`).
pub fn region_margin(opts: &RepairOptions, balls: &[Ball], h: f64) -> f64 {
    let rmax = balls.iter().map(|b| b.radius).fold(0.0, f64::max);
    if opts.method.is_motion() {
        0.5 * rmax + MARGIN_VOXELS * h + growth_allowance(opts, rmax)
    } else {
        MARGIN_VOXELS * h
    }
}

/// The growth c·T the margin of the shape-growing fills leaves room for, sized before the
/// vessel radius R is known (`rmax`: the largest region's radius, about R or more): c·T when
/// both are given; T/rmax for T alone (c = 1/R by default); rmax for neither (the defaults'
/// c·T is at most R); for c alone (T = R² or R²/2 by default) c·rmax², but at most rmax: on a
/// region several radii wide, c·rmax² sized the grids for the region's radius where the
/// vessel's is meant (a narrowing's region 3.6 R wide with c = 2.4/R: a 149 GiB estimate,
/// refused). Where the c·T that runs is more than this, the repair sizes its grids again for it.
fn growth_allowance(opts: &RepairOptions, rmax: f64) -> f64 {
    match (opts.speed, opts.time) {
        (Some(c), Some(t)) => c * t,
        (None, Some(t)) => t / rmax,
        (None, None) => rmax,
        (Some(c), None) => (c * rmax * rmax).min(rmax),
    }
}

/// Repairs `mesh` inside the union of `balls` (see the module docs). The `centerline` fill
/// traces the input's centreline first; [`repair_with_centerline`] takes one already traced.
pub fn repair(mesh: &TriMesh, balls: &[Ball], opts: &RepairOptions) -> Result<Repair> {
    repair_with_centerline(mesh, balls, opts, None)
}

/// [`repair`] with the input's centreline given (as traced by `compute_centerline` on `mesh`,
/// with its diameter profiles and healthy references), for the `centerline` fill; `None`
/// traces it when needed.
pub fn repair_with_centerline(
    mesh: &TriMesh,
    balls: &[Ball],
    opts: &RepairOptions,
    healthy: Option<&HealthyVessel>,
) -> Result<Repair> {
    repair_awaiting(mesh, balls, opts, &|| healthy)
}

/// [`repair_with_centerline`] with the centreline asked for only when the fill needs it
/// (`healthy` may wait for it to be traced meanwhile, as `pipeline` does).
pub(crate) fn repair_awaiting<'h>(
    mesh: &TriMesh,
    balls: &[Ball],
    opts: &RepairOptions,
    healthy: &dyn Fn() -> Option<&'h HealthyVessel>,
) -> Result<Repair> {
    let mut timings = Vec::new();
    let mut clock = Instant::now();
    let mut lap = |name: &str, timings: &mut Vec<(String, f64)>| {
        timings.push((name.to_string(), clock.elapsed().as_secs_f64()));
        clock = Instant::now();
    };
    if balls.is_empty() {
        return Err(Error::Geometry("no region to repair".into()));
    }
    for (k, b) in balls.iter().enumerate() {
        if !(b.radius > 0.0 && b.radius.is_finite()) {
            return Err(Error::Geometry(format!(
                "region {}: radius must be > 0, got {}",
                k + 1,
                b.radius
            )));
        }
    }
    for (name, v) in [
        ("c", opts.speed),
        ("time", opts.time),
        ("epsilon", opts.epsilon),
    ] {
        if let Some(v) = v {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::Geometry(format!("{name} must be > 0, got {v}")));
            }
        }
    }
    // An inward-facing input (negative enclosed volume) is turned outward (by the cap, which
    // faces its result outward, or here), so that the patch, the stitch and every volume of the
    // report agree.
    let mut flipped = false;
    let mut cap_faces = 0..0;
    let mut closed_input = if opts.open_ends || EdgeMap::new(mesh).boundary_edges() == 0 {
        mesh.clone()
    } else {
        let (capped, report) = cap_holes(mesh, &CapOptions::default())?;
        flipped = report.flipped;
        cap_faces = report.cap_faces;
        capped
    };
    let mut notices = Vec::new();
    if orient_outward(&mut closed_input) > 0 || flipped {
        notices.push("the input faced inward (negative volume): its triangles were flipped".into());
    }
    lap("cap", &mut timings);
    let (lo, hi) = bounding_box(&closed_input);
    // The default voxel's rule and the patch's stride (`patch_stride`) both read it.
    let mean_edge = mean_edge_length(&closed_input);
    let h = match opts.voxel {
        Some(v) if v > 0.0 && v.is_finite() => v,
        Some(v) => {
            return Err(Error::Geometry(format!(
                "--voxel must be a positive length in the mesh's units, got {v}"
            )))
        }
        None => {
            let rule = default_voxel(mean_edge, (hi - lo).max());
            // The curvature motions (flow, msr, paper) take a number of steps that grows as
            // h⁻² on a grid that grows as h⁻³: they work at MOTION_VOXELS_PER_RADIUS voxels
            // across the vessel's radius, the resolution their figures are measured at
            // (benches/inpaint), unless the rule is coarser.
            match opts
                .method
                .is_motion()
                .then(|| typical_vessel_radius(&closed_input))
                .flatten()
            {
                Some(r) => rule.max(r / MOTION_VOXELS_PER_RADIUS),
                None => rule,
            }
        }
    };
    // The lattice of the whole vessel (so the fallback re-mesh shares the sub-box's nodes).
    let rmax = balls.iter().map(|b| b.radius).fold(0.0, f64::max);
    let margin = region_margin(opts, balls, h);
    // Room for the fills that grow the shape (the sub-box is never clamped by the lattice).
    let pad = 4.0 * h + margin + 2.0 * rmax;
    let origin = lo - Vector3::repeat(pad);
    let whole_dims = [0, 1, 2].map(|a| ((hi[a] - lo[a] + 2.0 * pad) / h).ceil() as usize + 1);
    let sub = nodes_around(&origin, h, whole_dims, balls, margin);
    let first = sub.min;
    let dims = [0, 1, 2].map(|a| sub.max[a].saturating_sub(sub.min[a]));
    if dims.iter().any(|&n| n < 4) {
        return Err(Error::Geometry(
            "the regions lie outside the mesh's bounding box".into(),
        ));
    }
    let sub_origin = origin + Vector3::new(first[0] as f64, first[1] as f64, first[2] as f64) * h;
    let transform = GridTransform::new(sub_origin, h);
    let redistance_full = |g: &mut Grid3| {
        redistance(
            g,
            &RedistanceOptions {
                band: None,
                ..RedistanceOptions::default()
            },
        )
        .map(|_| ())
    };
    // The input cut open at D (for the stitch) meanwhile: mesh work that the voxelizer's
    // sequential sign flood leaves a core free for.
    let (phi0, cut) = rayon::join(
        || voxelize(&closed_input, dims, transform, &VoxelizeOptions::default()),
        || cut_out(&closed_input, balls, GRAZE_VOXELS * h),
    );
    let mut phi0 = phi0?;
    // True distances away from the surface too: the fills compare and interpolate them. The
    // axial fill reads φ_0 only within a few voxels of ∂D (where its lines leave D, and over the
    // blend band); beyond, the voxelizer's band is all marching cubes needs. There, the
    // closest-point transform: the sweeps' measure with the nearest crossing found exactly, at
    // a fixed cost (about 2.5× faster on the ~76³ core). The flows evolve the whole sub-box.
    // The centreline fill reads φ_0 within the voxelizer's band only: the core is redistanced
    // only if a region falls back to the axial fill (the transform was a fifth of the whole
    // command on a large region: 0.2 s of 1.2 s on the aneurysm's chops).
    let core = nodes_around(&sub_origin, h, dims, balls, AXIAL_CORE_VOXELS * h);
    let redistance_core = |phi0: &mut Grid3| -> Result<()> {
        let mut inner = phi0.extract(&core)?;
        redistance(
            &mut inner,
            &RedistanceOptions {
                scheme: RedistanceScheme::ClosestPointTransform,
                ..RedistanceOptions::default()
            },
        )?;
        phi0.write_back(&core, &inner)
    };
    match opts.method {
        InpaintMethod::Axial => redistance_core(&mut phi0)?,
        InpaintMethod::Centerline => {}
        _ => redistance_full(&mut phi0)?,
    }
    lap("voxelize", &mut timings);
    let depth = region_depth(&phi0, balls);
    let unknown = region_mask(&depth);
    // R: the largest inside distance in a shell just outside D. Where the core was redistanced,
    // over the nodes up to the largest ball's radius outside D (those of the core's box); for
    // the centreline fill, over the core's 3-voxel shell, measured to the input where the
    // voxelizer's band left a placeholder.
    let centreline_bvh =
        matches!(opts.method, InpaintMethod::Centerline).then(|| MeshBvh::new(&closed_input));
    let radius_estimate = match &centreline_bvh {
        Some(bvh) => shell_radius(
            &phi0,
            &depth,
            AXIAL_CORE_VOXELS * h,
            Some((&closed_input, bvh)),
        ),
        None => shell_radius(&phi0, &depth, rmax.max(3.0 * h), None),
    }
    .max(h);
    // c and T of the method that runs (the report gives what was used): `flow` 0.3/R and R²,
    // `paper` 1/R and R², `msr` (and the methods that use neither) 1/R and R²/2.
    let r2 = radius_estimate * radius_estimate;
    let (default_speed, default_time) = match opts.method {
        InpaintMethod::Flow => (0.3 / radius_estimate, r2),
        InpaintMethod::Paper => (1.0 / radius_estimate, r2),
        _ => (1.0 / radius_estimate, 0.5 * r2),
    };
    let speed = opts.speed.unwrap_or(default_speed);
    let time = opts.time.unwrap_or(default_time);
    let epsilon = opts
        .epsilon
        .unwrap_or(0.125 * radius_estimate * radius_estimate);
    if opts.method.is_motion() && speed * time > growth_allowance(opts, rmax) * (1.0 + 1e-9) {
        // The growth that runs needs a larger sub-box than the one sized before R was known
        // (c given without T): sized again for it, within the memory budget, with the c, T
        // and ε of this R (the larger box's shell would estimate R a little differently).
        let exact = RepairOptions {
            speed: Some(speed),
            time: Some(time),
            epsilon: Some(epsilon),
            ..opts.clone()
        };
        if let Some(max) = opts.max_memory {
            super::repair_budget::check(mesh, balls, &exact, max)?;
        }
        let mut resized = repair_awaiting(mesh, balls, &exact, healthy)?;
        resized.radius_estimate = radius_estimate;
        return Ok(resized);
    }
    let fill_opts = MsrFillOptions {
        speed,
        time,
        steps: opts.steps.max(1),
        harmonic: Default::default(),
    };
    let weights = blend_weights(&depth, opts.blend_voxels * h);
    let mut axes = Vec::new();
    let mut junctions = 0;
    let mut guides = Vec::new();
    let mut region_fill = vec![opts.method.as_str(); balls.len()];
    let mut iterations = 1;
    let mut converged = true;
    let psi = match opts.method {
        InpaintMethod::Axial => {
            let (g, a, j) =
                fill_axial_regions(&phi0, &closed_input, &cut, balls, &depth, radius_estimate)?;
            axes = a;
            junctions = j;
            g
        }
        InpaintMethod::Centerline => {
            let computed;
            let healthy = match healthy() {
                Some(h) => Some(h),
                None => match compute_centerline(mesh, &CenterlineOptions::default()) {
                    Ok((c, _)) => {
                        // The diameter profiles only where a narrowing is to be widened.
                        computed = if opts.intact_lumen.iter().any(|&i| i) {
                            HealthyVessel::new(mesh, c, &StenosisFindOptions::default())
                        } else {
                            HealthyVessel::unmeasured(c)
                        };
                        Some(&computed)
                    }
                    Err(e) => {
                        notices.push(format!(
                            "no centreline ({e}): every region filled along its axis instead"
                        ));
                        None
                    }
                },
            };
            let centerline = healthy.map(|h| &h.centerline);
            let bvh = centreline_bvh.unwrap_or_else(|| MeshBvh::new(&closed_input));
            let rim = hole_rims(&closed_input, cap_faces.clone(), balls);
            let holes = HoleCaps {
                faces: cap_faces.clone(),
                // Intact balls are sorted out per group by the planner (a group's cap is read
                // unless all its balls are intact).
                in_ball: hole_balls(&rim, balls, &[]),
                rim: rim_points(&rim),
            };
            let plans = centerline.map_or_else(Vec::new, |c| {
                plan_guides(
                    &bvh,
                    c,
                    balls,
                    &opts.intact_lumen,
                    healthy,
                    &holes,
                    h,
                    &GuideOptions::default(),
                )
            });
            let mut guided_ball = vec![false; balls.len()];
            // A ball no curve guides is filled along its axis.
            region_fill = vec![InpaintMethod::Axial.as_str(); balls.len()];
            for g in &plans {
                for &b in &g.balls {
                    guided_ball[b] = true;
                    region_fill[b] = GuideKind::region_fill(&g.kinds);
                }
                guides.extend(g.kinds.iter().copied());
            }
            let rest: Vec<Ball> = balls
                .iter()
                .zip(&guided_ball)
                .filter(|(_, &g)| !g)
                .map(|(b, _)| *b)
                .collect();
            let mut g = if rest.is_empty() {
                phi0.clone()
            } else {
                if centerline.is_some() {
                    notices.push(format!(
                        "{} region(s) with no vessel passing through them on the centreline: filled along their axis",
                        rest.len()
                    ));
                }
                redistance_core(&mut phi0)?;
                let (g, a, j) =
                    fill_axial_regions(&phi0, &closed_input, &cut, &rest, &depth, radius_estimate)?;
                axes = a;
                junctions = j;
                g
            };
            fill_guided(&mut g, balls, &plans);
            // A junction's union of tubes: its bumps shaved (see `shave`).
            let junction_balls: Vec<Ball> = balls
                .iter()
                .zip(&region_fill)
                .filter(|(_, &fill)| fill == JUNCTION_FILL)
                .map(|(b, _)| *b)
                .collect();
            shave_bumps(
                &mut g,
                &junction_balls,
                JUNCTION_SHAVE_R2 * radius_estimate * radius_estimate,
                opts.blend_voxels * h,
            )?;
            g
        }
        InpaintMethod::Msr => fill_msr(&phi0, &unknown, &fill_opts)?.0,
        InpaintMethod::Flow => {
            let steps = opts.flow_steps.max(1);
            let mut flow = Flow::new(
                Velocity::Inpaint { c: speed },
                time / steps as f64,
                FlowOptions {
                    allow_border: true,
                    ..FlowOptions::default()
                },
            )?;
            let mut psi = phi0.clone();
            iterations = steps;
            for _ in 0..steps {
                flow.step(&mut psi)?;
                redistance_full(&mut psi)?;
                blend_known(&mut psi, &phi0, &weights);
            }
            psi
        }
        InpaintMethod::Paper => {
            let paper = PaperOptions {
                speed,
                time,
                levels: opts.steps.max(1),
                dt: DT_VOXELS2 * h * h,
                epsilon,
                max_iterations: opts.max_iterations,
                tolerance: opts.tolerance_voxels * h,
                blend: opts.blend_voxels * h,
            };
            let (psi, report) = fill_paper(&phi0, balls, &paper)?;
            iterations = report.iterations;
            converged = report.converged;
            psi
        }
    };
    // What follows the fill works node by node (the known wall, the union with the input, the
    // blend into φ_0, the islands), and the patch is meshed on every `patch_stride`-th node: for
    // the centreline and axial fills, on those nodes only (an eighth of the work at a stride of
    // 2; the same values there, but that the pieces floating in D are now told by how those nodes
    // join: 6 of the 77 kept end bites of benches/repair_real, seeds 21–27, moved, by 0.23h at
    // most), the fine field being finished only for the whole-vessel re-mesh. The motions'
    // fields, redistanced afterwards, are finished on the fine grid.
    let patch_stride = patch_stride(radius_estimate, h, mean_edge);
    let finish = |phi0: &Grid3,
                  mut psi: Grid3,
                  mut weights: Vec<f32>,
                  unknown: &[bool],
                  close: Option<f64>| {
        let cap_outside = finish_fill(
            &closed_input,
            cap_faces.clone(),
            balls,
            &opts.intact_lumen,
            phi0,
            &mut psi,
            &mut weights,
            unknown,
            close,
            h,
        )?;
        // Marching cubes needs distances near the surface only. The axial and centreline fills
        // give distances, which are already that; the flows' and msr's fields are redistanced
        // first.
        if opts.method.is_motion() {
            redistance(
                &mut psi,
                &RedistanceOptions {
                    band: Some(3.0 * h),
                    ..RedistanceOptions::default()
                },
            )?;
        }
        Ok::<_, Error>((psi, cap_outside))
    };
    let coarse = patch_stride > 1 && !opts.method.is_motion();
    let coarse_nodes = if coarse {
        let nodes = |values: &[f32]| {
            Grid3::from_data(dims, transform, values.to_vec())
                .and_then(|g| g.subsample(patch_stride))
                .map(Grid3::into_data)
        };
        Some((
            phi0.subsample(patch_stride)?,
            region_mask(&nodes(&depth)?),
            nodes(&weights)?,
        ))
    } else {
        None
    };
    // The field finished (closed by `close`, world units: see `tunnel`), on the patch's nodes
    // when coarse, and its patch: the marching cubes on every `patch_stride`-th node, without
    // the closed pieces smaller than one of its cells (the grid's noise, no part of the vessel).
    let finished = |close: Option<f64>| {
        let (field, cap_outside) = match &coarse_nodes {
            Some((coarse_phi0, coarse_unknown, coarse_weights)) => finish(
                coarse_phi0,
                psi.subsample(patch_stride)?,
                coarse_weights.clone(),
                coarse_unknown,
                close,
            )?,
            None => finish(&phi0, psi.clone(), weights.clone(), &unknown, close)?,
        };
        let patch = if coarse || patch_stride == 1 {
            // The finished field itself (already on the patch's nodes).
            extract_surface(&field, &ExtractOptions::default())
        } else {
            field
                .subsample(patch_stride)
                .and_then(|g| extract_surface(&g, &ExtractOptions::default()))
        }?;
        let patch = without_specks(patch, (patch_stride as f64 * h).powi(3));
        Ok::<_, Error>((field, cap_outside, patch))
    };
    // Stitched into the kept triangles, or (without keep_outside, or when that fails) the whole
    // vessel re-meshed. Every cut depth is tried until a stitch passes the self-checks
    // (`checks`: no face inside the solid, no long stitch edges, outward, no volume lost in D;
    // they need a closed result). What the checks measure on the input, meanwhile (the cap's
    // volume the union leaves out does not depend on a closing, which only adds inside D).
    let (unclosed, (input_genus, checks)) = rayon::join(
        || finished(None),
        || {
            let checks = (opts.keep_outside && cut.open_edges == 0)
                .then(|| RepairChecks::new(&closed_input, balls, 3.0 * h));
            (genus(&closed_input), checks)
        },
    );
    let (mut field, mut cap_outside, mut patch) = unclosed?;
    // A handle the input does not have (`tunnel`): the field closed by the smallest radius that
    // removes it, or, when none does, kept as it is, with a notice either way.
    let mut tunnel_closing = None;
    if let (Some(g), Some(p)) = (input_genus, handles(&patch)) {
        if p > g {
            for r in closing_radii(radius_estimate) {
                let again = finished(Some(r))?;
                if handles(&again.2).is_some_and(|q| q <= g) {
                    tunnel_closing = Some(r);
                    (field, cap_outside, patch) = again;
                    break;
                }
            }
            notices.push(match tunnel_closing {
                Some(r) => format!(
                    "the fill left a tunnel through the vessel in D (the surface's genus {p} where the input's is {g}): closed by a morphological closing of radius {r:.3}"
                ),
                None => format!(
                    "the repaired surface has a tunnel through the vessel in D (its genus {p} where the input's is {g}) that closings up to half the vessel's radius did not remove"
                ),
            });
        }
    }
    let unfinished = coarse.then_some((psi, weights));
    lap("fill", &mut timings);
    let checks = checks.map(|c| c.allowing(&cap_outside));
    let stitch_in = |cut: &CutOut, balls: &[Ball]| {
        stitch_patch_checked(
            cut,
            &patch,
            balls,
            &STITCH_MARGINS_VOXELS.map(|m| m * h),
            |m| match &checks {
                Some(c) => c
                    .check(m)
                    .map(Some)
                    .map_err(|e| format!("self-check failed: {e}")),
                None => Ok(None),
            },
        )
    };
    let mut stitch_beyond = 0.0;
    let stitch = opts.keep_outside.then(|| {
        stitch_in(&cut, balls).or_else(|first| {
            // Once more at D grown by STITCH_BEYOND_VOXELS, where ψ is φ_0 (the fill's grid
            // reaches MARGIN_VOXELS beyond D): the patch there is the input's surface re-meshed.
            let grown: Vec<Ball> = balls
                .iter()
                .map(|b| Ball {
                    center: b.center,
                    radius: b.radius + STITCH_BEYOND_VOXELS * h,
                })
                .collect();
            let done = stitch_in(&cut_out(&closed_input, &grown, GRAZE_VOXELS * h), &grown)
                .map_err(|again| format!("{first}; {again} at D grown by {STITCH_BEYOND_VOXELS} voxels"))?;
            stitch_beyond = STITCH_BEYOND_VOXELS * h;
            notices.push(format!(
                "the patch did not meet the input at the edge of D ({first}): it was stitched {STITCH_BEYOND_VOXELS} voxels beyond D, where the input's surface is re-meshed"
            ));
            Ok(done)
        })
    });
    let stitched = matches!(stitch, Some(Ok(_)));
    let mut measured = None;
    let (mesh_out, fallback) = match stitch {
        Some(Ok((m, output_measured))) => {
            measured = checks.map(RepairChecks::into_input).zip(output_measured);
            (m, None)
        }
        other => (
            {
                let fine = match unfinished {
                    Some((psi, weights)) => {
                        let (fine, fine_cap_outside) =
                            finish(&phi0, psi, weights, &unknown, tunnel_closing)?;
                        cap_outside = fine_cap_outside;
                        fine
                    }
                    None => field,
                };
                remesh_whole(&closed_input, &fine, &depth, origin, whole_dims, first, h)?
            },
            other.and_then(|r| r.err()),
        ),
    };
    lap("mesh", &mut timings);
    let edges = EdgeMap::new(&mesh_out);
    if edges.boundary_edges() > cut.open_edges || edges.non_manifold_edges() > 0 {
        return Err(Error::Geometry(format!(
            "the repaired surface is not closed: {} open and {} non-manifold edges",
            edges.boundary_edges(),
            edges.non_manifold_edges()
        )));
    }
    Ok(Repair {
        mesh: mesh_out,
        closed_input,
        voxel: h,
        grid_dims: dims,
        patch_voxel: if stitched { patch_stride as f64 * h } else { h },
        radius_estimate,
        speed,
        time,
        epsilon,
        axes,
        junctions,
        iterations,
        converged,
        stitched,
        stitch_beyond,
        fallback,
        guides,
        region_fill,
        notices,
        timings,
        measured,
        cap_outside,
    })
}

/// After the fill `psi` (on `phi0`'s grid, or on every few of its nodes): the intact wall around
/// a hole kept (`keep_known_wall`: the fill acts in the hole's shadow only), the fill united with
/// the input (the damage a repair is for, a chopped wall, a narrowing, an occlusion, is missing
/// volume, so what the input has in D is kept) but for what only a hole's cap holds
/// (`cap_only_nodes`: a cap across a crotch spans space outside the vessel), blended into φ_0 by
/// `weights`, and the pieces floating in D (`unknown`) removed. `h` is the voxel of the input's
/// grid. Returns, per ball, the volume of the capped input that the union left out (world
/// units³).
#[allow(clippy::too_many_arguments)]
fn finish_fill(
    closed_input: &TriMesh,
    cap_faces: std::ops::Range<usize>,
    balls: &[Ball],
    intact_lumen: &[bool],
    phi0: &Grid3,
    psi: &mut Grid3,
    weights: &mut [f32],
    unknown: &[bool],
    close: Option<f64>,
    h: f64,
) -> Result<Vec<f64>> {
    let (cap_only, cap_outside) = match HoleWall::new(closed_input, cap_faces, balls, intact_lumen)
    {
        Some(holes) => {
            keep_known_wall(&holes, balls, phi0, psi, weights, h);
            cap_only_nodes(&holes, balls, phi0, psi)
        }
        None => (vec![false; psi.data().len()], vec![0.0; balls.len()]),
    };
    psi.data_mut()
        .par_iter_mut()
        .zip(phi0.data().par_iter())
        .zip(cap_only.par_iter())
        .for_each(|((v, &k), &cap)| {
            if !cap {
                *v = v.min(k);
            }
        });
    if let Some(r) = close {
        close_inside(psi, weights, r)?;
    }
    blend_known(psi, phi0, weights);
    remove_islands(psi, unknown);
    Ok(cap_outside)
}

/// The largest inside distance of `phi0` over the nodes outside D within `reach` of it (`depth`
/// in (−reach, 0]). With `exact` (the input and its hierarchy), a node that holds the voxelizer's
/// placeholder (−band·h, beyond its band) is measured to the input instead: its distance is at
/// most that to the previous such node's nearest triangle, which bounds the query, and a node
/// that bound shows cannot exceed the largest so far is not measured (the same maximum).
fn shell_radius(
    phi0: &Grid3,
    depth: &[f32],
    reach: f64,
    exact: Option<(&TriMesh, &MeshBvh)>,
) -> f64 {
    let placeholder = (VoxelizeOptions::default().band * phi0.voxel()) as f32;
    let reach = reach as f32;
    phi0.data()
        .par_iter()
        .zip(depth.par_iter())
        .enumerate()
        .filter(|(_, (_, &d))| d <= 0.0 && d > -reach)
        .fold(
            || (0.0_f64, None::<u32>),
            |(largest, hint), (n, (&v, _))| match exact {
                Some((mesh, bvh)) if v <= -placeholder * (1.0 - 1e-6) => {
                    let [i, j, k] = phi0.coords(n);
                    let p = phi0.world(i, j, k);
                    let bound = hint.map(|f| bound_by_triangle(&p, &mesh.triangle(f as usize)));
                    if bound.is_some_and(|b| b <= largest) {
                        return (largest, hint);
                    }
                    let q = bvh.closest_point_bounded(&p, bound);
                    let hint = q.is_found().then_some(q.face).or(hint);
                    (largest.max(q.distance), hint)
                }
                _ => (largest.max(-v as f64), hint),
            },
        )
        .map(|(largest, _)| largest)
        .reduce(|| 0.0, f64::max)
}

/// The axial fill of every ball (see `axial`): per ball, a tube through it (two crossings of
/// ∂D) takes the chord between them; a junction (three or more) the capsules of its branches;
/// otherwise (a chopped wall) the axis of the intact surface around the ball. Returns the filled
/// field, the axis used for each ball and the number of junctions.
fn fill_axial_regions(
    phi0: &Grid3,
    closed_input: &TriMesh,
    cut: &CutOut,
    balls: &[Ball],
    depth: &[f32],
    radius_estimate: f64,
) -> Result<(Grid3, Vec<[f64; 3]>, usize)> {
    // Per ball: a tube through it (two crossings) takes the chord between them; a
    // junction (three or more) tries each branch's axis; otherwise (a chopped wall) the
    // axis of the intact surface around the ball.
    let crossings = branch_crossings(cut, balls);
    let mut axes = Vec::new();
    let mut candidates = Vec::new();
    for (k, b) in balls.iter().enumerate() {
        let mine: Vec<_> = crossings.iter().filter(|c| c.ball == k).collect();
        let list = match mine.len() {
            2 => vec![(mine[1].center - mine[0].center)
                .try_normalize(1e-12)
                .unwrap_or(mine[0].axis)],
            n if n >= 3 => mine.iter().map(|c| c.axis).collect(),
            _ => vec![estimate_axis(closed_input, b, 2.0).ok_or_else(|| {
                Error::Geometry(format!(
                    "no surface around the region at {} (radius {}) to take the vessel axis from",
                    b.center, b.radius
                ))
            })?],
        };
        axes.push([list[0].x, list[0].y, list[0].z]);
        candidates.push(list);
    }
    let mut g = phi0.clone();
    let mut junctions = 0;
    fill_axial(&mut g, balls, &candidates)?;
    // A junction (three or more branches cross one ball): the capsules of the branches
    // instead, each with the radius it has at its crossing.
    for (k, _) in balls.iter().enumerate() {
        let mine: Vec<_> = crossings.iter().filter(|c| c.ball == k).collect();
        if mine.len() < 3 {
            continue;
        }
        // Each branch: a cylinder fitted to the intact wall next to its crossing.
        let branches: Vec<Branch> = mine
            .iter()
            .map(|c| {
                let fit = fit_cylinder(closed_input, balls, &c.center, 2.0 * radius_estimate);
                match fit {
                    Some((center, axis, radius)) => Branch {
                        center,
                        axis,
                        radius,
                    },
                    None => Branch {
                        center: c.center,
                        axis: c.axis,
                        radius: radius_estimate,
                    },
                }
            })
            .collect();
        let only: Vec<bool> = depth
            .iter()
            .enumerate()
            .map(|(n, &d)| {
                let [i, j, l] = phi0.coords(n);
                d > 0.0 && deepest_ball(balls, &phi0.world(i, j, l)).1 == k
            })
            .collect();
        fill_junction(&mut g, &only, &branches)?;
        junctions += 1;
    }
    Ok((g, axes, junctions))
}

/// The whole vessel re-meshed at h, with the filled sub-box in place of φ_0 inside D.
fn remesh_whole(
    closed: &TriMesh,
    psi: &Grid3,
    depth: &[f32],
    origin: Point3<f64>,
    dims: [usize; 3],
    first: [usize; 3],
    h: f64,
) -> Result<TriMesh> {
    let mut phi = voxelize(
        closed,
        dims,
        GridTransform::new(origin, h),
        &VoxelizeOptions::default(),
    )?;
    let [sx, sy, sz] = psi.dims();
    let reach = -(2.0 * h) as f32;
    for k in 0..sz {
        for j in 0..sy {
            for i in 0..sx {
                let n = psi.index(i, j, k);
                if depth[n] > reach {
                    phi.set(first[0] + i, first[1] + j, first[2] + k, psi.data()[n]);
                }
            }
        }
    }
    extract_surface(&phi, &ExtractOptions::default())
}

/// The nodes of the lattice of `dims` nodes from `origin` with spacing `h` that lie within
/// `margin` (world units) of the bounding box of `balls` (at most one node beyond), clamped to the
/// lattice.
fn nodes_around(
    origin: &Point3<f64>,
    h: f64,
    dims: [usize; 3],
    balls: &[Ball],
    margin: f64,
) -> SubBox {
    let mut min = dims;
    let mut max = [0usize; 3];
    for b in balls {
        for a in 0..3 {
            let lo = ((b.center[a] - b.radius - margin - origin[a]) / h).floor();
            let hi = ((b.center[a] + b.radius + margin - origin[a]) / h).ceil() + 1.0;
            min[a] = min[a].min(lo.clamp(0.0, dims[a] as f64) as usize);
            max[a] = max[a].max(hi.clamp(0.0, dims[a] as f64) as usize);
        }
    }
    SubBox::new(min, max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_patch_is_coarse_only_on_wide_vessels_at_the_input_density() {
        let (h, edge) = (0.25, 0.5);
        // Twelve voxels of radius and 2h within the mean edge: every other node.
        assert_eq!(patch_stride(12.0 * h, h, edge), 2);
        assert_eq!(patch_stride(30.0 * h, h, edge), 2);
        // A thinner vessel keeps the fill's grid (chords across it would lose volume).
        assert_eq!(patch_stride(11.9 * h, h, edge), 1);
        // A voxel coarser than half the mean edge: the patch would be coarser than the input.
        assert_eq!(patch_stride(30.0 * h, h, 0.49), 1);
        assert_eq!(patch_stride(30.0 * h, h, 0.51), 2);
    }
}
