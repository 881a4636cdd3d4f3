//! The MSR file: one NumPy `.npz` archive (`np.load` opens it, no pickling) holding an [`Msr`]
//! and its parameters, with a format name and version. Version 4 (written) stores the
//! representation in the predicted integer codes of [`super::compact`], its members
//! bzip2-compressed (a zip method Python's `zipfile` reads): 1.6 to 4.7× the input mesh file's
//! size on the shared vessels, where version 3 ([`super::compact_v3`], the codes themselves)
//! took 2.1 to 6.1× and version 2 (float64 arrays, deflated) 40 to 140×; versions 2 and 3 are
//! still read.
//!
//! Version 4 members (S samples, I of them the input's, V of those its vertices, F faces, N levels,
//! grid nx×ny×nz; "int" is int8, int16 or int32, the narrowest that holds the values; a row of
//! coordinates is stored as planes, one per axis): `format` (text "vesselmsr-msr"),
//! `format_version` (int64 4), `params` (text: the [`MsrParams`] as JSON), `faces` (uint32
//! F×3), `vertices` (float64 V×3: the input mesh's vertices), `extra_face_steps` (int I−V: the
//! face of each other input sample less the one before's, the first's less 0) and `extra_bary`
//! (float64 (I−V)×3: its barycentric coordinates), `quantum` (float64 q) and `birth_quantum`
//! (float64 q_b, world units), `snap_normal` (int I) and `snap_residual` (int 3×I: the snap, X_0
//! less the input position, as q_b·(t·n̂_0 + r)), `added_at` (int 3×(S−I): the position at birth
//! of each sample added after the input, in steps of q_b from `phi_origin`), `born` (int S: the
//! level each sample joined at, 0 for the input's), `face_normal_sign` (int64 ±1),
//! `normals` (int (N+1)×2×S: the octahedral codes of n_0..n_N, predicted), `normal_details`
//! (int N×S: w, predicted) and `residuals` (int N×3×S: r; the detail W_i = q·(w·n̂_i + r)),
//! `refine_key_steps` (int R: the refined (level, sample) pairs as level·S + sample, increasing,
//! each less the one before), `refine_position` (int 3×R: an offset of X_level in steps of q/64)
//! and `refine_normal` (int 2×R: n_level's code on a 32 times finer grid, m = 127·32, less 32
//! times its code),
//! `times` (float64 N+1), `phi` (int8 nz×ny×nx, x fastest: φ_T's codes), `phi_origin` (float64
//! 3), `phi_voxel` (float64 h) and `phi_far` (float64). Coordinates are in the units of the
//! input mesh. Nothing is stored for a sample before its birth (those entries are 0): its
//! normals are zero there and its details too.
//!
//! Decoding with NumPy (`z = np.load(path)`, m = 127; tests/suite/msr_archive.rs holds the whole
//! decoder): the input positions are the vertices and, for the other input samples,
//! v_a·b_0 + v_b·b_1 + v_c·b_2 of their face's corners (faces = `np.cumsum(extra_face_steps)`).
//! The order P is `np.argsort(key, kind="stable")`, key the Morton code (bits of x, y, z
//! interleaved from the lowest, 21 per axis) of clip(floor((p − phi_origin)/h) + 2²⁰, 0,
//! 2²¹ − 1), p the input position of an input sample and `added_at`·q_b of another. "Along P
//! over a set" means: the values of the set's samples, taken in the order P, are the
//! cumulative sums of their stored entries. A code (u, v) stands for the unit normal
//! (u/m, v/m, w), w = 1 − |u|/m − |v|/m, where w < 0 (u, v)/m ← ((1 − |v|/m)·sign u,
//! (1 − |u|/m)·sign v) (sign 0 = +1), normalised; (128, 128) is the zero normal. The codes at
//! level i: those of the samples born at i along P over them (at level 0 the other input
//! samples excepted: theirs is their entry plus the code of `face_normal_sign`·(b − a)×(c − a)
//! of their face, with l1 = |x| + |y| + |z|, (x, y) ← (x, y)/l1 folded as above when z < 0,
//! rounded with `np.rint`·m), and for those born before i the code at i − 1 plus the change,
//! along P over them. The snap is (t·n̂_0 + r)·q_b; each sample starts at its input position
//! plus its snap, or `phi_origin` + `added_at`·q_b, and at each level i above its birth moves
//! by (w·n̂_i + r)·q with w along P over the samples born before i; a refined pair's normal is
//! that of its finer code and its offset is added to its position at that level (at its
//! birth, to its starting position). φ_T = c·h/64 for |c| ≤ 64,
//! else sign(c)·(h + (|c| − 64)·phi_far).
//!
//! Version 3 members differ in `extra_face` (int64 I−V, the faces), `snap` (int 3×I, in steps
//! of q_b), `born` (int64), no `face_normal_sign`, `normals` (the codes, each level less the
//! level before) and `normal_details`/`residuals` (the details in steps of q on a lattice:
//! residuals[i−1] + np.rint(normal_details[i−1]·n̂_i)).
//!
//! [`read_msr`] checks the format name and version and that every shape agrees with the others,
//! so an archive of another version, a truncated one or one whose arrays were edited out of
//! shape or range gives an error naming the file and the member; members whose decoding would
//! need more than the memory limit are refused before it.

