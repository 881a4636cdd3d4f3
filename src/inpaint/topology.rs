//! Topology clean-up of a fill: pieces the fill created inside D that do not belong to the
//! vessel. A connected part of the inside {φ < 0} (or of the outside {φ ≥ 0}) that lies wholly
//! within D touches none of the known data: debris floating in D, or a void sealed in the lumen.
//! Both are removed by flipping their nodes to the other side (6-connected components).
//!
//! The components are labelled by runs: each grid row's maximal runs of nodes of one side in D
//! (found row by row in parallel, with whether a node of the run has a face neighbour of the same
//! side outside D: the component is then anchored to the known data), joined by union–find
//! wherever two runs of neighbouring rows overlap. The nodes are read once, with no division per
//! node: on the aneurysm's narrowing (a ball of 98 voxels' radius) 0.19 s by a node-by-node
//! flood, 0.012 s by runs.

use crate::grid::Grid3;
use crate::mesh::topology::{find, union};
use rayon::prelude::*;

/// A run of nodes `first..=last` along x in one grid row; `anchored` when one of its nodes has a
/// face neighbour of the same side outside D.
#[derive(Debug, Clone, Copy)]
struct Run {
    first: u32,
    last: u32,
    anchored: bool,
}

/// Joins every run of `row` (ids from `first`) with the overlapping runs of `other` (ids from
/// `other_first`); both sorted along x.
fn join_rows(parent: &mut [u32], row: &[Run], first: u32, other: &[Run], other_first: u32) {
    let (mut a, mut b) = (0, 0);
    while a < row.len() && b < other.len() {
        let (r, o) = (row[a], other[b]);
        if r.first <= o.last && o.first <= r.last {
            union(parent, first + a as u32, other_first + b as u32);
        }
        if r.last < o.last {
            a += 1;
        } else {
            b += 1;
        }
    }
}

/// Flips the components of the inside and of the outside of `phi` that contain no node outside D
/// (`unknown` marks D). Returns how many nodes were flipped.
pub fn remove_islands(phi: &mut Grid3, unknown: &[bool]) -> usize {
    let [nx, ny, nz] = phi.dims();
    let h = phi.voxel() as f32;
    let layer = nx * ny;
    let mut flipped = 0;
    for inside in [true, false] {
        let data = phi.data();
        let same = |n: usize| (data[n] < 0.0) == inside;
        let member = |n: usize| unknown[n] && same(n);
        let anchor = |n: usize| !unknown[n] && same(n);
        let rows: Vec<Vec<Run>> = (0..ny * nz)
            .into_par_iter()
            .map(|row| {
                let (j, k) = (row % ny, row / ny);
                let base = row * nx;
                let across = |n: usize| {
                    (j > 0 && anchor(n - nx))
                        || (j + 1 < ny && anchor(n + nx))
                        || (k > 0 && anchor(n - layer))
                        || (k + 1 < nz && anchor(n + layer))
                };
                let mut runs = Vec::new();
                let mut i = 0;
                while i < nx {
                    if !member(base + i) {
                        i += 1;
                        continue;
                    }
                    let first = i;
                    let mut anchored = first > 0 && anchor(base + first - 1);
                    while i < nx && member(base + i) {
                        anchored = anchored || across(base + i);
                        i += 1;
                    }
                    // The node after the run is not a member: of the same side, it is outside D.
                    anchored = anchored || (i < nx && anchor(base + i));
                    runs.push(Run {
                        first: first as u32,
                        last: (i - 1) as u32,
                        anchored,
                    });
                }
                runs
            })
            .collect();
        let mut offset = Vec::with_capacity(rows.len() + 1);
        offset.push(0u32);
        for r in &rows {
            offset.push(offset.last().copied().unwrap_or(0) + r.len() as u32);
        }
        let total = *offset.last().unwrap_or(&0) as usize;
        if total == 0 {
            continue;
        }
        let mut parent: Vec<u32> = (0..total as u32).collect();
        for row in 0..rows.len() {
            let (j, k) = (row % ny, row / ny);
            if j > 0 {
                let o = row - 1;
                join_rows(&mut parent, &rows[row], offset[row], &rows[o], offset[o]);
            }
            if k > 0 {
                let o = row - ny;
                join_rows(&mut parent, &rows[row], offset[row], &rows[o], offset[o]);
            }
        }
        let mut anchored = vec![false; total];
        for (row, runs) in rows.iter().enumerate() {
            for (a, run) in runs.iter().enumerate() {
                if run.anchored {
                    let r = find(&mut parent, offset[row] + a as u32);
                    anchored[r as usize] = true;
                }
            }
        }
        let value = if inside { 0.5 * h } else { -0.5 * h };
        let out = phi.data_mut();
        for (row, runs) in rows.iter().enumerate() {
            for (a, run) in runs.iter().enumerate() {
                let r = find(&mut parent, offset[row] + a as u32);
                if !anchored[r as usize] {
                    let base = row * nx;
                    out[base + run.first as usize..=base + run.last as usize].fill(value);
                    flipped += (run.last - run.first + 1) as usize;
                }
            }
        }
    }
    flipped
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{face_neighbours, GridTransform};
    use nalgebra::{Point3, Vector3};

    /// The components node by node (a depth-first flood over D's nodes of each side), as the
    /// reference for the runs.
    fn remove_islands_by_flood(phi: &mut Grid3, unknown: &[bool]) -> usize {
        let dims = phi.dims();
        let h = phi.voxel() as f32;
        let n = phi.data().len();
        let mut flipped = 0;
        for inside in [true, false] {
            let side = |v: f32| (v < 0.0) == inside;
            let mut seen = vec![false; n];
            for start in 0..n {
                if seen[start] || !unknown[start] || !side(phi.data()[start]) {
                    continue;
                }
                let (mut stack, mut members, mut anchored) = (vec![start], Vec::new(), false);
                seen[start] = true;
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
                    for &v in &members {
                        phi.data_mut()[v] = if inside { 0.5 * h } else { -0.5 * h };
                    }
                    flipped += members.len();
                }
            }
        }
        flipped
    }

    /// Random speckle (a quarter to three quarters inside) in a ball D of a box: many small
    /// components of both sides, some touching the box's faces, some D's boundary.
    #[test]
    fn runs_flip_what_the_flood_flips() {
        let dims = [23, 17, 19];
        let t = GridTransform::new(Point3::origin(), 1.0);
        let mut rng = crate::inpaint::phantom::SplitMix(12345);
        let mut next = || rng.uniform();
        for trial in 0..12 {
            let fill = 0.25 + 0.5 * next();
            let mut a = Grid3::new(dims, t, 1.0).unwrap();
            let mut unknown = vec![false; a.data().len()];
            let centre = Point3::new(11.0, 8.0, 9.0 + trial as f64 * 0.3);
            for n in 0..a.data().len() {
                let [i, j, k] = a.coords(n);
                let p = Point3::new(i as f64, j as f64, k as f64);
                unknown[n] = (p - centre).norm() < 7.5;
                a.data_mut()[n] = if next() < fill { -1.0 } else { 1.0 };
            }
            let mut b = a.clone();
            let (fa, fb) = (
                remove_islands(&mut a, &unknown),
                remove_islands_by_flood(&mut b, &unknown),
            );
            assert!(fb > 0, "trial {trial}: nothing to flip");
            assert_eq!(fa, fb, "trial {trial}");
            assert_eq!(a.data(), b.data(), "trial {trial}");
        }
    }

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
