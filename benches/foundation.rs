//! Foundation benchmark: `info` + `cap` + closest-point and winding-number queries on the shipped
//! cortex hemisphere (20,480 triangles) and the open-ended aorta, side by side with the Python
//! reference (libigl closest points and fast winding number, pymeshlab measures + manifold3d
//! check, pymeshlab hole closing against `cap`) on the same points in the same run, reported as throughput and as ratios.
//!
//! Run: `cargo bench --bench foundation` (the reference side needs reference/.venv, which
//! `bash tests/run_all.sh` creates, or $VESSELMSR_PYTHON).

mod common;

use common::{seconds, time_median, write_points, Reference};
use nalgebra::{Point3, Vector3};
use std::path::Path;
use std::time::Duration;
use vesselmsr::bvh::{MeshBvh, WindingNumber, WindingOptions};
use vesselmsr::io::read_mesh;
use vesselmsr::mesh::cap::{cap_holes, CapOptions};
use vesselmsr::mesh::info::mesh_info;
use vesselmsr::mesh::measures::mean_edge_length;
use vesselmsr::TriMesh;

/// Median wall time of `f` over repeated runs (at least 3, about half a second in all).
fn time<T>(f: impl FnMut() -> T) -> Duration {
    time_median(3, 200, Duration::from_millis(500), f).0
}

/// Query points: every other one near the surface (within two mean edges), the rest uniform in
/// the bounding box grown by 10%. A fixed linear congruential sequence keeps runs comparable.
fn query_points(mesh: &TriMesh, n: usize) -> Vec<Point3<f64>> {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut lo, mut hi) = (mesh.vertices[0], mesh.vertices[0]);
    for v in &mesh.vertices {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    let size = hi - lo;
    let edge = mean_edge_length(mesh);
    (0..n)
        .map(|i| {
            let r = Vector3::new(next(), next(), next());
            if i % 2 == 0 {
                let v = mesh.vertices
                    [(next() * mesh.num_vertices() as f64) as usize % mesh.num_vertices()];
                v + (r * 2.0 - Vector3::repeat(1.0)) * 2.0 * edge
            } else {
                lo - 0.05 * size + (1.1 * size).component_mul(&r)
            }
        })
        .collect()
}

/// The oracle's best of three (as our side takes a median of several runs) on a per-point query.
fn query_seconds(
    reference: &Reference,
    command: &str,
    mesh: &Path,
    points: &[Point3<f64>],
) -> Option<f64> {
    let dir = tempfile::tempdir().ok()?;
    let input = write_points(dir.path(), points)?;
    let output = dir.path().join("o.f64");
    let args = [
        command.as_ref(),
        mesh.as_os_str(),
        input.as_os_str(),
        output.as_os_str(),
    ];
    seconds(&reference.best_of(3, &args)?)
}

fn row(what: &str, count: usize, ours: Duration, reference: Option<f64>) {
    let s = ours.as_secs_f64();
    let rate = count as f64 / s;
    match reference {
        Some(r) => println!(
            "{what:<62} {:>10.3} ms {:>12.0}/s   reference {:>10.3} ms   ratio (reference/ours) {:>6.2}×",
            s * 1e3,
            rate,
            r * 1e3,
            r / s
        ),
        None => println!("{what:<62} {:>10.3} ms {:>12.0}/s", s * 1e3, rate),
    }
}

fn main() {
    let root = common::root();
    let cortex_path = root.join("data/cortex_rh_pial_fsaverage5.stl");
    let aorta_path = root.join("data/aorta_abdominal_open_ends.stl");
    let reference = Reference::find_or_notice("reference timings");
    println!(
        "vesselmsr foundation benchmark ({} rayon threads)",
        rayon::current_num_threads()
    );

    let cortex = read_mesh(&cortex_path).expect("data/ cortex reads");
    let aorta = read_mesh(&aorta_path).expect("data/ aorta reads");
    let f = cortex.num_faces();
    row(
        "read cortex STL (triangles/s)",
        f,
        time(|| read_mesh(&cortex_path).unwrap()),
        None,
    );
    let check = reference
        .as_ref()
        .and_then(|r| r.seconds(&["info".as_ref(), cortex_path.as_os_str()]));
    row(
        "info cortex (triangles/s)",
        f,
        time(|| mesh_info(&cortex)),
        check,
    );
    let fa = aorta.num_faces();
    // The reference closes the same holes with pymeshlab's hole filling (no refinement or quality
    // pass: a baseline, not the same output).
    let closed = tempfile::tempdir().expect("temporary folder");
    let close_holes = reference.as_ref().and_then(|r| {
        let out = closed.path().join("closed.stl");
        r.seconds(&[
            "close_holes".as_ref(),
            aorta_path.as_os_str(),
            out.as_os_str(),
        ])
    });
    row(
        "cap aorta open ends (triangles/s)",
        fa,
        time(|| cap_holes(&aorta, &CapOptions::default()).unwrap()),
        close_holes,
    );
    row(
        "BVH build cortex (triangles/s)",
        f,
        time(|| MeshBvh::new(&cortex)),
        None,
    );
    row(
        "winding hierarchy build cortex (triangles/s)",
        f,
        time(|| WindingNumber::new(&cortex, WindingOptions::default())),
        None,
    );

    let points = query_points(&cortex, 100_000);
    let bvh = MeshBvh::new(&cortex);
    let r = reference
        .as_ref()
        .and_then(|r| query_seconds(r, "closest", &cortex_path, &points));
    row(
        "closest point, 100k points (queries/s)",
        points.len(),
        time(|| bvh.closest_points(&points)),
        r,
    );
    let wn = WindingNumber::new(&cortex, WindingOptions::default());
    let r = reference
        .as_ref()
        .and_then(|r| query_seconds(r, "winding", &cortex_path, &points));
    row(
        "winding number, default (±1e-4), 100k points (queries/s)",
        points.len(),
        time(|| wn.winding_numbers(&points)),
        r,
    );
    // libigl's default expansion is second order at β = 2 (error ~1e-2): the like-for-like race.
    let coarse = WindingNumber::new(
        &cortex,
        WindingOptions {
            beta: 2.0,
            order: 2,
        },
    );
    row(
        "winding number, order 2 β 2 (±1e-2), 100k points (queries/s)",
        points.len(),
        time(|| coarse.winding_numbers(&points)),
        r,
    );
}
