//! VTK XML PolyData (`.vtp`): a generic writer and reader of points, polygons and polylines with
//! named point-data and cell-data arrays, for ParaView, 3D Slicer and VTK's Python bindings.
//!
//! **Cell order.** VTK numbers the cells of a PolyData as all Verts, then all Lines, then all
//! Polys, then all Strips. [`PolyData`] has no verts or strips, so each `cell_data` array holds one
//! tuple per entry of `lines` first, then one per entry of `polys`.
//!
//! **What is written.** `<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian"
//! header_type="UInt64">`, one Piece, points as Float64 (coordinates round-trip exactly),
//! connectivity and offsets as Int32 (Int64 if an index or count exceeds `i32::MAX`), data arrays
//! with their own type. By default ([`VtpEncoding::Appended`]) the arrays are stored raw and
//! uncompressed in the `<AppendedData encoding="raw">` section, each as a UInt64 byte count then
//! the little-endian values: the form VTK's own writer uses (without its compression), the
//! smallest and fastest to write and read. [`VtpEncoding::Base64`] (inline base64, pure XML) and
//! [`VtpEncoding::Ascii`] are also written, mostly for tests. The first one-component point-data
//! and cell-data arrays are named the active `Scalars`.
//!
//! **What is read.** Whatever `vtkXMLPolyDataWriter` writes, as far as PolyData goes: `ascii`,
//! inline `binary` (base64) and `appended` (raw or base64) arrays, UInt32 or UInt64 headers, little
//! or big endian, uncompressed or compressed by `vtkZLibDataCompressor` (VTK's default), any
//! number of pieces (concatenated). Verts are skipped (their cell-data tuples dropped); strips are
//! cut into triangles appended to `polys` (each triangle repeating its strip's cell-data tuple).
//! Data arrays keep Float32, Float64 and UInt8; Int8, Int16, UInt16 and Int32 become
//! [`DataValues::I32`], as do UInt32, Int64 and UInt64 when every value fits (otherwise
//! [`DataValues::F64`]); arrays of other types (String, Bit) and field data are skipped.
//! Every count, offset and index is checked against the bytes actually present before anything
//! is allocated, so a malformed or lying file gives an error naming the problem, never a panic or
//! a huge allocation.

use super::write_atomic;
use crate::{Error, Result};
use base64::Engine;
use nalgebra::Point3;
use quick_xml::events::{BytesStart, Event};
use std::borrow::Cow;
use std::io::{Read, Write};
use std::path::Path;

/// The values of a data array, in tuple order (components of one tuple adjacent).
#[derive(Clone, Debug, PartialEq)]
pub enum DataValues {
    F32(Vec<f32>),
    F64(Vec<f64>),
    I32(Vec<i32>),
    U8(Vec<u8>),
}

impl DataValues {
    /// Number of values (tuples × components).
    pub fn len(&self) -> usize {
        match self {
            DataValues::F32(v) => v.len(),
            DataValues::F64(v) => v.len(),
            DataValues::I32(v) => v.len(),
            DataValues::U8(v) => v.len(),
        }
    }

    /// Whether there is no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values as f64 (exact for every variant).
    pub fn to_f64(&self) -> Vec<f64> {
        match self {
            DataValues::F32(v) => v.iter().map(|&x| x as f64).collect(),
            DataValues::F64(v) => v.clone(),
            DataValues::I32(v) => v.iter().map(|&x| x as f64).collect(),
            DataValues::U8(v) => v.iter().map(|&x| x as f64).collect(),
        }
    }

    /// VTK's name of the value type.
    fn vtk_type(&self) -> &'static str {
        match self {
            DataValues::F32(_) => "Float32",
            DataValues::F64(_) => "Float64",
            DataValues::I32(_) => "Int32",
            DataValues::U8(_) => "UInt8",
        }
    }

    /// Size of one value in bytes.
    fn value_size(&self) -> usize {
        match self {
            DataValues::F32(_) | DataValues::I32(_) => 4,
            DataValues::F64(_) => 8,
            DataValues::U8(_) => 1,
        }
    }

    /// The values' bytes, little-endian.
    fn write_le(&self, w: &mut dyn Write) -> std::io::Result<()> {
        const CHUNK: usize = 8192;
        let mut buf = Vec::with_capacity(CHUNK * 8);
        macro_rules! put {
            ($v:expr) => {
                for chunk in $v.chunks(CHUNK) {
                    buf.clear();
                    for x in chunk {
                        buf.extend_from_slice(&x.to_le_bytes());
                    }
                    w.write_all(&buf)?;
                }
            };
        }
        match self {
            DataValues::F32(v) => put!(v),
            DataValues::F64(v) => put!(v),
            DataValues::I32(v) => put!(v),
            DataValues::U8(v) => w.write_all(v)?,
        }
        Ok(())
    }

    /// The values' bytes, little-endian, in memory.
    fn le_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.len() * self.value_size());
        self.write_le(&mut out)
            .expect("writing to a Vec cannot fail");
        out
    }

    /// The values as text separated by spaces, `{:?}` for floats (shortest exact form).
    fn write_ascii(&self, w: &mut dyn Write) -> std::io::Result<()> {
        fn put<T>(w: &mut dyn Write, v: &[T], f: impl Fn(&T) -> String) -> std::io::Result<()> {
            for (k, line) in v.chunks(12).enumerate() {
                if k > 0 {
                    w.write_all(b"\n")?;
                }
                let text: Vec<String> = line.iter().map(&f).collect();
                w.write_all(text.join(" ").as_bytes())?;
            }
            Ok(())
        }
        match self {
            DataValues::F32(v) => put(w, v, |x| format!("{x:?}")),
            DataValues::F64(v) => put(w, v, |x| format!("{x:?}")),
            DataValues::I32(v) => put(w, v, |x| x.to_string()),
            DataValues::U8(v) => put(w, v, |x| x.to_string()),
        }
    }

    /// Appends `other`, which must be of the same variant.
    fn extend(&mut self, other: &DataValues) -> bool {
        match (self, other) {
            (DataValues::F32(a), DataValues::F32(b)) => a.extend_from_slice(b),
            (DataValues::F64(a), DataValues::F64(b)) => a.extend_from_slice(b),
            (DataValues::I32(a), DataValues::I32(b)) => a.extend_from_slice(b),
            (DataValues::U8(a), DataValues::U8(b)) => a.extend_from_slice(b),
            _ => return false,
        }
        true
    }

    /// The tuples `range` (in tuples of `components` values).
    fn tuples(&self, components: usize, range: std::ops::Range<usize>) -> DataValues {
        let r = range.start * components..range.end * components;
        match self {
            DataValues::F32(v) => DataValues::F32(v[r].to_vec()),
            DataValues::F64(v) => DataValues::F64(v[r].to_vec()),
            DataValues::I32(v) => DataValues::I32(v[r].to_vec()),
            DataValues::U8(v) => DataValues::U8(v[r].to_vec()),
        }
    }

    /// Tuple `t` repeated `n` times, appended to `self` (same variant as `from`).
    fn push_repeated(&mut self, from: &DataValues, components: usize, t: usize, n: usize) {
        let r = t * components..(t + 1) * components;
        match (self, from) {
            (DataValues::F32(a), DataValues::F32(b)) => {
                (0..n).for_each(|_| a.extend_from_slice(&b[r.clone()]))
            }
            (DataValues::F64(a), DataValues::F64(b)) => {
                (0..n).for_each(|_| a.extend_from_slice(&b[r.clone()]))
            }
            (DataValues::I32(a), DataValues::I32(b)) => {
                (0..n).for_each(|_| a.extend_from_slice(&b[r.clone()]))
            }
            (DataValues::U8(a), DataValues::U8(b)) => {
                (0..n).for_each(|_| a.extend_from_slice(&b[r.clone()]))
            }
            _ => unreachable!("push_repeated between arrays of one type"),
        }
    }
}

