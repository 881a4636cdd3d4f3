//! Centrelines of shapes with a known axis and radius (issue 20): an open straight tube, a torus
//! segment, a helix tube and a Y, meshed from analytic distance functions. Away from the ends
//! and the junction (one radius), every centreline point lies within 0.5h of the true axis and
//! its inscribed radius within 0.5h of the true radius (h: the centreline's voxel); one branch
//! per tube; the Y's junction within one radius of the true one.

use nalgebra::{Point3, Vector3};
use vesselmsr::centerline::{compute_centerline, Centerline, CenterlineOptions, EndKind};
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::primitives::open_tube;
use vesselmsr::TriMesh;

/// The zero level set of `sdf` on a grid of voxel `h` over the box.
fn mesh_sdf(
    lo: Point3<f64>,
    hi: Point3<f64>,
    h: f64,
    sdf: impl Fn(&Point3<f64>) -> f64,
) -> TriMesh {
    let dims = [0, 1, 2].map(|a| ((hi[a] - lo[a]) / h).ceil() as usize + 1);
    let t = GridTransform::new(lo, h);
    let mut data = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = t.index_to_world(Vector3::new(i as f64, j as f64, k as f64));
                data.push(sdf(&p) as f32);
            }
        }
    }
    let phi = Grid3::from_data(dims, t, data).unwrap();
    extract_surface(&phi, &ExtractOptions::default()).unwrap()
}

fn seg_dist(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

fn polyline_dist(p: &Point3<f64>, line: &[Point3<f64>]) -> f64 {
    line.windows(2)
        .map(|w| seg_dist(p, &w[0], &w[1]))
        .fold(f64::INFINITY, f64::min)
}

/// Largest axis and radius errors (in h) over the centreline points that lie farther than
/// `margin` from every point of `keep_out` (ends, junctions); `axis` gives the true axis and
/// radius of the nearest tube at a point.
fn errors(
    cl: &Centerline,
    keep_out: &[Point3<f64>],
    margin: f64,
    axis: impl Fn(&Point3<f64>) -> (f64, f64),
) -> (f64, f64, usize) {
    let h = cl.voxel;
    let (mut ea, mut er, mut n) = (0.0f64, 0.0f64, 0);
    for b in &cl.branches {
        for (p, r) in b.points.iter().zip(&b.radius) {
            if keep_out.iter().any(|q| (p - q).norm() < margin) {
                continue;
            }
            let (d, rt) = axis(p);
            ea = ea.max(d / h);
            er = er.max((r - rt).abs() / h);
            n += 1;
        }
    }
    (ea, er, n)
}

fn centerline(mesh: &TriMesh) -> Centerline {
    compute_centerline(mesh, &CenterlineOptions::default())
        .unwrap()
        .0
}

#[test]
fn open_straight_tube() {
    let r = 3.0;
    let mesh = open_tube(r, 40.0, 64, 81);
    let cl = centerline(&mesh);
    println!("tube: {} branches, voxel {}", cl.branches.len(), cl.voxel);
    assert_eq!(cl.branches.len(), 1, "{:?}", cl.notices);
    let b = &cl.branches[0];
    assert_eq!((b.start, b.end), (EndKind::OpenEnd, EndKind::OpenEnd));
    let ends = [Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 0.0, 40.0)];
    for e in &ends {
        assert!(cl
            .endpoints
            .iter()
            .any(|q| (q.position - e).norm() < 0.5 * cl.voxel));
    }
    // The polygonal tube's inscribed radius is its apothem.
    let apothem = r * (std::f64::consts::PI / 64.0).cos();
    let (ea, er, n) = errors(&cl, &ends, r, |p| (p.x.hypot(p.y), apothem));
    println!("tube: axis {ea:.3}h radius {er:.3}h over {n} points");
    assert!(n > 50 && ea <= 0.5 && er <= 0.5, "axis {ea}h radius {er}h");
}

