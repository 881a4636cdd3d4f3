//! The centreline-guided fill of D: the vessel continued across D along its own centreline.
//!
//! Paper Section 4 inpaints D so that the shape follows the intact vessel around it; the
//! coarsest scale of a vessel is its centreline with a cross-section, so that is what is carried
//! across D here, before the finer scales (the wall's own surface outside D, kept by the union
//! and the blend of `repair`):
//!
//! 1. **Anchors.** The centreline of the damaged input (`centerline`) is cut where it enters the
//!    region: per branch, each maximal run of points inside the enlarged region E (the balls of D
//!    grown by a clearance of a few voxels). The branch point before the run (and the one after
//!    it) is an anchor, moved outward along the branch until its cross-section plane is clear of
//!    D (the section is then intact wall; where none is before the branch ends or the walk
//!    reaches a junction's flare, its inscribed sphere grown by the vessel's radius, the section
//!    is not read: the other anchor's is used, or a circle of the narrowest radius walked over;
//!    a section ray that ends on another branch's wall is dropped). An anchor has a position, the tangent pointing into
//!    D, and a cross-section: the wall's distance from the centreline point along rays in the
//!    section plane ([`GuideOptions::rays`] angles), so non-circular vessels keep their shape.
//! 2. **Curves.** A run with an anchor on both sides (the vessel passes through D) is bridged by
//!    the cubic Hermite curve matching both anchors' positions and tangents (tangent length: the
//!    chord scaled so that a circular bend is followed, within 0.03% of its radius at 90°; where
//!    D holds an intact, only narrowed lumen, its measured axis, the input's centreline
//!    smoothed, is followed instead). Around a hole, that curve is moved onto the centre of the
//!    intact wall it passes (circles fitted where the wall holds three quarters of a section,
//!    half in a round vessel, in a few passes: [`ROUND_SECTION`]; less their bias beside D,
//!    where the curve is the vessel's centreline: `recentre`).
//!    Runs that end inside D (a gap: the vessel cut in two; a junction in D) give
//!    one-sided anchors: two are bridged the same way (unless neither points at the other,
//!    [`BRIDGE_MIN_FACING`], and an open vessel end lies in E ahead of them: two branches side
//!    by side whose junction D holds, the vessel beyond cut short; that end is then a third
//!    branch); three or more (a bifurcation) are each
//!    continued to the junction point (the centreline's junction inside E, not a thin spur of the
//!    damage's skeleton: [`JUNCTION_MIN_RADIUS`]; else the point nearest to all anchor axes in
//!    least squares), along a Hermite curve that keeps the anchor's direction twice as long as a
//!    circular bend would and turns into the junction late ([`JUNCTION_TANGENTS`]), leaving the
//!    junction the way the damaged centreline does (the graph walked from the anchor's branch to
//!    that junction; unless the anchor's tangent already points at the junction: a straight
//!    vessel, whose centreline a cap bends), end there in a round cap (a ball no wider than the
//!    junction's inscribed sphere, unless that sphere rests on a hole's cap: the parent's own
//!    radius stood 1.2 mm out of the wall beside the aortic bifurcation) and are joined by a
//!    smooth minimum of a quarter radius (the fillet of a carina). Where two or more end in D,
//!    or one crosses it, a branch the damage took whole with its cut end (no anchor leads to
//!    it) joins them (as one more junction branch, or as a side branch) from that end, read off
//!    the hole's rim: the plane holding 8 or more rim points to 10⁻³ of the radius, a run of
//!    them along a circle of a vessel's size, with the rim on one side and no vessel beyond it
//!    (`cut_end_in_rim`), at the centre of that circle, its tube cut flat there. A single one
//!    beside a vessel that crosses D is a side branch, continued to that vessel's curve where its
//!    axis meets it and joined the same way; a single one alone is bridged to the branch's open
//!    vessel end (the centre of a cut across the vessel, outside the damage) and cut flat there;
//!    else to an open end inside E that the damaged centreline, broken into spurs by a cap
//!    across most of the wall, does not reach (`open_end_in`); else, where the hole has bitten
//!    into the vessel's cut end (an open end or a flat cap the damage reached, so that the
//!    hole's rim runs partly along the cut), to that cut's plane, found as the plane holding 8
//!    or more of the rim's points to 10⁻³ of the radius (`bitten_end`: segmentations are
//!    clipped by planes), at the centre of the circle through them; else, where the branch
//!    ends closed beyond D, to its section at the damaged centreline's tip (`closed_end_section`:
//!    a circle fitted to the intact wall, outside E, in the plane across the chord from the
//!    anchor; the damaged centreline bends towards the wall the hole left: 3.3 mm off the
//!    vessel's axis in a chop beside the capped aorta's closed end) and cut flat there; or,
//!    where that section is not intact (the damage reaches the end), continued along its own
//!    damaged centreline and capped round.
//! 3. **Sections.** Along a curve, a rotation-minimising frame (double reflection, Wang, Jüttler,
//!    Zheng and Liu 2008) is carried from the first anchor; the section at arc-length fraction w
//!    is (1 − w)·ρ_A(θ) + w·ρ_B(θ), both profiles read in the carried frame, so a tapering or
//!    flattening vessel changes smoothly across D. On top of this coarse shape, the wall's
//!    details: at each curve sample and angle, the ray meets the input's wall outside D at some
//!    offset from that section; these offsets are interpolated along the curve per angle across
//!    D (issue 21's "details carried across D"; faded out towards a junction point, and not read
//!    within a junction's flare, whose wall is no single vessel's). Around a hole (a group of
//!    balls holding a cap's rim, [`HoleCaps`]), every tube also reads the wall inside D wherever
//!    its ray meets the input's own triangles rather than the cap (a ray goes on past the cap,
//!    which beside a rim that is not planar hides intact wall), within a junction's flare
//!    too (on the branches of the tube's anchors: a gap's two ends may lie on two): that wall
//!    is intact. The offsets over the hole are then the biharmonic interpolation of the
//!    readings on the tube's wall chart (arc length × arc of the section, the second
//!    difference around weighing [`super::wall_chart::AROUND_WEIGHT`] of the one along;
//!    `wall_chart`), so the missing part of a section takes its shape, slope and bulge from the
//!    wall beside it, around the vessel as well as along it; on a tube with no second anchor a filled offset
//!    pushes the wall out by at most [`MAX_FILLED_BULGE`] of the section's radius (past the
//!    last reading, towards a junction point, the interpolation's slope runs on; between two
//!    anchors the readings on either side hold it, and a bulb's wall over a hole may stand
//!    well beyond the anchors' sections). Through a narrowing (an intact lumen,
//!    `--stenoses` or a point picked on it), a section whose rays all meet the narrowed wall
//!    takes that wall's own shape, scaled about its centroid to the interpolated size. (A
//!    narrowing's region is planned by [`super::widen`] instead, the lesion widened to the
//!    healthy reference between its shoulders, whenever the input's centreline finds it narrower
//!    than that reference; the anchors of this module are then its fallback.)
//! 4. **Field.** At a node x of D, each tube gives |x − c|⊥ − ρ(θ) from its nearest curve sample
//!    c (the offset projected on the section plane there; past an open anchor end the tube
//!    continues straight, past a capped end it closes as a ball), and the fill is the smallest
//!    over the tubes: a signed distance (to first order) to the union of the tubes.
//!
//! Where the centreline gives no anchor for a region (no vessel passes through it, a region on a
//! blob such as an aneurysm sac), the region is left to the caller (`repair` falls back to the
//! axial fill there).

use super::adaptive::{sample_adaptive, AdaptiveOptions};
use super::groups::linked_groups;
use super::junction::{junction_point, smooth_min, Branch as AxisBranch};
use super::region::Ball;
use super::wall_chart::fill_with_tension;
use super::widen::plan_widening;
use crate::bvh::{MeshBvh, RayHit};
use crate::centerline::healthy::HealthyVessel;
use crate::centerline::{Branch, Centerline, EndKind};
use crate::grid::Grid3;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::f64::consts::TAU;
use std::ops::Range;

/// The cap triangles of the closed input (`cap_holes`) and which balls of D hold a hole's rim:
/// inside those, the wall that is not cap is intact (`known_wall`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HoleCaps {
    /// Face range of the cap triangles in the mesh the sections are read on.
    pub faces: Range<usize>,
    /// Per ball: whether a hole's rim lies in it (missing entries: no).
    pub in_ball: Vec<bool>,
    /// The vertices of the holes' rims (each once).
    pub rim: Vec<Point3<f64>>,
}

/// Options of [`plan_guides`]. Lengths in voxels where the field says so.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuideOptions {
    /// Rays per cross-section (angles evenly spaced; default 48). Around a hole, where the
    /// wall's details are carried across it, a wider vessel gets more, up to [`MAX_RAYS`]: about
    /// one per [`RAY_SPACING_VOXELS`] of its wall around.
    pub rays: usize,
    /// The region is grown by this many voxels before the centreline is cut (default 2).
    pub clearance_voxels: f64,
    /// Farthest an anchor is moved outward along its branch looking for a section clear of D,
    /// in vessel radii at the anchor (default 6).
    pub max_walk_radii: f64,
    /// Curve samples per voxel of arc length (default 2).
    pub samples_per_voxel: f64,
}

impl Default for GuideOptions {
    fn default() -> Self {
        GuideOptions {
            rays: 48,
            clearance_voxels: 2.0,
            max_walk_radii: 6.0,
            samples_per_voxel: 2.0,
        }
    }
}

/// How a tube ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EndCap {
    /// Continues straight beyond the last sample (an anchor: the vessel goes on outside D).
    Open,
    /// Closed by a ball of the section's mean radius (a junction point, a dead end).
    Round,
    /// Cut by the plane across the last sample (a branch that ends at an open vessel end).
    Flat,
}

/// One tube of the fill: a sampled curve with frames and the sections at its two ends.
#[derive(Debug, Clone, PartialEq)]
pub struct GuideTube {
    /// Curve samples, world units.
    pub points: Vec<Point3<f64>>,
    /// Unit tangent and the two section axes at each sample (rotation-minimising).
    pub frames: Vec<[Vector3<f64>; 3]>,
    /// Arc-length fraction of each sample, 0 at the first and 1 at the last.
    pub weight: Vec<f64>,
    /// Section radii at the first sample, at angles 2πj/rays in its frame (world units).
    pub start_profile: Vec<f64>,
    /// Section radii at the last sample, same angles, in the carried frame there.
    pub end_profile: Vec<f64>,
    /// How the last sample ends the tube.
    pub end_cap: EndCap,
    /// The first sample ends the tube flat (a widened narrowing's); otherwise it is an anchor
    /// and the tube goes on straight beyond it.
    pub flat_start: bool,
    /// Radius of the ball that closes a round end, world units.
    pub cap_radius: f64,
    /// The wall's offset from the interpolated section at each sample and ray angle (sample-major,
    /// world units): the details of the wall around D carried across it.
    pub detail: Vec<f64>,
    /// Bounding spheres (centre, radius) of runs of [`CHUNK`] consecutive samples, for the
    /// nearest-sample search.
    chunks: Vec<(Point3<f64>, f64)>,
    /// The largest section radius with its detail, world units.
    widest: f64,
}

/// The mean of a section profile's radii, world units.
fn mean(profile: &[f64]) -> f64 {
    profile.iter().sum::<f64>() / profile.len() as f64
}

/// Curve samples per bounding sphere of [`GuideTube::distance`]'s search.
const CHUNK: usize = 16;

/// Around a hole, the section rays are about this many voxels apart on the widest anchor's
/// wall (the wall's details read and carried across the hole at about the grid's resolution),
/// at least [`GuideOptions::rays`] of them and at most [`MAX_RAYS`]. On the real chops of
/// `benches/repair_real` (48 rays everywhere before): the aneurysm's neck 3.10h → 2.49h, its
/// chop#3 3.09h → 2.98h, the capped aorta's wall 2.75h → 2.65h; the carotid's and coronary's
/// (48 rays already about 1.4 and 1.3 voxels apart) unchanged; the capped aorta's carina
/// 3.46h → 3.82h (its error comes from the junction's place). At 1.5 voxels the chart's solve
/// took 0.3 s on the aneurysm's neck.
pub const RAY_SPACING_VOXELS: f64 = 2.0;

/// Most rays per cross-section.
pub const MAX_RAYS: usize = 128;

/// Around a hole, a detail the wall chart's biharmonic fill gives (no ray read the wall there)
/// pushes the wall out by at most this fraction of the section's radius. The fill carries the
/// readings' slope on past the last of them: towards a junction point (no second anchor) it swelled
/// a section to 2.3 times its radius (a detail of 1.29 radii) on the seed-25 open aorta's
/// junction chop of `benches/repair_real`, a bulge 2 mm above the aorta's top wall. Over the
/// 105 wall chops of seeds 21–27, bounds of 0.5, 0.65 and 0.8 radii changed the junction fills
/// only: 8 better and 7 worse, 7 and 2, 5 and 0 (an aneurysm's flare is real and wide); 0.8 is
/// kept (the junction chops' mean 4.57h → 4.40h; the seed-25 open aorta's 8.24h → 6.26h).
/// Only a tube with no second anchor is bounded: between two anchors the bound held the
/// seed-34 carotid bulb's wall chop (held out) 1 mm inside the bulb, 4.08h / −16.2% in D, and
/// without it 3.10h / −4.8%; on the 325 kept cases of seeds 21–33 that changed 6 outputs, by
/// 0.09h at most (the seed-32 carotid's chop #3 1.50h → 1.59h, +2.0% → +2.3%; the seed-28
/// carotid's chop #3 +3.8% → +5.0% at the same 2.13h).
pub const MAX_FILLED_BULGE: f64 = 0.8;

/// Tension of a junction branch's wall chart over a hole, in units of 1/R² (R its section's
/// radius at the anchor): the offsets minimise Σ (L u)² + τ Σ |∇u|² (`wall_chart`), a thin plate
/// over lengths below R and a membrane above. The thin plate alone carried the wall's slope on
/// towards the junction point, where no wall is read, and the fill stood too high over a hole
/// at a bifurcation. On the 30 junction chops of `benches/repair_real` (seeds 21–27; Hausdorff
/// distance in D, voxels): chosen on those of seeds 21–23 (14; τ = 0, 0.5, 1, 2, 4, 16: medians
/// 3.35, 3.09, 3.09, 3.12, 3.42, 4.06h), held out on seeds 24–27 (16): median 3.96 → 3.61h; all
/// 30: median 3.50 → 3.33h, mean 4.20 → 4.04h, 11 → 13 within 3h, 15 closer and 10 farther,
/// MeshLib's fill beaten on 18 → 22. The same tension on every tube's chart made the other 75
/// chops worse (median 0.99 → 1.04h, mean 1.27 → 1.33h).
pub const JUNCTION_CHART_TENSION: f64 = 1.0;

/// A junction of the damaged centreline is taken as a bifurcation's only where its inscribed
/// sphere is at least this fraction of the narrowest anchor's radius. A hole's flat cap dents
/// the lumen, and its skeleton sprouts short spurs whose junctions are thin: in seed 29's
/// capped-aorta chop over the bifurcation of `benches/repair_real` (held out), ten junctions
/// lie in E with inscribed radii of 0.27–4.35 where the iliacs' are 4.1–4.2; the one nearest the
/// anchors (radius 1.24) stood 11.7 mm from the truth's (the widest one, 4.35, stands 7.0 mm
/// from it) and the trunk was led across the iliac's lumen to it: 15.79h. On the 61 junction
/// fills of the 375 kept cases of seeds 21–35 this moves three junctions (the seed-29 capped and
/// open aortas, 15.79h → 8.48h and 17.01h → 7.18h; the seed-30 capped aorta, 8.07h → 3.01h)
/// and no other output. (Judged by the junctions' distances to the truth's: 0.3 moves only the
/// seed-29 open aorta's, to one farther from it; 0.8 picks the same three as 0.5.)
pub const JUNCTION_MIN_RADIUS: f64 = 0.5;

