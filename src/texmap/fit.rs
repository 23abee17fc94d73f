//! The grain at a face's corners, fitted to the texels inside the face.
//!
//! A bilinear sample at a corner mixes texels of every face around it, and the texels a
//! corner's own face holds lie up to a texel away from it: where the grain turns quickly (by
//! up to 90° across one face next to a singular face) the sample is off by degrees. So each
//! face is read on its own. The baker ([`super::raster`]) wrote at every texel centre inside a
//! UV triangle, at barycentric coordinates b, the angle
//!
//!   θ(b) = atan2(u(b)·B(b), u(b)·T(b)),   u(b) = Σ_c b_c u_c,   u_c = cos α_c T_c + sin α_c B_c,
//!
//! with (T, B) the corners' frames interpolated as a viewer does ([`super::lerp_frame`]) and
//! (T_c, B_c) the frame at corner c. The three corner angles α_c are those that minimize
//! Σ_k wrap(θ(b_k) − θ_k)² over the face's texels k (θ_k the map's reading; wrap to (−π/2, π/2]
//! for a line field, (−π, π] for an oriented one): Levenberg–Marquardt from the readings of the
//! texels nearest each corner, for a line field from each choice of the corners' relative
//! signs until one fits. A map grainline baked is fitted to its 16-bit quantization; a map
//! painted elsewhere gets the closest field of that form. A face with fewer than
//! [`MIN_TEXELS`] texels, or whose best fit is off by more than [`MAX_RMS_DEG`] on average,
//! is read by the bilinear sample at each corner ([`super::GrainMap::sample`]).

use nalgebra::{Matrix3, Vector2, Vector3};

use super::{lerp_frame, GrainMap, MapKind};

/// Fewest texels inside a face for a fit (three unknowns, one more to check them).
pub const MIN_TEXELS: usize = 4;

/// Texels used per corner: the nearest to it inside the face.
const TEXELS_PER_CORNER: usize = 12;

/// The largest root-mean-square misfit (degrees) a fit may keep.
pub const MAX_RMS_DEG: f64 = 1.0;

/// Barycentric margin a texel centre keeps from the face's edges: a centre on a shared edge
/// may hold the neighbour's value (the later face wins).
const INSIDE: f64 = 1e-6;

/// What a face's fit reads: the texels' barycentric coordinates and the grain angle each holds
/// in its own frame.
struct Samples {
    b: Vec<[f64; 3]>,
    theta: Vec<f64>,
}

/// A face as the fit sees it: its corners' normals and MikkTSpace tangents, and whether the
/// grain is a line field.
pub(super) struct Face<'a> {
    pub normals: [Vector3<f64>; 3],
    pub tangents: &'a [[f32; 4]; 3],
    pub line: bool,
}

impl Face<'_> {
    /// The interpolated frame (T, B, N) at b.
    fn frame(&self, b: [f64; 3]) -> Option<(Vector3<f64>, Vector3<f64>, Vector3<f64>)> {
        lerp_frame(&self.normals, self.tangents, b).map(|(t, bt, n, _)| (t, bt, n))
    }

    /// θ(b) for corner angles α (module docs), `None` where u(b) vanishes.
    fn predict(&self, corners: &[Vector3<f64>; 3], b: [f64; 3]) -> Option<f64> {
        let (t, bt, _) = self.frame(b)?;
        let u: Vector3<f64> = (0..3).map(|c| b[c] * corners[c]).sum();
        let (x, y) = (u.dot(&t), u.dot(&bt));
        (x.hypot(y) > 1e-12).then(|| y.atan2(x))
    }

    /// The corner grains u_c of angles α.
    fn corners(
        &self,
        frames: &[(Vector3<f64>, Vector3<f64>); 3],
        a: &Vector3<f64>,
    ) -> [Vector3<f64>; 3] {
        [0, 1, 2].map(|c| frames[c].0 * a[c].cos() + frames[c].1 * a[c].sin())
    }

    fn wrap(&self, d: f64) -> f64 {
        let p = if self.line { std::f64::consts::PI } else { std::f64::consts::TAU };
        (d + 0.5 * p).rem_euclid(p) - 0.5 * p
    }

    /// Residuals θ(b_k) − θ_k, wrapped (a texel where u vanishes counts as a right angle).
    fn residuals(
        &self,
        frames: &[(Vector3<f64>, Vector3<f64>); 3],
        s: &Samples,
        a: &Vector3<f64>,
    ) -> Vec<f64> {
        let u = self.corners(frames, a);
        s.b.iter()
            .zip(&s.theta)
            .map(|(&b, &th)| {
                self.predict(&u, b).map_or(std::f64::consts::FRAC_PI_2, |p| self.wrap(p - th))
            })
            .collect()
    }
}

