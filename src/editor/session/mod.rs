//! The editor's state: the scene as read, the part as loaded and its preparations, the list of
//! edits with its undo and redo stacks, the edit being dragged, and the solver thread that
//! turns the latest list into a field (latest request wins: a solve made stale by a change is
//! cancelled at its next check point, [`crate::cancel`], and a result that is stale when it is
//! ready is dropped).
//!
//! Every field the page is shown is computed from the scene **text** that saving would write
//! ([`Session::scene_text`]), read back by [`Scene::from_str`] and run through the same stages
//! as `grainline run` ([`crate::pipeline::load_stage`], [`crate::pipeline::prepare_part`],
//! [`crate::pipeline::optimize::optimize_stage`],
//! [`crate::pipeline::optimize::optimized_field_file`], [`crate::output::json_compact`]).
//!
//! Refinement (`mesh.refine`, docs/math.md §12): `grainline run` refines the part inside the
//! brushes of the scene's edits before it computes the field. The session does the same for
//! the **committed** edits ([`Session::solve`], [`Session::part_for`]): the part as loaded is
//! prepared again for them, once per refinement request ([`crate::pipeline::refine_request`]:
//! an unchanged set of brushes is not refined again), so the FIELD.json of a run on the saved
//! scene is byte for byte the one the page showed. A drag step ([`Session::solve_drag`]) is
//! solved on the part prepared for the edits committed before it: the dragged brush's own
//! refinement is made when the drag ends (the change is committed), and the page then loads
//! the new mesh ([`Solved::part`]).
//!
//! The key light (`POST /api/light`, [`Change::Light`]) is a scene change like an edit: the
//! scene with the new direction is loaded and prepared again once ([`Base`], made by the solver
//! thread when it first solves for that light; every cache is keyed by the base's generation),
//! undo and redo restore it with the edits, and saving writes it into `lights`.

use std::path::Path;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::cancel::Cancel;
use crate::edit::{Edit, WarpKind};
use crate::editor::drag::DragBase;
use crate::fidelity::EditFidelity;
use crate::pipeline::run::StagePlan;
use crate::pipeline::{
    load_stage, prepare_part, refine_request, LoadedPart, Prepared, Silent, Stages,
};
use crate::scene::{LoadedScene, Scene};
use crate::{Error, Result};

mod page;
mod solve;

pub use solve::{PageStrokes, Solved};

/// Undo steps kept (older ones are forgotten).
pub const UNDO_DEPTH: usize = 200;

/// Solved fields kept for the page after a newer one is ready.
pub const RECENT_KEPT: usize = 4;

/// Refined preparations of the part kept (the oldest is forgotten past this).
pub const PARTS_KEPT: usize = 4;

/// One preparation of the part that fields are solved on.
pub struct Part {
    /// 0 for the part as loaded (nothing refined); a new number for each refinement made.
    pub id: u32,
    /// The mesh, its geometry and the initial field, as `grainline run` prepares them.
    pub prepared: Prepared,
}

/// The session's preparations of the part.
#[derive(Default)]
struct Parts {
    /// The next refined part's id.
    next_id: u32,
    /// Refined preparations, oldest first, keyed by their base's generation and their
    /// refinement request.
    refined: Vec<(u64, crate::edit::resolution::Resolution, Arc<Part>)>,
    /// The base's generation and edit list asked for last, and its part.
    last: Option<(u64, Vec<Edit>, Arc<Part>)>,
}

/// What the fields are solved from: the scene with the key light the page set (or as read),
/// the part loaded for it and prepared without edits. A new key light direction is a new base
/// (a new generation), made by the solver thread when it first solves for it.
pub struct Base {
    /// 0 for the scene as read; a new number for each base made.
    gen: u64,
    /// The key light's direction set on the page (`None`: as read).
    light: Option<[f64; 3]>,
    loaded: LoadedScene,
    /// The part as loaded, before any refinement.
    part: LoadedPart,
    /// The part prepared without edits (nothing refined).
    coarse: Arc<Part>,
}

