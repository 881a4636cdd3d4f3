//! The closest-point transform of the redistancer ([`RedistanceScheme::ClosestPointTransform`]):
//! every node that is not frozen gets, exactly, the interface node whose crossing point is
//! nearest (the one the closest-point sweeps carry, found there only approximately: a sweep
//! offers a node the candidates of its upwind neighbours only), and φ is its distance to that
//! node's patch, as in the sweeps' write-back.
//!
//! The nearest point is found by a separable squared-distance transform: the lower envelope of
//! parabolas along one axis at a time (Felzenszwalb and Huttenlocher 2012, "Distance transforms
//! of sampled functions", Theory of Computing 8), each parabola carrying the id of its point.
//! A crossing point lies on a grid edge, so two of its coordinates are whole numbers: the points
//! are split by the axis of their edge, and each class starts with the exact 1-D nearest point
//! along that axis (on the line of nodes through the point), followed by envelopes along the
//! two other axes, over whole-number parabola centres. With the three classes:
//! D = min(E_z(min(E_y(N_x), E_x(N_y))), E_y(E_x(N_z))), N_a the 1-D nearest points of the
//! class of axis a and E_a the envelope along a. All but E_z run within one z-layer (one rayon
//! task per layer); E_z runs per y-layer of columns. Each step's order is fixed, so the result
//! does not depend on the number of threads. The cost is a fixed handful of passes over the
//! grid, whatever the distances (no sweeps to converge).
//!
//! [`RedistanceScheme::ClosestPointTransform`]: super::RedistanceScheme::ClosestPointTransform

use super::init::{patch_distance, Seeds};
use crate::grid::Grid3;
use rayon::prelude::*;

/// No interface node (a line or layer without points).
const NONE: u32 = u32::MAX;

/// The points of one class (crossings on edges along one axis), grouped by the line of nodes
/// along that axis they lie on (`start[line]..start[line + 1]`, ascending position).
struct Lines {
    start: Vec<usize>,
    /// Position along the axis, voxels.
    pos: Vec<f64>,
    /// Interface node (seed) of the point.
    id: Vec<u32>,
}

impl Lines {
    /// The points of line `line`: positions and ids.
    #[inline]
    fn line(&self, line: usize) -> (&[f64], &[u32]) {
        let r = self.start[line]..self.start[line + 1];
        (&self.pos[r.clone()], &self.id[r])
    }
}

/// Groups the seeds' crossing points by the axis of their edge (a point at its node counts as
/// x) and by line: the line of a point along x is j + ny·k, along y i + nx·k, along z i + nx·j.
fn classes(seeds: &Seeds, dims: [usize; 3]) -> [Lines; 3] {
    let [nx, ny, nz] = dims;
    let line_count = [ny * nz, nx * nz, nx * ny];
    let axis_of = |s: usize| {
        let off = seeds.patch[s].off;
        (0..3).find(|&a| off[a] != 0.0).unwrap_or(0)
    };
    let line_of = |s: usize, axis: usize| {
        let b = seeds.patch[s].base.map(|c| c as usize);
        match axis {
            0 => b[1] + ny * b[2],
            1 => b[0] + nx * b[2],
            _ => b[0] + nx * b[1],
        }
    };
    std::array::from_fn(|axis| {
        // Counting sort by line.
        let mut start = vec![0usize; line_count[axis] + 1];
        let members: Vec<usize> = (0..seeds.len()).filter(|&s| axis_of(s) == axis).collect();
        for &s in &members {
            start[line_of(s, axis) + 1] += 1;
        }
        for l in 0..line_count[axis] {
            start[l + 1] += start[l];
        }
        let mut fill = start.clone();
        let mut pos = vec![0.0; members.len()];
        let mut id = vec![0u32; members.len()];
        for &s in &members {
            let slot = &mut fill[line_of(s, axis)];
            let p = &seeds.patch[s];
            pos[*slot] = p.base[axis] as f64 + p.off[axis] as f64;
            id[*slot] = s as u32;
            *slot += 1;
        }
        // Ascending position within each line (few points a line: insertion sort).
        for l in 0..line_count[axis] {
            let (a, b) = (start[l], start[l + 1]);
            for t in a + 1..b {
                let mut u = t;
                while u > a && pos[u - 1] > pos[u] {
                    pos.swap(u - 1, u);
                    id.swap(u - 1, u);
                    u -= 1;
                }
            }
        }
        Lines { start, pos, id }
    })
}

