//! The case table of the marching cubes, generated once at first use from a rule rather than typed
//! in: for every sign configuration of a cube's 8 corners and every outcome of the asymptotic
//! decider on its ambiguous faces, the triangles as triples of cube edges.
//!
//! Construction, per configuration:
//! 1. On each face, the crossed edges are paired into directed segments. A face with two crossings
//!    has one segment. A face with four (the two inside corners diagonal) is ambiguous: the
//!    asymptotic decider (Nielson and Hamann, "The asymptotic decider", IEEE Visualization 1991),
//!    evaluated at run time on the face's four values, says whether the inside corners are
//!    joined across the face's saddle; the table holds both outcomes. Segments run from the
//!    crossing where a counter-clockwise walk (seen from outside the cube) enters the inside to
//!    where it leaves, so the inside lies on their right; the neighbouring cube walks the shared
//!    face the other way round and gets the same segments reversed.
//! 2. Every crossed edge starts one segment and ends another, so the segments chain into closed
//!    polygons. Each polygon is capped by its own disk: interior ambiguities (where the trilinear
//!    interpolant would join two polygons by a tunnel through the cube) are always resolved
//!    without the tunnel.
//! 3. Each polygon is triangulated without diagonals between two crossings on one face (such a
//!    diagonal could be shared with the neighbouring cube, giving an edge with four triangles),
//!    choosing among the allowed triangulations the one with the largest smallest angle when the
//!    crossings sit at the edge midpoints (dynamic programming over the polygon). A polygon with
//!    no allowed triangulation (116 of the 656 entries have one, all with several ambiguous
//!    faces) is fanned from an extra vertex at the mean of its crossings, which lies strictly
//!    inside the cube, so its triangles are never flat.
//!
//! Corner c of a cube is at (c & 1, (c >> 1) & 1, c >> 2). Edges: 0–3 along x at (y, z) =
//! (e & 1, e >> 1); 4–7 along y at (x, z) = ((e − 4) & 1, (e − 4) >> 1); 8–11 along z at
//! (x, y) = ((e − 8) & 1, (e − 8) >> 1). Face f lies on axis f / 2 at coordinate f % 2.

use std::sync::OnceLock;

/// The generated table.
pub(crate) struct CaseTable {
    /// Per configuration (bit c set when corner c is inside): the ambiguous faces (bit f).
    pub ambiguous: [u8; 256],
    /// Per configuration: index of its first entry; the entry for decider outcomes `bits` (bit k
    /// set when the k-th ambiguous face, by increasing face number, has its inside corners
    /// joined) is `first[config] + bits`.
    pub first: [u16; 256],
    /// Per entry: (first triangle in `triangles`, number of triangles).
    pub entries: Vec<(u16, u8)>,
    /// Triangles as cube-edge triples, counter-clockwise seen from outside (the normal points
    /// from the inside, φ < 0, to the outside). Codes 12, 13, … stand for the entry's extra
    /// centre vertices, in the order of `centres`.
    pub triangles: Vec<[u8; 3]>,
    /// Per entry: the polygons (cube edges) that are fanned from an extra vertex at the mean of
    /// their crossings, because every triangulation of their own vertices would need a diagonal
    /// between two crossings on one face. Empty for most entries.
    pub centres: Vec<Vec<Vec<u8>>>,
}

/// The table, generated on first use.
pub(crate) fn case_table() -> &'static CaseTable {
    static TABLE: OnceLock<CaseTable> = OnceLock::new();
    TABLE.get_or_init(generate)
}

/// Corners of face `f`, counter-clockwise seen from outside the cube.
pub(crate) fn face_corners(f: usize) -> [usize; 4] {
    let (axis, side) = (f / 2, f % 2);
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    // Counter-clockwise about +axis in the right-handed frame (u, v, axis); reversed for −axis.
    let uv: [(usize, usize); 4] = if side == 1 {
        [(0, 0), (1, 0), (1, 1), (0, 1)]
    } else {
        [(0, 0), (0, 1), (1, 1), (1, 0)]
    };
    uv.map(|(a, b)| {
        let mut xyz = [0usize; 3];
        xyz[axis] = side;
        xyz[u] = a;
        xyz[v] = b;
        xyz[0] | (xyz[1] << 1) | (xyz[2] << 2)
    })
}

