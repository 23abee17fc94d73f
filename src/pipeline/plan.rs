//! The plan: which stages a scene needs, the files a run writes and reads, where its outputs
//! go, and the work it asks for, checked before any of it starts.

use std::path::{Component, Path, PathBuf};

use serde::Serialize;

use crate::output::OutputPlan;
use crate::scene::LoadedScene;
use crate::Result;

/// Options of [`run`](super::run::run).
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Every relative output path of the scene lands under this directory (default: the scene
    /// file's directory).
    pub out_dir: Option<PathBuf>,
    /// Take the grain from this FIELD.json (the output of `grainline optimize` or `grainline
    /// field` on the same mesh) instead of computing it: no edits, no solve.
    pub field: Option<PathBuf>,
    /// Also write the run report (pretty JSON) here, after every other output.
    pub report: Option<PathBuf>,
}

/// Which stages a scene needs: decided once per run ([`StagePlan::for_run`]) and read by every
/// stage, the output plan and the editor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct StagePlan {
    /// The scene has edits: apply them and solve.
    pub solve: bool,
    /// A toolpath output or a strokes / as-brushed / gap effect needs the strokes.
    pub trace: bool,
    /// The scene has a `render` section.
    pub render: bool,
    /// The as-brushed field is needed (as-brushed effect, `export.as_brushed`, or the edits
    /// measured as brushed).
    pub as_brushed: bool,
    /// Each bend, expand and curve edit is measured on the grain rebuilt from the strokes
    /// (`toolpaths.as_brushed_fidelity: "auto"` with strokes traced and such an edit).
    pub brushed_fidelity: bool,
    /// The scene asks for a glTF export (`export.glb`).
    pub export: bool,
    /// The scene asks for the grain maps (`export.maps`).
    pub maps: bool,
    /// The preview shows the coverage gaps (`render.effects.gap`): the trace keeps its
    /// coverage map and its field mesh.
    #[serde(skip)]
    pub gap: bool,
    /// The part needs a UV layout, made at loading when it has none: the strokes, the glb's
    /// texture and the maps live in it.
    #[serde(skip)]
    pub uv_layout: bool,
}

impl StagePlan {
    /// The stages `scene` needs.
    pub fn of(scene: &crate::scene::Scene) -> StagePlan {
        let fx = scene.render.as_ref().map(|r| &r.effects);
        let ex = scene.export.as_ref().filter(|e| e.glb.is_some());
        let export_needs_strokes = ex.is_some_and(|e| e.strokes || e.as_brushed);
        let as_brushed = Self::as_brushed_asked(scene);
        let render_needs_strokes =
            fx.is_some_and(|f| f.strokes.is_some() || f.as_brushed.is_some() || f.gap.is_some());
        let toolpath_outputs = scene
            .toolpaths
            .as_ref()
            .is_some_and(|t| t.svg.is_some() || t.gcode.is_some() || t.strokes_json.is_some());
        let trace = toolpath_outputs || render_needs_strokes || export_needs_strokes;
        let maps = scene.export.as_ref().is_some_and(|e| e.maps.is_some());
        let brushed_fidelity = trace && Self::measures_edits_as_brushed(scene);
        StagePlan {
            solve: !scene.edits.is_empty(),
            trace,
            render: scene.render.is_some(),
            as_brushed: as_brushed || brushed_fidelity,
            brushed_fidelity,
            export: ex.is_some(),
            maps,
            gap: fx.is_some_and(|f| f.gap.is_some()),
            uv_layout: trace || ex.is_some() || maps,
        }
    }

    /// The stages of a run of `scene` with `options`: a given field (`--field`) takes the
    /// place of the edits and the solve.
    pub fn for_run(scene: &crate::scene::Scene, options: &RunOptions) -> StagePlan {
        let mut plan = StagePlan::of(scene);
        if options.field.is_some() {
            // No edit is applied: nothing to measure as brushed.
            plan.solve = false;
            plan.brushed_fidelity = false;
            plan.as_brushed = Self::as_brushed_asked(scene);
        }
        plan
    }

    /// Whether a render effect or the export asks for the as-brushed grain.
    fn as_brushed_asked(scene: &crate::scene::Scene) -> bool {
        let fx = scene.render.as_ref().map(|r| &r.effects);
        let ex = scene.export.as_ref().filter(|e| e.glb.is_some());
        fx.is_some_and(|f| f.as_brushed.is_some()) || ex.is_some_and(|e| e.as_brushed)
    }

