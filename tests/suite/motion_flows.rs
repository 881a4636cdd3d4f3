//! The level-set motions of `vesselmsr::motion` against their closed-form solutions (issue 4's
//! acceptance points): mean curvature flow of a sphere (r² = R² − 4t) for Δt from 0.5h² to 8h²,
//! `expand` and `inpaint` growing a sphere at rate c, `vpmcf` rounding an ellipsoid at constant
//! volume and leaving a sphere in place; rotation and translation invariance on the real cortex
//! and a vessel; grid refinement (orders printed with --nocapture); the sub-voxel volume, area
//! and volume shift; a flow restricted to a sub-box; and bad input.
//!
//! **Radius measure.** The radius of an evolved sphere is the mean distance from its centre of
//! the zero crossings of φ on grid edges (linear interpolation along each edge with a sign
//! change), independent of the volume estimate the flows use; the spread (largest minus smallest
//! crossing distance) says how round it stayed.

use crate::common;

use nalgebra::{Matrix3, Point3, Rotation3, Vector3};
use vesselmsr::grid::{grid_for_mesh, Grid3, GridOptions, GridTransform, SubBox};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::levelset::redistance::{redistance, RedistanceOptions};
use vesselmsr::levelset::voxelize::{voxelize, VoxelizeOptions};
use vesselmsr::mesh::distance::{surface_distance, SurfaceDistanceOptions};
use vesselmsr::mesh::measures::signed_volume;
use vesselmsr::motion::volume::{find_volume_shift, measure_area, measure_volume};
use vesselmsr::motion::{evolve, Flow, FlowOptions, Velocity};
use vesselmsr::TriMesh;

use std::f64::consts::PI;

/// The voxel size of the analytic tests (world units): not 1, so unit slips show.
const H: f64 = 0.37;

/// A grid of `dims` nodes of voxel [`H`] with φ = f(x) at every node.
fn grid_of(dims: [usize; 3], f: impl Fn(&Point3<f64>) -> f64) -> Grid3 {
    let t = GridTransform::new(Point3::new(-3.0, 1.5, 0.25), H);
    let mut g = Grid3::new(dims, t, 0.0).unwrap();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = g.world(i, j, k);
                g.set(i, j, k, f(&p) as f32);
            }
        }
    }
    g
}

/// The signed distance to a sphere of `r` voxels, `pad` voxels of room around it, its centre
/// off the nodes; returns the grid and the centre.
fn sphere(r: f64, pad: f64) -> (Grid3, Point3<f64>) {
    let n = (2.0 * (r + pad)).ceil() as usize + 1;
    let t = GridTransform::new(Point3::new(-3.0, 1.5, 0.25), H);
    let middle = Vector3::from_element(0.5 * (n - 1) as f64);
    let c = t.index_to_world(middle + Vector3::new(0.31, -0.17, 0.44));
    let g = grid_of([n; 3], |p| (p - c).norm() - r * H);
    (g, c)
}

/// Mean, smallest and largest distance from `c` of the zero crossings on grid edges.
fn crossing_radii(g: &Grid3, c: &Point3<f64>) -> (f64, f64, f64) {
    let d = g.dims();
    let (mut sum, mut n, mut lo, mut hi) = (0.0, 0usize, f64::MAX, 0.0f64);
    for k in 0..d[2] {
        for j in 0..d[1] {
            for i in 0..d[0] {
                let a = g.get(i, j, k) as f64;
                for axis in 0..3 {
                    let mut q = [i, j, k];
                    q[axis] += 1;
                    if q[axis] >= d[axis] {
                        continue;
                    }
                    let b = g.get(q[0], q[1], q[2]) as f64;
                    if (a < 0.0) != (b < 0.0) {
                        let mut step = Vector3::zeros();
                        step[axis] = a / (a - b) * g.voxel();
                        let r = (g.world(i, j, k) + step - c).norm();
                        sum += r;
                        n += 1;
                        lo = lo.min(r);
                        hi = hi.max(r);
                    }
                }
            }
        }
    }
    assert!(n > 0, "no zero crossing");
    (sum / n as f64, lo, hi)
}

