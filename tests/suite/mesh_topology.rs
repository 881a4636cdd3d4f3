//! Topology queries, orientation and its repair on small generated meshes whose answers are known
//! by construction.

use nalgebra::{Point3, Vector3};
use std::collections::HashSet;
use std::f64::consts::TAU;
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::measures::{
    area_centroid, euler_characteristic, genus, handles, signed_volume, signed_volume_about,
};
use vesselmsr::mesh::orient::{orient_consistently, orient_outward};
use vesselmsr::mesh::primitives::{self, box_mesh, open_tube};
use vesselmsr::mesh::topology::{
    boundary_edges, boundary_loops, connected_components, is_consistently_oriented,
    non_manifold_edges, non_manifold_vertices, orientation, EdgeMap, Orientation,
};
use vesselmsr::TriMesh;

fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
    Point3::new(x, y, z)
}

/// Unit tetrahedron, outward.
fn tetra() -> TriMesh {
    TriMesh::new(
        vec![p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.), p(0., 0., 1.)],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
}

/// The box from `o` with sides `s`.
fn cube_at(o: Point3<f64>, s: [f64; 3]) -> TriMesh {
    box_mesh(o, o + Vector3::from(s))
}

fn cube() -> TriMesh {
    cube_at(p(0., 0., 0.), [1., 1., 1.])
}

/// Torus of radii 3 and 1 about the origin as an n × m quad grid, wrapped both ways.
fn torus(n: usize, m: usize) -> TriMesh {
    primitives::torus(3.0, 1.0, n, m, Point3::origin())
}

/// Open cylinder (radius 1, length 6 along z): `rings` rings of `m` vertices, outward.
fn tube(rings: usize, m: usize) -> TriMesh {
    open_tube(1.0, 6.0, m, rings)
}

/// A 3 × 3 grid of unit squares in the plane z = 0 with the middle square missing, facing +z.
fn square_with_hole() -> TriMesh {
    let n = 3u32;
    let v = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| p(i as f64, j as f64, 0.0)))
        .collect();
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            if (i, j) == (1, 1) {
                continue;
            }
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            f.push([a, b, c]);
            f.push([a, c, d]);
        }
    }
    TriMesh::new(v, f)
}

/// Two outward tetrahedra touching at one vertex (a bowtie in 3D).
fn bowtie() -> TriMesh {
    let mut m = tetra();
    let mut other = tetra();
    for q in &mut other.vertices {
        *q = p(-q.x, -q.y, -q.z); // point reflection: reverses winding
    }
    other.flip_faces();
    let off = m.vertices.len() as u32;
    m.vertices.extend_from_slice(&other.vertices[1..]);
    m.faces.extend(
        other
            .faces
            .iter()
            .map(|f| f.map(|i| if i == 0 { 0 } else { i - 1 + off })),
    );
    m
}

/// The directed half-edges of all faces.
fn half_edges(m: &TriMesh) -> HashSet<(u32, u32)> {
    m.faces
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k], f[(k + 1) % 3])))
        .collect()
}

/// Asserts that each loop is closed under the rule "consecutive (u, v) is a face's half-edge u→v".
fn assert_loop_direction(m: &TriMesh, loops: &[Vec<u32>]) {
    let he = half_edges(m);
    for lp in loops {
        for k in 0..lp.len() {
            let (u, v) = (lp[k], lp[(k + 1) % lp.len()]);
            assert!(
                he.contains(&(u, v)),
                "loop step {u}→{v} is not a face half-edge"
            );
            assert!(
                !he.contains(&(v, u)),
                "loop edge {u}-{v} is not a boundary edge"
            );
        }
    }
}

/// Signed area of a loop projected on the xy plane.
fn loop_area_xy(m: &TriMesh, lp: &[u32]) -> f64 {
    let mut s = 0.0;
    for k in 0..lp.len() {
        let (a, b) = (
            m.vertices[lp[k] as usize],
            m.vertices[lp[(k + 1) % lp.len()] as usize],
        );
        s += a.x * b.y - b.x * a.y;
    }
    0.5 * s
}