impl Base {
    /// Loads and prepares the part of `loaded` (its own edits left out).
    fn new(gen: u64, light: Option<[f64; 3]>, loaded: LoadedScene) -> Result<Base> {
        let plan = StagePlan::of(&loaded.scene);
        let mut stages = Stages::new(&Silent);
        let part = load_stage(&loaded, &mut stages, &plan).map_err(|e| loaded.wrap(e))?;
        let mut bare = loaded.clone();
        bare.scene.edits.clear();
        let prepared =
            prepare_part(&bare, part.clone(), &mut stages).map_err(|e| loaded.wrap(e))?;
        Ok(Base { gen, light, loaded, part, coarse: Arc::new(Part { id: 0, prepared }) })
    }
}

/// The scene's key light set to point towards `d` (it must be a directional light).
fn with_key_light(mut s: LoadedScene, d: [f64; 3]) -> Result<LoadedScene> {
    let i = crate::render::key_light_index(&s.scene.lights);
    match i.map(|i| &mut s.scene.lights[i]) {
        Some(crate::render::LightSpec::Directional { direction, .. }) => *direction = d,
        _ => {
            return Err(Error::setting(
                "lights",
                "the key light is not a directional light: the editor turns only those",
            ))
        }
    }
    Ok(s)
}

/// The scene file's text of base `b` with `edits` as its edits ([`Session::scene_text`]).
fn scene_text_of(b: &Base, edits: &[Edit]) -> Result<String> {
    let mut scene = b.loaded.scene.clone();
    scene.edits = edits.to_vec();
    let bytes = crate::output::json_pretty(&scene)?;
    String::from_utf8(bytes).map_err(|e| Error::invalid_arg("scene", e.to_string()))
}

/// The drag steps' reusable state: the base's generation, the part's id, the committed edits
/// it was made for.
type KeptDrag = (u64, u32, Vec<Edit>, Arc<DragBase>);

/// An undo step: the committed edits and the key light set.
type Snapshot = (Vec<Edit>, Option<[f64; 3]>);

/// What the page asked for and what the solver has done.
#[derive(Default)]
struct State {
    /// The committed edits.
    edits: Vec<Edit>,
    /// The edit being dragged (solved after the committed ones, not yet committed).
    preview: Option<Edit>,
    /// The key light's direction set on the page (`None`: as read).
    light: Option<[f64; 3]>,
    undo: Vec<Snapshot>,
    redo: Vec<Snapshot>,
    /// Bumped on every change of `edits` or `preview`.
    version: u64,
    /// The newest field computed for the version that was current when it was ready.
    solved: Option<Arc<Solved>>,
    /// The last [`RECENT_KEPT`] such fields, oldest first (the page may ask for one that was
    /// superseded between its state request and its grain request).
    recent: Vec<Arc<Solved>>,
    /// The newest solve that failed: its version and message.
    error: Option<(u64, String)>,
    /// The version whose committed edits were last saved (or read from the file).
    saved_edits: Vec<Edit>,
    /// The key light last saved (`None`: as read).
    saved_light: Option<[f64; 3]>,
    /// Results dropped because a newer request arrived while they were computed.
    dropped: u64,
    /// The solver thread is computing this version.
    solving: Option<u64>,
    /// The flag of the solve in progress: set by a change, which makes that solve stale.
    inflight: Option<Cancel>,
}

/// A summary of the state for the page (`GET /api/state`).
#[derive(Clone, Debug, Serialize)]
pub struct StateView {
    /// The current version (edits + preview).
    pub version: u64,
    /// The version of the newest solved field (`None` before the first one).
    pub solved_version: Option<u64>,
    /// The newest failed solve's version and message.
    pub error: Option<(u64, String)>,
    /// The committed edits, as the scene file would hold them.
    pub edits: Vec<Edit>,
    /// Whether an edit is being dragged.
    pub previewing: bool,
    /// The key light's direction set on the page (`None`: the scene's as read).
    pub light: Option<[f64; 3]>,
    /// Undo steps available.
    pub undo: usize,
    /// Redo steps available.
    pub redo: usize,
    /// The committed edits differ from the file's.
    pub dirty: bool,
    /// Stale results dropped so far.
    pub dropped: u64,
    /// The solver is busy.
    pub solving: bool,
    /// Of the solved field: solver stop reason, key light, fidelity, seconds.
    pub stop: Option<String>,
    /// The key light of the solved field.
    pub key_light: Option<[f64; 3]>,
    /// The fidelity figures of the solved field.
    pub fidelity: Vec<EditFidelity>,
    /// Seconds the newest solve took.
    pub seconds: Option<f64>,
}

