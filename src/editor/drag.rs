//! The editor's drag step: what the drag steps on one prepared part reuse while only the last
//! edit changes, and one step's field, bit for bit the solve `grainline run` makes.

use std::sync::{Arc, Mutex};

use nalgebra::{Matrix2, Vector2, Vector3};

use crate::edit::{EditBase, EditOptions, EditResult, TermValues};
use crate::highlight::critical::critical_points;
use crate::pipeline::optimize::{
    edit_input, epsilon_before, key_direction, resolved_edits, solve_targets,
};
use crate::pipeline::Prepared;
use crate::scene::LoadedScene;
use crate::solve::{optimize_with, HighlightEnergy, HighlightTerm, OptimizeReuse};
use crate::Result;

/// What the editor's drag steps on one prepared part reuse while only the last edit changes
/// (issue 16): the committed edits applied ([`EditBase`]), the field before and its ε, the
/// critical points, the cotangent weights, the gradient stencil's users and the solver's term
/// of the committed edits. Made by [`DragBase::new`] once per drag; a step's work is then the
/// brush's and its margin's, not the part's (bend, expand and curve edits: [`EditBase::with_then`]).
pub struct DragBase {
    edits: EditBase,
    options: EditOptions,
    /// φ before the designed grain, h and G after the committed edits: a dragged edit that
    /// leaves them as they are (a warp, a curve) reuses ε and the critical points below.
    phi_before: Vec<f64>,
    h: Arc<Vec<Vector3<f64>>>,
    h_gradient: Option<Vec<Matrix2<f64>>>,
    epsilon: f64,
    critical: Arc<Vec<bool>>,
    /// The vertices where φ before of the kept edits' targets ([`EditBase::with_kept`]) is not
    /// `phi_before` (untangling of the committed edits): a step must list them all to keep ε.
    kept_differs: Vec<u32>,
    reuse: OptimizeReuse,
    /// The solver's term of the kept edits' targets, restated per step at the vertices the
    /// dragged edit changed and put back after.
    term: Mutex<Option<KeptTerm>>,
}

/// The entries of the kept edits' [`HighlightTerm`] for one energy and ε.
struct KeptTerm {
    energy: HighlightEnergy,
    epsilon: u64,
    target_q: Vec<Option<Vector2<f64>>>,
    weight: Vec<f64>,
    target_g: Vec<Option<f64>>,
    /// False while a step has restated entries (left so if it unwound: made again).
    clean: bool,
}

/// One drag step's field: what the page shows while the pointer moves.
pub struct DragStep {
    /// φ after the solve: bit for bit the one [`optimize_stage`](crate::pipeline::optimize::optimize_stage) finds for the same edits on
    /// the same part.
    pub phi: Vec<f64>,
    /// Half vectors of the lighting after the edits (the drag base's when the dragged edit
    /// leaves the light).
    pub h: Arc<Vec<Vector3<f64>>>,
    /// Critical points under that lighting.
    pub critical: Arc<Vec<bool>>,
    /// The key light after the edits (as [`OptimizeStageReport::key_light`](crate::pipeline::optimize::OptimizeStageReport::key_light)).
    pub key_light: [f64; 3],
    /// Vertices inside an edit's support.
    pub edited_vertices: usize,
    /// Why the solver stopped.
    pub stop: crate::solve::StopReason,
    /// The vertices whose edit targets the dragged edit changed (ascending; `None`: it may
    /// have changed any, as a light tool does).
    pub changed: Option<Vec<u32>>,
}

