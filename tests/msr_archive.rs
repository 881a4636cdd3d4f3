//! The MSR archive: write → read gives the same representation bit for bit; NumPy's `np.load`
//! (no pickling) reads every member with the documented shapes and values; archives of another
//! version, truncated, or with members edited out of shape are refused with an error naming the
//! file and the member. Also the vertex reconstruction X_k = X_N − Σ_{i>k} W_i (the input:
//! X_0 less the snap) and the samples each level's level-set reconstruction reads (a sample
//! added at level 1 is not among those of level 0).

mod common;
use common::*;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::io::{read_npz, write_npz, NpyArray, NpyData};
use vesselmsr::msr::archive::{read_msr, write_msr, FORMAT_VERSION};
use vesselmsr::msr::{Msr, MsrParams};

/// A representation of 3 levels over a tetrahedron's 4 vertices plus 2 extra samples (snapped
/// by known offsets) and one sample added at level 1, with known samples X_0..X_3.
fn sample_msr() -> (Msr, Vec<Vec<Point3<f64>>>) {
    let mut rng = rng(11);
    let mut r = || rng.random::<f64>() * 2.0 - 1.0;
    let levels = 3;
    let s = 7;
    let mut xs: Vec<Vec<Point3<f64>>> = (0..=levels)
        .map(|_| (0..s).map(|_| Point3::new(r(), r(), r()) * 10.0).collect())
        .collect();
    // Sample 6 joins at level 1: before it, it stays where it was born.
    xs[0][6] = xs[1][6];
    let snap = (0..6).map(|_| Vector3::new(r(), r(), r()) * 0.1).collect();
    let details: Vec<Vec<Vector3<f64>>> = (1..=levels)
        .map(|i| (0..s).map(|k| xs[i][k] - xs[i - 1][k]).collect())
        .collect();
    let normal_details = details
        .iter()
        .map(|w| w.iter().map(|d| d.x).collect())
        .collect();
    let mut phi = Grid3::new(
        [4, 3, 2],
        GridTransform::new(Point3::new(-1.5, 0.25, 1e3 / 7.0), 0.7),
        0.0,
    )
    .unwrap();
    for (n, v) in phi.data_mut().iter_mut().enumerate() {
        *v = n as f32 * 0.5 - 3.0;
    }
    let msr = Msr {
        faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        num_vertices: 4,
        extra_face: vec![1, 3],
        extra_bary: vec![[0.2, 0.3, 0.5], [1.0 / 3.0; 3]],
        snap,
        born: vec![0, 0, 0, 0, 0, 0, 1],
        samples: xs[levels].clone(),
        details,
        normal_details,
        normals: (0..=levels)
            .map(|i| {
                (0..s)
                    .map(|k| (xs[i][k] - Point3::origin()).normalize())
                    .collect()
            })
            .collect(),
        times: vec![0.0, 0.5, 1.25, 2.0],
        phi,
        params: MsrParams {
            velocity: "vpmcf".into(),
            c: 0.0,
            time: 2.0,
            levels,
            dt: 0.125,
            voxel: 0.7,
            projection_tolerance_voxels: 1e-3,
            software: "vesselmsr test".into(),
        },
    };
    (msr, xs)
}

#[test]
fn vertices_reconstruct_every_level() {
    let (msr, xs) = sample_msr();
    for (k, x) in xs.iter().enumerate() {
        let got = msr.samples_at(k);
        for (a, b) in got.iter().zip(x) {
            assert!((a - b).norm() < 1e-12, "level {k}: {a} vs {b}");
        }
        let mesh = msr.mesh_at(k);
        assert_eq!(mesh.num_vertices(), 4);
        assert_eq!(mesh.faces, msr.faces);
        for (v, p) in mesh.vertices.iter().enumerate() {
            let want = if k == 0 { x[v] - msr.snap[v] } else { x[v] };
            assert!((p - want).norm() < 1e-12, "level {k} vertex {v}");
        }
    }
    // Level 1 is rebuilt from the 6 samples of S_0; level 2 from all 7 on S_1.
    for (i, count) in [(1, 6), (2, 7), (3, 7)] {
        let data = msr.level_data(i);
        assert_eq!(data.points.len(), count, "level {i}");
        assert_eq!(msr.level_normal_details(i).len(), count, "level {i}");
        let last = count - 1;
        assert!((data.points[last] - xs[i - 1][last]).norm() < 1e-12);
        assert_eq!(data.details[last], msr.details[i - 1][last]);
        assert_eq!(data.normals[last], msr.normals[i - 1][last]);
    }
}

