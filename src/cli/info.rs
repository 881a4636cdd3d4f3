//! `vesselmsr info MESH`: validation and measures of one mesh.

use super::{print_json, progress, Context};
use crate::io::read_mesh;
use crate::mesh::info::mesh_info;
use std::path::Path;

pub fn run(ctx: &Context, path: &Path) -> anyhow::Result<()> {
    let bar = progress::spinner(ctx.quiet, "reading and measuring");
    let mesh = read_mesh(path)?;
    let info = mesh_info(&mesh);
    bar.finish_and_clear();
    if ctx.json {
        print_json(&info)
    } else {
        println!("{}", path.display());
        println!("{info}");
        Ok(())
    }
}
