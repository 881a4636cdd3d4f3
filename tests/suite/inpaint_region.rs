//! Regions D of the inpainting (src/inpaint/region.rs, src/inpaint/holes.rs): `--region` parsing,
//! regions files (balls and picked points), validation against the mesh, the local vessel radius
//! on a tube of known radius, and the classification of boundary loops into vessel ends and holes
//! on tubes and on the real open-ended meshes, with and without a wall patch cut out.

use crate::common;
use common::*;

use nalgebra::Point3;
use std::path::Path;
use vesselmsr::bvh::MeshBvh;
use vesselmsr::inpaint::holes::{
    classify_loops, gap_balls, gap_groups, gap_regions, hole_regions, LoopInfo, LoopKind,
    LoopOptions,
};
use vesselmsr::inpaint::region::{
    local_vessel_radius, parse_ball, read_regions, validate_regions, Ball, PickedSite,
    PICKED_RADIUS_FACTOR,
};
use vesselmsr::mesh::measures::mean_edge_length;
use vesselmsr::mesh::primitives::{icosphere, open_tube};
use vesselmsr::mesh::topology::boundary_loops;
use vesselmsr::TriMesh;

/// Tube of radius 3 and length 30 along z, 48 segments, 61 rings.
fn tube3() -> TriMesh {
    open_tube(3.0, 30.0, 48, 61)
}

