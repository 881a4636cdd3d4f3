//! Capping of boundary loops (open vessel ends and holes) so that the mesh becomes closed.
//!
//! Each boundary loop is projected onto its best-fit plane (principal component analysis of the
//! loop's vertices). When the projection is a simple polygon, it is triangulated with spade's
//! constrained Delaunay triangulation: a full Ruppert/Chew Delaunay refinement of the polygon to
//! triangles of about the target edge length supplies interior points graded towards small rim
//! features, the points it put on the rim are dropped (the rim must keep its vertices, or the mesh
//! would get T-junctions), and the rim with the remaining points is triangulated again; local
//! optimisation (quality-raising flips, max-min smoothing, vertex removal, longest-edge bisection)
//! then repairs the triangles next to the rim. The cap is lifted back with rim vertices at their
//! exact positions and interior vertices offset from the plane by the harmonic (linear finite
//! element) interpolation of the rim's offsets, so non-planar rims get a smooth cap.
//!
//! When the projection is not simple (or the planar construction fails), the loop is closed by
//! the hole filling of Liepa (2003, "Filling holes in meshes", Eurographics SGP): minimum-area
//! triangulation of the 3D polygon by dynamic programming (a centroid fan for very long loops),
//! refinement by centroid splits with Delaunay edge relaxation, and membrane fairing.
//!
//! Rim edges shorter than a tiny fraction of the target edge length (vertices a rounding error
//! apart) are collapsed first: no cap triangle on such an edge can have a bounded aspect ratio.
//! Sliver ears of a loop (a triangle with two rim edges whose middle vertex lies within that
//! fraction of the line through the other two, as a clipped end can leave) are cut off too: the
//! cap through that vertex would overlap them.
//! Cap chords never duplicate an existing edge. Cap triangles are wound opposite to the loop
//! direction, which is how the adjacent mesh triangles traverse the rim, so a consistently
//! oriented input gives a consistently oriented closed output; the result is finally flipped as a
//! whole if its enclosed volume is negative.
//!
//! [`cap_mesh`] (`watertight`) is the whole of `vesselmsr cap` around [`cap_holes`]: welding,
//! consistent winding, and the refusal of a result that is not watertight.

mod fan;
mod fill;
mod harmonic;
mod improve;
mod planar;
mod watertight;
mod weld;

pub use fan::cap_loops_with_fans;
pub use watertight::{cap_mesh, CappedMesh};

use super::measures::{signed_volume, triangle_aspect_ratio};
use super::topology::boundary_loops;
use crate::{Error, Result, TriMesh};
use nalgebra::Point3;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::ops::Range;

/// Options of [`cap_holes`].
#[derive(Debug, Clone)]
pub struct CapOptions {
    /// Target edge length of cap triangles, in world (file) units. `None` uses, for each loop, the
    /// mean length of that loop's own edges.
    pub target_edge_length: Option<f64>,
    /// Minimum angle of the Delaunay refinement that places the interior points of planar caps,
    /// in degrees (values above 30 over-refine; 0 disables angle-driven refinement).
    pub min_angle_deg: f64,
    /// Flip the whole result when its signed enclosed volume is negative, so that it faces outward.
    pub orient_outward: bool,
    /// Longest loop, in vertices, closed by the O(n³) minimum-area triangulation in the fallback;
    /// longer loops start from a centroid fan instead.
    pub max_dp_loop_vertices: usize,
    /// Rim edges shorter than this fraction of their loop's target edge length (dimensionless)
    /// are collapsed before capping, merging two rim vertices that are a rounding error apart
    /// (no cap triangle on such an edge can have a bounded aspect ratio), and triangles with two
    /// rim edges whose middle vertex lies within this fraction of the line through the other two
    /// (a sliver ear the cap would overlap) are removed; 0 disables both.
    pub rim_weld_fraction: f64,
    /// Most vertices a single cap may add (a guard against a tiny target edge length), a count.
    pub max_vertices_per_cap: usize,
}

