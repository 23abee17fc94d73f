//! The edit and solve stages: targets from the scene's edits, then the sparse LM.

use nalgebra::{Matrix2, Vector3};
use serde::Serialize;

use super::{Prepared, Stages};
use crate::edit::{apply_edits, Edit, EditInput, EditOptions, EditReport, EditResult};
use crate::fidelity::{fidelity_of_edits, EditFidelity, FidelityOptions};
use crate::field::FieldFile;
use crate::highlight::critical::critical_points;
use crate::highlight::tensor::default_epsilon;
use crate::highlight::{highlight_field_near, HighlightField, Lighting};
use crate::scene::LoadedScene;
use crate::solve::{optimize_with, OptimizeReport, OptimizeReuse};
use crate::Result;

/// The field after the edits and the solve.
pub struct Optimized {
    /// φ after the solve.
    pub phi: Vec<f64>,
    /// φ after the edits' direct changes (stencils, and the grain the curve, bend and expand
    /// tools designed): the solve's start.
    pub phi_edited: Vec<f64>,
    /// φ the edits are measured from: the optimizer's input after the stencils, without the
    /// tools' designed grain ([`crate::fidelity`]'s field before).
    pub phi_before: Vec<f64>,
    /// The lighting after the light tools.
    pub lighting: Lighting,
    /// Half vectors of that lighting.
    pub h: Vec<Vector3<f64>>,
    /// The near term's G per vertex of that lighting (`None`: distant light and view).
    pub h_gradient: Option<Vec<Matrix2<f64>>>,
    /// ∇φ, m and ℓ of the solved field.
    pub highlight: HighlightField,
    /// Critical points under that lighting.
    pub critical: Vec<bool>,
    /// Target ℓ* per vertex.
    pub target_ell: Vec<Option<Vector3<f64>>>,
    /// Vertices inside an edit's support.
    pub support: Vec<bool>,
    /// What the edits and the solver did.
    pub report: OptimizeStageReport,
}

/// The edits' and the solver's report.
#[derive(Clone, Debug, Serialize)]
pub struct OptimizeStageReport {
    /// One entry per edit.
    pub edits: Vec<EditReport>,
    /// The key light after the edits (it differs from the scene's when a light tool ran); for
    /// a point light its nominal direction (`key_light_position` is the light).
    pub key_light: [f64; 3],
    /// The position of a point key light after the edits (absent for a distant light).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub key_light_position: Option<[f64; 3]>,
    /// Vertices inside an edit's support.
    pub edited_vertices: usize,
    /// The solver.
    pub solver: OptimizeReport,
    /// The refinement made for the edits before the field was computed (`mesh.refine`);
    /// absent when nothing was split.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refinement: Option<super::RefinementReport>,
    /// Did each edit land? One entry per bend, expand and curve edit: the key highlight of the
    /// solved field against the edit's target ([`crate::fidelity`]).
    pub fidelity: Vec<EditFidelity>,
}

/// The scene's edits with their file paths resolved (relative to the scene file).
pub(crate) fn resolved_edits(s: &LoadedScene) -> Vec<Edit> {
    s.scene
        .edits
        .iter()
        .map(|e| match e {
            Edit::Curve(c) if c.svg.is_some() => {
                let mut c = c.clone();
                c.svg = c.svg.clone().map(|p| s.input(&p).display().to_string());
                Edit::Curve(c)
            }
            other => other.clone(),
        })
        .collect()
}

/// The edit tools' input: the prepared part and its initial field.
pub(crate) fn edit_input(p: &Prepared) -> EditInput<'_> {
    EditInput {
        mesh: &p.mesh,
        geometry: &p.field.geometry,
        phi: &p.field.phi,
        lighting: &p.field_options.lighting,
        h: &p.field.h,
        symmetry: p.field_options.symmetry,
        gradient_form: p.field_options.gradient_form,
    }
}

/// The regularization ε of the tensor energy: [`default_epsilon`] of |m| of the field before
/// the solve (after the stencils, without the tools' designed grain) under the edits' lighting.
pub(crate) fn epsilon_before(p: &Prepared, er: &EditResult) -> f64 {
    let g = &p.field.geometry;
    let (symmetry, form) = (p.field_options.symmetry, p.field_options.gradient_form);
    let phi = &er.phi_before;
    let before = highlight_field_near(g, phi, symmetry, form, &er.h, er.h_gradient.as_deref());
    let m_norms: Vec<f64> = before.m.iter().map(|m| m.norm()).collect();
    default_epsilon(&m_norms)
}

/// The solve of [`optimize_stage`] on the edits' targets `er` with regularization `epsilon`.
pub(crate) fn solve_targets(
    s: &LoadedScene,
    p: &Prepared,
    er: &EditResult,
    epsilon: f64,
    reuse: &OptimizeReuse,
) -> Result<crate::solve::OptimizeResult> {
    let settings = &s.scene.solver;
    let g = &p.field.geometry;
    let (symmetry, form) = (p.field_options.symmetry, p.field_options.gradient_form);
    let term = er.highlight_term(g, symmetry, form, settings.highlight_energy, epsilon);
    optimize_with(&p.mesh, &term, &er.phi, &er.support, settings, reuse)
        .map_err(|e| crate::scene::prefix("solver", e))
}

