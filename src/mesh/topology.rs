//! Combinatorial topology of a triangle mesh: edges and their incident faces, connected components,
//! boundary loops, non-manifold edges and vertices, and orientation consistency.
//!
//! Everything edge-based goes through [`EdgeMap`], built once by sorting the 3·F half-edges by
//! their undirected key (a compressed-sparse-row table, cheaper than hashing for meshes of tens of
//! thousands of faces), so that `info` can answer all its questions from one map. The queries
//! follow the usual definitions of combinatorial surface topology (as in e.g. Botsch et al.,
//! *Polygon Mesh Processing*, ch. 2): a boundary edge has one incident face, a non-manifold edge more
//! than two, and a vertex is manifold when its incident faces form a single edge-connected fan.
//!
//! Preconditions: face indices are below `mesh.num_vertices()` (the readers check this). Faces with a
//! repeated index contribute no self-edge (u, u); their other edges are kept.

use super::TriMesh;
use serde::Serialize;
use std::fmt;

/// One face's use of an undirected edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeUse {
    /// The face.
    pub face: u32,
    /// The corner k of the face where the edge starts: the edge is `faces[face][k] → faces[face][(k+1)%3]`.
    pub slot: u8,
    /// Whether the face traverses the edge from its lower to its higher vertex index.
    pub forward: bool,
}

/// The undirected edges of a mesh with, per edge, the faces that use it and in which direction.
///
/// Edges are sorted by (lower index, higher index); edge ids are positions in that order.
#[derive(Debug, Clone)]
pub struct EdgeMap<'m> {
    mesh: &'m TriMesh,
    edges: Vec<[u32; 2]>,
    /// `uses[offsets[e]..offsets[e + 1]]` are the uses of edge e.
    offsets: Vec<u32>,
    uses: Vec<EdgeUse>,
    /// Per face and corner k, the id of edge `f[k] → f[k+1]`, or `u32::MAX` for a self-edge.
    face_edges: Vec<[u32; 3]>,
}

impl<'m> EdgeMap<'m> {
    /// Builds the map in O(F log F).
    pub fn new(mesh: &'m TriMesh) -> Self {
        let nf = mesh.faces.len();
        let mut keyed: Vec<(u64, u32)> = Vec::with_capacity(3 * nf);
        for (f, face) in mesh.faces.iter().enumerate() {
            for k in 0..3 {
                let (u, v) = (face[k], face[(k + 1) % 3]);
                if u != v {
                    let key = ((u.min(v) as u64) << 32) | u.max(v) as u64;
                    keyed.push((key, (3 * f + k) as u32));
                }
            }
        }
        keyed.sort_unstable();
        let mut edges = Vec::with_capacity(keyed.len() / 2 + 1);
        let mut offsets = Vec::with_capacity(keyed.len() / 2 + 2);
        let mut uses = Vec::with_capacity(keyed.len());
        let mut face_edges = vec![[u32::MAX; 3]; nf];
        let mut prev = u64::MAX;
        for &(key, h) in &keyed {
            if key != prev {
                offsets.push(uses.len() as u32);
                edges.push([(key >> 32) as u32, key as u32]);
                prev = key;
            }
            let (f, k) = (h / 3, (h % 3) as usize);
            let e = (edges.len() - 1) as u32;
            face_edges[f as usize][k] = e;
            let u = mesh.faces[f as usize][k];
            uses.push(EdgeUse {
                face: f,
                slot: k as u8,
                forward: u == (key >> 32) as u32,
            });
        }
        offsets.push(uses.len() as u32);
        EdgeMap {
            mesh,
            edges,
            offsets,
            uses,
            face_edges,
        }
    }

