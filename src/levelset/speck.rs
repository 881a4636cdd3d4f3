//! Specks: nodes a hair's breadth from zero whose six neighbours all lie on the other side. On its
//! own such a node is a marching-cubes component a few hundredths of a voxel across, a piece of
//! surface no grid-scale operation means to make: thresholding and interpolation can tip a node
//! that near zero either way. The multiscale representation clears them from every level it
//! measures and from every level it rebuilds, so that neither has a speck the other lacks.

use crate::grid::{face_neighbours, Grid3};
use rayon::prelude::*;

/// Default for [`clear_specks`]: nodes within this of zero (voxels) count as specks.
pub const SPECK: f64 = 0.05;

/// Gives the sign of its neighbours to every node of `phi` within `below` voxels of zero whose
/// six face neighbours all have the other sign (the value mirrored through zero; nodes on the
/// grid's border are left alone). Returns how many nodes changed side.
pub fn clear_specks(phi: &mut Grid3, below: f64) -> usize {
    let dims = phi.dims();
    let limit = (below * phi.voxel()) as f32;
    let data = phi.data();
    let specks: Vec<usize> = (0..data.len())
        .into_par_iter()
        .filter(|&n| {
            let v = data[n];
            if v.abs() >= limit {
                return false;
            }
            let c = phi.coords(n);
            (0..3).all(|a| c[a] > 0 && c[a] + 1 < dims[a])
                && face_neighbours(dims, n).all(|m| (data[m] < 0.0) != (v < 0.0))
        })
        .collect();
    let data = phi.data_mut();
    for &n in &specks {
        // Zero (either zero) counts as outside: its other side is just below it.
        let v = data[n];
        data[n] = if v == 0.0 { -f32::MIN_POSITIVE } else { -v };
    }
    specks.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridTransform;

    fn grid(values: impl Fn(usize, usize, usize) -> f32) -> Grid3 {
        let mut g = Grid3::new(
            [5, 5, 5],
            GridTransform::new(nalgebra::Point3::origin(), 0.5),
            0.0,
        )
        .unwrap();
        for k in 0..5 {
            for j in 0..5 {
                for i in 0..5 {
                    g.set(i, j, k, values(i, j, k));
                }
            }
        }
        g
    }

    #[test]
    fn a_lone_node_near_zero_takes_its_neighbours_side() {
        let h: f32 = 0.5;
        // Outside everywhere but a node at −0.02h (a speck), one at −0.2h (a real droplet, kept)
        // and a zero on the border (left alone).
        let mut g = grid(|i, j, k| match (i, j, k) {
            (1, 1, 1) => -0.02 * h,
            (3, 3, 3) => -0.2 * h,
            (0, 2, 2) => 0.0,
            _ => h,
        });
        assert_eq!(clear_specks(&mut g, SPECK), 1);
        assert_eq!(g.get(1, 1, 1), 0.02 * h);
        assert_eq!(g.get(3, 3, 3), -0.2 * h);
        // Inside everywhere but a zero (outside by the sign test): it goes just inside.
        let mut g = grid(|i, j, k| if (i, j, k) == (2, 2, 2) { 0.0 } else { -h });
        assert_eq!(clear_specks(&mut g, SPECK), 1);
        assert!(g.get(2, 2, 2) < 0.0);
        // A node near zero with one neighbour across is on the surface, not a speck.
        let mut g = grid(|i, j, k| match (i, j, k) {
            (2, 2, 2) => -0.01 * h,
            (2, 2, 3) => -h,
            _ => h,
        });
        assert_eq!(clear_specks(&mut g, SPECK), 0);
    }
}
