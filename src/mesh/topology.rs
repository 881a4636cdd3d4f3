//! Combinatorial topology of a triangle mesh: edges and their incident faces, connected components,
//! boundary loops, non-manifold edges and vertices, and orientation consistency.

use super::TriMesh;

/// Connected components of the mesh, connecting faces that share an edge or a vertex.
/// Returns the number of components and, per face, its component label (0-based).
pub fn connected_components(mesh: &TriMesh) -> (usize, Vec<u32>) {
    todo!("owned by the topology helper")
}

/// Boundary loops: closed chains of edges that belong to exactly one triangle. Each loop lists its
/// vertices in order; consecutive vertices (u, v) appear as the directed half-edge u→v in their
/// triangle, so a cap oriented like the mesh uses the loop reversed.
pub fn boundary_loops(mesh: &TriMesh) -> Vec<Vec<u32>> {
    todo!("owned by the topology helper")
}