/// The nearest of the points (`pos` ascending) to every node 0..n of their line: squared
/// distance (voxels²) into `d` and id into `id`, ∞ and [`NONE`] without points.
fn nearest_on_line(pos: &[f64], ids: &[u32], d: &mut [f64], id: &mut [u32]) {
    if pos.is_empty() {
        d.fill(f64::INFINITY);
        id.fill(NONE);
        return;
    }
    // `next`: the first point at or beyond the node; the nearest is it or the one before.
    let mut next = 0;
    for (t, (d, id)) in d.iter_mut().zip(id.iter_mut()).enumerate() {
        let x = t as f64;
        while next < pos.len() && pos[next] < x {
            next += 1;
        }
        let (mut best, mut who) = (f64::INFINITY, NONE);
        if next < pos.len() {
            (best, who) = ((pos[next] - x).powi(2), ids[next]);
        }
        if next > 0 && (x - pos[next - 1]).powi(2) < best {
            (best, who) = ((x - pos[next - 1]).powi(2), ids[next - 1]);
        }
        *d = best;
        *id = who;
    }
}

/// The nearest of the points (`pos` ascending) to position `x`: (squared distance, id).
fn nearest_to(pos: &[f64], ids: &[u32], x: f64) -> (f64, u32) {
    let next = pos.partition_point(|&p| p < x);
    let (mut best, mut who) = (f64::INFINITY, NONE);
    if next < pos.len() {
        (best, who) = ((pos[next] - x).powi(2), ids[next]);
    }
    if next > 0 && (x - pos[next - 1]).powi(2) < best {
        (best, who) = ((x - pos[next - 1]).powi(2), ids[next - 1]);
    }
    (best, who)
}

/// Scratch of [`envelope`] (parabola centres and the left ends of their stretches) and lines
/// of input and output.
#[derive(Default)]
struct Scratch {
    v: Vec<usize>,
    z: Vec<f64>,
    f: Vec<f64>,
    fid: Vec<u32>,
    d: Vec<f64>,
    id: Vec<u32>,
}

impl Scratch {
    /// Input and output lines of length `n`.
    fn lines(&mut self, n: usize) {
        for buf in [&mut self.f, &mut self.d] {
            buf.resize(n, 0.0);
        }
        for buf in [&mut self.fid, &mut self.id] {
            buf.resize(n, NONE);
        }
    }

    /// [`envelope`] of the first `n` entries of the scratch lines.
    fn envelope(&mut self, n: usize) {
        envelope(
            &mut self.v,
            &mut self.z,
            (&self.f[..n], &self.fid[..n]),
            (&mut self.d[..n], &mut self.id[..n]),
        );
    }

    /// The envelope along y of every column of an x-fastest `nx`×`ny` layer: from
    /// (`from_d`, `from_id`) into (`to_d`, `to_id`).
    fn envelope_along_y(
        &mut self,
        [nx, ny]: [usize; 2],
        (from_d, from_id): (&[f64], &[u32]),
        (to_d, to_id): (&mut [f64], &mut [u32]),
    ) {
        for i in 0..nx {
            for j in 0..ny {
                self.f[j] = from_d[i + nx * j];
                self.fid[j] = from_id[i + nx * j];
            }
            self.envelope(ny);
            for j in 0..ny {
                to_d[i + nx * j] = self.d[j];
                to_id[i + nx * j] = self.id[j];
            }
        }
    }
}

/// The lower envelope of the parabolas f[q] + (p − q)² (q = 0..n, ∞ skipped) at every p:
/// `d[p]` = min over q, `id[p]` the id of the minimising q (from `fid`); ∞ and [`NONE`] when
/// every f[q] is ∞. `v` and `z` are scratch.
fn envelope(
    v: &mut Vec<usize>,
    z: &mut Vec<f64>,
    (f, fid): (&[f64], &[u32]),
    (d, id): (&mut [f64], &mut [u32]),
) {
    let n = f.len();
    v.clear();
    z.clear();
    for q in 0..n {
        if f[q] == f64::INFINITY {
            continue;
        }
        let fq = f[q] + (q * q) as f64;
        loop {
            let Some(&r) = v.last() else {
                v.push(q);
                z.push(f64::NEG_INFINITY);
                break;
            };
            // Where the parabola of q starts to lie below that of r.
            let x = (fq - (f[r] + (r * r) as f64)) / (2 * (q - r)) as f64;
            if x <= *z.last().unwrap_or(&f64::NEG_INFINITY) {
                v.pop();
                z.pop();
            } else {
                v.push(q);
                z.push(x);
                break;
            }
        }
    }
    if v.is_empty() {
        d.fill(f64::INFINITY);
        id.fill(NONE);
        return;
    }
    let mut m = 0;
    for p in 0..n {
        while m + 1 < v.len() && z[m + 1] < p as f64 {
            m += 1;
        }
        let r = v[m];
        let dp = p.abs_diff(r) as f64;
        d[p] = f[r] + dp * dp;
        id[p] = fid[r];
    }
}

