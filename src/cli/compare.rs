//! `vesselmsr compare A B`: surface distances and volumes of two meshes.

use super::{print_json, progress, Context};
use crate::io::read_mesh;
use crate::mesh::distance::{surface_distance, SurfaceDistance, SurfaceDistanceOptions};
use crate::mesh::info::{mesh_info, MeshInfo};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// First mesh (the reference).
    pub a: PathBuf,
    /// Second mesh.
    pub b: PathBuf,
    /// Area-weighted sample points per surface.
    #[arg(long, default_value_t = SurfaceDistanceOptions::default().samples)]
    pub samples: usize,
}

#[derive(serde::Serialize)]
struct CompareOutput {
    #[serde(flatten)]
    distance: SurfaceDistance,
    /// Enclosed volume of A (null when A is not watertight).
    volume_a: Option<f64>,
    volume_b: Option<f64>,
    /// (volume_b − volume_a) / volume_a (null unless both are watertight).
    volume_rel_diff: Option<f64>,
}

pub fn run(ctx: &Context, args: &CompareArgs) -> anyhow::Result<()> {
    anyhow::ensure!(args.samples >= 1, "--samples must be at least 1");
    super::budget::check_samples("--samples", args.samples, ctx.max_memory)?;
    let bar = progress::spinner(ctx.quiet, "comparing surfaces");
    let a = read_mesh(&args.a)?;
    let b = read_mesh(&args.b)?;
    let (info_a, info_b) = (mesh_info(&a), mesh_info(&b));
    if let Some(note) = units_notice(&info_a, &info_b) {
        ctx.notice(&note);
    }
    let distance = surface_distance(
        &a,
        &b,
        &SurfaceDistanceOptions {
            samples: args.samples,
        },
    );
    bar.finish_and_clear();
    let volume_rel_diff = match (info_a.volume, info_b.volume) {
        (Some(va), Some(vb)) if va > 0.0 => Some((vb - va) / va),
        _ => None,
    };
    let out = CompareOutput {
        distance,
        volume_a: info_a.volume,
        volume_b: info_b.volume,
        volume_rel_diff,
    };
    if ctx.json {
        return print_json(&out);
    }
    let opt = |v: Option<f64>| v.map_or("n/a (not watertight)".to_string(), |v| format!("{v:.6}"));
    println!("A: {}\nB: {}", args.a.display(), args.b.display());
    println!(
        "hausdorff        {:.6}  (A→B {:.6}, B→A {:.6})",
        distance.hausdorff, distance.max_a_to_b, distance.max_b_to_a
    );
    println!("mean distance    {:.6}", distance.mean_distance);
    println!("rms distance     {:.6}", distance.rms_distance);
    println!("volume A         {}", opt(out.volume_a));
    println!("volume B         {}", opt(out.volume_b));
    println!(
        "volume rel diff  {}",
        out.volume_rel_diff
            .map_or("n/a".to_string(), |r| format!("{:+.4}%", 100.0 * r))
    );
    println!(
        "(distances in the meshes' units, {} samples per surface)",
        args.samples
    );
    Ok(())
}

/// A warning when the two meshes' sizes differ by a factor of 100 or more, which usually means
/// different units (mm against m): coordinates are never rescaled.
fn units_notice(a: &MeshInfo, b: &MeshInfo) -> Option<String> {
    let diagonal = |i: &MeshInfo| {
        (0..3)
            .map(|k| (i.bbox_max[k] - i.bbox_min[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let ratio = diagonal(a) / diagonal(b);
    (ratio.is_finite() && ratio > 0.0 && !(0.01..=100.0).contains(&ratio)).then(|| {
        format!(
            "the meshes' sizes differ by a factor of {:.0}: are they in the same units (mm, cm, m)? \
             Coordinates are compared as they are.",
            ratio.max(1.0 / ratio)
        )
    })
}
