//! Generalized winding number: exact values on a cube (inside, outside, flipped) and an open box,
//! the solid angle of an octant, the order of the far-field expansion (error decay per order on a
//! synthetic patch), and the fast hierarchical evaluation against the exact sum on the real
//! meshes (default options within 1e-4) and on a small mesh far from the origin.
//!
//! `cargo test --release --test suite bvh_winding:: -- --ignored --nocapture` also prints the
//! table of error and throughput per (order, β) that the default was chosen from.

use nalgebra::{Point3, Vector3};
use rand::prelude::*;
use rayon::prelude::*;
use std::f64::consts::PI;
use vesselmsr::bvh::brute::winding_number_exact;
use vesselmsr::bvh::{solid_angle, MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::mesh::primitives::icosphere;
use vesselmsr::TriMesh;

use crate::common;
use common::*;

/// The setting of Barill et al. (2018): second order, β = 2 (about 1e-2 on the real meshes).
const PAPER: WindingOptions = WindingOptions {
    beta: 2.0,
    order: 2,
};

#[test]
fn octant_solid_angle() {
    let o = Point3::origin();
    let (x, y, z) = (
        Point3::new(1.0, 0.0, 0.0),
        Point3::new(0.0, 1.0, 0.0),
        Point3::new(0.0, 0.0, 1.0),
    );
    // One eighth of the sphere; its normal (y−x)×(z−x) points away from the origin.
    assert!((solid_angle(&o, &x, &y, &z) - PI / 2.0).abs() < 1e-14);
    assert!((solid_angle(&o, &x, &z, &y) + PI / 2.0).abs() < 1e-14);
    // In the triangle's plane and at a corner: 0, not NaN.
    assert_eq!(solid_angle(&Point3::new(2.0, -1.0, 0.0), &x, &y, &z), 0.0);
    assert_eq!(solid_angle(&x, &x, &y, &z), 0.0);
    // A degenerate triangle subtends nothing.
    assert_eq!(solid_angle(&o, &x, &x, &z), 0.0);
}

#[test]
fn cube_inside_outside_and_flipped() {
    let mut mesh = cube(-1.0, 1.0);
    let default = WindingNumber::new(&mesh, WindingOptions::default());
    let paper = WindingNumber::new(&mesh, PAPER);
    mesh.flip_faces();
    let default_flipped = WindingNumber::new(&mesh, WindingOptions::default());
    mesh.flip_faces();
    let mut rng = StdRng::seed_from_u64(3);
    let (mut max_exact, mut max_default, mut max_paper): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for i in 0..4000 {
        let p = Point3::from(Vector3::from_fn(|_, _| rng.random::<f64>() * 8.0 - 4.0));
        let inside = p.iter().all(|c| c.abs() < 1.0);
        let margin = p
            .iter()
            .map(|c| (c.abs() - 1.0).abs())
            .fold(f64::INFINITY, f64::min);
        if margin < 1e-6 {
            continue;
        }
        let want = if inside { 1.0 } else { 0.0 };
        let w = winding_number_exact(&mesh, &p);
        max_exact = max_exact.max((w - want).abs());
        max_default = max_default.max((default.winding_number(&p) - want).abs());
        max_default = max_default.max((default_flipped.winding_number(&p) + want).abs());
        max_paper = max_paper.max((paper.winding_number(&p) - want).abs());
        assert_eq!(default.is_inside(&p), inside, "{p}");
        assert_eq!(paper.is_inside(&p), inside, "{p}");
        if i % 4 == 0 {
            let mut flipped = mesh.clone();
            flipped.flip_faces();
            max_exact = max_exact.max((winding_number_exact(&flipped, &p) + want).abs());
        }
    }
    println!(
        "cube: max error exact {max_exact:.3e}, default {max_default:.3e}, \
         order 2 beta 2 {max_paper:.3e}"
    );
    assert!(max_exact < 1e-12);
    assert!(max_default < 1e-4);
    assert!(max_paper < 1e-2);
}

#[test]
fn open_box_is_half_across_its_opening() {
    // Unit cube without its +z face: from a point of the missing face's plane the five faces
    // fill a half-space of directions, so w = 1/2 anywhere inside the opening.
    let mesh = cube_without_side(0.0, 1.0, 5);
    let fast = WindingNumber::new(&mesh, WindingOptions::default());
    for (x, y) in [(0.5, 0.5), (0.1, 0.8), (0.97, 0.02)] {
        let p = Point3::new(x, y, 1.0);
        let we = winding_number_exact(&mesh, &p);
        let wf = fast.winding_number(&p);
        println!("open box at ({x}, {y}, 1): exact {we:.15}, fast {wf:.15}");
        assert!((we - 0.5).abs() < 1e-12);
        assert!((wf - 0.5).abs() < 1e-4);
    }
}

/// Largest |fast − exact| over `pts`.
fn max_error(wn: &WindingNumber, pts: &[Point3<f64>], exact: &[f64]) -> f64 {
    let fast = wn.winding_numbers(pts);
    fast.iter()
        .zip(exact)
        .map(|(f, e)| (f - e).abs())
        .fold(0.0, f64::max)
}

/// The exact winding number (sum of solid angles) at each point, in parallel.
fn exact_winding_numbers(mesh: &TriMesh, pts: &[Point3<f64>]) -> Vec<f64> {
    pts.par_iter()
        .map(|p| winding_number_exact(mesh, p))
        .collect()
}

#[test]
fn real_meshes_fast_equals_exact() {
    let Some(meshes) = real_meshes() else { return };
    for (name, mesh) in &meshes {
        let diag = bbox_diagonal(mesh);
        let bvh = MeshBvh::new(mesh);
        let pts = sample_points(mesh, 10_000, 43);
        let exact = exact_winding_numbers(mesh, &pts);
        let err = |options: WindingOptions| {
            max_error(&WindingNumber::from_bvh(bvh.clone(), options), &pts, &exact)
        };
        let default = WindingOptions::default();
        let e_default = err(default);
        let e_lower = err(WindingOptions {
            order: default.order - 1,
            ..default
        });
        let e_beta2 = err(WindingOptions {
            beta: 2.0,
            ..default
        });
        let e_beta4 = err(WindingOptions {
            beta: 4.0,
            ..default
        });
        let e_paper = err(PAPER);
        println!(
            "{name}: max |w_fast − w_exact| = {e_default:.3e} (default: order {}, beta {}); \
             {e_lower:.3e} (order {}); {e_beta2:.3e} (beta 2), {e_beta4:.3e} (beta 4); \
             {e_paper:.3e} (order 2, beta 2)",
            default.order,
            default.beta,
            default.order - 1
        );
        assert!(e_default <= 1e-4, "{name}: default error {e_default}");
        assert!(e_paper <= 2e-2, "{name}: order 2, beta 2 error {e_paper}");
        // The highest-order term matters: dropping it costs a clear factor at the same β.
        assert!(
            e_lower / e_default > 3.0,
            "{name}: error ratio without the last order {}",
            e_lower / e_default
        );
        // and the error falls faster than β⁻⁵ (measured: about β⁻⁷ at order 4).
        assert!(
            e_beta2 / e_beta4 > 32.0,
            "{name}: error ratio beta 2 / beta 4 {}",
            e_beta2 / e_beta4
        );

        // Closed meshes: the exact number is an integer away from the surface, +1 inside for the
        // outward cortex and −1 inside for the inward-facing capped aorta.
        let closed_sign = match name.as_str() {
            "cortex_rh_pial_fsaverage5.stl" => Some(1.0),
            "aorta_abdominal_capped.stl" => Some(-1.0),
            _ => None,
        };
        if let Some(sign) = closed_sign {
            let dist = bvh.closest_points(&pts);
            let (mut worst, mut n_in): (f64, usize) = (0.0, 0);
            for (w, cp) in exact.iter().zip(&dist) {
                if cp.distance > 1e-4 * diag {
                    let nearest = if (w - sign).abs() < 0.5 { sign } else { 0.0 };
                    n_in += (nearest != 0.0) as usize;
                    worst = worst.max((w - nearest).abs());
                }
            }
            println!("{name}: closed, {n_in} points inside, max |w − integer| = {worst:.3e}");
            assert!(worst < 1e-8, "{name}: {worst}");
            assert!(n_in > 500, "{name}: too few inside points ({n_in})");
        }
    }
}

#[test]
fn small_mesh_far_from_origin_and_reused_bvh() {
    let mesh = icosphere(3, 1e-2, Point3::new(1e3, -2e3, 5e2));
    let wn = WindingNumber::from_bvh(MeshBvh::new(&mesh), WindingOptions::default());
    let pts = sample_points(&mesh, 3000, 8);
    let exact: Vec<f64> = pts
        .par_iter()
        .map(|p| winding_number_exact(&mesh, p))
        .collect();
    assert!(exact.iter().any(|w| (w - 1.0).abs() < 1e-9));
    let err = max_error(&wn, &pts, &exact);
    let err_paper = max_error(&WindingNumber::new(&mesh, PAPER), &pts, &exact);
    println!(
        "far small icosphere: max |w_fast − w_exact| = {err:.3e} (default), \
         {err_paper:.3e} (order 2, beta 2)"
    );
    assert!(err <= 1e-4);
    assert!(err_paper <= 2e-2);
    // The hierarchy is the one handed in, and still answers closest-point queries.
    let c = Point3::new(1e3, -2e3, 5e2);
    assert!((wn.bvh().closest_point(&c).distance - 1e-2).abs() < 1e-3);
    assert_eq!(wn.bvh().num_triangles(), mesh.num_faces());
}

#[test]
fn empty_mesh_has_winding_number_zero() {
    let wn = WindingNumber::new(&TriMesh::default(), WindingOptions::default());
    assert_eq!(wn.winding_number(&Point3::new(1.0, 2.0, 3.0)), 0.0);
    assert!(!wn.is_inside(&Point3::origin()));
}

/// Open bumpy height-field patch over [−1, 1]², `k` × `k` quads.
fn bumpy_patch(k: usize) -> TriMesh {
    let mut v = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            let x = -1.0 + 2.0 * i as f64 / k as f64;
            let y = -1.0 + 2.0 * j as f64 / k as f64;
            v.push(Point3::new(
                x,
                y,
                0.3 * (2.0 * x).sin() * (3.0 * y).cos() + 0.1 * x * y,
            ));
        }
    }
    let id = |i: usize, j: usize| (j * (k + 1) + i) as u32;
    let mut f = Vec::new();
    for j in 0..k {
        for i in 0..k {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(v, f)
}

#[test]
fn expansion_error_gains_one_power_per_order() {
    // Points far from a small open patch see it through the root's expansion alone (β = 1: the
    // root's radius is at most 2 × 1.47 and the points are at least 4 × 1.56 − 1.47 away from
    // its centre), so the error is the truncation error of one expansion: order k leaves the
    // order k + 1 term, which falls like distance^−(k+3).
    let mesh = bumpy_patch(8);
    let mut rng = StdRng::seed_from_u64(5);
    let dirs: Vec<Vector3<f64>> = (0..200).map(|_| unit_vector(&mut rng)).collect();
    let radius = 2f64.sqrt() * 1.1;
    let dists = [4.0, 8.0, 16.0, 32.0];
    let mut prev: Option<Vec<f64>> = None;
    for order in 0..=5u8 {
        let wn = WindingNumber::new(&mesh, WindingOptions { beta: 1.0, order });
        let errs: Vec<f64> = dists
            .iter()
            .map(|&k| {
                dirs.iter()
                    .map(|d| {
                        let p = Point3::from(d * (k * radius));
                        (wn.winding_number(&p) - winding_number_exact(&mesh, &p)).abs()
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        let slopes: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!(
            "patch, order {order}: max error {:?} at {dists:?} radii, log2 ratios {slopes:.2?}",
            errs.iter().map(|e| format!("{e:.2e}")).collect::<Vec<_>>()
        );
        let want = order as f64 + 3.0;
        let last = slopes[slopes.len() - 1];
        assert!((last - want).abs() < 0.25, "order {order}: slope {last}");
        if let Some(prev) = prev {
            for (e, p) in errs.iter().zip(&prev) {
                assert!(
                    e < p,
                    "order {order}: error {e} not below order {}: {p}",
                    order - 1
                );
            }
        }
        prev = Some(errs);
    }
}

#[test]
fn out_of_range_options_are_clamped() {
    // β below 1 or NaN means 1; orders above 5 mean 5: same values, finite.
    let mesh = icosphere(2, 1.0, Point3::origin());
    let pts = sample_points(&mesh, 500, 4);
    let reference = WindingNumber::new(
        &mesh,
        WindingOptions {
            beta: 1.0,
            order: 5,
        },
    );
    for options in [
        WindingOptions {
            beta: f64::NAN,
            order: 200,
        },
        WindingOptions {
            beta: 0.25,
            order: 6,
        },
    ] {
        let wn = WindingNumber::new(&mesh, options);
        for p in &pts {
            let w = wn.winding_number(p);
            assert!(w.is_finite());
            assert_eq!(w, reference.winding_number(p), "{options:?} at {p}");
        }
    }
    // An infinite β never uses an expansion: the exact sum.
    let exact_wn = WindingNumber::new(
        &mesh,
        WindingOptions {
            beta: f64::INFINITY,
            order: 4,
        },
    );
    for p in &pts {
        assert!((exact_wn.winding_number(p) - winding_number_exact(&mesh, p)).abs() < 1e-12);
    }
}

/// Measurement behind the default options (run with `--ignored --nocapture`, release): max
/// |fast − exact| per real mesh on 10,000 points for orders 2 to 5 and several β, and the
/// throughput on the cortex (100,000 points of the same mix, all threads, best of 5).
/// `WINDING_SWEEP_ORDERS` and `WINDING_SWEEP_BETAS` (comma-separated) override the grid.
#[test]
#[ignore = "measurement, not a check: cargo test --release --test suite bvh_winding:: -- --ignored --nocapture"]
fn winding_order_beta_sweep() {
    let Some(meshes) = real_meshes() else { return };
    let list = |key: &str, default: &str| -> Vec<f64> {
        std::env::var(key)
            .unwrap_or_else(|_| default.to_string())
            .split(',')
            .filter_map(|x| x.trim().parse().ok())
            .collect()
    };
    let orders: Vec<u8> = list("WINDING_SWEEP_ORDERS", "2,3,4,5")
        .iter()
        .map(|&o| o as u8)
        .collect();
    let betas = list("WINDING_SWEEP_BETAS", "1.5,2,2.5,3,4");
    let mut worst = vec![vec![0.0f64; betas.len()]; orders.len()];
    for (name, mesh) in &meshes {
        let bvh = MeshBvh::new(mesh);
        let pts = sample_points(mesh, 10_000, 43);
        let exact = exact_winding_numbers(mesh, &pts);
        for (oi, &order) in orders.iter().enumerate() {
            let mut line = format!("{name:32} order {order}:");
            for (bi, &beta) in betas.iter().enumerate() {
                let wn = WindingNumber::from_bvh(bvh.clone(), WindingOptions { beta, order });
                let e = max_error(&wn, &pts, &exact);
                worst[oi][bi] = worst[oi][bi].max(e);
                line += &format!("  beta {beta}: {e:.2e}");
            }
            println!("{line}");
        }
    }
    for (oi, &order) in orders.iter().enumerate() {
        let cells: Vec<String> = worst[oi].iter().map(|e| format!("{e:.2e}")).collect();
        println!("worst of six, order {order}: {}", cells.join("  "));
    }
    let cortex = &meshes[5].1;
    let pts = sample_points(cortex, 100_000, 7);
    let bvh = MeshBvh::new(cortex);
    for &order in &orders {
        let mut line = format!("cortex, order {order}, M queries/s:");
        for &beta in &betas {
            let wn = WindingNumber::from_bvh(bvh.clone(), WindingOptions { beta, order });
            let mut best = f64::INFINITY;
            for _ in 0..5 {
                let t = std::time::Instant::now();
                std::hint::black_box(wn.winding_numbers(&pts));
                best = best.min(t.elapsed().as_secs_f64());
            }
            line += &format!("  beta {beta}: {:.3}", pts.len() as f64 / best / 1e6);
        }
        println!("{line}");
    }
}

/// On a closed surface the winding number is the signed count of ray crossings
/// (`MeshBvh::winding_number_by_rays`, what the voxelizer's sign uses on closed meshes): equal
/// to the rounded exact sum at every sampled point off the surface of the closed real meshes
/// (outward cortex: 1 inside; inward capped aorta: −1 inside), and at the nodes of a lattice
/// through each (axis-aligned rows of points, as the voxelizer's seeds are); also on a sphere
/// (both orientations) and two overlapping spheres (2 in the overlap).
#[test]
fn closed_meshes_winding_by_rays_equals_exact() {
    let mut cases: Vec<(String, TriMesh)> = Vec::new();
    let sphere = icosphere(3, 1.0, Point3::origin());
    let mut flipped = sphere.clone();
    flipped.flip_faces();
    let mut two = sphere.clone();
    two.append(&icosphere(3, 1.0, Point3::new(0.7, 0.1, 0.0)));
    cases.push(("sphere".into(), sphere));
    cases.push(("inward sphere".into(), flipped));
    cases.push(("two overlapping spheres".into(), two));
    if let Some(meshes) = real_meshes() {
        for (name, mesh) in meshes {
            if name == "cortex_rh_pial_fsaverage5.stl" || name == "aorta_abdominal_capped.stl" {
                cases.push((name, mesh));
            }
        }
    }
    for (name, mesh) in &cases {
        let diag = bbox_diagonal(mesh);
        let bvh = MeshBvh::new(mesh);
        let mut pts = sample_points(mesh, 1_500, 7);
        let (lo, hi) = vesselmsr::mesh::measures::bounding_box(mesh);
        let n = 14;
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let t = Vector3::new(i as f64, j as f64, k as f64) / (n - 1) as f64;
                    pts.push(lo + (hi - lo).component_mul(&t));
                }
            }
        }
        let dist = bvh.closest_points(&pts);
        let checked: Vec<(Point3<f64>, f64)> = pts
            .par_iter()
            .zip(&dist)
            .filter(|(_, cp)| cp.distance > 1e-6 * diag)
            .map(|(p, _)| (*p, winding_number_exact(mesh, p)))
            .collect();
        let (mut nonzero, mut two) = (0, 0);
        for (p, exact) in &checked {
            let rays = bvh.winding_number_by_rays(p);
            assert_eq!(
                rays,
                Some(exact.round() as i64),
                "{name} at {p}: exact {exact}"
            );
            nonzero += usize::from(exact.round() != 0.0);
            two += usize::from(exact.round().abs() == 2.0);
        }
        println!(
            "{name}: {} points, {nonzero} with w ≠ 0, {two} with |w| = 2: rays = exact",
            checked.len()
        );
        assert!(nonzero > 100, "{name}: too few inside points");
        assert_eq!(two > 0, name.starts_with("two"), "{name}");
    }
}
