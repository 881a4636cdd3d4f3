//! Property tests of the geometry kernels on random inputs (proptest, shrinking to a minimal
//! failing case):
//! - closest point: the hierarchy's answer ([`MeshBvh::closest_point`], and
//!   [`MeshBvh::closest_point_within`]) equals a brute-force scan over random triangle soups
//!   (degenerate triangles included), lies on the face it names, and no point sampled on any
//!   triangle is nearer;
//! - winding number: on randomly scaled, stretched, rotated and moved icospheres and boxes, the
//!   fast winding number ([`WindingNumber`]) is ≈ 1 at points surely inside, ≈ 0 at points surely
//!   outside, ≈ −1 inside the flipped mesh, and agrees everywhere with an independent brute-force
//!   sum of solid angles (spherical excess by L'Huilier's theorem, not the library's formula);
//! - marching cubes: the zero level set of random unions of spheres (with random spherical bites
//!   taken out) on random grids is a closed 2-manifold (no boundary or non-manifold edge, no
//!   non-manifold vertex, even Euler characteristic), consistently oriented outward (positive
//!   volume), without degenerate triangles, and separates the inside nodes (winding ≈ 1) from the
//!   outside ones (≈ 0), whatever the collapse threshold.
//!
//! Case counts are kept small (ProptestConfig) so the file runs in a few seconds in release.

