//! Geometric measures against analytic values, and `mesh_info` against the figures of
//! ../shared/data/real/SOURCES.md.

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use std::f64::consts::PI;
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::measures::{
    area, area_centroid, bounding_box, degenerate_faces, euler_characteristic, genus,
    mean_edge_length, signed_volume, signed_volume_about, triangle_aspect_ratio,
};
use vesselmsr::mesh::orient::orient_outward;
use vesselmsr::mesh::primitives::{box_mesh, icosphere};
use vesselmsr::mesh::topology::Orientation;
use vesselmsr::TriMesh;

fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
    Point3::new(x, y, z)
}

/// The box from `o` with sides `s`.
fn box_at(o: Point3<f64>, s: [f64; 3]) -> TriMesh {
    box_mesh(o, o + Vector3::from(s))
}

#[test]
fn far_away_box_area_and_volume_are_exact() {
    let o = p(1e5, -2e5, 3e5);
    let m = box_at(o, [2.0, 3.0, 5.0]);
    assert!(rel(area(&m), 62.0) < 1e-9, "area {}", area(&m));
    assert!(
        rel(signed_volume(&m), 30.0) < 1e-9,
        "volume {}",
        signed_volume(&m)
    );
    let (lo, hi) = bounding_box(&m);
    assert_eq!(lo, o);
    assert_eq!(hi, p(1e5 + 2.0, -2e5 + 3.0, 3e5 + 5.0));
    let info = mesh_info(&m);
    assert!(info.watertight);
    assert!(rel(info.volume.unwrap(), 30.0) < 1e-9);
    assert!(rel(info.area, 62.0) < 1e-9);
    // A box of 2 × 3 × 5 µm at 1e5: its sides, as stored, are what f64 makes of 1e5 + 0.002 etc.
    // (exact differences by Sterbenz), and the volume must match their product to 1e-9.
    let small = box_at(o, [0.002, 0.003, 0.005]);
    let (lo, hi) = bounding_box(&small);
    let d = hi - lo;
    let exact = d.x * d.y * d.z;
    assert!(rel(exact, 3e-8) < 1e-7);
    assert!(
        rel(signed_volume(&small), exact) < 1e-9,
        "{} vs {exact}",
        signed_volume(&small)
    );
    assert!(rel(mesh_info(&small).volume.unwrap(), exact) < 1e-9);
    assert!(rel(area(&small), 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)) < 1e-9);
}

#[test]
fn icosphere_converges_to_sphere_area_and_volume() {
    let (r, c) = (2.5, p(-40.0, 1e4, 7.0));
    let (a_exact, v_exact) = (4.0 * PI * r * r, 4.0 / 3.0 * PI * r.powi(3));
    let mut prev: Option<(f64, f64)> = None;
    for level in 1..=5 {
        let m = icosphere(level, r, c);
        let info = mesh_info(&m);
        assert!(
            info.watertight && info.genus == Some(0) && info.orientation == Orientation::Outward
        );
        let (ea, ev) = (rel(info.area, a_exact), rel(info.volume.unwrap(), v_exact));
        // Inscribed polyhedron: both from below.
        assert!(info.area < a_exact && info.volume.unwrap() < v_exact);
        if let Some((pa, pv)) = prev {
            // Second-order convergence: each subdivision halves the edge, quartering the error.
            assert!(
                (3.5..4.5).contains(&(pa / ea)),
                "level {level}: area ratio {}",
                pa / ea
            );
            assert!(
                (3.5..4.5).contains(&(pv / ev)),
                "level {level}: volume ratio {}",
                pv / ev
            );
        }
        prev = Some((ea, ev));
    }
    let (ea, ev) = prev.unwrap();
    assert!(
        ea < 2e-3 && ev < 3e-3,
        "level 5 errors: area {ea}, volume {ev}"
    );
}

#[test]
fn unit_cube_mean_edge_by_hand() {
    let m = box_at(p(0., 0., 0.), [1., 1., 1.]);
    // 12 unit edges and 6 face diagonals of length √2, each counted once.
    let expected = (12.0 + 6.0 * 2f64.sqrt()) / 18.0;
    assert!((mean_edge_length(&m) - expected).abs() < 1e-14);
    assert!((mesh_info(&m).mean_edge - expected).abs() < 1e-14);
    assert_eq!(euler_characteristic(&m), 2);
    assert_eq!(genus(&m), Some(0));
}

