//! Highlight-editing tools (the paper's §5; docs/math.md, "Editing tools"): they turn a designer's gesture into
//! target highlight tangents ℓ*ᵢ (and, for the stencil, a new grain field; for the light tool, a
//! new light) for the optimizer of [`crate::solve`].
//!
//! Every brush tool acts on a support B — the vertices within a radius of a centre — with the
//! planar parametrization of a plane fitted to B, scaled so that B lies in the unit disk, and the
//! fall-off w(x, y) = (1 − x² − y²)² ([`support`]). The tools:
//!
//! - **bend / expand** ([`warp`]): ℓ*ᵢ = J_W(q) ℓ_q with q = W⁻¹(pᵢ), which moves the potential
//!   highlight curves through B by the warp W;
//! - **stencil** ([`stencil`]): u*ᵢ = ±h × nᵢ inside B (a highlight *region*), blended into the
//!   surrounding field by a connection-Laplacian solve;
//! - **light** and **move_light** ([`light`]): the light that produces a wanted ℓ at a vertex
//!   with the current field; or a new key light with the old highlights as targets;
//! - **curve** ([`curve`], beyond the paper): designer-drawn curves (UV polylines, an SVG file, or
//!   3D polylines) whose tangents become the targets of the vertices near them.
//!
//! Edits apply in order; each one reads the targets left by the ones before it (a bend after a
//! bend composes the two warps). Vertices outside every edit keep their current ℓ as target, with
//! weight [`EditOptions::outside_weight`].

// `!(x > 0.0)` is how the tools reject NaN along with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod chart;
pub mod curve;
mod kept;
pub mod light;
pub mod resolution;
mod segment_grid;
pub mod shape;
pub mod stencil;
pub mod support;
pub mod untangle;
pub mod uv_lift;
pub mod warp;

use nalgebra::{Matrix2, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::geometry::{Geometry, GradientForm};
use crate::highlight::critical::{critical_points, DEFAULT_CRITICAL_THRESHOLD};
use crate::highlight::{h_gradients, half_vectors, highlight_field_near, Lighting, Symmetry};
use crate::mesh::{Mesh, VertexFaces};
use crate::{Error, Result};

pub use curve::CurveEdit;
pub use light::{LightEdit, MoveLightEdit};
pub use stencil::StencilEdit;
pub use support::{Centre, Metric};
pub use warp::{WarpEdit, WarpKind};

/// What the tools edit: the surface, the current field and lighting.
#[derive(Clone, Copy, Debug)]
pub struct EditInput<'a> {
    /// The surface.
    pub mesh: &'a Mesh,
    /// Its per-vertex geometry.
    pub geometry: &'a Geometry,
    /// The current grain angle per vertex (in the geometry's frames).
    pub phi: &'a [f64],
    /// The current light and view.
    pub lighting: &'a Lighting,
    /// The half vectors of `lighting` at every vertex.
    pub h: &'a [Vector3<f64>],
    /// k = 1 or 2.
    pub symmetry: Symmetry,
    /// Which Eq. 10 regression computes ∇φ.
    pub gradient_form: GradientForm,
}

/// Options of [`apply_edits`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct EditOptions {
    /// Weight of the "keep the current ℓ" targets of the vertices outside every edit
    /// (default 1; 0 leaves them without a target).
    pub outside_weight: f64,
    /// Untangle the designed grain where it turns by more than a right angle within a triangle
    /// ([`untangle`]; default true).
    pub untangle: bool,
}

impl Default for EditOptions {
    fn default() -> Self {
        EditOptions { outside_weight: 1.0, untangle: true }
    }
}

impl EditOptions {
    /// Range-checks the options.
    pub fn validate(&self) -> Result<()> {
        check_weight("outside_weight", self.outside_weight)
    }
}