/// The cube edge joining corners `a` and `b` (which differ in one coordinate).
pub(crate) fn edge_between(a: usize, b: usize) -> usize {
    let lo = a.min(b);
    match a ^ b {
        1 => (lo >> 1) & 3,                         // x-edge at (y, z)
        2 => 4 + (lo & 1) + ((lo >> 2) << 1),       // y-edge at (x, z)
        4 => 8 + (lo & 1) + (((lo >> 1) & 1) << 1), // z-edge at (x, y)
        _ => unreachable!("corners {a} and {b} are not joined by an edge"),
    }
}

/// The two corners of edge `e`, the lower first.
pub(crate) fn edge_corners(e: usize) -> [usize; 2] {
    let (axis, k) = (e / 4, e % 4);
    // The two fixed coordinates, lower axis first: x-edges (y, z), y-edges (x, z), z-edges (x, y).
    let (p, q) = match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let lo = ((k & 1) << p) | ((k >> 1) << q);
    [lo, lo | (1 << axis)]
}

/// The two faces containing edge `e`.
fn edge_faces(e: usize) -> [usize; 2] {
    let [lo, _] = edge_corners(e);
    let axis = e / 4;
    let mut faces = [0usize; 2];
    let mut n = 0;
    for other in 0..3 {
        if other != axis {
            faces[n] = 2 * other + ((lo >> other) & 1);
            n += 1;
        }
    }
    faces
}

