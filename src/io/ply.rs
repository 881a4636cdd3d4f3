//! PLY reading (ascii, binary_little_endian, binary_big_endian) and binary little-endian writing,
//! optionally with per-vertex float scalars (e.g. detail or label fields).
//!
//! The reader follows the PLY header: the `vertex` element must have scalar `x`, `y`, `z` of any
//! numeric type; the `face` element must have an integer list `vertex_indices` (or `vertex_index`);
//! polygons are fan-triangulated from their first corner. Every other element and property is
//! skipped according to its declared type. Other scalar properties of `vertex` are returned as
//! f32 fields. ASCII values are taken as written (parsed as f64 whatever the declared type); binary
//! values are read with their declared type. Before anything is allocated, the element counts of the header are checked against
//! the number of bytes the data section can hold, so a lying header cannot cause a huge allocation.

use super::text::{parse_f64, parse_i64, show, Tokens};
use super::ScalarFields as Fields;
use crate::TriMesh;
use nalgebra::Point3;
use std::io::Write;

/// Scalar types of the PLY format.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the data section.
    data_start: usize,
    /// Number of header lines (the data section of an ASCII file starts on the next line).
    lines: usize,
}

/// A mesh read from PLY with its extra per-vertex scalar properties, in header order.
pub(crate) struct PlyMesh {
    pub(crate) mesh: TriMesh,
    pub(crate) scalars: Fields,
}

/// Parses PLY bytes into an (unvalidated) mesh and its extra vertex scalars.
pub(crate) fn read(bytes: &[u8]) -> Result<PlyMesh, String> {
    let header = read_header(bytes)?;
    let data = &bytes[header.data_start..];
    check_counts(&header, data.len())?;
    let mut body = match header.encoding {
        Encoding::Ascii => Body::Ascii(Tokens::new(data, header.lines + 1)),
        enc => Body::Binary {
            data,
            pos: 0,
            big_endian: enc == Encoding::BigEndian,
        },
    };
    let mut vertices = None;
    let mut scalars = Vec::new();
    let mut faces = None;
    for element in &header.elements {
        match element.name.as_str() {
            "vertex" if vertices.is_none() => {
                let (v, s) = read_vertices(&mut body, element)?;
                vertices = Some(v);
                scalars = s;
            }
            "face" if faces.is_none() => faces = Some(read_faces(&mut body, element)?),
            "vertex" | "face" => {
                return Err(format!(
                    "PLY header declares a second '{}' element",
                    element.name
                ))
            }
            _ => skip_element(&mut body, element)?,
        }
    }
    let vertices = vertices.ok_or("PLY file has no 'vertex' element")?;
    Ok(PlyMesh {
        mesh: TriMesh::new(vertices, faces.unwrap_or_default()),
        scalars,
    })
}

fn read_header(bytes: &[u8]) -> Result<Header, String> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line_no = 0;
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(if line_no == 0 && !bytes.starts_with(b"ply") {
                "not a PLY file (the first line must be 'ply')".to_string()
            } else {
                "PLY header has no 'end_header' line".to_string()
            });
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        line_no += 1;
        let line = String::from_utf8_lossy(raw);
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        if line_no == 1 {
            if words != ["ply"] {
                return Err("not a PLY file (the first line must be 'ply')".to_string());
            }
            continue;
        }
        let bad = |what: &str| format!("PLY header line {line_no}: {what}: '{}'", show(raw));
        match words.first().copied() {
            Some("format") => {
                encoding = Some(match words.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::LittleEndian,
                    Some("binary_big_endian") => Encoding::BigEndian,
                    _ => return Err(bad("unknown format")),
                });
            }
            Some("comment") | Some("obj_info") | None => {}
            Some("element") => {
                let (Some(name), Some(count), None) = (words.get(1), words.get(2), words.get(3))
                else {
                    return Err(bad("expected 'element <name> <count>'"));
                };
                let count = count
                    .parse::<u64>()
                    .map_err(|_| bad("element count is not a non-negative integer"))?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            Some("property") => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element"))?;
                let scalar = |w: Option<&&str>| w.and_then(|w| Scalar::from_name(w));
                let (kind, name) = match words.as_slice() {
                    [_, "list", count, item, name] => {
                        let (Some(count), Some(item)) = (scalar(Some(count)), scalar(Some(item)))
                        else {
                            return Err(bad("unknown list type"));
                        };
                        if !count.is_integer() {
                            return Err(bad("list count type must be an integer type"));
                        }
                        (Kind::List { count, item }, name)
                    }
                    [_, ty, name] => (
                        Kind::Scalar(scalar(Some(ty)).ok_or_else(|| bad("unknown property type"))?),
                        name,
                    ),
                    _ => return Err(bad(
                        "expected 'property <type> <name>' or 'property list <type> <type> <name>'",
                    )),
                };
                element.properties.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            Some("end_header") => break,
            Some(_) => return Err(bad("unknown header keyword (is 'end_header' missing?)")),
        }
    }
    let encoding = encoding.ok_or("PLY header has no 'format' line")?;
    Ok(Header {
        encoding,
        elements,
        data_start: pos,
        lines: line_no,
    })
}

