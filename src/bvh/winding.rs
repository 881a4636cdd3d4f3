//! Generalized winding number of a triangle mesh (soup), exact and fast.
//!
//! The winding number at q is w(q) = (1/4π) Σ_t Ω_t(q), the signed solid angles of the
//! triangles seen from q: 1 inside a closed outward-oriented mesh, 0 outside, −1 inside an
//! inward-oriented one, and a smooth "inside-ness" in between for open meshes (about ½ across an
//! open vessel end). Each solid angle follows Van Oosterom and Strackee, "The solid angle of a
//! plane triangle", IEEE Trans. Biomed. Eng. 30(2), 1983.
//!
//! The fast evaluation follows Barill, Dickson, Schmidt, Levin and Jacobson, "Fast winding
//! numbers for soups and clouds", ACM TOG 37(4), 2018: w is the flux of the field
//! f(x) = (x − q)/(4π|x − q|³) through the surface; for a hierarchy node whose triangles lie
//! within a ball of radius r about their area-weighted centroid p̃, f is expanded in a Taylor
//! series about p̃, and the node is evaluated by its expansion when |q − p̃| > β·r (opened
//! otherwise; leaves that are too near are summed exactly). The paper stops at order 2; here the
//! expansion is carried to any order up to 5 (default 4), derived as follows.
//!
//! With y = x − p̃ and d = p̃ − q, f(p̃ + y) = −∇φ(d + y)/4π with φ = 1/|·|, so the order-k term
//! of a node is −(1/k!) ∂^(k+1)φ(d) · C^k / 4π, where C^k_(i j1…jk) = Σ_t ∫_t n_i y_j1 ⋯ y_jk dA
//! are the node's moments (symmetric in the j's). The derivatives of 1/r, r = |d|, are
//! ∂^n φ = Σ_m (−1)^(n−m) (2n−2m−1)!! {δ^m d^(n−2m)} / r^(2n−2m+1), {δ^m d^(n−2m)} being the sum
//! over the distinct ways of putting Kronecker deltas on m index pairs and d on the other
//! indices. Contracted with C^k only the full symmetrization of C^k matters, and with
//! Q_k(d) = C^k(d, …, d) = Σ_t ∫_t (n·d)(y·d)^k dA, a polynomial of degree n = k + 1 in d,
//! {δ^m d^(n−2m)} · C^k = Δ^m Q_k(d) / (m! 2^m). Multiplying r^(2m) back in, order k is
//! P_n(d)/r^(2n+1) with the homogeneous polynomial
//! P_n = −(1/(4π k!)) Σ_m (−1)^(n−m) (2n−2m−1)!! |d|^(2m) Δ^m Q_k / (m! 2^m);
//! orders 0 to 2 reproduce Barill et al.'s (N·d)/r³, tr M/r³ − 3 dᵀMd/r⁵, and so on. A node stores
//! the coefficients of P_1 … P_(order+1) over the monomials of d (3 + 6 + 10 + 15 + 21 = 55
//! numbers at order 4), and a far node costs one square root and about two multiplications per
//! coefficient. The moments are exact for flat triangles: the mean of (y·d)^k over a triangle
//! with corners a, b, c is 2/((k+1)(k+2)) · h_k(a·d, b·d, c·d), h_k the complete homogeneous
//! symmetric polynomial of degree k. A node of at most 16 triangles sums its moments over them;
//! a larger one translates its two children's to its own centre (with y = y′ + δ,
//! mean((y·d)^k) = Σ_j C(k, j)(δ·d)^(k−j) mean((y′·d)^j)), so building the expansions visits each
//! triangle a few times instead of once per level of the hierarchy (0.26 s → 0.13 s on a
//! repaired vessel of 64,000 triangles, 2 threads).
//!
//! Accuracy (max |fast − exact| over 10,000 points per real mesh, half in the bounding box grown
//! by 20 %, half within two mean edges of the surface; worst of the project's six meshes) and
//! speed (cortex, 20,480 triangles, 100,000 points of the same mix, 2 threads): order 2 (the
//! paper's) gives 9e-3 at β = 2 (about 0.75 M queries/s) and needs β ≈ 6 for 1e-4 (0.08 M/s);
//! order 3 needs β ≈ 5 (0.1 M/s); order 4 gives 7.5e-5 at β = 3 (0.22 M/s, the default);
//! order 5 gives 7.7e-5 at β = 2.75 (0.22 M/s) and 4e-5 at β = 3. The error falls like β^−(order+2) to β^−(order+3), the cost grows
//! like β²; the full table is printed by the ignored test `winding_order_beta_sweep` in
//! tests/suite/bvh_winding.rs.

