//! Shaving the convex bumps off a fill: one step of mean curvature motion by threshold dynamics
//! on a signed distance (diffuse φ for a time t, the zero level set moves by −t·κ to first order:
//! Esedoglu, Ruuth and Tsai 2010, as `motion::flow`; the paper's Section 3), kept only where it
//! moves the surface inward, and only inside the given balls.
//!
//! What it is for: a junction's fill ([`super::guided`]) is a smooth union of tubes, each carrying
//! the wall's details read around the hole; where they meet, their sections and details add up
//! to bumps and ridges that no vessel has (the tubes overlap, a bulge read on one side of a bulb
//! is carried onto the other), and the fill stands too high over the hole (on the 30 junction
//! chops of `benches/repair_real`, seeds 21–27: +1.3% of the volume in D on average, up to
//! +15%). Mean curvature motion moves a ball's wall of radius ρ in by 2t/ρ and a tube's of radius
//! r by t/r, so a short time takes the bumps off and leaves the tubes' walls nearly where they
//! were; keeping only the inward motion leaves a concave crotch, such as a carina's, as the fill
//! made it (the motion moves it outward: measured, a mean curvature flow of the same time kept
//! whole took the capped aorta's junction chop of seed 21 from 3.72 to 4.66 voxels of the truth,
//! 3.71 with this module, inward only).

use super::mask::{blend_known, blend_weights, region_depth};
use super::region::Ball;
use crate::grid::Grid3;
use crate::motion::diffusion::diffuse;
use crate::Result;
use rayon::prelude::*;

/// Moves the zero level set of `phi` (a signed distance near it, negative inside) inward by one
/// mean-curvature step of `time` (world length²) wherever that step moves it inward, inside the
/// union of `balls`, blended into the unchanged `phi` over `band` (world units) inside their
/// boundary. Outside the balls `phi` is unchanged.
pub fn shave_bumps(phi: &mut Grid3, balls: &[Ball], time: f64, band: f64) -> Result<()> {
    if balls.is_empty() || time <= 0.0 {
        return Ok(());
    }
    let before = phi.clone();
    diffuse(phi, time, &Default::default())?;
    // Inward only: a larger φ is farther outside.
    phi.data_mut()
        .par_iter_mut()
        .zip(before.data().par_iter())
        .for_each(|(v, &b)| *v = v.max(b));
    let weights = blend_weights(&region_depth(phi, balls), band);
    blend_known(phi, &before, &weights);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridTransform;
    use nalgebra::{Point3, Vector3};

    /// A cylinder of radius `r` along z with a ball of radius `b` centred on its wall at x = r,
    /// as a signed distance (exact away from where the two meet), on a grid of voxel `h`.
    fn tube_with_bump(r: f64, b: f64, h: f64) -> Grid3 {
        let n = (2.0 * (r + b + 4.0 * h) / h).ceil() as usize;
        let half = 0.5 * (n - 1) as f64 * h;
        let t = GridTransform::new(Point3::new(-half, -half, -half), h);
        let mut g = Grid3::new([n, n, n], t, 0.0).unwrap();
        let dims = g.dims();
        for (idx, v) in g.data_mut().iter_mut().enumerate() {
            let (i, j, k) = (
                idx % dims[0],
                (idx / dims[0]) % dims[1],
                idx / (dims[0] * dims[1]),
            );
            let p = t.index_to_world(Vector3::new(i as f64, j as f64, k as f64));
            let tube = (p.x * p.x + p.y * p.y).sqrt() - r;
            let bump = (p - Point3::new(r, 0.0, 0.0)).norm() - b;
            *v = tube.min(bump) as f32;
        }
        g
    }

    /// Where the zero level set crosses the ray from the axis at height z along +x or −x.
    fn wall(g: &Grid3, z: f64, sign: f64) -> f64 {
        let mut prev = g.sample_trilinear(&Point3::new(0.0, 0.0, z)).unwrap();
        let step = 0.01;
        let mut x = step;
        loop {
            let v = g.sample_trilinear(&Point3::new(sign * x, 0.0, z)).unwrap();
            if prev < 0.0 && v >= 0.0 {
                return x - step * v / (v - prev);
            }
            prev = v;
            x += step;
        }
    }

    #[test]
    fn a_bump_is_shaved_a_tube_barely_and_nothing_outward_or_outside_the_balls() {
        let (r, b, h) = (4.0, 1.5, 0.2);
        let mut g = tube_with_bump(r, b, h);
        let before = g.clone();
        // One ball around the bump, one around the opposite wall.
        let balls = [
            Ball {
                center: Point3::new(r, 0.0, 0.0),
                radius: 2.0 * b,
            },
            Ball {
                center: Point3::new(-r, 0.0, 0.0),
                radius: 2.0 * b,
            },
        ];
        // The time the repair gives a junction: 0.01 R².
        let t = 0.01 * r * r;
        shave_bumps(&mut g, &balls, t, 2.0 * h).unwrap();
        // The bump's top (at x = r + b, curvature 2/b) goes in by about 2t/b; the tube's wall
        // opposite (curvature 1/r) by t/r, a fifth of that.
        let top = wall(&g, 0.0, 1.0);
        let far = wall(&g, 0.0, -1.0);
        assert!(
            (r + b - top - 2.0 * t / b).abs() < 0.25 * h,
            "bump top {top}"
        );
        assert!((r - far - t / r).abs() < 0.25 * h, "far wall {far}");
        // Nothing moves outward, and nothing outside the balls changes.
        let depth = region_depth(&g, &balls);
        let mut outside = 0;
        for ((&a, &z), &d) in g.data().iter().zip(before.data()).zip(&depth) {
            assert!(a >= z - 1e-5, "moved outward: {z} → {a}");
            if d < 0.0 {
                assert_eq!(a, z);
                outside += 1;
            }
        }
        assert!(outside > 0);
    }
}
