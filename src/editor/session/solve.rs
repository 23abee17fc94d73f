//! Solving for the page: the committed edits as `grainline run` solves them ([`Session::solve`]),
//! a drag step on the part prepared for the committed edits ([`Session::solve_drag`]), and
//! what the page is sent of a solved field — the grain, the key highlight's curves, FIELD.json
//! and the traced strokes, each made once when first asked for.

use std::sync::{Arc, OnceLock};
use std::time::Instant;

use crate::edit::Edit;
use crate::editor::drag::{DragBase, DragStep};
use crate::fidelity::{highlight_segments, EditFidelity};
use crate::pipeline::optimize::{
    field_file_angles, optimize_stage, optimized_field_file, Optimized,
};
use crate::pipeline::{Silent, Stages};
use crate::{Error, Result};

use super::page::PageField;
use super::{Base, Part, Session};

/// One solved field, ready for the page.
pub struct Solved {
    /// The state version it was computed for.
    pub version: u64,
    /// The scene (and key light) it was solved from.
    base: Arc<Base>,
    /// The part it was solved on (its mesh is the one the page must show it on).
    pub part: Arc<Part>,
    /// The edits solved.
    edits: Vec<Edit>,
    /// The edits' and the solver's result (`None` without edits, the initial field, and for a
    /// drag step, whose FIELD.json is made from `edits` when asked for).
    optimized: Option<Optimized>,
    /// FIELD.json, made when first asked for ([`Session::field_json`]).
    field_json: OnceLock<std::result::Result<Vec<u8>, String>>,
    /// The solved angles per vertex (the solver's own, before FIELD.json's round trip).
    phi: Vec<f64>,
    /// The strokes and the as-brushed grain, traced when first asked for ([`Session::traced`]).
    traced: OnceLock<std::result::Result<PageStrokes, String>>,
    /// The grain u per vertex (world space, unit), as FIELD.json's `u`.
    pub u: Vec<[f32; 3]>,
    /// The key light's highlight curves: segments of the zero set of g = hᵀu per triangle.
    pub segments: Vec<[f32; 6]>,
    /// Critical vertices (hᵀn above the threshold) of the solved field.
    pub critical: Vec<u32>,
    /// The key light after the edits (direction towards it).
    pub key_light: [f64; 3],
    /// The solver's stop reason (`none` without edits).
    pub stop: String,
    /// Did the bend / expand / curve edits land ([`crate::fidelity`]).
    pub fidelity: Vec<EditFidelity>,
    /// Vertices inside an edit's support.
    pub edited_vertices: usize,
    /// Seconds the solve took (targets, solve, grain, curves; FIELD.json is made later).
    pub seconds: f64,
}

/// The brush strokes traced on a solved field and the grain rebuilt from them
/// ([`Session::traced`]).
pub struct PageStrokes {
    /// Each stroke's points on the part (world space), in brushing order.
    pub strokes: Vec<Vec<[f32; 3]>>,
    /// The as-brushed grain per vertex (unit; the zero vector where no stroke passes).
    pub brushed_u: Vec<[f32; 3]>,
}

/// A field on a part: what the page is sent of it.
struct FieldOf<'a> {
    phi: &'a [f64],
    h: &'a [nalgebra::Vector3<f64>],
    critical: &'a [bool],
}

impl Solved {
    /// The solved angles per vertex (the solver's own, before FIELD.json's round trip).
    pub fn phi(&self) -> &[f64] {
        &self.phi
    }
}

impl Session {
    /// Solves the committed `edits` exactly as `grainline run` would solve a scene file holding
    /// them, on the part prepared for them ([`Session::part_for`]: refined inside their
    /// brushes): the grain, the highlight curves and the critical points for the page;
    /// FIELD.json is made from the same result when asked for ([`Session::field_json`]).
    pub fn solve(&self, b: &Arc<Base>, edits: &[Edit], version: u64) -> Result<Solved> {
        let start = Instant::now();
        let part = self.part_for(b, edits)?;
        self.solve_on(b, part, edits, version, start)
    }

    /// One drag step: the `committed` edits and the `dragged` one, solved on the part prepared
    /// for the committed edits alone (the dragged brush is refined when the drag ends and the
    /// edit is committed, [`Session::solve`]). Incremental ([`DragBase`]): the committed edits
    /// are applied once per drag and only the dragged one per step; the solve is the one
    /// `grainline run` makes for the same edits on the same part (the same φ, bit for bit),
    /// without its whole-mesh report (constraint violations, singularities, fidelity), which
    /// the commit's solve makes.
    pub fn solve_drag(
        &self,
        b: &Arc<Base>,
        committed: &[Edit],
        dragged: &Edit,
        version: u64,
    ) -> Result<Solved> {
        let start = Instant::now();
        let part = self.part_for(b, committed)?;
        let base = self.drag_base(b, &part, committed)?;
        let mut edits = committed.to_vec();
        edits.push(dragged.clone());
        let s = self.with_edits(b, &edits)?;
        let step = base.step(&s, &part.prepared, 1).map_err(|e| s.wrap(e))?;
        let (stop, key_light, edited) =
            (step.stop.to_string(), step.key_light, step.edited_vertices);
        let mut solved = self.drag_field(b, &part, step, version)?;
        solved.stop = stop;
        solved.key_light = key_light;
        solved.edited_vertices = edited;
        solved.edits = edits;
        solved.seconds = start.elapsed().as_secs_f64();
        solved.part = part;
        Ok(solved)
    }

