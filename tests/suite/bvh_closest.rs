//! Closest-point queries: the point–triangle routine against sampling and analytic cases, the
//! hierarchy against brute force on the real meshes (2,000 points each; 10,000 in the slow tests,
//! `bash tests/run_slow.sh`) and on a small mesh far from the origin, and an icosphere at known
//! radii.

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use rayon::prelude::*;
use vesselmsr::bvh::brute::closest_point_brute;
use vesselmsr::bvh::{closest_point_on_triangle, MeshBvh};
use vesselmsr::mesh::primitives::icosphere;
use vesselmsr::TriMesh;

#[test]
fn closest_point_on_triangle_is_optimal_and_consistent() {
    let mut rng = rng(11);
    let mut worst_gap: f64 = 0.0;
    for trial in 0..400 {
        let mut tri = [0; 3].map(|_| Point3::from(Vector3::from_fn(|_, _| rng.random::<f64>())));
        // Half the triangles degenerate (collinear, a repeated corner, a single point) or
        // slivers (needles and caps of height 1e-9 to 1e-13, right-angled or not).
        let e = tri[1] - tri[0];
        let off = Vector3::new(0.3, -0.2, 0.9).cross(&e).normalize();
        match trial % 16 {
            1 => tri[2] = tri[0] + e * 1.7,
            3 => tri[2] = tri[0] + e * 0.4,
            5 => tri[1] = tri[0],
            7 => tri = [tri[0]; 3],
            9 => tri[2] = tri[0] + e * 0.3 + off * 1e-13,
            11 => tri[2] = tri[0] + off * 1e-9,
            13 => tri[2] = tri[0] + e * 2.5 + off * 1e-11,
            15 => tri[2] = tri[0] - e * 0.5 + off * 1e-10,
            2 => tri[1] = tri[0] + off * 1e-9,
            4 => tri[2] = tri[0] + e * 1.3 + off * 1e-4,
            8 => tri[2] = tri[0] + e * 0.6 + off * 1e-6,
            10 => tri[2] = tri[0] + e * 0.9 + off * 3e-8,
            6 => tri[2] = tri[1] + off * 1e-9,
            _ => {}
        }
        let [a, b, c] = tri;
        for _ in 0..10 {
            let p = Point3::from(Vector3::from_fn(|_, _| rng.random::<f64>() * 3.0 - 1.0));
            let (x, w) = closest_point_on_triangle(&p, &a, &b, &c);
            assert!(x.iter().all(|c| c.is_finite()), "non-finite point");
            assert!(
                w.iter().all(|&wi| (-1e-12..=1.0 + 1e-12).contains(&wi)),
                "{w:?}"
            );
            assert!((w[0] + w[1] + w[2] - 1.0).abs() < 1e-12);
            let recon = Point3::from(a.coords * w[0] + b.coords * w[1] + c.coords * w[2]);
            assert!((recon - x).norm() < 1e-12, "bary does not give the point");
            // Projecting inside a proper triangle: the distance is the plane distance.
            let n = (b - a).cross(&(c - a));
            if n.norm() > 1e-3 {
                let n = n.normalize();
                let foot = p - n * n.dot(&(p - a));
                let inside = [(a, b), (b, c), (c, a)]
                    .iter()
                    .all(|(u, v)| (v - u).cross(&(foot - u)).dot(&n) > 1e-6);
                if inside {
                    assert!(((p - x).norm() - n.dot(&(p - a)).abs()).abs() < 1e-12);
                }
            }
            // No sampled point of the triangle (grid of barycentrics) may be closer.
            let d = (p - x).norm();
            let n = 40;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    let y = a + (b - a) * s + (c - a) * t;
                    worst_gap = worst_gap.max(d - (p - y).norm());
                }
            }
        }
    }
    println!("closest_point_on_triangle: worst (returned − sampled) distance {worst_gap:.3e}");
    assert!(
        worst_gap <= 1e-12,
        "a sampled point beats the returned one by {worst_gap}"
    );

    // Analytic: the unit right triangle in z = 0.
    let (a, b, c) = (
        Point3::origin(),
        Point3::new(1.0, 0.0, 0.0),
        Point3::new(0.0, 1.0, 0.0),
    );
    let cases = [
        (Point3::new(0.25, 0.25, 2.0), Point3::new(0.25, 0.25, 0.0)), // face
        (Point3::new(-1.0, -1.0, 0.5), a),                            // vertex a
        (Point3::new(3.0, -0.5, 0.0), b),                             // vertex b
        (Point3::new(-0.1, 4.0, 0.0), c),                             // vertex c
        (Point3::new(0.5, -2.0, 1.0), Point3::new(0.5, 0.0, 0.0)),    // edge ab
        (Point3::new(-3.0, 0.5, 0.0), Point3::new(0.0, 0.5, 0.0)),    // edge ca
        (Point3::new(1.0, 1.0, -1.0), Point3::new(0.5, 0.5, 0.0)),    // edge bc
    ];
    for (p, want) in cases {
        let (x, _) = closest_point_on_triangle(&p, &a, &b, &c);
        assert!((x - want).norm() < 1e-15, "{p} -> {x}, want {want}");
    }
}

