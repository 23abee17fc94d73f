//! Rotary (4-axis) fixtures: a turned part held on an A axis along machine X.
//!
//! **The mapping.** A part point `P` (part coordinates, the plan's length unit) is held so that
//! the part's axis (a point `c` and a unit direction `d`) lies on machine X. With `z₀` the unit
//! part direction that `A = 0` turns to machine +Z (`zero`, perpendicular to `d`) and
//! `y₀ = z₀ × d` (the part direction at machine +Y when `A = 0`, so that `(d, y₀, z₀)` is
//! right-handed like machine `(X, Y, Z)`):
//!
//! ```text
//! x = (P − c)·d                       machine X
//! r = (P − c) − x d                   the radial vector, |r| its distance from the axis
//! A = atan2(r·y₀, r·z₀)               degrees; turning the part by A about +X brings r to +Z
//! Z = |r| − contact_depth             the tool on top of the part, along machine Z
//! ```
//!
//! `A` is **right-handed about +X**: positive `A` turns the part counter-clockwise seen from
//! +X looking towards the origin, LinuxCNC's convention for the A axis (a rotation `R_x(A)`
//! takes `y₀` to `z₀` at `A = +90°`). The inverse, used by the tests and by anyone checking a
//! program: the tool point `(x, 0, Z)` in the machine frame, turned by `−A` about X, is the
//! part point `c + x d + Z sin A · y₀ + Z cos A · z₀` (plus `contact_depth` radially).
//!
//! **A developed as a length.** Inside the planner the angle is carried as the arc length
//! `s = r_ref · A` (radians) at the part's largest radius `r_ref`, so tangents, leads,
//! overtravel and the simplification tolerance are lengths: a linear move in `(x, s, Z)` is
//! the move the controller makes in `(X, A, Z)`, and its distance from the sampled stroke in
//! that space bounds its distance on the part (the arc at a radius `|r| ≤ r_ref` is shorter).
//! The program prints `A = s / r_ref` in degrees.
//!
//! **Unwrapped A.** Along a stroke `A` is unwrapped (each step the equivalent angle nearest the
//! previous one), and each pass starts at the equivalent of its start nearest where the last
//! pass ended: `A` never jumps by 360° and can run past ±360° over a program. Configure the
//! axis as an ordinary rotary axis (no `WRAPPED_ROTARY`, no soft limits on A, or limits wide
//! enough for the program's range).
//!
//! **Found from the mesh** ([`fit_axis`]): for a body of revolution every normal line meets
//! the axis. The candidate axes are the principal axes of the part's vertices (for a body of
//! revolution the axis is one of them); for each, the axis point that makes the normals miss
//! it least (linear least squares of `(P − c)·(n × d) = 0`), and the miss angle of each
//! normal, `asin |n · (d × r̂)|`. The candidate with the smallest 95th-percentile miss wins;
//! above [`MAX_MISS_DEG`], or with the axis farther from the part than its size (a flat part
//! fits an axis at infinity), the part is refused as not a body of revolution.

use serde::{Deserialize, Serialize};

use crate::error::{short, Result, ToolpathError};
use crate::geom::{cross3, dot3, norm3, sub3, Vec3};

/// Largest 95th-percentile angle (degrees) by which the normals of a part may miss the axis
/// [`fit_axis`] finds.
pub const MAX_MISS_DEG: f64 = 3.0;

/// A turned part's axis, in the part's coordinates (the plan's length unit).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct RotaryAxis {
    /// A point on the axis.
    pub point: Vec3,
    /// The axis direction (machine +X); any length > 0.
    pub direction: Vec3,
    /// The part direction that `A = 0` turns to machine +Z (projected perpendicular to the
    /// axis). Default: the part's +Z, +Y or +X, whichever is least aligned with the axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zero: Option<Vec3>,
}

/// The word `"auto"`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub enum Auto {
    /// Find the axis from the part ([`fit_axis`]).
    #[default]
    Auto,
}

/// Where the rotary axis comes from: `"auto"` (found from a body of revolution) or given.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub enum AxisSpec {
    /// `"auto"`: fitted from the part's positions and normals.
    Auto(Auto),
    /// `{"point": [..], "direction": [..], "zero": [..]}`.
    Given(RotaryAxis),
}

