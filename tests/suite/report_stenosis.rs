//! Stenosis and inpainted-volume measures (src/report/stenosis.rs) against analytic values:
//! volume of a solid inside a ball (ball inside a box, half-space, spherical cap, whole box,
//! ball across a tube), cross-sections of a polygonal tube (straight and oblique planes), the
//! local axis of a straight and a tilted tube, and the stenosis of a synthetic 50 % narrowing and
//! of an occlusion against the straight tube. On the real coronary of ../shared/data/real the
//! figures for balls of 1.5, 2 and 3 mm about the lesion are printed (`--nocapture`).

use crate::common;
use common::*;
use nalgebra::{Point3, Rotation3, Unit, Vector3};
use std::f64::consts::{PI, TAU};
use vesselmsr::bvh::MeshBvh;
use vesselmsr::inpaint::region::Ball;
use vesselmsr::mesh::cap::{cap_holes, CapOptions};
use vesselmsr::mesh::measures::signed_volume;
use vesselmsr::mesh::primitives::box_mesh;
use vesselmsr::report::stenosis::{
    cross_section, local_axis, measure_stenosis, volume_in_ball, StenosisOptions,
};
use vesselmsr::TriMesh;

/// A closed polygonal tube along z from `z0` to `z1`: `rings` rings of `segments` vertices at
/// radius `radius(z)`, closed by a fan about a centre vertex at each end, outward-facing.
fn closed_tube(
    radius: impl Fn(f64) -> f64,
    z0: f64,
    z1: f64,
    segments: usize,
    rings: usize,
) -> TriMesh {
    let mut vertices = Vec::new();
    for j in 0..rings {
        let z = z0 + (z1 - z0) * j as f64 / (rings - 1) as f64;
        let r = radius(z);
        for i in 0..segments {
            let th = TAU * i as f64 / segments as f64;
            vertices.push(Point3::new(r * th.cos(), r * th.sin(), z));
        }
    }
    let id = |i: usize, j: usize| (j * segments + i % segments) as u32;
    let mut faces = Vec::new();
    for j in 0..rings - 1 {
        for i in 0..segments {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    let bottom = vertices.len() as u32;
    vertices.push(Point3::new(0.0, 0.0, z0));
    let top = vertices.len() as u32;
    vertices.push(Point3::new(0.0, 0.0, z1));
    for i in 0..segments {
        faces.push([bottom, id(i + 1, 0), id(i, 0)]);
        faces.push([top, id(i, rings - 1), id(i + 1, rings - 1)]);
    }
    TriMesh::new(vertices, faces)
}

/// Area of the regular n-gon inscribed in the circle of radius `r`.
fn polygon_area(r: f64, n: usize) -> f64 {
    0.5 * n as f64 * r * r * (TAU / n as f64).sin()
}

/// Volume of the infinite cylinder of radius `rc` about the z axis inside the ball of radius `r`
/// centred on the axis: ∫ π min(rc², r² − z²) dz over [−r, r].
fn cylinder_in_ball(rc: f64, r: f64) -> f64 {
    if rc >= r {
        return 4.0 / 3.0 * PI * r.powi(3);
    }
    let z1 = (r * r - rc * rc).sqrt();
    2.0 * PI * (rc * rc * z1 + r * r * (r - z1) - (r.powi(3) - z1.powi(3)) / 3.0)
}

fn ball(c: [f64; 3], r: f64) -> Ball {
    Ball {
        center: Point3::from(c),
        radius: r,
    }
}

fn check(what: &str, ours: f64, truth: f64, tol: f64) {
    let e = rel(ours, truth);
    println!("{what}: {ours:.6} vs {truth:.6} (rel {e:.1e})");
    assert!(e <= tol, "{what}: {ours} vs {truth}");
}

#[test]
fn volume_in_ball_analytic_cases() {
    let cube = box_mesh(Point3::from([-10.0; 3]), Point3::from([10.0; 3]));
    let r: f64 = 4.0;
    let sphere = 4.0 / 3.0 * PI * r.powi(3);
    check(
        "ball inside a box",
        volume_in_ball(&cube, &ball([0.3, -0.2, 0.1], r)),
        sphere,
        1e-9,
    );
    check(
        "ball outside a box",
        volume_in_ball(&cube, &ball([20.0, 0.0, 0.0], r)) + 1.0,
        1.0,
        1e-12,
    );

    // Half-space: the box's top face through the ball's centre.
    let slab = box_mesh(
        Point3::new(-10.0, -10.0, -10.0),
        Point3::new(10.0, 10.0, 0.0),
    );
    check(
        "ball across a face (half)",
        volume_in_ball(&slab, &ball([1.0, 2.0, 0.0], 3.0)),
        2.0 / 3.0 * PI * 27.0,
        1e-5,
    );
    // The face 1.2 above the centre of a ball of radius 3: the ball less a cap of height 1.8.
    let (rb, h): (f64, f64) = (3.0, 1.8);
    let cap = PI * h * h * (3.0 * rb - h) / 3.0;
    check(
        "ball less a cap",
        volume_in_ball(&slab, &ball([1.0, 2.0, -1.2], rb)),
        4.0 / 3.0 * PI * rb.powi(3) - cap,
        1e-5,
    );
    // An edge of the box through the centre: a quarter; a corner: an eighth.
    check(
        "ball on an edge (quarter)",
        volume_in_ball(&slab, &ball([10.0, 3.0, 0.0], 2.0)),
        PI * 8.0 / 3.0,
        1e-5,
    );
    check(
        "ball on a corner (eighth)",
        volume_in_ball(&slab, &ball([10.0, 10.0, 0.0], 2.0)),
        PI * 8.0 / 6.0,
        1e-5,
    );
    // A whole box inside the ball; and inward-facing it is the same.
    let small = box_mesh(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 2.0, 0.5));
    check(
        "box inside a ball",
        volume_in_ball(&small, &ball([0.5, 1.0, 0.25], 5.0)),
        1.0,
        1e-12,
    );
    let mut inward = slab.clone();
    inward.flip_faces();
    check(
        "inward-facing ball less a cap",
        volume_in_ball(&inward, &ball([1.0, 2.0, -1.2], rb)),
        4.0 / 3.0 * PI * rb.powi(3) - cap,
        1e-5,
    );
    // Bad balls give 0, no panic.
    assert_eq!(volume_in_ball(&cube, &ball([0.0; 3], -1.0)), 0.0);
    assert_eq!(volume_in_ball(&cube, &ball([f64::NAN, 0.0, 0.0], 1.0)), 0.0);
}

#[test]
fn volume_in_ball_across_a_tube() {
    let (rc, n) = (1.0, 256);
    let tube = closed_tube(|_| rc, -10.0, 10.0, n, 41);
    assert!(signed_volume(&tube) > 0.0);
    // The polygon's area deficit, as an equivalent radius.
    let re = (polygon_area(rc, n) / PI).sqrt();
    for r in [0.8, 1.5, 2.0, 3.0] {
        check(
            &format!("tube R = 1 in a ball of radius {r}"),
            volume_in_ball(&tube, &ball([0.0, 0.0, 0.37], r)),
            cylinder_in_ball(re, r),
            1e-4,
        );
    }
}

/// Whether `p` is inside the closed polygonal tube of [`closed_tube`] with constant radius `rc`,
/// `n` segments, from z = `z0` to `z1` (the regular n-gon prism).
fn inside_prism(p: &Point3<f64>, rc: f64, n: usize, z0: f64, z1: f64) -> bool {
    if p.z < z0 || p.z > z1 {
        return false;
    }
    let step = TAU / n as f64;
    // Outward normal of the edge whose sector holds p.
    let k = (p.y.atan2(p.x).rem_euclid(TAU) / step).floor();
    let phi = (k + 0.5) * step;
    p.x * phi.cos() + p.y * phi.sin() <= rc * (0.5 * step).cos()
}

#[test]
fn volume_in_ball_off_axis_against_a_lattice_count() {
    let (rc, n) = (1.0, 48);
    let tube = closed_tube(|_| rc, -5.0, 5.0, n, 21);
    let (c, r) = (Point3::new(0.4, -0.3, 0.2), 1.3);
    // Brute force: midpoints of a 240³ lattice over the ball's bounding cube.
    let m = 240;
    let h = 2.0 * r / m as f64;
    let mut count = 0usize;
    for i in 0..m {
        for j in 0..m {
            for k in 0..m {
                let q = c + Vector3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * h
                    - Vector3::from([r; 3]);
                if (q - c).norm_squared() <= r * r && inside_prism(&q, rc, n, -5.0, 5.0) {
                    count += 1;
                }
            }
        }
    }
    let brute = count as f64 * h * h * h;
    let ours = volume_in_ball(&tube, &ball([c.x, c.y, c.z], r));
    check("off-axis ball vs lattice count", ours, brute, 1e-3);
    // The same, turned and moved far from the origin.
    let rot = Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::new(-0.3, 1.0, 0.7)), 1.1);
    let shift = Vector3::new(-120.0, 35.0, 410.0);
    let mut moved = tube.clone();
    for v in &mut moved.vertices {
        *v = rot * *v + shift;
    }
    let cm = rot * c + shift;
    check(
        "turned and moved",
        volume_in_ball(&moved, &ball([cm.x, cm.y, cm.z], r)),
        ours,
        1e-5,
    );
}

