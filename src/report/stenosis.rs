//! Stenosis and inpainted-volume measures of a repaired vessel (issue 6, point 4): how much of a
//! region D (a ball) the solid fills before and after repair, and how narrow the input lumen is
//! inside D compared with the repaired (output) lumen and with the input's own lumen next to D.
//! The paper (Dong, Chien, Shen and Osher, Section 4) judges its recovered vessels by eye; these
//! are the numbers that stand in for that judgement.
//!
//! - [`volume_in_ball`]: volume of the solid bounded by a closed mesh inside a ball, by the
//!   divergence theorem on the boundary of (solid ∩ ball) with the field x − c (c the ball's
//!   centre): V = ⅓ ∮ (x − c)·n dA. On the mesh part (each triangle clipped to the ball) the
//!   integrand is the constant signed distance d of the triangle's plane from c, so that part is
//!   ⅓ Σ d·area(triangle ∩ ball), computed exactly (triangle ∩ disk in the triangle's plane). On
//!   the sphere part the integrand is the radius r, so that part is r³Ω/3 with Ω the solid angle
//!   of the sphere inside the solid; Ω is integrated over a subdivided icosahedron whose spherical
//!   triangles are split wherever a corner is nearer the surface than the triangle is wide, each
//!   corner classified by the generalized winding number; at the finest level the inside part of
//!   a triangle cut by the surface is that of the linear interpolant of the corners' signed
//!   distances.
//! - [`local_axis`]: the vessel's direction near a point, the eigenvector of smallest eigenvalue
//!   of the area-weighted covariance Σ A n nᵀ of the unit normals of the surface inside a ball
//!   (a tube's normals are all perpendicular to its axis).
//! - [`cross_section`]: the closed polygon where a plane ⟂ the axis cuts the mesh, chosen as the
//!   smallest loop enclosing the point (or the nearest loop), with its area and equivalent
//!   diameter 2√(A/π).
//! - [`measure_stenosis`]: sections of input and output across D along the output's axis;
//!   diameter and area stenosis (1 − input/output at the input's narrowest section) and the
//!   NASCET degree (1 − narrowest input / input diameter just outside D), in percent.

use crate::bvh::{solid_angle, MeshBvh, WindingNumber, WindingOptions};
use crate::inpaint::region::Ball;
use crate::mesh::primitives::icosphere;
use crate::{Error, Result, TriMesh};
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;

/// Subdivisions of the icosahedron that starts the sphere integration (1280 triangles, corners
/// about 0.15 r apart).
const SPHERE_BASE_LEVEL: usize = 3;
/// Further halvings of the spherical triangles near the surface (leaf corners about 0.01 r
/// apart; one more halving doubles the time and gained under 2e-5 relative in the tests).
const SPHERE_REFINE_DEPTH: usize = 4;

/// Volume (world units³) of the solid bounded by `mesh` inside `ball` (see the module docs).
/// Exact on the mesh's part of the boundary; the sphere's part is integrated adaptively
/// (relative errors up to 3e-5 measured against a polygonal tube, a slab and a box edge and
/// corner). The mesh should be closed (an open vessel end far from the ball does no harm: the
/// winding number is then still near 1 inside); either orientation is accepted. Returns 0 for a ball whose radius is not
/// positive and finite or whose centre is not finite, and for an empty mesh.
pub fn volume_in_ball(mesh: &TriMesh, ball: &Ball) -> f64 {
    if !ball_is_valid(ball) || mesh.faces.is_empty() {
        return 0.0;
    }
    let winding = WindingNumber::new(mesh, WindingOptions::SIDES);
    volume_in_ball_with(mesh, &winding, ball)
}

/// [`volume_in_ball`] with a prebuilt winding number of `mesh` (its hierarchy also finds the
/// triangles inside the ball).
pub fn volume_in_ball_with(mesh: &TriMesh, winding: &WindingNumber, ball: &Ball) -> f64 {
    if !ball_is_valid(ball) || winding.bvh().is_empty() {
        return 0.0;
    }
    let sign = orientation_sign(mesh, &ball.center);
    let bvh = winding.bvh();
    let r = ball.radius;
    // Summed in face order, not the BVH's leaf order (its build need not be the same from run
    // to run), so the figure is the same bits every time.
    let mut slots = slots_in_ball(bvh, &ball.center, r);
    slots.sort_by_key(|&slot| bvh.slot_face(slot));
    let mesh_part: f64 = slots
        .iter()
        .map(|&slot| {
            let clip = clip_triangle_to_ball(bvh.slot_triangle(slot), &ball.center, r);
            clip.plane_distance * clip.area
        })
        .sum::<f64>()
        / 3.0;
    let probe = SphereProbe {
        mesh,
        winding,
        ball,
        sign,
    };
    let omega = probe.solid_angle_inside();
    sign * mesh_part + r * r * r * omega / 3.0
}

