//! The MSR archive: write → read gives the same representation within the compact coding's
//! bounds (samples of every level within half a lattice step per axis, input vertices exact,
//! normals within a degree, φ_T within h/128 near the surface); NumPy's `np.load` (no pickling)
//! reads every member and decodes samples, normals and φ_T with the documented formulas to the
//! values the reader gives (also the refined samples of a decomposition's archive); an archive
//! of the float64 layout of earlier builds reads back exactly, one of the version-3 layout
//! within its lattice; archives of another version, truncated, with members edited out of shape or range,
//! or needing more memory decoded than allowed are refused with an error naming the file and
//! the member. Also the vertex reconstruction X_k = X_N − Σ_{i>k} W_i (the input:
//! X_0 less the snap) and the samples each level's level-set reconstruction reads (a sample
//! added at level 1 is not among those of level 0).

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use std::path::Path;
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::io::{read_npz, write_npz, NpyArray, NpyData};
use vesselmsr::msr::archive::{read_msr, read_msr_within, write_msr, FORMAT_VERSION};
use vesselmsr::msr::compact::QUANTUM_VOXELS;
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
        // Zero before a sample's birth, as the decomposition leaves them (the archive stores none).
        normals: (0..=levels)
            .map(|i| {
                (0..s)
                    .map(|k| {
                        if k == 6 && i == 0 {
                            Vector3::zeros()
                        } else {
                            (xs[i][k] - Point3::origin()).normalize()
                        }
                    })
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

/// The version-2 layout (float64 arrays) of earlier builds, as they wrote it.
fn write_v2(path: &std::path::Path, msr: &Msr) {
    let s = msr.samples.len();
    let n = msr.levels();
    let [nx, ny, nz] = msr.phi.dims();
    let v3 = |v: &mut dyn Iterator<Item = Vector3<f64>>| {
        NpyData::F64(v.flat_map(|w| [w.x, w.y, w.z]).collect())
    };
    let members: Vec<(&str, NpyArray)> = vec![
        ("format", NpyArray::text("vesselmsr-msr")),
        ("format_version", NpyArray::scalar_i64(2)),
        (
            "params",
            NpyArray::text(&serde_json::to_string(&msr.params).unwrap()),
        ),
        (
            "faces",
            NpyArray::new(&[msr.faces.len(), 3], NpyData::U32(msr.faces.concat())),
        ),
        (
            "num_vertices",
            NpyArray::scalar_i64(msr.num_vertices as i64),
        ),
        (
            "extra_face",
            NpyArray::new(
                &[msr.extra_face.len()],
                NpyData::I64(msr.extra_face.iter().map(|&f| f as i64).collect()),
            ),
        ),
        (
            "extra_bary",
            NpyArray::new(
                &[msr.extra_bary.len(), 3],
                NpyData::F64(msr.extra_bary.concat()),
            ),
        ),
        (
            "snap",
            NpyArray::new(&[msr.snap.len(), 3], v3(&mut msr.snap.iter().copied())),
        ),
        (
            "born",
            NpyArray::new(
                &[s],
                NpyData::I64(msr.born.iter().map(|&b| b as i64).collect()),
            ),
        ),
        (
            "samples",
            NpyArray::new(&[s, 3], v3(&mut msr.samples.iter().map(|p| p.coords))),
        ),
        (
            "details",
            NpyArray::new(&[n, s, 3], v3(&mut msr.details.iter().flatten().copied())),
        ),
        (
            "normal_details",
            NpyArray::new(&[n, s], NpyData::F64(msr.normal_details.concat())),
        ),
        (
            "normals",
            NpyArray::new(
                &[n + 1, s, 3],
                v3(&mut msr.normals.iter().flatten().copied()),
            ),
        ),
        (
            "times",
            NpyArray::new(&[n + 1], NpyData::F64(msr.times.clone())),
        ),
        (
            "phi",
            NpyArray::new(&[nz, ny, nx], NpyData::F32(msr.phi.data().to_vec())),
        ),
        (
            "phi_origin",
            NpyArray::new(&[3], NpyData::F64(msr.phi.transform().origin.to_vec())),
        ),
        ("phi_voxel", NpyArray::scalar_f64(msr.phi.voxel())),
    ];
    write_npz(path, &members).unwrap();
}

#[test]
fn archive_round_trips_within_its_lattice_and_numpy_decodes_it() {
    let (msr, xs) = sample_msr();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shape.msr.npz");
    write_msr(&path, &msr).unwrap();
    let back = read_msr(&path).unwrap();
    let h = msr.phi.voxel();
    let q = QUANTUM_VOXELS * h;
    // Exact: connectivity, births, times, parameters, the input vertices.
    assert_eq!(
        (
            &back.faces,
            back.num_vertices,
            &back.extra_face,
            &back.extra_bary
        ),
        (
            &msr.faces,
            msr.num_vertices,
            &msr.extra_face,
            &msr.extra_bary
        )
    );
    assert_eq!(
        (&back.born, &back.times, &back.params),
        (&msr.born, &msr.times, &msr.params)
    );
    for (a, b) in back
        .mesh_at(0)
        .vertices
        .iter()
        .zip(&msr.mesh_at(0).vertices)
    {
        assert!((a - b).norm() < 1e-12, "{a} vs {b}");
    }
    // Every level's samples within half a lattice step per axis (never adding up).
    for (k, x) in xs.iter().enumerate() {
        for (j, (a, b)) in back.samples_at(k).iter().zip(x).enumerate() {
            assert!(
                (a - b).amax() <= 0.5 * q * (1.0 + 1e-9),
                "level {k}, sample {j}: {a} vs {b}"
            );
        }
    }
    // The normals within a degree.
    for i in 0..=msr.levels() {
        for (a, b) in back.normals[i].iter().zip(&msr.normals[i]) {
            assert!(a.angle(b).to_degrees() < 1.0, "level {i}: {a} vs {b}");
        }
    }
    // φ_T within h/128 near the surface, half a far step beyond (the reach: the largest detail
    // plus 4h, over 63 codes).
    let largest = msr.largest_detail();
    let step = (0.25 * h).max((largest + 3.0 * h) / 63.0);
    let (mut near, mut far) = (0, 0);
    for (a, b) in back.phi.data().iter().zip(msr.phi.data()) {
        let (a, b) = (*a as f64, *b as f64);
        if b.abs() <= h {
            assert!((a - b).abs() <= h / 128.0 + 1e-6, "{a} vs {b}");
            near += 1;
        } else if b.abs() < 6.0 * h {
            assert!(
                (a - b).abs() <= 0.5 * step + 1e-6 && a.signum() == b.signum(),
                "{a} vs {b}"
            );
            far += 1;
        }
    }
    assert!(near > 0 && far > 0, "near {near}, far {far}");

    // NumPy decodes the documented members with the documented formulas.
    let v = run_python(NUMPY_DECODER, &[&path]);
    let shape = |k: &str| v[k]["shape"].clone();
    assert_eq!(v["version"], FORMAT_VERSION);
    assert_eq!(shape("residuals"), serde_json::json!([3, 3, 7]));
    assert_eq!(shape("normals"), serde_json::json!([4, 2, 7]));
    assert_eq!(shape("snap_normal"), serde_json::json!([6]));
    assert_eq!(shape("snap_residual"), serde_json::json!([3, 6]));
    assert_eq!(shape("added_at"), serde_json::json!([3, 1]));
    assert_eq!(shape("phi"), serde_json::json!([2, 3, 4]));
    assert_eq!(v["phi"]["dtype"], "|i1");
    let floats = |k: &str| flatten_numbers(&v[k]);
    let samples: Vec<f64> = back.samples.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    for (a, b) in floats("x_n").iter().zip(&samples) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    for (a, b) in floats("phi_values").iter().zip(back.phi.data()) {
        assert!((a - *b as f64).abs() < 1e-5, "{a} vs {b}");
    }
    let normals: Vec<f64> = back
        .normals
        .iter()
        .flatten()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    for (a, b) in floats("normal_vectors").iter().zip(&normals) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }

    // An archive of the float64 layout of earlier builds reads back exactly.
    let old = dir.path().join("v2.npz");
    write_v2(&old, &msr);
    assert_eq!(read_msr(&old).unwrap(), msr);
    // One of the version-3 layout (written by the build before version 4, from this same
    // representation) within its lattice and its normal codes.
    let v3 =
        read_msr(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/msr_v3.npz")).unwrap();
    assert_eq!(
        (&v3.faces, &v3.born, &v3.times),
        (&msr.faces, &msr.born, &msr.times)
    );
    for (k, x) in xs.iter().enumerate() {
        for (a, b) in v3.samples_at(k).iter().zip(x) {
            assert!(
                (a - b).amax() <= 0.5 * q * (1.0 + 1e-9),
                "v3 level {k}: {a} vs {b}"
            );
        }
    }
    for i in 0..=msr.levels() {
        for (a, b) in v3.normals[i].iter().zip(&msr.normals[i]) {
            assert!(
                a.angle(b).to_degrees() < 1.0 || b.norm() == 0.0,
                "v3 level {i}"
            );
        }
    }
}

/// A decomposition's archive has refined pairs (the writer checks the level-set rebuild from
/// the codes): NumPy decodes them as the reader does.
#[test]
fn numpy_decodes_the_refined_samples_of_a_decomposition() {
    use vesselmsr::grid::{grid_for_mesh, GridOptions};
    use vesselmsr::mesh::primitives::torus;
    use vesselmsr::msr::decompose::{decompose, DecomposeOptions};
    let mesh = torus(6.0, 2.0, 48, 16, Point3::origin());
    let grid = GridOptions {
        voxel: Some(0.5),
        padding_voxels: 6,
        ..Default::default()
    };
    let spec = grid_for_mesh(&mesh, &grid).unwrap();
    let phi = common::phi_on(&mesh, &spec);
    let opts = DecomposeOptions {
        levels: 3,
        ..Default::default()
    };
    let msr = decompose(&mesh, phi, &opts, |_, _| {}).unwrap().msr;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("torus.msr.npz");
    write_msr(&path, &msr).unwrap();
    let back = read_msr(&path).unwrap();
    let v = run_python(NUMPY_DECODER, &[&path]);
    let refined = v["refined"].as_u64().unwrap();
    assert!(refined > 0, "no refined pairs");
    let flat = |k: &str| flatten_numbers(&v[k]);
    let samples: Vec<f64> = back.samples.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    let xn = flat("x_n");
    assert_eq!(xn.len(), samples.len());
    for (a, b) in xn.iter().zip(&samples) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    let normals: Vec<f64> = (back.normals.iter().flatten())
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    for (a, b) in flat("normal_vectors").iter().zip(&normals) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
    println!("{refined} refined pairs of {} samples", msr.samples.len());
}

/// The NumPy decoder of the archive module doc: prints the members' shapes and dtypes, the
/// version, X_N, n_0..n_N and φ_T as JSON.
const NUMPY_DECODER: &str = r#"
import json, sys
import numpy as np
z = np.load(sys.argv[1], allow_pickle=False)
out = {k: {"shape": list(z[k].shape), "dtype": z[k].dtype.str} for k in z.files}
out["version"] = int(z["format_version"])
m = 127
sg = lambda x: np.where(x < 0, -1.0, 1.0)
def unit(c, m=m):
    u, v = c[..., 0] / m, c[..., 1] / m
    w = 1 - np.abs(u) - np.abs(v)
    n = np.stack([np.where(w < 0, (1 - np.abs(v)) * sg(u), u), np.where(w < 0, (1 - np.abs(u)) * sg(v), v), w], -1)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    return np.where((c == m + 1).all(-1)[..., None], 0.0, n)
def code(d):
    l1 = np.abs(d[:, 0]) + np.abs(d[:, 1]) + np.abs(d[:, 2])
    x, y = d[:, 0] / l1, d[:, 1] / l1
    u = np.where(d[:, 2] < 0, (1 - np.abs(y)) * sg(x), x)
    v = np.where(d[:, 2] < 0, (1 - np.abs(x)) * sg(y), y)
    return np.stack([np.rint(u * m), np.rint(v * m)], -1).astype(np.int64)
q, qb, h = float(z["quantum"]), float(z["birth_quantum"]), float(z["phi_voxel"])
o = z["phi_origin"]
verts, faces = z["vertices"], z["faces"].astype(np.int64)
ef = np.cumsum(z["extra_face_steps"].astype(np.int64))
b = z["extra_bary"]
f = faces[ef]
pos = np.concatenate([verts, verts[f[:, 0]] * b[:, 0:1] + verts[f[:, 1]] * b[:, 1:2] + verts[f[:, 2]] * b[:, 2:3]])
added = z["added_at"].T.astype(np.int64)
born = z["born"].astype(np.int64)
S, I, V, N = len(born), len(pos), len(verts), len(z["times"]) - 1
# The refined (level, sample) pairs: a finer normal code and a position offset in steps of q/64.
rk = np.cumsum(z["refine_key_steps"].astype(np.int64))
rl, rs = rk // S, rk % S
rp = z["refine_position"].T * (q / 64)
rn = z["refine_normal"].T.astype(np.int64)
# The order P: Morton code of each sample's voxel at birth, ties by index.
cell = np.concatenate([np.floor((pos - o) / h), np.floor(added * qb / h)]).astype(np.int64)
cell = np.clip(cell + 2**20, 0, 2**21 - 1)
key = np.zeros(S, np.int64)
for bit in range(21):
    for a in range(3):
        key |= ((cell[:, a] >> bit) & 1) << (3 * bit + a)
P = np.argsort(key, kind="stable")
def along(stored, pick):
    idx = P[pick[P]]
    out = np.zeros_like(stored)
    out[idx] = np.cumsum(stored[idx], 0)
    return out
# Normals: births predicted along P (extras from their face's normal), then each level's change.
a, bb, c = verts[f[:, 0]], verts[f[:, 1]], verts[f[:, 2]]
cross = np.cross(bb - a, c - a) * float(z["face_normal_sign"])
st = z["normals"].astype(np.int64).transpose(0, 2, 1)
extra = np.zeros(S, bool)
extra[V:I] = True
codes = np.zeros((S, 2), np.int64)
n = []
for i in range(N + 1):
    here = (born == i) & ~extra if i == 0 else born == i
    new = along(st[i], here)
    if i > 0:
        codes = codes + along(st[i], born < i)
    codes[here] = new[here]
    if i == 0:
        codes[V:I] = st[0][V:I] + code(cross)
    ni = np.where((born > i)[:, None], 0.0, unit(codes))
    j = (rl == i) & ~(codes[rs] == m + 1).all(-1)
    ni[rs[j]] = unit(32 * codes[rs[j]] + rn[j], 32 * m)
    n.append(ni)
snap = (z["snap_normal"][:, None] * n[0][:I] + z["snap_residual"].T) * qb
j = rl == born[rs]
snap[rs[j & (rs < I)]] = snap[rs[j & (rs < I)]] + rp[j & (rs < I)]
x = np.concatenate([pos + snap, o + added * qb])
x[rs[j & (rs >= I)]] = x[rs[j & (rs >= I)]] + rp[j & (rs >= I)]
for i in range(1, N + 1):
    w = along(z["normal_details"][i - 1].astype(np.int64), born < i)
    d = (w[:, None] * n[i] + z["residuals"][i - 1].T) * q
    j = (rl == i) & (born[rs] < i)
    d[rs[j]] = d[rs[j]] + rp[j]
    x = x + np.where((born >= i)[:, None], 0.0, d)
out["refined"] = int(len(rk))
c = z["phi"].astype(np.float64)
far = float(z["phi_far"])
phi = np.where(np.abs(c) <= 64, c * h / 64, np.sign(c) * (h + (np.abs(c) - 64) * far))
out["x_n"] = x.tolist()
out["phi_values"] = phi.ravel().tolist()
out["normal_vectors"] = np.array(n).tolist()
print(json.dumps(out))
"#;

#[test]
fn damaged_archives_are_refused() {
    let (msr, _) = sample_msr();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shape.msr.npz");
    write_msr(&path, &msr).unwrap();
    let good = std::fs::read(&path).unwrap();
    // Every member fits in 1000 bytes; the decoded representation needs 1776.
    let e = read_msr_within(&path, 1000).unwrap_err().to_string();
    assert!(
        e.contains("decoding") && e.contains("memory limit") && e.contains("shape.msr.npz"),
        "{e}"
    );
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
                "residuals",
                Some(NpyArray::new(&[2, 3, 7], NpyData::I8(vec![0; 42]))),
            ),
            "residuals",
        ),
        (
            edited(
                "residuals",
                Some(NpyArray::new(&[3, 3, 7], NpyData::F64(vec![0.0; 63]))),
            ),
            "int8, int16 or int32",
        ),
        (
            edited(
                "born",
                Some(NpyArray::new(&[7], NpyData::I8(vec![0, 0, 0, 0, 0, 0, 5]))),
            ),
            "sample 6 at level 5",
        ),
        (
            edited(
                "snap_residual",
                Some(NpyArray::new(&[3, 3], NpyData::I8(vec![0; 9]))),
            ),
            "snap_residual",
        ),
        (
            edited(
                "extra_face_steps",
                Some(NpyArray::new(&[2], NpyData::I8(vec![1, 3]))),
            ),
            "face 4 is not within 0..4",
        ),
        (
            edited("face_normal_sign", Some(NpyArray::scalar_i64(0))),
            "face_normal_sign",
        ),
        (
            edited(
                "refine_key_steps",
                Some(NpyArray::new(&[1], NpyData::I8(vec![100]))),
            ),
            "refine_key_steps",
        ),
        (
            edited(
                "normals",
                Some(NpyArray::new(&[4, 2, 7], NpyData::I16(vec![300; 56]))),
            ),
            "not within ±127",
        ),
        (
            edited(
                "faces",
                Some(NpyArray::new(&[1, 3], NpyData::U32(vec![0, 1, 9]))),
            ),
            "index 9",
        ),
        (edited("added_at", None), "no member 'added_at'"),
        (
            edited("quantum", Some(NpyArray::scalar_f64(-1.0))),
            "quantum",
        ),
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

/// The numbers of a nested JSON array, in row-major order.
fn flatten_numbers(v: &serde_json::Value) -> Vec<f64> {
    let mut out = Vec::new();
    let mut walk = vec![v];
    while let Some(x) = walk.pop() {
        match x {
            serde_json::Value::Array(a) => walk.extend(a.iter().rev()),
            x => out.push(x.as_f64().unwrap()),
        }
    }
    out
}