use super::compact::{decode_msr, decoded_bytes, encode_msr, CompactMsr};
use super::compact_v3::{decode_msr as decode_msr_v3, CompactMsrV3};
use super::{Msr, MsrParams};
use crate::grid::{Grid3, GridTransform};
use crate::io::{read_npz_within, write_npz_with, NpyArray, NpyData, NpzCompression};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use std::path::Path;

/// The format name stored in every archive.
pub const FORMAT_NAME: &str = "vesselmsr-msr";
/// The archive layout version this build writes (it also reads [`FORMAT_VERSION_V3`] and
/// [`FORMAT_VERSION_F64`]).
pub const FORMAT_VERSION: i64 = 4;
/// The compact layout of earlier builds (codes not predicted), still read.
pub const FORMAT_VERSION_V3: i64 = 3;
/// The float64 layout of earlier builds, still read.
pub const FORMAT_VERSION_F64: i64 = 2;

/// Writes `msr` to `path` (atomic) in the compact layout (version [`FORMAT_VERSION`]).
pub fn write_msr(path: &Path, msr: &Msr) -> Result<()> {
    let c = encode_msr(msr);
    let s = c.born.len();
    let n = c.times.len() - 1;
    let inputs = c.snap_normal.len();
    let [nx, ny, nz] = c.phi_dims;
    let params = serde_json::to_string(&c.params)
        .map_err(|e| Error::format(path, format!("parameters: {e}")))?;
    let f64s = |v: &[[f64; 3]]| NpyData::F64(v.iter().flatten().copied().collect());
    let ints = |v: &[i32]| NpyData::narrowest_int(v);
    // The extra samples' faces as differences (they come mostly in the order of the faces).
    let face_steps: Vec<i32> = c
        .extra_face
        .iter()
        .scan(0i64, |before, &f| {
            let d = f as i64 - *before;
            *before = f as i64;
            Some(d as i32)
        })
        .collect();
    let refined = c.refine_key.len();
    let key_steps: Vec<i32> = c
        .refine_key
        .iter()
        .scan(0u64, |before, &k| {
            let d = k - *before;
            *before = k;
            Some(d as i32)
        })
        .collect();
    let members: Vec<(&str, NpyArray)> = vec![
        ("format", NpyArray::text(FORMAT_NAME)),
        ("format_version", NpyArray::scalar_i64(FORMAT_VERSION)),
        ("params", NpyArray::text(&params)),
        (
            "faces",
            NpyArray::new(
                &[c.faces.len(), 3],
                NpyData::U32(c.faces.iter().flatten().copied().collect()),
            ),
        ),
        (
            "vertices",
            NpyArray::new(&[c.vertices.len(), 3], f64s(&c.vertices)),
        ),
        (
            "extra_face_steps",
            NpyArray::new(&[face_steps.len()], ints(&face_steps)),
        ),
        (
            "extra_bary",
            NpyArray::new(&[c.extra_bary.len(), 3], f64s(&c.extra_bary)),
        ),
        ("quantum", NpyArray::scalar_f64(c.quantum)),
        ("birth_quantum", NpyArray::scalar_f64(c.birth_quantum)),
        (
            "snap_normal",
            NpyArray::new(&[inputs], ints(&c.snap_normal)),
        ),
        (
            "snap_residual",
            NpyArray::new(&[3, inputs], ints(&planes(&c.snap_residual, 3, 1))),
        ),
        (
            "added_at",
            NpyArray::new(&[3, c.added_at.len() / 3], ints(&planes(&c.added_at, 3, 1))),
        ),
        (
            "born",
            NpyArray::new(
                &[s],
                ints(&c.born.iter().map(|&b| b as i32).collect::<Vec<_>>()),
            ),
        ),
        (
            "face_normal_sign",
            NpyArray::scalar_i64(c.face_normal_sign as i64),
        ),
        (
            "normals",
            NpyArray::new(&[n + 1, 2, s], ints(&planes(&c.normals, 2, n + 1))),
        ),
        (
            "normal_details",
            NpyArray::new(&[n, s], ints(&c.normal_details)),
        ),
        (
            "residuals",
            NpyArray::new(&[n, 3, s], ints(&planes(&c.residuals, 3, n))),
        ),
        (
            "refine_key_steps",
            NpyArray::new(&[refined], ints(&key_steps)),
        ),
        (
            "refine_position",
            NpyArray::new(&[3, refined], ints(&planes(&c.refine_position, 3, 1))),
        ),
        (
            "refine_normal",
            NpyArray::new(&[2, refined], ints(&planes(&c.refine_normal, 2, 1))),
        ),
        (
            "times",
            NpyArray::new(&[c.times.len()], NpyData::F64(c.times.clone())),
        ),
        ("phi", NpyArray::new(&[nz, ny, nx], NpyData::I8(c.phi))),
        (
            "phi_origin",
            NpyArray::new(&[3], NpyData::F64(c.phi_origin.to_vec())),
        ),
        ("phi_voxel", NpyArray::scalar_f64(c.phi_voxel)),
        ("phi_far", NpyArray::scalar_f64(c.phi_far)),
    ];
    write_npz_with(path, &members, NpzCompression::Bzip2)
}

