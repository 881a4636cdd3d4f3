//! The compact coding of an [`Msr`] that its archive stores (format version 4): the same
//! representation (paper Definition 2.1: the samples, the details W_1..W_N and φ_T) in small
//! integers, each predicted from what the reader has already decoded, so that they compress
//! tightly (version 3, [`super::compact_v3`], stored the codes themselves: 2.1 to 6.1× the mesh
//! file on the shared vessels, where this is 1.6 to 4.7×).
//!
//! - **The order of prediction** P: the samples sorted (stably, ties by index) by the Morton code
//!   of their voxel at birth, floor((p − origin of φ_T)/h) per axis (+2²⁰, three 21-bit axes
//!   interleaved, x lowest), p an input sample's position on the input mesh or an added
//!   sample's `added_at`·q_b. Consecutive samples in P are mostly neighbours on the surface, so
//!   a value "predicted along P" over a set of samples is stored as its difference from the
//!   previous sample of the set in P (the first as it is): the reader takes cumulative sums.
//! - **Normals** n_0..n_N as octahedral codes (two integers in −[`NORMAL_STEPS`]..=
//!   [`NORMAL_STEPS`], within about 1° of the unit normal; a zero normal — where ∇φ vanished —
//!   is the code ([`ZERO_CODE`], [`ZERO_CODE`])). None is stored before a sample's birth. At its
//!   birth level a sample's code is predicted along P among the samples born at that level,
//!   except an extra input sample's (on a face of the input mesh), which is stored less the code
//!   of its face's normal (b − a)×(c − a) times `face_normal_sign` (the sign that turns the
//!   mesh's faces outward). After the birth, each level's change of code, c_i − c_{i−1}, is
//!   predicted along P among the samples born before level i.
//! - **Positions**: X_i = X_{i−1} + q·(w·n̂_i + r) for i above the sample's birth, q =
//!   [`QUANTUM_VOXELS`]·h, n̂_i the decoded normal: the integer w is the detail's normal
//!   component rounded from the exact one, w = rint((X_i − X_{i−1}')·n̂_i / q), and the integer
//!   residual r (N×3, mostly 0) is nonzero only where X_i would otherwise be more than q/2 off
//!   on an axis: then r = rint(E) with E the offset in steps of q, so every decoded X_i is within
//!   q/2 per axis of the exact one at every level (the error never adds up, and along the normal
//!   it is within q/2). (The details lie along the normals: the exact W_i's tangential part is
//!   below a thousandth of q on most samples, so only the rounding needs r.) The w of each level
//!   are predicted along P among the samples born before it. The detail is W_i = q·(w·n̂_i + r);
//!   the normal details w_i = W_i·n_i are recomputed from the decoded values.
//! - **Positions at birth** on a lattice [`BIRTH_SUBSTEPS`] times finer, q_b: an input sample's
//!   input position (the mesh vertices exactly, the extra samples by their barycentric
//!   coordinates) plus its snap q_b·(t·n̂_0 + r) (t the snap's normal component, r nonzero only
//!   where it would be more than q_b/2 off on an axis, as above); a sample added at level b as
//!   its position relative to φ_T's origin, `added_at` (rint((X_b − origin)/q_b)).
//! - **Refinement** where the level-set reconstruction needs it: the writer rebuilds each S̃_k
//!   (k < N) from the representation (φ̃_{k+1} carried back from φ_T level by level) and
//!   compares, at the nodes within a voxel of S̃_k, what the tangent-plane rebuild gives them
//!   from the decoded samples of S_k with what it gives from the exact ones; the samples within
//!   [`REFINE_RADIUS_VOXELS`] of a node off by more than [`REFINE_TOLERANCE_VOXELS`] or of the
//!   other sign get, at that level k, a normal code [`REFINE_NORMAL_STEPS`] times finer and a
//!   position offset in steps of q/[`REFINE_POSITION_STEPS`] (added to X_k, so the later
//!   levels are coded from there), in two rounds. (That rebuild turns on hundredths of a voxel
//!   in places — a sample's plane taken alone or averaged, a sign at a pinch — so rounding alone
//!   moved S̃_k by up to 0.08h somewhere on the shared vessels, at any lattice step tried down
//!   to 0.005h; refined, the reconstructions from the archive and from memory are within
//!   0.036h of each other at every level, for 1–3% of the samples per level refined.)
//! - **φ_T** as one signed byte per node in voxel units: c/64 within one voxel of the surface
//!   (steps of h/64), beyond it 1 + (|c| − 64)·far/h voxels (far ≥ [`PHI_FAR_VOXELS`]·h), up to
//!   the reach: [`PHI_REACH_VOXELS`] voxels or the largest detail plus 4 voxels, whichever is
//!   farther (the level-set reconstruction reads only the side of φ_T beyond its band of the
//!   largest detail plus 2 voxels); farther values are stored as the reach.
//!
//! Every rounding is `rint` (ties to even, as NumPy's `np.rint`) and every prediction is made
//! from integers or from float64 values the reader computes by the same operations in the same
//! order, so a NumPy reader decodes the same values; the archive module doc gives the formulas.

