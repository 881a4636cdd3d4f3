//! The level-set core: the function φ (negative inside) on a [`crate::grid::Grid3`], as the
//! level-set multiscale representation of Dong, Chien, Shen and Osher works on it, and the
//! bridges between φ and triangle meshes: `voxelize` (mesh → φ), `redistance` (fast sweeping
//! back to a signed distance function), `marching_cubes` (φ → closed mesh) and `project`
//! (extracted vertices onto the input surface), `speck` (lone nodes a hair's breadth across zero);
//! and `remesh`, the mesh → φ → mesh round trip of `vesselmsr remesh` built from them.

pub mod cavity;
pub mod chamfer;
pub mod marching_cubes;
pub mod project;
pub mod redistance;
pub mod refine;
pub mod remesh;
pub mod speck;
pub mod voxelize;
