//! The level-set multiscale representation (MSR) of a surface, after Dong, Chien, Shen and Osher
//! (Section 2, Definition 2.1 and Algorithm 1; mesh-native as their Remark 2.2(4) allows): the
//! sample points of the surface are followed across the scales of a curvature motion, and the
//! displacements W_i between consecutive scales are the details; MSR = {W_1..W_N, φ_T}.
//! `representation` holds the data, `archive` its `.npz` file (`compact` its integer coding, `compact_v3` the earlier one), `sample` the sample points X_0,
//! `cover` the samples added where a level's surface has none near, `misread` those added where
//! the level-set reconstruction would misread a level, `project` the Newton
//! projection onto a zero level set (`rescue` for the points where it stalls), `extend` and
//! `reconstruct` the reconstruction by the level set, `fidelity` how closely it gives back each
//! level from the next.

pub mod archive;
pub mod buckets;
pub mod compact;
pub mod compact_v3;
pub mod cover;
pub mod decompose;
pub mod extend;
pub mod fidelity;
pub mod misread;
pub mod project;
pub mod reconstruct;
pub mod representation;
pub mod rescue;
pub mod sample;

pub use representation::{LevelData, Msr, MsrParams};
