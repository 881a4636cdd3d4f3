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
    // A component of one side with no node outside D is a component of that side's nodes in D
    // with no face neighbour of the same side outside D: only D is walked.
    let mut stack = Vec::new();
    let mut members = Vec::new();
    for inside in [true, false] {
        let side = |v: f32| (v < 0.0) == inside;
        let mut seen = vec![false; n];
        for start in 0..n {
            if seen[start] || !unknown[start] || !side(phi.data()[start]) {
                continue;
            }
            members.clear();
            let mut anchored = false;
            seen[start] = true;
            stack.push(start);
            while let Some(v) = stack.pop() {
                members.push(v);
                for w in face_neighbours(dims, v) {
                    if !side(phi.data()[w]) {
                        continue;
                    }
                    if !unknown[w] {
                        anchored = true;
                    } else if !seen[w] {
                        seen[w] = true;
                        stack.push(w);
                    }
                }
            }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridTransform;
    use nalgebra::{Point3, Vector3};

    /// A slab (anchored: it leaves D), a blob floating in D and a void sealed in the slab inside
    /// D: the blob and the void are flipped, the slab is kept.
    #[test]
    fn floating_blob_and_sealed_void_are_flipped() {
        let n = 24;
        let t = GridTransform::new(Point3::origin(), 1.0);
        let mut phi = Grid3::new([n, n, n], t, 1.0).unwrap();
        let centre = Point3::new(11.5, 11.5, 11.5);
        let mut unknown = vec![false; n * n * n];
        let (mut blob, mut void) = (0, 0);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let p = Point3::new(i as f64, j as f64, k as f64);
                    let idx = phi.index(i, j, k);
                    unknown[idx] = (p - centre).norm() < 9.0;
                    let in_slab = (4..8).contains(&k);
                    let in_void = in_slab && (p - Point3::new(11.5, 11.5, 5.5)).norm() < 1.6;
                    let in_blob = (p - (centre + Vector3::new(0.0, 0.0, 4.0))).norm() < 2.5;
                    if (in_slab && !in_void) || in_blob {
                        phi.data_mut()[idx] = -1.0;
                    }
                    blob += usize::from(in_blob);
                    void += usize::from(in_void);
                }
            }
        }
        assert!(blob > 0 && void > 0);
        let slab_before = phi.data().iter().filter(|&&v| v < 0.0).count() - blob;
        assert_eq!(remove_islands(&mut phi, &unknown), blob + void);
        assert_eq!(
            phi.data().iter().filter(|&&v| v < 0.0).count(),
            slab_before + void
        );
        // Nothing left to flip.
        assert_eq!(remove_islands(&mut phi, &unknown), 0);
    }
}