    /// Whether the scene's edits are measured as brushed when strokes are traced: it has a
    /// bend, expand or curve edit and `toolpaths.as_brushed_fidelity` is not `off`.
    fn measures_edits_as_brushed(scene: &crate::scene::Scene) -> bool {
        use crate::edit::Edit;
        let on = scene.toolpaths.as_ref().is_none_or(|t| {
            t.as_brushed_fidelity != crate::scene::toolpaths::AsBrushedFidelity::Off
        });
        on && scene
            .edits
            .iter()
            .any(|e| matches!(e, Edit::Bend(_) | Edit::Expand(_) | Edit::Curve(_)))
    }

    /// Whether the trace keeps the field mesh it traced on: the as-brushed grain and the gaps
    /// per vertex are read from it.
    pub fn keeps_field_mesh(&self) -> bool {
        self.as_brushed || self.gap
    }
}

/// The files a run of `s` writes (with their scene keys) and the files it reads, for
/// [`OutputPlan::check`]: no output may be a directory, a device, a FIFO or a link, two
/// outputs may not share a file, and no output may overwrite an input. A relative output that
/// climbs out of its directory is refused here ([`output_path`]). `needs` is the run's plan.
pub fn output_plan(s: &LoadedScene, needs: &StagePlan, options: &RunOptions) -> Result<OutputPlan> {
    let scene = &s.scene;
    let out = |key: &str, p: &str| output_path(s, options.out_dir.as_deref(), key, p);
    let mut plan = OutputPlan::new();
    if let Some(p) = &scene.field.output {
        plan.output("field.output", out("field.output", p)?);
    }
    if let Some(t) = scene.toolpaths.as_ref().filter(|_| needs.trace) {
        for (key, p) in [
            ("toolpaths.svg", &t.svg),
            ("toolpaths.gcode", &t.gcode),
            ("toolpaths.strokes_json", &t.strokes_json),
        ] {
            if let Some(p) = p {
                plan.output(key, out(key, p)?);
            }
        }
    }
    if let Some(r) = &scene.render {
        plan.output("render.output", out("render.output", &r.output)?);
        if let Some(p) = &r.linear {
            plan.output("render.linear", out("render.linear", p)?);
        }
    }
    if let Some(p) = scene.export.as_ref().and_then(|e| e.glb.as_ref()) {
        plan.output("export.glb", out("export.glb", p)?);
    }
    if let Some(d) = scene.export.as_ref().and_then(|e| e.maps.as_ref()) {
        let dir = output_dir_path(s, options.out_dir.as_deref(), "export.maps", d)?;
        for f in super::export::MAP_FILES {
            plan.output("export.maps", dir.join(f));
        }
    }
    if let Some(p) = &options.report {
        plan.output("the run report", p.clone());
    }
    scene_inputs(s, &mut plan);
    if let Some(p) = &options.field {
        plan.input("--field", p.clone());
    }
    Ok(plan)
}

/// Adds the files a scene reads to `plan`: the scene file, the mesh or outline, the
/// directions file, curve edits' SVGs and environment images.
pub fn scene_inputs(s: &LoadedScene, plan: &mut OutputPlan) {
    let scene = &s.scene;
    plan.input("the scene file", s.path.clone());
    if let Some(m) = &scene.mesh {
        plan.input("mesh", s.input(&m.0.path));
    }
    if let Some(o) = &scene.outline {
        plan.input("outline", s.input(&o.path));
    }
    if let Some(p) = &scene.field.directions {
        plan.input("field.directions", s.input(p));
    }
    if let Some(m) = &scene.field.map {
        plan.input("field.map.path", s.input(&m.path));
    }
    for (i, e) in scene.edits.iter().enumerate() {
        if let crate::edit::Edit::Curve(c) = e {
            if let Some(p) = &c.svg {
                plan.input(format!("edits[{i}].svg"), s.input(p));
            }
        }
    }
    for (i, l) in scene.lights.iter().enumerate() {
        if let crate::render::LightSpec::Environment { file, .. } = l {
            plan.input(format!("lights[{i}].file"), s.input(file));
        }
    }
}

