//! Level-set motions (paper, Section 3): the motions of the multiscale representation are solved
//! by diffusion and thresholding. `diffusion` solves the heat equation u_t = Δu on a grid
//! (Gaussian convolution, separable and parallel, mirror boundary), the building block of the
//! threshold-dynamics (MBO) steps.

pub mod diffusion;
