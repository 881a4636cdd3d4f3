//! The centreline pipeline from a mesh: holes capped, the signed distance grid, the TEASAR
//! skeleton with the open vessel ends as endpoints, branches, and their refined curves.

use super::graph::{split_branches, EndKind};
use super::refine::{refine_branch, RefineOptions};
use super::skeleton::{trace_skeleton, SkeletonOptions};
use super::{Branch, Centerline, Endpoint, Junction};
use crate::bvh::MeshBvh;
use crate::grid::spec::default_voxel;
use crate::grid::{grid_for_mesh, GridOptions};
use crate::inpaint::holes::{classify_loops, LoopKind, LoopOptions};
use crate::levelset::chamfer::chamfer_inside;
use crate::levelset::voxelize::{voxelize, VoxelizeOptions};
use crate::mesh::cap::{cap_holes, cap_loops_with_fans, CapOptions};
use crate::mesh::measures::{
    area, area_centroid, bounding_box, mean_edge_length, signed_volume_about,
};
use crate::{Error, Result, TriMesh};
use nalgebra::Point3;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::time::Instant;

/// Options of [`compute_centerline`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CenterlineOptions {
    /// The grid (voxel in world units; default: the project's rule on the mesh, coarsened to a
    /// tenth of the typical vessel radius and so that the inside holds at most about 1.5 million
    /// nodes).
    pub grid: GridOptions,
    pub skeleton: SkeletonOptions,
    pub refine: RefineOptions,
}

/// Seconds spent in each step.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct CenterlineTimings {
    pub distance: f64,
    pub skeleton: f64,
    pub refine: f64,
}

/// Components of fewer inside nodes than this are left out (a speck is no vessel).
const MIN_COMPONENT_NODES: usize = 8;

/// The default voxel is coarsened until the inside holds about this many nodes at most: the
/// skeleton's searches cost in proportion (a vessel tree at the default voxel has 0.1–0.7
/// million; a blob such as a 10 mm sphere at 256 cells across has 9 million).
const MAX_INSIDE_NODES: f64 = 1.5e6;

/// Voxels across the typical vessel radius the centreline's grid needs at least (the skeleton
/// only has to find the lumen's ridge and topology; the curve is then centred on the mesh's own
/// sections and its radii are exact distances to the mesh).
const VOXELS_PER_RADIUS: f64 = 10.0;

/// The grid options of the centreline: the project's default voxel, coarsened to a tenth of the
/// typical vessel radius (2 × volume / area, exact for a long tube) and so that the enclosed
/// volume holds at most [`MAX_INSIDE_NODES`] nodes; a voxel or resolution the caller gave is
/// kept. Volumes are taken about the area centroid, so that open ends far from the origin do
/// not weigh.
fn centerline_grid(mesh: &TriMesh, grid: &GridOptions) -> GridOptions {
    if grid.voxel.is_some() || grid.resolution.is_some() {
        return *grid;
    }
    let (lo, hi) = bounding_box(mesh);
    let longest = (hi - lo).max();
    let voxel = default_voxel(mean_edge_length(mesh), longest);
    let volume = signed_volume_about(mesh, &area_centroid(mesh)).abs();
    let typical_radius = 2.0 * volume / area(mesh);
    let coarse = (volume / MAX_INSIDE_NODES)
        .cbrt()
        .max(typical_radius / VOXELS_PER_RADIUS);
    GridOptions {
        voxel: Some(voxel.max(coarse)).filter(|v| v.is_finite() && *v > 0.0 && *v <= longest),
        ..*grid
    }
}

