//! Distortion of a flattening, and whether it is valid.
//!
//! For a triangle with isometric corners x (in a frame of its plane) and UV corners u, the
//! map's Jacobian is `J = [u₁ − u₀, u₂ − u₀]·[x₁ − x₀, x₂ − x₀]⁻¹` (2×2) with singular values
//! σ₁ ≥ σ₂ (math.md, Eq. D1). With the layout's scale taken out (UV area = surface area):
//!
//! * **area distortion** σ₁σ₂, reported as max(σ₁σ₂, 1/(σ₁σ₂)) ≥ 1 (1: area kept);
//! * **angle distortion** σ₁/σ₂ ≥ 1 (1: conformal), and the corner angles' error in degrees;
//! * **stretch** max(σ₁, 1/σ₂) ≥ 1 (1: isometric), which decides whether a chart is kept;
//! * **edge-length error** |s·ℓ_uv − ℓ| / ℓ for every edge of every face.
//!
//! A chart is **valid** when no triangle is flipped (signed UV area ≤ 0), no two boundary
//! edges cross and the UV angles around every interior vertex add up to 2π (winding number
//! one): a locally injective map of a disk whose boundary is a simple curve is one-to-one.

use nalgebra::{Matrix2, Vector2, Vector3};
use serde::Serialize;

use super::charts::ChartMesh;
use super::lscm::local_frame;

/// Singular values (σ₁ ≥ σ₂ ≥ 0) and determinant of a 2×2 matrix (Eq. D1).
pub(crate) fn singular_values(j: &Matrix2<f64>) -> (f64, f64, f64) {
    let (a, b, c, d) = (j[(0, 0)], j[(0, 1)], j[(1, 0)], j[(1, 1)]);
    let e = 0.5 * (a + d);
    let f = 0.5 * (a - d);
    let g = 0.5 * (c + b);
    let h = 0.5 * (c - b);
    let q = e.hypot(h);
    let r = f.hypot(g);
    (q + r, (q - r).abs(), a * d - b * c)
}

/// The Jacobian of the map from a triangle's plane (corners `p`) to its UV corners `u`, or
/// `None` for a degenerate triangle.
pub(crate) fn jacobian(p: [Vector3<f64>; 3], u: [Vector2<f64>; 3]) -> Option<Matrix2<f64>> {
    let x = local_frame(p);
    let xm = Matrix2::from_columns(&[x[1] - x[0], x[2] - x[0]]);
    let um = Matrix2::from_columns(&[u[1] - u[0], u[2] - u[0]]);
    let inv = xm.try_inverse()?;
    let j = um * inv;
    j.iter().all(|v| v.is_finite()).then_some(j)
}

/// Signed area of a UV triangle.
pub(crate) fn signed_area(u: [Vector2<f64>; 3]) -> f64 {
    0.5 * (u[1] - u[0]).perp(&(u[2] - u[0]))
}

/// Area-weighted mean, area quantiles and maximum of a per-face measure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Stat {
    /// Area-weighted mean.
    pub mean: f64,
    /// The value below which 95 % of the area lies.
    pub p95: f64,
    /// Largest value.
    pub max: f64,
}

impl Stat {
    /// The statistics of `values` weighted by `weights` (pairs with a non-finite value count as
    /// `cap`).
    pub(crate) fn of(values: &[f64], weights: &[f64], cap: f64) -> Stat {
        let mut pairs: Vec<(f64, f64)> = values
            .iter()
            .zip(weights)
            .map(|(&v, &w)| (if v.is_finite() { v.min(cap) } else { cap }, w.max(0.0)))
            .collect();
        if pairs.is_empty() {
            return Stat::default();
        }
        let total: f64 = pairs.iter().map(|p| p.1).sum();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let max = pairs.last().map_or(0.0, |p| p.0);
        if total <= 0.0 || total.is_nan() {
            return Stat { mean: max, p95: max, max };
        }
        let mean = pairs.iter().map(|p| p.0 * p.1).sum::<f64>() / total;
        let mut acc = 0.0;
        let mut p95 = max;
        for &(v, w) in &pairs {
            acc += w;
            if acc >= 0.95 * total {
                p95 = v;
                break;
            }
        }
        Stat { mean, p95, max }
    }
}

/// Per-face measures of a chart's flattening, with the scale `s` applied to the UVs.
pub(crate) struct FaceMeasures {
    /// 3D areas.
    pub area: Vec<f64>,
    /// σ₁, σ₂, det per face (NaN for a degenerate face).
    pub sigma: Vec<(f64, f64, f64)>,
}

impl FaceMeasures {
    pub(crate) fn new(
        chart: &ChartMesh,
        pos: &[Vector3<f64>],
        uv: &[Vector2<f64>],
        s: f64,
    ) -> Self {
        let mut area = Vec::with_capacity(chart.tris.len());
        let mut sigma = Vec::with_capacity(chart.tris.len());
        for t in &chart.tris {
            let p = t.map(|v| pos[v as usize]);
            let u = t.map(|v| uv[v as usize] * s);
            area.push(0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm());
            sigma.push(
                jacobian(p, u).map_or((f64::NAN, f64::NAN, f64::NAN), |j| singular_values(&j)),
            );
        }
        FaceMeasures { area, sigma }
    }

