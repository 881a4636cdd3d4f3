//! Fallback hole filling after Liepa (2003, "Filling holes in meshes", Eurographics Symposium on
//! Geometry Processing): minimum-area triangulation of the 3D rim polygon by dynamic programming
//! (chords that duplicate existing mesh edges are forbidden), or a centroid fan for very long
//! loops; then refinement by centroid splits (density factor √2) with Delaunay edge relaxation,
//! and membrane (umbrella) fairing of the interior vertices.

use super::harmonic::harmonic_fill;
use super::planar::neighbours;
use super::{CapMethod, Patch};
use nalgebra::{Point3, Vector3};
use std::collections::{HashMap, HashSet};

/// Liepa's density factor: a triangle is split when its centroid is farther than σ/√2 from its
/// corners.
const DENSITY: f64 = std::f64::consts::SQRT_2;

/// Closes the loop `pts` (rim vertices, in loop order) with target edge length `h` (world units).
/// Returns the cap, the method used and a phrase saying how.
pub(super) fn cap_fill(
    pts: &[Point3<f64>],
    h: f64,
    max_dp: usize,
    max_new: usize,
    chord_taken: &dyn Fn(usize, usize) -> bool,
) -> (Patch, CapMethod, String) {
    let n = pts.len();
    let mut points: Vec<Point3<f64>> = pts.to_vec();
    let dp = if n <= max_dp {
        min_area_triangulation(pts, chord_taken)
    } else {
        None
    };
    let (mut faces, method, how) = match dp {
        Some(f) => (
            f,
            CapMethod::MinArea,
            "closed with a minimum-area triangulation, refined and faired instead".to_string(),
        ),
        None => {
            let centre =
                Point3::from(pts.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n as f64);
            points.push(centre);
            let why = if n > max_dp {
                format!("the loop is longer than {max_dp} vertices")
            } else {
                "existing mesh edges leave no chord-free triangulation".to_string()
            };
            (
                (0..n).map(|i| [(i + 1) % n, i, n]).collect(),
                CapMethod::CentroidFan,
                format!("closed with a centroid fan, refined and faired instead ({why})"),
            )
        }
    };

    let is_rim_chord = |a: usize, b: usize| a < n && b < n && chord_taken(a, b);
    // Refine: split triangles that are large compared with the target density, relax, repeat.
    for _round in 0..64 {
        let mut split = false;
        let mut next = Vec::with_capacity(faces.len() * 2);
        for &t in &faces {
            let c = Point3::from(
                (points[t[0]].coords + points[t[1]].coords + points[t[2]].coords) / 3.0,
            );
            let far = t.iter().all(|&v| DENSITY * (c - points[v]).norm() > h);
            if far && points.len() - n < max_new {
                let x = points.len();
                points.push(c);
                next.extend([[t[0], t[1], x], [t[1], t[2], x], [t[2], t[0], x]]);
                split = true;
            } else {
                next.push(t);
            }
        }
        faces = next;
        relax_edges(&points, &mut faces, &is_rim_chord);
        if !split {
            break;
        }
    }
    // Fair (membrane), relax once more on the faired shape, fair again.
    for _ in 0..2 {
        fair(&mut points, n, &faces);
        relax_edges(&points, &mut faces, &is_rim_chord);
    }
    fair(&mut points, n, &faces);
    let new_points = points[n..].to_vec();
    (Patch { new_points, faces }, method, how)
}

/// Moves every interior vertex to the harmonic (umbrella) position given the fixed rim.
fn fair(points: &mut [Point3<f64>], n: usize, faces: &[[usize; 3]]) {
    let m = points.len();
    let nb = neighbours(m, faces);
    let fixed: Vec<bool> = (0..m).map(|i| i < n).collect();
    for d in 0..3 {
        let mut v: Vec<f64> = points.iter().map(|p| p[d]).collect();
        harmonic_fill(&nb, &fixed, &mut v);
        for (p, x) in points.iter_mut().zip(v) {
            p[d] = x;
        }
    }
}

