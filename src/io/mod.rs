//! Reading and writing triangle meshes as STL, OBJ, PLY, VTK XML PolyData (`.vtp`) and legacy VTK
//! (`.vtk`), the format chosen by file extension.
//!
//! Readers accept binary and ASCII STL (corners welded by exact coordinates), OBJ (polygons
//! fan-triangulated, all objects merged), PLY (ascii and both binary byte orders), `.vtp` and
//! `.vtk` POLYDATA in the encodings VTK writes (`vtp`, `vtk_legacy`: polygons fan-triangulated,
//! triangle strips cut, lines and vertices ignored). Every mesh
//! read is validated: finite coordinates, at least one triangle, indices in range, and at least one
//! non-degenerate triangle; every mesh written passes the same checks (and the float32 range for
//! STL). Every error names the file and the problem in one line. Writers go through
//! [`write_atomic`], so a failed write leaves no partial file.
//!
//! Points picked in 3D Slicer come from its markups files (`markups`: `.mrk.json`, `.fcsv`).
//!
//! Grids (level-set functions) are written as NumPy `.npy` with a JSON sidecar (`npy`), as
//! VTK ImageData `.vti` (`vti`, for ParaView) and as NRRD (`nrrd`, for 3D Slicer and ITK).

mod atomic;
mod centerline;
mod markups;
mod npy;
mod npz;
mod nrrd;
mod obj;
mod ply;
mod stl;
mod text;
mod validate;
mod vti;
mod vtk_legacy;
mod vtp;

pub use atomic::write_atomic;
pub use centerline::{read_centerline_json, write_centerline_json, write_centerline_vtp};
pub use markups::{is_markups_path, read_markups};
pub use npy::{npy_sidecar_path, read_npy, write_npy, NpySidecar};
pub use npz::{
    read_npz, read_npz_within, write_npz, write_npz_with, NpyArray, NpyData, NpzCompression,
};
pub use nrrd::{read_nrrd, write_nrrd};
pub use vti::{read_vti, write_vti, VTI_ARRAY_NAME};
pub use vtk_legacy::{read_vtk_legacy, write_vtk_legacy, write_vtk_legacy_to};
pub use vtp::{
    read_vtp, write_vtp, write_vtp_encoded_to, write_vtp_to, DataArray, DataValues, PolyData,
    VtpEncoding,
};

use crate::{Error, Result, TriMesh};
use std::path::Path;

/// The mesh file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Stl,
    Obj,
    Ply,
    /// VTK XML PolyData.
    Vtp,
    /// Legacy VTK POLYDATA.
    Vtk,
}