/// Tangent lengths of a junction branch's Hermite curve, at its anchor and at the junction
/// point, as multiples of `hermite`'s (the chord's, for a circular bend): a vessel runs on along
/// its own axis up to the bifurcation and turns into the junction point inside the flare, where
/// the curve with equal tangents cut the corner from the anchor. In seed 27's capped-aorta chop
/// over the carina of `benches/repair_real` the left iliac's curve ran 3 mm inside the truth's
/// centreline 6 mm below the junction (x 218.7 against 215.5): the two iliacs' tubes met there,
/// and the carina stood 3 mm low (9.63h; 8.90h with the lengths kept). On the 61 junction fills
/// of the 375 kept cases of seeds 21–35 (Hausdorff in D; mean, median): (1, 1) 4.14h, 3.56h;
/// (1.5, 1) 4.03h, 3.12h; (2, 1) 4.06h, 3.60h; (1, 0.5) 4.80h, 3.96h; (1.5, 0.5) 4.13h, 3.54h;
/// (2.5, 0.5) 3.77h, 3.33h; (3, 0.5) 3.87h, 3.37h; (2, 0.75) 3.88h, 3.21h; (2, 0.25) 3.82h,
/// 3.22h; (2, 0.5), kept: 3.78h, 3.06h, 38 closer and 15 farther (seeds 21–28: 28 and 6, mean
/// 3.90h → 3.41h; seeds 29–35: 10 and 9, 4.46h → 4.28h), within 3h 25 → 28. Nothing else
/// moves. With these lengths neither the branches' fillet (0.15, 0.35 of a radius against 0.25)
/// nor the chart's tension (0.5, 2 against 1) does clearly better on those 61 (closer /
/// farther: 7 / 14; 14 / 12, mean 3.78h → 3.77h; 23 / 16, median 3.06h → 3.20h; 14 / 28).
pub const JUNCTION_TANGENTS: [f64; 2] = [2.0, 0.5];

/// Two vessel ends inside D are bridged as one vessel's two sides only where each one's tangent
/// into D points at the other within this cosine (an occlusion's ends: about 1; two sides of
/// a gap across a right-angled bend: 0.7); the open aorta's two iliacs, side by side below a
/// severed bifurcation, read 0.27 and 0.20.
pub const BRIDGE_MIN_FACING: f64 = 0.5;

/// A vessel counts as round where the radii of its anchors' sections vary by less than this
/// (their standard deviation over their mean; a section reads the wall along evenly spaced
/// rays). Its curve through a hole is then moved onto the intact wall's centre from half a
/// section of wall, in [`ROUND_FIT`]'s repeated passes, where others need three quarters in one
/// ([`STRICT_FIT`]). A cubic that cuts the inside of a bend over a hole there runs so near the
/// hole's cap that the far wall lies out of its reach: in seed 34's coronary bend chop of
/// `benches/repair_real` no sample of the curve's middle read a wall (its rays met the cap or
/// nothing), and the tube overfilled the bend's inner crease (1.91h, +10.2%). Each pass moves
/// the curve nearer the centre, and its sections read more of the wall. On the 141 through-hole
/// fills of the 375 kept cases of seeds 21–35 the anchors' sections vary by 0.25–1.04% or
/// 1.28–14% on the coronary, 1.27–15% on the aneurysm's ICA, 1.8–12% on the aortas and the
/// carotid. Half a section of a wall that is not round misplaces its centre: with every vessel
/// fitted from half its wall (three passes), 42 outputs came closer and 80 farther, the
/// aneurysm's ICA up to 1.12h → 13.85h (seed 32's chop #3); with a bound of 1.45% (three
/// passes), 17 and 8 of the 141 (seed 26's aneurysm chop #2 3.49h → 5.06h). With 1.2%: 14 closer and 1 farther (+0.07h), all
/// on the coronary but a carotid's dead end (0.17h → 0.19h); the coronary's bend chops of seeds
/// 34, 30 and 24 1.91h → 1.08h, 2.24h → 1.08h, 1.70h → 1.04h.
pub const ROUND_SECTION: f64 = 0.012;

/// How much of a section's intact wall `recentre` needs before it fits the section's circle, and
/// how many times the wall is read again from the moved curve.
#[derive(Clone, Copy, Debug)]
struct WallFit {
    /// Fewest rays meeting the wall, as a fraction of the section's rays.
    known: f64,
    /// Longest run of rays with no reading, as a fraction of a turn.
    gap: f64,
    /// Passes of `recentre`, each from the curve the last one moved.
    passes: usize,
}

/// The fit around a hole in a vessel whose sections are not round (see [`ROUND_SECTION`]).
const STRICT_FIT: WallFit = WallFit {
    known: 0.75,
    gap: 0.25,
    passes: 1,
};

/// The fit in a round vessel. On the 141 through-hole fills of the kept cases (closer / farther
/// than with [`STRICT_FIT`], all on the coronary; seed 34's bend chop): half the rays and half a
/// turn in 2 passes 13 / 0 (1.53h), 3 passes 13 / 1 (1.31h), 5 passes 13 / 1 (1.08h, kept), 8
/// passes 12 / 3 (0.95h); 0.4 of the rays and 0.6 of a turn in 3 passes 14 / 1 (0.81h), 8 passes
/// 11 / 3; 0.3 and 0.75 in 5 passes 13 / 2 (0.73h); 0.6 and 0.4 in 3 passes 8 / 2; three
/// quarters and a quarter turn in 3 passes 2 / 4 (2.01h). Mean over the 141: 1.34h before,
/// 1.29–1.31h for all of these but the last two.
const ROUND_FIT: WallFit = WallFit {
    known: 0.5,
    gap: 0.5,
    passes: 5,
};

/// The spread of a section's radii: their standard deviation over their mean (None for an
/// empty or degenerate section).
fn radius_spread(radii: &[f64]) -> Option<f64> {
    let mu = mean(radii); // NaN for no radii
    if !mu.is_finite() || mu <= 0.0 {
        return None;
    }
    let var = radii.iter().map(|r| (r - mu).powi(2)).sum::<f64>() / radii.len() as f64;
    Some(var.sqrt() / mu)
}

/// Holds each filled (not `known`) detail of a tube's chart (`m` rays per sample) to at most
/// [`MAX_FILLED_BULGE`] of its section radius `base(sample, ray)` outward.
fn bound_filled_bulge(
    detail: &mut [f64],
    known: &[bool],
    m: usize,
    base: &impl Fn(usize, usize) -> f64,
) {
    for (k, d) in detail.iter_mut().enumerate() {
        if !known[k] {
            *d = d.min(MAX_FILLED_BULGE * base(k / m, k % m));
        }
    }
}

/// What the centreline gave for one group of overlapping balls.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum GuideKind {
    /// The vessel passes through D: bridged between its two anchors.
    Through,
    /// The vessel is cut in two inside D (a gap): its two ends bridged.
    Bridge,
    /// Three or more branches meet in D: each continued to the junction point.
    Junction,
    /// A single branch ends in D at an end found there (an open end, a cut's plane, an intact
    /// closed end beyond D): continued to it and cut flat.
    DeadEnd,
    /// A single branch stops in D with nothing found beyond it: continued along its damaged
    /// centreline and capped round. The damage may have taken what went on beyond (a
    /// bifurcation cut off with its branches, which the input no longer holds).
    Stump,
    /// A narrowing widened to the healthy lumen between its shoulders ([`super::widen`]).
    Widened,
}

/// The report's `fill` of a region filled as a junction ([`GuideKind::region_fill`]).
pub const JUNCTION_FILL: &str = "junction";

/// The report's `fill` of a region where a vessel stops with nothing found beyond it
/// ([`GuideKind::Stump`]).
pub const STUMP_FILL: &str = "stump";

impl GuideKind {
    /// How a region D whose group of balls has these curves was filled, for the report: the
    /// least certain kind first (a junction's carina and flare are modelled, not measured).
    pub fn region_fill(kinds: &[GuideKind]) -> &'static str {
        let has = |k: GuideKind| kinds.contains(&k);
        if has(GuideKind::Junction) {
            JUNCTION_FILL
        } else if has(GuideKind::Stump) {
            STUMP_FILL
        } else if has(GuideKind::DeadEnd) {
            "dead-end"
        } else if has(GuideKind::Bridge) {
            "bridge"
        } else if has(GuideKind::Widened) {
            "widened"
        } else {
            "through"
        }
    }
}

/// The guide of one group of overlapping balls.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionGuide {
    /// Indices of the balls of the group.
    pub balls: Vec<usize>,
    pub tubes: Vec<GuideTube>,
    /// The kinds of the group's curves (one per tube).
    pub kinds: Vec<GuideKind>,
    /// Width of the smooth union of junction branches, world units (a quarter of the thinnest
    /// branch's mean radius).
    pub fillet: f64,
}

/// An anchor: where a branch enters D, moved out to an intact section.
#[derive(Debug, Clone, Copy)]
struct Anchor {
    point: Point3<f64>,
    /// Unit tangent pointing into D.
    into: Vector3<f64>,
    /// Inscribed radius there.
    radius: f64,
    /// Whether its section is clear of D (else the walk stopped at the branch's end or its
    /// limit: next to a junction, whose section is no tube's).
    clear: bool,
    /// The centreline branch it lies on (none for a curve's inner end).
    branch: Option<usize>,
    /// Its point's index on that branch.
    index: usize,
}

/// Groups of overlapping balls (indices), in order of their first ball.
fn ball_groups(balls: &[Ball]) -> Vec<Vec<usize>> {
    linked_groups(balls.len(), |a, b| {
        (balls[a].center - balls[b].center).norm() < balls[a].radius + balls[b].radius
    })
}

/// The guides of the balls: one per group of overlapping balls through which the centreline
/// gives a vessel (see the module docs); groups without are left out. `mesh_bvh` is the BVH of
/// the closed damaged input (the sections are read on it), `h` the voxel; `intact[i]`: ball i's
/// lumen is only narrowed, its centreline the vessel's (a group of such balls may follow it,
/// `follow_or_bridge`; missing entries are false).
pub fn plan_guides(
    mesh_bvh: &MeshBvh,
    centerline: &Centerline,
    balls: &[Ball],
    intact: &[bool],
    healthy: Option<&HealthyVessel>,
    holes: &HoleCaps,
    h: f64,
    opts: &GuideOptions,
) -> Vec<RegionGuide> {
    let mut out = Vec::new();
    for group in ball_groups(balls) {
        let gb: Vec<Ball> = group.iter().map(|&i| balls[i]).collect();
        let follow = group
            .iter()
            .all(|&i| intact.get(i).copied().unwrap_or(false));
        // A narrowing: the lesion widened to the healthy lumen (`widen`), when the centreline
        // finds it narrower than that.
        let widened = healthy.filter(|_| follow).and_then(|hv| {
            let spacing = h / opts.samples_per_voxel.max(0.5);
            let grow = opts.clearance_voxels * h;
            plan_widening(mesh_bvh, hv, &gb, grow, opts.rays.max(8), spacing)
        });
        if let Some(tubes) = widened {
            out.push(RegionGuide {
                balls: group,
                kinds: vec![GuideKind::Widened; tubes.len()],
                tubes,
                fillet: 0.0,
            });
            continue;
        }
        let cap = (!follow
            && group
                .iter()
                .any(|&i| holes.in_ball.get(i).copied().unwrap_or(false)))
        .then(|| holes.faces.clone());
        let rim: Vec<Point3<f64>> = holes
            .rim
            .iter()
            .filter(|p| gb.iter().any(|b| b.contains(p)))
            .copied()
            .collect();
        if let Some((tubes, kinds)) =
            plan_group(mesh_bvh, centerline, &gb, follow, cap, &rim, h, opts)
        {
            let fillet = 0.25
                * tubes
                    .iter()
                    .map(|t| mean(&t.start_profile))
                    .fold(f64::INFINITY, f64::min);
            out.push(RegionGuide {
                balls: group,
                tubes,
                kinds,
                fillet,
            });
        }
    }
    out
}

