//! Length units named by the user (`--units`) and whether a vessel's size is plausible in them.
//!
//! Coordinates are never rescaled; the unit is only a name. A wrong one goes unnoticed in the
//! figures (a carotid stored in metres reported as "0.0000 mm³"), so its size is checked: the
//! typical vessel radius 2·volume/area (exact for a long cylinder) should lie between 0.1 mm
//! (arterioles) and 50 mm (a large aortic aneurysm) once the unit is known.

use super::measures::{area, area_centroid, signed_volume_about};
use super::topology::boundary_loops;
use crate::TriMesh;
use nalgebra::{Point3, Vector3};

/// Millimetres in one `unit` (`mm`, `cm`, `m`, `um`/`µm`, `in` and their spelt-out names, any
/// case), or None for a unit it does not know (such as the default "file units").
pub fn millimetres_per_unit(unit: &str) -> Option<f64> {
    let u = unit.trim().to_lowercase();
    let u = u.strip_suffix('s').unwrap_or(&u);
    Some(match u {
        "mm" | "millimetre" | "millimeter" => 1.0,
        "cm" | "centimetre" | "centimeter" => 10.0,
        "m" | "metre" | "meter" => 1000.0,
        "um" | "µm" | "micron" | "micrometre" | "micrometer" => 1e-3,
        "in" | "inch" | "inche" => 25.4,
        _ => return None,
    })
}

/// The range of plausible vessel radii, in millimetres.
#[derive(Clone, Copy, Debug)]
pub struct VesselScaleOptions {
    /// Smallest plausible typical radius, mm.
    pub min_radius_mm: f64,
    /// Largest plausible typical radius, mm.
    pub max_radius_mm: f64,
}

impl Default for VesselScaleOptions {
    fn default() -> Self {
        VesselScaleOptions {
            min_radius_mm: 0.1,
            max_radius_mm: 50.0,
        }
    }
}

/// The typical vessel radius 2·volume/area of `mesh`, in its own units: the volume enclosed once
/// every boundary loop (an open vessel end) is closed by a fan from its centroid, over the area
/// of the mesh's own triangles (so an open tube of radius r gives r); None for a mesh without
/// area.
pub fn typical_vessel_radius(mesh: &TriMesh) -> Option<f64> {
    let a = area(mesh);
    let mut closed = mesh.clone();
    for lp in boundary_loops(mesh) {
        let c = lp
            .iter()
            .map(|&v| mesh.vertices[v as usize].coords)
            .sum::<Vector3<f64>>()
            / lp.len().max(1) as f64;
        let ci = closed.vertices.len() as u32;
        closed.vertices.push(Point3::from(c));
        // The loop reversed: a cap wound like the mesh.
        for (k, &v) in lp.iter().enumerate() {
            closed.faces.push([ci, lp[(k + 1) % lp.len()], v]);
        }
    }
    let v = signed_volume_about(&closed, &area_centroid(mesh)).abs();
    (a > 0.0 && v.is_finite()).then(|| 2.0 * v / a)
}

/// A notice when `mesh`'s typical vessel radius ([`typical_vessel_radius`]) is implausible in
/// `unit` (outside the options' range), naming a unit in which it would be plausible; None when
/// it is plausible, or the unit unknown.
pub fn check_vessel_scale(mesh: &TriMesh, unit: &str, opts: &VesselScaleOptions) -> Option<String> {
    let per_unit = millimetres_per_unit(unit)?;
    let radius = typical_vessel_radius(mesh)?;
    let plausible = |mm: f64| (opts.min_radius_mm..=opts.max_radius_mm).contains(&mm);
    let mm = radius * per_unit;
    if plausible(mm) {
        return None;
    }
    let side = if mm < opts.min_radius_mm {
        "below"
    } else {
        "above"
    };
    let guess = [("m", 1000.0), ("cm", 10.0), ("mm", 1.0), ("um", 1e-3)]
        .into_iter()
        .map(|(u, per)| (u, radius * per))
        .find(|&(_, mm)| plausible(mm))
        .map(|(u, mm)| format!("; in {u} it would be {mm:.3} mm"))
        .unwrap_or_default();
    Some(format!(
        "the typical vessel radius 2·volume/area is {radius:.4} {unit}, {side} the {}–{} mm of blood \
         vessels: is the mesh really in {unit}?{guess}",
        opts.min_radius_mm, opts.max_radius_mm
    ))
}