/// The centreline graph of `mesh` (see the module docs of `centerline`).
///
/// Holes in the wall (boundary loops that are not open vessel ends, `inpaint::holes`) are capped
/// first, with a notice; open ends stay open, the winding number closes them, and each is an
/// endpoint at its loop's centre. A component whose longest branch is shorter than three times
/// its largest inscribed radius (a blob, not a tube) gets a notice.
///
/// Errors: a mesh without triangles or that encloses no volume ("no inside"), a grid over the
/// memory limit (naming `--voxel`/`--max-memory`), and a cap that fails.
pub fn compute_centerline(
    mesh: &TriMesh,
    opts: &CenterlineOptions,
) -> Result<(Centerline, CenterlineTimings)> {
    if mesh.faces.is_empty() {
        return Err(Error::InvalidMesh("the mesh has no triangle".into()));
    }
    let mut notices = Vec::new();
    let t = Instant::now();
    let loops = classify_loops(mesh, &LoopOptions::default());
    let holes = loops.iter().filter(|l| l.kind == LoopKind::Hole).count();
    let capped;
    let mesh = if holes > 0 {
        // The ends by fans (as below), the holes by the cap that follows the wall.
        let ends: Vec<Vec<u32>> = loops
            .iter()
            .filter(|l| l.kind == LoopKind::End)
            .map(|l| l.vertices.clone())
            .collect();
        let (m, _) = cap_holes(&cap_loops_with_fans(mesh, &ends), &CapOptions::default())?;
        notices.push(format!(
            "{holes} hole(s) in the wall capped before the centreline was traced"
        ));
        capped = m;
        &capped
    } else {
        mesh
    };
    let bvh = MeshBvh::new(mesh);
    let ends: Vec<(Point3<f64>, f64)> = loops
        .iter()
        .filter(|l| l.kind == LoopKind::End)
        .map(|l| (l.center, l.radius))
        .collect();

    // The grid's signs come from a closed surface: open ends closed by centroid fans (ray
    // crossings are exact and several times cheaper than the winding number of an open mesh;
    // the fans are planar enough where the winding number's own closure would be). The curve is
    // refined on the mesh itself.
    // With holes, `mesh` is already the capped input: every loop, ends included, is closed.
    let end_loops: Vec<Vec<u32>> = if holes > 0 {
        Vec::new()
    } else {
        loops
            .iter()
            .filter(|l| l.kind == LoopKind::End)
            .map(|l| l.vertices.clone())
            .collect()
    };
    let fanned;
    let closed = if end_loops.is_empty() {
        mesh
    } else {
        fanned = cap_loops_with_fans(mesh, &end_loops);
        &fanned
    };
    // The closed surface also gives the true enclosed volume, hence the typical radius.
    let spec = grid_for_mesh(closed, &centerline_grid(closed, &opts.grid))?;
    let vox = VoxelizeOptions::default();
    let mut phi = voxelize(closed, spec.dims, spec.transform, &vox).map_err(|e| match e {
        Error::Geometry(m) if m.contains("encloses no volume") => {
            Error::Geometry("the mesh has no inside (it encloses no volume): no centreline".into())
        }
        e => e,
    })?;
    // Exact within the band; the chamfer distance deeper inside orders the ridge.
    let clamp = 0.999 * vox.band * phi.voxel();
    chamfer_inside(&mut phi, clamp);
    let distance_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let skeletons = trace_skeleton(&phi, &ends, MIN_COMPONENT_NODES, &opts.skeleton);
    if skeletons.is_empty() {
        return Err(Error::Geometry(
            "the mesh has no inside at this voxel size: no centreline".into(),
        ));
    }
    let skeleton_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let h = phi.voxel();
    let world = |n: usize| {
        let [i, j, k] = phi.coords(n);
        phi.world(i, j, k)
    };
    let mut branches = Vec::new();
    let mut junctions: Vec<Junction> = Vec::new();
    let mut endpoints = Vec::new();
    for (c, skel) in skeletons.iter().enumerate() {
        let voxel_branches = split_branches(&phi, skel, opts.skeleton.spur_factor);
        let curves: Vec<_> = voxel_branches
            .par_iter()
            .map(|b| {
                let pts: Vec<Point3<f64>> = b.nodes.iter().map(|&n| world(n)).collect();
                let open = b.open_ends.map(|e| e.map(|e| ends[e].0));
                refine_branch(&phi, mesh, &bvh, &pts, b.ends, open, &opts.refine)
            })
            .collect();
        let mut junction_of: BTreeMap<usize, usize> = BTreeMap::new();
        let mut longest: f64 = 0.0;
        for (b, curve) in voxel_branches.iter().zip(curves) {
            let id = branches.len();
            let length: f64 = curve.points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
            longest = longest.max(length);
            for (side, node) in [(0, b.nodes[0]), (1, *b.nodes.last().expect("branch nodes"))] {
                let (p, r) = if side == 0 {
                    (curve.points[0], curve.radius[0])
                } else {
                    (*curve.points.last().unwrap(), *curve.radius.last().unwrap())
                };
                // An open end's radius is its loop's (the curve's ends there sit on the fan
                // that closes the loop, whose centre is on the surface).
                let r = b.open_ends[side].map_or(r, |e| ends[e].1);
                match b.ends[side] {
                    EndKind::Junction => {
                        let j = *junction_of.entry(node).or_insert_with(|| {
                            let pos = world(node);
                            junctions.push(Junction {
                                id: junctions.len(),
                                component: c,
                                position: pos,
                                radius: bvh.closest_point(&pos).distance,
                                branches: Vec::new(),
                            });
                            junctions.len() - 1
                        });
                        junctions[j].branches.push(id);
                    }
                    kind => endpoints.push(Endpoint {
                        position: p,
                        radius: r,
                        branch: id,
                        open_end: kind == EndKind::OpenEnd,
                    }),
                }
            }
            branches.push(Branch {
                id,
                component: c,
                length,
                points: curve.points,
                radius: curve.radius,
                tangent: curve.tangent,
                start: b.ends[0],
                end: b.ends[1],
            });
        }
        if longest < 3.0 * skel.max_depth {
            notices.push(format!(
                "component {c} is not tube-like (longest branch {} against an inscribed radius of {}): its centreline is a short stub",
                short(longest),
                short(skel.max_depth)
            ));
        }
    }
    let refine_s = t.elapsed().as_secs_f64();
    let centerline = Centerline {
        voxel: h,
        components: skeletons.len(),
        branches,
        junctions,
        endpoints,
        notices,
    };
    Ok((
        centerline,
        CenterlineTimings {
            distance: distance_s,
            skeleton: skeleton_s,
            refine: refine_s,
        },
    ))
}

/// A length with four significant digits, for notices.
fn short(x: f64) -> String {
    format!("{x:.4}")
}
