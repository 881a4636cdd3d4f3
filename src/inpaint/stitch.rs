//! Stitching the inpainted patch into the original mesh (`--keep-outside`): the triangles of the
//! input with every vertex outside D are kept unchanged (and so are those of a piece of surface
//! that D only grazes, within a given depth of ∂D throughout); the marching-cubes surface of the
//! inpainted φ is kept where it lies deeper than a margin inside D; each hole the removal left is
//! joined to the patch boundary loop facing it by a strip of triangles (a zipper: of the strips
//! whose triangles each advance along one loop, the one with the fewest triangles folded over
//! against the two surfaces, then whose new edges are shortest in sum).
//! The result is checked (closed where the input was, manifold, consistently oriented); the
//! caller falls back to the full re-mesh otherwise.
//!
//! The holes lie at ∂D, the patch loops at the margin: they pair up one to one only when the
//! surface between the two depths holds no saddle of the depth in D. Where the surface grazes ∂D
//! (the outer walls of a bifurcation whose D is centred on the carina pass 0.6 voxel inside ∂D)
//! the depth on it has a saddle just inside ∂D, and any deeper cut joins the cross-sections on
//! either side of it into one loop; so the margins tried end with shallow ones, down to ∂D itself.

use super::region::{depth_in, Ball};
use crate::mesh::measures::{component_signed_volumes, vertex_normal_sums};
use crate::mesh::topology::{boundary_loops, connected_components, find, union, EdgeMap};
use crate::{Error, Result, TriMesh};
use nalgebra::{Point3, Vector3};
use std::collections::{HashMap, HashSet};

/// The part of `mesh` made of the faces `keep` selects, its vertices renumbered compactly, and
/// for each of its vertices the index it has in `mesh`.
pub(crate) fn submesh(mesh: &TriMesh, keep: impl Fn(&[u32; 3]) -> bool) -> (TriMesh, Vec<u32>) {
    let mut map: HashMap<u32, u32> = HashMap::new();
    let mut out = TriMesh::default();
    let mut source = Vec::new();
    for f in mesh.faces.iter().filter(|f| keep(f)) {
        let g = f.map(|v| {
            *map.entry(v).or_insert_with(|| {
                out.vertices.push(mesh.vertices[v as usize]);
                source.push(v);
                (out.vertices.len() - 1) as u32
            })
        });
        out.faces.push(g);
    }
    (out, source)
}

/// `patch` without its closed pieces that enclose less than `min_volume` (world units³): marching
/// cubes' noise where the grid's sampling leaves a node or two of a thin sheet apart (the coarse
/// patch over the aneurysm's bitten end in `benches/repair_real`'s end bites: an 8-triangle speck
/// of 4·10⁻⁶ mm³ beside the cut's lip, stitched in as a second piece of the output). A closed
/// piece has no boundary edge; the patch's own surface is open where ∂D or the grid cuts it, and a
/// piece of the vessel inside D that encloses a cell or more is kept.
pub(crate) fn without_specks(patch: TriMesh, min_volume: f64) -> TriMesh {
    let (count, labels) = connected_components(&patch);
    if count <= 1 {
        return patch;
    }
    let volumes = component_signed_volumes(&patch, count, &labels);
    // A piece with a boundary edge (used by one face) is open.
    let mut open = vec![false; count];
    {
        let edges = EdgeMap::new(&patch);
        for (f, &l) in labels.iter().enumerate() {
            open[l as usize] |=
                (0..3).any(|k| edges.face_edge(f, k).is_some_and(|e| edges.valence(e) == 1));
        }
    }
    let speck = |l: u32| !open[l as usize] && volumes[l as usize].abs() < min_volume;
    if !(0..count as u32).any(speck) {
        return patch;
    }
    // (The specks' vertices stay, unused: the stitch takes the faces it keeps.)
    let faces = patch
        .faces
        .iter()
        .zip(&labels)
        .filter(|(_, &l)| !speck(l))
        .map(|(f, _)| *f)
        .collect();
    TriMesh::new(patch.vertices, faces)
}

