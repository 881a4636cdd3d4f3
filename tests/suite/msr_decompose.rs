//! Decomposition (MST) and reconstruction (IMST) on shapes with known behaviour: an ellipsoid
//! under `vpmcf` keeps its volume within 1% per level and rounds off (details concentrate at
//! 0 as the levels go on); the vertices method gives back the input vertices to 1e-5h; the
//! level-set method rebuilds each level from the next within 0.5h (Hausdorff).

use crate::common;

use nalgebra::Point3;
use vesselmsr::grid::{grid_for_mesh, GridOptions};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::distance::{surface_distance, SurfaceDistanceOptions};
use vesselmsr::mesh::primitives::icosphere;
use vesselmsr::msr::decompose::{decompose, DecomposeOptions};
use vesselmsr::msr::reconstruct::{advect_back, AdvectOptions};
use vesselmsr::TriMesh;

fn ellipsoid(a: f64, b: f64, c: f64) -> TriMesh {
    let mut m = icosphere(4, 1.0, Point3::origin());
    for v in &mut m.vertices {
        *v = Point3::new(v.x * a, v.y * b, v.z * c);
    }
    m
}

#[test]
fn ellipsoid_decomposes_and_reconstructs() {
    let mesh = ellipsoid(12.0, 8.0, 6.0);
    let spec = grid_for_mesh(
        &mesh,
        &GridOptions {
            voxel: Some(0.5),
            padding_voxels: 6,
            ..Default::default()
        },
    )
    .unwrap();
    let h = spec.voxel();
    let phi = common::phi_on(&mesh, &spec);
    let opts = DecomposeOptions {
        levels: 4,
        time: Some(4.0 * 16.0 * h * h),
        keep_level_sets: true,
        ..Default::default()
    };
    let d = decompose(&mesh, phi, &opts, |_, _| {}).unwrap();
    let msr = &d.msr;
    let volume0 = 4.0 / 3.0 * std::f64::consts::PI * 12.0 * 8.0 * 6.0;

    // Vertices: S_0 is the input to 1e-5h.
    let s0 = msr.mesh_at(0);
    let worst = s0
        .vertices
        .iter()
        .zip(&mesh.vertices)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(worst <= 1e-5 * h, "vertices reconstruct to {worst}");

    let mut previous_mean = f64::INFINITY;
    for r in &d.reports {
        println!("{r:?}");
        assert!(
            (r.volume - volume0).abs() / volume0 < 0.01,
            "level {}: volume {}",
            r.level,
            r.volume
        );
        assert_eq!(r.unconverged, 0, "level {}", r.level);
        assert!(r.mean_abs_detail < previous_mean, "details shrink");
        previous_mean = r.mean_abs_detail;
    }
    // Level-set reconstruction of every level from the next.
    for i in 1..=msr.levels() {
        let rebuilt = advect_back(
            &d.level_sets[i],
            &msr.samples_at(i),
            &msr.details[i - 1],
            &AdvectOptions::default(),
        )
        .unwrap();
        let truth = extract_surface(&d.level_sets[i - 1], &ExtractOptions::default()).unwrap();
        let got = extract_surface(&rebuilt, &ExtractOptions::default()).unwrap();
        let dist = surface_distance(&truth, &got, &SurfaceDistanceOptions { samples: 20_000 });
        println!(
            "level {i}: hausdorff {:.3}h mean {:.4}h",
            dist.hausdorff / h,
            dist.mean_distance / h
        );
        assert!(
            dist.hausdorff <= 0.5 * h,
            "level {i}: {}",
            dist.hausdorff / h
        );
    }
}
