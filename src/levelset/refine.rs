//! Adaptive refinement of an extracted surface towards the surface it was voxelized from.
//!
//! After [`super::project::project_vertices`] the vertices of a marching-cubes surface lie on the
//! input, but its flat triangles still cut the chords of curved parts: on a vessel of radius R a
//! triangle of edge e leaves a gap of about e²/8R, which at coarse voxels is several hundredths of
//! a voxel. Each pass here splits the edges whose midpoint is farther than a tolerance from the
//! input and puts the new vertex on the input (its closest point), with the usual conforming
//! red–green templates (one, two or three split edges per triangle; the quadrilateral of the
//! two-edge case is cut along its shorter diagonal). Splitting an edge inserts one vertex shared
//! by both of its triangles, so a closed, manifold, consistently oriented surface stays so. A
//! split is withdrawn when one of the new triangles would turn by more than the allowed angle
//! against its parent or become a sliver, as in the projection step.

use super::project::ProjectionTarget;
use crate::bvh::MeshBvh;
use crate::mesh::topology::EdgeMap;
use crate::TriMesh;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Options of [`refine_to_surface`].
#[derive(Debug, Clone, Copy)]
pub struct RefineOptions {
    /// An edge is split when its midpoint is farther than this from the input (world units;
    /// `remesh` uses 0.05 voxel).
    pub tolerance: f64,
    /// Edges whose midpoint's closest input point is farther than this are left alone (world
    /// units; `remesh` uses one voxel).
    pub max_distance: f64,
    /// Edges shorter than this are never split (world units; `remesh` uses 0.1 voxel).
    pub min_edge: f64,
    /// Number of passes; each can halve the edges it splits.
    pub passes: usize,
    /// A split is withdrawn when a new triangle's normal turns by more than this angle (degrees)
    /// from its parent's.
    pub max_turn_deg: f64,
    /// ... or when its area falls below this fraction of its parent's area divided by the number
    /// of children.
    pub min_area_ratio: f64,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            tolerance: 0.0,
            max_distance: f64::INFINITY,
            min_edge: 0.0,
            passes: 2,
            max_turn_deg: 45.0,
            min_area_ratio: 0.05,
        }
    }
}

/// The options `remesh` uses on a grid of voxel `h` (world units).
pub fn remesh_refine_options(h: f64) -> RefineOptions {
    RefineOptions {
        tolerance: 0.05 * h,
        max_distance: h,
        min_edge: 0.1 * h,
        // The children of a triangle that cuts a crease (the rim of a capped open end, a right
        // angle, which marching cubes rounds off) land on its two sides and turn by up to 90°
        // less the triangle's tilt: 85° lets the crease come back; folds (beyond 90°) and
        // slivers are still refused. (At 45° the rims stayed 0.6–0.8 voxel off the input.)
        max_turn_deg: 85.0,
        ..Default::default()
    }
}

/// What [`refine_to_surface`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct RefineReport {
    /// Edges split over all passes.
    pub edges_split: usize,
    /// Passes that split at least one edge.
    pub passes: usize,
}

/// Splits the edges of `mesh` whose midpoints are farther than `opts.tolerance` from `target`
/// (see the module doc). `target_mesh` is the mesh `target` was built from.
pub fn refine_to_surface(
    mesh: &mut TriMesh,
    target_mesh: &TriMesh,
    target: &MeshBvh,
    opts: &RefineOptions,
) -> RefineReport {
    let target = ProjectionTarget::new(target_mesh, target);
    let mut report = RefineReport::default();
    for _ in 0..opts.passes {
        let split = split_pass(mesh, &target, opts);
        if split == 0 {
            break;
        }
        report.edges_split += split;
        report.passes += 1;
    }
    report
}

