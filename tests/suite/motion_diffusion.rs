//! Heat diffusion (`vesselmsr::motion::diffusion`): constant and linear fields, the variance of a
//! spread delta, the semigroup property, agreement of the two kernels, scipy's gaussian_filter
//! through the oracle, sub-boxes and bad input.

use crate::common;
use common::*;
use nalgebra::Point3;
use rand::RngExt;
use vesselmsr::grid::{Grid3, GridTransform, SubBox};
use vesselmsr::motion::diffusion::{
    diffuse, diffuse_in_box, DiffusionKernel, DiffusionOptions, AUTO_RECURSIVE_FROM_SIGMA,
};

const TRUNCATED: DiffusionOptions = DiffusionOptions {
    kernel: DiffusionKernel::Truncated { radius_sigmas: 4.0 },
};
const RECURSIVE: DiffusionOptions = DiffusionOptions {
    kernel: DiffusionKernel::Recursive,
};
const KERNELS: [(&str, DiffusionOptions); 2] = [("truncated", TRUNCATED), ("recursive", RECURSIVE)];

/// A grid of `dims` nodes, voxel `h`, origin (−1.5, 2, 0.25), values f(i, j, k).
fn grid_of(dims: [usize; 3], h: f64, f: impl Fn(usize, usize, usize) -> f64) -> Grid3 {
    let t = GridTransform::new(Point3::new(-1.5, 2.0, 0.25), h);
    let mut g = Grid3::new(dims, t, 0.0).unwrap();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                g.set(i, j, k, f(i, j, k) as f32);
            }
        }
    }
    g
}

fn random_grid(dims: [usize; 3], h: f64, seed: u64) -> Grid3 {
    let mut rng = rng(seed);
    let t = GridTransform::new(Point3::new(0.5, -3.0, 7.0), h);
    let mut g = Grid3::new(dims, t, 0.0).unwrap();
    g.data_mut()
        .iter_mut()
        .for_each(|v| *v = rng.random::<f32>() * 2.0 - 1.0);
    g
}

fn max_abs_diff(a: &[f32], b: &[f32]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| (x as f64 - y as f64).abs())
        .fold(0.0, f64::max)
}

#[test]
fn constant_field_is_unchanged() {
    // Non-cubic dims, σ from a fraction of a voxel to more than the grid (the mirror folds the
    // kernel several times), both kernels and Auto.
    for (name, opts) in KERNELS
        .iter()
        .chain(&[("auto", DiffusionOptions::default())])
    {
        for sigma_vox in [0.3, 1.0, 2.5, 7.0, 40.0] {
            let h = 0.37;
            let mut g = grid_of([23, 17, 9], h, |_, _, _| 3.25);
            let time = (sigma_vox * h) * (sigma_vox * h) / 2.0;
            diffuse(&mut g, time, opts).unwrap();
            let err = g
                .data()
                .iter()
                .map(|&v| (v as f64 - 3.25).abs() / 3.25)
                .fold(0.0, f64::max);
            assert!(
                err < 1e-6,
                "{name} σ = {sigma_vox} voxels: relative error {err:e}"
            );
        }
    }
}

/// Second moments of a diffused delta at the centre of a grid, per axis, in voxels².
fn delta_variances(opts: &DiffusionOptions, sigma_vox: f64, n: usize) -> ([f64; 3], f64) {
    let h = 0.5;
    let c = n / 2;
    let mut g = grid_of([n, n, n], h, |i, j, k| {
        f64::from(u8::from(i == c && j == c && k == c))
    });
    diffuse(&mut g, (sigma_vox * h).powi(2) / 2.0, opts).unwrap();
    let (mut mass, mut m2) = (0.0, [0.0; 3]);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let v = g.get(i, j, k) as f64;
                mass += v;
                for (a, x) in [i, j, k].into_iter().enumerate() {
                    m2[a] += v * (x as f64 - c as f64).powi(2);
                }
            }
        }
    }
    (m2.map(|m| m / mass), mass)
}