/// A named data array of `components` values per tuple (point or cell).
#[derive(Clone, Debug, PartialEq)]
pub struct DataArray {
    pub name: String,
    pub components: usize,
    pub values: DataValues,
}

impl DataArray {
    /// A one-component array.
    pub fn scalars(name: &str, values: DataValues) -> Self {
        DataArray {
            name: name.to_string(),
            components: 1,
            values,
        }
    }

    /// Number of tuples (0 when `components` is 0).
    pub fn num_tuples(&self) -> usize {
        self.values.len().checked_div(self.components).unwrap_or(0)
    }
}

/// Points, polygons and polylines with point and cell data.
///
/// `polys` and `lines` hold indices into `points`. `point_data` arrays hold one tuple per point;
/// `cell_data` arrays one tuple per line first, then one per polygon (VTK's cell order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolyData {
    pub points: Vec<[f64; 3]>,
    pub polys: Vec<Vec<u32>>,
    pub lines: Vec<Vec<u32>>,
    pub point_data: Vec<DataArray>,
    pub cell_data: Vec<DataArray>,
}

impl PolyData {
    /// Number of cells: lines then polygons.
    pub fn num_cells(&self) -> usize {
        self.lines.len() + self.polys.len()
    }

    /// A triangle mesh as polygons, without data.
    pub fn from_mesh(mesh: &crate::TriMesh) -> Self {
        PolyData {
            points: mesh.vertices.iter().map(|p| [p.x, p.y, p.z]).collect(),
            polys: mesh.faces.iter().map(|f| f.to_vec()).collect(),
            ..PolyData::default()
        }
    }

    /// The polygons as a triangle mesh (unvalidated): each polygon of n > 3 corners is cut into the
    /// fan of n − 2 triangles from its first corner; lines are ignored. A polygon of fewer than 3
    /// corners is an error.
    pub fn to_mesh(&self) -> std::result::Result<crate::TriMesh, String> {
        let mut faces = Vec::with_capacity(self.polys.len());
        for (k, poly) in self.polys.iter().enumerate() {
            if poly.len() < 3 {
                return Err(format!(
                    "polygon {k} has {} corners (at least 3 needed)",
                    poly.len()
                ));
            }
            super::fan_triangulate(poly, &mut faces);
        }
        let vertices = self
            .points
            .iter()
            .map(|&[x, y, z]| Point3::new(x, y, z))
            .collect();
        Ok(crate::TriMesh::new(vertices, faces))
    }

    /// Checks what a writer needs: indices in range, lines of at least 2 points and polygons of at
    /// least 3, data arrays of ≥ 1 component with one tuple per point or cell, names non-empty and
    /// unique within point data and within cell data.
    pub fn check(&self) -> std::result::Result<(), String> {
        let n = self.points.len();
        for (kind, cells, least) in [("line", &self.lines, 2), ("polygon", &self.polys, 3)] {
            for (k, cell) in cells.iter().enumerate() {
                if cell.len() < least {
                    return Err(format!(
                        "{kind} {k} has {} points (at least {least} needed)",
                        cell.len()
                    ));
                }
                if let Some(&v) = cell.iter().find(|&&v| v as usize >= n) {
                    return Err(format!(
                        "{kind} {k} references point {v} but only {n} points exist"
                    ));
                }
            }
        }
        for (what, arrays, count) in [
            ("point", &self.point_data, n),
            ("cell", &self.cell_data, self.num_cells()),
        ] {
            for (k, a) in arrays.iter().enumerate() {
                if a.name.is_empty() {
                    return Err(format!("{what}-data array {k} has no name"));
                }
                if arrays[..k].iter().any(|b| b.name == a.name) {
                    return Err(format!(
                        "{what}-data array name '{}' is given twice",
                        a.name
                    ));
                }
                if a.components == 0 || Some(a.values.len()) != count.checked_mul(a.components) {
                    return Err(format!(
                        "{what}-data array '{}' has {} values in {} components but there are {count} {what}s",
                        a.name,
                        a.values.len(),
                        a.components
                    ));
                }
            }
        }
        Ok(())
    }
}

/// How [`write_vtp_encoded_to`] stores the arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VtpEncoding {
    /// Values as decimal text inside each DataArray.
    Ascii,
    /// UInt64 byte count and values, base64-encoded together inside each DataArray (pure XML).
    Base64,
    /// Raw bytes in the `<AppendedData encoding="raw">` section (VTK's default layout).
    #[default]
    Appended,
}

/// Writes `data` to `path` as VTK XML PolyData, raw appended (atomic). See the module doc.
pub fn write_vtp(path: &Path, data: &PolyData) -> Result<()> {
    data.check().map_err(|m| Error::format(path, m))?;
    write_atomic(path, |w| {
        write_file(w, data, VtpEncoding::Appended).map_err(|e| Error::io(path, e))
    })
}

/// Writes `data` as VTK XML PolyData, raw appended, to a stream.
pub fn write_vtp_to(out: &mut dyn Write, data: &PolyData) -> Result<()> {
    write_vtp_encoded_to(out, data, VtpEncoding::Appended)
}

