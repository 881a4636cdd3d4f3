//! Enclosed cavities of the extraction: a bubble of outside behind a wall thinner than elsewhere
//! is joined to the outside through that thin wall only (one path of a few nodes), leaving one
//! component of genus 0; a mesh with a cavity of its own keeps it through `remesh`.

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::levelset::cavity::{extract_joining_cavities, find_cavities, CavityOptions};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::primitives::icosphere;
use vesselmsr::mesh::topology::{connected_components, Orientation};

/// A ball of radius 14 (voxel 1) with a spherical bubble of radius 8 whose centre is offset by
/// 4.5 along +x: the wall is 1.5 voxels thick at +x and 10.5 at −x.
fn ball_with_bubble() -> Grid3 {
    let n = 36;
    let c = Point3::new(17.3, 17.1, 16.9);
    let bubble = c + Vector3::new(4.5, 0.0, 0.0);
    let mut phi = Grid3::new([n; 3], GridTransform::new(Point3::origin(), 1.0), 0.0).unwrap();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = phi.world(i, j, k);
                let v = ((p - c).norm() - 14.0).max(8.0 - (p - bubble).norm());
                phi.set(i, j, k, v as f32);
            }
        }
    }
    phi
}

#[test]
fn a_bubble_is_joined_through_its_thinnest_wall() {
    let original = ball_with_bubble();
    let plain = extract_surface(&original, &ExtractOptions::default()).unwrap();
    assert_eq!(connected_components(&plain).0, 2);
    assert_eq!(find_cavities(&plain).len(), 1);

    let mut phi = original.clone();
    let (surface, joined) = extract_joining_cavities(
        &mut phi,
        &ExtractOptions::default(),
        &CavityOptions::default(),
    )
    .unwrap();
    assert_eq!(joined, 1);
    let info = mesh_info(&surface);
    assert!(info.watertight, "{:?}", info.leaks());
    assert_eq!(info.components, 1);
    assert_eq!(info.genus, Some(0));
    assert_eq!(info.orientation, Orientation::Outward);
    assert!(find_cavities(&surface).is_empty());

    // Only the nodes of the thin wall at +x changed, to +0.5 voxel.
    let changed: Vec<[usize; 3]> = (0..phi.data().len())
        .filter(|&n| phi.data()[n] != original.data()[n])
        .map(|n| phi.coords(n))
        .collect();
    assert!(
        !changed.is_empty() && changed.len() <= 3,
        "{} nodes changed",
        changed.len()
    );
    for &[i, j, k] in &changed {
        assert_eq!(phi.get(i, j, k), 0.5);
        let p = phi.world(i, j, k);
        assert!(
            p.x > 17.3 + 11.0,
            "changed node {p:?} is not in the thin wall"
        );
    }
}

#[test]
fn a_grid_without_cavities_is_left_alone() {
    // The same ball without the bubble.
    let mut phi = ball_with_bubble();
    let c = Point3::new(17.3, 17.1, 16.9);
    for n in 0..phi.data().len() {
        let [i, j, k] = phi.coords(n);
        let p = phi.world(i, j, k);
        phi.data_mut()[n] = ((p - c).norm() - 14.0) as f32;
    }
    let before = phi.clone();
    let (surface, joined) = extract_joining_cavities(
        &mut phi,
        &ExtractOptions::default(),
        &CavityOptions::default(),
    )
    .unwrap();
    assert_eq!(joined, 0);
    assert_eq!(connected_components(&surface).0, 1);
    assert_eq!(phi.data(), before.data());
}

#[test]
fn remesh_keeps_a_cavity_the_input_has() {
    // A hollow ball: outer sphere outward, inner sphere facing into the hollow.
    let mut mesh = icosphere(4, 10.0, Point3::origin());
    let mut inner = icosphere(4, 6.0, Point3::new(0.5, 0.0, 0.0));
    inner.flip_faces();
    mesh.append(&inner);
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("hollow.stl");
    vesselmsr::io::write_mesh(&input, &mesh).unwrap();
    let out = tmp.path().join("out.ply");
    let report = vesselmsr_json(&[
        "--json",
        "remesh",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--voxel",
        "0.5",
    ]);
    assert_eq!(report["cavities_joined"], 0);
    assert_eq!(report["output"]["components"], 2);
    assert_eq!(report["output"]["watertight"], true);
    let v = report["output"]["volume"].as_f64().unwrap();
    let exact = 4.0 / 3.0 * std::f64::consts::PI * (1000.0 - 216.0);
    assert!(rel(v, exact) < 0.02, "volume {v} vs {exact}");
}