impl Default for CapOptions {
    fn default() -> Self {
        CapOptions {
            target_edge_length: None,
            min_angle_deg: 28.0,
            orient_outward: true,
            max_dp_loop_vertices: 1000,
            rim_weld_fraction: 1e-3,
            max_vertices_per_cap: 1_000_000,
        }
    }
}

/// How one loop was closed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CapMethod {
    /// Refined constrained Delaunay triangulation of the projection on the best-fit plane.
    PlanarCdt,
    /// Fallback: minimum-area triangulation, then refinement and fairing (Liepa 2003).
    MinArea,
    /// Fallback for loops too long for the minimum-area triangulation: centroid fan, then
    /// refinement and fairing.
    CentroidFan,
}

/// What was done to one simple boundary loop. A loop that passes twice through a vertex is capped
/// as several simple loops, each with its own entry and the same `loop_index`.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LoopCap {
    /// Index of the loop in `topology::boundary_loops` order.
    pub loop_index: usize,
    /// Number of rim vertices.
    pub rim_vertices: usize,
    /// Target edge length used, in world units.
    pub target_edge_length: f64,
    /// Vertices added inside the cap.
    pub vertices_added: usize,
    /// Triangles of the cap.
    pub faces_added: usize,
    /// Method that closed the loop.
    pub method: CapMethod,
    /// Largest aspect ratio (equilateral = 1) of the cap's triangles.
    pub max_aspect_ratio: f64,
    /// Mean length of the cap's edges that are not rim edges, in world units (0 when there are
    /// none).
    pub mean_inner_edge_length: f64,
}

/// Summary of [`cap_holes`].
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct CapReport {
    /// Number of boundary loops closed.
    pub loops_capped: usize,
    /// Vertices appended to the mesh.
    pub vertices_added: usize,
    /// Triangles appended to the mesh.
    pub faces_added: usize,
    /// Indices (in `topology::boundary_loops` order) of the loops that needed the fallback.
    pub fallback_loops: Vec<usize>,
    /// Whether the whole result was flipped to face outward.
    pub flipped: bool,
    /// Largest aspect ratio (equilateral = 1) over all cap triangles; 0 when nothing was capped.
    pub max_cap_aspect_ratio: f64,
    /// The cap triangles: they come after the input's triangles (less `removed_faces`), in this
    /// index range.
    pub cap_faces: Range<usize>,
    /// Rim vertices merged into a neighbour before capping, as [kept, removed] vertex indices
    /// (see `CapOptions::rim_weld_fraction`); the removed ones stay in the vertex list unused.
    pub welded_rim_vertices: Vec<[u32; 2]>,
    /// Indices (in the input) of the sliver triangles dropped by those merges and of the sliver
    /// ears cut off (their middle vertices stay in the vertex list unused), ascending.
    pub removed_faces: Vec<usize>,
    /// Per simple loop details.
    pub loops: Vec<LoopCap>,
    /// One-line human notices (fallbacks, split loops, refinement limits), for the CLI's stderr.
    pub messages: Vec<String>,
}

/// A cap in loop-local numbering: index `i < rim` is the loop's i-th vertex, index `rim + k` is
/// `new_points[k]`. Faces are wound opposite to the loop direction.
pub(super) struct Patch {
    pub new_points: Vec<Point3<f64>>,
    pub faces: Vec<[usize; 3]>,
}

