//! Geometric measures of a triangle mesh: area, signed enclosed volume (divergence theorem),
//! bounding box, mean edge length, degenerate triangles, Euler characteristic and genus.
//!
//! All sums are in f64 and taken relative to a reference point near the mesh (a vertex or the
//! centroid), because vessel meshes often sit far from the origin (CT patient coordinates): a
//! volume summed about the origin would lose digits to cancellation. The volume of a closed surface
//! is Σ (a−p)·((b−p)×(c−p))/6 over its triangles (Gauss divergence theorem), independent of p.
//! Genus follows from Euler–Poincaré: χ = V − E + F = Σ over components (2 − 2gᵢ).

use super::topology::{connected_components, EdgeMap, EdgeSummary};
use super::TriMesh;
use nalgebra::{Point3, Vector3};

/// Total surface area (file units²).
pub fn area(mesh: &TriMesh) -> f64 {
    (0..mesh.num_faces())
        .map(|f| 0.5 * mesh.face_normal_raw(f).norm())
        .sum()
}

/// Signed enclosed volume by the divergence theorem: Σ a·(b×c)/6 over triangles. Positive when a
/// closed mesh faces outward; only meaningful for closed meshes.
pub fn signed_volume(mesh: &TriMesh) -> f64 {
    // Relative to the first vertex, to keep precision for meshes far from the origin.
    let Some(o) = mesh.vertices.first() else {
        return 0.0;
    };
    signed_volume_about(mesh, o)
}

/// Σ (a−p)·((b−p)×(c−p))/6 over all triangles: the signed volume of the cones from `p` to the
/// triangles. For a closed mesh it does not depend on `p`; for an open mesh it is the volume
/// enclosed once the holes are closed by cones to `p`.
pub fn signed_volume_about(mesh: &TriMesh, p: &Point3<f64>) -> f64 {
    let mut sum = 0.0;
    for f in 0..mesh.num_faces() {
        let [a, b, c] = mesh.triangle(f);
        sum += (a - p).dot(&(b - p).cross(&(c - p)));
    }
    sum / 6.0
}

/// Area-weighted centroid of the surface (of its triangles, not of the enclosed solid). Falls back
/// to the mean of the vertices when the total area is zero, and to the origin for an empty mesh.
pub fn area_centroid(mesh: &TriMesh) -> Point3<f64> {
    let labels = vec![0u32; mesh.num_faces()];
    if mesh.faces.is_empty() {
        return vertex_mean(&mesh.vertices).unwrap_or_else(Point3::origin);
    }
    component_centroids(mesh, 1, &labels)[0]
}

fn vertex_mean(pts: &[Point3<f64>]) -> Option<Point3<f64>> {
    let o = pts.first()?;
    let s: Vector3<f64> = pts.iter().map(|p| p - o).sum();
    Some(o + s / pts.len() as f64)
}

/// Per component (labels as from [`connected_components`]), the area-weighted centroid of its
/// triangles.
fn component_centroids(mesh: &TriMesh, n: usize, labels: &[u32]) -> Vec<Point3<f64>> {
    let mut reference: Vec<Option<Point3<f64>>> = vec![None; n];
    let mut moment = vec![Vector3::zeros(); n];
    let mut weight = vec![0.0; n];
    let mut vsum = vec![Vector3::zeros(); n];
    let mut vcount = vec![0usize; n];
    for (f, &l) in labels.iter().enumerate() {
        let l = l as usize;
        let [a, b, c] = mesh.triangle(f);
        let o = *reference[l].get_or_insert(a);
        let w = 0.5 * (b - a).cross(&(c - a)).norm();
        let rel = ((a - o) + (b - o) + (c - o)) / 3.0;
        moment[l] += rel * w;
        weight[l] += w;
        vsum[l] += rel;
        vcount[l] += 1;
    }
    (0..n)
        .map(|l| {
            let o = reference[l].unwrap_or_else(Point3::origin);
            if weight[l] > 0.0 {
                o + moment[l] / weight[l]
            } else if vcount[l] > 0 {
                o + vsum[l] / vcount[l] as f64
            } else {
                o
            }
        })
        .collect()
}

/// Per connected component (labels as from [`connected_components`]), its signed volume measured
/// about the component's area-weighted centroid. For a closed component this is its enclosed
/// volume; for an open vessel tube (ends small compared with its length) it is still positive when
/// the tube faces outward and negative when it faces inward.
pub fn component_signed_volumes(mesh: &TriMesh, n: usize, labels: &[u32]) -> Vec<f64> {
    let centres = component_centroids(mesh, n, labels);
    let mut vol = vec![0.0; n];
    for (f, &l) in labels.iter().enumerate() {
        let p = &centres[l as usize];
        let [a, b, c] = mesh.triangle(f);
        vol[l as usize] += (a - p).dot(&(b - p).cross(&(c - p)));
    }
    vol.iter().map(|v| v / 6.0).collect()
}