#[test]
fn tetrahedron_and_cube_are_closed_outward_genus_zero() {
    for (name, m, e) in [("tetra", tetra(), 6), ("cube", cube(), 18)] {
        let map = EdgeMap::new(&m);
        assert_eq!(map.num_edges(), e, "{name}");
        assert_eq!(boundary_edges(&m), 0, "{name}");
        assert_eq!(non_manifold_edges(&m), 0, "{name}");
        assert_eq!(non_manifold_vertices(&m), 0, "{name}");
        assert!(is_consistently_oriented(&m), "{name}");
        assert_eq!(orientation(&m), Orientation::Outward, "{name}");
        assert_eq!(euler_characteristic(&m), 2, "{name}");
        assert_eq!(genus(&m), Some(0), "{name}");
        assert!(boundary_loops(&m).is_empty(), "{name}");
        let info = mesh_info(&m);
        assert!(info.watertight, "{name}");
        assert_eq!(info.components, 1);
        assert_eq!(info.genus, Some(0));
    }
}

#[test]
fn torus_has_genus_one() {
    let m = torus(24, 12);
    assert_eq!(euler_characteristic(&m), 0);
    assert_eq!(genus(&m), Some(1));
    assert_eq!(boundary_edges(&m), 0);
    assert!(is_consistently_oriented(&m));
    let info = mesh_info(&m);
    assert!(info.watertight);
    assert_eq!(
        (info.components, info.genus, info.euler_characteristic),
        (1, Some(1), 0)
    );
    // A torus and a cube: total genus 1 over two components, χ = 0 + 2.
    let mut two = torus(16, 8);
    two.append(&cube_at(p(10., 0., 0.), [1., 1., 1.]));
    assert_eq!(euler_characteristic(&two), 2);
    assert_eq!(genus(&two), Some(1));
}

/// Handles with the boundary loops counted as capped: an open tube has none, a torus one, and
/// still one with a face cut out of it (a hole: one boundary loop) or beside an open tube.
#[test]
fn handles_count_a_torus_with_a_hole_and_not_an_open_tube() {
    let tube = open_tube(1.0, 4.0, 16, 8);
    assert_eq!(genus(&tube), None);
    assert_eq!(handles(&tube), Some(0));
    let mut holed = torus(24, 12);
    holed.faces.remove(7);
    assert_eq!(boundary_loops(&holed).len(), 1);
    assert_eq!((genus(&holed), handles(&holed)), (None, Some(1)));
    let mut both = torus(16, 8);
    let mut far = open_tube(1.0, 4.0, 16, 8);
    far.vertices.iter_mut().for_each(|v| v.x += 20.0);
    both.append(&far);
    assert_eq!(handles(&both), Some(1));
    assert_eq!(handles(&torus(24, 12)), genus(&torus(24, 12)));
}

#[test]
fn two_disjoint_cubes_are_two_components() {
    let mut m = cube();
    m.append(&cube_at(p(5., 0., 0.), [2., 1., 1.]));
    let (n, labels) = connected_components(&m);
    assert_eq!(n, 2);
    assert!(labels[..12].iter().all(|&l| l == 0));
    assert!(labels[12..].iter().all(|&l| l == 1));
    assert_eq!(euler_characteristic(&m), 4);
    assert_eq!(genus(&m), Some(0));
    assert_eq!(orientation(&m), Orientation::Outward);
    let info = mesh_info(&m);
    assert_eq!(info.components, 2);
    assert!((info.volume.unwrap() - 3.0).abs() < 1e-12);
}

#[test]
fn open_tube_has_two_directed_boundary_loops() {
    let m = tube(7, 16);
    assert_eq!(boundary_edges(&m), 32);
    assert_eq!(orientation(&m), Orientation::Open);
    assert_eq!(genus(&m), None);
    assert_eq!(euler_characteristic(&m), 0);
    let loops = boundary_loops(&m);
    assert_eq!(loops.len(), 2);
    assert!(loops.iter().all(|l| l.len() == 16));
    assert_loop_direction(&m, &loops);
    // One loop is the bottom ring (indices < 16), the other the top ring.
    let mut rings: Vec<bool> = loops.iter().map(|l| l.iter().all(|&v| v < 16)).collect();
    rings.sort();
    assert_eq!(rings, [false, true]);
    let info = mesh_info(&m);
    assert!(!info.watertight);
    assert_eq!((info.boundary_loops, info.volume), (2, None));
}

