//! The warp tools of the paper's §5 (Fig. 7–9): bend and expand.
//!
//! A warp W moves points of the brush chart (geodesic polar coordinates around the centre,
//! [`super::chart`]; on a plane, the plane itself) along y: W(x, y) = (x, y + s·d(x, y)), with
//!
//! ```text
//! bend:    d(x, y) = w(x, y)/2
//! expand:  d(x, y) = w(x, y)·g(y)/2,   g(y) = sin y / (sin² y + δ²)^(1/4),  δ = 0.02
//! ```
//!
//! w = (1 − x² − y²)² the fall-off and s the strength (s = 1 is the paper's tool). The paper
//! prints √(sin y) for the expand tool, imaginary for y < 0; math.md §5.7 reads it as
//! sign(y)√|sin y|, whose y-derivative is infinite at y = 0. g is that function regularized:
//! odd, smooth, equal to sign(y)√|sin y| within 1% for |y| > 0.2, with g′(0) = δ^(−1/2) ≈ 7.
//! W is the identity on and outside the unit circle, keeps x, and is a bijection of the disk as
//! long as ∂y′/∂y = 1 + s ∂d/∂y > 0, i.e. for s within [`strength_range`].
//!
//! The targets (paper §5): ℓ*ᵢ = J_W(q) ℓ_q with q = W⁻¹(pᵢ), pᵢ the chart coordinates of vertex
//! i and J_W = [[1, 0], [s ∂d/∂x, 1 + s ∂d/∂y]]. W⁻¹ is solved along the vertical line x = xᵢ by
//! Newton's method safeguarded by bisection (W maps the chord of the disk at x onto itself,
//! monotonically). ℓ_q is interpolated from the current targets in chart components (see
//! [`super::support`], "point location"), warped by J_W, and taken back to the tangent plane of
//! vertex i through its frame's chart angle ([`super::chart::Chart::vector_from_chart`]).

use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

use super::support::{Centre, Metric, PlaneLocator, Support};
use super::{
    check_direction, check_radius, check_weight, line_angle_deg, Context, EditReport, State,
};
use crate::highlight::Symmetry;
use crate::{Error, Result};

/// The regularization δ of the expand tool's √|sin y|.
pub const EXPAND_DELTA: f64 = 0.02;

/// Which warp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WarpKind {
    /// W_b(x, y) = (x, y + s·w/2): highlights bend towards +y.
    Bend,
    /// W_e(x, y) = (x, y + s·w·g(y)/2): highlights move away from the x axis.
    Expand,
}

/// The admissible strengths: W stays a bijection of the unit disk (min ∂y′/∂y > 0, with a
/// margin). Bend: max |∂d/∂y| = 4/(3√3) = 0.770 at (0, ±1/√3), so |s| < 1.299; expand: ∂d/∂y
/// ranges over [−0.511, 3.54] (δ = 0.02), so −0.283 < s < 1.957.
pub fn strength_range(kind: WarpKind) -> (f64, f64) {
    match kind {
        WarpKind::Bend => (-1.25, 1.25),
        WarpKind::Expand => (-0.25, 1.9),
    }
}

/// d(x, y) and its partial derivatives (∂d/∂x, ∂d/∂y); W(x, y) = (x, y + s·d).
pub fn displacement(kind: WarpKind, p: &Vector2<f64>) -> (f64, f64, f64) {
    let s = 1.0 - p.norm_squared();
    if s <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    let (w, wx, wy) = (s * s, -4.0 * p.x * s, -4.0 * p.y * s);
    match kind {
        WarpKind::Bend => (0.5 * w, 0.5 * wx, 0.5 * wy),
        WarpKind::Expand => {
            let (sn, cs) = p.y.sin_cos();
            let dd = EXPAND_DELTA * EXPAND_DELTA;
            let base = sn * sn + dd;
            let g = sn / base.powf(0.25);
            let gp = cs * (0.5 * sn * sn + dd) / base.powf(1.25);
            (0.5 * w * g, 0.5 * wx * g, 0.5 * (wy * g + w * gp))
        }
    }
}

/// The floor of [`finest_scale`]: a warp's brush is refined to at most 4 × finer edges than a
/// warp that moves nothing would ask for (bounded work; only bends past s = 0.97 and expands
/// past s = 1.47 or below −0.23 reach it).
pub const MIN_WARP_SCALE: f64 = 0.25;