impl DragBase {
    /// Applies the `committed` scene's edits to `p` and keeps what the drag steps reuse.
    pub fn new(committed: &LoadedScene, p: &Prepared) -> Result<DragBase> {
        let settings = &committed.scene.solver;
        let options =
            EditOptions { outside_weight: settings.outside_weight, untangle: settings.untangle };
        let input = edit_input(p);
        let edits = EditBase::new(&input, &resolved_edits(committed), &options)
            .map_err(|e| crate::scene::prefix("edits", e))?;
        let er = edits.then(&input, &[], &options).map_err(|e| crate::scene::prefix("edits", e))?;
        let epsilon = epsilon_before(p, &er);
        let normals = p.field.geometry.frames.iter().map(|f| f.n);
        let critical = critical_points(&er.h, normals, p.field_options.critical_threshold);
        let g = &p.field.geometry;
        let cotan_weights =
            Arc::new(crate::geometry::laplacian::cotan_weights(&p.mesh, &g.adjacency));
        let kept_differs = edits
            .with_kept(&options, |k| {
                (0..er.phi_before.len() as u32)
                    .filter(|&i| k.phi_before[i as usize] != er.phi_before[i as usize])
                    .collect()
            })
            .unwrap_or_default();
        Ok(DragBase {
            edits,
            options,
            phi_before: er.phi_before,
            h: Arc::new(er.h),
            h_gradient: er.h_gradient,
            epsilon,
            critical: Arc::new(critical),
            kept_differs,
            reuse: OptimizeReuse {
                cotan_weights: Some(cotan_weights),
                whole_mesh_report: false,
                stencil_users: Some(Arc::new(g.stencil.users())),
                surface_area: Some(crate::solve::optimize::surface_area(g)),
            },
            term: Mutex::new(None),
        })
    }

    /// One drag step: the scene `s` holds the committed edits followed by `dragged` edits;
    /// only those are applied, and the solve skips the whole-mesh report (violations,
    /// singularities, fidelity: made when the drag ends, by [`optimize_stage`](crate::pipeline::optimize::optimize_stage)).
    pub fn step(&self, s: &LoadedScene, p: &Prepared, dragged: usize) -> Result<DragStep> {
        let edits = resolved_edits(s);
        let more = &edits[edits.len().saturating_sub(dragged)..];
        let energy = s.scene.solver.highlight_energy;
        self.keep_term(p, energy);
        self.edits
            .with_then(&edit_input(p), more, &self.options, |er, changed| {
                self.solve_step(s, p, er, changed)
            })
            .map_err(|e| crate::scene::prefix("edits", e))?
    }

    /// The step's solve on the targets `er`, which differ from the kept edits' at `changed`
    /// alone (`None`: anywhere).
    fn solve_step(
        &self,
        s: &LoadedScene,
        p: &Prepared,
        er: &EditResult,
        changed: Option<&[u32]>,
    ) -> Result<DragStep> {
        let same_field = match changed {
            // In place: the lighting is the kept one, and φ before differs from the kept
            // edits' at the changed vertices alone.
            Some(c) => {
                self.kept_differs.iter().all(|i| c.binary_search(i).is_ok())
                    && c.iter().all(|&i| er.phi_before[i as usize] == self.phi_before[i as usize])
            }
            None => {
                er.phi_before == self.phi_before
                    && er.h == *self.h
                    && er.h_gradient == self.h_gradient
            }
        };
        let epsilon = if same_field { self.epsilon } else { epsilon_before(p, er) };
        let solved = match changed {
            Some(c) if same_field => self.solve_kept(s, p, er, c, epsilon)?,
            _ => solve_targets(s, p, er, epsilon, &self.reuse)?,
        };
        let (h, critical) = if changed.is_some() || er.h == *self.h {
            (Arc::clone(&self.h), Arc::clone(&self.critical))
        } else {
            let normals = p.field.geometry.frames.iter().map(|f| f.n);
            let c = critical_points(&er.h, normals, p.field_options.critical_threshold);
            (Arc::new(er.h.clone()), Arc::new(c))
        };
        let l = key_direction(p, &er.lighting);
        Ok(DragStep {
            phi: solved.phi,
            edited_vertices: er.support.iter().filter(|&&s| s).count(),
            h,
            critical,
            key_light: [l.x, l.y, l.z],
            stop: solved.report.stop,
            changed: changed.map(<[u32]>::to_vec),
        })
    }

