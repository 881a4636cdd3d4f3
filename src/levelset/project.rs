//! Projection of an extracted surface's vertices onto the surface it was voxelized from, so a
//! re-meshed surface lies on the input instead of on the linear interpolation of φ between grid
//! nodes (the "feature-aware" finish of marching cubes). Only vertices move: the triangles, and
//! so the closedness and manifoldness of the extraction, are kept. A vertex stays where it is
//! when its closest input point is farther than `max_distance`, lies on the rim of an open end
//! (the extraction closes open ends; those sheets have nothing to be projected on), or when the
//! move would turn a triangle around or flatten it.

use crate::bvh::MeshBvh;
use crate::mesh::topology::EdgeMap;
use crate::TriMesh;
use nalgebra::Point3;
use rayon::prelude::*;
use std::collections::HashSet;

/// Options of [`project_vertices`].
#[derive(Debug, Clone, Copy)]
pub struct ProjectOptions {
    /// Farthest a vertex may move, in world units (typically one voxel).
    pub max_distance: f64,
    /// A move is refused when a triangle's normal would turn by more than this angle (degrees)
    /// or its area would fall below `min_area_ratio` of what it was.
    pub max_turn_deg: f64,
    /// See `max_turn_deg`.
    pub min_area_ratio: f64,
}

impl Default for ProjectOptions {
    fn default() -> Self {
        ProjectOptions {
            max_distance: f64::INFINITY,
            max_turn_deg: 60.0,
            min_area_ratio: 0.05,
        }
    }
}

/// Moves each vertex of `mesh` to its closest point on `target` (see the module doc); returns
/// how many vertices moved. `target_mesh` is the mesh `target` was built from (its open rims
/// are found from it).
pub fn project_vertices(
    mesh: &mut TriMesh,
    target_mesh: &TriMesh,
    target: &MeshBvh,
    opts: &ProjectOptions,
) -> usize {
    let target = ProjectionTarget::new(target_mesh, target);
    let proposed: Vec<Option<Point3<f64>>> = mesh
        .vertices
        .par_iter()
        .map(|v| target.closest_off_rim(v, opts.max_distance))
        .collect();
    let original = mesh.vertices.clone();
    let mut moved: Vec<bool> = proposed.iter().map(Option::is_some).collect();
    for (v, p) in mesh.vertices.iter_mut().zip(&proposed) {
        if let Some(p) = p {
            *v = *p;
        }
    }
    // Undo moves that turn or flatten a triangle, until none does.
    let cos_limit = opts.max_turn_deg.to_radians().cos();
    loop {
        let bad: Vec<usize> = (0..mesh.num_faces())
            .into_par_iter()
            .filter(|&f| {
                let [a, b, c] = mesh.faces[f].map(|i| i as usize);
                if !(moved[a] || moved[b] || moved[c]) {
                    return false;
                }
                let old = (original[b] - original[a]).cross(&(original[c] - original[a]));
                let new = mesh.face_normal_raw(f);
                let (lo, ln) = (old.norm(), new.norm());
                ln < opts.min_area_ratio * lo || new.dot(&old) < cos_limit * lo * ln
            })
            .collect();
        if bad.is_empty() {
            break;
        }
        for f in bad {
            for v in mesh.faces[f] {
                let v = v as usize;
                moved[v] = false;
                mesh.vertices[v] = original[v];
            }
        }
    }
    moved.iter().filter(|&&m| m).count()
}

/// The surface vertices are projected onto: its BVH and the rim edges of its open ends.
pub(crate) struct ProjectionTarget<'a> {
    mesh: &'a TriMesh,
    bvh: &'a MeshBvh,
    rim: HashSet<(u32, u32)>,
}

impl<'a> ProjectionTarget<'a> {
    pub(crate) fn new(mesh: &'a TriMesh, bvh: &'a MeshBvh) -> Self {
        ProjectionTarget {
            mesh,
            bvh,
            rim: rim_edges(mesh),
        }
    }

    /// The closest point of the target to `p` when it is within `max_distance` and not on the
    /// rim of an open end.
    pub(crate) fn closest_off_rim(
        &self,
        p: &Point3<f64>,
        max_distance: f64,
    ) -> Option<Point3<f64>> {
        let c = self.bvh.closest_point_within(p, max_distance)?;
        let [a, b, cc] = self.mesh.faces[c.face as usize];
        // On a rim edge when the barycentric weight of the opposite corner vanishes.
        let on_rim = [(b, cc, 0), (cc, a, 1), (a, b, 2)]
            .iter()
            .any(|&(u, w, k)| c.bary[k] <= 1e-9 && self.rim.contains(&(u.min(w), u.max(w))));
        (!on_rim).then_some(c.point)
    }
}

/// Undirected boundary edges (used by exactly one triangle) of `mesh`.
fn rim_edges(mesh: &TriMesh) -> HashSet<(u32, u32)> {
    let map = EdgeMap::new(mesh);
    (0..map.num_edges())
        .filter(|&e| map.valence(e) == 1)
        .map(|e| {
            let [u, v] = map.edges()[e];
            (u.min(v), u.max(v))
        })
        .collect()
}
