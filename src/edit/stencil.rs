//! The stencil tool of the paper's §5 (Fig. 11): a highlight *region*.
//!
//! Inside the support, u*ᵢ = ±hᵢ × nᵢ / |hᵢ × nᵢ| (sign agreeing with the current uᵢ), so
//! hᵀu* = 0 and every point of the support reflects the light (paper §3.1). Where h ≈ n (a
//! critical point, |h × n| < 10⁻⁶) every tangent u has hᵀu ≈ 0 and the current u is kept.
//!
//! To avoid a steep edge, the field is blended into its surroundings over a band of vertices at
//! distance r < d ≤ r(1 + blend): with zᵢ = e^{ikφᵢ} (k = 1, or 2 for line fields — the
//! angle-doubled field), the band solves the discrete connection Laplace equation
//!
//! ```text
//! Σⱼ wᵢⱼ (zᵢ − e^{ikρᵢⱼ} zⱼ) = 0      for every band vertex i,
//! ```
//!
//! wᵢⱼ the clamped cotangent weights ([`crate::geometry::laplacian`]), ρᵢⱼ the transport angles,
//! with zⱼ fixed to e^{ikφ*ⱼ} in the support and to the current field outside the band (a
//! tiny σ·Aᵢ(zᵢ − zᵢ^current) term keeps the system definite). φᵢ = arg(zᵢ)/k. The paper instead
//! applies Laplacian smoothing to u* (§4.3); the harmonic blend is the limit of that smoothing
//! with the support and the far field held. The edited vertices (support and band) then get the
//! ℓ of the new field as their targets.

use faer::c64;
use faer::prelude::*;
use faer::sparse::{SparseColMat, Triplet};
use serde::{Deserialize, Serialize};

use super::support::{distances, resolve_centre, Centre, Metric};
use super::{check_radius, check_weight, Context, EditReport, State};
use crate::geometry::laplacian::cotan_weights;
use crate::{Error, Result};

/// A stencil edit: `{"tool": "stencil", "centre": {"vertex": 12}, "radius": 5}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StencilEdit {
    /// The brush centre.
    #[serde(alias = "center")]
    pub centre: Centre,
    /// The radius of the highlight region, scene units.
    pub radius: f64,
    /// How distances are measured (default `geodesic`).
    #[serde(default)]
    pub metric: Metric,
    /// Width of the blend band around the region, as a fraction of the radius (default 0.5;
    /// 0 = no blending, a steep edge).
    #[serde(default = "default_blend")]
    pub blend: f64,
    /// Weight of the edit's targets (default 1).
    #[serde(default = "super::one")]
    pub weight: f64,
}

fn default_blend() -> f64 {
    0.5
}

impl StencilEdit {
    /// Range-checks every number.
    pub fn validate(&self) -> Result<()> {
        self.centre.validate()?;
        check_radius("radius", self.radius)?;
        if !(self.blend.is_finite() && (0.0..=10.0).contains(&self.blend)) {
            return Err(Error::setting(
                "blend",
                format!(
                    "must be within [0, 10] (a fraction of the radius), got {}",
                    crate::error::fmt_num(self.blend)
                ),
            ));
        }
        check_weight("weight", self.weight)
    }
}

