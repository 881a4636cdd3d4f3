//! A [`Grid3`] as a NumPy `.npy` file plus a JSON sidecar holding its transform.
//!
//! **The array** is NumPy format version 1.0, dtype `'<f4'` (little-endian float32), C order,
//! shape `(nz, ny, nx)`: `np.load(path)[k, j, i]` is the value of node (i, j, k), so x varies
//! fastest in memory, exactly as in [`Grid3`]. The header is padded so the data starts on a
//! 64-byte boundary, as NumPy itself writes it.
//!
//! **The sidecar** is `<file>.json` next to it (`phi.npy` → `phi.npy.json`, see
//! [`npy_sidecar_path`]): `{"dims": [nx, ny, nz], "origin": [x, y, z], "voxel": h,
//! "axis_order": "z,y,x", "units": "file units", "sign": "negative inside"}`; node (i, j, k) sits
//! at `origin + voxel·(i, j, k)` in the units of the mesh file the grid came from.
//!
//! Both files are written with [`write_atomic`]: the array first, then the sidecar; when the
//! sidecar cannot be written the array just written is removed, so a failed write leaves neither.
//! The reader takes files of this layout (format versions 1.0 to 3.0, '<f4', C order, 3-D) with
//! their sidecar, and checks that the two agree.

use super::write_atomic;
use crate::grid::{Grid3, GridTransform};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 6] = b"\x93NUMPY";
/// The data starts at a multiple of this many bytes (NumPy ≥ 1.14 pads to 64).
const ALIGN: usize = 64;

/// The sidecar of a `.npy` grid: where its nodes are in the world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NpySidecar {
    /// Nodes along x, y, z (the array's shape reversed).
    pub dims: [usize; 3],
    /// World position of node (0, 0, 0).
    pub origin: [f64; 3],
    /// Voxel edge length, world units.
    pub voxel: f64,
    /// Order of the array's axes: always "z,y,x".
    pub axis_order: String,
    /// Units of origin and voxel: "file units" (those of the mesh the grid came from).
    pub units: String,
    /// Sign convention of the values: "negative inside".
    pub sign: String,
}

impl NpySidecar {
    /// The sidecar of `grid`.
    pub fn of(grid: &Grid3) -> NpySidecar {
        NpySidecar {
            dims: grid.dims(),
            origin: grid.transform().origin,
            voxel: grid.voxel(),
            axis_order: "z,y,x".into(),
            units: "file units".into(),
            sign: "negative inside".into(),
        }
    }
}

/// The sidecar path of an `.npy` file: the same path with `.json` appended.
pub fn npy_sidecar_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".json");
    PathBuf::from(name)
}

/// Writes `grid` to `path` as `.npy` and its transform to [`npy_sidecar_path`]`(path)`
/// (both atomic; on failure neither is left behind).
pub fn write_npy(path: &Path, grid: &Grid3) -> Result<()> {
    write_atomic(path, |w| {
        write_array(w, grid).map_err(|e| Error::io(path, e))
    })?;
    let sidecar = npy_sidecar_path(path);
    let written = write_atomic(&sidecar, |w| {
        serde_json::to_writer_pretty(&mut *w, &NpySidecar::of(grid))
            .map_err(|e| Error::io(&sidecar, e.into()))?;
        w.write_all(b"\n").map_err(|e| Error::io(&sidecar, e))
    });
    if written.is_err() {
        let _ = std::fs::remove_file(path);
    }
    written
}

fn header(dims: [usize; 3]) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}, {}), }}",
        dims[2], dims[1], dims[0]
    );
    // magic + version + u16 length + dict + padding + '\n', a multiple of ALIGN.
    let unpadded = MAGIC.len() + 2 + 2 + dict.len() + 1;
    let total = unpadded.div_ceil(ALIGN) * ALIGN;
    let len = (total - MAGIC.len() - 4) as u16;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&len.to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.resize(total - 1, b' ');
    out.push(b'\n');
    out
}

fn write_array(w: &mut dyn Write, grid: &Grid3) -> std::io::Result<()> {
    w.write_all(&header(grid.dims()))?;
    write_f32_le(w, grid.data())
}

/// Writes f32 values little-endian, a block at a time.
pub(crate) fn write_f32_le(w: &mut dyn Write, values: &[f32]) -> std::io::Result<()> {
    let mut buf = Vec::with_capacity(4 * 16384);
    for block in values.chunks(16384) {
        buf.clear();
        buf.extend(block.iter().flat_map(|v| v.to_le_bytes()));
        w.write_all(&buf)?;
    }
    Ok(())
}

