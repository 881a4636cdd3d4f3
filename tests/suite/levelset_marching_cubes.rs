//! Marching cubes (`vesselmsr::levelset::marching_cubes`): analytic spheres and tori converge
//! to their closed-form area and volume with the right topology, random fields full of ambiguous
//! cells always give closed outward 2-manifolds that separate the inside nodes from the outside
//! ones, exact zeros and surfaces cut by the grid border stay closed, no triangle is degenerate,
//! and manifold3d (through the Python oracle) agrees.

use crate::common;

use common::*;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use std::f64::consts::PI;
use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::info::{mesh_info, MeshInfo};
use vesselmsr::mesh::measures::bounding_box;
use vesselmsr::mesh::topology::Orientation;
use vesselmsr::TriMesh;

/// A grid of `dims` nodes from `origin` with spacing `h`, φ = f(world position).
fn grid_of(dims: [usize; 3], origin: [f64; 3], h: f64, f: impl Fn(Point3<f64>) -> f64) -> Grid3 {
    let mut g = Grid3::new(dims, GridTransform::new(Point3::from(origin), h), 0.0).unwrap();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let v = f(g.world(i, j, k)) as f32;
                g.set(i, j, k, v);
            }
        }
    }
    g
}

fn extract(g: &Grid3) -> TriMesh {
    extract_surface(g, &ExtractOptions::default()).unwrap()
}

/// Smallest triangle area, and the smallest, 1st-percentile and mean of the triangles' smallest
/// angles (degrees).
struct Quality {
    min_area: f64,
    min_angle: f64,
    p1_angle: f64,
    mean_angle: f64,
}

fn quality(mesh: &TriMesh) -> Quality {
    let mut angles: Vec<f64> = Vec::with_capacity(mesh.num_faces());
    let mut min_area = f64::INFINITY;
    for f in 0..mesh.num_faces() {
        let [a, b, c] = mesh.triangle(f);
        min_area = min_area.min(0.5 * (b - a).cross(&(c - a)).norm());
        let ang = |p: Point3<f64>, q: Point3<f64>, r: Point3<f64>| (q - p).angle(&(r - p));
        angles.push(
            ang(a, b, c)
                .min(ang(b, c, a))
                .min(ang(c, a, b))
                .to_degrees(),
        );
    }
    angles.sort_by(f64::total_cmp);
    Quality {
        min_area,
        min_angle: angles[0],
        p1_angle: angles[angles.len() / 100],
        mean_angle: angles.iter().sum::<f64>() / angles.len() as f64,
    }
}

/// Closed, 2-manifold, consistently wound, no degenerate triangle, no two vertices at one
/// place, every vertex used; returns the mesh's info.
fn assert_closed_manifold(mesh: &TriMesh, what: &str) -> MeshInfo {
    let info = mesh_info(mesh);
    assert!(mesh.num_faces() > 0, "{what}: empty");
    assert!(
        info.watertight,
        "{what}: not watertight: {:?}",
        info.leaks()
    );
    assert_eq!(info.boundary_edges, 0, "{what}");
    assert_eq!(info.non_manifold_edges, 0, "{what}");
    assert_eq!(info.non_manifold_vertices, 0, "{what}");
    assert_eq!(info.degenerate_faces, 0, "{what}");
    let q = quality(mesh);
    assert!(q.min_area > 0.0, "{what}: a triangle of zero area");
    // Welded: one vertex per place, each used.
    let mut keys: Vec<[u64; 3]> = mesh
        .vertices
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(
        keys.len(),
        mesh.num_vertices(),
        "{what}: two vertices at one place"
    );
    let mut used = vec![false; mesh.num_vertices()];
    mesh.faces
        .iter()
        .flatten()
        .for_each(|&v| used[v as usize] = true);
    assert!(used.iter().all(|&u| u), "{what}: an unused vertex");
    info
}

