//! A [`Grid3`] as a NRRD file (`.nrrd`, format NRRD0004), the volume format 3D Slicer, ITK and
//! MITK load natively (Slicer reads `.vti` only through its VTK route, NRRD through ITK as a
//! regular scalar volume).
//!
//! Layout written: the text header
//! `NRRD0004`, `type: float`, `dimension: 3`, `space: left-posterior-superior`,
//! `sizes: nx ny nz`, `space directions: (h,0,0) (0,h,0) (0,0,h)`, `kinds: domain domain domain`,
//! `endian: little`, `encoding: raw`, `space origin: (x0,y0,z0)`, a blank line, then the float32
//! values little-endian with x fastest (NRRD's first axis is the fastest, as in [`Grid3`]).
//! The coordinates are the mesh's own, unchanged and with no unit attached (files come in mm, cm
//! or m); the space is declared LPS because that is the frame of the STL models 3D Slicer writes
//! (since version 4.11), so a φ voxelized from such a model overlays it. The file is written
//! atomically.
//!
//! [`read_nrrd`] reads files of this layout back (raw float32, axis-aligned equal spacing); it is
//! not a general NRRD reader.

use super::npy::{read_f32_le, write_f32_le};
use super::write_atomic;
use crate::grid::{Grid3, GridTransform};
use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Writes `grid` to `path` as NRRD (atomic).
pub fn write_nrrd(path: &Path, grid: &Grid3) -> Result<()> {
    write_atomic(path, |w| {
        write_volume(w, grid).map_err(|e| Error::io(path, e))
    })
}

fn write_volume(w: &mut dyn Write, grid: &Grid3) -> std::io::Result<()> {
    let [nx, ny, nz] = grid.dims();
    let [ox, oy, oz] = grid.transform().origin;
    let h = grid.voxel();
    // `{:?}` prints f64 with all the digits needed to read back the same value.
    write!(
        w,
        "NRRD0004\n\
         # vesselmsr signed distance grid phi (negative inside), coordinates in the mesh's units\n\
         type: float\n\
         dimension: 3\n\
         space: left-posterior-superior\n\
         sizes: {nx} {ny} {nz}\n\
         space directions: ({h:?},0,0) (0,{h:?},0) (0,0,{h:?})\n\
         kinds: domain domain domain\n\
         endian: little\n\
         encoding: raw\n\
         space origin: ({ox:?},{oy:?},{oz:?})\n\n"
    )?;
    write_f32_le(w, grid.data())
}

/// Reads a grid written by [`write_nrrd`].
pub fn read_nrrd(path: &Path) -> Result<Grid3> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_nrrd(&bytes).map_err(|m| Error::format(path, m))
}

fn parse_nrrd(bytes: &[u8]) -> std::result::Result<Grid3, String> {
    if !bytes.starts_with(b"NRRD000") {
        return Err("not a NRRD file (no NRRD000x magic)".into());
    }
    let end = bytes
        .windows(2)
        .position(|w| w == b"\n\n")
        .ok_or("no blank line ending the header")?;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| "the header is not text")?;
    let mut field = std::collections::HashMap::new();
    for line in header.lines().skip(1) {
        if line.starts_with('#') {
            continue;
        }
        if let Some((k, v)) = line.split_once(": ") {
            field.insert(k.trim(), v.trim());
        }
    }
    let get = |k: &str| field.get(k).copied().ok_or(format!("no '{k}' field"));
    for (k, want) in [
        ("type", "float"),
        ("dimension", "3"),
        ("endian", "little"),
        ("encoding", "raw"),
    ] {
        let got = get(k)?;
        if got != want {
            return Err(format!("{k}: {got} is not supported (expected {want})"));
        }
    }
    let sizes: Vec<usize> = get("sizes")?
        .split_whitespace()
        .map(str::parse)
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| "cannot read sizes")?;
    let dims: [usize; 3] = sizes.try_into().map_err(|_| "sizes must have 3 numbers")?;
    let vectors = |text: &str| -> std::result::Result<Vec<[f64; 3]>, String> {
        text.split_whitespace()
            .map(|t| {
                let v: Vec<f64> = t
                    .trim_start_matches('(')
                    .trim_end_matches(')')
                    .split(',')
                    .map(str::parse)
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| format!("cannot read vector {t}"))?;
                v.try_into().map_err(|_| format!("{t} is not a 3-vector"))
            })
            .collect()
    };
    let dirs = vectors(get("space directions")?)?;
    let origin = vectors(get("space origin")?)?;
    let h = dirs.first().map(|d| d[0]).unwrap_or(0.0);
    let axis_aligned = dirs.len() == 3
        && (0..3).all(|a| (0..3).all(|b| dirs[a][b] == if a == b { h } else { 0.0 }));
    if !(axis_aligned && h > 0.0 && h.is_finite()) {
        return Err("space directions must be axis-aligned with one positive spacing".into());
    }
    let [o] = origin[..] else {
        return Err("space origin must be one 3-vector".into());
    };
    let n = Grid3::node_count(dims).map_err(|e| e.to_string())?;
    let data = &bytes[end + 2..];
    if data.len() != 4 * n {
        return Err(format!(
            "{} bytes of data, expected {} for sizes {} {} {}",
            data.len(),
            4 * n,
            dims[0],
            dims[1],
            dims[2]
        ));
    }
    let transform = GridTransform::new(o.into(), h);
    Grid3::from_data(dims, transform, read_f32_le(data)).map_err(|e| e.to_string())
}