#[test]
fn delta_spreads_to_the_right_variance() {
    // u_t = Δu: each axis gains variance 2·time = σ² (world units); in voxels σ²/h².
    for (name, opts) in KERNELS {
        for sigma_vox in [1.0f64, 2.0, 4.0, 8.0] {
            let n = (2.0 * (6.0 * sigma_vox).ceil()) as usize + 1;
            let (var, mass) = delta_variances(&opts, sigma_vox, n);
            println!("{name} σ = {sigma_vox}: variances {var:?}, mass {mass}");
            assert!((mass - 1.0).abs() < 1e-5, "{name}: mass {mass}");
            for v in var {
                let rel = (v - sigma_vox * sigma_vox).abs() / (sigma_vox * sigma_vox);
                assert!(
                    rel < 0.01,
                    "{name} σ = {sigma_vox}: variance {v} (rel {rel:e})"
                );
            }
        }
    }
}

#[test]
fn recursive_matches_truncated() {
    let g0 = random_grid([40, 33, 29], 1.0, 3);
    for sigma in [
        0.05,
        0.25,
        0.5,
        0.8,
        1.5,
        3.0,
        AUTO_RECURSIVE_FROM_SIGMA,
        12.0,
    ] {
        let time = sigma * sigma / 2.0;
        let mut a = g0.clone();
        let mut b = g0.clone();
        // ρ = 8: the truncation error is far below the recursive filter's.
        let wide = DiffusionOptions {
            kernel: DiffusionKernel::Truncated { radius_sigmas: 8.0 },
        };
        diffuse(&mut a, time, &wide).unwrap();
        diffuse(&mut b, time, &RECURSIVE).unwrap();
        let d = max_abs_diff(a.data(), b.data());
        let range = a.data().iter().fold(0.0f64, |m, &v| m.max(v.abs() as f64));
        println!("σ = {sigma}: recursive vs truncated max |diff| {d:e} (field max {range:e})");
        // Values in [−1, 1]: the recursive filter is within ~1e-5 of the peak at σ = ¼ voxel.
        assert!(d < 2e-5, "σ = {sigma}: {d}");
    }
}

#[test]
fn bad_time_is_an_error() {
    let mut g = grid_of([4, 4, 4], 1.0, |i, _, _| i as f64);
    // A tiny time is fine: nothing moves.
    for (name, opts) in KERNELS {
        let mut tiny = g.clone();
        diffuse(&mut tiny, 1e-9, &opts).unwrap();
        assert!(max_abs_diff(tiny.data(), g.data()) < 1e-6, "{name}");
    }
    for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = diffuse(&mut g, t, &DiffusionOptions::default()).unwrap_err();
        assert!(e.to_string().contains("diffusion time"), "{e}");
        let b = g.whole_box();
        assert!(diffuse_in_box(&mut g, &b, t, &DiffusionOptions::default()).is_err());
    }
    let bad = DiffusionOptions {
        kernel: DiffusionKernel::Truncated { radius_sigmas: 0.0 },
    };
    assert!(diffuse(&mut g, 1.0, &bad).is_err());
    let outside = SubBox::new([0, 0, 0], [5, 4, 4]);
    assert!(diffuse_in_box(&mut g, &outside, 1.0, &DiffusionOptions::default()).is_err());
}

/// Weights of the normalised sampled Gaussian cut at ⌊ρσ + ½⌋, w[0..=r] (independent of the
/// library: the rule is scipy's).
fn sampled_weights(sigma: f64, rho: f64) -> Vec<f64> {
    let r = (rho * sigma + 0.5).floor() as usize;
    let w: Vec<f64> = (0..=r)
        .map(|t| (-0.5 * (t as f64 / sigma).powi(2)).exp())
        .collect();
    let sum = w[0] + 2.0 * w[1..].iter().sum::<f64>();
    w.iter().map(|v| v / sum).collect()
}

/// Index i mirrored into 0..n about the half-voxel faces.
fn mirror(i: isize, n: usize) -> usize {
    let m = i.rem_euclid(2 * n as isize) as usize;
    if m < n {
        m
    } else {
        2 * n - 1 - m
    }
}