/// `mesh` without the faces whose corners all lie within `d` of `c`, unused vertices kept.
fn cut_patch(mesh: &TriMesh, c: &Point3<f64>, d: f64) -> TriMesh {
    let faces = mesh
        .faces
        .iter()
        .filter(|f| {
            !f.iter()
                .all(|&v| (mesh.vertices[v as usize] - c).norm() <= d)
        })
        .copied()
        .collect();
    TriMesh::new(mesh.vertices.clone(), faces)
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn err_text<T: std::fmt::Debug>(r: vesselmsr::Result<T>) -> String {
    let e = r.expect_err("an error").to_string();
    println!("error: {e}");
    e
}

#[test]
fn parse_ball_reads_four_numbers() {
    let b = parse_ball("1.5, -2,3e1,0.25").unwrap();
    assert_eq!(b.center, Point3::new(1.5, -2.0, 30.0));
    assert_eq!(b.radius, 0.25);
}

#[test]
fn parse_ball_errors() {
    for bad in ["1,2,3", "1,2,3,4,5", "", "a,2,3,4", "1,2,,4"] {
        assert!(
            err_text(parse_ball(bad)).contains("expected x,y,z,r"),
            "{bad}"
        );
    }
    for bad in ["1,2,3,0", "1,2,3,-1"] {
        assert!(
            err_text(parse_ball(bad)).contains("radius must be > 0"),
            "{bad}"
        );
    }
    for bad in ["nan,2,3,1", "1,inf,3,1", "1,2,3,NaN"] {
        assert!(
            err_text(parse_ball(bad)).contains("expected x,y,z,r"),
            "{bad}"
        );
    }
}

#[test]
fn local_radius_on_tube_of_radius_3() {
    let mesh = tube3();
    let bvh = MeshBvh::new(&mesh);
    let mut worst: f64 = 0.0;
    for (k, z) in [5.0, 10.0, 15.0, 22.5].iter().enumerate() {
        let th = 0.3 + 1.1 * k as f64;
        let p = Point3::new(3.0 * th.cos(), 3.0 * th.sin(), *z);
        let r = local_vessel_radius(&mesh, &bvh, &p).expect("a radius");
        println!("z {z}: local radius {r:.4} (true 3)");
        worst = worst.max(rel(r, 3.0));
    }
    println!("worst relative error {worst:.4}");
    assert!(worst < 0.05);
    // Inward-facing tube: the same answer.
    let mut flipped = mesh.clone();
    flipped.flip_faces();
    let fb = MeshBvh::new(&flipped);
    let r = local_vessel_radius(&flipped, &fb, &Point3::new(3.0, 0.0, 15.0)).unwrap();
    println!("flipped tube: {r:.4}");
    assert!(rel(r, 3.0) < 0.05);
    // A point off the surface is snapped first.
    let r = local_vessel_radius(&mesh, &bvh, &Point3::new(0.0, 3.4, 12.0)).unwrap();
    assert!(rel(r, 3.0) < 0.05);
    assert!(local_vessel_radius(&mesh, &bvh, &Point3::new(f64::NAN, 0.0, 0.0)).is_none());
}

#[test]
fn local_radius_on_sphere_is_its_radius() {
    let mesh = icosphere(4, 2.0, Point3::new(1.0, 1.0, 1.0));
    let bvh = MeshBvh::new(&mesh);
    let r = local_vessel_radius(&mesh, &bvh, &Point3::new(3.0, 1.0, 1.0)).unwrap();
    println!("sphere of radius 2: {r:.4}");
    assert!(rel(r, 2.0) < 0.05);
}

#[test]
fn read_regions_balls_and_points() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = tube3();
    let p = write(
        dir.path(),
        "r.json",
        r#"{"regions": [{"center": [0, 3, 10], "radius": 2}], "points": [[3.2, 0, 15], [0, -3, 20]]}"#,
    );
    let read = read_regions(&p, &mesh, &|_| None).unwrap();
    assert!(read.iter().all(|r| !r.narrowing));
    let balls: Vec<Ball> = read.iter().map(|r| r.ball).collect();
    assert_eq!(balls.len(), 3);
    assert_eq!(
        balls[0],
        Ball {
            center: Point3::new(0.0, 3.0, 10.0),
            radius: 2.0
        }
    );
    for b in &balls[1..] {
        let on_axis = (b.center.x.powi(2) + b.center.y.powi(2)).sqrt();
        println!("picked ball centre {:?} radius {}", b.center, b.radius);
        // Snapped onto the polygonal tube (inscribed radius 3 cos(π/48)).
        assert!((on_axis - 3.0).abs() < 0.01, "{on_axis}");
        assert!(rel(b.radius, PICKED_RADIUS_FACTOR * 3.0) < 0.05);
    }
    assert!((balls[1].center.z - 15.0).abs() < 1e-9);
    validate_regions(&mesh, &balls).unwrap();

    // Points only.
    let p = write(dir.path(), "p.json", r#"{"points": [[0, 3, 5]]}"#);
    assert_eq!(read_regions(&p, &mesh, &|_| None).unwrap().len(), 1);
    // Balls only, as write_regions writes them.
    let out = dir.path().join("w.json");
    vesselmsr::inpaint::region::write_regions(&out, &balls).unwrap();
    let again: Vec<Ball> = (read_regions(&out, &mesh, &|_| None).unwrap().iter())
        .map(|r| r.ball)
        .collect();
    assert_eq!(again, balls);
}

#[test]
fn a_point_picked_on_a_narrowing_reads_as_that_narrowing_s_region() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = tube3();
    let p = write(
        dir.path(),
        "r.json",
        r#"{"points": [[3.2, 0, 15], [0, -3, 20]]}"#,
    );
    // The caller knows of a narrowing around z = 20 (its region a ball of 5 on the axis) and
    // of the healthy radius 3 elsewhere.
    let lesion = Ball {
        center: Point3::new(0.0, 0.0, 20.0),
        radius: 5.0,
    };
    let site = |q: &Point3<f64>| {
        Some(if lesion.contains(q) {
            PickedSite::Narrowing(lesion)
        } else {
            PickedSite::Radius(3.0)
        })
    };
    let read = read_regions(&p, &mesh, &site).unwrap();
    assert_eq!(read.len(), 2);
    assert!(!read[0].narrowing);
    assert!((read[0].ball.radius - PICKED_RADIUS_FACTOR * 3.0).abs() < 1e-12);
    assert_eq!(read[1].ball, lesion);
    assert!(read[1].narrowing);
}

#[test]
fn read_regions_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = tube3();
    let cases = [
        ("bad.json", "{\"regions\": [", "not a regions file"),
        (
            "unknown.json",
            r#"{"regions": [], "balls": []}"#,
            "unknown field",
        ),
        (
            "unknown_in_ball.json",
            r#"{"regions": [{"center": [0,0,0], "radius": 1, "r": 2}]}"#,
            "unknown field",
        ),
        (
            "short.json",
            r#"{"regions": [{"center": [0,0], "radius": 1}]}"#,
            "not a regions file",
        ),
        ("empty.json", "{}", "no regions"),
        (
            "empty_lists.json",
            r#"{"regions": [], "points": []}"#,
            "no regions",
        ),
    ];
    for (name, text, word) in cases {
        let p = write(dir.path(), name, text);
        let e = err_text(read_regions(&p, &mesh, &|_| None));
        assert!(e.contains(word), "{name}: {e}");
        assert!(e.contains(name), "{name}: {e}");
    }
    let missing = dir.path().join("missing.json");
    assert!(err_text(read_regions(&missing, &mesh, &|_| None)).contains("missing.json"));
}