/// Reads an archive written by [`write_msr`] (see the module doc for what is checked), with the
/// default member limit of 8 GiB.
pub fn read_msr(path: &Path) -> Result<Msr> {
    read_msr_within(path, crate::grid::spec::DEFAULT_MAX_MEMORY_BYTES)
}

/// Reads an archive written by [`write_msr`], refusing a member whose header asks for more than
/// `max_bytes` before reading it (see the module doc for what is checked).
pub fn read_msr_within(path: &Path, max_bytes: u64) -> Result<Msr> {
    let mut m: HashMap<String, NpyArray> = read_npz_within(path, max_bytes)?.into_iter().collect();
    let bad = |what: String| Error::format(path, what);
    let format = match m.remove("format") {
        Some(NpyArray {
            data: NpyData::Text(t),
            ..
        }) => t,
        Some(_) => return Err(bad("member 'format' is not text".into())),
        None => return Err(bad("no member 'format' (not an MSR archive?)".into())),
    };
    if format != FORMAT_NAME {
        return Err(bad(format!("format '{format}' is not '{FORMAT_NAME}'")));
    }
    let version = m
        .remove("format_version")
        .ok_or_else(|| bad("no member 'format_version' (not an MSR archive?)".into()))
        .and_then(|a| scalar_i64(a, "format_version").map_err(&bad))?;
    match version {
        FORMAT_VERSION => read_compact(path, m, max_bytes, FORMAT_VERSION),
        FORMAT_VERSION_V3 => read_compact(path, m, max_bytes, FORMAT_VERSION_V3),
        FORMAT_VERSION_F64 => read_f64(path, m),
        _ => Err(bad(format!(
            "archive format version {version}; this vesselmsr reads versions \
             {FORMAT_VERSION_F64} to {FORMAT_VERSION}"
        ))),
    }
}

