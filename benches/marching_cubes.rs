//! Marching cubes benchmark: `extract_surface` against libigl's `igl.marching_cubes` (through
//! the Python oracle, which times the libigl call alone) on the same 256³ grid values in the
//! same run, printed side by side with the ratio (reference seconds / ours).
//!
//! Fields: a torus (R = 0.6, r = 0.25 in [−1, 1]³) and a union of twelve spheres, both as
//! signed distances (φ < 0 inside). Ours is timed with sliver collapse on (the default) and
//! off; libigl's mesh is not closed where its table is inconsistent, ours always is.
//!
//! Run: `cargo bench --bench marching_cubes` (the reference side needs reference/.venv, which
//! `bash tests/run_all.sh` creates, or $VESSELMSR_PYTHON).

mod common;

use common::{seconds, time_median, Reference};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::ffi::{OsStr, OsString};
use std::time::Duration;
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::levelset::marching_cubes::{extract_surface, ExtractOptions};
use vesselmsr::mesh::info::mesh_info;

const N: usize = 256;

/// Median wall time of `f` over repeated runs (at least 5, about two seconds in all).
fn time<T>(f: impl FnMut() -> T) -> Duration {
    time_median(5, 100, Duration::from_secs(2), f).0
}

/// φ = f(world position) on an N³ grid over [−1, 1]³, filled in parallel.
fn grid(f: impl Fn(Point3<f64>) -> f64 + Sync) -> Grid3 {
    let h = 2.0 / (N - 1) as f64;
    let t = GridTransform::new(Point3::new(-1.0, -1.0, -1.0), h);
    let mut g = Grid3::new([N; 3], t, 0.0).expect("grid");
    g.data_mut()
        .par_chunks_mut(N * N)
        .enumerate()
        .for_each(|(k, layer)| {
            for j in 0..N {
                for i in 0..N {
                    let p = Point3::new(i as f64, j as f64, k as f64) * h - Vector3::repeat(1.0);
                    layer[i + N * j] = f(p) as f32;
                }
            }
        });
    g
}

/// libigl's marching cubes on the grid's values: (best of three "seconds", faces).
fn libigl_marching_cubes(reference: &Reference, g: &Grid3) -> Option<(f64, u64)> {
    let dir = tempfile::tempdir().ok()?;
    let (grid, out) = (dir.path().join("phi.f64"), dir.path().join("mc.ply"));
    let bytes: Vec<u8> = g
        .data()
        .iter()
        .flat_map(|&v| (v as f64).to_le_bytes())
        .collect();
    std::fs::write(&grid, bytes).ok()?;
    let [nx, ny, nz] = g.dims();
    let o = g.transform().origin;
    let numbers: Vec<OsString> = [nx, ny, nz]
        .iter()
        .map(|d| d.to_string())
        // plain decimals: argparse takes "-1e0" for an option, "-1" for a number
        .chain(o.iter().map(|x| format!("{x}")))
        .chain([format!("{}", g.voxel())])
        .map(OsString::from)
        .collect();
    let mut args: Vec<&OsStr> = vec!["marching_cubes".as_ref(), grid.as_os_str()];
    args.extend(numbers.iter().map(OsString::as_os_str));
    args.push(out.as_os_str());
    let best = reference.best_of(3, &args)?;
    Some((seconds(&best)?, best["faces"].as_u64()?))
}

fn main() {
    let reference = Reference::find_or_notice("libigl timings");
    println!(
        "marching cubes on {N}³ grids ({} rayon threads); ratio = libigl seconds / ours",
        rayon::current_num_threads()
    );
    let torus = grid(|p| {
        let ring = (p.x * p.x + p.y * p.y).sqrt() - 0.6;
        (ring * ring + p.z * p.z).sqrt() - 0.25
    });
    let centres: Vec<(Point3<f64>, f64)> = (0..12)
        .map(|i| {
            let a = i as f64 * 2.399963; // golden angle
            let z = -0.75 + 1.5 * (i as f64 + 0.5) / 12.0;
            let r = 0.55 * (1.0 - z * z).sqrt().max(0.3);
            (
                Point3::new(r * a.cos(), r * a.sin(), z),
                0.18 + 0.02 * (i % 4) as f64,
            )
        })
        .collect();
    let spheres = grid(|p| {
        centres
            .iter()
            .map(|(c, r)| (p - c).norm() - r)
            .fold(f64::INFINITY, f64::min)
    });
    for (name, g) in [("torus", &torus), ("12 spheres", &spheres)] {
        let igl = reference.as_ref().and_then(|r| libigl_marching_cubes(r, g));
        for (label, collapse_below) in [("default (collapse 0.1)", 0.1), ("collapse off", 0.0)] {
            let opts = ExtractOptions { collapse_below };
            let mesh = extract_surface(g, &opts).expect("extract");
            let t = time(|| extract_surface(g, &opts).expect("extract")).as_secs_f64();
            let info = mesh_info(&mesh);
            let line = format!(
                "{name:<11} {label:<23} ours {:>8.2} ms ({} faces, watertight {})",
                t * 1e3,
                mesh.num_faces(),
                info.watertight
            );
            match igl {
                Some((s, faces)) => println!(
                    "{line}   libigl {:>8.2} ms ({faces} faces)   ratio {:>5.2}×",
                    s * 1e3,
                    s / t
                ),
                None => println!("{line}"),
            }
        }
    }
}
