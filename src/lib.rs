//! vesselmsr: repair of triangulated blood-vessel surfaces by the level-set multiscale
//! representation (MSR) and surface inpainting of Dong, Chien, Shen and Osher.
//!
//! Data types live apart from the operations on them: `mesh` (the triangle mesh, its topology and
//! measures, capping of open ends), `io` (meshes as STL, OBJ, PLY, VTP and VTK; Slicer
//! markups; grids as npy, vti, nrrd; npz archives), `bvh` (closest point, ray casts and the fast generalized winding number on a
//! bounding volume hierarchy), `grid` (the dense grid and its transform), `levelset` (voxelize,
//! redistance, marching cubes), `motion` (diffusion and threshold-dynamics flows), `msr` (the
//! multiscale representation: decompose, reconstruct, archive), `report` (figures), and `cli`
//! (the command-line tool; `main.rs` only calls it).

pub mod budget;
pub mod bvh;
pub mod centerline;
pub mod cli;
pub mod error;
pub mod grid;
pub mod inpaint;
pub mod io;
pub mod levelset;
pub mod mesh;
pub mod motion;
pub mod msr;
pub mod report;

pub use error::{Error, Result};
pub use mesh::TriMesh;