impl MeshFormat {
    /// The format named by the extension of `path` (`.stl`, `.obj`, `.ply`, `.vtp`, `.vtk`, any
    /// case).
    pub fn from_path(path: &Path) -> Result<MeshFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("stl") => Ok(MeshFormat::Stl),
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
            Some("vtp") => Ok(MeshFormat::Vtp),
            Some("vtk") => Ok(MeshFormat::Vtk),
            _ => Err(Error::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Reads the whole file, refusing an empty one.
fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if bytes.is_empty() {
        return Err(Error::format(path, "empty file"));
    }
    Ok(bytes)
}

/// Reads and validates a mesh, choosing the format from the file extension.
pub fn read_mesh(path: &Path) -> Result<TriMesh> {
    let format = MeshFormat::from_path(path)?;
    let bytes = read_bytes(path)?;
    parse_mesh(&bytes, format).map_err(|m| Error::format(path, m))
}

/// Parses and validates the bytes of a mesh file of `format` (what [`read_mesh`] does after
/// reading the file; the fuzz targets call it on arbitrary bytes). The error is one line.
pub fn parse_mesh(bytes: &[u8], format: MeshFormat) -> std::result::Result<TriMesh, String> {
    let mesh = match format {
        MeshFormat::Stl => stl::read(bytes),
        MeshFormat::Obj => obj::read(bytes),
        MeshFormat::Ply => ply::read(bytes).map(|p| p.mesh),
        MeshFormat::Vtp => vtp::parse_vtp(bytes).and_then(|d| d.to_mesh()),
        MeshFormat::Vtk => vtk_legacy::parse_vtk_legacy(bytes).and_then(|d| d.to_mesh()),
    }?;
    validate::validate_mesh(&mesh)?;
    Ok(mesh)
}

/// Checks a mesh that came from no file (arrays handed over by the Python package) as every
/// mesh read is checked: finite coordinates, indices in range, at least one non-degenerate
/// triangle ([`Error::InvalidMesh`] naming the first problem).
pub fn check_mesh(mesh: &TriMesh) -> Result<()> {
    validate::validate_mesh(mesh).map_err(Error::InvalidMesh)
}

/// Named per-vertex scalar fields, as read from PLY, VTP or VTK.
pub type ScalarFields = Vec<(String, Vec<f32>)>;

/// Reads and validates a PLY mesh together with its per-vertex scalar properties other than
/// x, y, z (as f32, in header order), e.g. those written by [`write_mesh_with_scalars`].
pub fn read_ply_scalars(path: &Path) -> Result<(TriMesh, ScalarFields)> {
    if MeshFormat::from_path(path)? != MeshFormat::Ply {
        return Err(Error::format(
            path,
            "per-vertex scalars can only be read from a .ply file",
        ));
    }
    read_mesh_with_scalars(path)
}

/// Reads and validates a mesh with its per-vertex scalar fields (as f32, in file order): PLY
/// vertex properties other than x, y, z, or the one-component point-data arrays of `.vtp` and
/// `.vtk`. STL and OBJ have none.
pub fn read_mesh_with_scalars(path: &Path) -> Result<(TriMesh, ScalarFields)> {
    let format = MeshFormat::from_path(path)?;
    let bytes = read_bytes(path)?;
    let from_poly = |d: PolyData| -> std::result::Result<(TriMesh, ScalarFields), String> {
        let fields = d
            .point_data
            .iter()
            .filter(|a| a.components == 1)
            .map(|a| {
                (
                    a.name.clone(),
                    a.values.to_f64().iter().map(|&v| v as f32).collect(),
                )
            })
            .collect();
        Ok((d.to_mesh()?, fields))
    };
    let (mesh, fields) = match format {
        MeshFormat::Stl => stl::read(&bytes).map(|m| (m, Vec::new())),
        MeshFormat::Obj => obj::read(&bytes).map(|m| (m, Vec::new())),
        MeshFormat::Ply => ply::read(&bytes).map(|p| (p.mesh, p.scalars)),
        MeshFormat::Vtp => vtp::parse_vtp(&bytes).and_then(from_poly),
        MeshFormat::Vtk => vtk_legacy::parse_vtk_legacy(&bytes).and_then(from_poly),
    }
    .map_err(|m| Error::format(path, m))?;
    validate::validate_mesh(&mesh).map_err(|m| Error::format(path, m))?;
    Ok((mesh, fields))
}

/// Writes a mesh in the format named by the extension: binary STL (f32, facet normals computed),
/// OBJ (exact f64 text), binary little-endian PLY (f64 coordinates), VTK XML PolyData (Float64
/// points, raw appended data) or binary legacy VTK (doubles). Atomic.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<()> {
    let format = MeshFormat::from_path(path)?;
    check_writable(path, mesh, format)?;
    if format == MeshFormat::Vtk && (mesh.num_faces() as u64 * 4 > i32::MAX as u64) {
        return Err(Error::format(
            path,
            "too many triangles for the legacy VTK format (32-bit)",
        ));
    }
    write_atomic(path, |w| {
        match format {
            MeshFormat::Stl => stl::write(w, mesh),
            MeshFormat::Obj => obj::write(w, mesh),
            MeshFormat::Ply => ply::write(w, mesh, &[]),
            MeshFormat::Vtp => {
                vtp::write_file(w, &PolyData::from_mesh(mesh), VtpEncoding::Appended)
            }
            MeshFormat::Vtk => vtk_legacy::write_file(w, &PolyData::from_mesh(mesh)),
        }
        .map_err(|e| Error::io(path, e))
    })
}

