//! `--holes`: telling the holes of a vessel mesh from its open vessel ends, and one ball of the
//! damaged region D per hole (paper Section 4: D is where the surface is missing; the open ends
//! where a vessel was cut are not damage and must stay open).
//!
//! Each boundary loop ([`crate::mesh::topology::boundary_loops`]) gets a best-fit plane (the
//! least-variance direction of its vertices about their centroid). A vessel end is a cut across
//! the vessel: the loop is nearly planar and its plane is roughly perpendicular to the vessel axis,
//! so the wall next to it has normals lying in the loop's plane (|wall normal · plane normal| near
//! 0). A hole in the wall has the wall's normals along its plane normal (near 1), or is not planar
//! at all. Anything that is not a clear end is a hole.
//!
//! An end that is planar only roughly (a "rough end": segmentations are clipped by planes, damage
//! is not) may be a cut the damage made through the whole vessel, and so may a loop too far off
//! its plane for an end whose wall runs across that plane as an end's does
//! ([`LoopInfo::may_be_cut`]). Where its pieces are kept, two or more such loops face each other
//! across a short gap ([`gap_groups`]): that gap is a region of its own ([`gap_regions`]), which
//! the fill bridges as it bridges an occlusion.

use super::groups::linked_groups;
use crate::inpaint::region::Ball;
use crate::mesh::topology::{boundary_loops, connected_components};
use crate::mesh::TriMesh;
use crate::{Error, Result};
use nalgebra::{Matrix3, Point3, Vector3};

/// What a boundary loop is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopKind {
    /// An open vessel end (a planar cut across the vessel): left open.
    End,
    /// A hole in the surface: to be repaired.
    Hole,
}

/// Thresholds of [`classify_loops`] and the ball size of [`hole_regions`] (all dimensionless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopOptions {
    /// Largest off-plane distance of an end's vertices from their best-fit plane, as a fraction of
    /// the loop's radius (mean vertex distance to the centroid).
    pub planarity_tolerance: f64,
    /// Largest mean |wall normal · loop plane normal| of an end (the wall of the faces touching
    /// the loop, area-weighted): 0 for a cut exactly across a straight tube, near 1 for a hole in
    /// a wall. 0.5 accepts cuts up to about 30° oblique.
    pub max_wall_alignment: f64,
    /// A hole's ball radius is this factor × the largest distance of a loop vertex from the
    /// centroid, plus one mean loop edge length.
    pub ball_factor: f64,
}

impl Default for LoopOptions {
    fn default() -> Self {
        LoopOptions {
            planarity_tolerance: 0.2,
            max_wall_alignment: 0.5,
            ball_factor: 1.25,
        }
    }
}

/// An open vessel end whose vertices lie farther than this fraction of its radius from their
/// best-fit plane is named in a notice of `repair --holes`: segmentations are clipped by planes
/// (the 423 other open ends that `--holes` met on the 195 chops of `benches/repair_real`'s
/// seeds 21–33: within 1.1 × 10⁻⁴ of their radius), a vessel cut through by damage is not (the
/// carotid severed at its junction by the chops of seeds 31 and 33, its branches gone: 0.19 and
/// 0.20, taken for an end and capped without a word before).
pub const ROUGH_END_PLANARITY: f64 = 0.05;

/// Two loops that may be a cut's sides ([`LoopInfo::may_be_cut`]) whose centroids lie within
/// this many sums of their radii, each facing the other ([`GAP_FACING`]), are taken for one
/// vessel cut in two by the damage, its pieces kept: `--holes` bridges the gap between them
/// ([`gap_balls`]).
pub const GAP_REACH: f64 = 3.0;

/// How squarely two sides of a gap face each other: the cosine between each one's plane
/// normal and the line joining their centroids is at least this (a severed junction's daughters
/// leave the parent's axis by 20–40°).
pub const GAP_FACING: f64 = 0.7;

