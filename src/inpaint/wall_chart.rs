//! The wall's offsets across a hole, on a guide tube's wall chart: the biharmonic interpolation
//! of the offsets read on the intact wall (`guided`'s details carried across D).
//!
//! A tube's chart has one row per curve sample (arc length along the tube) and one column per
//! section ray (periodic angle); a cell holds the wall's offset from the tube's interpolated
//! section there. Where the wall was read (outside D, or intact wall inside a hole's ball) the
//! cell is known; the cells over the hole are filled here.
//!
//! The fill minimises the sum over all cells of the squared discrete Laplacian (a thin plate on
//! the chart; the known cells fixed; its second difference around the section weighs
//! [`AROUND_WEIGHT`] of the one along the vessel): its unknowns solve the biharmonic equation,
//! so the wall's slope and curvature around the hole carry on into it. A harmonic (membrane)
//! fill never leaves the range of its boundary values and flattens a bulge whose crest lies
//! over the hole: on the real vessels of `benches/repair_real` the biharmonic fill took the
//! largest error inside a hole from 2.09h to 1.23h (open aorta), 3.88h to 3.09h (aneurysm's
//! ICA), 1.59h to 0.58h (the coronary's bend). The paper inpaints its multiscale details
//! across D with a diffusion (eq. 4.1, viscosity ε); this is the smoothest fill of that kind on
//! the vessel's own chart.
//!
//! A junction's branch uses a tension τ (`fill_with_tension`, `guided::JUNCTION_CHART_TENSION`):
//! Σ (L u)² + τ Σ |∇u|², a thin plate over short lengths and a membrane over long ones, so that
//! past the last reading, towards the junction point, the wall's slope is not carried on.
//!
//! Solver: the normal equations (P L L P + τ P (−L) P) x = −P L L u₀ + τ P L u₀ on the unknown
//! cells (L the chart's Laplacian, symmetric and negative semidefinite; P the selection of
//! unknown cells), symmetric positive definite when a
//! cell is known, banded in sample-major order (a cell couples to cells at most two rows away:
//! bandwidth 2 × rays), solved by banded Cholesky: O(unknowns × rays²), a few milliseconds for
//! a hole's few thousand cells, where conjugate gradients needed thousands of iterations.

/// Weight of the chart Laplacian's second difference around the section, against the one along
/// the vessel (1: isotropic in world units). A vessel's wall continues along the vessel more
/// faithfully than around it (towards its bifurcation a flattened aorta's sides flare where its
/// top and bottom close in: seed 26's junction chop, 4.36h isotropic): on the 375 kept cases of
/// `benches/repair_real` (seeds 21–35) 0.7 moved 157 outputs by more than 0.05h, 102 closer to
/// the truth and 55 farther (chosen against 0.5, 115 and 88, and 0.85, 80 and 26; on seeds
/// 21–28 and 29–35 apart, 54 and 30, 48 and 25).
pub const AROUND_WEIGHT: f64 = 0.7;

/// The stencil of the chart's Laplacian at cell (i, j) (cells sample-major, `m` angles per
/// sample): periodic in angle with `spacing[i]` (world units) between neighbouring angles at
/// sample i, arc length `arc` along; the first and last samples see only their one neighbour
/// (no flux). (cell, weight) pairs, the cell itself first.
fn stencil(i: usize, j: usize, arc: &[f64], spacing: &[f64], m: usize) -> Vec<(usize, f64)> {
    let n = arc.len();
    let c = i * m + j;
    let around = AROUND_WEIGHT / spacing[i].max(1e-12).powi(2);
    let mut out = vec![(c, 0.0)];
    let mut centre = 0.0;
    if m > 1 {
        out.push((i * m + (j + m - 1) % m, around));
        out.push((i * m + (j + 1) % m, around));
        centre -= 2.0 * around;
    }
    if i > 0 {
        let w = 1.0 / (arc[i] - arc[i - 1]).max(1e-12).powi(2);
        out.push((c - m, w));
        centre -= w;
    }
    if i + 1 < n {
        let w = 1.0 / (arc[i + 1] - arc[i]).max(1e-12).powi(2);
        out.push((c + m, w));
        centre -= w;
    }
    out[0].1 = centre;
    out
}

