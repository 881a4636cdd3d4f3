//! `vesselmsr phantom KIND -o DAMAGED --truth TRUTH --regions-out D.json`: a synthetic damaged
//! vessel, its intact truth and the regions D holding the damage (see
//! [`crate::inpaint::phantom`]; test data for the inpainting of paper Section 4). All three files
//! are written, or none.

use super::outputs::Outputs;
use super::{print_json, progress, Context};
use crate::inpaint::phantom::{make_phantom, PhantomKind, PhantomOptions};
use crate::inpaint::region::{write_regions, BallEntry};
use crate::io::{write_mesh, MeshFormat};
use crate::mesh::info::mesh_info;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct PhantomArgs {
    /// Phantom kind: tube, curved, bifurcation, stenosis or occlusion.
    pub kind: String,
    /// Damaged vessel mesh (.stl, .obj, .ply, .vtp or .vtk).
    #[arg(short, long, value_name = "DAMAGED")]
    pub output: PathBuf,
    /// Intact (ground truth) vessel mesh (.stl, .obj, .ply, .vtp or .vtk).
    #[arg(long, value_name = "TRUTH")]
    pub truth: PathBuf,
    /// Regions file (JSON balls) covering the damage.
    #[arg(long, value_name = "D.json")]
    pub regions_out: PathBuf,
    /// Seed of the small random moves and tilts of the damage.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Vessel radius R, world units (default 3, i.e. 3 mm in mm units).
    #[arg(long, value_name = "R")]
    pub radius: Option<f64>,
    /// Voxel size h of the grid the meshes are extracted on, world units (default R/8).
    #[arg(long, value_name = "H")]
    pub voxel: Option<f64>,
}

#[derive(serde::Serialize)]
struct PhantomOutput<'a> {
    kind: &'a str,
    seed: u64,
    radius: f64,
    voxel: f64,
    description: &'a str,
    damaged_volume: f64,
    truth_volume: f64,
    regions: Vec<BallEntry>,
    damaged: &'a Path,
    truth: &'a Path,
    regions_file: &'a Path,
}

pub fn run(ctx: &Context, args: &PhantomArgs) -> anyhow::Result<()> {
    let kind: PhantomKind = args.kind.parse()?;
    let mut opts = PhantomOptions {
        seed: args.seed,
        ..Default::default()
    };
    if let Some(r) = args.radius {
        // Far beyond this the phantom's coordinates, areas and volumes overflow.
        anyhow::ensure!(
            (1e-30..=1e30).contains(&r),
            "--radius must be a length from 1e-30 to 1e30, got {r}"
        );
        opts.radius = r;
    }
    if let Some(h) = args.voxel {
        anyhow::ensure!(
            h.is_finite() && h > 0.0,
            "--voxel must be a positive length, got {h}"
        );
        opts.voxels_per_radius = opts.radius / h;
        anyhow::ensure!(
            (2.0..=64.0).contains(&opts.voxels_per_radius),
            "--voxel {h} must lie between R/64 and R/2 (R = {})",
            opts.radius
        );
    }
    // Refuse unwritable formats, folders and clashing names before any work is done.
    MeshFormat::from_path(&args.output)?;
    MeshFormat::from_path(&args.truth)?;
    let mut outputs = Outputs::new(&[&args.output, &args.truth, &args.regions_out], &[])?;
    let bar = progress::spinner(ctx.quiet, "building the phantom");
    let phantom = make_phantom(kind, &opts)?;
    bar.finish_and_clear();
    outputs.write(&args.output, |p| write_mesh(p, &phantom.damaged))?;
    outputs.write(&args.truth, |p| write_mesh(p, &phantom.truth))?;
    outputs.write(&args.regions_out, |p| write_regions(p, &phantom.regions))?;
    outputs.commit()?;
    let damaged = mesh_info(&phantom.damaged);
    let truth = mesh_info(&phantom.truth);
    let damaged_volume = damaged.volume.unwrap_or(damaged.signed_volume);
    let truth_volume = truth.volume.unwrap_or(truth.signed_volume);
    if ctx.json {
        return print_json(&PhantomOutput {
            kind: kind.as_str(),
            seed: opts.seed,
            radius: phantom.radius,
            voxel: phantom.voxel,
            description: &phantom.description,
            damaged_volume,
            truth_volume,
            regions: phantom.regions.iter().map(BallEntry::from).collect(),
            damaged: &args.output,
            truth: &args.truth,
            regions_file: &args.regions_out,
        });
    }
    println!(
        "{}: damaged {kind} ({}), {} vertices, {} triangles, volume {:.6}",
        args.output.display(),
        phantom.description,
        damaged.vertices,
        damaged.faces,
        damaged_volume
    );
    println!(
        "{}: truth, {} vertices, {} triangles, volume {:.6} (voxel {})",
        args.truth.display(),
        truth.vertices,
        truth.faces,
        truth_volume,
        phantom.voxel
    );
    let balls: Vec<String> = phantom
        .regions
        .iter()
        .map(|b| {
            format!(
                "centre ({:.4}, {:.4}, {:.4}) radius {:.4}",
                b.center.x, b.center.y, b.center.z, b.radius
            )
        })
        .collect();
    println!(
        "{}: {} region(s): {}",
        args.regions_out.display(),
        phantom.regions.len(),
        balls.join("; ")
    );
    Ok(())
}
