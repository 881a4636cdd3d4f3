//! `vesselmsr cap MESH -o OUT`: close every boundary loop and write a watertight, outward mesh.

use super::outputs::Outputs;
use super::{print_json, progress, Context};
use crate::io::{read_mesh, write_mesh, MeshFormat};
use crate::mesh::cap::{cap_holes, CapOptions, CapReport};
use crate::mesh::info::{mesh_info, MeshInfo};
use crate::mesh::orient::orient_consistently;
use crate::mesh::weld::weld_coincident;
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

#[derive(serde::Serialize)]
struct CapOutput<'a> {
    input: &'a MeshInfo,
    cap: &'a CapReport,
    output: &'a MeshInfo,
    inconsistent_faces_flipped: usize,
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
    // A triangle soup (corners not shared) would be "capped" triangle by triangle into
    // back-to-back pairs: weld it into the surface it describes, as an STL reader would.
    let (mut mesh, merged) = weld_coincident(&mesh);
    if merged > 0 {
        ctx.notice(&format!(
            "{}: {merged} vertices at the same position as another were merged",
            args.mesh.display()
        ));
    }
    let input = mesh_info(&mesh);
    let inconsistent_faces_flipped = if orient {
        orient_consistently(&mut mesh)
    } else {
        0
    };
    let opts = CapOptions {
        target_edge_length: args.target_edge,
        orient_outward: orient,
        ..Default::default()
    };
    let (capped, report) = cap_holes(&mesh, &opts)
        .with_context(|| format!("{}: capping failed", args.mesh.display()))?;
    let output = mesh_info(&capped);
    // The promise of `cap` is a watertight mesh: refuse to write anything else. Defects that
    // capping cannot mend (non-manifold edges or vertices of the input) end up here.
    if !output.watertight {
        anyhow::bail!(
            "{}: capping could not make the mesh watertight: {} (input: {})",
            args.mesh.display(),
            output.leaks().join(", "),
            input.leaks().join(", ")
        );
    }
    outputs.write(&args.output, |p| write_mesh(p, &capped))?;
    outputs.commit()?;
    bar.finish_and_clear();
    for m in &report.messages {
        ctx.notice(m);
    }
    if inconsistent_faces_flipped > 0 {
        ctx.notice(&format!(
            "{inconsistent_faces_flipped} triangles were wound against their neighbours and were flipped"
        ));
    }
    if ctx.json {
        return print_json(&CapOutput {
            input: &input,
            cap: &report,
            output: &output,
            inconsistent_faces_flipped,
        });
    }
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
