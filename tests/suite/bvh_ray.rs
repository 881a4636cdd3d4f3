//! Ray casts: analytic hits on a cube (including rays through a shared edge and a vertex),
//! watertightness on an icosphere, the hierarchy against brute force (Möller–Trumbore) on the
//! real meshes and a small mesh far from the origin, and the parity of the hit count against the
//! winding number on the closed meshes.

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use rayon::prelude::*;
use vesselmsr::bvh::brute::{cast_ray_brute, count_ray_hits_brute, intersect_ray_triangle_mt};
use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::mesh::primitives::icosphere;
use vesselmsr::TriMesh;

#[test]
fn cube_analytic_hits() {
    let mesh = cube(-1.0, 1.0);
    let bvh = MeshBvh::new(&mesh);
    let inf = f64::INFINITY;
    let x = Vector3::new(1.0, 0.0, 0.0);

    let h = bvh
        .cast_ray(&Point3::new(-5.0, 0.3, 0.2), &x, inf)
        .expect("hit");
    assert!((h.t - 4.0).abs() < 1e-15);
    assert!((h.point - Point3::new(-1.0, 0.3, 0.2)).norm() < 1e-15);
    let [a, b, c] = mesh.triangle(h.face as usize);
    let recon = a.coords * h.bary[0] + b.coords * h.bary[1] + c.coords * h.bary[2];
    assert!((recon - h.point.coords).norm() < 1e-14);
    assert!(a.x == -1.0 && b.x == -1.0 && c.x == -1.0, "hit the −x face");
    assert_eq!(bvh.count_ray_hits(&Point3::new(-5.0, 0.3, 0.2), &x, inf), 2);
    // t is in units of |dir|.
    let h2 = bvh
        .cast_ray(&Point3::new(-5.0, 0.3, 0.2), &(x * 2.0), inf)
        .unwrap();
    assert!((h2.t - 2.0).abs() < 1e-15);
    // Bounded rays.
    assert!(bvh
        .cast_ray(&Point3::new(-5.0, 0.3, 0.2), &x, 3.9)
        .is_none());
    assert!(bvh
        .cast_ray(&Point3::new(-5.0, 0.3, 0.2), &x, 4.0)
        .is_some());
    assert_eq!(bvh.count_ray_hits(&Point3::new(-5.0, 0.3, 0.2), &x, 5.0), 1);
    // From inside, every axis direction leaves once (this origin avoids the face diagonals).
    let o = Point3::new(0.1, 0.2, 0.3);
    for k in 0..3 {
        for s in [-1.0, 1.0] {
            let d = Vector3::from_fn(|i, _| if i == k { s } else { 0.0 });
            let h = bvh.cast_ray(&o, &d, inf).unwrap();
            assert!((h.t - (1.0 - s * o[k])).abs() < 1e-15);
            assert_eq!(bvh.count_ray_hits(&o, &d, inf), 1);
        }
    }
    // Through the centre of a face, i.e. through its diagonal: both triangles may count.
    assert!((bvh.cast_ray(&Point3::origin(), &x, inf).unwrap().t - 1.0).abs() < 1e-15);
    // Misses, and rays pointing away.
    assert!(bvh
        .cast_ray(&Point3::new(-5.0, 1.5, 0.0), &x, inf)
        .is_none());
    assert!(bvh
        .cast_ray(&Point3::new(-5.0, 0.0, 0.0), &(-x), inf)
        .is_none());
    assert_eq!(bvh.count_ray_hits(&Point3::new(-5.0, 1.5, 0.0), &x, inf), 0);

    // Through the diagonal shared by the two triangles of the −x face (y = z there), and
    // through a corner: a watertight test cannot let these slip through.
    for (o, d, t) in [
        (Point3::new(-5.0, 0.3, 0.3), x, 4.0),
        (Point3::new(-5.0, -0.7, -0.7), x, 4.0),
        (
            Point3::new(-3.0, -3.0, -3.0),
            Vector3::new(1.0, 1.0, 1.0),
            2.0,
        ),
        (Point3::new(-5.0, 1.0, 1.0), x, 4.0),
    ] {
        let h = bvh.cast_ray(&o, &d, inf).expect("edge or vertex hit");
        assert!((h.t - t).abs() < 1e-14, "{o}: t = {}", h.t);
        assert!(bvh.count_ray_hits(&o, &d, inf) >= 2);
    }
}

