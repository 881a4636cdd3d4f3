//! Discrete harmonic interpolation over a weighted vertex graph with fixed boundary values, solved
//! by conjugate gradients: with unit weights the "umbrella" membrane fairing of Liepa (2003), with
//! cotangent weights the linear finite-element solution of Laplace's equation (Pinkall and
//! Polthier 1993) used for the out-of-plane offset of planar caps.

/// Overwrites `values[i]` for every vertex with `fixed[i] == false` so that Σ_j w_ij (x_i − x_j)
/// = 0 over its neighbours `nbrs[i]` = [(j, w_ij)] (symmetric weights), keeping fixed values.
/// Free vertices with no path to a fixed vertex keep their value.
pub(super) fn harmonic_fill(nbrs: &[Vec<(usize, f64)>], fixed: &[bool], values: &mut [f64]) {
    let n = values.len();
    // Free unknowns numbered 0..m.
    let mut slot = vec![usize::MAX; n];
    let mut free = Vec::new();
    for i in 0..n {
        if !fixed[i] && !nbrs[i].is_empty() {
            slot[i] = free.len();
            free.push(i);
        }
    }
    let m = free.len();
    if m == 0 {
        return;
    }
    // A x = b with A = D − W over free vertices; b gathers fixed neighbours.
    let mut b = vec![0.0; m];
    for (k, &i) in free.iter().enumerate() {
        b[k] = nbrs[i]
            .iter()
            .filter(|&&(j, _)| slot[j] == usize::MAX)
            .map(|&(j, w)| w * values[j])
            .sum();
    }
    let apply = |x: &[f64], y: &mut [f64]| {
        for (k, &i) in free.iter().enumerate() {
            let mut s = 0.0;
            for &(j, w) in &nbrs[i] {
                s += w * x[k];
                if slot[j] != usize::MAX {
                    s -= w * x[slot[j]];
                }
            }
            y[k] = s;
        }
    };
    let mut x: Vec<f64> = free.iter().map(|&i| values[i]).collect();
    let mut r = vec![0.0; m];
    apply(&x, &mut r);
    for k in 0..m {
        r[k] = b[k] - r[k];
    }
    let bnorm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    let scale = bnorm
        .max(x.iter().map(|v| v * v).sum::<f64>().sqrt())
        .max(f64::MIN_POSITIVE);
    let mut p = r.clone();
    let mut ap = vec![0.0; m];
    let mut rr: f64 = r.iter().map(|v| v * v).sum();
    for _ in 0..(4 * m + 100) {
        if rr.sqrt() <= 1e-12 * scale {
            break;
        }
        apply(&p, &mut ap);
        let pap: f64 = p.iter().zip(&ap).map(|(a, b)| a * b).sum();
        if pap.is_nan() || pap <= 0.0 {
            break; // singular part (a free component without fixed vertices): stop where we are
        }
        let alpha = rr / pap;
        for k in 0..m {
            x[k] += alpha * p[k];
            r[k] -= alpha * ap[k];
        }
        let rr_new: f64 = r.iter().map(|v| v * v).sum();
        let beta = rr_new / rr;
        rr = rr_new;
        for k in 0..m {
            p[k] = r[k] + beta * p[k];
        }
    }
    for (k, &i) in free.iter().enumerate() {
        if x[k].is_finite() {
            values[i] = x[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::harmonic_fill;

    #[test]
    fn path_graph_interpolates_linearly() {
        // 0 - 1 - 2 - 3 - 4 with ends fixed at 0 and 4: the harmonic values are 0,1,2,3,4.
        let nbrs = vec![
            vec![(1, 1.0)],
            vec![(0, 1.0), (2, 1.0)],
            vec![(1, 1.0), (3, 1.0)],
            vec![(2, 1.0), (4, 1.0)],
            vec![(3, 1.0)],
        ];
        let fixed = [true, false, false, false, true];
        let mut v = [0.0, 7.0, -3.0, 2.0, 4.0];
        harmonic_fill(&nbrs, &fixed, &mut v);
        for (i, x) in v.iter().enumerate() {
            assert!((x - i as f64).abs() < 1e-9, "{v:?}");
        }
    }
}
