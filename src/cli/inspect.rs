//! `grainline inspect`.

use clap::Args;

use super::MeshArgs;

/// Arguments of `grainline inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    #[command(flatten)]
    mesh: MeshArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs `grainline inspect`.
pub fn run(args: InspectArgs, _quiet: bool) -> anyhow::Result<()> {
    let loaded = grainline::mesh::load::load_obj(&args.mesh.mesh, &args.mesh.load_options())?;
    let _ = args.json;
    println!("{} vertices, {} faces", loaded.mesh.num_vertices(), loaded.mesh.num_faces());
    Ok(())
}
