//! `grainline export`: the part and its grain as glTF 2.0 binary (docs/gltf.md), and as
//! 16-bit PNG maps in UV space (docs/formats.md, "Grain maps").

use std::path::PathBuf;

use clap::Args;
use grainline::pipeline::run::{run as run_scene, RunOptions};
use grainline::scene::LoadedScene;

use super::absolute;
use super::progress::Spinner;

/// Arguments of `grainline export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The scene file (docs/scene.md); its `export` section, if any, gives the defaults.
    scene: PathBuf,
    /// Write the glTF binary here (overrides `export.glb`).
    #[arg(long, value_name = "OUT.glb")]
    glb: Option<PathBuf>,
    /// Write the grain as 16-bit PNG maps in UV space into this directory (overrides
    /// `export.maps`): grain-direction.png (RG = the direction across the grain, glTF's
    /// anisotropyTexture convention) and grain-angle.png (the grain's angle in [0, π)).
    #[arg(long, value_name = "DIR")]
    maps: Option<PathBuf>,
    /// The grain from `grainline optimize` or `grainline field` on the same mesh (default:
    /// the scene's field, after its edits and solve).
    #[arg(long, value_name = "FIELD.json")]
    field: Option<PathBuf>,
    /// Export the grain rebuilt from the strokes (the as-brushed field) instead of the designed
    /// one (needs the scene's `toolpaths` section).
    #[arg(long)]
    as_brushed: bool,
    /// Also write the strokes as a second node of lines (needs the scene's `toolpaths`).
    #[arg(long)]
    strokes: bool,
    /// The run report (JSON), with the export's figures under `export`.
    #[arg(long, value_name = "R.json")]
    report: Option<PathBuf>,
}

/// Runs `grainline export`.
pub fn run(args: ExportArgs, quiet: bool) -> anyhow::Result<()> {
    let mut plan = grainline::output::OutputPlan::new();
    for (flag, p) in [("--glb", &args.glb), ("--report", &args.report)] {
        if let Some(p) = p {
            plan.output(flag, p);
        }
    }
    if let Some(d) = &args.maps {
        for f in grainline::pipeline::export::MAP_FILES {
            plan.output("--maps", d.join(f));
        }
    }
    if let Some(f) = &args.field {
        plan.input("--field", f);
    }
    plan.check()?;
    let mut scene = LoadedScene::read(&args.scene)?;
    let e = scene.scene.export.get_or_insert_with(Default::default);
    if let Some(p) = &args.glb {
        e.glb = Some(absolute(p)?);
    }
    if let Some(d) = &args.maps {
        e.maps = Some(absolute(d)?);
    }
    e.as_brushed |= args.as_brushed;
    e.strokes |= args.strokes;
    if e.glb.is_none() && e.maps.is_none() {
        anyhow::bail!(
            "{}: no output: give --glb OUT.glb, --maps DIR, `export.glb` or `export.maps`",
            args.scene.display()
        );
    }
    // Only the glTF file is written: the other outputs are dropped (the strokes are still
    // traced when the export needs them).
    scene.scene.render = None;
    scene.scene.field.output = None;
    if let Some(t) = scene.scene.toolpaths.as_mut() {
        t.svg = None;
        t.gcode = None;
        t.strokes_json = None;
    }
    scene.scene.validate().map_err(|e| scene.wrap(e))?;
    let spinner = Spinner::new(quiet);
    let options =
        RunOptions { out_dir: None, field: args.field.clone(), report: args.report.clone() };
    let report = run_scene(&scene, &options, &spinner).map_err(|e| scene.wrap(e))?;
    drop(spinner);
    super::progress::report_tail(&report, false, quiet);
    if !quiet {
        if let Some(x) = &report.export {
            eprintln!(
                "glTF: {} vertices ({} mesh vertices, {} split), {} triangles, {} strokes",
                x.vertices, x.mesh_vertices, x.split_vertices, x.triangles, x.strokes
            );
        }
    }
    Ok(())
}