use super::reconstruct::{rebuild_from_tangent_planes, AdvectOptions, TangentPlanes};
use super::{Msr, MsrParams};
use crate::grid::{Grid3, GridTransform};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

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
/// A refined position has an offset in steps of q / REFINE_POSITION_STEPS.
pub const REFINE_POSITION_STEPS: f64 = 64.0;
/// A refined normal's octahedral code is this many times finer.
pub const REFINE_NORMAL_STEPS: i32 = 32;
/// A node near S̃_k whose rebuild from the codes differs by more than this (voxels), or in
/// sign, from the one from the representation gets its samples refined.
pub const REFINE_TOLERANCE_VOXELS: f64 = 0.02;
/// ... those of S_k within this many voxels of it.
pub const REFINE_RADIUS_VOXELS: f64 = 1.0;
/// Rounds of checking and refining.
const REFINE_ROUNDS: usize = 2;
/// Offset added to each axis of a voxel index before the Morton code of the order P.
const MORTON_OFFSET: i64 = 1 << 20;

/// An [`Msr`] as its version-4 archive holds it (see the module doc; flat arrays in C order,
/// per sample in sample order).
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
    /// I: the snap's normal component t, in steps of q_b along n̂_0.
    pub snap_normal: Vec<i32>,
    /// I×3: the snap's residual r, in steps of q_b.
    pub snap_residual: Vec<i32>,
    /// For each sample added after the input (`I..S`): rint((X_born − origin of φ_T) / q_b), ×3.
    pub added_at: Vec<i32>,
    pub born: Vec<u32>,
    /// ±1: turns (b − a)×(c − a) of the input's faces outward (the prediction of the extra
    /// samples' n_0).
    pub face_normal_sign: i32,
    /// (N+1)×S×2: the normal codes as predicted (see the module doc; 0 before birth).
    pub normals: Vec<i32>,
    /// N×S: the normal components w, predicted along P (0 before birth).
    pub normal_details: Vec<i32>,
    /// N×S×3: the residuals r in steps of q (0 before birth).
    pub residuals: Vec<i32>,
    /// The refined (level, sample) pairs as level·S + sample, increasing.
    pub refine_key: Vec<u64>,
    /// R×3: each refined position's offset in steps of q/[`REFINE_POSITION_STEPS`].
    pub refine_position: Vec<i32>,
    /// R×2: each refined normal's fine code (over ±[`NORMAL_STEPS`]·[`REFINE_NORMAL_STEPS`])
    /// less [`REFINE_NORMAL_STEPS`] times its code (0 for a zero normal).
    pub refine_normal: Vec<i32>,
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

/// The compact coding of `msr` (see the module doc), refined where the level-set
/// reconstruction from the codes would read a node otherwise than from `msr`.
pub fn encode_msr(msr: &Msr) -> CompactMsr {
    let mut refine: Vec<Vec<bool>> = vec![vec![false; msr.samples.len()]; msr.levels() + 1];
    let mut c = encode_refined(msr, &refine);
    let Some(reference) = reference(msr) else {
        return c;
    };
    // Each round refines what the codes so far misread; the second finds a few percent of the
    // first's (the aneurysm: 5489 then 159 samples), and a third none.
    for _ in 0..REFINE_ROUNDS {
        let Ok(decoded) = decode_msr(&c) else {
            return c;
        };
        if mark_misread(msr, &decoded, &reference, &mut refine) == 0 {
            break;
        }
        c = encode_refined(msr, &refine);
    }
    c
}

