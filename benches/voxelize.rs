//! Voxelize benchmark: our `voxelize` of the shipped cortex hemisphere (20,480 triangles, closed)
//! and open-ended aorta (11,887 triangles, three open ends) on their default grids (h = min(mean edge / 2, longest extent / 256): 256 cells along the longest axis)
//! against libigl's `signed_distance` (fast-winding-number sign, via reference/oracle.py) on the
//! same grid nodes, in the same run. libigl computes every node; our side is timed twice: band
//! only (exact distances within 3 voxels, sign everywhere, ±3h outside: `FarFill::Clamp`) and all
//! nodes (`FarFill::Exact`); libigl is also timed on the band nodes alone. The reference's time
//! is its own computation ("seconds": no Python start-up, no file reading). Also prints how far
//! the two fields agree.
//!
//! Run: `cargo bench --bench voxelize` (the reference side needs reference/.venv, which
//! `bash tests/run_all.sh` creates, or $VESSELMSR_PYTHON). `VOXELIZE_BENCH_CELLS=N` changes the
//! 256 cells along the longest axis.

mod common;

use common::{read_f64s, seconds, time_median, write_points, Reference};
use nalgebra::Point3;
use std::path::Path;
use std::time::Duration;
use vesselmsr::bvh::brute::winding_number_exact;
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::io::read_mesh;
use vesselmsr::levelset::voxelize::{voxelize_with_report, FarFill, VoxelizeOptions};
use vesselmsr::mesh::measures::{bounding_box, mean_edge_length};
use vesselmsr::TriMesh;

/// Median wall time of `f` over `runs` runs, with the last result.
fn time<T>(runs: usize, f: impl FnMut() -> T) -> (Duration, T) {
    time_median(runs, runs, Duration::ZERO, f)
}

/// The default grid of the issue: h = min(mean edge / 2, longest extent / cells), the bounding box
/// padded by 4 voxels on every side.
fn default_layout(mesh: &TriMesh, cells: f64) -> ([usize; 3], GridTransform) {
    let (lo, hi) = bounding_box(mesh);
    let ext = hi - lo;
    let h = (mean_edge_length(mesh) / 2.0).min(ext.max() / cells);
    let pad = 4.0;
    let dims = [0, 1, 2].map(|a| (ext[a] / h).ceil() as usize + 1 + 2 * pad as usize);
    let origin = lo - nalgebra::Vector3::repeat(pad * h);
    (dims, GridTransform::new(origin, h))
}

/// libigl signed distance at `points`: (values, seconds of computation).
fn libigl_signed_distance(
    reference: &Reference,
    mesh: &Path,
    points: &[Point3<f64>],
) -> Option<(Vec<f64>, f64)> {
    let dir = tempfile::tempdir().ok()?;
    let input = write_points(dir.path(), points)?;
    let output = dir.path().join("o.f64");
    let answer = reference.run(&[
        "signed_distance".as_ref(),
        mesh.as_os_str(),
        input.as_os_str(),
        output.as_os_str(),
    ])?;
    Some((read_f64s(&output)?, seconds(&answer)?))
}

