//! Evaluating the direction field inside a triangle, and finding its singularities.
//!
//! Inside a triangle the field is the barycentric blend of the corner directions,
//! `d(p) = Σ λᵢ(p) dᵢ`, normalized to unit *surface* length, `d / √I(d, d)`. For a line
//! field (k = 2) each corner is first flipped so that `I(dᵢ, h) ≥ 0` for the current heading
//! `h`; the blend is then a consistent vector field near the stroke and a stroke never
//! reverses (Knöppel et al., *Globally optimal direction fields*, 2013, §6 traces the same
//! way).
//!
//! Inside a triangle on a known surface with its corners' ambient grain
//! ([`crate::FieldMesh::ambient`], [`crate::SurfaceLift`]) the field is instead that grain
//! blended, projected onto the surface at the lifted point and pulled back into UV through
//! the lift's Jacobian ([`surface_sample`]).
//!
//! A triangle is singular when the field turns by a non-zero multiple of 2π/k around its
//! boundary (the discrete Poincaré index, Ray et al., *Geometry-aware direction field
//! processing*, 2009, §3), or when a corner vector vanishes.

use std::f64::consts::PI;

use crate::geom::{cross, norm, scale, sub, Vec2, Vec3};
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
    let line = dom.symmetry == Symmetry::Line;
    if let Some(d) = surface_sample(dom, f, bary, reference, line) {
        return d;
    }
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

/// The field at barycentric `bary` of face `f` where the face's surface and its corners'
/// ambient grain are known ([`crate::FieldMesh::ambient`]): the corners' blend `a = Σ λᵢ aᵢ` projected onto the
/// surface's tangent plane at the lifted point, `t = a − n (n·a)`, pulled back into UV
/// through the lift's Jacobian `J = ∂X/∂(u, v)` (by differences of the lift along the chord's
/// axes): `d = (JᵀJ)⁻¹ Jᵀ t`, at unit length in the face's metric and aligned as
/// `crate::field::sample` aligns. `None` on other faces; `Some(None)` where `t` vanishes
/// (the grain's own singular point, a world direction along the normal).
pub(crate) fn surface_sample(
    dom: &Domain,
    f: u32,
    bary: [f64; 3],
    reference: Vec2,
    line: bool,
) -> Option<Option<Vec2>> {
    let corners = dom.ambient.get(f as usize).copied().flatten()?;
    let hook = dom.surface.as_ref()?;
    let x = dom.chord_lift(f, bary)?;
    let (p, n) = hook.project(f, x)?;
    let a = [0, 1, 2].map(|k| (0..3).map(|i| bary[i] * corners[i][k]).sum::<f64>());
    let an = crate::geom::dot3(a, n) / crate::geom::dot3(n, n);
    let t = [0, 1, 2].map(|k| a[k] - an * n[k]);
    if crate::geom::norm3(t).is_nan() || crate::geom::norm3(t) <= 1e-2 * crate::geom::norm3(a) {
        return Some(None);
    }
    let jac = chord_jacobian(dom, f)?;
    // Differences of the lift along the chord's two UV axes, a step of 1e-4 of the axis's
    // own 3D length (the surface's curvature radius is far larger than that).
    let mut js = [[0.0; 3]; 2];
    for (c, col) in jac.iter().enumerate() {
        let h = 1e-4;
        let y = [0, 1, 2].map(|k| x[k] + h * col[k]);
        let (q, _) = hook.project(f, y)?;
        js[c] = [0, 1, 2].map(|k| (q[k] - p[k]) / h);
    }
    let dot = crate::geom::dot3;
    let (g11, g12, g22) = (dot(js[0], js[0]), dot(js[0], js[1]), dot(js[1], js[1]));
    let (r1, r2) = (dot(js[0], t), dot(js[1], t));
    let det = g11 * g22 - g12 * g12;
    if det.is_nan() || det <= 0.0 {
        return None;
    }
    let mut d = [(g22 * r1 - g12 * r2) / det, (g11 * r2 - g12 * r1) / det];
    let m = &dom.metric[f as usize];
    if line && m.inner(d, reference) < 0.0 {
        d = [-d[0], -d[1]];
    }
    let l = m.length(d);
    Some((l > 0.0 && l.is_finite()).then(|| [d[0] / l, d[1] / l]))
}

