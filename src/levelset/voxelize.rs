//! Voxelization: a triangle mesh to a signed distance grid φ, negative inside (the level-set
//! function the multiscale representation of Dong, Chien, Shen and Osher evolves).
//!
//! * **Magnitude**: the exact Euclidean distance to the triangles (computed in f64 by the BVH's
//!   point–triangle routine, stored as f32) at every node within a narrow band of
//!   [`VoxelizeOptions::band`] voxels of the surface; the triangles are scattered onto the grid
//!   rather than each node querying the hierarchy (see `voxelize/band.rs`). Outside the band
//!   the value is a placeholder ±band·h ([`FarFill::Clamp`], a lower bound of the true distance:
//!   φ is then the signed distance clamped to the band, which the redistancer turns into a full
//!   distance), or the exact distance at every node ([`FarFill::Exact`], slower).
//! * **Sign**: inside iff the generalized winding number w (Jacobson, Kavan and Sorkine-Hornung
//!   2013; fast evaluation of Barill et al. 2018) satisfies |w| ≥ ½. So open-ended vessels and
//!   meshes with holes have the inside one expects (the lumen, closed across each open end by
//!   the surface where |w| = ½), and the sign does not depend on the orientation: an
//!   inward-facing closed mesh (w = −1 inside) gives the same φ as the outward one. This is the
//!   rule of libigl's `signed_distance` with the fast winding number sign. w is evaluated at few
//!   nodes and carried along grid edges that provably cross no triangle (see
//!   `voxelize/sign.rs`), so the sign is known at every node, in and out of the band. On a
//!   closed surface (every edge used as often in each direction) w is an integer, the signed
//!   count of a ray's crossings, and is evaluated that way (exact; no hierarchy of expansions).
//!
//! Work is parallel (rayon) over z-layers of the grid, except the sign flood, which is a plain
//! breadth-first traversal. Memory: the f32 grid and one byte of state per node, plus the
//! flood's queue (its frontier) and the lists of evaluated nodes.

mod band;
mod sign;

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::time::Instant;

use crate::bvh::{MeshBvh, WindingNumber, WindingOptions};
use crate::grid::{Grid3, GridTransform};
use crate::{Error, Result, TriMesh};

/// What φ holds outside the narrow band.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FarFill {
    /// ±band·h (world units): the distance clamped to the band, correct sign. The redistancer
    /// (`levelset::redistance`) turns these into distances when the whole field is needed.
    #[default]
    Clamp,
    /// The exact distance to the triangles at every node (each node a bounded closest-point
    /// query); several times slower than `Clamp` on a grid mostly outside the band.
    Exact,
}

/// Options of [`voxelize`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoxelizeOptions {
    /// Half-width of the narrow band of exact distances, **in voxels** (≥ 1). Default 3: enough
    /// for central differences and the curvature stencils of the level-set motion next to the
    /// zero level set, and for a trilinear interpolation of φ two voxels away from it.
    pub band: f64,
    /// Values outside the band (default [`FarFill::Clamp`]).
    pub far: FarFill,
    /// Fast winding number accuracy (default: second order at β = 2, as libigl's
    /// `fast_winding_number`; only the sign matters here, and values near ½ are re-evaluated).
    pub winding: WindingOptions,
    /// Spacing of the coarse lattice of nodes where the winding number is always evaluated,
    /// **in voxels** (≥ 1; default 8). Smaller costs more evaluations and shortens the fronts
    /// that place the sign change across open ends.
    pub seed_stride: usize,
}

impl Default for VoxelizeOptions {
    fn default() -> Self {
        VoxelizeOptions {
            band: 3.0,
            far: FarFill::Clamp,
            winding: WindingOptions::SIDES,
            seed_stride: 8,
        }
    }
}

