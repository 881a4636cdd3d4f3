//! Sampling a Grid3 at world points: trilinear and tricubic (Catmull-Rom) values and gradients
//! against analytic fields (exact where the interpolant reproduces the field, measured
//! convergence order on a sphere's distance otherwise), the domain, and C¹ continuity.
//!
//! The exactness tests use node coordinates that are multiples of 1/4 and small polynomial
//! coefficients, so every node value is exact in f32 and the only error left is f64 round-off.

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use vesselmsr::grid::{Grid3, GridTransform};

/// A grid of `dims` with node (0,0,0) at `origin` and voxel `h`, filled with `f` at the nodes.
fn grid_of(dims: [usize; 3], origin: [f64; 3], h: f64, f: impl Fn(&Point3<f64>) -> f64) -> Grid3 {
    let mut g = Grid3::new(dims, GridTransform::new(origin.into(), h), 0.0).unwrap();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let v = f(&g.world(i, j, k));
                g.set(i, j, k, v as f32);
            }
        }
    }
    g
}

/// Random points in the node box of `g`; one in four snapped onto a face or an edge of the box,
/// so border cells are always exercised.
fn points_in(g: &Grid3, n: usize, seed: u64) -> Vec<Point3<f64>> {
    let mut rng = rng(seed);
    let d = g.dims();
    (0..n)
        .map(|m| {
            let mut u = Vector3::from_fn(|a, _| rng.random::<f64>() * (d[a] - 1) as f64);
            if m % 4 == 0 {
                let a = m / 4 % 3;
                u[a] = if m % 8 == 0 { 0.0 } else { (d[a] - 1) as f64 };
            }
            g.transform().index_to_world(u)
        })
        .collect()
}

#[test]
fn trilinear_is_exact_on_multilinear_fields() {
    let f = |p: &Point3<f64>| 0.5 + 2.0 * p.x - 1.0 * p.y + 0.75 * p.z + 0.5 * p.x * p.y * p.z;
    let grad = |p: &Point3<f64>| {
        Vector3::new(
            2.0 + 0.5 * p.y * p.z,
            -1.0 + 0.5 * p.x * p.z,
            0.75 + 0.5 * p.x * p.y,
        )
    };
    let g = grid_of([7, 5, 9], [-1.0, 0.5, -0.75], 0.25, f);
    let pts = points_in(&g, 4000, 1);
    let mut worst: f64 = 0.0;
    let mut worst_grad: f64 = 0.0;
    for p in &pts {
        let v = g.sample_trilinear(p).unwrap();
        let (v2, gr) = g.sample_trilinear_with_gradient(p).unwrap();
        assert_eq!(v, v2, "value alone and with gradient agree at {p}");
        assert_eq!(g.gradient_trilinear(p).unwrap(), gr);
        worst = worst.max((v - f(p)).abs());
        // The trilinear gradient of a multilinear field is exact too (product of linears).
        worst_grad = worst_grad.max((gr - grad(p)).norm());
    }
    println!(
        "trilinear on a multilinear field: max value error {worst:.2e}, gradient {worst_grad:.2e}"
    );
    assert!(worst < 1e-12 && worst_grad < 1e-11);
}

#[test]
fn tricubic_is_exact_on_quadratics_including_border_cells() {
    // Degree ≤ 2 in each coordinate separately (x²y² etc. included: tensor-product reproduction).
    let f = |p: &Point3<f64>| {
        1.0 + p.x - 2.0 * p.y + 0.5 * p.z + 0.5 * p.x * p.x - 0.25 * p.y * p.y
            + 0.75 * p.z * p.z
            + p.x * p.y
            - 0.5 * p.y * p.z
            + 0.25 * p.x * p.x * p.y * p.y
    };
    let grad = |p: &Point3<f64>| {
        Vector3::new(
            1.0 + p.x + p.y + 0.5 * p.x * p.y * p.y,
            -2.0 - 0.5 * p.y + p.x - 0.5 * p.z + 0.5 * p.x * p.x * p.y,
            0.5 + 1.5 * p.z - 0.5 * p.y,
        )
    };
    // Axes of 3 nodes (both borders in one cell pair), 4 and 8 nodes.
    for dims in [[8, 4, 3], [3, 8, 6], [5, 3, 4]] {
        let g = grid_of(dims, [-0.5, 0.25, -1.0], 0.25, f);
        let mut worst: f64 = 0.0;
        let mut worst_grad: f64 = 0.0;
        for p in &points_in(&g, 3000, 2) {
            let (v, gr) = g.sample_tricubic_with_gradient(p).unwrap();
            assert_eq!(
                g.sample_tricubic(p).unwrap(),
                v,
                "value alone and with gradient agree"
            );
            worst = worst.max((v - f(p)).abs());
            worst_grad = worst_grad.max((gr - grad(p)).norm());
        }
        println!("tricubic on a quadratic, dims {dims:?}: max value error {worst:.2e}, gradient {worst_grad:.2e}");
        assert!(worst < 1e-11 && worst_grad < 1e-10, "dims {dims:?}");
    }
}

