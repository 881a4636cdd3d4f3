//! The analytic shapes: counts, topology, orientation and measures against closed forms.

use nalgebra::Point3;
use std::f64::consts::PI;
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::primitives::{box_mesh, icosphere, open_tube, torus};
use vesselmsr::mesh::topology::{boundary_loops, Orientation};

#[test]
fn icosphere_counts_and_convergence() {
    let c = Point3::new(100.0, -50.0, 20.0);
    let mut last_err = f64::INFINITY;
    for k in 0..5 {
        let m = icosphere(k, 2.0, c);
        assert_eq!(m.num_vertices(), 10 * 4usize.pow(k as u32) + 2);
        assert_eq!(m.num_faces(), 20 * 4usize.pow(k as u32));
        assert!(m
            .vertices
            .iter()
            .all(|v| ((v - c).norm() - 2.0).abs() < 1e-12));
        let info = mesh_info(&m);
        assert!(
            info.watertight && info.orientation == Orientation::Outward && info.genus == Some(0)
        );
        let err = (4.0 / 3.0 * PI * 8.0 - info.volume.unwrap()) / (4.0 / 3.0 * PI * 8.0);
        assert!(
            err > 0.0 && err < last_err / 3.0,
            "level {k}: volume error {err}"
        );
        last_err = err;
    }
}

#[test]
fn box_torus_and_tube() {
    let b = mesh_info(&box_mesh(
        Point3::new(1.0, 2.0, 3.0),
        Point3::new(3.0, 5.0, 8.0),
    ));
    assert!(b.watertight && b.orientation == Orientation::Outward);
    assert!((b.volume.unwrap() - 30.0).abs() < 1e-12 && (b.area - 62.0).abs() < 1e-12);

    let t = torus(3.0, 1.0, 96, 48, Point3::origin());
    let info = mesh_info(&t);
    assert!(info.watertight && info.orientation == Orientation::Outward);
    assert_eq!(info.genus, Some(1));
    let exact = 2.0 * PI * PI * 3.0; // 2π²Rr²
    let err = (exact - info.volume.unwrap()) / exact; // inscribed polygons: slightly below
    assert!(err > 0.0 && err < 5e-3, "torus volume error {err}");

    let tube = open_tube(1.5, 10.0, 32, 11);
    assert_eq!(tube.num_vertices(), 32 * 11);
    let loops = boundary_loops(&tube);
    assert_eq!(loops.len(), 2);
    assert!(loops.iter().all(|l| l.len() == 32));
    let info = mesh_info(&tube);
    assert_eq!(info.orientation, Orientation::Open);
    let mut closed = tube.clone();
    // Outward: the signed volume about the axis is positive for the tube's side wall.
    closed.append(&box_mesh(
        Point3::new(10.0, 10.0, 10.0),
        Point3::new(11.0, 11.0, 11.0),
    ));
    assert_eq!(mesh_info(&closed).components, 2);
    let side: f64 = (0..tube.num_faces())
        .map(|f| {
            let [a, b, c] = tube.triangle(f);
            let mid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            tube.face_normal_raw(f)
                .dot(&nalgebra::Vector3::new(mid.x, mid.y, 0.0))
        })
        .sum();
    assert!(side > 0.0, "tube faces point inward");
}

#[test]
fn a_cavity_faces_into_its_hole() {
    use vesselmsr::mesh::orient::orient_outward;
    let c = Point3::new(1.0, 2.0, 3.0);
    let mut hollow = icosphere(3, 2.0, c);
    let mut cavity = icosphere(3, 1.0, c + nalgebra::Vector3::new(0.3, 0.0, 0.0));
    cavity.flip_faces();
    hollow.append(&cavity);
    let info = mesh_info(&hollow);
    assert_eq!(info.components, 2);
    assert_eq!(
        info.orientation,
        Orientation::Outward,
        "a correctly wound hollow ball"
    );
    let shell = 4.0 / 3.0 * PI * (8.0 - 1.0);
    assert!(
        (info.volume.unwrap() - shell).abs() / shell < 0.02,
        "volume {:?}",
        info.volume
    );
    assert_eq!(orient_outward(&mut hollow.clone()), 0);

    // The cavity's shell turned the wrong way: inconsistent, and orient_outward flips only it.
    let mut wrong = hollow.clone();
    let n = wrong.num_faces();
    for f in &mut wrong.faces[n / 2..] {
        f.swap(1, 2);
    }
    assert_eq!(mesh_info(&wrong).orientation, Orientation::Inconsistent);
    assert_eq!(orient_outward(&mut wrong), 1);
    assert_eq!(wrong, hollow);

    // Everything inward.
    let mut inward = hollow.clone();
    inward.flip_faces();
    assert_eq!(mesh_info(&inward).orientation, Orientation::Inward);
    assert_eq!(orient_outward(&mut inward), 2);
    assert_eq!(inward, hollow);
}
