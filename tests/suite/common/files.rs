//! Hand-made mesh files for the reader and CLI tests: binary STL bytes built field by field (so a
//! test can lie about the triangle count or put "solid" in the header), writing bytes into a
//! test folder, and listing what a folder holds.

use std::path::{Path, PathBuf};
use vesselmsr::TriMesh;

/// The names in `dir` (hidden ones too), sorted: what a command left behind.
pub fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Writes `bytes` to `dir/name` and returns the path.
pub fn write_file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// An 80-byte STL header starting with `text`, padded with spaces (so that a header starting
/// with "solid" looks like ASCII STL all the way).
pub fn stl_header(text: &str) -> [u8; 80] {
    let mut header = [b' '; 80];
    header[..text.len()].copy_from_slice(text.as_bytes());
    header
}

/// A binary STL file: `header`, the triangle count `declared` (which may differ from the number
/// of `triangles` given), then each triangle with a zero normal and a zero attribute word.
pub fn binary_stl(header: &[u8; 80], declared: u32, triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut bytes = header.to_vec();
    bytes.extend_from_slice(&declared.to_le_bytes());
    for t in triangles {
        bytes.extend_from_slice(&[0u8; 12]);
        t.iter()
            .flatten()
            .for_each(|c| bytes.extend_from_slice(&c.to_le_bytes()));
        bytes.extend_from_slice(&[0u8; 2]);
    }
    bytes
}

/// The triangles of `mesh` with f32 corners, as binary STL stores them.
pub fn stl_triangles(mesh: &TriMesh) -> Vec<[[f32; 3]; 3]> {
    (0..mesh.num_faces())
        .map(|f| {
            mesh.triangle(f)
                .map(|p| [p.x as f32, p.y as f32, p.z as f32])
        })
        .collect()
}
