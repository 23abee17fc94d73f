//! The scene job: the stages a scene's outputs need, and nothing else.
//!
//! `prepare` (load the part, geometry, initial field, ℓ) always runs; the solve runs only when
//! the scene has edits; the strokes are traced only when a toolpath output, a strokes /
//! as-brushed render effect or `export.strokes` / `export.as_brushed` asks for them; the preview
//! renders only when the scene has a `render` section, the glTF file only with `export.glb`.
//! Every stage is timed, and the times add up to the run's wall time.

pub mod brush_width;
pub mod export;
pub mod optimize;
pub mod plan;
pub mod prepare;
pub mod preview;
pub mod run;
pub mod stroke_constraints;
pub mod trace;

use std::time::Instant;

use serde::Serialize;

pub use plan::{check_scene_work, output_path, StagePlan};
pub use prepare::{
    ensure_layout, key_light, load_part, load_stage, prepare, prepare_part, prepare_with,
    refine_request, KeyLight, LoadedPart, PatchReport, Prepared, RefinementReport,
};

/// One timed stage.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct StageTime {
    /// The stage's name (`load`, `field`, `edits`, `solve`, `toolpaths`, `render`, `write`).
    pub stage: String,
    /// Wall seconds.
    pub seconds: f64,
    /// The process's largest resident memory during the stage, MB (10⁶ bytes;
    /// [`crate::resident`]: Linux's peak resident set size, reset when the stage starts);
    /// absent where the system does not say. Work on other threads at the same time counts
    /// too (added after 0.2.0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_rss_mb: Option<f64>,
}

/// Receives the name of each stage as it starts (the CLI shows it on a spinner).
pub trait Observer {
    /// A stage starts.
    fn stage(&self, name: &str);
}

/// An observer that ignores everything.
pub struct Silent;

impl Observer for Silent {
    fn stage(&self, _name: &str) {}
}

/// Times stages back to back, so their sum is the elapsed time.
pub struct Stages<'a> {
    observer: &'a dyn Observer,
    times: Vec<StageTime>,
    current: Option<(String, Instant)>,
}

impl<'a> Stages<'a> {
    /// No stage running yet.
    pub fn new(observer: &'a dyn Observer) -> Self {
        Stages { observer, times: Vec::new(), current: None }
    }

    /// Ends the running stage (if any) and starts `name`.
    pub fn start(&mut self, name: &str) {
        self.finish();
        self.observer.stage(name);
        crate::resident::reset_peak();
        self.current = Some((name.to_string(), Instant::now()));
    }

    /// Ends the running stage.
    pub fn finish(&mut self) {
        if let Some((stage, t)) = self.current.take() {
            let peak_rss_mb = crate::resident::peak_bytes().map(|b| b as f64 * 1e-6);
            self.times.push(StageTime { stage, seconds: t.elapsed().as_secs_f64(), peak_rss_mb });
        }
    }

    /// The finished stages.
    pub fn into_times(mut self) -> Vec<StageTime> {
        self.finish();
        self.times
    }
}