use nalgebra::{Point3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use vesselmsr::bvh::brute::closest_point_brute;
use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::measures::{degenerate_faces, euler_characteristic, signed_volume};
use vesselmsr::mesh::primitives::{box_mesh, icosphere};
use vesselmsr::mesh::topology::EdgeMap;
use vesselmsr::TriMesh;

fn p3(a: [f64; 3]) -> Point3<f64> {
    Point3::new(a[0], a[1], a[2])
}

/// A triangle soup over a pool of random vertices; the face indices are random, so repeated
/// indices (degenerate triangles) and shared vertices both occur.
fn soup() -> impl Strategy<Value = TriMesh> {
    prop::collection::vec(prop::array::uniform3(-10.0f64..10.0), 3..40).prop_flat_map(|verts| {
        let n = verts.len() as u32;
        prop::collection::vec(prop::array::uniform3(0..n), 1..60)
            .prop_map(move |faces| TriMesh::new(verts.iter().copied().map(p3).collect(), faces))
    })
}

/// Distance from `p` to the nearest of a grid of barycentric samples on every triangle: an
/// upper bound of the true distance, computed without any closest-point routine.
fn sampled_upper_bound(mesh: &TriMesh, p: &Point3<f64>) -> f64 {
    const N: usize = 12;
    let mut best = f64::INFINITY;
    for f in 0..mesh.num_faces() {
        let [a, b, c] = mesh.triangle(f);
        for i in 0..=N {
            for j in 0..=N - i {
                let (u, v) = (i as f64 / N as f64, j as f64 / N as f64);
                let x = a + (b - a) * u + (c - a) * v;
                best = best.min((x - p).norm());
            }
        }
    }
    best
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn closest_point_matches_brute_force(
        mesh in soup(),
        queries in prop::collection::vec(prop::array::uniform3(-20.0f64..20.0), 1..16),
    ) {
        let bvh = MeshBvh::new(&mesh);
        for q in queries.iter().copied().map(p3) {
            let fast = bvh.closest_point(&q);
            let brute = closest_point_brute(&mesh, &q);
            let tol = 1e-9 * (1.0 + brute.distance);
            prop_assert!(fast.is_found());
            prop_assert!((fast.distance - brute.distance).abs() <= tol,
                "at {q:?}: hierarchy {} vs brute force {}", fast.distance, brute.distance);
            prop_assert!(((fast.point - q).norm() - fast.distance).abs() <= tol);
            // The point is on the face it names, at the barycentric coordinates it gives.
            let [a, b, c] = mesh.triangle(fast.face as usize);
            let [u, v, w] = fast.bary;
            prop_assert!([u, v, w].iter().all(|&t| (-1e-9..=1.0 + 1e-9).contains(&t)));
            prop_assert!((u + v + w - 1.0).abs() <= 1e-9);
            let on_face = Point3::from(a.coords * u + b.coords * v + c.coords * w);
            prop_assert!((on_face - fast.point).norm() <= 1e-8 * (1.0 + fast.distance));
            // No sampled point of the mesh is nearer.
            prop_assert!(fast.distance <= sampled_upper_bound(&mesh, &q) + tol);
            // The narrow-band query finds it iff it lies within the band.
            let band = brute.distance * 1.001 + 1e-12;
            let within = bvh.closest_point_within(&q, band);
            prop_assert!(within.is_some_and(|c| (c.distance - brute.distance).abs() <= tol));
            if brute.distance > 1e-6 {
                prop_assert!(bvh.closest_point_within(&q, brute.distance * 0.999).is_none());
            }
        }
    }
}

/// Solid angle of triangle (a, b, c) seen from `q` by L'Huilier's theorem (spherical excess of
/// the projected triangle), signed positive when the normal (b − a) × (c − a) points away from
/// `q`: a brute-force reference independent of the library's Van Oosterom–Strackee formula.
fn solid_angle_lhuilier(q: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> f64 {
    let (ra, rb, rc) = (a - q, b - q, c - q);
    let arc = |u: &Vector3<f64>, v: &Vector3<f64>| u.cross(v).norm().atan2(u.dot(v));
    let (ta, tb, tc) = (arc(&rb, &rc), arc(&rc, &ra), arc(&ra, &rb));
    let s = 0.5 * (ta + tb + tc);
    let t =
        (0.5 * s).tan() * (0.5 * (s - ta)).tan() * (0.5 * (s - tb)).tan() * (0.5 * (s - tc)).tan();
    let excess = 4.0 * t.max(0.0).sqrt().atan();
    excess * ra.dot(&rb.cross(&rc)).signum()
}

fn winding_brute(mesh: &TriMesh, q: &Point3<f64>) -> f64 {
    (0..mesh.num_faces())
        .map(|f| {
            let [a, b, c] = mesh.triangle(f);
            solid_angle_lhuilier(q, &a, &b, &c)
        })
        .sum::<f64>()
        / (4.0 * std::f64::consts::PI)
}

/// A closed outward mesh in its local frame (an icosphere of radius 1 or the box [−1, 1]³) and
/// the local-frame classification of a point: Some(true) surely inside, Some(false) surely
/// outside, None too near the surface to say.
#[derive(Debug, Clone, Copy)]
enum Solid {
    Sphere(usize),
    Cube,
}

impl Solid {
    fn mesh(self) -> TriMesh {
        match self {
            Solid::Sphere(s) => icosphere(s, 1.0, Point3::origin()),
            Solid::Cube => box_mesh(Point3::new(-1.0, -1.0, -1.0), Point3::new(1.0, 1.0, 1.0)),
        }
    }

    fn classify(self, q: &Point3<f64>) -> Option<bool> {
        match self {
            // Every face plane of a subdivided icosahedron on the unit sphere is at least the
            // icosahedron's inradius (0.7947) from the centre, and the polyhedron is inside the sphere.
            Solid::Sphere(_) => {
                let r = q.coords.norm();
                (r < 0.79).then_some(true).or((r > 1.01).then_some(false))
            }
            Solid::Cube => {
                let m = q.coords.amax();
                (m < 0.99).then_some(true).or((m > 1.01).then_some(false))
            }
        }
    }
}

fn solid() -> impl Strategy<Value = Solid> {
    prop_oneof![(0usize..=3).prop_map(Solid::Sphere), Just(Solid::Cube)]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn winding_number_is_one_inside_zero_outside(
        shape in solid(),
        scale in 0.05f64..20.0,
        stretch in prop::array::uniform3(0.5f64..2.0),
        axis in prop::array::uniform3(-3.2f64..3.2),
        shift in prop::array::uniform3(-100.0f64..100.0),
        local in prop::collection::vec(prop::array::uniform3(-1.6f64..1.6), 8..40),
    ) {
        let rot = UnitQuaternion::from_scaled_axis(Vector3::from(axis));
        let place = |q: &Point3<f64>| {
            let s = Vector3::new(q.x * stretch[0], q.y * stretch[1], q.z * stretch[2]) * scale;
            Point3::from(rot * s + Vector3::from(shift))
        };
        let mut mesh = shape.mesh();
        for v in &mut mesh.vertices {
            *v = place(v);
        }
        let wn = WindingNumber::new(&mesh, WindingOptions::default());
        let mut flipped = mesh.clone();
        flipped.flip_faces();
        let wn_flipped = WindingNumber::new(&flipped, WindingOptions::default());
        for q in local.iter().copied().map(p3) {
            let p = place(&q);
            let fast = wn.winding_number(&p);
            let brute = winding_brute(&mesh, &p);
            prop_assert!((fast - brute).abs() < 1e-3, "at {p:?}: fast {fast} vs brute {brute}");
            prop_assert!((wn_flipped.winding_number(&p) + fast).abs() < 1e-3);
            if let Some(inside) = shape.classify(&q) {
                let want = if inside { 1.0 } else { 0.0 };
                prop_assert!((brute - want).abs() < 1e-9, "brute {brute} at local {q:?}");
                prop_assert!((fast - want).abs() < 1e-3, "fast {fast} at local {q:?}");
                prop_assert_eq!(wn.is_inside(&p), inside);
                prop_assert!((wn_flipped.winding_number(&p) + want).abs() < 1e-3);
            }
        }
    }
}

/// A random implicit field: the union of 1–4 spheres minus 0–2 spherical bites, in grid units
/// (multiplied by the voxel size when sampled).
#[derive(Debug, Clone)]
struct Field {
    dims: [usize; 3],
    voxel: f64,
    origin: [f64; 3],
    balls: Vec<([f64; 3], f64)>,
    bites: Vec<([f64; 3], f64)>,
    collapse_below: f64,
}

fn ball(dims: [usize; 3]) -> impl Strategy<Value = ([f64; 3], f64)> {
    let span = |d: usize| -1.0..d as f64;
    ([span(dims[0]), span(dims[1]), span(dims[2])], 0.3f64..6.0)
}

fn field() -> impl Strategy<Value = Field> {
    [4usize..18, 4usize..18, 4usize..18]
        .prop_flat_map(|dims| {
            (
                Just(dims),
                0.05f64..3.0,
                prop::array::uniform3(-50.0f64..50.0),
                prop::collection::vec(ball(dims), 1..5),
                prop::collection::vec(ball(dims), 0..3),
                prop_oneof![Just(0.0), Just(0.1), 0.0f64..0.49],
            )
        })
        .prop_map(
            |(dims, voxel, origin, balls, bites, collapse_below)| Field {
                dims,
                voxel,
                origin,
                balls,
                bites,
                collapse_below,
            },
        )
}

impl Field {
    fn grid(&self) -> Grid3 {
        let h = self.voxel;
        let mut g = Grid3::new(self.dims, GridTransform::new(p3(self.origin), h), 0.0).unwrap();
        let dist = |(c, r): &([f64; 3], f64), x: &Point3<f64>| (x - p3(*c)).norm() - r;
        for k in 0..self.dims[2] {
            for j in 0..self.dims[1] {
                for i in 0..self.dims[0] {
                    let x = Point3::new(i as f64, j as f64, k as f64);
                    let union = self
                        .balls
                        .iter()
                        .map(|b| dist(b, &x))
                        .fold(f64::INFINITY, f64::min);
                    let phi = self
                        .bites
                        .iter()
                        .map(|b| -dist(b, &x))
                        .fold(union, f64::max);
                    g.set(i, j, k, (phi * h) as f32);
                }
            }
        }
        g
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn marching_cubes_surfaces_are_closed_oriented_manifolds(field in field()) {
        let grid = field.grid();
        let opts = ExtractOptions { collapse_below: field.collapse_below };
        let mesh = extract_surface(&grid, &opts).unwrap();
        let inside_nodes = grid.data().iter().filter(|&&v| v < 0.0).count();
        if inside_nodes == 0 {
            prop_assert_eq!(mesh.num_faces(), 0);
            return Ok(());
        }
        prop_assert!(mesh.num_faces() > 0);
        prop_assert!(mesh.vertices.iter().all(|v| v.iter().all(|c| c.is_finite())));
        prop_assert!(mesh.faces.iter().flatten().all(|&i| (i as usize) < mesh.num_vertices()));
        let edges = EdgeMap::new(&mesh);
        prop_assert_eq!(edges.boundary_edges(), 0);
        prop_assert_eq!(edges.non_manifold_edges(), 0);
        prop_assert!(edges.non_manifold_vertex_ids().is_empty());
        prop_assert!(edges.is_consistently_oriented());
        prop_assert_eq!(euler_characteristic(&mesh) % 2, 0);
        prop_assert_eq!(degenerate_faces(&mesh), 0);
        prop_assert!(signed_volume(&mesh) > 0.0);
        // The surface separates the inside nodes from the outside ones, outward oriented.
        let wn = WindingNumber::new(&mesh, WindingOptions::default());
        let [nx, ny, nz] = field.dims;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let want = if grid.get(i, j, k) < 0.0 { 1.0 } else { 0.0 };
                    let w = wn.winding_number(&grid.world(i, j, k));
                    prop_assert!((w - want).abs() < 0.01,
                        "node ({i}, {j}, {k}) φ = {}: winding {w}", grid.get(i, j, k));
                }
            }
        }
    }
}