/// How many other components enclose each component (its nesting depth): a cavity inside a
/// solid has depth 1, an island inside that cavity depth 2. A component counts as enclosed by
/// another when the other's winding number (exact sum of solid angles) at one of its vertices is
/// at least ½ in magnitude. A correctly oriented closed mesh has positive signed volume on
/// components of even depth and negative on odd ones (cavities face into the hole).
pub fn component_nesting_depths(mesh: &TriMesh, n: usize, labels: &[u32]) -> Vec<usize> {
    if n <= 1 {
        return vec![0; n];
    }
    let mut faces_of: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (f, &l) in labels.iter().enumerate() {
        faces_of[l as usize].push(f);
    }
    let boxes: Vec<(Point3<f64>, Point3<f64>)> = faces_of
        .iter()
        .map(|faces| {
            let mut lo = Point3::from([f64::INFINITY; 3]);
            let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
            for &f in faces {
                for p in mesh.triangle(f) {
                    lo = lo.inf(&p);
                    hi = hi.sup(&p);
                }
            }
            (lo, hi)
        })
        .collect();
    let inside_box = |p: &Point3<f64>, (lo, hi): &(Point3<f64>, Point3<f64>)| {
        (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k])
    };
    (0..n)
        .map(|c| {
            let Some(&f) = faces_of[c].first() else {
                return 0;
            };
            let p = mesh.vertices[mesh.faces[f][0] as usize];
            (0..n)
                .filter(|&d| d != c && inside_box(&p, &boxes[d]))
                .filter(|&d| {
                    let w: f64 = faces_of[d]
                        .iter()
                        .map(|&g| {
                            let [a, b, c] = mesh.triangle(g);
                            crate::bvh::solid_angle(&p, &a, &b, &c)
                        })
                        .sum::<f64>()
                        / (4.0 * std::f64::consts::PI);
                    w.abs() >= 0.5
                })
                .count()
        })
        .collect()
}

/// At each vertex of `mesh`, the sum of the raw normals (cross products, twice the area) of
/// the faces `faces` it is on: the area-weighted vertex normal, not normalised (zero for a
/// vertex on none of them).
pub fn vertex_normal_sums<'a>(
    mesh: &TriMesh,
    faces: impl Iterator<Item = &'a [u32; 3]>,
) -> Vec<Vector3<f64>> {
    let mut normals = vec![Vector3::<f64>::zeros(); mesh.vertices.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| mesh.vertices[i as usize]);
        let nf = (b - a).cross(&(c - a));
        for &i in f {
            normals[i as usize] += nf;
        }
    }
    normals
}

/// [`vertex_normal_sums`] normalised (zero stays zero).
pub fn vertex_normals<'a>(
    mesh: &TriMesh,
    faces: impl Iterator<Item = &'a [u32; 3]>,
) -> Vec<Vector3<f64>> {
    let mut normals = vertex_normal_sums(mesh, faces);
    for v in &mut normals {
        *v = v.try_normalize(0.0).unwrap_or_else(Vector3::zeros);
    }
    normals
}

/// Axis-aligned bounding box (min, max) of the vertices used by faces (of all vertices when there
/// are no faces). An empty mesh gives two origins.
pub fn bounding_box(mesh: &TriMesh) -> (Point3<f64>, Point3<f64>) {
    let mut lo = Point3::from([f64::INFINITY; 3]);
    let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
    let mut grow = |p: &Point3<f64>| {
        lo = lo.inf(p);
        hi = hi.sup(p);
    };
    if mesh.faces.is_empty() {
        mesh.vertices.iter().for_each(&mut grow);
    } else {
        mesh.faces
            .iter()
            .flatten()
            .for_each(|&v| grow(&mesh.vertices[v as usize]));
    }
    if lo.x > hi.x {
        return (Point3::origin(), Point3::origin());
    }
    (lo, hi)
}

/// Mean length of the unique undirected edges (each edge counted once, however many faces use
/// it). Zero for a mesh without edges.
pub fn mean_edge_length(mesh: &TriMesh) -> f64 {
    mean_edge_length_of(&EdgeMap::new(mesh))
}

pub(crate) fn mean_edge_length_of(map: &EdgeMap) -> f64 {
    let v = &map.mesh().vertices;
    let n = map.num_edges();
    if n == 0 {
        return 0.0;
    }
    let total: f64 = map
        .edges()
        .iter()
        .map(|&[a, b]| (v[b as usize] - v[a as usize]).norm())
        .sum();
    total / n as f64
}

