//! `vesselmsr reconstruct MSR.npz -o OUT [--method vertices|levelset] [--level K]`: a scale S_K
//! (default the input, K = 0) rebuilt from a multiscale representation archive (paper
//! Definition 2.1(4), IMST).
//!
//! `vertices` (exact, the paper's Remark 2.2(4)): the original triangles on the samples
//! X_K = X_N − Σ_{i>K} W_i. `levelset`: from the archive's φ_T, φ is carried back one level at a
//! time along the details down to level K
//! ([`crate::msr::reconstruct::rebuild_from_tangent_planes`]: the semi-Lagrangian step with the
//! samples' frames rotated, from X_{i−1} = X_i − W_i and their normals), and its zero level set
//! extracted by marching cubes; each level's
//! reconstruction S̃_{i−1} (from S̃_i, as the archive keeps φ_T only: the steps' errors add up;
//! `decompose --measure-rebuilds` gives the paper's one-step figure) is compared with the exact S_{i−1} (the vertex reconstruction) by the
//! Hausdorff distance, reported in units of h, and the samples X_{i−1} (on S_{i−1}) by their
//! distance to S̃_{i−1} (the Hausdorff distance also counts the chords of long original edges
//! across a curved S_{i−1}, which are not errors of the reconstruction). A missing, damaged or
//! foreign archive, or a K beyond its levels, is refused before anything is written.

use super::outputs::Outputs;
use super::{print_json, progress, Context};
use crate::bvh::MeshBvh;
use crate::io::{write_mesh, MeshFormat};
use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
use crate::mesh::distance::{surface_distance, SurfaceDistanceOptions};
use crate::mesh::info::{mesh_info, MeshInfo};
use crate::msr::archive::read_msr_within;
use indicatif::ProgressStyle;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// How the surface is rebuilt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// The original triangles on the tracked samples (exact).
    Vertices,
    /// Advect φ_T back level by level along the details, then marching cubes.
    Levelset,
}

#[derive(Debug, clap::Args)]
pub struct ReconstructArgs {
    /// The multiscale representation (.npz written by `decompose`).
    pub archive: PathBuf,
    /// Output mesh (.stl, .obj, .ply, .vtp or .vtk).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// How the surface is rebuilt.
    #[arg(long, value_enum, default_value_t = Method::Vertices)]
    pub method: Method,
    /// The scale to rebuild: 0 the input (default), N the coarsest.
    #[arg(long, value_name = "K", default_value_t = 0)]
    pub level: usize,
}

#[derive(serde::Serialize)]
struct LevelJson {
    level: usize,
    samples: usize,
    /// Mean |w_i|, in units of h.
    mean_abs_detail: f64,
    /// Fraction of |w_i| < 0.1h.
    sparse_fraction: f64,
    /// Hausdorff distance between S̃_{i−1} (level set, rebuilt from level i) and S_{i−1}
    /// (vertices), in units of h; `None` for the vertices method.
    hausdorff_h: Option<f64>,
    /// Largest distance from the samples X_{i−1} (which lie on S_{i−1} within 10⁻³h and cover
    /// it to about h) to S̃_{i−1}, in units of h: the reconstruction's error without the chords
    /// of the original triangles (long edges cut across the curved S_{i−1}); `None` for vertices.
    samples_max_h: Option<f64>,
    /// Mean distance from the samples X_{i−1} to S̃_{i−1}, in units of h.
    samples_mean_h: Option<f64>,
}

#[derive(serde::Serialize)]
struct ReconstructOutput {
    voxel: f64,
    method: &'static str,
    level: usize,
    /// The levels the reconstruction went through, K+1..=N.
    levels: Vec<LevelJson>,
    output: MeshInfo,
    seconds: f64,
}