/// Semi-axes (sorted, world units) of the solid ellipsoid with the second moments of the inside
/// of φ (nodes weighted by their sub-voxel inside fraction): a² = 5·(eigenvalue).
fn semi_axes(g: &Grid3) -> [f64; 3] {
    let h = g.voxel();
    let d = g.dims();
    let mut w_sum = 0.0;
    let mut first = Vector3::zeros();
    let mut second = Matrix3::zeros();
    for k in 0..d[2] {
        for j in 0..d[1] {
            for i in 0..d[0] {
                let w = (0.5 - g.get(i, j, k) as f64 / h).clamp(0.0, 1.0);
                if w > 0.0 {
                    let p = g.world(i, j, k).coords;
                    w_sum += w;
                    first += w * p;
                    second += w * p * p.transpose();
                }
            }
        }
    }
    let mean = first / w_sum;
    let cov = second / w_sum - mean * mean.transpose();
    let mut axes: Vec<f64> = cov
        .symmetric_eigenvalues()
        .iter()
        .map(|&l| (5.0 * l).sqrt())
        .collect();
    axes.sort_by(f64::total_cmp);
    [axes[0], axes[1], axes[2]]
}

/// Volume of the zero level set's marching-cubes mesh (outward, so positive).
fn mesh_volume(g: &Grid3) -> f64 {
    signed_volume(&extract_surface(g, &ExtractOptions::default()).unwrap())
}

/// Largest |r − r_exact(t)| in voxels over all steps of `velocity` from a sphere of `r0` voxels
/// up to `t_end`, in steps of at most `dt`, and the largest spread; prints a few lines.
fn sphere_run(
    velocity: Velocity,
    r0: f64,
    pad: f64,
    t_end: f64,
    dt: f64,
    opts: &FlowOptions,
    exact: impl Fn(f64) -> f64,
) -> (f64, f64) {
    let (mut g, c) = sphere(r0, pad);
    let n = vesselmsr::motion::step_count(t_end, dt).unwrap();
    let mut flow = Flow::new(velocity, t_end / n as f64, opts.clone()).unwrap();
    let (mut worst, mut spread) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let report = flow.step(&mut g).unwrap();
        let (mean, lo, hi) = crossing_radii(&g, &c);
        let err = (mean - exact(report.time)) / H;
        worst = worst.max(err.abs());
        spread = spread.max((hi - lo) / H);
    }
    (worst, spread)
}

#[test]
fn mcf_sphere_follows_r_squared_is_r0_squared_minus_4t_from_small_to_large_steps() {
    let r0 = 24.0;
    // Until r = R/2: R² − 4t = R²/4.
    let t_end = 3.0 * (r0 * H).powi(2) / 16.0;
    for dt_vox in [0.5f64, 2.0, 8.0] {
        let dt = dt_vox * H * H;
        let pad = 4.0 * (2.0 * dt_vox).sqrt() + 4.0;
        let (err, spread) = sphere_run(
            Velocity::MeanCurvature,
            r0,
            pad,
            t_end,
            dt,
            &FlowOptions::default(),
            |t| ((r0 * H).powi(2) - 4.0 * t).sqrt(),
        );
        println!("mcf R = 24h, Δt = {dt_vox}h²: largest radius error {err:.4}h until r = R/2, spread {spread:.3}h");
        assert!(err <= 0.3, "Δt = {dt_vox}h²: radius error {err}h");
    }
}

/// Layers of the cylinder's grid: enough that the middle one is beyond the diffusion's reach
/// from the border layers, where the surface meets the grid's border and the redistancer's
/// patches are one-sided.
const NZ: usize = 33;

