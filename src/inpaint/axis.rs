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

/// The axes of the vessel branches that cross ∂D: the boundary loops that removing the triangles
/// with a vertex in D leaves in `mesh` (those within `reach` of D), each taken as a cross-section
/// of a branch, whose axis is the normal of the loop's best-fit plane (the eigenvector of the
/// smallest eigenvalue of the loop vertices' covariance).
pub fn branch_axes(mesh: &TriMesh, balls: &[Ball], reach: f64) -> Vec<Vector3<f64>> {
    let inside: Vec<bool> = mesh
        .vertices
        .iter()
        .map(|p| balls.iter().any(|b| b.contains(p)))
        .collect();
    let kept = TriMesh::new(
        mesh.vertices.clone(),
        mesh.faces
            .iter()
            .filter(|f| f.iter().all(|&v| !inside[v as usize]))
            .copied()
            .collect(),
    );
    let near = |p: &nalgebra::Point3<f64>| {
        balls
            .iter()
            .any(|b| (p - b.center).norm() < b.radius + reach)
    };
    crate::mesh::topology::boundary_loops(&kept)
        .into_iter()
        .filter(|lp| lp.len() >= 3 && lp.iter().all(|&v| near(&kept.vertices[v as usize])))
        .filter_map(|lp| {
            let n = lp.len() as f64;
            let c = lp.iter().fold(Vector3::zeros(), |s, &v| {
                s + kept.vertices[v as usize].coords
            }) / n;
            let mut cov = Matrix3::zeros();
            for &v in &lp {
                let d = kept.vertices[v as usize].coords - c;
                cov += d * d.transpose();
            }
            let eig = SymmetricEigen::new(cov);
            let k = eig.eigenvalues.imin();
            eig.eigenvectors.column(k).into_owned().try_normalize(1e-12)
        })
        .collect()
}
