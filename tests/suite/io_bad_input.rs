//! Bad input to the mesh readers and writers: each case must give the right error kind with the
//! file path and a word about the problem, never a panic, a huge allocation or a partial file.

use crate::common;
use common::*;
use rand::{rngs::StdRng, RngExt};
use std::path::Path;
use std::time::{Duration, Instant};
use vesselmsr::io::{read_mesh, write_atomic, write_mesh, write_mesh_with_scalars};
use vesselmsr::{Error, TriMesh};

/// Asserts a `Format` error whose message names the path and contains every word.
fn assert_format_error(
    result: vesselmsr::Result<impl std::fmt::Debug>,
    path: &Path,
    words: &[&str],
) {
    let err = result.expect_err("bad input was accepted");
    let text = err.to_string();
    assert!(matches!(err, Error::Format { .. }), "wrong kind: {err:?}");
    assert!(text.contains(path.to_str().unwrap()), "no path in: {text}");
    for w in words {
        assert!(text.contains(w), "'{w}' missing in: {text}");
    }
    assert!(!text.contains('\n'), "not one line: {text}");
}

fn read_error(dir: &Path, name: &str, bytes: &[u8], words: &[&str]) {
    let path = write_file(dir, name, bytes);
    assert_format_error(read_mesh(&path), &path, words);
}

/// Binary STL with a zeroed header declaring `n_declared` triangles.
fn zero_header_stl(n_declared: u32, triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    binary_stl(&[0; 80], n_declared, triangles)
}

fn tetra_triangles() -> Vec<[[f32; 3]; 3]> {
    let p = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
        .iter()
        .map(|t| t.map(|i| p[i]))
        .collect()
}

fn ascii_stl() -> String {
    let mut s = String::from("solid tetra\n");
    for t in tetra_triangles() {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for p in t {
            s += &format!("      vertex {} {} {}\n", p[0], p[1], p[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid tetra\n"
}

const OBJ_TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

fn ply_ascii_tetra(vertex_count: usize) -> String {
    format!(
        "ply\nformat ascii 1.0\nelement vertex {vertex_count}\nproperty float x\nproperty float y\nproperty float z\n\
         element face 4\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n"
    )
}

#[test]
fn missing_file_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nothing_here.stl");
    let err = read_mesh(&path).unwrap_err();
    assert!(
        matches!(&err, Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound),
        "{err:?}"
    );
    assert!(err.to_string().contains(path.to_str().unwrap()));
}

#[test]
fn unknown_extension_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path(), "mesh.off", b"OFF\n3 1 0\n");
    let err = read_mesh(&path).unwrap_err();
    assert!(matches!(err, Error::UnknownFormat { .. }), "{err:?}");
    let text = err.to_string();
    assert!(
        text.contains(path.to_str().unwrap()) && text.contains("unknown mesh format"),
        "{text}"
    );
    let err = write_mesh(&dir.path().join("out.off"), &TriMesh::default()).unwrap_err();
    assert!(matches!(err, Error::UnknownFormat { .. }), "{err:?}");
    assert_eq!(listing(dir.path()), ["mesh.off"]);
}

#[test]
fn empty_file_in_each_format() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["e.stl", "e.obj", "e.ply"] {
        read_error(dir.path(), name, b"", &["empty file"]);
    }
}

#[test]
fn binary_stl_claiming_four_billion_triangles_fails_fast() {
    let dir = tempfile::tempdir().unwrap();
    let start = Instant::now();
    read_error(
        dir.path(),
        "liar.stl",
        &zero_header_stl(u32::MAX, &tetra_triangles().repeat(3)),
        &["declares 4294967295 triangles", "holds only 12"],
    );
    // 4·10⁹ triangles would need hundreds of gigabytes: the size check comes first.
    assert!(
        start.elapsed() < Duration::from_secs(1),
        "took {:?}",
        start.elapsed()
    );
}