    /// Makes the kept edits' term for `energy` and the kept ε, unless it is kept (one lock at
    /// a time: a step holds the edits' and then the term's).
    fn keep_term(&self, p: &Prepared, energy: HighlightEnergy) {
        let eps = self.epsilon.to_bits();
        let fits = |k: &Option<KeptTerm>| {
            k.as_ref().is_some_and(|k| k.clean && k.energy == energy && k.epsilon == eps)
        };
        if fits(&self.term.lock().unwrap_or_else(|e| e.into_inner())) {
            return;
        }
        let made = self.edits.with_kept(&self.options, |r| {
            let g = &p.field.geometry;
            let (symmetry, form) = (p.field_options.symmetry, p.field_options.gradient_form);
            let t = r.highlight_term(g, symmetry, form, energy, self.epsilon);
            KeptTerm {
                energy,
                epsilon: eps,
                target_q: t.target_q,
                weight: t.weight,
                target_g: t.target_g,
                clean: true,
            }
        });
        *self.term.lock().unwrap_or_else(|e| e.into_inner()) = made;
    }

    /// [`solve_targets`] with the kept term restated at the `changed` vertices (ε the kept one).
    fn solve_kept(
        &self,
        s: &LoadedScene,
        p: &Prepared,
        er: &EditResult,
        changed: &[u32],
        epsilon: f64,
    ) -> Result<crate::solve::OptimizeResult> {
        let settings = &s.scene.solver;
        let energy = settings.highlight_energy;
        let mut guard = self.term.lock().unwrap_or_else(|e| e.into_inner());
        let kept = match guard.as_mut() {
            Some(k) if k.clean && k.energy == energy && k.epsilon == epsilon.to_bits() => k,
            _ => return solve_targets(s, p, er, epsilon, &self.reuse),
        };
        let g = &p.field.geometry;
        kept.clean = false;
        let mut undo: Vec<(u32, TermValues)> = Vec::with_capacity(changed.len());
        for &i in changed {
            let i = i as usize;
            undo.push((i as u32, (kept.target_q[i], kept.weight[i], kept.target_g[i])));
            (kept.target_q[i], kept.weight[i], kept.target_g[i]) =
                er.term_values(g, i, energy, epsilon);
        }
        let term = HighlightTerm {
            geometry: g,
            h: &er.h,
            symmetry: p.field_options.symmetry,
            form: p.field_options.gradient_form,
            epsilon,
            target_q: std::mem::take(&mut kept.target_q),
            weight: std::mem::take(&mut kept.weight),
            target_g: std::mem::take(&mut kept.target_g),
            h_gradient: er.h_gradient.as_deref(),
        };
        let solved = optimize_with(&p.mesh, &term, &er.phi, &er.support, settings, &self.reuse)
            .map_err(|e| crate::scene::prefix("solver", e));
        (kept.target_q, kept.weight, kept.target_g) = (term.target_q, term.weight, term.target_g);
        for (i, (q, w, tg)) in undo.into_iter().rev() {
            let i = i as usize;
            (kept.target_q[i], kept.weight[i], kept.target_g[i]) = (q, w, tg);
        }
        kept.clean = true;
        solved
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::optimize::optimize_stage;
    use crate::pipeline::{prepare, Silent, Stages};

    /// A cylinder brushed around and a scene holding `edits` (JSON), read from a temp dir.
    fn scene(name: &str, edits: &str) -> LoadedScene {
        let dir =
            std::env::temp_dir().join(format!("grainline-drag-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mesh = crate::generate::cylinder(30.0, 80.0, 48, 16);
        std::fs::write(dir.join("part.obj"), crate::mesh::write::obj_string(&mesh, "t")).unwrap();
        let text = format!(
            r#"{{"mesh": "part.obj", "view": {{"eye": [0, -300, 0]}},
                "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
                "field": {{"init": "uv", "symmetry": "line"}}, "edits": [{edits}]}}"#
        );
        std::fs::write(dir.join("scene.json"), text).unwrap();
        LoadedScene::read(&dir.join("scene.json")).unwrap()
    }

    const STENCIL: &str =
        r#"{"tool": "stencil", "centre": {"point": [25, -15, -25]}, "radius": 10}"#;

    fn bend(strength: f64) -> String {
        format!(
            r#"{{"tool": "bend", "centre": {{"point": [0, -30, 5]}}, "radius": 14,
                "strength": {strength}, "direction": [0, 0, 1]}}"#
        )
    }

    /// The editor's drag step (issue 16) is the solve `grainline run` makes: the same φ bit for
    /// bit, the same h and critical points, after committed edits that change φ (a stencil)
    /// and with the dragged bend at two strengths from one kept base.
    #[test]
    fn a_drag_step_is_bit_for_bit_the_full_stage() {
        let committed = scene("base", STENCIL);
        // Nothing is refined here (a coarse part would be refined for the bend): the drag and
        // the full stage run on one preparation, as they do in the editor.
        let mut bare = committed.clone();
        bare.scene.edits.clear();
        let p = prepare(&bare, &mut Stages::new(&Silent)).unwrap();
        let base = DragBase::new(&committed, &p).unwrap();
        // 0.3 again last: the kept state was put back after each step.
        for (k, strength) in [0.3, 0.8, 0.3].into_iter().enumerate() {
            let s = scene(&format!("step{k}"), &format!("{STENCIL}, {}", bend(strength)));
            let step = base.step(&s, &p, 1).unwrap();
            let full = optimize_stage(&s, &p, &mut Stages::new(&Silent)).unwrap();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&step.phi), bits(&full.phi), "strength {strength}");
            assert_eq!(*step.h, full.h);
            assert_eq!(*step.critical, full.critical);
            assert_eq!(step.edited_vertices, full.report.edited_vertices);
            assert_eq!(step.stop, full.report.solver.stop);
            assert_eq!(step.key_light, full.report.key_light);
            assert!(step.edited_vertices > 0);
            assert!(step.changed.is_some(), "a bend is applied in place");
        }
    }

    /// Edits applied in place ([`EditBase::with_then`]) give [`EditBase::then`]'s targets bit
    /// for bit, list every vertex where they differ from the kept ones, and leave the kept
    /// state as it was; a light edit goes through `then`.
    #[test]
    fn edits_in_place_are_then_bit_for_bit() {
        let committed = scene("inplace", &bend(0.4));
        let mut bare = committed.clone();
        bare.scene.edits.clear();
        let p = prepare(&bare, &mut Stages::new(&Silent)).unwrap();
        let base = DragBase::new(&committed, &p).unwrap();
        let input = edit_input(&p);
        let opts = &base.options;
        let kept = base.edits.then(&input, &[], opts).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let curve = r#"{"tool": "curve", "points": [[[30, 0, -10], [21, 21, 10]]], "radius": 6}"#;
        for more in [STENCIL.to_string(), bend(0.7), curve.to_string()] {
            let s = scene("inplace-more", &format!("{}, {more}", bend(0.4)));
            let edits = resolved_edits(&s);
            let more = &edits[1..];
            let then = base.edits.then(&input, more, opts).unwrap();
            let local = matches!(more[0], crate::edit::Edit::Bend(_) | crate::edit::Edit::Curve(_));
            base.edits
                .with_then(&input, more, opts, |r, changed| {
                    assert_eq!(changed.is_some(), local);
                    assert_eq!(bits(&r.phi), bits(&then.phi));
                    assert_eq!(bits(&r.phi_before), bits(&then.phi_before));
                    assert_eq!(r.h, then.h);
                    assert_eq!(r.target_ell, then.target_ell);
                    assert_eq!(bits(&r.weight), bits(&then.weight));
                    assert_eq!(r.target_g, then.target_g);
                    assert_eq!(bits(&r.weight_g), bits(&then.weight_g));
                    assert_eq!(r.support, then.support);
                    assert_eq!(r.reports, then.reports);
                    if let Some(c) = changed {
                        for i in (0..r.phi.len()).filter(|i| c.binary_search(&(*i as u32)).is_err())
                        {
                            assert_eq!(r.target_g[i], kept.target_g[i], "vertex {i} not listed");
                        }
                    }
                })
                .unwrap();
            let again = base.edits.then(&input, &[], opts).unwrap();
            assert_eq!(bits(&again.phi), bits(&kept.phi), "the kept state was put back");
            assert_eq!(again.target_g, kept.target_g);
            assert_eq!(again.support, kept.support);
        }
    }
}
