//! `grainline render`: the scene's preview alone — the PNG and, on request, the linear PFM.

use std::path::PathBuf;

use clap::Args;
use grainline::pipeline::run::{run as run_scene, RunOptions};
use grainline::scene::LoadedScene;

use super::absolute;
use super::progress::Spinner;

/// Arguments of `grainline render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The scene file (docs/scene.md); its `render` section sets the image, the tone mapping
    /// and the effects (its `toolpaths` section is used only when an effect needs the strokes).
    scene: PathBuf,
    /// Write the PNG here (overrides `render.output`).
    #[arg(long, value_name = "PNG")]
    out: Option<PathBuf>,
    /// Also write the linear radiance as PFM here (overrides `render.linear`).
    #[arg(long, value_name = "PFM")]
    linear: Option<PathBuf>,
    /// The grain from `grainline optimize` or `grainline field` on the same mesh (default:
    /// the scene's field, after its edits and solve).
    #[arg(long, value_name = "FIELD.json")]
    field: Option<PathBuf>,
    /// The report: the passes that ran with their times and what was not computed.
    #[arg(long, value_name = "PATH")]
    report: Option<PathBuf>,
}

/// Runs `grainline render`.
pub fn run(args: RenderArgs, quiet: bool) -> anyhow::Result<()> {
    // The flags among themselves first, so a clash is named by its flags.
    let mut plan = grainline::output::OutputPlan::new();
    for (flag, p) in [("--out", &args.out), ("--linear", &args.linear), ("--report", &args.report)]
    {
        if let Some(p) = p {
            plan.output(flag, p);
        }
    }
    if let Some(f) = &args.field {
        plan.input("--field", f);
    }
    plan.check()?;
    let mut scene = LoadedScene::read(&args.scene)?;
    let settings = scene.scene.render.get_or_insert_with(Default::default);
    if let Some(p) = &args.out {
        settings.output = absolute(p)?;
    }
    if let Some(p) = &args.linear {
        settings.linear = Some(absolute(p)?);
    }
    // Only the preview is written: the toolpath exports and FIELD.json are dropped (the
    // strokes are still traced when an effect needs them; a `--field` render of the scene
    // whose `field.output` wrote that file would otherwise be refused, or overwrite it with
    // the initial field).
    scene.scene.field.output = None;
    if let Some(t) = scene.scene.toolpaths.as_mut() {
        t.svg = None;
        t.gcode = None;
        t.strokes_json = None;
    }
    let spinner = Spinner::new(quiet);
    let options =
        RunOptions { out_dir: None, field: args.field.clone(), report: args.report.clone() };
    let report = run_scene(&scene, &options, &spinner).map_err(|e| scene.wrap(e))?;
    drop(spinner);
    super::progress::report_tail(&report, false, quiet);
    if !quiet {
        if let Some(r) = &report.render {
            let passes: Vec<String> =
                r.passes.iter().map(|p| format!("{} {:.0} ms", p.name, p.ms)).collect();
            eprintln!("render passes: {}", passes.join(", "));
        }
    }
    Ok(())
}
