//! The level-set core: the function φ (negative inside) on a [`crate::grid::Grid3`] and the
//! bridges between it and triangle meshes.

pub mod marching_cubes;