/// Largest |r − √(R² − 2t)| in voxels of a cylinder of `r0` voxels (axis along z: the
/// diffusion's mirror boundary keeps φ independent of z) under mean curvature flow down to half
/// its radius, in steps of `dt_vox`·h², measured on the middle layer.
fn cylinder_run(r0: f64, dt_vox: f64, second_order: bool) -> f64 {
    let pad = 4.0 * (2.0 * dt_vox).sqrt() + 4.0;
    let n = (2.0 * (r0 + pad)).ceil() as usize + 1;
    let t = GridTransform::new(Point3::new(-3.0, 1.5, 0.25), H);
    let c = t.index_to_world(Vector3::new(
        0.5 * (n - 1) as f64 + 0.31,
        0.5 * (n - 1) as f64 - 0.17,
        0.0,
    ));
    let mut g = grid_of([n, n, NZ], |p| (p.xy() - c.xy()).norm() - r0 * H);
    let t_end = 3.0 * (r0 * H).powi(2) / 8.0;
    let steps = vesselmsr::motion::step_count(t_end, dt_vox * H * H).unwrap();
    let opts = FlowOptions {
        second_order,
        ..FlowOptions::default()
    };
    let mut flow = Flow::new(Velocity::MeanCurvature, t_end / steps as f64, opts).unwrap();
    let mut worst = 0.0f64;
    for _ in 0..steps {
        let report = flow.step(&mut g).unwrap();
        let middle = g
            .extract(&SubBox::new([0, 0, NZ / 2], [n, n, NZ / 2 + 1]))
            .unwrap();
        let mut sum = 0.0;
        let mut count = 0;
        for j in 0..n {
            for i in 0..n {
                let a = middle.get(i, j, 0) as f64;
                for (di, dj) in [(1, 0), (0, 1)] {
                    if i + di < n && j + dj < n {
                        let b = middle.get(i + di, j + dj, 0) as f64;
                        if (a < 0.0) != (b < 0.0) {
                            let f = a / (a - b) * H;
                            let p = middle.world(i, j, 0)
                                + Vector3::new(f * di as f64, f * dj as f64, 0.0);
                            sum += (p.xy() - c.xy()).norm();
                            count += 1;
                        }
                    }
                }
            }
        }
        let exact = ((r0 * H).powi(2) - 2.0 * report.time).sqrt();
        worst = worst.max((sum / count as f64 - exact).abs() / H);
    }
    worst
}

#[test]
fn mcf_cylinder_follows_r_squared_is_r0_squared_minus_2t() {
    // A cylinder is not umbilic: the second-order scheme's umbilic-defect term matters here.
    for dt_vox in [2.0, 8.0] {
        let second = cylinder_run(16.0, dt_vox, true);
        let first = cylinder_run(16.0, dt_vox, false);
        println!(
            "mcf cylinder R = 16h, Δt = {dt_vox}h²: largest radius error {second:.4}h until r = R/2 \
             (first-order thresholding: {first:.4}h)"
        );
        assert!(second <= 0.15, "Δt = {dt_vox}h²: radius error {second}h");
        assert!(
            second < first / 2.0,
            "the second-order scheme gains little: {second} vs {first}"
        );
    }
}

#[test]
fn expand_moves_a_sphere_at_speed_c_and_back() {
    let r0 = 16.0;
    let c = 0.1 / H;
    // A growth of 10h, in steps of 2h².
    let t_end = 10.0 * H / c;
    for c in [c, -c] {
        let (err, spread) = sphere_run(
            Velocity::Expand { c },
            r0,
            14.0,
            t_end,
            2.0 * H * H,
            &FlowOptions::default(),
            |t| r0 * H + c * t,
        );
        println!("expand c = {:+.2}/h from R = 16h by 10h: largest radius error {err:.4}h, spread {spread:.3}h", c * H);
        assert!(err <= 0.25, "c = {c}: radius error {err}h");
    }
}

#[test]
fn inpaint_grows_a_sphere_at_rate_c() {
    let r0 = 16.0;
    let c = 0.1 / H;
    let t_end = 10.0 * H / c;
    for dt_vox in [2.0f64, 8.0] {
        let pad = 10.0 + 4.0 * (2.0 * dt_vox).sqrt() + 4.0;
        let (err, spread) = sphere_run(
            Velocity::Inpaint { c },
            r0,
            pad,
            t_end,
            dt_vox * H * H,
            &FlowOptions::default(),
            |t| r0 * H + c * t,
        );
        println!("inpaint c = 0.1/h, Δt = {dt_vox}h², from R = 16h by 10h: largest radius error {err:.4}h, spread {spread:.3}h");
        assert!(err <= 0.25, "Δt = {dt_vox}h²: radius error {err}h");
    }
}

