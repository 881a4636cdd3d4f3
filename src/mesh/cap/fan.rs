//! Centroid fans over given boundary loops: the cheapest closure of a mesh, for uses that need
//! only a closed surface (an integer winding number, ray-crossing signs) and not good cap
//! triangles, such as the centreline's signed distance grid.

use crate::TriMesh;
use nalgebra::Point3;
use std::collections::HashSet;

/// `mesh` with each loop of `loops` (vertex indices in order, as `topology::boundary_loops`
/// gives them) closed by a fan of triangles from the loop's vertex centroid (one new vertex per
/// loop). Fan triangles are wound opposite to the way the mesh's own triangles traverse the rim,
/// so a consistently oriented mesh stays consistently oriented. Loops of fewer than 3 vertices
/// are left open.
pub fn cap_loops_with_fans(mesh: &TriMesh, loops: &[Vec<u32>]) -> TriMesh {
    let directed: HashSet<(u32, u32)> = mesh
        .faces
        .iter()
        .flat_map(|f| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])])
        .collect();
    let mut out = mesh.clone();
    for lp in loops.iter().filter(|l| l.len() >= 3) {
        let sum = lp.iter().fold(nalgebra::Vector3::zeros(), |s, &v| {
            s + mesh.vertices[v as usize].coords
        });
        let c = out.vertices.len() as u32;
        out.vertices.push(Point3::from(sum / lp.len() as f64));
        // The mesh traverses a–b along the loop's order: the fan goes b–a.
        let along = directed.contains(&(lp[0], lp[1]));
        for (i, &a) in lp.iter().enumerate() {
            let b = lp[(i + 1) % lp.len()];
            out.faces.push(if along { [b, a, c] } else { [a, b, c] });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::measures::signed_volume;
    use crate::mesh::topology::boundary_loops;

    /// An open-ended square tube (4 side quads, no ends): fans close it into a box of volume 1.
    #[test]
    fn fans_close_an_open_box_outward() {
        let mut vertices = Vec::new();
        for z in [0.0, 1.0] {
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                vertices.push(Point3::new(x, y, z));
            }
        }
        let mut faces = Vec::new();
        for i in 0..4u32 {
            let j = (i + 1) % 4;
            faces.push([i, j, j + 4]);
            faces.push([i, j + 4, i + 4]);
        }
        let mesh = TriMesh::new(vertices, faces);
        let loops = boundary_loops(&mesh);
        assert_eq!(loops.len(), 2);
        let closed = cap_loops_with_fans(&mesh, &loops);
        assert!(boundary_loops(&closed).is_empty());
        assert!((signed_volume(&closed) - 1.0).abs() < 1e-12);
    }
}