/// What a change asks for (`POST /api/edit`).
#[derive(Clone, Debug)]
pub enum Change {
    /// Solve with this edit after the committed ones (a drag in progress).
    Preview(Edit),
    /// Append this edit to the committed ones.
    Commit(Edit),
    /// Drop the preview.
    Cancel,
    /// Back to the list before the last commit.
    Undo,
    /// Forward again.
    Redo,
    /// Point the key light (a directional light) towards this direction: a scene change,
    /// undone like an edit and saved into `lights`.
    Light([f64; 3]),
}

/// A file the editor writes for the committed edits (`POST /api/export`, [`Session::export`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExportKind {
    /// The toolpaths' SVG (`toolpaths.svg`).
    Svg,
    /// The toolpaths' G-code (`toolpaths.gcode`).
    Gcode,
    /// The glTF binary (`export.glb`).
    Glb,
}

/// The editor's session: shared by the request threads and the solver thread.
pub struct Session {
    /// The scene as read, its part loaded and prepared.
    original: Arc<Base>,
    /// The base of the key light set last (the original until one is set).
    lit: Mutex<Arc<Base>>,
    parts: Mutex<Parts>,
    /// The drag steps' reusable state.
    drag: Mutex<Option<KeptDrag>>,
    /// The last drag step's page field (the next step's grain and curves are made from it).
    drag_page: Mutex<Option<page::PageField>>,
    state: Mutex<State>,
    changed: Condvar,
}

impl Session {
    /// Reads the scene, loads the part and prepares it without edits (geometry, initial
    /// field) as `grainline run` would (a UV layout is made when the scene's toolpaths need one
    /// and the part has none). The scene's own edits are prepared for at the first solve.
    pub fn open(path: &Path) -> Result<Session> {
        let loaded = LoadedScene::read(path)?;
        let edits = loaded.scene.edits.clone();
        let original = Arc::new(Base::new(0, None, loaded)?);
        let state = State { saved_edits: edits.clone(), edits, version: 1, ..State::default() };
        let parts = Mutex::new(Parts { next_id: 1, ..Parts::default() });
        Ok(Session {
            lit: Mutex::new(Arc::clone(&original)),
            original,
            parts,
            drag: Mutex::new(None),
            drag_page: Mutex::new(None),
            state: Mutex::new(state),
            changed: Condvar::new(),
        })
    }

    /// The base for the key light `light` (`None`: as read): the one made last when it is
    /// for the same light, else a new one (the part loaded and prepared again).
    pub fn base_for(&self, light: Option<[f64; 3]>) -> Result<Arc<Base>> {
        let Some(d) = light else { return Ok(Arc::clone(&self.original)) };
        let last = Arc::clone(&self.lit.lock().unwrap_or_else(|e| e.into_inner()));
        if last.light == light {
            return Ok(last);
        }
        let loaded = with_key_light(self.original.loaded.clone(), d)?;
        let base = Arc::new(Base::new(last.gen + 1, light, loaded)?);
        *self.lit.lock().unwrap_or_else(|e| e.into_inner()) = Arc::clone(&base);
        Ok(base)
    }

    /// The base of the key light set now.
    fn current_base(&self) -> Result<Arc<Base>> {
        let light = self.lock().light;
        self.base_for(light)
    }

