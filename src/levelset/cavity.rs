//! Joining enclosed cavities of a level set to the outside.
//!
//! Where a fold of the input is narrower than the voxel (a sulcus of the cortex, two vessels
//! pressed together), the grid nodes at its mouth all fall inside and the outside part of the
//! fold deeper in becomes an enclosed bubble: marching cubes then returns the bubble as an extra,
//! inward-facing component, a cavity the input does not have. This step reopens the fold: from
//! the outside nodes of the bubble it finds the cheapest 6-connected path of grid nodes to the
//! outside region (Dijkstra; a node costs its depth −φ/h plus 0.1, so the path goes through the
//! thinnest wall, which is the fold's mouth) and raises the inside nodes on that path to
//! `open_value` voxels outside. The bubble and the outside are then one 6-connected region, so
//! the extracted surface becomes a pocket of the outer component instead of a separate shell
//! (one component, genus unchanged). The move is local: only the nodes of one path per cavity
//! change. It is for inputs without cavities of their own: the caller decides (`remesh` joins
//! the cavities only when the input has none).

use super::marching_cubes::{extract_surface, ExtractOptions};
use crate::grid::{face_neighbours, Grid3};
use crate::mesh::measures::component_nesting_depths;
use crate::mesh::topology::connected_components;
use crate::{Result, TriMesh};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

/// Options of [`join_cavities`].
#[derive(Debug, Clone, Copy)]
pub struct CavityOptions {
    /// Value given to the inside nodes of a joining path, in voxels (positive: outside).
    pub open_value: f32,
}

impl Default for CavityOptions {
    fn default() -> Self {
        CavityOptions { open_value: 0.5 }
    }
}

/// The components of a closed extracted `surface` that are cavities (odd nesting depth: the
/// surface around an enclosed outside region), as lists of their vertex indices.
pub fn find_cavities(surface: &TriMesh) -> Vec<Vec<u32>> {
    let (n, labels) = connected_components(surface);
    if n <= 1 {
        return Vec::new();
    }
    let depths = component_nesting_depths(surface, n, &labels);
    let mut vertices: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (f, &l) in labels.iter().enumerate() {
        if depths[l as usize] % 2 == 1 {
            vertices[l as usize].extend_from_slice(&surface.faces[f]);
        }
    }
    vertices
        .into_iter()
        .filter(|v| !v.is_empty())
        .map(|mut v| {
            v.sort_unstable();
            v.dedup();
            v
        })
        .collect()
}

const UNSEEN: u8 = 0;
const OUTSIDE: u8 = 1;
const BUBBLE: u8 = 2;

/// Joins the enclosed outside regions of `phi` next to the given `cavities` (vertex lists of
/// [`find_cavities`] on `surface`, extracted from `phi`) to the outside region, changing the
/// nodes of one path per cavity (see the module doc). Returns the number of cavities joined;
/// extract the surface again afterwards.
pub fn join_cavities(
    phi: &mut Grid3,
    surface: &TriMesh,
    cavities: &[Vec<u32>],
    opts: &CavityOptions,
) -> usize {
    if cavities.is_empty() {
        return 0;
    }
    let dims = phi.dims();
    let h = phi.voxel() as f32;
    let mut label = vec![UNSEEN; phi.data().len()];
    // The outside region: outside nodes 6-connected to the grid's border.
    let border: Vec<usize> = (0..label.len())
        .filter(|&n| {
            let [i, j, k] = phi.coords(n);
            phi.data()[n] > 0.0
                && (i == 0
                    || j == 0
                    || k == 0
                    || i + 1 == dims[0]
                    || j + 1 == dims[1]
                    || k + 1 == dims[2])
        })
        .collect();
    flood_outside(phi, &mut label, border, OUTSIDE);
    let mut joined = 0;
    for cavity in cavities {
        // The bubble: outside nodes at the corners of the cells holding the cavity's vertices.
        let seeds: Vec<usize> = cavity
            .iter()
            .flat_map(|&v| cell_corners(phi, &surface.vertices[v as usize]))
            .filter(|&n| label[n] == UNSEEN && phi.data()[n] > 0.0)
            .collect();
        let bubble = flood_outside(phi, &mut label, seeds, BUBBLE);
        if bubble.is_empty() {
            continue;
        }
        let path = cheapest_path_out(phi, &label, &bubble);
        for &n in bubble.iter().chain(&path) {
            label[n] = OUTSIDE;
        }
        for n in path {
            let v = &mut phi.data_mut()[n];
            if *v <= 0.0 {
                *v = opts.open_value * h;
            }
        }
        joined += 1;
    }
    joined
}