#[test]
fn degenerate_faces_are_counted() {
    let mut m = box_at(p(0., 0., 0.), [1., 1., 1.]);
    assert_eq!(degenerate_faces(&m), 0);
    // A small but proper triangle (1e-3 of the edge length) is not degenerate.
    m.vertices
        .extend([p(5., 5., 5.), p(5.001, 5., 5.), p(5., 5.001, 5.)]);
    m.faces.push([8, 9, 10]);
    assert_eq!(degenerate_faces(&m), 0);
    // Collinear corners, a repeated index, and a needle of relative height 1e-15.
    m.vertices.extend([
        p(7., 0., 0.),
        p(8., 0., 0.),
        p(9., 0., 0.),
        p(8., 1e-15, 0.),
    ]);
    m.faces.push([11, 12, 13]);
    m.faces.push([11, 11, 12]);
    m.faces.push([11, 13, 14]);
    assert_eq!(degenerate_faces(&m), 3);
    assert_eq!(mesh_info(&m).degenerate_faces, 3);
    // Scale invariance: the same mesh in metres (÷1000) has the same count.
    let small = TriMesh::new(
        m.vertices
            .iter()
            .map(|q| p(q.x, q.y, q.z) / 1000.0)
            .collect(),
        m.faces.clone(),
    );
    assert_eq!(degenerate_faces(&small), 3);
}

#[test]
fn aspect_ratio_of_equilateral_and_sliver() {
    let (a, b, c) = (
        p(1e5, 0., 0.),
        p(1e5 + 1., 0., 0.),
        p(1e5 + 0.5, 3f64.sqrt() / 2.0, 0.),
    );
    assert!((triangle_aspect_ratio(&a, &b, &c) - 1.0).abs() < 1e-9);
    let s = p(1e5 + 0.5, 1e-3, 0.);
    let sliver = triangle_aspect_ratio(&a, &b, &s);
    assert!(
        (sliver - 3f64.sqrt() / (2.0 * 1e-3)).abs() < 1e-3 * sliver,
        "{sliver}"
    );
    assert!(sliver > 500.0);
    assert_eq!(
        triangle_aspect_ratio(&a, &b, &p(1e5 + 2., 0., 0.)),
        f64::INFINITY
    );
}

#[test]
fn info_json_has_exactly_the_documented_keys() {
    let m = box_at(p(0., 0., 0.), [1., 2., 3.]);
    let info = mesh_info(&m);
    let json = serde_json::to_value(&info).unwrap();
    let mut keys: Vec<&str> = json
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    keys.sort();
    let mut want = vec![
        "vertices",
        "faces",
        "components",
        "boundary_loops",
        "boundary_edges",
        "non_manifold_edges",
        "non_manifold_vertices",
        "degenerate_faces",
        "watertight",
        "orientation",
        "volume",
        "signed_volume",
        "area",
        "bbox_min",
        "bbox_max",
        "mean_edge",
        "euler_characteristic",
        "genus",
    ];
    want.sort();
    assert_eq!(keys, want);
    assert_eq!(json["orientation"], "outward");
    assert_eq!(json["bbox_max"], serde_json::json!([1.0, 2.0, 3.0]));
    assert_eq!(json["genus"], 0);
    assert_eq!(json["volume"], 6.0);
    let text = info.to_string();
    for needle in [
        "watertight",
        "yes",
        "outward",
        "file units³",
        "1 × 2 × 3",
        "genus",
    ] {
        assert!(text.contains(needle), "{needle:?} missing from\n{text}");
    }
}

/// A SOURCES.md figure with its precision: the value and half a unit in its last written digit.
fn figure(s: &str) -> (f64, f64) {
    let decimals = s.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
    (
        s.parse().unwrap(),
        0.5 * 10f64.powi(-decimals) * (1.0 + 1e-9),
    )
}