    fn parts(&self) -> MutexGuard<'_, Parts> {
        self.parts.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The scene as `grainline run` would read it from a file holding `edits`.
    fn with_edits(&self, b: &Base, edits: &[Edit]) -> Result<LoadedScene> {
        let text = scene_text_of(b, edits)?;
        let scene = Scene::from_str(&text, &b.loaded.path)?;
        Ok(LoadedScene { scene, ..b.loaded.clone() })
    }

    /// The part as `grainline run` prepares it for a scene holding `edits`: the part as
    /// loaded, refined inside their brushes as `mesh.refine` says
    /// ([`crate::pipeline::prepare_part`]). A refinement is made once per request
    /// ([`refine_request`]) and kept ([`PARTS_KEPT`]); without one it is the coarse part.
    pub fn part_for(&self, b: &Base, edits: &[Edit]) -> Result<Arc<Part>> {
        if let Some((g, e, p)) = &self.parts().last {
            if *g == b.gen && e == edits {
                return Ok(Arc::clone(p));
            }
        }
        let s = self.with_edits(b, edits)?;
        let part = match refine_request(&s, &b.part.mesh).map_err(|e| s.wrap(e))? {
            None => Arc::clone(&b.coarse),
            Some(request) => self.refined_part(b, &s, request)?,
        };
        self.parts().last = Some((b.gen, edits.to_vec(), Arc::clone(&part)));
        Ok(part)
    }

    /// The part refined for `request` (made from the part as loaded when not kept).
    fn refined_part(
        &self,
        b: &Base,
        s: &LoadedScene,
        request: crate::edit::resolution::Resolution,
    ) -> Result<Arc<Part>> {
        let kept = self
            .parts()
            .refined
            .iter()
            .find(|(g, k, _)| *g == b.gen && *k == request)
            .map(|(_, _, p)| p.clone());
        if let Some(p) = kept {
            return Ok(p);
        }
        let mut stages = Stages::new(&Silent);
        let prepared = prepare_part(s, b.part.clone(), &mut stages).map_err(|e| s.wrap(e))?;
        let mut parts = self.parts();
        let part = if prepared.refinement.is_none() {
            Arc::clone(&b.coarse)
        } else {
            let id = parts.next_id;
            parts.next_id += 1;
            Arc::new(Part { id, prepared })
        };
        parts.refined.push((b.gen, request, Arc::clone(&part)));
        if parts.refined.len() > PARTS_KEPT {
            parts.refined.remove(0);
        }
        Ok(part)
    }