/// +1 for an outward-facing mesh, −1 for an inward-facing one: the sign of the volume of the
/// cones from `p` to the triangles (for an open vessel with `p` inside it, the cones close the
/// open ends through the lumen). Faces with out-of-range indices are skipped.
fn orientation_sign(mesh: &TriMesh, p: &Point3<f64>) -> f64 {
    let nv = mesh.vertices.len();
    let mut sum = 0.0;
    for f in &mesh.faces {
        if f.iter().any(|&i| i as usize >= nv) {
            continue;
        }
        let [a, b, c] = f.map(|i| mesh.vertices[i as usize] - p);
        let v = a.dot(&b.cross(&c));
        if v.is_finite() {
            sum += v;
        }
    }
    if sum < 0.0 {
        -1.0
    } else {
        1.0
    }
}

fn ball_is_valid(ball: &Ball) -> bool {
    ball.radius.is_finite() && ball.radius > 0.0 && ball.center.iter().all(|c| c.is_finite())
}

/// Leaf slots of `bvh` whose (padded) boxes come within `r` of `c`: a superset of the triangles
/// that meet the ball.
fn slots_in_ball(bvh: &MeshBvh, c: &Point3<f64>, r: f64) -> Vec<usize> {
    let mut out = Vec::new();
    if bvh.is_empty() {
        return out;
    }
    let q = c.coords - bvh.local_origin();
    let r2 = r * r;
    let box_d2 = |node: usize| {
        let (lo, hi) = bvh.node_box_local(node);
        (0..3)
            .map(|k| {
                let e = (lo[k] - q[k]).max(q[k] - hi[k]).max(0.0);
                e * e
            })
            .sum::<f64>()
    };
    let nodes = &bvh.obvhs_bvh().nodes;
    let mut stack = vec![0usize];
    while let Some(n) = stack.pop() {
        if box_d2(n) > r2 {
            continue;
        }
        let node = &nodes[n];
        if node.is_leaf() {
            let first = node.first_index as usize;
            out.extend(first..first + node.prim_count as usize);
        } else {
            stack.push(node.first_index as usize);
            stack.push(node.first_index as usize + 1);
        }
    }
    out
}

/// A triangle clipped to a ball.
struct ClippedTriangle {
    /// Area of the triangle inside the ball, world units².
    area: f64,
    /// Signed distance n̂·(a − c) of the triangle's plane from the ball's centre (n̂ the unit
    /// normal of (b − a) × (c − a)), world units.
    plane_distance: f64,
    /// Unit normal (zero for a degenerate triangle).
    normal: Vector3<f64>,
}

/// Area of triangle `t` inside the ball (centre `c`, radius `r`): the ball cuts the triangle's
/// plane in a disk, and the area of triangle ∩ disk is the sum over the edges of the signed area
/// of (disk centre, edge) ∩ disk.
fn clip_triangle_to_ball(t: &[Point3<f64>; 3], c: &Point3<f64>, r: f64) -> ClippedTriangle {
    let [a, b, cc] = t;
    let raw = (b - a).cross(&(cc - a));
    let len = raw.norm();
    let none = ClippedTriangle {
        area: 0.0,
        plane_distance: 0.0,
        normal: Vector3::zeros(),
    };
    if !(len > 0.0 && len.is_finite()) {
        return none;
    }
    let n = raw / len;
    let d = n.dot(&(a - c));
    if d.abs() >= r {
        return ClippedTriangle { normal: n, ..none };
    }
    let full = ClippedTriangle {
        area: 0.5 * len,
        plane_distance: d,
        normal: n,
    };
    if t.iter().all(|v| (v - c).norm_squared() <= r * r) {
        return full;
    }
    let rho2 = r * r - d * d;
    let o = c + n * d;
    let e1 = (b - a).normalize();
    let e2 = n.cross(&e1);
    let p2 = t.map(|v| {
        let w = v - o;
        [w.dot(&e1), w.dot(&e2)]
    });
    let area: f64 = (0..3)
        .map(|k| disk_wedge_area(p2[k], p2[(k + 1) % 3], rho2))
        .sum();
    ClippedTriangle {
        area: area.abs().min(full.area),
        ..full
    }
}