/// The members of a version-2 archive (float64 arrays), format and version already checked.
fn read_f64(path: &Path, mut m: HashMap<String, NpyArray>) -> Result<Msr> {
    let bad = |what: String| Error::format(path, what);
    let mut take = |name: &str| {
        m.remove(name)
            .ok_or_else(|| bad(format!("no member '{name}' (not an MSR archive?)")))
    };
    let text = |a: NpyArray, name: &str| match a.data {
        NpyData::Text(t) => Ok(t),
        _ => Err(bad(format!("member '{name}' is not text"))),
    };
    let params: MsrParams = serde_json::from_str(&text(take("params")?, "params")?)
        .map_err(|e| bad(format!("member 'params': {e}")))?;
    let num_vertices = scalar_i64(take("num_vertices")?, "num_vertices").map_err(&bad)?;
    let samples = f64_array(take("samples")?, "samples", &[None, Some(3)]).map_err(&bad)?;
    let s = samples.0[0];
    let num_vertices = usize::try_from(num_vertices)
        .ok()
        .filter(|&v| v <= s)
        .ok_or_else(|| bad(format!("num_vertices {num_vertices} is not within 0..={s}")))?;
    let (fshape, faces) = match take("faces")? {
        NpyArray {
            shape,
            data: NpyData::U32(v),
        } if shape.len() == 2 && shape[1] == 3 => (shape, v),
        _ => return Err(bad("member 'faces' is not a uint32 F×3 array".into())),
    };
    if let Some(&i) = faces.iter().find(|&&i| i as usize >= num_vertices) {
        return Err(bad(format!(
            "member 'faces': index {i} ≥ num_vertices {num_vertices}"
        )));
    }
    let snap = f64_array(take("snap")?, "snap", &[None, Some(3)]).map_err(&bad)?;
    let inputs = snap.0[0];
    if !(num_vertices..=s).contains(&inputs) {
        return Err(bad(format!(
            "member 'snap' has {inputs} rows, not within {num_vertices}..={s}"
        )));
    }
    let extra = inputs - num_vertices;
    let extra_face = match take("extra_face")? {
        NpyArray {
            shape,
            data: NpyData::I64(v),
        } if shape == [extra] => v,
        _ => {
            return Err(bad(format!(
                "member 'extra_face' is not an int64 array of {extra}"
            )))
        }
    };
    let nf = fshape[0];
    if let Some(&f) = extra_face.iter().find(|&&f| f < 0 || f as usize >= nf) {
        return Err(bad(format!(
            "member 'extra_face': face {f} is not within 0..{nf}"
        )));
    }
    let extra_bary =
        f64_array(take("extra_bary")?, "extra_bary", &[Some(extra), Some(3)]).map_err(&bad)?;
    let times = f64_array(take("times")?, "times", &[None]).map_err(&bad)?;
    let levels = times.0[0]
        .checked_sub(1)
        .ok_or_else(|| bad("member 'times' is empty".into()))?;
    check_params(&params, levels).map_err(|m| bad(format!("member 'params': {m}")))?;
    let details = f64_array(
        take("details")?,
        "details",
        &[Some(levels), Some(s), Some(3)],
    )
    .map_err(&bad)?;
    let normal = f64_array(
        take("normal_details")?,
        "normal_details",
        &[Some(levels), Some(s)],
    )
    .map_err(&bad)?;
    let normals = f64_array(
        take("normals")?,
        "normals",
        &[Some(levels + 1), Some(s), Some(3)],
    )
    .map_err(&bad)?;
    let born = match take("born")? {
        NpyArray {
            shape,
            data: NpyData::I64(v),
        } if shape == [s] => v,
        _ => return Err(bad(format!("member 'born' is not an int64 array of {s}"))),
    };
    born_levels_valid(&born, levels, inputs).map_err(&bad)?;
    let origin = f64_array(take("phi_origin")?, "phi_origin", &[Some(3)]).map_err(&bad)?;
    let voxel = f64_array(take("phi_voxel")?, "phi_voxel", &[])
        .map_err(&bad)?
        .1[0];
    let phi = match take("phi")? {
        NpyArray {
            shape,
            data: NpyData::F32(v),
        } if shape.len() == 3 => {
            let t = GridTransform::new(Point3::new(origin.1[0], origin.1[1], origin.1[2]), voxel);
            Grid3::from_data([shape[2], shape[1], shape[0]], t, v)
                .map_err(|e| bad(format!("member 'phi': {e}")))?
        }
        _ => return Err(bad("member 'phi' is not a float32 3-D array".into())),
    };
    if !(voxel > 0.0 && voxel.is_finite()) {
        return Err(bad(format!(
            "member 'phi_voxel': {voxel} is not a positive voxel size"
        )));
    }
    if let Some(v) = phi.data().iter().find(|v| !v.is_finite()) {
        return Err(bad(format!("member 'phi' holds {v}")));
    }
    fn p3(v: &[f64]) -> Vec<Point3<f64>> {
        v.chunks_exact(3)
            .map(|c| Point3::new(c[0], c[1], c[2]))
            .collect()
    }
    fn v3(v: &[f64]) -> Vec<Vector3<f64>> {
        v.chunks_exact(3)
            .map(|c| Vector3::new(c[0], c[1], c[2]))
            .collect()
    }
    Ok(Msr {
        faces: faces.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        num_vertices,
        extra_face: extra_face.iter().map(|&f| f as u32).collect(),
        extra_bary: extra_bary
            .1
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        snap: v3(&snap.1),
        born: born.iter().map(|&b| b as u32).collect(),
        samples: p3(&samples.1),
        details: (0..levels)
            .map(|i| v3(&details.1[3 * s * i..3 * s * (i + 1)]))
            .collect(),
        normal_details: (0..levels)
            .map(|i| normal.1[s * i..s * (i + 1)].to_vec())
            .collect(),
        normals: (0..=levels)
            .map(|i| v3(&normals.1[3 * s * i..3 * s * (i + 1)]))
            .collect(),
        times: times.1,
        phi,
        params,
    })
}

