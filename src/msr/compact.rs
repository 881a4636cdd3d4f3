//! The compact coding of an [`Msr`] that its archive stores (format version 3): the same
//! representation (paper Definition 2.1: the samples, the details W_1..W_N and φ_T) in integer
//! codes that compress tightly, some 20× smaller than the float64 arrays of version 2.
//!
//! - **Positions** on a lattice of step q = [`QUANTUM_VOXELS`]·h (h the voxel of φ_T). Each
//!   sample's position at birth (its base) is coded once, on a lattice [`BIRTH_SUBSTEPS`] times
//!   finer (q_b): an input sample's as its input position (kept exactly: the mesh vertices in
//!   float64, the extra samples by their barycentric coordinates) plus its snap; a sample added at
//!   level b by its position relative to φ_T's origin. (The samples the decomposition places
//!   where the level-set reconstruction would misread a level act through their exact place: on
//!   the coarser lattice the aorta's level-1 rebuild moved by 0.1h.) Every later X_i is the base
//!   plus a whole number of lattice steps q, rounded from the exact X_i, so the error stays within
//!   q/2 on each axis at every level (it never adds up across the levels); the details are the
//!   differences of consecutive lattice positions.
//! - **Normals** n_0..n_N as octahedral codes (two integers in −[`NORMAL_STEPS`]..=
//!   [`NORMAL_STEPS`], within about 1° of the unit normal; a zero normal — before a sample's
//!   birth, or where ∇φ vanished — is the code ([`ZERO_CODE`], [`ZERO_CODE`])), each level's code
//!   stored less the level before's (normals change little from one scale to the next). (n_N,
//!   which the reconstruction does not read, is stored too: recomputed from the coded φ_T it was
//!   20° off at places, and the normal details w_N with it.)
//! - **Details**: a detail W_i lies almost along n_i (it is the Newton projection onto S_i), so
//!   it is stored as its normal component in lattice steps, w = rint(W_i·n̂ / q) with n̂ the
//!   decoded n_i, and the residual W_i/q − rint(w·n̂), mostly 0. The normal
//!   details w_i = W_i·n_i are recomputed from the decoded values.
//! - **φ_T** as one signed byte per node in voxel units: c/64 within one voxel of the surface
//!   (steps of h/64), beyond it 1 + (|c| − 64)·far/h voxels (far ≥ [`PHI_FAR_VOXELS`]·h), up to
//!   the reach: [`PHI_REACH_VOXELS`] voxels or the largest detail plus 4 voxels, whichever is
//!   farther (the level-set reconstruction reads only the side of φ_T beyond its band of the
//!   largest detail plus 2 voxels); farther values are stored as the reach.
//!
//! Every rounding is `rint` (ties to even, as NumPy's `np.rint`), so a NumPy reader decodes the
//! same values; the archive module doc gives the formulas.

use super::{Msr, MsrParams};
use crate::grid::{Grid3, GridTransform};
use nalgebra::{Point3, Vector3};

/// The lattice step of the positions and details, in voxels of φ_T.
pub const QUANTUM_VOXELS: f64 = 0.02;
/// The positions at birth are on a lattice this many times finer.
pub const BIRTH_SUBSTEPS: f64 = 16.0;
/// Octahedral normal codes run over −NORMAL_STEPS..=NORMAL_STEPS on each of their two axes.
pub const NORMAL_STEPS: i32 = 127;
/// Both axes of the code of a zero normal.
pub const ZERO_CODE: i32 = NORMAL_STEPS + 1;
/// φ_T codes within one voxel of the surface: this many per voxel.
pub const PHI_NEAR_STEPS: f64 = 64.0;
/// φ_T codes beyond the first voxel: steps of at least this many voxels.
pub const PHI_FAR_VOXELS: f64 = 0.25;
/// The largest φ_T code stands at least this many voxels from the surface.
pub const PHI_REACH_VOXELS: f64 = 8.0;

