//! The MSR file: one NumPy `.npz` archive (`np.load` opens it, no pickling) holding every array
//! of an [`Msr`] and the parameters, with a format name and version.
//!
//! Members (S samples, V of them mesh vertices, F faces, N levels, grid nx×ny×nz):
//! `format` (text "vesselmsr-msr"), `format_version` (int64, [`FORMAT_VERSION`]), `params`
//! (text: the [`MsrParams`] as JSON), `faces` (uint32 F×3), `num_vertices` (int64),
//! `extra_face` (int64 I−V), `extra_bary` (float64 (I−V)×3), `snap` (float64 I×3: X_0 less the
//! input position of each of the I input samples), `born` (int64 S: the level each sample joined
//! at, 0 for the input's; I ≤ S), `samples` (float64 S×3: X_N),
//! `details` (float64 N×S×3: W_1..W_N), `normal_details` (float64 N×S: w_1..w_N), `normals`
//! (float64 (N+1)×S×3: the unit outward normals n_0..n_N of S_i at X_i), `times`
//! (float64 N+1), `phi` (float32 nz×ny×nx, x fastest: φ_T), `phi_origin` (float64 3) and
//! `phi_voxel` (float64). Coordinates are in the units of the input mesh.
//!
//! [`read_msr`] checks the format name and version and that every shape agrees with the others,
//! so an archive of another version, a truncated one or one whose arrays were edited out of
//! shape gives an error naming the file and the member.

use super::{Msr, MsrParams};
use crate::grid::{Grid3, GridTransform};
use crate::io::{read_npz_within, write_npz, NpyArray, NpyData};
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use std::path::Path;

/// The format name stored in every archive.
pub const FORMAT_NAME: &str = "vesselmsr-msr";
/// The archive layout version this build writes and reads.
pub const FORMAT_VERSION: i64 = 2;

/// Writes `msr` to `path` (atomic).
pub fn write_msr(path: &Path, msr: &Msr) -> Result<()> {
    let s = msr.samples.len();
    let n = msr.levels();
    let [nx, ny, nz] = msr.phi.dims();
    let flat3 = |v: &mut dyn Iterator<Item = [f64; 3]>| v.flatten().collect::<Vec<f64>>();
    let params = serde_json::to_string(&msr.params)
        .map_err(|e| Error::format(path, format!("parameters: {e}")))?;
    let members: Vec<(&str, NpyArray)> = vec![
        ("format", NpyArray::text(FORMAT_NAME)),
        ("format_version", NpyArray::scalar_i64(FORMAT_VERSION)),
        ("params", NpyArray::text(&params)),
        (
            "faces",
            NpyArray::new(
                &[msr.faces.len(), 3],
                NpyData::U32(msr.faces.iter().flatten().copied().collect()),
            ),
        ),
        (
            "num_vertices",
            NpyArray::scalar_i64(msr.num_vertices as i64),
        ),
        (
            "extra_face",
            NpyArray::new(
                &[msr.extra_face.len()],
                NpyData::I64(msr.extra_face.iter().map(|&f| f as i64).collect()),
            ),
        ),
        (
            "extra_bary",
            NpyArray::new(
                &[msr.extra_bary.len(), 3],
                NpyData::F64(flat3(&mut msr.extra_bary.iter().copied())),
            ),
        ),
        (
            "snap",
            NpyArray::new(
                &[msr.snap.len(), 3],
                NpyData::F64(flat3(&mut msr.snap.iter().map(|w| (*w).into()))),
            ),
        ),
        (
            "born",
            NpyArray::new(
                &[s],
                NpyData::I64(msr.born.iter().map(|&b| b as i64).collect()),
            ),
        ),
        (
            "samples",
            NpyArray::new(
                &[s, 3],
                NpyData::F64(flat3(&mut msr.samples.iter().map(|p| p.coords.into()))),
            ),
        ),
        (
            "details",
            NpyArray::new(
                &[n, s, 3],
                NpyData::F64(flat3(
                    &mut msr.details.iter().flatten().map(|w| (*w).into()),
                )),
            ),
        ),
        (
            "normal_details",
            NpyArray::new(
                &[n, s],
                NpyData::F64(msr.normal_details.iter().flatten().copied().collect()),
            ),
        ),
        (
            "normals",
            NpyArray::new(
                &[msr.normals.len(), s, 3],
                NpyData::F64(flat3(
                    &mut msr.normals.iter().flatten().map(|w| (*w).into()),
                )),
            ),
        ),
        (
            "times",
            NpyArray::new(&[msr.times.len()], NpyData::F64(msr.times.clone())),
        ),
        (
            "phi",
            NpyArray::new(&[nz, ny, nx], NpyData::F32(msr.phi.data().to_vec())),
        ),
        (
            "phi_origin",
            NpyArray::new(&[3], NpyData::F64(msr.phi.transform().origin.to_vec())),
        ),
        ("phi_voxel", NpyArray::scalar_f64(msr.phi.voxel())),
    ];
    write_npz(path, &members)
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
    let mut take = |name: &str| {
        m.remove(name)
            .ok_or_else(|| bad(format!("no member '{name}' (not an MSR archive?)")))
    };
    let text = |a: NpyArray, name: &str| match a.data {
        NpyData::Text(t) => Ok(t),
        _ => Err(bad(format!("member '{name}' is not text"))),
    };
    let format = text(take("format")?, "format")?;
    if format != FORMAT_NAME {
        return Err(bad(format!("format '{format}' is not '{FORMAT_NAME}'")));
    }
    let version = scalar_i64(take("format_version")?, "format_version").map_err(&bad)?;
    if version != FORMAT_VERSION {
        return Err(bad(format!(
            "archive format version {version}; this vesselmsr reads version {FORMAT_VERSION}"
        )));
    }
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
    if let Some((k, &b)) = born
        .iter()
        .enumerate()
        .find(|&(k, &b)| !(0..levels.max(1) as i64).contains(&b) || (k < inputs && b != 0))
    {
        return Err(bad(format!(
            "member 'born': sample {k} at level {b} (input samples: 0; others: 0..{levels})"
        )));
    }
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