/// The boundary loops of `mesh` that `keep` selects, each turned so that consecutive vertices
/// a→b are a directed edge of a face.
fn directed_loops(mesh: &TriMesh, keep: impl Fn(&[u32]) -> bool) -> Vec<Vec<u32>> {
    let loops: Vec<Vec<u32>> = boundary_loops(mesh)
        .into_iter()
        .filter(|lp| keep(lp))
        .collect();
    // Which of the loops' first edges some face holds in that direction (one pass over the
    // faces, looking up only those few edges).
    let firsts: HashSet<(u32, u32)> = loops
        .iter()
        .filter(|lp| lp.len() >= 2)
        .map(|lp| (lp[0], lp[1]))
        .collect();
    let along: HashSet<(u32, u32)> = mesh
        .faces
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k], f[(k + 1) % 3])))
        .filter(|e| firsts.contains(e))
        .collect();
    loops
        .into_iter()
        .map(|lp| {
            if lp.len() >= 2 && along.contains(&(lp[0], lp[1])) {
                lp
            } else {
                lp.into_iter().rev().collect()
            }
        })
        .collect()
}

/// The input with D cut out: its triangles with every vertex outside D (vertices renumbered), and
/// the holes that removal left: its boundary loops with an edge that was inside the input's
/// surface (not one of its open edges), each directed along its faces. Shared by the stitch and by
/// the branch crossings of `axis`.
pub struct CutOut {
    /// The kept triangles.
    pub kept: TriMesh,
    /// The holes around D, as vertex loops of `kept`.
    pub holes: Vec<Vec<u32>>,
    /// Open edges of the whole input (its open vessel ends, when kept open).
    pub open_edges: usize,
}

/// Cuts D out of `mesh` (see [`CutOut`]), except where D only grazes the surface: a connected
/// piece of the faces D reaches whose every vertex lies within `keep_within` (world units) of
/// ∂D is kept (a patch cut deeper than that has no loop there to meet its hole).
pub fn cut_out(mesh: &TriMesh, balls: &[Ball], keep_within: f64) -> CutOut {
    let cut = cut_vertices(mesh, balls, keep_within);
    let (kept, source) = submesh(mesh, |f| f.iter().all(|&v| !cut[v as usize]));
    let edges = EdgeMap::new(mesh);
    let open: HashSet<[u32; 2]> = (0..edges.num_edges())
        .filter(|&e| edges.valence(e) == 1)
        .map(|e| edges.edges()[e])
        .collect();
    // A loop made only of the input's open edges is an open vessel end, not a hole of D.
    let was_open = |a: u32, b: u32| {
        let (a, b) = (source[a as usize], source[b as usize]);
        open.contains(&[a.min(b), a.max(b)])
    };
    let holes = directed_loops(&kept, |lp| {
        (0..lp.len()).any(|i| !was_open(lp[i], lp[(i + 1) % lp.len()]))
    });
    CutOut {
        kept,
        holes,
        open_edges: open.len(),
    }
}

/// The vertices to cut out: those inside D (depth > 0), but for a connected piece of them
/// (joined through the faces they share) that lies within `keep_within` of ∂D throughout.
fn cut_vertices(mesh: &TriMesh, balls: &[Ball], keep_within: f64) -> Vec<bool> {
    let depth: Vec<f64> = mesh.vertices.iter().map(|p| depth_in(balls, p)).collect();
    let n = mesh.vertices.len();
    let inside = |v: u32| depth[v as usize] > 0.0;
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for f in &mesh.faces {
        let inner: Vec<u32> = f.iter().copied().filter(|&v| inside(v)).collect();
        for w in inner.windows(2) {
            union(&mut parent, w[0], w[1]);
        }
    }
    let mut deepest = vec![0.0f64; n];
    for v in (0..n as u32).filter(|&v| inside(v)) {
        let r = find(&mut parent, v) as usize;
        deepest[r] = deepest[r].max(depth[v as usize]);
    }
    (0..n as u32)
        .map(|v| inside(v) && deepest[find(&mut parent, v) as usize] > keep_within)
        .collect()
}

fn centroid(mesh: &TriMesh, lp: &[u32]) -> Point3<f64> {
    let s = lp.iter().fold(nalgebra::Vector3::zeros(), |s, &v| {
        s + mesh.vertices[v as usize].coords
    });
    Point3::from(s / lp.len().max(1) as f64)
}

/// Most cells of the table of [`zipper`]'s shortest strip (one byte each, the loops' vertex
/// counts plus one multiplied); longer pairs of loops are zipped greedily.
const SHORTEST_STRIP_CELLS: usize = 1 << 24;

