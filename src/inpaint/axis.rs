//! The vessel axis at a region D, estimated from the intact surface around it. Where a vessel
//! crosses ∂D its surface leaves a boundary loop once D is cut out (`stitch::cut_out`,
//! `branch_crossings`): a tube
//! through D leaves two, and the chord between their centroids is its axis across D; a junction
//! leaves three or more, each with its own axis. A chopped wall leaves one; there the axis is the
//! direction least represented among the surface normals (on a tube every normal is
//! perpendicular to the axis): the eigenvector of the smallest eigenvalue of the area-weighted
//! normal covariance Σ A n nᵀ of the triangles in a shell just outside the ball (`estimate_axis`).

use super::region::Ball;
use super::stitch::CutOut;
use crate::TriMesh;
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};

/// The axis direction (unit, sign arbitrary) of the vessel through `ball`, from the triangles
/// whose centroid lies between 1 and `shell` ball radii from its centre (`shell` > 1). None when
/// no triangle lies there.
pub fn estimate_axis(mesh: &TriMesh, ball: &Ball, shell: f64) -> Option<Vector3<f64>> {
    let samples = normal_samples(mesh, |_, centroid| {
        (1.0..=shell).contains(&((centroid - ball.center).norm() / ball.radius))
    });
    least_normal_axis(&samples)
}

/// (centroid, unit normal, twice the area) of the non-degenerate triangles `keep` selects (given
/// the corners and the centroid).
fn normal_samples(
    mesh: &TriMesh,
    keep: impl Fn(&[Point3<f64>; 3], &Point3<f64>) -> bool,
) -> Vec<(Point3<f64>, Vector3<f64>, f64)> {
    (0..mesh.num_faces())
        .filter_map(|f| {
            let corners = mesh.triangle(f);
            let [a, b, c] = corners;
            let centroid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            if !keep(&corners, &centroid) {
                return None;
            }
            let raw = mesh.face_normal_raw(f);
            let area2 = raw.norm();
            (area2 > 0.0).then(|| (centroid, raw / area2, area2))
        })
        .collect()
}

/// The direction least represented among the normals: the eigenvector of the smallest eigenvalue
/// of Σ A n nᵀ. None without samples.
fn least_normal_axis(samples: &[(Point3<f64>, Vector3<f64>, f64)]) -> Option<Vector3<f64>> {
    if samples.is_empty() {
        return None;
    }
    least_eigenvector(
        samples
            .iter()
            .fold(Matrix3::zeros(), |m, (_, n, w)| m + n * n.transpose() * *w),
    )
}

/// A branch of the vessel where it crosses ∂D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchCrossing {
    /// Centroid of the boundary loop, world units.
    pub center: Point3<f64>,
    /// Normal of the loop's best-fit plane (unit; sign arbitrary): the branch's axis there.
    pub axis: Vector3<f64>,
    /// The ball of D the loop is nearest to (index into the balls).
    pub ball: usize,
}

/// The branches of the vessel that cross ∂D: the holes that cutting D out of the mesh left
/// (`cut`), each a cross-section of a branch whose axis is the normal of the loop's best-fit
/// plane (the eigenvector of the smallest eigenvalue of the loop vertices' covariance).
pub fn branch_crossings(cut: &CutOut, balls: &[Ball]) -> Vec<BranchCrossing> {
    let gap = |p: &Point3<f64>, b: &Ball| (p - b.center).norm() - b.radius;
    let vertices = &cut.kept.vertices;
    cut.holes
        .iter()
        .filter(|lp| lp.len() >= 3)
        .filter_map(|lp| {
            let c = lp
                .iter()
                .fold(Vector3::zeros(), |s, &v| s + vertices[v as usize].coords)
                / lp.len() as f64;
            let cov = lp.iter().fold(Matrix3::zeros(), |m, &v| {
                let d = vertices[v as usize].coords - c;
                m + d * d.transpose()
            });
            let axis = least_eigenvector(cov)?;
            let center = Point3::from(c);
            let ball = (0..balls.len())
                .min_by(|&a, &b| gap(&center, &balls[a]).total_cmp(&gap(&center, &balls[b])))?;
            Some(BranchCrossing { center, axis, ball })
        })
        .collect()
}

/// The unit eigenvector of the smallest eigenvalue of a symmetric matrix.
fn least_eigenvector(m: Matrix3<f64>) -> Option<Vector3<f64>> {
    let eig = SymmetricEigen::new(m);
    eig.eigenvectors
        .column(eig.eigenvalues.imin())
        .into_owned()
        .try_normalize(1e-12)
}

/// A cylinder fitted to the triangles of `mesh` outside the balls whose centroid lies within
/// `reach` of `near`: the axis from the normal covariance (as [`estimate_axis`]), a point of the
/// axis where the normal lines meet (least squares, pinned along the axis at `near`), and the
/// radius as the area-weighted mean distance of the triangles from that axis. None without
/// triangles there.
pub fn fit_cylinder(
    mesh: &TriMesh,
    balls: &[Ball],
    near: &Point3<f64>,
    reach: f64,
) -> Option<(Point3<f64>, Vector3<f64>, f64)> {
    let picked = normal_samples(mesh, |corners, centroid| {
        !corners
            .iter()
            .any(|p| balls.iter().any(|ball| ball.contains(p)))
            && (centroid - near).norm() <= reach
    });
    if picked.len() < 3 {
        return None;
    }
    let axis = least_normal_axis(&picked)?;
    let total: f64 = picked.iter().map(|p| p.2).sum();
    let mut m = axis * axis.transpose() * total;
    let mut rhs = axis * axis.dot(&near.coords) * total;
    for (x, n, w) in &picked {
        let p = Matrix3::identity() - n * n.transpose();
        m += p * *w;
        rhs += p * x.coords * *w;
    }
    let point = Point3::from(m.try_inverse()? * rhs);
    let radius = picked
        .iter()
        .map(|(x, _, w)| {
            let d = x - point;
            (d - axis * d.dot(&axis)).norm() * w
        })
        .sum::<f64>()
        / total;
    Some((point, axis, radius))
}