/// Sets every node of `phi` that is not one of the `seeds` to sign·min(distance, band) (world
/// units), the distance being to the patch of the seed with the nearest crossing point (see
/// the module docs); the seeds get their own distance.
pub(super) fn transform_distance(phi: &mut Grid3, seeds: &Seeds, band: f64) {
    let mut own = vec![NONE; phi.data().len()];
    for (s, &node) in seeds.node.iter().enumerate() {
        own[node] = s as u32;
    }
    let h = phi.voxel();
    let data = phi.data();
    let values = nearest_points(seeds, phi.dims(), |q, [i, j, k], _, id| {
        let d = if own[q] != NONE {
            seeds.dist[own[q] as usize]
        } else {
            match seeds.patch.get(id as usize) {
                Some(p) => patch_distance(p, [i as f32, j as f32, k as f32]),
                None => f32::INFINITY,
            }
        };
        let w = (d as f64 * h).min(band) as f32;
        if data[q] < 0.0 {
            -w
        } else {
            w
        }
    });
    phi.data_mut().copy_from_slice(&values);
}

/// For every node q = (i, j, k) of a grid of `dims`, `finish(q, (i, j, k), d², id)` with the
/// seed whose crossing point is nearest (`id`, [`NONE`] when there is no seed) and its squared
/// distance (voxels², ∞ without seeds), in flat-index order.
fn nearest_points<T, F>(seeds: &Seeds, dims: [usize; 3], finish: F) -> Vec<T>
where
    T: Copy + Default + Send + Sync,
    F: Fn(usize, [usize; 3], f64, u32) -> T + Sync,
{
    let [nx, ny, nz] = dims;
    let layer = nx * ny;
    let n = layer * nz;
    let lines = classes(seeds, dims);
    // Per node: squared distance and id of the nearest point of classes x and y after their
    // in-layer envelopes (`xy`), and of class z after all of its own (`zc`).
    let mut xy_d = vec![0.0f64; n];
    let mut xy_id = vec![NONE; n];
    let mut zc_d = vec![0.0f64; n];
    let mut zc_id = vec![NONE; n];
    xy_d.par_chunks_mut(layer)
        .zip(xy_id.par_chunks_mut(layer))
        .zip(zc_d.par_chunks_mut(layer))
        .zip(zc_id.par_chunks_mut(layer))
        .enumerate()
        .for_each_init(
            || (Scratch::default(), vec![0.0f64; layer], vec![NONE; layer]),
            |(s, tmp_d, tmp_id), (k, (((xy_d, xy_id), zc_d), zc_id))| {
                s.lines(nx.max(ny));
                // Class x: nearest along each row, then the envelope along y.
                for j in 0..ny {
                    let (pos, ids) = lines[0].line(j + ny * k);
                    let r = j * nx..(j + 1) * nx;
                    nearest_on_line(pos, ids, &mut tmp_d[r.clone()], &mut tmp_id[r]);
                }
                s.envelope_along_y([nx, ny], (tmp_d, tmp_id), (xy_d, xy_id));
                // Class y: nearest along each column, then the envelope along x; the smaller.
                for i in 0..nx {
                    let (pos, ids) = lines[1].line(i + nx * k);
                    nearest_on_line(pos, ids, &mut s.d[..ny], &mut s.id[..ny]);
                    for j in 0..ny {
                        tmp_d[i + nx * j] = s.d[j];
                        tmp_id[i + nx * j] = s.id[j];
                    }
                }
                for j in 0..ny {
                    let r = j * nx..(j + 1) * nx;
                    s.f[..nx].copy_from_slice(&tmp_d[r.clone()]);
                    s.fid[..nx].copy_from_slice(&tmp_id[r.clone()]);
                    s.envelope(nx);
                    for (t, q) in r.enumerate() {
                        if s.d[t] < xy_d[q] {
                            xy_d[q] = s.d[t];
                            xy_id[q] = s.id[t];
                        }
                    }
                }
                // Class z: nearest along each column through the layer, then the envelopes
                // along x and y.
                for j in 0..ny {
                    for i in 0..nx {
                        let (pos, ids) = lines[2].line(i + nx * j);
                        (s.f[i], s.fid[i]) = nearest_to(pos, ids, k as f64);
                    }
                    s.envelope(nx);
                    let r = j * nx..(j + 1) * nx;
                    tmp_d[r.clone()].copy_from_slice(&s.d[..nx]);
                    tmp_id[r].copy_from_slice(&s.id[..nx]);
                }
                s.envelope_along_y([nx, ny], (tmp_d, tmp_id), (zc_d, zc_id));
            },
        );
    // Classes x and y: the envelope along z, per y-layer of columns, in blocks of adjacent
    // columns (read and written a row of the block at a time); the nearer of that and class z.
    // Results per y-layer, (i, k) with i fastest.
    const BLOCK: usize = 16;
    let columns: Vec<Vec<T>> = (0..ny)
        .into_par_iter()
        .map_init(Scratch::default, |s, j| {
            let mut out = vec![T::default(); nx * nz];
            let width = BLOCK.min(nx);
            s.lines(width * nz);
            for i0 in (0..nx).step_by(BLOCK) {
                let w = width.min(nx - i0);
                for k in 0..nz {
                    let q = i0 + nx * (j + ny * k);
                    for b in 0..w {
                        s.f[b * nz + k] = xy_d[q + b];
                        s.fid[b * nz + k] = xy_id[q + b];
                    }
                }
                for b in 0..w {
                    let r = b * nz..(b + 1) * nz;
                    envelope(
                        &mut s.v,
                        &mut s.z,
                        (&s.f[r.clone()], &s.fid[r.clone()]),
                        (&mut s.d[r.clone()], &mut s.id[r]),
                    );
                }
                for k in 0..nz {
                    let q = i0 + nx * (j + ny * k);
                    for b in 0..w {
                        let (d, id) = if zc_d[q + b] < s.d[b * nz + k] {
                            (zc_d[q + b], zc_id[q + b])
                        } else {
                            (s.d[b * nz + k], s.id[b * nz + k])
                        };
                        out[k * nx + i0 + b] = finish(q + b, [i0 + b, j, k], d, id);
                    }
                }
            }
            out
        })
        .collect();
    let mut all = vec![T::default(); n];
    all.par_chunks_mut(layer).enumerate().for_each(|(k, slab)| {
        for (j, col) in columns.iter().enumerate() {
            slab[j * nx..(j + 1) * nx].copy_from_slice(&col[k * nx..(k + 1) * nx]);
        }
    });
    all
}