/// The winding number of the mesh is 1 at every inside node (φ < 0) and 0 at every outside
/// one: the surface separates them and faces outward (voids included).
fn assert_separates(mesh: &TriMesh, g: &Grid3, what: &str) {
    let [nx, ny, nz] = g.dims();
    let mut points = Vec::with_capacity(g.data().len());
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                points.push(g.world(i, j, k));
            }
        }
    }
    let wn = WindingNumber::new(mesh, WindingOptions::default());
    let w = wn.winding_numbers(&points);
    for (idx, (&wi, &phi)) in w.iter().zip(g.data()).enumerate() {
        let expected = if phi < 0.0 { 1.0 } else { 0.0 };
        assert!(
            (wi - expected).abs() < 0.25,
            "{what}: winding number {wi} at node {:?} with φ = {phi}",
            g.coords(idx)
        );
    }
}

/// manifold3d's status (and genus) of the mesh, written as a temporary PLY.
fn manifold3d(mesh: &TriMesh) -> (String, Option<i64>) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mc.ply");
    vesselmsr::io::write_mesh(&path, mesh).unwrap();
    let answer = oracle().check(&path);
    (
        answer["manifold_status"].as_str().unwrap().to_string(),
        answer["manifold_genus"].as_i64(),
    )
}

/// Runs `shape` at h, h/2, h/4 and checks closedness, χ, orientation, manifold3d, and that the
/// area and volume errors against the closed forms shrink as h halves (second order: the
/// ratios should be near 4; at least 2.5 is required).
fn convergence(
    name: &str,
    chi: i64,
    genus: i64,
    area: f64,
    volume: f64,
    grid_at: impl Fn(f64) -> Grid3,
) {
    let mut errors = Vec::new();
    for (level, h) in [0.1, 0.05, 0.025].into_iter().enumerate() {
        let g = grid_at(h);
        let t = std::time::Instant::now();
        let mesh = extract(&g);
        let secs = t.elapsed().as_secs_f64();
        let what = format!("{name} h = {h}");
        let info = assert_closed_manifold(&mesh, &what);
        assert_eq!(info.euler_characteristic, chi, "{what}");
        assert_eq!(info.components, 1, "{what}");
        assert_eq!(info.orientation, Orientation::Outward, "{what}");
        let (status, mgenus) = manifold3d(&mesh);
        assert_eq!(status, "NoError", "{what}: manifold3d");
        assert_eq!(mgenus, Some(genus), "{what}: manifold3d genus");
        let vol = info.volume.unwrap();
        let (ea, ev) = (rel(info.area, area), rel(vol, volume));
        let q = quality(&mesh);
        println!(
            "{what}: grid {:?}, {} faces in {:.1} ms, area rel. error {ea:.3e}, volume rel. error \
             {ev:.3e}, min angle {:.2}° (1st percentile {:.2}°, mean {:.1}°), min area {:.2e} h²",
            g.dims(),
            mesh.num_faces(),
            secs * 1e3,
            q.min_angle,
            q.p1_angle,
            q.mean_angle,
            q.min_area / (h * h)
        );
        if level < 2 {
            // the two coarser levels also check the separation of the nodes
            assert_separates(&mesh, &g, &what);
        }
        errors.push((ea, ev));
    }
    for l in 1..errors.len() {
        let (ra, rv) = (errors[l - 1].0 / errors[l].0, errors[l - 1].1 / errors[l].1);
        println!(
            "{name}: error ratio h/{} → h/{}: area {ra:.2}, volume {rv:.2}",
            1 << (l - 1),
            1 << l
        );
        assert!(
            ra > 2.5 && rv > 2.5,
            "{name}: errors {errors:?} do not shrink as h halves"
        );
    }
    assert!(
        errors[2].0 < 2e-3 && errors[2].1 < 2e-3,
        "{name}: {errors:?}"
    );
}

#[test]
fn sphere_converges_with_genus_zero() {
    let (r, c) = (1.0, Vector3::new(0.0123, -0.0311, 0.0207));
    convergence(
        "sphere",
        2,
        0,
        4.0 * PI * r * r,
        4.0 / 3.0 * PI * r * r * r,
        |h| {
            let n = (2.6 / h).round() as usize + 1;
            grid_of([n; 3], [-1.3; 3], h, |p| (p.coords - c).norm() - r)
        },
    );
}