/// An [`Msr`] as its version-3 archive holds it (see the module doc; flat arrays in C order).
#[derive(Debug, Clone, PartialEq)]
pub struct CompactMsr {
    pub faces: Vec<[u32; 3]>,
    /// The input mesh's vertices (samples `0..V`), exactly.
    pub vertices: Vec<[f64; 3]>,
    pub extra_face: Vec<u32>,
    pub extra_bary: Vec<[f64; 3]>,
    /// Lattice step q, world units.
    pub quantum: f64,
    /// Lattice step q_b of the positions at birth (snap, added_at), world units.
    pub birth_quantum: f64,
    /// rint(snap / q_b), I×3.
    pub snap: Vec<i32>,
    /// For each sample added after the input (`I..S`): rint((X_born − origin of φ_T) / q_b), ×3.
    pub added_at: Vec<i32>,
    pub born: Vec<u32>,
    /// (N+1)×S×2 octahedral codes of n_0..n_N, each level less the level before.
    pub normals: Vec<i32>,
    /// N×S: rint(W_i·n̂_i / q).
    pub normal_details: Vec<i32>,
    /// N×S×3: W_i / q − rint(w·n̂_i).
    pub residuals: Vec<i32>,
    pub times: Vec<f64>,
    /// nz×ny×nx, x fastest.
    pub phi: Vec<i8>,
    pub phi_dims: [usize; 3],
    pub phi_origin: [f64; 3],
    pub phi_voxel: f64,
    /// World units per φ code beyond the first voxel.
    pub phi_far: f64,
    pub params: MsrParams,
}

/// The compact coding of `msr` (see the module doc).
pub fn encode_msr(msr: &Msr) -> CompactMsr {
    let h = msr.phi.voxel();
    let q = QUANTUM_VOXELS * h;
    let qb = q / BIRTH_SUBSTEPS;
    let origin = Vector3::from(msr.phi.transform().origin);
    let n = msr.levels();
    let s = msr.samples.len();
    let inputs = msr.snap.len();
    let xs: Vec<Vec<Point3<f64>>> = (0..=n).map(|k| msr.samples_at(k)).collect();
    let vertices: Vec<[f64; 3]> = (0..msr.num_vertices)
        .map(|k| (xs[0][k] - msr.snap[k]).coords.into())
        .collect();
    let positions = input_positions(
        &vertices,
        &msr.faces,
        &msr.extra_face,
        &msr.extra_bary,
        inputs,
    );
    // X_0 less the input position as placed here (for a decomposition's samples, its snap).
    let snap: Vec<i32> = (0..inputs)
        .flat_map(|k| {
            let v = xs[0][k].coords - positions[k];
            [v.x, v.y, v.z].map(|c| rint(c / qb) as i32)
        })
        .collect();
    let mut added_at = Vec::with_capacity(3 * (s - inputs));
    let bases: Vec<Vector3<f64>> = (0..s)
        .map(|k| {
            if k < inputs {
                positions[k] + lattice(&snap[3 * k..3 * k + 3], qb)
            } else {
                let b = msr.born[k] as usize;
                let code: Vec<i32> = (xs[b][k].coords - origin)
                    .iter()
                    .map(|&c| rint(c / qb) as i32)
                    .collect();
                added_at.extend_from_slice(&code);
                origin + lattice(&code, qb)
            }
        })
        .collect();
    let codes: Vec<Vec<[i32; 2]>> = msr
        .normals
        .iter()
        .map(|level| level.iter().map(encode_normal).collect())
        .collect();
    let mut normals = Vec::with_capacity(2 * (n + 1) * s);
    for (i, level) in codes.iter().enumerate() {
        for (k, c) in level.iter().enumerate() {
            let before = if i == 0 { [0, 0] } else { codes[i - 1][k] };
            normals.extend([c[0] - before[0], c[1] - before[1]]);
        }
    }
    let mut normal_details = Vec::with_capacity(n * s);
    let mut residuals = Vec::with_capacity(3 * n * s);
    for i in 1..=n {
        for k in 0..s {
            let b = msr.born[k] as usize;
            let step = |x: &Point3<f64>| -> [i64; 3] {
                let d = (x.coords - bases[k]) / q;
                [rint(d.x) as i64, rint(d.y) as i64, rint(d.z) as i64]
            };
            let w: [i64; 3] = if i <= b {
                [0; 3]
            } else {
                let (a, c) = (
                    if i - 1 <= b {
                        [0; 3]
                    } else {
                        step(&xs[i - 1][k])
                    },
                    step(&xs[i][k]),
                );
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]]
            };
            let nh = decode_normal(codes[i][k]);
            let along = rint(w[0] as f64 * nh.x + w[1] as f64 * nh.y + w[2] as f64 * nh.z);
            let pred = predicted(along as i64, &nh);
            normal_details.push(along as i32);
            residuals.extend((0..3).map(|a| (w[a] - pred[a]) as i32));
        }
    }
    let largest = msr.largest_detail();
    let reach = (PHI_REACH_VOXELS * h).max(largest + 4.0 * h);
    let phi_far = (PHI_FAR_VOXELS * h).max((reach - h) / (127.0 - PHI_NEAR_STEPS));
    let phi = msr
        .phi
        .data()
        .iter()
        .map(|&v| encode_phi((v as f64).clamp(-reach, reach), h, phi_far))
        .collect();
    CompactMsr {
        faces: msr.faces.clone(),
        vertices,
        extra_face: msr.extra_face.clone(),
        extra_bary: msr.extra_bary.clone(),
        quantum: q,
        birth_quantum: qb,
        snap,
        added_at,
        born: msr.born.clone(),
        normals,
        normal_details,
        residuals,
        times: msr.times.clone(),
        phi,
        phi_dims: msr.phi.dims(),
        phi_origin: msr.phi.transform().origin,
        phi_voxel: h,
        phi_far,
        params: msr.params.clone(),
    }
}

