//! STL reading (binary and ASCII) and binary STL writing.
//!
//! STL stores every triangle with its own three corners, so the reader welds corners whose
//! coordinates are exactly equal (-0.0 and 0.0 count as equal) into one vertex. Binary or ASCII is
//! decided by the size rule of the binary layout (80-byte header, u32 triangle count n, then 50
//! bytes per triangle: 84 + 50·n bytes), because binary files whose header begins with "solid"
//! exist; only a file that fails that rule and begins with "solid" is read as ASCII.

use super::text::{parse_f64, show, Tokens};
use crate::mesh::weld::weld_key;
use crate::TriMesh;
use nalgebra::Point3;
use std::collections::HashMap;
use std::io::Write;

const HEADER: usize = 80;
const RECORD: usize = 50;

/// Parses STL bytes into an (unvalidated) mesh; the error is a one-line message.
pub(crate) fn read(bytes: &[u8]) -> Result<TriMesh, String> {
    let declared = (bytes.len() >= HEADER + 4)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let binary_size = declared.map(|n| (HEADER + 4) as u64 + RECORD as u64 * n);
    if binary_size == Some(bytes.len() as u64) {
        return read_binary(bytes);
    }
    // The message when the declared count and the file's length disagree.
    let mismatch = |n: u64| {
        let held = (bytes.len() - HEADER - 4) / RECORD;
        let only = if (held as u64) < n { "only " } else { "" };
        format!(
            "binary STL header declares {n} triangles but the file holds {only}{held} (84 + 50·n bytes expected)"
        )
    };
    // Whole triangles missing, or beyond the declared count (the header or the file is wrong,
    // and reading either count could drop or invent triangles).
    let disagrees =
        |size: u64| size > bytes.len() as u64 || bytes.len() as u64 - size >= RECORD as u64;
    if starts_with_solid(bytes) {
        return read_ascii(bytes).map_err(|message| match (declared, binary_size) {
            // A NUL byte means binary data whose header happens to begin with "solid".
            (Some(n), Some(size)) if disagrees(size) && bytes.contains(&0) => mismatch(n),
            _ => message,
        });
    }
    match (declared, binary_size) {
        (Some(n), Some(size)) if disagrees(size) => Err(mismatch(n)),
        // Less than a triangle after the last one: some writers pad; the declared ones are read.
        (Some(_), Some(_)) => read_binary(bytes),
        _ => Err(format!(
            "not an STL file: {} bytes is too short for a binary STL (84 at least) and it does not start with 'solid'",
            bytes.len()
        )),
    }
}

fn starts_with_solid(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    bytes[start..].len() >= 5 && bytes[start..start + 5].eq_ignore_ascii_case(b"solid")
}

/// Merges corners with exactly equal coordinates into shared vertices.
struct Welder {
    index: HashMap<[u64; 3], u32>,
    vertices: Vec<Point3<f64>>,
}

impl Welder {
    fn with_capacity(triangles: usize) -> Self {
        // A closed surface has about half as many vertices as triangles.
        let guess = triangles / 2 + 3;
        Welder {
            index: HashMap::with_capacity(guess),
            vertices: Vec::with_capacity(guess),
        }
    }

    fn vertex(&mut self, p: [f64; 3]) -> Result<u32, String> {
        let key = weld_key(p);
        if let Some(&i) = self.index.get(&key) {
            return Ok(i);
        }
        let i = u32::try_from(self.vertices.len())
            .map_err(|_| "more than 2^32 distinct vertices".to_string())?;
        self.vertices.push(Point3::new(p[0], p[1], p[2]));
        self.index.insert(key, i);
        Ok(i)
    }
}

fn read_binary(bytes: &[u8]) -> Result<TriMesh, String> {
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    // The caller checked 84 + 50·n <= bytes.len(), so these allocations are bounded by the file.
    let records = &bytes[HEADER + 4..HEADER + 4 + RECORD * n];
    let mut welder = Welder::with_capacity(n);
    let mut faces = Vec::with_capacity(n);
    let f32_at =
        |r: &[u8], off: usize| f32::from_le_bytes([r[off], r[off + 1], r[off + 2], r[off + 3]]);
    for record in records.chunks_exact(RECORD) {
        let mut face = [0u32; 3];
        for (k, corner) in face.iter_mut().enumerate() {
            let off = 12 + 12 * k;
            let p = [0, 4, 8].map(|c| f32_at(record, off + c) as f64);
            *corner = welder.vertex(p)?;
        }
        faces.push(face);
    }
    Ok(TriMesh::new(welder.vertices, faces))
}

