//! Marching cubes: the zero level set of φ (negative inside) on a [`Grid3`] as a triangle mesh
//! in world coordinates that is always closed, 2-manifold and oriented outward (normals point
//! towards φ > 0).
//!
//! Method (marching cubes of Lorensen and Cline 1987, made topologically consistent):
//! - **Signs.** A node is inside when φ < 0; exact zeros count as outside, so the surface never
//!   passes through a node. Non-finite values: NaN is refused, ±∞ is taken as ±`f32::MAX`.
//! - **Padding.** The grid is padded, conceptually, by one layer of nodes outside it with value
//!   φ = +h (one voxel, world units), so the surface never touches the grid's border and is
//!   closed there: where the inside reaches the border, the cap lies between the last node and
//!   the padding node (at the crossing of the linear interpolation, e.g. half a voxel out for a
//!   border value of −h).
//! - **Vertices.** One vertex per crossed grid edge, at the zero of the linear interpolation of
//!   φ along the edge, kept at least `1e-3` of the edge away from either node (so no two vertices
//!   coincide and no triangle has zero area). Vertices are shared through the edge's index in
//!   the grid, never by comparing coordinates.
//! - **Cases.** Faces with two inside corners on a diagonal are resolved by the asymptotic
//!   decider (Nielson and Hamann 1991) from the face's four values, so the two cubes sharing the
//!   face agree; each closed curve on a cube's faces is capped by its own disk (interior
//!   ambiguities never get a tunnel through the cube: the only departure from the topology of
//!   the trilinear interpolant, and a consistent one). A disk is triangulated without diagonals
//!   between two crossings on one face; where that is impossible (a curve through both segments
//!   of several ambiguous faces, e.g. three diagonal corners with every face joined) it is
//!   fanned from an extra vertex at the mean of its crossings. Every mesh edge then has exactly
//!   two triangles, every vertex one fan, and all triangles agree in orientation. The case table
//!   is generated from this rule at first use (see `table`).
//! - **Slivers.** When the surface passes close to a node, the crossings on the node's edges
//!   are close together and form tiny triangles and needles. Edges shorter than
//!   [`ExtractOptions::collapse_below`] voxels are collapsed (the vertex nearer a grid node is
//!   merged into the other, which keeps its position on the interpolated surface), each collapse
//!   only when the link condition holds (Dey, Edelsbrunner, Guha, Nekhayev 1999: the result is
//!   still a closed 2-manifold of the same topology), no remaining triangle flips or loses its
//!   area, the smallest angle around does not get worse, and no grid node changes side (see
//!   `collapse`). So the surface still separates the inside nodes from the outside ones, exactly
//!   as before the collapses.
//!
//! The grid is processed in slabs of z-layers in parallel (rayon), the collapses too (those
//! around nodes on the layers two slabs share run once more on the joined mesh); the slabs are
//! fixed, so the output does not depend on the number of threads.

mod collapse;
mod table;

use crate::grid::Grid3;
use crate::{Error, Result, TriMesh};
use nalgebra::Point3;
use rayon::prelude::*;
use table::{case_table, edge_corners, face_corners, CaseTable};

/// Options of [`extract_surface`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtractOptions {
    /// Mesh edges shorter than this many voxels are collapsed (when that keeps the surface a
    /// closed manifold without flipping triangles). In voxels, in [0, 0.5); 0 keeps every
    /// triangle of the marching cubes.
    pub collapse_below: f64,
}

impl Default for ExtractOptions {
    fn default() -> Self {
        ExtractOptions {
            collapse_below: 0.1,
        }
    }
}

/// Vertices stay at least this fraction of their grid edge away from the edge's nodes.
const MIN_EDGE_FRACTION: f64 = 1e-3;
/// Cube layers per parallel work item (fixed, so the output does not depend on thread count).
const SLAB_LAYERS: usize = 8;
/// Marks a vertex index that belongs to the next slab (resolved when the slabs are joined).
const FOREIGN: u32 = 1 << 31;