use std::f64::consts::PI;

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

use super::MeshBvh;
use crate::TriMesh;

/// Solid angle subtended at `q` by the triangle (a, b, c), signed: positive when q sees the
/// triangle's back, i.e. when the normal (b − a) × (c − a) points away from q. In (−2π, 2π];
/// 0 for q in the triangle's plane or degenerate triangles (Van Oosterom and Strackee 1983).
pub fn solid_angle(q: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> f64 {
    let ra = a - q;
    let rb = b - q;
    let rc = c - q;
    let la = ra.norm();
    let lb = rb.norm();
    let lc = rc.norm();
    let num = ra.dot(&rb.cross(&rc));
    let den = la * lb * lc + ra.dot(&rb) * lc + rb.dot(&rc) * la + rc.dot(&ra) * lb;
    2.0 * num.atan2(den)
}

/// Options of the fast winding number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindingOptions {
    /// Accuracy parameter β (dimensionless ratio): a node is replaced by its Taylor expansion
    /// when the query is farther than β times the node's radius from the node's centre. Larger
    /// is more accurate and slower (the cost grows roughly like β², the error falls like
    /// β^−(order+2) to β^−(order+3)). Values below 1, and NaN, are treated as 1 (the expansion
    /// diverges inside); +∞ means the exact sum.
    pub beta: f64,
    /// Highest order of the Taylor expansion (dimensionless, 0 to 5; larger values mean 5).
    /// Barill et al. (2018) use 2. Order k stores (k+2)(k+3)(k+4)/6 − 1 numbers per hierarchy
    /// node (19 at order 2, 55 at order 4) and costs a little more time per far node.
    pub order: u8,
}

impl Default for WindingOptions {
    /// Order 4, β = 3: the cheapest setting found whose largest absolute error on the
    /// project's six real meshes stays below 1e-4 (7.5e-5 on 10,000 box and near-surface
    /// points per mesh; order 2 at β = 2, the paper's setting, gave 9e-3 and is about three
    /// times faster).
    fn default() -> Self {
        WindingOptions {
            beta: 3.0,
            order: 4,
        }
    }
}

impl WindingOptions {
    /// For telling inside from outside, where only the side of ½ matters: order 2, β = 2
    /// (Barill et al.'s setting; largest error 9e-3 on the project's real meshes, far from the
    /// ½ a side test compares with; about three times faster to build and to query than the
    /// default).
    pub const SIDES: WindingOptions = WindingOptions {
        beta: 2.0,
        order: 2,
    };
}

/// Highest supported order of the expansion.
const MAX_ORDER: usize = 5;
/// Length of a flat array holding every monomial (or polynomial coefficient) of degree 0 to n − 1.
const fn start(n: usize) -> usize {
    n * (n + 1) * (n + 2) / 6
}
/// Number of monomials of degree n in three variables.
const fn num_mono(n: usize) -> usize {
    (n + 1) * (n + 2) / 2
}
/// Position of x^p y^q z^(n−p−q) among the degree-n monomials, ordered by descending powers of
/// x, then of y (degree 2: xx xy xz yy yz zz).
const fn mono_index(n: usize, p: usize, q: usize) -> usize {
    (n - p) * (n - p + 1) / 2 + (n - p - q)
}
/// Number of stored coefficients per node for an order-`k` expansion: the homogeneous
/// polynomials P_1 … P_(k+1), P_n of degree n.
const fn coef_len(k: usize) -> usize {
    start(k + 2) - 1
}