#[test]
fn tricubic_is_exact_on_linear_fields_with_two_node_axes() {
    // On an axis of two nodes the ghosts are extrapolated linearly: linear fields stay exact,
    // and a single-node axis is constant.
    let f = |p: &Point3<f64>| 0.25 - 1.5 * p.x + 2.0 * p.y - 0.5 * p.z;
    let g = grid_of([2, 6, 2], [0.0, -1.0, 2.0], 0.5, f);
    for p in &points_in(&g, 1000, 3) {
        let (v, gr) = g.sample_tricubic_with_gradient(p).unwrap();
        assert!((v - f(p)).abs() < 1e-12, "value at {p}");
        assert!(
            (gr - Vector3::new(-1.5, 2.0, -0.5)).norm() < 1e-12,
            "gradient at {p}"
        );
        let (v, gr) = g.sample_trilinear_with_gradient(p).unwrap();
        assert!((v - f(p)).abs() < 1e-12 && (gr - Vector3::new(-1.5, 2.0, -0.5)).norm() < 1e-12);
    }
    let flat = grid_of([4, 1, 3], [0.0, 7.0, 0.0], 0.5, |p| p.x + p.z);
    let p = Point3::new(0.6, 7.0, 0.3);
    let (v, gr) = flat.sample_tricubic_with_gradient(&p).unwrap();
    assert!((v - 0.9).abs() < 1e-12 && (gr - Vector3::new(1.0, 0.0, 1.0)).norm() < 1e-12);
    assert!((flat.sample_trilinear(&p).unwrap() - 0.9).abs() < 1e-12);
    assert!(flat.sample_tricubic(&Point3::new(0.6, 7.01, 0.3)).is_none());
}

#[test]
fn both_interpolants_return_node_values_at_nodes() {
    let mut rng = rng(4);
    let dims = [6, 5, 7];
    let mut g = Grid3::new(
        dims,
        GridTransform::new(Point3::new(3.0, -2.0, 1.0), 0.37),
        0.0,
    )
    .unwrap();
    g.data_mut()
        .iter_mut()
        .for_each(|v| *v = rng.random::<f32>() * 2.0 - 1.0);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = g.world(i, j, k);
                let want = g.get(i, j, k) as f64;
                assert!(
                    (g.sample_trilinear(&p).unwrap() - want).abs() < 1e-6,
                    "trilinear at node {i},{j},{k}"
                );
                assert!(
                    (g.sample_tricubic(&p).unwrap() - want).abs() < 1e-6,
                    "tricubic at node {i},{j},{k}"
                );
            }
        }
    }
}

#[test]
fn outside_the_node_box_gives_none() {
    let g = grid_of([4, 5, 6], [1.0, 2.0, 3.0], 0.5, |p| p.x);
    let h = 0.5;
    let lo = Point3::new(1.0, 2.0, 3.0);
    let hi = g.world(3, 4, 5);
    for p in [lo, hi, Point3::new(1.0, 4.0, 3.0 + 2.5)] {
        assert!(g.contains_point(&p), "{p} is on the box");
        assert!(g.sample_trilinear(&p).is_some() && g.sample_tricubic_with_gradient(&p).is_some());
    }
    let eps = 1e-6 * h;
    for p in [
        lo - Vector3::new(eps, 0.0, 0.0),
        hi + Vector3::new(0.0, eps, 0.0),
        hi + Vector3::new(0.0, 0.0, eps),
        Point3::new(f64::NAN, 2.5, 3.5),
        Point3::new(1.5, f64::INFINITY, 3.5),
    ] {
        assert!(!g.contains_point(&p), "{p} is outside");
        assert!(g.sample_trilinear(&p).is_none() && g.gradient_trilinear(&p).is_none());
        assert!(g.sample_tricubic(&p).is_none() && g.gradient_tricubic(&p).is_none());
    }
    // The value on the high face is the node value (no extrapolation past it).
    assert!((g.sample_tricubic(&hi).unwrap() - hi.x).abs() < 1e-6);
}

