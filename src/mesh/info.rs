//! The `info` summary of a mesh (validation and measures), serialisable to JSON.
//!
//! [`mesh_info`] builds the edge map and the component labelling once and derives every count and
//! measure from them. A mesh is *watertight* when it has at least one face, no boundary edges, no
//! non-manifold edges or vertices, and consistent winding: then it bounds a solid and its volume is
//! reported.

use super::measures::{
    area, bounding_box, degenerate_faces_with, euler_characteristic_of, genus_of,
    mean_edge_length_of, signed_volume,
};
use super::topology::{connected_components, orientation_of, EdgeMap, Orientation};
use super::TriMesh;
use serde::Serialize;
use std::fmt;

/// Validation and measures of a mesh. Lengths are in file units (the mesh is never rescaled).
#[derive(Debug, Clone, Serialize)]
pub struct MeshInfo {
    /// Number of vertices stored (including any not used by faces).
    pub vertices: usize,
    /// Number of triangles.
    pub faces: usize,
    /// Connected components (faces joined through shared edges or vertices).
    pub components: usize,
    /// Closed chains of boundary edges: open vessel ends and holes.
    pub boundary_loops: usize,
    /// Edges used by one triangle.
    pub boundary_edges: usize,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices whose triangles form more than one fan (not counting ends of non-manifold edges).
    pub non_manifold_vertices: usize,
    /// Triangles with a repeated vertex or (near) zero area.
    pub degenerate_faces: usize,
    /// At least one face, no boundary or non-manifold edges, no non-manifold vertices, consistent
    /// winding.
    pub watertight: bool,
    /// Which way the triangles face.
    pub orientation: Orientation,
    /// Enclosed volume (file units³), only when watertight.
    pub volume: Option<f64>,
    /// Signed volume by the divergence theorem (file units³); meaningful only when closed.
    pub signed_volume: f64,
    /// Surface area (file units²).
    pub area: f64,
    /// Bounding box corner with the smallest coordinates.
    pub bbox_min: [f64; 3],
    /// Bounding box corner with the largest coordinates.
    pub bbox_max: [f64; 3],
    /// Mean length of the unique edges.
    pub mean_edge: f64,
    /// V − E + F (V counting vertices used by faces).
    pub euler_characteristic: i64,
    /// Total genus, only for closed orientable manifold meshes.
    pub genus: Option<i64>,
}

/// Validates and measures `mesh`.
pub fn mesh_info(mesh: &TriMesh) -> MeshInfo {
    let map = EdgeMap::new(mesh);
    let (components, labels) = connected_components(mesh);
    let edges = map.summary();
    let (boundary_edges, non_manifold_edges) = (edges.boundary_edges, edges.non_manifold_edges);
    let non_manifold_vertices = map.non_manifold_vertices();
    let watertight = mesh.num_faces() > 0
        && boundary_edges == 0
        && non_manifold_edges == 0
        && non_manifold_vertices == 0
        && edges.consistent;
    let boundary_loops = map.boundary_loops().len();
    let mean_edge = mean_edge_length_of(&map);
    let signed_volume = signed_volume(mesh);
    let (lo, hi) = bounding_box(mesh);
    MeshInfo {
        vertices: mesh.num_vertices(),
        faces: mesh.num_faces(),
        components,
        boundary_loops,
        boundary_edges,
        non_manifold_edges,
        non_manifold_vertices,
        degenerate_faces: degenerate_faces_with(mesh, mean_edge),
        watertight,
        orientation: orientation_of(&map, &edges, components, &labels),
        volume: watertight.then_some(signed_volume.abs()),
        signed_volume,
        area: area(mesh),
        bbox_min: lo.coords.into(),
        bbox_max: hi.coords.into(),
        mean_edge,
        euler_characteristic: euler_characteristic_of(&map),
        genus: genus_of(&map, &edges, components, non_manifold_vertices),
    }
}

