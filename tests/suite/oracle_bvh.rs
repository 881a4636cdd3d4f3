//! Our BVH queries against libigl (the Python oracle) on the real meshes: closest-point distances
//! equal libigl's point_mesh_squared_distance, and the fast winding number's inside/outside sign
//! equals libigl's fast winding number at points farther than one mean edge from the surface.

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::io::read_mesh;
use vesselmsr::mesh::measures::{bounding_box, mean_edge_length};

/// Half uniform in the bounding box grown by 20%, half near the surface (a vertex plus a random
/// offset of up to three mean edges per axis). Not `common::sample_points`: that one offsets by
/// at most two mean edges in a random direction and puts about half as many points between one
/// and three mean edges from the surface, the band the winding-sign test below keeps.
fn test_points(mesh: &vesselmsr::TriMesh, n: usize, seed: u64) -> Vec<Point3<f64>> {
    let mut rng = rng(seed);
    let (lo, hi) = bounding_box(mesh);
    let (size, edge) = (hi - lo, mean_edge_length(mesh));
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                let u = Vector3::from(rng.random::<[f64; 3]>());
                lo - 0.1 * size + (1.2 * size).component_mul(&u)
            } else {
                let v = mesh.vertices[rng.random_range(0..mesh.num_vertices())];
                let d: [f64; 3] = rng.random();
                v + (Vector3::from(d) * 2.0 - Vector3::repeat(1.0)) * 3.0 * edge
            }
        })
        .collect()
}

#[test]
fn closest_distances_equal_libigl() {
    let Some(dir) = real_dir() else { return };
    let oracle = oracle();
    for (file, ..) in REAL_MESHES {
        let path = dir.join(file);
        let mesh = read_mesh(&path).unwrap();
        let diag = bbox_diagonal(&mesh);
        let points = test_points(&mesh, 10_000, 7);
        let bvh = MeshBvh::new(&mesh);
        let ours = bvh.closest_points(&points);
        let (theirs, _) = oracle.query("closest", &path, &points, 4);
        let worst = ours
            .iter()
            .zip(theirs.chunks_exact(4))
            .map(|(c, t)| (c.distance - t[0]).abs())
            .fold(0.0, f64::max);
        println!(
            "{file}: max |d_ours − d_libigl| = {:.3e} × bbox diagonal",
            worst / diag
        );
        assert!(
            worst <= 1e-7 * diag,
            "{file}: closest distance differs from libigl by {worst}"
        );
    }
}

#[test]
fn winding_sign_matches_libigl_away_from_open_surfaces() {
    let Some(dir) = real_dir() else { return };
    let oracle = oracle();
    for (file, _, _, loops, _) in REAL_MESHES {
        if loops == 0 {
            continue;
        }
        let path = dir.join(file);
        let mesh = read_mesh(&path).unwrap();
        let edge = mean_edge_length(&mesh);
        let bvh = MeshBvh::new(&mesh);
        let points: Vec<_> = test_points(&mesh, 20_000, 11)
            .into_iter()
            .filter(|p| bvh.closest_point(p).distance > edge)
            .collect();
        let wn = WindingNumber::new(&mesh, WindingOptions::default());
        let (theirs, _) = oracle.query("winding", &path, &points, 1);
        let mut mismatches = 0;
        let mut inside = 0;
        for (p, w_igl) in points.iter().zip(&theirs) {
            let w = wn.winding_number(p);
            // Two of the open meshes face inward (w ≈ −1 inside): count |w| for the straddle check.
            inside += (w.abs() >= 0.5) as usize;
            if (w >= 0.5) != (*w_igl >= 0.5) {
                mismatches += 1;
                println!("{file}: mismatch at {p:?}: ours {w}, libigl {w_igl}");
            }
        }
        println!("{file}: {} points farther than one mean edge, {inside} inside, {mismatches} sign mismatches", points.len());
        assert!(
            inside > 100 && inside < points.len() - 100,
            "{file}: test points must straddle the surface"
        );
        assert_eq!(
            mismatches, 0,
            "{file}: winding-number sign differs from libigl"
        );
    }
}
