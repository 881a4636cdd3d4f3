//! `vesselmsr stenosis MESH [--centerline CL.json] [--min-degree P] [--json]`: narrowings found
//! automatically along every branch of the centreline, against the healthy lumen on either side
//! of each (see `centerline::stenosis`).

use super::centerline::{centerline_for, CenterlineSource};
use super::{print_json, progress, Context};
use crate::centerline::profile::measure_profiles;
use crate::centerline::stenosis::{find_stenoses, BranchNarrowing, Lesion, StenosisFindOptions};

#[derive(Debug, clap::Args)]
pub struct StenosisArgs {
    #[command(flatten)]
    pub source: CenterlineSource,
    /// Smallest diameter stenosis reported as a lesion, percent.
    #[arg(long, value_name = "P", default_value_t = StenosisFindOptions::default().min_degree_pct)]
    pub min_degree: f64,
}

/// What `stenosis --json` prints.
#[derive(serde::Serialize)]
pub(super) struct Stenoses {
    mesh: std::path::PathBuf,
    voxel: f64,
    min_degree_pct: f64,
    pub(super) lesions: Vec<Lesion>,
    branches: Vec<BranchNarrowing>,
}

/// The narrowings of the command's mesh (also for `batch`).
pub(super) fn find_in_file(ctx: &Context, args: &StenosisArgs) -> anyhow::Result<Stenoses> {
    anyhow::ensure!(
        args.min_degree.is_finite() && (0.0..100.0).contains(&args.min_degree),
        "--min-degree must be a percentage from 0 to below 100, got {}",
        args.min_degree
    );
    let bar = progress::spinner(ctx.quiet, "searching for narrowings");
    let (mesh, cl) = centerline_for(ctx, &args.source)?;
    let profiles = measure_profiles(&mesh, &cl);
    let opts = StenosisFindOptions {
        min_degree_pct: args.min_degree,
    };
    let (lesions, branches) = find_stenoses(&cl, &profiles, &opts);
    bar.finish_and_clear();
    Ok(Stenoses {
        mesh: args.source.mesh.clone(),
        voxel: cl.voxel,
        min_degree_pct: args.min_degree,
        lesions,
        branches,
    })
}

pub fn run(ctx: &Context, args: &StenosisArgs) -> anyhow::Result<()> {
    let found = find_in_file(ctx, args)?;
    if ctx.json {
        return print_json(&found);
    }
    let (lesions, branches) = (&found.lesions, &found.branches);
    println!("{}", args.source.mesh.display());
    if lesions.is_empty() {
        println!(
            "no narrowing of {}% or more (largest: {:.1}%)",
            args.min_degree,
            branches
                .iter()
                .map(|b| b.max_narrowing_pct)
                .fold(0.0, f64::max)
        );
    }
    for l in lesions {
        println!(
            "branch {} at ({:.4}, {:.4}, {:.4}), s = {:.4}: diameter {:.4} against {:.4} healthy: {:.1}% diameter, {:.1}% area stenosis, {:.1}% NASCET (normal lumen {:.4}), length {:.4}",
            l.branch,
            l.position[0],
            l.position[1],
            l.position[2],
            l.s,
            l.min_diameter,
            l.reference_diameter,
            l.diameter_stenosis_pct,
            l.area_stenosis_pct,
            l.nascet_stenosis_pct,
            l.normal_diameter,
            l.length
        );
    }
    Ok(())
}