#[test]
fn vpmcf_keeps_a_sphere_in_place() {
    let r0 = 20.0;
    let (mut g, c) = sphere(r0, 16.0);
    let reports = evolve(
        &mut g,
        Velocity::VolumePreserving,
        (r0 * H).powi(2),
        8.0 * H * H,
        &FlowOptions::default(),
        |_| {},
    )
    .unwrap();
    let (mean, lo, hi) = crossing_radii(&g, &c);
    let worst = ((lo - r0 * H).abs()).max((hi - r0 * H).abs()) / H;
    println!(
        "vpmcf sphere R = 20h, t = R² in {} steps of 8h²: mean radius {:+.4}h off, every crossing within {worst:.4}h",
        reports.len(),
        (mean - r0 * H) / H
    );
    assert!(worst <= 0.1, "a crossing moved {worst}h");
}

#[test]
fn vpmcf_rounds_an_ellipsoid_keeping_its_volume() {
    let axes = [30.0, 20.0, 15.0];
    let r_eq: f64 = axes.iter().product::<f64>().cbrt();
    // Room for the shortest axis to grow to r_eq and for the diffusion (σ = 4h at Δt = 8h²).
    let pad = r_eq - axes[2] + 16.0 + 4.0;
    let dims = axes.map(|a| (2.0 * (a + pad)).ceil() as usize + 1);
    let centre = GridTransform::new(Point3::new(-3.0, 1.5, 0.25), H)
        .index_to_world(Vector3::from_fn(|a, _| 0.5 * (dims[a] - 1) as f64 + 0.3));
    let mut g = grid_of(dims, |p| {
        let q = Vector3::from_fn(|a, _| (p[a] - centre[a]) / (axes[a] * H));
        (q.norm() - 1.0) * axes[2] * H
    });
    redistance(&mut g, &RedistanceOptions::default()).unwrap();
    let v_exact = 4.0 / 3.0 * PI * axes.iter().product::<f64>() * H.powi(3);
    let v_mesh0 = mesh_volume(&g);
    let v_grid0 = measure_volume(&g);
    println!(
        "ellipsoid 30h×20h×15h: volume {:.2} exact, {:.2} marching cubes, {:.2} sub-voxel",
        v_exact, v_mesh0, v_grid0
    );
    let t_end = 1.5 * (r_eq * H).powi(2);
    let dt = 8.0 * H * H;
    let n = vesselmsr::motion::step_count(t_end, dt).unwrap();
    let mut flow = Flow::new(
        Velocity::VolumePreserving,
        t_end / n as f64,
        FlowOptions::default(),
    )
    .unwrap();
    let (mut worst_grid, mut worst_mesh) = (0.0f64, 0.0f64);
    for s in 1..=n {
        let report = flow.step(&mut g).unwrap();
        worst_grid = worst_grid.max((report.volume / v_grid0 - 1.0).abs());
        if s % 10 == 0 || s == n {
            let v = mesh_volume(&g);
            worst_mesh = worst_mesh.max((v / v_mesh0 - 1.0).abs());
            let a = semi_axes(&g);
            println!(
                "  t = {:.2} r_eq²: semi-axes {:.2}h {:.2}h {:.2}h, mesh volume {:+.4}%",
                report.time / (r_eq * H).powi(2),
                a[0] / H,
                a[1] / H,
                a[2] / H,
                100.0 * (v / v_mesh0 - 1.0)
            );
        }
    }
    let a = semi_axes(&g);
    let ratio = a[2] / a[0];
    println!(
        "vpmcf ellipsoid → sphere at t = 1.5 r_eq² ({n} steps of {:.1}h²): axis ratio {ratio:.4}, \
         volume drift {:.4}% (sub-voxel), {:.4}% (marching cubes); r_eq {r_eq:.2}h, mean semi-axis {:.2}h",
        t_end / n as f64 / (H * H),
        100.0 * worst_grid,
        100.0 * worst_mesh,
        (a[0] + a[1] + a[2]) / 3.0 / H
    );
    assert!(ratio <= 1.02, "axis ratio {ratio}");
    assert!(worst_grid <= 0.005, "sub-voxel volume drifted {worst_grid}");
    assert!(worst_mesh <= 0.005, "mesh volume drifted {worst_mesh}");
}