/// Joins loop `a` (of the kept part, directed along its faces) and loop `b` (of the patch,
/// directed along its faces), both as indices into `verts`, by a strip of triangles oriented
/// consistently with both: from the closest pair of their vertices, a walked forward and b
/// backward, each triangle advancing along one loop, the strip whose new edges are shortest in
/// sum (the optimal tiling of two contours, Fuchs, Kedem and Uselton 1977, by dynamic
/// programming over the pairs of positions). Greedily advancing along whichever loop gives the
/// shorter next edge, as before, lost step on loops of unlike spacing and shape (a hole's rim
/// across a junction, with a third of its patch loop's vertices): one loop ran ahead, and edges
/// of 15 mm crossed a hole whose rim edges were under 2 mm. The greedy walk is kept for loops too
/// long for the table.
///
/// Of the strips, the one with the fewest *folded* triangles is taken first, and the shortest
/// among those: a triangle is folded when it faces against the surfaces its vertices lie on
/// (`normals`, per vertex of `verts`: their sum). The patch loop, cut near ∂D, runs unevenly
/// beside the rim, and the shortest strip turned slivers over there (a fold: two triangles lying
/// on each other; 148 in 82 of the 140 outputs of `benches/repair_real`'s seeds 21–27 on its four
/// vessels other than the ICA, whose input has folds of its own; 1 now). Returns the strip and
/// its folded triangles.
fn zipper(
    verts: &[Point3<f64>],
    normals: &[Vector3<f64>],
    a: &[u32],
    b: &[u32],
) -> (Vec<[u32; 3]>, usize) {
    let (n, m) = (a.len(), b.len());
    let (mut best, mut i0, mut k0) = (f64::INFINITY, 0, 0);
    for (i, &va) in a.iter().enumerate() {
        for (k, &vb) in b.iter().enumerate() {
            let d = (verts[va as usize] - verts[vb as usize]).norm_squared();
            if d < best {
                (best, i0, k0) = (d, i, k);
            }
        }
    }
    // Positions 0..=n along a and 0..=m along b (n and m: back at the start).
    let av = |i: usize| a[(i0 + i) % n];
    let bv = |k: usize| b[(k0 + m - k % m) % m];
    let dist = |i: usize, k: usize| (verts[av(i) as usize] - verts[bv(k) as usize]).norm();
    // Advancing a from (i, k) adds the triangle (a_i+1, a_i, b_k); advancing b, (b_k, b_k+1, a_i).
    let advance_a = |i: usize, k: usize| [av(i + 1), av(i), bv(k)];
    let advance_b = |i: usize, k: usize| [bv(k), bv(k + 1), av(i)];
    // A triangle is folded when it faces against its vertices' surfaces (their normals summed).
    let folded = |t: [u32; 3]| -> u32 {
        let [p, q, r] = t.map(|v| verts[v as usize]);
        let up: Vector3<f64> = t.iter().map(|&v| normals[v as usize]).sum();
        u32::from((q - p).cross(&(r - p)).dot(&up) <= 0.0)
    };
    let mut faces = Vec::with_capacity(n + m);
    let cells = (n + 1).saturating_mul(m + 1);
    if cells > SHORTEST_STRIP_CELLS {
        let (mut i, mut k) = (0, 0);
        while i < n || k < m {
            if k == m || (i < n && dist(i + 1, k) <= dist(i, k + 1)) {
                faces.push(advance_a(i, k));
                i += 1;
            } else {
                faces.push(advance_b(i, k));
                k += 1;
            }
        }
        let nf = faces.iter().map(|&t| folded(t) as usize).sum();
        return (faces, nf);
    }
    // Each step ends on the edge (a_i, b_k) of the position it reaches: the strip's length is
    // the sum over the positions it passes. `from_a[i·(m+1) + k]`: reached by advancing a.
    // The cost of a strip is (its folded triangles, its length), compared in that order.
    let never = (u32::MAX, f64::INFINITY);
    let mut from_a = vec![false; cells];
    let mut above = vec![never; m + 1];
    let mut row: Vec<(u32, f64)> = vec![(0, 0.0); m + 1];
    for i in 0..=n {
        for k in 0..=m {
            if i == 0 && k == 0 {
                row[0] = (0, 0.0);
                continue;
            }
            let via_a = if i > 0 {
                let (f, l) = above[k];
                (f.saturating_add(folded(advance_a(i - 1, k))), l)
            } else {
                never
            };
            let via_b = if k > 0 {
                let (f, l) = row[k - 1];
                (f.saturating_add(folded(advance_b(i, k - 1))), l)
            } else {
                never
            };
            let take_a = via_a.0 < via_b.0 || (via_a.0 == via_b.0 && via_a.1 <= via_b.1);
            from_a[i * (m + 1) + k] = take_a;
            let (f, l) = if take_a { via_a } else { via_b };
            row[k] = (f, l + dist(i, k));
        }
        std::mem::swap(&mut above, &mut row);
    }
    let (mut i, mut k) = (n, m);
    while i > 0 || k > 0 {
        if from_a[i * (m + 1) + k] {
            i -= 1;
            faces.push(advance_a(i, k));
        } else {
            k -= 1;
            faces.push(advance_b(i, k));
        }
    }
    faces.reverse();
    (faces, above[m].0 as usize)
}

