//! Combinatorial topology of a triangle mesh: edges and their incident faces, connected components,
//! boundary loops, non-manifold edges and vertices, and orientation consistency.

use super::TriMesh;
use std::collections::HashMap;

/// Connected components of the mesh, connecting faces that share an edge or a vertex.
/// Returns the number of components and, per face, its component label (0-based).
pub fn connected_components(mesh: &TriMesh) -> (usize, Vec<u32>) {
    // Union-find over vertices; faces take their first vertex's root.
    let n = mesh.num_vertices();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for f in &mesh.faces {
        let r0 = find(&mut parent, f[0]);
        for &v in &f[1..] {
            let r = find(&mut parent, v);
            if r != r0 {
                parent[r as usize] = r0;
            }
        }
    }
    let mut label_of_root: HashMap<u32, u32> = HashMap::new();
    let labels = mesh
        .faces
        .iter()
        .map(|f| {
            let r = find(&mut parent, f[0]);
            let next = label_of_root.len() as u32;
            *label_of_root.entry(r).or_insert(next)
        })
        .collect();
    (label_of_root.len(), labels)
}

/// Boundary loops: closed chains of edges that belong to exactly one triangle. Each loop lists its
/// vertices in order; consecutive vertices (u, v) appear as the directed half-edge u→v in their
/// triangle, so a cap oriented like the mesh uses the loop reversed.
///
/// Where a vertex has several outgoing boundary half-edges (a non-manifold boundary vertex), the
/// chains are still split into closed loops, each edge used once.
pub fn boundary_loops(mesh: &TriMesh) -> Vec<Vec<u32>> {
    // Count undirected edges; remember the directed half-edge of edges used once.
    let mut count: HashMap<(u32, u32), (u32, (u32, u32))> = HashMap::new();
    for f in &mesh.faces {
        for k in 0..3 {
            let (u, v) = (f[k], f[(k + 1) % 3]);
            let key = (u.min(v), u.max(v));
            let e = count.entry(key).or_insert((0, (u, v)));
            e.0 += 1;
        }
    }
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut half: Vec<(u32, u32)> = count
        .values()
        .filter(|(c, _)| *c == 1)
        .map(|(_, h)| *h)
        .collect();
    half.sort_unstable();
    for &(u, v) in &half {
        next.entry(u).or_default().push(v);
    }
    let mut loops = Vec::new();
    for &(start, _) in &half {
        while next.get(&start).is_some_and(|o| !o.is_empty()) {
            let mut lp = vec![start];
            let mut cur = start;
            loop {
                let outs = next.get_mut(&cur).unwrap();
                let v = outs.pop().unwrap();
                if v == start {
                    break;
                }
                lp.push(v);
                cur = v;
                if next.get(&cur).is_none_or(|o| o.is_empty()) {
                    break; // open chain (cannot happen on a valid mesh); keep what we have
                }
            }
            loops.push(lp);
        }
    }
    loops
}
