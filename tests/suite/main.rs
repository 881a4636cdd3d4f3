//! The integration tests, in one test binary: one module per area (formerly one binary per
//! file, each linking the whole library). `tests/suite/NAME.rs` is the module `NAME`, so a test's
//! path names its file: `cargo test --release --test suite bvh_winding::` runs the tests of
//! tests/suite/bvh_winding.rs. The shared helpers are the module `common` (tests/suite/common/).
//! Add new test files here as modules, not as tests/*.rs (each would be a binary of its own).

mod common;

mod bvh_closest;
mod bvh_ray;
mod bvh_winding;
mod centerline_analytic;
mod centerline_vessels;
mod cli_bad_input;
mod cli_batch;
mod cli_cap;
mod cli_centerline;
mod cli_compare;
mod cli_damaged_corpus;
mod cli_evolve;
mod cli_info;
mod cli_levelset;
mod cli_msr;
mod cli_reliability;
mod cli_repair_inputs;
mod grid_resize;
mod grid_sample;
mod grid_spec;
mod inpaint_paper;
mod inpaint_phantom;
mod inpaint_region;
mod inpaint_repair;
mod io_bad_input;
mod io_formats;
mod io_grid_formats;
mod io_vtk;
mod levelset_cavity;
mod levelset_marching_cubes;
mod levelset_redistance;
mod levelset_remesh;
mod levelset_voxelize;
mod mesh_cap;
mod mesh_decimate;
mod mesh_measures;
mod mesh_primitives;
mod mesh_topology;
mod motion_diffusion;
mod motion_flows;
mod msr_archive;
mod msr_cortex;
mod msr_decompose;
mod msr_real_vertices;
mod msr_reconstruct;
mod msr_sample_project;
mod oracle_bvh;
mod properties;
mod repair_real_aorta;
mod report_figures;
mod report_repair_picture;
mod report_stenosis;