/// Adds `l` · `src` (a polynomial of degree n times a linear form) to the degree-(n + 1) `dst`.
fn mul_linear_add(src: &[f64], n: usize, l: &Vector3<f64>, dst: &mut [f64]) {
    let mut i = 0;
    for p in (0..=n).rev() {
        for q in (0..=n - p).rev() {
            let c = src[i];
            i += 1;
            dst[mono_index(n + 1, p + 1, q)] += l.x * c;
            dst[mono_index(n + 1, p, q + 1)] += l.y * c;
            dst[mono_index(n + 1, p, q)] += l.z * c;
        }
    }
}

/// Adds Δ`src` (the Laplacian of a degree-n polynomial, n ≥ 2) to `dst` (degree n − 2).
fn laplacian_add(src: &[f64], n: usize, dst: &mut [f64]) {
    let mut i = 0;
    for p in (0..=n).rev() {
        for q in (0..=n - p).rev() {
            let r = n - p - q;
            let c = src[i];
            i += 1;
            if p >= 2 {
                dst[mono_index(n - 2, p - 2, q)] += (p * (p - 1)) as f64 * c;
            }
            if q >= 2 {
                dst[mono_index(n - 2, p, q - 2)] += (q * (q - 1)) as f64 * c;
            }
            if r >= 2 {
                dst[mono_index(n - 2, p, q)] += (r * (r - 1)) as f64 * c;
            }
        }
    }
}

/// Adds |d|² · `src` (a degree-n polynomial) to `dst` (degree n + 2).
fn mul_r2_add(src: &[f64], n: usize, dst: &mut [f64]) {
    let mut i = 0;
    for p in (0..=n).rev() {
        for q in (0..=n - p).rev() {
            let c = src[i];
            i += 1;
            dst[mono_index(n + 2, p + 2, q)] += c;
            dst[mono_index(n + 2, p, q + 2)] += c;
            dst[mono_index(n + 2, p, q)] += c;
        }
    }
}

/// The degree-(n + 1) monomials of d from the degree-n ones `prev` (N of them, M = N + n + 2):
/// x times each, then y times those without x, then z^(n+1); the order of [`mono_index`].
#[inline(always)]
fn next_degree<const N: usize, const M: usize>(prev: &[f64; N], d: &Vector3<f64>) -> [f64; M] {
    let mut out = [0.0; M];
    let tail = M - N - 1;
    for i in 0..N {
        out[i] = d.x * prev[i];
    }
    for i in 0..tail {
        out[N + i] = d.y * prev[N - tail + i];
    }
    out[M - 1] = d.z * prev[N - 1];
    out
}