#[test]
fn grid_refinement_shrinks_the_errors() {
    // The same sphere (radius R world units) on grids of R/6, R/12 and R/24: errors relative to R.
    let mut table = Vec::new();
    for (name, velocity, second_order) in [
        ("mcf", Velocity::MeanCurvature, true),
        ("mcf first order", Velocity::MeanCurvature, false),
        ("inpaint c = 0.5/R", Velocity::Inpaint { c: 0.0 }, true),
    ] {
        let mut errors = Vec::new();
        for r0 in [6.0, 12.0, 24.0] {
            let opts = FlowOptions {
                second_order,
                ..FlowOptions::default()
            };
            let r = r0 * H;
            let (err, _) = match name {
                n if n.starts_with("mcf") => sphere_run(
                    velocity,
                    r0,
                    4.0 * 2.0 + 4.0,
                    3.0 * r * r / 16.0,
                    2.0 * H * H,
                    &opts,
                    |t| (r * r - 4.0 * t).sqrt(),
                ),
                _ => {
                    // Growth R/4 at c = 0.5/R, i.e. t = R²/2.
                    let c = 0.5 / r;
                    sphere_run(
                        Velocity::Inpaint { c },
                        r0,
                        r0 / 4.0 + 4.0 * 2.0 + 4.0,
                        r * r / 2.0,
                        2.0 * H * H,
                        &opts,
                        |t| r + c * t,
                    )
                }
            };
            errors.push(err / r0);
        }
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!(
            "refinement {name}, Δt = 2h²: error/R at h = R/6, R/12, R/24: {:.2e} {:.2e} {:.2e}; orders {:.2} {:.2}",
            errors[0], errors[1], errors[2], orders[0], orders[1]
        );
        table.push((name, errors));
    }
    for (name, errors) in &table {
        assert!(
            errors[1] < errors[0] && errors[2] < errors[1],
            "{name}: errors {errors:?} do not shrink as h halves"
        );
    }
}

#[test]
fn volume_area_and_shift_estimates_on_spheres() {
    let mut rng = common::rng(4);
    let r0 = 10.0;
    let mut rel_volumes = Vec::new();
    for _ in 0..6 {
        use rand::RngExt;
        let off = Vector3::from_fn(|_, _| rng.random::<f64>());
        let n = 2 * 14 + 1;
        let t = GridTransform::new(Point3::new(-3.0, 1.5, 0.25), H);
        let c = t.index_to_world(Vector3::from_element(14.0) + off);
        let g = grid_of([n; 3], |p| (p - c).norm() - r0 * H);
        let exact_v = 4.0 / 3.0 * PI * (r0 * H).powi(3);
        let exact_a = 4.0 * PI * (r0 * H).powi(2);
        let rv = measure_volume(&g) / exact_v - 1.0;
        let ra = measure_area(&g) / exact_a - 1.0;
        let rm = mesh_volume(&g) / exact_v - 1.0;
        println!(
            "sphere R = 10h at offset {:.2?}: volume {rv:+.2e}, area {ra:+.2e}, marching-cubes volume {rm:+.2e} relative",
            off.as_slice()
        );
        // The smoothed Heaviside's bias: (1/6 − 1/π²)h²·∫κ dA = 6(1/6 − 1/π²)h²/R² relative.
        let bias = 6.0 * (1.0 / 6.0 - 1.0 / (PI * PI)) / (r0 * r0);
        assert!(
            (rv - bias).abs() < 3e-4,
            "volume {rv}, expected bias {bias}"
        );
        assert!(
            (rv - rm).abs() < 1.5e-2,
            "volume {rv} vs marching cubes {rm}"
        );
        assert!(ra.abs() < 0.01, "area {ra}");
        rel_volumes.push(rv);
        // The shift giving the volume of the sphere of radius R + 1.5h is 1.5h.
        let target = measure_volume(&grid_of([n; 3], |p| (p - c).norm() - (r0 + 1.5) * H));
        let lambda = find_volume_shift(&g, &g.whole_box(), target, 1e-12).unwrap();
        assert!((lambda / H - 1.5).abs() < 1e-4, "shift {}h", lambda / H);
    }
    let spread = rel_volumes.iter().cloned().fold(f64::MIN, f64::max)
        - rel_volumes.iter().cloned().fold(f64::MAX, f64::min);
    println!("volume estimate spread over offsets: {spread:.2e}");
    assert!(
        spread < 5e-4,
        "the volume estimate depends on the offset by {spread}"
    );
    // Unreachable targets.
    let (g, _) = sphere(5.0, 3.0);
    let b = g.whole_box();
    assert!(find_volume_shift(&g, &b, 0.0, 1e-9).is_err());
    assert!(find_volume_shift(&g, &b, 1e9, 1e-9).is_err());
    assert!(find_volume_shift(&g, &b, f64::NAN, 1e-9).is_err());
}