#[test]
fn icosphere_at_known_radii() {
    let r = 2.5;
    let mesh = icosphere(3, r, Point3::new(0.3, -0.2, 0.1));
    let center = mesh.vertices[0] - (mesh.vertices[0] - Point3::new(0.3, -0.2, 0.1));
    let bvh = MeshBvh::new(&mesh);
    // Plane distances of the faces from the centre: inradius = the smallest.
    let heights: Vec<f64> = (0..mesh.num_faces())
        .map(|f| {
            let n = mesh.face_normal_raw(f).normalize();
            (mesh.triangle(f)[0] - center).dot(&n)
        })
        .collect();
    let inradius = heights.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut max_err: f64 = 0.0;

    // Along a vertex direction the vertex is closest for every radius ≥ R (inscribed polytope).
    for v in mesh.vertices.iter().step_by(7) {
        let dir = (v - center).normalize();
        for rho in [r, 1.01 * r, 1.5 * r, 3.0 * r, 100.0 * r] {
            let cp = bvh.closest_point(&(center + dir * rho));
            max_err = max_err.max((cp.distance - (rho - r)).abs());
        }
    }
    // Along a face normal (through its circumcentre) the foot is closest from outside.
    for (f, &h) in heights.iter().enumerate().step_by(13) {
        let n = mesh.face_normal_raw(f).normalize();
        for rho in [h + 0.01, 1.2 * r, 2.0 * r] {
            let cp = bvh.closest_point(&(center + n * rho));
            max_err = max_err.max((cp.distance - (rho - h)).abs());
            assert_eq!(cp.face as usize, f);
        }
    }
    // The centre is the inradius away.
    max_err = max_err.max((bvh.closest_point(&center).distance - inradius).abs());
    println!("icosphere: max |distance − analytic| = {max_err:.3e}");
    assert!(max_err < 1e-12 * r);

    // Random directions at radius ρ: ρ − R ≤ d ≤ ρ − inradius.
    let mut rng = rng(5);
    for _ in 0..2000 {
        let rho = r * (1.0 + 2.0 * rng.random::<f64>());
        let d = bvh
            .closest_point(&(center + unit_vector(&mut rng) * rho))
            .distance;
        assert!(
            d >= rho - r - 1e-12 && d <= rho - inradius + 1e-12,
            "{d} at {rho}"
        );
    }
}

/// BVH against brute force on `pts`; returns the largest distance difference.
fn compare_with_brute(mesh: &TriMesh, bvh: &MeshBvh, pts: &[Point3<f64>]) -> f64 {
    let fast = bvh.closest_points(pts);
    pts.par_iter()
        .zip(fast.par_iter())
        .map(|(p, f)| {
            let b = closest_point_brute(mesh, p);
            // The reported point must lie on the reported face at the reported distance.
            let [x, y, z] = mesh.triangle(f.face as usize);
            let recon = x.coords * f.bary[0] + y.coords * f.bary[1] + z.coords * f.bary[2];
            let scale = b.distance + (x - y).norm();
            assert!((recon - f.point.coords).norm() <= 1e-9 * scale);
            assert!(((p - f.point).norm() - f.distance).abs() <= 1e-12 * scale);
            (f.distance - b.distance).abs()
        })
        .reduce(|| 0.0, f64::max)
}

