//! How closely the level-set reconstruction gives back each level from the next: the paper's
//! Figure 1 measure, Hausdorff(S_{i−1}, S̃_{i−1}) with S̃_{i−1} rebuilt from the exact φ_i and
//! the details W_i in one step ([`super::reconstruct::rebuild_from_tangent_planes`]), both
//! surfaces the marching-cubes zero level sets of their grids. The decomposition has every
//! φ_i ([`super::decompose::DecomposeOptions::keep_level_sets`]); an archive keeps φ_T only, so
//! its full reconstruction chains the steps from φ_T instead (`vesselmsr reconstruct`).

use super::decompose::Decomposition;
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::mesh::distance::{surface_distance, SurfaceDistance, SurfaceDistanceOptions};
use crate::{Error, Result};

/// For each level i = 1..=N of `d` (decomposed with its level sets kept), the distances between
/// S_{i−1} and its one-step reconstruction S̃_{i−1} from φ_i, measured with `distance` (area
/// samples on both surfaces plus every vertex; a Hausdorff distance estimated from samples is
/// a lower bound of the true one, closer with more samples). `progress(i)` is called after each
/// level.
pub fn measure_level_rebuilds(
    d: &Decomposition,
    distance: &SurfaceDistanceOptions,
    mut progress: impl FnMut(usize),
) -> Result<Vec<SurfaceDistance>> {
    let n = d.msr.levels();
    if d.level_sets.len() != n + 1 {
        return Err(Error::Geometry(format!(
            "measuring the rebuilds needs the {} level sets of the decomposition, it kept {}",
            n + 1,
            d.level_sets.len()
        )));
    }
    (1..=n)
        .map(|i| {
            let rebuilt = d.msr.rebuild_level(&d.level_sets[i], i)?;
            let truth = extract_surface(&d.level_sets[i - 1], &ExtractOptions::default())?;
            let got = extract_surface(&rebuilt, &ExtractOptions::default())?;
            let measured = surface_distance(&truth, &got, distance);
            progress(i);
            Ok(measured)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{grid_for_mesh, GridOptions};
    use crate::levelset::voxelize::voxelize;
    use crate::mesh::primitives::icosphere;
    use crate::msr::decompose::{decompose, DecomposeOptions};
    use nalgebra::Point3;

    /// A sphere's levels are spheres that shrink evenly under mean curvature flow: each rebuild
    /// gives back the level before to a twentieth of a voxel (measured 0.008h). Without the
    /// level sets kept, the measure is refused.
    #[test]
    fn sphere_levels_rebuild_closely_and_need_the_level_sets() {
        let mesh = icosphere(4, 1.0, Point3::origin());
        let spec = grid_for_mesh(
            &mesh,
            &GridOptions {
                voxel: Some(0.08),
                ..Default::default()
            },
        )
        .unwrap();
        let phi = voxelize(&mesh, spec.dims, spec.transform, &Default::default()).unwrap();
        let opts = DecomposeOptions {
            levels: 2,
            velocity: crate::motion::Velocity::MeanCurvature,
            keep_level_sets: true,
            ..Default::default()
        };
        let mut d = decompose(&mesh, phi, &opts, |_, _| {}).unwrap();
        let distance = SurfaceDistanceOptions { samples: 20_000 };
        let kept = std::mem::take(&mut d.level_sets);
        assert!(measure_level_rebuilds(&d, &distance, |_| {}).is_err());
        d.level_sets = kept;
        let mut seen = Vec::new();
        let measured = measure_level_rebuilds(&d, &distance, |i| seen.push(i)).unwrap();
        assert_eq!(seen, [1, 2]);
        for m in &measured {
            println!(
                "{:.4}h (mean {:.5}h)",
                m.hausdorff / 0.08,
                m.mean_distance / 0.08
            );
            assert!(m.hausdorff > 0.0 && m.hausdorff < 0.05 * 0.08, "{m:?}");
        }
    }
}
