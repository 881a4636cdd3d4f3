//! The checks every mesh passes after reading, and before writing: indices in range, finite
//! coordinates (within the float32 range for formats that store float32), at least one
//! triangle, and not only degenerate triangles. Vertices and triangles are numbered from 0 in
//! the messages.

use crate::TriMesh;

/// Checks that every face index refers to an existing vertex.
pub(crate) fn check_indices(mesh: &TriMesh) -> Result<(), String> {
    let n = mesh.num_vertices();
    for (f, face) in mesh.faces.iter().enumerate() {
        if let Some(&v) = face.iter().find(|&&v| v as usize >= n) {
            return Err(format!(
                "triangle {f} references vertex {v} but only {n} vertices exist"
            ));
        }
    }
    Ok(())
}

/// The full check of a mesh that was just read.
pub(crate) fn validate_mesh(mesh: &TriMesh) -> Result<(), String> {
    check_coordinates(mesh, f64::MAX, "")?;
    check_triangles(mesh)
}

/// The check of a mesh about to be written (so no file holds inf, NaN or no usable triangle):
/// every coordinate finite, and within ±`largest` (`f32::MAX` for binary STL, which stores
/// float32), indices in range, and at least one non-degenerate triangle.
pub(crate) fn check_writable(mesh: &TriMesh, largest: f64) -> Result<(), String> {
    let beyond = if largest < f64::MAX {
        " beyond the float32 range of the format"
    } else {
        ""
    };
    check_coordinates(mesh, largest, beyond)
        .and_then(|_| check_triangles(mesh))
        .map_err(|m| format!("refusing to write this mesh: {m}"))
}

fn check_coordinates(mesh: &TriMesh, largest: f64, beyond: &str) -> Result<(), String> {
    for (v, p) in mesh.vertices.iter().enumerate() {
        if let Some(bad) = p.iter().find(|c| !c.is_finite()) {
            return Err(format!("vertex {v} has a non-finite coordinate ({bad})"));
        }
        if let Some(bad) = p.iter().find(|c| c.abs() > largest) {
            return Err(format!("vertex {v} has a coordinate {bad:e}{beyond}"));
        }
    }
    Ok(())
}

fn check_triangles(mesh: &TriMesh) -> Result<(), String> {
    if mesh.faces.is_empty() {
        return Err("no triangles".to_string());
    }
    check_indices(mesh)?;
    let degenerate = |f: usize| {
        let [a, b, c] = mesh.faces[f];
        a == b || b == c || a == c || mesh.face_normal_raw(f) == nalgebra::Vector3::zeros()
    };
    if (0..mesh.num_faces()).all(degenerate) {
        return Err(format!("all {} triangles are degenerate", mesh.num_faces()));
    }
    Ok(())
}
