//! The compact coding of format version 3 (written by earlier builds, still read; version 4 is
//! [`super::compact`]): positions on a lattice of step q = 0.02h, each sample's position at birth
//! on a lattice 16 times finer (an input sample's as its input position plus its snap, a sample
//! added later relative to φ_T's origin); later positions are the base plus whole lattice
//! steps, the details the differences of consecutive lattice positions, stored as their normal
//! component in steps of q along the decoded normal, w = rint(W_i·n̂_i / q), plus the residual
//! W_i/q − rint(w·n̂_i); normals as octahedral codes, each level less the level before (a zero
//! normal is the code (128, 128)); φ_T as in version 4.

use super::compact::{decode_normal, decode_phi_grid, input_positions, NORMAL_STEPS, ZERO_CODE};
use super::{Msr, MsrParams};
use nalgebra::{Point3, Vector3};

/// An [`Msr`] as its version-3 archive holds it (see the module doc; flat arrays in C order).
#[derive(Debug, Clone, PartialEq)]
pub struct CompactMsrV3 {
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

/// The [`Msr`] the codes stand for. The shapes must agree (the archive reader checks them);
/// a code out of range or a position that is not finite is an error naming the member.
pub fn decode_msr(c: &CompactMsrV3) -> std::result::Result<Msr, String> {
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
    let phi = decode_phi_grid(&c.phi, c.phi_dims, c.phi_origin, h, c.phi_far)?;
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
