//! Reading and writing triangle meshes as STL, OBJ and PLY, the format chosen by file extension.
//!
//! Readers accept binary and ASCII STL (corners welded by exact coordinates), OBJ (polygons
//! fan-triangulated, all objects merged) and PLY (ascii and both binary byte orders). Every mesh
//! read is validated: finite coordinates, at least one triangle, indices in range, and at least one
//! non-degenerate triangle. Every error names the file and the problem in one line. Writers go
//! through [`write_atomic`], so a failed write leaves no partial file.
//!
//! Grids (level-set functions) are written as NumPy `.npy` with a JSON sidecar (`npy`), as
//! VTK ImageData `.vti` (`vti`, for ParaView) and as NRRD (`nrrd`, for 3D Slicer and ITK).

mod atomic;
mod npy;
mod npz;
mod nrrd;
mod obj;
mod ply;
mod stl;
mod text;
mod validate;
mod vti;
mod vtp;

pub use atomic::write_atomic;
pub use npy::{npy_sidecar_path, read_npy, write_npy, NpySidecar};
pub use npz::{read_npz, write_npz, NpyArray, NpyData};
pub use nrrd::{read_nrrd, write_nrrd};
pub use vti::{read_vti, write_vti, VTI_ARRAY_NAME};
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
}

impl MeshFormat {
    /// The format named by the extension of `path` (`.stl`, `.obj`, `.ply`, any case).
    pub fn from_path(path: &Path) -> Result<MeshFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("stl") => Ok(MeshFormat::Stl),
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
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
    let mesh = match format {
        MeshFormat::Stl => stl::read(&bytes),
        MeshFormat::Obj => obj::read(&bytes),
        MeshFormat::Ply => ply::read(&bytes).map(|p| p.mesh),
    }
    .map_err(|m| Error::format(path, m))?;
    validate::validate_mesh(&mesh).map_err(|m| Error::format(path, m))?;
    Ok(mesh)
}

/// Named per-vertex scalar fields, as read from PLY.
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
    let bytes = read_bytes(path)?;
    let read = ply::read(&bytes).map_err(|m| Error::format(path, m))?;
    validate::validate_mesh(&read.mesh).map_err(|m| Error::format(path, m))?;
    Ok((read.mesh, read.scalars))
}

/// Writes a mesh in the format named by the extension: binary STL (f32, facet normals computed),
/// OBJ (exact f64 text) or binary little-endian PLY (f64 coordinates). Atomic.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<()> {
    let format = MeshFormat::from_path(path)?;
    validate::check_indices(mesh).map_err(Error::InvalidMesh)?;
    write_atomic(path, |w| {
        match format {
            MeshFormat::Stl => stl::write(w, mesh),
            MeshFormat::Obj => obj::write(w, mesh),
            MeshFormat::Ply => ply::write(w, mesh, &[]),
        }
        .map_err(|e| Error::io(path, e))
    })
}

/// Writes a mesh as binary PLY with one float vertex property per `(name, values)` pair; `path`
/// must end in `.ply`, names must be identifiers other than x, y, z, and every `values` must have
/// one entry per vertex. Atomic.
pub fn write_mesh_with_scalars(
    path: &Path,
    mesh: &TriMesh,
    scalars: &[(&str, &[f32])],
) -> Result<()> {
    if MeshFormat::from_path(path)? != MeshFormat::Ply {
        return Err(Error::format(
            path,
            "per-vertex scalars can only be written to a .ply file",
        ));
    }
    validate::check_indices(mesh).map_err(Error::InvalidMesh)?;
    for (k, (name, values)) in scalars.iter().enumerate() {
        ply::check_field_name(name).map_err(|m| Error::format(path, m))?;
        if scalars[..k].iter().any(|(other, _)| other == name) {
            return Err(Error::format(
                path,
                format!("scalar name '{name}' is given twice"),
            ));
        }
        if values.len() != mesh.num_vertices() {
            return Err(Error::format(
                path,
                format!(
                    "scalar '{name}' has {} values but the mesh has {} vertices",
                    values.len(),
                    mesh.num_vertices()
                ),
            ));
        }
    }
    write_atomic(path, |w| {
        ply::write(w, mesh, scalars).map_err(|e| Error::io(path, e))
    })
}
