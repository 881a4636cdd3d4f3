//! voxelize: mesh → signed distance grid φ (negative inside). Analytic sphere and torus, brute
//! force distances, signs at every node against the winding number, inward meshes, open ends
//! (the lumen is the inside), agreement with libigl's signed distance on the real meshes, and the
//! errors.

use crate::common;
use common::*;

use nalgebra::{Point3, Vector3};
use rand::seq::SliceRandom;
use rand::RngExt;
use vesselmsr::bvh::brute::{closest_point_brute, winding_number_exact};
use vesselmsr::bvh::{WindingNumber, WindingOptions};
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::levelset::voxelize::{
    voxelize, voxelize_with_report, FarFill, VoxelizeOptions, VoxelizeReport,
};
use vesselmsr::mesh::cap::{cap_holes, CapOptions};
use vesselmsr::mesh::measures::{bounding_box, mean_edge_length, signed_volume};
use vesselmsr::mesh::primitives::{icosphere, open_tube, torus};
use vesselmsr::{Error, TriMesh};

/// Band half-width of the default options, voxels.
const BAND: f64 = 3.0;

/// The default grid rule of the issue (the grid module will own it): h = min(mean edge / 2,
/// longest extent / `cells`), the bounding box padded by 4 voxels on every side.
fn default_layout(mesh: &TriMesh, cells: f64) -> ([usize; 3], GridTransform) {
    let (lo, hi) = bounding_box(mesh);
    let ext = hi - lo;
    let h = (mean_edge_length(mesh) / 2.0).min(ext.max() / cells);
    layout_around(lo, hi, h, 4.0)
}

/// Grid of voxel `h` covering [lo, hi] padded by `pad` voxels.
fn layout_around(
    lo: Point3<f64>,
    hi: Point3<f64>,
    h: f64,
    pad: f64,
) -> ([usize; 3], GridTransform) {
    let ext = hi - lo;
    let dims = [0, 1, 2].map(|a| (ext[a] / h).ceil() as usize + 1 + 2 * pad as usize);
    (dims, GridTransform::new(lo - Vector3::repeat(pad * h), h))
}

fn run(
    mesh: &TriMesh,
    layout: ([usize; 3], GridTransform),
    opts: &VoxelizeOptions,
) -> (Grid3, VoxelizeReport) {
    voxelize_with_report(mesh, layout.0, layout.1, opts).expect("voxelize")
}

/// World positions of every node.
fn nodes(grid: &Grid3) -> impl Iterator<Item = (usize, Point3<f64>)> + '_ {
    (0..grid.data().len()).map(|idx| {
        let [i, j, k] = grid.coords(idx);
        (idx, grid.world(i, j, k))
    })
}

fn in_band(grid: &Grid3, idx: usize) -> bool {
    (grid.data()[idx].abs() as f64) < BAND * grid.voxel() * (1.0 - 1e-6)
}