    /// The part numbered `id`, if the session still holds it (the coarse part is 0).
    pub fn part_by_id(&self, id: u32) -> Option<Arc<Part>> {
        if id == 0 {
            // The same mesh under every key light.
            return Some(Arc::clone(&self.original.coarse));
        }
        let kept =
            self.parts().refined.iter().find(|(_, _, p)| p.id == id).map(|(_, _, p)| p.clone());
        kept.or_else(|| self.lock().recent.iter().map(|s| s.part.clone()).find(|p| p.id == id))
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The scene file.
    pub fn path(&self) -> &Path {
        &self.original.loaded.path
    }

    /// The scene as read.
    pub fn scene(&self) -> &Scene {
        &self.original.loaded.scene
    }

    /// The part prepared without edits (nothing refined): its vertices keep their indices in
    /// every refined part, which appends its new vertices after them.
    pub fn prepared(&self) -> &Prepared {
        &self.original.coarse.prepared
    }

    /// The scene file's text with `edits` as its edits: pretty JSON ending in a newline, every
    /// other key as read (comments and key order of the user's file are not kept).
    /// The key light is the one set on the page (or as read).
    pub fn scene_text(&self, edits: &[Edit]) -> Result<String> {
        scene_text_of(&*self.current_base()?, edits)
    }

    /// Checks an edit from the page: the tools the page drives (bend, expand, stencil, light,
    /// curve from 3D points or UV polylines), their numbers in range, a vertex centre on the
    /// part. A curve from an SVG file is refused: the page may not name files.
    pub fn check_edit(&self, e: &Edit) -> Result<()> {
        match e {
            Edit::Bend(_) | Edit::Expand(_) | Edit::Stencil(_) | Edit::Light(_) => {}
            Edit::Curve(c) if c.svg.is_none() => {}
            Edit::Curve(_) => {
                return Err(Error::setting("svg", "the editor takes curves as points, not files"))
            }
            other => {
                return Err(Error::setting(
                    "tool",
                    format!("the editor does not drive the `{}` tool yet", other.tool()),
                ))
            }
        }
        e.validate()?;
        let n = self.prepared().mesh.num_vertices();
        let centre = match e {
            Edit::Bend(w) | Edit::Expand(w) => Some(&w.centre),
            Edit::Stencil(s) => Some(&s.centre),
            Edit::Light(l) => Some(&l.centre),
            _ => None,
        };
        if let Some(crate::edit::Centre::Vertex(v)) = centre {
            if *v as usize >= n {
                return Err(Error::setting(
                    "centre.vertex",
                    format!("vertex {v} does not exist (the mesh has {n})"),
                ));
            }
        }
        Ok(())
    }

    /// Refuses an edit whose refinement, after the committed ones, would be past
    /// `mesh.refine.max_vertices`: the estimate `grainline run` makes before any split
    /// ([`crate::pipeline::prepare::check_refine_budget`]), made here at once so that the request is refused naming the edit
    /// (`edits[N]`) and the budget, instead of the solver thread refining for minutes. A
    /// dragged edit is checked too: it would be refused when committed.
    pub fn check_refinement(&self, e: &Edit) -> Result<()> {
        let mut edits = self.lock().edits.clone();
        edits.push(e.clone());
        // The part and the brushes do not depend on the key light: the original base serves.
        let b = &self.original;
        let s = self.with_edits(b, &edits)?;
        crate::pipeline::prepare::check_refine_budget(&s, &b.part.mesh)
    }

    /// Applies a change; returns the new version. The solver thread picks it up, and the solve
    /// in progress, now stale, is cancelled ([`Session::solver_loop`]). Nothing is applied
    /// when the request's work was cancelled meanwhile (its client left: [`super::http`]).
    pub fn change(&self, c: Change) -> Result<u64> {
        if let Change::Preview(e) | Change::Commit(e) = &c {
            self.check_edit(e)?;
            self.check_refinement(e)?;
        }
        crate::cancel::checkpoint("edit")?;
        let mut st = self.lock();
        match c {
            Change::Preview(e) => {
                st.preview = Some(e);
            }
            Change::Commit(e) => {
                let max = crate::limits::MAX_EDITS;
                if st.edits.len() >= max {
                    return Err(Error::setting(
                        "edits",
                        format!("the scene already has {max} edits, the most it may have"),
                    ));
                }
                let before = (st.edits.clone(), st.light);
                st.undo.push(before);
                if st.undo.len() > UNDO_DEPTH {
                    st.undo.remove(0);
                }
                st.redo.clear();
                st.edits.push(e);
                st.preview = None;
            }
            Change::Cancel => {
                st.preview = None;
            }
            Change::Undo => {
                let Some((edits, light)) = st.undo.pop() else {
                    return Err(Error::setting("undo", "nothing to undo"));
                };
                let now = (std::mem::replace(&mut st.edits, edits), st.light);
                st.light = light;
                st.redo.push(now);
                st.preview = None;
            }
            Change::Redo => {
                let Some((edits, light)) = st.redo.pop() else {
                    return Err(Error::setting("redo", "nothing to redo"));
                };
                let now = (std::mem::replace(&mut st.edits, edits), st.light);
                st.light = light;
                st.undo.push(now);
                st.preview = None;
            }
            Change::Light(d) => {
                let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if !(n.is_finite() && n > 1e-9) {
                    return Err(Error::setting("direction", "a finite, non-zero direction"));
                }
                // Checked here, not when the solver first meets it: the scene file's own
                // checks on the scene as it would be saved.
                with_key_light(self.original.loaded.clone(), d)?.scene.validate()?;
                let before = (st.edits.clone(), st.light);
                st.undo.push(before);
                if st.undo.len() > UNDO_DEPTH {
                    st.undo.remove(0);
                }
                st.redo.clear();
                st.light = Some(d.map(|c| c / n));
                st.preview = None;
            }
        }
        st.version += 1;
        if let Some(stale) = st.inflight.take() {
            stale.cancel();
        }
        let v = st.version;
        drop(st);
        self.changed.notify_all();
        Ok(v)
    }

    /// The state for the page; waits up to `wait` for a solve (or a failure) newer than
    /// `after` when one is asked for.
    pub fn view(&self, after: Option<u64>, wait: Duration) -> StateView {
        let deadline = Instant::now() + wait;
        let mut st = self.lock();
        if let Some(after) = after {
            loop {
                let newest = st
                    .solved
                    .as_ref()
                    .map(|s| s.version)
                    .max(st.error.as_ref().map(|e| e.0))
                    .unwrap_or(0);
                let now = Instant::now();
                // A page that left (its request cancelled, [`super::http`]) waits no longer.
                let gone = crate::cancel::checkpoint("state").is_err();
                if newest > after || now >= deadline || gone {
                    break;
                }
                let slice = (deadline - now).min(super::http::WATCH_INTERVAL);
                st = match self.changed.wait_timeout(st, slice) {
                    Ok((g, _)) => g,
                    Err(e) => e.into_inner().0,
                };
            }
        }
        let s = st.solved.clone();
        StateView {
            version: st.version,
            solved_version: s.as_ref().map(|s| s.version),
            error: st.error.clone(),
            edits: st.edits.clone(),
            previewing: st.preview.is_some(),
            light: st.light,
            undo: st.undo.len(),
            redo: st.redo.len(),
            dirty: st.edits != st.saved_edits || st.light != st.saved_light,
            dropped: st.dropped,
            solving: st.solving.is_some(),
            stop: s.as_ref().map(|s| s.stop.clone()),
            key_light: s.as_ref().map(|s| s.key_light),
            fidelity: s.as_ref().map(|s| s.fidelity.clone()).unwrap_or_default(),
            seconds: s.as_ref().map(|s| s.seconds),
        }
    }

    /// The newest solved field (`None`), or the one of `version` if it is among the last
    /// [`RECENT_KEPT`].
    pub fn solved(&self, version: Option<u64>) -> Option<Arc<Solved>> {
        let st = self.lock();
        match version {
            None => st.solved.clone(),
            Some(v) => st.recent.iter().rev().find(|s| s.version == v).cloned(),
        }
    }

    /// Writes the committed edits into the scene file (atomically, through
    /// [`crate::output::write_atomic`]); returns the path written.
    pub fn save(&self) -> Result<std::path::PathBuf> {
        let (edits, light) = {
            let st = self.lock();
            (st.edits.clone(), st.light)
        };
        let text = scene_text_of(&*self.base_for(light)?, &edits)?;
        let path = self.path().to_path_buf();
        // Saved only what reads back: the same check as every scene.
        Scene::from_str(&text, &path)?;
        crate::output::write_atomic(&path, text.as_bytes())?;
        let mut st = self.lock();
        (st.saved_edits, st.saved_light) = (edits, light);
        drop(st);
        self.changed.notify_all();
        Ok(path)
    }

    /// Writes one of the scene's fabrication or viewer files for the committed edits through
    /// `grainline run` itself ([`crate::pipeline::run::run`]) on the scene the editor would
    /// save ([`Session::scene_text`]), with every other output left out: the same refined part,
    /// the same solve and the same bytes as a run on the saved scene, renamed into place
    /// atomically by the run's staging ([`crate::output::Staged`]). The path is the scene's own
    /// (`toolpaths.svg`, `toolpaths.gcode`, `export.glb`), or `<scene stem>.svg / .ngc / .glb`
    /// beside the scene file when it names none. Returns the path written.
    pub fn export(&self, what: ExportKind) -> Result<std::path::PathBuf> {
        let (edits, light) = {
            let st = self.lock();
            (st.edits.clone(), st.light)
        };
        let b = self.base_for(light)?;
        let mut s = self.with_edits(&b, &edits)?;
        let beside = |ext: &str| self.path().with_extension(ext).display().to_string();
        let scene = &mut s.scene;
        scene.field.output = None;
        scene.render = None;
        match what {
            ExportKind::Svg | ExportKind::Gcode => {
                if scene.toolpaths.is_none() && b.part.mesh.uv.is_none() {
                    return Err(Error::setting(
                        "toolpaths",
                        format!(
                            "{} has no UV layout and the scene has no `toolpaths` section: add                              `\"toolpaths\": {{\"svg\": \"strokes.svg\"}}` (its `layout`                              makes a UV layout)",
                            self.prepared().mesh_name
                        ),
                    ));
                }
                let units = scene.units;
                let mut t = scene
                    .toolpaths
                    .take()
                    .unwrap_or_else(|| crate::scene::toolpaths::ToolpathSection::default_in(units));
                let (svg, gcode) = match what {
                    ExportKind::Svg => (Some(t.svg.clone().unwrap_or_else(|| beside("svg"))), None),
                    _ => (None, Some(t.gcode.clone().unwrap_or_else(|| beside("ngc")))),
                };
                (t.svg, t.gcode, t.strokes_json) = (svg, gcode, None);
                scene.toolpaths = Some(t);
                scene.export = None;
            }
            ExportKind::Glb => {
                let mut e = scene.export.take().unwrap_or_default();
                e.glb = Some(e.glb.clone().unwrap_or_else(|| beside("glb")));
                if let Some(t) = scene.toolpaths.as_mut() {
                    (t.svg, t.gcode, t.strokes_json) = (None, None, None);
                }
                scene.export = Some(e);
            }
        }
        let options = crate::pipeline::run::RunOptions::default();
        let report = crate::pipeline::run::run(&s, &options, &Silent)?;
        match report.outputs.as_slice() {
            [one] => Ok(std::path::PathBuf::from(one)),
            other => Err(Error::invalid_arg(
                "export",
                format!("the run wrote {} files, not one", other.len()),
            )),
        }
    }

    /// The solver thread's loop: solves the latest version, never returns. A change makes the
    /// solve in progress stale: it is cancelled ([`Cancel`]) and stops at its next check point
    /// (the refinement's levels, the stages, the solver's iterations), keeping nothing it made
    /// (a part, a drag's base); a result that is stale when it is ready is dropped.
    pub fn solver_loop(self: Arc<Self>) {
        let mut done = 0u64;
        loop {
            let cancel = Cancel::new();
            let (version, committed, dragged, light) = {
                let mut st = self.lock();
                while st.version <= done {
                    st = match self.changed.wait(st) {
                        Ok(g) => g,
                        Err(e) => e.into_inner(),
                    };
                }
                st.solving = Some(st.version);
                st.inflight = Some(cancel.clone());
                (st.version, st.edits.clone(), st.preview.clone(), st.light)
            };
            // A panic in the solve must not end the editor: it is reported like an error.
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                cancel.scope(|| {
                    let b = self.base_for(light)?;
                    match &dragged {
                        Some(d) => self.solve_drag(&b, &committed, d, version),
                        None => self.solve(&b, &committed, version),
                    }
                })
            }))
            .unwrap_or_else(|_| Err(Error::invalid_arg("solve", "the solver failed (panic)")));
            let mut st = self.lock();
            st.solving = None;
            st.inflight = None;
            done = version;
            if st.version == version {
                match result {
                    Ok(s) => {
                        let s = Arc::new(s);
                        st.recent.push(Arc::clone(&s));
                        if st.recent.len() > RECENT_KEPT {
                            st.recent.remove(0);
                        }
                        st.solved = Some(s);
                    }
                    Err(e) => st.error = Some((version, e.to_string())),
                }
            } else {
                st.dropped += 1;
            }
            drop(st);
            self.changed.notify_all();
        }
    }

    /// The strength range of a warp tool ([`crate::edit::warp::strength_range`]).
    pub fn strength_range(kind: WarpKind) -> (f64, f64) {
        crate::edit::warp::strength_range(kind)
    }
}