/// The members of a version-4 archive (the codes of [`super::compact`]) or of a version-3 one
/// ([`super::compact_v3`]), format and version already checked: every shape and range is
/// checked, then the memory the decoded representation needs, before decoding.
fn read_compact(
    path: &Path,
    mut m: HashMap<String, NpyArray>,
    max_bytes: u64,
    version: i64,
) -> Result<Msr> {
    let v4 = version == FORMAT_VERSION;
    let bad = |what: String| Error::format(path, what);
    let mut take = |name: &str| {
        m.remove(name)
            .ok_or_else(|| bad(format!("no member '{name}' (not an MSR archive?)")))
    };
    let params: MsrParams = match take("params")?.data {
        NpyData::Text(t) => {
            serde_json::from_str(&t).map_err(|e| bad(format!("member 'params': {e}")))?
        }
        _ => return Err(bad("member 'params' is not text".into())),
    };
    let faces = match take("faces")? {
        NpyArray {
            shape,
            data: NpyData::U32(v),
        } if shape.len() == 2 && shape[1] == 3 => v,
        _ => return Err(bad("member 'faces' is not a uint32 F×3 array".into())),
    };
    let nf = faces.len() / 3;
    let (vshape, vertices) =
        f64_array(take("vertices")?, "vertices", &[None, Some(3)]).map_err(&bad)?;
    let nv = vshape[0];
    if let Some(&i) = faces.iter().find(|&&i| i as usize >= nv) {
        return Err(bad(format!("member 'faces': index {i} ≥ {nv} vertices")));
    }
    let extra_face: Vec<i64> = if v4 {
        let (_, steps) =
            int_array(take("extra_face_steps")?, "extra_face_steps", &[None]).map_err(&bad)?;
        steps
            .iter()
            .scan(0i64, |f, &d| {
                *f += d as i64;
                Some(*f)
            })
            .collect()
    } else {
        match take("extra_face")? {
            NpyArray {
                shape,
                data: NpyData::I64(v),
            } if shape.len() == 1 => v,
            _ => return Err(bad("member 'extra_face' is not a 1-D int64 array".into())),
        }
    };
    let face_member = if v4 { "extra_face_steps" } else { "extra_face" };
    if let Some(&f) = extra_face.iter().find(|&&f| f < 0 || f as usize >= nf) {
        return Err(bad(format!(
            "member '{face_member}': face {f} is not within 0..{nf}"
        )));
    }
    let extra = extra_face.len();
    let (_, extra_bary) =
        f64_array(take("extra_bary")?, "extra_bary", &[Some(extra), Some(3)]).map_err(&bad)?;
    let inputs = nv + extra;
    let quantum = positive(take("quantum")?, "quantum").map_err(&bad)?;
    let birth_quantum = positive(take("birth_quantum")?, "birth_quantum").map_err(&bad)?;
    // Version 4: the snap's normal component and residual; version 3: the snap.
    let snap = if v4 {
        let (_, t) =
            int_array(take("snap_normal")?, "snap_normal", &[Some(inputs)]).map_err(&bad)?;
        let (_, r) = int_array(
            take("snap_residual")?,
            "snap_residual",
            &[Some(3), Some(inputs)],
        )
        .map_err(&bad)?;
        (t, interleaved(&r, 3, 1))
    } else {
        let (_, snap) = int_array(take("snap")?, "snap", &[Some(3), Some(inputs)]).map_err(&bad)?;
        (Vec::new(), interleaved(&snap, 3, 1))
    };
    let born: Vec<i64> = match take("born")? {
        NpyArray {
            shape,
            data: NpyData::I64(v),
        } if !v4 && shape.len() == 1 && shape[0] >= inputs => v,
        a if v4 && a.shape.len() == 1 && a.shape[0] >= inputs && a.data.to_i32().is_some() => a
            .data
            .to_i32()
            .unwrap_or_default()
            .iter()
            .map(|&b| b as i64)
            .collect(),
        _ => {
            return Err(bad(format!(
                "member 'born' is not an {} array of at least {inputs} samples",
                if v4 { "int8, int16 or int32" } else { "int64" }
            )))
        }
    };
    let face_normal_sign = if v4 {
        match scalar_i64(take("face_normal_sign")?, "face_normal_sign").map_err(&bad)? {
            v @ (-1 | 1) => v as i32,
            v => return Err(bad(format!("member 'face_normal_sign': {v} is not ±1"))),
        }
    } else {
        1
    };
    let s = born.len();
    let times = f64_array(take("times")?, "times", &[None]).map_err(&bad)?.1;
    let levels = times
        .len()
        .checked_sub(1)
        .ok_or_else(|| bad("member 'times' is empty".into()))?;
    check_params(&params, levels).map_err(|m| bad(format!("member 'params': {m}")))?;
    born_levels_valid(&born, levels, inputs).map_err(&bad)?;
    let (_, added_at) =
        int_array(take("added_at")?, "added_at", &[Some(3), Some(s - inputs)]).map_err(&bad)?;
    let added_at = interleaved(&added_at, 3, 1);
    let (_, normals) = int_array(
        take("normals")?,
        "normals",
        &[Some(levels + 1), Some(2), Some(s)],
    )
    .map_err(&bad)?;
    let normals = interleaved(&normals, 2, levels + 1);
    let (_, normal_details) = int_array(
        take("normal_details")?,
        "normal_details",
        &[Some(levels), Some(s)],
    )
    .map_err(&bad)?;
    let (_, residuals) = int_array(
        take("residuals")?,
        "residuals",
        &[Some(levels), Some(3), Some(s)],
    )
    .map_err(&bad)?;
    let residuals = interleaved(&residuals, 3, levels);
    let origin = f64_array(take("phi_origin")?, "phi_origin", &[Some(3)])
        .map_err(&bad)?
        .1;
    let voxel = positive(take("phi_voxel")?, "phi_voxel").map_err(&bad)?;
    let phi_far = positive(take("phi_far")?, "phi_far").map_err(&bad)?;
    let (phi_dims, phi) = match take("phi")? {
        NpyArray {
            shape,
            data: NpyData::I8(v),
        } if shape.len() == 3 => ([shape[2], shape[1], shape[0]], v),
        _ => return Err(bad("member 'phi' is not an int8 3-D array".into())),
    };
    let need = decoded_bytes(s, levels, phi.len());
    if need > max_bytes {
        return Err(bad(format!(
            "decoding {s} samples of {levels} levels and a {}×{}×{} φ needs {}, more than the \
             {} memory limit: raise --max-memory",
            phi_dims[0],
            phi_dims[1],
            phi_dims[2],
            crate::grid::spec::format_bytes(need),
            crate::grid::spec::format_bytes(max_bytes)
        )));
    }
    let triples = |v: Vec<f64>| v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let faces = faces.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let extra_face = extra_face.iter().map(|&f| f as u32).collect();
    let born = born.iter().map(|&b| b as u32).collect();
    let phi_origin = [origin[0], origin[1], origin[2]];
    if !v4 {
        let compact = CompactMsrV3 {
            faces,
            vertices: triples(vertices),
            extra_face,
            extra_bary: triples(extra_bary),
            quantum,
            birth_quantum,
            snap: snap.1,
            added_at,
            born,
            normals,
            normal_details,
            residuals,
            times,
            phi,
            phi_dims,
            phi_origin,
            phi_voxel: voxel,
            phi_far,
            params,
        };
        return decode_msr_v3(&compact).map_err(bad);
    }
    // The refined pairs: keys increasing within (N+1)·S, with their offsets and normals.
    let (_, steps) =
        int_array(take("refine_key_steps")?, "refine_key_steps", &[None]).map_err(&bad)?;
    let r = steps.len();
    let mut refine_key = Vec::with_capacity(r);
    let mut key = 0u64;
    for (j, &d) in steps.iter().enumerate() {
        if d < 0 || (j > 0 && d == 0) || key + d as u64 >= ((levels + 1) * s) as u64 {
            return Err(bad(format!(
                "member 'refine_key_steps': entry {j} ({d}) does not give an increasing key below {}",
                (levels + 1) * s
            )));
        }
        key += d as u64;
        refine_key.push(key);
    }
    let (_, refine_position) = int_array(
        take("refine_position")?,
        "refine_position",
        &[Some(3), Some(r)],
    )
    .map_err(&bad)?;
    let (_, refine_normal) =
        int_array(take("refine_normal")?, "refine_normal", &[Some(2), Some(r)]).map_err(&bad)?;
    let compact = CompactMsr {
        faces,
        vertices: triples(vertices),
        extra_face,
        extra_bary: triples(extra_bary),
        quantum,
        birth_quantum,
        snap_normal: snap.0,
        snap_residual: snap.1,
        added_at,
        born,
        face_normal_sign,
        normals,
        normal_details,
        residuals,
        refine_key,
        refine_position: interleaved(&refine_position, 3, 1),
        refine_normal: interleaved(&refine_normal, 2, 1),
        times,
        phi,
        phi_dims,
        phi_origin,
        phi_voxel: voxel,
        phi_far,
        params,
    };
    decode_msr(&compact).map_err(bad)
}