#[test]
fn sphere_matches_analytic_distance_in_band() {
    let h = 0.5;
    let r = 20.0 * h;
    let c = Point3::new(0.31 * h, -0.17 * h, 0.43 * h);
    let mesh = icosphere(5, r, c);
    // Chord error: the polyhedron lies inside the sphere, and the farthest the sphere gets from
    // it is r minus the smallest distance from the centre to a face plane.
    let chord = (0..mesh.num_faces())
        .map(|f| {
            let [a, _, _] = mesh.triangle(f);
            let n = mesh.face_normal_raw(f).normalize();
            r - n.dot(&(a - c)).abs()
        })
        .fold(0.0f64, f64::max);
    println!(
        "icosphere(5): {} faces, chord error {:.5} h",
        mesh.num_faces(),
        chord / h
    );
    assert!(chord < 0.01 * h, "chord error {chord}");

    let lo = c - Vector3::repeat(r);
    let hi = c + Vector3::repeat(r);
    let (grid, rep) = run(
        &mesh,
        layout_around(lo, hi, h, 6.0),
        &VoxelizeOptions::default(),
    );
    let bw = BAND * h;
    let (mut worst, mut band) = (0.0f64, 0usize);
    for (idx, p) in nodes(&grid) {
        let exact = (p - c).norm() - r;
        let phi = grid.data()[idx] as f64;
        if in_band(&grid, idx) {
            band += 1;
            worst = worst.max((phi - exact).abs());
        } else {
            // Outside the band: the clamp, with the sign of the sphere.
            assert_eq!(phi.abs(), (bw as f32) as f64, "far value at {p}");
            assert!(
                exact.abs() > bw - chord - 1e-9,
                "node at {exact} from the sphere left out of the band"
            );
        }
        if exact.abs() > chord {
            assert_eq!(
                phi < 0.0,
                exact < 0.0,
                "sign at {p}: φ {phi}, exact {exact}"
            );
        }
    }
    println!(
        "sphere r = 20h: {band} band nodes, max |φ − (|x − c| − r)| = {:.5} h (bound 0.05 h + chord {:.5} h); {} winding numbers for {} nodes",
        worst / h,
        chord / h,
        rep.winding_evaluations(),
        rep.nodes
    );
    assert!(band > 10_000);
    assert!(worst <= 0.05 * h + chord, "max error {worst}");
    // The sign needs the winding number at a small fraction of the nodes.
    assert!(rep.winding_evaluations() * 20 < rep.nodes, "{rep:?}");
}

#[test]
fn band_and_far_distances_match_brute_force() {
    let mut meshes = vec![(
        "torus".to_string(),
        torus(10.0, 3.0, 48, 24, Point3::new(0.2, -0.1, 0.3)),
    )];
    if let Some(dir) = real_dir() {
        meshes.push((
            "ica_aneurysm_c0015.stl".into(),
            read_real(&dir, "ica_aneurysm_c0015.stl"),
        ));
    }
    let mut rng = rng(7);
    for (name, mesh) in meshes {
        let layout = default_layout(&mesh, 96.0);
        let opts = VoxelizeOptions {
            far: FarFill::Exact,
            ..VoxelizeOptions::default()
        };
        let (exact, _) = run(&mesh, layout, &opts);
        let (clamped, _) = run(&mesh, layout, &VoxelizeOptions::default());
        let h = exact.voxel();
        // The band and the sign do not depend on the far fill.
        for (a, b) in exact.data().iter().zip(clamped.data()) {
            assert_eq!(a < &0.0, b < &0.0);
            if (a.abs() as f64) <= BAND * h {
                assert_eq!(a, b);
            }
        }
        let n = exact.data().len();
        let (mut band, mut far, mut worst) = (0, 0, 0.0f64);
        while band < 1000 || far < 300 {
            let idx = rng.random_range(0..n);
            let [i, j, k] = exact.coords(idx);
            let p = exact.world(i, j, k);
            let d = closest_point_brute(&mesh, &p).distance;
            let phi = exact.data()[idx] as f64;
            worst = worst.max((phi.abs() - d).abs());
            assert!(
                (phi.abs() - d).abs() <= 1e-6 * h.max(d),
                "{name}: |φ| {phi} vs brute {d} at {p}"
            );
            let c = clamped.data()[idx] as f64;
            if d <= BAND * h * (1.0 - 1e-6) {
                band += 1;
                assert_eq!(c, phi, "{name}: band node at {d} clamped");
            } else {
                far += 1;
                assert_eq!(c.abs(), (BAND * h) as f32 as f64);
            }
        }
        println!(
            "{name}: {band} band and {far} far nodes match brute force (max |Δ| {:.2e} h)",
            worst / h
        );
    }
}

/// Inside a torus about the z axis through `c` (major radius R, minor radius r).
fn torus_signed(p: &Point3<f64>, c: &Point3<f64>, big: f64, small: f64) -> f64 {
    let q = p - c;
    let rho = (q.x * q.x + q.y * q.y).sqrt() - big;
    (rho * rho + q.z * q.z).sqrt() - small
}

