//! The vertices method on every real vessel mesh of ../shared/data/real (the cortex is in
//! msr_cortex): the carotid in the quick suite, the others in the slow tests
//! (`bash tests/run_slow.sh`). Each is decomposed at the default voxel (5 levels of `vpmcf`),
//! its archive written and read back: the representation read equals the one in memory, and
//! S_0 = X_N − Σ W_i − snap gives back every input vertex to 1e-5h although the input samples
//! were snapped onto S_0 (by up to most of a voxel on these meshes).

mod common;
use common::*;
use vesselmsr::grid::{grid_for_mesh, GridOptions};
use vesselmsr::levelset::voxelize::{voxelize, VoxelizeOptions};
use vesselmsr::msr::archive::{read_msr, write_msr};
use vesselmsr::msr::decompose::{decompose, DecomposeOptions};

/// The check of the module doc on the real meshes whose file names `pick` accepts.
fn vertices_method_gives_back(pick: impl Fn(&str) -> bool) {
    let Some(meshes) = real_meshes() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    for (file, mesh) in meshes.iter().filter(|(f, _)| pick(f)) {
        let spec = grid_for_mesh(mesh, &GridOptions::default()).unwrap();
        let h = spec.voxel();
        let phi = voxelize(mesh, spec.dims, spec.transform, &VoxelizeOptions::default()).unwrap();
        let d = decompose(mesh, phi, &DecomposeOptions::default(), |_, _| {}).unwrap();
        let path = tmp.path().join("msr.npz");
        write_msr(&path, &d.msr).unwrap();
        let back = read_msr(&path).unwrap();
        assert!(
            back == d.msr,
            "{file}: the archive differs from the representation"
        );
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
    vertices_method_gives_back(|f| f == CAROTID);
}

const CAROTID: &str = "carotid_bifurcation.stl";

mod slow {
    /// The other vessels (two aortas, the aneurysm, the coronary).
    #[test]
    #[ignore = "slow: run by tests/run_slow.sh"]
    fn vertices_method_gives_back_every_other_real_vessel() {
        super::vertices_method_gives_back(|f| f != super::CAROTID && !f.starts_with("cortex"));
    }
}
