//! Legacy VTK files (`.vtk`) of dataset POLYDATA: a reader of what VTK writes and a binary writer,
//! both through [`PolyData`] (points, polygons, polylines, point and cell data).
//!
//! **Written**: `# vtk DataFile Version 4.2`, `BINARY` (big-endian, as the format requires),
//! `POINTS n double` (exact coordinates), `LINES` and `POLYGONS` in the classic layout (each cell
//! as its size then its indices, 32-bit), then `POINT_DATA` and `CELL_DATA`, each with its first
//! array of 1 to 4 components as `SCALARS name type k` (`LOOKUP_TABLE default`, the active
//! scalars) and the others in a `FIELD` (VTK's reader keeps only the first SCALARS by default).
//! Types: float, double, int, unsigned_char. Names are written with VTK's `%XX` escapes for
//! spaces, `%` and non-printable bytes. This layout is read by every VTK since 4, ParaView and
//! 3D Slicer included.
//!
//! **Read**: `ASCII` and `BINARY`; the classic cell layout and VTK 9's (`# vtk DataFile Version
//! 5.1`: `OFFSETS` then `CONNECTIVITY` of any integer type); `VERTICES` (skipped with their
//! cell-data tuples), `LINES`, `POLYGONS` and `TRIANGLE_STRIPS` (cut into triangles, as in
//! [`read_vtp`](super::read_vtp)); point and cell data given as `SCALARS`, `VECTORS`, `NORMALS`,
//! `TENSORS`, `TEXTURE_COORDINATES`, `GLOBAL_IDS`, `COLOR_SCALARS` or `FIELD` arrays (value types
//! converted as `read_vtp` does); `METADATA` blocks and dataset-level `FIELD` data skipped.
//! Every declared count is checked against the bytes left before anything is allocated.

use super::vtp::{self, DataArray, DataValues, Numbers, PolyData, Ty};
use super::write_atomic;
use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Reads a legacy VTK POLYDATA file (ASCII or BINARY).
pub fn read_vtk_legacy(path: &Path) -> Result<PolyData> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_vtk_legacy(&bytes).map_err(|m| Error::format(path, m))
}

/// Writes `data` to `path` as a binary legacy VTK POLYDATA file (atomic).
pub fn write_vtk_legacy(path: &Path, data: &PolyData) -> Result<()> {
    check_writable(data).map_err(|m| Error::format(path, m))?;
    write_atomic(path, |w| {
        write_file(w, data).map_err(|e| Error::io(path, e))
    })
}

/// Writes `data` as a binary legacy VTK POLYDATA file to a stream.
pub fn write_vtk_legacy_to(out: &mut dyn Write, data: &PolyData) -> Result<()> {
    check_writable(data).map_err(Error::InvalidMesh)?;
    write_file(out, data).map_err(|e| Error::io(Path::new("<output stream>"), e))
}

pub(super) fn check_writable(data: &PolyData) -> std::result::Result<(), String> {
    data.check()?;
    for cells in [&data.lines, &data.polys] {
        let size: u64 = cells.iter().map(|c| c.len() as u64 + 1).sum();
        if size > i32::MAX as u64 || data.points.len() > i32::MAX as usize {
            return Err("too many cells or points for the legacy VTK format (32-bit)".into());
        }
    }
    Ok(())
}

/// A name with VTK's `%XX` escapes for bytes that would break the whitespace-separated syntax.
fn encode_name(name: &str) -> String {
    let mut out = String::new();
    for &b in name.as_bytes() {
        if b <= b' ' || b >= 0x7f || b == b'%' {
            out.push_str(&format!("%{b:02X}"));
        } else {
            out.push(b as char);
        }
    }
    out
}