/// Signed area of the triangle (origin, p, q) inside the disk of squared radius `rho2` about the
/// origin (2D): the pieces of pq inside the disk contribute their triangle with the origin, the
/// pieces outside their circular sector.
fn disk_wedge_area(p: [f64; 2], q: [f64; 2], rho2: f64) -> f64 {
    let dx = [q[0] - p[0], q[1] - p[1]];
    let a = dx[0] * dx[0] + dx[1] * dx[1];
    let b = p[0] * dx[0] + p[1] * dx[1];
    let c = p[0] * p[0] + p[1] * p[1] - rho2;
    let mut ts = [0.0, 1.0, 1.0, 1.0];
    let mut n = 1;
    if a > 0.0 {
        let disc = b * b - a * c;
        if disc > 0.0 {
            let sq = disc.sqrt();
            for t in [(-b - sq) / a, (-b + sq) / a] {
                if t > 0.0 && t < 1.0 {
                    ts[n] = t;
                    n += 1;
                }
            }
        }
    }
    ts[n] = 1.0;
    let at = |t: f64| [p[0] + t * dx[0], p[1] + t * dx[1]];
    let mut sum = 0.0;
    for k in 0..n {
        let (t0, t1) = (ts[k], ts[k + 1]);
        let (u, v) = (at(t0), at(t1));
        let cross = u[0] * v[1] - u[1] * v[0];
        let m = at(0.5 * (t0 + t1));
        if m[0] * m[0] + m[1] * m[1] <= rho2 {
            sum += 0.5 * cross;
        } else {
            let dot = u[0] * v[0] + u[1] * v[1];
            sum += 0.5 * rho2 * cross.atan2(dot);
        }
    }
    sum
}

/// A corner of the sphere integration: unit direction, whether the point of the sphere there is
/// inside the solid, and its distance to the surface (∞ beyond the bound it was queried with).
#[derive(Clone, Copy)]
struct SphereCorner {
    dir: Vector3<f64>,
    inside: bool,
    dist: f64,
}

/// Probes the sphere of a ball for the part of it inside a solid (winding number × `sign` ≥ ½).
struct SphereProbe<'a> {
    mesh: &'a TriMesh,
    winding: &'a WindingNumber,
    ball: &'a Ball,
    sign: f64,
}

impl SphereProbe<'_> {
    /// Solid angle (steradians) of the part of the ball's sphere inside the solid.
    fn solid_angle_inside(&self) -> f64 {
        let base = icosphere(SPHERE_BASE_LEVEL, 1.0, Point3::origin());
        let chord = base
            .faces
            .iter()
            .flat_map(|f| {
                let [a, b, c] = f.map(|i| base.vertices[i as usize]);
                [(b - a).norm(), (c - b).norm(), (a - c).norm()]
            })
            .fold(0.0, f64::max);
        // Every point of a triangle lies within its longest chord of each corner; 20 % more for
        // the spherical triangle bulging past its chords.
        let base_reach = 1.2 * chord * self.ball.radius;
        let corners: Vec<SphereCorner> = base
            .vertices
            .par_iter()
            .map(|v| self.corner(v.coords, base_reach, None))
            .collect();
        base.faces
            .par_iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| corners[i as usize]);
                self.triangle([a, b, c], base_reach, 0)
            })
            // Summed in face order (not by rayon's split, which follows the thread count), so
            // the figure is the same bits for every --threads.
            .collect::<Vec<f64>>()
            .iter()
            .sum()
    }

    /// The sphere's point in direction `dir`. Near the surface (within `reach`), where a
    /// face's interior is closest, the side of that face's plane tells inside from outside
    /// (what the winding number's jump across the face says, at the cost of the closest-point
    /// query made anyway). With no surface within `reach`, a corner `near` (closer than
    /// `reach`) is on the same side; elsewhere the winding number tells.
    fn corner(&self, dir: Vector3<f64>, reach: f64, near: Option<&SphereCorner>) -> SphereCorner {
        let p = self.ball.center + dir * self.ball.radius;
        let closest = self.winding.bvh().closest_point_within(&p, reach);
        let dist = closest.map_or(f64::INFINITY, |c| c.distance);
        if let Some(n) =
            near.filter(|n| closest.is_none() && (n.dir - dir).norm() * self.ball.radius < reach)
        {
            return SphereCorner {
                dir,
                inside: n.inside,
                dist,
            };
        }
        let face_side = closest
            .filter(|c| c.distance > 0.0 && c.bary.iter().all(|&b| b > 1e-6))
            .and_then(|c| {
                let f = self.mesh.faces.get(c.face as usize)?;
                let [a, b, q] = f.map(|i| self.mesh.vertices.get(i as usize).copied());
                let n = (b? - a?).cross(&(q? - a?));
                let side = (p - c.point).dot(&n) * self.sign;
                (side != 0.0 && side.is_finite()).then_some(side < 0.0)
            });
        let inside =
            face_side.unwrap_or_else(|| self.sign * self.winding.winding_number(&p) >= 0.5);
        SphereCorner { dir, inside, dist }
    }

    /// Inside solid angle of the spherical triangle with corners `t`, whose points all lie within
    /// `reach` (world units) of each corner.
    fn triangle(&self, t: [SphereCorner; 3], reach: f64, depth: usize) -> f64 {
        let o = Point3::origin();
        let omega = || {
            solid_angle(
                &o,
                &Point3::from(t[0].dir),
                &Point3::from(t[1].dir),
                &Point3::from(t[2].dir),
            )
            .abs()
        };
        let inside = t.iter().filter(|c| c.inside).count();
        let near = t.iter().any(|c| c.dist <= reach);
        if (inside == 0 || inside == 3) && !near {
            return if inside == 3 { omega() } else { 0.0 };
        }
        if depth == SPHERE_REFINE_DEPTH {
            // Signed distances at the corners, interpolated linearly over the triangle.
            if t.iter().all(|c| c.dist.is_finite()) {
                let sd = t.map(|c| if c.inside { -c.dist } else { c.dist });
                return omega() * negative_fraction(sd);
            }
            return omega() * inside as f64 / 3.0;
        }
        let half = 0.5 * reach;
        let mid = |i: usize, j: usize| {
            let dir = (t[i].dir + t[j].dir).normalize();
            self.corner(dir, half, Some(&t[i]))
        };
        let (ab, bc, ca) = (mid(0, 1), mid(1, 2), mid(2, 0));
        [[t[0], ab, ca], [ab, t[1], bc], [ca, bc, t[2]], [ab, bc, ca]]
            .into_iter()
            .map(|c| self.triangle(c, half, depth + 1))
            .sum()
    }
}