/// Minimum-area triangulation of the closed 3D polygon `pts` (dynamic programming over
/// sub-polygons, O(n³)); faces wound against the loop direction. `None` when every triangulation
/// needs a chord the mesh already has.
fn min_area_triangulation(
    pts: &[Point3<f64>],
    chord_taken: &dyn Fn(usize, usize) -> bool,
) -> Option<Vec<[usize; 3]>> {
    let n = pts.len();
    let idx = |i: usize, j: usize| i * n + j;
    let mut w = vec![0.0f64; n * n];
    let mut arg = vec![0u32; n * n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !(i == 0 && j == n - 1) && chord_taken(i, j) {
                w[idx(i, j)] = f64::INFINITY;
                continue;
            }
            let (pi, pj) = (pts[i], pts[j]);
            let mut best = f64::INFINITY;
            let mut best_k = i + 1;
            for k in i + 1..j {
                let s = w[idx(i, k)] + w[idx(k, j)];
                if s >= best {
                    continue;
                }
                let a = 0.5 * (pts[k] - pi).cross(&(pj - pi)).norm();
                if s + a < best {
                    best = s + a;
                    best_k = k;
                }
            }
            w[idx(i, j)] = best;
            arg[idx(i, j)] = best_k as u32;
        }
    }
    if !w[idx(0, n - 1)].is_finite() {
        return None;
    }
    let mut faces = Vec::with_capacity(n - 2);
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j < i + 2 {
            continue;
        }
        let k = arg[idx(i, j)] as usize;
        faces.push([i, j, k]);
        stack.push((i, k));
        stack.push((k, j));
    }
    Some(faces)
}

/// Interior angle at `c` of the triangle (a, b, c).
fn angle_at(c: Point3<f64>, a: Point3<f64>, b: Point3<f64>) -> f64 {
    let (u, v) = (a - c, b - c);
    u.cross(&v).norm().atan2(u.dot(&v))
}

/// Flips interior cap edges that are not locally Delaunay (opposite angles summing to more than
/// π) when the new edge does not exist yet, until none is left (bounded number of passes).
fn relax_edges(
    points: &[Point3<f64>],
    faces: &mut [[usize; 3]],
    is_rim_chord: &dyn Fn(usize, usize) -> bool,
) {
    for _pass in 0..32 {
        // Directed edge → (face, corner of the edge's start).
        let mut half: HashMap<(usize, usize), usize> = HashMap::with_capacity(faces.len() * 3);
        let mut undirected: HashSet<(usize, usize)> = HashSet::with_capacity(faces.len() * 3);
        for (fi, t) in faces.iter().enumerate() {
            for k in 0..3 {
                half.insert((t[k], t[(k + 1) % 3]), fi);
                undirected.insert((t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])));
            }
        }
        let mut touched = vec![false; faces.len()];
        let mut flipped = 0;
        for f1 in 0..faces.len() {
            for k in 0..3 {
                if touched[f1] {
                    break;
                }
                let t1 = faces[f1];
                let (a, b, c) = (t1[k], t1[(k + 1) % 3], t1[(k + 2) % 3]);
                let Some(&f2) = half.get(&(b, a)) else {
                    continue;
                };
                if touched[f2] || f2 == f1 {
                    continue;
                }
                let t2 = faces[f2];
                let d = t2[(0..3).find(|&m| t2[m] != a && t2[m] != b).unwrap_or(0)];
                if d == c || undirected.contains(&(c.min(d), c.max(d))) || is_rim_chord(c, d) {
                    continue;
                }
                let (pa, pb, pc, pd) = (points[a], points[b], points[c], points[d]);
                if angle_at(pc, pa, pb) + angle_at(pd, pa, pb) <= std::f64::consts::PI + 1e-9 {
                    continue;
                }
                // Quad a → d → b → c: new faces (a, d, c) and (d, b, c).
                faces[f1] = [a, d, c];
                faces[f2] = [d, b, c];
                touched[f1] = true;
                touched[f2] = true;
                undirected.insert((c.min(d), c.max(d)));
                flipped += 1;
            }
        }
        if flipped == 0 {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::min_area_triangulation;
    use nalgebra::Point3;

    #[test]
    fn min_area_triangulation_of_a_square_uses_no_forbidden_chord() {
        let p = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        let f = min_area_triangulation(&p, &|i, j| (i, j) == (0, 2)).unwrap();
        assert_eq!(f.len(), 2);
        // The chord 0–2 is forbidden, so both triangles contain vertices 1 and 3.
        assert!(f.iter().all(|t| t.contains(&1) && t.contains(&3)));
        // Wound against the loop: edge 1 → 0 is present.
        assert!(f
            .iter()
            .any(|t| (0..3).any(|k| t[k] == 1 && t[(k + 1) % 3] == 0)));
        assert!(min_area_triangulation(&p, &|i, j| (i, j) == (0, 2) || (i, j) == (1, 3)).is_none());
    }
}