impl Default for AxisSpec {
    fn default() -> Self {
        AxisSpec::Auto(Auto::Auto)
    }
}

/// A resolved fixture: the axis, the zero direction, the radius A is developed at.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Fixture {
    /// A point on the axis (part coordinates).
    pub point: Vec3,
    /// Unit axis direction: machine +X.
    pub direction: Vec3,
    /// Unit part direction at machine +Z when `A = 0` (perpendicular to `direction`).
    pub zero: Vec3,
    /// The part's largest distance from the axis: the radius at which the planner develops A
    /// into a length (see the module docs).
    pub r_ref: f64,
    /// The brush's contact depth (the plan's `contact_depth`): the surface is this far above
    /// the tool point, radially.
    pub contact_depth: f64,
}

fn unit(v: Vec3) -> Option<Vec3> {
    let l = norm3(v);
    (l.is_finite() && l > 1e-12).then(|| v.map(|x| x / l))
}

fn axis_err(message: String) -> ToolpathError {
    ToolpathError::Rotary { key: "plan.z_mode.axis", message }
}

/// The default zero: the part's +Z, +Y or +X, whichever is least aligned with `d` (the first
/// on a tie), projected perpendicular to `d`.
fn default_zero(d: Vec3) -> Vec3 {
    let mut best = [0.0, 0.0, 1.0];
    for e in [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]] {
        if dot3(e, d).abs() < dot3(best, d).abs() - 1e-12 {
            best = e;
        }
    }
    perpendicular(best, d).unwrap_or([0.0, 0.0, 1.0])
}

fn perpendicular(v: Vec3, d: Vec3) -> Option<Vec3> {
    let t = dot3(v, d);
    unit([v[0] - t * d[0], v[1] - t * d[1], v[2] - t * d[2]])
}

/// The unit direction and zero of a given axis: the direction normalized, the zero projected
/// perpendicular to it (refused when parallel, zero or non-finite; naming `plan.z_mode.axis`).
pub fn check_axis(axis: &RotaryAxis) -> Result<(Vec3, Vec3)> {
    if !axis.point.iter().chain(&axis.direction).all(|x| x.is_finite()) {
        return Err(axis_err("point and direction must be finite".into()));
    }
    let d = unit(axis.direction)
        .ok_or_else(|| axis_err("direction must be a non-zero vector".into()))?;
    let zero = match axis.zero {
        None => default_zero(d),
        Some(z) => {
            if !z.iter().all(|x| x.is_finite()) {
                return Err(axis_err("zero must be finite".into()));
            }
            perpendicular(z, d).filter(|_| norm3(cross3(z, d)) > 1e-6 * norm3(z)).ok_or_else(
                || axis_err("zero must not be parallel to direction (nor zero)".into()),
            )?
        }
    };
    Ok((d, zero))
}

impl Fixture {
    /// A fixture for a given axis ([`check_axis`]); `r_ref` is the largest radius of `points`.
    pub fn new(axis: RotaryAxis, points: &[Vec3], contact_depth: f64) -> Result<Fixture> {
        let (direction, zero) = check_axis(&axis)?;
        let mut f = Fixture { point: axis.point, direction, zero, r_ref: 0.0, contact_depth };
        f.r_ref = points.iter().map(|&p| f.cylindrical(p)[2]).fold(0.0, f64::max);
        if !(f.r_ref.is_finite() && f.r_ref > 0.0) {
            return Err(axis_err("the part lies on its axis (largest radius 0)".into()));
        }
        Ok(f)
    }

    /// `y₀ = zero × direction`: the part direction at machine +Y when `A = 0`.
    pub fn y0(&self) -> Vec3 {
        cross3(self.zero, self.direction)
    }

    /// `(x, A in radians in (−π, π], |r|)` of a part point (see the module docs).
    pub fn cylindrical(&self, p: Vec3) -> Vec3 {
        let q = sub3(p, self.point);
        let x = dot3(q, self.direction);
        let r = [0, 1, 2].map(|k| q[k] - x * self.direction[k]);
        [x, dot3(r, self.y0()).atan2(dot3(r, self.zero)), norm3(r)]
    }