#[test]
fn torus_signs_everywhere_match_analytic() {
    let c = Point3::new(0.2, -0.1, 0.3);
    let (big, small) = (10.0, 3.0);
    let mesh = torus(big, small, 96, 48, c);
    // Chord error of the tube: sagitta of the two polygons.
    let chord = small * (1.0 - (std::f64::consts::PI / 48.0).cos())
        + (big + small) * (1.0 - (std::f64::consts::PI / 96.0).cos());
    for cells in [40.0, 100.0] {
        let layout = default_layout(&mesh, cells);
        let (grid, rep) = run(&mesh, layout, &VoxelizeOptions::default());
        let mut checked = 0;
        for (idx, p) in nodes(&grid) {
            let exact = torus_signed(&p, &c, big, small);
            if exact.abs() > chord {
                checked += 1;
                assert_eq!(
                    grid.data()[idx] < 0.0,
                    exact < 0.0,
                    "sign at {p} (exact {exact})"
                );
            }
        }
        println!(
            "torus, {cells} cells: {checked} nodes' signs match; {} winding numbers ({} seeds, {} pockets, {} fronts)",
            rep.winding_evaluations(),
            rep.seed_evaluations,
            rep.pocket_evaluations,
            rep.front_evaluations
        );
    }
}

/// Whether `p` is inside by the exact winding number (every triangle's solid angle), and how far
/// |w| is from ½.
fn exact_inside(mesh: &TriMesh, p: &Point3<f64>) -> (bool, f64) {
    let w = winding_number_exact(mesh, p).abs();
    (w >= 0.5, (w - 0.5).abs())
}

/// Signs of every node against |w| ≥ ½ evaluated at every node (fast winding number, and the
/// exact one where the fast one is within 0.02 of ½): the flood and the fronts must reproduce it,
/// but for nodes where the exact |w| is within 1e-4 of ½.
fn assert_signs_match_winding_everywhere(
    name: &str,
    mesh: &TriMesh,
    layout: ([usize; 3], GridTransform),
) -> VoxelizeReport {
    let opts = VoxelizeOptions::default();
    let (grid, rep) = run(mesh, layout, &opts);
    let wn = WindingNumber::new(mesh, opts.winding);
    let points: Vec<Point3<f64>> = nodes(&grid).map(|(_, p)| p).collect();
    let w = wn.winding_numbers(&points);
    let (mut wrong, mut ties, mut exact) = (Vec::new(), 0, 0);
    for (i, p) in points.iter().enumerate() {
        let ours = grid.data()[i] < 0.0;
        let (inside, margin) = if (w[i].abs() - 0.5).abs() < 0.02 {
            exact += 1;
            exact_inside(mesh, p)
        } else {
            (w[i].abs() >= 0.5, 1.0)
        };
        if ours != inside {
            if margin < 1e-4 {
                ties += 1;
            } else {
                wrong.push(i);
            }
        }
    }
    println!(
        "{name}: {} nodes, {} inside, signs differing from |w| ≥ ½ at every node: {} (and {ties} within 1e-4 of ½; {exact} nodes needed the exact w); {} winding numbers: {} seeds, {} pockets, {} fronts in {} rounds, {} refined",
        rep.nodes,
        rep.inside_nodes,
        wrong.len(),
        rep.winding_evaluations(),
        rep.seed_evaluations,
        rep.pocket_evaluations,
        rep.front_evaluations,
        rep.front_rounds,
        rep.refined_evaluations
    );
    for &i in wrong.iter().take(5) {
        println!("  {}: w = {}, φ = {}", points[i], w[i], grid.data()[i]);
    }
    assert!(wrong.is_empty(), "{name}: {} signs differ", wrong.len());
    assert!(ties < 10, "{name}: {ties} ties");
    rep
}