#[test]
fn a_flow_restricted_to_a_sub_box_changes_only_its_nodes() {
    // Two spheres of 8h; the region holds the first one with room for the work margin.
    let (r0, n) = (8.0, [64usize, 26, 26]);
    let t = GridTransform::new(Point3::new(-3.0, 1.5, 0.25), H);
    let ca = t.index_to_world(Vector3::new(12.3, 12.6, 12.2));
    let cb = t.index_to_world(Vector3::new(50.4, 12.1, 12.7));
    let mut g = grid_of(n, |p| ((p - ca).norm()).min((p - cb).norm()) - r0 * H);
    let before = g.clone();
    let region = SubBox::new([1, 1, 1], [30, 25, 25]);
    let opts = FlowOptions {
        region: Some(region),
        ..FlowOptions::default()
    };
    let t_end = 0.1 * (r0 * H).powi(2);
    evolve(
        &mut g,
        Velocity::MeanCurvature,
        t_end,
        2.0 * H * H,
        &opts,
        |_| {},
    )
    .unwrap();
    let mut changed_outside = 0;
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                if !region.contains([i, j, k]) && g.get(i, j, k) != before.get(i, j, k) {
                    changed_outside += 1;
                }
            }
        }
    }
    assert_eq!(changed_outside, 0, "nodes outside the region changed");
    // Sphere A shrank as r² = R² − 4t, sphere B did not move.
    let left = g.extract(&SubBox::new([0, 0, 0], [32, 26, 26])).unwrap();
    let right = g.extract(&SubBox::new([32, 0, 0], [64, 26, 26])).unwrap();
    let (ra, _, _) = crossing_radii(&left, &ca);
    let (rb, _, _) = crossing_radii(&right, &cb);
    let right_before = before
        .extract(&SubBox::new([32, 0, 0], [64, 26, 26]))
        .unwrap();
    let (rb0, _, _) = crossing_radii(&right_before, &cb);
    let exact = ((r0 * H).powi(2) - 4.0 * t_end).sqrt();
    println!(
        "region flow: sphere A radius {:+.4}h off r² = R² − 4t, sphere B moved {:+.4}h",
        (ra - exact) / H,
        (rb - rb0) / H
    );
    assert!((ra - exact).abs() < 0.3 * H);
    assert_eq!(rb, rb0, "sphere B, outside the region, moved");
}

/// A shape growing into the grid's border is an error (the grid needs more padding), unless
/// `allow_border` says the grid is a sub-box of a larger scene (the inpainting's coarse level).
#[test]
fn a_shape_reaching_the_border_is_an_error_unless_allowed() {
    // A sphere of 6 voxels with 3 voxels of room, expanding by 6 voxels.
    let (g, _) = sphere(6.0, 3.0);
    let c = 1.0;
    let run = |opts: &FlowOptions| {
        let mut phi = g.clone();
        evolve(
            &mut phi,
            Velocity::Expand { c },
            6.0 * H / c,
            H / c,
            opts,
            |_| {},
        )
    };
    let err = run(&FlowOptions::default()).unwrap_err().to_string();
    assert!(err.contains("reached the border"), "{err}");
    let steps = run(&FlowOptions {
        allow_border: true,
        ..FlowOptions::default()
    })
    .unwrap();
    assert_eq!(steps.len(), 6);
}