/// The smallest singular value of J_W over the unit disk, floored at [`MIN_WARP_SCALE`]: how
/// much the warp compresses the highlight pattern it moves at most (docs/math.md §12). The
/// target g ∘ W⁻¹ carries the field's detail shrunk by this factor, so its brush needs edges
/// shrunk by as much to be resolved as well as the field before the edit was. Sampled on a
/// 129 × 129 grid (exact at s = 0, within 1 % of the analytic 1 − 0.770 s for bends).
pub fn finest_scale(kind: WarpKind, s: f64) -> f64 {
    if !s.is_finite() {
        return MIN_WARP_SCALE;
    }
    let n = 128;
    let mut smallest: f64 = 1.0;
    for i in 0..=n {
        for j in 0..=n {
            let p =
                Vector2::new(-1.0 + 2.0 * i as f64 / n as f64, -1.0 + 2.0 * j as f64 / n as f64);
            if p.norm_squared() >= 1.0 {
                continue;
            }
            // Singular values of [[1, 0], [c, d]]: σ² = (T ∓ √(T² − 4d²))/2, T = 1 + c² + d².
            let (_, dx, dy) = displacement(kind, &p);
            let (c, d) = (s * dx, 1.0 + s * dy);
            let t = 1.0 + c * c + d * d;
            let q = (t * t - 4.0 * d * d).max(0.0).sqrt();
            smallest = smallest.min((0.5 * (t - q)).max(0.0).sqrt());
        }
    }
    smallest.max(MIN_WARP_SCALE)
}

/// W(p) for strength `s`.
pub fn warp(kind: WarpKind, s: f64, p: &Vector2<f64>) -> Vector2<f64> {
    Vector2::new(p.x, p.y + s * displacement(kind, p).0)
}

/// The Jacobian J_W(p).
pub fn jacobian(kind: WarpKind, s: f64, p: &Vector2<f64>) -> Matrix2<f64> {
    let (_, dx, dy) = displacement(kind, p);
    Matrix2::new(1.0, 0.0, s * dx, 1.0 + s * dy)
}

/// W⁻¹(p): Newton's method on y ↦ y + s·d(x, y) − p_y along the chord x = p_x, safeguarded by
/// bisection. `None` if the root is not found or W is not monotone there (∂y′/∂y ≤ 0).
pub fn inverse(kind: WarpKind, s: f64, p: &Vector2<f64>) -> Option<Vector2<f64>> {
    let half = (1.0 - p.x * p.x).max(0.0).sqrt();
    if s == 0.0 || half == 0.0 || p.y.abs() >= half {
        return Some(*p);
    }
    let f = |y: f64| {
        let (d, _, dy) = displacement(kind, &Vector2::new(p.x, y));
        (y + s * d - p.y, 1.0 + s * dy)
    };
    let (mut lo, mut hi) = (-half, half);
    let mut y = p.y;
    for _ in 0..200 {
        let (fy, dfy) = f(y);
        if fy.abs() <= 1e-14 {
            break;
        }
        if fy < 0.0 {
            lo = y;
        } else {
            hi = y;
        }
        let newton = y - fy / dfy;
        y = if dfy > 0.0 && newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
        if hi - lo <= 1e-15 {
            break;
        }
    }
    let (fy, dfy) = f(y);
    (fy.abs() <= 1e-10 && dfy > 0.0 && y.is_finite()).then(|| Vector2::new(p.x, y))
}

/// A bend or expand edit: `{"tool": "bend", "centre": {"vertex": 12}, "radius": 5}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WarpEdit {
    /// The brush centre.
    #[serde(alias = "center")]
    pub centre: Centre,
    /// The brush radius, scene units.
    pub radius: f64,
    /// How distances are measured (default `geodesic`).
    #[serde(default)]
    pub metric: Metric,
    /// The warp strength s (default 1, the paper's tool; see [`strength_range`]; negative
    /// bends the other way).
    #[serde(default = "super::one")]
    pub strength: f64,
    /// A world vector whose projection onto the brush plane is the brush's +y axis (the way
    /// highlights are pushed). Default: across the current highlights at the brush.
    #[serde(default)]
    pub direction: Option<[f64; 3]>,
    /// Weight of the edit's targets (default 1).
    #[serde(default = "super::one")]
    pub weight: f64,
}

impl WarpEdit {
    /// Range-checks every number.
    pub fn validate(&self, kind: WarpKind) -> Result<()> {
        self.centre.validate()?;
        check_radius("radius", self.radius)?;
        let (lo, hi) = strength_range(kind);
        if !(self.strength.is_finite() && self.strength >= lo && self.strength <= hi) {
            return Err(Error::setting(
                "strength",
                format!(
                    "must be within [{lo}, {hi}] (beyond, the warp folds the brush onto \
                     itself), got {}",
                    self.strength
                ),
            ));
        }
        if let Some(d) = &self.direction {
            check_direction("direction", d)?;
        }
        check_weight("weight", self.weight)
    }
}