/// The [`Msr`] the codes stand for. The shapes must agree (the archive reader checks them);
/// a code out of range or a position that is not finite is an error naming the member.
pub fn decode_msr(c: &CompactMsr) -> std::result::Result<Msr, String> {
    let q = c.quantum;
    let qb = c.birth_quantum;
    let s = c.born.len();
    let n = c.times.len() - 1;
    let inputs = c.snap.len() / 3;
    let origin = Vector3::from(c.phi_origin);
    let positions = input_positions(&c.vertices, &c.faces, &c.extra_face, &c.extra_bary, inputs);
    let snap: Vec<Vector3<f64>> = c.snap.chunks_exact(3).map(|v| lattice(v, qb)).collect();
    let bases: Vec<Vector3<f64>> = (0..s)
        .map(|k| {
            if k < inputs {
                positions[k] + snap[k]
            } else {
                let a = 3 * (k - inputs);
                origin + lattice(&c.added_at[a..a + 3], qb)
            }
        })
        .collect();
    let h = c.phi_voxel;
    let transform = GridTransform::new(Point3::from(c.phi_origin), h);
    let values = c
        .phi
        .iter()
        .map(|&code| decode_phi(code, h, c.phi_far))
        .collect();
    let phi = Grid3::from_data(c.phi_dims, transform, values)
        .map_err(|e| format!("member 'phi': {e}"))?;
    let mut normals = Vec::with_capacity(n + 1);
    let mut code = vec![[0i64; 2]; s];
    for i in 0..=n {
        let level = (0..s)
            .map(|k| {
                let d = &c.normals[2 * (i * s + k)..2 * (i * s + k) + 2];
                code[k] = [code[k][0] + d[0] as i64, code[k][1] + d[1] as i64];
                let ok = |v: i64| v.abs() <= NORMAL_STEPS as i64;
                match code[k] {
                    [u, v] if ok(u) && ok(v) => Ok(decode_normal([u as i32, v as i32])),
                    [u, v] if u == ZERO_CODE as i64 && v == ZERO_CODE as i64 => {
                        Ok(Vector3::zeros())
                    }
                    [u, v] => Err(format!(
                        "member 'normals': sample {k} at level {i} has the code ({u}, {v}), \
                         not within ±{NORMAL_STEPS}"
                    )),
                }
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        normals.push(level);
    }
    let mut steps = vec![[0i64; 3]; s];
    let mut details = Vec::with_capacity(n);
    for (i, level_normals) in normals.iter().enumerate().skip(1) {
        let mut level = Vec::with_capacity(s);
        for (k, nk) in level_normals.iter().enumerate() {
            let j = (i - 1) * s + k;
            let pred = predicted(c.normal_details[j] as i64, nk);
            let r = &c.residuals[3 * j..3 * j + 3];
            let w = [0, 1, 2].map(|a| pred[a] + r[a] as i64);
            steps[k] = [0, 1, 2].map(|a| steps[k][a] + w[a]);
            level.push(Vector3::new(w[0] as f64, w[1] as f64, w[2] as f64) * q);
        }
        details.push(level);
    }
    let samples: Vec<Point3<f64>> = (0..s)
        .map(|k| {
            let p = steps[k];
            Point3::from(bases[k] + Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) * q)
        })
        .collect();
    if let Some(k) = samples
        .iter()
        .position(|p| !p.coords.iter().all(|c| c.is_finite()))
    {
        return Err(format!(
            "sample {k} decodes to a position that is not finite (members 'quantum', \
             'added_at', 'residuals')"
        ));
    }
    // w_i = W_i·n_i, as the decomposition defines it, from the decoded values.
    let normal_details = (1..=n)
        .map(|i| {
            (details[i - 1].iter().zip(&normals[i]))
                .map(|(w, nn)| w.dot(nn))
                .collect()
        })
        .collect();
    Ok(Msr {
        faces: c.faces.clone(),
        num_vertices: c.vertices.len(),
        extra_face: c.extra_face.clone(),
        extra_bary: c.extra_bary.clone(),
        snap,
        born: c.born.clone(),
        samples,
        details,
        normal_details,
        normals,
        times: c.times.clone(),
        phi,
        params: c.params.clone(),
    })
}

/// Bytes the decoded representation of S samples, N levels and a φ of `nodes` nodes takes.
pub fn decoded_bytes(samples: usize, levels: usize, nodes: usize) -> u64 {
    // X_N, snap, N details, N normal details, N + 1 normals (f64) and φ (f32).
    let per_sample = 8 * (3 + 3 + 3 * levels + levels + 3 * (levels + 1)) as u64;
    (samples as u64)
        .saturating_mul(per_sample)
        .saturating_add((nodes as u64).saturating_mul(4))
}

/// NumPy's `np.rint`: to the nearest integer, ties to even.
fn rint(x: f64) -> f64 {
    x.round_ties_even()
}

fn lattice(code: &[i32], q: f64) -> Vector3<f64> {
    Vector3::new(code[0] as f64, code[1] as f64, code[2] as f64) * q
}

/// rint(along · n) on each axis: the lattice detail the normal component stands for.
fn predicted(along: i64, n: &Vector3<f64>) -> [i64; 3] {
    let a = along as f64;
    [
        rint(a * n.x) as i64,
        rint(a * n.y) as i64,
        rint(a * n.z) as i64,
    ]
}

/// Where each input sample lies on the input mesh: the vertices, then each extra sample's
/// barycentric combination of its face's corners (as [`super::sample`] placed it).
fn input_positions(
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
    extra_face: &[u32],
    extra_bary: &[[f64; 3]],
    inputs: usize,
) -> Vec<Vector3<f64>> {
    let v = |i: u32| Vector3::from(vertices[i as usize]);
    let mut out: Vec<Vector3<f64>> = vertices.iter().map(|&p| Vector3::from(p)).collect();
    out.extend(extra_face.iter().zip(extra_bary).map(|(&f, b)| {
        let [x, y, z] = faces[f as usize];
        v(x) * b[0] + v(y) * b[1] + v(z) * b[2]
    }));
    debug_assert_eq!(out.len(), inputs);
    out
}

/// The octahedral code of a unit normal (a zero normal: [`ZERO_CODE`] twice).
pub fn encode_normal(n: &Vector3<f64>) -> [i32; 2] {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if l1.is_nan() || l1 <= 0.5 {
        return [ZERO_CODE; 2];
    }
    let (x, y) = (n.x / l1, n.y / l1);
    let (u, v) = if n.z < 0.0 {
        ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y))
    } else {
        (x, y)
    };
    let m = NORMAL_STEPS as f64;
    [rint(u * m) as i32, rint(v * m) as i32]
}

