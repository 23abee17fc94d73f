//! Command-line definitions and dispatch. No algorithm lives here.

mod edit;
mod export;
mod field;
mod flatten;
mod inspect;
mod mesh_args;
mod optimize;
mod panel;
mod progress;
mod render;
mod run;
mod schema;
mod trace;

use clap::{Parser, Subcommand};

pub use mesh_args::MeshArgs;

/// grainline: design how brushed metal shines, get the toolpaths that brush it.
#[derive(Debug, Parser)]
#[command(name = "grainline", version, about, long_about = None)]
pub struct Cli {
    /// No progress bars or status lines.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Worker threads (results are identical whatever the count); at most 4 per available core.
    #[arg(long, global = true, value_name = "N")]
    pub threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Counts, topology, UV charts and problems of a mesh.
    Inspect(inspect::InspectArgs),
    /// Geometry, an initial grain field and its highlight field (Eq. 7), written as FIELD.json.
    Field(field::FieldArgs),
    /// Highlight edits and the solve (paper §4–5): FIELD.json with the field before and after.
    Optimize(optimize::OptimizeArgs),
    /// The whole scene: edits, solve, strokes, SVG and G-code, preview — only what it asks for.
    Run(run::RunArgs),
    /// The scene's strokes alone: SVG, G-code and strokes JSON (optionally from a FIELD.json).
    Trace(trace::TraceArgs),
    /// The scene's preview alone: PNG and optional linear PFM (strokes traced only if an effect
    /// needs them).
    Render(render::RenderArgs),
    /// The part and its grain as glTF 2.0 binary with KHR_materials_anisotropy (docs/gltf.md).
    Export(export::ExportArgs),
    /// The interactive editor: a local page (http://127.0.0.1:PORT/, the first line on stdout)
    /// that sculpts the highlights with the mouse and saves the edits into the scene file.
    Edit(edit::EditArgs),
    /// The JSON Schema of the scene file (docs/scene.md), for editors' completion.
    Schema(schema::SchemaArgs),
    /// A flat panel mesh (OBJ, mm, UV = XY) from a closed SVG outline with holes.
    Panel(panel::PanelArgs),
    /// A UV layout (charts, seams, LSCM / ARAP) for a part without one, written as OBJ with vt.
    Flatten(flatten::FlattenArgs),
}

/// Runs the parsed command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Inspect(a) => inspect::run(a, cli.quiet),
        Command::Field(a) => field::run(a, cli.quiet),
        Command::Schema(a) => schema::run(a),
        Command::Trace(a) => trace::run(a, cli.quiet),
        Command::Render(a) => render::run(a, cli.quiet),
        Command::Export(a) => export::run(a, cli.quiet),
        Command::Edit(a) => edit::run(a, cli.quiet),
        Command::Run(a) => run::run(a, cli.quiet),
        Command::Optimize(a) => optimize::run(a, cli.quiet),
        Command::Panel(a) => panel::run(a, cli.quiet),
        Command::Flatten(a) => flatten::run(a, cli.quiet),
    }
}

/// A path given on the command line, made absolute against the working directory (scene paths
/// are otherwise resolved against the scene file).
fn absolute(p: &std::path::Path) -> anyhow::Result<String> {
    let p = if p.is_absolute() { p.to_path_buf() } else { std::env::current_dir()?.join(p) };
    Ok(p.display().to_string())
}