/// The stitched mesh (see the module docs): `cut` (the input with D cut out), `patch` (a closed
/// surface: the marching cubes of the inpainted φ), `balls` (D), `margins` (world units: the
/// depths inside D at which the patch is cut, tried in turn; near a junction the branches'
/// cross-sections may merge at one depth and not at another). Errors (with the first depth's
/// reason) when at no depth the holes and the patch loops pair up one to one into a clean surface.
pub fn stitch_patch(
    cut: &CutOut,
    patch: &TriMesh,
    balls: &[Ball],
    margins: &[f64],
) -> Result<TriMesh> {
    stitch_patch_checked(cut, patch, balls, margins, |_| Ok(()))
        .map(|(m, ())| m)
        .map_err(Error::Geometry)
}

/// [`stitch_patch`] whose result must also pass `check` (a depth whose stitch fails the check
/// is passed over like one that does not stitch), with what the check gave; Err: the first
/// reason met. A stitch that passes with a triangle folded over (`zipper`) is taken only when
/// no later depth gives one without.
pub fn stitch_patch_checked<T>(
    cut: &CutOut,
    patch: &TriMesh,
    balls: &[Ball],
    margins: &[f64],
    check: impl Fn(&TriMesh) -> std::result::Result<T, String>,
) -> std::result::Result<(TriMesh, T), String> {
    let mut first_error = None;
    let mut folded = None;
    for &margin in margins {
        match stitch_at(cut, patch, balls, margin)
            .map_err(|e| e.to_string())
            .and_then(|(m, folds)| check(&m).map(|t| (m, t, folds)))
        {
            Ok((m, t, 0)) => return Ok((m, t)),
            Ok((m, t, _)) => {
                folded.get_or_insert((m, t));
            }
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
    }
    folded.ok_or_else(|| first_error.unwrap_or_else(|| "stitching: no cut depth given".into()))
}

/// [`stitch_patch`] with the patch cut at one depth, and the strips' folded triangles.
fn stitch_at(
    cut: &CutOut,
    patch: &TriMesh,
    balls: &[Ball],
    margin: f64,
) -> Result<(TriMesh, usize)> {
    let (kept, holes) = (&cut.kept, &cut.holes);
    let (part, _) = submesh(patch, |f| {
        f.iter()
            .all(|&v| depth_in(balls, &patch.vertices[v as usize]) > margin)
    });
    let rims = directed_loops(&part, |_| true);
    if holes.len() != rims.len() || holes.is_empty() {
        return Err(Error::Geometry(format!(
            "stitching: {} holes around D but {} patch loops",
            holes.len(),
            rims.len()
        )));
    }
    let offset = kept.vertices.len() as u32;
    let mut out = kept.clone();
    out.append(&part);
    let normals = vertex_normal_sums(&out, out.faces.iter());
    let mut folds = 0;
    let mut free: Vec<bool> = vec![true; rims.len()];
    for hole in holes {
        let c = centroid(kept, hole);
        let (r, _) = rims
            .iter()
            .enumerate()
            .filter(|(r, _)| free[*r])
            .map(|(r, lp)| (r, (centroid(&part, lp) - c).norm()))
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .ok_or_else(|| Error::Geometry("stitching: no patch loop left".into()))?;
        free[r] = false;
        let b: Vec<u32> = rims[r].iter().map(|&v| v + offset).collect();
        let (strip, f) = zipper(&out.vertices, &normals, hole, &b);
        out.faces.extend(strip);
        folds += f;
    }
    let edges = EdgeMap::new(&out);
    if edges.non_manifold_edges() > 0
        || !edges.is_consistently_oriented()
        || edges.boundary_edges() > cut.open_edges
        || edges.non_manifold_vertices() > 0
    {
        return Err(Error::Geometry(format!(
            "stitching produced a surface with {} open and {} non-manifold edges",
            edges.boundary_edges(),
            edges.non_manifold_edges()
        )));
    }
    Ok((out, folds))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::primitives::icosphere;

    #[test]
    fn specks_are_dropped_and_the_vessel_kept() {
        // An open tube (the patch's own surface), a speck (volume 4·10⁻⁹) and a closed sphere of
        // radius 0.5 (0.52), both closed; at a cell of 0.1³ only the speck goes.
        let mut patch = crate::mesh::primitives::open_tube(1.0, 4.0, 24, 8);
        let tube_faces = patch.faces.len();
        let sphere = icosphere(2, 0.5, Point3::new(5.0, 0.0, 0.0));
        patch.append(&icosphere(1, 0.001, Point3::new(0.0, 0.0, 2.0)));
        patch.append(&sphere);
        let out = without_specks(patch.clone(), 1e-3);
        assert_eq!(out.faces.len(), tube_faces + sphere.faces.len());
        let (count, _) = connected_components(&out);
        assert_eq!(count, 2);
        // Nothing smaller than the threshold: the patch as it was.
        assert_eq!(without_specks(patch.clone(), 1e-12).faces, patch.faces);
    }

    /// Two unit spheres 0.3 apart; D a ball of radius 0.5 on the first one's wall, facing the
    /// second, which it reaches 0.2 deep at most.
    fn grazing() -> (TriMesh, Ball) {
        let mut mesh = icosphere(4, 1.0, Point3::origin());
        mesh.append(&icosphere(4, 1.0, Point3::new(2.3, 0.0, 0.0)));
        let ball = Ball {
            center: Point3::new(1.0, 0.0, 0.0),
            radius: 0.5,
        };
        (mesh, ball)
    }

    /// Every edge of the loops `a` (vertices 0..a.len()) and `b` (the rest) is used by `faces`
    /// once, against its loop's direction, and no other edge joins two vertices of one loop.
    fn assert_each_loop_edge_once_reversed(faces: &[[u32; 3]], a: &[u32], b: &[u32]) {
        let na = a.len() as u32;
        let mut directed: Vec<(u32, u32)> = faces
            .iter()
            .flat_map(|f| (0..3).map(move |e| (f[e], f[(e + 1) % 3])))
            .filter(|&(p, q)| (p < na) == (q < na))
            .collect();
        directed.sort_unstable();
        let loop_edges = |l: &[u32]| {
            (0..l.len())
                .map(|j| (l[(j + 1) % l.len()], l[j]))
                .collect::<Vec<_>>()
        };
        let mut expected = loop_edges(a);
        expected.extend(loop_edges(b));
        expected.sort_unstable();
        assert_eq!(directed, expected);
    }

    /// Loops of unlike spacing on an elongated saddle (a hole's rim across a junction, and a
    /// patch loop three times as fine and unevenly spaced): every loop edge is used once, against
    /// its loop's direction, and the longest edge across is 0.86 (0.85 apart at the closest;
    /// the greedy walk, advancing along whichever loop gave the shorter next edge, ran ahead on
    /// one loop and left an edge of 1.54).
    #[test]
    fn the_zipper_keeps_step_on_loops_of_unlike_spacing() {
        let saddle = |n: usize, r: f64, amp: f64, uneven: f64| {
            (0..n).map(move |j| {
                let t0 = std::f64::consts::TAU * j as f64 / n as f64;
                let t = t0 + uneven * t0.sin();
                Point3::new(3.0 * r * t.cos(), r * t.sin(), amp * (2.0 * t).cos())
            })
        };
        let mut verts: Vec<Point3<f64>> = saddle(20, 1.0, 2.0, 0.0).collect();
        verts.extend(saddle(60, 0.85, 1.6, 0.5));
        let a: Vec<u32> = (0..20).collect();
        let b: Vec<u32> = (20..80).rev().collect();
        let (faces, _) = zipper(&verts, &vec![Vector3::zeros(); verts.len()], &a, &b);
        assert_eq!(faces.len(), 80);
        assert_each_loop_edge_once_reversed(&faces, &a, &b);
        let longest = faces
            .iter()
            .flat_map(|f| (0..3).map(move |e| (f[e], f[(e + 1) % 3])))
            .filter(|&(p, q)| (p < 20) != (q < 20))
            .map(|(p, q)| (verts[p as usize] - verts[q as usize]).norm())
            .fold(0.0, f64::max);
        assert!(longest < 0.9, "longest edge across {longest}");
    }

    /// A hole's rim (8 vertices on a unit circle, in the plane z = 0 whose surface faces +z,
    /// clockwise along the kept faces) and a patch loop inside it (24 vertices, anticlockwise,
    /// unevenly spaced and 0.73–0.97 from the centre, as a patch cut near ∂D can be): the shortest
    /// strip folds two triangles over (they face −z); the strip of fewest folded triangles
    /// has none.
    #[test]
    fn the_zipper_folds_no_triangle_over_where_it_can_avoid_it() {
        let patch_loop = [
            [0.969, 0.0],
            [0.716, 0.329],
            [0.522, 0.595],
            [0.238, 0.709],
            [-0.033, 0.791],
            [-0.329, 0.852],
            [-0.545, 0.713],
            [-0.592, 0.478],
            [-0.727, 0.38],
            [-0.788, 0.264],
            [-0.872, 0.174],
            [-0.836, 0.078],
            [-0.871, 0.0],
            [-0.928, -0.086],
            [-0.887, -0.177],
            [-0.775, -0.26],
            [-0.742, -0.388],
            [-0.637, -0.514],
            [-0.459, -0.601],
            [-0.281, -0.726],
            [-0.033, -0.797],
            [0.256, -0.764],
            [0.531, -0.605],
            [0.789, -0.363],
        ];
        let mut verts: Vec<Point3<f64>> = (0..8)
            .map(|j| {
                let t = -std::f64::consts::TAU * j as f64 / 8.0;
                Point3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        verts.extend(patch_loop.iter().map(|&[x, y]| Point3::new(x, y, 0.0)));
        let a: Vec<u32> = (0..8).collect();
        let b: Vec<u32> = (8..32).collect();
        let facing_down = |faces: &[[u32; 3]]| {
            faces
                .iter()
                .filter(|t| {
                    let [p, q, r] = t.map(|v| verts[v as usize]);
                    (q - p).cross(&(r - p)).z <= 0.0
                })
                .count()
        };
        // Without normals every triangle counts as folded: the shortest strip.
        let (shortest, _) = zipper(&verts, &vec![Vector3::zeros(); 32], &a, &b);
        assert_eq!(facing_down(&shortest), 2);
        let (faces, folded) = zipper(&verts, &vec![Vector3::z(); 32], &a, &b);
        assert_eq!((folded, facing_down(&faces)), (0, 0));
        assert_each_loop_edge_once_reversed(&faces, &a, &b);
    }

    #[test]
    fn a_grazed_wall_is_kept_and_leaves_no_hole() {
        let (mesh, ball) = grazing();
        let second = |m: &TriMesh| {
            m.faces
                .iter()
                .filter(|f| f.iter().all(|&v| m.vertices[v as usize].x > 1.15))
                .count()
        };
        let whole = second(&mesh);
        // Cut everywhere D reaches: a hole in each sphere.
        let cut = cut_out(&mesh, &[ball], 0.0);
        assert_eq!(cut.holes.len(), 2);
        assert!(second(&cut.kept) < whole);
        // Kept within 0.1 of ∂D only: the second sphere's piece, 0.2 deep, is still cut.
        assert_eq!(cut_out(&mesh, &[ball], 0.1).holes.len(), 2);
        // Within 0.3 of ∂D: the second sphere is kept whole, the first one's hole stays.
        let cut = cut_out(&mesh, &[ball], 0.3);
        assert_eq!(cut.holes.len(), 1);
        assert_eq!(second(&cut.kept), whole);
        assert!(cut.kept.num_faces() < mesh.num_faces());
    }
}