#[test]
fn cross_section_of_a_tube() {
    let (rc, n) = (1.0, 64);
    let tube = closed_tube(|_| rc, -10.0, 10.0, n, 21);
    let exact = polygon_area(rc, n);
    let z = Vector3::z();
    let s = cross_section(&tube, &Point3::new(0.1, -0.2, 0.37), &z).unwrap();
    check("section area", s.area, exact, 1e-9);
    check("equivalent diameter", s.equivalent_diameter, 2.0 * rc, 1e-2);
    assert!(s.encloses_point && s.distance == 0.0);
    assert!((s.centroid - Point3::new(0.0, 0.0, 0.37)).norm() < 1e-9);
    check(
        "perimeter",
        s.perimeter,
        2.0 * n as f64 * (PI / n as f64).sin(),
        1e-9,
    );
    // Through a ring of vertices.
    let s = cross_section(&tube, &Point3::new(0.0, 0.0, 1.0), &z).unwrap();
    check("section through a ring", s.area, exact, 1e-9);
    // An oblique plane cuts the prism in the polygon stretched by 1/cos α.
    let alpha = 20f64.to_radians();
    let tilted = Vector3::new(alpha.sin(), 0.0, alpha.cos());
    let s = cross_section(&tube, &Point3::new(0.0, 0.0, 0.37), &tilted).unwrap();
    check("oblique section", s.area, exact / alpha.cos(), 1e-9);
    // A point outside the tube gets the nearest loop.
    let s = cross_section(&tube, &Point3::new(3.0, 0.0, 0.0), &z).unwrap();
    assert!(!s.encloses_point);
    assert!((s.distance - 2.0).abs() < 1e-9, "{}", s.distance);
    // Beyond the tube's ends, and with a zero axis: nothing.
    assert!(cross_section(&tube, &Point3::new(0.0, 0.0, 11.0), &z).is_none());
    assert!(cross_section(&tube, &Point3::origin(), &Vector3::zeros()).is_none());
}

fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.normalize()
        .dot(&b.normalize())
        .abs()
        .min(1.0)
        .acos()
        .to_degrees()
}

#[test]
fn local_axis_of_straight_and_tilted_tubes() {
    let tube = closed_tube(|_| 1.0, -10.0, 10.0, 48, 41);
    let bvh = MeshBvh::new(&tube);
    let axis = local_axis(&tube, &bvh, &Point3::new(0.2, 0.1, 0.3), 2.0).unwrap();
    let e = angle_deg(&axis, &Vector3::z());
    println!("straight tube: axis {axis:?}, {e:.4}° off");
    assert!(e < 2.0);

    let rot = Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, 1.0, 0.3)), 0.61);
    let shift = Vector3::new(12.0, -40.0, 7.5);
    let mut tilted = tube.clone();
    for v in &mut tilted.vertices {
        *v = rot * *v + shift;
    }
    let bvh = MeshBvh::new(&tilted);
    let p = rot * Point3::new(0.2, 0.1, 0.3) + shift;
    let truth = rot * Vector3::z();
    for radius in [1.5, 2.0, 4.0] {
        let axis = local_axis(&tilted, &bvh, &p, radius).unwrap();
        let e = angle_deg(&axis, &truth);
        println!("tilted tube, normals within {radius}: {e:.4}° off");
        assert!(e < 2.0);
    }
    // No surface within reach, and a sphere (no preferred direction): none.
    assert!(local_axis(&tilted, &bvh, &p, 0.5).is_none());
    let sphere = vesselmsr::mesh::primitives::icosphere(4, 1.0, Point3::origin());
    let sbvh = MeshBvh::new(&sphere);
    assert!(local_axis(&sphere, &sbvh, &Point3::origin(), 2.0).is_none());
}