/// One item of the scene's `edits` list: `{"tool": "bend", ...}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "tool", rename_all = "snake_case")]
pub enum Edit {
    /// Bend the highlights through the brush towards its +y direction (paper §5, Fig. 8).
    Bend(WarpEdit),
    /// Push the highlights through the brush away from its x axis (paper §5, Fig. 9).
    Expand(WarpEdit),
    /// Make the brush a highlight region: u ⟂ h (paper §5, Fig. 11).
    Stencil(StencilEdit),
    /// Find the light that gives a wanted ℓ at a vertex with the current field (paper §5, Fig. 10).
    Light(LightEdit),
    /// Move the key light and keep the current highlights as targets (paper §5, Fig. 10).
    MoveLight(MoveLightEdit),
    /// Highlight curves drawn by the designer (UV polylines, SVG or 3D polylines).
    Curve(CurveEdit),
}

impl Edit {
    /// The tool's name as written in the scene.
    pub fn tool(&self) -> &'static str {
        match self {
            Edit::Bend(_) => "bend",
            Edit::Expand(_) => "expand",
            Edit::Stencil(_) => "stencil",
            Edit::Light(_) => "light",
            Edit::MoveLight(_) => "move_light",
            Edit::Curve(_) => "curve",
        }
    }

    /// Range-checks every number; error keys are relative to the edit (`radius`, `centre.point`).
    pub fn validate(&self) -> Result<()> {
        match self {
            Edit::Bend(e) => e.validate(WarpKind::Bend),
            Edit::Expand(e) => e.validate(WarpKind::Expand),
            Edit::Stencil(e) => e.validate(),
            Edit::Light(e) => e.validate(),
            Edit::MoveLight(e) => e.validate(),
            Edit::Curve(e) => e.validate(),
        }
    }
}

/// Validates a list of edits; error keys are `[k].key` (the scene loader adds `edits`).
pub fn validate_edits(edits: &[Edit]) -> Result<()> {
    let max = crate::limits::MAX_EDITS;
    if edits.len() > max {
        return Err(Error::setting(
            "",
            format!("lists {} edits, more than the {max} a scene may have", edits.len()),
        ));
    }
    for (k, e) in edits.iter().enumerate() {
        e.validate().map_err(|err| at_edit(k, e.tool(), err))?;
    }
    Ok(())
}

/// What [`apply_edits`] produces: the inputs of the optimizer.
#[derive(Clone, Debug)]
pub struct EditResult {
    /// The grain angles after the stencils, with the grain the curve, bend and expand tools
    /// designed inside their supports (docs/math.md §9): the optimizer's starting field.
    pub phi: Vec<f64>,
    /// The grain angles after the stencils alone: the field the edits' fidelity figures
    /// compare against (`phi` without the designed grain).
    pub phi_before: Vec<f64>,
    /// The lighting after the light tools.
    pub lighting: Lighting,
    /// The half vectors of `lighting`.
    pub h: Vec<Vector3<f64>>,
    /// The near term's G per vertex for `lighting` (`None` when the light and view are both
    /// distant): [`crate::highlight::h_gradients`].
    pub h_gradient: Option<Vec<Matrix2<f64>>>,
    /// World-space target tangent ℓ*ᵢ (in the tangent plane of vertex i, not normalized);
    /// `None` where the vertex has no target (weight 0, or a critical point, where ℓ does not
    /// depend on the field).
    pub target_ell: Vec<Option<Vector3<f64>>>,
    /// Weight of each target (0 where `target_ell` is `None`).
    pub weight: Vec<f64>,
    /// The position target ĝ*ᵢ (docs/math.md §9): the cosine between the grain and the tangent
    /// part of h that vertex i should have, in the orientation of `phi[i]`; `None` exactly where
    /// `None` at critical points and where the position weight is 0.
    pub target_g: Vec<Option<f64>>,
    /// Weight of each position target (0 where `target_g` is `None`).
    pub weight_g: Vec<f64>,
    /// Inside the support of some edit (the vertices the optimizer should free).
    pub support: Vec<bool>,
    /// One report per edit.
    pub reports: Vec<EditReport>,
}

