//! Capping a whole mesh into a watertight one, as `vesselmsr cap` (and the Python package's
//! `cap`) does: coincident vertices welded, triangles wound consistently and the result faced
//! outward (unless asked not to), every boundary loop closed by [`cap_holes`], and the result
//! refused unless it is watertight.

use super::{cap_holes, CapOptions, CapReport};
use crate::mesh::info::{mesh_info, MeshInfo};
use crate::mesh::orient::orient_consistently;
use crate::mesh::weld::weld_coincident;
use crate::{Error, Result, TriMesh};

/// The watertight mesh of [`cap_mesh`] and what was done; serialises as `cap --json` prints it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CappedMesh {
    /// The closed mesh.
    #[serde(skip)]
    pub mesh: TriMesh,
    /// The input's measures, after welding.
    pub input: MeshInfo,
    /// What capping did.
    pub cap: CapReport,
    /// The output's measures.
    pub output: MeshInfo,
    /// Triangles flipped to agree with their neighbours' winding before capping.
    pub inconsistent_faces_flipped: usize,
}

impl CappedMesh {
    /// The notices of the capping (the CLI prints them on stderr after writing the output).
    pub fn notices(&self) -> Vec<String> {
        let mut notices = self.cap.messages.clone();
        if self.inconsistent_faces_flipped > 0 {
            notices.push(format!(
                "{} triangles were wound against their neighbours and were flipped",
                self.inconsistent_faces_flipped
            ));
        }
        notices
    }
}

/// Closes every boundary loop of `mesh` into a watertight mesh. A triangle soup (corners not
/// shared) is first welded into the surface it describes, as an STL reader would: `on_weld` is
/// told how many vertices were merged (when any), before capping starts. When
/// `opts.orient_outward`, triangles wound against their neighbours are flipped first and the
/// result faces outward; otherwise the input's winding is kept.
///
/// Errors: [`Error::BadOption`] (`target_edge`) for a target edge length that is not a positive
/// length; the error of [`cap_holes`] in the context "capping failed"; [`Error::Geometry`] when
/// the capped mesh is not watertight (defects capping cannot mend, such as non-manifold edges or
/// vertices of the input), naming what leaks in the output and in the input.
pub fn cap_mesh(
    mesh: &TriMesh,
    opts: &CapOptions,
    on_weld: &mut dyn FnMut(usize),
) -> Result<CappedMesh> {
    if let Some(l) = opts.target_edge_length {
        if !(l.is_finite() && l > 0.0) {
            return Err(Error::BadOption {
                option: "target_edge",
                problem: format!("must be a positive length, got {l}"),
            });
        }
    }
    let (mut mesh, merged) = weld_coincident(mesh);
    if merged > 0 {
        on_weld(merged);
    }
    let input = mesh_info(&mesh);
    let inconsistent_faces_flipped = if opts.orient_outward {
        orient_consistently(&mut mesh)
    } else {
        0
    };
    let (capped, cap) = cap_holes(&mesh, opts).map_err(|e| e.context("capping failed"))?;
    let output = mesh_info(&capped);
    // The promise of `cap` is a watertight mesh: refuse anything else.
    if !output.watertight {
        return Err(Error::Geometry(format!(
            "capping could not make the mesh watertight: {} (input: {})",
            output.leaks().join(", "),
            input.leaks().join(", ")
        )));
    }
    Ok(CappedMesh {
        mesh: capped,
        input,
        cap,
        output,
        inconsistent_faces_flipped,
    })
}