#[test]
fn fifty_percent_narrowing_against_the_straight_tube() {
    let (rc, sigma) = (1.0, 1.0);
    let narrow = |z: f64| rc * (1.0 - 0.5 * (-z * z / (2.0 * sigma * sigma)).exp());
    let input = closed_tube(narrow, -10.0, 10.0, 64, 401);
    let output = closed_tube(|_| rc, -10.0, 10.0, 64, 401);
    let opts = StenosisOptions::default();
    for c in [[0.0, 0.0, 0.0], [0.3, -0.2, 0.1]] {
        let b = ball(c, 2.0);
        let rep = measure_stenosis(&input, &output, &b, &opts).unwrap();
        println!(
            "centre {c:?}: min input diameter {:.4} at {:+.3}, output {:.4}; diameter {:.2} %, area {:.2} %, NASCET {:.2} % (normal {:.4}); {} sections; volumes in ball {:.4} -> {:.4}",
            rep.min_input_diameter,
            rep.min_offset,
            rep.output_diameter_at_min,
            rep.diameter_stenosis_pct,
            rep.area_stenosis_pct,
            rep.nascet_stenosis_pct.unwrap(),
            rep.normal_diameter.unwrap(),
            rep.sections,
            rep.input_volume_in_ball,
            rep.output_volume_in_ball
        );
        assert_eq!(rep.sections, 21);
        assert!(angle_deg(&Vector3::from(rep.axis), &Vector3::z()) < 0.5);
        assert!((rep.diameter_stenosis_pct - 50.0).abs() <= 2.0);
        assert!((rep.area_stenosis_pct - 75.0).abs() <= 3.0);
        assert!((rep.nascet_stenosis_pct.unwrap() - 50.0).abs() <= 2.0);
        // The output's volume in the ball is the cylinder's; the narrowing holds less.
        let re = (polygon_area(rc, 64) / PI).sqrt();
        let truth = cylinder_in_ball(re, 2.0);
        if c == [0.0; 3] {
            check(
                "output volume in ball",
                rep.output_volume_in_ball,
                truth,
                1e-4,
            );
        }
        assert!(rep.input_volume_in_ball < 0.6 * rep.output_volume_in_ball);
    }
    // The straight tube against itself: no stenosis.
    let rep = measure_stenosis(&output, &output, &ball([0.0; 3], 2.0), &opts).unwrap();
    assert!(rep.diameter_stenosis_pct.abs() < 1e-9);
    assert!(rep.nascet_stenosis_pct.unwrap().abs() < 1e-9);
}

