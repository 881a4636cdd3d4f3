//! Self-checks of a repaired surface before it is written: what a closed, manifold mesh can still
//! get wrong where a patch was stitched in.
//!
//! - **No face inside the solid.** Every triangle near D must separate inside from outside: the
//!   winding number of the output is about 1 just behind it and about 0 just in front of it. A
//!   slit (two coincident sheets across the lumen, left by a stitch that zipped the wrong rims),
//!   a fin or a pocket of faces inside the vessel has inside on both sides.
//! - **No long edges from the stitch.** Near D, no edge that the input does not have longer than
//!   [`LONG_EDGE_FACTOR`] times the input's mean edge and twice its longest edge there (a zipper
//!   that closed across the lumen leaves slivers).
//! - **Outward, and nothing taken away.** The enclosed volume is positive, and the volume in each
//!   ball of D is at least the input's (the damage is missing volume: a repair only adds).
//!
//! `repair` runs them on the stitched surface and, when one fails, re-meshes the whole vessel
//! instead, saying why (paper Section 4 ends Algorithm 4 by re-meshing; the stitch that keeps the
//! input's triangles is this project's addition, so it is the part that is checked).

use super::region::{depth_in, Ball};
use crate::bvh::{WindingNumber, WindingOptions};
use crate::mesh::measures::signed_volume;
use crate::report::stenosis::volume_in_ball_with;
use crate::TriMesh;
use nalgebra::Point3;
use rayon::prelude::*;
use std::collections::HashSet;

/// An edge near D longer than this many mean edges fails the check.
pub const LONG_EDGE_FACTOR: f64 = 4.0;

/// Faces near D whose two sides do not differ (inside behind, outside in front) tolerated, as a
/// fraction of the faces checked (thin features narrower than the probe offset).
const SIDE_TOLERANCE: f64 = 0.002;

/// Checks `output` (the repaired, closed surface) against `input` (the closed input) around the
/// balls of D grown by `reach` (world units). Err names the first check that failed.
pub fn check_repaired(
    output: &TriMesh,
    input: &TriMesh,
    balls: &[Ball],
    reach: f64,
) -> Result<(), String> {
    let volume = signed_volume(output);
    if !(volume > 0.0) {
        return Err(format!(
            "the repaired surface encloses a volume of {volume:.4} (not outward)"
        ));
    }
    let near = |p: &Point3<f64>| depth_in(balls, p) > -reach;
    let v = &output.vertices;
    let key = |a: &Point3<f64>, b: &Point3<f64>| {
        let (a, b) = (a.coords.map(f64::to_bits), b.coords.map(f64::to_bits));
        let (a, b) = ((a.x, a.y, a.z), (b.x, b.y, b.z));
        if a <= b {
            (a, b)
        } else {
            (b, a)
        }
    };
    // The input's own edges (the stitch copies their corners exactly) and their mean length.
    let mut input_edges = HashSet::new();
    let mut total = 0.0;
    for f in &input.faces {
        for e in 0..3 {
            let (a, b) = (
                &input.vertices[f[e] as usize],
                &input.vertices[f[(e + 1) % 3] as usize],
            );
            if input_edges.insert(key(a, b)) {
                total += (b - a).norm();
            }
        }
    }
    let mean = total / input_edges.len().max(1) as f64;
    let near_faces: Vec<usize> = (0..output.faces.len())
        .filter(|&i| output.faces[i].iter().any(|&k| near(&v[k as usize])))
        .collect();
    // A zipper edge spans a rim triangle of the input at most: the limit is the larger of
    // LONG_EDGE_FACTOR mean edges and twice the longest input edge near D.
    let longest_near = input
        .faces
        .iter()
        .filter(|f| f.iter().any(|&k| near(&input.vertices[k as usize])))
        .flat_map(|f| (0..3).map(move |e| (f[e], f[(e + 1) % 3])))
        .map(|(a, b)| (input.vertices[b as usize] - input.vertices[a as usize]).norm())
        .fold(0.0, f64::max);
    let limit = (LONG_EDGE_FACTOR * mean).max(2.0 * longest_near);
    for &i in &near_faces {
        let f = output.faces[i];
        for e in 0..3 {
            let (a, b) = (&v[f[e] as usize], &v[f[(e + 1) % 3] as usize]);
            let len = (b - a).norm();
            if len > limit && !input_edges.contains(&key(a, b)) {
                return Err(format!(
                    "a new edge of {len:.4} near D (the input's mean edge is {mean:.4}, its longest there {longest_near:.4})"
                ));
            }
        }
    }
    let winding = WindingNumber::new(output, WindingOptions::default());
    let eps = 0.1 * mean.min(reach / 3.0);
    let wrong = near_faces
        .par_iter()
        .filter(|&&i| {
            let f = output.faces[i];
            let [a, b, c] = f.map(|k| v[k as usize]);
            let n = (b - a).cross(&(c - a));
            let Some(n) = n.try_normalize(1e-300) else {
                return false;
            };
            let p = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let front = winding.winding_number(&(p + n * eps));
            let back = winding.winding_number(&(p - n * eps));
            !(front < 0.5 && back >= 0.5)
        })
        .count();
    if wrong as f64 > SIDE_TOLERANCE * near_faces.len() as f64 {
        return Err(format!(
            "{wrong} of the {} faces near D do not separate inside from outside (a slit, fin or pocket inside the vessel)",
            near_faces.len()
        ));
    }
    let input_winding = WindingNumber::new(input, WindingOptions::default());
    for (k, ball) in balls.iter().enumerate() {
        let before = volume_in_ball_with(input, &input_winding, ball);
        let after = volume_in_ball_with(output, &winding, ball);
        if after < before - 1e-3 * before.abs().max(ball.radius.powi(3)) {
            return Err(format!(
                "region {} holds less volume after the repair ({after:.4}) than before ({before:.4})",
                k + 1
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::primitives::icosphere;

    fn ball() -> Ball {
        Ball {
            center: Point3::new(1.0, 0.0, 0.0),
            radius: 0.5,
        }
    }

    #[test]
    fn a_sphere_passes() {
        let s = icosphere(3, 1.0, Point3::origin());
        assert_eq!(check_repaired(&s, &s, &[ball()], 0.1), Ok(()));
    }

    #[test]
    fn an_inward_sphere_fails() {
        let s = icosphere(3, 1.0, Point3::origin());
        let mut inward = s.clone();
        inward.flip_faces();
        let e = check_repaired(&inward, &s, &[ball()], 0.1).unwrap_err();
        assert!(e.contains("not outward"), "{e}");
    }

    #[test]
    fn a_slit_inside_fails() {
        // A sphere with a double-sided disc across its inside near D: a slit.
        let s = icosphere(3, 1.0, Point3::origin());
        let mut slit = s.clone();
        let base = slit.vertices.len() as u32;
        for p in [
            [0.6, -0.1, -0.1],
            [0.6, 0.1, -0.1],
            [0.6, 0.1, 0.1],
            [0.6, -0.1, 0.1],
        ] {
            slit.vertices.push(Point3::new(p[0], p[1], p[2]));
        }
        for f in [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]] {
            slit.faces.push(f.map(|k| base + k));
        }
        let e = check_repaired(&slit, &s, &[ball()], 0.1).unwrap_err();
        assert!(e.contains("do not separate"), "{e}");
    }
}