/// What one edit did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct EditReport {
    /// Position in the `edits` list.
    pub index: usize,
    /// The tool's name.
    pub tool: String,
    /// Vertices that received a target (or, for the light tools, the vertices of the search).
    pub vertices: usize,
    /// Critical points (hᵀn above the threshold) inside the support: left without a target.
    pub critical_vertices: usize,
    /// Warps: the largest angle between ℓ* and the ℓ it replaced, degrees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_turn_deg: Option<f64>,
    /// Stencil: vertices of the blend band around the support.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blend_vertices: Option<usize>,
    /// Stencil: the largest |hᵀu| inside the support after the edit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_h_dot_u: Option<f64>,
    /// Light tools: the vertex of the search (light) or none (move_light).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertex: Option<usize>,
    /// Light tools: the new light direction (unit, towards the light; for a point light, from
    /// the searched vertex).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light: Option<[f64; 3]>,
    /// Light tool with a point key light: the new light's position (it keeps its distance from
    /// the searched vertex).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_position: Option<[f64; 3]>,
    /// Light tool: the angle (mod π) between the wanted ℓ and the ℓ the new light produces,
    /// degrees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_error_deg: Option<f64>,
    /// Light tools: the angle between the old and the new light, degrees.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_turn_deg: Option<f64>,
    /// move_light: the median angle (mod π) between ℓ under the old and the new light before
    /// re-optimization, degrees: how far the highlights would move if the field were kept.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub median_ell_change_deg: Option<f64>,
    /// Curve: the number of polylines and of their segments.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub polylines: Option<usize>,
    /// Curve: segments after flattening.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub segments: Option<usize>,
    /// What may keep the edit from doing what it asks (the CLI prints them as warnings):
    /// critical points in the support, a warp reaching beyond the part's boundary.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// What the edit asked for (bend, expand, curve), for [`crate::fidelity`].
    #[serde(skip)]
    pub shape: Option<shape::EditShape>,
}

impl EditReport {
    fn new(index: usize, tool: &str) -> Self {
        EditReport { index, tool: tool.into(), ..Default::default() }
    }
}

/// Applies `edits` in order and returns the optimizer's targets.
///
/// Errors: an invalid edit (`[k].key`), an edit whose support holds no vertex, a warp that cannot
/// be inverted, a light tool with no admissible light, a curve tool without UVs.
pub fn apply_edits(input: &EditInput, edits: &[Edit], options: &EditOptions) -> Result<EditResult> {
    EditBase::new(input, edits, options)?.finish_with(input, &[], options)
}

/// Edits applied and kept, ready for more: the state [`apply_edits`] reaches after a prefix of
/// its list. The editor keeps one for the committed edits and applies only the dragged one per
/// drag step ([`EditBase::then`]); the result is bit for bit the one [`apply_edits`] gives for
/// the whole list, since it runs the same steps on the same state.
pub struct EditBase {
    tables: Tables,
    /// The kept edits' state ([`EditBase::with_then`] applies more in place and puts it back).
    work: std::sync::Mutex<kept::Work>,
    reports: Vec<EditReport>,
}

/// What the tools look up on the mesh, made once per [`EditBase`].
struct Tables {
    vf: VertexFaces,
    normals: Vec<Vector3<f64>>,
    /// Brush centres found on the surface (a dragged brush keeps its centre).
    centres: support::CentreMemo,
}

impl EditBase {
    /// Applies `edits` to `input` (the errors of [`apply_edits`]).
    pub fn new(input: &EditInput, edits: &[Edit], options: &EditOptions) -> Result<EditBase> {
        options.validate()?;
        validate_edits(edits)?;
        let n = input.mesh.num_vertices();
        if input.geometry.num_vertices() != n || input.phi.len() != n || input.h.len() != n {
            return Err(Error::invalid_arg(
                "edit input",
                format!(
                    "{} vertices, but geometry {}, phi {}, h {}",
                    n,
                    input.geometry.num_vertices(),
                    input.phi.len(),
                    input.h.len()
                ),
            ));
        }
        let tables = Tables {
            vf: VertexFaces::new(input.mesh),
            normals: input.geometry.frames.iter().map(|f| f.n).collect(),
            centres: Default::default(),
        };
        let ctx = Context::new(input, &tables);
        let mut state = State::new(&ctx, input);
        let reports = apply_in_order(&ctx, &mut state, edits, 0)?;
        Ok(EditBase { tables, work: std::sync::Mutex::new(kept::Work::new(state)), reports })
    }

