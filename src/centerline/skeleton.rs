//! The voxel skeleton of a vessel's inside: TEASAR (Sato, Bitter, Bender, Kaufman and Nakajima
//! 2000, "TEASAR: tree-structure extraction algorithm for accurate and robust skeletons") on the
//! nodes of a signed distance grid φ (negative inside), with the distance to the boundary
//! d = −φ as the DBF.
//!
//! Per connected component of the inside (26-connected nodes with φ < 0):
//! 1. The root is the open vessel end of largest radius in the component, or, without open ends,
//!    the node farthest (along the inside) from the deepest node.
//! 2. A Dijkstra from the root with plain step lengths gives the distance from the root along
//!    the inside (DAF), which picks the targets: first every open end, then repeatedly the node
//!    of largest DAF not yet covered.
//! 3. Each target's path is the cheapest to the skeleton so far with step cost |step| / d²
//!    (a Dijkstra from the target stopped at the first skeleton node, as kimimaro's TEASAR with
//!    its existing paths at no cost). That cost makes paths hug the ridge of d: on a bent tube
//!    the centre is the cheapest radius for any power ≥ 1 (the shorter inner side costs more per
//!    length than it saves).
//! 4. A path whose farthest node lies less than one vessel radius beyond the vessel's radius at
//!    its join (the largest inscribed sphere of the skeleton holding the join node) is a spur:
//!    the corner of a blunt or open end, a bump of the wall. It is not kept. Every node within
//!    `scale·d + constant` of a path node, kept or not, is covered (a flood over the inside
//!    whose budget shrinks by the step length), so no later target comes from the same tube.
//!
//! The result is a tree per component whose edges are grid steps; `graph` splits it into
//! branches and `refine` turns them into smooth sub-voxel curves.