/// Writes `data` as VTK XML PolyData with the given encoding to a stream.
pub fn write_vtp_encoded_to(
    out: &mut dyn Write,
    data: &PolyData,
    encoding: VtpEncoding,
) -> Result<()> {
    data.check().map_err(Error::InvalidMesh)?;
    write_file(out, data, encoding).map_err(|e| Error::io(Path::new("<output stream>"), e))
}

/// One array to write: its XML attributes and values.
struct Out<'a> {
    name: &'a str,
    components: usize,
    values: Cow<'a, DataValues>,
}

/// An array's payload for writing: typed values or already-encoded Int64 bytes.
enum Payload<'a> {
    Values(Out<'a>),
    Int64 {
        name: &'static str,
        bytes: Vec<u8>,
        count: usize,
    },
}

impl Payload<'_> {
    fn header(&self) -> (String, String, usize) {
        match self {
            Payload::Values(o) => (o.values.vtk_type().into(), o.name.into(), o.components),
            Payload::Int64 { name, .. } => ("Int64".into(), (*name).into(), 1),
        }
    }
    fn byte_len(&self) -> u64 {
        match self {
            Payload::Values(o) => (o.values.len() * o.values.value_size()) as u64,
            Payload::Int64 { bytes, .. } => bytes.len() as u64,
        }
    }
    fn write_le(&self, w: &mut dyn Write) -> std::io::Result<()> {
        match self {
            Payload::Values(o) => o.values.write_le(w),
            Payload::Int64 { bytes, .. } => w.write_all(bytes),
        }
    }
    fn le_bytes(&self) -> Vec<u8> {
        match self {
            Payload::Values(o) => o.values.le_bytes(),
            Payload::Int64 { bytes, .. } => bytes.clone(),
        }
    }
    fn write_ascii(&self, w: &mut dyn Write) -> std::io::Result<()> {
        match self {
            Payload::Values(o) => o.values.write_ascii(w),
            Payload::Int64 { bytes, count, .. } => {
                let v: Vec<String> = (0..*count)
                    .map(|k| {
                        i64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().unwrap()).to_string()
                    })
                    .collect();
                w.write_all(v.join(" ").as_bytes())
            }
        }
    }
}

/// Connectivity and end offsets of cells: Int32, or Int64 when a count or index exceeds i32.
fn cell_payloads(cells: &[Vec<u32>]) -> [Payload<'static>; 2] {
    let total: usize = cells.iter().map(Vec::len).sum();
    let wide = total > i32::MAX as usize || cells.iter().flatten().any(|&v| v > i32::MAX as u32);
    if wide {
        let mut conn = Vec::with_capacity(8 * total);
        let mut offsets = Vec::with_capacity(8 * cells.len());
        let mut end = 0i64;
        for c in cells {
            for &v in c {
                conn.extend_from_slice(&(v as i64).to_le_bytes());
            }
            end += c.len() as i64;
            offsets.extend_from_slice(&end.to_le_bytes());
        }
        return [
            Payload::Int64 {
                name: "connectivity",
                bytes: conn,
                count: total,
            },
            Payload::Int64 {
                name: "offsets",
                bytes: offsets,
                count: cells.len(),
            },
        ];
    }
    let conn = cells.iter().flatten().map(|&v| v as i32).collect();
    let mut end = 0i32;
    let offsets = cells
        .iter()
        .map(|c| {
            end += c.len() as i32;
            end
        })
        .collect();
    [
        Payload::Values(Out {
            name: "connectivity",
            components: 1,
            values: Cow::Owned(DataValues::I32(conn)),
        }),
        Payload::Values(Out {
            name: "offsets",
            components: 1,
            values: Cow::Owned(DataValues::I32(offsets)),
        }),
    ]
}

fn xml_escape(s: &str) -> Cow<'_, str> {
    quick_xml::escape::escape(s)
}

/// The data arrays of one section, borrowed for writing.
fn array_payloads(list: &[DataArray]) -> Vec<Payload<'_>> {
    list.iter()
        .map(|a| {
            Payload::Values(Out {
                name: &a.name,
                components: a.components,
                values: Cow::Borrowed(&a.values),
            })
        })
        .collect()
}

pub(super) fn write_file(
    w: &mut dyn Write,
    data: &PolyData,
    encoding: VtpEncoding,
) -> std::io::Result<()> {
    let points = Payload::Values(Out {
        name: "Points",
        components: 3,
        values: Cow::Owned(DataValues::F64(
            data.points.iter().flatten().copied().collect(),
        )),
    });
    let empty: &[Vec<u32>] = &[];
    let sections: [(&str, Vec<Payload>); 7] = [
        ("PointData", array_payloads(&data.point_data)),
        ("CellData", array_payloads(&data.cell_data)),
        ("Points", vec![points]),
        ("Verts", cell_payloads(empty).into()),
        ("Lines", cell_payloads(&data.lines).into()),
        ("Strips", cell_payloads(empty).into()),
        ("Polys", cell_payloads(&data.polys).into()),
    ];
    write!(
        w,
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n\
         \x20 <PolyData>\n\
         \x20   <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" NumberOfPolys=\"{}\">\n",
        data.points.len(),
        data.lines.len(),
        data.polys.len()
    )?;
    let mut offset = 0u64;
    for (section, arrays) in &sections {
        let active = match *section {
            "PointData" | "CellData" => arrays.iter().find_map(|p| match p {
                Payload::Values(o) if o.components == 1 => Some(o.name),
                _ => None,
            }),
            _ => None,
        };
        match active {
            Some(name) => writeln!(w, "      <{section} Scalars=\"{}\">", xml_escape(name))?,
            None => writeln!(w, "      <{section}>")?,
        }
        for p in arrays {
            let (ty, name, components) = p.header();
            write!(
                w,
                "        <DataArray type=\"{ty}\" Name=\"{}\" NumberOfComponents=\"{components}\"",
                xml_escape(&name)
            )?;
            match encoding {
                VtpEncoding::Appended => {
                    writeln!(w, " format=\"appended\" offset=\"{offset}\"/>")?;
                    offset += 8 + p.byte_len();
                }
                VtpEncoding::Base64 => {
                    w.write_all(b" format=\"binary\">\n")?;
                    let mut bytes = p.byte_len().to_le_bytes().to_vec();
                    bytes.extend_from_slice(&p.le_bytes());
                    w.write_all(
                        base64::engine::general_purpose::STANDARD
                            .encode(&bytes)
                            .as_bytes(),
                    )?;
                    w.write_all(b"\n        </DataArray>\n")?;
                }
                VtpEncoding::Ascii => {
                    w.write_all(b" format=\"ascii\">\n")?;
                    p.write_ascii(w)?;
                    w.write_all(b"\n        </DataArray>\n")?;
                }
            }
        }
        writeln!(w, "      </{section}>")?;
    }
    w.write_all(b"    </Piece>\n  </PolyData>\n")?;
    if encoding == VtpEncoding::Appended {
        w.write_all(b"  <AppendedData encoding=\"raw\">\n   _")?;
        for (_, arrays) in &sections {
            for p in arrays {
                w.write_all(&p.byte_len().to_le_bytes())?;
                p.write_le(w)?;
            }
        }
        w.write_all(b"\n  </AppendedData>\n")?;
    }
    w.write_all(b"</VTKFile>\n")
}

