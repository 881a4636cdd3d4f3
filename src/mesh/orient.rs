//! Orientation repair: make the triangles of each component consistently wound, and outward.
//!
//! The approach is the standard one of mesh-repair tools (e.g. MeshLab's "re-orient all faces
//! coherently" and trimesh's `fix_winding`/`fix_inversion`): a breadth-first traversal of the
//! face-adjacency graph through manifold edges propagates the winding of a seed face, each neighbour
//! being flipped when it traverses the shared edge in the same direction; then the sign of the
//! enclosed volume given by the divergence theorem tells whether a consistently wound component
//! faces outward, and the component is flipped when it is negative.

use super::measures::{component_nesting_depths, component_signed_volumes};
use super::topology::{connected_components, EdgeMap};
use super::TriMesh;
use std::collections::VecDeque;

/// Per face, whether to flip it so that every region of faces connected through manifold edges
/// (edges with exactly two faces) is consistently wound; plus the number of conflicts met (edges
/// that could not be made consistent: the region is non-orientable, e.g. a Möbius strip).
///
/// In each region the winding of its first face is propagated; if that would flip more than half of
/// the region, the complement is flipped instead (fewest flips, ties keep the first face).
fn consistency_flips(map: &EdgeMap) -> (Vec<bool>, usize) {
    let nf = map.mesh().num_faces();
    let mut visited = vec![false; nf];
    let mut flip = vec![false; nf];
    let mut conflicts = 0usize;
    let mut queue = VecDeque::new();
    let mut region = Vec::new();
    for seed in 0..nf {
        if visited[seed] {
            continue;
        }
        visited[seed] = true;
        queue.push_back(seed);
        region.clear();
        while let Some(f) = queue.pop_front() {
            region.push(f);
            for k in 0..3 {
                let Some(e) = map.face_edge(f, k) else {
                    continue;
                };
                let uses = map.uses(e);
                if uses.len() != 2 || uses[0].face == uses[1].face {
                    continue;
                }
                let (mine, other) = if uses[0].face as usize == f {
                    (uses[0], uses[1])
                } else {
                    (uses[1], uses[0])
                };
                let g = other.face as usize;
                // Consistent when the effective directions differ.
                let want = flip[f] ^ (mine.forward == other.forward);
                if !visited[g] {
                    visited[g] = true;
                    flip[g] = want;
                    queue.push_back(g);
                } else if flip[g] != want {
                    conflicts += 1;
                }
            }
        }
        let flipped = region.iter().filter(|&&f| flip[f]).count();
        if 2 * flipped > region.len() {
            for &f in &region {
                flip[f] = !flip[f];
            }
        }
    }
    // Each conflicting edge was seen from both faces.
    (flip, conflicts.div_ceil(2))
}

/// Whether every region connected through manifold edges can be wound consistently.
pub(crate) fn is_orientable_of(map: &EdgeMap) -> bool {
    consistency_flips(map).1 == 0
}

/// Flips faces so that the faces of each region connected through manifold edges agree in winding
/// (every manifold edge traversed in opposite directions by its two faces), flipping the smaller
/// part of each region. Regions joined only through non-manifold edges or vertices are oriented
/// independently. On a non-orientable region some edges necessarily stay inconsistent.
/// Returns the number of faces flipped.
pub fn orient_consistently(mesh: &mut TriMesh) -> usize {
    let (flip, _) = consistency_flips(&EdgeMap::new(mesh));
    let mut n = 0;
    for (face, flip) in mesh.faces.iter_mut().zip(flip) {
        if flip {
            face.swap(1, 2);
            n += 1;
        }
    }
    n
}

/// Flips every connected component whose signed volume, measured about the component's
/// area-weighted centroid, is negative, so closed components enclose positive volume and open
/// vessel tubes (whose ends are small) face outward. Expects consistently wound components (run
/// [`orient_consistently`] first). Returns the number of components flipped.
pub fn orient_outward(mesh: &mut TriMesh) -> usize {
    let (n, labels) = connected_components(mesh);
    let vols = component_signed_volumes(mesh, n, &labels);
    // A shell nested inside another (a cavity) faces into its cavity: negative volume.
    let depths = component_nesting_depths(mesh, n, &labels);
    let flip: Vec<bool> = vols
        .iter()
        .zip(&depths)
        .map(|(&v, &d)| (v < 0.0) == (d % 2 == 0))
        .collect();
    for (face, &l) in mesh.faces.iter_mut().zip(&labels) {
        if flip[l as usize] {
            face.swap(1, 2);
        }
    }
    flip.iter().filter(|&&f| f).count()
}
