//! The junction fill of D: where three or more branches cross ∂D (a bifurcation), each branch is
//! continued into D as a capsule from its crossing to the junction point J (the point nearest to
//! all the branch axes, in least squares), with the radius the branch has at its crossing; the
//! fill is the smooth union of the capsules. A vessel tree is locally such a union of tubes
//! (paper Section 4: the inpainted shape follows the intact branches around D).

use crate::grid::Grid3;
use crate::{Error, Result};
use nalgebra::{Matrix3, Point3, Vector3};
use rayon::prelude::*;

/// One branch where it crosses ∂D: a point on its axis, its axis and its radius (world units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Branch {
    /// A point on the axis (the centroid of the crossing loop).
    pub center: Point3<f64>,
    /// The axis direction (unit; sign arbitrary).
    pub axis: Vector3<f64>,
    /// The branch radius, world units.
    pub radius: f64,
}

/// The point nearest to all the branch axes in least squares; None when the axes are parallel.
pub fn junction_point(branches: &[Branch]) -> Option<Point3<f64>> {
    let mut a = Matrix3::zeros();
    let mut b = Vector3::zeros();
    for br in branches {
        let p = Matrix3::identity() - br.axis * br.axis.transpose();
        a += p;
        b += p * br.center.coords;
    }
    let x = a.try_inverse()? * b;
    Some(Point3::from(x))
}

/// Polynomial smooth minimum of width `k` (world units).
pub(crate) fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

fn segment_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// Replaces `phi` at the nodes where `unknown` is true by the signed distance to the smooth union
/// of the capsules (see the module docs). Errors with fewer than two branches or parallel axes.
pub fn fill_junction(phi: &mut Grid3, unknown: &[bool], branches: &[Branch]) -> Result<()> {
    if branches.len() < 2 {
        return Err(Error::Geometry(
            "junction fill: fewer than two branches".into(),
        ));
    }
    let j = junction_point(branches)
        .ok_or_else(|| Error::Geometry("junction fill: the branch axes are parallel".into()))?;
    let k = 0.25
        * branches
            .iter()
            .map(|b| b.radius)
            .fold(f64::INFINITY, f64::min);
    let [nx, ny, _] = phi.dims();
    let t = *phi.transform();
    phi.data_mut()
        .par_iter_mut()
        .enumerate()
        .filter(|(n, _)| unknown[*n])
        .for_each(|(n, v)| {
            let p = t.index_to_world(Vector3::new(
                (n % nx) as f64,
                ((n / nx) % ny) as f64,
                (n / (nx * ny)) as f64,
            ));
            let mut d = f64::INFINITY;
            for b in branches {
                let di = segment_distance(&p, &b.center, &j) - b.radius;
                d = if d.is_finite() {
                    smooth_min(d, di, k)
                } else {
                    di
                };
            }
            *v = d as f32;
        });
    Ok(())
}