/// The zero level set of `phi` (negative inside) as a closed, 2-manifold, outward-oriented
/// triangle mesh in world coordinates (see the module documentation for the method). An empty
/// mesh when no node is inside. Errors when φ holds NaN, when the options are out of range, or
/// when the surface has more than 2³¹ vertices.
pub fn extract_surface(phi: &Grid3, opts: &ExtractOptions) -> Result<TriMesh> {
    if !(opts.collapse_below.is_finite() && (0.0..0.5).contains(&opts.collapse_below)) {
        return Err(Error::Geometry(format!(
            "collapse_below must be in [0, 0.5) voxels, got {}",
            opts.collapse_below
        )));
    }
    let ex = Extractor::new(phi, opts.collapse_below)?;
    let layers = ex.pz - 1;
    let slabs: Vec<(usize, usize)> = (0..layers)
        .step_by(SLAB_LAYERS)
        .map(|r0| (r0, (r0 + SLAB_LAYERS).min(layers)))
        .collect();
    let params = collapse::CollapseParams {
        max_length: opts.collapse_below * ex.h,
        voxel: ex.h,
        origin: ex.origin,
    };
    let parts: Vec<SlabOut> = slabs
        .par_iter()
        .map_init(
            || ex.buffers(),
            |buf, &(r0, r1)| {
                let mut part = ex.run_slab(r0, r1, buf);
                if opts.collapse_below > 0.0 {
                    ex.collapse_slab(&mut part, r0, r1, &params);
                }
                part
            },
        )
        .collect();

    // Join the slabs: local indices become global, FOREIGN ones point into the next slab.
    let mut offsets = Vec::with_capacity(parts.len() + 1);
    let mut total = 0usize;
    for p in &parts {
        offsets.push(total);
        total += p.vertices.len();
    }
    offsets.push(total);
    if total >= FOREIGN as usize {
        return Err(Error::Geometry(format!(
            "the surface has {total} vertices, more than a mesh index holds (2^31)"
        )));
    }
    let mut vertices = Vec::with_capacity(total);
    let mut faces = Vec::with_capacity(parts.iter().map(|p| p.faces.len()).sum());
    let mut near = Vec::new();
    for (s, p) in parts.iter().enumerate() {
        let (own, next) = (offsets[s] as u32, offsets[s + 1] as u32);
        vertices.extend_from_slice(&p.vertices);
        faces.extend(p.faces.iter().map(|f| {
            f.map(|i| {
                if i & FOREIGN != 0 {
                    next + (i & !FOREIGN)
                } else {
                    own + i
                }
            })
        }));
        near.extend(p.near.iter().map(|&(i, _)| own + i));
    }
    drop(parts);
    // The clusters on the slabs' shared node layers, left by the slabs.
    if !near.is_empty() {
        let merged = collapse::collapse_short_edges(&vertices, &mut faces, &near, &params);
        if !merged.is_empty() {
            compact(&mut vertices, &mut faces, &merged);
        }
    }
    Ok(TriMesh::new(vertices, faces))
}

/// Drops dead faces and the `merged` vertices, keeping the order of the rest; returns the new
/// index of each old vertex (u32::MAX for dropped ones).
fn compact(vertices: &mut Vec<Point3<f64>>, faces: &mut Vec<[u32; 3]>, merged: &[u32]) -> Vec<u32> {
    faces.retain(|f| f[0] != collapse::DEAD);
    let mut new_index = vec![0u32; vertices.len()];
    for &v in merged {
        new_index[v as usize] = u32::MAX;
    }
    let mut kept = 0usize;
    for i in 0..vertices.len() {
        if new_index[i] == 0 {
            vertices[kept] = vertices[i];
            new_index[i] = kept as u32;
            kept += 1;
        }
    }
    vertices.truncate(kept);
    for v in faces.iter_mut().flatten() {
        *v = new_index[*v as usize];
    }
    new_index
}

/// One slab's vertices (local numbering), triangles (local or FOREIGN indices), the vertices
/// near a grid node (collapse candidates: local index, padded z-layer of the node) and the
/// positions of the FOREIGN vertices it refers to (the next slab's, in its numbering).
struct SlabOut {
    vertices: Vec<Point3<f64>>,
    faces: Vec<[u32; 3]>,
    near: Vec<(u32, u32)>,
    foreign: Vec<Point3<f64>>,
}

/// Per-thread scratch: vertex indices of the crossed edges of the current layers, indexed by
/// padded node (q·px + p). x- and y-edges for two node layers (by parity), z-edges for one.
struct Buffers {
    ix: [Vec<u32>; 2],
    iy: [Vec<u32>; 2],
    iz: Vec<u32>,
}