/// Labels with `mark` the outside nodes (φ > 0) 6-connected to `seeds` that are still unseen;
/// returns them.
fn flood_outside(phi: &Grid3, label: &mut [u8], seeds: Vec<usize>, mark: u8) -> Vec<usize> {
    let mut region = Vec::new();
    let mut stack = Vec::new();
    for s in seeds {
        if label[s] == UNSEEN && phi.data()[s] > 0.0 {
            label[s] = mark;
            stack.push(s);
        }
    }
    while let Some(n) = stack.pop() {
        region.push(n);
        for m in face_neighbours(phi.dims(), n) {
            if label[m] == UNSEEN && phi.data()[m] > 0.0 {
                label[m] = mark;
                stack.push(m);
            }
        }
    }
    region
}

/// The cheapest 6-connected path of nodes from `start` (cost 0) to the first node labelled
/// outside; returns its nodes, both ends excluded. Empty when there is none.
fn cheapest_path_out(phi: &Grid3, label: &[u8], start: &[usize]) -> Vec<usize> {
    let h = phi.voxel() as f32;
    let cost = |n: usize| (-phi.data()[n] / h).max(0.0) + 0.1;
    let mut best: HashMap<usize, (f32, usize)> = HashMap::new();
    let mut heap = BinaryHeap::new();
    for &s in start {
        best.insert(s, (0.0, usize::MAX));
        heap.push(Reverse((0.0f32.to_bits(), s)));
    }
    while let Some(Reverse((bits, n))) = heap.pop() {
        let d = f32::from_bits(bits);
        if best.get(&n).is_some_and(|&(b, _)| b < d) {
            continue;
        }
        if label[n] == OUTSIDE {
            let mut path = Vec::new();
            let mut m = best[&n].1;
            while m != usize::MAX && best[&m].1 != usize::MAX {
                path.push(m);
                m = best[&m].1;
            }
            return path;
        }
        for m in face_neighbours(phi.dims(), n) {
            // Non-negative f32 costs order like their bit patterns.
            let dm = d + cost(m);
            if best.get(&m).is_none_or(|&(b, _)| dm < b) {
                best.insert(m, (dm, n));
                heap.push(Reverse((dm.to_bits(), m)));
            }
        }
    }
    Vec::new()
}

/// The grid nodes at the corners of the cell holding `p`.
fn cell_corners(phi: &Grid3, p: &nalgebra::Point3<f64>) -> Vec<usize> {
    let q = phi.transform().world_to_index(p);
    let dims = phi.dims();
    let base: [usize; 3] =
        std::array::from_fn(|a| (q[a].floor().max(0.0) as usize).min(dims[a].saturating_sub(2)));
    let mut out = Vec::with_capacity(8);
    for c in 0..8 {
        let [i, j, k] = [
            base[0] + (c & 1),
            base[1] + ((c >> 1) & 1),
            base[2] + ((c >> 2) & 1),
        ];
        out.push(phi.index(i, j, k));
    }
    out
}

/// Marching cubes of `phi` with its cavities joined to the outside (a few rounds of
/// [`find_cavities`] → [`join_cavities`] → extract, until none is left). Returns the surface and
/// the number of cavities joined; `phi` keeps the joining paths.
pub fn extract_joining_cavities(
    phi: &mut Grid3,
    extract: &ExtractOptions,
    opts: &CavityOptions,
) -> Result<(TriMesh, usize)> {
    let mut surface = extract_surface(phi, extract)?;
    let mut joined = 0;
    for _ in 0..3 {
        let cavities = find_cavities(&surface);
        let n = join_cavities(phi, &surface, &cavities, opts);
        if n == 0 {
            break;
        }
        joined += n;
        surface = extract_surface(phi, extract)?;
    }
    Ok((surface, joined))
}
