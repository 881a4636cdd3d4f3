//! Reading and writing STL, OBJ and PLY meshes.
//!
//! Placeholder: binary STL reading only, with exact-coordinate vertex welding. The io issue work
//! replaces this module while keeping `read_mesh`'s signature.

use crate::{Error, Result, TriMesh};
use nalgebra::Point3;
use std::collections::HashMap;
use std::path::Path;

/// Reads a mesh, choosing the format from the file extension.
pub fn read_mesh(path: &Path) -> Result<TriMesh> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if bytes.len() < 84 {
        return Err(Error::format(path, "file too short for binary STL"));
    }
    let n = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
    if bytes.len() < 84 + 50 * n {
        return Err(Error::format(path, "binary STL truncated"));
    }
    let mut map: HashMap<[u32; 3], u32> = HashMap::new();
    let mut vertices = Vec::new();
    let mut faces = Vec::with_capacity(n);
    for t in 0..n {
        let rec = &bytes[84 + 50 * t..84 + 50 * (t + 1)];
        let mut face = [0u32; 3];
        for (k, idx) in face.iter_mut().enumerate() {
            let mut key = [0u32; 3];
            let mut p = [0f64; 3];
            for c in 0..3 {
                let off = 12 + 12 * k + 4 * c;
                let bits = u32::from_le_bytes(rec[off..off + 4].try_into().unwrap());
                key[c] = bits;
                p[c] = f32::from_bits(bits) as f64;
            }
            *idx = *map.entry(key).or_insert_with(|| {
                vertices.push(Point3::new(p[0], p[1], p[2]));
                (vertices.len() - 1) as u32
            });
        }
        faces.push(face);
    }
    Ok(TriMesh::new(vertices, faces))
}
