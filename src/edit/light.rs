//! The light tool of the paper's §5 (Fig. 10): the field is fixed and the light is sought.
//!
//! A highlight passes through vertex i when hᵀuᵢ = 0, so h lies in the plane ⟂ uᵢ: with
//! v = n × u (math.md §1),
//!
//! ```text
//! h(θ) = cos θ n + sin θ v,   θ ∈ (−π/2, π/2),      ω_in(θ) = 2(hᵀω_out)h − ω_out,
//! ```
//!
//! restricted to lights that keep the vertex lit: nᵀω_in ≥ sin(elevation) (the paper's
//! "nᵀω_in > π/8" read as sin(π/8), math.md §5.10: an elevation of 22.5°). On this family
//! h̄ = sin θ v̄ and nᵀh = cos θ, so Eq. 7 gives
//!
//! ```text
//! m(θ) = sin θ ∇φᵢ + cos θ Wᵢūᵢ,       ℓ(θ) = R m(θ).
//! ```
//!
//! The search minimizes the angle (mod π) between ℓ(θ) and the wanted ℓ*: 2000 samples of θ
//! (global), golden-section refinement around the best admissible sample, and the closed-form
//! roots θ = atan2(−⟨Rb, ℓ*⟩×, ⟨Ra, ℓ*⟩×) (a = ∇φ, b = Wū, × the 2D cross product) when they are
//! admissible; the best of these wins.
//!
//! The move_light tool instead switches the key light and keeps the current ℓ (under the old
//! light) as the target of every vertex, so the optimizer re-orients the grain to keep the
//! highlights where they were.

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

use super::support::{resolve_centre, Centre};
use super::{check_direction, line_angle_deg, Context, EditReport, State};
use crate::geometry::{Geometry, GradientForm};
use crate::highlight::{Lighting, Symmetry};
use crate::{Error, Result};

/// A light edit: `{"tool": "light", "centre": {"vertex": 12}, "ell": [1, 0, 0]}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LightEdit {
    /// The vertex the highlight must pass through (a point picks its nearest vertex).
    #[serde(alias = "center")]
    pub centre: Centre,
    /// The wanted highlight tangent there, a world direction projected onto the tangent plane
    /// (default: the current ℓ, so the highlight keeps its direction).
    #[serde(default)]
    pub ell: Option<[f64; 3]>,
    /// Minimum elevation of the light above the vertex's tangent plane, degrees (default 22.5,
    /// the paper's π/8).
    #[serde(default = "default_elevation")]
    pub min_elevation_deg: f64,
}

fn default_elevation() -> f64 {
    22.5
}

impl LightEdit {
    /// Range-checks every number.
    pub fn validate(&self) -> Result<()> {
        self.centre.validate()?;
        if let Some(d) = &self.ell {
            check_direction("ell", d)?;
        }
        let e = self.min_elevation_deg;
        if !(e.is_finite() && (0.0..90.0).contains(&e)) {
            return Err(Error::setting(
                "min_elevation_deg",
                format!("must be within [0, 90), got {}", crate::error::fmt_num(e)),
            ));
        }
        Ok(())
    }
}

/// A move_light edit: `{"tool": "move_light", "light": [0, 1, 1]}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MoveLightEdit {
    /// The new direction towards the light (normalized).
    pub light: [f64; 3],
}

impl MoveLightEdit {
    /// Range-checks the direction.
    pub fn validate(&self) -> Result<()> {
        check_direction("light", &self.light)
    }
}

/// The light found by [`find_light`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSearch {
    /// Unit direction towards the light.
    pub light: Vector3<f64>,
    /// The half-vector angle θ (radians; 0 means h = n).
    pub theta: f64,
    /// The angle (mod π) between the wanted ℓ and ℓ(θ), degrees.
    pub angle_error_deg: f64,
}

/// What [`find_light`] needs to know about the field at one vertex.
#[derive(Clone, Copy, Debug)]
pub struct LightQuery<'a> {
    /// The surface.
    pub geometry: &'a Geometry,
    /// The grain angles.
    pub phi: &'a [f64],
    /// k = 1 or 2.
    pub symmetry: Symmetry,
    /// Eq. 10 form.
    pub form: GradientForm,
    /// The vertex.
    pub vertex: usize,
    /// ω_out at the vertex (unit, away from the surface).
    pub omega_out: Vector3<f64>,
    /// The wanted ℓ (world; projected onto the tangent plane).
    pub wanted: Vector3<f64>,
    /// The minimum nᵀω_in.
    pub min_cos: f64,
}

const SAMPLES: usize = 2000;

