//! Merging vertices with exactly equal coordinates (−0.0 and 0.0 count as equal): what a binary
//! STL reader does to every file, applied to a mesh in memory. A triangle soup (every triangle
//! with its own three corners) becomes the connected surface it describes, so its topology
//! (boundary loops, watertightness) is the one any reader of the written file will see.

use super::TriMesh;
use std::collections::HashMap;

/// The welding key of a point: its coordinates' bits, with −0.0 made +0.0.
pub fn weld_key(p: [f64; 3]) -> [u64; 3] {
    // Adding 0.0 turns -0.0 into +0.0 and leaves every other value unchanged.
    p.map(|c| (c + 0.0).to_bits())
}

/// `mesh` with coincident vertices merged (the first of each group kept, in order) and the
/// number of vertices merged away. Triangles are kept as they are, even those that become
/// degenerate.
pub fn weld_coincident(mesh: &TriMesh) -> (TriMesh, usize) {
    let mut index: HashMap<[u64; 3], u32> = HashMap::with_capacity(mesh.num_vertices());
    let mut vertices = Vec::with_capacity(mesh.num_vertices());
    let remap: Vec<u32> = mesh
        .vertices
        .iter()
        .map(|p| {
            *index.entry(weld_key([p.x, p.y, p.z])).or_insert_with(|| {
                vertices.push(*p);
                (vertices.len() - 1) as u32
            })
        })
        .collect();
    let merged = mesh.num_vertices() - vertices.len();
    let faces = mesh
        .faces
        .iter()
        .map(|f| f.map(|v| remap[v as usize]))
        .collect();
    (TriMesh::new(vertices, faces), merged)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn soup_welds_to_shared_vertices() {
        let p = |x: f64, y: f64| Point3::new(x, y, 0.0);
        // Two triangles sharing an edge, given as a soup (one corner at -0.0).
        let soup = TriMesh::new(
            vec![
                p(0.0, 0.0),
                p(1.0, 0.0),
                p(0.0, 1.0),
                p(1.0, 0.0),
                p(1.0, 1.0),
                p(-0.0, 1.0),
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        );
        let (welded, merged) = weld_coincident(&soup);
        assert_eq!(merged, 2);
        assert_eq!(welded.num_vertices(), 4);
        assert_eq!(welded.faces, vec![[0, 1, 2], [1, 3, 2]]);
    }
}
