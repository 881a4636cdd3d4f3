//! The vertices method on every real vessel mesh of ../shared/data/real (the cortex is in
//! msr_cortex): the carotid in the quick suite, the others in the slow tests
//! (`bash tests/run_slow.sh`). Each is decomposed at the default voxel (5 levels of `vpmcf`),
//! its archive written and read back: the compact archive (format 4) is at most 5× the mesh
//! file (the carotid's 1.60×, the aneurysm's 4.61×), every sample of every level comes back
//! within the lattice's half step q/2 per axis (q = 0.02h), the level-set reconstructions from
//! the archive within 0.05h of those from the representation in memory (1,000,000 area samples
//! a surface; S̃_(N−1) for the carotid, every level S̃_(N−1)..S̃_0 for the slow ones: at most
//! 0.036h measured),
//! and S_0 = X_N − Σ W_i − snap gives back every input vertex to 1e-5h although the input
//! samples were snapped onto S_0 (by up to most of a voxel on these meshes).

use crate::common;
use common::*;
use vesselmsr::grid::{grid_for_mesh, GridOptions};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::distance::{surface_distance, SurfaceDistanceOptions};
use vesselmsr::msr::archive::{read_msr, write_msr};
use vesselmsr::msr::compact::QUANTUM_VOXELS;
use vesselmsr::msr::decompose::{decompose, DecomposeOptions};
use vesselmsr::msr::Msr;

/// S̃_{N−1}, …, S̃_{N−levels}: the level-set reconstructions of `msr` carried back from φ_T level
/// by level, as `vesselmsr reconstruct --method levelset` makes them.
fn rebuilds(msr: &Msr, levels: usize) -> Vec<vesselmsr::TriMesh> {
    let n = msr.levels();
    let mut phi = msr.phi.clone();
    let mut out = Vec::new();
    for i in (n + 1 - levels..=n).rev() {
        phi = msr.rebuild_level(&phi, i).unwrap();
        out.push(extract_surface(&phi, &ExtractOptions::default()).unwrap());
    }
    out
}

/// The check of the module doc on the real meshes whose file names `pick` accepts, the archive
/// at most `max_ratio` times the mesh file, the reconstructions of the last `levels` levels
/// compared.
fn vertices_method_gives_back(pick: impl Fn(&str) -> bool, max_ratio: f64, levels: usize) {
    let Some(meshes) = real_meshes() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    for (file, mesh) in meshes.iter().filter(|(f, _)| pick(f)) {
        let spec = grid_for_mesh(mesh, &GridOptions::default()).unwrap();
        let h = spec.voxel();
        let phi = common::phi_on(mesh, &spec);
        let d = decompose(mesh, phi, &DecomposeOptions::default(), |_, _| {}).unwrap();
        let path = tmp.path().join("msr.npz");
        write_msr(&path, &d.msr).unwrap();
        let back = read_msr(&path).unwrap();
        let input_bytes = std::fs::metadata(real_dir().unwrap().join(file))
            .unwrap()
            .len() as f64;
        let ratio = std::fs::metadata(&path).unwrap().len() as f64 / input_bytes;
        assert!(
            ratio <= max_ratio,
            "{file}: archive {ratio:.2}× the mesh file"
        );
        assert_eq!(
            (&back.faces, &back.born, &back.times, &back.params),
            (&d.msr.faces, &d.msr.born, &d.msr.times, &d.msr.params)
        );
        let half = 0.5 * QUANTUM_VOXELS * h * (1.0 + 1e-9);
        for k in 0..=d.msr.levels() {
            let (a, b) = (back.samples_at(k), d.msr.samples_at(k));
            let off = a
                .iter()
                .zip(&b)
                .map(|(p, q)| (p - q).amax())
                .fold(0.0, f64::max);
            assert!(
                off <= half,
                "{file}: level {k} samples off by {off} > {half}"
            );
        }
        let apart: Vec<f64> = rebuilds(&back, levels)
            .iter()
            .zip(&rebuilds(&d.msr, levels))
            .map(|(a, b)| {
                surface_distance(a, b, &SurfaceDistanceOptions { samples: 1_000_000 }).hausdorff / h
            })
            .collect();
        println!(
            "{file}: archive {:.2} MB, {ratio:.2}× the mesh file; S̃_(N-1), S̃_(N-2), … rebuilt \
             from it within {apart:.4?} h of the ones from memory",
            std::fs::metadata(&path).unwrap().len() as f64 / 1e6,
        );
        // Issue 23: no figure moves by more than 0.05h. Measured at most 0.036h (the carotid's
        // S̃_0), 0.013 to 0.028h at S̃_(N-1); 0.084h before the writer refined (format 3).
        let worst = apart.iter().copied().fold(0.0, f64::max);
        assert!(worst <= 0.05, "{file}: {apart:.4?} h");
        let worst = back
            .mesh_at(0)
            .vertices
            .iter()
            .zip(&mesh.vertices)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        let snap = back.snap.iter().map(|s| s.norm()).fold(0.0, f64::max);
        println!(
            "{file}: h = {h:.4}, {} samples, largest snap {:.2} h, vertices back to {:.1e} h",
            back.samples.len(),
            snap / h,
            worst / h
        );
        assert!(snap > 1e-3 * h, "{file}: nothing was snapped");
        assert!(worst <= 1e-5 * h, "{file}: {worst}");
        assert_eq!(back.mesh_at(0).faces, mesh.faces, "{file}");
    }
}

/// The carotid: in metres (h = 0.2 mm), snapped by up to 0.68h.
#[test]
fn vertices_method_gives_back_the_carotid() {
    vertices_method_gives_back(|f| f == CAROTID, 5.0, 1);
}

const CAROTID: &str = "carotid_bifurcation.stl";

mod slow {
    /// The other vessels (two aortas, the aneurysm, the coronary).
    #[test]
    #[ignore = "slow: run by tests/run_slow.sh"]
    fn vertices_method_gives_back_every_other_real_vessel() {
        // Issue 23's 5× (measured with format 4: the aneurysm 4.61×, the others 2.0 to 2.7×).
        super::vertices_method_gives_back(
            |f| f != super::CAROTID && !f.starts_with("cortex"),
            5.0,
            5,
        );
    }
}