fn plan_group(
    bvh: &MeshBvh,
    centerline: &Centerline,
    balls: &[Ball],
    follow: bool,
    cap: Option<Range<usize>>,
    rim: &[Point3<f64>],
    h: f64,
    opts: &GuideOptions,
) -> Option<(Vec<GuideTube>, Vec<GuideKind>)> {
    let grow = opts.clearance_voxels * h;
    let in_e = |p: &Point3<f64>| {
        balls
            .iter()
            .any(|b| (p - b.center).norm() < b.radius + grow)
    };
    // A section of radius about `r` around p, perpendicular to t, misses every ball.
    let clear = |p: &Point3<f64>, t: &Vector3<f64>, r: f64| {
        balls.iter().all(|b| {
            let off = (b.center - p).dot(t);
            let reach = b.radius + grow;
            if off.abs() >= reach {
                return true;
            }
            let disk = (reach * reach - off * off).sqrt();
            let q = b.center - t * off;
            (q - p).norm() >= 1.5 * r + disk
        })
    };
    // Within a junction's inscribed sphere grown by the vessel's own radius.
    let near_junction = |p: &Point3<f64>, r: f64| {
        centerline
            .junctions
            .iter()
            .any(|j| (p - j.position).norm() < j.radius + r)
    };
    // Every place a branch enters E from outside: an anchor, with the branch's run inside E
    // (from the entry inward) and the run's other anchor when the branch leaves E again.
    let mut stubs: Vec<Stub> = Vec::new();
    for (bi, br) in centerline.branches.iter().enumerate() {
        let n = br.points.len();
        if n < 2 {
            continue;
        }
        let inside: Vec<bool> = br.points.iter().map(&in_e).collect();
        let arc = |a: usize, b: usize| -> f64 {
            br.points[a.min(b)..=a.max(b)]
                .windows(2)
                .map(|w| (w[1] - w[0]).norm())
                .sum()
        };
        let mut i = 0;
        while i < n {
            if !inside[i] {
                i += 1;
                continue;
            }
            let s = i;
            while i < n && inside[i] {
                i += 1;
            }
            let e = i - 1;
            // Walk outward from the run until the section is clear of D.
            let walk = |from: usize, step: isize| -> Anchor {
                let mut k = from as isize;
                let start = br.points[from];
                let sign = if step < 0 { 1.0 } else { -1.0 };
                let limit = opts.max_walk_radii * br.radius[from].max(h);
                let mut thinnest = f64::INFINITY;
                loop {
                    let ku = k as usize;
                    let t = br.tangent[ku] * sign;
                    let next = k + step;
                    let last = next < 0 || next >= n as isize;
                    thinnest = thinnest.min(br.radius[ku]);
                    // Within a junction's flare the section is no single vessel's.
                    let flare = near_junction(&br.points[ku], br.radius[ku]);
                    let is_clear = !flare && clear(&br.points[ku], &t, br.radius[ku]);
                    if is_clear || flare || last || (br.points[ku] - start).norm() > limit {
                        return Anchor {
                            point: br.points[ku],
                            into: t,
                            // Not clear: the narrowest radius walked over (a junction's
                            // inscribed sphere is wider than either vessel).
                            radius: if is_clear { br.radius[ku] } else { thinnest },
                            clear: is_clear,
                            branch: Some(bi),
                            index: ku,
                        };
                    }
                    k = next;
                }
            };
            // How far the branch goes on outside E from the run's edge (a junction or an open
            // end beyond: the vessel goes on).
            let outside_len = |edge: usize, step: isize| -> f64 {
                let mut k = edge as isize;
                while k + step >= 0 && k + step < n as isize && !inside[(k + step) as usize] {
                    k += step;
                }
                let tip = k as usize;
                let goes_on = if tip == 0 { br.start } else { br.end };
                if (tip == 0 || tip == n - 1) && goes_on != EndKind::End {
                    f64::INFINITY
                } else {
                    arc(edge, tip)
                }
            };
            let first = stubs.len();
            if s > 0 {
                stubs.push(Stub {
                    anchor: walk(s - 1, -1),
                    outside: outside_len(s - 1, -1),
                    run: br.points[s..=e].to_vec(),
                    partner: None,
                    cut: false,
                });
            }
            if e + 1 < n {
                stubs.push(Stub {
                    anchor: walk(e + 1, 1),
                    outside: outside_len(e + 1, 1),
                    run: br.points[s..=e].iter().rev().copied().collect(),
                    partner: None,
                    cut: false,
                });
            }
            if stubs.len() == first + 2 {
                stubs[first].partner = Some(first + 1);
                stubs[first + 1].partner = Some(first);
            }
        }
    }
    // Spurs of the damage (the skeleton of a dented lumen sprouts short, thin branches) are no
    // vessels: an anchor needs the branch to go on outside E for one of its radii and a radius
    // of at least a third of the widest anchor's. The same vessel reached twice (a run that
    // leaves E right where another enters) counts once.
    let widest = stubs.iter().map(|s| s.anchor.radius).fold(0.0, f64::max);
    // An anchor that seems too thin next to its branch's open end may be the end's inscribed
    // sphere, not the vessel's (`radius_clear_of_open_ends`): the section's radius is taken for
    // a branch that leaves D only there (a branch from a junction in D to its open end just
    // beyond E: dropped, the junction lost it). A run across E that leaves it by its open end
    // keeps its other anchor alone, which is then bridged to that end's cut.
    for s in &mut stubs {
        if s.partner.is_none() && s.anchor.radius < widest / 3.0 {
            if let Some(br) = s.anchor.branch.map(|b| &centerline.branches[b]) {
                let r = radius_clear_of_open_ends(br, s.anchor.index, bvh, 4.0 * widest);
                s.anchor.radius = s.anchor.radius.max(r);
            }
        }
    }
    let mut keep: Vec<bool> = stubs
        .iter()
        .map(|s| s.outside >= s.anchor.radius && s.anchor.radius >= widest / 3.0)
        .collect();
    // Two anchors closer than half a radius read the same section (two branches leaving one
    // junction node, when no section between the junction and D is clear of D): the one that
    // points more towards D stays.
    let towards_d = |a: &Anchor| {
        balls
            .iter()
            .map(|b| {
                (b.center - a.point)
                    .try_normalize(1e-12)
                    .map_or(0.0, |d| d.dot(&a.into))
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    for a in 0..stubs.len() {
        for b in a + 1..stubs.len() {
            let (p, q) = (&stubs[a].anchor, &stubs[b].anchor);
            if keep[a] && keep[b] && (p.point - q.point).norm() < 0.5 * p.radius.max(q.radius) {
                if towards_d(q) > towards_d(p) {
                    keep[a] = false;
                } else {
                    keep[b] = false;
                }
            }
        }
    }
    let kept: Vec<usize> = (0..stubs.len()).filter(|&i| keep[i]).collect();
    let mut tubes = Vec::new();
    let mut kinds = Vec::new();
    let spacing = h / opts.samples_per_voxel.max(0.5);
    let widest = kept
        .iter()
        .map(|&i| stubs[i].anchor.radius)
        .fold(0.0, f64::max);
    let around = (TAU * widest / (RAY_SPACING_VOXELS * h)).ceil();
    let rays = if cap.is_some() && around.is_finite() {
        (around as usize).clamp(opts.rays.max(8), MAX_RAYS.max(opts.rays))
    } else {
        opts.rays.max(8)
    };
    let sections = Sections {
        bvh,
        centerline,
        rays,
        balls,
        grow,
        cap,
        narrowed: follow,
    };
    // `through`: the vessel passes D on the centreline (its wall around a hole then tells where
    // its axis runs); otherwise a gap, whose two ends are bridged.
    let bridge = |a: &Anchor, b: &Anchor, through: bool| {
        let pts = if follow {
            follow_or_bridge(centerline, a, b, spacing)
        } else {
            hermite(a, b, spacing)
        };
        make_tube(&sections, pts, a, Some(b), EndCap::Open, through, 0.0)
    };
    // A branch continued from its anchor to the point `j` (a junction), capped there; it
    // leaves j along `leave` (the damaged centreline's path from j to the anchor) where known,
    // else straight towards the anchor; it keeps its anchor's direction longer and turns into
    // j late ([`JUNCTION_TANGENTS`]).
    let to_point = |a: &Anchor, j: Point3<f64>, leave: Option<Vector3<f64>>, cap: f64| {
        let end = Anchor {
            point: j,
            into: leave.unwrap_or_else(|| (a.point - j).try_normalize(1e-12).unwrap_or(-a.into)),
            radius: a.radius,
            clear: false,
            branch: None,
            index: 0,
        };
        let mut tube = make_tube(
            &sections,
            hermite_scaled(a, &end, spacing, JUNCTION_TANGENTS),
            a,
            None,
            EndCap::Round,
            false,
            JUNCTION_CHART_TENSION,
        );
        tube.cap_radius = tube.cap_radius.min(cap);
        tube
    };
    // A run through E joins its two anchors (a vessel crossing D, or clipped by it); the
    // anchors left over are the vessel's ends inside D, joined below.
    let mut single: Vec<usize> = Vec::new();
    for &i in &kept {
        match stubs[i].partner.filter(|&p| keep[p]) {
            Some(p) if i < p => {
                tubes.push(bridge(&stubs[i].anchor, &stubs[p].anchor, true));
                kinds.push(GuideKind::Through);
            }
            Some(_) => {}
            None => single.push(i),
        }
    }
    // Two or more vessels ending in D are joined at a junction, and a vessel crossing D takes
    // side branches; a branch the damage took whole from its cut end to that junction, or to
    // that vessel, has no anchor, but its end's rim, left on the hole's rim, tells where it
    // was: it joins them from there.
    if single.len() >= 2 || (single.is_empty() && !tubes.is_empty()) {
        let widest = kept
            .iter()
            .map(|&i| stubs[i].anchor.radius)
            .fold(0.0, f64::max);
        // (Not where an anchor already is: that vessel's own end.)
        let end = cut_end_in_rim(rim, widest, bvh).filter(|e| {
            kept.iter().all(|&i| {
                let a = &stubs[i].anchor;
                (a.point - e.point).norm() > a.radius.max(e.radius)
            })
        });
        if let Some(anchor) = end {
            add_end(&mut stubs, &mut single, anchor);
        }
    }
    // Two ends that do not face each other are no vessel's two sides of a gap: two branches
    // side by side, both heading into D, whose junction D holds with the vessel beyond it, cut
    // off by the damage and too short to give an anchor (a big ball over the open aorta's
    // bifurcation, its pieces kept: the two iliacs were bridged to each other, a U-turn, and
    // the aorta's 12 mm stub above was left apart). That vessel's open end inside E joins them
    // as a junction's third branch.
    if single.len() == 2 {
        let (a, b) = (stubs[single[0]].anchor, stubs[single[1]].anchor);
        let facing = (b.point - a.point).try_normalize(1e-12).is_some_and(|d| {
            a.into.dot(&d) >= BRIDGE_MIN_FACING && b.into.dot(&-d) >= BRIDGE_MIN_FACING
        });
        let beyond = if facing {
            None
        } else {
            // The farthest such end ahead of the two (their tangents' sum), clear of both.
            let ahead = a.into + b.into;
            let mid = Point3::from((a.point.coords + b.point.coords) / 2.0);
            let mut ends: Vec<&crate::centerline::Endpoint> = centerline
                .endpoints
                .iter()
                .filter(|e| {
                    e.open_end
                        && in_e(&e.position)
                        && (e.position - mid).dot(&ahead) > 0.0
                        && [a, b]
                            .iter()
                            .all(|x| (x.point - e.position).norm() > x.radius)
                })
                .collect();
            ends.sort_by(|p, q| {
                (q.position - mid)
                    .norm()
                    .total_cmp(&(p.position - mid).norm())
            });
            ends.into_iter()
                .find_map(|e| end_anchor(centerline, e, a.radius.min(b.radius)))
        };
        if let Some(anchor) = beyond {
            add_end(&mut stubs, &mut single, anchor);
        }
    }
    match single.len() {
        0 => {}
        1 if !tubes.is_empty() => {
            // A side branch joining a vessel that crosses D: continued to the point of that
            // vessel's curve nearest to its axis, capped there, joined by the fillet.
            let a = stubs[single[0]].anchor;
            let j = tubes
                .iter()
                .flat_map(|t: &GuideTube| t.points.iter())
                .min_by(|p, q| axis_distance(&a, p).total_cmp(&axis_distance(&a, q)))
                .copied()
                .expect("tubes have points");
            let mut tube = to_point(&a, j, None, f64::INFINITY);
            tube.flat_start = stubs[single[0]].cut;
            tubes.push(tube);
            kinds.push(GuideKind::Junction);
        }
        1 => {
            // A dead end. Where the branch ends at an open vessel end (a cut across the vessel,
            // whose centre the end's loop gives, outside the damage), bridged from the anchor to
            // that end like a vessel through D and cut flat there; otherwise (a closed end whose
            // section beyond D is damaged, a stump) continued along its own damaged centreline
            // and capped round.
            let st = &stubs[single[0]];
            let mut pts = vec![st.anchor.point];
            pts.extend(st.run.iter().copied());
            let open_end = st.anchor.branch.and_then(|b| {
                let br = &centerline.branches[b];
                let last = pts.last()?;
                let near = |q: Option<&Point3<f64>>| q.map_or(f64::INFINITY, |q| (q - last).norm());
                let kind = if near(br.points.first()) <= near(br.points.last()) {
                    br.start
                } else {
                    br.end
                };
                // The run's last stretch of about one radius gives the end's direction.
                let n = pts.len();
                let back = pts[..n - 1]
                    .iter()
                    .rev()
                    .find(|q| (*q - last).norm() >= st.anchor.radius)
                    .unwrap_or(&pts[0]);
                let into = (back - last).try_normalize(1e-12)?;
                (kind == EndKind::OpenEnd && n >= 2).then_some(Anchor {
                    point: *last,
                    into,
                    radius: st.anchor.radius,
                    clear: false,
                    branch: None,
                    index: 0,
                })
            });
            // Else an open vessel end inside E that the anchor's run does not reach: the hole's
            // cap, across most of the vessel's wall, breaks the damaged centreline into spurs
            // between them (a chop of two radii beside the aneurysm's open ICA end, its loop
            // intact inside D); the vessel goes on to the nearest such end. Else, where the hole
            // has bitten into the vessel's cut end, that cut's plane (the end's rim left on it).
            // Else, where the vessel ends closed beyond D, its intact section at the tip.
            let open_end = open_end
                .or_else(|| open_end_in(centerline, &in_e, &st.anchor))
                .or_else(|| bitten_end(rim, &st.anchor))
                .or_else(|| closed_end_section(&sections, &in_e, &pts, st.anchor.radius));
            let (tube, kind) = match open_end {
                Some(end) => (
                    make_tube(
                        &sections,
                        hermite(&st.anchor, &end, spacing),
                        &st.anchor,
                        Some(&end),
                        EndCap::Flat,
                        true,
                        0.0,
                    ),
                    GuideKind::DeadEnd,
                ),
                None => (
                    make_tube(
                        &sections,
                        resample(&pts, spacing),
                        &st.anchor,
                        None,
                        EndCap::Round,
                        false,
                        0.0,
                    ),
                    GuideKind::Stump,
                ),
            };
            tubes.push(tube);
            kinds.push(kind);
        }
        2 => {
            tubes.push(bridge(
                &stubs[single[0]].anchor,
                &stubs[single[1]].anchor,
                false,
            ));
            kinds.push(GuideKind::Bridge);
        }
        _ => {
            // A junction: the centreline's junction in E nearest to the anchors (one with an
            // inscribed sphere of [`JUNCTION_MIN_RADIUS`] of the narrowest anchor's radius at
            // least: the others are spurs of the damage's skeleton), else where the
            // anchors' axes meet (least squares) when that is in E, else their centroid. (The
            // axes of branches that part at a shallow angle meet far from where they part: the
            // carotid's, 4.7 mm downstream, 2.6 junction radii.)
            let anchors: Vec<Anchor> = single.iter().map(|&i| stubs[i].anchor).collect();
            let sum = anchors
                .iter()
                .fold(Vector3::zeros(), |s, a| s + a.point.coords);
            let centroid = Point3::from(sum / anchors.len() as f64);
            let axes: Vec<AxisBranch> = anchors
                .iter()
                .map(|a| AxisBranch {
                    center: a.point,
                    axis: a.into,
                    radius: a.radius,
                })
                .collect();
            let narrowest = anchors
                .iter()
                .map(|a| a.radius)
                .fold(f64::INFINITY, f64::min);
            let found = centerline
                .junctions
                .iter()
                .filter(|q| in_e(&q.position) && q.radius >= JUNCTION_MIN_RADIUS * narrowest)
                .min_by(|a, b| {
                    (a.position - centroid)
                        .norm()
                        .total_cmp(&(b.position - centroid).norm())
                });
            let j = found
                .map(|q| q.position)
                .or_else(|| junction_point(&axes).filter(|p| in_e(p)))
                .unwrap_or(centroid);
            // The junction's inscribed sphere bounds the balls that close the branches there,
            // unless the sphere rests on a hole's cap (the damage is at the junction: the
            // sphere is then smaller than the vessel's).
            let on_cap = |q: &crate::centerline::Junction| {
                sections.cap.is_some()
                    && sections.is_cap(sections.bvh.closest_point(&q.position).face)
            };
            let cap = found
                .filter(|q| !on_cap(q))
                .map_or(f64::INFINITY, |q| q.radius);
            for (&i, a) in single.iter().zip(&anchors) {
                let leave = leaving_direction(centerline, &stubs[i], &j)
                    .map(|l| junction_tangent(a, &j, &l));
                let mut tube = to_point(a, j, leave, cap);
                // A cut end: the vessel ends at its plane.
                tube.flat_start = stubs[i].cut;
                tubes.push(tube);
                kinds.push(GuideKind::Junction);
            }
        }
    }
    (!tubes.is_empty()).then_some((tubes, kinds))
}

/// Where a branch enters E: its anchor, how far the branch goes on outside E beyond the edge of
/// the run (∞ when it reaches a junction or an open end), its points inside E from the entry
/// inward, and the stub at the run's other end when the branch leaves E again.
struct Stub {
    anchor: Anchor,
    outside: f64,
    run: Vec<Point3<f64>>,
    partner: Option<usize>,
    /// The anchor is a vessel's cut end inside D, read off the hole's rim ([`cut_end_in_rim`]):
    /// the vessel does not go on beyond it.
    cut: bool,
}

/// Adds a vessel's end inside D (a cut end read off the rim, an open end) as one more single
/// anchor: the vessel goes no farther than that end.
fn add_end(stubs: &mut Vec<Stub>, single: &mut Vec<usize>, anchor: Anchor) {
    stubs.push(Stub {
        anchor,
        outside: f64::INFINITY,
        run: Vec::new(),
        partner: None,
        cut: true,
    });
    single.push(stubs.len() - 1);
}

/// The direction in which the damaged centreline leaves the junction at `j` towards the stub's
/// anchor: the stub's run ends at its branch's junction, from which the branch graph is walked
/// (breadth first) to the junction at `j`; the branch arriving there gives the direction from j
/// to its point one junction radius away. None when `j` is no junction of the centreline or no
/// path reaches it. (A vessel leaves a bifurcation along its own axis, not along the chord to
/// its anchor: the aneurysm's daughter rises 1.6 mm from the junction before it turns.)
fn leaving_direction(
    centerline: &Centerline,
    stub: &Stub,
    j: &Point3<f64>,
) -> Option<Vector3<f64>> {
    let target = centerline
        .junctions
        .iter()
        .position(|q| (q.position - j).norm() < 1e-9)?;
    let end = *stub.run.last()?;
    let bi = stub.anchor.branch?;
    let near = |a: &Point3<f64>, b: &Point3<f64>| (a - b).norm() < 1e-9;
    let at_junction = |b: usize, p: &Point3<f64>| {
        centerline
            .junctions
            .iter()
            .position(|q| q.branches.contains(&b) && near(&q.position, p))
    };
    let start = at_junction(bi, &end)?;
    // Breadth first over junctions; `via[k]`: the branch by which junction k was reached.
    let mut via: Vec<Option<usize>> = vec![None; centerline.junctions.len()];
    let mut seen = vec![false; centerline.junctions.len()];
    let mut queue = std::collections::VecDeque::from([start]);
    seen[start] = true;
    via[start] = Some(bi);
    while let Some(k) = queue.pop_front() {
        if k == target {
            break;
        }
        for &b in &centerline.junctions[k].branches {
            let br = centerline.branches.get(b)?;
            for p in [br.points.first()?, br.points.last()?] {
                if let Some(next) = at_junction(b, p).filter(|&n| !seen[n]) {
                    seen[next] = true;
                    via[next] = Some(b);
                    queue.push_back(next);
                }
            }
        }
    }
    let br = centerline.branches.get(via[target]?)?;
    let reach = centerline.junctions[target].radius;
    let mut pts: Vec<&Point3<f64>> = br.points.iter().collect();
    if !near(br.points.first()?, j) {
        pts.reverse();
    }
    let far = pts
        .iter()
        .find(|p| (**p - j).norm() >= reach)
        .or(pts.last())?;
    (**far - j).try_normalize(1e-12)
}

/// The tangent with which a junction branch's curve leaves the junction point `j` towards its
/// anchor `a`, given the damaged centreline's leaving direction `leave`: `leave` where the
/// anchor's own tangent misses j by 12° or more (the vessel bends between: a daughter curving
/// off its parent), the chord from j to the anchor where it points at j within 4° (a straight
/// vessel: in a hole over the aorta's bifurcation, the cap flattens the lumen and bends the
/// damaged centreline 17–26° off the aorta's axis), blended linearly between.
fn junction_tangent(a: &Anchor, j: &Point3<f64>, leave: &Vector3<f64>) -> Vector3<f64> {
    let Some(chord) = (a.point - j).try_normalize(1e-12) else {
        return *leave;
    };
    let w = (((-a.into).angle(&chord).to_degrees() - 4.0) / 8.0).clamp(0.0, 1.0);
    (chord * (1.0 - w) + leave * w)
        .try_normalize(1e-12)
        .unwrap_or(*leave)
}

/// The open vessel end of `centerline` inside E (`in_e`) nearest to `from`, as the far anchor
/// of a curve from `from`: at the end loop's centre, pointing into the vessel along its branch
/// (over about `from`'s radius), with the loop's radius (`from`'s where the endpoint has none);
/// its section is not read (`clear` false). None when no open end lies in E.
fn open_end_in(
    centerline: &Centerline,
    in_e: &dyn Fn(&Point3<f64>) -> bool,
    from: &Anchor,
) -> Option<Anchor> {
    let end = centerline
        .endpoints
        .iter()
        .filter(|e| e.open_end && in_e(&e.position))
        .min_by(|a, b| {
            (a.position - from.point)
                .norm()
                .total_cmp(&(b.position - from.point).norm())
        })?;
    end_anchor(centerline, end, from.radius)
}

/// An open vessel end of the centreline as an anchor: at the end, heading along its branch
/// into the vessel (towards the branch's first point `radius` or more away; its own inscribed
/// radius, else `radius`). None where the branch is shorter than that.
fn end_anchor(
    centerline: &Centerline,
    end: &crate::centerline::Endpoint,
    radius: f64,
) -> Option<Anchor> {
    let br = centerline.branches.get(end.branch)?;
    let at_start = br
        .points
        .first()
        .map_or(f64::INFINITY, |q| (q - end.position).norm())
        <= br
            .points
            .last()
            .map_or(f64::INFINITY, |q| (q - end.position).norm());
    let inward = |q: &&Point3<f64>| (*q - end.position).norm() >= radius;
    let inner = if at_start {
        br.points.iter().find(inward)
    } else {
        br.points.iter().rev().find(inward)
    }?;
    Some(Anchor {
        point: end.position,
        into: (inner - end.position).try_normalize(1e-12)?,
        radius: if end.radius > 0.0 { end.radius } else { radius },
        clear: false,
        branch: None,
        index: 0,
    })
}

/// The section of a vessel at the tip of a dead end's run `pts` (from its anchor to the damaged
/// centreline's tip, where the vessel ends closed beyond D), as the far anchor of a curve from
/// that anchor: the centre of the circle fitted to the wall that rays from the tip meet in the
/// plane across the chord from the anchor (cast again from that centre), pointing back along
/// the chord, with the wall's mean distance from the centre as radius; its section is not read
/// (`clear` false). Only intact wall counts: a ray that misses within two radii, meets a hole's
/// cap or meets the wall inside E (`in_e`) is dropped, and with fewer than half of the rays
/// left the section is not the vessel's (the damage reaches it): None.
fn closed_end_section(
    sections: &Sections,
    in_e: &dyn Fn(&Point3<f64>) -> bool,
    pts: &[Point3<f64>],
    radius: f64,
) -> Option<Anchor> {
    let tip = *pts.last()?;
    let into = (pts.first()? - tip).try_normalize(1e-12)?;
    let e1 = any_perpendicular(&into);
    let e2 = into.cross(&e1);
    let dirs = ray_dirs(sections.rays.max(8));
    let mut circle = (tip, 0.0);
    for _ in 0..2 {
        let c = circle.0;
        // The intact wall the rays meet.
        let rim: Vec<Point3<f64>> = dirs
            .iter()
            .filter_map(|&(cs, sn)| {
                let d = e1 * cs + e2 * sn;
                let hit = sections.bvh.cast_ray(&c, &d, 2.0 * radius)?;
                let wall = c + d * hit.t;
                (!sections.is_cap(hit.face) && !in_e(&wall)).then_some(wall)
            })
            .collect();
        if rim.len() * 2 < dirs.len() {
            return None;
        }
        circle = circle_in_plane(&rim, &into, &tip)?;
    }
    Some(Anchor {
        point: circle.0,
        into,
        radius: circle.1,
        clear: false,
        branch: None,
        index: 0,
    })
}

/// Rim points within this fraction of the vessel's radius of a plane lie on it (a clipped
/// segmentation's cut, or a flat cap, is planar to rounding).
const BITTEN_PLANE_TOLERANCE: f64 = 1e-3;
/// Least number of a hole's rim points on the plane of a bitten end (inside D the damage may
/// have left only a short arc of the end's rim: an eighth of the rim on a tube bitten by a
/// chop of its own radius).
const BITTEN_MIN_POINTS: usize = 8;

/// The plane of a vessel's cut among a hole's `rim` points (segmentations are clipped by planes):
/// of the planes through three of the points `pool` indexes (`tries` triples in a fixed order:
/// the same input gives the same output), the one holding the most rim points within `tol`,
/// spread over `spread` or more, with no rim point beyond it on its outer side (`outer` gives
/// that side from the plane's unit normal and a point on it, or None to pass the plane by).
/// Returns the rim points on it, its outer normal and a point on it; None when no plane holds
/// [`BITTEN_MIN_POINTS`].
fn cut_plane(
    rim: &[Point3<f64>],
    pool: &[usize],
    tries: usize,
    tol: f64,
    spread: f64,
    outer: impl Fn(&Vector3<f64>, &Point3<f64>) -> Option<Vector3<f64>>,
) -> Option<(Vec<Point3<f64>>, Vector3<f64>, Point3<f64>)> {
    let m = pool.len();
    if m == 0 {
        return None;
    }
    let mut best: Option<(Vec<Point3<f64>>, Vector3<f64>, Point3<f64>)> = None;
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as usize % m
    };
    for _ in 0..tries {
        let (a, b, c) = (rim[pool[next()]], rim[pool[next()]], rim[pool[next()]]);
        let Some(normal) = (b - a).cross(&(c - a)).try_normalize(1e-12) else {
            continue;
        };
        let Some(out) = outer(&normal, &a) else {
            continue;
        };
        if rim.iter().any(|p| (p - a).dot(&out) > tol) {
            continue;
        }
        let on: Vec<Point3<f64>> = rim
            .iter()
            .filter(|p| (*p - a).dot(&normal).abs() <= tol)
            .copied()
            .collect();
        let reach = on.iter().map(|p| (p - a).norm()).fold(0.0, f64::max);
        if reach >= spread && best.as_ref().map_or(true, |(k, _, _)| on.len() > k.len()) {
            best = Some((on, out, a));
        }
    }
    best.filter(|(arc, _, _)| arc.len() >= BITTEN_MIN_POINTS)
}

/// The median distance from each point to its nearest other one.
fn median_spacing(points: &[Point3<f64>]) -> f64 {
    let mut nearest: Vec<f64> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            points
                .iter()
                .enumerate()
                .filter(|&(k, _)| k != i)
                .map(|(_, q)| (q - p).norm())
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    nearest.sort_by(f64::total_cmp);
    nearest.get(nearest.len() / 2).copied().unwrap_or(0.0)
}

/// The circle through `arc`, points on the plane through `on` with unit normal `normal`, fitted
/// in that plane (Kåsa): its centre and the points' mean distance from it.
fn circle_in_plane(
    arc: &[Point3<f64>],
    normal: &Vector3<f64>,
    on: &Point3<f64>,
) -> Option<(Point3<f64>, f64)> {
    let e1 = any_perpendicular(normal);
    let e2 = normal.cross(&e1);
    let flat: Vec<(f64, f64)> = arc
        .iter()
        .map(|p| ((p - on).dot(&e1), (p - on).dot(&e2)))
        .collect();
    let (x, y) = fit_circle(&flat)?;
    let centre = on + e1 * x + e2 * y;
    let radius = arc.iter().map(|p| (p - centre).norm()).sum::<f64>() / arc.len() as f64;
    Some((centre, radius))
}

/// A vessel's cut end inside D whose branch the damage took whole (from the end to past the
/// junction, so that no anchor leads to it): the part of the end's rim the damage left lies on
/// the hole's `rim` in the cut's plane (found by [`cut_plane`] among all the rim's points, the
/// plane holding them spread over half of `widest`, the widest anchor's radius, or more), the
/// vessel lies on one side of it and does not go on beyond it (the closed input's winding number
/// half a radius beyond the end's centre is 0: a rim that runs along one of the slice planes of
/// a segmentation whose vessel goes on through it is no end), and the circle through the points
/// on it is of a vessel's size (a third to 1.5 times `widest`), the points a run along it (no
/// gap of more than three rim spacings but the part the damage took). The anchor is at the circle's
/// centre, with its radius, pointing into the vessel. The aneurysm's ICA end bitten off with its
/// branch in `benches/repair_real --end-bites`, which was bridged past it.
fn cut_end_in_rim(rim: &[Point3<f64>], widest: f64, bvh: &MeshBvh) -> Option<Anchor> {
    if rim.len() < BITTEN_MIN_POINTS || !(widest > 0.0) {
        return None;
    }
    let tol = BITTEN_PLANE_TOLERANCE * widest;
    let pool: Vec<usize> = (0..rim.len()).collect();
    let (arc, out, on) = cut_plane(rim, &pool, 1024, tol, 0.5 * widest, |normal, a| {
        // The side no rim point is on.
        let side = |n: Vector3<f64>| rim.iter().all(|p| (p - a).dot(&n) <= tol).then_some(n);
        side(*normal).or_else(|| side(-normal))
    })?;
    // The tests in order of cost: the circle's size, the run (quadratic in the rim's points),
    // the winding number's ray.
    let (point, radius) = circle_in_plane(&arc, &out, &on)
        .filter(|(_, radius)| (widest / 3.0..=1.5 * widest).contains(radius))?;
    // A cut's rim is a run of the rim's own points: along the arc (the circle less its widest
    // gap, the part the damage took), no gap wider than three of the rim's spacings (points that
    // only happen to lie on one plane are scattered along it: on the rippled tube's hole of
    // `tests/suite/inpaint_repair.rs`, 15 of them with a gap of 12 spacings; the aneurysm's bitten
    // ends, 1.2 spacings). The gaps do not depend on the in-plane axes the angles are read from.
    let e1 = any_perpendicular(&out);
    let e2 = out.cross(&e1);
    let mut angles: Vec<f64> = arc
        .iter()
        .map(|p| (p - point).dot(&e2).atan2((p - point).dot(&e1)))
        .collect();
    angles.sort_by(f64::total_cmp);
    let mut gaps: Vec<f64> = angles.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.push(TAU - (angles[angles.len() - 1] - angles[0]));
    gaps.sort_by(f64::total_cmp);
    let run = gaps[gaps.len() - 2] * radius <= 3.0 * median_spacing(rim);
    let ends = || bvh.winding_number_by_rays(&(point + out * (0.5 * radius))) == Some(0);
    (run && ends()).then_some(Anchor {
        point,
        into: -out,
        radius,
        clear: false,
        branch: None,
        index: 0,
    })
}

/// Where a hole has bitten into a vessel's cut end (an open end, or a flat cap, that the damage
/// reached), the far anchor of the curve from `from`: the part of the end's rim the damage left
/// lies in the cut's plane, and the vessel ends there. The plane is the one through three rim
/// points (tried in a fixed order among the farthest along `from`'s direction) that holds the
/// most of them within [`BITTEN_PLANE_TOLERANCE`] of the radius: at least
/// [`BITTEN_MIN_POINTS`], spread over a radius or more, facing along the vessel (within 50°),
/// with no rim point beyond it (the vessel's end). The anchor is at the centre of the circle
/// through the rim's points on the plane (with that circle's radius), or where `from`'s axis
/// meets the plane when no circle of about `from`'s radius fits them, pointing back into the
/// vessel; its section is not read. None when no such plane is.
fn bitten_end(rim: &[Point3<f64>], from: &Anchor) -> Option<Anchor> {
    let n = rim.len();
    if n < BITTEN_MIN_POINTS {
        return None;
    }
    let t = from.into;
    let tol = BITTEN_PLANE_TOLERANCE * from.radius;
    // The end is beyond the anchor: candidates among the farthest third along the vessel.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| {
        (rim[b] - from.point)
            .dot(&t)
            .total_cmp(&(rim[a] - from.point).dot(&t))
    });
    let far = &order[..(n / 3).max(3)];
    let facing = 50f64.to_radians().cos();
    let (arc, normal, on) = cut_plane(rim, far, 256, tol, from.radius, |normal, _| {
        // Facing along the vessel; the end is beyond the plane along it.
        (normal.dot(&t).abs() >= facing).then(|| {
            if normal.dot(&t) > 0.0 {
                *normal
            } else {
                -normal
            }
        })
    })?;
    let along = (on - from.point).dot(&normal) / t.dot(&normal);
    if along <= 0.0 {
        return None;
    }
    // The end's centre: the circle through the rim's arc on the plane (Kåsa), where it fits a
    // vessel of about the anchor's size; else where the anchor's axis meets the plane (off the
    // end's centre where the vessel bends before its end: the aneurysm's ICA).
    let fitted = circle_in_plane(&arc, &normal, &on)
        .filter(|(_, r)| (0.5 * from.radius..=2.0 * from.radius).contains(r));
    let (point, radius) = fitted.unwrap_or((from.point + t * along, from.radius));
    Some(Anchor {
        point,
        into: if normal.dot(&t) < 0.0 {
            normal
        } else {
            -normal
        },
        radius,
        clear: false,
        branch: None,
        index: 0,
    })
}

