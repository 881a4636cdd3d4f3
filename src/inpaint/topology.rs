//! Topology clean-up of a fill: pieces the fill created inside D that do not belong to the
//! vessel. A connected part of the inside {φ < 0} (or of the outside {φ ≥ 0}) that lies wholly
//! within D touches none of the known data: debris floating in D, or a void sealed in the lumen.
//! Both are removed by flipping their nodes to the other side (6-connected flood fill).

use crate::grid::{face_neighbours, Grid3};

/// Flips the components of the inside and of the outside of `phi` that contain no node outside D
/// (`unknown` marks D). Returns how many nodes were flipped.
pub fn remove_islands(phi: &mut Grid3, unknown: &[bool]) -> usize {
    let dims = phi.dims();
    let h = phi.voxel() as f32;
    let n = phi.data().len();
    let mut flipped = 0;
    for inside in [true, false] {
        let side = |v: f32| (v < 0.0) == inside;
        let mut label = vec![u32::MAX; n];
        let mut next = 0u32;
        let mut stack = Vec::new();
        for start in 0..n {
            if label[start] != u32::MAX || !side(phi.data()[start]) {
                continue;
            }
            let mut members = Vec::new();
            let mut anchored = false;
            label[start] = next;
            stack.push(start);
            while let Some(v) = stack.pop() {
                members.push(v);
                anchored |= !unknown[v];
                for w in face_neighbours(dims, v) {
                    if label[w] == u32::MAX && side(phi.data()[w]) {
                        label[w] = next;
                        stack.push(w);
                    }
                }
            }
            next += 1;
            if !anchored {
                let data = phi.data_mut();
                for &v in &members {
                    data[v] = if inside { 0.5 * h } else { -0.5 * h };
                }
                flipped += members.len();
            }
        }
    }
    flipped
}