#[test]
fn tricubic_gradient_is_continuous_across_cell_faces() {
    // Random node values: the gradient jumps across faces for trilinear, not for Catmull-Rom.
    let mut rng = rng(5);
    let dims = [6, 6, 6];
    let mut g = Grid3::new(dims, GridTransform::new(Point3::origin(), 1.0), 0.0).unwrap();
    g.data_mut()
        .iter_mut()
        .for_each(|v| *v = rng.random::<f32>());
    let (mut cubic_jump, mut linear_jump): (f64, f64) = (0.0, 0.0);
    let d = 1e-7;
    for _ in 0..500 {
        let a = rng.random_range(0..3usize);
        // A face at integer coordinate 1..4 along axis a (interior and border-adjacent faces).
        let mut p = Point3::from(Vector3::from_fn(|_, _| 0.5 + rng.random::<f64>() * 4.0));
        p[a] = rng.random_range(1..5usize) as f64;
        let (mut below, mut above) = (p, p);
        below[a] -= d;
        above[a] += d;
        let jump = |f: &dyn Fn(&Point3<f64>) -> Vector3<f64>| (f(&above) - f(&below)).norm();
        cubic_jump = cubic_jump.max(jump(&|q| g.gradient_tricubic(q).unwrap()));
        linear_jump = linear_jump.max(jump(&|q| g.gradient_trilinear(q).unwrap()));
    }
    println!("largest gradient jump across a face: tricubic {cubic_jump:.2e}, trilinear {linear_jump:.2e}");
    assert!(cubic_jump < 1e-5, "tricubic gradient is C¹");
    assert!(
        linear_jump > 0.1,
        "the trilinear gradient does jump (the test can tell)"
    );
}

/// Root-mean-square value and gradient errors of both interpolants against the signed distance to
/// a sphere, on a grid of voxel `h` over [−1, 1]³, at points at least 0.25 from the centre.
fn sphere_errors(h: f64, pts: &[Point3<f64>]) -> [f64; 4] {
    let c = Point3::new(0.1, 0.05, -0.07);
    let r = 0.5;
    let n = (2.0 / h).round() as usize + 1;
    let g = grid_of([n; 3], [-1.0; 3], h, |p| (p - c).norm() - r);
    let mut sum = [0.0; 4];
    for p in pts {
        let exact = (p - c).norm() - r;
        let normal = (p - c).normalize();
        let (v1, g1) = g.sample_trilinear_with_gradient(p).unwrap();
        let (v3, g3) = g.sample_tricubic_with_gradient(p).unwrap();
        for (s, e) in sum.iter_mut().zip([
            v1 - exact,
            (g1 - normal).norm(),
            v3 - exact,
            (g3 - normal).norm(),
        ]) {
            *s += e * e;
        }
    }
    sum.map(|s| (s / pts.len() as f64).sqrt())
}

#[test]
fn convergence_orders_on_a_sphere_distance() {
    let c = Point3::new(0.1, 0.05, -0.07);
    let mut rng = rng(6);
    let pts: Vec<Point3<f64>> = std::iter::repeat_with(|| {
        Point3::from(Vector3::from_fn(|_, _| rng.random::<f64>() * 2.0 - 1.0))
    })
    .filter(|p| (p - c).norm() > 0.25)
    .take(4000)
    .collect();
    let hs = [1.0 / 8.0, 1.0 / 16.0, 1.0 / 32.0, 1.0 / 64.0];
    let errs: Vec<[f64; 4]> = hs.iter().map(|&h| sphere_errors(h, &pts)).collect();
    let names = [
        "trilinear value",
        "trilinear gradient",
        "tricubic value",
        "tricubic gradient",
    ];
    let want = [1.8, 0.9, 2.7, 1.8];
    for q in 0..4 {
        let orders: Vec<f64> = errs
            .windows(2)
            .map(|w| (w[0][q] / w[1][q]).log2())
            .collect();
        println!(
            "{}: rms errors {:?}, orders {:?}",
            names[q],
            errs.iter()
                .map(|e| format!("{:.2e}", e[q]))
                .collect::<Vec<_>>(),
            orders.iter().map(|o| format!("{o:.2}")).collect::<Vec<_>>()
        );
        for (o, w) in orders.iter().zip(errs.windows(2)) {
            assert!(
                *o > want[q],
                "{}: order {o:.2} between h = errors {:?}",
                names[q],
                w
            );
        }
    }
    // Tricubic beats trilinear at every resolution.
    for e in &errs {
        assert!(e[2] < e[0] && e[3] < e[1]);
    }
}