struct Extractor<'a> {
    phi: &'a [f32],
    n: [usize; 3],
    /// Padded node counts (n + 2).
    px: usize,
    py: usize,
    pz: usize,
    /// u64 words per padded row of sign bits.
    w: usize,
    /// Inside bits (φ < 0) of the padded grid, row (q, r) at words [(r·py + q)·w ..][..w], bit p
    /// for padded node p (grid node p − 1); padding bits are 0 (outside).
    signs: Vec<u64>,
    origin: [f64; 3],
    h: f64,
    /// Vertices within this fraction of their edge from a node are collapse candidates.
    near: f64,
    table: &'static CaseTable,
}

impl<'a> Extractor<'a> {
    fn new(grid: &'a Grid3, collapse_below: f64) -> Result<Self> {
        let n = grid.dims();
        let (px, py, pz) = (n[0] + 2, n[1] + 2, n[2] + 2);
        let w = px.div_ceil(64);
        let phi = grid.data();
        let mut signs = vec![0u64; w * py * pz];
        let has_nan = signs
            .par_chunks_mut(w * py)
            .enumerate()
            .map(|(r, layer)| {
                if r == 0 || r == pz - 1 {
                    return false;
                }
                let mut nan = false;
                for j in 0..n[1] {
                    let start = n[0] * (j + n[1] * (r - 1));
                    let row = &phi[start..start + n[0]];
                    nan |= fill_row(row, &mut layer[(j + 1) * w..(j + 2) * w]);
                }
                nan
            })
            .reduce(|| false, |a, b| a || b);
        if has_nan {
            let at = phi.iter().position(|v| v.is_nan()).unwrap_or(0);
            let [i, j, k] = grid.coords(at);
            return Err(Error::Geometry(format!(
                "φ is NaN at node ({i}, {j}, {k}): the level set is undefined there"
            )));
        }
        Ok(Extractor {
            phi,
            n,
            px,
            py,
            pz,
            w,
            signs,
            origin: grid.transform().origin,
            h: grid.voxel(),
            near: collapse_below,
            table: case_table(),
        })
    }

    fn buffers(&self) -> Buffers {
        let len = self.px * self.py;
        Buffers {
            ix: [vec![0; len], vec![0; len]],
            iy: [vec![0; len], vec![0; len]],
            iz: vec![0; len],
        }
    }

    /// Sign bits of padded row (q, r).
    #[inline]
    fn row(&self, q: usize, r: usize) -> &[u64] {
        let at = (r * self.py + q) * self.w;
        &self.signs[at..at + self.w]
    }

    /// φ at padded node (p, q, r) as f64: +h in the padding, infinities clamped.
    #[inline]
    fn value(&self, p: usize, q: usize, r: usize) -> f64 {
        let [nx, ny, nz] = self.n;
        if (1..=nx).contains(&p) && (1..=ny).contains(&q) && (1..=nz).contains(&r) {
            let v = self.phi[(p - 1) + nx * ((q - 1) + ny * (r - 1))];
            v.clamp(-f32::MAX, f32::MAX) as f64
        } else {
            self.h
        }
    }

    /// The crossing on the edge from padded node (p, q, r) along `axis` (whose ends differ in
    /// sign), as grid coordinates, and its fraction t along the edge before clamping.
    #[inline]
    fn crossing(&self, p: usize, q: usize, r: usize, axis: usize) -> ([f64; 3], f64) {
        let va = self.value(p, q, r);
        let vb = match axis {
            0 => self.value(p + 1, q, r),
            1 => self.value(p, q + 1, r),
            _ => self.value(p, q, r + 1),
        };
        // The signs differ (one < 0 ≤ other), so va − vb ≠ 0 and t ∈ [0, 1].
        let t = va / (va - vb);
        let mut g = [p as f64 - 1.0, q as f64 - 1.0, r as f64 - 1.0];
        g[axis] += t.clamp(MIN_EDGE_FRACTION, 1.0 - MIN_EDGE_FRACTION);
        (g, t)
    }

    /// World position of grid coordinates `g`.
    #[inline]
    fn to_world(&self, g: [f64; 3]) -> Point3<f64> {
        Point3::new(
            self.origin[0] + self.h * g[0],
            self.origin[1] + self.h * g[1],
            self.origin[2] + self.h * g[2],
        )
    }