#[test]
fn torus_converges_with_genus_one() {
    let (big, small) = (1.0, 0.35);
    let c = Vector3::new(-0.0171, 0.0093, 0.0137);
    convergence(
        "torus",
        0,
        1,
        4.0 * PI * PI * big * small,
        2.0 * PI * PI * big * small * small,
        |h| {
            let nxy = (3.0 / h).round() as usize + 1;
            let nz = (1.0 / h).round() as usize + 1;
            grid_of([nxy, nxy, nz], [-1.5, -1.5, -0.5], h, |p| {
                let q = p.coords - c;
                let ring = (q.x * q.x + q.y * q.y).sqrt() - big;
                (ring * ring + q.z * q.z).sqrt() - small
            })
        },
    );
}

/// White noise in [−1, 1] (about a third of the cube faces are ambiguous), quantised noise in
/// {−1, 0, 1} (exact zeros everywhere), and smooth random blobs (several components, handles and
/// voids), with sliver collapsing off, at its default and at its most aggressive: always a
/// closed outward 2-manifold separating the inside nodes from the outside ones.
#[test]
fn random_fields_give_closed_outward_manifolds() {
    let settings = [0.0, 0.1, 0.45];
    let mut ambiguous_faces = 0usize;
    let mut checked = 0;
    let mut worst = [f64::INFINITY; 3];
    let mut min_area = [f64::INFINITY; 3];
    let mut multi_component = 0;
    let mut with_handles = 0;
    for seed in 0..300u64 {
        let mut rng = rng(seed);
        let n = [
            rng.random_range(2..13usize),
            rng.random_range(2..13usize),
            rng.random_range(2..13usize),
        ];
        let h = 0.5 + rng.random::<f64>();
        let origin = [
            rng.random::<f64>(),
            -rng.random::<f64>(),
            3.0 * rng.random::<f64>(),
        ];
        let kind = seed % 3;
        let blobs: Vec<(Point3<f64>, f64, f64)> = (0..8)
            .map(|_| {
                let c = Point3::from(origin)
                    + Vector3::new(
                        rng.random::<f64>() * n[0] as f64,
                        rng.random::<f64>() * n[1] as f64,
                        rng.random::<f64>() * n[2] as f64,
                    ) * h;
                (
                    c,
                    (0.5 + 2.0 * rng.random::<f64>()) * h,
                    rng.random::<f64>() * 2.0 - 0.7,
                )
            })
            .collect();
        // smooth: a threshold minus a sum of Gaussian blobs of either sign
        let mut g = grid_of(n, origin, h, |p| {
            0.2 - blobs
                .iter()
                .map(|(c, s, w)| w * (-(p - c).norm_squared() / (s * s)).exp())
                .sum::<f64>()
        });
        if kind != 2 {
            for v in g.data_mut() {
                *v = if kind == 0 {
                    rng.random::<f32>() * 2.0 - 1.0
                } else {
                    (rng.random_range(0..3u8) as f32 - 1.0) * 0.5
                };
            }
        }
        ambiguous_faces += count_ambiguous_faces(&g);
        if g.data().iter().all(|&v| v >= 0.0) {
            assert_eq!(extract(&g).num_faces(), 0, "seed {seed}: nothing inside");
            continue;
        }
        for (s, &collapse_below) in settings.iter().enumerate() {
            let what = format!("seed {seed} kind {kind} dims {n:?} collapse {collapse_below}");
            let mesh = extract_surface(&g, &ExtractOptions { collapse_below }).unwrap();
            let info = assert_closed_manifold(&mesh, &what);
            assert_separates(&mesh, &g, &what);
            let q = quality(&mesh);
            worst[s] = worst[s].min(q.min_angle);
            min_area[s] = min_area[s].min(q.min_area / (h * h));
            if s == 0 {
                multi_component += usize::from(info.components > 1);
                with_handles += usize::from(info.genus.is_some_and(|g| g > 0));
            }
            checked += 1;
        }
    }
    println!(
        "{checked} meshes of random fields: {ambiguous_faces} ambiguous faces in all, \
         {multi_component} fields with several components, {with_handles} with handles"
    );
    for (s, c) in settings.iter().enumerate() {
        println!(
            "  collapse_below {c}: smallest angle {:.4}°, smallest area {:.2e} h²",
            worst[s], min_area[s]
        );
    }
    assert!(ambiguous_faces > 10_000);
    assert!(multi_component > 100 && with_handles > 50);

    // manifold3d agrees on a few of the hardest (white noise, most ambiguous).
    for seed in [1000u64, 1001, 1002] {
        let mut rng = rng(seed);
        let mut g = grid_of([14, 13, 12], [0.0; 3], 1.0, |_| 0.0);
        for v in g.data_mut() {
            *v = rng.random::<f32>() * 2.0 - 1.0;
        }
        let mesh = extract(&g);
        let (status, _) = manifold3d(&mesh);
        assert_eq!(status, "NoError", "white noise seed {seed}");
    }
}