/// The work a scene asks for, estimated as soon as its part is loaded (before the field, the
/// solve, the strokes or the render start) and refused past its budget, naming the key:
/// the strokes' samples (`toolpaths.placement.*`, over the part's surface area).
/// The render's memory and the ordering's neighbours are checked with the scene itself
/// (`Scene::validate`), the panel's triangles before the outline is meshed. `plan` is the
/// run's.
pub fn check_scene_work(
    scene: &crate::scene::Scene,
    plan: &StagePlan,
    mesh: &crate::mesh::Mesh,
) -> Result<()> {
    if let (true, Some(t)) = (plan.trace, &scene.toolpaths) {
        // Placement lengths are in scene units on the part, and the UV field is scaled to
        // the part's area, so the mesh's surface area is the area the strokes cover.
        t.placement.check_budget(mesh.area()).map_err(|e| {
            crate::scene::prefix("toolpaths", crate::scene::toolpaths::toolpath_error(e))
        })?;
    }
    Ok(())
}

/// Where an output of the scene goes: under `out_dir` when given, else relative to the scene
/// file. An absolute path is taken as it is; a relative one must stay inside that directory:
/// a `..` that climbs out of it (`../x.svg`, `a/../../x.svg`) is refused, naming `key` (the
/// scene key, e.g. `render.output`), and so is a path longer than
/// [`crate::limits::MAX_OUTPUT_PATH_BYTES`] (echoed shortened).
///
/// An output names a file: an empty path, `.`, a path ending in `/` or in `.` or `..` names
/// a directory and is refused, naming `key` (an empty one would otherwise have been the
/// directory itself, and `export.maps: ""` put its maps in the file system's root).
pub fn output_path(s: &LoadedScene, out_dir: Option<&Path>, key: &str, p: &str) -> Result<PathBuf> {
    if let Some(why) = not_a_file_name(p) {
        return Err(crate::Error::setting(
            key,
            format!("{:?} {why}; an output is a file: give its name", crate::error::shorten(p)),
        ));
    }
    output_dir_path(s, out_dir, key, p)
}

/// Why the output path `p` does not name a file, if it does not.
fn not_a_file_name(p: &str) -> Option<&'static str> {
    if p.is_empty() {
        return Some("is empty");
    }
    if p.ends_with('/') || p.ends_with(std::path::MAIN_SEPARATOR) {
        return Some("ends in a separator (a directory)");
    }
    match Path::new(p).components().next_back() {
        Some(Component::Normal(_)) if !p.ends_with("/.") && p != "." => None,
        _ => Some("names a directory"),
    }
}

/// Where an output directory of the scene (`export.maps`) goes, as [`output_path`] but a
/// directory: `.` (the output directory itself) and a trailing `/` are accepted; an empty
/// path is refused naming `key`.
pub fn output_dir_path(
    s: &LoadedScene,
    out_dir: Option<&Path>,
    key: &str,
    p: &str,
) -> Result<PathBuf> {
    if p.is_empty() {
        return Err(crate::Error::setting(
            key,
            "is empty; give a directory (`.` for the output directory itself)",
        ));
    }
    if p.len() > crate::limits::MAX_OUTPUT_PATH_BYTES {
        return Err(crate::Error::setting(
            key,
            format!(
                "{:?} is longer than {} bytes, the longest path an output may have",
                crate::error::shorten(p),
                crate::limits::MAX_OUTPUT_PATH_BYTES
            ),
        ));
    }
    let path = Path::new(p);
    if path.is_absolute() {
        return Ok(path.to_path_buf());
    }
    if leaves(path) {
        let (dir, which) = match out_dir {
            Some(d) => (d, "--out-dir"),
            None => (s.base.as_path(), "the scene file's directory"),
        };
        return Err(crate::Error::setting(
            key,
            format!(
                "{p:?} leaves {} ({which}) through `..`; a relative output must stay inside \
                 it: give a path below it, or an absolute path",
                dir.display()
            ),
        ));
    }
    Ok(match out_dir {
        Some(d) => d.join(path),
        None => s.base.join(path),
    })
}

/// Whether the relative path `p`, read component by component, climbs above its start.
fn leaves(p: &Path) -> bool {
    let mut depth = 0usize;
    for c in p.components() {
        match c {
            Component::ParentDir if depth == 0 => return true,
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            // A prefix or root makes the path absolute (handled by the caller).
            Component::Prefix(_) | Component::RootDir => return false,
        }
    }
    false
}