/// Distance from `p` to the half-line from the anchor into D (to the anchor itself behind it).
fn axis_distance(a: &Anchor, p: &Point3<f64>) -> f64 {
    let v = p - a.point;
    let along = v.dot(&a.into).max(0.0);
    (v - a.into * along).norm()
}

/// Samples of the cubic Hermite curve from `a` (leaving along a.into) to `b` (arriving against
/// b.into), tangent lengths the chord, about `spacing` apart.
fn hermite(a: &Anchor, b: &Anchor, spacing: f64) -> Vec<Point3<f64>> {
    hermite_scaled(a, b, spacing, [1.0, 1.0])
}

/// [`hermite`] with its tangent lengths at `a` and at `b` multiplied by `lengths`.
fn hermite_scaled(a: &Anchor, b: &Anchor, spacing: f64, lengths: [f64; 2]) -> Vec<Point3<f64>> {
    let chord = (b.point - a.point).norm();
    // Tangent length: the chord scaled so that a circular arc turning by α between the two
    // tangents is followed (2·tan(α/4) / sin(α/2): 1 for a straight line, 1.17 at 90°).
    let turn = a.into.angle(&-b.into).min(170f64.to_radians());
    let scale = if turn > 1e-6 {
        2.0 * (turn / 4.0).tan() / (turn / 2.0).sin()
    } else {
        1.0
    };
    let m0 = a.into * chord * scale * lengths[0];
    let m1 = -b.into * chord * scale * lengths[1];
    let at = |u: f64| {
        let (u2, u3) = (u * u, u * u * u);
        let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
        let h10 = u3 - 2.0 * u2 + u;
        let h01 = -2.0 * u3 + 3.0 * u2;
        let h11 = u3 - u2;
        Point3::from(a.point.coords * h00 + m0 * h10 + b.point.coords * h01 + m1 * h11)
    };
    // Dense first, then resampled by arc length.
    let dense = ((4.0 * chord / spacing).ceil() as usize).clamp(8, 20_000);
    let pts: Vec<Point3<f64>> = (0..=dense).map(|k| at(k as f64 / dense as f64)).collect();
    resample(&pts, spacing)
}