    /// The drag steps' reusable state for `committed` on `part` (made once per drag).
    fn drag_base(&self, b: &Base, part: &Arc<Part>, committed: &[Edit]) -> Result<Arc<DragBase>> {
        if let Some((g, id, e, d)) = &*self.drag.lock().unwrap_or_else(|e| e.into_inner()) {
            if *g == b.gen && *id == part.id && e == committed {
                return Ok(Arc::clone(d));
            }
        }
        let s = self.with_edits(b, committed)?;
        let base = Arc::new(DragBase::new(&s, &part.prepared).map_err(|e| s.wrap(e))?);
        *self.drag.lock().unwrap_or_else(|e| e.into_inner()) =
            Some((b.gen, part.id, committed.to_vec(), Arc::clone(&base)));
        Ok(base)
    }

    /// The stages of `grainline run` after the preparation, on `part`.
    fn solve_on(
        &self,
        b: &Arc<Base>,
        part: Arc<Part>,
        edits: &[Edit],
        version: u64,
        start: Instant,
    ) -> Result<Solved> {
        let s = self.with_edits(b, edits)?;
        let p = &part.prepared;
        let (optimized, stop, key_light, fidelity, edited) = if s.scene.edits.is_empty() {
            let l = p.field_options.lighting.light;
            (None, "none".to_string(), [l.x, l.y, l.z], Vec::new(), 0)
        } else {
            let mut stages = Stages::new(&Silent);
            let o = optimize_stage(&s, p, &mut stages).map_err(|e| s.wrap(e))?;
            let r = &o.report;
            let (stop, key, fid, edited) =
                (r.solver.stop.to_string(), r.key_light, r.fidelity.clone(), r.edited_vertices);
            (Some(o), stop, key, fid, edited)
        };
        let field = match &optimized {
            Some(o) => FieldOf { phi: &o.phi, h: &o.h, critical: &o.critical },
            None => FieldOf { phi: &p.field.phi, h: &p.field.h, critical: &p.field.critical },
        };
        let mut solved = self.solved_field(b, &part, &field, version)?;
        solved.optimized = optimized;
        solved.stop = stop;
        solved.key_light = key_light;
        solved.fidelity = fidelity;
        solved.edited_vertices = edited;
        solved.edits = edits.to_vec();
        solved.seconds = start.elapsed().as_secs_f64();
        solved.part = part;
        Ok(solved)
    }

    /// [`Session::solved_field`] of a drag step, made from the previous step's where that was
    /// on the same part ([`page::PageField`]: the grain and the curves recomputed only around
    /// the vertices whose φ or h changed; the same bits).
    fn drag_field(
        &self,
        b: &Arc<Base>,
        part: &Arc<Part>,
        step: DragStep,
        version: u64,
    ) -> Result<Solved> {
        let p = &part.prepared;
        let (phi, h) = (&step.phi, &step.h);
        let mut kept = self.drag_page.lock().unwrap_or_else(|e| e.into_inner());
        let previous = kept.take().filter(|k| k.is_on(b.gen, part.id, phi.len()));
        let page = match previous {
            Some(mut k) => {
                if k.update(p, phi, h)? {
                    k
                } else {
                    PageField::new(b.gen, part.id, p, phi, h)?
                }
            }
            None => PageField::new(b.gen, part.id, p, phi, h)?,
        };
        let field = FieldOf { phi, h, critical: &step.critical };
        let (u, segments) = (page.u32s.clone(), page.segments());
        let mut solved = self.page_view(b, part, &field, version, u, segments);
        *kept = Some(page);
        solved.phi = step.phi;
        Ok(solved)
    }