#[test]
fn validate_regions_errors() {
    let mesh = tube3();
    let ok = Ball {
        center: Point3::new(3.0, 0.0, 15.0),
        radius: 1.0,
    };
    validate_regions(&mesh, &[ok]).unwrap();
    let cases = [
        (Point3::new(3.0, 0.0, 15.0), 0.0, "radius must be > 0"),
        (Point3::new(3.0, 0.0, 15.0), -2.0, "radius must be > 0"),
        (Point3::new(3.0, 0.0, 15.0), f64::NAN, "not finite"),
        (Point3::new(3.0, 0.0, 15.0), f64::INFINITY, "not finite"),
        (Point3::new(f64::NAN, 0.0, 15.0), 1.0, "not finite"),
        (
            Point3::new(50.0, 0.0, 15.0),
            1.0,
            "outside the mesh's bounding box",
        ),
        (Point3::new(0.0, 0.0, 15.0), 2.0, "touches no surface"),
    ];
    for (c, r, word) in cases {
        let bad = Ball {
            center: c,
            radius: r,
        };
        let e = err_text(validate_regions(&mesh, &[ok, bad]));
        assert!(e.contains(word), "{e}");
        assert!(e.contains("region 2"), "{e}");
        assert!(
            e.contains(&format!("centre {}, {}, {}", c.x, c.y, c.z)),
            "{e}"
        );
    }
    // Grown box: a centre just outside the box but whose ball reaches the wall is fine.
    validate_regions(
        &mesh,
        &[Ball {
            center: Point3::new(3.5, 0.0, 15.0),
            radius: 1.0,
        }],
    )
    .unwrap();
    assert!(err_text(validate_regions(&mesh, &[])).contains("no regions"));
}

#[test]
fn open_tube_has_two_ends() {
    let mesh = tube3();
    let loops = classify_loops(&mesh, &LoopOptions::default());
    assert_eq!(loops.len(), 2);
    for l in &loops {
        println!(
            "{:?}: planarity {:.3} alignment {:.3} radius {:.3}",
            l.kind, l.planarity, l.wall_alignment, l.radius
        );
        assert_eq!(l.kind, LoopKind::End);
        assert!(rel(l.radius, 3.0) < 1e-9);
        assert!(l.normal.z.abs() > 1.0 - 1e-9);
    }
    let e = err_text(hole_regions(&mesh, &LoopOptions::default()));
    assert!(e.contains("mesh has no holes (2 boundary loops, all open vessel ends)"));
    let closed = icosphere(2, 1.0, Point3::origin());
    assert!(err_text(hole_regions(&closed, &LoopOptions::default()))
        .contains("mesh has no boundary loops"));
}

/// The tube cut through by a band 3 long about z = `cut` whose edges rise and fall by 0.5 twice
/// around (a saddle, which no plane fits: the cuts lie 17% of the radius off their planes, where
/// a clipped end lies within 10⁻⁴), both pieces kept; or, with no `cut`, a short tube whose two
/// ends are made as rough.
fn rough_cut_tube(cut: Option<f64>) -> TriMesh {
    let rough = |p: &Point3<f64>| 0.5 * (2.0 * p.y.atan2(p.x)).sin();
    if let Some(z0) = cut {
        let tube = tube3();
        let faces = tube
            .faces
            .iter()
            .filter(|f| {
                let c = f
                    .iter()
                    .map(|&v| tube.vertices[v as usize].coords)
                    .sum::<nalgebra::Vector3<f64>>()
                    / 3.0;
                (c.z - z0 - rough(&Point3::from(c))).abs() > 1.5
            })
            .copied()
            .collect();
        TriMesh::new(tube.vertices.clone(), faces)
    } else {
        let mut tube = open_tube(3.0, 10.0, 48, 21);
        for p in tube.vertices.iter_mut() {
            if p.z == 0.0 || p.z == 10.0 {
                p.z += rough(p);
            }
        }
        tube
    }
}