    /// The targets of the kept edits followed by `more`, for the same `input` as
    /// [`EditBase::new`]'s (the state is copied; the kept one is left as it was).
    pub fn then(
        &self,
        input: &EditInput,
        more: &[Edit],
        options: &EditOptions,
    ) -> Result<EditResult> {
        let first = self.reports.len();
        for (j, e) in more.iter().enumerate() {
            e.validate().map_err(|err| at_edit(first + j, e.tool(), err))?;
        }
        self.finish_with(input, more, options)
    }

    fn finish_with(
        &self,
        input: &EditInput,
        more: &[Edit],
        options: &EditOptions,
    ) -> Result<EditResult> {
        let ctx = Context::new(input, &self.tables);
        let mut state = self.work.lock().unwrap_or_else(|e| e.into_inner()).state.clone();
        let mut reports = self.reports.clone();
        reports.extend(apply_in_order(&ctx, &mut state, more, self.reports.len())?);
        if options.untangle {
            untangle_noted(&ctx, &mut state, &mut reports);
        }
        state.finish(options, reports)
    }
}

/// Untangles the designed grain of `st` ([`untangle`]), noting in the last report what it
/// could not untangle.
fn untangle_noted(ctx: &Context, st: &mut State, reports: &mut [EditReport]) {
    let u = untangle::untangle(ctx, st);
    if let (Some(last), true) = (reports.last_mut(), u.singular_designed > 0) {
        last.notes.push(format!(
            "the designed grain turned by more than a right angle within {} triangles \
             (critical points of the key light close together, as on skin folds finer \
             than the brush); untangling turned {} vertices and left {} of them \
             (docs/math.md §10, \"Untangling\")",
            u.singular_designed, u.vertices_turned, u.singular_left
        ));
    }
}

/// Applies `edits` (indices from `first` in the whole list) to `st`, in order.
fn apply_in_order(
    ctx: &Context,
    st: &mut State,
    edits: &[Edit],
    first: usize,
) -> Result<Vec<EditReport>> {
    let mut reports = Vec::with_capacity(edits.len());
    for (j, e) in edits.iter().enumerate() {
        crate::cancel::checkpoint("edits")?;
        let k = first + j;
        let mut report = EditReport::new(k, e.tool());
        let r = match e {
            Edit::Bend(w) => warp::apply(ctx, st, w, WarpKind::Bend, &mut report),
            Edit::Expand(w) => warp::apply(ctx, st, w, WarpKind::Expand, &mut report),
            Edit::Stencil(s) => stencil::apply(ctx, st, s, &mut report),
            Edit::Light(l) => light::apply(ctx, st, l, &mut report),
            Edit::MoveLight(l) => light::apply_move(ctx, st, l, &mut report),
            Edit::Curve(c) => curve::apply(ctx, st, c, &mut report),
        };
        r.map_err(|err| at_edit(k, e.tool(), err))?;
        reports.push(report);
    }
    Ok(reports)
}

impl EditResult {
    /// The optimizer's data term for these targets: the position energy (ĝ*, `weight_g`) or the
    /// paper's tensor energy (q(ℓ̄*) with regularization `epsilon`, `weight`), under the half
    /// vectors after the light tools.
    pub fn highlight_term<'a>(
        &'a self,
        geometry: &'a Geometry,
        symmetry: Symmetry,
        form: GradientForm,
        energy: crate::solve::HighlightEnergy,
        epsilon: f64,
    ) -> crate::solve::HighlightTerm<'a> {
        let n = self.weight.len();
        let base = crate::solve::HighlightTerm {
            geometry,
            h: &self.h,
            symmetry,
            form,
            epsilon,
            target_q: vec![None; n],
            weight: vec![0.0; n],
            target_g: vec![None; n],
            // A point eye or light: ℓ has the near term (∇h)ᵀu (docs/math.md §2.1).
            h_gradient: self.h_gradient.as_deref(),
        };
        match energy {
            crate::solve::HighlightEnergy::Tensor => crate::solve::HighlightTerm {
                target_q: target_q(geometry, &self.target_ell, epsilon),
                weight: self.weight.clone(),
                ..base
            },
            crate::solve::HighlightEnergy::Position => crate::solve::HighlightTerm {
                weight: self.weight_g.clone(),
                target_g: self.target_g.clone(),
                ..base
            },
        }
    }
}

