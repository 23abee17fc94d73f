//! `grainline trace`: the scene's toolpath part alone — strokes, SVG, G-code, strokes JSON.

use std::path::PathBuf;

use clap::Args;
use grainline::pipeline::run::{run as run_scene, RunOptions};
use grainline::scene::LoadedScene;

use super::absolute;
use super::progress::Spinner;

/// Arguments of `grainline trace`.
#[derive(Debug, Args)]
pub struct TraceArgs {
    /// The scene file (docs/scene.md); its `toolpaths` section sets the strokes and exports.
    scene: PathBuf,
    /// The grain from `grainline optimize` or `grainline field` on the same mesh (default:
    /// the scene's field, after its edits and solve).
    #[arg(long, value_name = "FIELD.json")]
    field: Option<PathBuf>,
    /// Write the SVG here (overrides the scene).
    #[arg(long, value_name = "PATH")]
    svg: Option<PathBuf>,
    /// Write the G-code here (overrides the scene).
    #[arg(long, value_name = "PATH")]
    gcode: Option<PathBuf>,
    /// Write the strokes JSON here (overrides the scene).
    #[arg(long, value_name = "PATH")]
    strokes: Option<PathBuf>,
    /// The report: stroke count, lengths, coverage, stop reasons, time per phase.
    #[arg(long, value_name = "PATH")]
    report: Option<PathBuf>,
}

/// Runs `grainline trace`.
pub fn run(args: TraceArgs, quiet: bool) -> anyhow::Result<()> {
    // The flags among themselves first, so a clash is named by its flags.
    let mut plan = grainline::output::OutputPlan::new();
    for (flag, p) in [
        ("--svg", &args.svg),
        ("--gcode", &args.gcode),
        ("--strokes", &args.strokes),
        ("--report", &args.report),
    ] {
        if let Some(p) = p {
            plan.output(flag, p);
        }
    }
    if let Some(f) = &args.field {
        plan.input("--field", f);
    }
    plan.check()?;
    let mut scene = LoadedScene::read(&args.scene)?;
    scene.scene.render = None;
    let section = scene.scene.toolpaths.get_or_insert_with(Default::default);
    if let Some(p) = &args.svg {
        section.svg = Some(absolute(p)?);
    }
    if let Some(p) = &args.gcode {
        section.gcode = Some(absolute(p)?);
    }
    if let Some(p) = &args.strokes {
        section.strokes_json = Some(absolute(p)?);
    }
    if section.svg.is_none() && section.gcode.is_none() && section.strokes_json.is_none() {
        anyhow::bail!(
            "{}: nothing to write: give --svg, --gcode or --strokes, or set toolpaths.svg / \
             toolpaths.gcode / toolpaths.strokes_json in the scene",
            args.scene.display()
        );
    }
    let spinner = Spinner::new(quiet);
    let options =
        RunOptions { out_dir: None, field: args.field.clone(), report: args.report.clone() };
    let report = run_scene(&scene, &options, &spinner).map_err(|e| scene.wrap(e))?;
    drop(spinner);
    super::progress::report_tail(&report, true, quiet);
    if !quiet {
        if let Some(t) = &report.toolpaths {
            let cycle = t
                .job
                .cycle_time_s
                .map_or(String::new(), |s| format!(", about {:.1} min of machine time", s / 60.0));
            eprintln!(
                "{} strokes, {:.0} mm brushed, {:.0} mm travel{cycle}",
                t.job.stroke_count, t.job.cut_length_mm, t.job.travel_length_mm
            );
        }
    }
    Ok(())
}
