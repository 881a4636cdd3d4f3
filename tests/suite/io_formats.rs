//! Reading and writing STL, OBJ and PLY: round trips, the format variants met in practice (ASCII
//! STL, binary STL with a "solid" header, OBJ polygons and objects, PLY in all three encodings with
//! extra properties and elements), scalar fields, and the real meshes of ../shared/data/real.

use crate::common;
use common::*;
use nalgebra::Point3;
use std::path::Path;
use std::time::Instant;
use vesselmsr::io::{read_mesh, read_ply_scalars, write_mesh, write_mesh_with_scalars, MeshFormat};
use vesselmsr::TriMesh;

/// The unit cube as binary STL triangles.
fn cube_triangles() -> Vec<[[f32; 3]; 3]> {
    stl_triangles(&cube(0.0, 1.0))
}

/// Every triangle of `b` has the same corners as the same triangle of `a`, within `tol`.
fn assert_same_triangles(a: &TriMesh, b: &TriMesh, tol: f64) {
    assert_eq!(a.num_faces(), b.num_faces());
    for f in 0..a.num_faces() {
        for (p, q) in a.triangle(f).iter().zip(b.triangle(f).iter()) {
            assert!(
                (p - q).norm() <= tol * (1.0 + p.coords.norm()),
                "triangle {f}: {p} vs {q}"
            );
        }
    }
}

#[test]
fn obj_round_trip_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = odd_octahedron();
    let path = dir.path().join("m.obj");
    write_mesh(&path, &mesh).unwrap();
    assert_eq!(read_mesh(&path).unwrap(), mesh);
}

#[test]
fn ply_round_trip_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = odd_octahedron();
    let path = dir.path().join("m.ply");
    write_mesh(&path, &mesh).unwrap();
    assert_eq!(read_mesh(&path).unwrap(), mesh);
}

#[test]
fn stl_round_trip_is_within_f32() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = odd_octahedron();
    let path = dir.path().join("m.stl");
    write_mesh(&path, &mesh).unwrap();
    let back = read_mesh(&path).unwrap();
    assert_eq!(back.num_vertices(), mesh.num_vertices());
    assert_same_triangles(&mesh, &back, 1e-7);
    // The stored facet normal is the unit normal of the triangle.
    let bytes = std::fs::read(&path).unwrap();
    assert!(!bytes.starts_with(b"solid"));
    assert_eq!(bytes.len(), 84 + 50 * 8);
    let n: Vec<f32> = (0..3)
        .map(|c| f32::from_le_bytes(bytes[84 + 4 * c..88 + 4 * c].try_into().unwrap()))
        .collect();
    let expected = mesh.face_normal_raw(0).normalize();
    for c in 0..3 {
        assert!(
            (n[c] as f64 - expected[c]).abs() < 1e-6,
            "normal {n:?} vs {expected}"
        );
    }
}

#[test]
fn ascii_stl_is_read_and_welded() {
    let dir = tempfile::tempdir().unwrap();
    // A tetrahedron; the origin appears as 0, -0.0 and 0e0, which must weld into one vertex.
    let text = "solid tetra made by hand\n\
        facet normal 0 0 -1\n  outer loop\n    vertex 0 0 0\n    vertex 0 1 0\n    vertex 1 0 0\n  endloop\nendfacet\n\
        facet normal 0 -1 0\n outer loop\n vertex -0.0 0 0\n vertex 1 0 0\n vertex 0 0 1\n endloop\n endfacet\n\
        FACET NORMAL -1 0 0 OUTER LOOP VERTEX 0e0 0 0 VERTEX 0 0 1 VERTEX 0 1 0 ENDLOOP ENDFACET\n\
        \tfacet normal 0.577 0.577 0.577\r\n\touter loop\r\n\tvertex 1 0 0\r\n\tvertex 0 1 0\r\n\tvertex 0 0 1.5e-1\r\n\tendloop\r\n\tendfacet\r\n\
        endsolid tetra made by hand\n";
    let path = write_file(dir.path(), "tetra.stl", text.as_bytes());
    let mesh = read_mesh(&path).unwrap();
    assert_eq!(mesh.num_faces(), 4);
    // (0,0,1) and (0,0,0.15) differ, so 5 distinct points.
    assert_eq!(mesh.num_vertices(), 5);
    assert_eq!(mesh.faces[0], [0, 1, 2]);
    assert_eq!(mesh.faces[1], [0, 2, 3]);
    assert_eq!(mesh.faces[2], [0, 3, 1]);
    assert_eq!(mesh.vertices[4], Point3::new(0.0, 0.0, 0.15));
}

