//! A [`Grid3`] as a VTK XML ImageData file (`.vti`), for ParaView and other VTK-based viewers.
//!
//! The file is `<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian"
//! header_type="UInt64">` with `WholeExtent="0 nx−1 0 ny−1 0 nz−1"`, `Origin` (node (0, 0, 0),
//! file units), `Spacing="h h h"`, and one piece whose PointData holds a single Float32 array
//! named `phi` (the active scalars; its RangeMin/RangeMax given). The values are stored in
//! VTK's appended-data section as **raw binary**, not base64: `_`, then the byte count as a
//! little-endian UInt64, then the float32 values little-endian with x fastest (VTK's point order,
//! which is also [`Grid3`]'s). Raw appended data is the compact form VTK's own XML writer
//! produces by default, read by `vtkXMLImageDataReader` (ParaView, VTK's Python bindings).
//! The file is written atomically.
//!
//! [`read_vti`] reads files of exactly this layout back (for tests and later commands); it is not
//! a general VTK reader.

use super::npy::{read_f32_le, write_f32_le};
use super::write_atomic;
use crate::grid::{Grid3, GridTransform};
use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Name of the point-data array.
pub const VTI_ARRAY_NAME: &str = "phi";

/// Writes `grid` to `path` as VTK ImageData with the point array `phi` (atomic).
pub fn write_vti(path: &Path, grid: &Grid3) -> Result<()> {
    write_atomic(path, |w| {
        write_image(w, grid).map_err(|e| Error::io(path, e))
    })
}

fn write_image(w: &mut dyn Write, grid: &Grid3) -> std::io::Result<()> {
    let [nx, ny, nz] = grid.dims();
    let [ox, oy, oz] = grid.transform().origin;
    let h = grid.voxel();
    let extent = format!("0 {} 0 {} 0 {}", nx - 1, ny - 1, nz - 1);
    let (lo, hi) = grid
        .data()
        .iter()
        .filter(|v| !v.is_nan())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let range = if lo <= hi {
        format!(" RangeMin=\"{lo:?}\" RangeMax=\"{hi:?}\"")
    } else {
        String::new()
    };
    // `{:?}` prints f64 with all the digits needed to read back the same value.
    write!(
        w,
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n\
         \x20 <ImageData WholeExtent=\"{extent}\" Origin=\"{ox:?} {oy:?} {oz:?}\" Spacing=\"{h:?} {h:?} {h:?}\">\n\
         \x20   <Piece Extent=\"{extent}\">\n\
         \x20     <PointData Scalars=\"{VTI_ARRAY_NAME}\">\n\
         \x20       <DataArray type=\"Float32\" Name=\"{VTI_ARRAY_NAME}\" NumberOfComponents=\"1\" format=\"appended\" offset=\"0\"{range}/>\n\
         \x20     </PointData>\n\
         \x20     <CellData>\n\
         \x20     </CellData>\n\
         \x20   </Piece>\n\
         \x20 </ImageData>\n\
         \x20 <AppendedData encoding=\"raw\">\n   _"
    )?;
    let bytes = grid.data().len() as u64 * 4;
    w.write_all(&bytes.to_le_bytes())?;
    write_f32_le(w, grid.data())?;
    w.write_all(b"\n  </AppendedData>\n</VTKFile>\n")
}

/// Reads a grid written by [`write_vti`]: one Float32 point array in raw appended data with a
/// UInt64 header, little-endian, equal spacing on the three axes.
pub fn read_vti(path: &Path) -> Result<Grid3> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_vti(&bytes).map_err(|m| Error::format(path, m))
}

