//! Every command on a corpus of damaged inputs under a 2 GiB address-space limit (`ulimit -v`):
//! no panic, no abort, no signal, exit status 0 or 2, and no file left behind on a failure (nor a
//! staging folder on success). Issue 22's acceptance test.

use crate::common;
use common::*;
use std::io::Write;
use std::path::{Path, PathBuf};
use vesselmsr::io::write_mesh;

/// The address-space limit, KiB (2 GiB).
const LIMIT_KIB: u64 = 2 << 20;

/// Damaged (and a few odd but valid) mesh files in `dir`.
fn mesh_corpus(dir: &Path) -> Vec<PathBuf> {
    let tris = stl_triangles(&odd_octahedron());
    let header = [0u8; 80];
    let mut files = vec![
        write_file(dir, "empty.stl", b""),
        write_file(dir, "garbage.stl", &(0..3000u32).map(|i| (i * 7919 % 251) as u8).collect::<Vec<_>>()),
        write_file(dir, "short.stl", &binary_stl(&header, 12, &tris[..3])),
        write_file(dir, "count_mismatch.stl", &binary_stl(&header, 1, &tris)),
        write_file(dir, "claims_a_billion.stl", &binary_stl(&header, 1_000_000_000, &tris)),
        write_file(dir, "nan.stl", &binary_stl(&header, 1, &[[[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])),
        write_file(dir, "degenerate.stl", &binary_stl(&header, 1, &[[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]])),
        write_file(dir, "truncated_ascii.stl", b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"),
        write_file(dir, "control\x1b.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \x1b9\n"),
        write_file(dir, "index.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999\n"),
        write_file(dir, "ply_header.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n"),
        write_file(dir, "one_triangle.stl", &binary_stl(&header, 1, &tris[..1])),
    ];
    let mut huge = odd_octahedron();
    huge.vertices.iter_mut().for_each(|p| *p *= 1e39);
    let path = dir.join("huge.obj");
    write_mesh(&path, &huge).unwrap();
    files.push(path);
    let closed = odd_octahedron();
    let soup = soup_of(&closed);
    let path = dir.join("soup.obj");
    write_mesh(&path, &soup).unwrap();
    files.push(path);
    files
}

/// Damaged `.npz` archives in `dir`.
fn archive_corpus(dir: &Path) -> Vec<PathBuf> {
    let member = |name: &str, dict: &str, data: &[u8]| {
        let path = dir.join(name);
        let mut zip = zip::ZipWriter::new(std::fs::File::create(&path).unwrap());
        zip.start_file("phi.npy", zip::write::SimpleFileOptions::default())
            .unwrap();
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        b.extend_from_slice(dict.as_bytes());
        b.extend_from_slice(data);
        zip.write_all(&b).unwrap();
        zip.finish().unwrap();
        path
    };
    vec![
        member(
            "shape_paren.npz",
            "{'descr': '<f4', 'fortran_order': False, 'shape': ), }",
            &[0; 8],
        ),
        member(
            "multibyte.npz",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (é,), }",
            &[0; 8],
        ),
        member(
            "huge_phi.npz",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (4096, 4096, 4096), }",
            &[0; 64],
        ),
        write_file(dir, "not_zip.npz", b"PK\x03\x04 not really"),
        write_file(dir, "empty.npz", b""),
    ]
}

/// Runs the binary under the address-space limit; returns (exit code, stderr). Panics on a
/// signal.
fn run_limited(args: &[&str]) -> (i32, String) {
    let out = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!("ulimit -v {LIMIT_KIB} && exec \"$@\""))
        .arg("vesselmsr")
        .arg(env!("CARGO_BIN_EXE_vesselmsr"))
        .args(args)
        .output()
        .expect("bash runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let code = out
        .status
        .code()
        .unwrap_or_else(|| panic!("{args:?} ended by a signal: {:?}\n{stderr}", out.status));
    (code, stderr)
}

#[test]
fn every_command_on_damaged_inputs_under_2_gib() {
    let dir = tempfile::tempdir().unwrap();
    let corpus = dir.path().join("corpus");
    std::fs::create_dir(&corpus).unwrap();
    let meshes = mesh_corpus(&corpus);
    let archives = archive_corpus(&corpus);
    let outputs = dir.path().join("out");
    let grid = ["--resolution", "24"];
    let mut runs = 0;
    let mut check = |args: Vec<String>| {
        std::fs::create_dir(&outputs).unwrap();
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, stderr) = run_limited(&argv);
        assert!(code == 0 || code == 2, "{argv:?}: exit {code}\n{stderr}");
        assert!(!stderr.contains("panicked"), "{argv:?}: {stderr}");
        let left: Vec<String> = std::fs::read_dir(&outputs)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        if code == 2 {
            assert!(
                left.is_empty(),
                "{argv:?} failed and left {left:?}: {stderr}"
            );
            let errors = stderr
                .lines()
                .filter(|l| l.starts_with("vesselmsr: error: "))
                .count();
            assert_eq!(errors, 1, "{argv:?}: {stderr}");
        }
        assert!(
            !left.iter().any(|n| n.starts_with('.')),
            "{argv:?} left {left:?}"
        );
        std::fs::remove_dir_all(&outputs).unwrap();
        runs += 1;
    };
    let o = |name: &str| outputs.join(name).to_str().unwrap().to_string();
    for mesh in &meshes {
        let m = mesh.to_str().unwrap().to_string();
        let with_grid = |mut v: Vec<String>| {
            v.extend(grid.iter().map(|s| s.to_string()));
            v
        };
        let commands: Vec<Vec<String>> = vec![
            vec!["info".into(), m.clone()],
            vec!["cap".into(), m.clone(), "-o".into(), o("c.stl")],
            vec![
                "compare".into(),
                m.clone(),
                aorta(),
                "--samples".into(),
                "1000".into(),
            ],
            with_grid(vec![
                "voxelize".into(),
                m.clone(),
                "-o".into(),
                o("phi.npy"),
            ]),
            with_grid(vec!["remesh".into(), m.clone(), "-o".into(), o("r.stl")]),
            with_grid(vec![
                "evolve".into(),
                m.clone(),
                "-o".into(),
                o("e.stl"),
                "--velocity".into(),
                "mcf".into(),
                "--time".into(),
                "0.01".into(),
            ]),
            with_grid(vec![
                "decompose".into(),
                m.clone(),
                "-o".into(),
                o("m.npz"),
                "--levels".into(),
                "1".into(),
            ]),
            with_grid(vec![
                "centerline".into(),
                m.clone(),
                "-o".into(),
                o("cl.json"),
            ]),
            vec!["stenosis".into(), m.clone()],
            vec!["profile".into(), m.clone(), "-o".into(), o("p.csv")],
            vec![
                "repair".into(),
                m.clone(),
                "--holes".into(),
                "-o".into(),
                o("h.stl"),
                "--report".into(),
                o("h.json"),
            ],
        ];
        for c in commands {
            check(c);
        }
    }
    for archive in &archives {
        let a = archive.to_str().unwrap().to_string();
        for method in ["vertices", "levelset"] {
            check(vec![
                "reconstruct".into(),
                a.clone(),
                "--method".into(),
                method.into(),
                "-o".into(),
                o("x.stl"),
            ]);
        }
    }
    println!("{runs} runs under ulimit -v {LIMIT_KIB} KiB");
    assert_eq!(runs, meshes.len() * 11 + archives.len() * 2);
}