/// Relative area tolerance of [`degenerate_faces`]: a triangle is degenerate when its area is at
/// most this times the squared mean edge length of the mesh (so the test does not depend on units).
pub const DEGENERATE_AREA_REL: f64 = 1e-12;

/// Number of degenerate triangles: with a repeated vertex index, or with area
/// ≤ [`DEGENERATE_AREA_REL`] · (mean edge length)².
pub fn degenerate_faces(mesh: &TriMesh) -> usize {
    degenerate_faces_with(mesh, mean_edge_length(mesh))
}

pub(crate) fn degenerate_faces_with(mesh: &TriMesh, mean_edge: f64) -> usize {
    let tol = DEGENERATE_AREA_REL * mean_edge * mean_edge;
    (0..mesh.num_faces())
        .filter(|&f| {
            let [a, b, c] = mesh.faces[f];
            a == b || b == c || a == c || 0.5 * mesh.face_normal_raw(f).norm() <= tol
        })
        .count()
}

/// Euler characteristic χ = V − E + F, with V the vertices used by faces and E the unique
/// undirected edges.
pub fn euler_characteristic(mesh: &TriMesh) -> i64 {
    euler_characteristic_of(&EdgeMap::new(mesh))
}

pub(crate) fn euler_characteristic_of(map: &EdgeMap) -> i64 {
    let mesh = map.mesh();
    let mut seen = vec![false; mesh.num_vertices()];
    let mut v = 0i64;
    for &i in mesh.faces.iter().flatten() {
        if !std::mem::replace(&mut seen[i as usize], true) {
            v += 1;
        }
    }
    v - map.num_edges() as i64 + mesh.num_faces() as i64
}

/// Total genus (number of handles summed over components), defined only for closed, orientable,
/// manifold meshes (no boundary edges, no non-manifold edges or vertices, at least one face):
/// g = (2·components − χ)/2. `None` otherwise.
pub fn genus(mesh: &TriMesh) -> Option<i64> {
    let map = EdgeMap::new(mesh);
    let (n, _) = connected_components(mesh);
    genus_of(&map, &map.summary(), n, map.non_manifold_vertices())
}

/// Handles of a surface that may have boundary (an open vessel, a patch cut by a box): the
/// genus of the closed surface its boundary loops would bound if each were capped by a disk,
/// g = (2·components − χ − loops)/2. `None` unless every edge has one or two faces, every vertex
/// is manifold and the faces are oriented consistently.
pub fn handles(mesh: &TriMesh) -> Option<i64> {
    let map = EdgeMap::new(mesh);
    let edges = map.summary();
    if mesh.faces.is_empty()
        || edges.non_manifold_edges > 0
        || map.non_manifold_vertices() > 0
        || !edges.consistent
    {
        return None;
    }
    let (n, _) = connected_components(mesh);
    genus_capped(&map, n, map.boundary_loops().len())
}

/// g = (2·components − χ − loops)/2: the genus of the surface of `map` with its `loops` boundary
/// loops capped by disks; `None` when that is not a whole number ≥ 0.
fn genus_capped(map: &EdgeMap, components: usize, loops: usize) -> Option<i64> {
    let twice = 2 * components as i64 - euler_characteristic_of(map) - loops as i64;
    (twice >= 0 && twice % 2 == 0).then_some(twice / 2)
}

pub(crate) fn genus_of(
    map: &EdgeMap,
    edges: &EdgeSummary,
    components: usize,
    non_manifold_vertices: usize,
) -> Option<i64> {
    if map.mesh().faces.is_empty()
        || non_manifold_vertices > 0
        || edges.boundary_edges > 0
        || edges.non_manifold_edges > 0
    {
        return None;
    }
    if !edges.consistent && !super::orient::is_orientable_of(map) {
        return None;
    }
    genus_capped(map, components, 0)
}

/// Aspect ratio of the triangle (a, b, c), normalised so an equilateral triangle gives 1:
/// L_max² · √3 / (4 · area), i.e. the longest edge over the shortest altitude times √3/2.
/// Degenerate triangles give `f64::INFINITY`.
pub fn triangle_aspect_ratio(
    a: &nalgebra::Point3<f64>,
    b: &nalgebra::Point3<f64>,
    c: &nalgebra::Point3<f64>,
) -> f64 {
    let l2 = (b - a)
        .norm_squared()
        .max((c - b).norm_squared())
        .max((a - c).norm_squared());
    let area = 0.5 * (b - a).cross(&(c - a)).norm();
    if area <= 0.0 {
        return f64::INFINITY;
    }
    l2 * 3f64.sqrt() / (4.0 * area)
}
