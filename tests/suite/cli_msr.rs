//! `vesselmsr decompose` and `vesselmsr reconstruct` through the CLI, on the shipped aorta at a
//! coarse voxel: the archive round trip gives the input vertices back to 1e-5h; the per-level
//! PLY files carry the scales and their details (as do VTP and VTK ones, on a sphere); the figures show the histograms and the
//! surfaces; the level-set reconstruction rebuilds each level close to the samples; bad input
//! (levels 0, too many levels for the time, a shape that vanishes, a missing, truncated or edited
//! archive, a level beyond the archive) gives exit status 2, one line naming the file, and no
//! output.

use crate::common;
use common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use vesselmsr::io::{read_mesh, read_npz, read_ply_scalars, write_npz, NpyArray, NpyData};
use vesselmsr::msr::archive::read_msr;

/// Voxel size for the tests (mm; the aorta's mean edge is 0.95 mm, its tubes ~5 mm in radius).
const VOXEL: &str = "1.25";

fn aorta() -> PathBuf {
    data_dir().join("aorta_abdominal_open_ends.stl")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// Decodes a PNG written by the report module: (width, height, RGB bytes).
fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Pixels of columns `x0..x1` whose colour satisfies `pred`.
fn count_pixels(
    (w, h, rgb): &(u32, u32, Vec<u8>),
    x0: u32,
    x1: u32,
    pred: impl Fn([u8; 3]) -> bool,
) -> usize {
    let mut n = 0;
    for y in 0..*h {
        for x in x0..x1.min(*w) {
            let i = 3 * (y * w + x) as usize;
            if pred([rgb[i], rgb[i + 1], rgb[i + 2]]) {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn decompose_archive_levels_and_figures_round_trip() {
    let tmp = tempfile::tempdir().unwrap();
    let archive = tmp.path().join("aorta.npz");
    let levels_dir = tmp.path().join("levels");
    let figures = tmp.path().join("figures");
    let a = aorta();
    let report = vesselmsr_json(&[
        "--json",
        "decompose",
        s(&a),
        "-o",
        s(&archive),
        "--voxel",
        VOXEL,
        "--levels",
        "3",
        "--levels-dir",
        s(&levels_dir),
        "--figures",
        s(&figures),
        "--measure-rebuilds",
        "200000",
    ]);
    let h = f(&report["voxel"]);
    assert!((h - 1.25).abs() < 1e-12, "{h}");
    // Default time N·4h², default step 2h²: two steps per level.
    assert!((f(&report["time"]) - 3.0 * 4.0 * h * h).abs() < 1e-9);
    assert!((f(&report["dt"]) - 2.0 * h * h).abs() < 1e-9);
    assert_eq!(report["output"], s(&archive));
    let levels = report["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    let samples = report["samples"].as_u64().unwrap();
    assert!(samples >= 6068, "the samples include the 6068 vertices");
    let volume1 = f(&levels[0]["volume"]);
    let mut area = f64::INFINITY;
    // Samples join where a level's surface has none near: never fewer level by level.
    let mut count = 6068;
    for (i, l) in levels.iter().enumerate() {
        println!("{l}");
        assert_eq!(l["level"], i + 1);
        let c = l["samples"].as_u64().unwrap();
        assert!(c >= count && c <= samples, "{l}");
        count = c;
        assert!((f(&l["time"]) - (i + 1) as f64 * 4.0 * h * h).abs() < 1e-9);
        // vpmcf keeps the volume and reduces the area; details are a fraction of a voxel.
        assert!((f(&l["volume"]) / volume1 - 1.0).abs() < 0.01, "{l}");
        assert!(f(&l["area"]) < area, "{l}");
        area = f(&l["area"]);
        let mean = f(&l["mean_abs_detail"]);
        assert!(mean > 0.01 && mean < 2.0, "{l}");
        let sparse = f(&l["sparse_fraction"]);
        assert!(sparse > 0.0 && sparse < 1.0, "{l}");
        // The level-set rebuild of the level before from this one's exact φ (the paper's
        // Figure 1 measure): within half a voxel.
        let rebuilt = f(&l["rebuild_hausdorff_h"]);
        assert!(rebuilt > 0.0 && rebuilt <= 0.5, "{l}");
        assert!(f(&l["rebuild_mean_h"]) < 0.05, "{l}");
    }

    // The archive, read by the library, matches the report; the vertices method gives back the
    // input vertices to 1e-5h and its triangles.
    let msr = read_msr(&archive).unwrap();
    assert_eq!(msr.levels(), 3);
    assert_eq!(msr.samples.len() as u64, samples);
    let out = tmp.path().join("s0.ply");
    let rec = vesselmsr_json(&["--json", "reconstruct", s(&archive), "-o", s(&out)]);
    assert_eq!(rec["method"], "vertices");
    assert_eq!(rec["level"], 0);
    assert_eq!(rec["levels"].as_array().unwrap().len(), 3);
    for l in rec["levels"].as_array().unwrap() {
        assert!(l["hausdorff_h"].is_null(), "{l}");
        let i = l["level"].as_u64().unwrap() as usize;
        // The per-level figures of decompose's, from the archive's lattice (q = 0.02h) and
        // normals (within 1°): the mean |w| within 0.002h, the share below 0.1h within 2%.
        let d = &levels[i - 1];
        assert!(
            (f(&l["mean_abs_detail"]) - f(&d["mean_abs_detail"])).abs() < 2e-3,
            "{l} {d}"
        );
        assert!(
            (f(&l["sparse_fraction"]) - f(&d["sparse_fraction"])).abs() < 0.02,
            "{l} {d}"
        );
    }
    let input = read_mesh(&a).unwrap();
    let back = read_mesh(&out).unwrap();
    assert_eq!(back.faces, input.faces);
    assert_eq!(back.num_vertices(), input.num_vertices());
    let worst = back
        .vertices
        .iter()
        .zip(&input.vertices)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    println!("vertices reconstruct the input to {:.2e} h", worst / h);
    assert!(worst <= 1e-5 * h, "{worst}");
    // ... and S_2 is the vertex samples of level 2 (the .obj keeps every f64 digit).
    let out2 = tmp.path().join("s2.obj");
    vesselmsr_json(&[
        "--json",
        "reconstruct",
        s(&archive),
        "-o",
        s(&out2),
        "--level",
        "2",
    ]);
    let s2 = read_mesh(&out2).unwrap();
    let x2 = msr.samples_at(2);
    assert_eq!(s2.vertices[..], x2[..msr.num_vertices]);

    // Levels as PLY: S_0 plain, S_k with `detail` = w_k at the vertices.
    for k in 0..=3 {
        let (mesh, scalars) = read_ply_scalars(&levels_dir.join(format!("level_{k}.ply"))).unwrap();
        let expected = msr.mesh_at(k);
        assert_eq!(mesh.faces, expected.faces);
        // Written from the decomposition in memory, compared with the archive read back: within
        // the archive's half lattice step (0.01h) per axis (S_0 exactly: the input's vertices).
        let off = mesh
            .vertices
            .iter()
            .zip(&expected.vertices)
            .map(|(a, b)| (a - b).amax())
            .fold(0.0, f64::max);
        assert!(
            off <= if k == 0 { 1e-5 } else { 0.0101 } * h,
            "level {k}: {off}"
        );
        if k == 0 {
            assert!(scalars.is_empty());
        } else {
            assert_eq!(scalars.len(), 1);
            assert_eq!(scalars[0].0, "detail");
            let w = &msr.normal_details[k - 1];
            assert_eq!(scalars[0].1.len(), msr.num_vertices);
            // w_k = W_k·n_k within the lattice's and the normals' rounding.
            for (a, b) in scalars[0].1.iter().zip(w) {
                let tol = 0.03 * h + 0.02 * b.abs();
                assert!((*a as f64 - b).abs() <= tol, "level {k}: {a} vs {b}");
            }
        }
    }

    // Figures: three histogram panels with bars, and four surfaces, S_1..S_3 coloured.
    let hist = read_png(&figures.join("details_histograms.png"));
    let third = hist.0 / 3;
    for p in 0..3 {
        let bars = count_pixels(&hist, p * third, (p + 1) * third, |c| c == [52, 101, 164]);
        println!("histogram panel {p}: {bars} bar pixels");
        assert!(bars > 200, "panel {p}: {bars}");
    }
    let strip = read_png(&figures.join("levels_strip.png"));
    // Default strip panels are 320 px wide with 8 px between them.
    assert_eq!(strip.0, 4 * 320 + 3 * 8);
    for p in 0..4 {
        let (x0, x1) = (p * 328, p * 328 + 320);
        let surface = count_pixels(&strip, x0, x1, |c| c != [255, 255, 255]);
        let coloured = count_pixels(&strip, x0, x1, |c| {
            (c[0] as i32 - c[2] as i32).abs() > 12 && c != [255, 255, 255]
        });
        println!("strip panel {p}: {surface} drawn, {coloured} coloured");
        // The aorta fills a good part of its 320×400 panel.
        assert!(surface > 10_000, "panel {p}: {surface}");
        if p == 0 {
            assert!(coloured < surface / 20, "S_0 is drawn plain: {coloured}");
        } else {
            assert!(coloured > surface / 4, "panel {p}: {coloured} of {surface}");
        }
    }

    // Level-set reconstruction from φ_T, level by level down to S_1.
    let ls = tmp.path().join("s1_levelset.stl");
    let rec = vesselmsr_json(&[
        "--json",
        "reconstruct",
        s(&archive),
        "-o",
        s(&ls),
        "--method",
        "levelset",
        "--level",
        "1",
    ]);
    assert_eq!(rec["method"], "levelset");
    let rl = rec["levels"].as_array().unwrap();
    assert_eq!(rl.len(), 2);
    for l in rl {
        println!("levelset {l}");
        // The samples X_{i−1} lie on S_{i−1}: on average far within a voxel of S̃_{i−1}, at
        // worst within one. (The Hausdorff distance to the open vertex mesh also counts the
        // caps the closed level set puts on the open ends: several h.)
        assert!(f(&l["samples_mean_h"]) < 0.1, "{l}");
        assert!(f(&l["samples_max_h"]) < 1.0, "{l}");
        assert!(f(&l["hausdorff_h"]) >= f(&l["samples_max_h"]) - 1e-9, "{l}");
    }
    assert_eq!(rec["output"]["watertight"], true);
    let info = info_json(&ls);
    assert_eq!(info["watertight"], true);
    // S̃_1 keeps the volume of S_1 (vpmcf) within a few percent (marching cubes, h = 1.25 mm).
    let v = f(&info["volume"]);
    assert!((v / f(&levels[0]["volume"]) - 1.0).abs() < 0.03, "{v}");

    // The text summaries.
    let run = vesselmsr(&[
        "reconstruct",
        s(&archive),
        "-o",
        s(&tmp.path().join("s3.ply")),
        "--level",
        "3",
        "--method",
        "levelset",
    ]);
    assert!(run.status.success());
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(text.contains("S_3 of 3 levels by levelset"), "{text}");
    assert!(text.contains("watertight"), "{text}");
}

/// `args` fail with exit status 2 and one line on stderr naming the file `names` (if any) and
/// holding `word`, and none of `outputs` exists.
fn assert_fails(args: &[&str], names: Option<&Path>, word: &str, outputs: &[&Path]) {
    let run = vesselmsr(args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
    if let Some(file) = names.and_then(|p| p.file_name()?.to_str()) {
        assert!(stderr.contains(file), "{args:?}: no {file}: {stderr}");
    }
    assert!(stderr.contains(word), "{args:?}: no {word:?}: {stderr}");
    for o in outputs {
        assert!(!o.exists(), "{args:?} left {}", o.display());
    }
    println!("{args:?} -> {}", stderr.trim_end());
}

#[test]
fn decompose_refuses_bad_input_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out.npz");
    let dir = tmp.path().join("levels");
    let fig = tmp.path().join("figures");
    let a = aorta();
    let base = [
        "decompose",
        s(&a),
        "-o",
        s(&out),
        "--voxel",
        "1.5",
        "--levels-dir",
        s(&dir),
        "--figures",
        s(&fig),
    ];
    let with = |extra: &[&'static str]| -> Vec<&str> {
        base.iter().copied().chain(extra.iter().copied()).collect()
    };
    for (extra, word, names_file) in [
        (&["--levels", "0"][..], "at least 1", true),
        // 0.1 mm² over 10 levels is below 0.25h² per level.
        (&["--levels", "10", "--time", "0.1"], "fewer levels", true),
        (&["--time", "-1"], "positive", true),
        (&["--dt", "0"], "positive", true),
        // The aorta's tubes (radius ~5 mm) vanish long before t = 1000 mm² under mcf.
        (
            &["--velocity", "mcf", "--time", "1000"],
            "vanished at t =",
            true,
        ),
        // A flag error: refused before the mesh is read.
        (&["--velocity", "mcf", "--c", "1"], "takes no speed", false),
    ] {
        let names = names_file.then_some(a.as_path());
        assert_fails(&with(extra), names, word, &[&out, &dir, &fig]);
    }
    let bad = tmp.path().join("out.stl");
    assert_fails(
        &["decompose", s(&a), "-o", s(&bad)],
        Some(&bad),
        ".npz",
        &[&bad],
    );
}

#[test]
fn reconstruct_refuses_bad_archives_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let archive = tmp.path().join("good.npz");
    let a = aorta();
    vesselmsr_json(&[
        "--json",
        "decompose",
        s(&a),
        "-o",
        s(&archive),
        "--voxel",
        "1.5",
        "--levels",
        "2",
    ]);
    let out = tmp.path().join("out.ply");
    for method in ["vertices", "levelset"] {
        let run = |p: &Path, extra: &[&str], word: &str| {
            let mut args = vec!["reconstruct", s(p), "-o", s(&out), "--method", method];
            args.extend_from_slice(extra);
            assert_fails(&args, Some(p), word, &[&out]);
        };
        run(&tmp.path().join("missing.npz"), &[], "No such file");
        run(&archive, &["--level", "3"], "beyond the archive's 2 levels");

        let bytes = std::fs::read(&archive).unwrap();
        let truncated = tmp.path().join("truncated.npz");
        std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
        run(&truncated, &[], "npz");

        // Edited archives: another format version, a member cut short, a NaN voxel size.
        let members = read_npz(&archive).unwrap();
        let edit = |name: &str, f: &dyn Fn(&str, NpyArray) -> NpyArray| -> PathBuf {
            let path = tmp.path().join(format!("{name}.npz"));
            let edited: Vec<(String, NpyArray)> = members
                .iter()
                .map(|(n, m)| (n.clone(), f(n, m.clone())))
                .collect();
            let refs: Vec<(&str, NpyArray)> = edited
                .iter()
                .map(|(n, m)| (n.as_str(), m.clone()))
                .collect();
            write_npz(&path, &refs).unwrap();
            path
        };
        let v1 = edit("version1", &|n, m| {
            if n == "format_version" {
                NpyArray::scalar_i64(1)
            } else {
                m
            }
        });
        run(&v1, &[], "format version 1");
        let short = edit("short", &|n, m| match (n, m.data.to_i32()) {
            ("residuals", Some(v)) => {
                let mut shape = m.shape.clone();
                shape[2] -= 1;
                let keep = shape.iter().product();
                NpyArray::new(&shape, NpyData::narrowest_int(&v[..keep]))
            }
            _ => m,
        });
        run(&short, &[], "residuals");
        let nan = edit("nan", &|n, m| match n {
            "phi_voxel" => NpyArray::scalar_f64(f64::NAN),
            _ => m,
        });
        run(&nan, &[], "NaN");
    }
    // A φ_T edited to have no inside: the vertices do not need it, the level set refuses.
    let members = read_npz(&archive).unwrap();
    let empty = tmp.path().join("empty_phi.npz");
    let edited: Vec<(&str, NpyArray)> = members
        .iter()
        .map(|(n, m)| match (n.as_str(), &m.data) {
            ("phi", NpyData::I8(v)) => (
                n.as_str(),
                NpyArray::new(&m.shape, NpyData::I8(vec![1; v.len()])),
            ),
            _ => (n.as_str(), m.clone()),
        })
        .collect();
    write_npz(&empty, &edited).unwrap();
    assert_fails(
        &[
            "reconstruct",
            s(&empty),
            "-o",
            s(&out),
            "--method",
            "levelset",
        ],
        Some(&empty),
        "is empty",
        &[&out],
    );
    vesselmsr_json(&["--json", "reconstruct", s(&empty), "-o", s(&out)]);
    std::fs::remove_file(&out).unwrap();
    // The good archive works, and an unknown output format is refused before reading it.
    let bad = tmp.path().join("out.xyz");
    assert_fails(
        &["reconstruct", s(&archive), "-o", s(&bad)],
        Some(&bad),
        "unknown mesh format",
        &[&bad],
    );
    vesselmsr_json(&["--json", "reconstruct", s(&archive), "-o", s(&out)]);
    assert!(out.exists());
}

#[test]
fn levels_as_vtp_and_vtk() {
    // A small sphere, one level: the scales written as VTK XML PolyData and legacy VTK carry the
    // same meshes and details as the PLY files.
    let tmp = tempfile::tempdir().unwrap();
    let sphere = tmp.path().join("sphere.stl");
    vesselmsr::io::write_mesh(
        &sphere,
        &vesselmsr::mesh::primitives::icosphere(3, 4.0, nalgebra::Point3::origin()),
    )
    .unwrap();
    let mut scales = Vec::new();
    for ext in ["ply", "vtp", "vtk"] {
        let dir = tmp.path().join(ext);
        let out = tmp.path().join(format!("{ext}.npz"));
        let args = [
            "decompose",
            s(&sphere),
            "-o",
            s(&out),
            "--voxel",
            "0.5",
            "--levels",
            "1",
            "--levels-dir",
            s(&dir),
            "--levels-format",
            ext,
            "-q",
        ];
        assert!(vesselmsr(&args).status.success(), "{args:?}");
        let level: Vec<_> = (0..=1)
            .map(|k| {
                vesselmsr::io::read_mesh_with_scalars(&dir.join(format!("level_{k}.{ext}")))
                    .unwrap()
            })
            .collect();
        assert!(level[0].1.is_empty());
        assert_eq!(level[1].1.len(), 1);
        assert_eq!(level[1].1[0].0, "detail");
        scales.push(level);
    }
    assert_eq!(scales[1], scales[0]);
    assert_eq!(scales[2], scales[0]);
    let bad = tmp.path().join("bad.npz");
    assert_fails(
        &[
            "decompose",
            s(&sphere),
            "-o",
            s(&bad),
            "--levels-dir",
            s(&tmp.path().join("never")),
            "--levels-format",
            "stl",
        ],
        None,
        "--levels-format",
        &[&bad, &tmp.path().join("never")],
    );
}