/// Rows of sign bits are 64-bit words and the grid is cut into slabs of z-layers: noise on grids
/// whose padded rows end right at, before or after a word boundary, and tall grids with many
/// slabs, stays closed, manifold and separating, with sliver collapse on and off.
#[test]
fn word_and_slab_boundaries_are_seamless() {
    let dims = [
        [62, 3, 4],
        [63, 2, 3],
        [64, 3, 2],
        [65, 2, 5],
        [126, 3, 3],
        [130, 2, 2],
        [4, 3, 70],
        [5, 6, 41],
    ];
    for (n, &d) in dims.iter().enumerate() {
        let mut rng = rng(500 + n as u64);
        let mut g = grid_of(d, [0.5, -1.0, 2.0], 0.7, |_| 0.0);
        for v in g.data_mut() {
            *v = rng.random::<f32>() * 2.0 - 1.0;
        }
        for collapse_below in [0.0, 0.1, 0.45] {
            let what = format!("dims {d:?} collapse {collapse_below}");
            let mesh = extract_surface(&g, &ExtractOptions { collapse_below }).unwrap();
            assert_closed_manifold(&mesh, &what);
            assert_separates(&mesh, &g, &what);
        }
    }
}

/// The real meshes' signed distance (exact distance within 3h, sign from the winding number,
/// |w| ≥ ½ inside, as libigl signs it) on a grid of 96 cells along the longest side: the surface
/// is closed, one outward genus-0 component for the vessels, and manifold3d agrees. For the two
/// closed inputs it stays on the input (vertices within 0.5h, on average within 0.02h) and keeps
/// the volume to 1%; the open ones are closed across their open ends, far from any input
/// triangle there, so only their figures are printed.
#[test]
fn real_meshes_give_closed_surfaces_on_the_input() {
    let Some(meshes) = real_meshes() else { return };
    for (name, mesh) in meshes {
        let (lo, hi) = bounding_box(&mesh);
        let ext = hi - lo;
        let h = ext.max() / 96.0;
        let origin = lo - Vector3::repeat(2.0 * h);
        let dims = [0, 1, 2].map(|i| (ext[i] / h).ceil() as usize + 5);
        let mut g = Grid3::new(dims, GridTransform::new(origin, h), 0.0).unwrap();
        let points: Vec<Point3<f64>> = (0..g.data().len())
            .map(|i| {
                let [a, b, c] = g.coords(i);
                g.world(a, b, c)
            })
            .collect();
        let bvh = MeshBvh::new(&mesh);
        let near = bvh.closest_points_within(&points, 3.0 * h);
        let w = WindingNumber::new(&mesh, WindingOptions::default()).winding_numbers(&points);
        for (i, v) in g.data_mut().iter_mut().enumerate() {
            let d = near[i]
                .as_ref()
                .map_or(3.0 * h, |c| (c.point - points[i]).norm());
            *v = if w[i].abs() >= 0.5 { -d } else { d } as f32;
        }
        let t = std::time::Instant::now();
        let out = extract(&g);
        let secs = t.elapsed().as_secs_f64();
        let info = assert_closed_manifold(&out, &name);
        assert_eq!(info.orientation, Orientation::Outward, "{name}");
        assert_eq!(manifold3d(&out).0, "NoError", "{name}");
        let d: Vec<f64> = bvh
            .closest_points(&out.vertices)
            .iter()
            .zip(&out.vertices)
            .map(|(c, p)| (c.point - p).norm() / h)
            .collect();
        let max = d.iter().copied().fold(0.0, f64::max);
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        let input = mesh_info(&mesh);
        let q = quality(&out);
        println!(
            "{name}: grid {dims:?}, h {h:.4}, {} faces in {:.1} ms, components {}, genus {:?}, \
             vertex→input max {max:.3} h, mean {mean:.4} h, volume {:.6e} (input {:?}), \
             min angle {:.2}° (1st percentile {:.2}°)",
            out.num_faces(),
            secs * 1e3,
            info.components,
            info.genus,
            info.volume.unwrap(),
            input.volume,
            q.min_angle,
            q.p1_angle
        );
        if let Some(v) = input.volume {
            assert!(max <= 0.5 && mean <= 0.02, "{name}: {max} {mean}");
            assert!(rel(info.volume.unwrap(), v) < 0.01, "{name}: volume");
        } else {
            assert_eq!((info.components, info.genus), (1, Some(0)), "{name}");
        }
    }
}