#[test]
fn truncated_binary_stl_whose_header_starts_with_solid() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = zero_header_stl(4, &tetra_triangles());
    bytes[..11].copy_from_slice(b"solid part ");
    bytes.truncate(84 + 50 * 3 + 20);
    read_error(
        dir.path(),
        "cut.stl",
        &bytes,
        &["declares 4 triangles", "holds only 3"],
    );
}

#[test]
fn binary_stl_shorter_than_its_header() {
    let dir = tempfile::tempdir().unwrap();
    read_error(dir.path(), "short.stl", &[7u8; 40], &["too short", "solid"]);
}

#[test]
fn truncated_ascii_stl() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_stl();
    let cut = text.find("endloop").unwrap();
    read_error(
        dir.path(),
        "cut.stl",
        &text.as_bytes()[..cut],
        &["truncated after line 6", "'endloop'"],
    );
    let wrong = text.replacen("endloop", "endlop", 1);
    read_error(
        dir.path(),
        "typo.stl",
        wrong.as_bytes(),
        &["line 7", "'endloop'", "'endlop'"],
    );
    let bad_number = text.replacen("vertex 1 0 0", "vertex 1 zero 0", 1);
    read_error(
        dir.path(),
        "nan.stl",
        bad_number.as_bytes(),
        &["not a number", "'zero'"],
    );
    let no_end = text.replace("endsolid tetra\n", "");
    read_error(
        dir.path(),
        "noend.stl",
        no_end.as_bytes(),
        &["truncated", "'endsolid'"],
    );
}

#[test]
fn non_finite_coordinates_in_stl() {
    let dir = tempfile::tempdir().unwrap();
    let mut t = tetra_triangles();
    t[1][2][1] = f32::NAN;
    read_error(
        dir.path(),
        "nan.stl",
        &zero_header_stl(4, &t),
        &["vertex 3", "non-finite", "NaN"],
    );
    let mut t = tetra_triangles();
    t[0][0][2] = f32::NEG_INFINITY;
    read_error(
        dir.path(),
        "inf.stl",
        &zero_header_stl(4, &t),
        &["vertex 0", "non-finite", "-inf"],
    );
    let text = ascii_stl().replacen("vertex 0 1 0", "vertex 0 inf 0", 1);
    read_error(
        dir.path(),
        "inf_ascii.stl",
        text.as_bytes(),
        &["non-finite", "inf"],
    );
}

#[test]
fn non_finite_coordinates_in_obj() {
    let dir = tempfile::tempdir().unwrap();
    let nan = OBJ_TETRA.replace("v 0 1 0", "v 0 NaN 0");
    read_error(
        dir.path(),
        "nan.obj",
        nan.as_bytes(),
        &["line 3", "vertex 3", "non-finite", "NaN"],
    );
    let inf = OBJ_TETRA.replace("v 0 0 1", "v 0 0 -inf");
    read_error(
        dir.path(),
        "inf.obj",
        inf.as_bytes(),
        &["line 4", "non-finite", "inf"],
    );
    let huge = OBJ_TETRA.replace("v 0 0 1", "v 0 0 1e999");
    read_error(
        dir.path(),
        "huge.obj",
        huge.as_bytes(),
        &["non-finite", "inf"],
    );
}

#[test]
fn obj_face_index_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{OBJ_TETRA}f 1 2 12\n");
    read_error(
        dir.path(),
        "range.obj",
        text.as_bytes(),
        &["line 9", "references vertex 12", "only 4 vertices"],
    );
    let text = format!("{OBJ_TETRA}f 1 2 99999999999999999999\n");
    read_error(
        dir.path(),
        "overflow.obj",
        text.as_bytes(),
        &["line 9", "not a vertex index"],
    );
    let text = format!("{OBJ_TETRA}f 1 2 18446744073709551\n");
    read_error(
        dir.path(),
        "beyond_u32.obj",
        text.as_bytes(),
        &["line 9", "references vertex 18446744073709551"],
    );
}