/// The curve between two anchors of one run through E where the lumen in D is intact (a
/// narrowing): the input's own centreline between the anchors, smoothed over about one radius
/// of arc (its ends, the anchors, kept); the cubic Hermite curve where the anchors lie on two
/// branches or fewer than three centreline points apart. The lumen is intact, so its axis is
/// measured rather than guessed, and the widened sections are centred on the narrowed wall
/// ([`Sections::widen_narrowed`]) whatever the curve: a cubic that leaves the lumen's axis
/// tilts them and misplaces the sections beside them (the synthetic narrowings of the real
/// vessels bench: the capped aorta's 2.18h → 0.83h, the open aorta's 2.41h → 1.88h, the
/// others unchanged; a cubic was kept before unless the centreline strayed from it by half a
/// radius).
fn follow_or_bridge(
    centerline: &Centerline,
    a: &Anchor,
    b: &Anchor,
    spacing: f64,
) -> Vec<Point3<f64>> {
    let (Some(ba), Some(bb)) = (a.branch, b.branch) else {
        return hermite(a, b, spacing);
    };
    let Some(br) = centerline.branches.get(ba).filter(|_| ba == bb) else {
        return hermite(a, b, spacing);
    };
    let (lo, hi) = (a.index.min(b.index), a.index.max(b.index));
    if hi >= br.points.len() || hi - lo < 2 {
        return hermite(a, b, spacing);
    }
    let mut path: Vec<Point3<f64>> = br.points[lo..=hi].to_vec();
    if a.index > b.index {
        path.reverse();
    }
    smooth_path(&path, a.radius.min(b.radius), spacing)
}

/// A centreline stretch smoothed over about ±`radius` of arc (a moving average at a quarter
/// radius apart: the skeleton's voxel steps taken out) and resampled `spacing` apart.
pub(super) fn smooth_path(path: &[Point3<f64>], radius: f64, spacing: f64) -> Vec<Point3<f64>> {
    let r = radius.max(spacing);
    let dense = resample(path, 0.25 * r);
    let half = 4usize; // ±one radius of arc at a quarter-radius spacing
    let n = dense.len();
    let smooth: Vec<Point3<f64>> = (0..n)
        .map(|k| {
            let w = half.min(k).min(n - 1 - k);
            let sum = dense[k - w..=k + w]
                .iter()
                .fold(Vector3::zeros(), |acc, p| acc + p.coords);
            Point3::from(sum / (2 * w + 1) as f64)
        })
        .collect();
    resample(&smooth, spacing)
}

/// The polyline resampled about `spacing` apart by arc length (ends kept).
fn resample(pts: &[Point3<f64>], spacing: f64) -> Vec<Point3<f64>> {
    let len: f64 = pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    if pts.len() < 2 || len <= 0.0 {
        return pts.to_vec();
    }
    let n = ((len / spacing).ceil() as usize).max(2);
    let step = len / n as f64;
    let mut out = vec![pts[0]];
    let mut seg = 0;
    let mut acc = 0.0; // arc length at pts[seg]
    for k in 1..n {
        let target = k as f64 * step;
        while seg + 1 < pts.len() - 1 && acc + (pts[seg + 1] - pts[seg]).norm() < target {
            acc += (pts[seg + 1] - pts[seg]).norm();
            seg += 1;
        }
        let l = (pts[seg + 1] - pts[seg]).norm();
        let f = if l > 0.0 {
            ((target - acc) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(pts[seg] + (pts[seg + 1] - pts[seg]) * f);
    }
    out.push(*pts.last().expect("non-empty"));
    out
}

/// A unit vector perpendicular to `t`.
fn any_perpendicular(t: &Vector3<f64>) -> Vector3<f64> {
    let helper = if t.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    t.cross(&helper).normalize()
}

/// Rays in a section plane that measure a vessel's radius next to an open end.
const END_SECTION_RAYS: usize = 16;

/// The radius of `br` at its point `i`: the inscribed radius, unless an open end of the branch
/// lies nearer along it than the wall does in the section plane there. The centreline is traced
/// on the capped input, so within a section's radius of an open end the inscribed sphere touches
/// the cap before the wall and falls to 0 at the end (a branch of 0.9 radii read 0.44 a fifth of
/// a radius from its end, and was dropped as a spur of the damage: seed 28's aneurysm junction
/// chop in `benches/repair_real`); there, the median distance to the wall along
/// [`END_SECTION_RAYS`] rays in the section plane (within `reach`), when that is larger.
fn radius_clear_of_open_ends(br: &Branch, i: usize, bvh: &MeshBvh, reach: f64) -> f64 {
    let n = br.points.len();
    let arc = |a: usize, b: usize| -> f64 {
        br.points[a.min(b)..=a.max(b)]
            .windows(2)
            .map(|w| (w[1] - w[0]).norm())
            .sum()
    };
    let to_end = [(br.start, 0), (br.end, n - 1)]
        .iter()
        .filter(|(kind, _)| *kind == EndKind::OpenEnd)
        .map(|&(_, end)| arc(i, end))
        .fold(f64::INFINITY, f64::min);
    if to_end > reach {
        return br.radius[i];
    }
    let (c, t) = (br.points[i], br.tangent[i]);
    let u = any_perpendicular(&t);
    let v = t.cross(&u);
    let mut hits: Vec<f64> = ray_dirs(END_SECTION_RAYS)
        .into_iter()
        .filter_map(|(cs, sn)| {
            bvh.cast_ray(&c, &(u * cs + v * sn), reach)
                .map(|hit| hit.t)
                .filter(|&d| d > 0.0)
        })
        .collect();
    if hits.len() * 2 < END_SECTION_RAYS {
        return br.radius[i];
    }
    hits.sort_by(f64::total_cmp);
    let wall = hits[hits.len() / 2];
    if to_end < wall {
        br.radius[i].max(wall)
    } else {
        br.radius[i]
    }
}

/// Tangents (central differences) and rotation-minimising frames along `pts`, the first frame
/// built on `t0`.
pub(super) fn frames(pts: &[Point3<f64>], t0: &Vector3<f64>) -> Vec<[Vector3<f64>; 3]> {
    let n = pts.len();
    let tangent = |i: usize| {
        let (a, b) = (pts[i.saturating_sub(1)], pts[(i + 1).min(n - 1)]);
        (b - a).try_normalize(1e-15).unwrap_or(*t0)
    };
    let mut out = Vec::with_capacity(n);
    let t = tangent(0);
    let r = any_perpendicular(&t);
    out.push([t, r, t.cross(&r)]);
    for i in 1..n {
        let [ti, ri, _] = out[i - 1];
        let t_next = tangent(i);
        // Double reflection (Wang et al. 2008).
        let v1 = pts[i] - pts[i - 1];
        let c1 = v1.norm_squared();
        let (rl, tl) = if c1 > 0.0 {
            (
                ri - v1 * (2.0 / c1 * v1.dot(&ri)),
                ti - v1 * (2.0 / c1 * v1.dot(&ti)),
            )
        } else {
            (ri, ti)
        };
        let v2 = t_next - tl;
        let c2 = v2.norm_squared();
        let r_next = if c2 > 0.0 {
            rl - v2 * (2.0 / c2 * v2.dot(&rl))
        } else {
            rl
        };
        let r_next = (r_next - t_next * t_next.dot(&r_next))
            .try_normalize(1e-15)
            .unwrap_or_else(|| any_perpendicular(&t_next));
        out.push([t_next, r_next, t_next.cross(&r_next)]);
    }
    out
}

/// Whether wall point `p` belongs to the branches `own` (a tube's anchors' branches; any branch
/// when empty): no other branch of `centerline` is nearer by more than a quarter of `radius` (a
/// ray that crossed a junction into a neighbouring vessel ends on that vessel's wall).
pub(super) fn on_branch(
    centerline: &Centerline,
    p: &Point3<f64>,
    own: &[usize],
    radius: f64,
) -> bool {
    if own.is_empty() {
        return true;
    }
    let dist = |b: &crate::centerline::Branch| {
        b.points
            .iter()
            .map(|q| (p - q).norm_squared())
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    };
    let mine = own
        .iter()
        .filter_map(|&b| centerline.branches.get(b))
        .map(dist)
        .fold(f64::INFINITY, f64::min);
    centerline
        .branches
        .iter()
        .enumerate()
        .all(|(i, b)| own.contains(&i) || mine <= dist(b) + 0.25 * radius)
}

/// The `m` ray directions of a section, at angles 2πj/m in its frame (cos, sin).
pub(super) fn ray_dirs(m: usize) -> Vec<(f64, f64)> {
    (0..m)
        .map(|j| {
            let th = TAU * j as f64 / m as f64;
            (th.cos(), th.sin())
        })
        .collect()
}

/// The input's wall around `c` in the section of frame `f`, along the rays `dirs`, in the
/// section's coordinates: ray j meets the wall within `reach(j)` on the branches `own`
/// ([`on_branch`] with `belong(j)`). None when a ray misses the wall or ends on another branch.
pub(super) fn read_wall(
    bvh: &MeshBvh,
    centerline: &Centerline,
    c: &Point3<f64>,
    f: &[Vector3<f64>; 3],
    dirs: &[(f64, f64)],
    own: &[usize],
    reach: impl Fn(usize) -> f64,
    belong: impl Fn(usize) -> f64,
) -> Option<Vec<(f64, f64)>> {
    let mut wall = Vec::with_capacity(dirs.len());
    for (j, &(cs, sn)) in dirs.iter().enumerate() {
        let d = f[1] * cs + f[2] * sn;
        let hit = bvh.cast_ray(c, &d, reach(j))?;
        if !(hit.t > 0.0 && on_branch(centerline, &(c + d * hit.t), own, belong(j))) {
            return None;
        }
        wall.push((hit.t * cs, hit.t * sn));
    }
    Some(wall)
}

/// `wall` scaled by `k` about `g` (section coordinates), read along the rays `dirs` from the
/// section's origin; None where a ray misses it.
pub(super) fn scaled_section(
    wall: &[(f64, f64)],
    g: (f64, f64),
    k: f64,
    dirs: &[(f64, f64)],
) -> Option<Vec<f64>> {
    let poly: Vec<(f64, f64)> = wall
        .iter()
        .map(|w| (g.0 + k * (w.0 - g.0), g.1 + k * (w.1 - g.1)))
        .collect();
    dirs.iter().map(|&dir| ray_polygon(dir, &poly)).collect()
}

/// Cumulative arc length along `points` from the first.
fn arc_lengths(points: &[Point3<f64>]) -> Vec<f64> {
    let mut acc = vec![0.0];
    for w in points.windows(2) {
        acc.push(acc.last().copied().unwrap_or(0.0) + (w[1] - w[0]).norm());
    }
    acc
}

/// Reads cross-sections of the input's wall around its centreline.
struct Sections<'a> {
    bvh: &'a MeshBvh,
    centerline: &'a Centerline,
    rays: usize,
    /// The balls of D and the clearance they are grown by (world units): the wall is read
    /// outside them only.
    balls: &'a [Ball],
    grow: f64,
    /// In a group of balls around a hole: the cap triangles `cap_holes` added (face indices of
    /// the BVH's mesh). The rest of the wall inside D is then intact and read too (`known_wall`).
    cap: Option<Range<usize>>,
    /// The group's lumen is intact, only narrowed (`--stenoses`): inside D an anchored tube's
    /// sections keep the narrowed wall's own shape, widened to the interpolated size.
    narrowed: bool,
}

impl Sections<'_> {
    /// Whether `face` is one of the holes' cap triangles (false without caps).
    fn is_cap(&self, face: u32) -> bool {
        self.cap
            .as_ref()
            .is_some_and(|cap| cap.contains(&(face as usize)))
    }

    /// The first hit of the ray from `c` along the unit `d` within `t_max` that is not a hole's
    /// cap: a cap spans its hole inside the lumen, and where the hole's rim is not planar it
    /// hides the intact wall next to the rim from rays that pass through it; the ray goes on
    /// past it (past at most a few caps). Without caps, the first hit.
    fn past_caps(&self, c: &Point3<f64>, d: &Vector3<f64>, t_max: f64) -> Option<RayHit> {
        let step = 1e-6 * t_max;
        let mut start = 0.0;
        for _ in 0..4 {
            let mut hit = self.bvh.cast_ray(&(c + d * start), d, t_max - start)?;
            hit.t += start;
            if !self.is_cap(hit.face) {
                return Some(hit);
            }
            start = hit.t + step;
        }
        None
    }

    /// The wall's distance from `c` along `rays` directions in the plane of `frame` (angles
    /// 2πj/rays from frame[1] towards frame[2]), on the anchor's branch. A ray that misses,
    /// goes beyond 4 radii or ends on another branch's wall (the section cuts a junction) is
    /// interpolated from its neighbours; with fewer than half the rays left the section is not
    /// the vessel's: none.
    fn read(&self, a: &Anchor, c: &Point3<f64>, frame: &[Vector3<f64>; 3]) -> Option<Vec<f64>> {
        let branch = a.branch?;
        let rays = self.rays;
        let reach = 4.0 * a.radius;
        let raw: Vec<Option<f64>> = ray_dirs(rays)
            .into_iter()
            .map(|(cs, sn)| {
                let d = frame[1] * cs + frame[2] * sn;
                self.bvh
                    .cast_ray(c, &d, reach)
                    .map(|hit| hit.t)
                    .filter(|&t| {
                        t > 0.0 && on_branch(self.centerline, &(c + d * t), &[branch], a.radius)
                    })
            })
            .collect();
        let good = raw.iter().filter(|r| r.is_some()).count();
        if good * 2 < rays {
            return None;
        }
        Some(
            (0..rays)
                .map(|j| {
                    raw[j].unwrap_or_else(|| {
                        // Nearest valid neighbours on either side, linearly by angle.
                        let mut back = 1;
                        while raw[(j + rays - back) % rays].is_none() {
                            back += 1;
                        }
                        let mut fwd = 1;
                        while raw[(j + fwd) % rays].is_none() {
                            fwd += 1;
                        }
                        let (a, b) = (
                            raw[(j + rays - back) % rays].unwrap(),
                            raw[(j + fwd) % rays].unwrap(),
                        );
                        a + (b - a) * back as f64 / (back + fwd) as f64
                    })
                })
                .collect(),
        )
    }

    /// The wall's offset from the tube's interpolated section, per sample and ray angle (step 3
    /// of the module docs): read where the ray from a sample (outside D on a tube towards a
    /// junction point) meets the input's wall
    /// (E: D grown by the clearance) within half a section radius of where the section puts it,
    /// on the anchors' branches `own` (not a neighbouring vessel's wall at a junction),
    /// and interpolated along the tube per angle, by arc length, between the readings on either
    /// side (the first reading held before the first one; past the last, held when the tube
    /// ends at an anchor (`open_end`), else faded out over one section radius; no offset for
    /// an angle never read).
    /// Whether `p` lies in E (the balls of D grown by the clearance).
    fn in_e(&self, p: &Point3<f64>) -> bool {
        self.balls
            .iter()
            .any(|b| (p - b.center).norm() < b.radius + self.grow)
    }

    /// Whether `p` lies within a junction's inscribed sphere grown by `r`.
    fn in_flare(&self, p: &Point3<f64>, r: f64) -> bool {
        self.centerline
            .junctions
            .iter()
            .any(|j| (p - j.position).norm() < j.radius + r)
    }

    fn carry_details(
        &self,
        points: &[Point3<f64>],
        frames: &[[Vector3<f64>; 3]],
        arc: &[f64],
        open_end: bool,
        flat_end: bool,
        own: &[usize],
        tension_r2: f64,
        base: impl Fn(usize, usize) -> f64 + Sync,
    ) -> Vec<f64> {
        let m = self.rays;
        let n = points.len();
        let outside_e = |p: &Point3<f64>| !self.in_e(p);
        // Through a hole's ball, a tube also reads the intact wall inside D (every face but the
        // cap's).
        let known_inside = self.cap.is_some();
        let known_wall =
            |p: &Point3<f64>, face: u32| outside_e(p) || (known_inside && !self.is_cap(face));
        let dirs = ray_dirs(m);
        let read: Vec<Option<f64>> = (0..points.len())
            .into_par_iter()
            .flat_map_iter(|i| {
                let (c, f) = (&points[i], &frames[i]);
                let base = &base;
                // Towards a junction point, sections outside E only: from inside, a ray that
                // leaves E crosses into whatever lies beyond D (another branch).
                // The last sample of a tube cut flat lies in the plane of the vessel's open end:
                // its rays graze the end's rim and misread the wall (on a straight tube 0.09
                // off the readings one sample before, where they vary by 0.02), a slope the
                // biharmonic fill carried across the hole.
                let outside =
                    (open_end || known_inside || outside_e(c)) && !(flat_end && i + 1 == n);
                let known_wall = &known_wall;
                dirs.iter().enumerate().map(move |(j, &(cs, sn))| {
                    if !outside {
                        return None;
                    }
                    let d = f[1] * cs + f[2] * sn;
                    let rho = base(i, j);
                    // Within a junction's flare the wall is no single vessel's (as for the
                    // anchors' sections); around a hole, the intact wall there is read too
                    // (on the tube's own branch): the fill's taper into the junction follows it.
                    if !known_inside && self.in_flare(c, rho) {
                        return None;
                    }
                    let hit = self.past_caps(c, &d, 1.5 * rho)?;
                    let wall = c + d * hit.t;
                    (hit.t > 0.0
                        && (hit.t - rho).abs() < 0.5 * rho
                        && known_wall(&wall, hit.face)
                        && on_branch(self.centerline, &wall, own, rho))
                    .then_some(hit.t - rho)
                })
            })
            .collect();
        let mut detail = vec![0.0; n * m];
        for j in 0..m {
            let known: Vec<usize> = (0..n).filter(|&i| read[i * m + j].is_some()).collect();
            let (Some(&first), Some(&last)) = (known.first(), known.last()) else {
                continue;
            };
            let at = |i: usize| read[i * m + j].unwrap_or(0.0);
            for i in 0..n {
                detail[i * m + j] = if i <= first {
                    at(first)
                } else if i >= last {
                    // Held to a second anchor; towards a junction point (no anchor: the
                    // branches' walls merge there) faded out over one section radius.
                    let fade = if open_end {
                        1.0
                    } else {
                        (1.0 - (arc[i] - arc[last]) / base(last, j).max(f64::MIN_POSITIVE)).max(0.0)
                    };
                    at(last) * fade
                } else {
                    // The readings on either side of i.
                    let k = known.partition_point(|&q| q <= i);
                    let (lo, hi) = (known[k - 1], known[k]);
                    let w = (arc[i] - arc[lo]) / (arc[hi] - arc[lo]).max(f64::MIN_POSITIVE);
                    at(lo) * (1.0 - w) + at(hi) * w
                };
            }
        }
        if open_end && self.narrowed {
            self.widen_narrowed(points, frames, own, &base, &mut detail);
        }
        if known_inside {
            let known: Vec<bool> = read.iter().map(|r| r.is_some()).collect();
            let spacing: Vec<f64> = (0..n)
                .map(|i| TAU / m as f64 * (0..m).map(|j| base(i, j)).sum::<f64>() / m as f64)
                .collect();
            // A junction's branch: membrane-like beyond a section radius (see
            // JUNCTION_CHART_TENSION); elsewhere a thin plate.
            let radius = (0..m).map(|j| base(0, j)).sum::<f64>() / m as f64;
            let tension = tension_r2 / (radius * radius).max(f64::MIN_POSITIVE);
            fill_with_tension(&mut detail, &known, arc, &spacing, m, tension);
            // Past its last reading a tube with no second anchor runs on towards a point
            // where no wall is read (a junction point): its filled offsets are bounded there.
            // Between two anchors the fill is held by readings on either side, and a bulge
            // over the hole (a carotid bulb's) can reach well beyond the anchors' sections.
            if !open_end {
                bound_filled_bulge(&mut detail, &known, m, &base);
            }
        }
        detail
    }
}