/// Reads f32 values little-endian.
pub(crate) fn read_f32_le(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Reads a grid written by [`write_npy`] (or any 3-D '<f4' C-order `.npy` with such a sidecar).
pub fn read_npy(path: &Path) -> Result<Grid3> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let (shape, data) = parse_npy(&bytes).map_err(|m| Error::format(path, m))?;
    let sidecar_path = npy_sidecar_path(path);
    let text = std::fs::read_to_string(&sidecar_path).map_err(|e| Error::io(&sidecar_path, e))?;
    let sidecar: NpySidecar = serde_json::from_str(&text)
        .map_err(|e| Error::format(&sidecar_path, format!("not a grid sidecar: {e}")))?;
    let dims = [shape[2], shape[1], shape[0]];
    if sidecar.dims != dims {
        return Err(Error::format(
            &sidecar_path,
            format!(
                "dims {:?} do not match the array's shape {shape:?} (expected dims {dims:?})",
                sidecar.dims
            ),
        ));
    }
    if sidecar.axis_order != "z,y,x" {
        return Err(Error::format(
            &sidecar_path,
            format!("axis_order '{}' (expected \"z,y,x\")", sidecar.axis_order),
        ));
    }
    if !sidecar.origin.iter().all(|v| v.is_finite()) {
        return Err(Error::format(&sidecar_path, "origin is not finite"));
    }
    let transform = GridTransform {
        origin: sidecar.origin,
        voxel: sidecar.voxel,
    };
    Grid3::from_data(dims, transform, data).map_err(|e| Error::format(&sidecar_path, e.to_string()))
}

/// The header of a `.npy` array: dtype, order, shape and where the data starts.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct NpyHeader {
    /// The dtype text without quotes, e.g. `<f4`.
    pub descr: String,
    /// C-order shape (empty for a scalar).
    pub shape: Vec<usize>,
    /// Byte offset of the data.
    pub data_start: usize,
}

impl NpyHeader {
    /// Number of values the shape holds (None on overflow).
    pub fn count(&self) -> Option<usize> {
        self.shape.iter().try_fold(1usize, |a, &d| a.checked_mul(d))
    }
}

/// Bytes of a `.npy` file needed to know where its header ends: the magic, version and length.
pub(crate) const PREAMBLE: usize = 12;

/// Largest header accepted (NumPy writes under a hundred bytes; version 1.0 allows 64 KiB).
const MAX_HEADER: usize = 1 << 20;

/// Where the header dict of a `.npy` file ends (the data start), from its first bytes (at least
/// 10, or [`PREAMBLE`] for format versions 2 and 3).
pub(crate) fn header_end(bytes: &[u8]) -> std::result::Result<usize, String> {
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err("not a NumPy .npy array (no \\x93NUMPY magic)".into());
    }
    let (len, start): (usize, usize) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("unsupported .npy format version {v}.{}", bytes[7])),
    };
    if len > MAX_HEADER {
        return Err(format!("a header of {len} bytes is not a .npy header"));
    }
    Ok(start + len)
}

/// Parses the header of a `.npy` file (format versions 1.0 to 3.0, C order); `bytes` holds at
/// least the header. Every malformed header is an error, never a panic.
pub(crate) fn parse_header(bytes: &[u8]) -> std::result::Result<NpyHeader, String> {
    let end = header_end(bytes)?;
    let start = if bytes[6] == 1 { 10 } else { 12 };
    let dict = bytes.get(start..end).ok_or("truncated .npy header")?;
    let dict = std::str::from_utf8(dict).map_err(|_| "the header is not text")?;
    let descr = dict_value(dict, "descr").ok_or("the header has no 'descr'")?;
    let descr = descr
        .strip_prefix(['\'', '"'])
        .and_then(|d| d.strip_suffix(['\'', '"']))
        .ok_or_else(|| {
            format!(
                "cannot read the dtype {}",
                super::text::show(descr.as_bytes())
            )
        })?;
    let fortran = dict_value(dict, "fortran_order").ok_or("the header has no 'fortran_order'")?;
    if fortran != "False" {
        return Err("Fortran-ordered arrays are not supported (expected C order)".into());
    }
    let shape_text = dict_value(dict, "shape").ok_or("the header has no 'shape'")?;
    let shape = parse_shape(shape_text).ok_or_else(|| {
        format!(
            "cannot read the shape {}",
            super::text::show(shape_text.as_bytes())
        )
    })?;
    Ok(NpyHeader {
        descr: descr.to_owned(),
        shape,
        data_start: end,
    })
}

