//! NumPy `.npz` archives: a zip file of `.npy` arrays, as `np.savez_compressed` writes and
//! `np.load` reads (without pickling: no object arrays).
//!
//! [`NpyArray`] holds one array of the dtypes the project stores: `<f8`, `<f4`, `<u4`, `<i8`,
//! the narrow integers `|i1`, `<i2` and `<i4` (the compact MSR archive's codes) and `<U` text (a string of UTF-32 code points, as NumPy keeps `str` arrays), each with its
//! C-order shape (`()` for a scalar). [`write_npz`] writes the members deflated in the given
//! order, atomically ([`write_npz_with`] also bzip2-compressed); [`read_npz`] reads every member back and checks each header (format
//! version 1.0 to 3.0, little-endian, C order, a byte count that matches the shape), so a
//! truncated or edited archive gives an error naming the file, the member and the problem.

use super::npy::{header_end, parse_header, NpyHeader, PREAMBLE};
use super::write_atomic;
use crate::{Error, Result};
use std::io::{Read, Write};
use std::path::Path;

const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// The values of one array, flat in C order.
#[derive(Debug, Clone, PartialEq)]
pub enum NpyData {
    F64(Vec<f64>),
    F32(Vec<f32>),
    U32(Vec<u32>),
    I64(Vec<i64>),
    /// `|i1`, `<i2` and `<i4`: integer codes stored as narrow as their values allow (read back
    /// widened to i32; [`NpyData::narrowest_int`] picks the width when writing).
    I8(Vec<i8>),
    I16(Vec<i16>),
    I32(Vec<i32>),
    /// Text, stored as a scalar `<U` array of this many code points.
    Text(String),
}

impl NpyData {
    /// Integer codes as the narrowest of `|i1`, `<i2`, `<i4` that holds every value (deflate
    /// packs small codes far better in one byte than in the high zero bytes of a wider type).
    pub fn narrowest_int(v: &[i32]) -> NpyData {
        let (lo, hi) = v.iter().fold((0, 0), |(lo, hi), &x| (x.min(lo), x.max(hi)));
        if lo >= i8::MIN as i32 && hi <= i8::MAX as i32 {
            NpyData::I8(v.iter().map(|&x| x as i8).collect())
        } else if lo >= i16::MIN as i32 && hi <= i16::MAX as i32 {
            NpyData::I16(v.iter().map(|&x| x as i16).collect())
        } else {
            NpyData::I32(v.to_vec())
        }
    }

    /// The values of an `|i1`, `<i2` or `<i4` array widened to i32; None for other dtypes.
    pub fn to_i32(&self) -> Option<Vec<i32>> {
        match self {
            NpyData::I8(v) => Some(v.iter().map(|&x| x as i32).collect()),
            NpyData::I16(v) => Some(v.iter().map(|&x| x as i32).collect()),
            NpyData::I32(v) => Some(v.clone()),
            _ => None,
        }
    }
}

/// One array: its shape (C order; empty for a scalar) and values.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    pub shape: Vec<usize>,
    pub data: NpyData,
}

impl NpyArray {
    /// An array of `data` with `shape`; panics if the sizes differ (a programming error).
    pub fn new(shape: &[usize], data: NpyData) -> NpyArray {
        let a = NpyArray {
            shape: shape.to_vec(),
            data,
        };
        assert_eq!(a.expected_len(), a.len(), "shape {shape:?} vs data");
        a
    }

    /// A scalar text array.
    pub fn text(s: &str) -> NpyArray {
        NpyArray::new(&[], NpyData::Text(s.to_owned()))
    }

    /// A scalar f64.
    pub fn scalar_f64(v: f64) -> NpyArray {
        NpyArray::new(&[], NpyData::F64(vec![v]))
    }

    /// A scalar i64.
    pub fn scalar_i64(v: i64) -> NpyArray {
        NpyArray::new(&[], NpyData::I64(vec![v]))
    }

    fn expected_len(&self) -> usize {
        match self.data {
            NpyData::Text(_) => 1,
            _ => self.shape.iter().product(),
        }
    }

    /// Number of stored values (1 for text).
    pub fn len(&self) -> usize {
        match &self.data {
            NpyData::F64(v) => v.len(),
            NpyData::F32(v) => v.len(),
            NpyData::U32(v) => v.len(),
            NpyData::I64(v) => v.len(),
            NpyData::I8(v) => v.len(),
            NpyData::I16(v) => v.len(),
            NpyData::I32(v) => v.len(),
            NpyData::Text(_) => 1,
        }
    }