/// The grain a warp asks for at vertex `v`, designed as an angle (docs/math.md §9, "bend /
/// expand"): the grain's angle from h̄ at W⁻¹(p), ψ* (the corners' unit vectors (cos ψ, sin ψ)
/// interpolated barycentrically, a line field's corners in the orientation of v's grain), put
/// back at v: φ* = θ(h̄ᵥ) + ψ*, whose ĝ = cos ψ* is the target ([`State::design`]). Its zero
/// set is the one of the interpolated ĝ (the cosine's sign is the interpolated vector's x), so
/// W(C0) is the same; but it also says on which side of h̄ the grain lies, as the field before
/// the edit did at W⁻¹(p), which ĝ alone does not: rows alone let neighbours take mirrored
/// grains. `None` at a critical point, where the corners disagree by so much that the
/// interpolated vector is short (the grain turns within one triangle there), or where a
/// corner's target is not its grain's ĝ (after a move_light): the vertex keeps its grain and
/// the interpolated ĝ.
fn pulled_back_grain(
    ctx: &Context,
    st: &State,
    locator: &PlaneLocator,
    q: &Vector2<f64>,
    pos: &nalgebra::Vector3<f64>,
    v: usize,
    sign: &impl Fn(usize) -> f64,
) -> Option<f64> {
    let theta_v = st.h_angle(ctx, v)?;
    let ((f, b), _) = locator.locate_or_nearest(ctx, q, pos);
    let mut sum = Vector2::zeros();
    for (k, &c) in ctx.mesh.faces[f].iter().enumerate() {
        let c = c as usize;
        // The grain stands for the target only where an earlier edit did not set one apart
        // from it (a move_light keeps the old light's ĝ as the target).
        if !((st.g[c] - st.target_g[c]).abs() <= 1e-6) {
            return None;
        }
        let flip = if sign(c) < 0.0 { std::f64::consts::PI } else { 0.0 };
        let psi = st.phi[c] + flip - st.h_angle(ctx, c)?;
        sum += Vector2::new(psi.cos(), psi.sin()) * b[k];
    }
    if !(sum.norm() > 0.5) {
        return None;
    }
    // The representative of θ + ψ* nearest the vertex's own angle.
    let a = theta_v + sum.y.atan2(sum.x);
    let phi = st.phi[v] + crate::geometry::connection::wrap_angle(a - st.phi[v]);
    phi.is_finite().then_some(phi)
}

