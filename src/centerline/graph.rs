//! The branches of a voxel skeleton: its tree (`skeleton`) split at the nodes where three or more
//! paths meet (junctions) and at its tips (endpoints), with short terminal branches pruned.
//!
//! A terminal branch that reaches less than one vessel radius beyond the vessel around its
//! junction is a spur (the rule the tracing applies to each new path; here it also reaches the
//! root's own branch). Pruning repeats until no spur is left; a junction left with two branches joins
//! them into one.

use super::skeleton::ComponentSkeleton;
use crate::grid::Grid3;
use std::collections::{BTreeMap, BTreeSet};

/// What a branch's end is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EndKind {
    /// An open vessel end of the mesh (a boundary loop cut across the vessel).
    OpenEnd,
    /// A closed end of the vessel (a tip of the skeleton).
    End,
    /// A junction with other branches.
    Junction,
}

/// A branch as grid nodes, from one end to the other.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelBranch {
    /// Grid indices in order along the branch (at least 2).
    pub nodes: Vec<usize>,
    /// Kind of the first and last node.
    pub ends: [EndKind; 2],
    /// The open end (index into the ends given to the tracing) at the first and last node.
    pub open_ends: [Option<usize>; 2],
}

/// Splits a component's skeleton into branches and prunes its spurs (see the module docs).
/// `spur_factor` as in [`super::skeleton::SkeletonOptions::spur_factor`].
pub fn split_branches(phi: &Grid3, skel: &ComponentSkeleton, spur_factor: f64) -> Vec<VoxelBranch> {
    let mut adj: BTreeMap<usize, BTreeSet<usize>> = BTreeMap::new();
    adj.entry(skel.root).or_default();
    let mut open: BTreeMap<usize, usize> = BTreeMap::new();
    if let Some(e) = skel.root_end {
        open.insert(skel.root, e);
    }
    for (path, end) in skel.paths.iter().zip(&skel.path_ends) {
        for w in path.windows(2) {
            adj.entry(w[0]).or_default().insert(w[1]);
            adj.entry(w[1]).or_default().insert(w[0]);
        }
        if let (Some(e), Some(&first)) = (end, path.first()) {
            open.insert(first, *e);
        }
    }
    loop {
        let branches = walk(&adj, &open);
        let depth = |n: usize| -phi.data()[n] as f64;
        let world = |n: usize| {
            let [i, j, k] = phi.coords(n);
            phi.world(i, j, k)
        };
        // Terminal branches that are spurs (never an open end, never the only branch): their
        // farthest node within one vessel radius beyond that radius from the junction, the
        // radius being the largest inscribed sphere of the other branches holding the junction.
        let spurs: Vec<&VoxelBranch> = branches
            .iter()
            .enumerate()
            .filter(|_| branches.len() > 1)
            .filter(|(bi, b)| {
                let join = match b.ends {
                    [EndKind::End, EndKind::Junction] => b.nodes[b.nodes.len() - 1],
                    [EndKind::Junction, EndKind::End] => b.nodes[0],
                    _ => return false,
                };
                let j = world(join);
                let mut radius = depth(join);
                for (oi, o) in branches.iter().enumerate() {
                    if oi == *bi {
                        continue;
                    }
                    for &n in &o.nodes {
                        let d = depth(n);
                        if d > radius && (world(n) - j).norm() <= d {
                            radius = d;
                        }
                    }
                }
                let reach = b
                    .nodes
                    .iter()
                    .map(|&n| (world(n) - j).norm())
                    .fold(0.0, f64::max);
                reach - radius < spur_factor * radius.max(phi.voxel())
            })
            .map(|(_, b)| b)
            .collect();
        if spurs.is_empty() {
            return branches;
        }
        for b in spurs {
            // Remove every node of the spur but its junction.
            let inner: Vec<usize> = if b.ends[0] == EndKind::Junction {
                b.nodes[1..].to_vec()
            } else {
                b.nodes[..b.nodes.len() - 1].to_vec()
            };
            for n in inner {
                if let Some(nb) = adj.remove(&n) {
                    for m in nb {
                        if let Some(s) = adj.get_mut(&m) {
                            s.remove(&n);
                        }
                    }
                }
            }
        }
    }
}

/// The maximal chains of degree-2 nodes between nodes of other degrees (and each cycle, which a
/// tree does not have, is ignored).
fn walk(adj: &BTreeMap<usize, BTreeSet<usize>>, open: &BTreeMap<usize, usize>) -> Vec<VoxelBranch> {
    let kind = |n: usize| -> EndKind {
        let deg = adj.get(&n).map_or(0, |s| s.len());
        if deg >= 3 {
            EndKind::Junction
        } else if open.contains_key(&n) {
            EndKind::OpenEnd
        } else {
            EndKind::End
        }
    };
    let is_stop = |n: usize| adj.get(&n).map_or(0, |s| s.len()) != 2 || open.contains_key(&n);
    let mut seen: BTreeSet<(usize, usize)> = BTreeSet::new();
    let mut out = Vec::new();
    for (&start, nbs) in adj {
        if !is_stop(start) {
            continue;
        }
        for &next in nbs {
            if seen.contains(&(start, next)) {
                continue;
            }
            let mut nodes = vec![start, next];
            let (mut prev, mut cur) = (start, next);
            while !is_stop(cur) {
                let nxt = *adj[&cur]
                    .iter()
                    .find(|&&m| m != prev)
                    .expect("degree-2 node has another neighbour");
                nodes.push(nxt);
                prev = cur;
                cur = nxt;
            }
            seen.insert((start, next));
            seen.insert((cur, prev));
            let (a, b) = (start, cur);
            out.push(VoxelBranch {
                ends: [kind(a), kind(b)],
                open_ends: [open.get(&a).copied(), open.get(&b).copied()],
                nodes,
            });
        }
    }
    out
}