// ---------------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------------

/// Reads a VTK XML PolyData file (see the module doc for what is accepted).
pub fn read_vtp(path: &Path) -> Result<PolyData> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_vtp(&bytes).map_err(|m| Error::format(path, m))
}

/// Parses VTK XML PolyData bytes.
pub(crate) fn parse_vtp(bytes: &[u8]) -> std::result::Result<PolyData, String> {
    if bytes.is_empty() {
        return Err("empty file".into());
    }
    let file = parse_structure(bytes)?;
    // Starts of all appended arrays, sorted: where each base64 appended array's text ends.
    let mut ends: Vec<u64> = file
        .pieces
        .iter()
        .flat_map(|p| {
            p.point_data
                .iter()
                .chain(&p.cell_data)
                .chain(&p.coordinates)
                .chain(
                    p.topology
                        .iter()
                        .flat_map(|t| t.connectivity.iter().chain(&t.offsets)),
                )
        })
        .filter(|d| d.format == Format::Appended)
        .map(|d| d.offset)
        .collect();
    ends.sort_unstable();
    ends.dedup();
    let mut pieces = Vec::with_capacity(file.pieces.len());
    for (k, piece) in file.pieces.iter().enumerate() {
        let p = read_piece(&file, piece, bytes, &ends).map_err(|m| {
            if file.pieces.len() > 1 {
                format!("piece {k}: {m}")
            } else {
                m
            }
        })?;
        pieces.push(p);
    }
    merge_pieces(pieces)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Ty {
    fn from_name(name: &str) -> Option<Ty> {
        Some(match name {
            "Int8" | "Char" => Ty::I8,
            "UInt8" => Ty::U8,
            "Int16" => Ty::I16,
            "UInt16" => Ty::U16,
            "Int32" => Ty::I32,
            "UInt32" => Ty::U32,
            "Int64" | "IdType" => Ty::I64,
            "UInt64" => Ty::U64,
            "Float32" => Ty::F32,
            "Float64" => Ty::F64,
            _ => return None,
        })
    }
    pub(super) fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::I64 | Ty::U64 | Ty::F64 => 8,
        }
    }
    pub(super) fn is_float(self) -> bool {
        matches!(self, Ty::F32 | Ty::F64)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Binary,
    Appended,
}

#[derive(Debug)]
struct ArrayDesc {
    /// None for a type we skip (String, Bit, ...), with its name kept for messages.
    ty: Option<Ty>,
    type_name: String,
    name: String,
    components: usize,
    format: Format,
    offset: u64,
    text: Vec<u8>,
}

#[derive(Debug, Default)]
struct CellDesc {
    connectivity: Option<ArrayDesc>,
    offsets: Option<ArrayDesc>,
}

/// Cell kinds in VTK's cell order.
const VERTS: usize = 0;
const LINES: usize = 1;
const POLYS: usize = 2;
const STRIPS: usize = 3;
const CELL_NAMES: [&str; 4] = ["Verts", "Lines", "Polys", "Strips"];

#[derive(Debug, Default)]
struct PieceDesc {
    points: u64,
    cells: [u64; 4],
    point_data: Vec<ArrayDesc>,
    cell_data: Vec<ArrayDesc>,
    coordinates: Option<ArrayDesc>,
    topology: [CellDesc; 4],
}

#[derive(Debug)]
enum Appended {
    None,
    /// Byte position of the first byte after `_`.
    Raw(usize),
    /// The base64 text after `_` (whitespace-free prefix up to `<` or the end).
    Base64(usize, usize),
}

#[derive(Debug)]
struct FileDesc {
    big_endian: bool,
    header64: bool,
    compressed: bool,
    pieces: Vec<PieceDesc>,
    appended: Appended,
}

/// Where a DataArray being read belongs.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    PointData,
    CellData,
    Points,
    Cells(usize),
    Ignored,
}

fn attr(e: &BytesStart, key: &str) -> std::result::Result<Option<String>, String> {
    match e.try_get_attribute(key) {
        Ok(Some(a)) => a
            .normalized_value(quick_xml::XmlVersion::Implicit1_0)
            .map(|v| Some(v.into_owned()))
            .map_err(|err| format!("bad value of attribute {key}: {err}")),
        Ok(None) => Ok(None),
        Err(err) => Err(format!("bad attributes in <{}>: {err}", e.name().as_ref())),
    }
}

fn count_attr(e: &BytesStart, key: &str) -> std::result::Result<u64, String> {
    match attr(e, key)? {
        None => Ok(0),
        Some(v) => v
            .trim()
            .parse::<u64>()
            .map_err(|_| format!("{key}=\"{v}\" is not a count")),
    }
}

