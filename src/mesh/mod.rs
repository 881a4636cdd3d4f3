//! The triangle mesh and what is measured or repaired on it without a level set: topology
//! (components, boundary loops, manifoldness, orientation), measures (area, enclosed volume by the
//! divergence theorem, bounding box, edge length, genus), the `info` summary, capping of open
//! vessel ends, welding of coincident vertices, simplification within a distance bound,
//! surface-to-surface distances for `compare`, and the plausibility of a vessel's size in a named
//! length unit.

pub mod cap;
pub mod decimate;
pub mod distance;
pub mod info;
pub mod measures;
pub mod orient;
pub mod primitives;
pub mod topology;
mod trimesh;
pub mod units;
pub mod weld;

pub use trimesh::TriMesh;