fn main() {
    let root = common::root();
    let cells: f64 = std::env::var("VOXELIZE_BENCH_CELLS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256.0);
    let reference = Reference::find_or_notice("libigl timings");
    println!(
        "vesselmsr voxelize benchmark ({} rayon threads)",
        rayon::current_num_threads()
    );
    for (name, file) in [
        ("cortex (closed)", "data/cortex_rh_pial_fsaverage5.stl"),
        ("aorta (open ends)", "data/aorta_abdominal_open_ends.stl"),
    ] {
        bench_mesh(reference.as_ref(), name, &root.join(file), cells);
    }
}

fn bench_mesh(reference: Option<&Reference>, name: &str, path: &Path, cells: f64) {
    let mesh = read_mesh(path).expect("data/ mesh reads");
    let (dims, transform) = default_layout(&mesh, cells);
    let n = dims.iter().product::<usize>();
    println!(
        "\n{name}: {} triangles, grid {}×{}×{} = {} nodes, h = {:.4}",
        mesh.num_faces(),
        dims[0],
        dims[1],
        dims[2],
        n,
        transform.voxel
    );

    let band = VoxelizeOptions::default();
    let exact = VoxelizeOptions {
        far: FarFill::Exact,
        ..band
    };
    let (t_band, (phi_band, rep)) = time(3, || {
        voxelize_with_report(&mesh, dims, transform, &band).expect("voxelize")
    });
    println!(
        "ours, band only (FarFill::Clamp): {:.3} s  [hierarchy {:.3}, band {:.3}, sign {:.3}, fill {:.3}]",
        t_band.as_secs_f64(),
        rep.seconds_hierarchy,
        rep.seconds_band,
        rep.seconds_sign,
        rep.seconds_far
    );
    println!(
        "  closed surface: {}; band nodes {} ({:.1}%), winding numbers evaluated {} ({:.2}% of nodes: seeds {}, pockets {}, fronts {} in {} rounds), inside {}",
        rep.closed,
        rep.band_nodes,
        100.0 * rep.band_nodes as f64 / n as f64,
        rep.winding_evaluations(),
        100.0 * rep.winding_evaluations() as f64 / n as f64,
        rep.seed_evaluations,
        rep.pocket_evaluations,
        rep.front_evaluations,
        rep.front_rounds,
        rep.inside_nodes
    );
    let (t_all, (phi_all, rep)) = time(3, || {
        voxelize_with_report(&mesh, dims, transform, &exact).expect("voxelize")
    });
    println!(
        "ours, all nodes (FarFill::Exact): {:.3} s  [far distances {:.3} s]",
        t_all.as_secs_f64(),
        rep.seconds_far
    );

    let Some(reference) = reference else { return };
    let world = |idx: usize| {
        let [i, j, k] = phi_all.coords(idx);
        phi_all.world(i, j, k)
    };
    let points: Vec<Point3<f64>> = (0..n).map(world).collect();
    let Some((igl, t_igl)) = libigl_signed_distance(reference, path, &points) else {
        return;
    };
    // Far nodes hold the clamp value band·h rounded to f32, which may fall just below band·h:
    // the same relative margin as `agreement` keeps them out.
    let bw = band.band * transform.voxel * (1.0 - 1e-6);
    let band_points: Vec<Point3<f64>> = (0..n)
        .filter(|&i| (phi_band.data()[i].abs() as f64) < bw)
        .map(world)
        .collect();
    let t_igl_band = libigl_signed_distance(reference, path, &band_points).map(|(_, t)| t);
    println!("libigl signed_distance (fast winding number), all {n} nodes: {t_igl:.3} s");
    println!(
        "ratio libigl(all nodes) / ours(band only) = {:.2}×",
        t_igl / t_band.as_secs_f64()
    );
    println!(
        "ratio libigl(all nodes) / ours(all nodes) = {:.2}×",
        t_igl / t_all.as_secs_f64()
    );
    if let Some(t) = t_igl_band {
        println!(
            "libigl on the {} band nodes only: {t:.3} s; ratio libigl(band nodes) / ours(band only) = {:.2}×",
            band_points.len(),
            t / t_band.as_secs_f64()
        );
    }
    agreement("all nodes, FarFill::Exact", &phi_all, &igl, None, &mesh);
    agreement(
        "band nodes, FarFill::Clamp",
        &phi_band,
        &igl,
        Some(band.band),
        &mesh,
    );
}

/// Largest |φ − libigl| and sign disagreements (over the band only when `band` is given); for
/// the disagreements, the largest ||w| − ½| of the exact winding number (brute force; |w|, since
/// an inward-facing mesh has w = −1 inside): where it is below libigl's own approximation error
/// (about 1e-2) the sign is a toss-up for libigl.
fn agreement(what: &str, phi: &Grid3, igl: &[f64], band: Option<f64>, mesh: &TriMesh) {
    let h = phi.voxel();
    let (mut worst, mut signs, mut count) = (0.0f64, 0usize, 0usize);
    let mut margin = 0.0f64;
    for (n, (&p, &r)) in phi.data().iter().zip(igl).enumerate() {
        if band.is_some_and(|b| p.abs() as f64 >= b * h * (1.0 - 1e-6)) {
            continue;
        }
        count += 1;
        worst = worst.max((p as f64 - r).abs());
        if (p < 0.0) != (r < 0.0) && p != 0.0 && r != 0.0 {
            signs += 1;
            let [i, j, k] = phi.coords(n);
            let w = winding_number_exact(mesh, &phi.world(i, j, k));
            margin = margin.max((w.abs() - 0.5).abs());
        }
    }
    println!(
        "agreement with libigl, {what}: {count} nodes, max |φ − libigl| = {:.2e} h, sign disagreements {signs}{}",
        worst / h,
        if signs > 0 {
            format!(" (all where the exact |winding number| is within {margin:.1e} of ½)")
        } else {
            String::new()
        }
    );
}