/// What [`voxelize_with_report`] did: node counts, winding-number evaluations and timings.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VoxelizeReport {
    /// Grid nodes.
    pub nodes: usize,
    /// Whether the triangles form a closed surface (every edge used as often in each direction;
    /// orientation may be inward). Only then is the winding number constant off the triangles.
    pub closed: bool,
    /// Nodes within the band (exact distance ≤ band·h).
    pub band_nodes: usize,
    /// Nodes inside (φ < 0, or φ = −0 on the surface).
    pub inside_nodes: usize,
    /// Winding numbers evaluated at seeds: the coarse lattice and the nodes nearest the surface.
    pub seed_evaluations: usize,
    /// Winding numbers evaluated in pockets that no seed reached.
    pub pocket_evaluations: usize,
    /// Winding numbers evaluated on fronts (sign changes away from the triangles: open ends).
    pub front_evaluations: usize,
    /// Rounds of front evaluation.
    pub front_rounds: usize,
    /// Evaluations (among the above) whose fast value came within 0.02 of ±½ and were repeated
    /// with β = 8.
    pub refined_evaluations: usize,
    /// Seconds building the hierarchy and the winding-number expansions.
    pub seconds_hierarchy: f64,
    /// Seconds for the band distances.
    pub seconds_band: f64,
    /// Seconds for the signs.
    pub seconds_sign: f64,
    /// Seconds for the values outside the band (exact distances or the clamp).
    pub seconds_far: f64,
}

impl VoxelizeReport {
    /// All winding-number evaluations.
    pub fn winding_evaluations(&self) -> usize {
        self.seed_evaluations + self.pocket_evaluations + self.front_evaluations
    }
}

/// Whether the valid triangles (as the hierarchy indexes them: indices in range, finite corners)
/// form a closed 2-cycle: for every edge, as many triangles run along it in one direction as in
/// the other. A consistently oriented closed manifold does (outward or inward), and so does a
/// closed surface with several components, touching components or overlapping closed shells.
fn is_closed(mesh: &TriMesh) -> bool {
    let nv = mesh.vertices.len();
    // Each directed use of an edge as (lower, higher) index pair and ±1; sorted, every pair's
    // uses must sum to 0.
    let mut uses: Vec<(u64, i32)> = Vec::with_capacity(3 * mesh.faces.len());
    for face in &mesh.faces {
        if face.iter().any(|&i| i as usize >= nv)
            || face
                .iter()
                .any(|&i| mesh.vertices[i as usize].iter().any(|c| !c.is_finite()))
        {
            continue;
        }
        for e in 0..3 {
            let (a, b) = (face[e], face[(e + 1) % 3]);
            let key = |lo: u32, hi: u32| ((lo as u64) << 32) | hi as u64;
            match a.cmp(&b) {
                std::cmp::Ordering::Less => uses.push((key(a, b), 1)),
                std::cmp::Ordering::Greater => uses.push((key(b, a), -1)),
                std::cmp::Ordering::Equal => {}
            }
        }
    }
    uses.par_sort_unstable_by_key(|&(k, _)| k);
    uses.chunk_by(|x, y| x.0 == y.0)
        .all(|run| run.iter().map(|&(_, s)| s).sum::<i32>() == 0)
}

/// Node state bits shared by the submodules.
pub(crate) const BAND: u8 = 1;
pub(crate) const ASSIGNED: u8 = 2;
pub(crate) const NEG: u8 = 4;
pub(crate) const EVAL: u8 = 8;
pub(crate) const QUEUED: u8 = 16;

/// Grid dimensions and transform in the form the loops use.
pub(crate) struct Layout {
    dims: [usize; 3],
    transform: GridTransform,
    origin: [f64; 3],
    h: f64,
}

impl Layout {
    /// World position of node (i, j, k), computed as [`Grid3::world`] does.
    #[inline]
    fn world(&self, i: usize, j: usize, k: usize) -> Point3<f64> {
        self.transform
            .index_to_world(Vector3::new(i as f64, j as f64, k as f64))
    }

    #[inline]
    fn coords(&self, idx: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [idx % nx, (idx / nx) % ny, idx / (nx * ny)]
    }
}

/// Signed distance to `mesh` at the nodes of the grid `dims` × `transform` (φ < 0 inside; see
/// the module documentation for the sign rule and the values outside the band).
///
/// Errors: [`Error::InvalidMesh`] for a mesh without a usable triangle; [`Error::Geometry`] for
/// invalid options or grid (band < 1 voxel, stride 0, bad dimensions or voxel size, more than
/// 2³² − 1 nodes) and for a mesh that encloses no grid node ("mesh encloses no volume": an open
/// sheet such as a flat disc, or a grid that misses the mesh's inside).
pub fn voxelize(
    mesh: &TriMesh,
    dims: [usize; 3],
    transform: GridTransform,
    opts: &VoxelizeOptions,
) -> Result<Grid3> {
    voxelize_with_report(mesh, dims, transform, opts).map(|(grid, _)| grid)
}