/// Replaces the unknown cells of `values` (`known[c]` false) by the biharmonic interpolation of
/// the known ones (see the module docs). Nothing changes when every cell or no cell is known.
pub fn fill_biharmonic(values: &mut [f64], known: &[bool], arc: &[f64], spacing: &[f64], m: usize) {
    fill_with_tension(values, known, arc, spacing, m, 0.0)
}

/// [`fill_biharmonic`] with a tension τ (1/world length²): minimises Σ (L u)² + τ Σ |∇u|²,
/// a thin plate for features shorter than 1/√τ and a membrane for longer ones.
pub fn fill_with_tension(
    values: &mut [f64],
    known: &[bool],
    arc: &[f64],
    spacing: &[f64],
    m: usize,
    tension: f64,
) {
    let n = arc.len();
    if n < 2 || m == 0 || values.len() != n * m || known.len() != n * m {
        return;
    }
    if known.iter().all(|&k| k) || !known.iter().any(|&k| k) {
        return;
    }
    // Unknown cells, numbered in cell order.
    let mut slot = vec![usize::MAX; n * m];
    let mut cells = Vec::new();
    for c in 0..n * m {
        if !known[c] {
            slot[c] = cells.len();
            cells.push(c);
        }
    }
    let count = cells.len();
    // The rows of L that touch an unknown cell: each adds l lᵀ to the matrix (l its weights on
    // the unknown cells) and −l (L u₀)ₑ to the right-hand side (u₀: the known values, 0 on the
    // unknown cells).
    let mut rows: Vec<usize> = cells
        .iter()
        .flat_map(|&c| {
            stencil(c / m, c % m, arc, spacing, m)
                .into_iter()
                .map(|(e, _)| e)
        })
        .collect();
    rows.sort_unstable();
    rows.dedup();
    let mut band_width = 0;
    let entries: Vec<(Vec<(usize, f64)>, f64)> = rows
        .iter()
        .map(|&e| {
            let st = stencil(e / m, e % m, arc, spacing, m);
            let known_part: f64 = st
                .iter()
                .filter(|(c, _)| known[*c])
                .map(|(c, w)| w * values[*c])
                .sum();
            let l: Vec<(usize, f64)> = st
                .iter()
                .filter(|(c, _)| !known[*c])
                .map(|(c, w)| (slot[*c], *w))
                .collect();
            let lo = l.iter().map(|x| x.0).min().unwrap_or(0);
            let hi = l.iter().map(|x| x.0).max().unwrap_or(0);
            band_width = band_width.max(hi - lo);
            (l, known_part)
        })
        .collect();
    // Lower band: a[k * w1 + d] = A[k][k − d], d in 0..=band_width.
    let w1 = band_width + 1;
    let mut a = vec![0.0; count * w1];
    let mut rhs = vec![0.0; count];
    for (&e, (l, known_part)) in rows.iter().zip(&entries) {
        for &(p, wp) in l {
            rhs[p] -= wp * known_part;
            for &(q, wq) in l {
                if q <= p {
                    a[p * w1 + (p - q)] += wp * wq;
                }
            }
        }
        // The membrane part, on the rows of unknown cells: τ (−L) on the matrix, τ (L u₀) on
        // the right-hand side (the row's known part).
        if tension > 0.0 && !known[e] {
            let p = slot[e];
            rhs[p] += tension * known_part;
            for &(q, wq) in l {
                if q <= p {
                    a[p * w1 + (p - q)] -= tension * wq;
                }
            }
        }
    }
    // Banded Cholesky A = G Gᵀ in place (G lower, same band).
    for k in 0..count {
        let first = k.saturating_sub(band_width);
        for j in first..=k {
            let mut sum = a[k * w1 + (k - j)];
            let lo = first.max(j.saturating_sub(band_width));
            for p in lo..j {
                sum -= a[k * w1 + (k - p)] * a[j * w1 + (j - p)];
            }
            if j == k {
                if !(sum > 0.0) {
                    // Not positive definite (cannot happen with a known cell; guard against
                    // degenerate charts): leave the values as they were.
                    return;
                }
                a[k * w1] = sum.sqrt();
            } else {
                a[k * w1 + (k - j)] = sum / a[j * w1];
            }
        }
    }
    // G y = rhs, then Gᵀ x = y.
    let mut x = rhs;
    for k in 0..count {
        let first = k.saturating_sub(band_width);
        let mut sum = x[k];
        for p in first..k {
            sum -= a[k * w1 + (k - p)] * x[p];
        }
        x[k] = sum / a[k * w1];
    }
    for k in (0..count).rev() {
        let mut sum = x[k];
        for q in k + 1..(k + w1).min(count) {
            sum -= a[q * w1 + (q - k)] * x[q];
        }
        x[k] = sum / a[k * w1];
    }
    for (k, &c) in cells.iter().enumerate() {
        values[c] = x[k];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chart of `n` samples 0.1 apart and `m` angles 0.3 apart with `truth(s, j)` on it and
    /// a hole of samples 20..40, angles 5..17 set to 0.
    fn holed(
        n: usize,
        m: usize,
        truth: impl Fn(f64, usize) -> f64,
    ) -> (Vec<f64>, Vec<bool>, Vec<f64>, Vec<f64>) {
        let arc: Vec<f64> = (0..n).map(|i| 0.1 * i as f64).collect();
        let mut known = vec![true; n * m];
        let mut u: Vec<f64> = (0..n * m).map(|c| truth(arc[c / m], c % m)).collect();
        for i in 20..40 {
            for j in 5..17 {
                known[i * m + j] = false;
                u[i * m + j] = 0.0;
            }
        }
        (u, known, arc, vec![0.3; n])
    }

    #[test]
    fn a_hole_in_a_quadratic_chart_is_filled_with_that_quadratic() {
        // u = (s − 3)² + 2 along the tube, the same at every angle: its Laplacian is constant,
        // so it is biharmonic and the fill is exact; a harmonic fill would flatten it (the
        // crest at s = 3 lies in the hole at 1 below the hole's rim values, 2 + 0.01).
        let truth = |s: f64, _: usize| (s - 3.0).powi(2) + 2.0;
        let (mut u, known, arc, spacing) = holed(60, 24, truth);
        fill_biharmonic(&mut u, &known, &arc, &spacing, 24);
        let worst = (0..u.len())
            .map(|c| (u[c] - truth(arc[c / 24], c % 24)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-8, "worst {worst}");
    }

    #[test]
    fn a_hole_in_a_linear_chart_is_filled_with_that_plane_and_known_cells_stay() {
        let truth = |s: f64, j: usize| 2.0 * s + 3.0 + 0.0 * j as f64;
        let (mut u, known, arc, spacing) = holed(60, 24, truth);
        let before = u.clone();
        fill_biharmonic(&mut u, &known, &arc, &spacing, 24);
        for c in 0..u.len() {
            if known[c] {
                assert_eq!(u[c], before[c]);
            } else {
                assert!(
                    (u[c] - truth(arc[c / 24], c % 24)).abs() < 1e-8,
                    "cell {c}: {}",
                    u[c]
                );
            }
        }
        // A hole over the first rows has no reading beyond it: a constant chart stays constant
        // (the plate's energy is 0 there), as a membrane with no flux through its end would.
        let mut known = vec![true; 60 * 24];
        let mut w = vec![1.0; 60 * 24];
        for c in 0..5 * 24 {
            known[c] = false;
            w[c] = -4.0;
        }
        fill_biharmonic(&mut w, &known, &arc, &spacing, 24);
        assert!(w.iter().all(|v| (v - 1.0).abs() < 1e-9), "{:?}", &w[..24]);
        // Nothing known: nothing changes.
        let mut v = vec![5.0; 60 * 24];
        fill_biharmonic(&mut v, &vec![false; 60 * 24], &arc, &spacing, 24);
        assert!(v.iter().all(|&x| x == 5.0));
    }

    /// The membrane (harmonic) fill of the same cells, by Gauss–Seidel sweeps: what the tubes
    /// used before.
    fn fill_harmonic(values: &mut [f64], known: &[bool], arc: &[f64], spacing: &[f64], m: usize) {
        for _ in 0..20_000 {
            for c in 0..values.len() {
                if !known[c] {
                    let st = stencil(c / m, c % m, arc, spacing, m);
                    let off: f64 = st[1..].iter().map(|(e, w)| w * values[*e]).sum();
                    values[c] = -off / st[0].1;
                }
            }
        }
    }

    #[test]
    fn tension_holds_a_slope_back_past_the_last_reading_as_a_membrane_would() {
        // u = s along the tube, every angle; the last 20 samples (2 units, towards a junction
        // point) unknown. The thin plate carries the slope on (to 4.9 at the end, where the
        // chart's one-sided Laplacian levels it off; u = s would be 5.9); a membrane with no
        // flux through the end stays at the last reading (3.9); a tension τ = 1 lies between,
        // and a very large one is the membrane.
        let (n, m) = (60, 24);
        let arc: Vec<f64> = (0..n).map(|i| 0.1 * i as f64).collect();
        let spacing = vec![0.3; n];
        let known: Vec<bool> = (0..n * m).map(|c| c / m < 40).collect();
        let u0: Vec<f64> = (0..n * m)
            .map(|c| if known[c] { arc[c / m] } else { 0.0 })
            .collect();
        let end = |tension: f64| {
            let mut u = u0.clone();
            fill_with_tension(&mut u, &known, &arc, &spacing, m, tension);
            u[(n - 1) * m]
        };
        let (plate, taut, membrane) = (end(0.0), end(1.0), end(1e6));
        println!("end value: thin plate {plate}, tension 1 {taut}, membrane {membrane}");
        assert!((plate - 4.9).abs() < 1e-6, "thin plate {plate}");
        assert!((membrane - 3.9).abs() < 1e-3, "membrane {membrane}");
        assert!(
            taut > membrane + 0.1 && taut < plate - 0.1,
            "tension 1: {taut}"
        );
        // No tension is the thin plate, to the bit.
        let mut a = u0.clone();
        let mut b = u0.clone();
        fill_biharmonic(&mut a, &known, &arc, &spacing, m);
        fill_with_tension(&mut b, &known, &arc, &spacing, m, 0.0);
        assert_eq!(a, b);
    }

    #[test]
    fn a_bulge_around_the_tube_is_carried_across_the_hole_better_than_by_a_membrane() {
        // A wall offset that varies around the tube, cos θ, constant along it; the hole spans
        // angles 5..17 of 24 (75°–255°), the trough at 180° inside it. Not biharmonic on the
        // ring, but smooth: the thin plate follows it within 0.03; the membrane cannot go
        // below its values around the hole (about −0.7 at 225°) towards the trough's −1.
        let m = 24;
        let truth = |_: f64, j: usize| (std::f64::consts::TAU * j as f64 / m as f64).cos();
        let (u0, known, arc, spacing) = holed(60, m, truth);
        let error = |u: &[f64]| {
            (0..u.len())
                .map(|c| (u[c] - truth(arc[c / m], c % m)).abs())
                .fold(0.0, f64::max)
        };
        let mut thin_plate = u0.clone();
        fill_biharmonic(&mut thin_plate, &known, &arc, &spacing, m);
        let mut membrane = u0;
        fill_harmonic(&mut membrane, &known, &arc, &spacing, m);
        let (bi, harm) = (error(&thin_plate), error(&membrane));
        assert!(bi < 0.03, "biharmonic worst {bi}");
        assert!(harm > 3.0 * bi, "harmonic worst {harm}, biharmonic {bi}");
    }
}