#[cfg(test)]
mod tests {
    use super::super::init::interface_seeds;
    use super::*;
    use crate::grid::GridTransform;
    use nalgebra::Point3;

    /// The transform's nearest crossing point against a scan of every seed, on a grid whose
    /// interface (two spheres, one cut by the border, and a slanted plane) puts crossings on
    /// edges along every axis, several to a line, with empty lines and layers between.
    #[test]
    fn nearest_point_matches_a_scan_of_every_seed() {
        let dims = [23, 17, 19];
        let t = GridTransform::new(Point3::new(-0.37, 0.21, -0.13), 1.0);
        let mut phi = Grid3::new(dims, t, 0.0).unwrap();
        for idx in 0..phi.data().len() {
            let [i, j, k] = phi.coords(idx);
            let p = phi.world(i, j, k);
            let a = (p - Point3::new(6.3, 7.1, 8.2)).norm() - 4.4;
            let b = (p - Point3::new(19.6, 2.2, 15.4)).norm() - 5.3;
            let plane = 0.3 * p.x + 0.5 * p.y + 0.81 * p.z - 25.0;
            phi.data_mut()[idx] = a.min(b).min(-plane) as f32;
        }
        let seeds = interface_seeds(&phi).unwrap();
        assert!(seeds.len() > 500, "{} seeds", seeds.len());
        let axes: Vec<usize> = seeds
            .patch
            .iter()
            .filter_map(|p| (0..3).find(|&a| p.off[a] != 0.0))
            .collect();
        for a in 0..3 {
            assert!(axes.iter().filter(|&&b| b == a).count() > 50, "axis {a}");
        }
        let points: Vec<[f64; 3]> = seeds.patch.iter().map(|p| p.point()).collect();
        let found = nearest_points(&seeds, dims, |_, x, d, id| (x, d, id));
        for &([i, j, k], d, id) in &found {
            let x = [i as f64, j as f64, k as f64];
            let dist2 = |p: &[f64; 3]| (0..3).map(|c| (x[c] - p[c]).powi(2)).sum::<f64>();
            let scan = points.iter().map(dist2).fold(f64::INFINITY, f64::min);
            assert!(id != NONE, "node {x:?} got no seed");
            assert!(
                (d - scan).abs() <= 1e-9 * (1.0 + scan),
                "{x:?}: {d} vs {scan}"
            );
            let own = dist2(&points[id as usize]);
            assert!(
                (own - d).abs() <= 1e-9 * (1.0 + d),
                "{x:?}: id at {own}, not {d}"
            );
        }
        // No seeds at all: ∞ and no id.
        let empty = Seeds {
            node: Vec::new(),
            dist: Vec::new(),
            patch: Vec::new(),
        };
        let none = nearest_points(&empty, [4, 3, 2], |_, _, d, id| (d, id));
        assert!(none.iter().all(|&(d, id)| d == f64::INFINITY && id == NONE));
    }
}
