//! One edit of a case run as `grainline run` runs it with strokes (issue 47): the brush
//! [`BRUSH_WIDTH`] of the part's diagonal, overlap [`BRUSH_OVERLAP`], the strokes written as an
//! SVG into the scratch directory; the run report gives the edit's fidelity as designed
//! (`optimize.fidelity`) and as brushed (`as_brushed.fidelity`), and the stages' times.

use std::time::Instant;

use grainline::pipeline::run::{run, RunOptions};
use grainline::pipeline::Silent;
use grainline::scene::{LoadedScene, Scene};

use super::{edits_json, scene_json, scratch_dir, Case, PreparedCase};

/// Brush width, share of the part's bounding-box diagonal (`toolpaths.placement.width`).
pub const BRUSH_WIDTH: f64 = 0.008;
/// `toolpaths.placement.overlap`.
pub const BRUSH_OVERLAP: f64 = 0.1;

/// What a run with strokes reports of one edit.
#[derive(Clone, Debug)]
pub struct BrushedOutcome {
    /// The case.
    pub case: String,
    /// bend / expand / curve.
    pub edit: String,
    /// Vertices of the part the run worked on (after refinement).
    pub vertices: usize,
    /// The brush width, scene units.
    pub width: f64,
    /// The run report's `as_brushed.fidelity[0]` (designed, as brushed, singular triangles
    /// added, departure), or `None` when the run measured none.
    pub fidelity: Option<serde_json::Value>,
    /// The run's wall time (the report's `wall_seconds`).
    pub wall_seconds: f64,
    /// The `as-brushed` and `as-brushed fidelity` stages' seconds.
    pub brushed_seconds: f64,
    /// The report's `as_brushed.carrying_width[0]` (the brush that carries an edit the strokes
    /// lose), when the run searched for one.
    pub carrying: Option<serde_json::Value>,
    /// The `brush width` stage's seconds (0 when the edit landed as brushed).
    pub width_seconds: f64,
    /// The `toolpaths` stage's seconds.
    pub trace_seconds: f64,
    /// Strokes traced.
    pub strokes: u64,
    /// The run's error, if it failed.
    pub error: Option<String>,
}

/// The scene of one edit of a case with strokes traced (`toolpaths.svg`), as JSON.
pub fn brushed_scene_json(
    case: &Case,
    p: &PreparedCase,
    tool: &str,
) -> Result<(serde_json::Value, f64), String> {
    let pl = p.placement.as_ref().map_err(|e| format!("{}: {e}", case.name))?;
    let (_, edit) = edits_json(pl).into_iter().find(|(n, _)| *n == tool).ok_or("unknown tool")?;
    let width = BRUSH_WIDTH * pl.diag;
    let mut json = scene_json(case);
    json["edits"] = serde_json::json!([edit]);
    json["solver"] = serde_json::json!({ "highlight_energy": "position" });
    json["toolpaths"] = serde_json::json!({
        "svg": format!("{}-{tool}-brushed.svg", case.name),
        "placement": { "width": width, "overlap": BRUSH_OVERLAP },
    });
    // Further `toolpaths` keys (bench_fidelity's `--toolpaths`).
    if let Ok(extra) = std::env::var("GRAINLINE_CORPUS_TOOLPATHS") {
        let extra: serde_json::Value =
            serde_json::from_str(&extra).map_err(|e| format!("GRAINLINE_CORPUS_TOOLPATHS: {e}"))?;
        for (k, v) in extra.as_object().into_iter().flatten() {
            json["toolpaths"][k] = v.clone();
        }
    }
    Ok((json, width))
}

/// Runs one edit of a prepared case with strokes (position energy) and reads its report.
pub fn run_brushed(case: &Case, p: &PreparedCase, tool: &str) -> Result<BrushedOutcome, String> {
    let (json, width) = brushed_scene_json(case, p, tool)?;
    let path = scratch_dir().join(format!("{}-{tool}-brushed.json", case.name));
    // The run reads its scene file too (checked against its outputs).
    let text = json.to_string();
    std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
    let scene = Scene::from_str(&text, &path).map_err(|e| e.to_string())?;
    let loaded = LoadedScene { base: scratch_dir(), path, scene };
    let mut out = BrushedOutcome {
        case: case.name.clone(),
        edit: tool.into(),
        vertices: 0,
        width,
        fidelity: None,
        wall_seconds: 0.0,
        brushed_seconds: 0.0,
        carrying: None,
        width_seconds: 0.0,
        trace_seconds: 0.0,
        strokes: 0,
        error: None,
    };
    let t = Instant::now();
    let report = match run(&loaded, &RunOptions::default(), &Silent) {
        Ok(r) => r,
        Err(e) => {
            out.error = Some(e.to_string());
            out.wall_seconds = t.elapsed().as_secs_f64();
            return Ok(out);
        }
    };
    let r = serde_json::to_value(&report).map_err(|e| e.to_string())?;
    out.vertices = report.vertices;
    out.wall_seconds = report.wall_seconds;
    let secs = |name: &str| -> f64 {
        report.stages.iter().filter(|s| s.stage == name).map(|s| s.seconds).sum()
    };
    out.brushed_seconds = secs("as-brushed") + secs("as-brushed fidelity");
    out.trace_seconds = secs("toolpaths");
    out.width_seconds = secs("brush width");
    out.carrying = r["as_brushed"]["carrying_width"].get(0).cloned();
    out.strokes = r["toolpaths"]["job"]["stroke_count"].as_u64().unwrap_or(0);
    out.fidelity = r["as_brushed"]["fidelity"].get(0).cloned();
    Ok(out)
}