#[test]
fn a_shape_vanishing_before_the_final_time_is_an_error_naming_the_time() {
    let r0 = 6.0;
    let (mut g, _) = sphere(r0, 6.0);
    let dt = 0.5 * H * H;
    let err = evolve(
        &mut g,
        Velocity::MeanCurvature,
        20.0 * H * H,
        dt,
        &FlowOptions::default(),
        |_| {},
    )
    .unwrap_err()
    .to_string();
    println!("{err}");
    assert!(err.contains("vanished"), "{err}");
    let at = err.split("vanished at t = ").nth(1).unwrap();
    let t: f64 = at.split_whitespace().next().unwrap().parse().unwrap();
    // A sphere vanishes at R²/4 under mean curvature flow.
    let expected = (r0 * H).powi(2) / 4.0;
    assert!(
        (t - expected).abs() <= 2.0 * dt,
        "vanished at {t}, expected {expected}"
    );
}

#[test]
fn bad_input_is_refused() {
    let (g, _) = sphere(5.0, 4.0);
    let opts = FlowOptions::default();
    for dt in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(
            Flow::new(Velocity::MeanCurvature, dt, opts.clone()).is_err(),
            "dt {dt}"
        );
        let mut phi = g.clone();
        assert!(evolve(&mut phi, Velocity::MeanCurvature, 1.0, dt, &opts, |_| {}).is_err());
        let mut phi = g.clone();
        assert!(evolve(&mut phi, Velocity::MeanCurvature, dt, 0.1, &opts, |_| {}).is_err());
    }
    // Steps below 0.25h², and a final time shorter than one.
    let mut phi = g.clone();
    let err = evolve(
        &mut phi,
        Velocity::MeanCurvature,
        1.0,
        0.2 * H * H,
        &opts,
        |_| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("smallest step"), "{err}");
    let mut phi = g.clone();
    let err = evolve(
        &mut phi,
        Velocity::VolumePreserving,
        0.2 * H * H,
        1.0,
        &opts,
        |_| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("shorter than one"), "{err}");
    let mut phi = g.clone();
    assert!(
        Flow::new(Velocity::MeanCurvature, 0.2 * H * H, opts.clone())
            .unwrap()
            .step(&mut phi)
            .is_err()
    );
    assert!(Flow::new(Velocity::Inpaint { c: -0.5 }, 0.1, opts.clone()).is_err());
    assert!(Flow::new(Velocity::Expand { c: f64::NAN }, 0.1, opts.clone()).is_err());
    assert!(Velocity::from_name("inpaint", Some(-1.0)).is_err());
    assert!(Velocity::from_name("mcf", Some(1.0)).is_err());
    assert!(Velocity::from_name("curvature", None).is_err());
    assert_eq!(
        Velocity::from_name("expand", Some(2.0)).unwrap(),
        Velocity::Expand { c: 2.0 }
    );
    let bad_band = FlowOptions {
        band_voxels: Some(0.5),
        ..FlowOptions::default()
    };
    assert!(Flow::new(Velocity::MeanCurvature, 0.1, bad_band).is_err());
    // NaN in φ, no inside, a region outside the grid.
    let mut phi = g.clone();
    phi.data_mut()[100] = f32::NAN;
    assert!(evolve(&mut phi, Velocity::MeanCurvature, 0.1, 0.1, &opts, |_| {}).is_err());
    let mut phi = g.clone();
    phi.data_mut().iter_mut().for_each(|v| *v = v.abs() + 0.1);
    let err = evolve(
        &mut phi,
        Velocity::VolumePreserving,
        0.1,
        0.1,
        &opts,
        |_| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("nothing to evolve"), "{err}");
    let outside = FlowOptions {
        region: Some(SubBox::new([0, 0, 0], [1000, 2, 2])),
        ..FlowOptions::default()
    };
    let mut phi = g.clone();
    assert!(Flow::new(Velocity::MeanCurvature, 0.1, outside)
        .unwrap()
        .step(&mut phi)
        .is_err());
}

/// `mesh` voxelized with voxel `h` and evolved by `velocity` to `t_end` in steps of `dt`, as a
/// marching-cubes mesh; with room for the diffusion around the mesh.
fn evolve_mesh(mesh: &TriMesh, h: f64, velocity: Velocity, t_end: f64, dt: f64) -> TriMesh {
    let pad = (4.0 * (2.0 * dt).sqrt() / h + 2.0 * t_end.sqrt() / h + 4.0).ceil() as usize;
    let spec = grid_for_mesh(
        mesh,
        &GridOptions {
            voxel: Some(h),
            padding_voxels: pad,
            ..GridOptions::default()
        },
    )
    .unwrap();
    let mut phi = voxelize(mesh, spec.dims, spec.transform, &VoxelizeOptions::default()).unwrap();
    if t_end > 0.0 {
        evolve(
            &mut phi,
            velocity,
            t_end,
            dt,
            &FlowOptions::default(),
            |_| {},
        )
        .unwrap();
    }
    extract_surface(&phi, &ExtractOptions::default()).unwrap()
}