#[test]
fn torus_segment() {
    // A 180° arc of bend radius 12 and tube radius 3 in the z = 0 plane, cut flat at y = 0.
    let (rb, r) = (12.0, 3.0);
    let h = r / 8.0;
    let sdf = |p: &Point3<f64>| {
        let torus = ((p.x.hypot(p.y) - rb).powi(2) + p.z * p.z).sqrt() - r;
        torus.max(-p.y)
    };
    let lo = Point3::new(-rb - r - 1.0, -1.0, -r - 1.0);
    let hi = Point3::new(rb + r + 1.0, rb + r + 1.0, r + 1.0);
    let mesh = mesh_sdf(lo, hi, h, sdf);
    let cl = centerline(&mesh);
    println!("torus: {} branches, voxel {}", cl.branches.len(), cl.voxel);
    assert_eq!(
        cl.branches.len(),
        1,
        "{:?}",
        cl.branches.iter().map(|b| b.length).collect::<Vec<_>>()
    );
    let ends = [Point3::new(rb, 0.0, 0.0), Point3::new(-rb, 0.0, 0.0)];
    let (ea, er, n) = errors(&cl, &ends, r, |p| {
        (((p.x.hypot(p.y) - rb).powi(2) + p.z * p.z).sqrt(), r)
    });
    println!("torus: axis {ea:.3}h radius {er:.3}h over {n} points");
    assert!(n > 50 && ea <= 0.5 && er <= 0.5, "axis {ea}h radius {er}h");
}

#[test]
fn helix_tube() {
    // Two turns of a helix of radius 10 and pitch 16, tube radius 2.5, rounded ends.
    let (a, pitch, r) = (10.0, 16.0, 2.5);
    let helix: Vec<Point3<f64>> = (0..=800)
        .map(|i| {
            let t = i as f64 / 800.0 * 4.0 * std::f64::consts::PI;
            Point3::new(
                a * t.cos(),
                a * t.sin(),
                pitch * t / (2.0 * std::f64::consts::PI),
            )
        })
        .collect();
    let h = r / 8.0;
    let lo = Point3::new(-a - r - 1.0, -a - r - 1.0, -r - 1.0);
    let hi = Point3::new(a + r + 1.0, a + r + 1.0, 2.0 * pitch + r + 1.0);
    let mesh = mesh_sdf(lo, hi, h, |p| polyline_dist(p, &helix) - r);
    let cl = centerline(&mesh);
    println!("helix: {} branches, voxel {}", cl.branches.len(), cl.voxel);
    assert_eq!(cl.branches.len(), 1);
    let ends = [helix[0], *helix.last().unwrap()];
    let (ea, er, n) = errors(&cl, &ends, 2.0 * r, |p| (polyline_dist(p, &helix), r));
    println!("helix: axis {ea:.3}h radius {er:.3}h over {n} points");
    assert!(n > 50 && ea <= 0.5 && er <= 0.5, "axis {ea}h radius {er}h");
}

#[test]
fn y_bifurcation() {
    // A parent of radius 3 along z from -24 to 0, two daughters of radius 2.4 from the origin
    // at ±35° from the z axis, 22 long; capsule union.
    let (rp, rd) = (3.0, 2.4);
    let o = Point3::origin();
    let p0 = Point3::new(0.0, 0.0, -24.0);
    let ang = 35f64.to_radians();
    let d1 = Point3::new(22.0 * ang.sin(), 0.0, 22.0 * ang.cos());
    let d2 = Point3::new(-22.0 * ang.sin(), 0.0, 22.0 * ang.cos());
    let sdf = |p: &Point3<f64>| {
        (seg_dist(p, &p0, &o) - rp)
            .min(seg_dist(p, &o, &d1) - rd)
            .min(seg_dist(p, &o, &d2) - rd)
    };
    let h = rd / 8.0;
    let mesh = mesh_sdf(
        Point3::new(-20.0, -5.0, -29.0),
        Point3::new(20.0, 5.0, 22.0),
        h,
        sdf,
    );
    let cl = centerline(&mesh);
    println!(
        "Y: {} branches, {} junctions, voxel {}",
        cl.branches.len(),
        cl.junctions.len(),
        cl.voxel
    );
    assert_eq!(cl.branches.len(), 3);
    assert_eq!(cl.junctions.len(), 1);
    let j = cl.junctions[0].position;
    println!(
        "Y: junction {:.3} from the true one (radius {rp})",
        (j - o).norm()
    );
    assert!((j - o).norm() <= rp);
    let keep = [p0, d1, d2, o];
    let (ea, er, n) = errors(&cl, &keep, 2.0 * rp, |p| {
        let a = (seg_dist(p, &p0, &o), rp);
        let b = (seg_dist(p, &o, &d1), rd);
        let c = (seg_dist(p, &o, &d2), rd);
        [a, b, c]
            .into_iter()
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .unwrap()
    });
    println!("Y: axis {ea:.3}h radius {er:.3}h over {n} points");
    assert!(n > 50 && ea <= 0.5 && er <= 0.5, "axis {ea}h radius {er}h");
}