/// Writes a mesh with one float per-vertex field per `(name, values)` pair: as PLY vertex
/// properties (`.ply`; names must be identifiers other than x, y, z) or as point-data arrays
/// (`.vtp`, `.vtk`). Every `values` must have one entry per vertex; names must be distinct. Atomic.
pub fn write_mesh_with_scalars(
    path: &Path,
    mesh: &TriMesh,
    scalars: &[(&str, &[f32])],
) -> Result<()> {
    write_mesh_with_fields(path, mesh, scalars, &[])
}

/// Writes a mesh with float per-vertex fields (`point_scalars`, one value per vertex) and per-face
/// fields (`face_scalars`, one value per triangle, e.g. an "inpainted" flag as 0/1) as point-data
/// and cell-data arrays of a `.vtp` or `.vtk` file. A `.ply` takes per-vertex fields only.
/// Atomic.
pub fn write_mesh_with_fields(
    path: &Path,
    mesh: &TriMesh,
    point_scalars: &[(&str, &[f32])],
    face_scalars: &[(&str, &[f32])],
) -> Result<()> {
    let format = MeshFormat::from_path(path)?;
    let vtk = matches!(format, MeshFormat::Vtp | MeshFormat::Vtk);
    if !vtk && !face_scalars.is_empty() {
        return Err(Error::format(
            path,
            "per-face scalars can only be written to a .vtp or .vtk file",
        ));
    }
    if !vtk && format != MeshFormat::Ply {
        return Err(Error::format(
            path,
            "per-vertex scalars can only be written to a .ply, .vtp or .vtk file",
        ));
    }
    check_writable(path, mesh, format)?;
    for (what, fields, count, unit) in [
        ("scalar", point_scalars, mesh.num_vertices(), "vertices"),
        ("face scalar", face_scalars, mesh.num_faces(), "triangles"),
    ] {
        for (k, (name, values)) in fields.iter().enumerate() {
            if format == MeshFormat::Ply {
                ply::check_field_name(name).map_err(|m| Error::format(path, m))?;
            } else if name.is_empty() {
                return Err(Error::format(path, format!("{what} {k} has an empty name")));
            }
            if fields[..k].iter().any(|(other, _)| other == name) {
                return Err(Error::format(
                    path,
                    format!("{what} name '{name}' is given twice"),
                ));
            }
            if values.len() != count {
                return Err(Error::format(
                    path,
                    format!(
                        "{what} '{name}' has {} values but the mesh has {count} {unit}",
                        values.len(),
                    ),
                ));
            }
        }
    }
    if format == MeshFormat::Ply {
        return write_atomic(path, |w| {
            ply::write(w, mesh, point_scalars).map_err(|e| Error::io(path, e))
        });
    }
    let arrays = |fields: &[(&str, &[f32])]| -> Vec<DataArray> {
        fields
            .iter()
            .map(|(name, values)| DataArray::scalars(name, DataValues::F32(values.to_vec())))
            .collect()
    };
    let data = PolyData {
        point_data: arrays(point_scalars),
        cell_data: arrays(face_scalars),
        ..PolyData::from_mesh(mesh)
    };
    match format {
        MeshFormat::Vtp => write_vtp(path, &data),
        _ => write_vtk_legacy(path, &data),
    }
}

/// Refuses to write a mesh no reader would take back (see `validate::check_writable`).
fn check_writable(path: &Path, mesh: &TriMesh, format: MeshFormat) -> Result<()> {
    let largest = match format {
        MeshFormat::Stl => f32::MAX as f64,
        _ => f64::MAX,
    };
    validate::check_writable(mesh, largest).map_err(|m| Error::format(path, m))
}

/// Appends the fan of `corners.len() − 2` triangles from the first corner of a polygon (the
/// readers' triangulation of OBJ, PLY and VTK polygons; the caller has checked ≥ 3 corners).
pub(crate) fn fan_triangulate(corners: &[u32], faces: &mut Vec<[u32; 3]>) {
    for i in 1..corners.len().saturating_sub(1) {
        faces.push([corners[0], corners[i], corners[i + 1]]);
    }
}