/// Every real mesh: the BVH's closest points of `n` seeded points (near the surface and in the
/// box) equal a scan of every triangle, and the narrow-band query finds them at their distance.
fn real_meshes_bvh_equals_brute_force(n: usize) {
    let Some(meshes) = real_meshes() else { return };
    for (name, mesh) in &meshes {
        let diag = bbox_diagonal(mesh);
        let bvh = MeshBvh::new(mesh);
        assert_eq!(bvh.num_triangles(), mesh.num_faces());
        let pts = sample_points(mesh, n, 42);
        let max_err = compare_with_brute(mesh, &bvh, &pts);
        println!(
            "{name}: {} faces, max |d_bvh − d_brute| = {max_err:.3e} ({:.3e} of diagonal)",
            mesh.num_faces(),
            max_err / diag
        );
        assert!(max_err <= 1e-7 * diag, "{name}: {max_err}");

        // Narrow band: found just beyond the true distance, not found just short of it.
        for p in pts.iter().step_by(50) {
            let d = closest_point_brute(mesh, p).distance;
            let inside = bvh.closest_point_within(p, d * (1.0 + 1e-9) + 1e-300);
            let got = inside.expect("closest point within its own distance");
            assert!((got.distance - d).abs() <= 1e-7 * diag);
            if d > 1e-9 * diag {
                assert!(bvh.closest_point_within(p, d * (1.0 - 1e-6)).is_none());
            }
        }
    }
}

#[test]
fn real_meshes_bvh_equals_brute_force_on_2000_points() {
    real_meshes_bvh_equals_brute_force(2_000);
}

mod slow {
    /// The same on 10,000 points per mesh (the brute-force scans are most of the time).
    #[test]
    #[ignore = "slow: run by tests/run_slow.sh"]
    fn real_meshes_bvh_equals_brute_force_on_10000_points() {
        super::real_meshes_bvh_equals_brute_force(10_000);
    }
}

#[test]
fn small_mesh_far_from_origin() {
    // 1 cm sphere 1 m (in mm) away from the origin: f32 has ~6e-5 mm resolution there.
    let mesh = icosphere(4, 1e-2, Point3::new(1e3, -2e3, 5e2));
    let bvh = MeshBvh::new(&mesh);
    let pts = sample_points(&mesh, 4000, 9);
    let max_err = compare_with_brute(&mesh, &bvh, &pts);
    println!("far small icosphere: max |d_bvh − d_brute| = {max_err:.3e} (diag 0.035)");
    assert!(max_err <= 1e-7 * 0.035);
}

#[test]
fn degenerate_inputs_do_not_panic() {
    let empty = MeshBvh::new(&TriMesh::default());
    let p = Point3::new(1.0, 2.0, 3.0);
    assert!(empty.is_empty());
    assert!(empty.closest_point(&p).distance.is_infinite());
    assert!(empty.closest_point_within(&p, 10.0).is_none());

    // One triangle, plus a face with an out-of-range index and one with a NaN corner.
    let mesh = TriMesh::new(
        vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(f64::NAN, 0.0, 0.0),
        ],
        vec![[0, 1, 9], [0, 1, 3], [0, 1, 2]],
    );
    let bvh = MeshBvh::new(&mesh);
    assert_eq!(bvh.num_triangles(), 1);
    let cp = bvh.closest_point(&Point3::new(0.2, 0.2, 5.0));
    assert_eq!(cp.face, 2);
    assert!((cp.distance - 5.0).abs() < 1e-15);
    assert!(bvh
        .closest_point_within(&Point3::new(0.2, 0.2, 5.0), 4.9)
        .is_none());
    assert!(bvh.closest_point_within(&p, -1.0).is_none());
    assert!(bvh.closest_point_within(&p, f64::NAN).is_none());
    let _ = bvh.closest_point(&Point3::new(f64::NAN, 0.0, 0.0));

    // All corners equal: a mesh of one point.
    let dot = TriMesh::new(
        vec![Point3::new(4.0, 4.0, 4.0); 3],
        vec![[0, 1, 2], [2, 1, 0]],
    );
    let cp = MeshBvh::new(&dot).closest_point(&Point3::new(4.0, 4.0, 7.0));
    assert!((cp.distance - 3.0).abs() < 1e-15);
}