    /// Creates the vertex on the crossed edge from padded node (p, q, r) along `axis`.
    #[inline]
    fn make_vertex(&self, p: usize, q: usize, r: usize, axis: usize, out: &mut SlabOut) -> u32 {
        let (g, t) = self.crossing(p, q, r, axis);
        if self.near > 0.0 && (t < self.near || t > 1.0 - self.near) {
            let layer = if axis == 2 && t > 0.5 { r + 1 } else { r };
            out.near.push((out.vertices.len() as u32, layer as u32));
        }
        let id = out.vertices.len() as u32;
        out.vertices.push(self.to_world(g));
        id
    }

    /// A vertex of the next slab (its crossed x- or y-edge on the shared node layer): numbered
    /// in the order that slab creates them, its position kept for the collapse checks.
    #[inline]
    fn foreign_vertex(&self, p: usize, q: usize, r: usize, axis: usize, out: &mut SlabOut) -> u32 {
        let (g, _) = self.crossing(p, q, r, axis);
        out.foreign.push(self.to_world(g));
        FOREIGN | (out.foreign.len() as u32 - 1)
    }

    /// Creates the centre vertex of a polygon of cube (p, q, r): the mean of its crossings.
    fn make_centre(&self, p: usize, q: usize, r: usize, poly: &[u8], out: &mut SlabOut) -> u32 {
        let mut sum = [0.0; 3];
        for &e in poly {
            let [c, _] = edge_corners(e as usize);
            let (g, _) = self.crossing(
                p + (c & 1),
                q + ((c >> 1) & 1),
                r + (c >> 2),
                e as usize / 4,
            );
            (0..3).for_each(|i| sum[i] += g[i]);
        }
        out.vertices
            .push(self.to_world(sum.map(|x| x / poly.len() as f64)));
        out.vertices.len() as u32 - 1
    }

    /// Numbers the crossed x- and y-edges of padded node layer r into `ix`, `iy` (rows in order,
    /// x-edges then y-edges of each row). `own`: create the vertices; otherwise only number them
    /// as FOREIGN (they belong to the next slab, which numbers them first, in the same order).
    fn layer_xy(&self, r: usize, own: bool, ix: &mut [u32], iy: &mut [u32], out: &mut SlabOut) {
        for q in 1..self.py - 1 {
            let row = self.row(q, r);
            let below = self.row(q + 1, r);
            for wi in 0..self.w {
                let next = if wi + 1 < self.w { row[wi + 1] } else { 0 };
                let mut xc = row[wi] ^ ((row[wi] >> 1) | (next << 63));
                while xc != 0 {
                    let p = wi * 64 + xc.trailing_zeros() as usize;
                    xc &= xc - 1;
                    ix[q * self.px + p] = if own {
                        self.make_vertex(p, q, r, 0, out)
                    } else {
                        self.foreign_vertex(p, q, r, 0, out)
                    };
                }
            }
            for wi in 0..self.w {
                let mut yc = row[wi] ^ below[wi];
                while yc != 0 {
                    let p = wi * 64 + yc.trailing_zeros() as usize;
                    yc &= yc - 1;
                    iy[q * self.px + p] = if own {
                        self.make_vertex(p, q, r, 1, out)
                    } else {
                        self.foreign_vertex(p, q, r, 1, out)
                    };
                }
            }
        }
        // Row 0 is padding: its x-edges are never crossed, its y-edges (to row 1) may be.
        let (row, below) = (self.row(0, r), self.row(1, r));
        for wi in 0..self.w {
            let mut yc = row[wi] ^ below[wi];
            while yc != 0 {
                let p = wi * 64 + yc.trailing_zeros() as usize;
                yc &= yc - 1;
                iy[p] = if own {
                    self.make_vertex(p, 0, r, 1, out)
                } else {
                    self.foreign_vertex(p, 0, r, 1, out)
                };
            }
        }
    }

    /// Creates the vertices of the crossed z-edges from padded node layer r to r + 1.
    fn layer_z(&self, r: usize, iz: &mut [u32], out: &mut SlabOut) {
        for q in 1..self.py - 1 {
            let (a, b) = (self.row(q, r), self.row(q, r + 1));
            for wi in 0..self.w {
                let mut zc = a[wi] ^ b[wi];
                while zc != 0 {
                    let p = wi * 64 + zc.trailing_zeros() as usize;
                    zc &= zc - 1;
                    iz[q * self.px + p] = self.make_vertex(p, q, r, 2, out);
                }
            }
        }
    }