/// Midpoint of edge `e` in cube coordinates.
fn edge_midpoint(e: usize) -> [f64; 3] {
    let [a, b] = edge_corners(e);
    let p = |c: usize| [(c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64];
    let (pa, pb) = (p(a), p(b));
    [0, 1, 2].map(|i| 0.5 * (pa[i] + pb[i]))
}

/// The directed segments (from edge, to edge) of face `f` for `config`, with `joined` saying
/// whether the inside corners of an ambiguous face are joined.
fn face_segments(config: usize, f: usize, joined: bool) -> Vec<(usize, usize)> {
    let q = face_corners(f);
    let inside = |c: usize| (config >> c) & 1 == 1;
    // Crossings in counter-clockwise order: (edge, entering the inside?).
    let mut crossings = Vec::new();
    for i in 0..4 {
        let (a, b) = (q[i], q[(i + 1) % 4]);
        if inside(a) != inside(b) {
            crossings.push((edge_between(a, b), inside(b)));
        }
    }
    match crossings.len() {
        0 => Vec::new(),
        2 => {
            let (entry, exit) = if crossings[0].1 {
                (crossings[0].0, crossings[1].0)
            } else {
                (crossings[1].0, crossings[0].0)
            };
            vec![(entry, exit)]
        }
        4 => {
            // Separated insides: each entry pairs with the exit that follows it (the inside arc);
            // joined insides: each exit pairs with the entry that follows it (the outside arc is
            // cut off), the segment still running entry → exit.
            let mut segs = Vec::new();
            for i in 0..4 {
                let (e, enters) = crossings[i];
                let (next, _) = crossings[(i + 1) % 4];
                if enters && !joined {
                    segs.push((e, next));
                } else if !enters && joined {
                    segs.push((next, e));
                }
            }
            segs
        }
        n => unreachable!("a face has an even number of crossings, got {n}"),
    }
}

/// Whether face `f` is ambiguous for `config` (inside corners diagonal, outside corners diagonal).
fn is_ambiguous(config: usize, f: usize) -> bool {
    let q = face_corners(f);
    let s = q.map(|c| (config >> c) & 1);
    s[0] == s[2] && s[1] == s[3] && s[0] != s[1]
}

/// Polygons (cycles of cube edges) of `config` under the decider outcomes `joined` (per face).
fn polygons(config: usize, joined: [bool; 6]) -> Vec<Vec<usize>> {
    let mut next = [usize::MAX; 12];
    for (f, &j) in joined.iter().enumerate() {
        for (from, to) in face_segments(config, f, j) {
            assert_eq!(next[from], usize::MAX, "edge {from} starts two segments");
            next[from] = to;
        }
    }
    let mut seen = [false; 12];
    let mut polys = Vec::new();
    for start in 0..12 {
        if next[start] == usize::MAX || seen[start] {
            continue;
        }
        let mut poly = Vec::new();
        let mut e = start;
        while !seen[e] {
            seen[e] = true;
            poly.push(e);
            e = next[e];
            assert_ne!(e, usize::MAX, "open chain in configuration {config}");
        }
        assert_eq!(e, start, "chain does not close in configuration {config}");
        polys.push(poly);
    }
    polys
}

/// Smallest angle (radians) of the triangle (a, b, c).
fn min_angle(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let angle = |u: [f64; 3], v: [f64; 3]| {
        let dot = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let cross = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let cn = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
        cn.atan2(dot)
    };
    let (ab, ac, bc) = (sub(b, a), sub(c, a), sub(c, b));
    let neg = |u: [f64; 3]| [-u[0], -u[1], -u[2]];
    angle(ab, ac)
        .min(angle(neg(ab), bc))
        .min(angle(neg(ac), neg(bc)))
}

/// Triangulates a polygon of cube edges (in order) with no diagonal between two edges of one
/// face, maximising the smallest angle at the edge midpoints. None when impossible.
fn triangulate(poly: &[usize]) -> Option<Vec<[usize; 3]>> {
    let n = poly.len();
    let pos: Vec<[f64; 3]> = poly.iter().map(|&e| edge_midpoint(e)).collect();
    let allowed = |i: usize, j: usize| -> bool {
        let adjacent = (i + 1) % n == j || (j + 1) % n == i;
        if adjacent {
            return true;
        }
        let (fa, fb) = (edge_faces(poly[i]), edge_faces(poly[j]));
        !fa.iter().any(|f| fb.contains(f))
    };
    // best[i][j]: the largest smallest angle of a triangulation of vertices i..=j (chord i–j).
    let mut best = vec![vec![f64::NEG_INFINITY; n]; n];
    let mut split = vec![vec![usize::MAX; n]; n];
    for i in 0..n - 1 {
        best[i][i + 1] = f64::INFINITY;
    }
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !allowed(i, j) {
                continue;
            }
            for k in i + 1..j {
                let q = best[i][k]
                    .min(best[k][j])
                    .min(min_angle(pos[i], pos[k], pos[j]));
                if q > best[i][j] {
                    best[i][j] = q;
                    split[i][j] = k;
                }
            }
        }
    }
    if best[0][n - 1] == f64::NEG_INFINITY {
        return None;
    }
    let mut tris = Vec::new();
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let k = split[i][j];
        tris.push([poly[i], poly[k], poly[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    Some(tris)
}

fn generate() -> CaseTable {
    let mut table = CaseTable {
        ambiguous: [0; 256],
        first: [0; 256],
        entries: Vec::new(),
        triangles: Vec::new(),
        centres: Vec::new(),
    };
    for config in 0..256 {
        let amb: Vec<usize> = (0..6).filter(|&f| is_ambiguous(config, f)).collect();
        table.ambiguous[config] = amb.iter().fold(0u8, |m, &f| m | (1 << f));
        table.first[config] = table.entries.len() as u16;
        for bits in 0..1usize << amb.len() {
            let mut joined = [false; 6];
            for (k, &f) in amb.iter().enumerate() {
                joined[f] = (bits >> k) & 1 == 1;
            }
            let start = table.triangles.len();
            let mut centres = Vec::new();
            for poly in polygons(config, joined) {
                let tris = triangulate(&poly).unwrap_or_else(|| {
                    // A fan from a vertex inside the cube: no diagonals at all.
                    let c = 12 + centres.len();
                    centres.push(poly.iter().map(|&e| e as u8).collect());
                    (0..poly.len())
                        .map(|i| [c, poly[i], poly[(i + 1) % poly.len()]])
                        .collect()
                });
                table
                    .triangles
                    .extend(tris.iter().map(|t| t.map(|e| e as u8)));
            }
            let count = table.triangles.len() - start;
            table.entries.push((start as u16, count as u8));
            table.centres.push(centres);
        }
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corner_pos(c: usize) -> [f64; 3] {
        [(c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64]
    }

    #[test]
    fn edges_and_faces_are_consistent() {
        for e in 0..12 {
            let [a, b] = edge_corners(e);
            assert_eq!(edge_between(a, b), e);
            for f in edge_faces(e) {
                let q = face_corners(f);
                assert!(q.contains(&a) && q.contains(&b), "edge {e} on face {f}");
            }
        }
        for f in 0..6 {
            // Counter-clockwise seen from outside: the Newell normal points out of the cube.
            let q = face_corners(f).map(corner_pos);
            let (u, v) = (
                [0, 1, 2].map(|i| q[1][i] - q[0][i]),
                [0, 1, 2].map(|i| q[2][i] - q[1][i]),
            );
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let axis = f / 2;
            let outward = if f % 2 == 1 { 1.0 } else { -1.0 };
            assert_eq!(n[axis], outward, "face {f}");
        }
    }

    /// The triangles of every entry form disks whose boundary is exactly the face segments,
    /// run in the same direction (so neighbouring cubes, which run them the other way, join with
    /// consistent orientation); every crossed edge is used and no other.
    #[test]
    fn table_covers_every_configuration() {
        let t = case_table();
        assert_eq!(t.entries[t.first[0] as usize].1, 0);
        assert_eq!(t.entries[t.first[255] as usize].1, 0);
        let mut with_centre = 0;
        for config in 0..256usize {
            let amb: Vec<usize> = (0..6).filter(|&f| is_ambiguous(config, f)).collect();
            assert_eq!(t.ambiguous[config].count_ones() as usize, amb.len());
            for bits in 0..1usize << amb.len() {
                let entry = t.first[config] as usize + bits;
                let (start, count) = t.entries[entry];
                let tris = &t.triangles[start as usize..start as usize + count as usize];
                with_centre += usize::from(!t.centres[entry].is_empty());
                assert!(t.centres[entry].len() <= 4, "at most four centres per cube");
                let mut directed: Vec<(u8, u8)> = tris
                    .iter()
                    .flat_map(|tr| [(tr[0], tr[1]), (tr[1], tr[2]), (tr[2], tr[0])])
                    .collect();
                directed.sort_unstable();
                let n = directed.len();
                directed.dedup();
                assert_eq!(directed.len(), n, "config {config}: a directed edge twice");
                let mut boundary: Vec<(u8, u8)> = directed
                    .iter()
                    .filter(|&&(a, b)| directed.binary_search(&(b, a)).is_err())
                    .copied()
                    .collect();
                boundary.sort_unstable();
                let mut joined = [false; 6];
                for (k, &f) in amb.iter().enumerate() {
                    joined[f] = (bits >> k) & 1 == 1;
                }
                let mut segments: Vec<(u8, u8)> = (0..6)
                    .flat_map(|f| face_segments(config, f, joined[f]))
                    .map(|(a, b)| (a as u8, b as u8))
                    .collect();
                segments.sort_unstable();
                assert_eq!(boundary, segments, "config {config} bits {bits}");
                for e in 0..12 {
                    let [a, b] = edge_corners(e);
                    let crossed = ((config >> a) ^ (config >> b)) & 1 == 1;
                    let used = tris.iter().any(|tr| tr.contains(&(e as u8)));
                    assert_eq!(used, crossed, "config {config} bits {bits} edge {e}");
                }
            }
        }
        // Case 7 with its three faces joined (and its complement) needs a centre vertex.
        assert!(with_centre > 0);
        println!(
            "entries {}, with a centre vertex {with_centre}",
            t.entries.len()
        );
    }

    /// A single inside (or outside) corner: the triangle faces away from the inside corner.
    #[test]
    fn corner_triangles_face_outward() {
        let t = case_table();
        for c in 0..8 {
            for (config, sign) in [(1usize << c, 1.0), (255 ^ (1usize << c), -1.0)] {
                let (start, count) = t.entries[t.first[config] as usize];
                assert_eq!(count, 1);
                let p = t.triangles[start as usize].map(|e| edge_midpoint(e as usize));
                let (u, v) = (
                    [0, 1, 2].map(|i| p[1][i] - p[0][i]),
                    [0, 1, 2].map(|i| p[2][i] - p[0][i]),
                );
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                let corner = corner_pos(c);
                let away = [0, 1, 2].map(|i| sign * (p[0][i] - corner[i]));
                let dot: f64 = (0..3).map(|i| n[i] * away[i]).sum();
                assert!(dot > 0.0, "config {config}");
            }
        }
    }
}