    /// The part point under the tool point `(x, 0, z)` at `a_deg`: the tool point turned by
    /// `−A` about X (no contact depth added).
    pub fn to_part(&self, x: f64, a_deg: f64, z: f64) -> Vec3 {
        let (s, c) = a_deg.to_radians().sin_cos();
        let y0 = self.y0();
        [0, 1, 2]
            .map(|k| self.point[k] + x * self.direction[k] + z * (s * y0[k] + c * self.zero[k]))
    }

    /// Angle (degrees) between a unit normal at `p` and the radial direction (the tool axis
    /// once the point is turned to the top); 90° on the axis.
    pub fn tilt_deg(&self, p: Vec3, n: Vec3) -> f64 {
        let q = sub3(p, self.point);
        let x = dot3(q, self.direction);
        let r = [0, 1, 2].map(|k| q[k] - x * self.direction[k]);
        match unit(r) {
            Some(rh) => dot3(rh, n).clamp(-1.0, 1.0).acos().to_degrees(),
            None => 90.0,
        }
    }

    /// The period of the developed angle `s = r_ref · A`: `2π r_ref`.
    pub fn period(&self) -> f64 {
        std::f64::consts::TAU * self.r_ref
    }
}

/// Length of the path the contact point runs on the part during a linear move in `(X, A, Z)`
/// from `from` to `to` (`[x, A in degrees, z]`, any length unit; `depth` the contact depth in
/// that unit): `∫ √(ẋ² + ρ̇² + ρ² Ȧ²) dt` with `ρ = z + depth` the contact point's radius, by
/// 5-point Gauss–Legendre (the integrand is smooth; exact for a helix on a cylinder).
pub fn rotary_move_length(from: Vec3, to: Vec3, depth: f64) -> f64 {
    const X: [f64; 5] = [
        -0.906_179_845_938_664,
        -0.538_469_310_105_683,
        0.0,
        0.538_469_310_105_683,
        0.906_179_845_938_664,
    ];
    const W: [f64; 5] = [
        0.236_926_885_056_189,
        0.478_628_670_499_366,
        0.568_888_888_888_889,
        0.478_628_670_499_366,
        0.236_926_885_056_189,
    ];
    let (dx, dz, da) = (to[0] - from[0], to[2] - from[2], (to[1] - from[1]).to_radians());
    let lin = dx * dx + dz * dz;
    X.iter()
        .zip(W)
        .map(|(&t, w)| {
            let rho = from[2] + depth + dz * 0.5 * (t + 1.0);
            0.5 * w * (lin + (rho * da).powi(2)).sqrt()
        })
        .sum()
}

/// Unwrap the developed angles `s` (index 1) of a polyline: each the equivalent (mod
/// `period`) nearest the previous one.
pub(crate) fn unwrap_developed(points: &mut [Vec3], period: f64) {
    for k in 1..points.len() {
        let prev = points[k - 1][1];
        points[k][1] = nearest_equivalent(points[k][1], prev, period);
    }
}

/// The value equivalent to `v` (mod `period`) nearest `target`.
pub(crate) fn nearest_equivalent(v: f64, target: f64, period: f64) -> f64 {
    v - ((v - target) / period).round() * period
}

/// Eigenvectors of a symmetric 3 × 3 matrix (cyclic Jacobi), as columns of the result.
#[allow(clippy::needless_range_loop)]
fn eigenvectors(mut a: [[f64; 3]; 3]) -> [Vec3; 3] {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        if off < 1e-30 * (a[0][0].powi(2) + a[1][1].powi(2) + a[2][2].powi(2)).max(1e-300) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    [0, 1, 2].map(|j| [v[0][j], v[1][j], v[2][j]])
}

/// Solve a 3 × 3 system by Cramer's rule; none when (nearly) singular.
fn solve3(m: [[f64; 3]; 3], b: Vec3) -> Option<Vec3> {
    let det = |m: [[f64; 3]; 3]| dot3(m[0], cross3(m[1], m[2]));
    let d = det(m);
    let scale = m.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max).powi(3);
    if d.is_nan() || d.abs() <= 1e-12 * scale {
        return None;
    }
    Some([0, 1, 2].map(|j| {
        let mut mj = m;
        for i in 0..3 {
            mj[i][j] = b[i];
        }
        det(mj) / d
    }))
}

/// What [`fit_axis`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisFit {
    /// The axis: `point` on it at the part's lowest axial coordinate (X = 0 at the part's end),
    /// `direction` with its largest component positive, `zero` the default.
    pub axis: RotaryAxis,
    /// 95th percentile of the angle by which the normals miss the axis, degrees.
    pub miss_p95_deg: f64,
}

