//! Planar caps: best-fit plane by principal component analysis, simplicity test of the projected
//! polygon, spade's constrained Delaunay triangulation with interior points from Ruppert/Chew
//! Delaunay refinement (rim kept whole), quality optimisation, and lifting back with a harmonic
//! (cotangent-weight finite element) out-of-plane offset.

use super::harmonic::harmonic_fill;
use super::improve::Improver;
use super::Patch;
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use spade::handles::FixedVertexHandle;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};
use std::collections::{HashMap, HashSet};

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// A planar cap and whether the refinement finished within its vertex budget.
pub(super) struct PlanarCap {
    pub patch: Patch,
    pub complete: bool,
}

/// Area of an equilateral triangle of unit edge.
const UNIT_TRIANGLE_AREA: f64 = 0.433_012_701_892_219_3;

/// The best-fit plane of points: centroid and orthonormal (e1, e2, normal) with e1 × e2 = normal,
/// normal along the direction of least variance.
pub(super) fn best_fit_plane(pts: &[Point3<f64>]) -> (Point3<f64>, [Vector3<f64>; 3]) {
    let n = pts.len() as f64;
    let c = Point3::from(pts.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n);
    let mut cov = Matrix3::zeros();
    for p in pts {
        let d = p - c;
        cov += d * d.transpose();
    }
    let eig = SymmetricEigen::new(cov / n);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let e1: Vector3<f64> = eig.eigenvectors.column(order[0]).into_owned().normalize();
    let nrm: Vector3<f64> = eig.eigenvectors.column(order[2]).into_owned().normalize();
    let e2 = nrm.cross(&e1).normalize();
    (c, [e1, e2, nrm])
}

/// Caps a loop through the refined CDT of its projection on the best-fit plane. `h` is the target
/// edge length in world units; `chord_taken(i, j)` says whether rim vertices i and j are already
/// joined by an edge of the mesh (such a chord would become non-manifold). Returns why the planar
/// method does not apply otherwise.
pub(super) fn cap_planar(
    pts: &[Point3<f64>],
    h: f64,
    min_angle_deg: f64,
    max_new: usize,
    chord_taken: &dyn Fn(usize, usize) -> bool,
) -> Result<PlanarCap, String> {
    let n = pts.len();
    let (c, [e1, e2, nrm]) = best_fit_plane(pts);
    // 2D coordinates in units of the target edge length (spade's numerics are then scale-free).
    let q: Vec<[f64; 2]> = pts
        .iter()
        .map(|p| {
            let d = p - c;
            [d.dot(&e1) / h, d.dot(&e2) / h]
        })
        .collect();
    check_simple(&q)?;

    // spade panics only on internal precision failures; treat that as "not applicable".
    let run = std::panic::AssertUnwindSafe(|| triangulate(&q, min_angle_deg, max_new));
    let (pts2, faces, complete) = std::panic::catch_unwind(run)
        .map_err(|_| "the constrained Delaunay triangulation failed".to_string())??;
    let left = max_new.saturating_sub(pts2.len() - n);
    let mut imp = Improver::new(pts2, faces, n, chord_taken);
    imp.split_taken_chords();
    imp.run(4.0, left);
    let (pts2, mut cap_faces) = imp.finish();
    // spade faces are counter-clockwise in (e1, e2); the cap must traverse rim edges against the
    // loop direction (the mesh holds i → i+1).
    let same_as_loop = cap_faces
        .iter()
        .any(|t| (0..3).any(|k| t[k] == 0 && t[(k + 1) % 3] == 1));
    if same_as_loop {
        for t in &mut cap_faces {
            t.swap(1, 2);
        }
    }

    // Lift: harmonic out-of-plane offset with the rim's offsets as boundary values.
    let m = pts2.len();
    let mut offset = vec![0.0; m];
    let mut fixed = vec![false; m];
    for i in 0..n {
        offset[i] = (pts[i] - c).dot(&nrm);
        fixed[i] = true;
    }
    harmonic_fill(&cotan_neighbours(&pts2, &cap_faces), &fixed, &mut offset);
    let new_points = (n..m)
        .map(|k| c + e1 * (pts2[k][0] * h) + e2 * (pts2[k][1] * h) + nrm * offset[k])
        .collect();
    Ok(PlanarCap {
        patch: Patch {
            new_points,
            faces: cap_faces,
        },
        complete,
    })
}

/// Vertex adjacency of a triangle list over `m` vertices, with unit weights.
pub(super) fn neighbours(m: usize, faces: &[[usize; 3]]) -> Vec<Vec<(usize, f64)>> {
    let mut nb: Vec<Vec<(usize, f64)>> = vec![Vec::new(); m];
    for t in faces {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !nb[a].iter().any(|&(v, _)| v == b) {
                nb[a].push((b, 1.0));
                nb[b].push((a, 1.0));
            }
        }
    }
    nb
}

