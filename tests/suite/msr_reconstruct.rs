//! Reconstruction by the level set: from a sphere's φ and details that move the surface by a
//! known normal displacement, the zero level set of the advected φ is the displaced surface;
//! tangential details (samples sliding along the surface) leave it where it was.

use nalgebra::{Point3, Vector3};
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::primitives::icosphere;
use vesselmsr::msr::reconstruct::{
    advect_back, rebuild_from_tangent_planes, AdvectOptions, Departure,
};
use vesselmsr::msr::sample::sample_for_spacing;

const R: f64 = 15.0;

fn sphere() -> (Grid3, Point3<f64>, Vec<Point3<f64>>) {
    let n = 48;
    let c = Point3::new(24.13, 23.71, 24.37);
    let mut g = Grid3::new([n; 3], GridTransform::new(Point3::origin(), 1.0), 0.0).unwrap();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                g.set(i, j, k, ((g.world(i, j, k) - c).norm() - R) as f32);
            }
        }
    }
    let mesh = icosphere(3, R, c);
    let samples = sample_for_spacing(&mesh, 1.0)
        .points
        .iter()
        .map(|p| c + (p - c).normalize() * R)
        .collect();
    (g, c, samples)
}

/// Largest |radius − expected(direction)| over the vertices of the zero level set of `phi`.
fn radial_error(phi: &Grid3, c: Point3<f64>, expected: impl Fn(&Vector3<f64>) -> f64) -> f64 {
    let mesh = extract_surface(phi, &ExtractOptions::default()).unwrap();
    mesh.vertices
        .iter()
        .map(|v| {
            let d = v - c;
            (d.norm() - expected(&d.normalize())).abs()
        })
        .fold(0.0, f64::max)
}

/// Advects `phi` back along `details` with both departure rules and checks the radial error
/// against `expected` (radius per direction).
fn advect_both_ways(
    phi: &Grid3,
    c: Point3<f64>,
    samples: &[Point3<f64>],
    details: &[Vector3<f64>],
    expected: impl Fn(&Vector3<f64>) -> f64 + Copy,
    limit: f64,
    what: &str,
) {
    for departure in [Departure::FootPoint, Departure::Arrival] {
        let opts = AdvectOptions {
            departure,
            ..Default::default()
        };
        let back = advect_back(phi, samples, details, &opts).unwrap();
        let err = radial_error(&back, c, expected);
        println!("{what}, {departure:?}: max radial error {err:.3} h");
        assert!(err < limit, "{what}, {departure:?}: {err}");
    }
}

#[test]
fn normal_details_move_the_surface_back() {
    let (phi, c, samples) = sphere();
    // W = X_i − X_{i−1} = (a + b n_z) n: S_{i−1} has radius R − a − b n_z.
    let (a, b) = (2.0, 1.5);
    let details: Vec<Vector3<f64>> = samples
        .iter()
        .map(|p| {
            let n = (p - c).normalize();
            n * (a + b * n.z)
        })
        .collect();
    let expected = |n: &Vector3<f64>| R - a - b * n.z;
    advect_both_ways(
        &phi,
        c,
        &samples,
        &details,
        expected,
        0.05,
        "normal details",
    );
}

#[test]
fn tangential_details_leave_the_surface() {
    let (phi, c, samples) = sphere();
    let details: Vec<Vector3<f64>> = samples
        .iter()
        .map(|p| {
            let n = (p - c).normalize();
            Vector3::z().cross(&n) * 1.0
        })
        .collect();
    // Sliding a sample by |W| along the sphere leaves it at radius √(R² + |W|²) ≈ R + 0.033h.
    advect_both_ways(
        &phi,
        c,
        &samples,
        &details,
        |_| R,
        0.06,
        "tangential details",
    );
}

#[test]
fn tangent_planes_of_the_previous_samples_rebuild_the_surface() {
    let (phi, c, samples) = sphere();
    // S_{i−1}: the sphere of radius R − a − b n_z, sampled at the displaced points with the
    // normals of that surface of revolution, r(θ) = R − a − b cos θ.
    let (a, b) = (2.0, 1.5);
    let mut previous = Vec::new();
    let mut normals = Vec::new();
    let mut details = Vec::new();
    for p in &samples {
        let n = (p - c).normalize();
        let r = R - a - b * n.z;
        previous.push(c + n * r);
        // Gradient of |x − c| − r(n_z): n − (dr/dn_z)·∇n_z = n + b (e_z − n_z n)/|x − c|.
        let g = n + (Vector3::z() - n * n.z) * (b / r);
        normals.push(g.normalize());
        details.push(p - (c + n * r));
    }
    // The samples are one voxel apart (no samples added as the decomposition does): they cover
    // the surface within half a voxel.
    let back = rebuild_from_tangent_planes(
        &phi,
        &previous,
        &normals,
        &details,
        &AdvectOptions {
            coverage: 0.5,
            ..AdvectOptions::default()
        },
    )
    .unwrap();
    let err = radial_error(&back, c, |n| R - a - b * n.z);
    println!("tangent planes: max radial error {err:.3} h");
    assert!(err < 0.05, "{err}");
}