/// Fraction of a triangle's area where the linear interpolant of the corner values `s` is
/// negative (zero counts as positive, as in the corners' classification).
fn negative_fraction(s: [f64; 3]) -> f64 {
    let neg = s.map(|v| v < 0.0);
    let count = neg.iter().filter(|&&n| n).count();
    if count == 0 || count == 3 {
        return count as f64 / 3.0;
    }
    // The corner alone on its side cuts off a similar triangle at the zero line.
    let lone = (0..3).find(|&i| neg[i] == (count == 1)).unwrap_or(0);
    let (a, b, c) = (s[lone], s[(lone + 1) % 3], s[(lone + 2) % 3]);
    let corner = (a * a / ((a - b) * (a - c))).clamp(0.0, 1.0);
    if count == 1 {
        corner
    } else {
        1.0 - corner
    }
}

/// Direction of the vessel near `p` (unit, sign chosen so that its largest component is
/// positive): the eigenvector of smallest eigenvalue of Σ A n nᵀ over the triangles of `mesh`
/// inside the ball of `radius` (world units) about `p`, A the area of the triangle inside the
/// ball and n its unit normal. `bvh` must be the hierarchy of `mesh`; it finds the triangles.
/// `None` when no surface lies in the ball, or when the normals do not single out a direction
/// (smallest eigenvalue more than half the middle one, as on a sphere, or the middle one under
/// 5 % of the largest, as on a flat patch).
pub fn local_axis(
    mesh: &TriMesh,
    bvh: &MeshBvh,
    p: &Point3<f64>,
    radius: f64,
) -> Option<Vector3<f64>> {
    if !(radius.is_finite() && radius > 0.0 && p.iter().all(|c| c.is_finite())) {
        return None;
    }
    let nv = mesh.vertices.len();
    let mut cov = Matrix3::zeros();
    for slot in slots_in_ball(bvh, p, radius) {
        let Some(face) = mesh.faces.get(bvh.slot_face(slot) as usize) else {
            continue;
        };
        if face.iter().any(|&i| i as usize >= nv) {
            continue;
        }
        let t = face.map(|i| mesh.vertices[i as usize]);
        let clip = clip_triangle_to_ball(&t, p, radius);
        if clip.area > 0.0 {
            cov += clip.normal * clip.normal.transpose() * clip.area;
        }
    }
    if !cov.iter().all(|c| c.is_finite()) || cov.trace() <= 0.0 {
        return None;
    }
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let [l0, l1, l2] = order.map(|i| eig.eigenvalues[i]);
    if l0 > 0.5 * l1 || l1 < 0.05 * l2 {
        return None;
    }
    let mut axis = eig
        .eigenvectors
        .column(order[0])
        .into_owned()
        .try_normalize(0.0)?;
    let k = axis.iamax();
    if axis[k] < 0.0 {
        axis = -axis;
    }
    Some(axis)
}