/// Applies a warp edit to the state.
pub(crate) fn apply(
    ctx: &Context,
    st: &mut State,
    e: &WarpEdit,
    kind: WarpKind,
    report: &mut EditReport,
) -> Result<()> {
    let support =
        Support::new(ctx, &e.centre, e.radius, e.metric, e.direction.as_ref(), &st.target)?;
    let locator = PlaneLocator::new(ctx, &support);
    let align = ctx.symmetry == Symmetry::Line;
    let mut targets = Vec::with_capacity(support.vertices.len());
    let mut max_turn: f64 = 0.0;
    let mut critical = 0;
    let mut outside = 0usize;
    for (&v, p) in support.vertices.iter().zip(&support.xy) {
        if st.critical[v] {
            critical += 1;
            continue;
        }
        let q = inverse(kind, e.strength, p).ok_or_else(|| Error::Numerical {
            stage: "warp inverse",
            message: format!(
                "W⁻¹ not found at vertex {v} (planar point ({:.4}, {:.4})); lower the strength",
                p.x, p.y
            ),
        })?;
        let pos = ctx.mesh.positions[v];
        let ell_q = locator.interpolate(ctx, &support, &q, &pos, &st.target, align);
        let planar = jacobian(kind, e.strength, &q) * ell_q;
        let new = support.vector_from_chart(ctx, v, &planar);
        max_turn = max_turn.max(line_angle_deg(&new, &st.target[v]));
        // The position target (math.md §9): g*(p) = g(W⁻¹(p)), the corners' ĝ stated in the
        // orientation of vertex v's grain for line fields.
        let u_v = ctx.grain(&st.phi, v);
        let sign = |c: usize| {
            if align && ctx.grain(&st.phi, c).dot(&u_v) < 0.0 {
                -1.0
            } else {
                1.0
            }
        };
        let (g_new, inside) = locator.interpolate_scalar(ctx, &q, &pos, &st.target_g, sign);
        if !inside {
            outside += 1;
        }
        let design = pulled_back_grain(ctx, st, &locator, &q, &pos, v, &sign);
        targets.push((v, new, g_new, design));
    }
    for &(v, t, g, design) in &targets {
        st.set_target(v, t, e.weight);
        match design {
            Some(phi) => {
                let g = st.design(ctx, v, phi);
                st.set_target_g(v, g, e.weight);
            }
            None => st.set_target_g(v, g, e.weight),
        }
    }
    for &v in &support.vertices {
        st.set_support(v);
    }
    report.vertices = targets.len();
    report.critical_vertices = critical;
    report.max_turn_deg = Some(max_turn);
    if outside > 0 {
        report.notes.push(format!(
            "the warp pulls the highlight of {outside} of {} brush vertices from beyond the \
             part's boundary (the nearest boundary values were used); move the brush away \
             from the edge or lower the strength",
            targets.len()
        ));
    }
    if critical > 0 {
        report.notes.push(format!(
            "{critical} brush vertices are critical points (h ∥ n), where no grain moves the \
             highlight"
        ));
    }
    report.shape = Some(super::shape::warp_shape(kind, e.strength, &support));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scans ∂y′/∂y = 1 + s ∂d/∂y over the disk at the ends of the admissible range.
    #[test]
    fn admissible_strengths_keep_the_warp_monotone() {
        for kind in [WarpKind::Bend, WarpKind::Expand] {
            let (lo, hi) = strength_range(kind);
            let n = 400;
            let mut min_dy: f64 = f64::INFINITY;
            let mut max_dy: f64 = f64::NEG_INFINITY;
            for i in 0..=n {
                for j in 0..=n {
                    let p = Vector2::new(
                        -1.0 + 2.0 * i as f64 / n as f64,
                        -1.0 + 2.0 * j as f64 / n as f64,
                    );
                    let (_, _, dy) = displacement(kind, &p);
                    min_dy = min_dy.min(dy);
                    max_dy = max_dy.max(dy);
                }
            }
            assert!(1.0 + hi * min_dy > 0.02, "{kind:?}: {min_dy}");
            assert!(1.0 + lo * max_dy > 0.02, "{kind:?}: {max_dy}");
        }
    }

    /// The bend's compression is analytic: J_W = [[1, 0], [s ∂d/∂x, 1 + s ∂d/∂y]] and on the
    /// axis x = 0 the smallest ∂y′/∂y is 1 − s · 4/(3√3), where ∂d/∂x = 0 (a diagonal J).
    #[test]
    fn finest_scale_is_the_warps_largest_compression() {
        let max_slope = 4.0 / (3.0 * 3f64.sqrt());
        for s in [0.2f64, 0.5, 0.8, -0.8] {
            let want = 1.0 - s.abs() * max_slope;
            let got = finest_scale(WarpKind::Bend, s);
            assert!((got - want).abs() <= 0.01 * want, "bend {s}: {got} vs {want}");
        }
        assert_eq!(finest_scale(WarpKind::Bend, 0.0), 1.0);
        assert_eq!(finest_scale(WarpKind::Bend, 1.25), MIN_WARP_SCALE);
        assert_eq!(finest_scale(WarpKind::Expand, f64::NAN), MIN_WARP_SCALE);
        // The expand stretches across its axis and compresses beside it: 1 + s · min ∂d/∂y.
        let e = finest_scale(WarpKind::Expand, 0.8);
        assert!((e - (1.0 - 0.8 * 0.511)).abs() < 0.01, "{e}");
    }

    #[test]
    fn inverse_undoes_the_warp() {
        for kind in [WarpKind::Bend, WarpKind::Expand] {
            for &(x, y) in &[(0.0, 0.0), (0.3, -0.4), (-0.7, 0.5), (0.1, 0.001), (0.0, 0.9)] {
                let p = Vector2::new(x, y);
                let w = warp(kind, 1.0, &p);
                let back = inverse(kind, 1.0, &w).unwrap();
                assert!((back - p).norm() < 1e-9, "{kind:?} {p:?} {back:?}");
            }
        }
    }

    #[test]
    fn regularized_expand_matches_the_paper_away_from_the_axis() {
        for &y in &[0.2f64, 0.5, -0.7, 1.0] {
            let (d, _, _) = displacement(WarpKind::Expand, &Vector2::new(0.0, y));
            let w = (1.0 - y * y).powi(2);
            let paper = 0.5 * w * y.signum() * y.sin().abs().sqrt();
            assert!((d - paper).abs() <= 0.01 * paper.abs(), "{y}: {d} vs {paper}");
        }
    }
}