/// Reads the ASCII grammar: `solid name` { `facet normal nx ny nz` `outer loop` 3×(`vertex x y z`)
/// `endloop` `endfacet` } `endsolid name`, possibly several solids in a row. Keywords are matched
/// without regard to case.
fn read_ascii(bytes: &[u8]) -> Result<TriMesh, String> {
    let mut t = Tokens::new(bytes, 1);
    let mut welder = Welder::with_capacity(bytes.len() / 256);
    let mut faces = Vec::with_capacity(bytes.len() / 256);
    expect(&mut t, "solid")?;
    t.skip_line();
    loop {
        let Some(tok) = t.next_token() else {
            return Err(truncated(&t, "'facet' or 'endsolid'"));
        };
        if tok.eq_ignore_ascii_case(b"endsolid") {
            t.skip_line();
            match t.next_token() {
                None => break,
                Some(next) if next.eq_ignore_ascii_case(b"solid") => {
                    t.skip_line();
                    continue;
                }
                Some(other) => {
                    return Err(format!(
                        "ASCII STL line {}: expected 'solid' or the end of the file after 'endsolid', found '{}'",
                        t.line(),
                        show(other)
                    ))
                }
            }
        }
        if !tok.eq_ignore_ascii_case(b"facet") {
            return Err(unexpected(&t, "'facet' or 'endsolid'", tok));
        }
        expect(&mut t, "normal")?;
        for _ in 0..3 {
            // The stored normal is recomputed from the corners by whoever needs it.
            number(&mut t, "a normal component")?;
        }
        expect(&mut t, "outer")?;
        expect(&mut t, "loop")?;
        let mut face = [0u32; 3];
        for corner in &mut face {
            expect(&mut t, "vertex")?;
            let mut p = [0.0; 3];
            for c in &mut p {
                *c = number(&mut t, "a vertex coordinate")?;
            }
            *corner = welder.vertex(p)?;
        }
        expect(&mut t, "endloop")?;
        expect(&mut t, "endfacet")?;
        faces.push(face);
    }
    Ok(TriMesh::new(welder.vertices, faces))
}

fn expect(t: &mut Tokens, keyword: &str) -> Result<(), String> {
    match t.next_token() {
        Some(tok) if tok.eq_ignore_ascii_case(keyword.as_bytes()) => Ok(()),
        Some(tok) => Err(unexpected(t, &format!("'{keyword}'"), tok)),
        None => Err(truncated(t, &format!("'{keyword}'"))),
    }
}

fn number(t: &mut Tokens, what: &str) -> Result<f64, String> {
    let Some(tok) = t.next_token() else {
        return Err(truncated(t, what));
    };
    parse_f64(tok).ok_or_else(|| {
        format!(
            "ASCII STL line {}: expected {what}, found '{}' which is not a number",
            t.line(),
            show(tok)
        )
    })
}

fn truncated(t: &Tokens, expected: &str) -> String {
    format!(
        "ASCII STL truncated after line {}: expected {expected}",
        t.line()
    )
}

fn unexpected(t: &Tokens, expected: &str, found: &[u8]) -> String {
    format!(
        "ASCII STL line {}: expected {expected}, found '{}'",
        t.line(),
        show(found)
    )
}

/// Writes binary STL: facet normals computed from the corners (zero for a degenerate triangle),
/// coordinates rounded to f32. Face indices must be in range (the caller checks).
pub(crate) fn write(w: &mut dyn Write, mesh: &TriMesh) -> std::io::Result<()> {
    let n = u32::try_from(mesh.num_faces()).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "binary STL holds at most 2^32 - 1 triangles",
        )
    })?;
    let mut header = [b' '; HEADER];
    let text = b"binary STL written by vesselmsr";
    header[..text.len()].copy_from_slice(text);
    w.write_all(&header)?;
    w.write_all(&n.to_le_bytes())?;
    let mut record = [0u8; RECORD];
    for f in 0..mesh.num_faces() {
        let normal = mesh.face_normal_raw(f);
        let unit = normal
            .try_normalize(0.0)
            .unwrap_or_else(nalgebra::Vector3::zeros);
        let corners = mesh.triangle(f);
        let values = [unit.x, unit.y, unit.z]
            .into_iter()
            .chain(corners.iter().flat_map(|p| [p.x, p.y, p.z]));
        for (k, v) in values.enumerate() {
            record[4 * k..4 * k + 4].copy_from_slice(&(v as f32).to_le_bytes());
        }
        w.write_all(&record)?;
    }
    Ok(())
}