/// Faces of grid cells whose inside corners are diagonal (the cases the decider resolves).
fn count_ambiguous_faces(g: &Grid3) -> usize {
    let [nx, ny, nz] = g.dims();
    let s = |i: usize, j: usize, k: usize| g.get(i, j, k) < 0.0;
    let amb = |a: bool, b: bool, c: bool, d: bool| a == c && b == d && a != b;
    let mut count = 0;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if i + 1 < nx && j + 1 < ny {
                    count += amb(
                        s(i, j, k),
                        s(i + 1, j, k),
                        s(i + 1, j + 1, k),
                        s(i, j + 1, k),
                    ) as usize;
                }
                if i + 1 < nx && k + 1 < nz {
                    count += amb(
                        s(i, j, k),
                        s(i + 1, j, k),
                        s(i + 1, j, k + 1),
                        s(i, j, k + 1),
                    ) as usize;
                }
                if j + 1 < ny && k + 1 < nz {
                    count += amb(
                        s(i, j, k),
                        s(i, j + 1, k),
                        s(i, j + 1, k + 1),
                        s(i, j, k + 1),
                    ) as usize;
                }
            }
        }
    }
    count
}

/// Exact zeros count as outside: a sphere through grid nodes (x² + y² + z² − 25 on an integer
/// grid: zero at (±5, 0, 0), (±3, ±4, 0), …) stays closed, no vertex sits on a node (every one
/// is at least 1e-3 of an edge away), and no triangle is degenerate.
#[test]
fn exact_zeros_at_nodes_stay_closed() {
    let g = grid_of([15, 15, 15], [-7.0; 3], 1.0, |p| {
        p.coords.norm_squared() - 25.0
    });
    let zeros = g.data().iter().filter(|&&v| v == 0.0).count();
    assert!(zeros >= 30, "{zeros} zero nodes");
    for collapse_below in [0.0, 0.1] {
        let mesh = extract_surface(&g, &ExtractOptions { collapse_below }).unwrap();
        let what = format!("zeros, collapse {collapse_below}");
        let info = assert_closed_manifold(&mesh, &what);
        assert_eq!(info.euler_characteristic, 2, "{what}");
        assert_eq!(info.orientation, Orientation::Outward);
        assert_separates(&mesh, &g, &what);
        let nearest_node = mesh
            .vertices
            .iter()
            .map(|p| (p.coords - p.coords.map(f64::round)).norm())
            .fold(f64::INFINITY, f64::min);
        let q = quality(&mesh);
        println!(
            "{what}: {zeros} zero nodes, {} faces, nearest vertex to a node {nearest_node:.1e} h, \
             min angle {:.2}°, min area {:.2e} h²",
            mesh.num_faces(),
            q.min_angle,
            q.min_area
        );
        assert!(nearest_node >= 0.999e-3, "{what}: a vertex on a node");
    }
    // A grid of zeros has no inside: no surface.
    let zero = grid_of([5, 6, 7], [0.0; 3], 0.5, |_| 0.0);
    assert_eq!(extract(&zero).num_faces(), 0);
}

