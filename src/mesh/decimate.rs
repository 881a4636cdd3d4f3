//! Lean outputs: quadric edge-collapse simplification of a mesh within a distance bound
//! (`--decimate` of `remesh` and `repair`).
//!
//! The collapses are meshoptimizer's (`meshopt::simplify`, Garland–Heckbert quadrics, topology
//! kept, an absolute error limit, vertices kept where they are: the output's vertices are a
//! subset of the input's, in f64). The simplifier's own error is an estimate, so the result is
//! checked: its symmetric Hausdorff distance to the mesh it came from (area samples plus every
//! vertex, [`surface_distance`]) must be within the bound, and a closed manifold input must stay
//! closed and manifold. When the distance check fails, the vertices where the result strays
//! beyond three quarters of the bound (the input's vertices far from it, the corners of its
//! triangles whose centroid or edge midpoints lie far from the input) and a ring around them are
//! locked and the simplifier tries again at the same limit (the bound is usually passed in a few
//! places: the aneurysm's remesh 16,726 faces at a lower limit without locks, 10,844 with them);
//! when nothing new is locked, or the topology check fails, the limit is lowered by a quarter.
//! A failed topology check also locks the vertices of the edges the result tore (edges of more
//! than two triangles, where collapses brought two sheets together) and a ring around them: the
//! aneurysm's remesh, whose open ends come out with sharp rims, tore at every limit above the
//! one that kept 34,104 faces without these locks, and keeps 6,506 with them. After a few tries
//! the mesh is given back unchanged.

use super::distance::{surface_distance, SurfaceDistanceOptions};
use super::info::mesh_info;
use super::measures::bounding_box;
use super::topology::EdgeMap;
use crate::bvh::MeshBvh;
use crate::TriMesh;
use meshopt::{simplify_with_locks_decoder, SimplifyOptions};
use nalgebra::Point3;
use rayon::prelude::*;

/// Options of [`decimate_mesh`].
#[derive(Clone, Debug)]
pub struct DecimateOptions {
    /// Largest Hausdorff distance allowed between the result and the input, world units.
    pub max_distance: f64,
    /// The simplifier's first error limit, as a fraction of `max_distance` (its quadric estimate
    /// runs well below the true distance: on the shared vessels limits of 0.1h to 0.2h give
    /// 0.3h to 0.45h, so it starts under the bound).
    pub first_limit_fraction: f64,
    /// Tries (simplifications checked): after each failed one, vertices are locked or the limit
    /// is multiplied by `shrink`.
    pub tries: usize,
    /// Factor of the limit after a failed check (dimensionless, in (0, 1)).
    pub shrink: f64,
    /// Area samples per surface of the Hausdorff check (every vertex is measured too).
    pub samples: usize,
}

impl Default for DecimateOptions {
    fn default() -> Self {
        DecimateOptions {
            max_distance: 0.0,
            first_limit_fraction: 0.4,
            tries: 8,
            shrink: 0.75,
            samples: 200_000,
        }
    }
}

/// What [`decimate_mesh`] did.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DecimateReport {
    /// Triangles before and after.
    pub faces_before: usize,
    pub faces_after: usize,
    /// The Hausdorff distance of the result to the input, world units (0 when unchanged).
    pub hausdorff: f64,
    /// The bound it was held to, world units.
    pub max_distance: f64,
    /// The simplifier's error limit of the accepted try, world units.
    pub limit: f64,
    /// Whether the mesh was simplified (false: every try failed the checks, or nothing to do).
    pub simplified: bool,
}

