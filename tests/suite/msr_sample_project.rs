//! Sample points of a decomposition and the Newton projection onto a zero level set: samples
//! cover a coarse mesh to within the spacing, lie on their faces, and are not repeated; points
//! near a sphere's signed distance grid land on the sphere (radius error ≪ h) along the normal.

use crate::common;
use common::*;
use nalgebra::Point3;
use rand::RngExt;
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::mesh::distance::sample_surface;
use vesselmsr::mesh::primitives::{box_mesh, icosphere};
use vesselmsr::msr::project::{project_to_zero_level, LevelProjectOptions};
use vesselmsr::msr::sample::sample_for_spacing;
use vesselmsr::TriMesh;

#[test]
fn samples_cover_a_coarse_mesh_within_the_spacing() {
    for (name, mesh, spacing) in [
        (
            "box",
            box_mesh(Point3::origin(), Point3::new(10.0, 6.0, 3.0)),
            1.0,
        ),
        ("icosphere", icosphere(1, 8.0, Point3::origin()), 0.7),
    ] {
        let s = sample_for_spacing(&mesh, spacing);
        assert_eq!(&s.points[..s.num_vertices], &mesh.vertices[..]);
        assert_eq!(s.extra_face.len(), s.points.len() - s.num_vertices);
        // Extra samples are on their faces, at their barycentric coordinates.
        for (k, (&f, b)) in s.extra_face.iter().zip(&s.extra_bary).enumerate() {
            let [a, bb, c] = mesh.triangle(f as usize);
            let p = Point3::from(a.coords * b[0] + bb.coords * b[1] + c.coords * b[2]);
            assert!((p - s.points[s.num_vertices + k]).norm() < 1e-12);
            assert!(b.iter().all(|&x| (-1e-12..=1.0).contains(&x)));
        }
        // No sample twice.
        let cloud = TriMesh::new(s.points.clone(), vec![]);
        let mut sorted: Vec<[i64; 3]> = cloud
            .vertices
            .iter()
            .map(|p| [p.x, p.y, p.z].map(|v| (v * 1e9).round() as i64))
            .collect();
        sorted.sort();
        let n = sorted.len();
        sorted.dedup();
        assert_eq!(sorted.len(), n, "{name}: repeated samples");
        // Every surface point is within the spacing of a sample (brute force).
        let worst = sample_surface(&mesh, 3000)
            .iter()
            .map(|q| {
                s.points
                    .iter()
                    .map(|p| (p - q).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        println!(
            "{name}: {} samples ({} vertices), farthest surface point {worst:.3}",
            s.points.len(),
            s.num_vertices
        );
        assert!(worst <= spacing, "{name}: {worst} > {spacing}");
    }
}

/// Signed distance grid of a sphere of radius `r` voxels (voxel 1).
fn sphere_grid(r: f64) -> (Grid3, Point3<f64>) {
    let n = (2.0 * r + 12.0) as usize;
    let c = Point3::new(
        n as f64 / 2.0 + 0.31,
        n as f64 / 2.0 - 0.17,
        n as f64 / 2.0 + 0.05,
    );
    let mut g = Grid3::new([n; 3], GridTransform::new(Point3::origin(), 1.0), 0.0).unwrap();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let v = (g.world(i, j, k) - c).norm() - r;
                g.set(i, j, k, v as f32);
            }
        }
    }
    (g, c)
}

#[test]
fn newton_lands_on_the_sphere_along_the_normal() {
    let r = 20.0;
    let (phi, c) = sphere_grid(r);
    let mut rng = rng(3);
    let points: Vec<Point3<f64>> = (0..2000)
        .map(|_| {
            let d = loop {
                let v = nalgebra::Vector3::new(
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                );
                if v.norm() > 0.1 {
                    break v.normalize();
                }
            };
            c + d * (r + rng.random::<f64>() * 6.0 - 3.0)
        })
        .collect();
    let out = project_to_zero_level(&phi, &points, &LevelProjectOptions::default());
    let (mut radius_err, mut angle) = (0.0f64, 0.0f64);
    for (p, q) in points.iter().zip(&out) {
        assert!(q.converged, "{p:?} did not converge: {q:?}");
        assert!(q.residual <= 1e-3);
        radius_err = radius_err.max(((q.point - c).norm() - r).abs());
        angle = angle.max((p - c).normalize().cross(&(q.point - c).normalize()).norm());
    }
    println!("max radius error {radius_err:.2e} h, max angle {angle:.2e} rad");
    // The grid stores f32 distances; tricubic interpolation of a sphere of 20 voxels.
    assert!(radius_err < 2.5e-3, "radius error {radius_err}");
    assert!(angle < 1e-3, "not orthogonal: {angle}");
}

#[test]
fn points_outside_the_grid_are_not_converged() {
    let (phi, _) = sphere_grid(5.0);
    let out = project_to_zero_level(
        &phi,
        &[Point3::new(-50.0, 0.0, 0.0)],
        &LevelProjectOptions::default(),
    );
    assert!(!out[0].converged);
}
