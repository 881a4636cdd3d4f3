//! Wavefront OBJ reading and writing (geometry only).
//!
//! The reader takes `v` and `f` lines and ignores everything else (texture coordinates, normals,
//! groups, objects, materials, lines, points). Indices are global in OBJ, so several objects or
//! groups merge into one mesh naturally. Face corners may be `v`, `v/vt`, `v//vn` or `v/vt/vn`;
//! negative indices count back from the last vertex read. Polygons are fan-triangulated from their
//! first corner. The file's vertex order is kept, so a write followed by a read gives back the same
//! mesh exactly (coordinates are written with Rust's shortest round-trip formatting).
//!
//! This is hand-written rather than built on `tobj` 4.0.5: that crate panics on overflow for
//! out-of-range negative texture indices (e.g. `f 1/-5 2/-5 3/-5` with one `vt`), reads f32 unless
//! a feature is enabled, reorders vertices by first use, and reports errors without line numbers.

use super::fan_triangulate;
use super::text::show;
use crate::TriMesh;
use nalgebra::Point3;
use std::io::Write;

/// Parses OBJ bytes into an (unvalidated) mesh; the error is a one-line message.
pub(crate) fn read(bytes: &[u8]) -> Result<TriMesh, String> {
    let mut vertices: Vec<Point3<f64>> = Vec::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    // The largest positive (absolute) index seen, 0-based, and its line: checked once all vertices
    // are known, since a face may legally precede vertices it references.
    let mut largest: Option<(u64, usize)> = None;
    let mut corners: Vec<u32> = Vec::new();
    for (k, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = k + 1;
        let line = match raw.iter().position(|&b| b == b'#') {
            Some(hash) => &raw[..hash],
            None => raw,
        };
        let mut tokens = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty());
        match tokens.next() {
            Some(b"v") => {
                let mut p = [0.0; 3];
                for c in &mut p {
                    let tok = tokens.next().ok_or_else(|| {
                        format!("OBJ line {line_no}: a vertex needs 3 coordinates")
                    })?;
                    *c = super::text::parse_f64(tok).ok_or_else(|| {
                        format!(
                            "OBJ line {line_no}: vertex coordinate '{}' is not a number",
                            show(tok)
                        )
                    })?;
                }
                if let Some(bad) = p.iter().find(|c| !c.is_finite()) {
                    return Err(format!(
                        "OBJ line {line_no}: vertex {} has a non-finite coordinate ({bad})",
                        vertices.len() + 1
                    ));
                }
                vertices.push(Point3::new(p[0], p[1], p[2]));
            }
            Some(b"f") => {
                corners.clear();
                for tok in tokens {
                    let index = corner_index(tok, vertices.len(), line_no)?;
                    if largest.is_none_or(|(m, _)| index > m) {
                        largest = Some((index, line_no));
                    }
                    // An index beyond u32 is out of range anyway; the check below reports it.
                    corners.push(u32::try_from(index).unwrap_or(u32::MAX));
                }
                if corners.len() < 3 {
                    return Err(format!(
                        "OBJ face on line {line_no} has {} vertices (at least 3 needed)",
                        corners.len()
                    ));
                }
                fan_triangulate(&corners, &mut faces);
            }
            _ => {}
        }
    }
    if u32::try_from(vertices.len()).is_err() {
        return Err(format!(
            "{} vertices is more than the 2^32 this program indexes",
            vertices.len()
        ));
    }
    if let Some((index, line_no)) = largest {
        if index >= vertices.len() as u64 {
            return Err(format!(
                "OBJ face on line {line_no} references vertex {} but only {} vertices exist",
                index + 1,
                vertices.len()
            ));
        }
    }
    Ok(TriMesh::new(vertices, faces))
}

/// The 0-based vertex index of one face corner (`v`, `v/vt`, `v//vn` or `v/vt/vn`).
fn corner_index(tok: &[u8], read_so_far: usize, line_no: usize) -> Result<u64, String> {
    let v = tok.split(|&b| b == b'/').next().unwrap_or(tok);
    let Some(i) = super::text::parse_i64(v) else {
        return Err(format!(
            "OBJ face on line {line_no}: '{}' is not a vertex index",
            show(tok)
        ));
    };
    match i {
        0 => Err(format!(
            "OBJ face on line {line_no} uses vertex index 0 (OBJ indices start at 1)"
        )),
        i if i > 0 => Ok(i as u64 - 1),
        i => {
            let back = i.unsigned_abs();
            if back > read_so_far as u64 {
                Err(format!(
                    "OBJ face on line {line_no} references vertex {i} but only {read_so_far} vertices precede it"
                ))
            } else {
                Ok(read_so_far as u64 - back)
            }
        }
    }
}

/// Writes `v x y z` lines (shortest exact f64 text) then 1-based `f a b c` lines.
pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    writeln!(
        w,
        "# written by vesselmsr: {} vertices, {} triangles",
        mesh.num_vertices(),
        mesh.num_faces()
    )?;
    for p in &mesh.vertices {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for [a, b, c] in &mesh.faces {
        writeln!(w, "f {} {} {}", *a as u64 + 1, *b as u64 + 1, *c as u64 + 1)?;
    }
    Ok(())
}
