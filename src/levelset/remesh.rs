//! Re-meshing through the level set, the work of `vesselmsr remesh` (and the Python package's
//! `remesh`): the zero level set of the input's signed distance grid φ extracted by marching
//! cubes (enclosed cavities the input does not have reopened), its vertices then projected onto
//! the input and edges split where the surface is still off it: a closed, manifold, outward mesh
//! at the grid's resolution; optionally simplified within a number of voxels (`mesh::decimate`).
//! Open ends come out closed: an open input is followed with its ends capped as `cap` caps them
//! (planar caps), so the ends come out flat and their rims sharp, where marching cubes alone
//! rounds a rim off by 0.6–0.8 voxel.

use super::cavity::{extract_joining_cavities, find_cavities, CavityOptions};
use super::marching_cubes::{extract_surface, ExtractOptions};
use super::project::{project_vertices, ProjectOptions};
use super::refine::{refine_to_surface, remesh_refine_options, RefineReport};
use super::voxelize::{voxelize_with_report, VoxelizeOptions};
use crate::bvh::MeshBvh;
use crate::grid::spec::{grid_for_mesh, GridJson, GridOptions, GridSpec};
use crate::grid::Grid3;
use crate::mesh::cap::{cap_holes, CapOptions};
use crate::mesh::decimate::{decimate_mesh, DecimateOptions, DecimateReport};
use crate::mesh::info::{mesh_info, MeshInfo};
use crate::mesh::topology::EdgeMap;
use crate::{Error, Result, TriMesh};
use std::time::Instant;

/// Options of [`remesh_mesh`] and [`remesh_levelset`].
#[derive(Debug, Clone)]
pub struct RemeshOptions {
    /// The grid (voxel size or resolution, memory limit); [`remesh_mesh`] only.
    pub grid: GridOptions,
    /// Move the extracted vertices onto the input (its open ends capped; within one voxel) and
    /// split the edges whose midpoints stay farther than 0.05 voxel from it (the default); false
    /// keeps the marching-cubes surface as it is.
    pub project: bool,
    /// Simplify the output by quadric edge collapses, its Hausdorff distance to the undecimated
    /// output held within this many voxels; None: no simplification.
    pub decimate: Option<f64>,
}

impl Default for RemeshOptions {
    fn default() -> Self {
        RemeshOptions {
            grid: GridOptions::default(),
            project: true,
            decimate: None,
        }
    }
}

impl RemeshOptions {
    /// Checks the options before any work: [`Error::BadOption`] naming `voxel`, `resolution` or
    /// `decimate`.
    pub fn validate(&self) -> Result<()> {
        let bad = |option: &'static str, problem: String| Err(Error::BadOption { option, problem });
        if let Some(v) = self.grid.voxel {
            if !(v.is_finite() && v > 0.0) {
                return bad("voxel", format!("must be a positive length, got {v}"));
            }
            if self.grid.resolution.is_some() {
                return bad("voxel", "and resolution cannot both be given".into());
            }
        }
        if self.grid.resolution == Some(0) {
            return bad(
                "resolution",
                "must be at least 1 cell along the longest side".into(),
            );
        }
        if let Some(v) = self.decimate {
            if !(v.is_finite() && v > 0.0) {
                return bad(
                    "decimate",
                    format!("must be a positive number of voxels, got {v}"),
                );
            }
        }
        Ok(())
    }
}

/// What [`remesh_levelset`] tells while it works.
#[derive(Debug, Clone, Copy)]
pub enum RemeshEvent<'a> {
    /// A one-line notice (the CLI prints it on stderr).
    Notice(&'a str),
    /// The stage starting: "extracting the surface", "projecting onto the input", "refining
    /// towards the input", "decimating".
    Stage(&'static str),
}

/// What `remesh --json` prints but the timings.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RemeshReport {
    pub grid: GridJson,
    pub output: MeshInfo,
    /// Enclosed cavities of the extraction reopened to the outside (folds narrower than h).
    pub cavities_joined: usize,
    /// Edges split to bring the surface within 0.05 voxel of the input.
    pub edges_split: usize,
    /// The simplification of `decimate`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decimate: Option<DecimateReport>,
}