#[test]
fn square_with_hole_has_outer_ccw_and_inner_cw_loops() {
    let m = square_with_hole();
    assert_eq!(euler_characteristic(&m), 0);
    let mut loops = boundary_loops(&m);
    loops.sort_by_key(|l| l.len());
    assert_eq!(loops.iter().map(|l| l.len()).collect::<Vec<_>>(), [4, 12]);
    assert_loop_direction(&m, &loops);
    // Faces point +z (counter-clockwise seen from above): the outer boundary runs counter-clockwise
    // and the hole clockwise.
    assert!((loop_area_xy(&m, &loops[1]) - 9.0).abs() < 1e-12);
    assert!((loop_area_xy(&m, &loops[0]) + 1.0).abs() < 1e-12);
    assert_eq!(orientation(&m), Orientation::Open);
}

#[test]
fn touching_holes_split_into_simple_loops() {
    // Two triangles sharing only vertex 0: one boundary vertex with two outgoing boundary edges.
    let m = TriMesh::new(
        vec![
            p(0., 0., 0.),
            p(1., 0., 0.),
            p(1., 1., 0.),
            p(-1., 0., 0.),
            p(-1., -1., 0.),
        ],
        vec![[0, 1, 2], [0, 3, 4]],
    );
    let loops = boundary_loops(&m);
    assert_eq!(loops.len(), 2);
    for l in &loops {
        assert_eq!(l.len(), 3);
        assert_eq!(
            l.iter().collect::<HashSet<_>>().len(),
            3,
            "loop not simple: {l:?}"
        );
    }
    assert_loop_direction(&m, &loops);
    assert_eq!(non_manifold_vertices(&m), 1);
}

#[test]
fn one_flipped_face_is_inconsistent_and_repaired() {
    for flipped in [0usize, 7] {
        let mut m = cube();
        m.faces[flipped].swap(1, 2);
        assert!(!is_consistently_oriented(&m));
        assert_eq!(orientation(&m), Orientation::Inconsistent);
        assert_eq!(genus(&m), Some(0), "still an orientable closed surface");
        let info = mesh_info(&m);
        assert!(!info.watertight);
        assert_eq!(info.volume, None);
        assert!(info.to_string().contains("inconsistent"));
        assert_eq!(orient_consistently(&mut m), 1, "flipped face {flipped}");
        assert_eq!(m, cube());
        assert_eq!(orientation(&m), Orientation::Outward);
        assert_eq!(orient_consistently(&mut m), 0);
    }
}