/// Checks that the data section can hold every declared element: each element needs at least its
/// smallest encoding (binary: sum of scalar and list-count sizes; ASCII: one character and one
/// separator per property).
fn check_counts(header: &Header, data_len: usize) -> Result<(), String> {
    // In ASCII the last value may lack its trailing separator.
    let mut left = data_len as u128 + u128::from(header.encoding == Encoding::Ascii);
    for e in &header.elements {
        let min: u128 = match header.encoding {
            Encoding::Ascii => 2 * e.properties.len() as u128,
            _ => e
                .properties
                .iter()
                .map(|p| match p.kind {
                    Kind::Scalar(s) | Kind::List { count: s, .. } => s.size() as u128,
                })
                .sum(),
        };
        if min == 0 {
            continue;
        }
        let need = min * e.count as u128;
        if need > left {
            return Err(format!(
                "PLY header declares {} '{}' elements but the data section ({} bytes) can hold at most {} more",
                e.count,
                e.name,
                data_len,
                left / min
            ));
        }
        left -= need;
    }
    Ok(())
}

/// The data section, read value by value.
enum Body<'a> {
    Ascii(Tokens<'a>),
    Binary {
        data: &'a [u8],
        pos: usize,
        big_endian: bool,
    },
}

/// Why a value could not be read.
enum ValueError {
    End,
    Bad(String),
}

macro_rules! binary_value {
    ($data:expr, $pos:expr, $big:expr, $t:ty) => {{
        const N: usize = std::mem::size_of::<$t>();
        let bytes: [u8; N] = $data
            .get(*$pos..*$pos + N)
            .ok_or(ValueError::End)?
            .try_into()
            .unwrap();
        *$pos += N;
        if $big {
            <$t>::from_be_bytes(bytes)
        } else {
            <$t>::from_le_bytes(bytes)
        }
    }};
}

/// A binary value as stored: integer types widened to i64, float types to f64.
enum Number {
    Int(i64),
    Float(f64),
}

/// The next ASCII token read by `parse`, or an error naming the line and what was expected.
fn ascii_value<T>(
    t: &mut Tokens<'_>,
    parse: fn(&[u8]) -> Option<T>,
    expected: &str,
) -> Result<T, ValueError> {
    let tok = t.next_token().ok_or(ValueError::End)?;
    parse(tok).ok_or_else(|| {
        ValueError::Bad(format!(
            "PLY line {}: '{}' is not {expected}",
            t.line(),
            show(tok)
        ))
    })
}

/// The next binary value of type `s` at `pos`, which it advances.
fn binary_number(
    data: &[u8],
    pos: &mut usize,
    big_endian: bool,
    s: Scalar,
) -> Result<Number, ValueError> {
    use Number::{Float, Int};
    Ok(match s {
        Scalar::I8 => Int(binary_value!(data, pos, big_endian, i8).into()),
        Scalar::U8 => Int(binary_value!(data, pos, big_endian, u8).into()),
        Scalar::I16 => Int(binary_value!(data, pos, big_endian, i16).into()),
        Scalar::U16 => Int(binary_value!(data, pos, big_endian, u16).into()),
        Scalar::I32 => Int(binary_value!(data, pos, big_endian, i32).into()),
        Scalar::U32 => Int(binary_value!(data, pos, big_endian, u32).into()),
        Scalar::F32 => Float(binary_value!(data, pos, big_endian, f32).into()),
        Scalar::F64 => Float(binary_value!(data, pos, big_endian, f64)),
    })
}