impl Sections<'_> {
    /// Inside E on a tube through a narrowing: where every ray of a section meets the narrowed
    /// wall (within 1.5 section radii, on the tube's branches), that wall's polygon is scaled about
    /// its centroid so that its mean distance from the centroid is the mean of the interpolated
    /// section (`base` plus `detail`), and the section becomes that polygon, read along the
    /// rays from the curve point: the vessel's own cross-section shape at its healthy size
    /// (exact for a concentric narrowing; an eccentric plaque's lumen keeps its shape, widened).
    fn widen_narrowed(
        &self,
        points: &[Point3<f64>],
        frames: &[[Vector3<f64>; 3]],
        own: &[usize],
        base: &(impl Fn(usize, usize) -> f64 + Sync),
        detail: &mut [f64],
    ) {
        let m = self.rays;
        let inside_e = |p: &Point3<f64>| self.in_e(p);
        let detail_ro: &[f64] = detail;
        let rows: Vec<Option<Vec<f64>>> = (0..points.len())
            .into_par_iter()
            .map(|i| {
                let (c, f) = (&points[i], &frames[i]);
                if !inside_e(c) {
                    return None;
                }
                let dirs = ray_dirs(m);
                let rho: Vec<f64> = (0..m).map(|j| base(i, j) + detail_ro[i * m + j]).collect();
                let wall = read_wall(
                    self.bvh,
                    self.centerline,
                    c,
                    f,
                    &dirs,
                    own,
                    |j| 1.5 * rho[j],
                    |j| rho[j],
                )?;
                let g = wall.iter().fold((0.0, 0.0), |a, w| {
                    (a.0 + w.0 / m as f64, a.1 + w.1 / m as f64)
                });
                let spread = wall
                    .iter()
                    .map(|w| (w.0 - g.0).hypot(w.1 - g.1))
                    .sum::<f64>()
                    / m as f64;
                let target = rho.iter().sum::<f64>() / m as f64;
                if spread <= 0.0 || target <= spread {
                    return None;
                }
                let widened = scaled_section(&wall, g, target / spread, &dirs)?;
                Some(
                    widened
                        .iter()
                        .enumerate()
                        .map(|(j, t)| t - base(i, j))
                        .collect(),
                )
            })
            .collect();
        for (i, row) in rows.into_iter().enumerate() {
            if let Some(row) = row {
                detail[i * m..(i + 1) * m].copy_from_slice(&row);
            }
        }
    }

    /// Whether the vessel between anchors `a` and `b` is round: the sections read at the ends of
    /// `points` (of the anchors clear of D; one of them at least) vary in radius by less than
    /// [`ROUND_SECTION`].
    fn round_between(&self, a: &Anchor, b: &Anchor, points: &[Point3<f64>]) -> bool {
        let (Some(first), Some(last)) = (points.first(), points.last()) else {
            return false;
        };
        let fr = frames(points, &a.into);
        let spread = |anchor: &Anchor, at: &Point3<f64>, frame: &[Vector3<f64>; 3]| {
            anchor
                .clear
                .then(|| self.read(anchor, at, frame))
                .flatten()
                .and_then(|radii| radius_spread(&radii))
        };
        let spreads = [
            spread(a, first, &fr[0]),
            spread(b, last, fr.last().expect("frames")),
        ];
        spreads.iter().any(Option::is_some) && spreads.iter().flatten().all(|&s| s < ROUND_SECTION)
    }

    /// A curve through a hole's ball moved onto the intact wall's centre: at each sample whose
    /// rays meet the intact wall (not the cap; within half a radius of `radius`, on the branches
    /// `own`) at `fit.known` of the angles or more (three quarters; half in a round vessel, see
    /// [`ROUND_SECTION`]), no more than `fit.gap` of a turn missing, the circle
    /// fitted to those wall points (Kåsa's algebraic fit) gives the section's centre. Beside E
    /// the curve runs on the vessel's centreline, so the mean offset there on either side is the
    /// fit's bias (a section that is not round), taken off inside E linearly between the sides.
    /// The offsets inside E (at most half a radius) are interpolated between samples, fall to 0
    /// towards the curve's ends, are smoothed over about one radius of arc and fade out at both
    /// ends over the arc that keeps the end's turn within [`END_FADE_SLOPE`]. The wall around a
    /// hole says where the vessel's axis runs better than a cubic between the anchors does at a
    /// bend (the coronary's 47° bend: 3.36h → 1.59h).
    fn recentre(
        &self,
        points: Vec<Point3<f64>>,
        into: &Vector3<f64>,
        own: &[usize],
        radius: f64,
        fit: WallFit,
    ) -> Vec<Point3<f64>> {
        let n = points.len();
        let m = self.rays;
        if self.cap.is_none() {
            return points;
        }
        if n < 3 || !(radius > 0.0) {
            return points;
        }
        let fr = frames(&points, into);
        let dirs = ray_dirs(m);
        let inside_e = |p: &Point3<f64>| self.in_e(p);
        let fits: Vec<Option<Vector3<f64>>> = (0..n)
            .into_par_iter()
            .map(|i| {
                let (c, f) = (&points[i], &fr[i]);
                let mut known = Vec::new();
                let mut angles = Vec::new();
                for (j, &(cs, sn)) in dirs.iter().enumerate() {
                    let d = f[1] * cs + f[2] * sn;
                    let Some(hit) = self.bvh.cast_ray(c, &d, 1.5 * radius) else {
                        continue;
                    };
                    let wall = c + d * hit.t;
                    if (hit.t - radius).abs() < 0.5 * radius
                        && !self.is_cap(hit.face)
                        && on_branch(self.centerline, &wall, own, radius)
                    {
                        known.push((hit.t * cs, hit.t * sn));
                        angles.push(j);
                    }
                }
                if (known.len() as f64) < fit.known * m as f64 {
                    return None;
                }
                // The largest run of angles without a reading: at most `fit.gap` of a turn.
                let gap = angles
                    .iter()
                    .zip(angles.iter().cycle().skip(1))
                    .map(|(&a, &b)| (b + m - a) % m)
                    .max()
                    .unwrap_or(m);
                if gap as f64 > fit.gap * m as f64 {
                    return None;
                }
                let (cx, cy) = fit_circle(&known)?;
                (cx.hypot(cy) <= 0.5 * radius).then(|| f[1] * cx + f[2] * cy)
            })
            .collect();
        // A section that is not round has its fitted centre off its axis: the offset outside E
        // on either side (where the curve runs on the vessel's own centreline) is that bias,
        // taken off the offsets inside E, linearly between the two sides.
        let inside: Vec<bool> = points.iter().map(inside_e).collect();
        let Some(enter) = inside.iter().position(|&x| x) else {
            return points;
        };
        let leave = inside.iter().rposition(|&x| x).unwrap_or(enter);
        let mean_of = |range: std::ops::Range<usize>| {
            let v: Vec<Vector3<f64>> = range.filter_map(|i| fits[i]).collect();
            (!v.is_empty()).then(|| v.iter().sum::<Vector3<f64>>() / v.len() as f64)
        };
        let bias_a = mean_of(0..enter);
        let bias_b = mean_of(leave + 1..n);
        let (bias_a, bias_b) = match (bias_a, bias_b) {
            (Some(a), Some(b)) => (a, b),
            (Some(a), None) => (a, a),
            (None, Some(b)) => (b, b),
            (None, None) => (Vector3::zeros(), Vector3::zeros()),
        };
        let fits: Vec<Option<Vector3<f64>>> = (0..n)
            .map(|i| {
                let w = (i.saturating_sub(enter)) as f64 / (leave - enter).max(1) as f64;
                fits[i]
                    .filter(|_| inside[i])
                    .map(|f| f - (bias_a * (1.0 - w.min(1.0)) + bias_b * w.min(1.0)))
            })
            .collect();
        let have: Vec<usize> = (0..n).filter(|&i| fits[i].is_some()).collect();
        let (Some(&first), Some(&last)) = (have.first(), have.last()) else {
            return points;
        };
        let mut arc = vec![0.0];
        for w in points.windows(2) {
            arc.push(arc.last().unwrap() + (w[1] - w[0]).norm());
        }
        let at = |i: usize| fits[i].unwrap_or_else(Vector3::zeros);
        let offset: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                let lerp = |lo: usize, a: Vector3<f64>, hi: usize, b: Vector3<f64>| {
                    let w = (arc[i] - arc[lo]) / (arc[hi] - arc[lo]).max(f64::MIN_POSITIVE);
                    a * (1.0 - w) + b * w
                };
                if i < first {
                    lerp(0, Vector3::zeros(), first, at(first))
                } else if i > last {
                    lerp(last, at(last), n - 1, Vector3::zeros())
                } else {
                    let k = have.partition_point(|&q| q <= i);
                    if k == have.len() {
                        at(last)
                    } else {
                        lerp(have[k - 1], at(have[k - 1]), have[k], at(have[k]))
                    }
                }
            })
            .collect();
        // A moving average over about one radius of arc, the ends kept at 0.
        let half = radius * 0.5;
        let total = arc[n - 1];
        let averaged: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                if i == 0 || i + 1 == n {
                    return Vector3::zeros();
                }
                let (mut sum, mut count) = (Vector3::zeros(), 0.0);
                for k in (0..n).filter(|&k| (arc[k] - arc[i]).abs() <= half) {
                    sum += offset[k];
                    count += 1.0;
                }
                sum / count
            })
            .collect();
        // Beside an end kept at 0, a sample moved by the average bends the curve: the samples lie
        // a fraction of a voxel apart, and an anchor inside E (its section clear of D, its point
        // not) has fits up to the curve's last sample; the tube, continued straight past that
        // end along its last tangent, stood out of the wall as a fin 7 mm long (a slit in the
        // open aorta's wall: 22.6h). So the average fades out at each end (a smoothstep) over
        // the arc that keeps the curve's turn there within END_FADE_SLOPE: the largest offset
        // within half a radius of the end over that slope, at most half a radius.
        let fade = |near: &dyn Fn(usize) -> f64| {
            let largest = (0..n)
                .filter(|&i| near(i) <= half)
                .map(|i| averaged[i].norm())
                .fold(0.0, f64::max);
            (1.5 * largest / END_FADE_SLOPE).min(half)
        };
        let (fade_start, fade_end) = (fade(&|i| arc[i]), fade(&|i| total - arc[i]));
        let smooth = |d: f64, len: f64| {
            if len <= 0.0 {
                return 1.0;
            }
            let x = (d / len).clamp(0.0, 1.0);
            x * x * (3.0 - 2.0 * x)
        };
        (0..n)
            .map(|i| {
                points[i]
                    + averaged[i] * smooth(arc[i], fade_start) * smooth(total - arc[i], fade_end)
            })
            .collect()
    }
}