/// `v`, `blocks` blocks of rows of `k` values, as `blocks` blocks of `k` planes (one per
/// column): deflate and bzip2 pack each column's similar values better together.
fn planes(v: &[i32], k: usize, blocks: usize) -> Vec<i32> {
    let rows = v.len() / blocks.max(1) / k.max(1);
    transpose_blocks(v, rows, k, blocks)
}

/// The inverse of [`planes`].
fn interleaved(v: &[i32], k: usize, blocks: usize) -> Vec<i32> {
    let rows = v.len() / blocks.max(1) / k.max(1);
    transpose_blocks(v, k, rows, blocks)
}

/// Each of the `blocks` blocks of `v`, a `rows` × `cols` matrix stored by rows, transposed.
fn transpose_blocks(v: &[i32], rows: usize, cols: usize, blocks: usize) -> Vec<i32> {
    let per = v.len() / blocks.max(1);
    let mut out = Vec::with_capacity(v.len());
    for b in v.chunks_exact(per.max(1)) {
        for c in 0..cols {
            out.extend((0..rows).map(|r| b[r * cols + c]));
        }
    }
    out
}

/// A positive finite float64 scalar.
fn positive(a: NpyArray, name: &str) -> std::result::Result<f64, String> {
    let v = f64_array(a, name, &[])?.1[0];
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(format!("member '{name}': {v} is not positive"))
    }
}

