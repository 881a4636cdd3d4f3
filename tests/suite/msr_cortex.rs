//! The paper's Figure 1 experiment on the real cortex (../shared/data/real), at the default voxel
//! size: 5 levels of `vpmcf`; a slow test (`bash tests/run_slow.sh`). Asserted: the vertices method gives back the input to 1e-5h; each
//! level keeps the volume within 1%; details get sparser (the fraction of |w_i| < 0.1h grows)
//! and the levels smoother (the mean |κ| at the samples falls);
//! both level-set reconstructions of S_{i−1} from S_i stay within 0.05h of it on average; the
//! tangent-plane reconstruction (the default; measured by `msr::fidelity`, as
//! `vesselmsr decompose --measure-rebuilds` measures it) within 0.5h everywhere. The Hausdorff
//! distance is a largest distance, estimated from samples, so more samples find maxima fewer
//! miss: the default measure takes 1,000,000 area samples per surface and every vertex, and
//! `VESSELMSR_HAUSDORFF_SAMPLES` sets another count (asserted all the same). Measured
//! 2026-12-03: 0.37, 0.23, 0.22, 0.21, 0.22 h with 100,000 samples; 0.41, 0.31, 0.36, 0.35,
//! 0.31 h with 2,000,000; 0.39, 0.33, 0.40, 0.38, 0.31 h with 8,000,000.
//! Printed (`--nocapture`): the table of Hausdorff(S_{i−1}, S̃_{i−1}) in h for both level-set
//! methods, with the levels where the goal of 0.5h is not met.

use crate::common;
use common::*;
use vesselmsr::grid::{grid_for_mesh, GridOptions};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::distance::{surface_distance, SurfaceDistanceOptions};
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::msr::decompose::{decompose, DecomposeOptions};
use vesselmsr::msr::fidelity::measure_level_rebuilds;
use vesselmsr::msr::reconstruct::{advect_back, AdvectOptions};

/// Area samples per surface for the paper's foot-point advection, whose mean distance only is
/// asserted.
const ADVECT_SAMPLES: usize = 100_000;

/// The whole experiment is slow (about two minutes on two cores): the quick suite's guards of
/// the same points are msr_decompose (an ellipsoid), msr_real_vertices and cli_msr (the aorta,
/// `decompose --measure-rebuilds` within 0.5h).
mod slow {
    use super::*;

    #[test]
    #[ignore = "slow: run by tests/run_slow.sh"]
    fn cortex_five_levels_of_vpmcf() {
        let Some(dir) = real_dir() else { return };
        let mesh = read_real(&dir, "cortex_rh_pial_fsaverage5.stl");
        let volume0 = mesh_info(&mesh).volume.unwrap();
        let spec = grid_for_mesh(&mesh, &GridOptions::default()).unwrap();
        let h = spec.voxel();
        let phi = common::phi_on(&mesh, &spec);
        let opts = DecomposeOptions {
            levels: 5,
            keep_level_sets: true,
            ..Default::default()
        };
        let d = decompose(&mesh, phi, &opts, |_, _| {}).unwrap();
        // The Hausdorff distance is a largest distance, sampled (see the module doc).
        let samples: usize = std::env::var("VESSELMSR_HAUSDORFF_SAMPLES")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1_000_000);
        let m = &d.msr;
        println!(
            "cortex: h = {h:.4}, T = {:.4} ({:.0} h²), dt = {:.4}, {} samples; Hausdorff from {samples} \
             area samples per surface and every vertex",
            m.params.time,
            m.params.time / (h * h),
            m.params.dt,
            m.samples.len()
        );
        let s0 = m.mesh_at(0);
        let worst = s0
            .vertices
            .iter()
            .zip(&mesh.vertices)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-5 * h, "vertices method: {worst}");

        // The default level-set reconstruction, S̃_{i−1} from the exact φ_i (the paper's measure).
        let tangent_all =
            measure_level_rebuilds(&d, &SurfaceDistanceOptions { samples }, |_| {}).unwrap();
        let mut not_met = Vec::new();
        let mut sparse = 0.0;
        let mut curvature = f64::INFINITY;
        println!("level | mean|w| (h) | |w|<0.1h | volume | mean|κ|·h | hausdorff advect | tangent planes (h)");
        for i in 1..=m.levels() {
            let r = &d.reports[i - 1];
            assert!(
                ((r.volume - volume0) / volume0).abs() < 0.01,
                "level {i}: volume {}",
                r.volume
            );
            assert!(
                r.sparse_fraction > sparse,
                "level {i}: sparsity does not grow"
            );
            sparse = r.sparse_fraction;
            assert!(
                r.mean_abs_curvature < curvature,
                "level {i}: mean |κ| does not fall"
            );
            curvature = r.mean_abs_curvature;
            let truth = extract_surface(&d.level_sets[i - 1], &ExtractOptions::default()).unwrap();
            let data = m.level_data(i);
            let arrived: Vec<_> = data
                .points
                .iter()
                .zip(&data.details)
                .map(|(x, w)| x + w)
                .collect();
            let advected = advect_back(
                &d.level_sets[i],
                &arrived,
                &data.details,
                &AdvectOptions::default(),
            )
            .unwrap();
            let advect = surface_distance(
                &truth,
                &extract_surface(&advected, &ExtractOptions::default()).unwrap(),
                // Its Hausdorff distance, several h, is printed for comparison only.
                &SurfaceDistanceOptions {
                    samples: ADVECT_SAMPLES,
                },
            );
            let tangent = tangent_all[i - 1];
            println!(
                "{i} | {:.3} | {:.1}% | {:+.3}% | {:.4} | {:.2} (mean {:.4}) | {:.2} (mean {:.4})",
                r.mean_abs_detail / h,
                100.0 * r.sparse_fraction,
                100.0 * (r.volume - volume0) / volume0,
                r.mean_abs_curvature * h,
                advect.hausdorff / h,
                advect.mean_distance / h,
                tangent.hausdorff / h,
                tangent.mean_distance / h
            );
            assert!(
                advect.mean_distance < 0.05 * h && tangent.mean_distance < 0.05 * h,
                "level {i}"
            );
            if tangent.hausdorff > 0.5 * h {
                not_met.push(format!(
                    "level {i}: Hausdorff {:.2}h (tangent planes) > 0.5h",
                    tangent.hausdorff / h
                ));
            }
        }
        for n in &not_met {
            println!("NOT MET: {n}");
        }
        assert!(not_met.is_empty(), "{not_met:?}");
    }
}