#[test]
fn ascii_stl_with_several_solids_is_merged() {
    let dir = tempfile::tempdir().unwrap();
    let facet = |z: f64| {
        format!("facet normal 0 0 1\nouter loop\nvertex 0 0 {z}\nvertex 1 0 {z}\nvertex 0 1 {z}\nendloop\nendfacet\n")
    };
    let text = format!(
        "solid a\n{}endsolid a\nsolid b\n{}{}endsolid b\n",
        facet(0.0),
        facet(1.0),
        facet(2.0)
    );
    let path = write_file(dir.path(), "two.stl", text.as_bytes());
    let mesh = read_mesh(&path).unwrap();
    assert_eq!((mesh.num_vertices(), mesh.num_faces()), (9, 3));
}

#[test]
fn binary_stl_whose_header_starts_with_solid() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = binary_stl(
        &stl_header("solid exported by some CAD tool"),
        12,
        &cube_triangles(),
    );
    let path = write_file(dir.path(), "cube.stl", &bytes);
    let mesh = read_mesh(&path).unwrap();
    assert_eq!((mesh.num_vertices(), mesh.num_faces()), (8, 12));
}

#[test]
fn binary_stl_with_padding_after_the_last_triangle() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = binary_stl(&stl_header("padded"), 12, &cube_triangles());
    bytes.extend_from_slice(&[0u8; 30]);
    let path = write_file(dir.path(), "padded.stl", &bytes);
    let mesh = read_mesh(&path).unwrap();
    assert_eq!((mesh.num_vertices(), mesh.num_faces()), (8, 12));
}

#[test]
fn stl_cube_welds_to_8_vertices() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(
        dir.path(),
        "cube.stl",
        &binary_stl(&stl_header("cube"), 12, &cube_triangles()),
    );
    let mesh = read_mesh(&path).unwrap();
    assert_eq!((mesh.num_vertices(), mesh.num_faces()), (8, 12));
    // Welding keeps the triangles: each has the corners it had in the file.
    assert_same_triangles(&cube(0.0, 1.0), &mesh, 0.0);
    // Every vertex is shared by several triangles (12·3 corners on 8 vertices).
    let mut uses = vec![0; 8];
    mesh.faces
        .iter()
        .flatten()
        .for_each(|&i| uses[i as usize] += 1);
    assert!(uses.iter().all(|&u| u >= 3), "{uses:?}");
}

#[test]
fn obj_quads_and_pentagon_are_triangulated() {
    let dir = tempfile::tempdir().unwrap();
    let text = "# cube of quads and a pentagon\nmtllib none.mtl\no cube\n\
        v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
        vt 0 0\nvt 1 0\nvn 0 0 1\ns off\nusemtl red\n\
        f 1 3 4 2\nf 5/1 6/2 8/1 7/2\nf 1//1 2//1 6//1 5//1\nf 3/1/1 7/1/1 8/1/1 4/1/1\nf 1 5 7 3\nf 2 4 8 6 # comment\n\
        o pentagon\nv 3 0 0\nv 4 0 0\nv 4.5 1 0\nv 3.5 2 0\nv 2.5 1 0\n\
        f -5 -4 -3 -2 -1\nl 9 10\n";
    let path = write_file(dir.path(), "poly.obj", text.as_bytes());
    let mesh = read_mesh(&path).unwrap();
    assert_eq!(mesh.num_vertices(), 13);
    assert_eq!(mesh.num_faces(), 6 * 2 + 3);
    assert_eq!(mesh.faces[0], [0, 2, 3]);
    assert_eq!(mesh.faces[1], [0, 3, 1]);
    // The pentagon is a fan from its first corner, vertex 9 (0-based 8).
    assert_eq!(&mesh.faces[12..], &[[8, 9, 10], [8, 10, 11], [8, 11, 12]]);
}

