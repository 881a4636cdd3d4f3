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
//! - **In no more pieces than the input.** A piece of the patch apart from the vessel (a speck
//!   of the grid, a blob in the lumen's outside) is no part of a repair.
//! - **Outward, and nothing taken away.** The enclosed volume is positive, and the volume in each
//!   ball of D is at least the input's (the damage is missing volume: a repair only adds), less
//!   what only a hole's cap held outside the vessel, which the fill does not keep
//!   ([`RepairChecks::allowing`]).
//!
//! `repair` runs them on the stitched surface and, when one fails, re-meshes the whole vessel
//! instead, saying why (paper Section 4 ends Algorithm 4 by re-meshing; the stitch that keeps the
//! input's triangles is this project's addition, so it is the part that is checked).

use super::region::{depth_in, Ball};
use crate::bvh::{WindingNumber, WindingOptions};
use crate::mesh::measures::{mean_edge_length, signed_volume};
use crate::mesh::topology::connected_components;
use crate::report::repair_report::Measured;
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

/// At most this many faces near D have their two sides probed (evenly strided).
const SIDE_SAMPLES: usize = 4000;

/// An undirected edge by the exact bits of its corners (the stitch copies the input's corners
/// exactly, so an input edge in the output has the same key).
type EdgeKey = ((u64, u64, u64), (u64, u64, u64));

fn edge_key(a: &Point3<f64>, b: &Point3<f64>) -> EdgeKey {
    let (a, b) = (a.coords.map(f64::to_bits), b.coords.map(f64::to_bits));
    let (a, b) = ((a.x, a.y, a.z), (b.x, b.y, b.z));
    if a <= b {
        (a, b)
    } else {
        (b, a)
    }
}

/// What the checks need of the input, measured once for every surface checked against it
/// (`repair` checks one stitch per cut depth it tries).
pub struct RepairChecks<'a> {
    balls: &'a [Ball],
    /// Faces and edges within this distance outside D are checked, world units.
    reach: f64,
    input_edges: HashSet<EdgeKey>,
    /// The input's mean edge and its longest edge near D, world units.
    mean: f64,
    longest_near: f64,
    /// The input's connected pieces.
    input_pieces: usize,
    /// The input's fast winding number and volume inside each ball (the report reads them).
    input: Measured,
    /// Per ball, the volume the output may hold less than the input, world units³.
    allowed_loss: Vec<f64>,
}

impl<'a> RepairChecks<'a> {
    /// The checks of surfaces repaired from `input` (the closed input) in `balls`, around the
    /// balls grown by `reach` (world units).
    pub fn new(input: &TriMesh, balls: &'a [Ball], reach: f64) -> Self {
        let near = |k: u32| depth_in(balls, &input.vertices[k as usize]) > -reach;
        let mut input_edges = HashSet::new();
        let mut longest_near: f64 = 0.0;
        for f in &input.faces {
            let touches = f.iter().any(|&k| near(k));
            for e in 0..3 {
                let (a, b) = (
                    &input.vertices[f[e] as usize],
                    &input.vertices[f[(e + 1) % 3] as usize],
                );
                input_edges.insert(edge_key(a, b));
                if touches {
                    longest_near = longest_near.max((b - a).norm());
                }
            }
        }
        RepairChecks {
            balls,
            reach,
            input_edges,
            mean: mean_edge_length(input),
            longest_near,
            input_pieces: connected_components(input).0,
            input: Measured::new(input, balls),
            allowed_loss: Vec::new(),
        }
    }

    /// The checks allowing, per ball, for `cap_outside` (world units³): the volume of the capped
    /// input that only a hole's cap held outside the vessel, which the fill did not keep
    /// (`Repair::cap_outside`). That volume is estimated by the fill grid's cells, so twice it
    /// may be missing from the output in the ball.
    pub fn allowing(mut self, cap_outside: &[f64]) -> Self {
        self.allowed_loss = cap_outside.iter().map(|v| 2.0 * v.max(0.0)).collect();
        self
    }

    /// The input's fast winding number (`WindingOptions::SIDES`) and volume in each ball, measured
    /// once by [`RepairChecks::new`].
    pub fn into_input(self) -> Measured {
        self.input
    }

