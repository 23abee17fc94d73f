//! Evaluating the direction field inside a triangle, and finding its singularities.
//!
//! Inside a triangle the field is the barycentric blend of the corner directions,
//! `d(p) = Σ λᵢ(p) dᵢ`, normalized to unit *surface* length, `d / √I(d, d)`. For a line
//! field (k = 2) each corner is first flipped so that `I(dᵢ, h) ≥ 0` for the current heading
//! `h`; the blend is then a consistent vector field near the stroke and a stroke never
//! reverses (Knöppel et al., *Globally optimal direction fields*, 2013, §6 traces the same
//! way).
//!
//! A triangle is singular when the field turns by a non-zero multiple of 2π/k around its
//! boundary (the discrete Poincaré index, Ray et al., *Geometry-aware direction field
//! processing*, 2009, §3), or when a corner vector vanishes.

use std::f64::consts::PI;

use crate::geom::{cross, norm, scale, sub, Vec2};
pub use crate::mesh::Singularity;
use crate::mesh::{Domain, Symmetry};

/// Below this fraction of `Σ λᵢ |dᵢ|` the blended field counts as vanishing or incoherent.
const VANISH_RATIO: f64 = 1e-2;

/// Unit-surface-length field direction at barycentric `bary` of face `f`, aligned to
/// `heading` for line fields (to the first corner when there is no heading). `None` where
/// the field vanishes or its corners disagree.
pub(crate) fn sample(dom: &Domain, f: u32, bary: [f64; 3], heading: Option<Vec2>) -> Option<Vec2> {
    let t = dom.tris[f as usize];
    let m = &dom.metric[f as usize];
    let mut v = [0.0, 0.0];
    let mut mag = 0.0;
    let reference = heading.unwrap_or(dom.dirs[t[0] as usize]);
    for i in 0..3 {
        let mut d = dom.dirs[t[i] as usize];
        if dom.symmetry == Symmetry::Line && m.inner(d, reference) < 0.0 {
            d = [-d[0], -d[1]];
        }
        let w = bary[i].max(0.0);
        v[0] += w * d[0];
        v[1] += w * d[1];
        mag += w * norm(d);
    }
    let len = norm(v);
    if !(len > VANISH_RATIO * mag && mag > 0.0) {
        return None;
    }
    let l = m.length(v);
    (l > 0.0).then(|| scale(v, 1.0 / l))
}

fn wrap(a: f64) -> f64 {
    let mut a = a % (2.0 * PI);
    if a > PI {
        a -= 2.0 * PI;
    } else if a <= -PI {
        a += 2.0 * PI;
    }
    a
}

/// All singularities of the field, in face order.
///
/// A face is singular when its boundary turning is a non-zero multiple of 2π/k, or when the
/// linear blend of the corners' k-fold representation `rᵢ = |dᵢ| (cos kθᵢ, sin kθᵢ)`
/// vanishes inside the closed face (this catches zeros on edges and vertices, where the
/// turning sum is ambiguous). The index is the turning number when it is unambiguous, else
/// `sign(det ∂r/∂uv) / k`, the index of the linear blend's zero. Zeros shared by several
/// faces (on an edge or vertex) are reported once.
pub fn singularities(dom: &Domain) -> Vec<Singularity> {
    let k = match dom.symmetry {
        Symmetry::Vector => 1.0,
        Symmetry::Line => 2.0,
    };
    let mut out = Vec::new();
    let b = dom.bbox;
    let merge = 1e-9 * ((b[1][0] - b[0][0]).abs() + (b[1][1] - b[0][1]).abs());
    for (f, t) in dom.tris.iter().enumerate() {
        let d = t.map(|v| dom.dirs[v as usize]);
        let c = dom.corners(f as u32);
        let ang = d.map(|x| k * x[1].atan2(x[0]));
        let turn: f64 = (0..3).map(|i| wrap(ang[(i + 1) % 3] - ang[i])).sum();
        let orient = cross(sub(c[1], c[0]), sub(c[2], c[0])).signum();
        let zero = zero_in_triangle(c, d, k);
        let clear_turn = turn.abs() > PI + 1e-6;
        if !clear_turn && zero.is_none() {
            continue;
        }
        let (uv, index) = match zero {
            Some((uv, det_sign)) if !clear_turn => (uv, det_sign / k),
            _ => {
                let uv = zero.map(|z| z.0).unwrap_or([
                    (c[0][0] + c[1][0] + c[2][0]) / 3.0,
                    (c[0][1] + c[1][1] + c[2][1]) / 3.0,
                ]);
                // The turning sum is k · 2π · index (mirrored UV triangles flip it).
                (uv, (turn * orient / (2.0 * PI * k) * 2.0).round() / 2.0)
            }
        };
        // A zero on an edge or vertex shows up in every incident face: keep the first.
        let dup = out.iter().any(|s: &Singularity| {
            (s.uv[0] - uv[0]).abs() <= merge && (s.uv[1] - uv[1]).abs() <= merge
        });
        if !dup {
            out.push(Singularity { uv, face: f as u32, index });
        }
    }
    out
}

/// Where the blend of the corners' k-fold representation vanishes (solve
/// `Σ λᵢ rᵢ = 0, Σ λᵢ = 1`), if inside the closed triangle, with the sign of the blend's
/// Jacobian determinant in UV.
fn zero_in_triangle(c: [Vec2; 3], d: [Vec2; 3], k: f64) -> Option<(Vec2, f64)> {
    let r = d.map(|x| {
        let a = k * x[1].atan2(x[0]);
        let l = norm(x);
        [l * a.cos(), l * a.sin()]
    });
    // λ2 = 1 − λ0 − λ1: (r0 − r2) λ0 + (r1 − r2) λ1 = −r2.
    let a = sub(r[0], r[2]);
    let b = sub(r[1], r[2]);
    let det = cross(a, b);
    let scale = norm(r[0]).max(norm(r[1])).max(norm(r[2]));
    if det.abs().is_nan() || det.abs() <= 1e-12 * scale * scale {
        return None;
    }
    let rhs = [-r[2][0], -r[2][1]];
    let l0 = cross(rhs, b) / det;
    let l1 = cross(a, rhs) / det;
    let l = [l0, l1, 1.0 - l0 - l1];
    if l.iter().any(|x| !(-1e-9..=1.0 + 1e-9).contains(x)) {
        return None;
    }
    // det ∂r/∂uv = cross(r1 − r0, r2 − r0) / cross(c1 − c0, c2 − c0).
    let jr = cross(sub(r[1], r[0]), sub(r[2], r[0]));
    let jc = cross(sub(c[1], c[0]), sub(c[2], c[0]));
    let p = [0, 1].map(|j| l[0] * c[0][j] + l[1] * c[1][j] + l[2] * c[2][j]);
    Some((p, (jr / jc).signum()))
}

impl Domain {
    /// The field's singularities ([`crate::singularities`]), computed once and cached.
    pub fn singularities(&self) -> &[Singularity] {
        self.sing.get_or_init(|| singularities(self))
    }
}