/// The key light's direction after the edits (a point light's from the part's centre).
pub(crate) fn key_direction(p: &Prepared, lighting: &Lighting) -> Vector3<f64> {
    match lighting.light_position {
        None => lighting.light,
        Some(lp) => (lp - crate::highlight::lighting::centre_of(&p.mesh.positions))
            .try_normalize(0.0)
            .unwrap_or(lighting.light),
    }
}

/// Applies the edits and solves for φ.
pub fn optimize_stage(s: &LoadedScene, p: &Prepared, stages: &mut Stages) -> Result<Optimized> {
    stages.start("edits");
    let settings = &s.scene.solver;
    let edits = resolved_edits(s);
    let options =
        EditOptions { outside_weight: settings.outside_weight, untangle: settings.untangle };
    let er = apply_edits(&edit_input(p), &edits, &options)
        .map_err(|e| crate::scene::prefix("edits", e))?;
    stages.start("solve");
    crate::cancel::checkpoint("solve")?;
    let epsilon = epsilon_before(p, &er);
    let solved = solve_targets(s, p, &er, epsilon, &OptimizeReuse::default())?;
    crate::cancel::checkpoint("solve")?;
    finish_optimized(p, er, solved)
}

/// The whole-mesh results of a solve: ℓ after, the fidelity of the edits, the critical points.
fn finish_optimized(
    p: &Prepared,
    er: EditResult,
    solved: crate::solve::OptimizeResult,
) -> Result<Optimized> {
    let g = &p.field.geometry;
    let (symmetry, form) = (p.field_options.symmetry, p.field_options.gradient_form);
    let normals: Vec<Vector3<f64>> = g.frames.iter().map(|f| f.n).collect();
    let h = er.h.clone();
    let hg = er.h_gradient.clone();
    let highlight = highlight_field_near(g, &solved.phi, symmetry, form, &h, hg.as_deref());
    // The field before is the optimizer's input after the stencils (without the tools'
    // designed grain), under the key light.
    let fidelity = fidelity_of_edits(
        &p.mesh,
        g,
        &h,
        symmetry,
        &er.phi_before,
        &solved.phi,
        &er.reports,
        &FidelityOptions::default(),
    )?;
    let critical = critical_points(&h, normals.into_iter(), p.field_options.critical_threshold);
    let l = key_direction(p, &er.lighting);
    Ok(Optimized {
        phi: solved.phi,
        phi_edited: er.phi,
        phi_before: er.phi_before,
        lighting: er.lighting,
        h,
        h_gradient: hg.clone(),
        highlight,
        critical,
        target_ell: er.target_ell,
        support: er.support.clone(),
        report: OptimizeStageReport {
            edits: er.reports,
            key_light: [l.x, l.y, l.z],
            key_light_position: er.lighting.light_position.map(|p| [p.x, p.y, p.z]),
            edited_vertices: er.support.iter().filter(|&&s| s).count(),
            solver: solved.report,
            refinement: p.refinement.clone(),
            fidelity,
        },
    })
}

/// Angles `phi` as FIELD.json states them: u = direction(φ) in each vertex's frame, read back
/// by atan2 — the angles a run given the written file (`--field`) traces, so that tracing the
/// solved field and tracing its FIELD.json give the same outputs bit for bit (the solver's own
/// φ may differ from them by whole turns, and cos/sin of φ + 2π by an ulp).
pub fn field_file_angles(geometry: &crate::geometry::Geometry, phi: &[f64]) -> Vec<f64> {
    geometry.angles_of(&geometry.directions_of(phi))
}

/// FIELD.json of an optimized field: the `field` format plus `phi_before`, `u_before`,
/// `phi` and `target_ell`.
pub fn optimized_field_file(p: &Prepared, o: &Optimized) -> Result<FieldFile> {
    let mut options = p.field_options.clone();
    options.lighting = o.lighting;
    let result = crate::field::FieldResult {
        geometry: p.field.geometry.clone(),
        phi: o.phi.clone(),
        h: o.h.clone(),
        h_gradient: o.h_gradient.clone(),
        highlight: o.highlight.clone(),
        critical: o.critical.clone(),
        fallback_vertices: p.field.fallback_vertices.clone(),
    };
    let mut file = FieldFile::new(&p.mesh, &p.mesh_name, &options, &result)?;
    let arr = |v: &Vector3<f64>| [v.x, v.y, v.z];
    file.phi_before = Some(p.field.phi.clone());
    file.u_before = Some(p.field.geometry.directions_of(&p.field.phi).iter().map(arr).collect());
    file.phi = Some(o.phi.clone());
    file.target_ell = Some(o.target_ell.iter().map(|t| t.as_ref().map(arr)).collect());
    file.patch_copies = p.patches.as_ref().map(|r| r.copies_of.clone());
    file.surfaces = p.surfaces.as_ref().map(|r| r.report.clone());
    file.check_finite()?;
    Ok(file)
}