/// [`voxelize`], also returning what it did.
pub fn voxelize_with_report(
    mesh: &TriMesh,
    dims: [usize; 3],
    transform: GridTransform,
    opts: &VoxelizeOptions,
) -> Result<(Grid3, VoxelizeReport)> {
    if !(opts.band.is_finite() && opts.band >= 1.0) {
        return Err(Error::Geometry(format!(
            "voxelize: the band must be at least 1 voxel wide, got {}",
            opts.band
        )));
    }
    if opts.seed_stride == 0 {
        return Err(Error::Geometry(
            "voxelize: the seed stride must be at least 1 voxel".into(),
        ));
    }
    if !(opts.winding.beta.is_finite() && opts.winding.beta > 0.0) {
        return Err(Error::Geometry(format!(
            "voxelize: the winding-number accuracy β must be positive, got {}",
            opts.winding.beta
        )));
    }
    // Validates dims and voxel size.
    // The grid holds the unsigned distances (+∞ outside the band) until the signs are applied.
    let mut grid = Grid3::new(dims, transform, f32::INFINITY)?;
    let n = grid.data().len();
    if n > u32::MAX as usize {
        return Err(Error::Geometry(format!(
            "voxelize: a grid of {n} nodes is too large (at most {} nodes)",
            u32::MAX
        )));
    }
    let h = transform.voxel;
    let layout = Layout {
        dims,
        transform,
        origin: transform.origin,
        h,
    };
    let mut report = VoxelizeReport {
        nodes: n,
        ..VoxelizeReport::default()
    };

    let t = Instant::now();
    report.closed = is_closed(mesh);
    let bvh = MeshBvh::new(mesh);
    if bvh.is_empty() {
        return Err(Error::InvalidMesh(
            "cannot voxelize a mesh without triangles (none with valid vertices)".into(),
        ));
    }
    // A closed surface's winding number is its signed count of ray crossings: no expansions to
    // build. An open one needs the fast winding number's hierarchy.
    let source = if report.closed {
        sign::SignSource::Rays { bvh, mesh }
    } else {
        sign::SignSource::Winding(WindingNumber::from_bvh(bvh, opts.winding))
    };
    let bvh = source.bvh();
    report.seconds_hierarchy = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let bw = opts.band * h;
    let mut state = vec![0u8; n];
    report.band_nodes = band::band_distances(bvh, &layout, bw, grid.data_mut(), &mut state);
    report.seconds_band = t.elapsed().as_secs_f64();

    let t = Instant::now();
    // On a closed surface w is an integer off the triangles, so the flood alone is exact; on an
    // open one, every node within one voxel of a triangle is evaluated too (see `sign`).
    let near = if report.closed { 0.0 } else { h };
    let counts = sign::assign_signs(
        &source,
        &layout,
        grid.data(),
        &mut state,
        opts.seed_stride,
        near,
    );
    report.seed_evaluations = counts.seeds;
    report.pocket_evaluations = counts.pockets;
    report.front_evaluations = counts.fronts;
    report.front_rounds = counts.front_rounds;
    report.refined_evaluations = counts.refined;
    report.inside_nodes = state.par_iter().filter(|&&s| s & NEG != 0).count();
    report.seconds_sign = t.elapsed().as_secs_f64();
    if report.inside_nodes == 0 {
        return Err(no_volume(dims, h));
    }

    let t = Instant::now();
    if opts.far == FarFill::Exact {
        band::far_distances(mesh, bvh, &layout, grid.data_mut());
    }
    let clamp = bw as f32;
    grid.data_mut()
        .par_iter_mut()
        .zip(state.par_iter())
        .for_each(|(phi, &s)| {
            let m = if phi.is_finite() { *phi } else { clamp };
            *phi = if s & NEG != 0 { -m } else { m };
        });
    report.seconds_far = t.elapsed().as_secs_f64();
    // Inside nodes that all sit on the surface itself (a flat sheet through grid nodes, where
    // the winding number is exactly ½) enclose nothing either.
    let whisker = (1e-3 * h) as f32;
    if !grid.data().par_iter().any(|&v| v < -whisker) {
        return Err(no_volume(dims, h));
    }
    Ok((grid, report))
}

fn no_volume(dims: [usize; 3], h: f64) -> Error {
    Error::Geometry(format!(
        "mesh encloses no volume: no node of the {}×{}×{} grid has a winding number of \
             magnitude ≥ 0.5 (an open sheet such as a disc has no inside; a vessel thinner than \
             the voxel {h} or a grid that misses the mesh has no inside node either)",
        dims[0], dims[1], dims[2]
    ))
}
