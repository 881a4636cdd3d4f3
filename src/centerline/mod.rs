//! Vessel centrelines: the centreline graph of a closed or open vessel mesh, each point with its
//! maximal inscribed radius and tangent, split into branches at junctions; diameter profiles
//! along it and the narrowings found on them (issue 20).
//!
//! The paper (Dong, Chien, Shen and Osher) has no centreline; vessel tools (VMTK, 3D Slicer's VMTK
//! extension, morphMan) all start from one, and the repair uses it to size and measure damage.
//! It is computed from the signed distance grid φ the project already builds (`levelset`):
//! - `skeleton`: TEASAR shortest paths through the inside, with open vessel ends as endpoints;
//! - `graph`: the tree split into branches at junctions, spurs pruned;
//! - `refine`: smooth sub-voxel curves centred on the mesh's cross-sections, radius −φ;
//! - `extract`: the whole pipeline from a mesh ([`compute_centerline`]);
//! - `profile`: equivalent (cross-section area) and inscribed diameters along each branch;
//! - `stenosis`: narrowings against the healthy lumen on either side (local and NASCET-like references).
//!
//! Lengths are in the mesh's own units throughout.

pub mod extract;
pub mod graph;
pub mod healthy;
pub mod profile;
pub mod refine;
pub mod skeleton;
pub mod stenosis;

pub use extract::{compute_centerline, CenterlineOptions};
pub use graph::EndKind;

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// One branch: a curve between two ends (open vessel ends, closed ends or junctions).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Branch {
    /// Index in [`Centerline::branches`].
    pub id: usize,
    /// Connected component of the vessel's inside it belongs to.
    pub component: usize,
    /// Arc length, world units.
    pub length: f64,
    /// Points along the branch, world units.
    #[serde(serialize_with = "ser_points", deserialize_with = "de_points")]
    pub points: Vec<Point3<f64>>,
    /// Maximal inscribed radius at each point (−φ), world units.
    pub radius: Vec<f64>,
    /// Unit tangent at each point, from the first point towards the last.
    #[serde(serialize_with = "ser_vectors", deserialize_with = "de_vectors")]
    pub tangent: Vec<Vector3<f64>>,
    /// Kind of the first point.
    pub start: EndKind,
    /// Kind of the last point.
    pub end: EndKind,
}

/// A point where three or more branches meet.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Junction {
    pub id: usize,
    pub component: usize,
    #[serde(serialize_with = "ser_point", deserialize_with = "de_point")]
    pub position: Point3<f64>,
    /// Inscribed radius there, world units.
    pub radius: f64,
    /// Ids of the branches that meet there.
    pub branches: Vec<usize>,
}

/// A free end of the graph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Endpoint {
    #[serde(serialize_with = "ser_point", deserialize_with = "de_point")]
    pub position: Point3<f64>,
    /// Inscribed radius there (an open end: the end loop's mean radius), world units.
    pub radius: f64,
    /// The branch it ends.
    pub branch: usize,
    /// Whether it is an open vessel end of the mesh.
    pub open_end: bool,
}

/// The centreline graph of a vessel mesh.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Centerline {
    /// Voxel of the grid it was computed on, world units.
    pub voxel: f64,
    /// Connected components of the inside that have a centreline.
    pub components: usize,
    pub branches: Vec<Branch>,
    pub junctions: Vec<Junction>,
    pub endpoints: Vec<Endpoint>,
    /// One-line notices (holes capped, components without a tube shape, ...).
    pub notices: Vec<String>,
}

impl Centerline {
    /// Total length of all branches, world units.
    pub fn total_length(&self) -> f64 {
        self.branches.iter().map(|b| b.length).sum()
    }
}

fn ser_point<S: serde::Serializer>(p: &Point3<f64>, s: S) -> Result<S::Ok, S::Error> {
    [p.x, p.y, p.z].serialize(s)
}

fn ser_points<S: serde::Serializer>(ps: &[Point3<f64>], s: S) -> Result<S::Ok, S::Error> {
    let v: Vec<[f64; 3]> = ps.iter().map(|p| [p.x, p.y, p.z]).collect();
    v.serialize(s)
}

fn ser_vectors<S: serde::Serializer>(vs: &[Vector3<f64>], s: S) -> Result<S::Ok, S::Error> {
    let v: Vec<[f64; 3]> = vs.iter().map(|p| [p.x, p.y, p.z]).collect();
    v.serialize(s)
}

fn de_point<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Point3<f64>, D::Error> {
    let [x, y, z] = <[f64; 3]>::deserialize(d)?;
    Ok(Point3::new(x, y, z))
}

fn de_points<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<Point3<f64>>, D::Error> {
    let v = Vec::<[f64; 3]>::deserialize(d)?;
    Ok(v.into_iter().map(Point3::from).collect())
}

fn de_vectors<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<Vector3<f64>>, D::Error> {
    let v = Vec::<[f64; 3]>::deserialize(d)?;
    Ok(v.into_iter().map(Vector3::from).collect())
}