#[test]
fn icosphere_edges_and_vertices_are_watertight() {
    let mesh = icosphere(3, 1.0, Point3::new(0.1, 0.2, -0.3));
    let bvh = MeshBvh::new(&mesh);
    let c = Point3::new(0.1, 0.2, -0.3);
    let mut targets: Vec<Point3<f64>> = mesh.vertices.clone();
    for f in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (
                mesh.vertices[f[k] as usize],
                mesh.vertices[f[(k + 1) % 3] as usize],
            );
            targets.push(nalgebra::center(&a, &b));
        }
    }
    let mut rng = rng(17);
    for t in &targets {
        // From outside, through the vertex or edge point, within ~30° of the inward radial
        // direction (so the ray enters the polyhedron there rather than grazing it).
        let d = ((c - t).normalize() + unit_vector(&mut rng) * 0.5).normalize();
        let o = t - d * 3.0;
        let h = bvh.cast_ray(&o, &d, f64::INFINITY);
        assert!(h.is_some(), "ray through {t} slipped through the mesh");
        assert!(h.unwrap().t <= 3.0 + 1e-12);
        // From the centre, straight out.
        assert!(bvh.cast_ray(&c, &(t - c), f64::INFINITY).is_some());
    }
    println!(
        "icosphere: {} rays through vertices and edges all hit",
        2 * targets.len()
    );
}

/// Random rays: (origin, direction, t_max). Every tenth direction is an axis, the next one
/// nearly so; a third of the rays are bounded, and some directions are far from unit length.
fn sample_rays(mesh: &TriMesh, n: usize, seed: u64) -> Vec<(Point3<f64>, Vector3<f64>, f64)> {
    let origins = sample_points(mesh, n, seed);
    let diag = bbox_diagonal(mesh);
    let mut rng = rng(seed + 1);
    origins
        .into_iter()
        .enumerate()
        .map(|(i, o)| {
            let k = rng.random_range(0..3usize);
            let s = if rng.random::<bool>() { 1.0 } else { -1.0 };
            let axis = Vector3::from_fn(|j, _| if j == k { s } else { 0.0 });
            let mut d = match i % 10 {
                0 => axis,
                1 => (axis + unit_vector(&mut rng) * 1e-9).normalize(),
                _ => unit_vector(&mut rng),
            };
            let len = [1.0, 1e-3, 1e3][i % 3];
            d *= len;
            let t_max = if i % 3 == 2 {
                rng.random::<f64>() * diag / len
            } else {
                f64::INFINITY
            };
            (o, d, t_max)
        })
        .collect()
}

struct RayStats {
    max_rel_t: f64,
    hits: usize,
    tie_faces: usize,
}