    /// The page's view of a field on `part`: the grain, the key light's highlight curves, the
    /// critical vertices (the rest of [`Solved`] is the caller's to fill).
    fn solved_field(
        &self,
        b: &Arc<Base>,
        part: &Arc<Part>,
        f: &FieldOf,
        version: u64,
    ) -> Result<Solved> {
        let p = &part.prepared;
        let u = p.field.geometry.directions_of(f.phi);
        if let Some(i) = u.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(Error::invalid_arg(
                "solve",
                format!("the grain at vertex {i} is not finite"),
            ));
        }
        let segments = highlight_segments(&p.mesh, f.h, &u, p.field_options.symmetry)
            .iter()
            .map(|[a, b]| [a.x, a.y, a.z, b.x, b.y, b.z].map(|c| c as f32))
            .collect();
        let u = u.iter().map(|v| [v.x as f32, v.y as f32, v.z as f32]).collect();
        let mut solved = self.page_view(b, part, f, version, u, segments);
        solved.phi = f.phi.to_vec();
        Ok(solved)
    }

    /// A [`Solved`] of the grain `u` and the curves `segments` of the field `f`, without its
    /// angles (the caller's to move in).
    fn page_view(
        &self,
        b: &Arc<Base>,
        part: &Arc<Part>,
        f: &FieldOf,
        version: u64,
        u: Vec<[f32; 3]>,
        segments: Vec<[f32; 6]>,
    ) -> Solved {
        let critical =
            f.critical.iter().enumerate().filter(|(_, c)| **c).map(|(i, _)| i as u32).collect();
        Solved {
            version,
            base: Arc::clone(b),
            part: Arc::clone(part),
            edits: Vec::new(),
            optimized: None,
            field_json: OnceLock::new(),
            phi: Vec::new(),
            traced: OnceLock::new(),
            u,
            segments,
            critical,
            key_light: [0.0; 3],
            stop: String::new(),
            fidelity: Vec::new(),
            edited_vertices: 0,
            seconds: 0.0,
        }
    }

    /// FIELD.json of a solved field, exactly as `grainline run` writes it (`field.output`) for
    /// a scene file holding the same edits: [`optimized_field_file`] (or the initial field's
    /// file without edits) through [`crate::output::json_compact`]. Made once per result; work
    /// cancelled ([`crate::cancel`]: the page left) is not kept, and is made again when asked.
    pub fn field_json<'a>(&self, solved: &'a Solved) -> Result<&'a [u8]> {
        let made = match solved.field_json.get() {
            Some(m) => m,
            None => {
                let m = match self.make_field_json(solved) {
                    Err(e @ Error::Cancelled { .. }) => return Err(e),
                    m => m.map_err(|e| e.to_string()),
                };
                // Another request may have made it meanwhile: the same bytes.
                let _ = solved.field_json.set(m);
                solved.field_json.get().expect("set above")
            }
        };
        match made {
            Ok(b) => Ok(b.as_slice()),
            Err(e) => Err(Error::invalid_arg("field.json", e.clone())),
        }
    }

    fn make_field_json(&self, solved: &Solved) -> Result<Vec<u8>> {
        let p = &solved.part.prepared;
        let file = match (&solved.optimized, solved.edits.is_empty()) {
            (Some(o), _) => optimized_field_file(p, o),
            (None, true) => crate::pipeline::prepare::initial_field_file(p),
            // A drag step: the whole stage, as `grainline run` makes it, when asked for.
            (None, false) => self.with_edits(&solved.base, &solved.edits).and_then(|s| {
                let o = optimize_stage(&s, p, &mut Stages::new(&Silent))?;
                optimized_field_file(p, &o)
            }),
        };
        file.and_then(|f| crate::output::json_compact(&f))
    }

    /// The strokes `grainline run` traces for a solved field and the as-brushed grain rebuilt
    /// from them, through the run's own trace stage ([`crate::pipeline::trace::trace`]) on the angles the run
    /// traces (FIELD.json's, after a solve). Made once per result; a part without a UV layout
    /// is told the key to add.
    pub fn traced<'a>(&self, solved: &'a Solved) -> Result<&'a PageStrokes> {
        let made = match solved.traced.get() {
            Some(m) => m,
            None => {
                let m = match self.trace(solved) {
                    Err(e @ Error::Cancelled { .. }) => return Err(e),
                    m => m.map_err(|e| e.to_string()),
                };
                let _ = solved.traced.set(m);
                solved.traced.get().expect("set above")
            }
        };
        match made {
            Ok(t) => Ok(t),
            Err(e) => Err(Error::setting("toolpaths", e.clone())),
        }
    }

    fn trace(&self, solved: &Solved) -> Result<PageStrokes> {
        let p = &solved.part.prepared;
        if p.mesh.uv.is_none() {
            return Err(Error::setting(
                "toolpaths",
                format!(
                    "{} has no UV layout: add a `toolpaths` section to the scene (its `layout` \
                     makes one) to trace the strokes",
                    p.mesh_name
                ),
            ));
        }
        let s = self.with_edits(&solved.base, &solved.edits)?;
        let (g, symmetry) = (&p.field.geometry, p.field_options.symmetry);
        // As `grainline run`: the solved angles as FIELD.json states them, the initial as is.
        let phi = if solved.edits.is_empty() {
            solved.phi.clone()
        } else {
            field_file_angles(g, &solved.phi)
        };
        let input = crate::pipeline::trace::TraceInput {
            toolpaths: s.scene.toolpaths.as_ref(),
            constraints: &s.scene.solver.constraints,
            mesh: &p.mesh,
            geometry: g,
            phi: &phi,
            symmetry,
            keep_map: false,
            keep_field_mesh: true,
            surfaces: p.surfaces.as_ref(),
            straddle: &[],
        };
        let t = crate::pipeline::trace::trace(&input)?;
        let ab =
            t.as_brushed(&input)?.ok_or_else(|| Error::invalid_arg("trace", "no field mesh"))?;
        let job = t.job;
        let f32s = |v: &[f64; 3]| v.map(|c| c as f32);
        Ok(PageStrokes {
            strokes: job.strokes_3d.iter().map(|s| s.iter().map(f32s).collect()).collect(),
            brushed_u: ab.u.iter().map(f32s).collect(),
        })
    }
}