#[test]
fn obj_face_index_zero_or_negative_beyond_range() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{OBJ_TETRA}f 0 1 2\n");
    read_error(
        dir.path(),
        "zero.obj",
        text.as_bytes(),
        &["line 9", "index 0"],
    );
    let text = format!("{OBJ_TETRA}f -1 -2 -5\n");
    read_error(
        dir.path(),
        "neg.obj",
        text.as_bytes(),
        &["line 9", "vertex -5", "only 4 vertices precede"],
    );
    let text = format!("{OBJ_TETRA}f 1/-9 2/-9 3/-9\n");
    // Texture indices are ignored, so this is a valid extra triangle (tobj panicked here).
    let path = write_file(dir.path(), "vt.obj", text.as_bytes());
    assert_eq!(read_mesh(&path).unwrap().num_faces(), 5);
    let text = format!("{OBJ_TETRA}f 1 2\n");
    read_error(
        dir.path(),
        "two.obj",
        text.as_bytes(),
        &["line 9", "2 vertices"],
    );
}

#[test]
fn ply_element_count_larger_than_the_data() {
    let dir = tempfile::tempdir().unwrap();
    // ASCII: 4·10⁹ vertices cannot fit in a few dozen bytes.
    let start = Instant::now();
    read_error(
        dir.path(),
        "liar.ply",
        ply_ascii_tetra(4_000_000_000).as_bytes(),
        &["declares 4000000000 'vertex'"],
    );
    assert!(start.elapsed() < Duration::from_secs(1));
    // Plausible but too many: the data ends inside the face element.
    let text = ply_ascii_tetra(4).replace("element face 4", "element face 9");
    read_error(
        dir.path(),
        "short.ply",
        text.as_bytes(),
        &["ends early", "'face' element 4 of the 9"],
    );
    // Binary: 1000 vertices declared, 4 present.
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\n\
        property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    b.extend((0..12).flat_map(|i| (i as f32).to_le_bytes()));
    read_error(
        dir.path(),
        "short_bin.ply",
        &b,
        &["declares 1000 'vertex'", "at most 4"],
    );
}

#[test]
fn ply_malformed_headers_and_faces() {
    let dir = tempfile::tempdir().unwrap();
    let good = ply_ascii_tetra(4);
    read_error(
        dir.path(),
        "h1.ply",
        b"plx\nformat ascii 1.0\nend_header\n",
        &["not a PLY file"],
    );
    read_error(
        dir.path(),
        "h2.ply",
        good.replace("end_header\n", "").as_bytes(),
        &["end_header"],
    );
    read_error(
        dir.path(),
        "h3.ply",
        good.replace("ascii", "binary_middle_endian").as_bytes(),
        &["unknown format"],
    );
    read_error(
        dir.path(),
        "h4.ply",
        good.replace("property float z", "property real z")
            .as_bytes(),
        &["line 6", "type"],
    );
    read_error(
        dir.path(),
        "h5.ply",
        good.replace("property float z\n", "").as_bytes(),
        &["no scalar 'z'"],
    );
    read_error(
        dir.path(),
        "h6.ply",
        good.replace("vertex_indices", "corners").as_bytes(),
        &["vertex_indices"],
    );
    read_error(
        dir.path(),
        "f1.ply",
        good.replace("3 0 3 2", "3 0 -3 2").as_bytes(),
        &["face 3", "-3"],
    );
    read_error(
        dir.path(),
        "f2.ply",
        good.replace("3 0 3 2", "2 0 3 2").as_bytes(),
        &["face 3", "2 vertices"],
    );
    read_error(
        dir.path(),
        "f3.ply",
        good.replace("3 0 3 2", "3 0 9 2").as_bytes(),
        &["vertex 9", "only 4"],
    );
    read_error(
        dir.path(),
        "f4.ply",
        good.replace("0 1 0\n", "0 one 0\n").as_bytes(),
        &["line 12", "'one'"],
    );
    read_error(
        dir.path(),
        "f5.ply",
        good.replace("0 0 1\n", "0 0 nan\n").as_bytes(),
        &["vertex 3", "NaN"],
    );
}

