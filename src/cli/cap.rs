//! `vesselmsr cap MESH -o OUT`: close every boundary loop and write a watertight, outward mesh
//! (the work is the library's `mesh::cap::cap_mesh`, which the Python package's `cap` calls too).

use super::outputs::Outputs;
use super::{print_json, progress, Context};
use crate::io::{read_mesh, write_mesh, MeshFormat};
use crate::mesh::cap::{cap_mesh, CapOptions, CappedMesh};
use anyhow::Context as _;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct CapArgs {
    /// Input mesh (.stl, .obj, .ply, .vtp or .vtk).
    pub mesh: PathBuf,
    /// Output mesh (.stl, .obj, .ply, .vtp or .vtk); written only if capping succeeds.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Target edge length of cap triangles, in the mesh's own units (default: the mean length
    /// of each loop's own edges).
    #[arg(long, value_name = "LENGTH")]
    pub target_edge: Option<f64>,
    /// Orient the result outward: fix inconsistent triangles and flip inward-facing input
    /// (the default).
    #[arg(long, overrides_with = "no_orient")]
    pub orient: bool,
    /// Keep the input's triangle orientation as it is.
    #[arg(long)]
    pub no_orient: bool,
}

pub fn run(ctx: &Context, args: &CapArgs) -> anyhow::Result<()> {
    if let Some(l) = args.target_edge {
        anyhow::ensure!(
            l.is_finite() && l > 0.0,
            "--target-edge must be a positive length, got {l}"
        );
    }
    // Refuse an unwritable output format or folder before any work is done.
    MeshFormat::from_path(&args.output)?;
    let mut outputs = Outputs::new(&[&args.output], &[])?;
    let orient = !args.no_orient;
    let bar = progress::spinner(ctx.quiet, "capping boundary loops");
    let mesh = read_mesh(&args.mesh)?;
    let opts = CapOptions {
        target_edge_length: args.target_edge,
        orient_outward: orient,
        ..Default::default()
    };
    let capped = cap_mesh(&mesh, &opts, &mut |merged| {
        ctx.notice(&format!(
            "{}: {merged} vertices at the same position as another were merged",
            args.mesh.display()
        ))
    })
    .with_context(|| args.mesh.display().to_string())?;
    outputs.write(&args.output, |p| write_mesh(p, &capped.mesh))?;
    outputs.commit()?;
    bar.finish_and_clear();
    for m in capped.notices() {
        ctx.notice(&m);
    }
    if ctx.json {
        return print_json(&capped);
    }
    let CappedMesh {
        input,
        cap: report,
        output,
        ..
    } = &capped;
    println!(
        "{}: {} boundary loop(s), orientation {}",
        args.mesh.display(),
        input.boundary_loops,
        input.orientation
    );
    println!(
        "capped {} loop(s): +{} vertices, +{} triangles (largest cap aspect ratio {:.2}){}",
        report.loops_capped,
        report.vertices_added,
        report.faces_added,
        report.max_cap_aspect_ratio,
        if report.flipped {
            "; flipped to face outward"
        } else {
            ""
        }
    );
    println!("{}", args.output.display());
    println!("{output}");
    Ok(())
}