/// A shape tuple `(a, b, c)`, `(a,)` or `()`.
fn parse_shape(text: &str) -> Option<Vec<usize>> {
    let inner = text.strip_prefix('(')?.strip_suffix(')')?;
    let parts: Vec<&str> = inner.split(',').map(str::trim).collect();
    // A trailing comma leaves one empty part at the end; no other part may be empty.
    let parts = match parts.split_last() {
        Some((last, rest)) if last.is_empty() => rest,
        _ => &parts[..],
    };
    parts.iter().map(|p| p.parse::<usize>().ok()).collect()
}

/// Shape and values of a 3-D '<f4' C-order `.npy` file.
fn parse_npy(bytes: &[u8]) -> std::result::Result<([usize; 3], Vec<f32>), String> {
    let header = parse_header(bytes)?;
    if header.descr != "<f4" {
        return Err(format!(
            "dtype '{}' is not supported (expected little-endian float32 '<f4')",
            super::text::show(header.descr.as_bytes())
        ));
    }
    let [nz, ny, nx] = header.shape[..] else {
        return Err(format!(
            "the array has {} dimensions, a grid needs 3",
            header.shape.len()
        ));
    };
    let count = Grid3::node_count([nx, ny, nz]).map_err(|e| e.to_string())?;
    let data = &bytes[header.data_start..];
    if Some(data.len()) != count.checked_mul(4) {
        return Err(format!(
            "the shape ({nz}, {ny}, {nx}) needs {count} float32 values but the file holds {} bytes of data",
            data.len()
        ));
    }
    Ok(([nz, ny, nx], read_f32_le(data)))
}

/// The text of the value of `'key'` in a NumPy header dict (a quoted string, a word, or a
/// parenthesised tuple).
fn dict_value<'a>(dict: &'a str, key: &str) -> Option<&'a str> {
    let quoted = [format!("'{key}'"), format!("\"{key}\"")];
    let at = quoted
        .iter()
        .find_map(|q| dict.find(q.as_str()).map(|i| i + q.len()))?;
    let rest = dict[at..].trim_start().strip_prefix(':')?.trim_start();
    // Every position below follows an ASCII character, so the slices are on char boundaries.
    let end = match rest.chars().next()? {
        '(' => rest.find(')')? + 1,
        q @ ('\'' | '"') => rest[1..].find(q)? + 2,
        _ => rest.find([',', '}']).unwrap_or(rest.len()),
    };
    Some(rest[..end].trim())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_aligned_and_parses() {
        for dims in [[1, 1, 1], [300, 2, 77], [123456, 7, 1]] {
            let h = header(dims);
            assert_eq!(h.len() % ALIGN, 0);
            assert_eq!(*h.last().unwrap(), b'\n');
            let mut bytes = h.clone();
            let n = dims.iter().product::<usize>();
            bytes.extend(std::iter::repeat_n(0u8, 4 * n));
            let (shape, data) = parse_npy(&bytes).unwrap();
            assert_eq!(shape, [dims[2], dims[1], dims[0]]);
            assert_eq!(data.len(), n);
        }
    }

    #[test]
    fn malformed_headers_are_errors_not_panics() {
        let with_dict = |dict: &str| {
            let mut b = MAGIC.to_vec();
            b.extend_from_slice(&[1, 0]);
            b.extend_from_slice(&(dict.len() as u16).to_le_bytes());
            b.extend_from_slice(dict.as_bytes());
            b
        };
        for dict in [
            "{'descr': '<f4', 'fortran_order': False, 'shape': ), }",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (é, 2), }",
            "{'descr': '<f4', 'fortran_order': False, 'shape': é, }",
            "{'descr': 'é}",
            "{'descr': é, 'fortran_order': False, 'shape': (1,), }",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (1,,2), }",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 2",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999999999999,), }",
            "{'descr': '<f4', 'fortran_order': True, 'shape': (1, 1, 1), }",
        ] {
            assert!(parse_header(&with_dict(dict)).is_err(), "{dict}");
        }
        let ok = parse_header(&with_dict(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }",
        ))
        .unwrap();
        assert_eq!((ok.descr.as_str(), &ok.shape[..]), ("<f8", &[2, 3][..]));
        assert_eq!(parse_shape("()"), Some(vec![]));
        assert_eq!(parse_shape("(4,)"), Some(vec![4]));
        assert_eq!(parse_shape("(,)"), None);
    }

    #[test]
    fn dict_values() {
        let d = "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 5), }";
        assert_eq!(dict_value(d, "descr"), Some("'<f4'"));
        assert_eq!(dict_value(d, "fortran_order"), Some("False"));
        assert_eq!(dict_value(d, "shape"), Some("(3, 4, 5)"));
        assert_eq!(dict_value(d, "nothing"), None);
    }
}