/// The texels of `map` whose centres lie inside the face's UV triangle `st`, the nearest
/// [`TEXELS_PER_CORNER`] to each corner, with the grain angle each holds in its frame.
fn samples(face: &Face, map: &GrainMap, st: &[Vector2<f64>; 3]) -> Samples {
    let (w, h) = (map.width as f64, map.height as f64);
    let p = st.map(|q| Vector2::new(q.x * w, (1.0 - q.y) * h));
    let area = (p[1] - p[0]).perp(&(p[2] - p[0]));
    let mut found: Vec<([f64; 3], usize)> = Vec::new();
    if area.abs() > 1e-12 && area.is_finite() {
        let lo = p.iter().fold(Vector2::repeat(f64::INFINITY), |a, q| a.inf(q));
        let hi = p.iter().fold(Vector2::repeat(f64::NEG_INFINITY), |a, q| a.sup(q));
        let i0 = (lo.x - 0.5).ceil().max(0.0);
        let j0 = (lo.y - 0.5).ceil().max(0.0);
        let i1 = (hi.x - 0.5).floor().min(w - 1.0);
        let j1 = (hi.y - 0.5).floor().min(h - 1.0);
        let (mut j, mut i);
        j = j0;
        while j <= j1 {
            i = i0;
            while i <= i1 {
                let q = Vector2::new(i + 0.5, j + 0.5);
                let b1 = (q - p[0]).perp(&(p[2] - p[0])) / area;
                let b2 = (p[1] - p[0]).perp(&(q - p[0])) / area;
                let b = [1.0 - b1 - b2, b1, b2];
                if b.iter().all(|&x| x >= INSIDE) {
                    found.push((b, j as usize * map.width + i as usize));
                }
                i += 1.0;
            }
            j += 1.0;
        }
    }
    let mut keep = vec![false; found.len()];
    for c in 0..3 {
        let mut order: Vec<usize> = (0..found.len()).collect();
        order.sort_by(|&x, &y| found[y].0[c].total_cmp(&found[x].0[c]).then(x.cmp(&y)));
        order.iter().take(TEXELS_PER_CORNER).for_each(|&k| keep[k] = true);
    }
    let mut s = Samples { b: Vec::new(), theta: Vec::new() };
    for ((b, k), _) in found.into_iter().zip(keep).filter(|(_, kept)| *kept) {
        if let Some(th) = reading(face, map, b, k) {
            s.b.push(b);
            s.theta.push(th);
        }
    }
    s
}

/// The grain angle texel `k` holds, in the frame at b: an angle map's θ, or a direction map's
/// n × u turned back (n × u = w·(−y, x) in (T, B), so u = w·(q, −p) for a stored (p, q)).
fn reading(face: &Face, map: &GrainMap, b: [f64; 3], k: usize) -> Option<f64> {
    let t = map.texels[k];
    let (p, q) = (f64::from(t[0]), f64::from(t[1]));
    if p.hypot(q).is_nan() || p.hypot(q) <= 1e-9 {
        return None;
    }
    Some(match map.kind {
        MapKind::Angle => q.atan2(p),
        MapKind::Direction => {
            let (_, _, _, w) = lerp_frame(&face.normals, face.tangents, b)?;
            (-w * p).atan2(w * q)
        }
    })
}

