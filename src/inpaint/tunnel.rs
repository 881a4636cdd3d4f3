//! A tunnel the fill leaves through the vessel, and its closing.
//!
//! The fill is united with what the input has in D. Where the fill's lumen lies beside a piece of
//! the input's own lumen instead of over it (a junction's estimated lumen placed off the true one,
//! next to a strip of intact wall: `benches/repair_real`, seed 29, the aortas' junction chops,
//! the fill 3 mm to the side of the wall left on the other), the gap between the two runs through
//! the solid from one side to the other: the repaired surface has a handle the vessel never had
//! (its genus 1 where the input's is 0), inside what should be one lumen. The repair measures the
//! patch's handles ([`crate::mesh::measures::handles`]) against the input's genus and, when the
//! patch has more, closes the inside of the united field in D morphologically (dilated then
//! eroded by a radius, the smallest of [`closing_radii`] that removes the new handles): a gap
//! narrower than twice the radius is filled, wider lumens and a junction's crotch wider than
//! that are left as they were. The paper allows topology to change while it inpaints (its
//! Section 4); a vessel's surface after the repair should not have gained a handle.

use crate::grid::Grid3;
use crate::levelset::redistance::{redistance, RedistanceOptions};
use crate::Result;
use rayon::prelude::*;

/// The closing radii tried, in turn, as fractions of the vessel's radius around D: the smallest
/// (about a millimetre on the aorta) fills a gap of a few voxels.
pub const CLOSING_RADII_OF_VESSEL: [f64; 3] = [0.15, 0.3, 0.5];

/// [`CLOSING_RADII_OF_VESSEL`] for a vessel of radius `radius` (world units).
pub fn closing_radii(radius: f64) -> [f64; 3] {
    CLOSING_RADII_OF_VESSEL.map(|f| f * radius)
}

/// Closes the inside of `psi` (a signed distance near its zero level set, negative inside) by a
/// ball of `radius` (world units): the set dilated by the radius, then eroded by it, on the
/// nodes where `weights` is 1 (deep in D); elsewhere `psi` is kept. Only adds to the inside.
pub fn close_inside(psi: &mut Grid3, weights: &[f32], radius: f64) -> Result<()> {
    let mut closed = psi.clone();
    // The fills give distances within a few voxels of the surface only: measured afresh, so the
    // dilation reaches the radius.
    let full = RedistanceOptions::default();
    redistance(&mut closed, &full)?;
    let r = radius as f32;
    closed.data_mut().par_iter_mut().for_each(|v| *v -= r);
    redistance(&mut closed, &full)?;
    closed.data_mut().par_iter_mut().for_each(|v| *v += r);
    psi.data_mut()
        .par_iter_mut()
        .zip(closed.data().par_iter())
        .zip(weights.par_iter())
        .for_each(|((v, &c), &w)| {
            if w >= 1.0 && c < *v {
                *v = c;
            }
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridTransform;
    use nalgebra::Point3;

    /// Two slabs with a gap of 2 voxels between them: a closing of 2 voxels fills the gap where
    /// the weights are 1 and nowhere else; one of half a voxel leaves it.
    #[test]
    fn a_closing_fills_a_narrow_gap_only_in_d() {
        let n = 24;
        let h = 1.0;
        let t = GridTransform::new(Point3::origin(), h);
        let slab = |x: f64| {
            // Inside for |x − 12| ≥ 1 and 4 ≤ x ≤ 20: two slabs of 7 voxels with a gap of 2.
            let outer = (x - 12.0).abs() - 8.0;
            let gap = 1.0 - (x - 12.0).abs();
            outer.max(gap)
        };
        let data: Vec<f32> = (0..n * n * n)
            .map(|i| slab((i % n) as f64 * h) as f32)
            .collect();
        let grid = Grid3::from_data([n, n, n], t, data).unwrap();
        // D: the half of the grid with y < 12.
        let weights: Vec<f32> = (0..n * n * n)
            .map(|i| if (i / n) % n < 12 { 1.0 } else { 0.0 })
            .collect();
        let at = |g: &Grid3, x: usize, y: usize| g.data()[(12 * n + y) * n + x];
        let mut wide = grid.clone();
        close_inside(&mut wide, &weights, 2.0).unwrap();
        assert!(at(&wide, 12, 5) < 0.0, "the gap in D is filled");
        assert!(at(&wide, 12, 18) > 0.0, "the gap outside D is kept");
        assert!(at(&wide, 1, 5) > 0.0, "outside the slabs stays outside");
        let mut narrow = grid.clone();
        close_inside(&mut narrow, &weights, 0.5).unwrap();
        assert!(
            at(&narrow, 12, 5) > 0.0,
            "a closing of half a voxel leaves the gap"
        );
    }
}