/// One vertex's entries of a [`crate::solve::HighlightTerm`]: its `target_q`, `weight` and
/// `target_g`.
pub type TermValues = (Option<Vector2<f64>>, f64, Option<f64>);

impl EditResult {
    /// Vertex `i`'s entries of the term [`EditResult::highlight_term`] makes with `energy` and
    /// `epsilon` (the same bits).
    pub fn term_values(
        &self,
        geometry: &Geometry,
        i: usize,
        energy: crate::solve::HighlightEnergy,
        epsilon: f64,
    ) -> TermValues {
        match energy {
            crate::solve::HighlightEnergy::Tensor => {
                let f = &geometry.frames[i];
                let q = self.target_ell[i]
                    .map(|l| crate::highlight::tensor::q(&f.to_local(&l), epsilon));
                (q, self.weight[i], None)
            }
            crate::solve::HighlightEnergy::Position => (None, self.weight_g[i], self.target_g[i]),
        }
    }
}

/// The targets q(ℓ̄*ᵢ) of [`crate::solve::HighlightTerm::target_q`]: ℓ* in the frame of vertex
/// i (ℓ̄* = [tᵢ bᵢ]ᵀℓ*) through the regularized tensor of [`crate::highlight::tensor::q`].
pub fn target_q(
    geometry: &Geometry,
    target_ell: &[Option<Vector3<f64>>],
    epsilon: f64,
) -> Vec<Option<Vector2<f64>>> {
    geometry
        .frames
        .iter()
        .zip(target_ell)
        .map(|(f, t)| t.map(|l| crate::highlight::tensor::q(&f.to_local(&l), epsilon)))
        .collect()
}

/// Read-only data shared by the tools.
pub(crate) struct Context<'a> {
    pub mesh: &'a Mesh,
    pub geom: &'a Geometry,
    pub symmetry: Symmetry,
    pub form: GradientForm,
    pub vf: &'a VertexFaces,
    pub normals: &'a [Vector3<f64>],
    pub centres: &'a support::CentreMemo,
}

impl<'a> Context<'a> {
    fn new(input: &EditInput<'a>, tables: &'a Tables) -> Self {
        Context {
            mesh: input.mesh,
            geom: input.geometry,
            symmetry: input.symmetry,
            form: input.gradient_form,
            vf: &tables.vf,
            normals: &tables.normals,
            centres: &tables.centres,
        }
    }

    /// ℓ of the field `phi` under half vectors `h` and near-term matrices `g` (Eq. 7 and
    /// docs/math.md §2.1).
    pub fn ell_of(
        &self,
        phi: &[f64],
        h: &[Vector3<f64>],
        g: Option<&[Matrix2<f64>]>,
    ) -> Vec<Vector3<f64>> {
        highlight_field_near(self.geom, phi, self.symmetry, self.form, h, g).ell
    }

    /// ĝ = h̄ᵀū/|h̄| of the field `phi` under `h` (docs/math.md §9; 0 where h̄ = 0).
    pub fn g_of(&self, phi: &[f64], h: &[Vector3<f64>]) -> Vec<f64> {
        self.geom.frames.iter().zip(phi).zip(h).map(|((f, &p), h)| g_hat(f, p, h)).collect()
    }

    /// The grain direction of vertex `i` for the field `phi`.
    pub fn grain(&self, phi: &[f64], i: usize) -> Vector3<f64> {
        self.geom.frames[i].direction(phi[i])
    }
}