    /// Extracts cube layers r0..r1 (padded): the cubes between padded node layers r and r + 1.
    fn run_slab(&self, r0: usize, r1: usize, buf: &mut Buffers) -> SlabOut {
        let mut out = SlabOut {
            vertices: Vec::new(),
            faces: Vec::new(),
            near: Vec::new(),
            foreign: Vec::new(),
        };
        let Buffers { ix, iy, iz } = buf;
        {
            let s = r0 & 1;
            self.layer_xy(r0, true, &mut ix[s], &mut iy[s], &mut out);
        }
        self.layer_z(r0, iz, &mut out);
        for r in r0..r1 {
            let s = (r + 1) & 1;
            let own = r + 1 < r1;
            self.layer_xy(r + 1, own, &mut ix[s], &mut iy[s], &mut out);
            self.emit_layer(r, ix, iy, iz, &mut out);
            if own {
                self.layer_z(r + 1, iz, &mut out);
            }
        }
        out
    }

    /// Collapses the short edges of this slab's clusters whose node has all its cubes in the
    /// slab (cube layers r0..r1); those of nodes on the layers shared with the neighbouring
    /// slabs stay in `near` for the pass over the joined mesh.
    fn collapse_slab(
        &self,
        part: &mut SlabOut,
        r0: usize,
        r1: usize,
        params: &collapse::CollapseParams,
    ) {
        let last = self.pz - 1;
        let here = |z: u32| {
            let z = z as usize;
            (z == 0 || z > r0) && (z < r1 || z == last)
        };
        let local: Vec<u32> = part
            .near
            .iter()
            .filter(|&&(_, z)| here(z))
            .map(|&(v, _)| v)
            .collect();
        if local.is_empty() {
            return;
        }
        // One index space: own vertices, then the foreign ones.
        let own = part.vertices.len();
        part.vertices.extend_from_slice(&part.foreign);
        for v in part.faces.iter_mut().flatten() {
            if *v & FOREIGN != 0 {
                *v = own as u32 + (*v & !FOREIGN);
            }
        }
        let merged =
            collapse::collapse_short_edges(&part.vertices, &mut part.faces, &local, params);
        if !merged.is_empty() {
            // Only candidates (own vertices off the shared layers) are merged away: the first
            // vertices, which the previous slab refers to, and the foreign ones keep their order.
            let new_index = compact(&mut part.vertices, &mut part.faces, &merged);
            part.near.retain(|&(_, z)| !here(z));
            for (v, _) in &mut part.near {
                *v = new_index[*v as usize];
            }
        } else {
            part.near.retain(|&(_, z)| !here(z));
        }
        let own = part.vertices.len() - part.foreign.len();
        part.vertices.truncate(own);
        for v in part.faces.iter_mut().flatten() {
            if *v as usize >= own {
                *v = FOREIGN | (*v - own as u32);
            }
        }
    }