#[test]
fn obj_several_objects_merge_into_one_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let text = "o first\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\
        g second\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 4 5 6\n\
        o third\nv 9 9 9\nf 7 4 6\n";
    let path = write_file(dir.path(), "objects.obj", text.as_bytes());
    let mesh = read_mesh(&path).unwrap();
    assert_eq!((mesh.num_vertices(), mesh.num_faces()), (7, 3));
    assert_eq!(mesh.faces, vec![[0, 1, 2], [3, 4, 5], [6, 3, 5]]);
    assert_eq!(mesh.vertices[3], Point3::new(5.0, 0.0, 0.0));
}

/// The cube [0.3, 0.4]³ as quads (the two triangles of each side of `cube` joined), written as
/// PLY with normals and colors on the vertices, a face flag and a texture-coordinate list beside
/// the indices, and an extra `edge` element before the faces. 0.3 and 0.4 are not f32 values, so
/// float and double storage differ.
fn cube_quads() -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
    let m = cube(0.3, 0.4);
    let v = m.vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
    let quads = m
        .faces
        .chunks_exact(2)
        .map(|t| {
            assert_eq!((t[0][0], t[0][2]), (t[1][0], t[1][1]), "a quad's fan");
            [t[0][0], t[0][1], t[0][2], t[1][2]]
        })
        .collect();
    (v, quads)
}

fn ply_ascii_cube() -> String {
    let (v, q) = cube_quads();
    let mut s = String::from(
        "ply\r\nformat ascii 1.0\ncomment made by hand\nobj_info nothing\nelement vertex 8\n\
         property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n\
         property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element edge 2\nproperty int vertex1\nproperty int vertex2\nproperty list uchar float weights\n\
         element face 6\nproperty uchar flags\nproperty list uchar int vertex_indices\n\
         property list uchar float texcoord\nend_header\n",
    );
    for p in &v {
        s += &format!("{} {} {} 0 0 1 255 128 0\n", p[0], p[1], p[2]);
    }
    s += "0 1 2 0.5 0.25\n2 3 0\n";
    for f in &q {
        s += &format!(
            "7 4 {} {} {} {} 8 0 0 1 0 1 1 0 1\n",
            f[0], f[1], f[2], f[3]
        );
    }
    s
}

/// The same cube in binary; `big` picks the byte order. x and y are double, z is float; indices
/// are uint with a ushort count.
fn ply_binary_cube(big: bool) -> Vec<u8> {
    let (v, q) = cube_quads();
    let order = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = format!(
        "ply\nformat {order} 1.0\nelement vertex 8\nproperty double x\nproperty char tag\n\
         property double y\nproperty float z\nproperty list uchar short junk\nproperty uchar red\n\
         element edge 2\nproperty int vertex1\nproperty int vertex2\n\
         element face 6\nproperty list ushort uint vertex_indices\nproperty float quality\nend_header\n"
    )
    .into_bytes();
    macro_rules! put {
        ($x:expr) => {
            b.extend_from_slice(&if big {
                $x.to_be_bytes()
            } else {
                $x.to_le_bytes()
            })
        };
    }
    for p in &v {
        put!(p[0]);
        put!(-3i8);
        put!(p[1]);
        put!(p[2] as f32);
        put!(2u8);
        put!(-7i16);
        put!(300i16);
        put!(200u8);
    }
    for e in [[0i32, 1], [2, 3]] {
        put!(e[0]);
        put!(e[1]);
    }
    for f in &q {
        put!(4u16);
        for &i in f {
            put!(i);
        }
        put!(0.5f32);
    }
    b
}

fn assert_is_quad_cube(mesh: &TriMesh, z_is_f32: bool) {
    let (v, q) = cube_quads();
    assert_eq!((mesh.num_vertices(), mesh.num_faces()), (8, 12));
    // ASCII values are taken as written; binary ones with their declared type.
    for (p, e) in mesh.vertices.iter().zip(&v) {
        assert_eq!((p.x, p.y), (e[0], e[1]));
        assert_eq!(p.z, if z_is_f32 { e[2] as f32 as f64 } else { e[2] });
    }
    for (k, f) in q.iter().enumerate() {
        assert_eq!(mesh.faces[2 * k], [f[0], f[1], f[2]]);
        assert_eq!(mesh.faces[2 * k + 1], [f[0], f[2], f[3]]);
    }
}