/// The state the edits transform, in order.
#[derive(Clone)]
pub(crate) struct State {
    pub phi: Vec<f64>,
    pub lighting: Lighting,
    pub h: Vec<Vector3<f64>>,
    /// The near term's G of `lighting` (`None`: distant light and view).
    pub h_gradient: Option<Vec<Matrix2<f64>>>,
    /// ℓ of `phi` under `lighting` (the "current" ℓ).
    pub ell: Vec<Vector3<f64>>,
    /// hᵀn above the critical threshold.
    pub critical: Vec<bool>,
    /// The target field so far.
    pub target: Vec<Vector3<f64>>,
    /// ĝ = h̄ᵀū/|h̄| of `phi` under `h` (the "current" position value; 0 at h̄ = 0).
    pub g: Vec<f64>,
    /// The position target so far (docs/math.md §9), in the orientation of `phi`.
    pub target_g: Vec<f64>,
    /// Weight of an edit's target; `None` where no edit has set one yet.
    pub edit_weight: Vec<Option<f64>>,
    /// Weight of an edit's position target; `None` where no edit has set one yet.
    pub edit_weight_g: Vec<Option<f64>>,
    /// Inside some edit's support.
    pub support: Vec<bool>,
    /// Set by move_light: the untargeted vertices keep the old light's ℓ from then on.
    pub pinned: bool,
    /// The angle a vertex had before an edit designed its grain (`None`: not designed).
    pub designed: Vec<Option<f64>>,
    /// While edits are applied in place ([`kept`]): each written vertex's values from before
    /// the write, in order (a vertex may repeat; put back in reverse order).
    pub undo: Option<Vec<(u32, kept::VertexValues)>>,
}

impl State {
    fn new(ctx: &Context, input: &EditInput) -> Self {
        let h_gradient = h_gradients(input.lighting, &ctx.mesh.positions, &ctx.geom.frames);
        let ell = ctx.ell_of(input.phi, input.h, h_gradient.as_deref());
        let g = ctx.g_of(input.phi, input.h);
        let n = ell.len();
        State {
            target_g: g.clone(),
            g,
            phi: input.phi.to_vec(),
            lighting: *input.lighting,
            h: input.h.to_vec(),
            h_gradient,
            critical: critical_points(
                input.h,
                ctx.normals.iter().copied(),
                DEFAULT_CRITICAL_THRESHOLD,
            ),
            target: ell.clone(),
            ell,
            edit_weight: vec![None; n],
            edit_weight_g: vec![None; n],
            support: vec![false; n],
            pinned: false,
            designed: vec![None; n],
            undo: None,
        }
    }

    /// Notes vertex `i`'s values in the undo log (when applying in place) before a write.
    fn touch(&mut self, i: usize) {
        if let Some(mut log) = self.undo.take() {
            log.push((i as u32, kept::VertexValues::of(self, i)));
            self.undo = Some(log);
        }
    }

    /// Sets vertex `i`'s grain angle (not a design: see [`State::design`]).
    pub fn set_phi(&mut self, i: usize, phi: f64) {
        self.touch(i);
        self.phi[i] = phi;
    }

    /// Sets vertex `i`'s position target without changing its weight.
    pub fn set_g_target(&mut self, i: usize, g: f64) {
        self.touch(i);
        self.target_g[i] = g;
    }

    /// Puts vertex `i` inside an edit's support.
    pub fn set_support(&mut self, i: usize) {
        self.touch(i);
        self.support[i] = true;
    }

    /// Recomputes h, ℓ and the critical points after φ or the lighting changed, and refreshes
    /// the "keep current" targets of the vertices no edit has set (unless pinned).
    pub fn refresh(&mut self, ctx: &Context, lighting_changed: bool) {
        debug_assert!(self.undo.is_none(), "a whole-part refresh while applying in place");
        if lighting_changed {
            self.h = half_vectors(&self.lighting, &ctx.mesh.positions, ctx.normals);
            self.h_gradient = h_gradients(&self.lighting, &ctx.mesh.positions, &ctx.geom.frames);
            self.critical =
                critical_points(&self.h, ctx.normals.iter().copied(), DEFAULT_CRITICAL_THRESHOLD);
        }
        self.ell = ctx.ell_of(&self.phi, &self.h, self.h_gradient.as_deref());
        self.g = ctx.g_of(&self.phi, &self.h);
        if !self.pinned {
            for i in 0..self.ell.len() {
                if self.edit_weight[i].is_none() {
                    self.target[i] = self.ell[i];
                }
                if self.edit_weight_g[i].is_none() {
                    self.target_g[i] = self.g[i];
                }
            }
        }
    }