#[test]
fn rough_ends_facing_across_a_gap_are_one_region_and_a_short_tubes_are_not() {
    let options = LoopOptions::default();
    let cut = rough_cut_tube(Some(15.0));
    let loops = classify_loops(&cut, &options);
    assert_eq!(loops.len(), 4);
    let rough: Vec<usize> = (0..4).filter(|&i| loops[i].is_rough_end()).collect();
    assert_eq!(rough.len(), 2, "{loops:?}");
    let groups = gap_groups(&cut, &loops);
    assert_eq!(groups, vec![rough.clone()]);
    let balls = gap_balls(&cut, &loops, &groups, &options);
    assert_eq!(balls.len(), 1);
    // The ball holds both cut ends and the gap between them, not the clipped ends.
    for &i in &rough {
        assert!(loops[i]
            .vertices
            .iter()
            .all(|&v| balls[0].contains(&cut.vertices[v as usize])));
    }
    assert!(
        (balls[0].center - Point3::new(0.0, 0.0, 15.0)).norm() < 0.1,
        "{:?}",
        balls[0]
    );
    assert!(!balls[0].contains(&Point3::new(3.0, 0.0, 0.0)));
    assert_eq!(gap_regions(&cut, &loops, &options), (groups, balls));
    // A short tube with two rough ends facing each other: one piece, no gap.
    let short = rough_cut_tube(None);
    let loops = classify_loops(&short, &options);
    assert_eq!(
        loops.iter().filter(|l| l.is_rough_end()).count(),
        2,
        "{loops:?}"
    );
    assert!(gap_groups(&short, &loops).is_empty());
    // Cut 3 from a clipped end: the stub between them gives the fill nothing to hold, and the
    // gap's ball would hold the clipped end: no gap region.
    let stub = rough_cut_tube(Some(3.0));
    let loops = classify_loops(&stub, &options);
    assert_eq!(gap_groups(&stub, &loops).len(), 1);
    assert!(gap_regions(&stub, &loops, &options).0.is_empty());
}

/// A cut across a tube that strays a third of its radius from its plane (as a ball through a
/// real vessel's bend left 0.20–0.32): its loops, too far off their planes for ends, are taken
/// for holes, yet the wall beside them runs across their planes as beside an end, and facing
/// each other on two pieces they are one gap. Two tubes side by side, each with a hole in its
/// wall facing the other, are no gap: the wall runs along those holes.
#[test]
fn holes_cut_through_a_tube_are_a_gap_and_facing_wall_holes_are_not() {
    let options = LoopOptions::default();
    let tube = tube3();
    let cut = cut_where(&tube, |p| {
        (p.z - 15.0 - 0.8 * (2.0 * p.y.atan2(p.x)).sin()).abs() < 1.5
    });
    let loops = classify_loops(&cut, &options);
    let holes: Vec<usize> = (0..loops.len())
        .filter(|&i| loops[i].kind == LoopKind::Hole)
        .collect();
    assert_eq!(holes.len(), 2, "{loops:?}");
    for &i in &holes {
        let l = &loops[i];
        assert!(l.planarity > options.planarity_tolerance, "{l:?}");
        assert!(l.may_be_cut(), "{l:?}");
    }
    assert_eq!(gap_groups(&cut, &loops), vec![holes]);
    // Two tubes 8 apart (axes), a hole in each wall facing the other across a gap of 2.
    let a = cut_patch(&tube, &Point3::new(3.0, 0.0, 15.0), 2.0);
    let b = cut_patch(&tube, &Point3::new(-3.0, 0.0, 15.0), 2.0);
    let shift = a.vertices.len() as u32;
    let mut vertices = a.vertices.clone();
    vertices.extend(
        b.vertices
            .iter()
            .map(|p| p + nalgebra::Vector3::new(8.0, 0.0, 0.0)),
    );
    let mut faces = a.faces.clone();
    faces.extend(b.faces.iter().map(|f| f.map(|v| v + shift)));
    let pair = TriMesh::new(vertices, faces);
    let loops = classify_loops(&pair, &options);
    let facing: Vec<&LoopInfo> = loops.iter().filter(|l| l.kind == LoopKind::Hole).collect();
    assert_eq!(facing.len(), 2, "{loops:?}");
    assert!(facing.iter().all(|l| !l.may_be_cut()), "{facing:?}");
    assert!(gap_groups(&pair, &loops).is_empty());
}

#[test]
fn open_tube_with_wall_patch_removed_has_one_hole() {
    let tube = tube3();
    let c = Point3::new(0.0, 3.0, 15.0);
    let mesh = cut_patch(&tube, &c, 1.5);
    assert_eq!(boundary_loops(&mesh).len(), 3);
    let (balls, loops) = hole_regions(&mesh, &LoopOptions::default()).unwrap();
    for l in &loops {
        println!(
            "{:?}: planarity {:.3} alignment {:.3} radius {:.3} centre {:?}",
            l.kind, l.planarity, l.wall_alignment, l.radius, l.center
        );
    }
    assert_eq!(loops.iter().filter(|l| l.kind == LoopKind::End).count(), 2);
    assert_eq!(balls.len(), 1);
    let b = balls[0];
    println!("hole ball {:?} radius {}", b.center, b.radius);
    assert!((b.center - c).norm() < 0.5);
    // The ball covers every vertex of the hole's loop, and is a valid region.
    let hole = loops.iter().find(|l| l.kind == LoopKind::Hole).unwrap();
    assert!(hole
        .vertices
        .iter()
        .all(|&v| b.contains(&mesh.vertices[v as usize])));
    assert!(b.radius < 3.0);
    validate_regions(&mesh, &balls).unwrap();
}

