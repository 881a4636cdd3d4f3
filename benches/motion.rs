//! Level-set motion benchmarks (issue 4), side by side with the Python reference in one run,
//! ratio = reference seconds / our seconds:
//!
//! 1. Heat diffusion: our `diffuse` (Auto, and both kernels) against
//!    `scipy.ndimage.gaussian_filter` (`reference/oracle.py gaussian`, mode "reflect", truncate 4)
//!    on the same 256³ field — the signed distance of a sphere of radius 80h — for σ = 1h, 2h,
//!    4h (the MBO steps Δt = 0.5h² to 8h²), plus 8h and 16h to show the cost of each kernel as
//!    σ grows. The max |ours − scipy| is printed beside each timing.
//! 2. One full MBO step against the oracle's `mbo_step`: pending (see [`mbo_step`]).
//!
//! Run: `cargo bench --bench motion` (the reference side needs reference/.venv, which
//! `bash tests/run_all.sh` creates, or $VESSELMSR_PYTHON).

mod common;

use common::{seconds, time_median_with_setup, Reference};
use nalgebra::Point3;
use std::ffi::OsString;
use std::path::Path;
use std::time::Duration;
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::motion::diffusion::{diffuse, DiffusionKernel, DiffusionOptions};

const N: usize = 256;
/// Voxel size, world units (not 1, so σ in voxels and in world units differ).
const H: f64 = 0.25;

/// The signed distance to a sphere of radius 80h centred near the middle of a 256³ grid.
fn sphere_field() -> Grid3 {
    use rayon::prelude::*;
    let t = GridTransform::new(Point3::new(-10.0, 3.0, 0.5), H);
    let mut g = Grid3::new([N, N, N], t, 0.0).unwrap();
    let c = t.index_to_world(nalgebra::Vector3::new(127.3, 128.6, 127.8));
    let transform = *g.transform();
    g.data_mut()
        .par_chunks_mut(N)
        .enumerate()
        .for_each(|(r, row)| {
            for (i, v) in row.iter_mut().enumerate() {
                let p = transform.index_to_world(nalgebra::Vector3::new(
                    i as f64,
                    (r % N) as f64,
                    (r / N) as f64,
                ));
                *v = ((p - c).norm() - 80.0 * H) as f32;
            }
        });
    g
}

/// Median wall time of `diffuse` over 3 runs, each on a fresh copy (not timed), and the result.
fn time_diffuse(field: &Grid3, time: f64, opts: &DiffusionOptions) -> (Duration, Grid3) {
    time_median_with_setup(
        3,
        3,
        Duration::ZERO,
        || field.clone(),
        |mut g| {
            diffuse(&mut g, time, opts).expect("diffuse runs");
            g
        },
    )
}

/// scipy's gaussian_filter of the grid in `input` for `time`: best "seconds" of three runs and
/// the filtered grid.
fn scipy_gaussian(reference: &Reference, input: &Path, time: f64) -> Option<(f64, Grid3)> {
    let out = input.with_file_name("gaussian_out.npy");
    let time = OsString::from(time.to_string());
    let args = [
        "gaussian".as_ref(),
        input.as_os_str(),
        &time,
        out.as_os_str(),
    ];
    let best = seconds(&reference.best_of(3, &args)?)?;
    Some((best, vesselmsr::io::read_npy(&out).ok()?))
}

fn max_abs_diff(a: &Grid3, b: &Grid3) -> f64 {
    a.data()
        .iter()
        .zip(b.data())
        .map(|(&x, &y)| (x as f64 - y as f64).abs())
        .fold(0.0, f64::max)
}

fn diffusion(reference: Option<&Reference>, dir: &Path, field: &Grid3) {
    println!("\nheat diffusion of a sphere SDF (r = 80h, h = {H}), {N}³ f32, vs scipy.ndimage.gaussian_filter (reflect, truncate 4)");
    let peak = field.data().iter().fold(0.0f32, |m, &v| m.max(v.abs()));
    println!("(|field| ≤ {peak:.1}; scipy cuts its kernel at 4σ, the recursive filter does not: their max difference is that cut)");
    let input = dir.join("field.npy");
    let reference = reference.filter(|_| vesselmsr::io::write_npy(&input, field).is_ok());
    let kernels = [
        ("auto", DiffusionKernel::Auto),
        (
            "truncated 4σ",
            DiffusionKernel::Truncated { radius_sigmas: 4.0 },
        ),
        ("recursive", DiffusionKernel::Recursive),
    ];
    for sigma_vox in [1.0f64, 2.0, 4.0, 8.0, 16.0] {
        let time = (sigma_vox * H).powi(2) / 2.0;
        println!(
            "σ = {sigma_vox}h (time {time} world units, Δt = {}h²)",
            time / (H * H)
        );
        let scipy = reference.and_then(|r| scipy_gaussian(r, &input, time));
        for (name, kernel) in kernels {
            let (t, g) = time_diffuse(field, time, &DiffusionOptions { kernel });
            let s = t.as_secs_f64();
            match &scipy {
                Some((r, values)) => println!(
                    "  {name:<13} {:>8.1} ms   scipy {:>8.1} ms   ratio {:>5.2}×   max |ours − scipy| {:.1e}",
                    s * 1e3,
                    r * 1e3,
                    r / s,
                    max_abs_diff(&g, values)
                ),
                None => println!("  {name:<13} {:>8.1} ms", s * 1e3),
            }
        }
    }
}

/// One full MBO step (diffuse + threshold + redistance) against `oracle.py mbo_step`.
// TODO(issue 4, flows): time one `Flow::step()` for mcf and vpmcf on `field` with Δt = 2h²
// against `reference.run(["mbo_step", field.npy, dt, out.npy, "--velocity", v])` ("seconds"),
// printing ours / reference / ratio like `diffusion`.
fn mbo_step(_reference: Option<&Reference>, _dir: &Path, _field: &Grid3) {
    println!("\nmbo step: pending");
}

fn main() {
    let reference = Reference::find_or_notice("reference timings");
    println!(
        "vesselmsr motion benchmark, {N}³ grid ({} rayon threads; the machine is shared: timings vary); ratio = reference seconds / ours",
        rayon::current_num_threads()
    );
    let dir = tempfile::tempdir().expect("a temporary folder");
    let field = sphere_field();
    diffusion(reference.as_ref(), dir.path(), &field);
    mbo_step(reference.as_ref(), dir.path(), &field);
}