pub fn run(ctx: &Context, args: &ReconstructArgs) -> anyhow::Result<()> {
    MeshFormat::from_path(&args.output)?;
    let mut outputs = Outputs::new(&[&args.output], &[])?;
    let msr = read_msr_within(&args.archive, ctx.max_memory)?;
    let n = msr.levels();
    let k = args.level;
    anyhow::ensure!(
        k <= n,
        "{}: --level {k} is beyond the archive's {n} levels (0..={n})",
        args.archive.display()
    );
    anyhow::ensure!(
        !msr.faces.is_empty(),
        "{}: the archive holds no triangles",
        args.archive.display()
    );
    let h = msr.phi.voxel();
    let t = Instant::now();
    let mut levels: Vec<LevelJson> = (k + 1..=n)
        .map(|i| {
            let w = &msr.level_normal_details(i);
            let count = w.len().max(1) as f64;
            LevelJson {
                level: i,
                samples: w.len(),
                mean_abs_detail: w.iter().map(|x| x.abs()).sum::<f64>() / count / h,
                sparse_fraction: w.iter().filter(|x| x.abs() < 0.1 * h).count() as f64 / count,
                hausdorff_h: None,
                samples_max_h: None,
                samples_mean_h: None,
            }
        })
        .collect();
    let (surface, method) = match args.method {
        Method::Vertices => (msr.mesh_at(k), "vertices"),
        Method::Levelset => {
            let bar = progress::spinner(ctx.quiet, "advecting back");
            if !bar.is_hidden() {
                bar.set_style(
                    ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {pos}/{len} levels")
                        .unwrap_or_else(|_| ProgressStyle::default_bar()),
                );
                bar.set_length((n - k) as u64);
            }
            let inside = msr.phi.data().iter().any(|&v| v < 0.0);
            let outside = msr.phi.data().iter().any(|&v| v > 0.0);
            anyhow::ensure!(
                inside && outside,
                "{}: φ_T is empty (no node {} its surface): nothing to rebuild the level set from",
                args.archive.display(),
                if inside { "outside" } else { "inside" }
            );
            let mut phi = msr.phi.clone();
            let mut surface = None;
            for i in (k + 1..=n).rev() {
                bar.set_message(format!("level {i} → {}", i - 1));
                let data = msr.level_data(i);
                phi = msr
                    .rebuild_level(&phi, i)
                    .map_err(|e| anyhow::anyhow!("{}: level {i}: {e}", args.archive.display()))?;
                let rebuilt = extract_surface(&phi, &ExtractOptions::default()).map_err(|e| {
                    anyhow::anyhow!("{}: level {}: {e}", args.archive.display(), i - 1)
                })?;
                anyhow::ensure!(
                    !rebuilt.faces.is_empty(),
                    "{}: the level-set reconstruction of level {} is empty",
                    args.archive.display(),
                    i - 1
                );
                let exact = msr.mesh_at(i - 1);
                let d = surface_distance(&rebuilt, &exact, &SurfaceDistanceOptions::default());
                let bvh = MeshBvh::new(&rebuilt);
                let to_rebuilt: Vec<f64> = data
                    .points
                    .par_iter()
                    .map(|p| bvh.closest_point(p).distance)
                    .collect();
                let count = to_rebuilt.len().max(1) as f64;
                let l = &mut levels[i - k - 1];
                l.hausdorff_h = Some(d.hausdorff / h);
                l.samples_max_h = Some(to_rebuilt.iter().copied().fold(0.0, f64::max) / h);
                l.samples_mean_h = Some(to_rebuilt.iter().sum::<f64>() / count / h);
                surface = Some(rebuilt);
                bar.inc(1);
            }
            bar.finish_and_clear();
            let surface = match surface {
                Some(s) => s,
                None => extract_surface(&phi, &ExtractOptions::default())
                    .map_err(|e| anyhow::anyhow!("{}: {e}", args.archive.display()))?,
            };
            (surface, "levelset")
        }
    };
    outputs.write(&args.output, |p| write_mesh(p, &surface))?;
    outputs.commit()?;
    let out = ReconstructOutput {
        voxel: h,
        method,
        level: k,
        levels,
        output: mesh_info(&surface),
        seconds: t.elapsed().as_secs_f64(),
    };
    if ctx.json {
        return print_json(&out);
    }
    println!(
        "{}: S_{k} of {n} levels by {method}, voxel h = {h} (file units)",
        args.output.display()
    );
    println!(
        "level  samples  mean |w|/h  |w|<0.1h  Hausdorff(S̃_{{i-1}}, S_{{i-1}})/h  \
         X_{{i-1}} to S̃_{{i-1}} max/h, mean/h"
    );
    let show = |v: Option<f64>| v.map_or("-".to_string(), |d| format!("{d:.3}"));
    for l in &out.levels {
        println!(
            "{:>5}  {:>7}  {:>10.4}  {:>7.1}%  {:>28}  {:>7}  {:>7}",
            l.level,
            l.samples,
            l.mean_abs_detail,
            100.0 * l.sparse_fraction,
            show(l.hausdorff_h),
            show(l.samples_max_h),
            show(l.samples_mean_h)
        );
    }
    println!("{}", out.output);
    Ok(())
}