#[test]
fn linear_field_is_kept_inside_and_mirrored_at_the_faces() {
    // f = 2 + 0.5·i − 0.25·j + 0.125·k, σ = 2 voxels (h = 0.5 world units).
    let (n, h, sigma) = ([40usize, 36, 34], 0.5, 2.0);
    let f = |i: f64, j: f64, k: f64| 2.0 + 0.5 * i - 0.25 * j + 0.125 * k;
    let time = (sigma * h) * (sigma * h) / 2.0;
    for (name, opts) in KERNELS {
        let mut g = grid_of(n, h, |i, j, k| f(i as f64, j as f64, k as f64));
        diffuse(&mut g, time, &opts).unwrap();
        // Interior (6σ from every face): unchanged.
        let reach = 12;
        let mut worst: f64 = 0.0;
        for k in reach..n[2] - reach {
            for j in reach..n[1] - reach {
                for i in reach..n[0] - reach {
                    let e = f(i as f64, j as f64, k as f64);
                    worst = worst.max((g.get(i, j, k) as f64 - e).abs());
                }
            }
        }
        println!("{name}: linear field, interior max |change| {worst:e}");
        assert!(worst < 2e-5, "{name}: interior changed by {worst}");
        // Faces: the field is reflected, so node i becomes Σ_t w_t·f(mirror(i + t)) (the mirror
        // flattens the slope at the face: node 0 rises, the last node sinks).
        // (The truncated kernel's own radius; the recursive filter is the untruncated Gaussian.)
        let rho = if name == "truncated" { 4.0 } else { 10.0 };
        let w = sampled_weights(sigma, rho);
        let r = w.len() as isize - 1;
        let expect = |i: usize| -> f64 {
            (-r..=r)
                .map(|t| w[t.unsigned_abs()] * mirror(i as isize + t, n[0]) as f64)
                .sum()
        };
        let (j, k) = (n[1] / 2, n[2] / 2);
        for i in [0, 1, 3, n[0] - 1] {
            let got = g.get(i, j, k) as f64;
            let want = f(expect(i), j as f64, k as f64);
            assert!(
                (got - want).abs() < 2e-5,
                "{name}: node {i}: {got} vs {want}"
            );
        }
        assert!(g.get(0, j, k) as f64 > f(0.0, j as f64, k as f64) + 0.1);
        let last = (n[0] - 1) as f64;
        assert!((g.get(n[0] - 1, j, k) as f64) < f(last, j as f64, k as f64) - 0.1);
    }
}

#[test]
fn mass_is_conserved_at_the_faces() {
    // A delta in a corner: the mirror folds the kernel back, nothing leaks out (zero padding would
    // lose 7/8 of the mass, scipy's whole-sample "mirror" mode would not conserve it either).
    for (name, opts) in KERNELS {
        for sigma in [1.5, 5.0] {
            let mut g = grid_of([20, 18, 16], 1.0, |i, j, k| {
                f64::from(u8::from(i + j + k == 0))
            });
            diffuse(&mut g, sigma * sigma / 2.0, &opts).unwrap();
            let mass: f64 = g.data().iter().map(|&v| v as f64).sum();
            println!("{name} σ = {sigma}: mass {mass}");
            assert!((mass - 1.0).abs() < 1e-5, "{name} σ = {sigma}: mass {mass}");
            // Even about the faces: node 0 and node 1 of the corner's line see the same images.
            assert!(g.get(0, 0, 0) > g.get(1, 0, 0) && g.get(1, 0, 0) > g.get(2, 0, 0));
        }
    }
}

#[test]
fn semigroup() {
    // u(t1 + t2) = u(t2) after u(t1): on the mirrored (periodic) field the Gaussians compose.
    let g0 = random_grid([30, 28, 26], 0.8, 11);
    let (t1, t2) = (0.8, 1.7); // σ = 1.6h, 2.3h, together 2.8h
    let wide = DiffusionOptions {
        kernel: DiffusionKernel::Truncated { radius_sigmas: 6.0 },
    };
    for (name, opts) in [("truncated ρ = 6", wide), ("recursive", RECURSIVE)] {
        let mut two = g0.clone();
        diffuse(&mut two, t1, &opts).unwrap();
        diffuse(&mut two, t2, &opts).unwrap();
        let mut one = g0.clone();
        diffuse(&mut one, t1 + t2, &opts).unwrap();
        let d = max_abs_diff(one.data(), two.data());
        let amp = one
            .data()
            .iter()
            .fold(0.0f64, |m, &v| m.max(v.abs() as f64));
        println!("{name}: semigroup max |diff| {d:e} (field max {amp:e})");
        // f32 rounding (truncated); the recursive filter's ~3e-6-of-peak approximation, twice.
        assert!(d < 2e-5 * amp, "{name}: {d}");
    }
}