use crate::grid::Grid3;
use nalgebra::Point3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Options of [`trace_skeleton`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkeletonOptions {
    /// Covered around each path node: within `invalidation_scale · d` of it (dimensionless
    /// multiple of the node's distance to the boundary; default 1.5, as kimimaro's TEASAR).
    pub invalidation_scale: f64,
    /// Plus this much, **in voxels** (default 2).
    pub invalidation_const_voxels: f64,
    /// A path is a spur when its farthest node lies less than this many vessel radii beyond
    /// the vessel's radius at its join (dimensionless; default 1).
    pub spur_factor: f64,
    /// Most targets tried per component (a guard; default 100,000).
    pub max_targets: usize,
}

impl Default for SkeletonOptions {
    fn default() -> Self {
        SkeletonOptions {
            invalidation_scale: 1.5,
            invalidation_const_voxels: 2.0,
            spur_factor: 1.0,
            max_targets: 100_000,
        }
    }
}

/// The skeleton of one connected component of the inside.
#[derive(Debug, Clone, PartialEq)]
pub struct ComponentSkeleton {
    /// Grid index of the root node.
    pub root: usize,
    /// Kept paths, each from its target (first) to the node where it meets the skeleton (last;
    /// the root for the first path). Grid indices.
    pub paths: Vec<Vec<usize>>,
    /// For each path, the open end it was traced to (index into the `ends` given), if any.
    pub path_ends: Vec<Option<usize>>,
    /// The open end the root is (index into `ends`), if any.
    pub root_end: Option<usize>,
    /// Largest distance to the boundary in the component, world units.
    pub max_depth: f64,
}

/// Total order on f32 costs for the heaps (NaN never enters).
#[derive(Clone, Copy, PartialEq)]
struct Cost(f32, u32);

impl Eq for Cost {}
impl PartialOrd for Cost {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Cost {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

/// The 26 neighbour offsets and their lengths in voxels.
fn offsets(dims: [usize; 3]) -> Vec<(isize, [isize; 3], f32)> {
    let (sy, sz) = (dims[0] as isize, (dims[0] * dims[1]) as isize);
    let mut out = Vec::with_capacity(26);
    for dz in -1isize..=1 {
        for dy in -1isize..=1 {
            for dx in -1isize..=1 {
                if dx == 0 && dy == 0 && dz == 0 {
                    continue;
                }
                let len = ((dx * dx + dy * dy + dz * dz) as f32).sqrt();
                out.push((dx + dy * sy + dz * sz, [dx, dy, dz], len));
            }
        }
    }
    out
}

/// The inside of φ as compact node ids, with the 26-neighbourhood among inside nodes.
struct Inside {
    dims: [usize; 3],
    /// Grid index of each inside node.
    grid: Vec<usize>,
    /// Compact id of each grid node (u32::MAX outside).
    id: Vec<u32>,
    /// Distance to the boundary (−φ), voxels.
    depth: Vec<f32>,
    offsets: Vec<(isize, [isize; 3], f32)>,
}

impl Inside {
    fn new(phi: &Grid3) -> Inside {
        let dims = phi.dims();
        let h = phi.voxel() as f32;
        let mut id = vec![u32::MAX; phi.data().len()];
        let mut grid = Vec::new();
        let mut depth = Vec::new();
        for (n, &v) in phi.data().iter().enumerate() {
            if v < 0.0 {
                id[n] = grid.len() as u32;
                grid.push(n);
                depth.push(-v / h);
            }
        }
        Inside {
            dims,
            grid,
            id,
            depth,
            offsets: offsets(dims),
        }
    }

    fn len(&self) -> usize {
        self.grid.len()
    }

    /// Grid coordinates of node `u`, voxels.
    fn position(&self, u: u32) -> [f64; 3] {
        let n = self.grid[u as usize];
        let [nx, ny, _] = self.dims;
        [
            (n % nx) as f64,
            ((n / nx) % ny) as f64,
            (n / (nx * ny)) as f64,
        ]
    }

    /// Calls `f(neighbour id, step length in voxels)` for each inside 26-neighbour of `u`.
    #[inline]
    fn for_neighbours(&self, u: u32, mut f: impl FnMut(u32, f32)) {
        let n = self.grid[u as usize];
        let [nx, ny, nz] = self.dims;
        let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
        let interior = i > 0 && j > 0 && k > 0 && i + 1 < nx && j + 1 < ny && k + 1 < nz;
        for &(off, d, len) in &self.offsets {
            if !interior {
                let (a, b, c) = (i as isize + d[0], j as isize + d[1], k as isize + d[2]);
                if a < 0
                    || b < 0
                    || c < 0
                    || a >= nx as isize
                    || b >= ny as isize
                    || c >= nz as isize
                {
                    continue;
                }
            }
            let m = (n as isize + off) as usize;
            let v = self.id[m];
            if v != u32::MAX {
                f(v, len);
            }
        }
    }

    /// Distances along the inside (voxels) from `source` over its component (f32::INFINITY
    /// elsewhere), by Dijkstra over the 26-neighbourhood.
    fn geodesic(&self, source: u32) -> Vec<f32> {
        let mut dist = vec![f32::INFINITY; self.len()];
        let mut heap = BinaryHeap::new();
        dist[source as usize] = 0.0;
        heap.push(std::cmp::Reverse(Cost(0.0, source)));
        while let Some(std::cmp::Reverse(Cost(d, u))) = heap.pop() {
            if d > dist[u as usize] {
                continue;
            }
            self.for_neighbours(u, |v, len| {
                let nd = d + len;
                if nd < dist[v as usize] {
                    dist[v as usize] = nd;
                    heap.push(std::cmp::Reverse(Cost(nd, v)));
                }
            });
        }
        dist
    }

    /// Labels the 26-connected components; returns the label of each node and the count.
    fn components(&self) -> (Vec<u32>, usize) {
        let mut label = vec![u32::MAX; self.len()];
        let mut count = 0u32;
        let mut stack = Vec::new();
        for s in 0..self.len() as u32 {
            if label[s as usize] != u32::MAX {
                continue;
            }
            label[s as usize] = count;
            stack.push(s);
            while let Some(u) = stack.pop() {
                self.for_neighbours(u, |v, _| {
                    if label[v as usize] == u32::MAX {
                        label[v as usize] = count;
                        stack.push(v);
                    }
                });
            }
            count += 1;
        }
        (label, count as usize)
    }
}

/// The TEASAR skeleton of every connected component of the inside of `phi` (φ < 0; |φ| a
/// distance, world units, at least inside). `ends` are points on the open vessel ends (world
/// units, e.g. the centroids of the end loops) with their radii: each is taken as a target in
/// the component of the inside node nearest to it (within 3 voxels; an end with none is
/// ignored). Components are in order of their first node; components of fewer than
/// `min_nodes` nodes are left out.
pub fn trace_skeleton(
    phi: &Grid3,
    ends: &[(Point3<f64>, f64)],
    min_nodes: usize,
    opts: &SkeletonOptions,
) -> Vec<ComponentSkeleton> {
    let inside = Inside::new(phi);
    if inside.len() == 0 {
        return Vec::new();
    }
    let (label, count) = inside.components();
    let h = phi.voxel();

    // Each end's nearest inside node.
    let end_nodes: Vec<Option<u32>> = ends
        .iter()
        .map(|(p, _)| nearest_inside(phi, &inside, p, 3))
        .collect();

    let mut members: Vec<Vec<u32>> = vec![Vec::new(); count];
    for (u, &l) in label.iter().enumerate() {
        members[l as usize].push(u as u32);
    }
    let mut out = Vec::new();
    for (c, nodes) in members.iter().enumerate() {
        if nodes.len() < min_nodes.max(1) {
            continue;
        }
        let comp_ends: Vec<(usize, u32)> = end_nodes
            .iter()
            .enumerate()
            .filter_map(|(e, n)| n.filter(|&u| label[u as usize] == c as u32).map(|u| (e, u)))
            .collect();
        out.push(trace_component(&inside, nodes, &comp_ends, ends, h, opts));
    }
    out
}

/// The inside node nearest to `p` within `reach` voxels, if any.
fn nearest_inside(phi: &Grid3, inside: &Inside, p: &Point3<f64>, reach: isize) -> Option<u32> {
    let x = phi.transform().world_to_index(p);
    let dims = phi.dims();
    let c = [
        x.x.round() as isize,
        x.y.round() as isize,
        x.z.round() as isize,
    ];
    let mut best: Option<(f64, u32)> = None;
    for dk in -reach..=reach {
        for dj in -reach..=reach {
            for di in -reach..=reach {
                let (i, j, k) = (c[0] + di, c[1] + dj, c[2] + dk);
                if i < 0
                    || j < 0
                    || k < 0
                    || i >= dims[0] as isize
                    || j >= dims[1] as isize
                    || k >= dims[2] as isize
                {
                    continue;
                }
                let n = phi.index(i as usize, j as usize, k as usize);
                let u = inside.id[n];
                if u == u32::MAX {
                    continue;
                }
                let d2 =
                    (i as f64 - x.x).powi(2) + (j as f64 - x.y).powi(2) + (k as f64 - x.z).powi(2);
                if best.is_none_or(|(b, _)| d2 < b) {
                    best = Some((d2, u));
                }
            }
        }
    }
    best.map(|(_, u)| u)
}

fn trace_component(
    inside: &Inside,
    nodes: &[u32],
    comp_ends: &[(usize, u32)],
    ends: &[(Point3<f64>, f64)],
    h: f64,
    opts: &SkeletonOptions,
) -> ComponentSkeleton {
    let depth = &inside.depth;
    let deepest = *nodes
        .iter()
        .max_by(|a, b| depth[**a as usize].total_cmp(&depth[**b as usize]))
        .expect("component has nodes");
    let max_depth = depth[deepest as usize] as f64 * h;

    // Root: the widest open end, or the node farthest from the deepest one.
    let (root, root_end) = match comp_ends
        .iter()
        .max_by(|a, b| ends[a.0].1.total_cmp(&ends[b.0].1))
    {
        Some(&(e, u)) => (u, Some(e)),
        None => {
            let d = inside.geodesic(deepest);
            let far = *nodes
                .iter()
                .max_by(|a, b| d[**a as usize].total_cmp(&d[**b as usize]))
                .expect("component has nodes");
            (far, None)
        }
    };
    // The distance along the inside from the root picks the targets.
    let daf = inside.geodesic(root);

    let mut order: Vec<u32> = nodes.to_vec();
    order.sort_by(|a, b| daf[*b as usize].total_cmp(&daf[*a as usize]));
    let mut budget = vec![f32::NEG_INFINITY; inside.len()];
    let mut in_skeleton = vec![false; inside.len()];
    in_skeleton[root as usize] = true;
    let mut skeleton_nodes = vec![root];
    let mut search = RidgeSearch::new(inside.len());
    let mut paths = Vec::new();
    let mut path_ends = Vec::new();
    let scale = opts.invalidation_scale as f32;
    let constant = opts.invalidation_const_voxels as f32;
    cover(inside, &[root], scale, constant, &mut budget);

    // Open ends first (farthest first), then the farthest node not yet covered.
    let mut forced: Vec<(usize, u32)> = comp_ends
        .iter()
        .copied()
        .filter(|&(e, _)| Some(e) != root_end)
        .collect();
    forced.sort_by(|a, b| daf[b.1 as usize].total_cmp(&daf[a.1 as usize]));
    let mut forced = forced.into_iter();
    let mut cursor = 0;
    for _ in 0..opts.max_targets {
        let (target, end) = if let Some((e, u)) = forced.next() {
            (u, Some(e))
        } else {
            while cursor < order.len() && budget[order[cursor] as usize] >= 0.0 {
                cursor += 1;
            }
            match order.get(cursor) {
                Some(&u) if daf[u as usize].is_finite() => (u, None),
                _ => break,
            }
        };
        if in_skeleton[target as usize] {
            continue;
        }
        let Some(path) = search.path_to_skeleton(inside, target, &in_skeleton) else {
            // Unreachable (cannot happen within a component): cover and go on.
            cover(inside, &[target], scale, constant, &mut budget);
            continue;
        };
        let join = *path.last().expect("path has its join");
        if end.is_none() && is_spur(inside, &path, join, &skeleton_nodes, opts.spur_factor) {
            cover(inside, &path, scale, constant, &mut budget);
            continue;
        }
        for &v in &path[..path.len() - 1] {
            in_skeleton[v as usize] = true;
            skeleton_nodes.push(v);
        }
        cover(inside, &path, scale, constant, &mut budget);
        paths.push(path.iter().map(|&v| inside.grid[v as usize]).collect());
        path_ends.push(end);
    }
    ComponentSkeleton {
        root: inside.grid[root as usize],
        paths,
        path_ends,
        root_end,
        max_depth,
    }
}

/// Whether a path is a spur: its farthest node lies less than `factor` vessel radii beyond that
/// radius from its join node, the vessel radius there being the largest inscribed sphere of the
/// skeleton that holds the join node (voxels throughout). A side branch reaches out of its
/// parent vessel; the corner of a blunt end or a bump of the wall does not.
fn is_spur(inside: &Inside, path: &[u32], join: u32, skeleton: &[u32], factor: f64) -> bool {
    let j = inside.position(join);
    let mut radius = inside.depth[join as usize] as f64;
    for &s in skeleton {
        let d = inside.depth[s as usize] as f64;
        if d > radius && dist(&inside.position(s), &j) <= d {
            radius = d;
        }
    }
    let reach = path
        .iter()
        .map(|&u| dist(&inside.position(u), &j))
        .fold(0.0, f64::max);
    reach - radius < factor * radius.max(1.0)
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Dijkstra from a target with step cost |step| / d², stopped at the first skeleton node: the
/// path that hugs the ridge of d to the skeleton (as kimimaro's TEASAR, whose existing paths
/// cost nothing). The arrays are kept between searches and only the touched entries reset.
struct RidgeSearch {
    dist: Vec<f32>,
    parent: Vec<u32>,
    touched: Vec<u32>,
}

impl RidgeSearch {
    fn new(n: usize) -> RidgeSearch {
        RidgeSearch {
            dist: vec![f32::INFINITY; n],
            parent: vec![u32::MAX; n],
            touched: Vec::new(),
        }
    }

    /// The path from `target` (first) to the nearest skeleton node by ridge cost (last).
    fn path_to_skeleton(
        &mut self,
        inside: &Inside,
        target: u32,
        in_skeleton: &[bool],
    ) -> Option<Vec<u32>> {
        for &u in &self.touched {
            self.dist[u as usize] = f32::INFINITY;
            self.parent[u as usize] = u32::MAX;
        }
        self.touched.clear();
        let mut heap = BinaryHeap::new();
        self.dist[target as usize] = 0.0;
        self.touched.push(target);
        heap.push(std::cmp::Reverse(Cost(0.0, target)));
        let mut found = None;
        while let Some(std::cmp::Reverse(Cost(d, u))) = heap.pop() {
            if d > self.dist[u as usize] {
                continue;
            }
            if in_skeleton[u as usize] {
                found = Some(u);
                break;
            }
            inside.for_neighbours(u, |v, len| {
                let dv = inside.depth[v as usize].max(0.05);
                let nd = d + len / (dv * dv);
                if nd < self.dist[v as usize] {
                    if self.dist[v as usize] == f32::INFINITY {
                        self.touched.push(v);
                    }
                    self.dist[v as usize] = nd;
                    self.parent[v as usize] = u;
                    heap.push(std::cmp::Reverse(Cost(nd, v)));
                }
            });
        }
        let mut u = found?;
        let mut path = vec![u];
        while u != target {
            u = self.parent[u as usize];
            path.push(u);
        }
        path.reverse();
        Some(path)
    }
}

/// Marks every node within `scale·d(p) + constant` voxels (along the inside) of a path node p
/// as covered: `budget` ≥ 0 there. A flood from all path nodes at once, keeping at each node the
/// largest budget left.
fn cover(inside: &Inside, path: &[u32], scale: f32, constant: f32, budget: &mut [f32]) {
    let mut heap = BinaryHeap::new();
    for &u in path {
        let b = scale * inside.depth[u as usize] + constant;
        if b > budget[u as usize] {
            budget[u as usize] = b;
            heap.push(Cost(b, u));
        }
    }
    while let Some(Cost(b, u)) = heap.pop() {
        if b < budget[u as usize] {
            continue;
        }
        inside.for_neighbours(u, |v, len| {
            let nb = b - len;
            if nb >= 0.0 && nb > budget[v as usize] {
                budget[v as usize] = nb;
                heap.push(Cost(nb, v));
            }
        });
    }
}