/// A loop taken for a hole may still be one side of a cut through the vessel (its pieces kept)
/// when it lies within this fraction of its radius off its plane: the balls of 2.2 vessel radii
/// of `benches/repair_real -- --shapes` that cut a vessel in two left loops 0.20–0.32 off their
/// planes, taken for holes, each then filled alone as a dead end: the vessel stayed in two
/// pieces (5 of its 15 such cases). A loop that wraps a junction, the aorta cut with one iliac
/// (0.46 and 0.63), is no single vessel's cut: bridged as a gap to the other iliac's end, the
/// fill followed the aorta alone and left that iliac apart.
pub const CUT_MAX_PLANARITY: f64 = 0.4;

/// A loop taken for a hole is a cut's side only where the wall beside it runs across its plane
/// as beside an open end (the area-weighted |wall normal · plane normal| at most this, the
/// default [`LoopOptions::max_wall_alignment`]): the cut loops of that study's big balls read
/// 0.28–0.44, the loops wrapping the capped aorta's junction 0.52 and 0.58; a hole in a wall
/// reads near 1, so two vessels side by side, each with a hole facing the other, are no gap.
pub const CUT_MAX_WALL_ALIGNMENT: f64 = 0.5;

/// One boundary loop and its classification.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopInfo {
    /// End or hole.
    pub kind: LoopKind,
    /// The loop's vertices in order (as [`boundary_loops`] gives them).
    pub vertices: Vec<u32>,
    /// Centroid of the loop's vertices (world units).
    pub center: Point3<f64>,
    /// Unit normal of the best-fit plane (sign arbitrary).
    pub normal: Vector3<f64>,
    /// Mean distance of the loop's vertices to the centroid (world units).
    pub radius: f64,
    /// Largest distance of a loop vertex to the centroid (world units).
    pub max_distance: f64,
    /// Mean length of the loop's edges (world units).
    pub mean_edge: f64,
    /// Largest off-plane distance of a vertex / `radius` (dimensionless).
    pub planarity: f64,
    /// Area-weighted mean |face normal · `normal`| over the faces touching the loop (0..1).
    pub wall_alignment: f64,
}

impl LoopInfo {
    /// Taken for an open vessel end, but not planar as a clipped end is
    /// ([`ROUGH_END_PLANARITY`]): perhaps a cut made by the damage.
    pub fn is_rough_end(&self) -> bool {
        self.kind == LoopKind::End && self.planarity > ROUGH_END_PLANARITY
    }

    /// May be one side of a cut the damage made through the vessel: a rough end, or a loop
    /// taken for a hole that lies within [`CUT_MAX_PLANARITY`] of its radius off its plane (a
    /// ball through a tube leaves a saddle beyond an end's
    /// [`LoopOptions::planarity_tolerance`]) with the wall beside it running across that plane
    /// as beside an end ([`CUT_MAX_WALL_ALIGNMENT`]; a hole in a wall has the wall along it).
    /// Only loops on different pieces of the mesh that face each other are then taken for a gap
    /// ([`gap_groups`]).
    pub fn may_be_cut(&self) -> bool {
        self.is_rough_end()
            || (self.kind == LoopKind::Hole
                && self.planarity <= CUT_MAX_PLANARITY
                && self.wall_alignment <= CUT_MAX_WALL_ALIGNMENT)
    }
}

/// Finds and classifies every boundary loop of `mesh` (see the module docs), in the order of
/// [`boundary_loops`]. Loops of fewer than three vertices or of zero size are holes.
pub fn classify_loops(mesh: &TriMesh, options: &LoopOptions) -> Vec<LoopInfo> {
    let loops = boundary_loops(mesh);
    if loops.is_empty() {
        return Vec::new();
    }
    // Faces touching each vertex, for the wall next to each loop.
    let mut vertex_faces: Vec<Vec<u32>> = vec![Vec::new(); mesh.num_vertices()];
    for (f, tri) in mesh.faces.iter().enumerate() {
        for &v in tri {
            if let Some(list) = vertex_faces.get_mut(v as usize) {
                list.push(f as u32);
            }
        }
    }
    loops
        .into_iter()
        .map(|vs| describe_loop(mesh, &vertex_faces, vs, options))
        .collect()
}

