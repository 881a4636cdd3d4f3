//! How a repaired surface is judged against the truth inside the damaged region D (benches
//! inpaint and repair_real): the symmetric Hausdorff distance restricted to D, from dense
//! barycentric samples of each surface inside D to the other whole surface (BVH closest point),
//! and the volume in D (`volume_in_ball`); plus area-weighted random surface points and the
//! small number helpers both benches print with.

use nalgebra::Point3;
use vesselmsr::bvh::MeshBvh;
use vesselmsr::inpaint::phantom::SplitMix;
use vesselmsr::inpaint::region::Ball;
use vesselmsr::report::stenosis::volume_in_ball;
use vesselmsr::TriMesh;

/// Barycentric sample points per triangle (vertices, edge midpoints, centroid, three more).
pub const BARY: [[f64; 3]; 10] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
    [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
    [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
];

/// Whether `p` lies inside one of the balls of D.
pub fn in_region(balls: &[Ball], p: &Point3<f64>) -> bool {
    balls.iter().any(|b| (p - b.center).norm() < b.radius)
}

/// Largest distance from the samples of `a` inside D to the surface `b` (None when `a` has none).
pub fn directed_hausdorff(a: &TriMesh, b: &MeshBvh, balls: &[Ball]) -> Option<f64> {
    let mut worst: Option<f64> = None;
    for f in 0..a.num_faces() {
        let [p, q, r] = a.triangle(f);
        for w in BARY {
            let s = Point3::from(p.coords * w[0] + q.coords * w[1] + r.coords * w[2]);
            if in_region(balls, &s) {
                let d = b.closest_point(&s).distance;
                worst = Some(worst.map_or(d, |x: f64| x.max(d)));
            }
        }
    }
    worst
}

/// Symmetric Hausdorff distance between `output` and `truth` restricted to D, world units: the
/// larger of the two directed distances (either alone when the other surface has no sample in
/// D); None for an output without triangles or when neither surface reaches into D.
pub fn hausdorff_in(output: &TriMesh, truth: &TriMesh, balls: &[Ball]) -> Option<f64> {
    if output.num_faces() == 0 {
        return None;
    }
    let to_truth = directed_hausdorff(output, &MeshBvh::new(truth), balls);
    let to_output = directed_hausdorff(truth, &MeshBvh::new(output), balls);
    match (to_truth, to_output) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    }
}

/// Volume of the solid bounded by `mesh` inside D (Σ over the balls of `volume_in_ball`).
pub fn volume_in(mesh: &TriMesh, balls: &[Ball]) -> f64 {
    balls.iter().map(|b| volume_in_ball(mesh, b)).sum()
}

/// Random points on a surface, each triangle drawn with the probability of its area.
pub struct AreaSampler {
    areas: Vec<f64>,
    total: f64,
}

impl AreaSampler {
    pub fn new(mesh: &TriMesh) -> AreaSampler {
        let areas: Vec<f64> = (0..mesh.num_faces())
            .map(|f| 0.5 * mesh.face_normal_raw(f).norm())
            .collect();
        let total = areas.iter().sum();
        AreaSampler { areas, total }
    }

    /// A point of `mesh` (the mesh the sampler was built on): an area-weighted face, then a
    /// uniform barycentric point in it.
    pub fn draw(&self, mesh: &TriMesh, rng: &mut SplitMix) -> Point3<f64> {
        let mut t = rng.uniform() * self.total;
        let mut f = 0;
        while f + 1 < self.areas.len() && t > self.areas[f] {
            t -= self.areas[f];
            f += 1;
        }
        let (mut u, mut v) = (rng.uniform(), rng.uniform());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let [a, b, c] = mesh.triangle(f);
        Point3::from(a.coords * (1.0 - u - v) + b.coords * u + c.coords * v)
    }
}

/// `x` with 4 significant digits (the meshes' units range from metres to millimetres).
pub fn sig(x: f64) -> String {
    let digits = if x == 0.0 || !x.is_finite() {
        0
    } else {
        (3 - x.abs().log10().floor() as i64).max(0) as usize
    };
    format!("{x:.digits$}")
}

/// Median of the finite values (NaN when there is none).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    median_all(v)
}

/// Median of all the values, infinities included (NaN for none).
pub fn median_all(v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    vesselmsr::inpaint::region::median(v)
}
