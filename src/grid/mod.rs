//! Dense 3-D grids of f32 values (x fastest) with an index↔world transform: the level-set
//! function φ of the paper lives here (negative inside). Besides the grid itself: sampling with
//! gradients (`sample`), padding and sub-boxes (`resize`), and sizing a grid for a mesh with its
//! memory estimate (`spec`).

mod grid3;
mod resize;
mod sample;
pub mod spec;
mod transform;

pub use grid3::{face_neighbours, Grid3};
pub use resize::SubBox;
pub use spec::{grid_for_mesh, GridOptions, GridSpec};
pub use transform::GridTransform;