fn parse_vti(bytes: &[u8]) -> std::result::Result<Grid3, String> {
    let marker = b"<AppendedData";
    let at = find(bytes, marker).ok_or("no <AppendedData> section (not a vesselmsr .vti)")?;
    let xml = std::str::from_utf8(&bytes[..at]).map_err(|_| "the XML header is not text")?;
    let tag_end = at + find(&bytes[at..], b">").ok_or("unterminated <AppendedData>")?;
    let appended_tag =
        std::str::from_utf8(&bytes[at..tag_end]).map_err(|_| "bad <AppendedData>")?;
    let underscore = tag_end + find(&bytes[tag_end..], b"_").ok_or("no '_' before the data")?;
    let file_tag = tag(xml, "VTKFile")?;
    let image = tag(xml, "ImageData")?;
    let array = tag(xml, "DataArray")?;
    for (t, name, want) in [
        (file_tag, "type", "ImageData"),
        (file_tag, "byte_order", "LittleEndian"),
        (file_tag, "header_type", "UInt64"),
        (array, "type", "Float32"),
        (array, "format", "appended"),
        (appended_tag, "encoding", "raw"),
    ] {
        let got = attribute(t, name).ok_or(format!("no {name} attribute"))?;
        if got != want {
            return Err(format!(
                "{name}=\"{got}\" is not supported (expected \"{want}\")"
            ));
        }
    }
    let numbers = |t: &str, name: &str, n: usize| -> std::result::Result<Vec<f64>, String> {
        let text = attribute(t, name).ok_or(format!("no {name} attribute"))?;
        let v: Vec<f64> = text
            .split_whitespace()
            .map(str::parse)
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| format!("cannot read {name}=\"{text}\""))?;
        if v.len() != n {
            return Err(format!("{name} has {} numbers, expected {n}", v.len()));
        }
        Ok(v)
    };
    let extent = numbers(image, "WholeExtent", 6)?;
    let origin = numbers(image, "Origin", 3)?;
    let spacing = numbers(image, "Spacing", 3)?;
    if spacing[1] != spacing[0] || spacing[2] != spacing[0] {
        return Err(format!(
            "unequal spacing {spacing:?} (grids have cubic voxels)"
        ));
    }
    let mut dims = [0usize; 3];
    for a in 0..3 {
        let (lo, hi) = (extent[2 * a], extent[2 * a + 1]);
        if lo.fract() != 0.0 || hi.fract() != 0.0 || hi < lo {
            return Err(format!("bad WholeExtent {extent:?}"));
        }
        dims[a] = (hi - lo) as usize + 1;
    }
    let offset = numbers(array, "offset", 1)?[0] as usize;
    let data = &bytes[underscore + 1..];
    let block = data
        .get(offset..)
        .ok_or("the data offset is past the end")?;
    let size_bytes: [u8; 8] = block
        .get(..8)
        .ok_or("truncated data block")?
        .try_into()
        .unwrap();
    let size = u64::from_le_bytes(size_bytes) as usize;
    let count = Grid3::node_count(dims).map_err(|e| e.to_string())?;
    if Some(size) != count.checked_mul(4) {
        return Err(format!(
            "the data block holds {size} bytes, {dims:?} nodes need {}",
            count.saturating_mul(4)
        ));
    }
    let values = block
        .get(8..8 + size)
        .ok_or("the data block is shorter than its header says")?;
    let transform = GridTransform {
        origin: [origin[0], origin[1], origin[2]],
        voxel: spacing[0],
    };
    Grid3::from_data(dims, transform, read_f32_le(values)).map_err(|e| e.to_string())
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

/// The text of the first `<name ...>` start tag (without the brackets).
fn tag<'a>(xml: &'a str, name: &str) -> std::result::Result<&'a str, String> {
    let open = format!("<{name}");
    let mut from = 0;
    while let Some(i) = xml[from..].find(&open) {
        let start = from + i;
        let after = &xml[start + open.len()..];
        if after.starts_with(|c: char| c.is_whitespace() || c == '>' || c == '/') {
            let end = after.find('>').ok_or(format!("unterminated <{name}>"))?;
            return Ok(&xml[start + 1..start + open.len() + end]);
        }
        from = start + open.len();
    }
    Err(format!("no <{name}> element"))
}

/// The value of attribute `name="..."` in a start tag's text.
fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let mut from = 0;
    let pattern = format!("{name}=\"");
    while let Some(i) = tag[from..].find(&pattern) {
        let start = from + i;
        let preceded = tag[..start].ends_with(char::is_whitespace);
        let value_start = start + pattern.len();
        if preceded {
            let len = tag[value_start..].find('"')?;
            return Some(&tag[value_start..value_start + len]);
        }
        from = value_start;
    }
    None
}
