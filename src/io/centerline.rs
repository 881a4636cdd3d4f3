//! Centreline files: JSON (the `centerline::Centerline` as serde writes it: every branch's
//! points, radii and tangents, the junctions and endpoints) and VTK XML PolyData (one polyline
//! per branch; point data `Radius` (VMTK's MaximumInscribedSphereRadius), `Tangent`, `BranchId`,
//! `ArcLength`; cell data `BranchId`, `Length`), which ParaView and 3D Slicer open.

use super::vtp::{write_vtp, DataArray, DataValues, PolyData};
use super::write_atomic;
use crate::centerline::Centerline;
use crate::{Error, Result};
use std::path::Path;

/// Writes `centerline` as JSON, atomically.
pub fn write_centerline_json(path: &Path, centerline: &Centerline) -> Result<()> {
    write_atomic(path, |out| {
        serde_json::to_writer(&mut *out, centerline)
            .map_err(|e| Error::format(path, format!("cannot write JSON: {e}")))
    })
}

/// Writes `centerline` as VTK XML PolyData, atomically.
pub fn write_centerline_vtp(path: &Path, centerline: &Centerline) -> Result<()> {
    let mut data = PolyData::default();
    let (mut radius, mut tangent, mut branch_id, mut arc) = (vec![], vec![], vec![], vec![]);
    for b in &centerline.branches {
        let first = data.points.len() as u32;
        let mut s = 0.0;
        for (i, p) in b.points.iter().enumerate() {
            if i > 0 {
                s += (p - b.points[i - 1]).norm();
            }
            data.points.push([p.x, p.y, p.z]);
            radius.push(b.radius[i]);
            tangent.extend_from_slice(&[b.tangent[i].x, b.tangent[i].y, b.tangent[i].z]);
            branch_id.push(b.id as i32);
            arc.push(s);
        }
        data.lines
            .push((first..first + b.points.len() as u32).collect());
    }
    data.point_data = vec![
        DataArray::scalars("Radius", DataValues::F64(radius)),
        DataArray {
            name: "Tangent".into(),
            components: 3,
            values: DataValues::F64(tangent),
        },
        DataArray::scalars("BranchId", DataValues::I32(branch_id)),
        DataArray::scalars("ArcLength", DataValues::F64(arc)),
    ];
    data.cell_data = vec![
        DataArray::scalars(
            "BranchId",
            DataValues::I32(centerline.branches.iter().map(|b| b.id as i32).collect()),
        ),
        DataArray::scalars(
            "Length",
            DataValues::F64(centerline.branches.iter().map(|b| b.length).collect()),
        ),
    ];
    write_vtp(path, &data)
}

/// Reads a centreline JSON file written by [`write_centerline_json`], checking that every branch
/// has as many radii and tangents as points, at least two points, finite values, and that the
/// ids agree with the positions.
pub fn read_centerline_json(path: &Path) -> Result<Centerline> {
    let text = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let cl: Centerline = serde_json::from_slice(&text)
        .map_err(|e| Error::format(path, format!("not a centreline JSON file: {e}")))?;
    for (i, b) in cl.branches.iter().enumerate() {
        let n = b.points.len();
        if b.id != i || n < 2 || b.radius.len() != n || b.tangent.len() != n {
            return Err(Error::format(
                path,
                format!("branch {i}: id, points, radii and tangents do not agree"),
            ));
        }
        let finite = b.points.iter().all(|p| p.iter().all(|c| c.is_finite()))
            && b.radius.iter().all(|r| r.is_finite() && *r >= 0.0)
            && b.tangent.iter().all(|t| t.iter().all(|c| c.is_finite()));
        if !finite {
            return Err(Error::format(
                path,
                format!("branch {i}: non-finite values"),
            ));
        }
    }
    if cl.branches.is_empty() {
        return Err(Error::format(path, "the centreline has no branch"));
    }
    Ok(cl)
}