/// The corner angles that fit `s` from the start `a`: Levenberg–Marquardt with a numerical
/// Jacobian; the angles and their root-mean-square misfit.
fn solve(
    face: &Face,
    frames: &[(Vector3<f64>, Vector3<f64>); 3],
    s: &Samples,
    mut a: Vector3<f64>,
) -> (Vector3<f64>, f64) {
    let cost = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    let mut r = face.residuals(frames, s, &a);
    let mut c = cost(&r);
    let mut lambda = 1e-3;
    for _ in 0..40 {
        const H: f64 = 1e-7;
        let cols: Vec<Vec<f64>> = (0..3)
            .map(|j| {
                let mut ah = a;
                ah[j] += H;
                let rh = face.residuals(frames, s, &ah);
                rh.iter().zip(&r).map(|(x, y)| face.wrap(x - y) / H).collect()
            })
            .collect();
        let mut jtj = Matrix3::zeros();
        let mut jtr = Vector3::zeros();
        for k in 0..r.len() {
            let row = Vector3::new(cols[0][k], cols[1][k], cols[2][k]);
            jtj += row * row.transpose();
            jtr += row * r[k];
        }
        let mut step = None;
        while lambda < 1e12 {
            let m =
                jtj + Matrix3::from_diagonal(&(jtj.diagonal() * lambda + Vector3::repeat(1e-12)));
            let Some(d) = m.lu().solve(&(-jtr)) else { break };
            let rn = face.residuals(frames, s, &(a + d));
            let cn = cost(&rn);
            if cn < c {
                step = Some((d, rn, cn));
                lambda = (lambda * 0.1).max(1e-12);
                break;
            }
            lambda *= 10.0;
        }
        let Some((d, rn, cn)) = step else { break };
        a += d;
        let done = c - cn <= 1e-14 * c.max(1e-30) || d.norm() < 1e-12;
        (r, c) = (rn, cn);
        if done {
            break;
        }
    }
    (a, (c / r.len().max(1) as f64).sqrt())
}

/// The grain at the face's three corners fitted to the map's texels inside it (module docs),
/// each unit in its corner's frame; `None` when the face has too few texels or no good fit.
pub(super) fn fit_face(
    face: &Face,
    map: &GrainMap,
    st: &[Vector2<f64>; 3],
) -> Option<[Vector3<f64>; 3]> {
    let s = samples(face, map, st);
    if s.b.len() < MIN_TEXELS {
        return None;
    }
    let frames = [0, 1, 2].map(|c| {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        face.frame(e).map(|(t, b, _)| (t, b))
    });
    let frames = [frames[0]?, frames[1]?, frames[2]?];
    // The start: per corner, the reading of its nearest texel, carried into the corner's frame.
    let start = Vector3::from_fn(|c, _| {
        let k = (0..s.b.len()).max_by(|&x, &y| s.b[x][c].total_cmp(&s.b[y][c])).unwrap_or(0);
        let (t, bt, _) = face.frame(s.b[k]).unwrap_or((frames[c].0, frames[c].1, Vector3::zeros()));
        let u = t * s.theta[k].cos() + bt * s.theta[k].sin();
        u.dot(&frames[c].1).atan2(u.dot(&frames[c].0))
    });
    let flips: &[[f64; 2]] =
        if face.line { &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]] } else { &[[0.0, 0.0]] };
    // For a line field, the corners' relative signs most alike first.
    let mut order: Vec<(f64, Vector3<f64>)> = flips
        .iter()
        .map(|f| {
            let a = start + Vector3::new(0.0, f[0], f[1]) * std::f64::consts::PI;
            let u = face.corners(&frames, &a);
            (-(u[0].dot(&u[1]) + u[1].dot(&u[2]) + u[0].dot(&u[2])), a)
        })
        .collect();
    order.sort_by(|x, y| x.0.total_cmp(&y.0));
    let tol = MAX_RMS_DEG.to_radians();
    let mut best: Option<(Vector3<f64>, f64)> = None;
    for (_, a0) in order {
        let (a, rms) = solve(face, &frames, &s, a0);
        if best.is_none_or(|b| rms < b.1) {
            best = Some((a, rms));
        }
        if rms <= 0.1 * tol {
            break;
        }
    }
    let (a, rms) = best?;
    (rms <= tol && a.iter().all(|x| x.is_finite())).then(|| face.corners(&frames, &a))
}
