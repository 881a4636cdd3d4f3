//! Dense 3-D grids of f32 values (x fastest) with an index↔world transform: the level-set
//! function φ of the paper lives here (negative inside). Besides the grid itself: sampling with
//! gradients (`sample`).

mod grid3;
mod sample;
mod transform;

pub use grid3::Grid3;
pub use transform::GridTransform;