    /// The mesh this map was built from.
    pub fn mesh(&self) -> &'m TriMesh {
        self.mesh
    }

    /// Number of unique undirected edges.
    pub fn num_edges(&self) -> usize {
        self.edges.len()
    }

    /// All undirected edges as (lower, higher) vertex index pairs, sorted.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// The faces using edge `e`, with their directions.
    pub fn uses(&self, e: usize) -> &[EdgeUse] {
        &self.uses[self.offsets[e] as usize..self.offsets[e + 1] as usize]
    }

    /// Number of faces using edge `e`.
    pub fn valence(&self, e: usize) -> usize {
        (self.offsets[e + 1] - self.offsets[e]) as usize
    }

    /// The id of the edge `f[k] → f[(k+1)%3]` of face `f`, or `None` when both ends are the same vertex.
    pub fn face_edge(&self, f: usize, k: usize) -> Option<usize> {
        let e = self.face_edges[f][k];
        (e != u32::MAX).then_some(e as usize)
    }

    /// The edge counts and winding check in one pass.
    pub(crate) fn summary(&self) -> EdgeSummary {
        let mut s = EdgeSummary {
            boundary_edges: 0,
            non_manifold_edges: 0,
            consistent: true,
        };
        for e in 0..self.num_edges() {
            let u = self.uses(e);
            match u.len() {
                1 => s.boundary_edges += 1,
                2 => s.consistent &= u[0].forward != u[1].forward,
                _ => s.non_manifold_edges += 1,
            }
        }
        s
    }

    /// Number of boundary edges (used by exactly one face).
    pub fn boundary_edges(&self) -> usize {
        self.summary().boundary_edges
    }

    /// Number of non-manifold edges (used by more than two faces).
    pub fn non_manifold_edges(&self) -> usize {
        self.summary().non_manifold_edges
    }

    /// Whether every edge used by exactly two faces is traversed in opposite directions by them.
    /// Boundary and non-manifold edges are not judged.
    pub fn is_consistently_oriented(&self) -> bool {
        self.summary().consistent
    }

    /// The non-manifold vertices, sorted: vertices whose incident faces split into two or more fans,
    /// a fan being a set of faces connected through edges incident to the vertex (e.g. the tip
    /// shared by two cones, or the point where two boundary loops touch).
    ///
    /// Faces are connected through *every* shared edge, including non-manifold ones, so the end
    /// points of a non-manifold edge are not counted for that reason alone: this count and
    /// [`EdgeMap::non_manifold_edges`] report different defects. Unreferenced vertices are not
    /// counted.
    pub fn non_manifold_vertex_ids(&self) -> Vec<u32> {
        let faces = &self.mesh.faces;
        // Union-find over corners (3f + k); corners of one vertex joined across shared edges.
        let mut parent: Vec<u32> = (0..3 * faces.len() as u32).collect();
        for e in 0..self.num_edges() {
            let u = self.uses(e);
            let corners = |x: &EdgeUse| {
                let (a, b) = (x.slot as u32, (x.slot as u32 + 1) % 3);
                let (lo, hi) = if x.forward { (a, b) } else { (b, a) };
                (3 * x.face + lo, 3 * x.face + hi)
            };
            let (lo0, hi0) = corners(&u[0]);
            for x in &u[1..] {
                let (lo, hi) = corners(x);
                union(&mut parent, lo0, lo);
                union(&mut parent, hi0, hi);
            }
        }
        // Repeated corners of one degenerate face belong together.
        for (f, face) in faces.iter().enumerate() {
            let c = 3 * f as u32;
            for (i, j) in [(0, 1), (1, 2), (0, 2)] {
                if face[i] == face[j] {
                    union(&mut parent, c + i as u32, c + j as u32);
                }
            }
        }
        let mut root_of = vec![u32::MAX; self.mesh.num_vertices()];
        let mut bad = vec![false; self.mesh.num_vertices()];
        for (f, face) in faces.iter().enumerate() {
            for (k, &v) in face.iter().enumerate() {
                let r = find(&mut parent, (3 * f + k) as u32);
                let slot = &mut root_of[v as usize];
                if *slot == u32::MAX {
                    *slot = r;
                } else if *slot != r {
                    bad[v as usize] = true;
                }
            }
        }
        (0..bad.len() as u32).filter(|&v| bad[v as usize]).collect()
    }

    /// Number of non-manifold vertices (see [`EdgeMap::non_manifold_vertex_ids`]).
    pub fn non_manifold_vertices(&self) -> usize {
        self.non_manifold_vertex_ids().len()
    }

    /// The boundary loops; see [`boundary_loops`].
    pub fn boundary_loops(&self) -> Vec<Vec<u32>> {
        // Boundary half-edges in the direction their face traverses them.
        let mut half: Vec<[u32; 2]> = Vec::new();
        for e in 0..self.num_edges() {
            let u = self.uses(e);
            if u.len() == 1 {
                let [lo, hi] = self.edges[e];
                half.push(if u[0].forward { [lo, hi] } else { [hi, lo] });
            }
        }
        if half.is_empty() {
            return Vec::new();
        }
        // Incidence lists (CSR) of boundary edges per vertex.
        let nv = self.mesh.num_vertices();
        let mut start = vec![0u32; nv + 1];
        for h in &half {
            start[h[0] as usize + 1] += 1;
            start[h[1] as usize + 1] += 1;
        }
        for i in 0..nv {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut inc = vec![0u32; 2 * half.len()];
        for (i, h) in half.iter().enumerate() {
            for &v in h {
                inc[fill[v as usize] as usize] = i as u32;
                fill[v as usize] += 1;
            }
        }
        let mut used = vec![false; half.len()];
        let mut pos_in_path = vec![u32::MAX; nv];
        let mut loops = Vec::new();
        // Next unused edge at `v`: prefer one leaving `v` in its own direction; otherwise (only on
        // inconsistently wound meshes) walk an edge backwards.
        let next_edge = |used: &[bool], v: u32| -> Option<(usize, u32, bool)> {
            let list = &inc[start[v as usize] as usize..start[v as usize + 1] as usize];
            let mut back = None;
            for &i in list {
                let i = i as usize;
                if used[i] {
                    continue;
                }
                if half[i][0] == v {
                    return Some((i, half[i][1], true));
                }
                back.get_or_insert((i, half[i][0], false));
            }
            back
        };
        for seed in 0..half.len() {
            if used[seed] {
                continue;
            }
            let s = half[seed][0];
            // Walk from s, cutting off a simple loop whenever the path returns to a vertex on it.
            let mut path: Vec<u32> = vec![s];
            let mut along: Vec<bool> = Vec::new(); // per path edge: walked in its own direction?
            pos_in_path[s as usize] = 0;
            while let Some((i, w, fwd)) = next_edge(&used, *path.last().unwrap()) {
                used[i] = true;
                along.push(fwd);
                let p = pos_in_path[w as usize];
                if p == u32::MAX {
                    pos_in_path[w as usize] = path.len() as u32;
                    path.push(w);
                    continue;
                }
                let p = p as usize;
                let mut lp: Vec<u32> = path.drain(p + 1..).collect();
                lp.insert(0, path[p]);
                let dirs: Vec<bool> = along.drain(p..).collect();
                for &v in &lp[1..] {
                    pos_in_path[v as usize] = u32::MAX;
                }
                let agree = dirs.iter().filter(|&&d| d).count();
                if 2 * agree < dirs.len() {
                    lp[1..].reverse(); // mostly walked backwards: report it the way faces run
                }
                loops.push(lp);
            }
            for &v in &path {
                pos_in_path[v as usize] = u32::MAX;
            }
            if path.len() > 1 {
                // An open chain (only on meshes whose boundary does not close up); keep it.
                loops.push(path);
            }
        }
        loops
    }
}