/// Σ a_i b_i over the first M entries of `a` (its length is checked once by the caller), in four
/// independent partial sums so the additions overlap.
#[inline(always)]
fn dot<const M: usize>(a: &[f64], b: &[f64; M]) -> f64 {
    let a = &a[..M];
    let mut acc = [0.0; 4];
    for i in 0..M {
        acc[i % 4] += a[i] * b[i];
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// What the traversal reads of a node (a compact copy of the hierarchy next to the expansion
/// centres, so a node visit touches one record): where its expansion applies, and its children
/// or triangles.
#[derive(Debug, Clone, Copy)]
struct FarField {
    /// Area-weighted centroid p̃ of the node's triangles (world units).
    center: Vector3<f64>,
    /// (β·r)², r = largest distance from p̃ to a corner of the node's triangles.
    far2: f64,
    /// First child (children are `first` and `first + 1`), or first triangle slot of a leaf.
    first: u32,
    /// Number of triangles of a leaf; 0 for an inner node.
    count: u32,
}

/// Value of an order-`K` expansion with coefficients `coef` at d = p̃ − q:
/// Σ_n P_n(d)/r^(2n+1), n = 1..=K+1, P_n homogeneous of degree n (coefficients of P_1, P_2, …
/// in turn, in the monomial order of [`mono_index`]).
#[inline(always)]
fn eval_expansion<const K: usize>(coef: &[f64], d: &Vector3<f64>) -> f64 {
    let coef = &coef[..coef_len(K)];
    let r2 = d.norm_squared();
    let inv_r2 = 1.0 / r2;
    let m1 = [d.x, d.y, d.z];
    let mut p = [0.0; MAX_ORDER + 1];
    p[0] = dot(coef, &m1);
    if K >= 1 {
        let m2: [f64; 6] = next_degree(&m1, d);
        p[1] = dot(&coef[start(2) - 1..], &m2);
        if K >= 2 {
            let m3: [f64; 10] = next_degree(&m2, d);
            p[2] = dot(&coef[start(3) - 1..], &m3);
            if K >= 3 {
                let m4: [f64; 15] = next_degree(&m3, d);
                p[3] = dot(&coef[start(4) - 1..], &m4);
                if K >= 4 {
                    let m5: [f64; 21] = next_degree(&m4, d);
                    p[4] = dot(&coef[start(5) - 1..], &m5);
                    if K >= 5 {
                        let m6: [f64; 28] = next_degree(&m5, d);
                        p[5] = dot(&coef[start(6) - 1..], &m6);
                    }
                }
            }
        }
    }
    // Σ_n P_n / r^(2n+1), by Horner in 1/r² from the highest degree down.
    let mut w = 0.0;
    for n in (0..=K).rev() {
        w = w * inv_r2 + p[n];
    }
    w * inv_r2 / r2.sqrt()
}

/// Fast generalized winding number of a triangle mesh (Barill et al. 2018) on a [`MeshBvh`].
#[derive(Debug, Clone)]
pub struct WindingNumber {
    bvh: MeshBvh,
    far: Vec<FarField>,
    /// Per node, `coef_len(order)` expansion coefficients.
    coefs: Vec<f64>,
    order: usize,
    options: WindingOptions,
}

/// Slots (indices into `MeshBvh::tris`) under `node`.
fn subtree_slots(bvh: &MeshBvh, node: usize, out: &mut Vec<usize>) {
    out.clear();
    let mut stack = vec![node];
    while let Some(n) = stack.pop() {
        let nd = &bvh.bvh.nodes[n];
        if nd.is_leaf() {
            let s = nd.first_index as usize;
            out.extend(s..s + nd.prim_count as usize);
        } else {
            stack.push(nd.first_index as usize);
            stack.push(nd.first_index as usize + 1);
        }
    }
}

/// Per component i of the normal, the polynomials Σ_t a_t n_t,i · mean_t((y·d)^k) of d for
/// k = 0..=MAX_ORDER (degree k at `start(k)..start(k + 1)`), y relative to a node's centre.
type Moments = [[f64; MOMENTS_LEN]; 3];
const MOMENTS_LEN: usize = start(MAX_ORDER + 1);

/// A node's centre (area-weighted centroid of its triangles, world units), the squared largest
/// distance from it to a corner, and its moments about it up to order `order`, summed over the
/// triangles in `slots` directly.
fn node_moments(bvh: &MeshBvh, slots: &[usize], order: usize) -> (Vector3<f64>, f64, Moments) {
    // Work relative to the first corner so moments keep their precision far from the origin.
    let base = bvh.tris[slots[0]][0].coords;
    let mut area = 0.0;
    let mut acc = Vector3::zeros();
    let mut vsum = Vector3::zeros();
    for &s in slots {
        let [a, b, c] = bvh.tris[s].map(|v| v.coords - base);
        let ar = 0.5 * (b - a).cross(&(c - a)).norm();
        area += ar;
        acc += (a + b + c) * (ar / 3.0);
        vsum += a + b + c;
    }
    // Area-weighted centroid; the plain corner mean if the node has no area.
    let local_center = if area > 0.0 {
        acc / area
    } else {
        vsum / (3.0 * slots.len() as f64)
    };

    // moments[i], for every k ≤ order (degree k at start(k)..start(k + 1)): the polynomial
    // Σ_t a_t n_t,i · mean_t((y·d)^k) of d, i.e. C^k_i(d, …, d).
    const LEN: usize = MOMENTS_LEN;
    let mut moments = [[0.0; LEN]; 3];
    let mut r2max: f64 = 0.0;
    for &s in slots {
        let [a, b, c] = bvh.tris[s].map(|v| v.coords - base - local_center);
        for p in [a, b, c] {
            r2max = r2max.max(p.norm_squared());
        }
        // Vector area a_t n_t.
        let an = 0.5 * (b - a).cross(&(c - a));
        // h_k(a·d, b·d, c·d) by h_k(x, y, z) = x h_(k−1)(x, y, z) + h_k(y, z),
        // h_k(y, z) = y h_(k−1)(y, z) + z^k.
        let (mut zk, mut hyz, mut h) = ([0.0; LEN], [0.0; LEN], [0.0; LEN]);
        zk[0] = 1.0;
        hyz[0] = 1.0;
        h[0] = 1.0;
        for k in 1..=order {
            let (prev, cur, next) = (start(k - 1), start(k), start(k + 1));
            for (poly, factor) in [(&mut zk, &c), (&mut hyz, &b), (&mut h, &a)] {
                let (lo, hi) = poly.split_at_mut(cur);
                mul_linear_add(&lo[prev..], k - 1, factor, &mut hi[..next - cur]);
            }
            // The recursions' additive terms, in dependency order.
            for (x, y) in hyz[cur..next].iter_mut().zip(&zk[cur..next]) {
                *x += y;
            }
            for (x, y) in h[cur..next].iter_mut().zip(&hyz[cur..next]) {
                *x += y;
            }
        }
        for k in 0..=order {
            let scale = 2.0 / ((k + 1) * (k + 2)) as f64;
            for (i, mom) in moments.iter_mut().enumerate() {
                let w = an[i] * scale;
                for (m, hk) in mom[start(k)..start(k + 1)]
                    .iter_mut()
                    .zip(&h[start(k)..start(k + 1)])
                {
                    *m += w * hk;
                }
            }
        }
    }
    (local_center + base, r2max, moments)
}

/// Adds to `parent` the moments `child` taken about a centre `delta` away from the child's
/// (`delta` = child's centre − parent's): with y = y′ + δ,
/// mean((y·d)^k) = Σ_(j ≤ k) C(k, j) (δ·d)^(k−j) mean((y′·d)^j), so a node's moments follow from
/// its children's without visiting their triangles again.
fn translate_moments_add(
    child: &Moments,
    delta: &Vector3<f64>,
    order: usize,
    parent: &mut Moments,
) {
    for (c, p) in child.iter().zip(parent.iter_mut()) {
        for j in 0..=order {
            // t = (δ·d)^(k−j) · M_j, raised one degree at a time.
            let mut t = [0.0; MOMENTS_LEN];
            t[..num_mono(j)].copy_from_slice(&c[start(j)..start(j + 1)]);
            let mut binom = 1.0;
            for k in j..=order {
                if k > j {
                    let mut next = [0.0; MOMENTS_LEN];
                    mul_linear_add(&t, k - 1, delta, &mut next);
                    t = next;
                    binom = binom * k as f64 / (k - j) as f64;
                }
                for (x, y) in p[start(k)..start(k + 1)].iter_mut().zip(&t) {
                    *x += binom * y;
                }
            }
        }
    }
}

/// Appends to `coef` the coefficients of P_1 … P_(order+1) (see the module documentation) of a
/// node with these moments.
fn expansion_coefficients(moments: &Moments, order: usize, coef: &mut Vec<f64>) {
    // Q_k(d) = Σ_i d_i C^k_i(d, …, d), then P_(k+1) (see the module documentation).
    const QLEN: usize = start(MAX_ORDER + 2);
    let axes = [Vector3::x(), Vector3::y(), Vector3::z()];
    let mut k_fact = 1.0;
    for k in 0..=order {
        if k > 0 {
            k_fact *= k as f64;
        }
        let n = k + 1;
        // lap = Δ^m Q_k (degree n − 2m), starting from m = 0.
        let mut lap = [0.0; QLEN];
        for (i, mom) in moments.iter().enumerate() {
            mul_linear_add(&mom[start(k)..start(k + 1)], k, &axes[i], &mut lap);
        }
        let mut p = [0.0; QLEN];
        let mut m_fact_2m = 1.0;
        for m in 0..=n / 2 {
            if m > 0 {
                let mut next = [0.0; QLEN];
                laplacian_add(&lap, n - 2 * m + 2, &mut next);
                lap = next;
                m_fact_2m *= 2.0 * m as f64;
            }
            let double_fact: f64 = (1..2 * (n - m)).step_by(2).map(|x| x as f64).product();
            let sign = if (n - m) % 2 == 0 { -1.0 } else { 1.0 };
            let c = sign * double_fact / (4.0 * PI * k_fact * m_fact_2m);
            // c · |d|^(2m) · Δ^m Q_k, of degree n.
            let mut term = [0.0; QLEN];
            for (t, l) in term.iter_mut().zip(&lap[..num_mono(n - 2 * m)]) {
                *t = c * l;
            }
            for deg in (n - 2 * m..n).step_by(2) {
                let mut next = [0.0; QLEN];
                mul_r2_add(&term, deg, &mut next);
                term = next;
            }
            for (x, t) in p.iter_mut().zip(&term[..num_mono(n)]) {
                *x += t;
            }
        }
        coef.extend_from_slice(&p[..num_mono(n)]);
    }
}

/// Nodes with at most this many triangles sum their moments over the triangles; larger ones
/// translate their children's (the same moments, up to rounding, at a cost that no longer grows
/// with the depth of the hierarchy).
const DIRECT_MAX_TRIANGLES: usize = 16;

/// Every node's far-field record and expansion coefficients (`coef_len(order)` per node, in node
/// order): nodes of at most `direct_max` triangles from their triangles, the others by
/// translating their children's moments.
fn build_expansions(
    bvh: &MeshBvh,
    beta: f64,
    order: usize,
    direct_max: usize,
) -> (Vec<FarField>, Vec<f64>) {
    let nodes = &bvh.bvh.nodes;
    // Children after their parent (pre-order), and each node's triangle count.
    let mut pre = Vec::with_capacity(nodes.len());
    let mut parent = vec![0usize; nodes.len()];
    let mut stack = vec![0usize];
    while let Some(n) = stack.pop() {
        pre.push(n);
        if !nodes[n].is_leaf() {
            for c in [0, 1].map(|k| nodes[n].first_index as usize + k) {
                parent[c] = n;
                stack.push(c);
            }
        }
    }
    let mut count = vec![0usize; nodes.len()];
    for &n in pre.iter().rev() {
        let nd = &nodes[n];
        count[n] = if nd.is_leaf() {
            nd.prim_count as usize
        } else {
            count[nd.first_index as usize] + count[nd.first_index as usize + 1]
        };
    }
    // A leaf is always summed over its triangles (it has no children to translate from), whatever
    // `direct_max` is.
    let direct = |n: usize| nodes[n].is_leaf() || count[n] <= direct_max;
    let children = |n: usize| {
        let f = nodes[n].first_index as usize;
        [f, f + 1]
    };
    let far2 = |r2max: f64| beta.max(1.0).powi(2) * r2max;
    let record = |n: usize, center: Vector3<f64>, r2max: f64| FarField {
        center,
        far2: far2(r2max),
        first: nodes[n].first_index,
        count: nodes[n].prim_count,
    };
    // The small nodes from their triangles; those under a large parent keep their moments.
    let small: Vec<(usize, FarField, Vec<f64>, Option<Box<Moments>>)> = pre
        .par_iter()
        .copied()
        .filter(|&n| direct(n))
        .map_init(Vec::new, |slots, n| {
            subtree_slots(bvh, n, slots);
            let (center, r2max, moments) = node_moments(bvh, slots, order);
            let mut c = Vec::with_capacity(coef_len(order));
            expansion_coefficients(&moments, order, &mut c);
            let frontier = n != 0 && !direct(parent[n]);
            (
                n,
                record(n, center, r2max),
                c,
                frontier.then(|| Box::new(moments)),
            )
        })
        .collect();
    let mut far = vec![record(0, Vector3::zeros(), 0.0); nodes.len()];
    let mut coefs = vec![0.0; coef_len(order) * nodes.len()];
    let len = coef_len(order);
    let mut kept: std::collections::HashMap<usize, Box<Moments>> = std::collections::HashMap::new();
    for (n, f, c, m) in small {
        far[n] = f;
        coefs[n * len..(n + 1) * len].copy_from_slice(&c);
        if let Some(m) = m {
            kept.insert(n, m);
        }
    }
    // The large nodes, children first: the area-weighted centre from the children's and the
    // moments translated there.
    let mut area = vec![0.0; nodes.len()];
    let mut corners_sum = vec![Vector3::zeros(); nodes.len()];
    for &n in pre.iter().rev() {
        let (a, v) = if nodes[n].is_leaf() {
            let s = nodes[n].first_index as usize;
            bvh.tris[s..s + nodes[n].prim_count as usize].iter().fold(
                (0.0, Vector3::zeros()),
                |(a, v), [p, q, r]| {
                    (
                        a + 0.5 * (q - p).cross(&(r - p)).norm(),
                        v + p.coords + q.coords + r.coords,
                    )
                },
            )
        } else {
            let [l, r] = children(n);
            (area[l] + area[r], corners_sum[l] + corners_sum[r])
        };
        (area[n], corners_sum[n]) = (a, v);
    }
    let large: Vec<usize> = pre.iter().rev().copied().filter(|&n| !direct(n)).collect();
    for &n in &large {
        let [l, r] = children(n);
        let total = area[l] + area[r];
        let center = if total > 0.0 {
            (far[l].center * area[l] + far[r].center * area[r]) / total
        } else {
            corners_sum[n] / (3.0 * count[n] as f64)
        };
        let mut moments = [[0.0; MOMENTS_LEN]; 3];
        for c in [l, r] {
            let m = kept
                .remove(&c)
                .expect("a child's moments are kept for its parent");
            translate_moments_add(&m, &(far[c].center - center), order, &mut moments);
        }
        // The radius later (below), over the subtree's corners.
        far[n] = record(n, center, 0.0);
        let mut c = Vec::with_capacity(len);
        expansion_coefficients(&moments, order, &mut c);
        coefs[n * len..(n + 1) * len].copy_from_slice(&c);
        kept.insert(n, Box::new(moments));
    }
    // Each large node's radius over its subtree's corners (a scan of the subtree each), in
    // parallel.
    let radii: Vec<f64> = large
        .par_iter()
        .map_init(Vec::new, |slots, &n| {
            subtree_slots(bvh, n, slots);
            let center = far[n].center;
            slots
                .iter()
                .flat_map(|&s| bvh.tris[s].iter())
                .map(|p| (p.coords - center).norm_squared())
                .fold(0.0, f64::max)
        })
        .collect();
    for (&n, r2max) in large.iter().zip(radii) {
        far[n].far2 = far2(r2max);
    }
    (far, coefs)
}

impl WindingNumber {
    /// Builds the hierarchy of `mesh` and the per-node expansions.
    pub fn new(mesh: &TriMesh, options: WindingOptions) -> Self {
        Self::from_bvh(MeshBvh::new(mesh), options)
    }

    /// Adds the per-node expansions to an existing hierarchy (which it keeps; see
    /// [`WindingNumber::bvh`] to run closest-point or ray queries on the same hierarchy).
    pub fn from_bvh(bvh: MeshBvh, options: WindingOptions) -> Self {
        let order = (options.order as usize).min(MAX_ORDER);
        let (far, coefs) = if bvh.is_empty() {
            (Vec::new(), Vec::new())
        } else {
            build_expansions(&bvh, options.beta, order, DIRECT_MAX_TRIANGLES)
        };
        WindingNumber {
            bvh,
            far,
            coefs,
            order,
            options,
        }
    }

    /// The hierarchy the winding number is evaluated on.
    pub fn bvh(&self) -> &MeshBvh {
        &self.bvh
    }

    /// The options it was built with.
    pub fn options(&self) -> &WindingOptions {
        &self.options
    }

    /// Generalized winding number at `p` (fast: far nodes by their expansion).
    pub fn winding_number(&self, p: &Point3<f64>) -> f64 {
        match self.order {
            0 => self.traverse::<0>(p),
            1 => self.traverse::<1>(p),
            2 => self.traverse::<2>(p),
            3 => self.traverse::<3>(p),
            4 => self.traverse::<4>(p),
            _ => self.traverse::<5>(p),
        }
    }

    fn traverse<const K: usize>(&self, p: &Point3<f64>) -> f64 {
        if self.bvh.is_empty() {
            return 0.0;
        }
        let len = coef_len(K);
        let mut sum = 0.0;
        let mut exact = 0.0;
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(n) = stack.pop() {
            let n = n as usize;
            let f = &self.far[n];
            let d = f.center - p.coords;
            if d.norm_squared() > f.far2 {
                sum += eval_expansion::<K>(&self.coefs[n * len..(n + 1) * len], &d);
            } else if f.count > 0 {
                let s = f.first as usize;
                for [a, b, c] in &self.bvh.tris[s..s + f.count as usize] {
                    exact += solid_angle(p, a, b, c);
                }
            } else {
                stack.push(f.first);
                stack.push(f.first + 1);
            }
        }
        sum + exact / (4.0 * PI)
    }

    /// Whether `p` is inside: winding number ≥ ½ (for an inward-oriented mesh, flip it first).
    pub fn is_inside(&self, p: &Point3<f64>) -> bool {
        self.winding_number(p) >= 0.5
    }

    /// [`WindingNumber::winding_number`] for many points, in parallel (rayon).
    pub fn winding_numbers(&self, ps: &[Point3<f64>]) -> Vec<f64> {
        ps.par_iter().map(|p| self.winding_number(p)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::primitives::icosphere;

    fn eval(order: usize, coef: &[f64], d: &Vector3<f64>) -> f64 {
        match order {
            2 => eval_expansion::<2>(coef, d),
            4 => eval_expansion::<4>(coef, d),
            _ => eval_expansion::<5>(coef, d),
        }
    }

    #[test]
    fn translated_moments_give_the_expansions_summed_over_the_triangles() {
        // A bumpy sphere far from the origin (moments keep their precision there too).
        let mut mesh = icosphere(4, 2.0, Point3::new(150.0, -80.0, 40.0));
        for (k, v) in mesh.vertices.iter_mut().enumerate() {
            let bump = 0.05 * ((k * 7919 % 101) as f64 / 101.0 - 0.5);
            *v += (v.coords - Vector3::new(150.0, -80.0, 40.0)) * bump;
        }
        let bvh = MeshBvh::new(&mesh);
        // Down to 1: every node with children translated (leaves hold up to 4 triangles).
        for (order, direct_max) in [(2, DIRECT_MAX_TRIANGLES), (4, DIRECT_MAX_TRIANGLES), (5, 1)] {
            let (far, coefs) = build_expansions(&bvh, 3.0, order, usize::MAX);
            let (far_t, coefs_t) = build_expansions(&bvh, 3.0, order, direct_max);
            let len = coef_len(order);
            let mut translated = 0;
            for (n, (a, b)) in far.iter().zip(&far_t).enumerate() {
                assert!((a.center - b.center).norm() < 1e-9, "node {n}");
                assert!((a.far2 - b.far2).abs() <= 1e-9 * a.far2, "node {n}");
                assert_eq!((a.first, a.count), (b.first, b.count));
                let (ca, cb) = (
                    &coefs[n * len..(n + 1) * len],
                    &coefs_t[n * len..(n + 1) * len],
                );
                // The node's share of the winding number, seen from where its expansion applies.
                for dir in [
                    Vector3::x(),
                    -Vector3::y(),
                    Vector3::new(1.0, 2.0, -2.0) / 3.0,
                ] {
                    let d = dir * a.far2.sqrt() * 1.01;
                    let (wa, wb) = (eval(order, ca, &d), eval(order, cb, &d));
                    assert!(
                        (wa - wb).abs() < 1e-12,
                        "order {order}, node {n}: {wa} against {wb}"
                    );
                }
                translated += usize::from(ca != cb);
            }
            // The large nodes were translated (rounding differs), not summed again.
            assert!(translated > 0);
        }
    }
}