/// Where the inside reaches the grid's border the surface is closed by the padding (φ = +h one
/// node outside): an all-inside grid with φ = −h gives the box grown by h/2 on every side with
/// its edges and corners bevelled as marching cubes does (exact volume below), and a sphere cut
/// by the grid is closed, outward and separates the nodes.
#[test]
fn surface_touching_the_border_is_closed() {
    let h = 0.25;
    let dims = [7, 5, 4];
    let g = grid_of(dims, [1.0, 2.0, -3.0], h, |_| -0.25);
    let mesh = extract(&g);
    let info = assert_closed_manifold(&mesh, "all inside");
    assert_eq!(info.euler_characteristic, 2);
    assert_eq!(info.orientation, Orientation::Outward);
    // In voxels: the block between the nodes, half-voxel slabs on its sides, prisms of
    // cross-section 1/8 along its edges and tetrahedra of 1/48 at its corners.
    let l = dims.map(|n| n as f64 - 1.0);
    let expected = (l[0] * l[1] * l[2]
        + (l[1] * l[2] + l[0] * l[2] + l[0] * l[1])
        + 4.0 * (l[0] + l[1] + l[2]) / 8.0
        + 8.0 / 48.0)
        * h.powi(3);
    println!(
        "all-inside grid: volume {} (expected {expected})",
        info.volume.unwrap()
    );
    assert!(rel(info.volume.unwrap(), expected) < 1e-12);
    for axis in 0..3 {
        let lo = [1.0, 2.0, -3.0][axis] - h / 2.0;
        assert!((info.bbox_min[axis] - lo).abs() < 1e-12);
        let hi = lo + dims[axis] as f64 * h;
        assert!((info.bbox_max[axis] - hi).abs() < 1e-12);
    }

    // A sphere of radius 1.2 about a corner region of a [0, 1.5]³ grid: cut by three sides.
    let h = 0.05;
    let g = grid_of([31; 3], [0.0; 3], h, |p| {
        (p - Point3::new(0.4, 0.5, 0.3)).norm() - 1.2
    });
    let mesh = extract(&g);
    let info = assert_closed_manifold(&mesh, "cut sphere");
    assert_eq!(info.euler_characteristic, 2);
    assert_eq!(info.orientation, Orientation::Outward);
    assert_separates(&mesh, &g, "cut sphere");
    assert_eq!(manifold3d(&mesh).0, "NoError");
    // The closing caps lie at most one node spacing outside the grid.
    for axis in 0..3 {
        assert!(info.bbox_min[axis] >= -h && info.bbox_max[axis] <= 1.5 + h);
        assert!(
            info.bbox_min[axis] < 0.0,
            "cut on the low side of axis {axis}"
        );
    }
}

/// Every one-node grid and every 2×2×2 sign configuration (with random magnitudes) gives a
/// closed outward manifold: the smallest grids exercise the padding on all sides.
#[test]
fn every_cube_configuration_is_closed() {
    let single = grid_of([1, 1, 1], [0.0; 3], 1.0, |_| -0.3);
    let info = assert_closed_manifold(&extract(&single), "single node");
    assert_eq!((info.vertices, info.faces), (6, 8), "an octahedron");
    let mut rng = rng(7);
    for config in 1..256usize {
        for trial in 0..4 {
            let mut g = grid_of([2, 2, 2], [0.0; 3], 1.0, |_| 0.0);
            for c in 0..8 {
                let m = 0.05 + rng.random::<f32>();
                let v = if (config >> c) & 1 == 1 { -m } else { m };
                g.set(c & 1, (c >> 1) & 1, c >> 2, v);
            }
            for collapse_below in [0.0, 0.3] {
                let what = format!("config {config} trial {trial} collapse {collapse_below}");
                let mesh = extract_surface(&g, &ExtractOptions { collapse_below }).unwrap();
                assert_closed_manifold(&mesh, &what);
                assert_separates(&mesh, &g, &what);
            }
        }
    }
}