/// The normals' miss sines `n · (d × r̂)` about the axis through `c` along `d` (points on the
/// axis left out).
fn misses(points: &[Vec3], normals: &[Vec3], c: Vec3, d: Vec3) -> Vec<f64> {
    points
        .iter()
        .zip(normals)
        .filter_map(|(p, n)| {
            let q = sub3(*p, c);
            let x = dot3(q, d);
            let rh = unit([0, 1, 2].map(|k| q[k] - x * d[k]))?;
            Some(dot3(*n, cross3(d, rh)))
        })
        .collect()
}

/// Refine an axis by Levenberg–Marquardt on the miss sines (4 parameters: the direction tilted
/// in its normal plane, the point moved in it; forward-difference Jacobian).
fn refine(points: &[Vec3], normals: &[Vec3], mut c: Vec3, mut d: Vec3) -> (Vec3, Vec3) {
    let cost = |c: Vec3, d: Vec3| misses(points, normals, c, d).iter().map(|m| m * m).sum::<f64>();
    let size = points.iter().map(|p| norm3(sub3(*p, c))).fold(0.0, f64::max).max(1e-12);
    let mut mu = 1e-3;
    let mut f0 = cost(c, d);
    for _ in 0..30 {
        let u = perpendicular(default_zero(d), d).unwrap_or([1.0, 0.0, 0.0]);
        let v = cross3(d, u);
        let at = |x: [f64; 4]| {
            let dd = unit([0, 1, 2].map(|k| d[k] + x[0] * u[k] + x[1] * v[k])).unwrap_or(d);
            let cc = [0, 1, 2].map(|k| c[k] + size * (x[2] * u[k] + x[3] * v[k]));
            (cc, dd)
        };
        let r0 = misses(points, normals, c, d);
        let h = 1e-7;
        let cols: Vec<Vec<f64>> = (0..4)
            .map(|j| {
                let mut x = [0.0; 4];
                x[j] = h;
                let (cc, dd) = at(x);
                let r = misses(points, normals, cc, dd);
                r.iter().zip(&r0).map(|(a, b)| (a - b) / h).collect()
            })
            .collect();
        if cols.iter().any(|col| col.len() != r0.len()) {
            break;
        }
        let mut jtj = [[0.0; 4]; 4];
        let mut jtr = [0.0; 4];
        for i in 0..4 {
            for j in 0..4 {
                jtj[i][j] = cols[i].iter().zip(&cols[j]).map(|(a, b)| a * b).sum();
            }
            jtr[i] = -cols[i].iter().zip(&r0).map(|(a, b)| a * b).sum::<f64>();
        }
        let mut improved = false;
        while mu < 1e8 {
            let mut a = jtj;
            for (i, row) in a.iter_mut().enumerate() {
                row[i] += mu * (jtj[i][i] + 1e-12);
            }
            let Some(x) = solve4(a, jtr) else { break };
            let (cc, dd) = at(x);
            let f1 = cost(cc, dd);
            if f1 < f0 {
                (c, d, f0, mu) = (cc, dd, f1, mu * 0.3);
                improved = true;
                break;
            }
            mu *= 10.0;
        }
        if !improved || f0 < 1e-24 {
            break;
        }
    }
    (c, d)
}