#[test]
fn occlusion_is_one_hundred_percent() {
    let mut input = closed_tube(|_| 1.0, -10.0, -0.5, 64, 39);
    input.append(&closed_tube(|_| 1.0, 0.5, 10.0, 64, 39));
    let output = closed_tube(|_| 1.0, -10.0, 10.0, 64, 81);
    let rep = measure_stenosis(
        &input,
        &output,
        &ball([0.0, 0.0, 0.0], 2.0),
        &StenosisOptions::default(),
    )
    .unwrap();
    println!(
        "occlusion: diameter {:.1} %, area {:.1} %, NASCET {:?} %, normal diameter {:?}, volumes {:.4} -> {:.4}",
        rep.diameter_stenosis_pct,
        rep.area_stenosis_pct,
        rep.nascet_stenosis_pct,
        rep.normal_diameter,
        rep.input_volume_in_ball,
        rep.output_volume_in_ball
    );
    assert_eq!(rep.min_input_diameter, 0.0);
    assert_eq!(rep.diameter_stenosis_pct, 100.0);
    assert_eq!(rep.area_stenosis_pct, 100.0);
    assert_eq!(rep.nascet_stenosis_pct, Some(100.0));
    // The gap of length 1 takes π·R²·1 (polygonal) out of the ball.
    let gap = polygon_area(1.0, 64) * 1.0;
    check(
        "volume missing in the gap",
        rep.output_volume_in_ball - rep.input_volume_in_ball,
        gap,
        1e-4,
    );
}

#[test]
fn stenosis_bad_input_is_an_error() {
    let tube = closed_tube(|_| 1.0, -10.0, 10.0, 32, 21);
    let opts = StenosisOptions::default();
    let empty = TriMesh::default();
    assert!(measure_stenosis(&empty, &tube, &ball([0.0; 3], 2.0), &opts).is_err());
    assert!(measure_stenosis(&tube, &tube, &ball([0.0; 3], 0.0), &opts).is_err());
    let zero = StenosisOptions {
        sections: 0,
        ..opts
    };
    assert!(measure_stenosis(&tube, &tube, &ball([0.0; 3], 2.0), &zero).is_err());
    // A ball far from the vessel: no axis there.
    assert!(measure_stenosis(&tube, &tube, &ball([50.0, 0.0, 0.0], 2.0), &opts).is_err());
}

#[test]
fn real_coronary_stenosis() {
    let Some(dir) = real_dir() else {
        return;
    };
    let open = read_real(&dir, "coronary_stenosis_xray.stl");
    let (mesh, _) = cap_holes(&open, &CapOptions::default()).unwrap();
    // The lesion position of SOURCES.md.
    let lesion = [26.0, -21.6, 68.2];
    for r in [1.5f64, 2.0, 3.0] {
        let rep =
            measure_stenosis(&mesh, &mesh, &ball(lesion, r), &StenosisOptions::default()).unwrap();
        let nascet = rep.nascet_stenosis_pct.unwrap();
        println!(
            "coronary, ball {r} mm: min diameter {:.3} mm at {:+.2} mm, normal diameter {:.3} mm, NASCET {:.1} %, {} sections, volume in ball {:.3} mm³, axis {:?}",
            rep.min_input_diameter,
            rep.min_offset,
            rep.normal_diameter.unwrap(),
            nascet,
            rep.sections,
            rep.input_volume_in_ball,
            rep.axis
        );
        let profile: Vec<String> = rep
            .profile
            .iter()
            .map(|s| format!("{:.2}", s.input_diameter))
            .collect();
        println!("  diameters across the ball: {}", profile.join(" "));
        assert!(rep.diameter_stenosis_pct.abs() < 1e-9);
        assert!(
            nascet.is_finite() && (5.0..95.0).contains(&nascet),
            "{nascet}"
        );
        assert!(rep.min_input_diameter > 0.0);
        assert!(rep.input_volume_in_ball > 0.0);
        assert!(rep.input_volume_in_ball < 4.0 / 3.0 * PI * r.powi(3));
    }
}