    /// Sets vertex `i`'s grain to the angle an edit designed for it (the optimizer's start;
    /// the grain before is kept for the fidelity figures) and returns its ĝ, the position
    /// target it meets. Only ĝ is brought up to date: ℓ, and with it every vertex's "keep the
    /// current ℓ" target, stays the field's before the design, as the tensor energy's targets
    /// outside the brushes must.
    ///
    /// A grain within acos(0.995) of ±h̄ is turned out to that angle (on its own side of h̄):
    /// the position rows' targets are clamped there
    /// ([`crate::solve::position_term::TARGET_BOUND`]), so the designed grain meets its row
    /// exactly and the solve has nothing left to do.
    pub fn design(&mut self, ctx: &Context, i: usize, phi: f64) -> f64 {
        let phi = self.h_angle(ctx, i).map_or(phi, |theta| clamp_design(phi, theta));
        self.touch(i);
        self.designed[i].get_or_insert(self.phi[i]);
        self.phi[i] = phi;
        self.g[i] = g_hat(&ctx.geom.frames[i], phi, &self.h[i]);
        self.g[i]
    }

    /// The angle θ of h̄ (the tangent part of h) in vertex `i`'s frame; `None` at a critical
    /// point or where h̄ (nearly) vanishes, where no grain moves the highlight.
    pub fn h_angle(&self, ctx: &Context, i: usize) -> Option<f64> {
        let hb = ctx.geom.frames[i].to_local(&self.h[i]);
        (hb.norm() > MIN_TANGENT_H && !self.critical[i]).then(|| hb.y.atan2(hb.x))
    }

    /// Sets the position target of vertex `i` from an edit of weight `w`.
    pub fn set_target_g(&mut self, i: usize, g: f64, w: f64) {
        self.touch(i);
        self.target_g[i] = g;
        self.edit_weight_g[i] = Some(w);
        self.support[i] = true;
    }

    /// Sets the target of vertex `i` from an edit of weight `w`.
    pub fn set_target(&mut self, i: usize, ell: Vector3<f64>, w: f64) {
        self.touch(i);
        self.target[i] = ell;
        self.edit_weight[i] = Some(w);
        self.support[i] = true;
    }

    fn finish(self, options: &EditOptions, reports: Vec<EditReport>) -> Result<EditResult> {
        let n = self.target.len();
        let mut target_ell = vec![None; n];
        let mut target_g = vec![None; n];
        let mut weight = vec![0.0; n];
        let mut weight_g = vec![0.0; n];
        for i in 0..n {
            let t = self.targets_at(i, options)?;
            (target_ell[i], weight[i], target_g[i], weight_g[i]) =
                (t.ell, t.weight, t.g, t.weight_g);
        }
        if let Some(i) = self.phi.iter().position(|p| !p.is_finite()) {
            return Err(phi_not_finite(i));
        }
        let phi_before =
            self.phi.iter().zip(&self.designed).map(|(p, d)| d.unwrap_or(*p)).collect();
        Ok(EditResult {
            phi: self.phi,
            phi_before,
            lighting: self.lighting,
            h: self.h,
            h_gradient: self.h_gradient,
            target_ell,
            weight,
            target_g,
            weight_g,
            support: self.support,
            reports,
        })
    }

    /// Vertex `i`'s targets as [`EditResult`] states them (none at a critical point; a weight
    /// of 0 drops a target); the error of a target that is not finite.
    fn targets_at(&self, i: usize, options: &EditOptions) -> Result<kept::Targets> {
        let mut out = kept::Targets { ell: None, weight: 0.0, g: None, weight_g: 0.0 };
        if self.critical[i] {
            return Ok(out);
        }
        let wg = self.edit_weight_g[i].unwrap_or(options.outside_weight);
        if wg > 0.0 {
            let g = self.target_g[i];
            if !g.is_finite() {
                return Err(Error::Numerical {
                    stage: "edits",
                    message: format!("the position target of vertex {i} is not finite"),
                });
            }
            (out.g, out.weight_g) = (Some(g), wg);
        }
        let w = self.edit_weight[i].unwrap_or(options.outside_weight);
        if w <= 0.0 {
            return Ok(out);
        }
        let t = self.target[i];
        if !t.iter().all(|c| c.is_finite()) {
            return Err(Error::Numerical {
                stage: "edits",
                message: format!("the target of vertex {i} is not finite"),
            });
        }
        (out.ell, out.weight) = (Some(t), w);
        Ok(out)
    }
}

