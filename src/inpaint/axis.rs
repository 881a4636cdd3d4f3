//! The vessel axis at a region D, estimated from the intact surface around it: on a tube every
//! surface normal is perpendicular to the axis, so the axis is the direction least represented
//! among the normals, the eigenvector of the smallest eigenvalue of the area-weighted normal
//! covariance Σ A n nᵀ of the triangles in a shell just outside the ball.

use super::region::Ball;
use crate::TriMesh;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// The axis direction (unit, sign arbitrary) of the vessel through `ball`, from the triangles
/// whose centroid lies between 1 and `shell` ball radii from its centre (`shell` > 1). None when
/// no triangle lies there.
pub fn estimate_axis(mesh: &TriMesh, ball: &Ball, shell: f64) -> Option<Vector3<f64>> {
    let mut cov = Matrix3::zeros();
    let mut found = false;
    for f in 0..mesh.num_faces() {
        let [a, b, c] = mesh.triangle(f);
        let centroid = nalgebra::Point3::from((a.coords + b.coords + c.coords) / 3.0);
        let r = (centroid - ball.center).norm() / ball.radius;
        if !(1.0..=shell).contains(&r) {
            continue;
        }
        let raw = mesh.face_normal_raw(f);
        let area2 = raw.norm();
        if area2 <= 0.0 {
            continue;
        }
        let n = raw / area2;
        cov += n * n.transpose() * area2;
        found = true;
    }
    if !found {
        return None;
    }
    let eig = SymmetricEigen::new(cov);
    let k = eig.eigenvalues.imin();
    Some(eig.eigenvectors.column(k).into_owned().normalize())
}