/// Largest slope (offset per arc length) by which the recentred curve's offset may fade out at
/// its ends ([`Sections::recentre`]): a turn of its end tangent of about 6°.
const END_FADE_SLOPE: f64 = 0.1;

/// Centre of the circle fitted to 2-D points (Kåsa: least squares of x² + y² + Dx + Ey + F).
fn fit_circle(pts: &[(f64, f64)]) -> Option<(f64, f64)> {
    let mut a = nalgebra::Matrix3::<f64>::zeros();
    let mut r = Vector3::zeros();
    for &(x, y) in pts {
        let row = Vector3::new(x, y, 1.0);
        a += row * row.transpose();
        r -= row * (x * x + y * y);
    }
    let sol = a.lu().solve(&r)?;
    Some((-0.5 * sol.x, -0.5 * sol.y))
}

/// How much longer (a fraction) [`ray_polygon`] takes each edge at both ends.
const EDGE_HAIR: f64 = 1e-9;

/// Distance from the origin along the unit direction `dir` to the closed polygon `poly` (the
/// nearest crossing ahead), 2-D.
fn ray_polygon(dir: (f64, f64), poly: &[(f64, f64)]) -> Option<f64> {
    let n = poly.len();
    let mut best: Option<f64> = None;
    for a in 0..n {
        let (p, q) = (poly[a], poly[(a + 1) % n]);
        let e = (q.0 - p.0, q.1 - p.1);
        // origin + t·dir = p + u·e
        let den = dir.0 * (-e.1) - dir.1 * (-e.0);
        if den.abs() < 1e-15 {
            continue;
        }
        let t = (p.0 * (-e.1) - p.1 * (-e.0)) / den;
        let u = (dir.0 * p.1 - dir.1 * p.0) / den;
        // A ray through a corner meets both edges there at u = 1 and u = 0 up to rounding,
        // which can put both just outside: the corner's edges are taken a hair longer.
        if t > 0.0 && (-EDGE_HAIR..=1.0 + EDGE_HAIR).contains(&u) && best.is_none_or(|b| t < b) {
            best = Some(t);
        }
    }
    best
}

fn make_tube(
    sections: &Sections,
    points: Vec<Point3<f64>>,
    a: &Anchor,
    b: Option<&Anchor>,
    end_cap: EndCap,
    recentre: bool,
    tension_r2: f64,
) -> GuideTube {
    // The wall a tube reads is on its anchors' branches (a gap's two sides may be two).
    let mut own: Vec<usize> = a
        .branch
        .into_iter()
        .chain(b.and_then(|b| b.branch))
        .collect();
    own.dedup();
    // Between two anchors of a vessel that passes a hole, the curve is moved onto the centre
    // of the intact wall around the hole.
    // In a round vessel from half its wall, in a few passes (see ROUND_SECTION).
    let points = match b {
        Some(b) if recentre && sections.cap.is_some() => {
            let fit = if sections.round_between(a, b, &points) {
                ROUND_FIT
            } else {
                STRICT_FIT
            };
            let radius = 0.5 * (a.radius + b.radius);
            (0..fit.passes).fold(points, |p, _| {
                sections.recentre(p, &a.into, &own, radius, fit)
            })
        }
        _ => points,
    };
    let frames = frames(&points, &a.into);
    let acc = arc_lengths(&points);
    let total = acc.last().copied().unwrap_or(0.0).max(f64::MIN_POSITIVE);
    let weight: Vec<f64> = acc.iter().map(|s| s / total).collect();
    // A section that is not clear of D (next to a junction) or not the vessel's own is not
    // used: the other end's is, or a circle of the anchor's radius.
    let circle = |r: f64| vec![r; sections.rays];
    let start_read = a
        .clear
        .then(|| sections.read(a, &points[0], &frames[0]))
        .flatten();
    let end_read = b.filter(|b| b.clear).and_then(|b| {
        sections.read(
            b,
            points.last().expect("points"),
            frames.last().expect("frames"),
        )
    });
    let start_profile = start_read
        .clone()
        .or_else(|| end_read.clone())
        .unwrap_or_else(|| circle(a.radius));
    let end_profile = match b {
        Some(b) => end_read.or(start_read).unwrap_or_else(|| circle(b.radius)),
        None => start_profile.clone(),
    };
    let base = |i: usize, j: usize| {
        let w = weight[i];
        start_profile[j] * (1.0 - w) + end_profile[j] * w
    };
    let flat = end_cap == EndCap::Flat;
    let detail = sections.carry_details(
        &points,
        &frames,
        &acc,
        b.is_some(),
        flat,
        &own,
        tension_r2,
        base,
    );
    let chunks = bounding_chunks(&points);
    let widest = start_profile
        .iter()
        .chain(&end_profile)
        .fold(0.0, |m: f64, &r| m.max(r))
        + detail.iter().fold(0.0, |m: f64, &d| m.max(d));
    let cap_radius = mean(&end_profile);
    GuideTube {
        points,
        frames,
        weight,
        start_profile,
        end_profile,
        end_cap,
        flat_start: false,
        cap_radius,
        detail,
        chunks,
        widest,
    }
}

/// The bounding spheres of runs of [`CHUNK`] consecutive samples.
fn bounding_chunks(points: &[Point3<f64>]) -> Vec<(Point3<f64>, f64)> {
    points
        .chunks(CHUNK)
        .map(|run| {
            let c = Point3::from(
                run.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / run.len() as f64,
            );
            let r = run.iter().map(|p| (p - c).norm()).fold(0.0, f64::max);
            (c, r)
        })
        .collect()
}

impl GuideTube {
    /// A tube given by its section radii (`radii[i·m + j]` at sample i, angle 2πj/m in its frame),
    /// cut flat at both ends.
    pub(super) fn from_radii(
        points: Vec<Point3<f64>>,
        frames: Vec<[Vector3<f64>; 3]>,
        radii: Vec<f64>,
        m: usize,
    ) -> GuideTube {
        let acc = arc_lengths(&points);
        let total = acc.last().copied().unwrap_or(0.0).max(f64::MIN_POSITIVE);
        GuideTube {
            chunks: bounding_chunks(&points),
            weight: acc.iter().map(|s| s / total).collect(),
            widest: radii.iter().fold(0.0, |w: f64, &r| w.max(r)),
            points,
            frames,
            start_profile: vec![0.0; m],
            end_profile: vec![0.0; m],
            end_cap: EndCap::Flat,
            flat_start: true,
            cap_radius: 0.0,
            detail: radii,
        }
    }

    /// Section radius at sample `i` and angle `theta` (radians, in the sample's frame).
    fn radius_at(&self, i: usize, theta: f64) -> f64 {
        let m = self.start_profile.len();
        let x = theta.rem_euclid(TAU) / TAU * m as f64;
        let j = (x.floor() as usize) % m;
        let f = x - x.floor();
        let k = (j + 1) % m;
        let a = self.start_profile[j] * (1.0 - f) + self.start_profile[k] * f;
        let b = self.end_profile[j] * (1.0 - f) + self.end_profile[k] * f;
        let w = self.weight[i];
        let d = &self.detail[i * m..(i + 1) * m];
        a * (1.0 - w) + b * w + d[j] * (1.0 - f) + d[k] * f
    }

    /// Signed distance (to first order) from `x` to the tube.
    pub fn distance(&self, x: &Point3<f64>) -> f64 {
        // The nearest sample (the first of equals, as a scan in order gives), skipping the
        // runs whose bounding sphere is farther than the best so far; the run whose sphere is
        // nearest is scanned first, so that most others are skipped.
        // Far from the curve (beyond twice the widest section) only the sign matters: a lower
        // bound of the distance is returned, without the search.
        let widest = self.widest;
        let lower_bound = |k: usize| {
            let (c, r) = &self.chunks[k];
            ((x - c).norm() - r).max(0.0)
        };
        // The runs' lower bounds, kept for the second pass (the first LOWS runs).
        const LOWS: usize = 64;
        let mut lows = [0.0; LOWS];
        let (mut k0, mut nearest_chunk) = (0, f64::INFINITY);
        for k in 0..self.chunks.len() {
            let lower = lower_bound(k);
            if let Some(slot) = lows.get_mut(k) {
                *slot = lower;
            }
            if lower < nearest_chunk {
                (k0, nearest_chunk) = (k, lower);
            }
        }
        if nearest_chunk > 2.0 * widest {
            return nearest_chunk - widest;
        }
        // The nearest run first: its best bounds the others, most of which are then skipped.
        let (mut i, mut best) = (usize::MAX, f64::INFINITY);
        let scan = |k: usize, i: &mut usize, best: &mut f64| {
            let from = k * CHUNK;
            for (j, p) in self.points[from..(from + CHUNK).min(self.points.len())]
                .iter()
                .enumerate()
            {
                let d = (x - p).norm_squared();
                if d < *best || (d == *best && from + j < *i) {
                    (*i, *best) = (from + j, d);
                }
            }
        };
        scan(k0, &mut i, &mut best);
        for k in 0..self.chunks.len() {
            let lower = lows.get(k).copied().unwrap_or_else(|| lower_bound(k));
            if k == k0 || lower * lower > best {
                continue;
            }
            scan(k, &mut i, &mut best);
        }
        let [t, e1, e2] = self.frames[i];
        let v = x - self.points[i];
        let along = v.dot(&t);
        let last = i + 1 == self.points.len();
        let beyond = last && along > 0.0 && self.end_cap == EndCap::Round;
        if beyond {
            return v.norm() - self.cap_radius;
        }
        let perp = v - t * along;
        let theta = perp.dot(&e2).atan2(perp.dot(&e1));
        let radial = perp.norm() - self.radius_at(i, theta);
        if last && along > 0.0 && self.end_cap == EndCap::Flat {
            return radial.max(along);
        }
        if i == 0 && along < 0.0 && self.flat_start {
            return radial.max(-along);
        }
        radial
    }
}