#[test]
fn zero_triangles() {
    let dir = tempfile::tempdir().unwrap();
    read_error(
        dir.path(),
        "none.stl",
        &zero_header_stl(0, &[]),
        &["no triangles"],
    );
    read_error(
        dir.path(),
        "none.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\n",
        &["no triangles"],
    );
    read_error(
        dir.path(),
        "none2.obj",
        b"# nothing at all\n",
        &["no triangles"],
    );
    let ply = ply_ascii_tetra(4).replace("element face 4", "element face 0");
    read_error(dir.path(), "none.ply", ply.as_bytes(), &["no triangles"]);
    read_error(
        dir.path(),
        "ascii_none.stl",
        b"solid empty\nendsolid empty\n",
        &["no triangles"],
    );
}

#[test]
fn only_degenerate_triangles() {
    let dir = tempfile::tempdir().unwrap();
    // A repeated index, a collinear triple, and a triangle whose corners coincide.
    let text = "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 1 1 1\nf 1 2 2\nf 1 2 3\nf 2 4 3\n";
    read_error(
        dir.path(),
        "flat.obj",
        text.as_bytes(),
        &["all 3 triangles are degenerate"],
    );
    let p = [0.5f32, 0.5, 0.5];
    read_error(
        dir.path(),
        "point.stl",
        &zero_header_stl(2, &[[p, p, p], [p, [1.0; 3], p]]),
        &["all 2", "degenerate"],
    );
    // One good triangle among degenerate ones is enough.
    let path = write_file(
        dir.path(),
        "ok.obj",
        format!("{text}v 0 1 0\nf 1 2 5\n").as_bytes(),
    );
    assert_eq!(read_mesh(&path).unwrap().num_faces(), 4);
}

fn tetra_mesh() -> TriMesh {
    let path_dir = tempfile::tempdir().unwrap();
    let path = write_file(path_dir.path(), "t.obj", OBJ_TETRA.as_bytes());
    read_mesh(&path).unwrap()
}

#[test]
fn writing_into_a_missing_folder_fails_without_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no/such/folder/out.stl");
    let err = write_mesh(&path, &tetra_mesh()).unwrap_err();
    assert!(matches!(err, Error::Io { .. }), "{err:?}");
    assert!(err.to_string().contains(path.to_str().unwrap()), "{err}");
    assert!(!path.exists());
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn a_write_that_fails_midway_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.json");
    let result = write_atomic(&path, |w| {
        w.write_all(&vec![b'x'; 100_000]).unwrap();
        Err(Error::Geometry("stopped halfway".into()))
    });
    assert!(matches!(result, Err(Error::Geometry(_))), "{result:?}");
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
}

#[test]
fn an_existing_file_is_replaced_only_on_success() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path(), "out.obj", b"old contents");
    let failed = write_atomic(&path, |w| {
        w.write_all(b"new contents, half").unwrap();
        Err(Error::Geometry("no".into()))
    });
    assert!(failed.is_err());
    assert_eq!(std::fs::read(&path).unwrap(), b"old contents");
    // A mesh with an index out of range is refused, naming the file, before anything is written.
    let mut bad = tetra_mesh();
    bad.faces.push([0, 1, 7]);
    let err = write_mesh(&path, &bad).unwrap_err();
    assert!(
        matches!(&err, Error::Format { path: p, message } if p == &path && message.contains("vertex 7")),
        "{err:?}"
    );
    assert_eq!(std::fs::read(&path).unwrap(), b"old contents");
    write_mesh(&path, &tetra_mesh()).unwrap();
    assert_eq!(read_mesh(&path).unwrap(), tetra_mesh());
    assert_eq!(listing(dir.path()), ["out.obj"]);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // The same permissions as any new file (the temporary file alone would be 0600).
        let plain = write_file(dir.path(), "plain", b"");
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode();
        assert_eq!(mode(&path), mode(&plain), "{:o}", mode(&path));
    }
}