    /// max(σ₁, 1/σ₂) per face.
    pub(crate) fn stretch(&self) -> Vec<f64> {
        self.sigma.iter().map(|&(a, b, _)| a.max(1.0 / b)).collect()
    }
}

/// The scale that makes the UV area of a chart its surface area.
pub(crate) fn area_scale(chart: &ChartMesh, pos: &[Vector3<f64>], uv: &[Vector2<f64>]) -> f64 {
    let (mut a3, mut a2) = (0.0, 0.0);
    for t in &chart.tris {
        let p = t.map(|v| pos[v as usize]);
        a3 += 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        a2 += signed_area(t.map(|v| uv[v as usize])).abs();
    }
    let s = (a3 / a2).sqrt();
    if s.is_finite() && s > 0.0 {
        s
    } else {
        1.0
    }
}

/// Why a flattening is not valid, or `None` when it is (see the module documentation).
pub(crate) fn invalid(chart: &ChartMesh, uv: &[Vector2<f64>]) -> Option<&'static str> {
    let n = chart.num_vertices();
    if uv.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
        return Some("a coordinate is not finite");
    }
    let mut angle_sum = vec![0.0f64; n];
    for t in &chart.tris {
        let u = t.map(|v| uv[v as usize]);
        let a = signed_area(u);
        if a <= 0.0 || a.is_nan() {
            return Some("a triangle is flipped or degenerate");
        }
        for k in 0..3 {
            let a = u[(k + 1) % 3] - u[k];
            let b = u[(k + 2) % 3] - u[k];
            angle_sum[t[k] as usize] += a.perp(&b).atan2(a.dot(&b));
        }
    }
    let mut on_boundary = vec![false; n];
    for e in &chart.boundary {
        on_boundary[e[0] as usize] = true;
        on_boundary[e[1] as usize] = true;
    }
    let two_pi = std::f64::consts::TAU;
    if (0..n).any(|v| !on_boundary[v] && (angle_sum[v] - two_pi).abs() > 1e-6 * two_pi) {
        return Some("the UV angles around an interior vertex do not add up to 2π");
    }
    // A boundary vertex whose fan turns through 2π or more wraps over itself (the boundary
    // edges there share the vertex, so the crossing test below does not see it).
    if (0..n).any(|v| on_boundary[v] && angle_sum[v] >= two_pi * (1.0 - 1e-9)) {
        return Some("the UV angles at a boundary vertex reach 2π");
    }
    if boundary_crosses(chart, uv) {
        return Some("the UV boundary crosses itself");
    }
    None
}

/// True when two boundary edges that share no vertex cross (a uniform grid of the edges'
/// boxes, then exact orientation tests).
fn boundary_crosses(chart: &ChartMesh, uv: &[Vector2<f64>]) -> bool {
    let segs: Vec<(usize, usize)> =
        chart.boundary.iter().map(|e| (e[0] as usize, e[1] as usize)).collect();
    if segs.len() < 4 {
        return false;
    }
    let (mut lo, mut hi) = (Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY));
    let mut total = 0.0;
    for &(a, b) in &segs {
        lo = lo.inf(&uv[a]).inf(&uv[b]);
        hi = hi.sup(&uv[a]).sup(&uv[b]);
        total += (uv[b] - uv[a]).norm();
    }
    let cell = (total / segs.len() as f64).max((hi - lo).max() / 2048.0).max(f64::MIN_POSITIVE);
    let nx = (((hi.x - lo.x) / cell) as usize + 1).min(4096);
    let ny = (((hi.y - lo.y) / cell) as usize + 1).min(4096);
    let cell_of = |p: Vector2<f64>| {
        let i = (((p.x - lo.x) / cell) as usize).min(nx - 1);
        let j = (((p.y - lo.y) / cell) as usize).min(ny - 1);
        (i, j)
    };
    let mut grid: std::collections::HashMap<(usize, usize), Vec<u32>> = Default::default();
    for (k, &(a, b)) in segs.iter().enumerate() {
        let (i0, j0) = cell_of(uv[a].inf(&uv[b]));
        let (i1, j1) = cell_of(uv[a].sup(&uv[b]));
        for i in i0..=i1 {
            for j in j0..=j1 {
                grid.entry((i, j)).or_default().push(k as u32);
            }
        }
    }
    let orient = |a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>| (b - a).perp(&(c - a));
    let mut keys: Vec<_> = grid.keys().copied().collect();
    keys.sort_unstable();
    for key in keys {
        let list = &grid[&key];
        for (x, &s) in list.iter().enumerate() {
            for &t in &list[x + 1..] {
                let (a, b) = segs[s as usize];
                let (c, d) = segs[t as usize];
                if a == c || a == d || b == c || b == d {
                    continue;
                }
                let (pa, pb, pc, pd) = (uv[a], uv[b], uv[c], uv[d]);
                let d1 = orient(pa, pb, pc);
                let d2 = orient(pa, pb, pd);
                let d3 = orient(pc, pd, pa);
                let d4 = orient(pc, pd, pb);
                if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
                    return true;
                }
            }
        }
    }
    false
}