/// Reads the XML structure (everything up to the appended data).
fn parse_structure(bytes: &[u8]) -> std::result::Result<FileDesc, String> {
    let mut reader = quick_xml::Reader::from_reader(bytes);
    let mut file = FileDesc {
        big_endian: false,
        header64: false,
        compressed: false,
        pieces: Vec::new(),
        appended: Appended::None,
    };
    let mut seen_root = false;
    // Open elements; the DataArray being read, if any, with where it goes.
    let mut stack: Vec<String> = Vec::new();
    let mut current: Option<(ArrayDesc, Slot)> = None;
    loop {
        let pos = reader.buffer_position();
        let event = reader
            .read_event()
            .map_err(|e| format!("not well-formed XML near byte {pos}: {e}"))?;
        let (e, empty) = match event {
            Event::Eof => break,
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(_) => {
                if stack.pop().as_deref() == Some("DataArray") {
                    finish_array(&mut file, current.take())?;
                }
                continue;
            }
            Event::Text(t) => {
                if let Some((desc, _)) = &mut current {
                    if stack.last().map(String::as_str) == Some("DataArray") {
                        desc.text.extend_from_slice(t.as_bytes());
                    }
                }
                continue;
            }
            Event::CData(t) => {
                if let Some((desc, _)) = &mut current {
                    desc.text.extend_from_slice(t.as_bytes());
                }
                continue;
            }
            Event::GeneralRef(_) if current.is_some() => {
                return Err("entity reference inside a DataArray".into());
            }
            _ => continue,
        };
        let name = e.name().as_ref().to_string();
        let parent = stack.last().map(String::as_str);
        match (parent, name.as_str()) {
            (None, "VTKFile") => {
                seen_root = true;
                let ty = attr(&e, "type")?.unwrap_or_default();
                if ty != "PolyData" {
                    return Err(format!("a VTK XML file of type '{ty}', not PolyData"));
                }
                file.big_endian = match attr(&e, "byte_order")?.as_deref() {
                    None | Some("LittleEndian") => false,
                    Some("BigEndian") => true,
                    Some(o) => return Err(format!("unknown byte_order '{o}'")),
                };
                file.header64 = match attr(&e, "header_type")?.as_deref() {
                    None | Some("UInt32") => false,
                    Some("UInt64") => true,
                    Some(h) => return Err(format!("unknown header_type '{h}'")),
                };
                file.compressed = match attr(&e, "compressor")?.as_deref() {
                    None | Some("") => false,
                    Some("vtkZLibDataCompressor") => true,
                    Some(c) => {
                        return Err(format!(
                            "compressed with {c}, which is not read (only vtkZLibDataCompressor or no compression)"
                        ))
                    }
                };
            }
            (None, other) => return Err(format!("root element <{other}> is not <VTKFile>")),
            (Some("VTKFile"), "PolyData") => {}
            (Some("PolyData"), "Piece") => {
                let mut p = PieceDesc {
                    points: count_attr(&e, "NumberOfPoints")?,
                    ..PieceDesc::default()
                };
                for (k, kind) in CELL_NAMES.iter().enumerate() {
                    p.cells[k] = count_attr(&e, &format!("NumberOf{kind}"))?;
                }
                file.pieces.push(p);
            }
            (Some("VTKFile"), "AppendedData") => {
                let encoding = attr(&e, "encoding")?.unwrap_or_else(|| "raw".into());
                let after = (reader.buffer_position() as usize).min(bytes.len());
                let rest = &bytes[after..];
                let skip = rest.iter().position(|b| !b.is_ascii_whitespace());
                let start = match skip {
                    Some(s) if !empty && rest[s] == b'_' => after + s + 1,
                    _ => return Err("<AppendedData> does not start with '_'".into()),
                };
                file.appended = match encoding.as_str() {
                    "raw" => Appended::Raw(start),
                    "base64" => {
                        let len = bytes[start..]
                            .iter()
                            .position(|&b| b == b'<' || b.is_ascii_whitespace())
                            .unwrap_or(bytes.len() - start);
                        Appended::Base64(start, start + len)
                    }
                    other => return Err(format!("unknown AppendedData encoding '{other}'")),
                };
                // The appended bytes are not XML: stop here.
                break;
            }
            (Some(p), "DataArray") => {
                let slot = match (p, stack.len()) {
                    ("PointData", 4) => Slot::PointData,
                    ("CellData", 4) => Slot::CellData,
                    ("Points", 4) => Slot::Points,
                    (kind, 4) if CELL_NAMES.contains(&kind) => {
                        Slot::Cells(CELL_NAMES.iter().position(|k| *k == kind).unwrap())
                    }
                    _ => Slot::Ignored,
                };
                if current.is_some() {
                    return Err("a DataArray inside a DataArray".into());
                }
                let desc = array_desc(&e)?;
                if empty {
                    finish_array(&mut file, Some((desc, slot)))?;
                } else {
                    current = Some((desc, slot));
                }
            }
            _ => {}
        }
        if !empty {
            stack.push(name);
        }
    }
    if !seen_root {
        return Err("no <VTKFile> element (not a VTK XML file)".into());
    }
    if file.pieces.is_empty() {
        return Err("no <Piece> in <PolyData>".into());
    }
    Ok(file)
}

fn array_desc(e: &BytesStart) -> std::result::Result<ArrayDesc, String> {
    let type_name = attr(e, "type")?.unwrap_or_default();
    let name = attr(e, "Name")?.unwrap_or_default();
    let components = match attr(e, "NumberOfComponents")? {
        None => 1,
        Some(v) => match v.trim().parse::<usize>() {
            Ok(c) if (1..=1024).contains(&c) => c,
            _ => {
                return Err(format!(
                    "DataArray '{name}': NumberOfComponents=\"{v}\" is not between 1 and 1024"
                ))
            }
        },
    };
    let format = match attr(e, "format")?.as_deref() {
        Some("ascii") => Format::Ascii,
        Some("binary") => Format::Binary,
        Some("appended") => Format::Appended,
        other => return Err(format!("DataArray '{name}': unknown format {other:?}")),
    };
    let offset = match (format, attr(e, "offset")?) {
        (Format::Appended, Some(v)) => v
            .trim()
            .parse::<u64>()
            .map_err(|_| format!("DataArray '{name}': offset=\"{v}\" is not a number"))?,
        (Format::Appended, None) => {
            return Err(format!("DataArray '{name}': appended without an offset"))
        }
        _ => 0,
    };
    Ok(ArrayDesc {
        ty: Ty::from_name(&type_name),
        type_name,
        name,
        components,
        format,
        offset,
        text: Vec::new(),
    })
}

fn finish_array(
    file: &mut FileDesc,
    current: Option<(ArrayDesc, Slot)>,
) -> std::result::Result<(), String> {
    let Some((desc, slot)) = current else {
        return Ok(());
    };
    let Some(piece) = file.pieces.last_mut() else {
        return Ok(());
    };
    match slot {
        Slot::PointData => piece.point_data.push(desc),
        Slot::CellData => piece.cell_data.push(desc),
        Slot::Points => {
            if piece.coordinates.is_none() {
                piece.coordinates = Some(desc);
            }
        }
        Slot::Cells(k) => match desc.name.as_str() {
            "connectivity" => piece.topology[k].connectivity = Some(desc),
            "offsets" => piece.topology[k].offsets = Some(desc),
            _ => {}
        },
        Slot::Ignored => {}
    }
    Ok(())
}