/// Measures one loop and classifies it.
fn describe_loop(
    mesh: &TriMesh,
    vertex_faces: &[Vec<u32>],
    vertices: Vec<u32>,
    options: &LoopOptions,
) -> LoopInfo {
    let pts: Vec<Point3<f64>> = vertices
        .iter()
        .map(|&v| mesh.vertices[v as usize])
        .collect();
    let n = pts.len().max(1) as f64;
    let center = Point3::from(pts.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n);
    let mut cov = Matrix3::zeros();
    for p in &pts {
        let d = p - center;
        cov += d * d.transpose();
    }
    let eig = cov.symmetric_eigen();
    let normal = eig
        .eigenvectors
        .column(eig.eigenvalues.imin())
        .into_owned()
        .try_normalize(0.0)
        .unwrap_or_else(Vector3::z);
    let dists: Vec<f64> = pts.iter().map(|p| (p - center).norm()).collect();
    let radius = dists.iter().sum::<f64>() / n;
    let max_distance = dists.iter().cloned().fold(0.0, f64::max);
    let off_plane = pts
        .iter()
        .map(|p| (p - center).dot(&normal).abs())
        .fold(0.0, f64::max);
    let planarity = if radius > 0.0 {
        off_plane / radius
    } else {
        f64::INFINITY
    };
    let mean_edge = (0..pts.len())
        .map(|i| (pts[(i + 1) % pts.len()] - pts[i]).norm())
        .sum::<f64>()
        / n;

    let mut faces: Vec<u32> = vertices
        .iter()
        .flat_map(|&v| vertex_faces[v as usize].iter().copied())
        .collect();
    faces.sort_unstable();
    faces.dedup();
    let (mut weighted, mut total) = (0.0, 0.0);
    for &f in &faces {
        let raw = mesh.face_normal_raw(f as usize);
        let area = raw.norm();
        if area > 0.0 {
            weighted += raw.dot(&normal).abs();
            total += area;
        }
    }
    let wall_alignment = if total > 0.0 { weighted / total } else { 1.0 };

    let is_end = pts.len() >= 3
        && planarity <= options.planarity_tolerance
        && wall_alignment <= options.max_wall_alignment;
    LoopInfo {
        kind: if is_end {
            LoopKind::End
        } else {
            LoopKind::Hole
        },
        vertices,
        center,
        normal,
        radius,
        max_distance,
        mean_edge,
        planarity,
        wall_alignment,
    }
}

/// The damaged region of `--holes`: one ball per [`LoopKind::Hole`] loop, centred on the loop's
/// centroid with radius `ball_factor` × its largest vertex distance + one mean loop edge, and
/// every loop's description. A mesh without boundary loops, or whose loops are all vessel ends,
/// is an error saying so.
pub fn hole_regions(mesh: &TriMesh, options: &LoopOptions) -> Result<(Vec<Ball>, Vec<LoopInfo>)> {
    let loops = classify_loops(mesh, options);
    let balls = hole_balls(&loops, options)?;
    Ok((balls, loops))
}

/// The balls of [`hole_regions`] for loops [`classify_loops`] already gave: an error when there
/// are no loops or no hole among them.
pub fn hole_balls(loops: &[LoopInfo], options: &LoopOptions) -> Result<Vec<Ball>> {
    if loops.is_empty() {
        return Err(Error::Geometry("mesh has no boundary loops".into()));
    }
    let balls: Vec<Ball> = loops
        .iter()
        .filter(|l| l.kind == LoopKind::Hole)
        .map(|l| Ball {
            center: l.center,
            radius: options.ball_factor * l.max_distance + l.mean_edge,
        })
        .collect();
    if balls.is_empty() {
        return Err(Error::Geometry(format!(
            "mesh has no holes ({} boundary loops, all open vessel ends)",
            loops.len()
        )));
    }
    Ok(balls)
}