/// Seconds spent in the stages of [`remesh_levelset`].
#[derive(Debug, Clone, Copy, Default)]
pub struct RemeshTimings {
    pub marching_cubes: f64,
    pub project: f64,
    pub decimate: f64,
}

/// The re-meshed surface and its report.
#[derive(Debug, Clone)]
pub struct Remeshed {
    pub mesh: TriMesh,
    pub report: RemeshReport,
    pub timings: RemeshTimings,
}

/// Re-meshes `input` on the grid `opts.grid` asks for: sizes the grid
/// ([`grid_for_mesh`]), voxelizes the input with the default options and runs
/// [`remesh_levelset`]. Errors: bad options ([`RemeshOptions::validate`]), a grid over the memory
/// limit or a mesh no grid can be sized for, and the errors of voxelization and extraction.
pub fn remesh_mesh(
    input: &TriMesh,
    opts: &RemeshOptions,
    on_event: &mut dyn FnMut(RemeshEvent<'_>),
) -> Result<Remeshed> {
    opts.validate()?;
    let spec = grid_for_mesh(input, &opts.grid)?;
    let (phi, _) = voxelize_with_report(
        input,
        spec.dims,
        spec.transform,
        &VoxelizeOptions::default(),
    )?;
    remesh_levelset(input, &spec, phi, opts, on_event)
}

/// Re-meshes `input` from its signed distance grid `phi` (on `spec`, from `voxelize` with the
/// default options; marching cubes reads φ only next to its zero level set, so the narrow band
/// is enough): see the module doc. `opts.grid` is not read.
pub fn remesh_levelset(
    input: &TriMesh,
    spec: &GridSpec,
    mut phi: Grid3,
    opts: &RemeshOptions,
    on_event: &mut dyn FnMut(RemeshEvent<'_>),
) -> Result<Remeshed> {
    on_event(RemeshEvent::Stage("extracting the surface"));
    let t = Instant::now();
    // A fold narrower than the voxel can enclose a bubble of outside the input does not have:
    // reopen it (only when the input has no cavity of its own).
    let extract = ExtractOptions::default();
    let (mut surface, cavities_joined) = if find_cavities(input).is_empty() {
        extract_joining_cavities(&mut phi, &extract, &CavityOptions::default())?
    } else {
        (extract_surface(&phi, &extract)?, 0)
    };
    if cavities_joined > 0 {
        on_event(RemeshEvent::Notice(&format!(
            "reopened {cavities_joined} fold(s) of the input that closed into an enclosed \
             cavity at this voxel size"
        )));
    }
    let marching_cubes = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut refined = RefineReport::default();
    if opts.project {
        on_event(RemeshEvent::Stage("projecting onto the input"));
        let project = ProjectOptions {
            max_distance: spec.voxel(),
            ..Default::default()
        };
        // The extraction closes open ends: its end sheets follow the input with its ends capped
        // (the planar caps of `cap`), so the rims come out sharp; an input that cannot be
        // capped is followed away from its rims only.
        let capped = (EdgeMap::new(input).boundary_edges() > 0)
            .then(|| cap_holes(input, &CapOptions::default()).ok())
            .flatten()
            .map(|(m, _)| m);
        let target = capped.as_ref().unwrap_or(input);
        let bvh = MeshBvh::new(target);
        project_vertices(&mut surface, target, &bvh, &project);
        on_event(RemeshEvent::Stage("refining towards the input"));
        refined = refine_to_surface(
            &mut surface,
            target,
            &bvh,
            &remesh_refine_options(spec.voxel()),
        );
    }
    let project = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let decimate = opts.decimate.map(|voxels| {
        on_event(RemeshEvent::Stage("decimating"));
        let decimate = DecimateOptions {
            max_distance: voxels * spec.voxel(),
            ..DecimateOptions::default()
        };
        let (lean, report) = decimate_mesh(&surface, &decimate);
        surface = lean;
        report
    });
    let decimate_s = t.elapsed().as_secs_f64();
    let output = mesh_info(&surface);
    Ok(Remeshed {
        mesh: surface,
        report: RemeshReport {
            grid: GridJson::of(spec),
            output,
            cavities_joined,
            edges_split: refined.edges_split,
            decimate,
        },
        timings: RemeshTimings {
            marching_cubes,
            project,
            decimate: decimate_s,
        },
    })
}
