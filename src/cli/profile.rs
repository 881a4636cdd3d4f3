//! `vesselmsr profile MESH [--centerline CL.json] -o P.csv [--picture P.png]`: equivalent and
//! inscribed diameters along every branch of the vessel's centreline, as CSV and as a plot.

use super::centerline::{centerline_for, CenterlineSource};
use super::outputs::Outputs;
use super::{print_json, progress, Context};
use crate::centerline::profile::measure_profiles;
use crate::centerline::stenosis::{find_stenoses, StenosisFindOptions};
use crate::io::write_atomic;
use crate::mesh::units::{check_vessel_scale, VesselScaleOptions};
use crate::report::image::write_png;
use crate::report::profile_plot::profile_picture;
use crate::Error;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct ProfileArgs {
    #[command(flatten)]
    pub source: CenterlineSource,
    /// Output CSV: branch, s, x, y, z, inscribed_diameter, equivalent_diameter, area (empty where
    /// no single lumen is cut).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also draw the profiles (PNG): diameters against arc length, one panel per branch.
    #[arg(long, value_name = "P.png")]
    pub picture: Option<PathBuf>,
    /// Length unit for the picture's axes (e.g. mm); lengths are never rescaled.
    #[arg(long)]
    pub units: Option<String>,
}

pub fn run(ctx: &Context, args: &ProfileArgs) -> anyhow::Result<()> {
    let targets: Vec<&Path> = std::iter::once(&args.output)
        .chain(&args.picture)
        .map(|p| &**p)
        .collect();
    let mut outputs = Outputs::new(&targets, &[])?;
    let bar = progress::spinner(ctx.quiet, "measuring the diameter profiles");
    let (mesh, cl) = centerline_for(ctx, &args.source)?;
    let scale = args
        .units
        .as_deref()
        .and_then(|u| check_vessel_scale(&mesh, u, &VesselScaleOptions::default()));
    if let (Some(n), false) = (scale, ctx.quiet) {
        bar.suspend(|| eprintln!("vesselmsr: notice: {}: {n}", args.source.mesh.display()));
    }
    let profiles = measure_profiles(&mesh, &cl);
    let image = match &args.picture {
        Some(_) => {
            let (lesions, narrowing) =
                find_stenoses(&cl, &profiles, &StenosisFindOptions::default());
            Some(profile_picture(
                &profiles,
                &narrowing,
                &lesions,
                args.units.as_deref().unwrap_or(""),
                (640, 360),
            )?)
        }
        None => None,
    };
    bar.finish_and_clear();
    let path = &args.output;
    outputs.write(path, |path| {
        write_atomic(path, |out| {
            let io = |e| Error::io(path, e);
            writeln!(
                out,
                "branch,s,x,y,z,inscribed_diameter,equivalent_diameter,area"
            )
            .map_err(io)?;
            for prof in &profiles {
                for p in &prof.points {
                    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
                    writeln!(
                        out,
                        "{},{},{},{},{},{},{},{}",
                        prof.branch,
                        p.s,
                        p.position[0],
                        p.position[1],
                        p.position[2],
                        p.inscribed_diameter,
                        opt(p.equivalent_diameter),
                        opt(p.area)
                    )
                    .map_err(io)?;
                }
            }
            Ok(())
        })
    })?;
    if let (Some(p), Some(image)) = (&args.picture, &image) {
        outputs.write(p, |p| write_png(p, image))?;
    }
    outputs.commit()?;
    if ctx.json {
        return print_json(&serde_json::json!({
            "mesh": args.source.mesh,
            "branches": profiles.len(),
            "points": profiles.iter().map(|p| p.points.len()).sum::<usize>(),
            "output": path,
            "picture": args.picture,
        }));
    }
    println!(
        "{}: {} branch(es), {} points; wrote {}{}",
        args.source.mesh.display(),
        profiles.len(),
        profiles.iter().map(|p| p.points.len()).sum::<usize>(),
        path.display(),
        args.picture
            .as_ref()
            .map_or(String::new(), |p| format!(" and {}", p.display()))
    );
    Ok(())
}