/// The error of a grain angle that is not finite at vertex `i`.
fn phi_not_finite(i: usize) -> Error {
    Error::Numerical {
        stage: "edits",
        message: format!("the grain angle of vertex {i} is not finite"),
    }
}

/// |h̄| (of a unit h) below which an edit leaves a vertex's grain alone: h ∥ n, every grain
/// puts the highlight through it.
const MIN_TANGENT_H: f64 = 1e-6;

/// The grain angle `phi` turned, if need be, to within
/// [`crate::solve::position_term::TARGET_BOUND`] of ±h̄ in cosine (h̄ at angle `theta`), on its
/// side of h̄.
fn clamp_design(phi: f64, theta: f64) -> f64 {
    let bound = crate::solve::position_term::TARGET_BOUND;
    let psi = crate::geometry::connection::wrap_angle(phi - theta);
    let clamped = psi.cos().clamp(-bound, bound).acos();
    let turned = if psi < 0.0 { -clamped } else { clamped };
    let out = phi + (turned - psi);
    if out.is_finite() {
        out
    } else {
        phi
    }
}

/// ĝ = h̄ᵀū/|h̄| at one vertex: the cosine between the grain of angle `phi` and the tangent part
/// of `h` (0 where that part vanishes).
pub fn g_hat(frame: &crate::geometry::Frame, phi: f64, h: &Vector3<f64>) -> f64 {
    let hb = frame.to_local(h);
    let len = hb.norm();
    if !(len > 0.0) {
        return 0.0;
    }
    let (sn, cs) = phi.sin_cos();
    ((cs * hb.x + sn * hb.y) / len).clamp(-1.0, 1.0)
}

/// Prefixes the key of a setting error with the edit's index; names the edit in other errors.
fn at_edit(k: usize, tool: &str, err: Error) -> Error {
    match err {
        Error::Setting { key, message } => Error::setting(format!("[{k}].{key}"), message),
        Error::Numerical { stage, message } => {
            Error::Numerical { stage, message: format!("edit [{k}] ({tool}): {message}") }
        }
        other => other,
    }
}

/// A weight must be finite, ≥ 0 and at most [`crate::limits::MAX_EDIT_WEIGHT`].
pub(crate) fn check_weight(key: &str, w: f64) -> Result<()> {
    use crate::limits::MAX_EDIT_WEIGHT;
    if !(w.is_finite() && (0.0..=MAX_EDIT_WEIGHT).contains(&w)) {
        return Err(Error::setting(
            key,
            format!(
                "must be a finite number ≥ 0 and at most {} (limits::MAX_EDIT_WEIGHT), got {}",
                crate::error::fmt_num(MAX_EDIT_WEIGHT),
                crate::error::fmt_num(w)
            ),
        ));
    }
    Ok(())
}

/// A radius must be finite and > 0.
pub(crate) fn check_radius(key: &str, r: f64) -> Result<()> {
    use crate::limits::MAX_EDIT_RADIUS;
    if !(r.is_finite() && r > 0.0 && r <= MAX_EDIT_RADIUS) {
        return Err(Error::setting(
            key,
            format!(
                "must be a finite number > 0 and at most {} (limits::MAX_EDIT_RADIUS), got {}",
                crate::error::fmt_num(MAX_EDIT_RADIUS),
                crate::error::fmt_num(r)
            ),
        ));
    }
    Ok(())
}

/// A direction must be finite and non-zero.
pub(crate) fn check_direction(key: &str, d: &[f64; 3]) -> Result<()> {
    let ok = d.iter().all(|c| c.is_finite()) && d.iter().any(|&c| c != 0.0);
    if !ok {
        return Err(Error::setting(
            key,
            format!("must be a finite non-zero vector, got [{}, {}, {}]", d[0], d[1], d[2]),
        ));
    }
    Ok(())
}

/// The angle between two directions modulo π (0 to 90°), in degrees; 90° if either vanishes.
pub(crate) fn line_angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let (na, nb) = (a.norm(), b.norm());
    if !(na > 0.0 && nb > 0.0) {
        return 90.0;
    }
    a.cross(b).norm().atan2(a.dot(b).abs()).to_degrees()
}

pub(crate) fn one() -> f64 {
    1.0
}