impl MeshInfo {
    /// Why the mesh is not watertight, as short phrases (empty when it is).
    pub fn leaks(&self) -> Vec<String> {
        let mut why = Vec::new();
        if self.faces == 0 {
            why.push("no faces".to_string());
        }
        if self.boundary_edges > 0 {
            why.push(format!(
                "{} boundary loop{} ({} boundary edges)",
                self.boundary_loops,
                plural(self.boundary_loops),
                self.boundary_edges
            ));
        }
        if self.non_manifold_edges > 0 {
            why.push(format!(
                "{} non-manifold edge{}",
                self.non_manifold_edges,
                plural(self.non_manifold_edges)
            ));
        }
        if self.non_manifold_vertices > 0 {
            why.push(format!(
                "{} non-manifold vert{}",
                self.non_manifold_vertices,
                if self.non_manifold_vertices == 1 {
                    "ex"
                } else {
                    "ices"
                }
            ));
        }
        if self.orientation == Orientation::Inconsistent {
            why.push("inconsistent orientation".to_string());
        }
        why
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// About six significant digits, without a long tail of zeros or a needless exponent.
fn num(x: f64) -> String {
    if !x.is_finite() {
        return x.to_string();
    }
    let a = x.abs();
    if a == 0.0 {
        return "0".to_string();
    }
    if !(1e-4..1e9).contains(&a) {
        return format!("{x:.5e}");
    }
    let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn triple(p: &[f64; 3]) -> String {
    format!("({}, {}, {})", num(p[0]), num(p[1]), num(p[2]))
}

impl fmt::Display for MeshInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let row = |f: &mut fmt::Formatter<'_>, k: &str, v: String| writeln!(f, "{k:<22}{v}");
        row(f, "vertices", self.vertices.to_string())?;
        row(f, "faces", self.faces.to_string())?;
        row(f, "components", self.components.to_string())?;
        row(
            f,
            "boundary loops",
            format!("{} (open ends or holes)", self.boundary_loops),
        )?;
        row(f, "boundary edges", self.boundary_edges.to_string())?;
        row(f, "non-manifold edges", self.non_manifold_edges.to_string())?;
        row(
            f,
            "non-manifold vertices",
            self.non_manifold_vertices.to_string(),
        )?;
        row(f, "degenerate faces", self.degenerate_faces.to_string())?;
        let wt = if self.watertight {
            "yes".to_string()
        } else {
            format!("no: {}", self.leaks().join(", "))
        };
        row(f, "watertight", wt)?;
        let orient = match self.orientation {
            Orientation::Outward => "outward (normals point out of the enclosed volume)",
            Orientation::Inward => {
                "inward (normals point into the enclosed volume; flip to repair)"
            }
            Orientation::Inconsistent => {
                "inconsistent (neighbouring triangles disagree in winding)"
            }
            Orientation::Open => "open (consistent winding, but open: no inside to point to)",
        };
        row(f, "orientation", orient.to_string())?;
        let vol = match self.volume {
            Some(v) => format!("{} (file units³)", num(v)),
            None => "n/a (not watertight)".to_string(),
        };
        row(f, "volume", vol)?;
        row(f, "area", format!("{} (file units²)", num(self.area)))?;
        row(f, "bounding box min", triple(&self.bbox_min))?;
        row(f, "bounding box max", triple(&self.bbox_max))?;
        let ext = [0, 1, 2].map(|i| num(self.bbox_max[i] - self.bbox_min[i]));
        row(
            f,
            "extent",
            format!("{} × {} × {} (file units)", ext[0], ext[1], ext[2]),
        )?;
        row(
            f,
            "mean edge",
            format!("{} (file units)", num(self.mean_edge)),
        )?;
        row(
            f,
            "euler characteristic",
            self.euler_characteristic.to_string(),
        )?;
        let genus = match self.genus {
            Some(g) => g.to_string(),
            None => "n/a (defined for closed orientable manifold surfaces only)".to_string(),
        };
        row(f, "genus", genus)
    }
}