/// Decoded numbers of one array, in the widest form of their kind.
pub(super) enum Numbers {
    Int(Vec<i64>),
    Float(Vec<f64>),
}

/// Decodes base64 that may be several padded blocks one after the other (VTK encodes a
/// compressed array's header and its data separately), ignoring whitespace.
fn decode_base64(text: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let clean: Vec<u8> = text
        .iter()
        .copied()
        .filter(|b| !b.is_ascii_whitespace())
        .collect();
    if !clean.len().is_multiple_of(4) {
        return Err(format!(
            "base64 data of {} characters (not a multiple of 4)",
            clean.len()
        ));
    }
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    let mut start = 0;
    for group in 0..clean.len() / 4 {
        let end = 4 * group + 4;
        if clean[end - 1] == b'=' || end == clean.len() {
            base64::engine::general_purpose::STANDARD
                .decode_vec(&clean[start..end], &mut out)
                .map_err(|e| format!("bad base64 data: {e}"))?;
            start = end;
        }
    }
    Ok(out)
}

/// Reads an unsigned header word at `pos` of `bytes`.
fn header_word(bytes: &[u8], pos: usize, file: &FileDesc) -> Option<u64> {
    let size = if file.header64 { 8 } else { 4 };
    let b = bytes.get(pos..pos.checked_add(size)?)?;
    Some(match (file.header64, file.big_endian) {
        (true, false) => u64::from_le_bytes(b.try_into().ok()?),
        (true, true) => u64::from_be_bytes(b.try_into().ok()?),
        (false, false) => u32::from_le_bytes(b.try_into().ok()?) as u64,
        (false, true) => u32::from_be_bytes(b.try_into().ok()?) as u64,
    })
}

/// zlib's largest expansion ratio (a little over 1032:1), with room for stream overhead.
fn max_inflated(compressed: u64) -> u64 {
    compressed.saturating_mul(1032).saturating_add(1024)
}

/// The data bytes of a binary array whose header starts at `bytes[0]` (the slice may run on past
/// the array, as in raw appended data).
fn unpack<'a>(bytes: &'a [u8], file: &FileDesc) -> std::result::Result<Cow<'a, [u8]>, String> {
    let hs = if file.header64 { 8 } else { 4 };
    let short = || "data ends inside an array header".to_string();
    if !file.compressed {
        let n = header_word(bytes, 0, file).ok_or_else(short)?;
        let end = (hs as u64)
            .checked_add(n)
            .filter(|&e| e <= bytes.len() as u64)
            .ok_or_else(|| {
                format!(
                    "an array declares {n} bytes but only {} follow",
                    bytes.len().saturating_sub(hs)
                )
            })?;
        return Ok(Cow::Borrowed(&bytes[hs..end as usize]));
    }
    let blocks = header_word(bytes, 0, file).ok_or_else(short)?;
    let block_size = header_word(bytes, hs, file).ok_or_else(short)?;
    let last_size = header_word(bytes, 2 * hs, file).ok_or_else(short)?;
    let header_len = blocks
        .checked_add(3)
        .and_then(|b| b.checked_mul(hs as u64))
        .filter(|&l| l <= bytes.len() as u64)
        .ok_or_else(|| {
            format!("a compressed array declares {blocks} blocks, more than the data holds")
        })? as usize;
    let mut sizes = Vec::with_capacity(blocks as usize);
    let mut total_compressed = 0u64;
    for b in 0..blocks as usize {
        let s = header_word(bytes, (3 + b) * hs, file).ok_or_else(short)?;
        total_compressed = total_compressed.saturating_add(s);
        sizes.push(s);
    }
    if total_compressed > (bytes.len() - header_len) as u64 {
        return Err(format!(
            "a compressed array declares {total_compressed} bytes but only {} follow",
            bytes.len() - header_len
        ));
    }
    let mut out = Vec::new();
    let mut pos = header_len;
    for (b, &s) in sizes.iter().enumerate() {
        let want = if b + 1 == sizes.len() && last_size != 0 {
            last_size
        } else {
            block_size
        };
        if want > max_inflated(s) {
            return Err(format!("a compressed block of {s} bytes declares {want} bytes inflated, more than zlib allows"));
        }
        let chunk = &bytes[pos..pos + s as usize];
        pos += s as usize;
        let before = out.len();
        flate2::read::ZlibDecoder::new(chunk)
            .take(want + 1)
            .read_to_end(&mut out)
            .map_err(|e| format!("bad zlib data in block {b}: {e}"))?;
        if (out.len() - before) as u64 != want {
            return Err(format!(
                "compressed block {b} inflates to {} bytes, not the {want} declared",
                out.len() - before
            ));
        }
    }
    Ok(Cow::Owned(out))
}

/// Decodes the numbers of an array.
fn decode(
    desc: &ArrayDesc,
    file: &FileDesc,
    bytes: &[u8],
    ends: &[u64],
) -> std::result::Result<Numbers, String> {
    let ty = desc.ty.ok_or_else(|| {
        format!(
            "DataArray '{}' has unsupported type '{}'",
            desc.name, desc.type_name
        )
    })?;
    let data: Cow<[u8]> = match desc.format {
        Format::Ascii => return parse_ascii(&desc.text, ty),
        Format::Binary => {
            let decoded = decode_base64(&desc.text)?;
            Cow::Owned(unpack(&decoded, file)?.into_owned())
        }
        Format::Appended => match file.appended {
            Appended::None => {
                return Err("an array is appended but the file has no <AppendedData>".into())
            }
            Appended::Raw(start) => {
                let avail = (bytes.len() - start) as u64;
                if desc.offset >= avail {
                    return Err(format!(
                        "appended offset {} is past the end of the data ({avail} bytes)",
                        desc.offset
                    ));
                }
                let from = start + desc.offset as usize;
                // The array cannot run past the next array's start; giving it everything up to the
                // end is also safe since its header says its length and is checked.
                unpack(&bytes[from..], file)?
            }
            Appended::Base64(start, end) => {
                let avail = (end - start) as u64;
                if desc.offset >= avail {
                    return Err(format!(
                        "appended offset {} is past the end of the data ({avail} characters)",
                        desc.offset
                    ));
                }
                let stop = ends
                    .iter()
                    .copied()
                    .find(|&o| o > desc.offset)
                    .unwrap_or(avail)
                    .min(avail);
                let text = &bytes[start + desc.offset as usize..start + stop as usize];
                let decoded = decode_base64(text)?;
                Cow::Owned(unpack(&decoded, file)?.into_owned())
            }
        },
    };
    from_bytes(&data, ty, file.big_endian)
}