#[test]
fn bad_scalar_fields_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = tetra_mesh();
    let four = [1.0f32; 4];
    let path = dir.path().join("s.stl");
    assert_format_error(
        write_mesh_with_scalars(&path, &mesh, &[("a", &four)]),
        &path,
        &[".ply"],
    );
    let path = dir.path().join("s.ply");
    assert_format_error(
        write_mesh_with_scalars(&path, &mesh, &[("a", &four[..3])]),
        &path,
        &["3 values", "4 vertices"],
    );
    assert_format_error(
        write_mesh_with_scalars(&path, &mesh, &[("my field", &four)]),
        &path,
        &["identifier"],
    );
    assert_format_error(
        write_mesh_with_scalars(&path, &mesh, &[("x", &four)]),
        &path,
        &["'x'"],
    );
    assert_format_error(
        write_mesh_with_scalars(&path, &mesh, &[("a", &four), ("a", &four)]),
        &path,
        &["twice"],
    );
    assert!(listing(dir.path()).is_empty());
}

/// Reads `bytes` as `name` after every cut and after seeded random byte changes: the reader may
/// accept or refuse but must not panic.
fn survives_damage(dir: &Path, name: &str, bytes: &[u8], rng: &mut StdRng) -> (usize, usize) {
    let mut outcomes = (0, 0);
    let mut tries = 0;
    let mut try_read = |data: &[u8], what: &str| {
        // A fresh name each time: rewriting one file makes ext4 flush it on every close.
        tries += 1;
        let path = dir.join(format!("{tries}-{name}"));
        std::fs::write(&path, data).unwrap();
        let result = std::panic::catch_unwind(|| read_mesh(&path));
        std::fs::remove_file(&path).unwrap();
        match result {
            Ok(Ok(_)) => outcomes.0 += 1,
            Ok(Err(e)) => {
                assert!(e.to_string().contains(path.to_str().unwrap()));
                outcomes.1 += 1
            }
            Err(_) => panic!("{name}: reader panicked on {what}"),
        }
    };
    for cut in 0..=bytes.len() {
        try_read(&bytes[..cut], &format!("the first {cut} bytes"));
    }
    let interesting = b"0123456789 \n-+.eE/#naifv\x00\xff";
    for round in 0..300 {
        let mut damaged = bytes.to_vec();
        for _ in 0..rng.random_range(1..4) {
            let at = rng.random_range(0..damaged.len());
            damaged[at] = if rng.random_bool(0.5) {
                interesting[rng.random_range(0..interesting.len())]
            } else {
                rng.random()
            };
        }
        try_read(&damaged, &format!("random damage round {round}"));
    }
    outcomes
}

#[test]
fn damaged_files_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = rng(20240611);
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("binary.stl", zero_header_stl(4, &tetra_triangles())),
        ("ascii.stl", ascii_stl().into_bytes()),
        ("tetra.obj", OBJ_TETRA.as_bytes().to_vec()),
        ("ascii.ply", ply_ascii_tetra(4).into_bytes()),
    ];
    // A binary PLY of the tetrahedron, written by the library (little-endian, double, int).
    let ply_path = dir.path().join("source.ply");
    write_mesh(&ply_path, &tetra_mesh()).unwrap();
    let ply_binary = std::fs::read(&ply_path).unwrap();
    let mut all = cases;
    all.push(("binary.ply", ply_binary));
    for (name, bytes) in &all {
        let (ok, refused) = survives_damage(dir.path(), name, bytes, &mut rng);
        // The whole file is accepted, most damaged versions are refused.
        assert!(
            ok >= 1 && refused > bytes.len() / 2,
            "{name}: {ok} accepted, {refused} refused"
        );
    }
}