fn decode_name(name: &str) -> String {
    let b = name.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = b
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok());
        match (b[i], hex.and_then(|h| u8::from_str_radix(h, 16).ok())) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn write_be(w: &mut dyn Write, values: &DataValues) -> std::io::Result<()> {
    let mut buf = Vec::with_capacity(values.len() * 8);
    match values {
        DataValues::F32(v) => v
            .iter()
            .for_each(|x| buf.extend_from_slice(&x.to_be_bytes())),
        DataValues::F64(v) => v
            .iter()
            .for_each(|x| buf.extend_from_slice(&x.to_be_bytes())),
        DataValues::I32(v) => v
            .iter()
            .for_each(|x| buf.extend_from_slice(&x.to_be_bytes())),
        DataValues::U8(v) => buf.extend_from_slice(v),
    }
    w.write_all(&buf)?;
    w.write_all(b"\n")
}

fn type_name(values: &DataValues) -> &'static str {
    match values {
        DataValues::F32(_) => "float",
        DataValues::F64(_) => "double",
        DataValues::I32(_) => "int",
        DataValues::U8(_) => "unsigned_char",
    }
}

pub(super) fn write_file(w: &mut dyn Write, data: &PolyData) -> std::io::Result<()> {
    write!(
        w,
        "# vtk DataFile Version 4.2\nvesselmsr\nBINARY\nDATASET POLYDATA\nPOINTS {} double\n",
        data.points.len()
    )?;
    write_be(
        w,
        &DataValues::F64(data.points.iter().flatten().copied().collect()),
    )?;
    for (keyword, cells) in [("LINES", &data.lines), ("POLYGONS", &data.polys)] {
        if cells.is_empty() {
            continue;
        }
        let mut flat = Vec::new();
        for c in cells.iter() {
            flat.push(c.len() as i32);
            flat.extend(c.iter().map(|&v| v as i32));
        }
        writeln!(w, "{keyword} {} {}", cells.len(), flat.len())?;
        write_be(w, &DataValues::I32(flat))?;
    }
    for (keyword, arrays, count) in [
        ("POINT_DATA", &data.point_data, data.points.len()),
        ("CELL_DATA", &data.cell_data, data.num_cells()),
    ] {
        if arrays.is_empty() {
            continue;
        }
        writeln!(w, "{keyword} {count}")?;
        // The first array of 1 to 4 components as the active SCALARS; every other one in a FIELD,
        // which VTK's reader always reads (it keeps only the first SCALARS by default).
        let first = arrays.iter().position(|a| a.components <= 4);
        if let Some(a) = first.map(|k| &arrays[k]) {
            writeln!(
                w,
                "SCALARS {} {} {}\nLOOKUP_TABLE default",
                encode_name(&a.name),
                type_name(&a.values),
                a.components
            )?;
            write_be(w, &a.values)?;
        }
        let wide: Vec<&DataArray> = (0..arrays.len())
            .filter(|&k| Some(k) != first)
            .map(|k| &arrays[k])
            .collect();
        if !wide.is_empty() {
            writeln!(w, "FIELD FieldData {}", wide.len())?;
            for a in wide {
                writeln!(
                    w,
                    "{} {} {count} {}",
                    encode_name(&a.name),
                    a.components,
                    type_name(&a.values)
                )?;
                write_be(w, &a.values)?;
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------------

/// A cursor over the file: keywords and ASCII values as whitespace-separated tokens, BINARY values
/// as big-endian bytes right after the line that announces them.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    binary: bool,
}

type Res<T> = std::result::Result<T, String>;

impl<'a> Cursor<'a> {
    fn line_no(&self) -> usize {
        1 + self.bytes[..self.pos.min(self.bytes.len())]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    /// The next token, or None at the end.
    fn token(&mut self) -> Option<&'a str> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return None;
        }
        // Binary bytes are never taken for a token except by a malformed file: lossy is enough.
        std::str::from_utf8(&self.bytes[start..self.pos])
            .ok()
            .or(Some("\u{fffd}"))
    }

    fn expect_token(&mut self, what: &str) -> Res<&'a str> {
        self.token()
            .ok_or_else(|| format!("file ends where {what} was expected"))
    }

    fn count(&mut self, what: &str) -> Res<u64> {
        let t = self.expect_token(what)?;
        t.parse::<u64>()
            .map_err(|_| format!("line {}: {what} '{t}' is not a count", self.line_no()))
    }

    /// The rest of the current line (without its newline), consumed.
    fn rest_of_line(&mut self) -> &'a [u8] {
        let start = self.pos;
        while self.pos < self.bytes.len() && self.bytes[self.pos] != b'\n' {
            self.pos += 1;
        }
        let line = &self.bytes[start..self.pos];
        if self.pos < self.bytes.len() {
            self.pos += 1;
        }
        line
    }

    /// Whether the next token (not consumed) is `word`, case-insensitively.
    fn peek_is(&self, word: &str) -> bool {
        let mut p = self.pos;
        while p < self.bytes.len() && self.bytes[p].is_ascii_whitespace() {
            p += 1;
        }
        let end = p + word.len();
        end <= self.bytes.len()
            && self.bytes[p..end].eq_ignore_ascii_case(word.as_bytes())
            && self.bytes.get(end).is_none_or(|b| b.is_ascii_whitespace())
    }

    /// `n` values of type `ty`: ASCII tokens, or big-endian bytes starting after the current line.
    fn values(&mut self, n: u64, ty: Ty, what: &str) -> Res<Numbers> {
        if self.binary {
            self.rest_of_line();
            let len = n
                .checked_mul(ty.size() as u64)
                .filter(|&l| l <= (self.bytes.len() - self.pos) as u64)
                .ok_or_else(|| {
                    format!(
                        "{what}: {n} values declared but the file ends after {} bytes",
                        self.bytes.len() - self.pos
                    )
                })? as usize;
            let data = &self.bytes[self.pos..self.pos + len];
            self.pos += len;
            return vtp::from_bytes(data, ty, true).map_err(|m| format!("{what}: {m}"));
        }
        if n > (self.bytes.len() - self.pos) as u64 {
            return Err(format!(
                "{what}: {n} values declared but only {} bytes are left",
                self.bytes.len() - self.pos
            ));
        }
        let n = n as usize;
        let short = |got: usize| format!("{what}: {n} values declared, the file ends after {got}");
        if ty.is_float() {
            let mut v = Vec::with_capacity(n);
            for k in 0..n {
                let t = self.token().ok_or_else(|| short(k))?;
                let x = t
                    .parse::<f64>()
                    .map_err(|_| format!("{what}: '{t}' is not a number"))?;
                v.push(if ty == Ty::F32 { x as f32 as f64 } else { x });
            }
            Ok(Numbers::Float(v))
        } else {
            let mut v = Vec::with_capacity(n);
            for k in 0..n {
                let t = self.token().ok_or_else(|| short(k))?;
                v.push(
                    t.parse::<i64>()
                        .map_err(|_| format!("{what}: '{t}' is not an integer"))?,
                );
            }
            Ok(Numbers::Int(v))
        }
    }

    fn ints(&mut self, n: u64, ty: Ty, what: &str) -> Res<Vec<i64>> {
        match self.values(n, ty, what)? {
            Numbers::Int(v) => Ok(v),
            Numbers::Float(_) => Err(format!("{what}: not an integer type")),
        }
    }

    fn data_type(&mut self, what: &str) -> Res<Ty> {
        let t = self.expect_token(what)?;
        legacy_type(t).ok_or_else(|| {
            format!(
                "line {}: {what}: unsupported data type '{t}'",
                self.line_no()
            )
        })
    }

    /// Skips a METADATA block: lines up to the first empty one.
    fn skip_metadata(&mut self) {
        self.rest_of_line();
        while self.pos < self.bytes.len() {
            if self.rest_of_line().iter().all(|b| b.is_ascii_whitespace()) {
                break;
            }
        }
    }
}