/// The unit normal of an octahedral code within ±[`NORMAL_STEPS`].
pub fn decode_normal(code: [i32; 2]) -> Vector3<f64> {
    if code == [ZERO_CODE; 2] {
        return Vector3::zeros();
    }
    let m = NORMAL_STEPS as f64;
    let (u, v) = (code[0] as f64 / m, code[1] as f64 / m);
    let z = 1.0 - u.abs() - v.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - v.abs()) * sign(u), (1.0 - u.abs()) * sign(v))
    } else {
        (u, v)
    };
    Vector3::new(x, y, z).normalize()
}

/// ±1 (+1 at zero, as the octahedral fold needs).
fn sign(x: f64) -> f64 {
    if x < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// The byte code of a φ value (see the module doc); a nonzero value keeps its sign.
fn encode_phi(v: f64, h: f64, far: f64) -> i8 {
    let a = v.abs() / h;
    let code = if a <= 1.0 {
        rint(a * PHI_NEAR_STEPS)
    } else {
        PHI_NEAR_STEPS + rint((a - 1.0) * h / far)
    };
    let code = if v != 0.0 { code.max(1.0) } else { 0.0 }.min(127.0);
    (code.copysign(v)) as i8
}

/// The φ value of a byte code.
fn decode_phi(code: i8, h: f64, far: f64) -> f32 {
    let a = (code as f64).abs();
    let v = if a <= PHI_NEAR_STEPS {
        a / PHI_NEAR_STEPS * h
    } else {
        h + (a - PHI_NEAR_STEPS) * far
    };
    v.copysign(code as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_code_within_a_degree() {
        let mut worst: f64 = 0.0;
        for i in 0..40 {
            for j in 0..80 {
                let (t, p) = (
                    std::f64::consts::PI * i as f64 / 39.0,
                    std::f64::consts::TAU * j as f64 / 80.0,
                );
                let n = Vector3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                let back = decode_normal(encode_normal(&n));
                worst = worst.max(back.angle(&n).to_degrees());
            }
        }
        assert!(worst < 1.0, "worst {worst}°");
        assert_eq!(
            decode_normal(encode_normal(&Vector3::zeros())),
            Vector3::zeros()
        );
    }

    #[test]
    fn phi_codes_keep_sign_and_near_precision() {
        let (h, far) = (0.3, 0.3 * 7.0 / 63.0);
        for v in [
            -2.0, -0.31, -0.001, 0.0, 1e-9, 0.05, 0.29, 0.31, 1.0, 2.4, 50.0,
        ] {
            let back = decode_phi(encode_phi(v, h, far), h, far) as f64;
            assert_eq!((back > 0.0, back < 0.0), (v > 0.0, v < 0.0), "{v} → {back}");
            let tol = if v.abs() <= h {
                h / 64.0
            } else {
                far / 2.0 + 1e-6
            };
            assert!(
                (back - v).abs() <= tol || v.abs() > h + 63.0 * far,
                "{v} → {back}"
            );
        }
    }
}