#[test]
fn open_tube_inside_is_the_lumen() {
    // A straight vessel of radius 8h cut open at both ends, in a grid reaching 10h past them.
    let h = 0.25;
    let (radius, length) = (8.0 * h, 64.0 * h);
    let tube = open_tube(radius, length, 64, 65);
    let lo = Point3::new(-radius, -radius, 0.0);
    let hi = Point3::new(radius, radius, length);
    let layout = layout_around(lo, hi, h, 10.0);
    let rep = assert_signs_match_winding_everywhere("open tube", &tube, layout);
    assert!(!rep.closed);
    assert!(rep.front_evaluations > 0, "open ends need fronts");
    // The inside is the lumen: every inside node lies in the cylinder, and every node of the
    // cylinder farther than a voxel from its wall and a radius from its ends is inside.
    let (grid, _) = run(&tube, layout, &VoxelizeOptions::default());
    let (mut core, mut cylinder) = (0, 0);
    for (idx, p) in nodes(&grid) {
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let inside = grid.data()[idx] < 0.0;
        let in_cylinder = rho < radius && p.z > 0.0 && p.z < length;
        cylinder += in_cylinder as usize;
        if inside {
            assert!(in_cylinder, "inside node {p} out of the lumen");
        }
        if rho < radius - h && p.z > radius && p.z < length - radius {
            core += 1;
            assert!(inside, "lumen node {p} outside");
        }
    }
    let ratio = rep.inside_nodes as f64 / cylinder as f64;
    println!(
        "open tube: {} inside nodes ({core} in the core) of the {cylinder} nodes in the cylinder (ratio {ratio:.4})",
        rep.inside_nodes
    );
    assert!(ratio > 0.98, "ratio {ratio}");
}

#[test]
fn real_open_meshes_signs_match_winding_everywhere() {
    let Some(dir) = real_dir() else { return };
    for file in ["ica_aneurysm_c0015.stl", "aorta_abdominal_open_ends.stl"] {
        let mesh = read_real(&dir, file);
        assert_signs_match_winding_everywhere(file, &mesh, default_layout(&mesh, 64.0));
    }
}

#[test]
fn inward_mesh_gives_the_same_field() {
    let sphere = icosphere(3, 5.0, Point3::new(0.1, 0.2, 0.3));
    let mut inward = sphere.clone();
    inward.flip_faces();
    let layout = default_layout(&sphere, 40.0);
    let (a, ra) = run(&sphere, layout, &VoxelizeOptions::default());
    let (b, _) = run(&inward, layout, &VoxelizeOptions::default());
    assert!(ra.inside_nodes > 1000);
    assert_eq!(a.data(), b.data());

    let Some(dir) = real_dir() else { return };
    let capped = read_real(&dir, "aorta_abdominal_capped.stl");
    assert!(signed_volume(&capped) < 0.0, "the file is inward-facing");
    let mut outward = capped.clone();
    outward.flip_faces();
    let layout = default_layout(&capped, 96.0);
    let (a, ra) = run(&capped, layout, &VoxelizeOptions::default());
    let (b, _) = run(&outward, layout, &VoxelizeOptions::default());
    let volume = ra.inside_nodes as f64 * a.voxel().powi(3);
    println!(
        "inward capped aorta: inside volume {volume:.1} vs |signed volume| {:.1}",
        -signed_volume(&capped)
    );
    assert!(rel(volume, -signed_volume(&capped)) < 0.02);
    assert_eq!(a.data(), b.data());
}