/// Nearest hits and hit counts of the hierarchy against brute force.
fn compare_rays(
    mesh: &TriMesh,
    bvh: &MeshBvh,
    rays: &[(Point3<f64>, Vector3<f64>, f64)],
) -> RayStats {
    let diag = bbox_diagonal(mesh);
    let per_ray: Vec<(f64, bool, bool)> = rays
        .par_iter()
        .map(|(o, d, t_max)| {
            let fast = bvh.cast_ray(o, d, *t_max);
            let slow = cast_ray_brute(mesh, o, d, *t_max);
            assert_eq!(
                bvh.count_ray_hits(o, d, *t_max),
                count_ray_hits_brute(mesh, o, d, *t_max),
                "hit count of ray {o} {d}"
            );
            match (fast, slow) {
                (None, None) => (0.0, false, false),
                (Some(f), Some(s)) => {
                    // Relative in t, with a floor of 1e-12 of the diagonal for hits near the origin.
                    let scale = s.t.max(1e-3 * diag / d.norm());
                    let rel = (f.t - s.t).abs() / scale;
                    let mut tie = false;
                    if f.face != s.face {
                        // Only a genuine tie (a shared edge or vertex) may pick another face.
                        let [a, b, c] = mesh.triangle(f.face as usize);
                        let other = intersect_ray_triangle_mt(o, d, f64::INFINITY, &a, &b, &c);
                        let same_t = other.is_some_and(|(t, _)| (t - s.t).abs() <= 1e-9 * scale);
                        assert!(same_t, "ray {o} {d}: face {} vs brute {}", f.face, s.face);
                        tie = true;
                    }
                    (rel, true, tie)
                }
                (f, s) => panic!("ray {o} {d} (t_max {t_max}): bvh {f:?}, brute {s:?}"),
            }
        })
        .collect();
    RayStats {
        max_rel_t: per_ray.iter().map(|r| r.0).fold(0.0, f64::max),
        hits: per_ray.iter().filter(|r| r.1).count(),
        tie_faces: per_ray.iter().filter(|r| r.2).count(),
    }
}

#[test]
fn real_meshes_rays_equal_brute_force() {
    let Some(meshes) = real_meshes() else { return };
    for (name, mesh) in &meshes {
        let bvh = MeshBvh::new(mesh);
        let rays = sample_rays(mesh, 3000, 77);
        let st = compare_rays(mesh, &bvh, &rays);
        println!(
            "{name}: {} rays, {} hits, max |t_bvh − t_brute|/t = {:.3e}, {} ties on another face",
            rays.len(),
            st.hits,
            st.max_rel_t,
            st.tie_faces
        );
        assert!(st.max_rel_t <= 1e-9, "{name}: {}", st.max_rel_t);
        assert!(
            st.hits > rays.len() / 4,
            "{name}: too few hits to test anything"
        );
    }
}

#[test]
fn real_closed_meshes_hit_parity_matches_winding_number() {
    let Some(meshes) = real_meshes() else { return };
    for (name, mesh) in &meshes {
        if name != "cortex_rh_pial_fsaverage5.stl" && name != "aorta_abdominal_capped.stl" {
            continue;
        }
        let diag = bbox_diagonal(mesh);
        let wn = WindingNumber::new(mesh, WindingOptions::default());
        let origins = sample_points(mesh, 4000, 99);
        let mut rng = rng(100);
        let dirs: Vec<Vector3<f64>> = origins.iter().map(|_| unit_vector(&mut rng)).collect();
        let (mut checked, mut odd) = (0, 0);
        for (o, d) in origins.iter().zip(&dirs) {
            if wn.bvh().closest_point(o).distance < 1e-6 * diag {
                continue;
            }
            let w = wn.winding_number(o);
            let inside = w.abs().round() as usize % 2 == 1;
            assert!(
                (w - w.round()).abs() < 0.05,
                "{name}: w = {w} on a closed mesh"
            );
            let n = wn.bvh().count_ray_hits(o, d, f64::INFINITY);
            assert_eq!(n % 2 == 1, inside, "{name}: {n} hits from {o}, w = {w}");
            checked += 1;
            odd += n % 2;
        }
        println!("{name}: hit parity matches the winding number on {checked} rays ({odd} odd)");
        assert!(odd > 300 && checked - odd > 300);
    }
}

#[test]
fn small_mesh_far_from_origin() {
    let mesh = icosphere(4, 1e-2, Point3::new(1e3, -2e3, 5e2));
    let bvh = MeshBvh::new(&mesh);
    let rays = sample_rays(&mesh, 3000, 5);
    let st = compare_rays(&mesh, &bvh, &rays);
    println!(
        "far small icosphere: {} hits, max |Δt|/t = {:.3e}, {} ties",
        st.hits, st.max_rel_t, st.tie_faces
    );
    assert!(st.max_rel_t <= 1e-9);
    assert!(st.hits > 500);
}