/// The groups of rough ends and cut-like holes ([`LoopInfo::may_be_cut`]) that face each other
/// across a short gap ([`GAP_REACH`], [`GAP_FACING`]), joined through shared members (a
/// junction severed from its branches, every piece kept, gives a group of three): each a vessel
/// cut in two or more by the damage. Clipped ends lie within 10⁻⁴ of their plane and never join
/// one; nor do two loops of one connected piece of `mesh` (a short vessel between two rough
/// cuts: what lies between its ends is that vessel, not a gap). Indices into `loops`, in order;
/// a loop with no partner is in no group.
pub fn gap_groups(mesh: &TriMesh, loops: &[LoopInfo]) -> Vec<Vec<usize>> {
    let cuts: Vec<usize> = (0..loops.len())
        .filter(|&i| loops[i].may_be_cut())
        .collect();
    if cuts.len() < 2 {
        return Vec::new();
    }
    // The piece of each vertex (that of a face holding it).
    let (_, labels) = connected_components(mesh);
    let mut piece = vec![u32::MAX; mesh.num_vertices()];
    for (f, &l) in mesh.faces.iter().zip(&labels) {
        for &v in f {
            piece[v as usize] = l;
        }
    }
    let piece_of = |l: &LoopInfo| l.vertices.first().map(|&v| piece[v as usize]);
    let faces = |a: &LoopInfo, b: &LoopInfo| {
        if piece_of(a) == piece_of(b) {
            return false;
        }
        let d = b.center - a.center;
        let len = d.norm();
        len > 0.0
            && len <= GAP_REACH * (a.radius + b.radius)
            && (a.normal.dot(&d) / len).abs() >= GAP_FACING
            && (b.normal.dot(&d) / len).abs() >= GAP_FACING
    };
    linked_groups(cuts.len(), |i, j| faces(&loops[cuts[i]], &loops[cuts[j]]))
        .into_iter()
        .filter(|g| g.len() >= 2)
        .map(|g| g.into_iter().map(|i| cuts[i]).collect())
        .collect()
}

/// The gaps of `--holes`: the groups of [`gap_groups`] with their balls ([`gap_balls`]), but
/// those whose ball holds the centroid of a loop outside the group. A cut next to a clipped end
/// leaves a stub between them (the carotid's and the aneurysm's short branches cut through 2 mm
/// from their ends, `benches/repair_real -- --shapes`): the stub gives the fill no anchor, which
/// then closed the stub as a dead end and lost volume in D; such a cut is left as it is, with
/// the rough end's notice.
pub fn gap_regions(
    mesh: &TriMesh,
    loops: &[LoopInfo],
    options: &LoopOptions,
) -> (Vec<Vec<usize>>, Vec<Ball>) {
    let groups = gap_groups(mesh, loops);
    let balls = gap_balls(mesh, loops, &groups, options);
    groups
        .into_iter()
        .zip(balls)
        .filter(|(g, b)| {
            (0..loops.len())
                .filter(|i| !g.contains(i))
                .all(|i| !b.contains(&loops[i].center))
        })
        .unzip()
}

/// One ball per gap group ([`gap_groups`]): centred on the mean of its loops' centroids, with
/// radius `ball_factor` × the largest distance of a loop vertex from that centre plus the loops'
/// mean edge, so that the gap and both cut ends lie inside it (as a hole's ball holds its loop).
pub fn gap_balls(
    mesh: &TriMesh,
    loops: &[LoopInfo],
    groups: &[Vec<usize>],
    options: &LoopOptions,
) -> Vec<Ball> {
    groups
        .iter()
        .map(|g| {
            let center = Point3::from(
                g.iter()
                    .map(|&i| loops[i].center.coords)
                    .sum::<Vector3<f64>>()
                    / g.len() as f64,
            );
            let farthest = g
                .iter()
                .flat_map(|&i| loops[i].vertices.iter())
                .map(|&v| (mesh.vertices[v as usize] - center).norm())
                .fold(0.0, f64::max);
            let edge = g.iter().map(|&i| loops[i].mean_edge).sum::<f64>() / g.len() as f64;
            Ball {
                center,
                radius: options.ball_factor * farthest + edge,
            }
        })
        .collect()
}