impl Body<'_> {
    fn float(&mut self, s: Scalar) -> Result<f64, ValueError> {
        match self {
            Body::Ascii(t) => ascii_value(t, parse_f64, "a number"),
            Body::Binary {
                data,
                pos,
                big_endian,
            } => Ok(match binary_number(data, pos, *big_endian, s)? {
                Number::Int(i) => i as f64,
                Number::Float(x) => x,
            }),
        }
    }

    /// An integer value (`s` is an integer type: checked in the header or by the caller).
    fn integer(&mut self, s: Scalar) -> Result<i64, ValueError> {
        match self {
            Body::Ascii(t) => ascii_value(t, parse_i64, "an integer"),
            Body::Binary {
                data,
                pos,
                big_endian,
            } => match binary_number(data, pos, *big_endian, s)? {
                Number::Int(i) => Ok(i),
                Number::Float(_) => Err(ValueError::Bad("float where an integer belongs".into())),
            },
        }
    }

    /// Skips `n` values of type `s`.
    fn skip(&mut self, s: Scalar, n: u64) -> Result<(), ValueError> {
        match self {
            Body::Ascii(t) => {
                for _ in 0..n {
                    t.next_token().ok_or(ValueError::End)?;
                }
                Ok(())
            }
            Body::Binary { data, pos, .. } => {
                let len = (s.size() as u64).checked_mul(n).ok_or(ValueError::End)?;
                let end = (*pos as u64)
                    .checked_add(len)
                    .filter(|&e| e <= data.len() as u64)
                    .ok_or(ValueError::End)?;
                *pos = end as usize;
                Ok(())
            }
        }
    }

    /// A list length (a non-negative integer).
    fn list_len(&mut self, s: Scalar, what: &str) -> Result<u64, ValueError> {
        let n = self.integer(s)?;
        u64::try_from(n)
            .map_err(|_| ValueError::Bad(format!("{what} has a negative list length {n}")))
    }

    fn skip_property(&mut self, p: &Property, what: &str) -> Result<(), ValueError> {
        match p.kind {
            Kind::Scalar(s) => self.skip(s, 1),
            Kind::List { count, item } => {
                let n = self.list_len(count, what)?;
                self.skip(item, n)
            }
        }
    }
}

/// Turns a value error into the message for item `i` of `element`.
fn located(e: ValueError, element: &Element, i: u64) -> String {
    match e {
        ValueError::End => format!(
            "PLY data ends early: '{}' element {i} of the {} the header declares is missing or incomplete",
            element.name, element.count
        ),
        ValueError::Bad(m) => format!("{m} (in '{}' element {i})", element.name),
    }
}

/// What to do with each property of the vertex element.
enum VertexSlot {
    /// Coordinate 0, 1 or 2, stored with this type.
    Coord(usize, Scalar),
    /// Extra scalar field number k, stored with this type.
    Field(usize, Scalar),
    /// A list: skipped.
    Skip,
}

fn read_vertices(body: &mut Body, e: &Element) -> Result<(Vec<Point3<f64>>, Fields), String> {
    let mut fields: Fields = Vec::new();
    let mut seen = [false; 3];
    let mut slots = Vec::with_capacity(e.properties.len());
    for p in &e.properties {
        let slot = match (&p.kind, p.name.as_str()) {
            (&Kind::Scalar(s), "x") => VertexSlot::Coord(0, s),
            (&Kind::Scalar(s), "y") => VertexSlot::Coord(1, s),
            (&Kind::Scalar(s), "z") => VertexSlot::Coord(2, s),
            (&Kind::Scalar(s), name) => {
                // Bounded: check_counts verified the count against the file size.
                fields.push((name.to_string(), Vec::with_capacity(e.count as usize)));
                VertexSlot::Field(fields.len() - 1, s)
            }
            (Kind::List { .. }, _) => VertexSlot::Skip,
        };
        if let VertexSlot::Coord(c, _) = slot {
            if seen[c] {
                return Err(format!("PLY vertex element declares '{}' twice", p.name));
            }
            seen[c] = true;
        }
        slots.push(slot);
    }
    if let Some(c) = seen.iter().position(|s| !s) {
        return Err(format!(
            "PLY vertex element has no scalar '{}' property",
            ["x", "y", "z"][c]
        ));
    }
    let mut vertices = Vec::with_capacity(e.count as usize);
    for i in 0..e.count {
        let mut p = [0.0; 3];
        for (prop, slot) in e.properties.iter().zip(&slots) {
            match *slot {
                VertexSlot::Coord(c, s) => {
                    p[c] = body.float(s).map_err(|err| located(err, e, i))?
                }
                VertexSlot::Field(f, s) => fields[f]
                    .1
                    .push(body.float(s).map_err(|err| located(err, e, i))? as f32),
                VertexSlot::Skip => body
                    .skip_property(prop, "a vertex")
                    .map_err(|err| located(err, e, i))?,
            }
        }
        vertices.push(Point3::new(p[0], p[1], p[2]));
    }
    Ok((vertices, fields))
}

