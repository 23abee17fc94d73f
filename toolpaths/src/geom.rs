//! Small vector helpers and the first fundamental form (the surface metric in UV).

use serde::{Deserialize, Serialize};

/// A 2D point or vector in UV (mm on a flat sheet, or chart units).
pub type Vec2 = [f64; 2];
/// A 3D point or vector (mm).
pub type Vec3 = [f64; 3];

/// Length unit of the plan and of the length options of [`crate::GcodeOptions`]. The program is
/// always printed in millimetres (`G21`): lengths are multiplied by [`LengthUnit::in_mm`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LengthUnit {
    /// Millimetres (the default).
    #[default]
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Inches.
    In,
}

impl LengthUnit {
    /// Length of one unit in millimetres.
    pub fn in_mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::Cm => 10.0,
            LengthUnit::M => 1000.0,
            LengthUnit::In => 25.4,
        }
    }

    /// Short name (`mm`, `cm`, `m`, `in`).
    pub fn as_str(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::Cm => "cm",
            LengthUnit::M => "m",
            LengthUnit::In => "in",
        }
    }
}

pub(crate) fn sub(a: Vec2, b: Vec2) -> Vec2 {
    [a[0] - b[0], a[1] - b[1]]
}
pub(crate) fn add(a: Vec2, b: Vec2) -> Vec2 {
    [a[0] + b[0], a[1] + b[1]]
}
pub(crate) fn scale(a: Vec2, s: f64) -> Vec2 {
    [a[0] * s, a[1] * s]
}
pub(crate) fn dot(a: Vec2, b: Vec2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
pub(crate) fn cross(a: Vec2, b: Vec2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
pub(crate) fn norm(a: Vec2) -> f64 {
    dot(a, a).sqrt()
}
pub(crate) fn sub3(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn dot3(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn norm3(a: Vec3) -> f64 {
    dot3(a, a).sqrt()
}
/// The closest point to `p` on the segment `[a, b]` in space, with its parameter in `[0, 1]`
/// along the segment (0 when `a == b`).
pub(crate) fn segment_foot3(p: Vec3, a: Vec3, b: Vec3) -> (f64, Vec3) {
    let ab = sub3(b, a);
    let l2 = dot3(ab, ab);
    let t = if l2 > 0.0 { (dot3(sub3(p, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (t, [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]])
}
pub(crate) fn cross3(a: Vec3, b: Vec3) -> Vec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Length of a helical arc in the XY plane from `from` to `to` about `center`, counter-
/// clockwise when `ccw`: `√((r·θ)² + Δz²)` with `r = |from − center|` in XY and `θ` the sweep
/// in `[0, 2π)` (coinciding ends in XY sweep 0: a straight move in Z).
pub(crate) fn helix_length(from: Vec3, to: Vec3, center: Vec2, ccw: bool) -> f64 {
    let r = ((from[0] - center[0]).powi(2) + (from[1] - center[1]).powi(2)).sqrt();
    let a0 = (from[1] - center[1]).atan2(from[0] - center[0]);
    let a1 = (to[1] - center[1]).atan2(to[0] - center[0]);
    let tau = std::f64::consts::TAU;
    let sweep = if ccw { (a1 - a0).rem_euclid(tau) } else { (a0 - a1).rem_euclid(tau) };
    ((r * sweep).powi(2) + (to[2] - from[2]).powi(2)).sqrt()
}

/// The first fundamental form of the surface in UV coordinates,
/// `I(du, dv) = E du² + 2F du dv + G dv²`, constant over a triangle for a piecewise-linear lift.
///
/// For a triangle with UV edges `e₁, e₂` and 3D edges `E₁, E₂`, the Jacobian of the lift is
/// `J = [E₁ E₂]·[e₁ e₂]⁻¹` and the metric is `JᵀJ` (do Carmo, *Differential Geometry of
/// Curves and Surfaces*, §2-5). The identity metric means UV units are surface millimetres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metric {
    /// `E = ⟨x_u, x_u⟩`.
    pub e: f64,
    /// `F = ⟨x_u, x_v⟩`.
    pub f: f64,
    /// `G = ⟨x_v, x_v⟩`.
    pub g: f64,
}

impl Metric {
    /// The Euclidean metric (UV units are millimetres on the part).
    pub const IDENTITY: Metric = Metric { e: 1.0, f: 0.0, g: 1.0 };

    /// Metric of a triangle from its UV corners and 3D corners (`JᵀJ`, see the type docs).
    /// Returns `None` when the UV triangle is degenerate.
    pub fn from_triangle(uv: [Vec2; 3], xyz: [Vec3; 3]) -> Option<Metric> {
        let e1 = sub(uv[1], uv[0]);
        let e2 = sub(uv[2], uv[0]);
        let det = cross(e1, e2);
        if det.abs() < f64::MIN_POSITIVE * 1e6 {
            return None;
        }
        let p1 = sub3(xyz[1], xyz[0]);
        let p2 = sub3(xyz[2], xyz[0]);
        // [e1 e2]^-1 = 1/det [[e2y, -e2x], [-e1y, e1x]]
        let inv = [[e2[1] / det, -e2[0] / det], [-e1[1] / det, e1[0] / det]];
        let xu = [0, 1, 2].map(|k| p1[k] * inv[0][0] + p2[k] * inv[1][0]);
        let xv = [0, 1, 2].map(|k| p1[k] * inv[0][1] + p2[k] * inv[1][1]);
        Some(Metric { e: dot3(xu, xu), f: dot3(xu, xv), g: dot3(xv, xv) })
    }

    /// `I(a, b) = aᵀ [[E F] [F G]] b`.
    pub fn inner(&self, a: Vec2, b: Vec2) -> f64 {
        self.e * a[0] * b[0] + self.f * (a[0] * b[1] + a[1] * b[0]) + self.g * a[1] * b[1]
    }

    /// Surface length of the UV vector `a`: `√I(a, a)`.
    pub fn length(&self, a: Vec2) -> f64 {
        self.inner(a, a).max(0.0).sqrt()
    }

    /// Area element `√(EG − F²)`: surface area per unit UV area.
    pub fn area_factor(&self) -> f64 {
        (self.e * self.g - self.f * self.f).max(0.0).sqrt()
    }

    /// Smallest and largest eigenvalues of `[[E F] [F G]]`; their square roots bound how much
    /// a UV length is stretched on the surface.
    pub fn eigen_range(&self) -> (f64, f64) {
        let tr = 0.5 * (self.e + self.g);
        let d = (0.25 * (self.e - self.g).powi(2) + self.f * self.f).sqrt();
        ((tr - d).max(0.0), tr + d)
    }

    /// A UV vector `n` with `I(t, n) = 0` and `I(n, n) = 1`, turned counter-clockwise from
    /// `t` in UV (the surface normal of the stroke, expressed in UV).
    pub fn unit_normal(&self, t: Vec2) -> Vec2 {
        let gt = [self.e * t[0] + self.f * t[1], self.f * t[0] + self.g * t[1]];
        let mut n = [-gt[1], gt[0]];
        if cross(t, n) < 0.0 {
            n = [-n[0], -n[1]];
        }
        let l = self.length(n);
        if l > 0.0 {
            scale(n, 1.0 / l)
        } else {
            [0.0, 0.0]
        }
    }

    /// Whether all three coefficients are finite and the form is positive definite.
    pub fn is_valid(&self) -> bool {
        self.e.is_finite()
            && self.f.is_finite()
            && self.g.is_finite()
            && self.e > 0.0
            && self.g > 0.0
            && self.e * self.g - self.f * self.f > 0.0
    }
}

/// Euclidean distance in the plane from `p` to the segment `[a, b]` (a point when `a == b`).
///
/// The plane distance (no metric) of both crates: the toolpaths' part-edge test and grainline's
/// strokes read back in UV (`uvfield`) measure with it.
pub fn segment_distance(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    let (ab, ap) = (sub(b, a), sub(p, a));
    let l2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if l2 > 0.0 { ((ap[0] * ab[0] + ap[1] * ab[1]) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
}

/// Distance from `p` to the segment `[a, b]` measured with metric `m`.
pub(crate) fn point_segment_distance(m: &Metric, p: Vec2, a: Vec2, b: Vec2) -> f64 {
    let ab = sub(b, a);
    let ap = sub(p, a);
    let l2 = m.inner(ab, ab);
    let t = if l2 > 0.0 { (m.inner(ap, ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    m.length(sub(ap, scale(ab, t)))
}

/// Barycentric coordinates of `p` in face `f` (they sum to 1; all ≥ 0 inside).
#[inline]
pub(crate) fn barycentric(corners: [Vec2; 3], p: Vec2) -> [f64; 3] {
    let [a, b, c] = corners;
    let area = cross(sub(b, a), sub(c, a));
    let l0 = cross(sub(b, p), sub(c, p)) / area;
    let l1 = cross(sub(c, p), sub(a, p)) / area;
    [l0, l1, 1.0 - l0 - l1]
}