/// `mesh` simplified by edge collapses with its Hausdorff distance to `mesh` at most
/// `opts.max_distance` (see the module docs); boundary vertices (open ends) do not move.
pub fn decimate_mesh(mesh: &TriMesh, opts: &DecimateOptions) -> (TriMesh, DecimateReport) {
    let mut report = DecimateReport {
        faces_before: mesh.num_faces(),
        faces_after: mesh.num_faces(),
        hausdorff: 0.0,
        max_distance: opts.max_distance,
        limit: 0.0,
        simplified: false,
    };
    if !(opts.max_distance > 0.0) || mesh.faces.is_empty() {
        return (mesh.clone(), report);
    }
    let before = mesh_info(mesh);
    let closed = before.watertight;
    // f32 positions about the box centre (CT coordinates lie far from the origin).
    let (lo, hi) = bounding_box(mesh);
    let centre = nalgebra::center(&lo, &hi);
    let positions: Vec<[f32; 3]> = mesh
        .vertices
        .iter()
        .map(|p| {
            let d = p - centre;
            [d.x as f32, d.y as f32, d.z as f32]
        })
        .collect();
    let indices: Vec<u32> = mesh.faces.iter().flatten().copied().collect();
    let mut limit = opts.first_limit_fraction * opts.max_distance;
    let mut locks = vec![false; mesh.num_vertices()];
    let rings = vertex_rings(mesh);
    let input_bvh = MeshBvh::new(mesh);
    for _ in 0..opts.tries.max(1) {
        let kept = simplify_with_locks_decoder(
            &indices,
            &positions,
            &locks,
            0,
            limit as f32,
            SimplifyOptions::LockBorder | SimplifyOptions::ErrorAbsolute,
            None,
        );
        let candidate = compact(mesh, &kept);
        let ok_topology = !closed || {
            let after = mesh_info(&candidate);
            after.watertight && after.components == before.components && after.genus == before.genus
        };
        if ok_topology && candidate.num_faces() < mesh.num_faces() {
            let d = surface_distance(
                mesh,
                &candidate,
                &SurfaceDistanceOptions {
                    samples: opts.samples,
                },
            );
            if d.hausdorff <= opts.max_distance {
                report.faces_after = candidate.num_faces();
                report.hausdorff = d.hausdorff;
                report.limit = limit;
                report.simplified = true;
                return (candidate, report);
            }
            // The bound is passed in a few places: keep the vertices there and try again at
            // the same limit.
            if lock_where_far(
                mesh,
                &kept,
                &input_bvh,
                &candidate,
                opts.max_distance,
                &rings,
                &mut locks,
            ) > 0
            {
                continue;
            }
        } else if !ok_topology {
            // A few collapses tore the surface (edges of more than two triangles, where two
            // sheets met): keep the vertices there too (and lower the limit, as below).
            lock_where_torn(&candidate, &kept, &rings, &mut locks);
        }
        limit *= opts.shrink.clamp(0.01, 0.99);
    }
    (mesh.clone(), report)
}

/// Locks the vertices of `mesh` (`to_mesh` its hierarchy) where `candidate` (its triangles
/// `kept`, an index list over `mesh`'s vertices) strays more than three quarters of
/// `max_distance` from it — the input's vertices far from the candidate, the corners of
/// candidate triangles whose centroid or edge midpoints lie far from the input — and one ring
/// around them. Returns how many were newly locked.
fn lock_where_far(
    mesh: &TriMesh,
    kept: &[u32],
    to_mesh: &MeshBvh,
    candidate: &TriMesh,
    max_distance: f64,
    rings: &[Vec<u32>],
    locks: &mut [bool],
) -> usize {
    let far = 0.75 * max_distance;
    let to_candidate = MeshBvh::new(candidate);
    let mut mark: Vec<bool> = mesh
        .vertices
        .par_iter()
        .map(|p| to_candidate.closest_point(p).distance > far)
        .collect();
    let strays: Vec<usize> = (0..candidate.num_faces())
        .into_par_iter()
        .filter(|&f| {
            let [a, b, c] = candidate.triangle(f);
            [
                Point3::from((a.coords + b.coords + c.coords) / 3.0),
                Point3::from((a.coords + b.coords) / 2.0),
                Point3::from((b.coords + c.coords) / 2.0),
                Point3::from((c.coords + a.coords) / 2.0),
            ]
            .iter()
            .any(|p| to_mesh.closest_point(p).distance > far)
        })
        .collect();
    for f in strays {
        for &v in &kept[3 * f..3 * f + 3] {
            mark[v as usize] = true;
        }
    }
    let marked = (0..mark.len() as u32).filter(|&v| mark[v as usize]);
    lock_with_rings(marked, rings, locks)
}