fn read_faces(body: &mut Body, e: &Element) -> Result<Vec<[u32; 3]>, String> {
    let Some(list) = e.properties.iter().position(|p| {
        matches!(p.kind, Kind::List { .. })
            && (p.name == "vertex_indices" || p.name == "vertex_index")
    }) else {
        return Err("PLY face element has no list property 'vertex_indices'".to_string());
    };
    let Kind::List {
        count: count_type,
        item,
    } = e.properties[list].kind
    else {
        unreachable!()
    };
    if !item.is_integer() {
        return Err(format!(
            "PLY face list '{}' has a non-integer index type",
            e.properties[list].name
        ));
    }
    // Most meshes are triangles; a polygon of k corners adds k − 2 triangles as it comes.
    let mut faces = Vec::with_capacity(e.count as usize);
    let mut corners: Vec<u32> = Vec::new();
    for i in 0..e.count {
        for (k, prop) in e.properties.iter().enumerate() {
            if k != list {
                body.skip_property(prop, "a face")
                    .map_err(|err| located(err, e, i))?;
                continue;
            }
            let n = body
                .list_len(count_type, "a face")
                .map_err(|err| located(err, e, i))?;
            corners.clear();
            for _ in 0..n {
                let v = body.integer(item).map_err(|err| located(err, e, i))?;
                let v = u32::try_from(v)
                    .map_err(|_| format!("PLY face {i} has vertex index {v}, outside 0..2^32"))?;
                corners.push(v);
            }
            if corners.len() < 3 {
                return Err(format!(
                    "PLY face {i} has {} vertices (at least 3 needed)",
                    corners.len()
                ));
            }
            super::fan_triangulate(&corners, &mut faces);
        }
    }
    Ok(faces)
}

fn skip_element(body: &mut Body, e: &Element) -> Result<(), String> {
    if e.properties.is_empty() {
        return Ok(());
    }
    // Scalar-only binary elements are skipped in one step.
    if let Body::Binary { .. } = body {
        if e.properties
            .iter()
            .all(|p| matches!(p.kind, Kind::Scalar(_)))
        {
            let size: u64 = e
                .properties
                .iter()
                .map(|p| match p.kind {
                    Kind::Scalar(s) => s.size() as u64,
                    Kind::List { .. } => 0,
                })
                .sum();
            return body.skip(Scalar::U8, size * e.count).map_err(|_| {
                format!(
                    "PLY data ends early: the {} '{}' elements the header declares do not fit",
                    e.count, e.name
                )
            });
        }
    }
    let what = format!("a '{}' element", e.name);
    for i in 0..e.count {
        for p in &e.properties {
            body.skip_property(p, &what)
                .map_err(|err| located(err, e, i))?;
        }
    }
    Ok(())
}

/// Checks a scalar field name: a PLY identifier that is not a coordinate.
pub(crate) fn check_field_name(name: &str) -> Result<(), String> {
    let mut chars = name.chars();
    let ok = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !ok {
        return Err(format!(
            "scalar name '{name}' is not an identifier (letters, digits, '_')"
        ));
    }
    if ["x", "y", "z"].contains(&name) {
        return Err(format!(
            "scalar name '{name}' is taken by the vertex coordinates"
        ));
    }
    Ok(())
}

/// Writes binary little-endian PLY: double x, y, z, then one float property per scalar field (the
/// caller checked names and lengths), and faces as `list uchar int vertex_indices`.
pub(crate) fn write(
    w: &mut dyn Write,
    mesh: &TriMesh,
    scalars: &[(&str, &[f32])],
) -> std::io::Result<()> {
    if i32::try_from(mesh.num_vertices()).is_err() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "PLY with int indices holds at most 2^31 - 1 vertices",
        ));
    }
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by vesselmsr\nelement vertex {}\n\
         property double x\nproperty double y\nproperty double z\n",
        mesh.num_vertices()
    );
    for (name, _) in scalars {
        header.push_str(&format!("property float {name}\n"));
    }
    header.push_str(&format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.num_faces()
    ));
    w.write_all(header.as_bytes())?;
    let mut record = Vec::with_capacity(24 + 4 * scalars.len());
    for (v, p) in mesh.vertices.iter().enumerate() {
        record.clear();
        for c in [p.x, p.y, p.z] {
            record.extend_from_slice(&c.to_le_bytes());
        }
        for (_, values) in scalars {
            record.extend_from_slice(&values[v].to_le_bytes());
        }
        w.write_all(&record)?;
    }
    for face in &mesh.faces {
        let mut record = [3u8; 13];
        for (k, &i) in face.iter().enumerate() {
            record[1 + 4 * k..5 + 4 * k].copy_from_slice(&(i as i32).to_le_bytes());
        }
        w.write_all(&record)?;
    }
    Ok(())
}