/// A closed loop where a plane cuts a mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct CrossSection {
    /// Area enclosed by the loop, world units².
    pub area: f64,
    /// Diameter of the circle of the same area, 2√(area/π), world units.
    pub equivalent_diameter: f64,
    /// Centroid of the enclosed polygon (in the plane), world units.
    pub centroid: Point3<f64>,
    /// Length of the loop, world units.
    pub perimeter: f64,
    /// Whether the loop encloses the query point.
    pub encloses_point: bool,
    /// Distance from the query point to the loop (0 when enclosed), world units.
    pub distance: f64,
    /// The loop's corners, in order (world units).
    pub points: Vec<Point3<f64>>,
}

/// Cuts `mesh` by the plane through `point` perpendicular to `axis` and returns the closed loop
/// of smallest area that encloses `point`, or, when none does, the loop nearest to it. Vertices
/// exactly on the plane count as being on its positive side, so every crossing lies on an edge
/// with one end on either side and loops stay consistent. Loops that do not close (the plane
/// runs through a hole of an open mesh) and loops of zero area are ignored; `None` when no loop
/// remains or `axis` is zero or not finite. Crossings are joined through shared mesh edges, so
/// the mesh must share vertices between neighbouring triangles (as the readers leave it).
pub fn cross_section(
    mesh: &TriMesh,
    point: &Point3<f64>,
    axis: &Vector3<f64>,
) -> Option<CrossSection> {
    let n = axis.try_normalize(0.0)?;
    if !n.iter().all(|c| c.is_finite()) || !point.iter().all(|c| c.is_finite()) {
        return None;
    }
    let nv = mesh.vertices.len();
    let s: Vec<f64> = mesh.vertices.iter().map(|v| n.dot(&(v - point))).collect();
    let pos = |i: u32| s[i as usize] >= 0.0;

    // Crossing points (one per cut edge) and the segments joining them.
    let mut node_of: HashMap<(u32, u32), u32> = HashMap::new();
    let mut nodes: Vec<Point3<f64>> = Vec::new();
    let mut adj: Vec<Vec<(u32, u32)>> = Vec::new();
    let mut num_segments = 0u32;
    for f in &mesh.faces {
        if f.iter().any(|&i| i as usize >= nv) {
            continue;
        }
        if pos(f[0]) == pos(f[1]) && pos(f[1]) == pos(f[2]) {
            continue;
        }
        let mut ends = [0u32; 2];
        let mut k_end = 0;
        for k in 0..3 {
            let (u, v) = (f[k], f[(k + 1) % 3]);
            if pos(u) == pos(v) || k_end == 2 {
                continue;
            }
            let key = (u.min(v), u.max(v));
            let id = *node_of.entry(key).or_insert_with(|| {
                let (a, b) = (key.0 as usize, key.1 as usize);
                let t = s[a] / (s[a] - s[b]);
                let (pa, pb) = (mesh.vertices[a], mesh.vertices[b]);
                nodes.push(pa + (pb - pa) * t);
                adj.push(Vec::new());
                (nodes.len() - 1) as u32
            });
            ends[k_end] = id;
            k_end += 1;
        }
        if k_end == 2 && ends[0] != ends[1] {
            adj[ends[0] as usize].push((num_segments, ends[1]));
            adj[ends[1] as usize].push((num_segments, ends[0]));
            num_segments += 1;
        }
    }
    if num_segments == 0 {
        return None;
    }

    // Walk the segments into chains; keep the closed ones.
    let mut used = vec![false; num_segments as usize];
    let mut loops: Vec<Vec<u32>> = Vec::new();
    // Open chains first (from odd-degree nodes), so loops are walked from their own nodes.
    let mut starts: Vec<u32> = (0..nodes.len() as u32)
        .filter(|&i| adj[i as usize].len() % 2 == 1)
        .collect();
    starts.extend(0..nodes.len() as u32);
    for start in starts {
        while adj[start as usize].iter().any(|(e, _)| !used[*e as usize]) {
            let mut chain = vec![start];
            let mut cur = start;
            let mut closed = false;
            while let Some(&(e, next)) = adj[cur as usize].iter().find(|(e, _)| !used[*e as usize])
            {
                used[e as usize] = true;
                if next == start {
                    closed = true;
                    break;
                }
                chain.push(next);
                cur = next;
            }
            if closed && chain.len() >= 3 {
                loops.push(chain);
            }
        }
    }

    // Measure each loop in the plane's coordinates about `point`.
    let e1 = n
        .cross(&Vector3::x())
        .try_normalize(1e-6)
        .unwrap_or_else(|| {
            n.cross(&Vector3::y())
                .try_normalize(0.0)
                .unwrap_or(Vector3::z())
        });
    let e2 = n.cross(&e1);
    let mut best: Option<CrossSection> = None;
    for lp in loops {
        let pts: Vec<Point3<f64>> = lp.iter().map(|&i| nodes[i as usize]).collect();
        let uv: Vec<[f64; 2]> = pts
            .iter()
            .map(|q| {
                let w = q - point;
                [w.dot(&e1), w.dot(&e2)]
            })
            .collect();
        let m = uv.len();
        let (mut a2, mut cx, mut cy, mut perimeter, mut dist2) =
            (0.0, 0.0, 0.0, 0.0, f64::INFINITY);
        let mut crossings = 0usize;
        for k in 0..m {
            let (p, q) = (uv[k], uv[(k + 1) % m]);
            let cr = p[0] * q[1] - q[0] * p[1];
            a2 += cr;
            cx += (p[0] + q[0]) * cr;
            cy += (p[1] + q[1]) * cr;
            perimeter += (pts[(k + 1) % m] - pts[k]).norm();
            // Ray from the origin along +u.
            if (p[1] > 0.0) != (q[1] > 0.0) {
                let x = p[0] + (0.0 - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
                if x > 0.0 {
                    crossings += 1;
                }
            }
            dist2 = dist2.min(point_segment_dist2(p, q));
        }
        if a2 == 0.0 || !a2.is_finite() {
            continue;
        }
        let area = 0.5 * a2.abs();
        let (gx, gy) = (cx / (3.0 * a2), cy / (3.0 * a2));
        let encloses = crossings % 2 == 1;
        let section = CrossSection {
            area,
            equivalent_diameter: 2.0 * (area / std::f64::consts::PI).sqrt(),
            centroid: point + e1 * gx + e2 * gy,
            perimeter,
            encloses_point: encloses,
            distance: if encloses { 0.0 } else { dist2.sqrt() },
            points: pts,
        };
        let better = match &best {
            None => true,
            Some(b) => match (section.encloses_point, b.encloses_point) {
                (true, true) => section.area < b.area,
                (true, false) => true,
                (false, true) => false,
                (false, false) => section.distance < b.distance,
            },
        };
        if better {
            best = Some(section);
        }
    }
    best
}

/// Squared distance from the origin to the segment pq (2D).
fn point_segment_dist2(p: [f64; 2], q: [f64; 2]) -> f64 {
    let d = [q[0] - p[0], q[1] - p[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 0.0 {
        (-(p[0] * d[0] + p[1] * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = [p[0] + t * d[0], p[1] + t * d[1]];
    x[0] * x[0] + x[1] * x[1]
}

/// Options of [`measure_stenosis`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StenosisOptions {
    /// Number of cross-sections across the ball, evenly spaced along the axis from −r to +r of
    /// its (re-centred) centre, a count (1 takes the centre only).
    pub sections: usize,
    /// Where the input's normal (healthy) lumen is measured for NASCET, at ± this multiple of
    /// the ball radius along the axis (dimensionless; above 1 is outside D).
    pub normal_offset: f64,
}

impl Default for StenosisOptions {
    fn default() -> Self {
        StenosisOptions {
            sections: 21,
            normal_offset: 1.5,
        }
    }
}

/// One cross-section of the profile across D.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SectionMeasure {
    /// Position along the axis from the report's `center`, world units.
    pub offset: f64,
    /// Equivalent diameter of the input's lumen (0 where the input has none), world units.
    pub input_diameter: f64,
    /// Equivalent diameter of the output's lumen, world units.
    pub output_diameter: f64,
    /// Area of the input's lumen (0 where it has none), world units².
    pub input_area: f64,
    /// Area of the output's lumen, world units².
    pub output_area: f64,
}

/// Stenosis and volume measures of one region D (see [`measure_stenosis`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StenosisReport {
    /// Where the sections' line crosses the ball's central plane: the centroid of the output's
    /// lumen through the ball's centre, world units.
    pub center: [f64; 3],
    /// Unit direction of the output vessel there (the sections' normal).
    pub axis: [f64; 3],
    /// Smallest equivalent diameter of the input's lumen over the sections, world units.
    pub min_input_diameter: f64,
    /// The output's equivalent diameter at that section, world units.
    pub output_diameter_at_min: f64,
    /// The input's lumen area at that section, world units².
    pub min_input_area: f64,
    /// The output's lumen area at that section, world units².
    pub output_area_at_min: f64,
    /// Position of that section along the axis from `center`, world units.
    pub min_offset: f64,
    /// (1 − min input diameter / output diameter there) × 100 (negative when the input is the
    /// wider).
    pub diameter_stenosis_pct: f64,
    /// (1 − input area / output area at that section) × 100.
    pub area_stenosis_pct: f64,
    /// Mean equivalent diameter of the input just outside D (at ± `normal_offset` radii), world
    /// units; `None` when the input has a lumen on neither side.
    pub normal_diameter: Option<f64>,
    /// NASCET degree: (1 − min input diameter / normal diameter) × 100.
    pub nascet_stenosis_pct: Option<f64>,
    /// Number of sections measured (those where the output has a lumen).
    pub sections: usize,
    /// Volume of the input's solid inside the ball, world units³.
    pub input_volume_in_ball: f64,
    /// Volume of the output's solid inside the ball, world units³.
    pub output_volume_in_ball: f64,
    /// The sections, in order along the axis.
    pub profile: Vec<SectionMeasure>,
}

/// Measures the stenosis of `input` that `output` (its repair) removed inside `ball`.
///
/// The axis is the output's [`local_axis`] near the ball's centre (normals within the larger of
/// the ball radius and twice the centre's distance to the output surface), taken again at the
/// centroid of the output's lumen through the centre, which becomes the line's origin. At each
/// of `opts.sections` planes across the ball the output's lumen is the [`cross_section`] nearest
/// the line; the input's is the section about the output lumen's centroid, accepted when it
/// encloses that centroid or comes within the output's equivalent radius of it; otherwise
/// (occlusion) its diameter is 0. The narrowest input section gives the diameter and area
/// stenosis against the output there; the NASCET degree compares it with the mean input
/// diameter at ± `opts.normal_offset` radii along the axis, where both lumens are cut again
/// perpendicular to the output's own local axis (normals within its lumen diameter), since the
/// vessel may have turned. Volumes inside the ball come from [`volume_in_ball`].
///
/// Errors with [`Error::InvalidMesh`] when either mesh has no triangle, and with
/// [`Error::Geometry`] for a ball or options that are not positive and finite, a ball that neither
/// reaches the output surface nor lies inside the output, or when the output gives no axis or no
/// lumen in the ball.
pub fn measure_stenosis(
    input: &TriMesh,
    output: &TriMesh,
    ball: &Ball,
    opts: &StenosisOptions,
) -> Result<StenosisReport> {
    check_mesh(input, "input")?;
    check_mesh(output, "output")?;
    let wi = WindingNumber::new(input, WindingOptions::SIDES);
    let wo = WindingNumber::new(output, WindingOptions::SIDES);
    measure_stenosis_with(input, &wi, output, &wo, ball, opts)
}

fn check_mesh(mesh: &TriMesh, what: &str) -> Result<()> {
    if mesh.faces.is_empty() {
        return Err(Error::InvalidMesh(format!(
            "the {what} mesh has no triangle"
        )));
    }
    Ok(())
}

/// [`measure_stenosis`] with prebuilt winding numbers (and through them hierarchies) of the
/// input and the output.
pub fn measure_stenosis_with(
    input: &TriMesh,
    input_winding: &WindingNumber,
    output: &TriMesh,
    output_winding: &WindingNumber,
    ball: &Ball,
    opts: &StenosisOptions,
) -> Result<StenosisReport> {
    check_mesh(input, "input")?;
    check_mesh(output, "output")?;
    if !ball_is_valid(ball) {
        return Err(Error::Geometry(format!(
            "stenosis ball needs a finite centre and a positive finite radius, got centre {:?} radius {}",
            [ball.center.x, ball.center.y, ball.center.z],
            ball.radius
        )));
    }
    if opts.sections == 0 {
        return Err(Error::Geometry(
            "stenosis needs at least one section".into(),
        ));
    }
    if !(opts.normal_offset.is_finite() && opts.normal_offset > 0.0) {
        return Err(Error::Geometry(format!(
            "stenosis normal offset must be positive and finite, got {}",
            opts.normal_offset
        )));
    }
    let obvh = output_winding.bvh();
    if obvh.is_empty() {
        return Err(Error::InvalidMesh(
            "the output mesh has no usable triangle".into(),
        ));
    }
    let r = ball.radius;
    let d0 = obvh.closest_point(&ball.center).distance;
    let sign = orientation_sign(output, &ball.center);
    if d0 > r && sign * output_winding.winding_number(&ball.center) < 0.5 {
        return Err(Error::Geometry(format!(
            "the ball (radius {r}) does not reach the output surface ({d0} away) and its centre is outside the vessel"
        )));
    }
    let axis_at = |p: &Point3<f64>| {
        let d = obvh.closest_point(p).distance.min(r);
        local_axis(output, obvh, p, r.max(2.0 * d))
    };
    let axis0 = axis_at(&ball.center).ok_or_else(|| {
        Error::Geometry("the output surface gives no vessel direction in the ball".into())
    })?;
    let sec0 = cross_section(output, &ball.center, &axis0).ok_or_else(|| {
        Error::Geometry("the output has no lumen through the ball's centre".into())
    })?;
    let center = sec0.centroid;
    let axis = axis_at(&center).unwrap_or(axis0);

    // The input's lumen about the output's (or about `p` where the output has none).
    let input_section = |p: &Point3<f64>, out: Option<&CrossSection>, axis: &Vector3<f64>| {
        let (q, reach) = match out {
            Some(o) => (o.centroid, 0.5 * o.equivalent_diameter),
            None => (*p, r),
        };
        cross_section(input, &q, axis).filter(|s| s.encloses_point || s.distance <= reach)
    };

    let n = opts.sections;
    let mut profile = Vec::with_capacity(n);
    for k in 0..n {
        let t = if n == 1 {
            0.0
        } else {
            -r + 2.0 * r * k as f64 / (n - 1) as f64
        };
        let p = center + axis * t;
        let Some(out) = cross_section(output, &p, &axis) else {
            continue;
        };
        let inp = input_section(&p, Some(&out), &axis);
        profile.push(SectionMeasure {
            offset: t,
            input_diameter: inp.as_ref().map_or(0.0, |s| s.equivalent_diameter),
            output_diameter: out.equivalent_diameter,
            input_area: inp.as_ref().map_or(0.0, |s| s.area),
            output_area: out.area,
        });
    }
    let min = profile
        .iter()
        .min_by(|a, b| a.input_diameter.total_cmp(&b.input_diameter))
        .cloned()
        .ok_or_else(|| Error::Geometry("the output has no lumen across the ball".into()))?;

    // Outside D the vessel may have turned: cut there perpendicular to the output's own axis
    // (normals within its lumen diameter of the lumen's centroid).
    let normals: Vec<f64> = [-1.0, 1.0]
        .iter()
        .filter_map(|side| {
            let p = center + axis * (side * opts.normal_offset * r);
            let Some(out) = cross_section(output, &p, &axis) else {
                return input_section(&p, None, &axis).map(|s| s.equivalent_diameter);
            };
            let local = local_axis(output, obvh, &out.centroid, out.equivalent_diameter)
                .map(|a| if a.dot(&axis) < 0.0 { -a } else { a })
                .unwrap_or(axis);
            let out = cross_section(output, &out.centroid, &local).unwrap_or(out);
            input_section(&out.centroid, Some(&out), &local).map(|s| s.equivalent_diameter)
        })
        .collect();
    let normal_diameter =
        (!normals.is_empty()).then(|| normals.iter().sum::<f64>() / normals.len() as f64);
    let pct = |num: f64, den: f64| (1.0 - num / den) * 100.0;
    let nascet = normal_diameter
        .filter(|&d| d > 0.0)
        .map(|d| pct(min.input_diameter, d));

    Ok(StenosisReport {
        center: [center.x, center.y, center.z],
        axis: [axis.x, axis.y, axis.z],
        min_input_diameter: min.input_diameter,
        output_diameter_at_min: min.output_diameter,
        min_input_area: min.input_area,
        output_area_at_min: min.output_area,
        min_offset: min.offset,
        diameter_stenosis_pct: pct(min.input_diameter, min.output_diameter),
        area_stenosis_pct: pct(min.input_area, min.output_area),
        normal_diameter,
        nascet_stenosis_pct: nascet,
        sections: profile.len(),
        input_volume_in_ball: volume_in_ball_with(input, input_winding, ball),
        output_volume_in_ball: volume_in_ball_with(output, output_winding, ball),
        profile,
    })
}
