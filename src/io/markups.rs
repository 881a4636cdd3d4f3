//! Points picked in 3D Slicer, read from its markups files: Markups JSON (`.mrk.json`) and the
//! fiducial CSV (`.fcsv`), returned in the mesh's frame.
//!
//! Slicer keeps its scene in RAS (x right, y anterior, z superior) but writes files in LPS
//! (x left, y posterior) by default since version 4.11: markups files and the models it exports
//! (STL, OBJ, VTK). A mesh file is therefore taken to be in LPS, as `voxelize`'s NRRD output is,
//! and a point stored in RAS is turned into LPS by negating x and y. Coordinates are never
//! rescaled (Slicer's unit is the millimetre).
//!
//! `.mrk.json` (schema `markups-schema-v1.0.0`): every control point with a position of every
//! markup in `"markups"` (point lists, and the control points of lines, curves, planes…), in the
//! markup's `"coordinateSystem"` (`"LPS"` when absent, the schema's default); points whose
//! `"positionStatus"` is `"undefined"` (listed but never placed) are left out.
//!
//! `.fcsv`: `#` header lines, among them `# CoordinateSystem = LPS|RAS` (older files: `1` = LPS,
//! `0` = RAS; without the line, RAS, as files from before Slicer 4.11 are) and `# columns = id,
//! x,y,z,…` (without it, x, y, z are the 2nd to 4th fields); then one control point per line.

use crate::{Error, Result};
use nalgebra::Point3;
use serde_json::Value;
use std::path::Path;

/// The frame a markups file stores its points in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MarkupsFrame {
    /// x left, y posterior, z superior (Slicer's file default, and the mesh's frame).
    Lps,
    /// x right, y anterior, z superior (Slicer's scene).
    Ras,
}

impl MarkupsFrame {
    /// The frame named by a coordinate-system text: `LPS`/`RAS` (any case) or the old codes
    /// `1`/`0`.
    fn parse(text: &str) -> Option<MarkupsFrame> {
        match text.trim().to_ascii_uppercase().as_str() {
            "LPS" | "1" => Some(MarkupsFrame::Lps),
            "RAS" | "0" => Some(MarkupsFrame::Ras),
            _ => None,
        }
    }

    /// `p` (stored in this frame) in LPS, the mesh's frame.
    fn to_lps(self, p: [f64; 3]) -> Point3<f64> {
        match self {
            MarkupsFrame::Lps => Point3::new(p[0], p[1], p[2]),
            MarkupsFrame::Ras => Point3::new(-p[0], -p[1], p[2]),
        }
    }
}

/// Whether `path` names a Slicer markups file (`.mrk.json` or `.fcsv`, any case).
pub fn is_markups_path(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    name.ends_with(".mrk.json") || name.ends_with(".fcsv")
}

/// Reads the picked points of a Slicer markups file (`.mrk.json` or `.fcsv`, see the module
/// docs) in the mesh's frame (LPS), in file order. A malformed file, an unknown coordinate
/// system, a non-finite coordinate or a file with no placed point is an error naming the file.
pub fn read_markups(path: &Path) -> Result<Vec<Point3<f64>>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let name = path.to_string_lossy().to_ascii_lowercase();
    let points = if name.ends_with(".fcsv") {
        parse_fcsv(&text)
    } else {
        parse_mrk_json(&text)
    }
    .map_err(|m| Error::format(path, m))?;
    if points.is_empty() {
        return Err(Error::format(path, "no placed control point"));
    }
    Ok(points)
}

/// The points of a Markups JSON text, in LPS.
fn parse_mrk_json(text: &str) -> std::result::Result<Vec<Point3<f64>>, String> {
    let root: Value =
        serde_json::from_str(text).map_err(|e| format!("not a Markups JSON file: {e}"))?;
    let markups = root
        .get("markups")
        .and_then(Value::as_array)
        .ok_or("not a Markups JSON file: no \"markups\" list")?;
    let mut points = Vec::new();
    for (m, markup) in markups.iter().enumerate() {
        let frame = match markup.get("coordinateSystem") {
            None => MarkupsFrame::Lps,
            Some(v) => v.as_str().and_then(MarkupsFrame::parse).ok_or_else(|| {
                format!(
                    "markup {}: coordinateSystem {v} is neither \"LPS\" nor \"RAS\"",
                    m + 1
                )
            })?,
        };
        let Some(controls) = markup.get("controlPoints") else {
            continue;
        };
        let controls = controls
            .as_array()
            .ok_or_else(|| format!("markup {}: \"controlPoints\" is not a list", m + 1))?;
        for (k, point) in controls.iter().enumerate() {
            if point.get("positionStatus").and_then(Value::as_str) == Some("undefined") {
                continue;
            }
            let bad = || {
                format!(
                    "markup {} control point {}: \"position\" must be three finite numbers",
                    m + 1,
                    k + 1
                )
            };
            let position = point
                .get("position")
                .and_then(Value::as_array)
                .ok_or_else(bad)?;
            let xyz: Vec<f64> = position.iter().filter_map(Value::as_f64).collect();
            if position.len() != 3 || xyz.len() != 3 || !xyz.iter().all(|v| v.is_finite()) {
                return Err(bad());
            }
            points.push(frame.to_lps([xyz[0], xyz[1], xyz[2]]));
        }
    }
    Ok(points)
}

/// The points of a fiducial CSV text, in LPS.
fn parse_fcsv(text: &str) -> std::result::Result<Vec<Point3<f64>>, String> {
    let mut frame = MarkupsFrame::Ras;
    let mut columns = [1usize, 2, 3];
    let mut points = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(header) = line.strip_prefix('#') {
            let Some((key, value)) = header.split_once('=') else {
                continue;
            };
            match key.trim().to_ascii_lowercase().as_str() {
                "coordinatesystem" => {
                    frame = MarkupsFrame::parse(value).ok_or_else(|| {
                        format!(
                            "line {}: CoordinateSystem {:?} is neither LPS nor RAS",
                            n + 1,
                            value.trim()
                        )
                    })?;
                }
                "columns" => {
                    let names: Vec<&str> = value.split(',').map(str::trim).collect();
                    for (c, axis) in columns.iter_mut().zip(["x", "y", "z"]) {
                        *c = names.iter().position(|&s| s == axis).ok_or_else(|| {
                            format!("line {}: the columns list no {axis:?}", n + 1)
                        })?;
                    }
                }
                _ => {}
            }
            continue;
        }
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let mut p = [0.0f64; 3];
        for (v, &c) in p.iter_mut().zip(&columns) {
            *v = fields
                .get(c)
                .and_then(|f| f.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    format!(
                        "line {}: field {} is not a finite coordinate: {line:?}",
                        n + 1,
                        c + 1
                    )
                })?;
        }
        points.push(frame.to_lps(p));
    }
    Ok(points)
}