/// The chord's Jacobian `∂X/∂(u, v)` of face `f` (two 3D columns), from its corners' UV and
/// 3D positions.
fn chord_jacobian(dom: &Domain, f: u32) -> Option<[Vec3; 2]> {
    let pos = dom.positions.as_ref()?;
    let t = dom.tris[f as usize];
    let [w0, w1, w2] = t.map(|v| dom.uv[v as usize]);
    let [p0, p1, p2] = t.map(|v| pos[v as usize]);
    let (a, b) = ([w1[0] - w0[0], w1[1] - w0[1]], [w2[0] - w0[0], w2[1] - w0[1]]);
    let det = a[0] * b[1] - a[1] * b[0];
    if det.is_nan() || det == 0.0 {
        return None;
    }
    let (e1, e2) = ([0, 1, 2].map(|k| p1[k] - p0[k]), [0, 1, 2].map(|k| p2[k] - p0[k]));
    // [e1 e2] = J [a b]  →  J = [e1 e2] [a b]⁻¹.
    let inv = [[b[1] / det, -b[0] / det], [-a[1] / det, a[0] / det]];
    let col = |c: usize| [0, 1, 2].map(|k| e1[k] * inv[0][c] + e2[k] * inv[1][c]);
    Some([col(0), col(1)])
}

#[cfg(test)]
mod surface_tests {
    use super::*;
    use crate::geom::Vec3;
    use crate::mesh::{Directions, Domain, FieldMesh, Symmetry};
    use crate::{SurfaceHook, SurfaceLift};
    use std::sync::Arc;

    /// A cylinder of radius 5 about z.
    struct Cylinder;

    impl SurfaceLift for Cylinder {
        fn project(&self, _: u32, p: Vec3) -> Option<(Vec3, Vec3)> {
            let r = p[0].hypot(p[1]);
            let n = [p[0] / r, p[1] / r, 0.0];
            Some(([5.0 * n[0], 5.0 * n[1], p[2]], n))
        }
    }

    fn unit(v: Vec3) -> Vec3 {
        let l = crate::geom::norm3(v);
        v.map(|x| x / l)
    }

    /// `w` projected onto the cylinder's tangent plane at `p`.
    fn grain(p: Vec3, w: Vec3) -> Vec3 {
        let n = unit([p[0], p[1], 0.0]);
        let s = crate::geom::dot3(w, n);
        unit([0, 1, 2].map(|k| w[k] - s * n[k]))
    }

    /// Strips of 30° of a cylinder (unrolled along their chords), every corner's ambient grain
    /// one world direction: inside every face the sampled field, lifted through the surface,
    /// is that direction projected onto the cylinder at the lifted point (1e-9 in cosine).
    #[test]
    fn a_projected_world_direction_is_sampled_exactly_between_the_chords() {
        let (step, h) = (30f64.to_radians(), 4.0);
        let w = [0.2, 1.0, 0.3];
        let (mut uv, mut pos, mut tris) = (Vec::new(), Vec::new(), Vec::new());
        let chord = 2.0 * 5.0 * (0.5 * step).sin();
        for i in 0..=4 {
            let a = i as f64 * step;
            for z in [0.0, h] {
                uv.push([i as f64 * chord, z]);
                pos.push([5.0 * a.cos(), 5.0 * a.sin(), z]);
            }
        }
        for i in 0..4u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
        let normals: Vec<Vec3> = pos.iter().map(|p| unit([p[0], p[1], 0.0])).collect();
        let ambient = vec![Some([w; 3]); tris.len()];
        let dirs = Directions::Vectors(vec![[1.0, 0.0]; uv.len()]);
        let fm = FieldMesh::new(uv, tris, dirs, Symmetry::Line)
            .with_lift(pos, Some(normals))
            .with_surface(SurfaceHook(Arc::new(Cylinder)), ambient);
        let dom = Domain::new(fm).unwrap();
        for f in 0..dom.tris.len() as u32 {
            for bary in [[1.0 / 3.0; 3], [0.6, 0.2, 0.2], [0.1, 0.1, 0.8]] {
                let d = surface_sample(&dom, f, bary, [1.0, 0.0], true).unwrap().unwrap();
                let x = dom.lift(f, bary).unwrap();
                let jac = chord_jacobian(&dom, f).unwrap();
                let y = dom.chord_lift(f, bary).unwrap();
                let e = 1e-7;
                let moved = [0, 1, 2].map(|k| y[k] + e * (jac[0][k] * d[0] + jac[1][k] * d[1]));
                let (q, _) = Cylinder.project(f, moved).unwrap();
                let along = unit([0, 1, 2].map(|k| q[k] - x[k]));
                let g = grain(x, w);
                let cos = crate::geom::dot3(along, g).abs();
                assert!(cos > 1.0 - 1e-9, "face {f} {bary:?}: {along:?} vs {g:?}");
            }
        }
    }
}