/// Vertex adjacency of a planar triangulation with cotangent weights ½(cot α + cot β), the
/// stiffness matrix of linear finite elements; each weight is kept above a small positive floor
/// so that the discrete maximum principle holds.
fn cotan_neighbours(pts: &[[f64; 2]], faces: &[[usize; 3]]) -> Vec<Vec<(usize, f64)>> {
    let mut w: HashMap<(usize, usize), f64> = HashMap::new();
    for t in faces {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let (u, v) = (
                [pts[a][0] - pts[c][0], pts[a][1] - pts[c][1]],
                [pts[b][0] - pts[c][0], pts[b][1] - pts[c][1]],
            );
            let cross = (u[0] * v[1] - u[1] * v[0]).abs();
            let cot = if cross > 0.0 {
                (u[0] * v[0] + u[1] * v[1]) / cross
            } else {
                0.0
            };
            *w.entry((a.min(b), a.max(b))).or_insert(0.0) += 0.5 * cot;
        }
    }
    let mut nb: Vec<Vec<(usize, f64)>> = vec![Vec::new(); pts.len()];
    for ((a, b), x) in w {
        let x = x.max(1e-3);
        nb[a].push((b, x));
        nb[b].push((a, x));
    }
    // In neighbour order, not the map's (random per run): the solve's sums are then the same
    // bits every time.
    for list in &mut nb {
        list.sort_by_key(|&(v, _)| v);
    }
    nb
}

/// Points (rim first), counter-clockwise triangles, and whether refinement completed.
type Planar2d = (Vec<[f64; 2]>, Vec<[usize; 3]>, bool);

/// The constrained Delaunay triangulation of the rim polygon `q` alone; errors when the polygon
/// is not simple.
fn rim_cdt(q: &[[f64; 2]]) -> Result<Cdt, String> {
    const NOT_SIMPLE: &str = "projection onto its best-fit plane is not a simple polygon";
    let n = q.len();
    let mut cdt = Cdt::new();
    for (i, p) in q.iter().enumerate() {
        let hnd = cdt
            .insert(Point2::new(p[0], p[1]))
            .map_err(|e| format!("projected vertex rejected by the triangulation ({e:?})"))?;
        if hnd.index() != i {
            return Err("two vertices project onto the same point of the best-fit plane".into());
        }
    }
    for i in 0..n {
        let (a, b) = (
            FixedVertexHandle::from_index(i),
            FixedVertexHandle::from_index((i + 1) % n),
        );
        if !cdt.can_add_constraint(a, b) {
            return Err(NOT_SIMPLE.into());
        }
        cdt.add_constraint(a, b);
        if !cdt.exists_constraint(a, b) {
            return Err(NOT_SIMPLE.into());
        }
    }
    if cdt.num_constraints() != n {
        return Err(NOT_SIMPLE.into());
    }
    Ok(cdt)
}

/// Triangulation of the simple polygon `q` (coordinates in units of the target edge length) with
/// interior points graded towards small rim features: returns the points (rim first), the
/// counter-clockwise triangles inside the polygon, and whether refinement completed.
///
/// The interior points come from a full Ruppert refinement of the polygon, which may split rim
/// edges; the split points are dropped (the rim must keep its vertices) and the rim with the
/// remaining interior points is triangulated again.
fn triangulate(q: &[[f64; 2]], min_angle_deg: f64, max_new: usize) -> Result<Planar2d, String> {
    let n = q.len();
    let area = polygon_area(q).abs();
    // Vertex budget: several times what the area needs at the target size, within the caller's cap.
    let budget = ((8.0 * area / UNIT_TRIANGLE_AREA) as usize + 10 * n + 100).min(max_new);
    let mut graded = rim_cdt(q)?;
    let result = graded.refine(
        RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .with_angle_limit(AngleLimit::from_deg(min_angle_deg.clamp(0.0, 34.0)))
            .with_max_allowed_area(1.6 * UNIT_TRIANGLE_AREA)
            .with_max_additional_vertices(budget),
    );
    let excluded: HashSet<_> = result.excluded_faces.iter().copied().collect();
    let mut interior: Vec<Point2<f64>> = Vec::new();
    for v in graded.vertices().skip(n) {
        let on_rim = v.out_edges().any(|e| e.is_constraint_edge());
        let inside = v.out_edges().any(|e| {
            e.face()
                .as_inner()
                .is_some_and(|f| !excluded.contains(&f.fix()))
        });
        if inside && !on_rim {
            interior.push(v.position());
        }
    }

    let mut cdt = rim_cdt(q)?;
    for p in interior {
        cdt.insert(p)
            .map_err(|e| format!("interior point rejected ({e:?})"))?;
    }
    // A refinement with no vertex budget only classifies the faces inside and outside the rim.
    let outer: HashSet<_> = cdt
        .refine(
            RefinementParameters::<f64>::new()
                .exclude_outer_faces(true)
                .keep_constraint_edges()
                .with_max_additional_vertices(0),
        )
        .excluded_faces
        .into_iter()
        .collect();
    if cdt.num_constraints() != n {
        return Err("the triangulation split the rim".into());
    }
    let pts = cdt
        .vertices()
        .map(|v| [v.position().x, v.position().y])
        .collect();
    let faces = cdt
        .inner_faces()
        .filter(|f| !outer.contains(&f.fix()))
        .map(|f| f.vertices().map(|v| v.fix().index()))
        .collect();
    Ok((pts, faces, result.refinement_complete))
}