pub(super) fn from_bytes(data: &[u8], ty: Ty, big: bool) -> std::result::Result<Numbers, String> {
    let size = ty.size();
    if !data.len().is_multiple_of(size) {
        return Err(format!(
            "{} bytes of data do not hold whole {size}-byte values",
            data.len()
        ));
    }
    macro_rules! conv {
        ($t:ty, $wrap:ident, $as:ty) => {
            Numbers::$wrap(
                data.chunks_exact(size)
                    .map(|c| {
                        let a: [u8; std::mem::size_of::<$t>()] = c.try_into().unwrap();
                        (if big {
                            <$t>::from_be_bytes(a)
                        } else {
                            <$t>::from_le_bytes(a)
                        }) as $as
                    })
                    .collect(),
            )
        };
    }
    Ok(match ty {
        Ty::I8 => conv!(i8, Int, i64),
        Ty::U8 => conv!(u8, Int, i64),
        Ty::I16 => conv!(i16, Int, i64),
        Ty::U16 => conv!(u16, Int, i64),
        Ty::I32 => conv!(i32, Int, i64),
        Ty::U32 => conv!(u32, Int, i64),
        Ty::I64 => conv!(i64, Int, i64),
        Ty::U64 => {
            let v: Vec<u64> = data
                .chunks_exact(8)
                .map(|c| {
                    let a: [u8; 8] = c.try_into().unwrap();
                    if big {
                        u64::from_be_bytes(a)
                    } else {
                        u64::from_le_bytes(a)
                    }
                })
                .collect();
            if v.iter().all(|&x| x <= i64::MAX as u64) {
                Numbers::Int(v.into_iter().map(|x| x as i64).collect())
            } else {
                Numbers::Float(v.into_iter().map(|x| x as f64).collect())
            }
        }
        Ty::F32 => conv!(f32, Float, f64),
        Ty::F64 => conv!(f64, Float, f64),
    })
}

fn parse_ascii(text: &[u8], ty: Ty) -> std::result::Result<Numbers, String> {
    let text = std::str::from_utf8(text).map_err(|_| "ascii DataArray is not text".to_string())?;
    let tokens = text.split_ascii_whitespace();
    if ty.is_float() {
        tokens
            .map(|t| {
                t.parse::<f64>()
                    .map_err(|_| format!("'{t}' is not a number"))
            })
            .collect::<std::result::Result<Vec<_>, _>>()
            .map(|v| {
                Numbers::Float(if ty == Ty::F32 {
                    v.into_iter().map(|x| x as f32 as f64).collect()
                } else {
                    v
                })
            })
    } else {
        tokens
            .map(|t| {
                t.parse::<i64>()
                    .map_err(|_| format!("'{t}' is not an integer"))
            })
            .collect::<std::result::Result<Vec<_>, _>>()
            .map(Numbers::Int)
    }
}

/// The values of a point- or cell-data array in our types (see the module doc).
pub(super) fn data_values(numbers: Numbers, ty: Ty) -> DataValues {
    match numbers {
        Numbers::Float(v) if ty == Ty::F32 => {
            DataValues::F32(v.into_iter().map(|x| x as f32).collect())
        }
        Numbers::Float(v) => DataValues::F64(v),
        Numbers::Int(v) if ty == Ty::U8 => DataValues::U8(v.into_iter().map(|x| x as u8).collect()),
        Numbers::Int(v) => {
            if v.iter().all(|&x| i32::try_from(x).is_ok()) {
                DataValues::I32(v.into_iter().map(|x| x as i32).collect())
            } else {
                DataValues::F64(v.into_iter().map(|x| x as f64).collect())
            }
        }
    }
}

/// Cells read from connectivity and offsets: their point lists.
fn read_cells(
    kind: usize,
    desc: &CellDesc,
    count: u64,
    points: usize,
    file: &FileDesc,
    bytes: &[u8],
    ends: &[u64],
) -> std::result::Result<Vec<Vec<u32>>, String> {
    let name = CELL_NAMES[kind];
    if count == 0 {
        return Ok(Vec::new());
    }
    let (Some(conn), Some(offs)) = (&desc.connectivity, &desc.offsets) else {
        return Err(format!(
            "{count} {name} declared but no connectivity and offsets arrays"
        ));
    };
    let ints = |d: &ArrayDesc| -> std::result::Result<Vec<i64>, String> {
        match decode(d, file, bytes, ends).map_err(|m| format!("{name} {}: {m}", d.name))? {
            Numbers::Int(v) => Ok(v),
            Numbers::Float(_) => Err(format!("{name} {} is not an integer array", d.name)),
        }
    };
    let offsets = ints(offs)?;
    if offsets.len() as u64 != count {
        return Err(format!(
            "{name}: {} offsets for {count} cells",
            offsets.len()
        ));
    }
    let connectivity = ints(conn)?;
    let mut cells = Vec::with_capacity(offsets.len());
    let mut start = 0i64;
    for (c, &end) in offsets.iter().enumerate() {
        if end < start || end > connectivity.len() as i64 {
            return Err(format!(
                "{name}: offset {end} of cell {c} is out of order or past the {} connectivity entries",
                connectivity.len()
            ));
        }
        let mut cell = Vec::with_capacity((end - start) as usize);
        for &v in &connectivity[start as usize..end as usize] {
            if v < 0 || v as u64 >= points as u64 {
                return Err(format!(
                    "{name}: cell {c} references point {v} but only {points} points exist"
                ));
            }
            cell.push(v as u32);
        }
        cells.push(cell);
        start = end;
    }
    if start != connectivity.len() as i64 {
        return Err(format!(
            "{name}: the offsets end at {start} but there are {} connectivity entries",
            connectivity.len()
        ));
    }
    Ok(cells)
}