#[test]
fn unusable_rays_and_empty_meshes_miss() {
    let bvh = MeshBvh::new(&cube(0.0, 1.0));
    let o = Point3::new(0.5, 0.5, -1.0);
    let z = Vector3::new(0.0, 0.0, 1.0);
    assert!(bvh.cast_ray(&o, &z, f64::INFINITY).is_some());
    assert!(bvh.cast_ray(&o, &Vector3::zeros(), f64::INFINITY).is_none());
    assert!(bvh
        .cast_ray(&o, &Vector3::new(f64::NAN, 0.0, 1.0), 1.0)
        .is_none());
    assert!(bvh
        .cast_ray(&Point3::new(f64::INFINITY, 0.0, 0.0), &z, 1.0)
        .is_none());
    assert!(bvh.cast_ray(&o, &z, -1.0).is_none());
    assert!(bvh.cast_ray(&o, &z, f64::NAN).is_none());
    assert_eq!(bvh.count_ray_hits(&o, &Vector3::zeros(), f64::INFINITY), 0);
    let empty = MeshBvh::new(&TriMesh::default());
    assert!(empty.cast_ray(&o, &z, f64::INFINITY).is_none());
    assert_eq!(empty.count_ray_hits(&o, &z, f64::INFINITY), 0);
}

#[test]
fn grazing_ray_is_not_culled_by_f32_boxes() {
    // A triangle in the plane x = 0 (a flat leaf box) and a ray crossing that plane at a shallow
    // angle whose x-direction component (4e-8) is below f32 epsilon, which obvhs's slab test
    // clamps to 1.19e-7: the f32 ray crosses x = 0 at t ≈ 1.7 instead of 5, outside the
    // triangle's z-range, so without the box padding the leaf would be culled. A ring of small
    // triangles keeps the ray origin inside the root box and the flat triangle in its own leaf.
    let mut v = vec![
        Point3::new(0.0, -1.0, -1.0),
        Point3::new(0.0, 1.0, -1.0),
        Point3::new(0.0, 0.0, 2.0),
    ];
    let mut f = vec![[0, 1, 2]];
    for k in 0..64 {
        let a = k as f64 * std::f64::consts::TAU / 64.0;
        let c = Point3::new(-3.0 + 6.0 * a.cos(), 8.0 * a.sin(), -8.0 + 0.1 * k as f64);
        let n = v.len() as u32;
        v.extend([
            c,
            c + Vector3::new(0.1, 0.0, 0.0),
            c + Vector3::new(0.0, 0.1, 0.0),
        ]);
        f.push([n, n + 1, n + 2]);
    }
    let mesh = TriMesh::new(v, f);
    let bvh = MeshBvh::new(&mesh);
    let o = Point3::new(-2e-7, 0.2, -5.0);
    let d = Vector3::new(4e-8, 0.0, 1.0);
    // The set-up is what it claims: the origin inside the root box, face 0 in a leaf whose box
    // is flat in x up to the padding.
    let tree = bvh.obvhs_bvh();
    let root = tree.nodes[0].aabb();
    let local = o.coords - bvh.local_origin();
    assert!((0..3).all(|k| (root.min[k] as f64) < local[k] && local[k] < root.max[k] as f64));
    let leaf = tree
        .nodes
        .iter()
        .find(|n| {
            n.is_leaf()
                && (n.first_index..n.first_index + n.prim_count)
                    .any(|s| bvh.slot_face(s as usize) == 0)
        })
        .unwrap();
    assert!(leaf.aabb().max.x - leaf.aabb().min.x < 1e-3);

    let want = cast_ray_brute(&mesh, &o, &d, f64::INFINITY).expect("brute-force hit");
    let got = bvh
        .cast_ray(&o, &d, f64::INFINITY)
        .expect("grazing hit culled");
    assert_eq!(got.face, 0);
    assert!((got.t - want.t).abs() <= 1e-12 * want.t);
    assert_eq!(bvh.count_ray_hits(&o, &d, f64::INFINITY), 1);
}