/// What the refinement compares with: for each level k < N, φ̃_{k+1} rebuilt from `msr` level
/// by level from φ_T (φ_T itself for k = N − 1), the nodes within a voxel of S̃_k and the values
/// the tangent-plane rebuild gives them from `msr`'s samples of S_k.
struct Reference {
    phis: Vec<Grid3>,
    near: Vec<Vec<usize>>,
    values: Vec<Vec<f32>>,
}

/// The [`Reference`] of `msr` (None where a rebuild fails).
fn reference(msr: &Msr) -> Option<Reference> {
    let n = msr.levels();
    let h = msr.phi.voxel();
    let opts = AdvectOptions::default();
    let mut phis = vec![msr.phi.clone()];
    let (mut near, mut values) = (Vec::new(), Vec::new());
    for i in (1..=n).rev() {
        let data = msr.level_data(i);
        let above = phis.last()?;
        let planes = TangentPlanes::new(above, &data.points, &data.normals, &data.details, &opts);
        let rebuilt =
            rebuild_from_tangent_planes(above, &data.points, &data.normals, &data.details, &opts)
                .ok()?;
        let nodes: Vec<usize> = (0..rebuilt.data().len())
            .filter(|&j| (rebuilt.data()[j].abs() as f64) < h)
            .collect();
        values.push(
            nodes
                .par_iter()
                .map(|&j| planes.node_value(above, j))
                .collect(),
        );
        near.push(nodes);
        if i > 1 {
            phis.push(rebuilt);
        }
    }
    phis.reverse();
    near.reverse();
    values.reverse();
    Some(Reference { phis, near, values })
}

/// Marks for refinement, at each level k < N, the samples of S_k within
/// [`REFINE_RADIUS_VOXELS`] of a node near S̃_k to which the tangent-plane rebuild from
/// φ̃_{k+1} and the `decoded` samples gives a value more than [`REFINE_TOLERANCE_VOXELS`] off
/// the one from `msr`'s, or of the other sign. Returns how many were newly marked.
fn mark_misread(
    msr: &Msr,
    decoded: &Msr,
    reference: &Reference,
    refine: &mut [Vec<bool>],
) -> usize {
    let h = msr.phi.voxel();
    let n = msr.levels();
    let tol = (REFINE_TOLERANCE_VOXELS * h) as f32;
    let radius = REFINE_RADIUS_VOXELS * h;
    let mut marked = 0;
    for (k, refine_k) in refine.iter_mut().enumerate().take(n) {
        let data = decoded.level_data(k + 1);
        let phi = &reference.phis[k];
        let planes = TangentPlanes::new(
            phi,
            &data.points,
            &data.normals,
            &data.details,
            &AdvectOptions::default(),
        );
        let nodes = &reference.near[k];
        let bad: Vec<Point3<f64>> = nodes
            .par_iter()
            .zip(&reference.values[k])
            .filter_map(|(&j, &x)| {
                let y = planes.node_value(phi, j);
                ((x - y).abs() > tol || (x < 0.0) != (y < 0.0)).then(|| {
                    let [i0, i1, i2] = phi.coords(j);
                    phi.world(i0, i1, i2)
                })
            })
            .collect();
        if bad.is_empty() {
            continue;
        }
        let mut cells: std::collections::HashMap<[i64; 3], Vec<Point3<f64>>> = Default::default();
        for p in bad {
            cells
                .entry([0, 1, 2].map(|c| (p[c] / radius).floor() as i64))
                .or_default()
                .push(p);
        }
        let xk = msr.samples_at(k);
        for (s, p) in xk.iter().enumerate() {
            if msr.born[s] as usize > k || refine_k[s] {
                continue;
            }
            let key = [0, 1, 2].map(|c| (p[c] / radius).floor() as i64);
            let hit = (-1..=1).any(|dz| {
                (-1..=1).any(|dy| {
                    (-1..=1).any(|dx| {
                        cells
                            .get(&[key[0] + dx, key[1] + dy, key[2] + dz])
                            .is_some_and(|v| v.iter().any(|q| (q - p).norm() <= radius))
                    })
                })
            });
            if hit {
                refine_k[s] = true;
                marked += 1;
            }
        }
    }
    marked
}