fn read_piece(
    file: &FileDesc,
    piece: &PieceDesc,
    bytes: &[u8],
    ends: &[u64],
) -> std::result::Result<PolyData, String> {
    let n = piece.points;
    let points = if n == 0 {
        Vec::new()
    } else {
        let desc = piece
            .coordinates
            .as_ref()
            .ok_or_else(|| format!("{n} points declared but no <Points> array"))?;
        if desc.components != 3 {
            return Err(format!(
                "the points have {} components, not 3",
                desc.components
            ));
        }
        let v = match decode(desc, file, bytes, ends).map_err(|m| format!("points: {m}"))? {
            Numbers::Float(v) => v,
            Numbers::Int(v) => v.into_iter().map(|x| x as f64).collect(),
        };
        if v.len() as u64 != n.saturating_mul(3) {
            return Err(format!("{} point coordinates for {n} points", v.len()));
        }
        v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
    };
    let np = points.len();

    let mut cells: [Vec<Vec<u32>>; 4] = Default::default();
    for kind in [VERTS, LINES, POLYS, STRIPS] {
        cells[kind] = read_cells(
            kind,
            &piece.topology[kind],
            piece.cells[kind],
            np,
            file,
            bytes,
            ends,
        )?;
    }
    let section =
        |descs: &[ArrayDesc], what: &str| -> std::result::Result<Vec<DataArray>, String> {
            let mut out = Vec::new();
            for desc in descs {
                let Some(ty) = desc.ty else { continue };
                let numbers = decode(desc, file, bytes, ends)
                    .map_err(|m| format!("{what} '{}': {m}", desc.name))?;
                out.push(DataArray {
                    name: desc.name.clone(),
                    components: desc.components,
                    values: data_values(numbers, ty),
                });
            }
            Ok(out)
        };
    let point_data = section(&piece.point_data, "point data")?;
    let cell_data = section(&piece.cell_data, "cell data")?;
    assemble(points, cells, point_data, cell_data)
}

/// A [`PolyData`] from VTK's parts: cells of the four kinds (verts, lines, polys, strips), point
/// data with one tuple per point and cell data with one tuple per cell of all four kinds in that
/// order (both checked here). Verts and their tuples are dropped; strips are cut into triangles
/// appended to the polygons, each repeating its strip's cell-data tuple.
pub(super) fn assemble(
    points: Vec<[f64; 3]>,
    cells: [Vec<Vec<u32>>; 4],
    point_data: Vec<DataArray>,
    mut cell_data: Vec<DataArray>,
) -> std::result::Result<PolyData, String> {
    let n = points.len();
    for a in &point_data {
        if a.components == 0 || Some(a.values.len()) != n.checked_mul(a.components) {
            return Err(format!(
                "point data '{}' has {} values, not {n} points × {} components",
                a.name,
                a.values.len(),
                a.components
            ));
        }
    }
    let [verts, lines, mut polys, strips] = cells;
    let [nv, nl, np, ns] = [verts.len(), lines.len(), polys.len(), strips.len()];
    let total = nv + nl + np + ns;
    for a in &mut cell_data {
        let c = a.components;
        if c == 0 || Some(a.values.len()) != total.checked_mul(c) {
            return Err(format!(
                "cell data '{}' has {} values, not {total} cells × {c} components",
                a.name,
                a.values.len()
            ));
        }
        if nv == 0 && ns == 0 {
            continue;
        }
        let mut kept = a.values.tuples(c, nv..nv + nl + np);
        for (s, strip) in strips.iter().enumerate() {
            kept.push_repeated(
                &a.values,
                c,
                nv + nl + np + s,
                strip.len().saturating_sub(2),
            );
        }
        a.values = kept;
    }
    for strip in &strips {
        for i in 0..strip.len().saturating_sub(2) {
            let (a, b, c) = (strip[i], strip[i + 1], strip[i + 2]);
            polys.push(if i % 2 == 0 {
                vec![a, b, c]
            } else {
                vec![b, a, c]
            });
        }
    }
    Ok(PolyData {
        points,
        polys,
        lines,
        point_data,
        cell_data,
    })
}

/// Concatenates pieces: points, lines and polygons in piece order (indices shifted), point data
/// likewise, cell data as all pieces' line tuples then all pieces' polygon tuples.
fn merge_pieces(mut pieces: Vec<PolyData>) -> std::result::Result<PolyData, String> {
    if pieces.len() == 1 {
        return Ok(pieces.pop().unwrap());
    }
    let first = &pieces[0];
    let mut out = PolyData {
        point_data: first
            .point_data
            .iter()
            .map(|a| DataArray {
                name: a.name.clone(),
                components: a.components,
                values: a.values.tuples(a.components, 0..0),
            })
            .collect(),
        cell_data: first
            .cell_data
            .iter()
            .map(|a| DataArray {
                name: a.name.clone(),
                components: a.components,
                values: a.values.tuples(a.components, 0..0),
            })
            .collect(),
        ..PolyData::default()
    };
    let mut poly_tuples: Vec<DataValues> = out.cell_data.iter().map(|a| a.values.clone()).collect();
    for (k, p) in pieces.iter().enumerate() {
        let base = out.points.len() as u64;
        if base + p.points.len() as u64 > u32::MAX as u64 {
            return Err("more than 2^32 points in all pieces".into());
        }
        let shift = |cells: &[Vec<u32>]| {
            cells
                .iter()
                .map(|c| c.iter().map(|&v| v + base as u32).collect())
                .collect::<Vec<_>>()
        };
        out.points.extend_from_slice(&p.points);
        out.lines.extend(shift(&p.lines));
        out.polys.extend(shift(&p.polys));
        let same = |a: &[DataArray], b: &[DataArray]| {
            a.len() == b.len()
                && a.iter().zip(b).all(|(x, y)| {
                    x.name == y.name
                        && x.components == y.components
                        && x.values.vtk_type() == y.values.vtk_type()
                })
        };
        if !same(&out.point_data, &p.point_data) || !same(&out.cell_data, &p.cell_data) {
            return Err(format!("piece {k} has other data arrays than piece 0"));
        }
        for (o, a) in out.point_data.iter_mut().zip(&p.point_data) {
            o.values.extend(&a.values);
        }
        let nl = p.lines.len();
        for ((o, pt), a) in out
            .cell_data
            .iter_mut()
            .zip(&mut poly_tuples)
            .zip(&p.cell_data)
        {
            let c = a.components;
            o.values.extend(&a.values.tuples(c, 0..nl));
            pt.extend(&a.values.tuples(c, nl..a.num_tuples()));
        }
    }
    for (o, pt) in out.cell_data.iter_mut().zip(&poly_tuples) {
        o.values.extend(pt);
    }
    Ok(out)
}