/// Undirected edge key.
fn ekey(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Closes every boundary loop of `mesh` (see the module documentation) and returns the closed
/// mesh: the input's vertices (same indices) followed by the cap vertices, and the input's
/// triangles followed by the cap triangles (`report.cap_faces`). The only change to the input's
/// part is the collapse of degenerate rim edges (`CapOptions::rim_weld_fraction`): those
/// triangles (`report.removed_faces`) are left out, the merged vertices
/// (`report.welded_rim_vertices`) are renamed in the remaining triangles, and stay in the vertex
/// list unreferenced.
///
/// Errors with [`Error::InvalidMesh`] for out-of-range vertex indices and with
/// [`Error::Geometry`] for loops that cannot be capped (non-finite coordinates, a loop part of fewer
/// than 3 distinct vertices left by a degenerate triangle, zero-length loops, or an invalid target
/// edge length).
pub fn cap_holes(mesh: &TriMesh, opts: &CapOptions) -> Result<(TriMesh, CapReport)> {
    let nv = mesh.num_vertices();
    if let Some(f) = mesh
        .faces
        .iter()
        .position(|f| f.iter().any(|&v| v as usize >= nv))
    {
        return Err(Error::InvalidMesh(format!(
            "triangle {f} refers to a vertex beyond the {nv} vertices"
        )));
    }
    if let Some(t) = opts.target_edge_length {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::Geometry(format!(
                "cap target edge length must be positive and finite, got {t}"
            )));
        }
    }
    let mut report = CapReport::default();
    let mut loops = boundary_loops(mesh);
    let loop_target = |lp: &[u32]| {
        let n = lp.len();
        let perimeter: f64 = (0..n)
            .map(|i| {
                (mesh.vertices[lp[(i + 1) % n] as usize] - mesh.vertices[lp[i] as usize]).norm()
            })
            .sum();
        opts.target_edge_length.unwrap_or(perimeter / n as f64)
    };
    for (li, lp) in loops.iter().enumerate() {
        if lp.iter().any(|&v| {
            !mesh.vertices[v as usize]
                .coords
                .iter()
                .all(|c| c.is_finite())
        }) {
            return Err(Error::Geometry(format!(
                "boundary loop {li} has a vertex with a non-finite coordinate"
            )));
        }
        let h = loop_target(lp);
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::Geometry(format!(
                "boundary loop {li} ({} vertices) has zero length; cannot cap it",
                lp.len()
            )));
        }
    }

    // Collapse degenerate rim edges.
    let mut work = weld::Working::new(nv, &mesh.faces);
    if opts.rim_weld_fraction > 0.0 {
        let mut on_loops: HashMap<u32, usize> = HashMap::new();
        for &v in loops.iter().flatten() {
            *on_loops.entry(v).or_insert(0) += 1;
        }
        for (li, lp) in loops.iter_mut().enumerate() {
            let min_len = opts.rim_weld_fraction * loop_target(lp);
            let n0 = lp.len();
            let (merged, removed) =
                weld::collapse_short_rim_edges(&mesh.vertices, &mut work, lp, min_len, &on_loops);
            if !merged.is_empty() {
                report.messages.push(format!(
                    "loop {li} ({n0} vertices): merged {} rim vertices into a neighbour closer than {min_len:.3e} \
                     ({} × the target edge length), removing {} sliver triangles",
                    merged.len(),
                    opts.rim_weld_fraction,
                    removed.len()
                ));
            }
            report.welded_rim_vertices.extend(merged);
            report.removed_faces.extend(removed);
            let n1 = lp.len();
            let ears = weld::cut_sliver_ears(&mesh.vertices, &mut work, lp, min_len, &on_loops);
            if !ears.is_empty() {
                report.messages.push(format!(
                    "loop {li} ({n1} vertices): cut off {} sliver triangle(s) with two rim edges whose middle vertex lies within {min_len:.3e} of the line through its neighbours",
                    ears.len()
                ));
            }
            report.removed_faces.extend(ears);
        }
        report.removed_faces.sort_unstable();
    }
    let kept_faces: Vec<[u32; 3]> = (0..work.faces.len())
        .filter(|&f| work.alive[f])
        .map(|f| work.faces[f])
        .collect();
    let base_faces = kept_faces.len();
    let mut out = TriMesh::new(mesh.vertices.clone(), kept_faces);
    let mut edges: HashSet<(u32, u32)> = HashSet::new();
    for f in &out.faces {
        for k in 0..3 {
            edges.insert(ekey(f[k], f[(k + 1) % 3]));
        }
    }

    // Every cycle to cap (a loop that passes twice through a vertex is split into cycles).
    let mut jobs: Vec<(usize, Vec<u32>, f64)> = Vec::new();
    for (li, lp) in loops.iter().enumerate() {
        let cycles = split_at_repeated_vertices(lp);
        if cycles.len() > 1 {
            report.messages.push(format!(
                "loop {li} ({} vertices) passes more than once through a vertex; capped as {} separate loops",
                lp.len(),
                cycles.len()
            ));
        }
        for cyc in cycles {
            if cyc.len() < 3 {
                return Err(Error::Geometry(format!(
                    "boundary loop {li} has a part with only {} distinct vertex(es) (a triangle with a repeated vertex?); cannot cap it",
                    cyc.len()
                )));
            }
            let h = loop_target(&cyc);
            if !(h.is_finite() && h > 0.0) {
                return Err(Error::Geometry(format!(
                    "boundary loop {li} ({} vertices) has zero length; cannot cap it",
                    cyc.len()
                )));
            }
            jobs.push((li, cyc, h));
        }
    }
    let cap_job = |(li, cyc, h): &(usize, Vec<u32>, f64), edges: &HashSet<(u32, u32)>| {
        let pts: Vec<Point3<f64>> = cyc.iter().map(|&v| mesh.vertices[v as usize]).collect();
        let mut messages = Vec::new();
        let (patch, method) = cap_one(*li, cyc, &pts, *h, opts, edges, &mut messages);
        (patch, method, messages)
    };
    // Cycles that share no vertex are capped independently (a cap's new edges join its own
    // rim's vertices only), so in parallel; the others one after another, each seeing the edges
    // of the caps before it.
    let mut seen = HashSet::new();
    let disjoint = jobs
        .iter()
        .all(|(_, cyc, _)| cyc.iter().all(|&v| seen.insert(v)));
    let mut done: Vec<Option<_>> = if disjoint {
        jobs.par_iter().map(|j| Some(cap_job(j, &edges))).collect()
    } else {
        (0..jobs.len()).map(|_| None).collect()
    };
    for (k, job) in jobs.iter().enumerate() {
        let (patch, method, messages) = done[k].take().unwrap_or_else(|| cap_job(job, &edges));
        let (li, cyc, h) = job;
        report.messages.extend(messages);
        if method != CapMethod::PlanarCdt && report.fallback_loops.last() != Some(li) {
            report.fallback_loops.push(*li);
        }
        report.loops.push(append_patch(
            &mut out, &mut edges, *li, cyc, *h, method, &patch,
        ));
    }
    report.loops_capped += loops.len();

    report.vertices_added = out.num_vertices() - nv;
    report.faces_added = out.num_faces() - base_faces;
    report.cap_faces = base_faces..out.num_faces();
    report.max_cap_aspect_ratio = report
        .loops
        .iter()
        .map(|l| l.max_aspect_ratio)
        .fold(0.0, f64::max);
    if opts.orient_outward && signed_volume(&out) < 0.0 {
        out.flip_faces();
        report.flipped = true;
    }
    Ok((out, report))
}