/// Signed area of a polygon (positive when counter-clockwise).
fn polygon_area(q: &[[f64; 2]]) -> f64 {
    let n = q.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (q[i], q[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Checks that the closed polygon `q` (coordinates in units of about one edge) is simple with a
/// margin: no two non-adjacent edges meet or come within `tol` of touching, no two adjacent edges
/// fold back onto each other, and the polygon has area.
fn check_simple(q: &[[f64; 2]]) -> Result<(), String> {
    const NOT_SIMPLE: &str = "projection onto its best-fit plane is not a simple polygon";
    let n = q.len();
    let extent = q
        .iter()
        .fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()))
        .max(1.0);
    let tol = 1e-9 * extent;
    if polygon_area(q).abs() <= tol * extent {
        return Err(NOT_SIMPLE.into());
    }
    let seg = |i: usize| (q[i], q[(i + 1) % n]);
    // Adjacent edges must not overlap (a spike of angle zero).
    for i in 0..n {
        let (a, b, c) = (q[(i + n - 1) % n], q[i], q[(i + 1) % n]);
        let (u, v) = ([a[0] - b[0], a[1] - b[1]], [c[0] - b[0], c[1] - b[1]]);
        let (lu, lv) = (u[0].hypot(u[1]), v[0].hypot(v[1]));
        if lu <= tol || lv <= tol {
            return Err(NOT_SIMPLE.into());
        }
        let cross = (u[0] * v[1] - u[1] * v[0]) / (lu * lv);
        let dot = u[0] * v[0] + u[1] * v[1];
        if cross.abs() <= 1e-12 && dot > 0.0 {
            return Err(NOT_SIMPLE.into());
        }
    }
    // Bounding boxes first, then orientation tests.
    let bbox: Vec<[f64; 4]> = (0..n)
        .map(|i| {
            let (a, b) = seg(i);
            [
                a[0].min(b[0]) - tol,
                a[0].max(b[0]) + tol,
                a[1].min(b[1]) - tol,
                a[1].max(b[1]) + tol,
            ]
        })
        .collect();
    // Candidate pairs from a uniform grid of cells about one mean edge wide.
    let mean = bbox
        .iter()
        .map(|b| (b[1] - b[0]).max(b[3] - b[2]))
        .sum::<f64>()
        / n as f64;
    let (x0, y0) = (
        bbox.iter().map(|b| b[0]).fold(f64::INFINITY, f64::min),
        bbox.iter().map(|b| b[2]).fold(f64::INFINITY, f64::min),
    );
    let cell = mean.max(1e-12);
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, b) in bbox.iter().enumerate() {
        let cx = |x: f64| ((x - x0) / cell).floor() as i64;
        let cy = |y: f64| ((y - y0) / cell).floor() as i64;
        for gx in cx(b[0])..=cx(b[1]) {
            for gy in cy(b[2])..=cy(b[3]) {
                grid.entry((gx, gy)).or_default().push(i);
            }
        }
    }
    for segs in grid.values() {
        for (u, &i) in segs.iter().enumerate() {
            for &j in &segs[u + 1..] {
                let (i, j) = (i.min(j), i.max(j));
                if j == i + 1 || (i == 0 && j == n - 1) {
                    continue; // adjacent edges share a vertex
                }
                let (bi, bj) = (bbox[i], bbox[j]);
                if bi[1] < bj[0] || bj[1] < bi[0] || bi[3] < bj[2] || bj[3] < bi[2] {
                    continue;
                }
                let ((a, b), (c, d)) = (seg(i), seg(j));
                if segments_close(a, b, c, d, tol) {
                    return Err(NOT_SIMPLE.into());
                }
            }
        }
    }
    Ok(())
}

/// Whether segments ab and cd intersect or pass within `tol` of each other.
fn segments_close(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2], tol: f64) -> bool {
    let (o1, o2, o3, o4) = (
        orient(a, b, c),
        orient(a, b, d),
        orient(c, d, a),
        orient(c, d, b),
    );
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0))
        && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0))
    {
        return true;
    }
    point_segment_distance(c, a, b) <= tol
        || point_segment_distance(d, a, b) <= tol
        || point_segment_distance(a, c, d) <= tol
        || point_segment_distance(b, c, d) <= tol
}

fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let l2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if l2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
}

#[cfg(test)]
mod tests {
    use super::check_simple;

    #[test]
    fn simplicity_test_accepts_square_and_rejects_bowtie() {
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(check_simple(&square).is_ok());
        let bowtie = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(check_simple(&bowtie).is_err());
        // A vertex touching a non-adjacent edge.
        let touching = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, 0.0], [0.0, 2.0]];
        assert!(check_simple(&touching).is_err());
    }
}
