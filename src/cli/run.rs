//! `grainline run`: the whole scene, exactly the stages its outputs need.

use std::path::PathBuf;

use clap::Args;
use grainline::pipeline::run::{run as run_scene, RunOptions};
use grainline::scene::LoadedScene;

use super::progress::Spinner;

/// Arguments of `grainline run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The scene file (docs/scene.md).
    scene: PathBuf,
    /// Every relative output path of the scene lands under this directory (default: the
    /// scene file's directory).
    #[arg(long, value_name = "DIR")]
    out_dir: Option<PathBuf>,
    /// The run report (JSON): stages and times, solver, strokes, coverage, constraints,
    /// singularities, as-brushed fidelity. Default: run-report.json in the output directory.
    #[arg(long, value_name = "REPORT.json")]
    report: Option<PathBuf>,
}

/// Runs `grainline run`.
pub fn run(args: RunArgs, quiet: bool) -> anyhow::Result<()> {
    let scene = LoadedScene::read(&args.scene)?;
    if let Some(d) = &args.out_dir {
        // Created with the outputs, once the run has succeeded (a failed run writes nothing).
        if d.as_os_str().is_empty() {
            anyhow::bail!("--out-dir is empty: give a directory (`.` for this one)");
        }
        if std::fs::metadata(d).is_ok_and(|m| !m.is_dir()) {
            anyhow::bail!("--out-dir {}: is a file, not a directory", d.display());
        }
    }
    let report_path = args.report.clone().unwrap_or_else(|| {
        args.out_dir.clone().unwrap_or_else(|| scene.base.clone()).join("run-report.json")
    });
    let spinner = Spinner::new(quiet);
    let options = RunOptions {
        out_dir: args.out_dir.clone(),
        field: None,
        report: Some(report_path.clone()),
    };
    // Every output, then the report, is written only once all of them are computed.
    let report = run_scene(&scene, &options, &spinner).map_err(|e| scene.wrap(e))?;
    drop(spinner);
    if let Some(o) = &report.optimize {
        super::progress::warn_about(o);
        if !quiet {
            super::progress::warn_missed(o);
        }
    }
    if let (Some(b), false) = (&report.as_brushed, quiet) {
        for line in super::progress::brushed_lines(&b.fidelity, &b.carrying_width, &report.units) {
            eprintln!("{line}");
        }
    }
    if let Some(n) = report.patches.as_ref().and_then(|p| p.narrow.as_ref()) {
        eprintln!("grainline: warning: {}", n.warning());
    }
    super::progress::report_tail(&report, true, quiet);
    if !quiet {
        let stages: Vec<String> =
            report.stages.iter().map(|s| format!("{} {:.2}s", s.stage, s.seconds)).collect();
        eprintln!(
            "wrote {} ({:.2} s: {})",
            grainline::error::escape_control(&report_path.display().to_string()),
            report.wall_seconds,
            stages.join(", ")
        );
    }
    Ok(())
}