/// The coding of `msr` with the (level, sample) pairs of `refine` refined.
fn encode_refined(msr: &Msr, refine: &[Vec<bool>]) -> CompactMsr {
    let h = msr.phi.voxel();
    let q = QUANTUM_VOXELS * h;
    let qb = q / BIRTH_SUBSTEPS;
    let origin = Vector3::from(msr.phi.transform().origin);
    let n = msr.levels();
    let s = msr.samples.len();
    let inputs = msr.snap.len();
    let nv = msr.num_vertices;
    let xs: Vec<Vec<Point3<f64>>> = (0..=n).map(|k| msr.samples_at(k)).collect();
    let vertices: Vec<[f64; 3]> = (0..nv)
        .map(|k| (xs[0][k] - msr.snap[k]).coords.into())
        .collect();
    let positions = input_positions(
        &vertices,
        &msr.faces,
        &msr.extra_face,
        &msr.extra_bary,
        inputs,
    );
    let mut added_at = Vec::with_capacity(3 * (s - inputs));
    for (k, &b) in msr.born.iter().enumerate().skip(inputs) {
        let b = b as usize;
        added_at.extend(
            (xs[b][k].coords - origin)
                .iter()
                .map(|&c| rint(c / qb) as i32),
        );
    }
    let order = prediction_order(&positions, &added_at, qb, &origin, h);
    let codes: Vec<Vec<[i32; 2]>> = msr
        .normals
        .iter()
        .map(|level| level.iter().map(encode_normal).collect())
        .collect();
    let faces_normals = face_normal_codes(&vertices, &msr.faces, &msr.extra_face, 1);
    // The sign that turns the input's faces the way the normals n_0 of their samples point.
    let agree: f64 = (nv..inputs)
        .map(|k| {
            let [a, b, c] =
                msr.faces[msr.extra_face[k - nv] as usize].map(|i| vertices[i as usize]);
            face_cross(&a, &b, &c).dot(&msr.normals[0][k])
        })
        .sum();
    let face_normal_sign = if agree < 0.0 { -1 } else { 1 };
    let extra_pred: Vec<[i32; 2]> = if face_normal_sign == 1 {
        faces_normals
    } else {
        face_normal_codes(&vertices, &msr.faces, &msr.extra_face, -1)
    };
    let mut normals = vec![0i32; 2 * (n + 1) * s];
    for i in 0..=n {
        let at = |k: usize| 2 * (i * s + k);
        let born_here =
            |k: usize| msr.born[k] as usize == i && !(i == 0 && (nv..inputs).contains(&k));
        predict_along(
            &order,
            born_here,
            |k| codes[i][k],
            |k, v| normals[at(k)..at(k) + 2].copy_from_slice(&v),
        );
        if i == 0 {
            for k in nv..inputs {
                let p = extra_pred[k - nv];
                normals[at(k)] = codes[0][k][0] - p[0];
                normals[at(k) + 1] = codes[0][k][1] - p[1];
            }
        } else {
            let change = |k: usize| {
                let (c, b) = (codes[i][k], codes[i - 1][k]);
                [c[0] - b[0], c[1] - b[1]]
            };
            predict_along(
                &order,
                |k| (msr.born[k] as usize) < i,
                change,
                |k, v| normals[at(k)..at(k) + 2].copy_from_slice(&v),
            );
        }
    }
    let mut refine_key = Vec::new();
    let mut refine_normal = Vec::new();
    let decoded: Vec<Vec<Vector3<f64>>> = codes
        .iter()
        .enumerate()
        .map(|(i, level)| {
            (level.iter().enumerate())
                .map(|(k, &c)| {
                    if !refine[i][k] {
                        return decode_normal(c);
                    }
                    refine_key.push((i * s + k) as u64);
                    if c == [ZERO_CODE; 2] {
                        refine_normal.extend([0, 0]);
                        return Vector3::zeros();
                    }
                    let fine = fine_code(&msr.normals[i][k]);
                    let g = [0, 1].map(|a| fine[a] - REFINE_NORMAL_STEPS * c[a]);
                    refine_normal.extend(g);
                    decode_fine(c, g)
                })
                .collect()
        })
        .collect();
    let mut refine_position = vec![0i32; 3 * refine_key.len()];
    let refined_at = |i: usize, k: usize| refine_key.binary_search(&((i * s + k) as u64)).ok();
    let qf = q / REFINE_POSITION_STEPS;
    // The snap: its normal component and, where needed, a residual (steps of q_b).
    let mut snap_normal = Vec::with_capacity(inputs);
    let mut snap_residual = Vec::with_capacity(3 * inputs);
    let mut bases: Vec<Vector3<f64>> = Vec::with_capacity(s);
    let mut snaps: Vec<Vector3<f64>> = Vec::with_capacity(inputs);
    for k in 0..inputs {
        // X_0 less the input position as placed here (for a decomposition's samples, its snap).
        let snap = xs[0][k].coords - positions[k];
        let (t, r, step) = normal_step(&snap, &decoded[0][k], qb);
        snap_normal.push(t as i32);
        snap_residual.extend(r.map(|v| v as i32));
        snaps.push(step);
        bases.push(positions[k] + step);
    }
    for k in inputs..s {
        let a = 3 * (k - inputs);
        bases.push(origin + lattice(&added_at[a..a + 3], qb));
    }
    // A refined position at birth: the base plus its fine offset.
    for (k, base) in bases.iter_mut().enumerate() {
        let b = msr.born[k] as usize;
        if let Some(j) = refined_at(b, k) {
            let f = fine_offset(&(xs[b][k].coords - *base), qf);
            refine_position[3 * j..3 * j + 3].copy_from_slice(&f);
            // An input sample's offset is part of its snap (as the reader adds it).
            *base = match k < inputs {
                true => positions[k] + (snaps[k] + lattice(&f, qf)),
                false => *base + lattice(&f, qf),
            };
        }
    }
    let mut along = vec![0i64; n * s];
    let mut residuals = vec![0i32; 3 * n * s];
    for k in 0..s {
        let b = msr.born[k] as usize;
        let mut x = bases[k];
        for i in b + 1..=n {
            let (w, r, step) = normal_step(&(xs[i][k].coords - x), &decoded[i][k], q);
            along[(i - 1) * s + k] = w;
            residuals[3 * ((i - 1) * s + k)..3 * ((i - 1) * s + k) + 3]
                .copy_from_slice(&r.map(|v| v as i32));
            x += step;
            if let Some(j) = refined_at(i, k) {
                let f = fine_offset(&(xs[i][k].coords - x), qf);
                refine_position[3 * j..3 * j + 3].copy_from_slice(&f);
                x += lattice(&f, qf);
            }
        }
    }
    let mut normal_details = vec![0i32; n * s];
    for i in 1..=n {
        predict_along(
            &order,
            |k| (msr.born[k] as usize) < i,
            |k| [along[(i - 1) * s + k] as i32],
            |k, v| normal_details[(i - 1) * s + k] = v[0],
        );
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
        snap_normal,
        snap_residual,
        added_at,
        born: msr.born.clone(),
        face_normal_sign,
        normals,
        normal_details,
        residuals,
        refine_key,
        refine_position,
        refine_normal,
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
    let nv = c.vertices.len();
    let inputs = c.snap_normal.len();
    let origin = Vector3::from(c.phi_origin);
    let h = c.phi_voxel;
    let positions = input_positions(&c.vertices, &c.faces, &c.extra_face, &c.extra_bary, inputs);
    let order = prediction_order(&positions, &c.added_at, qb, &origin, h);
    let refined_at = |i: usize, k: usize| c.refine_key.binary_search(&((i * s + k) as u64)).ok();
    let qf = q / REFINE_POSITION_STEPS;
    let fine = |j: usize| lattice(&c.refine_position[3 * j..3 * j + 3], qf);
    let extra_pred = face_normal_codes(&c.vertices, &c.faces, &c.extra_face, c.face_normal_sign);
    // The codes, level by level (see the module doc), then the normals they stand for.
    let mut codes = vec![[0i64; 2]; s];
    let mut normals: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(n + 1);
    for i in 0..=n {
        let stored = |k: usize| {
            let j = 2 * (i * s + k);
            [c.normals[j] as i64, c.normals[j + 1] as i64]
        };
        let born_here =
            |k: usize| c.born[k] as usize == i && !(i == 0 && (nv..inputs).contains(&k));
        let mut births = Vec::new();
        accumulate_along(&order, born_here, stored, |k, v| births.push((k, v)));
        let mut changes = Vec::new();
        if i > 0 {
            accumulate_along(
                &order,
                |k| (c.born[k] as usize) < i,
                stored,
                |k, v| changes.push((k, v)),
            );
        }
        for (k, v) in births {
            codes[k] = v;
        }
        for (k, v) in changes {
            codes[k] = [codes[k][0] + v[0], codes[k][1] + v[1]];
        }
        if i == 0 {
            for k in nv..inputs {
                let (d, p) = (stored(k), extra_pred[k - nv]);
                codes[k] = [d[0] + p[0] as i64, d[1] + p[1] as i64];
            }
        }
        let level = (0..s)
            .map(|k| {
                if (c.born[k] as usize) > i {
                    return Ok(Vector3::zeros());
                }
                let ok = |v: i64| v.abs() <= NORMAL_STEPS as i64;
                match codes[k] {
                    [u, v] if ok(u) && ok(v) => Ok(match refined_at(i, k) {
                        Some(j) => decode_fine(
                            [u as i32, v as i32],
                            [c.refine_normal[2 * j], c.refine_normal[2 * j + 1]],
                        ),
                        None => decode_normal([u as i32, v as i32]),
                    }),
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
    let snap: Vec<Vector3<f64>> = (0..inputs)
        .map(|k| {
            let r = &c.snap_residual[3 * k..3 * k + 3];
            step_of(c.snap_normal[k] as f64, &normals[0][k], r, qb)
        })
        .collect();
    // X_0 − snap is the input position exactly: a refined X_0's offset is part of its snap.
    let snap: Vec<Vector3<f64>> = (snap.into_iter().enumerate())
        .map(|(k, v)| match refined_at(0, k) {
            Some(j) => v + fine(j),
            None => v,
        })
        .collect();
    let mut x: Vec<Vector3<f64>> = (0..s)
        .map(|k| {
            if k < inputs {
                return positions[k] + snap[k];
            }
            let a = 3 * (k - inputs);
            let base = origin + lattice(&c.added_at[a..a + 3], qb);
            match refined_at(c.born[k] as usize, k) {
                Some(j) => base + fine(j),
                None => base,
            }
        })
        .collect();
    let mut details = Vec::with_capacity(n);
    for (i, level_normals) in normals.iter().enumerate().skip(1) {
        let mut w = Vec::new();
        accumulate_along(
            &order,
            |k| (c.born[k] as usize) < i,
            |k| [c.normal_details[(i - 1) * s + k] as i64],
            |k, v| w.push((k, v[0])),
        );
        let mut along = vec![0i64; s];
        for (k, v) in w {
            along[k] = v;
        }
        let level: Vec<Vector3<f64>> = (0..s)
            .map(|k| {
                if (c.born[k] as usize) >= i {
                    return Vector3::zeros();
                }
                let j = 3 * ((i - 1) * s + k);
                let step = step_of(
                    along[k] as f64,
                    &level_normals[k],
                    &c.residuals[j..j + 3],
                    q,
                );
                match refined_at(i, k) {
                    Some(j) => step + fine(j),
                    None => step,
                }
            })
            .collect();
        for (p, d) in x.iter_mut().zip(&level) {
            *p += d;
        }
        details.push(level);
    }
    let samples: Vec<Point3<f64>> = x.into_iter().map(Point3::from).collect();
    if let Some(k) = samples
        .iter()
        .position(|p| !p.coords.iter().all(|c| c.is_finite()))
    {
        return Err(format!(
            "sample {k} decodes to a position that is not finite (members 'quantum', \
             'added_at', 'normal_details', 'residuals')"
        ));
    }
    let phi = decode_phi_grid(&c.phi, c.phi_dims, c.phi_origin, h, c.phi_far)?;
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
        num_vertices: nv,
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

/// The offset `d` as q·(t·n + r): t = rint(d·n / q), and r = rint(d/q − t·n) only where that
/// is more than half a step off on an axis (else 0). Returns (t, r, the offset decoded).
fn normal_step(d: &Vector3<f64>, n: &Vector3<f64>, q: f64) -> (i64, [i64; 3], Vector3<f64>) {
    let t = rint(d.dot(n) / q);
    let e = d / q - n * t;
    let r = if e.amax() > 0.5 {
        [rint(e.x) as i64, rint(e.y) as i64, rint(e.z) as i64]
    } else {
        [0; 3]
    };
    let r32 = r.map(|v| v as i32);
    (t as i64, r, step_of(t, n, &r32, q))
}

/// rint(d / q) per axis.
fn fine_offset(d: &Vector3<f64>, q: f64) -> [i32; 3] {
    [
        rint(d.x / q) as i32,
        rint(d.y / q) as i32,
        rint(d.z / q) as i32,
    ]
}

/// The octahedral code of a unit normal on the refined grid (±NORMAL_STEPS·REFINE_NORMAL_STEPS).
fn fine_code(n: &Vector3<f64>) -> [i32; 2] {
    octahedral(n, (NORMAL_STEPS * REFINE_NORMAL_STEPS) as f64)
}

/// The unit normal of code `c` refined by `g`: the fine code REFINE_NORMAL_STEPS·c + g.
fn decode_fine(c: [i32; 2], g: [i32; 2]) -> Vector3<f64> {
    let m = (NORMAL_STEPS * REFINE_NORMAL_STEPS) as f64;
    let f = [0, 1].map(|a| (REFINE_NORMAL_STEPS * c[a] + g[a]) as f64 / m);
    unfold(f[0], f[1])
}

/// q·(t·n + r), as the reader computes it.
fn step_of(t: f64, n: &Vector3<f64>, r: &[i32], q: f64) -> Vector3<f64> {
    Vector3::new(
        (t * n.x + r[0] as f64) * q,
        (t * n.y + r[1] as f64) * q,
        (t * n.z + r[2] as f64) * q,
    )
}

/// The order P of the module doc: the samples by the Morton code of their voxel at birth.
fn prediction_order(
    positions: &[Vector3<f64>],
    added_at: &[i32],
    qb: f64,
    origin: &Vector3<f64>,
    h: f64,
) -> Vec<usize> {
    let voxel = |v: f64| (v.floor() as i64 + MORTON_OFFSET).clamp(0, (1 << 21) - 1) as u64;
    let mut keys: Vec<u64> = positions
        .iter()
        .map(|p| morton([0, 1, 2].map(|a| voxel((p[a] - origin[a]) / h))))
        .collect();
    keys.extend(
        added_at
            .chunks_exact(3)
            .map(|c| morton([0, 1, 2].map(|a| voxel(c[a] as f64 * qb / h)))),
    );
    let mut order: Vec<usize> = (0..keys.len()).collect();
    order.sort_by_key(|&k| keys[k]);
    order
}

/// The three 21-bit axes interleaved, x in the lowest bit.
fn morton(v: [u64; 3]) -> u64 {
    let mut key = 0;
    for b in 0..21 {
        for (a, &x) in v.iter().enumerate() {
            key |= ((x >> b) & 1) << (3 * b + a);
        }
    }
    key
}

/// Stores `value` of the samples that `pick` accepts predicted along `order`: `store(k, v)`
/// gets its difference from the previous such sample's (the first's as it is).
fn predict_along<const D: usize>(
    order: &[usize],
    pick: impl Fn(usize) -> bool,
    value: impl Fn(usize) -> [i32; D],
    mut store: impl FnMut(usize, [i32; D]),
) {
    let mut before = [0i32; D];
    for &k in order.iter().filter(|&&k| pick(k)) {
        let v = value(k);
        store(k, std::array::from_fn(|a| v[a] - before[a]));
        before = v;
    }
}

/// The inverse of [`predict_along`]: `take(k, v)` gets each picked sample's value, the
/// cumulative sum of the stored differences along `order`.
fn accumulate_along<const D: usize>(
    order: &[usize],
    pick: impl Fn(usize) -> bool,
    stored: impl Fn(usize) -> [i64; D],
    mut take: impl FnMut(usize, [i64; D]),
) {
    let mut sum = [0i64; D];
    for &k in order.iter().filter(|&&k| pick(k)) {
        let d = stored(k);
        sum = std::array::from_fn(|a| sum[a] + d[a]);
        take(k, sum);
    }
}

/// (b − a)×(c − a).
fn face_cross(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3]) -> Vector3<f64> {
    let (a, b, c) = (Vector3::from(*a), Vector3::from(*b), Vector3::from(*c));
    let (u, v) = (b - a, c - a);
    Vector3::new(
        u.y * v.z - u.z * v.y,
        u.z * v.x - u.x * v.z,
        u.x * v.y - u.y * v.x,
    )
}

/// The octahedral code of `sign`·(b − a)×(c − a) of each extra sample's face.
fn face_normal_codes(
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
    extra_face: &[u32],
    sign: i32,
) -> Vec<[i32; 2]> {
    extra_face
        .iter()
        .map(|&f| {
            let [a, b, c] = faces[f as usize].map(|i| vertices[i as usize]);
            encode_direction(&(face_cross(&a, &b, &c) * sign as f64))
        })
        .collect()
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
pub(crate) fn rint(x: f64) -> f64 {
    x.round_ties_even()
}

fn lattice(code: &[i32], q: f64) -> Vector3<f64> {
    Vector3::new(code[0] as f64, code[1] as f64, code[2] as f64) * q
}

/// Where each input sample lies on the input mesh: the vertices, then each extra sample's
/// barycentric combination of its face's corners (as [`super::sample`] placed it).
pub(crate) fn input_positions(
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
    encode_direction(n)
}

/// The octahedral code of the direction of any nonzero vector ([`ZERO_CODE`] twice for a zero
/// or not finite one).
fn encode_direction(n: &Vector3<f64>) -> [i32; 2] {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if !(l1 > 0.0 && l1.is_finite()) {
        return [ZERO_CODE; 2];
    }
    octahedral(n, NORMAL_STEPS as f64)
}

/// The octahedral code of a nonzero vector's direction with `m` steps per axis.
fn octahedral(n: &Vector3<f64>, m: f64) -> [i32; 2] {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    let (x, y) = (n.x / l1, n.y / l1);
    let (u, v) = if n.z < 0.0 {
        ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y))
    } else {
        (x, y)
    };
    [rint(u * m) as i32, rint(v * m) as i32]
}

/// The unit vector of the octahedral coordinates (u, v) in −1..=1.
fn unfold(u: f64, v: f64) -> Vector3<f64> {
    let z = 1.0 - u.abs() - v.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - v.abs()) * sign(u), (1.0 - u.abs()) * sign(v))
    } else {
        (u, v)
    };
    Vector3::new(x, y, z).normalize()
}

/// The unit normal of an octahedral code within ±[`NORMAL_STEPS`].
pub fn decode_normal(code: [i32; 2]) -> Vector3<f64> {
    if code == [ZERO_CODE; 2] {
        return Vector3::zeros();
    }
    let m = NORMAL_STEPS as f64;
    unfold(code[0] as f64 / m, code[1] as f64 / m)
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
/// φ_T from its codes (both archive versions 3 and 4 store it alike).
pub(crate) fn decode_phi_grid(
    codes: &[i8],
    dims: [usize; 3],
    origin: [f64; 3],
    h: f64,
    far: f64,
) -> Result<Grid3, String> {
    let transform = GridTransform::new(Point3::from(origin), h);
    let values = codes.iter().map(|&code| decode_phi(code, h, far)).collect();
    Grid3::from_data(dims, transform, values).map_err(|e| format!("member 'phi': {e}"))
}

pub(crate) fn decode_phi(code: i8, h: f64, far: f64) -> f32 {
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
                // The direction of any multiple codes the same.
                assert_eq!(encode_direction(&(n * 3.7)), encode_normal(&n));
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

    #[test]
    fn predictions_along_an_order_invert() {
        let order = vec![3, 0, 4, 1, 2];
        let values = [[5, -1], [7, 2], [-3, 0], [1, 1], [0, 9]];
        let pick = |k: usize| k != 2;
        let mut stored = [[0i32; 2]; 5];
        predict_along(&order, pick, |k| values[k], |k, v| stored[k] = v);
        assert_eq!(stored[3], values[3]);
        assert_eq!(stored[0], [5 - 1, -1 - 1]);
        let mut back = [[0i64; 2]; 5];
        accumulate_along(
            &order,
            pick,
            |k| stored[k].map(|v| v as i64),
            |k, v| back[k] = v,
        );
        for k in [0, 1, 3, 4] {
            assert_eq!(back[k], values[k].map(|v| v as i64));
        }
        assert_eq!(morton([1, 0, 0]), 1);
        assert_eq!(morton([0, 1, 1]), 6);
        assert_eq!(morton([2, 0, 0]), 8);
    }
}