#[test]
fn archive_round_trips_and_numpy_reads_it() {
    let (msr, _) = sample_msr();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shape.msr.npz");
    write_msr(&path, &msr).unwrap();
    assert_eq!(read_msr(&path).unwrap(), msr);

    let script = r#"
import json, sys
import numpy as np
z = np.load(sys.argv[1], allow_pickle=False)
out = {k: {"shape": list(z[k].shape), "dtype": z[k].dtype.str} for k in z.files}
out["format"] = str(z["format"])
out["version"] = int(z["format_version"])
out["params"] = json.loads(str(z["params"]))
out["details_121"] = float(z["details"][1, 2, 1])
out["phi_k_j_i"] = float(z["phi"][1, 2, 3])
out["faces_row"] = [int(v) for v in z["faces"][2]]
print(json.dumps(out))
"#;
    let v = run_python(script, &[&path]);
    println!("{v}");
    let shape = |k: &str| v[k]["shape"].clone();
    assert_eq!(v["format"], "vesselmsr-msr");
    assert_eq!(v["version"], FORMAT_VERSION);
    assert_eq!(v["params"]["velocity"], "vpmcf");
    assert_eq!(v["params"]["levels"], 3);
    assert_eq!(shape("faces"), serde_json::json!([4, 3]));
    assert_eq!(v["faces"]["dtype"], "<u4");
    assert_eq!(shape("samples"), serde_json::json!([7, 3]));
    assert_eq!(shape("details"), serde_json::json!([3, 7, 3]));
    assert_eq!(shape("normal_details"), serde_json::json!([3, 7]));
    assert_eq!(shape("times"), serde_json::json!([4]));
    assert_eq!(shape("normals"), serde_json::json!([4, 7, 3]));
    assert_eq!(shape("snap"), serde_json::json!([6, 3]));
    assert_eq!(shape("born"), serde_json::json!([7]));
    assert_eq!(v["born"]["dtype"], "<i8");
    assert_eq!(shape("extra_face"), serde_json::json!([2]));
    assert_eq!(shape("extra_bary"), serde_json::json!([2, 3]));
    assert_eq!(shape("phi"), serde_json::json!([2, 3, 4]));
    assert_eq!(v["phi"]["dtype"], "<f4");
    assert_eq!(v["details_121"].as_f64().unwrap(), msr.details[1][2].y);
    assert_eq!(
        v["phi_k_j_i"].as_f64().unwrap(),
        msr.phi.get(3, 2, 1) as f64
    );
    assert_eq!(v["faces_row"], serde_json::json!(msr.faces[2]));
}

#[test]
fn damaged_archives_are_refused() {
    let (msr, _) = sample_msr();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shape.msr.npz");
    write_msr(&path, &msr).unwrap();
    let good = std::fs::read(&path).unwrap();
    let members = read_npz(&path).unwrap();
    let edited = |name: &str, array: Option<NpyArray>| {
        let m: Vec<(&str, NpyArray)> = members
            .iter()
            .filter_map(|(k, a)| {
                if k == name {
                    array.clone().map(|b| (k.as_str(), b))
                } else {
                    Some((k.as_str(), a.clone()))
                }
            })
            .collect();
        let p = dir.path().join(format!("edited-{name}.npz"));
        write_npz(&p, &m).unwrap();
        p
    };
    let cases: Vec<(std::path::PathBuf, &str)> = vec![
        (
            edited("format_version", Some(NpyArray::scalar_i64(1))),
            "version 1",
        ),
        (
            edited(
                "details",
                Some(NpyArray::new(&[2, 7, 3], NpyData::F64(vec![0.0; 42]))),
            ),
            "details",
        ),
        (
            edited(
                "born",
                Some(NpyArray::new(&[7], NpyData::I64(vec![0, 0, 0, 0, 0, 0, 5]))),
            ),
            "sample 6 at level 5",
        ),
        (
            edited(
                "snap",
                Some(NpyArray::new(&[3, 3], NpyData::F64(vec![0.0; 9]))),
            ),
            "'snap' has 3 rows",
        ),
        (
            edited(
                "faces",
                Some(NpyArray::new(&[1, 3], NpyData::U32(vec![0, 1, 9]))),
            ),
            "index 9",
        ),
        (edited("samples", None), "no member 'samples'"),
        (
            edited("format", Some(NpyArray::text("something-else"))),
            "format",
        ),
        (
            edited(
                "times",
                Some(NpyArray::new(
                    &[4],
                    NpyData::F64(vec![0.0, f64::NAN, 1.0, 2.0]),
                )),
            ),
            "NaN",
        ),
    ];
    for (p, word) in cases {
        let e = read_msr(&p).unwrap_err().to_string();
        assert!(
            e.contains(p.file_name().unwrap().to_str().unwrap()) && e.contains(word),
            "{word}: {e}"
        );
    }
    for cut in [good.len() / 2, good.len() - 10, 30] {
        std::fs::write(&path, &good[..cut]).unwrap();
        let e = read_msr(&path).unwrap_err().to_string();
        assert!(e.contains("shape.msr.npz"), "cut at {cut}: {e}");
    }
    std::fs::write(&path, b"not a zip at all").unwrap();
    assert!(read_msr(&path).unwrap_err().to_string().contains("zip"));
}