/// Caps one simple loop: planar CDT when possible, the fallback otherwise.
fn cap_one(
    li: usize,
    cyc: &[u32],
    pts: &[Point3<f64>],
    h: f64,
    opts: &CapOptions,
    edges: &HashSet<(u32, u32)>,
    messages: &mut Vec<String>,
) -> (Patch, CapMethod) {
    let n = cyc.len();
    // A chord between rim vertices i and j must not duplicate an existing edge.
    let chord_taken = |i: usize, j: usize| edges.contains(&ekey(cyc[i], cyc[j]));
    let max_new = opts.max_vertices_per_cap;
    let reason = match planar::cap_planar(pts, h, opts.min_angle_deg, max_new, &chord_taken) {
        Ok(planar::PlanarCap { patch, complete }) => {
            if !complete {
                messages.push(format!(
                    "loop {li} ({n} vertices): cap refinement stopped at its vertex budget; the cap is coarser than the target"
                ));
            }
            return (patch, CapMethod::PlanarCdt);
        }
        Err(reason) => reason,
    };
    let (patch, method, how) =
        fill::cap_fill(pts, h, opts.max_dp_loop_vertices, max_new, &chord_taken);
    messages.push(format!("loop {li} ({n} vertices): {reason}; {how}"));
    (patch, method)
}

