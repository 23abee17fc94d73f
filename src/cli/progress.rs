//! Status output for long work: a spinner with the current stage on a terminal, nothing with
//! `--quiet` or when stderr is not a terminal.

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// A stage spinner; it observes the library's pipeline stages.
pub struct Spinner {
    bar: Option<ProgressBar>,
}

impl Spinner {
    /// A spinner, or nothing when `quiet` or stderr is not a terminal.
    pub fn new(quiet: bool) -> Self {
        if quiet || !std::io::stderr().is_terminal() {
            return Spinner { bar: None };
        }
        let bar = ProgressBar::new_spinner();
        bar.set_style(
            ProgressStyle::with_template("{spinner} {elapsed_precise} {msg}")
                .expect("valid template"),
        );
        bar.enable_steady_tick(Duration::from_millis(100));
        Spinner { bar: Some(bar) }
    }

    /// Shows the stage now running.
    pub fn stage(&self, message: &str) {
        if let Some(b) = &self.bar {
            b.set_message(message.to_string());
        }
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

impl grainline::pipeline::Observer for Spinner {
    fn stage(&self, name: &str) {
        Spinner::stage(self, name);
    }
}

/// What a scene command prints after its run: when `strokes`, the strokes' warnings (an empty
/// G-code program written with `allow_empty`, a stroke-level constraint broken), even with
/// `--quiet` (the run report carries them too); then, unless `quiet`, one `wrote PATH` per
/// output.
pub fn report_tail(report: &grainline::pipeline::run::RunReport, strokes: bool, quiet: bool) {
    if strokes {
        for w in report.toolpaths.iter().flat_map(|t| &t.job.warnings) {
            eprintln!("warning: {w}");
        }
        for w in report.toolpaths.iter().filter_map(|t| t.stroke_constraints.as_ref()) {
            for line in w.warnings() {
                eprintln!("grainline: warning: {line}");
            }
        }
    }
    if !quiet {
        for o in &report.outputs {
            eprintln!("wrote {}", grainline::error::escape_control(o));
        }
    }
}

/// Warnings a designer should see even when the run succeeds: a light tool that could not reach
/// the wanted ℓ, a solve that made no progress.
pub fn warn_about(report: &grainline::pipeline::optimize::OptimizeStageReport) {
    for e in &report.edits {
        for note in &e.notes {
            eprintln!("grainline: warning: edit [{}] ({}): {note}", e.index, e.tool);
        }
        if let Some(err) = e.angle_error_deg.filter(|&a| a > 5.0) {
            eprintln!(
                "grainline: warning: edit [{}] ({}): the best light reaches the wanted highlight \
                 direction only within {err:.1}°",
                e.index, e.tool
            );
        }
    }
    let s = &report.solver;
    if s.iterations.is_empty()
        && matches!(
            s.stop,
            grainline::solve::StopReason::NoProgress | grainline::solve::StopReason::Gradient
        )
        && s.initial_energy.highlight > 1e-12
    {
        eprintln!(
            "grainline: warning: the solver made no step ({}): where the grain is constant \
             on a flat region ℓ = 0 and the tensor energy has no gradient; use \
             `solver.highlight_energy: \"position\"` (the default)",
            s.stop
        );
    }
}

/// One warning per edit that did not land (issue 13's fidelity measure, src/fidelity/): the
/// share of the target highlight within tolerance, the 95th-percentile distance and the singular
/// triangles before and after, or why the edit could not be measured. Printed unless `--quiet`.
pub fn warn_missed(report: &grainline::pipeline::optimize::OptimizeStageReport) {
    for line in missed_lines(&report.fidelity) {
        eprintln!("{line}");
    }
}

/// The warning lines of [`warn_missed`].
pub fn missed_lines(fidelity: &[grainline::fidelity::EditFidelity]) -> Vec<String> {
    let tolerance = grainline::fidelity::FidelityOptions::default().tolerance;
    fidelity
        .iter()
        .filter(|f| !f.landed)
        .map(|f| {
            let head = format!("grainline: warning: edit [{}] ({})", f.index, f.tool);
            if f.samples == 0 {
                let why = f.note.as_deref().unwrap_or("nothing to compare");
                return format!("{head} could not be measured: {why}");
            }
            let forced = f.singular_forced_after.saturating_sub(f.singular_forced_before);
            let forced = if forced > 0 { format!(" ({forced} forced)") } else { String::new() };
            format!(
                "{head} missed: {:.0} % of the target highlight within {tolerance} r (goal {:.0} \
                 %), p95 {:.2} r, singular triangles {} → {}{forced}",
                100.0 * f.within,
                100.0 * grainline::fidelity::GOAL_WITHIN,
                f.p95,
                f.singular_before,
                f.singular_after
            )
        })
        .collect()
}

/// One warning per edit that lands as designed but not as brushed (the run report's
/// `as_brushed.fidelity`): the figures on the grain rebuilt from the strokes against the
/// designed ones, the singular triangles the strokes add, and where the two highlights depart
/// most. An edit that missed as designed already has its warning ([`missed_lines`]).
pub fn brushed_lines(
    fidelity: &[grainline::fidelity::BrushedEditFidelity],
    carrying: &[grainline::pipeline::brush_width::CarryingWidth],
    units: &str,
) -> Vec<String> {
    let tolerance = grainline::fidelity::FidelityOptions::default().tolerance;
    fidelity
        .iter()
        .filter(|f| f.designed.landed && !f.as_brushed.landed)
        .map(|f| {
            let c = carrying.iter().find(|c| c.index == f.index);
            let width = c.map_or(String::new(), |c| carrying_note(c, units));
            let (d, b) = (&f.designed, &f.as_brushed);
            let place = f.departure.as_ref().map_or(String::new(), |x| {
                format!(
                    "; the highlight departs most, by {:.2} r, at ({:.1}, {:.1}, {:.1}) (face {})",
                    x.value, x.point[0], x.point[1], x.point[2], x.face
                )
            });
            format!(
                "grainline: warning: edit [{}] ({}) lands as designed but not as brushed: {:.0} % \
                 of the target highlight within {tolerance} r ({:.0} % designed), p95 {:.2} r \
                 ({:.2} designed), {:+} singular triangles from the strokes{place}{width}",
                f.index,
                f.tool,
                100.0 * b.within,
                100.0 * d.within,
                b.p95,
                d.p95,
                f.singular_added
            )
        })
        .collect()
}

/// "; a brush of W carries it (…)" or "; no brush down to W carries it (…)".
fn carrying_note(c: &grainline::pipeline::brush_width::CarryingWidth, units: &str) -> String {
    let b = &c.as_brushed;
    let figures = format!(
        "{:.0} % within, p95 {:.2} r, {:+} singular triangles",
        100.0 * b.within,
        b.p95,
        c.singular_added
    );
    match (c.width, c.tried.last()) {
        (Some(w), _) => format!("; a brush {} {units} wide carries it ({figures})", fmt_len(w)),
        (None, Some(w)) => {
            format!("; no brush down to {} {units} wide carries it (there: {figures})", fmt_len(*w))
        }
        (None, None) => String::new(),
    }
}

/// A length with three significant digits.
fn fmt_len(x: f64) -> String {
    let digits = (2 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{x:.digits$}")
}