/// What one pass over the edges tells: see [`EdgeMap::boundary_edges`],
/// [`EdgeMap::non_manifold_edges`] and [`EdgeMap::is_consistently_oriented`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct EdgeSummary {
    pub boundary_edges: usize,
    pub non_manifold_edges: usize,
    pub consistent: bool,
}

/// Union–find root of `x` in `parent` (a forest over 0..n, roots their own parent), halving
/// the path on the way.
pub(crate) fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let g = parent[parent[x as usize] as usize];
        parent[x as usize] = g;
        x = g;
    }
    x
}

/// Joins the sets of `a` and `b` (the smaller root becomes the root).
pub(crate) fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

/// Connected components of the mesh, connecting faces that share an edge or a vertex.
/// Returns the number of components and, per face, its component label (0-based, numbered in
/// order of each component's first face).
pub fn connected_components(mesh: &TriMesh) -> (usize, Vec<u32>) {
    let n = mesh.num_vertices();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for f in &mesh.faces {
        union(&mut parent, f[0], f[1]);
        union(&mut parent, f[0], f[2]);
    }
    let mut label_of_root = vec![u32::MAX; n];
    let mut count = 0u32;
    let labels = mesh
        .faces
        .iter()
        .map(|f| {
            let r = find(&mut parent, f[0]) as usize;
            if label_of_root[r] == u32::MAX {
                label_of_root[r] = count;
                count += 1;
            }
            label_of_root[r]
        })
        .collect();
    (count as usize, labels)
}