/// Sliver collapsing removes the tiny triangles near nodes without opening the surface or
/// moving it: fewer faces, same area and volume to 1e-4, better smallest angles.
#[test]
fn sliver_collapse_keeps_the_surface() {
    let h = 0.04;
    let c = Vector3::new(0.011, 0.023, -0.017);
    let g = grid_of([61; 3], [-1.2; 3], h, |p| (p.coords - c).norm() - 1.0);
    let plain = extract_surface(
        &g,
        &ExtractOptions {
            collapse_below: 0.0,
        },
    )
    .unwrap();
    let mut last: Option<(usize, f64)> = None;
    let (pi, pq) = (mesh_info(&plain), quality(&plain));
    println!(
        "collapse 0: {} faces, min angle {:.3}° (1st percentile {:.2}°, mean {:.1}°)",
        plain.num_faces(),
        pq.min_angle,
        pq.p1_angle,
        pq.mean_angle
    );
    for collapse_below in [0.05, 0.1, 0.2, 0.3] {
        let mesh = extract_surface(&g, &ExtractOptions { collapse_below }).unwrap();
        let what = format!("collapse {collapse_below}");
        let info = assert_closed_manifold(&mesh, &what);
        assert_eq!(info.euler_characteristic, 2);
        assert_separates(&mesh, &g, &what);
        let q = quality(&mesh);
        println!(
            "{what}: {} faces, min angle {:.3}° (1st percentile {:.2}°, mean {:.1}°), area {:+.2e}, \
             volume {:+.2e} relative to no collapse",
            mesh.num_faces(),
            q.min_angle,
            q.p1_angle,
            q.mean_angle,
            info.area / pi.area - 1.0,
            info.volume.unwrap() / pi.volume.unwrap() - 1.0
        );
        assert!(
            rel(info.area, pi.area) < 1e-4 && rel(info.volume.unwrap(), pi.volume.unwrap()) < 1e-4
        );
        assert!(
            q.p1_angle > pq.p1_angle,
            "{what}: no better than no collapse"
        );
        if let Some((faces, p1)) = last {
            assert!(mesh.num_faces() < faces && q.p1_angle > p1, "{what}");
        }
        last = Some((mesh.num_faces(), q.p1_angle));
    }
}

/// The output does not depend on the number of threads (fixed slabs), and φ = ±∞ is accepted.
#[test]
fn output_is_independent_of_thread_count() {
    let mut g = grid_of([40, 33, 27], [0.0; 3], 0.1, |p| {
        (p - Point3::new(2.0, 1.6, 1.3)).norm() - 1.1 + 0.2 * (7.0 * p.x).sin() * (5.0 * p.y).cos()
    });
    let many = extract(&g);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| extract(&g));
    assert_eq!(many, one);
    for v in g.data_mut() {
        *v = if *v < 0.0 {
            f32::NEG_INFINITY
        } else {
            f32::INFINITY
        };
    }
    let inf = extract(&g);
    assert_closed_manifold(&inf, "infinite values");
    assert_separates(&inf, &g, "infinite values");
}

#[test]
fn bad_input_is_refused() {
    let mut g = grid_of([4, 4, 4], [0.0; 3], 1.0, |p| p.x - 1.5);
    for bad in [-0.1, 0.5, f64::NAN, f64::INFINITY] {
        let err = extract_surface(
            &g,
            &ExtractOptions {
                collapse_below: bad,
            },
        )
        .unwrap_err();
        assert!(err.to_string().contains("collapse_below"), "{err}");
    }
    g.set(1, 2, 3, f32::NAN);
    let err = extract_surface(&g, &ExtractOptions::default()).unwrap_err();
    assert!(err.to_string().contains("NaN at node (1, 2, 3)"), "{err}");
}