fn legacy_type(name: &str) -> Option<Ty> {
    Some(match name.to_ascii_lowercase().as_str() {
        "unsigned_char" => Ty::U8,
        "char" | "signed_char" => Ty::I8,
        "unsigned_short" => Ty::U16,
        "short" => Ty::I16,
        "unsigned_int" => Ty::U32,
        "int" => Ty::I32,
        "unsigned_long" | "vtktypeuint64" => Ty::U64,
        "long" | "vtktypeint64" | "vtkidtype" => Ty::I64,
        "float" => Ty::F32,
        "double" => Ty::F64,
        _ => return None,
    })
}

/// Parses legacy VTK POLYDATA bytes.
pub(crate) fn parse_vtk_legacy(bytes: &[u8]) -> Res<PolyData> {
    if bytes.is_empty() {
        return Err("empty file".into());
    }
    let mut c = Cursor {
        bytes,
        pos: 0,
        binary: false,
    };
    let first = c.rest_of_line();
    if !first.starts_with(b"# vtk DataFile") {
        return Err("not a legacy VTK file (no '# vtk DataFile Version' line)".into());
    }
    let version: f64 = std::str::from_utf8(first)
        .ok()
        .and_then(|l| l.split_whitespace().last())
        .and_then(|v| v.parse().ok())
        .unwrap_or(3.0);
    c.rest_of_line(); // title
    c.binary = match c
        .expect_token("ASCII or BINARY")?
        .to_ascii_uppercase()
        .as_str()
    {
        "ASCII" => false,
        "BINARY" => true,
        other => return Err(format!("line 3: '{other}' is neither ASCII nor BINARY")),
    };
    if !c.expect_token("DATASET")?.eq_ignore_ascii_case("DATASET") {
        return Err("line 4: DATASET expected".into());
    }
    let dataset = c.expect_token("the dataset type")?;
    if !dataset.eq_ignore_ascii_case("POLYDATA") {
        return Err(format!(
            "a legacy VTK file of dataset {dataset}, not POLYDATA"
        ));
    }
    let mut points: Option<Vec<[f64; 3]>> = None;
    let mut cells: [Vec<Vec<u32>>; 4] = Default::default();
    let mut point_data = Vec::new();
    let mut cell_data = Vec::new();
    // Where attribute arrays go: (true for point data, count), or None before POINT_DATA/CELL_DATA.
    let mut target: Option<(bool, u64)> = None;
    while let Some(keyword) = c.token() {
        let line = c.line_no();
        let keyword = keyword.to_ascii_uppercase();
        match keyword.as_str() {
            "POINTS" => {
                let n = c.count("the number of points")?;
                let ty = c.data_type("POINTS")?;
                let v = match c.values(n.saturating_mul(3), ty, "POINTS")? {
                    Numbers::Float(v) => v,
                    Numbers::Int(v) => v.into_iter().map(|x| x as f64).collect(),
                };
                points = Some(v.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect());
            }
            "VERTICES" | "LINES" | "POLYGONS" | "TRIANGLE_STRIPS" => {
                let kind = ["VERTICES", "LINES", "POLYGONS", "TRIANGLE_STRIPS"]
                    .iter()
                    .position(|k| *k == keyword)
                    .unwrap();
                let np = points
                    .as_ref()
                    .ok_or_else(|| format!("line {line}: {keyword} before POINTS"))?
                    .len();
                let a = c.count(&keyword)?;
                let b = c.count(&keyword)?;
                if c.binary {
                    c.rest_of_line();
                }
                cells[kind] = if c.peek_is("OFFSETS") {
                    c.token();
                    let ty = c.data_type("OFFSETS")?;
                    let offsets = c.ints(a, ty, "OFFSETS")?;
                    if !c
                        .expect_token("CONNECTIVITY")?
                        .eq_ignore_ascii_case("CONNECTIVITY")
                    {
                        return Err(format!("{keyword}: CONNECTIVITY expected after OFFSETS"));
                    }
                    let ty = c.data_type("CONNECTIVITY")?;
                    let conn = c.ints(b, ty, "CONNECTIVITY")?;
                    cells_from_offsets(&offsets, &conn, np)
                        .map_err(|m| format!("{keyword}: {m}"))?
                } else {
                    if version >= 5.0 {
                        return Err(format!(
                            "{keyword}: OFFSETS expected (file version {version})"
                        ));
                    }
                    if c.binary {
                        c.pos -= 1; // `values` skips to the end of the (already read) line
                    }
                    let flat = c.ints(b, Ty::I32, &keyword)?;
                    cells_from_sizes(a, &flat, np).map_err(|m| format!("{keyword}: {m}"))?
                };
            }
            "POINT_DATA" | "CELL_DATA" => {
                let n = c.count(&keyword)?;
                target = Some((keyword == "POINT_DATA", n));
            }
            "METADATA" => c.skip_metadata(),
            "FIELD" => {
                c.expect_token("the field name")?;
                let k = c.count("the number of field arrays")?;
                for _ in 0..k {
                    if c.peek_is("METADATA") {
                        c.token();
                        c.skip_metadata();
                    }
                    let name = decode_name(c.expect_token("a field array name")?);
                    let comps = c.count("the number of components")?;
                    let tuples = c.count("the number of tuples")?;
                    let ty = c.data_type(&name)?;
                    let numbers = c.values(comps.saturating_mul(tuples), ty, &name)?;
                    if let Some((to_points, count)) = target {
                        if tuples != count {
                            return Err(format!(
                                "field array '{name}' has {tuples} tuples, not {count}"
                            ));
                        }
                        push(
                            &mut point_data,
                            &mut cell_data,
                            to_points,
                            name,
                            comps,
                            numbers,
                            ty,
                        )?;
                    }
                }
            }
            "SCALARS"
            | "VECTORS"
            | "NORMALS"
            | "TENSORS"
            | "TEXTURE_COORDINATES"
            | "GLOBAL_IDS"
            | "COLOR_SCALARS" => {
                let (to_points, count) = target.ok_or_else(|| {
                    format!("line {line}: {keyword} outside POINT_DATA or CELL_DATA")
                })?;
                let name = decode_name(c.expect_token("an array name")?);
                let (comps, ty) = match keyword.as_str() {
                    "SCALARS" => {
                        let ty = c.data_type(&name)?;
                        // The optional component count is on the same line.
                        let rest = c.rest_of_line();
                        let comps = match std::str::from_utf8(rest).unwrap_or("").trim() {
                            "" => 1,
                            t => t.parse::<u64>().map_err(|_| {
                                format!(
                                    "line {line}: SCALARS {name}: '{t}' is not a component count"
                                )
                            })?,
                        };
                        // Required, as VTK's own reader requires it.
                        if !c.peek_is("LOOKUP_TABLE") {
                            return Err(format!(
                                "line {}: SCALARS {name}: LOOKUP_TABLE expected",
                                c.line_no()
                            ));
                        }
                        c.token();
                        c.expect_token("the lookup table name")?;
                        (comps, ty)
                    }
                    "VECTORS" | "NORMALS" => (3, c.data_type(&name)?),
                    "TENSORS" => (9, c.data_type(&name)?),
                    "TEXTURE_COORDINATES" => {
                        let d = c.count("the texture dimension")?;
                        (d, c.data_type(&name)?)
                    }
                    "GLOBAL_IDS" => (1, c.data_type(&name)?),
                    _ => {
                        let k = c.count("the number of color components")?;
                        (k, if c.binary { Ty::U8 } else { Ty::F32 })
                    }
                };
                if !(1..=1024).contains(&comps) {
                    return Err(format!("{name}: {comps} components"));
                }
                let numbers = c.values(count.saturating_mul(comps), ty, &name)?;
                push(
                    &mut point_data,
                    &mut cell_data,
                    to_points,
                    name,
                    comps,
                    numbers,
                    ty,
                )?;
            }
            "LOOKUP_TABLE" => {
                c.token();
                let n = c.count("the lookup table size")?;
                let ty = if c.binary { Ty::U8 } else { Ty::F32 };
                c.values(n.saturating_mul(4), ty, "LOOKUP_TABLE")?;
            }
            other => {
                return Err(format!("line {line}: unsupported section '{other}'"));
            }
        }
    }
    let points = points.ok_or("no POINTS")?;
    vtp::assemble(points, cells, point_data, cell_data)
}

