//! The axial fill of D: the signed distance φ_0 carried across D along the vessel axis. Each
//! node x of D takes the linear interpolation, along the line through x parallel to the axis a,
//! between the known values where that line leaves D on either side:
//! ψ(x) = (t₋ φ_0(x + t₊a) + t₊ φ_0(x − t₋a)) / (t₊ + t₋).
//! This is Laplace's equation (the harmonic transfer of the inpainting scheme of Cai, Chan and
//! Shen that the paper's Algorithm 4 follows) restricted to the axis direction: the distance to a
//! straight tube does not vary along its axis, so a tube, a narrowing, an occlusion or a chopped
//! wall inside D are filled exactly; a gently curved vessel is filled with an error of the order
//! of the sagitta of its axis over D. The curvature motion that follows smooths what is left.

use super::region::{deepest_ball, Ball};
use crate::grid::{Grid3, SubBox};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// Replaces `phi` at the nodes inside the union of `balls` by the axial interpolation of the
/// module docs; node x uses the candidate axes `axes[b]` of the ball b in which it lies deepest,
/// and of those the one whose two line ends disagree least, lines with both ends on the same side
/// of the surface first (several candidates: the branches of a junction). Where a line leaves the grid before D, the other end alone is used.
/// `phi` must be a true signed distance around D. Returns the number of nodes filled.
pub fn fill_axial(phi: &mut Grid3, balls: &[Ball], axes: &[Vec<Vector3<f64>>]) -> Result<usize> {
    if balls.len() != axes.len() || balls.is_empty() {
        return Err(Error::Geometry(format!(
            "axial fill: {} balls and {} axes",
            balls.len(),
            axes.len()
        )));
    }
    let axes: Vec<Vec<Vector3<f64>>> = axes
        .iter()
        .map(|list| {
            list.iter()
                .filter_map(|a| a.try_normalize(1e-12))
                .collect::<Vec<_>>()
        })
        .collect();
    if let Some(b) = axes.iter().position(|list| list.is_empty()) {
        return Err(Error::Geometry(format!(
            "axial fill: no axis for region {}",
            b + 1
        )));
    }
    let [nx, ny, _] = phi.dims();
    let t = *phi.transform();
    let h = phi.voxel();
    let source = phi.clone();
    // Where the line p + s·dir (s > 0) leaves the union of the balls: jump to the far side of
    // every ball that holds the current point until none does (exact; each jump leaves a ball
    // for good, so at most one jump per ball).
    let exit = |p: &Point3<f64>, dir: &Vector3<f64>| -> Option<(f64, f64)> {
        let mut s = 0.0;
        for _ in 0..=balls.len() {
            let q = p + dir * s;
            let mut far = s;
            for ball in balls {
                let m = q - ball.center;
                let c = m.norm_squared() - ball.radius * ball.radius;
                if c < 0.0 {
                    let b = m.dot(dir);
                    far = far.max(s + (-b + (b * b - c).sqrt()));
                }
            }
            if far <= s {
                break;
            }
            // A hair beyond the sphere, so rounding does not leave the point inside it.
            s = far + 1e-6 * h;
        }
        let q = p + dir * s;
        source.sample_trilinear(&q).map(|v| (s, v))
    };
    // Only nodes within the balls' bounding box can lie in D: per z-layer of that box, the
    // layer's rows within it, written in place.
    let lo = balls.iter().fold(Point3::from([f64::INFINITY; 3]), |m, b| {
        m.inf(&(b.center - Vector3::repeat(b.radius)))
    });
    let hi = balls
        .iter()
        .fold(Point3::from([f64::NEG_INFINITY; 3]), |m, b| {
            m.sup(&(b.center + Vector3::repeat(b.radius)))
        });
    let inside = SubBox::around_world(&lo, &hi, &t, phi.dims());
    let layer = nx * ny;
    let value_at = |i: usize, j: usize, k: usize| -> Option<f32> {
        let p = t.index_to_world(Vector3::new(i as f64, j as f64, k as f64));
        let (d, b) = deepest_ball(balls, &p);
        if d <= 0.0 {
            return None;
        }
        // Each candidate axis gives a value; the line whose two ends agree best runs along
        // a vessel (on a straight tube they agree exactly).
        // Lines whose ends lie on the same side of the surface come first.
        let mut best: Option<(f64, (bool, f64))> = None;
        for a in &axes[b] {
            let (value, rank) = match (exit(&p, a), exit(&p, &-a)) {
                (Some((tp, vp)), Some((tm, vm))) => (
                    (tm * vp + tp * vm) / (tp + tm),
                    ((vp < 0.0) != (vm < 0.0), (vp - vm).abs()),
                ),
                (Some((_, v)), None) | (None, Some((_, v))) => (v, (true, f64::INFINITY)),
                (None, None) => continue,
            };
            if best.is_none_or(|(_, r)| rank < r) {
                best = Some((value, rank));
            }
        }
        Some(best.map_or(source.data()[i + nx * (j + ny * k)], |(v, _)| v as f32))
    };
    let filled: usize = phi
        .data_mut()
        .par_chunks_mut(layer)
        .enumerate()
        .filter(|(k, _)| (inside.min[2]..inside.max[2]).contains(k))
        .map(|(k, slab)| {
            let mut count = 0;
            for j in inside.min[1]..inside.max[1] {
                for i in inside.min[0]..inside.max[0] {
                    if let Some(v) = value_at(i, j, k) {
                        slab[i + nx * j] = v;
                        count += 1;
                    }
                }
            }
            count
        })
        .sum();
    Ok(filled)
}