#[test]
fn open_aorta_inside_is_the_capped_lumen() {
    let Some(dir) = real_dir() else { return };
    let open = read_real(&dir, "aorta_abdominal_open_ends.stl");
    let (capped, report) = cap_holes(&open, &CapOptions::default()).expect("cap");
    let layout = default_layout(&open, 256.0);
    let (grid, rep) = run(&open, layout, &VoxelizeOptions::default());
    let h = grid.voxel();
    let volume = rep.inside_nodes as f64 * h.powi(3);
    let capped_volume = signed_volume(&capped).abs();
    println!(
        "open aorta: {}×{}×{} grid, h = {h:.4}: inside volume {volume:.1} vs capped mesh {capped_volume:.1} (rel {:.4}); {} front evaluations",
        layout.0[0],
        layout.0[1],
        layout.0[2],
        rel(volume, capped_volume),
        rep.front_evaluations
    );
    assert!(rel(volume, capped_volume) < 0.02);
    // Node by node: inside the open mesh iff inside the capped one, except next to the caps
    // (where the |w| = ½ surface and the planar cap part).
    let cap_faces: Vec<usize> = report.cap_faces.clone().collect();
    let caps = TriMesh::new(
        capped.vertices.clone(),
        cap_faces.iter().map(|&f| capped.faces[f]).collect(),
    );
    let wn = WindingNumber::new(&capped, WindingOptions::default());
    let mut rng = rng(11);
    let n = grid.data().len();
    let (mut checked, mut near_cap) = (0, 0);
    for _ in 0..20_000 {
        let idx = rng.random_range(0..n);
        let [i, j, k] = grid.coords(idx);
        let p = grid.world(i, j, k);
        let inside_capped = wn.winding_number(&p).abs() >= 0.5;
        checked += 1;
        if inside_capped != (grid.data()[idx] < 0.0) {
            near_cap += 1;
            let d = closest_point_brute(&caps, &p).distance;
            assert!(
                d < 2.0 * h,
                "node {p} differs from the capped mesh {d:.3} from its caps"
            );
        }
    }
    println!("open aorta: {checked} random nodes, {near_cap} differ from the capped mesh (all within 2h of a cap)");
}

#[test]
fn real_meshes_agree_with_libigl() {
    let Some(meshes) = real_meshes() else { return };
    let oracle = oracle();
    let dir = real_dir().unwrap();
    for (file, mesh) in meshes {
        let layout = default_layout(&mesh, 256.0);
        let t = std::time::Instant::now();
        let (grid, rep) = run(&mesh, layout, &VoxelizeOptions::default());
        let seconds = t.elapsed().as_secs_f64();
        let h = grid.voxel();
        let mut rng = rng(3);
        let mut band: Vec<usize> = (0..grid.data().len())
            .filter(|&i| in_band(&grid, i))
            .collect();
        let band_count = band.len();
        let (picked, _) = band.partial_shuffle(&mut rng, 10_000);
        let points: Vec<Point3<f64>> = picked
            .iter()
            .map(|&idx| {
                let [i, j, k] = grid.coords(idx);
                grid.world(i, j, k)
            })
            .collect();
        let (igl, _) = oracle.query("signed_distance", &dir.join(&file), &points, 1);
        // Sign disagreements must be where |w| is so close to ½ (across open ends) that libigl's
        // fast winding number cannot tell; there the exact w must side with us.
        let check_sign = |ours: bool, theirs: bool, p: &Point3<f64>, what: &str| -> usize {
            if ours == theirs {
                return 0;
            }
            let (inside, margin) = exact_inside(&mesh, p);
            println!("  {file}: {what} sign differs at {p}: ours inside {ours}, libigl {theirs}, exact |w| − ½ within {margin:.1e}");
            assert!(
                margin < 5e-3,
                "{file}: {what} sign disagreement at {p}, exact |w| {margin} from ½"
            );
            assert!(
                inside == ours || margin < 1e-4,
                "{file}: exact w sides with libigl at {p}"
            );
            1
        };
        let (mut worst, mut signs) = (0.0f64, 0);
        for ((&idx, &s), p) in picked.iter().zip(&igl).zip(&points) {
            let phi = grid.data()[idx] as f64;
            worst = worst.max((phi.abs() - s.abs()).abs());
            if phi != 0.0 {
                signs += check_sign(phi < 0.0, s < 0.0, p, "band");
            }
        }
        // Signs far from the surface against libigl's fast winding number.
        let far: Vec<usize> = (0..3000)
            .map(|_| loop {
                let idx = rng.random_range(0..grid.data().len());
                if !in_band(&grid, idx) {
                    break idx;
                }
            })
            .collect();
        let far_points: Vec<Point3<f64>> = far
            .iter()
            .map(|&idx| {
                let [i, j, k] = grid.coords(idx);
                grid.world(i, j, k)
            })
            .collect();
        let (w, _) = oracle.query("winding", &dir.join(&file), &far_points, 1);
        let mut far_signs = 0;
        for ((&idx, &w), p) in far.iter().zip(&w).zip(&far_points) {
            far_signs += check_sign(grid.data()[idx] < 0.0, w.abs() >= 0.5, p, "far");
        }
        println!(
            "{file}: grid {:?}, h = {h:.5}, {band_count} band nodes, voxelize {seconds:.2} s; 10,000 band nodes: max ||φ| − |libigl|| = {:.2e} h, sign disagreements {signs}; 3000 far nodes: sign disagreements with libigl's winding number {far_signs}; {} inside nodes",
            layout.0,
            worst / h,
            rep.inside_nodes
        );
        assert!(worst <= 1e-4 * h, "{file}: {worst}");
    }
}

