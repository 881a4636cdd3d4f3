//! Level-set core: the bridges between triangle meshes and signed distance grids φ (negative
//! inside), as the level-set multiscale representation of Dong, Chien, Shen and Osher works on φ.

pub mod voxelize;