#[test]
fn flipped_cube_is_inward_and_orient_outward_fixes_it() {
    let mut m = cube();
    m.flip_faces();
    assert!(is_consistently_oriented(&m));
    assert_eq!(orientation(&m), Orientation::Inward);
    assert!(mesh_info(&m).watertight);
    assert!((mesh_info(&m).volume.unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(orient_outward(&mut m), 1);
    assert_eq!(orientation(&m), Orientation::Outward);
    assert!(signed_volume(&m) > 0.0);
    assert_eq!(orient_outward(&mut m), 0);

    // Two cubes facing opposite ways: the components disagree.
    let mut two = cube();
    let mut other = cube_at(p(3., 0., 0.), [1., 1., 1.]);
    other.flip_faces();
    two.append(&other);
    assert_eq!(orientation(&two), Orientation::Inconsistent);
    assert_eq!(orient_outward(&mut two), 1);
    assert_eq!(orientation(&two), Orientation::Outward);
    assert_eq!(two.faces[..12], cube().faces[..]);
}

#[test]
fn flipped_open_tube_is_turned_outward() {
    let mut m = tube(9, 20);
    let c = area_centroid(&m);
    assert!(signed_volume_about(&m, &c) > 0.0);
    assert_eq!(orient_outward(&mut m), 0);
    m.flip_faces();
    assert!(signed_volume_about(&m, &area_centroid(&m)) < 0.0);
    assert_eq!(orient_outward(&mut m), 1);
    assert!(signed_volume_about(&m, &area_centroid(&m)) > 0.0);
    assert_eq!(m, tube(9, 20));
}

#[test]
fn orient_consistently_repairs_a_scrambled_tube() {
    let good = tube(6, 12);
    let mut m = good.clone();
    let scrambled: Vec<usize> = (0..m.num_faces()).filter(|f| f % 3 == 1).collect();
    for &f in &scrambled {
        m.faces[f].swap(1, 2);
    }
    assert_eq!(orientation(&m), Orientation::Inconsistent);
    assert_eq!(orient_consistently(&mut m), scrambled.len());
    assert_eq!(m, good);
}

#[test]
fn mobius_strip_cannot_be_oriented() {
    // A Möbius band: 12 segments, the last joined to the first with a half twist.
    let n = 12u32;
    let mut v = Vec::new();
    for i in 0..n {
        let t = TAU * i as f64 / n as f64;
        for s in [-0.3, 0.3] {
            let (cx, cy) = (t.cos(), t.sin());
            let w = s * (t / 2.0).cos();
            v.push(p(cx * (1.0 + w), cy * (1.0 + w), s * (t / 2.0).sin()));
        }
    }
    let mut f = Vec::new();
    for i in 0..n {
        let (a, b) = (2 * i, 2 * i + 1);
        let (c, d) = if i + 1 < n {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        f.push([a, c, d]);
        f.push([a, d, b]);
    }
    let mut m = TriMesh::new(v, f);
    assert_eq!(non_manifold_edges(&m), 0);
    assert_eq!(
        boundary_loops(&m).len(),
        1,
        "a Möbius band has one boundary curve"
    );
    assert!(!is_consistently_oriented(&m));
    orient_consistently(&mut m);
    assert!(!is_consistently_oriented(&m));
    assert_eq!(genus(&m), None);
}

#[test]
fn three_triangles_on_one_edge_make_a_non_manifold_edge() {
    let m = TriMesh::new(
        vec![
            p(0., 0., 0.),
            p(1., 0., 0.),
            p(0., 1., 0.),
            p(0., -1., 0.),
            p(0., 0., 1.),
        ],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    );
    assert_eq!(non_manifold_edges(&m), 1);
    assert_eq!(boundary_edges(&m), 6);
    // The fin's end points are not counted as non-manifold vertices (documented convention).
    assert_eq!(non_manifold_vertices(&m), 0);
    let map = EdgeMap::new(&m);
    let e = map.edges().iter().position(|&e| e == [0, 1]).unwrap();
    assert_eq!(map.valence(e), 3);
    let info = mesh_info(&m);
    assert_eq!(info.non_manifold_edges, 1);
    assert!(!info.watertight);
    assert_eq!(info.genus, None);
}

#[test]
fn bowtie_vertex_is_non_manifold() {
    let m = bowtie();
    assert_eq!(m.num_vertices(), 7);
    assert_eq!(boundary_edges(&m), 0);
    assert_eq!(non_manifold_edges(&m), 0);
    assert_eq!(EdgeMap::new(&m).non_manifold_vertex_ids(), [0]);
    assert_eq!(orientation(&m), Orientation::Outward);
    let info = mesh_info(&m);
    assert_eq!(info.non_manifold_vertices, 1);
    assert_eq!(info.components, 1);
    assert!(!info.watertight);
    assert_eq!(info.volume, None);
    assert_eq!(info.genus, None);
    assert!(info.to_string().contains("1 non-manifold vertex"));
}

#[test]
fn orientation_serialises_lowercase() {
    for (o, s) in [
        (Orientation::Outward, "outward"),
        (Orientation::Inward, "inward"),
        (Orientation::Inconsistent, "inconsistent"),
        (Orientation::Open, "open"),
    ] {
        assert_eq!(serde_json::to_string(&o).unwrap(), format!("\"{s}\""));
        assert_eq!(o.to_string(), s);
    }
}

#[test]
fn empty_mesh_does_not_panic() {
    let m = TriMesh::default();
    let info = mesh_info(&m);
    assert_eq!((info.vertices, info.faces, info.components), (0, 0, 0));
    assert!(!info.watertight);
    assert_eq!(info.orientation, Orientation::Open);
    assert_eq!(info.genus, None);
    assert!(info.to_string().contains("no faces"));
    serde_json::to_string(&info).unwrap();
}