/// Boundary loops: closed chains of edges that belong to exactly one triangle. Each loop lists its
/// vertices in order; consecutive vertices (u, v) appear as the directed half-edge u→v in their
/// triangle, so a cap oriented like the mesh uses the loop reversed.
///
/// Where a vertex has several outgoing boundary half-edges (a non-manifold boundary vertex), the
/// chains are still split into closed loops, each edge used once, and each loop is simple (it
/// visits no vertex twice). On an inconsistently wound mesh, where boundary directions do not chain,
/// edges are walked against their direction when needed and each loop is given the direction of
/// most of its edges; a boundary that does not close up is returned as an open chain.
pub fn boundary_loops(mesh: &TriMesh) -> Vec<Vec<u32>> {
    EdgeMap::new(mesh).boundary_loops()
}

/// Number of boundary edges (edges used by exactly one face).
pub fn boundary_edges(mesh: &TriMesh) -> usize {
    EdgeMap::new(mesh).boundary_edges()
}

/// Number of non-manifold edges (undirected edges used by more than two faces).
pub fn non_manifold_edges(mesh: &TriMesh) -> usize {
    EdgeMap::new(mesh).non_manifold_edges()
}

/// Number of non-manifold vertices: vertices whose faces form more than one edge-connected fan.
/// End points of non-manifold edges are not counted for that alone; see
/// [`EdgeMap::non_manifold_vertex_ids`].
pub fn non_manifold_vertices(mesh: &TriMesh) -> usize {
    EdgeMap::new(mesh).non_manifold_vertices()
}

/// Whether every edge with exactly two faces is traversed in opposite directions by them.
pub fn is_consistently_oriented(mesh: &TriMesh) -> bool {
    EdgeMap::new(mesh).is_consistently_oriented()
}

/// Which way a mesh's triangles face.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Orientation {
    /// Closed, consistently wound, enclosing positive volume (normals point out).
    Outward,
    /// Closed, consistently wound, enclosing negative volume (normals point in).
    Inward,
    /// Some edge is traversed in the same direction by its two faces, or closed components
    /// disagree (some outward, some inward).
    Inconsistent,
    /// Consistently wound but with boundary edges (or no faces), so inside and outside are undefined.
    Open,
}

impl Orientation {
    /// The lowercase name, as in JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Orientation::Outward => "outward",
            Orientation::Inward => "inward",
            Orientation::Inconsistent => "inconsistent",
            Orientation::Open => "open",
        }
    }
}

impl fmt::Display for Orientation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The orientation of the mesh: `Inconsistent` if some edge with two faces is traversed the same
/// way by both; else `Open` if there are boundary edges (or no faces); else, per connected
/// component, the sign of its enclosed signed volume: `Outward` if every component's is ≥ 0,
/// `Inward` if every one is < 0, and `Inconsistent` if the components disagree — where a
/// component nested inside another (a cavity) counts as outward when it faces into the cavity.
pub fn orientation(mesh: &TriMesh) -> Orientation {
    let map = EdgeMap::new(mesh);
    let (n, labels) = connected_components(mesh);
    orientation_of(&map, &map.summary(), n, &labels)
}

/// [`orientation`] from an already built edge map and component labelling.
pub(crate) fn orientation_of(
    map: &EdgeMap,
    edges: &EdgeSummary,
    n_components: usize,
    labels: &[u32],
) -> Orientation {
    if !edges.consistent {
        return Orientation::Inconsistent;
    }
    if map.mesh().faces.is_empty() || edges.boundary_edges > 0 {
        return Orientation::Open;
    }
    let vols = super::measures::component_signed_volumes(map.mesh(), n_components, labels);
    if n_components == 1 {
        return if vols[0] >= 0.0 {
            Orientation::Outward
        } else {
            Orientation::Inward
        };
    }
    // Several shells: a cavity's shell rightly faces into the cavity (negative volume).
    let depths = super::measures::component_nesting_depths(map.mesh(), n_components, labels);
    let outward_shell = |c: usize| (vols[c] >= 0.0) == depths[c].is_multiple_of(2);
    if (0..n_components).all(outward_shell) {
        Orientation::Outward
    } else if (0..n_components).all(|c| !outward_shell(c)) {
        Orientation::Inward
    } else {
        Orientation::Inconsistent
    }
}