#[test]
fn matches_scipy_gaussian_filter() {
    // scipy.ndimage.gaussian_filter, mode "reflect" (= our mirror about the half-voxel faces),
    // σ = √(2t)/h voxels, on a random 48³ field.
    let oracle = oracle();
    let dir = tempfile::tempdir().unwrap();
    let g0 = random_grid([48, 48, 48], 0.7, 21);
    let input = dir.path().join("g.npy");
    vesselmsr::io::write_npy(&input, &g0).unwrap();
    for sigma_vox in [1.0, 2.5, 8.0] {
        let time = (sigma_vox * 0.7f64).powi(2) / 2.0;
        // scipy's default cut (4σ) for our truncated kernel, and a cut at 10σ (the untruncated
        // Gaussian to 1e-20) for the recursive filter.
        let reference = |truncate: &str| {
            let out = dir.path().join(format!("o{truncate}.npy"));
            let answer = oracle.run(&[
                &"gaussian",
                &input,
                &time.to_string(),
                &out,
                &"--truncate",
                &truncate,
            ]);
            let sv = answer["sigma_voxels"].as_f64().unwrap();
            assert!((sv - sigma_vox).abs() < 1e-9, "{sv}");
            vesselmsr::io::read_npy(&out).unwrap()
        };
        let (cut4, cut10) = (reference("4"), reference("10"));
        let auto_recursive = sigma_vox >= AUTO_RECURSIVE_FROM_SIGMA;
        for (name, opts) in KERNELS
            .iter()
            .chain(&[("auto", DiffusionOptions::default())])
        {
            let mut g = g0.clone();
            diffuse(&mut g, time, opts).unwrap();
            let recursive = *name == "recursive" || (*name == "auto" && auto_recursive);
            let (reference, cut, tol) = if recursive {
                (&cut10, 10, 5e-6)
            } else {
                (&cut4, 4, 3e-7)
            };
            let d = max_abs_diff(g.data(), reference.data());
            println!("σ = {sigma_vox} voxels, {name}: max |ours − scipy (truncate {cut})| {d:e}");
            // Field values in [−1, 1]: f32 rounding for the same truncated kernel; the recursive
            // filter's approximation (≤ 3e-6 of the kernel's peak) for the recursive one.
            assert!(d < tol, "σ = {sigma_vox}, {name}: {d}");
        }
    }
}

#[test]
fn diffuse_in_box_equals_diffuse_on_the_extracted_grid() {
    let g0 = random_grid([30, 26, 22], 0.4, 31);
    let sub_box = SubBox::new([3, 5, 2], [27, 19, 17]);
    for (name, opts) in KERNELS {
        let mut g = g0.clone();
        diffuse_in_box(&mut g, &sub_box, 0.3, &opts).unwrap();
        let mut sub = g0.extract(&sub_box).unwrap();
        diffuse(&mut sub, 0.3, &opts).unwrap();
        for idx in 0..g.data().len() {
            let [i, j, k] = g.coords(idx);
            if sub_box.contains([i, j, k]) {
                let m = sub_box.min;
                let want = sub.get(i - m[0], j - m[1], k - m[2]);
                assert_eq!(g.data()[idx].to_bits(), want.to_bits(), "{name} inside");
            } else {
                assert_eq!(
                    g.data()[idx].to_bits(),
                    g0.data()[idx].to_bits(),
                    "{name} outside"
                );
            }
        }
        // And it differs from diffusing the whole grid near the box's faces (mirror there), but
        // not deep inside (σ = √0.6/0.4 ≈ 1.9 voxels; the box centre is ≥ 7 voxels from a face).
        let mut whole = g0.clone();
        diffuse(&mut whole, 0.3, &opts).unwrap();
        let (c, f) = ([15, 12, 9], [3, 12, 9]);
        let at = |g: &Grid3, p: [usize; 3]| g.get(p[0], p[1], p[2]) as f64;
        assert!((at(&g, c) - at(&whole, c)).abs() < 1e-4, "{name} centre");
        assert!((at(&g, f) - at(&whole, f)).abs() > 1e-4, "{name} face");
    }
}