/// An int8/int16/int32 array whose shape matches `want` (None: any length on that axis).
fn int_array(
    a: NpyArray,
    name: &str,
    want: &[Option<usize>],
) -> std::result::Result<(Vec<usize>, Vec<i32>), String> {
    let fits = a.shape.len() == want.len()
        && a.shape
            .iter()
            .zip(want)
            .all(|(d, w)| w.is_none_or(|w| *d == w));
    match a.data.to_i32() {
        Some(v) if fits => Ok((a.shape, v)),
        _ => {
            let want: Vec<String> = want
                .iter()
                .map(|w| w.map_or("any".to_string(), |n| n.to_string()))
                .collect();
            Err(format!(
                "member '{name}' is not an int8, int16 or int32 array of shape ({}) (found \
                 shape {:?})",
                want.join(", "),
                a.shape
            ))
        }
    }
}

/// The parameters must describe a decomposition this build can have written: at least one level
/// and as many as `times` has, a known velocity, positive finite voxel, time and step.
fn check_params(p: &MsrParams, levels: usize) -> std::result::Result<(), String> {
    if p.levels == 0 || p.levels != levels {
        return Err(format!(
            "levels {} (member 'times' gives {levels}; at least 1)",
            p.levels
        ));
    }
    if !["mcf", "vpmcf", "expand", "inpaint"].contains(&p.velocity.as_str()) {
        return Err(format!(
            "unknown velocity '{}' (expected mcf, vpmcf, expand or inpaint)",
            p.velocity.chars().take(40).collect::<String>()
        ));
    }
    for (name, v) in [("voxel", p.voxel), ("time", p.time), ("dt", p.dt)] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(format!("{name} {v} is not positive"));
        }
    }
    for (name, v) in [
        ("c", p.c),
        ("projection_tolerance_voxels", p.projection_tolerance_voxels),
    ] {
        if !v.is_finite() {
            return Err(format!("{name} {v} is not finite"));
        }
    }
    Ok(())
}