    /// Emits the triangles of cube layer r.
    fn emit_layer(
        &self,
        r: usize,
        ix: &[Vec<u32>; 2],
        iy: &[Vec<u32>; 2],
        iz: &[u32],
        out: &mut SlabOut,
    ) {
        let px = self.px;
        let (x0, x1) = (&ix[r & 1], &ix[(r + 1) & 1]);
        let (y0, y1) = (&iy[r & 1], &iy[(r + 1) & 1]);
        for q in 0..self.py - 1 {
            let (a, b, c, d) = (
                self.row(q, r),
                self.row(q + 1, r),
                self.row(q, r + 1),
                self.row(q + 1, r + 1),
            );
            for wi in 0..self.w {
                let any = a[wi] | b[wi] | c[wi] | d[wi];
                let all = a[wi] & b[wi] & c[wi] & d[wi];
                let (any_n, all_n) = if wi + 1 < self.w {
                    (
                        a[wi + 1] | b[wi + 1] | c[wi + 1] | d[wi + 1],
                        a[wi + 1] & b[wi + 1] & c[wi + 1] & d[wi + 1],
                    )
                } else {
                    (0, 0)
                };
                let some_inside = any | (any >> 1) | (any_n << 63);
                let all_inside = all & ((all >> 1) | (all_n << 63));
                let mut active = some_inside & !all_inside;
                while active != 0 {
                    let p = wi * 64 + active.trailing_zeros() as usize;
                    active &= active - 1;
                    let config = two_bits(a, p)
                        | (two_bits(b, p) << 2)
                        | (two_bits(c, p) << 4)
                        | (two_bits(d, p) << 6);
                    let entry = self.entry(config, p, q, r);
                    let (start, count) = self.table.entries[entry];
                    let tris = &self.table.triangles[start as usize..][..count as usize];
                    let mut centre = [0u32; 4];
                    for (k, poly) in self.table.centres[entry].iter().enumerate() {
                        centre[k] = self.make_centre(p, q, r, poly, out);
                    }
                    for tri in tris {
                        out.faces.push(tri.map(|e| match e {
                            0..=3 => {
                                let row = (q + (e & 1) as usize) * px + p;
                                if e < 2 {
                                    x0[row]
                                } else {
                                    x1[row]
                                }
                            }
                            4..=7 => {
                                let k = (e - 4) as usize;
                                let at = q * px + p + (k & 1);
                                if k < 2 {
                                    y0[at]
                                } else {
                                    y1[at]
                                }
                            }
                            8..=11 => {
                                let k = (e - 8) as usize;
                                iz[(q + (k >> 1)) * px + p + (k & 1)]
                            }
                            _ => centre[(e - 12) as usize],
                        }));
                    }
                }
            }
        }
    }

    /// The table entry of cube (p, q, r) with sign configuration `config`: the asymptotic
    /// decider on each ambiguous face picks between its two resolutions.
    #[inline]
    fn entry(&self, config: usize, p: usize, q: usize, r: usize) -> usize {
        let first = self.table.first[config] as usize;
        let mut amb = self.table.ambiguous[config];
        if amb == 0 {
            return first;
        }
        let mut bits = 0usize;
        let mut k = 0;
        while amb != 0 {
            let f = amb.trailing_zeros() as usize;
            amb &= amb - 1;
            let v =
                face_corners(f).map(|c| self.value(p + (c & 1), q + ((c >> 1) & 1), r + (c >> 2)));
            // Inside corners diagonal: joined across the face when the bilinear saddle value is
            // negative, i.e. when (product of the inside pair) > (product of the outside pair).
            // f32 products are exact in f64, so both cubes sharing the face decide alike.
            let (inside, outside) = if v[0] < 0.0 {
                (v[0] * v[2], v[1] * v[3])
            } else {
                (v[1] * v[3], v[0] * v[2])
            };
            if inside > outside {
                bits |= 1 << k;
            }
            k += 1;
        }
        first + bits
    }
}

/// Bits p and p + 1 of a row of sign words.
#[inline]
fn two_bits(row: &[u64], p: usize) -> usize {
    let (wi, b) = (p >> 6, p & 63);
    if b < 63 {
        ((row[wi] >> b) & 3) as usize
    } else {
        let hi = row.get(wi + 1).map_or(0, |w| w & 1);
        ((row[wi] >> 63) | (hi << 1)) as usize
    }
}

/// Writes the inside bits (φ < 0) of a grid row into padded words (value i at bit i + 1);
/// returns whether the row holds a NaN.
fn fill_row(values: &[f32], out: &mut [u64]) -> bool {
    let mut nan = false;
    let mut put = |c: usize, m: u64| {
        out[c] |= m << 1;
        if let Some(w) = out.get_mut(c + 1) {
            *w |= m >> 63;
        }
    };
    let chunks = values.chunks_exact(64);
    let rest = chunks.remainder();
    let full = values.len() / 64;
    for (c, chunk) in chunks.enumerate() {
        // Fixed-length loops over 64 lanes: compiled to vector compares and mask moves.
        let chunk: &[f32; 64] = chunk.try_into().expect("64 values");
        let mut m = 0u64;
        let mut any_nan = false;
        for (b, &v) in chunk.iter().enumerate() {
            m |= ((v < 0.0) as u64) << b;
            any_nan |= v.is_nan();
        }
        nan |= any_nan;
        put(c, m);
    }
    let mut m = 0u64;
    for (b, &v) in rest.iter().enumerate() {
        m |= ((v < 0.0) as u64) << b;
        nan |= v.is_nan();
    }
    put(full, m);
    nan
}