/// Replaces `phi` at the nodes inside the balls of the guides by the smallest tube distance
/// (see the module docs): exactly within a few voxels of the tubes' walls, by interpolation
/// farther from them (`adaptive`). Returns the number of nodes filled.
pub fn fill_guided(phi: &mut Grid3, balls: &[Ball], guides: &[RegionGuide]) -> usize {
    let mine: Vec<(Ball, usize)> = guides
        .iter()
        .enumerate()
        .flat_map(|(g, guide)| guide.balls.iter().map(move |&b| (balls[b], g)))
        .collect();
    // Exact near the tubes' walls, interpolated deep inside and far outside them.
    guides
        .iter()
        .enumerate()
        .map(|(g, guide)| {
            let own: Vec<Ball> = guide.balls.iter().map(|&b| balls[b]).collect();
            // A node belongs to the guide of the first ball holding it.
            let owns =
                |p: &Point3<f64>| mine.iter().find(|(b, _)| b.contains(p)).map(|m| m.1) == Some(g);
            let field = |p: &Point3<f64>| {
                guide
                    .tubes
                    .iter()
                    .zip(&guide.kinds)
                    .map(|(tube, &kind)| (tube.distance(p), kind))
                    .fold(f64::INFINITY, |d, (di, kind)| {
                        // A junction's branches meet in a fillet, as at a carina.
                        if kind == GuideKind::Junction && d.is_finite() {
                            smooth_min(d, di, guide.fillet)
                        } else {
                            d.min(di)
                        }
                    })
            };
            sample_adaptive(phi, &own, owns, field, &AdaptiveOptions::default())
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_region_is_reported_by_its_least_certain_curve() {
        use GuideKind::*;
        assert_eq!(
            GuideKind::region_fill(&[Through, Junction, Through]),
            "junction"
        );
        assert_eq!(GuideKind::region_fill(&[Through, DeadEnd]), "dead-end");
        assert_eq!(GuideKind::region_fill(&[DeadEnd, Stump]), "stump");
        assert_eq!(GuideKind::region_fill(&[Stump, Junction]), "junction");
        assert_eq!(GuideKind::region_fill(&[Bridge, Through]), "bridge");
        assert_eq!(GuideKind::region_fill(&[Widened, Widened]), "widened");
        assert_eq!(GuideKind::region_fill(&[Through]), "through");
    }

    #[test]
    fn only_filled_details_are_bounded_and_only_outward() {
        // Two samples of two rays, section radius 2: the bound is 1.6 outward.
        let known = [true, false, false, false];
        let mut detail = [5.0, 5.0, -5.0, 1.0];
        bound_filled_bulge(&mut detail, &known, 2, &|_, _| 2.0);
        assert_eq!(detail, [5.0, 1.6, -5.0, 1.0]);
    }

    #[test]
    fn hermite_follows_a_quarter_circle() {
        // Anchors on a circle of radius 10 a quarter turn apart, tangents along the circle.
        let a = Anchor {
            point: Point3::new(10.0, 0.0, 0.0),
            into: Vector3::new(0.0, 1.0, 0.0),
            radius: 1.0,
            clear: true,
            branch: None,
            index: 0,
        };
        let b = Anchor {
            point: Point3::new(0.0, 10.0, 0.0),
            into: Vector3::new(1.0, 0.0, 0.0),
            radius: 1.0,
            clear: true,
            branch: None,
            index: 0,
        };
        let pts = hermite(&a, &b, 0.1);
        let worst = pts
            .iter()
            .map(|p| (p.coords.norm() - 10.0).abs())
            .fold(0.0, f64::max);
        // The cubic with arc-matched tangents stays within 0.03% of the radius over 90°.
        assert!(worst < 0.003, "worst radial deviation {worst}");
        let gaps = pts.windows(2).map(|w| (w[1] - w[0]).norm());
        assert!(gaps.clone().fold(0.0, f64::max) <= 0.1 + 1e-9);
    }

    #[test]
    fn frames_stay_orthonormal_and_do_not_twist_on_a_plane_curve() {
        let pts: Vec<Point3<f64>> = (0..100)
            .map(|k| {
                let a = k as f64 * 0.02;
                Point3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let f = frames(&pts, &Vector3::y());
        for [t, r, s] in &f {
            assert!((t.norm() - 1.0).abs() < 1e-9 && (r.norm() - 1.0).abs() < 1e-9);
            assert!(t.dot(r).abs() < 1e-9 && t.dot(s).abs() < 1e-9);
            // On a plane curve the RMF keeps its binormal-like axis fixed.
            assert!((s.z.abs() - 1.0).abs() < 1e-6 || (r.z.abs() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn rays_from_inside_meet_a_square_where_it_is() {
        let square = [(-1.0, -2.0), (3.0, -2.0), (3.0, 2.0), (-1.0, 2.0)];
        let t = |x: f64, y: f64| ray_polygon((x, y), &square).unwrap();
        assert!((t(1.0, 0.0) - 3.0).abs() < 1e-12);
        assert!((t(-1.0, 0.0) - 1.0).abs() < 1e-12);
        assert!((t(0.0, 1.0) - 2.0).abs() < 1e-12);
        let d = 0.5f64.sqrt();
        assert!((t(-d, -d) - 2f64.sqrt()).abs() < 1e-12);
        // From outside, looking away: nothing ahead.
        assert!(ray_polygon((1.0, 0.0), &[(-3.0, -1.0), (-2.0, -1.0), (-2.0, 1.0)]).is_none());
    }

    #[test]
    fn every_ray_through_a_corner_meets_the_polygon() {
        // A section read along the rays has its corners on them; scaled about a centroid a
        // rounding error off the origin, they stay there, and each ray meets two edges at a
        // corner (it once missed both on a synthetic tube's sections).
        let dirs = ray_dirs(48);
        let r = |j: usize| 1.0 + 0.3 * (3.0 * j as f64).sin();
        let wall: Vec<(f64, f64)> = (0..48)
            .map(|j| (r(j) * dirs[j].0, r(j) * dirs[j].1))
            .collect();
        let got = scaled_section(&wall, (1e-17, -2e-17), 1.7, &dirs).unwrap();
        for (j, t) in got.iter().enumerate() {
            assert!(
                (t - 1.7 * r(j)).abs() < 1e-9,
                "{j}: {t} against {}",
                1.7 * r(j)
            );
        }
    }

    #[test]
    fn a_circle_is_round_and_a_slightly_flattened_section_is_not() {
        // A section's radii along evenly spaced rays from its centre: a circle's are equal; an
        // ellipse's with axes 1.02 and 0.98 (4% flatter one way) vary by about 1.4%.
        let m = 48;
        let ellipse = |a: f64, b: f64| -> Vec<f64> {
            ray_dirs(m)
                .into_iter()
                .map(|(c, s)| 1.0 / ((c / a).powi(2) + (s / b).powi(2)).sqrt())
                .collect()
        };
        assert!(radius_spread(&ellipse(2.0, 2.0)).unwrap() < 1e-12);
        let flat = radius_spread(&ellipse(1.02, 0.98)).unwrap();
        assert!((0.013..0.015).contains(&flat), "{flat}");
        assert!(flat > ROUND_SECTION);
        assert!(radius_spread(&ellipse(1.005, 0.995)).unwrap() < ROUND_SECTION);
        assert_eq!(radius_spread(&[]), None);
        assert_eq!(radius_spread(&[0.0, 0.0]), None);
    }

    #[test]
    fn the_circle_through_a_third_of_a_ring_has_its_centre() {
        // 16 points on 120° of a circle of radius 2 around (0.7, −0.3): Kåsa's fit is exact.
        let pts: Vec<(f64, f64)> = (0..16)
            .map(|k| {
                let a = 0.5 + k as f64 * (TAU / 3.0) / 15.0;
                (0.7 + 2.0 * a.cos(), -0.3 + 2.0 * a.sin())
            })
            .collect();
        let (x, y) = fit_circle(&pts).unwrap();
        assert!((x - 0.7).abs() < 1e-9 && (y + 0.3).abs() < 1e-9, "{x} {y}");
        // Collinear points have no circle.
        assert!(fit_circle(&[(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)]).is_none());
    }

    /// An anchor at `p` looking along `into`, radius 1, read as clear.
    fn looking(p: Point3<f64>, into: Vector3<f64>) -> Anchor {
        Anchor {
            point: p,
            into,
            radius: 1.0,
            clear: true,
            branch: None,
            index: 0,
        }
    }

    /// The rim a chop leaves where it bites the end of a tube of radius 1 along +z cut at z = 5
    /// by a plane tilted `tilt` about x: the half of the end's section left on the plane, then
    /// the bite's edge down the wall (a curve off any plane).
    fn bitten_rim(tilt: f64) -> (Vec<Point3<f64>>, Vec<Point3<f64>>) {
        let on_cut = |a: f64| {
            let (x, y) = (a.cos(), a.sin());
            Point3::new(x, y, 5.0 + y * tilt.tan())
        };
        let cut = (0..=24).map(|k| on_cut(k as f64 * TAU / 48.0)).collect();
        let bite = (1..24)
            .map(|k| {
                let a = std::f64::consts::PI + k as f64 * TAU / 48.0;
                let dip = 1.5 * (k as f64 * std::f64::consts::PI / 24.0).sin();
                on_cut(a) - Vector3::new(0.0, 0.0, dip + 0.1 * (3.0 * a).cos())
            })
            .collect();
        (cut, bite)
    }

    /// `end` is the end of [`bitten_rim`]'s untilted cut: the centre of the rim's circle on it
    /// (the tube's axis at z = 5), with its radius, pointing back down the vessel.
    fn assert_end_of_the_untilted_cut(end: &Anchor) {
        assert!(
            (end.point - Point3::new(0.0, 0.0, 5.0)).norm() < 1e-9,
            "{:?}",
            end.point
        );
        assert!((end.radius - 1.0).abs() < 1e-9, "{}", end.radius);
        assert!((end.into + Vector3::z()).norm() < 1e-9, "{:?}", end.into);
    }

    #[test]
    fn a_bitten_end_is_found_on_the_plane_of_its_cut() {
        let (cut, bite) = bitten_rim(0.0);
        let rim: Vec<Point3<f64>> = cut.iter().chain(&bite).copied().collect();
        // An anchor off the end's axis (the vessel bends before its end): the end is the centre
        // of the rim's circle on the cut, with its radius, pointing back down the vessel.
        let from = looking(Point3::new(0.4, 0.0, 0.0), Vector3::z());
        let end = bitten_end(&rim, &from).expect("the cut's plane");
        assert_end_of_the_untilted_cut(&end);
        assert!(!end.clear);
        // A cut tilted 20°: its plane exactly; the centre of the circle fitted to the half
        // ellipse the tube leaves on it within a tenth of the radius of the tube's axis.
        let tilt = 20f64.to_radians();
        let (cut, bite) = bitten_rim(tilt);
        let rim: Vec<Point3<f64>> = cut.iter().chain(&bite).copied().collect();
        let end = bitten_end(&rim, &looking(Point3::origin(), Vector3::z())).expect("tilted");
        let normal = Vector3::new(0.0, -tilt.sin(), tilt.cos());
        assert!((end.into + normal).norm() < 1e-9, "{:?}", end.into);
        assert!(
            (end.point - Point3::new(0.0, 0.0, 5.0)).norm() < 0.1,
            "{:?}",
            end.point
        );
        // The bite alone (no planar part of the rim left) is no cut end; nor a cut behind the
        // anchor, nor one along the vessel rather than across it.
        let from = looking(Point3::origin(), Vector3::z());
        assert!(bitten_end(&bite, &from).is_none());
        assert!(bitten_end(&rim, &looking(Point3::new(0.0, 0.0, 9.0), Vector3::z())).is_none());
        assert!(bitten_end(&rim, &looking(Point3::origin(), Vector3::x())).is_none());
    }

    #[test]
    fn a_cut_end_is_read_off_a_rim_where_the_vessel_does_not_go_on() {
        let (cut, bite) = bitten_rim(0.0);
        let rim: Vec<Point3<f64>> = cut.iter().chain(&bite).copied().collect();
        // The vessel (a box around the tube, closed) ends at the cut, z = 5: its end is the
        // centre of the rim's circle there, with its radius, pointing back into the vessel.
        let box_to = |z: f64| {
            MeshBvh::new(&crate::mesh::primitives::box_mesh(
                Point3::new(-1.0, -1.0, -5.0),
                Point3::new(1.0, 1.0, z),
            ))
        };
        let end = cut_end_in_rim(&rim, 1.0, &box_to(5.0)).expect("the cut end");
        assert_end_of_the_untilted_cut(&end);
        // A vessel that goes on through the plane (a rim along a slice plane): no end; nor the
        // bite alone, nor a circle far from the vessels' size.
        assert!(cut_end_in_rim(&rim, 1.0, &box_to(9.0)).is_none());
        assert!(cut_end_in_rim(&bite, 1.0, &box_to(5.0)).is_none());
        assert!(cut_end_in_rim(&rim, 4.0, &box_to(5.0)).is_none());
    }

    #[test]
    fn an_open_end_in_the_region_is_the_far_anchor() {
        // One branch from an open end at the origin up the z axis; the region holds the end.
        let points: Vec<Point3<f64>> = (0..=20)
            .map(|k| Point3::new(0.0, 0.0, k as f64 * 0.5))
            .collect();
        let n = points.len();
        let centerline = Centerline {
            voxel: 0.5,
            components: 1,
            branches: vec![crate::centerline::Branch {
                id: 0,
                component: 0,
                length: 10.0,
                points,
                radius: vec![1.0; n],
                tangent: vec![Vector3::z(); n],
                start: EndKind::OpenEnd,
                end: EndKind::End,
            }],
            junctions: Vec::new(),
            endpoints: vec![crate::centerline::Endpoint {
                position: Point3::origin(),
                radius: 1.5,
                branch: 0,
                open_end: true,
            }],
            notices: Vec::new(),
        };
        let from = looking(Point3::new(0.0, 0.0, 12.0), -Vector3::z());
        let near = |p: &Point3<f64>| (p - Point3::new(0.0, 0.0, 2.0)).norm() < 4.0;
        let end = open_end_in(&centerline, &near, &from).expect("the open end");
        assert_eq!(end.point, Point3::origin());
        // Pointing into the vessel, with the end loop's radius; its section is not read.
        assert!((end.into - Vector3::z()).norm() < 1e-12, "{:?}", end.into);
        assert_eq!((end.radius, end.clear), (1.5, false));
        let far = |p: &Point3<f64>| (p - Point3::new(0.0, 0.0, 8.0)).norm() < 4.0;
        assert!(open_end_in(&centerline, &far, &from).is_none());
    }

    /// A capped tube of radius 1 along z from 0 to 8, open at z = 0: its centreline's inscribed
    /// radius falls to the distance to the cap within a radius of the end; the section's rays
    /// read the tube's radius there, and farther in (and at the closed end) nothing changes.
    #[test]
    fn the_radius_next_to_an_open_end_is_the_sections() {
        use crate::mesh::cap::{cap_holes, CapOptions};
        use crate::mesh::primitives::open_tube;
        let (capped, _) = cap_holes(&open_tube(1.0, 8.0, 48, 33), &CapOptions::default()).unwrap();
        let bvh = MeshBvh::new(&capped);
        let mut br = line_branch(
            0,
            Point3::origin(),
            Point3::new(0.0, 0.0, 8.0),
            EndKind::OpenEnd,
            EndKind::End,
        );
        // As traced on the capped tube: the distance to the nearer cap where under the radius.
        br.radius = br
            .points
            .iter()
            .map(|p| p.z.min(8.0 - p.z).min(1.0))
            .collect();
        let radii: Vec<f64> = (0..br.points.len())
            .map(|i| radius_clear_of_open_ends(&br, i, &bvh, 4.0))
            .collect();
        let n = radii.len();
        for (i, p) in br.points.iter().enumerate() {
            if p.z > 0.0 && p.z < 0.95 {
                assert!((radii[i] - 1.0).abs() < 0.01, "{} at z = {}", radii[i], p.z);
            } else if p.z > 1.05 {
                assert_eq!(radii[i], br.radius[i], "at z = {}", p.z);
            }
        }
        // The closed end's (a tip of the skeleton) is left as traced.
        assert!(radii[n - 2] < 0.2);
    }

    #[test]
    fn ball_groups_join_overlapping_balls() {
        let b = |x: f64| Ball {
            center: Point3::new(x, 0.0, 0.0),
            radius: 1.0,
        };
        let g = ball_groups(&[b(0.0), b(5.0), b(1.5), b(6.0)]);
        assert_eq!(g, vec![vec![0, 2], vec![1, 3]]);
    }

    /// A straight branch from `a` to `b` sampled every 0.1, with kinds of its ends.
    fn line_branch(
        id: usize,
        a: Point3<f64>,
        b: Point3<f64>,
        start: EndKind,
        end: EndKind,
    ) -> crate::centerline::Branch {
        let n = ((b - a).norm() / 0.1).ceil() as usize;
        let t = (b - a).normalize();
        crate::centerline::Branch {
            id,
            component: 0,
            length: (b - a).norm(),
            points: (0..=n)
                .map(|k| a + (b - a) * (k as f64 / n as f64))
                .collect(),
            radius: vec![1.0; n + 1],
            tangent: vec![t; n + 1],
            start,
            end,
        }
    }

    #[test]
    fn a_junction_branch_leaves_the_junction_along_its_own_centreline() {
        use crate::centerline::Junction;
        use EndKind::{Junction as J, OpenEnd as O};
        // The aneurysm's chop: the daughter rises along z from the bifurcation at the origin,
        // then turns along x; the damage split it at k = (0, 0, 2) with a stub (branch 4).
        let o = Point3::origin();
        let k = Point3::new(0.0, 0.0, 2.0);
        let branches = vec![
            line_branch(0, Point3::new(0.0, -8.0, 0.0), o, O, J),
            line_branch(1, Point3::new(-8.0, 0.0, 0.0), o, O, J),
            line_branch(2, o, k, J, J),
            line_branch(3, Point3::new(6.0, 0.0, 2.0), k, O, J),
            line_branch(4, k, Point3::new(0.0, 1.0, 3.0), J, EndKind::End),
        ];
        let junctions = vec![
            Junction {
                id: 0,
                component: 0,
                position: o,
                radius: 1.2,
                branches: vec![0, 1, 2],
            },
            Junction {
                id: 1,
                component: 0,
                position: k,
                radius: 0.5,
                branches: vec![2, 3, 4],
            },
        ];
        let centerline = Centerline {
            voxel: 0.1,
            components: 1,
            branches,
            junctions,
            endpoints: Vec::new(),
            notices: Vec::new(),
        };
        // The daughter's anchor at x = 5, its run inside E from x = 4 to the split.
        let br = &centerline.branches[3];
        let anchor = Anchor {
            point: br.points[10],
            into: Vector3::new(-1.0, 0.0, 0.0),
            radius: 1.0,
            clear: true,
            branch: Some(3),
            index: 10,
        };
        let stub = Stub {
            anchor,
            outside: f64::INFINITY,
            run: br.points[20..].to_vec(),
            partner: None,
            cut: false,
        };
        let leave = leaving_direction(&centerline, &stub, &o).expect("a path to the junction");
        assert!(
            (leave - Vector3::z()).norm() < 1e-9,
            "leaves along {leave:?}"
        );
        // Not a junction of the centreline: no direction.
        assert!(leaving_direction(&centerline, &stub, &Point3::new(0.0, 0.0, 1.0)).is_none());
        // The anchor's tangent misses the junction by 22°: the centreline's direction is taken.
        let t = junction_tangent(&anchor, &o, &leave);
        assert!((t - Vector3::z()).norm() < 1e-9, "{t:?}");
        // An anchor straight in line with the junction keeps the chord.
        let straight = Anchor {
            point: Point3::new(0.0, -8.0, 0.0),
            into: Vector3::y(),
            ..anchor
        };
        let t = junction_tangent(&straight, &o, &Vector3::new(0.4, -1.0, 0.0).normalize());
        assert!((t + Vector3::y()).norm() < 1e-9, "{t:?}");
    }
}