/// SOURCES.md figures beyond the counts of `REAL_MESHES`.
struct Expected {
    file: &'static str,
    bbox: [&'static str; 3],
    mean_edge: &'static str,
    orientation: Orientation,
}

#[test]
fn real_meshes_match_sources_md() {
    let Some(dir) = real_dir() else { return };
    use Orientation::*;
    let table = [
        Expected {
            file: "aorta_abdominal_open_ends.stl",
            bbox: ["34.26", "78.04", "22.78"],
            mean_edge: "0.95",
            orientation: Open,
        },
        Expected {
            file: "aorta_abdominal_capped.stl",
            bbox: ["34.30", "83.96", "22.91"],
            mean_edge: "0.97",
            orientation: Inward,
        },
        Expected {
            file: "carotid_bifurcation.stl",
            bbox: ["0.02231", "0.01554", "0.07117"],
            mean_edge: "0.00048",
            orientation: Open,
        },
        Expected {
            file: "ica_aneurysm_c0015.stl",
            bbox: ["9.065", "8.379", "15.53"],
            mean_edge: "0.245",
            orientation: Open,
        },
        Expected {
            file: "coronary_stenosis_xray.stl",
            bbox: ["49.99", "21.86", "40.81"],
            mean_edge: "0.575",
            orientation: Open,
        },
        Expected {
            file: "cortex_rh_pial_fsaverage5.stl",
            bbox: ["69.97", "173.6", "127.6"],
            mean_edge: "3.10",
            orientation: Outward,
        },
    ];
    for (file, v, f, loops, closed) in REAL_MESHES {
        let e = table.iter().find(|e| e.file == file).expect(file);
        let m = read_real(&dir, file);
        let t = std::time::Instant::now();
        let info = mesh_info(&m);
        let dt = t.elapsed();
        println!(
            "{file}: mesh_info in {:.2} ms\n{info}",
            dt.as_secs_f64() * 1e3
        );
        println!("{}", serde_json::to_string(&info).unwrap());
        assert_eq!((info.vertices, info.faces), (v, f), "{file}");
        assert_eq!(info.components, 1, "{file}");
        assert_eq!(info.non_manifold_edges, 0, "{file}");
        assert_eq!(info.boundary_loops, loops, "{file}");
        assert_eq!(info.watertight, closed, "{file}");
        assert_eq!(info.orientation, e.orientation, "{file}");
        assert_eq!(info.volume.is_some(), closed, "{file}");
        assert_eq!(info.genus, if closed { Some(0) } else { None }, "{file}");
        for k in 0..3 {
            let (want, tol) = figure(e.bbox[k]);
            let got = info.bbox_max[k] - info.bbox_min[k];
            assert!(
                (got - want).abs() <= tol,
                "{file}: extent {k} is {got}, SOURCES.md says {want}"
            );
        }
        // Mean edge to two significant digits.
        let (want, _) = figure(e.mean_edge);
        let tol = 0.5 * 10f64.powi(want.log10().floor() as i32 - 1) * (1.0 + 1e-9);
        assert!(
            (info.mean_edge - want).abs() <= tol,
            "{file}: mean edge {} vs {want}",
            info.mean_edge
        );
        // Turning outward: the inward capped aorta is flipped, the cortex is left alone.
        let mut turned = m.clone();
        let flipped = orient_outward(&mut turned);
        let c = area_centroid(&m);
        println!(
            "{file}: volume about the area centroid {}, orient_outward flips {flipped}",
            signed_volume_about(&m, &c)
        );
        if closed {
            assert_eq!(flipped, usize::from(e.orientation == Inward), "{file}");
            let after = mesh_info(&turned);
            assert_eq!(after.orientation, Outward, "{file}");
            assert!(
                rel(after.volume.unwrap(), info.volume.unwrap()) < 1e-12,
                "{file}"
            );
        }
    }
}

#[test]
fn open_aorta_faces_inward_like_its_capped_sibling() {
    let Some(dir) = real_dir() else { return };
    let open = read_real(&dir, "aorta_abdominal_open_ends.stl");
    let capped = read_real(&dir, "aorta_abdominal_capped.stl");
    // Ground truth by geometry: compare each sampled open-mesh face normal with the normal of the
    // nearest capped-mesh face (by centroid); the capped mesh is known to face inward.
    let centroid = |m: &TriMesh, f: usize| {
        let [a, b, c] = m.triangle(f);
        Point3::from((a.coords + b.coords + c.coords) / 3.0)
    };
    let capped_c: Vec<Point3<f64>> = (0..capped.num_faces())
        .map(|f| centroid(&capped, f))
        .collect();
    let (mut agree, mut total) = (0, 0);
    for f in (0..open.num_faces()).step_by(37) {
        let q = centroid(&open, f);
        let (g, d2) = capped_c
            .iter()
            .enumerate()
            .map(|(g, c)| (g, (c - q).norm_squared()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        if d2.sqrt() < 1.0 {
            total += 1;
            let (n1, n2) = (open.face_normal_raw(f), capped.face_normal_raw(g));
            agree += usize::from(n1.dot(&n2) > 0.0);
        }
    }
    println!("{agree} of {total} sampled normals agree");
    assert!(total > 200, "only {total} sampled faces overlap");
    assert!(
        agree as f64 > 0.95 * total as f64,
        "{agree} of {total} normals agree"
    );
    // The centroid-volume rule of orient_outward reaches the same verdict: inward, flip it.
    let c = area_centroid(&open);
    assert!(signed_volume_about(&open, &c) < 0.0);
    let mut turned = open.clone();
    assert_eq!(orient_outward(&mut turned), 1);
}