/// Locks `vertices` and one ring around each; returns how many were newly locked.
fn lock_with_rings(
    vertices: impl IntoIterator<Item = u32>,
    rings: &[Vec<u32>],
    locks: &mut [bool],
) -> usize {
    let mut added = 0;
    for v in vertices {
        for u in std::iter::once(v).chain(rings[v as usize].iter().copied()) {
            let l = &mut locks[u as usize];
            if !*l {
                *l = true;
                added += 1;
            }
        }
    }
    added
}

/// Locks the vertices of the edges of `candidate` (its triangles `kept`, an index list over the
/// mesh's vertices) that are not shared by exactly two triangles, and one ring around them;
/// returns how many were newly locked.
fn lock_where_torn(
    candidate: &TriMesh,
    kept: &[u32],
    rings: &[Vec<u32>],
    locks: &mut [bool],
) -> usize {
    let map = EdgeMap::new(candidate);
    let torn: Vec<u32> = (0..map.num_edges())
        .filter(|&e| map.valence(e) != 2)
        .flat_map(|e| {
            let u = map.uses(e)[0];
            let (f, k) = (3 * u.face as usize, u.slot as usize);
            [kept[f + k], kept[f + (k + 1) % 3]]
        })
        .collect();
    lock_with_rings(torn, rings, locks)
}

/// Each vertex's neighbours along the mesh's edges.
fn vertex_rings(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let mut rings = vec![Vec::new(); mesh.num_vertices()];
    for f in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            rings[a as usize].push(b);
            rings[b as usize].push(a);
        }
    }
    for r in &mut rings {
        r.sort_unstable();
        r.dedup();
    }
    rings
}

/// The triangles of the index list `kept` over `mesh`'s vertices, the unused vertices dropped
/// (order kept).
fn compact(mesh: &TriMesh, kept: &[u32]) -> TriMesh {
    let mut new_index = vec![u32::MAX; mesh.num_vertices()];
    let mut vertices = Vec::new();
    let faces = kept
        .chunks_exact(3)
        .map(|t| {
            let mut f = [0u32; 3];
            for (k, &v) in t.iter().enumerate() {
                if new_index[v as usize] == u32::MAX {
                    new_index[v as usize] = vertices.len() as u32;
                    vertices.push(mesh.vertices[v as usize]);
                }
                f[k] = new_index[v as usize];
            }
            f
        })
        .collect();
    TriMesh::new(vertices, faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torn_edges_lock_their_vertices_and_one_ring() {
        // The triangles `kept` over 7 vertices, as the simplifier's candidate.
        let mesh = TriMesh::new(vec![Point3::origin(); 7], Vec::new());
        let lock_where_torn = |kept: &[u32], rings: &[Vec<u32>], locks: &mut [bool]| {
            super::lock_where_torn(&compact(&mesh, kept), kept, rings, locks)
        };
        // A closed tetrahedron (0..4) and a path 4–5–6 on its own: nothing is torn.
        let tetra: Vec<u32> = vec![0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2];
        let mut rings = vec![Vec::new(); 7];
        for t in tetra.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                rings[a as usize].push(b);
            }
        }
        rings[4] = vec![5];
        rings[5] = vec![4, 6];
        rings[6] = vec![5];
        let mut locks = vec![false; 7];
        assert_eq!(lock_where_torn(&tetra, &rings, &mut locks), 0);
        // A third triangle on the edge 0–1 (a fin to vertex 5): 0–1 is in three triangles,
        // 1–5 and 5–0 in one, so 0, 1, 5 and their rings (every vertex) are locked.
        let mut torn = tetra.clone();
        torn.extend([0, 1, 5]);
        let added = lock_where_torn(&torn, &rings, &mut locks);
        assert_eq!(added, 7);
        assert!(locks.iter().all(|&l| l));
        // Only a torn edge's own vertices and rings: a fin 4–5–6 apart from the tetrahedron.
        let mut locks = vec![false; 7];
        let mut apart = tetra.clone();
        apart.extend([4, 5, 6]);
        lock_where_torn(&apart, &rings, &mut locks);
        assert_eq!(locks, [false, false, false, false, true, true, true]);
    }
}