fn push(
    point_data: &mut Vec<DataArray>,
    cell_data: &mut Vec<DataArray>,
    to_points: bool,
    name: String,
    components: u64,
    numbers: Numbers,
    ty: Ty,
) -> Res<()> {
    let list = if to_points { point_data } else { cell_data };
    if list.iter().any(|a| a.name == name) {
        return Err(format!("array '{name}' is given twice"));
    }
    list.push(DataArray {
        name,
        components: components as usize,
        values: vtp::data_values(numbers, ty),
    });
    Ok(())
}

fn point_index(v: i64, points: usize, cell: usize) -> Res<u32> {
    if v < 0 || v as u64 >= points as u64 {
        return Err(format!(
            "cell {cell} references point {v} but only {points} points exist"
        ));
    }
    Ok(v as u32)
}

/// Cells of VTK 9's layout: `offsets` (cell count + 1 entries, from 0) into `connectivity`.
fn cells_from_offsets(offsets: &[i64], connectivity: &[i64], points: usize) -> Res<Vec<Vec<u32>>> {
    if offsets.is_empty() {
        return if connectivity.is_empty() {
            Ok(Vec::new())
        } else {
            Err("connectivity without offsets".into())
        };
    }
    if offsets[0] != 0 || *offsets.last().unwrap() != connectivity.len() as i64 {
        return Err(format!(
            "offsets run from {} to {}, not from 0 to the {} connectivity entries",
            offsets[0],
            offsets.last().unwrap(),
            connectivity.len()
        ));
    }
    let mut cells = Vec::with_capacity(offsets.len() - 1);
    for (k, w) in offsets.windows(2).enumerate() {
        if w[1] < w[0] {
            return Err(format!("offsets decrease at cell {k}"));
        }
        let cell = connectivity[w[0] as usize..w[1] as usize]
            .iter()
            .map(|&v| point_index(v, points, k))
            .collect::<Res<Vec<u32>>>()?;
        cells.push(cell);
    }
    Ok(cells)
}

/// Cells of the classic layout: `count` runs of (size, indices…) filling `flat` exactly.
fn cells_from_sizes(count: u64, flat: &[i64], points: usize) -> Res<Vec<Vec<u32>>> {
    if count > flat.len() as u64 {
        return Err(format!("{count} cells declared in {} numbers", flat.len()));
    }
    let mut cells = Vec::with_capacity(count as usize);
    let mut pos = 0usize;
    for k in 0..count as usize {
        let size = *flat
            .get(pos)
            .ok_or_else(|| format!("the numbers end before cell {k}"))?;
        if size < 0 || size as u64 > (flat.len() - pos - 1) as u64 {
            return Err(format!(
                "cell {k} declares {size} points, more than the numbers left"
            ));
        }
        let cell = flat[pos + 1..pos + 1 + size as usize]
            .iter()
            .map(|&v| point_index(v, points, k))
            .collect::<Res<Vec<u32>>>()?;
        pos += 1 + size as usize;
        cells.push(cell);
    }
    if pos != flat.len() {
        return Err(format!(
            "{count} cells use {pos} numbers but {} are declared",
            flat.len()
        ));
    }
    Ok(cells)
}