/// One pass; returns the number of edges split.
fn split_pass(mesh: &mut TriMesh, target: &ProjectionTarget, opts: &RefineOptions) -> usize {
    let map = EdgeMap::new(mesh);
    let verts = &mesh.vertices;
    // New vertex per edge, where the edge is to be split.
    let mut new_point: Vec<Option<Point3<f64>>> = map
        .edges()
        .par_iter()
        .map(|&[u, v]| {
            let (a, b) = (verts[u as usize], verts[v as usize]);
            if (b - a).norm() < opts.min_edge {
                return None;
            }
            let mid = nalgebra::center(&a, &b);
            let c = target.closest_off_rim(&mid, opts.max_distance)?;
            ((c - mid).norm() > opts.tolerance).then_some(c)
        })
        .collect();
    let face_edges: Vec<[usize; 3]> = (0..mesh.num_faces())
        .map(|f| [0, 1, 2].map(|k| map.face_edge(f, k).unwrap_or(usize::MAX)))
        .collect();
    drop(map);
    // Withdraw splits that would turn or flatten a child triangle, until none does.
    let cos_limit = opts.max_turn_deg.to_radians().cos();
    loop {
        let bad: Vec<usize> = (0..mesh.num_faces())
            .into_par_iter()
            .filter(|&f| {
                let children =
                    split_face_shortest(mesh.faces[f], face_edges[f], &new_point, &mesh.vertices);
                if children.len() == 1 {
                    return false;
                }
                let pos = |c: Corner| match c {
                    Corner::Old(v) => mesh.vertices[v as usize],
                    Corner::New(e) => new_point[e].expect("split edge"),
                };
                let parent = mesh.face_normal_raw(f);
                let parent_area = parent.norm();
                let min_area = opts.min_area_ratio * parent_area / children.len() as f64;
                children.iter().any(|t| {
                    let [a, b, c] = t.map(pos);
                    let n: Vector3<f64> = (b - a).cross(&(c - a));
                    let ln = n.norm();
                    ln < min_area || n.dot(&parent) < cos_limit * ln * parent_area
                })
            })
            .collect();
        if bad.is_empty() {
            break;
        }
        for f in bad {
            for e in face_edges[f] {
                if e != usize::MAX {
                    new_point[e] = None;
                }
            }
        }
    }
    // Number the new vertices and rebuild the faces.
    let mut index = vec![u32::MAX; new_point.len()];
    let mut split = 0;
    for (e, p) in new_point.iter().enumerate() {
        if let Some(p) = p {
            index[e] = mesh.vertices.len() as u32;
            mesh.vertices.push(*p);
            split += 1;
        }
    }
    if split == 0 {
        return 0;
    }
    let faces = std::mem::take(&mut mesh.faces);
    let lookup = |e: usize| index[e];
    let verts = &mesh.vertices;
    let mut out = Vec::with_capacity(faces.len() + 3 * split);
    for (f, face) in faces.iter().enumerate() {
        for t in split_face_shortest(*face, face_edges[f], &new_point, verts) {
            out.push(t.map(|c| match c {
                Corner::Old(v) => v,
                Corner::New(e) => lookup(e),
            }));
        }
    }
    mesh.faces = out;
    split
}

/// A corner of a child triangle: an old vertex or the new vertex of an edge.
#[derive(Debug, Clone, Copy)]
enum Corner {
    Old(u32),
    New(usize),
}

/// The children of `face` for the split edges among `edges` (edge k runs from corner k to
/// corner k+1). `diagonal` picks, in the two-edge case, which diagonal of the quadrilateral to
/// cut (0 or 1; see [`split_face_shortest`]).
fn split_face(
    face: [u32; 3],
    edges: [usize; 3],
    new_point: &[Option<Point3<f64>>],
    diagonal: &dyn Fn(&[Corner; 4]) -> usize,
) -> Vec<[Corner; 3]> {
    let is_split = |k: usize| edges[k] != usize::MAX && new_point[edges[k]].is_some();
    let v = |k: usize| Corner::Old(face[k % 3]);
    let m = |k: usize| Corner::New(edges[k % 3]);
    let marked: Vec<usize> = (0..3).filter(|&k| is_split(k)).collect();
    match marked.as_slice() {
        [] => vec![[v(0), v(1), v(2)]],
        &[k] => vec![[v(k), m(k), v(k + 2)], [m(k), v(k + 1), v(k + 2)]],
        &[a, b] => {
            // The unsplit edge is k+2 → k: split edges k (k→k+1) and k+1 (k+1→k+2).
            let k = if b == a + 1 { a } else { b };
            let quad = [v(k), m(k), m(k + 1), v(k + 2)];
            let mut out = vec![[m(k), v(k + 1), m(k + 1)]];
            if diagonal(&quad) == 0 {
                out.push([quad[0], quad[1], quad[2]]);
                out.push([quad[0], quad[2], quad[3]]);
            } else {
                out.push([quad[0], quad[1], quad[3]]);
                out.push([quad[1], quad[2], quad[3]]);
            }
            out
        }
        _ => vec![
            [v(0), m(0), m(2)],
            [m(0), v(1), m(1)],
            [m(2), m(1), v(2)],
            [m(0), m(1), m(2)],
        ],
    }
}

/// [`split_face`] cutting the two-edge quadrilateral along its shorter diagonal.
fn split_face_shortest(
    face: [u32; 3],
    edges: [usize; 3],
    new_point: &[Option<Point3<f64>>],
    verts: &[Point3<f64>],
) -> Vec<[Corner; 3]> {
    let pos = |c: &Corner| match *c {
        Corner::Old(v) => verts[v as usize],
        Corner::New(e) => new_point[e].expect("split edge"),
    };
    split_face(face, edges, new_point, &|q: &[Corner; 4]| {
        let d02 = (pos(&q[2]) - pos(&q[0])).norm();
        let d13 = (pos(&q[3]) - pos(&q[1])).norm();
        usize::from(d13 < d02)
    })
}
