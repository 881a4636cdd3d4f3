//! Level-set motions (paper, Section 3): the motions of the multiscale representation are solved
//! by diffusion and thresholding. `diffusion` solves the heat equation u_t = Δu on a grid
//! (Gaussian convolution, separable and parallel, mirror boundary), the building block of the
//! threshold-dynamics (MBO) steps. `flow` steps the paper's velocities (`velocity`: mean
//! curvature, volume-preserving, constant speed, inpainting) by diffusing the signed distance
//! function, thresholding it and redistancing, `evolve` drives a flow up to a final time, and
//! `volume` holds the sub-voxel volume and area estimates and the volume-preserving threshold.

pub mod diffusion;
pub mod evolve;
pub mod flow;
pub mod velocity;
pub mod volume;

pub use evolve::{evolve, step_count};
pub use flow::{Flow, FlowOptions, StepReport};
pub use velocity::Velocity;
