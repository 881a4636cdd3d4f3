//! Bad input through the CLI: one line on stderr naming the file and the problem, exit status 2,
//! no output file, no panic.

use crate::common;
use common::*;
use std::path::{Path, PathBuf};

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// (name, contents, a word the message must contain)
fn bad_files() -> Vec<(&'static str, Vec<u8>, &'static str)> {
    vec![
        ("empty.stl", vec![], "empty"),
        ("empty.obj", vec![], ""),
        ("empty.ply", vec![], ""),
        ("unknown.xyz", b"1 2 3\n".to_vec(), "format"),
        (
            "claims_more.stl",
            binary_stl(&[0; 80], 1_000_000_000, &[TRI]),
            "1000000000",
        ),
        (
            "truncated_ascii.stl",
            b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n".to_vec(),
            "",
        ),
        (
            "nan.stl",
            binary_stl(
                &[0; 80],
                1,
                &[[[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]],
            ),
            "",
        ),
        (
            "inf.obj",
            b"v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
            "",
        ),
        (
            "index_out_of_range.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n".to_vec(),
            "9",
        ),
        (
            "no_triangles.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\n".to_vec(),
            "triangle",
        ),
        ("no_triangles.stl", binary_stl(&[0; 80], 0, &[]), "triangle"),
        (
            "degenerate.stl",
            binary_stl(&[0; 80], 1, &[[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]]),
            "degenerate",
        ),
    ]
}

fn assert_clean_failure(args: &[&str], file: &Path, word: &str, output: Option<&PathBuf>) {
    let out = vesselmsr(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{args:?}: exit status; stderr: {stderr}"
    );
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "{args:?}: one line expected, got: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    let name = file.file_name().unwrap().to_str().unwrap();
    assert!(
        stderr.contains(name),
        "{args:?}: message does not name the file: {stderr}"
    );
    assert!(
        stderr.to_lowercase().contains(&word.to_lowercase()),
        "{args:?}: message lacks {word:?}: {stderr}"
    );
    if let Some(o) = output {
        assert!(!o.exists(), "{args:?}: an output file was left behind");
        let leftovers: Vec<_> = std::fs::read_dir(o.parent().unwrap()).unwrap().collect();
        assert!(
            leftovers.is_empty(),
            "{args:?}: files left in the output folder: {leftovers:?}"
        );
    }
    println!("{args:?} -> {}", stderr.trim_end());
}

#[test]
fn bad_inputs_fail_cleanly_in_info_cap_and_compare() {
    let tmp = tempfile::tempdir().unwrap();
    let good = data_dir().join("aorta_abdominal_open_ends.stl");
    for (name, contents, word) in bad_files() {
        let path = write_file(tmp.path(), name, &contents);
        let p = path.to_str().unwrap();
        assert_clean_failure(&["info", p], &path, word, None);
        assert_clean_failure(&["info", "--json", p], &path, word, None);
        let outdir = tempfile::tempdir().unwrap();
        let out = outdir.path().join("out.stl");
        assert_clean_failure(
            &["cap", p, "-o", out.to_str().unwrap()],
            &path,
            word,
            Some(&out),
        );
        assert_clean_failure(&["compare", good.to_str().unwrap(), p], &path, word, None);
    }
}

#[test]
fn missing_file_fails_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("does_not_exist.stl");
    let outdir = tempfile::tempdir().unwrap();
    let out = outdir.path().join("out.stl");
    assert_clean_failure(&["info", path.to_str().unwrap()], &path, "", None);
    assert_clean_failure(
        &["cap", path.to_str().unwrap(), "-o", out.to_str().unwrap()],
        &path,
        "",
        Some(&out),
    );
}

#[test]
fn unwritable_output_fails_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("no_such_folder").join("out.stl");
    let input = data_dir().join("aorta_abdominal_open_ends.stl");
    assert_clean_failure(
        &["cap", input.to_str().unwrap(), "-o", out.to_str().unwrap()],
        &out,
        "",
        None,
    );
    assert!(!out.exists());
    let bad_ext = tmp.path().join("out.xyz");
    assert_clean_failure(
        &[
            "cap",
            input.to_str().unwrap(),
            "-o",
            bad_ext.to_str().unwrap(),
        ],
        &bad_ext,
        "format",
        None,
    );
    assert!(!bad_ext.exists());
}

#[test]
fn bad_flags_fail_with_status_2() {
    let input = data_dir().join("aorta_abdominal_open_ends.stl");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out.stl");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    for args in [
        vec!["info", i, "--threads", "zero"],
        vec!["cap", i, "-o", o, "--target-edge=-1"],
        vec!["cap", i, "-o", o, "--target-edge=nan"],
        vec!["compare", i, i, "--samples", "0"],
        vec!["cap", i],
    ] {
        let run = vesselmsr(&args);
        assert_eq!(run.status.code(), Some(2), "{args:?}");
        assert!(
            !String::from_utf8_lossy(&run.stderr).contains("panicked"),
            "{args:?}"
        );
        assert!(!out.exists(), "{args:?} wrote an output");
    }
}

#[test]
fn cap_refuses_what_it_cannot_make_watertight() {
    // Two closed tetrahedra touching at one vertex (a non-manifold vertex): there is no hole to
    // cap, and the result is not a watertight manifold, so nothing is written.
    let tmp = tempfile::tempdir().unwrap();
    let path = write_file(
        tmp.path(),
        "bowtie.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv -1 0 0\nv 0 -1 0\nv 0 0 -1\n\
         f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n\
         f 1 6 5\nf 1 5 7\nf 5 6 7\nf 6 1 7\n",
    );
    let outdir = tempfile::tempdir().unwrap();
    let out = outdir.path().join("out.ply");
    assert_clean_failure(
        &["cap", path.to_str().unwrap(), "-o", out.to_str().unwrap()],
        &path,
        "watertight",
        Some(&out),
    );
}