    /// Checks `output` (the repaired, closed surface). Err names the first check that failed;
    /// Ok gives the output's fast winding number (`WindingOptions::SIDES`) and volume in each
    /// ball, which the checks measure.
    pub fn check(&self, output: &TriMesh) -> Result<Measured, String> {
        let (mean, longest_near) = (self.mean, self.longest_near);
        let volume = signed_volume(output);
        if !(volume > 0.0) {
            return Err(format!(
                "the repaired surface encloses a volume of {volume:.4} (not outward)"
            ));
        }
        let v = &output.vertices;
        let near_faces: Vec<usize> = (0..output.faces.len())
            .filter(|&i| {
                output.faces[i]
                    .iter()
                    .any(|&k| depth_in(self.balls, &v[k as usize]) > -self.reach)
            })
            .collect();
        // A zipper edge spans a rim triangle of the input at most: the limit is the larger of
        // LONG_EDGE_FACTOR mean edges and twice the longest input edge near D.
        let limit = (LONG_EDGE_FACTOR * mean).max(2.0 * longest_near);
        for &i in &near_faces {
            let f = output.faces[i];
            for e in 0..3 {
                let (a, b) = (&v[f[e] as usize], &v[f[(e + 1) % 3] as usize]);
                let len = (b - a).norm();
                if len > limit && !self.input_edges.contains(&edge_key(a, b)) {
                    return Err(format!(
                        "a new edge of {len:.4} near D (the input's mean edge is {mean:.4}, its longest there {longest_near:.4})"
                    ));
                }
            }
        }
        let winding = WindingNumber::new(output, WindingOptions::SIDES);
        let eps = 0.1 * mean.min(self.reach / 3.0);
        // Evenly strided faces, at most SIDE_SAMPLES: a slit, fin or pocket spans many faces.
        let stride = near_faces.len().div_ceil(SIDE_SAMPLES).max(1);
        let sampled: Vec<usize> = near_faces.iter().step_by(stride).copied().collect();
        let wrong = faces_not_facing_out(output, &winding, &sampled, eps);
        if wrong as f64 > SIDE_TOLERANCE * sampled.len() as f64 {
            return Err(format!(
                "{wrong} of {} faces sampled near D do not separate inside from outside (a slit, fin or pocket inside the vessel)",
                sampled.len()
            ));
        }
        let pieces = connected_components(output).0;
        if pieces > self.input_pieces {
            return Err(format!(
                "the repaired surface is in {pieces} pieces, the input in {} (a piece apart from the vessel)",
                self.input_pieces
            ));
        }
        let mut volumes = Vec::with_capacity(self.balls.len());
        for (k, (ball, &before)) in self.balls.iter().zip(&self.input.volumes).enumerate() {
            let after = volume_in_ball_with(output, &winding, ball);
            let allowed = self.allowed_loss.get(k).copied().unwrap_or(0.0);
            if after < before - allowed - 1e-3 * before.abs().max(ball.radius.powi(3)) {
                return Err(format!(
                    "region {} holds less volume after the repair ({after:.4}) than before ({before:.4})",
                    k + 1
                ));
            }
            volumes.push(after);
        }
        Ok(Measured { winding, volumes })
    }
}

/// How many of `faces` (indices into `mesh`) do not separate inside from outside: the winding
/// number (`winding`, of `mesh`) `eps` in front of the face's centroid, along its normal, is not
/// below ½, or `eps` behind it is not at least ½. A slit, fin or pocket inside the solid has
/// inside on both sides; a triangle folded over (facing in) has inside in front. Degenerate
/// faces are not counted.
pub fn faces_not_facing_out(
    mesh: &TriMesh,
    winding: &WindingNumber,
    faces: &[usize],
    eps: f64,
) -> usize {
    let v = &mesh.vertices;
    faces
        .par_iter()
        .filter(|&&i| {
            let [a, b, c] = mesh.faces[i].map(|k| v[k as usize]);
            let Some(n) = (b - a).cross(&(c - a)).try_normalize(1e-300) else {
                return false;
            };
            let p = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let front = winding.winding_number(&(p + n * eps));
            let back = winding.winding_number(&(p - n * eps));
            !(front < 0.5 && back >= 0.5)
        })
        .count()
}

/// Checks `output` (the repaired, closed surface) against `input` (the closed input) around the
/// balls of D grown by `reach` (world units): [`RepairChecks`] for one surface.
pub fn check_repaired(
    output: &TriMesh,
    input: &TriMesh,
    balls: &[Ball],
    reach: f64,
) -> Result<(), String> {
    RepairChecks::new(input, balls, reach)
        .check(output)
        .map(|_| ())
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
    fn a_piece_apart_from_the_vessel_fails() {
        let s = icosphere(3, 1.0, Point3::origin());
        let mut two = s.clone();
        two.append(&icosphere(1, 0.01, Point3::new(1.2, 0.0, 0.0)));
        let e = check_repaired(&two, &s, &[ball()], 0.1).unwrap_err();
        assert!(e.contains("in 2 pieces, the input in 1"), "{e}");
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