/// Appends a patch to the mesh (rim vertices are the loop's own indices) and measures it.
fn append_patch(
    out: &mut TriMesh,
    edges: &mut HashSet<(u32, u32)>,
    li: usize,
    cyc: &[u32],
    h: f64,
    method: CapMethod,
    patch: &Patch,
) -> LoopCap {
    let n = cyc.len();
    let base = out.num_vertices() as u32;
    out.vertices.extend_from_slice(&patch.new_points);
    let global = |i: usize| if i < n { cyc[i] } else { base + (i - n) as u32 };
    let rim: HashSet<(u32, u32)> = (0..n).map(|i| ekey(cyc[i], cyc[(i + 1) % n])).collect();
    // Ordered, so the reported mean is the same to the last digit on every run.
    let mut inner_edges: std::collections::BTreeSet<(u32, u32)> = Default::default();
    let mut max_ar: f64 = 0.0;
    for f in &patch.faces {
        let g = [global(f[0]), global(f[1]), global(f[2])];
        out.faces.push(g);
        let [a, b, c] = out.triangle(out.num_faces() - 1);
        max_ar = max_ar.max(triangle_aspect_ratio(&a, &b, &c));
        for k in 0..3 {
            let e = ekey(g[k], g[(k + 1) % 3]);
            edges.insert(e);
            if !rim.contains(&e) {
                inner_edges.insert(e);
            }
        }
    }
    let mean_inner = if inner_edges.is_empty() {
        0.0
    } else {
        inner_edges
            .iter()
            .map(|&(a, b)| (out.vertices[a as usize] - out.vertices[b as usize]).norm())
            .sum::<f64>()
            / inner_edges.len() as f64
    };
    LoopCap {
        loop_index: li,
        rim_vertices: n,
        target_edge_length: h,
        vertices_added: patch.new_points.len(),
        faces_added: patch.faces.len(),
        method,
        max_aspect_ratio: max_ar,
        mean_inner_edge_length: mean_inner,
    }
}

/// Splits a closed vertex chain that passes more than once through a vertex into simple cycles,
/// each keeping the chain's edges and direction.
fn split_at_repeated_vertices(lp: &[u32]) -> Vec<Vec<u32>> {
    let mut cycles = Vec::new();
    let mut stack: Vec<u32> = Vec::with_capacity(lp.len());
    let mut pos: HashMap<u32, usize> = HashMap::new();
    for &v in lp {
        if let Some(&p) = pos.get(&v) {
            let sub: Vec<u32> = stack[p..].to_vec();
            for w in &stack[p + 1..] {
                pos.remove(w);
            }
            stack.truncate(p + 1);
            cycles.push(sub);
        } else {
            pos.insert(v, stack.len());
            stack.push(v);
        }
    }
    if !stack.is_empty() {
        cycles.push(stack);
    }
    cycles
}

#[cfg(test)]
mod tests {
    use super::split_at_repeated_vertices;

    #[test]
    fn figure_eight_loop_splits_into_two_cycles() {
        let c = split_at_repeated_vertices(&[1, 2, 9, 3, 4, 9, 5]);
        assert_eq!(c, vec![vec![9, 3, 4], vec![1, 2, 9, 5]]);
        assert_eq!(split_at_repeated_vertices(&[1, 2, 3]), vec![vec![1, 2, 3]]);
    }
}