#[test]
fn shipped_aorta_has_only_ends_and_a_cut_patch_is_one_hole() {
    let mesh = vesselmsr::io::read_mesh(Path::new(&aorta())).unwrap();
    let options = LoopOptions::default();
    let loops = classify_loops(&mesh, &options);
    for l in &loops {
        println!(
            "aorta {:?}: {} vertices planarity {:.3} alignment {:.3} radius {:.3}",
            l.kind,
            l.vertices.len(),
            l.planarity,
            l.wall_alignment,
            l.radius
        );
    }
    assert_eq!(loops.len(), 3);
    assert!(loops.iter().all(|l| l.kind == LoopKind::End));
    assert!(err_text(hole_regions(&mesh, &options)).contains("3 boundary loops"));

    // Cut a patch around the wall vertex farthest from every boundary vertex.
    let boundary: Vec<Point3<f64>> = loops
        .iter()
        .flat_map(|l| l.vertices.iter().map(|&v| mesh.vertices[v as usize]))
        .collect();
    let far = |p: &Point3<f64>| {
        boundary
            .iter()
            .map(|b| (b - p).norm())
            .fold(f64::INFINITY, f64::min)
    };
    let c = mesh
        .vertices
        .iter()
        .max_by(|a, b| far(a).total_cmp(&far(b)))
        .copied()
        .unwrap();
    let h = mean_edge_length(&mesh);
    let cut = cut_patch(&mesh, &c, 3.0 * h);
    assert_eq!(boundary_loops(&cut).len(), 4);
    let (balls, loops) = hole_regions(&cut, &options).unwrap();
    for l in &loops {
        println!(
            "cut aorta {:?}: {} vertices planarity {:.3} alignment {:.3} radius {:.3}",
            l.kind,
            l.vertices.len(),
            l.planarity,
            l.wall_alignment,
            l.radius
        );
    }
    assert_eq!(balls.len(), 1);
    println!(
        "hole ball at {:.3} from the patch centre (patch radius {:.3}), radius {:.3}",
        (balls[0].center - c).norm(),
        3.0 * h,
        balls[0].radius
    );
    assert!((balls[0].center - c).norm() < 1.5 * h);
    validate_regions(&cut, &balls).unwrap();
}

#[test]
fn real_open_meshes_have_only_ends() {
    let Some(dir) = real_dir() else { return };
    for (file, _, _, loops_expected, closed) in REAL_MESHES {
        if closed {
            continue;
        }
        let mesh = read_real(&dir, file);
        let loops = classify_loops(&mesh, &LoopOptions::default());
        for l in &loops {
            println!(
                "{file} {:?}: {} vertices planarity {:.3} alignment {:.3} radius {:.3}",
                l.kind,
                l.vertices.len(),
                l.planarity,
                l.wall_alignment,
                l.radius
            );
        }
        assert_eq!(loops.len(), loops_expected, "{file}");
        assert!(loops.iter().all(|l| l.kind == LoopKind::End), "{file}");
    }
}

#[test]
fn oblique_ends_are_ends_and_a_missing_triangle_is_a_hole() {
    // Shear z += x·tan 25°: both ends become planes 25° off perpendicular to the axis.
    let mut mesh = tube3();
    let k = 25f64.to_radians().tan();
    for v in &mut mesh.vertices {
        v.z += v.x * k;
    }
    let loops = classify_loops(&mesh, &LoopOptions::default());
    for l in &loops {
        println!(
            "oblique {:?}: planarity {:.3} alignment {:.3}",
            l.kind, l.planarity, l.wall_alignment
        );
    }
    assert_eq!(loops.len(), 2);
    assert!(loops.iter().all(|l| l.kind == LoopKind::End));

    // One triangle missing from the middle of the wall.
    let mut mesh = tube3();
    let f = mesh.faces.len() / 2 + 7;
    let removed = mesh.faces.remove(f);
    let (balls, loops) = hole_regions(&mesh, &LoopOptions::default()).unwrap();
    assert_eq!(loops.len(), 3);
    assert_eq!(balls.len(), 1);
    let hole = loops.iter().find(|l| l.kind == LoopKind::Hole).unwrap();
    let mut got = hole.vertices.clone();
    let mut want = removed.to_vec();
    got.sort_unstable();
    want.sort_unstable();
    assert_eq!(got, want);
    println!(
        "one-triangle hole: alignment {:.3}, ball radius {:.3}",
        hole.wall_alignment, balls[0].radius
    );
}