fn scalar_i64(a: NpyArray, name: &str) -> std::result::Result<i64, String> {
    match a {
        NpyArray {
            shape,
            data: NpyData::I64(v),
        } if shape.is_empty() => Ok(v[0]),
        _ => Err(format!("member '{name}' is not an int64 scalar")),
    }
}

/// A float64 array whose shape matches `want` (None: any length on that axis).
fn f64_array(
    a: NpyArray,
    name: &str,
    want: &[Option<usize>],
) -> std::result::Result<(Vec<usize>, Vec<f64>), String> {
    match a {
        NpyArray {
            shape,
            data: NpyData::F64(v),
        } if shape.len() == want.len()
            && shape
                .iter()
                .zip(want)
                .all(|(d, w)| w.is_none_or(|w| *d == w)) =>
        {
            if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                return Err(format!("member '{name}' holds {x}"));
            }
            Ok((shape, v))
        }
        NpyArray { shape, .. } => {
            let want: Vec<String> = want
                .iter()
                .map(|w| w.map_or("any".to_string(), |n| n.to_string()))
                .collect();
            Err(format!(
                "member '{name}' is not a float64 array of shape ({}) (found shape {shape:?})",
                want.join(", ")
            ))
        }
    }
}

/// Every sample's birth level is a level of the archive, 0 for the input samples.
fn born_levels_valid(
    born: &[i64],
    levels: usize,
    inputs: usize,
) -> std::result::Result<(), String> {
    match born
        .iter()
        .enumerate()
        .find(|&(k, &b)| !(0..levels.max(1) as i64).contains(&b) || (k < inputs && b != 0))
    {
        Some((k, b)) => Err(format!(
            "member 'born': sample {k} at level {b} (input samples: 0; others: 0..{levels})"
        )),
        None => Ok(()),
    }
}
