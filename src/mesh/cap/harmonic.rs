//! Discrete harmonic interpolation over a vertex graph (uniform "umbrella" Laplacian) with fixed
//! boundary values, solved by conjugate gradients: the membrane fairing of Liepa (2003) and the
//! out-of-plane offset of planar caps.

/// Overwrites `values[i]` for every vertex with `fixed[i] == false` so that each such value is
/// the mean of its neighbours' values (neighbours listed in `nbrs`), keeping fixed values. Free
/// vertices with no path to a fixed vertex keep their value.
pub(super) fn harmonic_fill(nbrs: &[Vec<usize>], fixed: &[bool], values: &mut [f64]) {
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
            .filter(|&&j| slot[j] == usize::MAX)
            .map(|&j| values[j])
            .sum();
    }
    let apply = |x: &[f64], y: &mut [f64]| {
        for (k, &i) in free.iter().enumerate() {
            let mut s = nbrs[i].len() as f64 * x[k];
            for &j in &nbrs[i] {
                if slot[j] != usize::MAX {
                    s -= x[slot[j]];
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
        let nbrs = vec![vec![1], vec![0, 2], vec![1, 3], vec![2, 4], vec![3]];
        let fixed = [true, false, false, false, true];
        let mut v = [0.0, 7.0, -3.0, 2.0, 4.0];
        harmonic_fill(&nbrs, &fixed, &mut v);
        for (i, x) in v.iter().enumerate() {
            assert!((x - i as f64).abs() < 1e-9, "{v:?}");
        }
    }
}
