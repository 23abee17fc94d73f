//! The editor's drag step: what the drag steps on one prepared part reuse while only the last
//! edit changes, and one step's field, bit for bit the solve `grainline run` makes.

use nalgebra::{Matrix2, Vector3};

use crate::edit::{EditBase, EditOptions};
use crate::highlight::critical::critical_points;
use crate::pipeline::optimize::{
    edit_input, epsilon_before, key_direction, resolved_edits, solve_targets,
};
use crate::pipeline::Prepared;
use crate::scene::LoadedScene;
use crate::solve::OptimizeReuse;
use crate::Result;

/// What the editor's drag steps on one prepared part reuse while only the last edit changes
/// (issue 16): the committed edits applied ([`EditBase`]), the field before and its ε, the
/// critical points, the cotangent weights. Made by [`DragBase::new`] once per drag.
pub struct DragBase {
    edits: EditBase,
    options: EditOptions,
    /// φ before the designed grain, h and G after the committed edits: a dragged edit that
    /// leaves them as they are (a warp, a curve) reuses ε and the critical points below.
    phi_before: Vec<f64>,
    h: Vec<Vector3<f64>>,
    h_gradient: Option<Vec<Matrix2<f64>>>,
    epsilon: f64,
    critical: Vec<bool>,
    cotan_weights: std::sync::Arc<Vec<f64>>,
}

/// One drag step's field: what the page shows while the pointer moves.
pub struct DragStep {
    /// φ after the solve: bit for bit the one [`optimize_stage`](crate::pipeline::optimize::optimize_stage) finds for the same edits on
    /// the same part.
    pub phi: Vec<f64>,
    /// Half vectors of the lighting after the edits.
    pub h: Vec<Vector3<f64>>,
    /// Critical points under that lighting.
    pub critical: Vec<bool>,
    /// The key light after the edits (as [`OptimizeStageReport::key_light`](crate::pipeline::optimize::OptimizeStageReport::key_light)).
    pub key_light: [f64; 3],
    /// Vertices inside an edit's support.
    pub edited_vertices: usize,
    /// Why the solver stopped.
    pub stop: crate::solve::StopReason,
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
            std::sync::Arc::new(crate::geometry::laplacian::cotan_weights(&p.mesh, &g.adjacency));
        Ok(DragBase {
            edits,
            options,
            phi_before: er.phi_before,
            h: er.h,
            h_gradient: er.h_gradient,
            epsilon,
            critical,
            cotan_weights,
        })
    }

    /// One drag step: the scene `s` holds the committed edits followed by `dragged` edits;
    /// only those are applied, and the solve skips the whole-mesh report (violations,
    /// singularities, fidelity: made when the drag ends, by [`optimize_stage`](crate::pipeline::optimize::optimize_stage)).
    pub fn step(&self, s: &LoadedScene, p: &Prepared, dragged: usize) -> Result<DragStep> {
        let edits = resolved_edits(s);
        let more = &edits[edits.len().saturating_sub(dragged)..];
        let er = self
            .edits
            .then(&edit_input(p), more, &self.options)
            .map_err(|e| crate::scene::prefix("edits", e))?;
        let same_field =
            er.phi_before == self.phi_before && er.h == self.h && er.h_gradient == self.h_gradient;
        let epsilon = if same_field { self.epsilon } else { epsilon_before(p, &er) };
        let reuse = OptimizeReuse {
            cotan_weights: Some(self.cotan_weights.clone()),
            whole_mesh_report: false,
        };
        let solved = solve_targets(s, p, &er, epsilon, &reuse)?;
        let critical = if er.h == self.h {
            self.critical.clone()
        } else {
            let normals = p.field.geometry.frames.iter().map(|f| f.n);
            critical_points(&er.h, normals, p.field_options.critical_threshold)
        };
        let l = key_direction(p, &er.lighting);
        Ok(DragStep {
            phi: solved.phi,
            edited_vertices: er.support.iter().filter(|&&s| s).count(),
            h: er.h,
            critical,
            key_light: [l.x, l.y, l.z],
            stop: solved.report.stop,
        })
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
        for (k, strength) in [0.3, 0.8].into_iter().enumerate() {
            let s = scene(&format!("step{k}"), &format!("{STENCIL}, {}", bend(strength)));
            let step = base.step(&s, &p, 1).unwrap();
            let full = optimize_stage(&s, &p, &mut Stages::new(&Silent)).unwrap();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&step.phi), bits(&full.phi), "strength {strength}");
            assert_eq!(step.h, full.h);
            assert_eq!(step.critical, full.critical);
            assert_eq!(step.edited_vertices, full.report.edited_vertices);
            assert_eq!(step.stop, full.report.solver.stop);
            assert_eq!(step.key_light, full.report.key_light);
            assert!(step.edited_vertices > 0);
        }
    }
}