/// Each (file, voxel as a fraction of the bounding-box diagonal, velocity, final time in h²)
/// evolved as read and rotated and translated: the two results agree within 0.5h (Hausdorff).
fn evolution_is_invariant_under_rotation_and_translation(cases: &[(&str, f64, Velocity, f64)]) {
    let Some(dir) = common::real_dir() else {
        return;
    };
    let rotation = Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0)),
        0.7,
    );
    for &(file, fraction, velocity, t_mult) in cases {
        let mesh = common::read_real(&dir, file);
        let h = common::bbox_diagonal(&mesh) * fraction;
        let shift = Vector3::new(0.37, -0.21, 0.55) * h
            + Vector3::new(3.0, -1.0, 2.0) * common::bbox_diagonal(&mesh);
        let moved = TriMesh::new(
            mesh.vertices.iter().map(|p| rotation * p + shift).collect(),
            mesh.faces.clone(),
        );
        let (t_end, dt) = (t_mult * h * h, 2.0 * h * h);
        let opts = SurfaceDistanceOptions { samples: 50_000 };
        let compare = |a: &TriMesh, b: &TriMesh| {
            let back = TriMesh::new(
                a.vertices.iter().map(|p| rotation * p + shift).collect(),
                a.faces.clone(),
            );
            surface_distance(&back, b, &opts)
        };
        let a0 = evolve_mesh(&mesh, h, velocity, 0.0, dt);
        let d0 = compare(&a0, &evolve_mesh(&moved, h, velocity, 0.0, dt));
        let a = evolve_mesh(&mesh, h, velocity, t_end, dt);
        let b = evolve_mesh(&moved, h, velocity, t_end, dt);
        let d = compare(&a, &b);
        let motion = surface_distance(&a, &a0, &opts);
        println!(
            "{file} ({velocity}, h = {h:.4}, t = {t_mult}h²): rotated+translated vs original Hausdorff {:.3}h \
             (mean {:.3}h); without evolving {:.3}h (mean {:.3}h); the evolution moved the surface by up to {:.2}h",
            d.hausdorff / h,
            d.mean_distance / h,
            d0.hausdorff / h,
            d0.mean_distance / h,
            motion.hausdorff / h
        );
        assert!(
            d.hausdorff <= 0.5 * h,
            "{file}: Hausdorff {}h",
            d.hausdorff / h
        );
    }
}

// The cases of the invariance test: (file, voxel as a fraction of the bounding-box diagonal,
// velocity, final time in h²). The times are long enough to smooth the creases that the grid
// resolves differently at each orientation (the voxelizations alone differ by up to 0.9h
// there), and short enough that no part of the shape is pinching off (where the outcome depends
// on sub-voxel details).

#[test]
fn evolution_is_invariant_under_rotation_and_translation_on_the_aorta() {
    evolution_is_invariant_under_rotation_and_translation(&[(
        "aorta_abdominal_open_ends.stl",
        1.0 / 200.0,
        Velocity::VolumePreserving,
        8.0,
    )]);
}

mod slow {
    use super::*;

    /// The cortex (16 steps on a finer grid: most of the time) and the aorta under `mcf`.
    #[test]
    #[ignore = "slow: run by tests/run_slow.sh"]
    fn evolution_is_invariant_under_rotation_and_translation_on_real_meshes() {
        evolution_is_invariant_under_rotation_and_translation(&[
            (
                "cortex_rh_pial_fsaverage5.stl",
                1.0 / 150.0,
                Velocity::MeanCurvature,
                32.0,
            ),
            (
                "aorta_abdominal_open_ends.stl",
                1.0 / 200.0,
                Velocity::MeanCurvature,
                8.0,
            ),
        ]);
    }
}