#[test]
fn ply_ascii_with_quads_and_extra_properties() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path(), "cube.ply", ply_ascii_cube().as_bytes());
    assert_is_quad_cube(&read_mesh(&path).unwrap(), false);
    // The other vertex scalars come back as fields, in header order.
    let (_, fields) = read_ply_scalars(&path).unwrap();
    let names: Vec<&str> = fields.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["nx", "ny", "nz", "red", "green", "blue"]);
    assert_eq!(fields[3].1, vec![255.0; 8]);
    assert_eq!(fields[4].1, vec![128.0; 8]);
}

#[test]
fn ply_binary_little_endian_with_quads_and_extra_properties() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path(), "cube.ply", &ply_binary_cube(false));
    assert_is_quad_cube(&read_mesh(&path).unwrap(), true);
    let (_, fields) = read_ply_scalars(&path).unwrap();
    assert_eq!(
        fields,
        vec![
            ("tag".to_string(), vec![-3.0; 8]),
            ("red".to_string(), vec![200.0; 8])
        ]
    );
}

#[test]
fn ply_binary_big_endian_with_quads_and_extra_properties() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path(), "cube.ply", &ply_binary_cube(true));
    assert_is_quad_cube(&read_mesh(&path).unwrap(), true);
}

#[test]
fn extensions_are_case_insensitive() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = odd_octahedron();
    for name in ["a.STL", "b.Obj", "c.PlY", "d.sTl"] {
        let path = dir.path().join(name);
        write_mesh(&path, &mesh).unwrap();
        assert_eq!(read_mesh(&path).unwrap().num_faces(), 8, "{name}");
    }
    assert_eq!(
        MeshFormat::from_path(Path::new("x/y.OBJ")).unwrap(),
        MeshFormat::Obj
    );
    assert_eq!(
        MeshFormat::from_path(Path::new("y.Ply")).unwrap(),
        MeshFormat::Ply
    );
    assert_eq!(
        MeshFormat::from_path(Path::new("y.stl")).unwrap(),
        MeshFormat::Stl
    );
    assert!(MeshFormat::from_path(Path::new("y.stl.gz")).is_err());
    assert!(MeshFormat::from_path(Path::new("stl")).is_err());
}

#[test]
fn ply_scalars_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = odd_octahedron();
    let detail: Vec<f32> = (0..6).map(|i| i as f32 * 0.37 - 1.0).collect();
    let label: Vec<f32> = vec![0.0, 1.0, 1.0, 2.0, f32::MAX, -0.5];
    let path = dir.path().join("fields.ply");
    write_mesh_with_scalars(&path, &mesh, &[("detail", &detail), ("label_2", &label)]).unwrap();
    let (back, fields) = read_ply_scalars(&path).unwrap();
    assert_eq!(back, mesh);
    assert_eq!(
        fields,
        vec![
            ("detail".to_string(), detail),
            ("label_2".to_string(), label)
        ]
    );
    // read_mesh skips the fields.
    assert_eq!(read_mesh(&path).unwrap(), mesh);
}

#[test]
fn real_meshes_read_with_documented_counts_and_survive_every_format() {
    let Some(dir) = real_dir() else { return };
    let out = tempfile::tempdir().unwrap();
    for (name, v, f, ..) in REAL_MESHES {
        let start = Instant::now();
        let mesh = read_mesh(&dir.join(name)).unwrap();
        let took = start.elapsed();
        println!(
            "{name}: {} vertices, {} triangles, read in {:.1} ms",
            mesh.num_vertices(),
            mesh.num_faces(),
            took.as_secs_f64() * 1e3
        );
        assert_eq!((mesh.num_vertices(), mesh.num_faces()), (v, f), "{name}");
        for ext in ["stl", "obj", "ply"] {
            let path = out.path().join(format!("copy.{ext}"));
            write_mesh(&path, &mesh).unwrap();
            let back = read_mesh(&path).unwrap();
            assert_eq!(
                (back.num_vertices(), back.num_faces()),
                (v, f),
                "{name} via {ext}"
            );
            // The files hold f32 values, so every format gives back exactly the same mesh.
            assert_eq!(back, mesh, "{name} via {ext}");
        }
    }
}
