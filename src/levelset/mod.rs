//! Level-set tools on [`crate::grid::Grid3`] (φ negative inside, world units): redistancing by
//! fast sweeping.

pub mod redistance;