#[test]
fn bad_input_is_refused() {
    let layout = (
        [20, 20, 20],
        GridTransform::new(Point3::new(-5.0, -5.0, -5.0), 0.5),
    );
    let opts = VoxelizeOptions::default();
    // No triangles.
    let empty = TriMesh::new(vec![], vec![]);
    let err = voxelize(&empty, layout.0, layout.1, &opts).unwrap_err();
    assert!(matches!(err, Error::InvalidMesh(_)), "{err}");
    // A flat disc encloses nothing.
    let n = 64;
    let mut vertices = vec![Point3::new(0.1, 0.05, 0.13)];
    let mut faces = Vec::new();
    for i in 0..n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        vertices.push(Point3::new(0.1 + 4.0 * t.cos(), 0.05 + 4.0 * t.sin(), 0.13));
        faces.push([0, 1 + i as u32, 1 + ((i + 1) % n) as u32]);
    }
    let disc = TriMesh::new(vertices, faces);
    let err = voxelize(&disc, layout.0, layout.1, &opts).unwrap_err();
    println!("disc: {err}");
    assert!(
        matches!(&err, Error::Geometry(m) if m.starts_with("mesh encloses no volume")),
        "{err}"
    );
    // A grid that misses the mesh.
    let sphere = icosphere(2, 2.0, Point3::new(100.0, 0.0, 0.0));
    let err = voxelize(&sphere, layout.0, layout.1, &opts).unwrap_err();
    assert!(
        err.to_string().starts_with("mesh encloses no volume"),
        "{err}"
    );
    // Bad options and grids.
    let sphere = icosphere(2, 2.0, Point3::origin());
    for bad in [
        VoxelizeOptions { band: 0.5, ..opts },
        VoxelizeOptions {
            band: f64::NAN,
            ..opts
        },
        VoxelizeOptions {
            seed_stride: 0,
            ..opts
        },
    ] {
        let err = voxelize(&sphere, layout.0, layout.1, &bad).unwrap_err();
        assert!(matches!(err, Error::Geometry(_)), "{err}");
    }
    for transform in [
        GridTransform::new(Point3::origin(), 0.0),
        GridTransform::new(Point3::origin(), -1.0),
    ] {
        assert!(voxelize(&sphere, layout.0, transform, &opts).is_err());
    }
    assert!(voxelize(&sphere, [0, 10, 10], layout.1, &opts).is_err());
    // The sphere itself voxelizes.
    let grid = voxelize(&sphere, layout.0, layout.1, &opts).unwrap();
    assert!(grid.data().iter().any(|&v| v < 0.0));
}
