//! `grainline optimize`: edits and the solve, written as FIELD.json and a report.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use grainline::pipeline::optimize::{optimize_stage, optimized_field_file};
use grainline::pipeline::{prepare, Stages};
use grainline::scene::LoadedScene;

use super::progress::Spinner;

/// Arguments of `grainline optimize`.
#[derive(Debug, Args)]
pub struct OptimizeArgs {
    /// The scene file (docs/scene.md).
    scene: PathBuf,
    /// Output FIELD.json (docs/formats.md) with `phi_before`, `u_before` and `target_ell`.
    #[arg(long, value_name = "FIELD.json")]
    out: PathBuf,
    /// Also write the solver's report (iterations, energies, constraints, singularities).
    #[arg(long, value_name = "REPORT.json")]
    report: Option<PathBuf>,
}

/// Runs `grainline optimize`.
pub fn run(args: OptimizeArgs, quiet: bool) -> anyhow::Result<()> {
    let scene = LoadedScene::read(&args.scene)?;
    let mut plan = grainline::output::OutputPlan::new();
    plan.output("--out", &args.out);
    if let Some(r) = &args.report {
        plan.output("--report", r);
    }
    grainline::pipeline::run::scene_inputs(&scene, &mut plan);
    plan.check()?;
    let spinner = Spinner::new(quiet);
    let mut stages = Stages::new(&spinner);
    let prepared = prepare(&scene, &mut stages).map_err(|e| scene.wrap(e))?;
    let optimized = optimize_stage(&scene, &prepared, &mut stages).map_err(|e| scene.wrap(e))?;
    stages.start("write");
    let file = optimized_field_file(&prepared, &optimized)?;
    // FIELD.json and the report are put in place together, the report last.
    let mut staged = grainline::output::Staged::new();
    staged
        .add(&args.out, &grainline::output::json_compact(&file)?)
        .with_context(|| format!("writing {}", args.out.display()))?;
    if let Some(r) = &args.report {
        #[derive(serde::Serialize)]
        struct Report<'a> {
            format: &'static str,
            version: u32,
            scene: String,
            stages: Vec<grainline::pipeline::StageTime>,
            #[serde(flatten)]
            optimize: &'a grainline::pipeline::optimize::OptimizeStageReport,
        }
        let report = Report {
            format: "grainline-optimize-report",
            version: 1,
            scene: args.scene.display().to_string(),
            stages: std::mem::replace(&mut stages, Stages::new(&spinner)).into_times(),
            optimize: &optimized.report,
        };
        staged
            .add(r, &grainline::output::json_pretty(&report)?)
            .with_context(|| format!("writing {}", r.display()))?;
    }
    staged.commit()?;
    drop(spinner);
    super::progress::warn_about(&optimized.report);
    if !quiet {
        let s = &optimized.report.solver;
        eprintln!(
            "wrote {} ({} edited vertices; solver: {})",
            args.out.display(),
            optimized.report.edited_vertices,
            s.stop
        );
    }
    Ok(())
}