#[test]
fn thin_and_flat_grids() {
    // Axes of one node are left alone (a mirror of one node is constant): a 2-D grid diffuses
    // as in 2-D, and matches a 3-D grid whose z-slices are all equal.
    let flat = random_grid([17, 13, 1], 1.0, 41);
    let stacked = grid_of([17, 13, 5], 1.0, |i, j, _| flat.get(i, j, 0) as f64);
    for (name, opts) in KERNELS {
        let mut a = flat.clone();
        diffuse(&mut a, 2.0, &opts).unwrap();
        let mut b = stacked.clone();
        diffuse(&mut b, 2.0, &opts).unwrap();
        for k in 0..5 {
            for j in 0..13 {
                for i in 0..17 {
                    let d = (a.get(i, j, 0) - b.get(i, j, k)).abs();
                    assert!(d < 1e-6, "{name} ({i}, {j}, {k}): {d}");
                }
            }
        }
        let mut tiny = grid_of([1, 1, 1], 1.0, |_, _, _| 4.0);
        diffuse(&mut tiny, 1e-12, &opts).unwrap();
        diffuse(&mut tiny, 100.0, &opts).unwrap();
        assert_eq!(tiny.get(0, 0, 0), 4.0);
    }
}

#[test]
fn kernel_wider_than_the_grid() {
    // The mirror folds a kernel wider than an axis back onto it: σ = 6 voxels on axes of 12, 10
    // and 8 nodes (ρ = 8: 48 nodes each side) still agrees with the recursive filter, and a huge
    // σ leaves the mean everywhere (Neumann: the heat equation conserves it and flattens).
    let g0 = random_grid([12, 10, 8], 0.5, 51);
    let mean = g0.data().iter().map(|&v| v as f64).sum::<f64>() / g0.data().len() as f64;
    let wide = DiffusionOptions {
        kernel: DiffusionKernel::Truncated { radius_sigmas: 8.0 },
    };
    let time = (6.0f64 * 0.5).powi(2) / 2.0;
    let mut a = g0.clone();
    diffuse(&mut a, time, &wide).unwrap();
    let mut b = g0.clone();
    diffuse(&mut b, time, &RECURSIVE).unwrap();
    let d = max_abs_diff(a.data(), b.data());
    let spread = a
        .data()
        .iter()
        .map(|&v| (v as f64 - mean).abs())
        .fold(0.0, f64::max);
    println!(
        "σ = 6 voxels on 12×10×8: truncated vs recursive {d:e}, spread about the mean {spread:e}"
    );
    assert!(d < 2e-6, "{d}");
    assert!(
        spread > 1e-3,
        "not yet flat: the comparison means something"
    );
    for (name, opts) in KERNELS {
        let mut g = g0.clone();
        diffuse(&mut g, (1000.0f64 * 0.5).powi(2) / 2.0, &opts).unwrap();
        let worst = g
            .data()
            .iter()
            .map(|&v| (v as f64 - mean).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-6,
            "{name}: σ = 1000 voxels, max |u − mean| {worst}"
        );
    }
    // A truncated kernel wider than MAX_RADIUS nodes is refused (the recursive one is not).
    let mut g = g0.clone();
    let e = diffuse(&mut g, 1e16, &TRUNCATED).unwrap_err();
    assert!(e.to_string().contains("recursive"), "{e}");
    for time in [1e16, 1e300] {
        let mut g = g0.clone();
        diffuse(&mut g, time, &DiffusionOptions::default()).unwrap();
        assert!(
            g.data().iter().all(|&v| (v as f64 - mean).abs() < 1e-5),
            "time {time}"
        );
    }
}