/// Applies a stencil edit to the state.
pub(crate) fn apply(
    ctx: &Context,
    st: &mut State,
    e: &StencilEdit,
    report: &mut EditReport,
) -> Result<()> {
    let src = resolve_centre(ctx, &e.centre)?;
    let outer = e.radius * (1.0 + e.blend);
    let found = distances(ctx, &src, outer, e.metric);
    let inside: Vec<usize> = found.iter().filter(|x| x.1 <= e.radius).map(|x| x.0).collect();
    if inside.is_empty() {
        return Err(Error::setting(
            "radius",
            format!(
                "the support holds no vertex: no vertex is within {} of the centre; increase \
                 the radius or move the centre",
                e.radius
            ),
        ));
    }
    let band: Vec<usize> = found.iter().filter(|x| x.1 > e.radius).map(|x| x.0).collect();
    let k = ctx.symmetry.k() as f64;
    let frames = &ctx.geom.frames;
    let mut critical = 0;
    for &i in &inside {
        let f = &frames[i];
        let c = st.h[i].cross(&f.n);
        let len = c.norm();
        if st.critical[i] {
            critical += 1;
        }
        if !(len > 1e-6) {
            continue;
        }
        let u = f.direction(st.phi[i]);
        let c = if c.dot(&u) < 0.0 { -c / len } else { c / len };
        st.set_phi(i, f.angle_of(&c));
    }
    if !band.is_empty() {
        blend_band(ctx, &mut st.phi, &band, k)?;
    }
    st.refresh(ctx, false);
    let mut max_hu: f64 = 0.0;
    for &i in &inside {
        let u = frames[i].direction(st.phi[i]);
        max_hu = max_hu.max(st.h[i].dot(&u).abs());
    }
    for &i in inside.iter().chain(&band) {
        if !st.critical[i] {
            let (ell, g) = (st.ell[i], st.g[i]);
            st.set_target(i, ell, e.weight);
            st.set_target_g(i, g, e.weight);
        }
        st.set_support(i);
    }
    report.vertices = inside.len() - inside.iter().filter(|&&i| st.critical[i]).count()
        + band.iter().filter(|&&i| !st.critical[i]).count();
    report.critical_vertices = critical;
    report.blend_vertices = Some(band.len());
    report.max_h_dot_u = Some(max_hu);
    Ok(())
}

/// Solves the connection Laplace equation on the band vertices (module documentation).
fn blend_band(ctx: &Context, phi: &mut [f64], band: &[usize], k: f64) -> Result<()> {
    let n = phi.len();
    let adj = &ctx.geom.adjacency;
    let w = cotan_weights(ctx.mesh, adj);
    let mut col = vec![usize::MAX; n];
    for (c, &i) in band.iter().enumerate() {
        col[i] = c;
    }
    let z: Vec<c64> = phi.iter().map(|&p| c64::new((k * p).cos(), (k * p).sin())).collect();
    let mean_w = {
        let s: f64 = band.iter().flat_map(|&i| adj.slots(i).map(|s| w[s])).sum();
        let a: f64 = band.iter().map(|&i| ctx.geom.areas[i].max(0.0)).sum();
        if a > 0.0 && s > 0.0 {
            s / a
        } else {
            1.0
        }
    };
    let sigma = 1e-8 * mean_w;
    let mut triplets = Vec::new();
    let mut rhs = Mat::<c64>::zeros(band.len(), 1);
    for (r, &i) in band.iter().enumerate() {
        let area = ctx.geom.areas[i].max(0.0) + 1e-300;
        let mut diag = sigma * area;
        let mut b = z[i] * (sigma * area);
        for s in adj.slots(i) {
            let j = adj.target(s);
            if !(w[s] > 0.0) {
                continue;
            }
            diag += w[s];
            let a = k * ctx.geom.transport[s];
            let rot = c64::new(w[s] * a.cos(), w[s] * a.sin());
            if col[j] == usize::MAX {
                b += rot * z[j];
            } else {
                triplets.push(Triplet::new(r, col[j], -rot));
            }
        }
        triplets.push(Triplet::new(r, r, c64::new(diag.max(1e-300), 0.0)));
        rhs[(r, 0)] = b;
    }
    let m = band.len();
    let a = SparseColMat::<usize, c64>::try_new_from_triplets(m, m, &triplets).map_err(|e| {
        Error::Numerical {
            stage: "stencil blend",
            message: format!("matrix assembly: {}", crate::error::describe_creation(&e)),
        }
    })?;
    let llt = crate::factor::Factor::new(a.as_ref(), "stencil blend")?;
    llt.solve_in_place(rhs.as_mut());
    for (r, &i) in band.iter().enumerate() {
        let zi = rhs[(r, 0)];
        if zi.re.is_finite() && zi.im.is_finite() && (zi.re != 0.0 || zi.im != 0.0) {
            phi[i] = zi.im.atan2(zi.re) / k;
        }
    }
    Ok(())
}