    /// Whether the array holds no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn descr(&self) -> String {
        match &self.data {
            NpyData::F64(_) => "<f8".into(),
            NpyData::F32(_) => "<f4".into(),
            NpyData::U32(_) => "<u4".into(),
            NpyData::I64(_) => "<i8".into(),
            NpyData::I8(_) => "|i1".into(),
            NpyData::I16(_) => "<i2".into(),
            NpyData::I32(_) => "<i4".into(),
            NpyData::Text(s) => format!("<U{}", s.chars().count().max(1)),
        }
    }

    /// The `.npy` bytes of this array (format 1.0, header padded to 64 bytes).
    pub fn to_npy(&self) -> Vec<u8> {
        let shape = match self.shape.len() {
            0 => "()".to_owned(),
            1 => format!("({},)", self.shape[0]),
            _ => format!(
                "({})",
                self.shape
                    .iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let dict = format!(
            "{{'descr': '{}', 'fortran_order': False, 'shape': {shape}, }}",
            self.descr()
        );
        let unpadded = MAGIC.len() + 4 + dict.len() + 1;
        let total = unpadded.div_ceil(64) * 64;
        let mut out = Vec::with_capacity(total + 8 * self.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&((total - MAGIC.len() - 4) as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.resize(total - 1, b' ');
        out.push(b'\n');
        match &self.data {
            NpyData::F64(v) => v.iter().for_each(|x| out.extend(x.to_le_bytes())),
            NpyData::F32(v) => v.iter().for_each(|x| out.extend(x.to_le_bytes())),
            NpyData::U32(v) => v.iter().for_each(|x| out.extend(x.to_le_bytes())),
            NpyData::I64(v) => v.iter().for_each(|x| out.extend(x.to_le_bytes())),
            NpyData::I8(v) => v.iter().for_each(|x| out.extend(x.to_le_bytes())),
            NpyData::I16(v) => v.iter().for_each(|x| out.extend(x.to_le_bytes())),
            NpyData::I32(v) => v.iter().for_each(|x| out.extend(x.to_le_bytes())),
            NpyData::Text(s) => {
                s.chars().for_each(|c| out.extend((c as u32).to_le_bytes()));
                if s.is_empty() {
                    out.extend(0u32.to_le_bytes());
                }
            }
        }
        out
    }

    /// Parses `.npy` bytes of the dtypes above.
    pub fn from_npy(bytes: &[u8]) -> std::result::Result<NpyArray, String> {
        let header = parse_header(bytes)?;
        let (descr, shape) = (header.descr.as_str(), header.shape.clone());
        let count = header.count().ok_or("shape too large")?;
        let end = header.data_start;
        let body = &bytes[end..];
        let need = |width: usize| -> std::result::Result<(), String> {
            match count.checked_mul(width) {
                Some(n) if n == body.len() => Ok(()),
                _ => Err(format!(
                    "{} bytes of data, expected {} for shape {shape:?} of {descr}",
                    body.len(),
                    count.saturating_mul(width)
                )),
            }
        };
        let data = match descr {
            "<f8" => {
                need(8)?;
                NpyData::F64(
                    body.chunks_exact(8)
                        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                )
            }
            "<f4" => {
                need(4)?;
                NpyData::F32(super::npy::read_f32_le(body))
            }
            "<u4" => {
                need(4)?;
                NpyData::U32(
                    body.chunks_exact(4)
                        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                )
            }
            "<i8" => {
                need(8)?;
                NpyData::I64(
                    body.chunks_exact(8)
                        .map(|c| i64::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                )
            }
            "|i1" | "<i1" => {
                need(1)?;
                NpyData::I8(body.iter().map(|&b| b as i8).collect())
            }
            "<i2" => {
                need(2)?;
                NpyData::I16(
                    body.chunks_exact(2)
                        .map(|c| i16::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                )
            }
            "<i4" => {
                need(4)?;
                NpyData::I32(
                    body.chunks_exact(4)
                        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                )
            }
            d if d.starts_with("<U") && shape.is_empty() => {
                let n: usize = d[2..].parse().map_err(|_| format!("bad dtype {d}"))?;
                need(n.checked_mul(4).ok_or("text too long")?)?;
                let text: String = body
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                    .take_while(|&u| u != 0)
                    .map(|u| char::from_u32(u).ok_or("invalid character in text"))
                    .collect::<std::result::Result<_, _>>()?;
                NpyData::Text(text)
            }
            d => return Err(format!("unsupported dtype {d}")),
        };
        Ok(NpyArray { shape, data })
    }
}

/// How the members of an `.npz` are compressed; both are methods of the zip format that
/// Python's `zipfile` (so `np.load`) reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NpzCompression {
    /// Deflate, as `np.savez_compressed` writes.
    Deflate,
    /// bzip2: slower, but about a quarter smaller on integer codes (the compact MSR archive).
    Bzip2,
}

/// Writes `members` (name without `.npy`, array) to `path` as a deflated `.npz` (atomic).
pub fn write_npz(path: &Path, members: &[(&str, NpyArray)]) -> Result<()> {
    write_npz_with(path, members, NpzCompression::Deflate)
}

/// Writes `members` (name without `.npy`, array) to `path` as an `.npz` whose members are
/// compressed by `method` (atomic).
pub fn write_npz_with(
    path: &Path,
    members: &[(&str, NpyArray)],
    method: NpzCompression,
) -> Result<()> {
    let method = match method {
        NpzCompression::Deflate => zip::CompressionMethod::Deflated,
        NpzCompression::Bzip2 => zip::CompressionMethod::Bzip2,
    };
    write_atomic(path, |w| {
        let mut buf = std::io::Cursor::new(Vec::new());
        {
            let mut zip = zip::ZipWriter::new(&mut buf);
            let options = zip::write::SimpleFileOptions::default()
                .compression_method(method)
                .large_file(true);
            for (name, array) in members {
                zip.start_file(format!("{name}.npy"), options)
                    .map_err(|e| Error::format(path, format!("zip: {e}")))?;
                zip.write_all(&array.to_npy())
                    .map_err(|e| Error::io(path, e))?;
            }
            zip.finish()
                .map_err(|e| Error::format(path, format!("zip: {e}")))?;
        }
        w.write_all(buf.get_ref()).map_err(|e| Error::io(path, e))
    })
}

/// Reads every `.npy` member of the `.npz` at `path`, in archive order (names without `.npy`),
/// with the default limit of [`read_npz_within`] (8 GiB).
pub fn read_npz(path: &Path) -> Result<Vec<(String, NpyArray)>> {
    read_npz_within(path, crate::grid::spec::DEFAULT_MAX_MEMORY_BYTES)
}

/// Reads every `.npy` member of the `.npz` at `path`, in archive order (names without `.npy`).
/// Each member's header is read first: a member whose shape needs more than `max_bytes` is
/// refused before its data is read, and no member is read past the size its header gives.
pub fn read_npz_within(path: &Path, max_bytes: u64) -> Result<Vec<(String, NpyArray)>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut zip = zip::ZipArchive::new(std::io::BufReader::new(file))
        .map_err(|e| Error::format(path, format!("not a readable .npz (zip) archive: {e}")))?;
    let mut out = Vec::with_capacity(zip.len().min(1024));
    for i in 0..zip.len() {
        let member = zip
            .by_index(i)
            .map_err(|e| Error::format(path, format!("member {i}: {e}")))?;
        let name = member
            .name()
            .map_err(|e| Error::format(path, format!("member {i}: {e}")))?
            .into_owned();
        let Some(stem) = name.strip_suffix(".npy") else {
            return Err(Error::format(
                path,
                format!("member {} is not a .npy array", show_name(&name)),
            ));
        };
        let bytes = read_member(member, max_bytes)
            .map_err(|m| Error::format(path, format!("member {}: {m}", show_name(&name))))?;
        let array = NpyArray::from_npy(&bytes)
            .map_err(|m| Error::format(path, format!("member {}: {m}", show_name(&name))))?;
        out.push((stem.to_owned(), array));
    }
    Ok(out)
}

/// A member name for a message (control characters and length are the CLI's business; this
/// keeps a hostile name from running on).
fn show_name(name: &str) -> String {
    super::text::show(name.as_bytes())
}

/// The bytes of one member: its header first, then exactly the data its shape needs (refused
/// when that exceeds `max_bytes`); a member holding fewer or more bytes is an error.
fn read_member(mut member: impl Read, max_bytes: u64) -> std::result::Result<Vec<u8>, String> {
    let io = |e: std::io::Error| e.to_string();
    let mut bytes = Vec::with_capacity(PREAMBLE);
    (&mut member)
        .take(PREAMBLE as u64)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    let end = header_end(&bytes)?;
    let rest = end.saturating_sub(bytes.len()) as u64;
    (&mut member)
        .take(rest)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    let header = parse_header(&bytes)?;
    let data = data_bytes(&header)?;
    let total = (header.data_start as u64).saturating_add(data);
    if total > max_bytes {
        return Err(format!(
            "shape {:?} of {} needs {}, more than the {} memory limit: raise --max-memory",
            header.shape,
            super::text::show(header.descr.as_bytes()),
            crate::grid::spec::format_bytes(total),
            crate::grid::spec::format_bytes(max_bytes)
        ));
    }
    bytes.reserve_exact(data as usize);
    // One byte more than the shape needs tells a member that holds too much.
    (&mut member)
        .take(data + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    Ok(bytes)
}

/// Bytes of data the header's dtype and shape need (`u64::MAX` when that overflows).
fn data_bytes(header: &NpyHeader) -> std::result::Result<u64, String> {
    let width = match header.descr.as_str() {
        "<f8" | "<i8" => 8,
        "<f4" | "<u4" | "<i4" => 4,
        "<i2" => 2,
        "|i1" | "<i1" => 1,
        d if d.starts_with("<U") => {
            let n: u64 = d[2..]
                .parse()
                .map_err(|_| format!("bad dtype {}", super::text::show(d.as_bytes())))?;
            n.saturating_mul(4)
        }
        d => {
            return Err(format!(
                "unsupported dtype {}",
                super::text::show(d.as_bytes())
            ))
        }
    };
    Ok(header
        .count()
        .map_or(u64::MAX, |c| (c as u64).saturating_mul(width)))
}