/// Solve a 4 × 4 system by Gaussian elimination with partial pivoting; none when singular.
#[allow(clippy::needless_range_loop)]
fn solve4(mut a: [[f64; 4]; 4], mut b: [f64; 4]) -> Option<[f64; 4]> {
    for col in 0..4 {
        let piv = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].is_nan() || a[piv][col].abs() <= 1e-300 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for row in col + 1..4 {
            let f = a[row][col] / a[col][col];
            for k in col..4 {
                a[row][k] -= f * a[col][k];
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 4];
    for row in (0..4).rev() {
        let s: f64 = (row + 1..4).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The axis through the point that makes the normals miss direction `d` least, refined
/// ([`refine`]), and the normals' 95th-percentile miss angle (degrees).
fn candidate(points: &[Vec3], normals: &[Vec3], c0: Vec3, d: Vec3) -> Option<(Vec3, Vec3, f64)> {
    let (mut m3, mut b) = ([[0.0; 3]; 3], [0.0; 3]);
    for (p, n) in points.iter().zip(normals) {
        let m = cross3(*n, d);
        let mp = dot3(m, *p);
        for i in 0..3 {
            for j in 0..3 {
                m3[i][j] += m[i] * m[j];
            }
            b[i] += m[i] * mp;
        }
    }
    let lambda = (m3[0][0] + m3[1][1] + m3[2][2]).max(1e-300) / 3.0;
    let dc0 = dot3(d, c0);
    for i in 0..3 {
        for j in 0..3 {
            m3[i][j] += lambda * d[i] * d[j];
        }
        b[i] += lambda * d[i] * dc0;
    }
    let c = solve3(m3, b)?;
    let (c, d) = refine(points, normals, c, d);
    let mut miss: Vec<f64> = misses(points, normals, c, d)
        .iter()
        .map(|m| m.abs().min(1.0).asin().to_degrees())
        .collect();
    if miss.is_empty() {
        return None;
    }
    miss.sort_by(f64::total_cmp);
    Some((c, d, miss[((miss.len() - 1) as f64 * 0.95).round() as usize]))
}

/// Find the axis of a body of revolution from its points and unit normals (see the module
/// docs); refused (naming `plan.z_mode.axis`) when the part is not near one.
pub fn fit_axis(points: &[Vec3], normals: &[Vec3]) -> Result<AxisFit> {
    let n = points.len().min(normals.len());
    if n < 3 {
        return Err(axis_err("auto: the part has fewer than 3 vertices".into()));
    }
    let (points, normals) = (&points[..n], &normals[..n]);
    let c0 = [0, 1, 2].map(|k| points.iter().map(|p| p[k]).sum::<f64>() / n as f64);
    let mut cov = [[0.0; 3]; 3];
    for p in points {
        let q = sub3(*p, c0);
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += q[i] * q[j] / n as f64;
            }
        }
    }
    let size = points.iter().map(|p| norm3(sub3(*p, c0))).fold(0.0, f64::max);
    let mut best: Option<(Vec3, Vec3, f64)> = None;
    for d in eigenvectors(cov) {
        let Some(d) = unit(d) else { continue };
        let Some((c, d, miss)) = candidate(points, normals, c0, d) else { continue };
        // An axis far outside the part fits a flat part (normals all parallel) at infinity.
        let q = sub3(c0, c);
        let off = norm3([0, 1, 2].map(|k| q[k] - dot3(q, d) * d[k]));
        if off <= size && best.is_none_or(|b| miss < b.2) {
            best = Some((c, d, miss));
        }
    }
    let Some((c, mut d, miss)) = best else {
        return Err(axis_err(
            "auto: no axis found: the part is not near a body of revolution (every principal \
             axis lies outside the part or leaves the normals undetermined); give the axis as \
             {\"point\": [..], \"direction\": [..]}"
                .into(),
        ));
    };
    if miss > MAX_MISS_DEG {
        return Err(axis_err(format!(
            "auto: the part is not near a body of revolution: its normals miss the best axis \
             (through {}, direction {}) by {}° (95th percentile), above {MAX_MISS_DEG}°; give \
             the axis as {{\"point\": [..], \"direction\": [..]}}",
            fmt3(c),
            fmt3(d),
            short((miss * 100.0).round() / 100.0)
        )));
    }
    let big = (0..3).max_by(|&i, &j| d[i].abs().total_cmp(&d[j].abs())).unwrap_or(0);
    if d[big] < 0.0 {
        d = d.map(|x| -x);
    }
    let x_min = points.iter().map(|p| dot3(sub3(*p, c), d)).fold(f64::INFINITY, f64::min);
    let point = [0, 1, 2].map(|k| c[k] + x_min * d[k]);
    let point = point.map(|x| if x.abs() < 1e-9 * size.max(1.0) { 0.0 } else { x });
    let d = d.map(|x| if x.abs() < 1e-12 { 0.0 } else { x });
    Ok(AxisFit { axis: RotaryAxis { point, direction: d, zero: None }, miss_p95_deg: miss })
}

fn fmt3(v: Vec3) -> String {
    format!("[{}, {}, {}]", short(v[0]), short(v[1]), short(v[2]))
}