/// The light of the family h(θ) whose ℓ at the vertex is closest to the wanted one (module
/// documentation). Errors if the vertex faces away from the viewer, if the wanted ℓ has no
/// tangential part, or if no light of the family is high enough.
pub fn find_light(q: &LightQuery) -> Result<LightSearch> {
    let i = q.vertex;
    let f = &q.geometry.frames[i];
    let n = f.n;
    if !(n.dot(&q.omega_out) > 1e-6) {
        return Err(Error::setting(
            "centre",
            format!("vertex {i} faces away from the viewer (nᵀω_out ≤ 0)"),
        ));
    }
    let target = f.to_local(&q.wanted);
    if !(target.norm() > 1e-9 * q.wanted.norm()) {
        return Err(Error::setting(
            "ell",
            format!("the wanted ℓ has no component in the tangent plane of vertex {i}"),
        ));
    }
    let target = target.normalize();
    let u = f.direction(q.phi[i]);
    let v = n.cross(&u);
    let grad = q.geometry.stencil.gradient_at(q.phi, q.symmetry.k(), q.form, i);
    let (sn, cs) = q.phi[i].sin_cos();
    let wu = q.geometry.weingarten[i] * Vector2::new(cs, sn);
    let rot = |m: Vector2<f64>| Vector2::new(-m.y, m.x);
    let (ra, rb) = (rot(grad), rot(wu));
    let error = |theta: f64| {
        let l = ra * theta.sin() + rb * theta.cos();
        let cross = (l.x * target.y - l.y * target.x).abs();
        let dot = l.dot(&target).abs();
        if cross == 0.0 && dot == 0.0 {
            std::f64::consts::FRAC_PI_2
        } else {
            cross.atan2(dot)
        }
    };
    let light_of = |theta: f64| {
        let h = n * theta.cos() + v * theta.sin();
        h * (2.0 * h.dot(&q.omega_out)) - q.omega_out
    };
    let admissible = |theta: f64| n.dot(&light_of(theta)) >= q.min_cos;
    let half_pi = std::f64::consts::FRAC_PI_2;
    let step = std::f64::consts::PI / SAMPLES as f64;
    let mut best: Option<(f64, f64)> = None;
    for j in 0..SAMPLES {
        let t = -half_pi + step * (j as f64 + 0.5);
        if admissible(t) {
            let e = error(t);
            if best.is_none_or(|b| e < b.1) {
                best = Some((t, e));
            }
        }
    }
    let Some((t0, _)) = best else {
        return Err(Error::setting(
            "min_elevation_deg",
            format!(
                "no light through vertex {i} is that high above its tangent plane for this view"
            ),
        ));
    };
    let penalized = |t: f64| if admissible(t) { error(t) } else { f64::INFINITY };
    let mut candidates = vec![golden_section(&penalized, t0 - step, t0 + step)];
    let root = (-(rb.x * target.y - rb.y * target.x)).atan2(ra.x * target.y - ra.y * target.x);
    for t in [root, root + std::f64::consts::PI, root - std::f64::consts::PI] {
        if t > -half_pi && t < half_pi {
            candidates.push(t);
        }
    }
    let (theta, err) = candidates
        .into_iter()
        .map(|t| (t, penalized(t)))
        .filter(|c| c.1.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((t0, error(t0)));
    let light = light_of(theta);
    Ok(LightSearch { light: light.normalize(), theta, angle_error_deg: err.to_degrees() })
}

/// Golden-section minimization of `f` on [a, b].
fn golden_section(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - r * (b - a);
    let mut d = a + r * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..80 {
        if fc <= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    if fc <= fd {
        c
    } else {
        d
    }
}

/// Applies a light edit: finds the light and switches to it.
pub(crate) fn apply(
    ctx: &Context,
    st: &mut State,
    e: &LightEdit,
    report: &mut EditReport,
) -> Result<()> {
    let i = resolve_centre(ctx, &e.centre)?.nearest_vertex;
    let wanted = match &e.ell {
        Some(d) => Vector3::new(d[0], d[1], d[2]),
        None => st.ell[i],
    };
    if e.ell.is_none() && !(wanted.norm() > 0.0) {
        return Err(Error::setting(
            "ell",
            format!("the current ℓ vanishes at vertex {i}; give the wanted direction"),
        ));
    }
    let found = find_light(&LightQuery {
        geometry: ctx.geom,
        phi: &st.phi,
        symmetry: ctx.symmetry,
        form: ctx.form,
        vertex: i,
        omega_out: st.lighting.omega_out(&ctx.mesh.positions[i]),
        wanted,
        min_cos: e.min_elevation_deg.to_radians().sin(),
    })?;
    let old = st.lighting.light;
    st.lighting = Lighting::new(found.light, st.lighting.view)?;
    st.refresh(ctx, true);
    report.vertices = 1;
    report.vertex = Some(i);
    report.light = Some([found.light.x, found.light.y, found.light.z]);
    report.angle_error_deg = Some(found.angle_error_deg);
    report.light_turn_deg = Some(old.angle(&found.light).to_degrees());
    Ok(())
}

/// Applies a move_light edit: the new light, with every vertex keeping its current target.
pub(crate) fn apply_move(
    ctx: &Context,
    st: &mut State,
    e: &MoveLightEdit,
    report: &mut EditReport,
) -> Result<()> {
    let old_ell = st.ell.clone();
    let old = st.lighting.light;
    let new = Vector3::new(e.light[0], e.light[1], e.light[2]);
    st.lighting = Lighting::new(new, st.lighting.view)
        .map_err(|err| Error::setting("light", err.to_string()))?;
    st.pinned = true;
    st.refresh(ctx, true);
    let mut changes: Vec<f64> = (0..old_ell.len())
        .filter(|&i| !st.critical[i])
        .map(|i| line_angle_deg(&old_ell[i], &st.ell[i]))
        .collect();
    let median = if changes.is_empty() {
        0.0
    } else {
        let mid = changes.len() / 2;
        *changes.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1
    };
    st.support.iter_mut().for_each(|s| *s = true);
    report.vertices = st.critical.iter().filter(|c| !**c).count();
    report.critical_vertices = st.critical.len() - report.vertices;
    report.light = Some([st.lighting.light.x, st.lighting.light.y, st.lighting.light.z]);
    report.light_turn_deg = Some(old.angle(&st.lighting.light).to_degrees());
    report.median_ell_change_deg = Some(median);
    Ok(())
}
