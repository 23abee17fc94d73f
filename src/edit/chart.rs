//! The brush chart: geodesic polar coordinates around a brush centre (docs/math.md §13).
//!
//! A bend or an expand moves highlights *along the surface*. Seen in a plane (the support's
//! fitted plane, orthogonal projection), a brush on a strongly curved region folds over itself —
//! a thin fin, a rim, a knob — and a warped highlight pushed towards the fold has no surface
//! under it in the plane although the surface goes on. The chart instead unrolls the support
//! onto the base plane: the discrete exponential map of Schmidt, Grimm & Wyvill ("Interactive
//! decal compositing with discrete exponential maps", SIGGRAPH 2006), with upwind averaging.
//!
//! - The **base frame** is the brush plane's (origin o = the centre point, axes eₓ, e_y, normal
//!   n₀). A seed vertex q (a corner of the centre's face) is placed at L₀(q − o), the step of E2
//!   taken from the base frame (E1).
//! - Every other vertex q, in order of its geodesic distance, averages the estimates of its
//!   neighbours p already placed (weights 1/|q − p|²): x_q = x_p + R(θ_p) L_p(q − p), where
//!   L_p(d) is the part of d across the mean normal m of n_p and n_q, carried into p's frame
//!   [t b] by the rotation taking m to n_p and lengthened from the chord to the arc (E2): on a
//!   circular arc it is the arc's tangent at p with the arc's length, and a scan's noise (the
//!   height difference along m) adds nothing to it. Each vertex also
//!   carries the angle θ_q of its frame's t axis in the chart: p's axis is carried to q by the
//!   smallest rotation taking n_p to n_q (a discrete parallel transport), and θ_q = θ_p − β with
//!   β that axis's angle in q's frame (E3; angles averaged as unit vectors).
//! - On a plane every estimate is exact, so the chart is the plane's own coordinates. On a
//!   sphere of radius R its error grows like (r/R)² r (a geodesic polar map of a disk of radius r
//!   cannot be an isometry); the tests bound it.
//!
//! Vectors: a tangent vector w at vertex v has chart components R(θ_v)[t_v b_v]ᵀ w, and back.

use nalgebra::{Vector2, Vector3};

use crate::geometry::Frame;

/// Chart coordinates and frame angles of a brush's vertices.
#[derive(Clone, Debug, Default)]
pub struct Chart {
    /// (vertex, chart coordinates in units of r, angle θ of the vertex frame's t axis in the
    /// chart), sorted by vertex.
    entries: Vec<(u32, Vector2<f64>, f64)>,
}

/// The base of a chart: the centre and the brush plane's axes.
pub(crate) struct Base<'a> {
    /// The centre point on the surface.
    pub origin: Vector3<f64>,
    /// Unit x axis of the brush plane.
    pub ex: Vector3<f64>,
    /// Unit y axis (ex × ey = normal).
    pub ey: Vector3<f64>,
    /// Unit normal of the brush plane.
    pub normal: Vector3<f64>,
    /// Vertices placed directly from the centre (the corners of its face, or its vertex).
    pub seeds: &'a [(usize, f64)],
    /// The brush radius r (chart coordinates are in units of r).
    pub radius: f64,
}

/// The smallest rotation taking unit `a` to unit `b`, applied to `v` (Rodrigues; None when
/// `a` and `b` are nearly opposite and the rotation is not defined).
fn transport(a: &Vector3<f64>, b: &Vector3<f64>, v: &Vector3<f64>) -> Option<Vector3<f64>> {
    let c = a.dot(b);
    if c <= -0.9 {
        return None;
    }
    let k = a.cross(b);
    let kv = k.cross(v);
    Some(v + kv + k.cross(&kv) / (1.0 + c))
}

/// E2's L_p: the step `d` from p to q as a tangent vector in p's `frame`, q's unit normal being
/// `nq`. The part of d across the mean normal m = (n_p + n_q)/|n_p + n_q| is left out — on a
/// circular arc d is perpendicular to m, and on a scan it is the noise's height difference, which
/// a rescaling to |d| would add to every step and so stretch the chart (by 7 % at RMS noise a
/// third of the vertex spacing) — carried into p's tangent plane by the rotation taking m to n_p,
/// and lengthened from the chord to the arc, (α/2)/sin(α/2) with α the angle between the normals
/// (exact on a circular arc, as the support's geodesic distance of docs/math.md §8). Without a
/// mean normal (opposite normals) the tangential part of d in p's frame rescaled to |d|; zero
/// for d ∥ n_p.
fn unrolled(frame: &Frame, nq: &Vector3<f64>, d: &Vector3<f64>) -> Vector2<f64> {
    let np = frame.n;
    if let Some(m) = (np + nq).try_normalize(1e-6) {
        let across = d - m * m.dot(d);
        let alpha = np.dot(nq).clamp(-1.0, 1.0).acos();
        let arc = if alpha > 1e-8 { 0.5 * alpha / (0.5 * alpha).sin() } else { 1.0 };
        if let Some(t) = transport(&m, &np, &across) {
            return frame.to_local(&t) * arc;
        }
    }
    let l = frame.to_local(d);
    let n = l.norm();
    if n > 1e-300 {
        l * (d.norm() / n)
    } else {
        Vector2::zeros()
    }
}

fn rotate(theta: f64, v: &Vector2<f64>) -> Vector2<f64> {
    let (s, c) = theta.sin_cos();
    Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// Running weighted means of a position and an angle.
#[derive(Default)]
struct Mean {
    x: Vector2<f64>,
    dir: Vector2<f64>,
    w: f64,
}

impl Mean {
    fn add(&mut self, x: Vector2<f64>, theta: f64, w: f64) {
        self.x += x * w;
        self.dir += Vector2::new(theta.cos(), theta.sin()) * w;
        self.w += w;
    }
}

impl Chart {
    /// Places `order` (vertices, nearest the centre first; every vertex after the seeds has a
    /// mesh neighbour earlier in the list) in the chart of `base`.
    pub(crate) fn new(
        positions: &[Vector3<f64>],
        frames: &[Frame],
        neighbours: impl Fn(usize) -> Vec<usize>,
        base: &Base,
        order: &[usize],
    ) -> Chart {
        let mut placed: std::collections::HashMap<usize, (Vector2<f64>, f64)> =
            std::collections::HashMap::with_capacity(order.len());
        let base_frame = Frame { t: base.ex, b: base.ey, n: base.normal };
        for &q in order {
            let fq = &frames[q];
            let pq = positions[q];
            let mut m = Mean::default();
            let direct = base.seeds.iter().any(|s| s.0 == q);
            for p in neighbours(q) {
                let Some(&(xp, tp)) = placed.get(&p) else { continue };
                let fp = &frames[p];
                let d = pq - positions[p];
                let w = 1.0 / d.norm_squared().max(1e-300);
                let x = xp + rotate(tp, &unrolled(fp, &fq.n, &d));
                let Some(t) = transport(&fp.n, &fq.n, &fp.t) else { continue };
                let beta = fq.b.dot(&t).atan2(fq.t.dot(&t));
                m.add(x, tp - beta, w);
            }
            if direct || m.w == 0.0 {
                // E1: straight from the centre.
                let d = pq - base.origin;
                let w = 1.0 / d.norm_squared().max(1e-24 * base.radius * base.radius);
                let x = unrolled(&base_frame, &fq.n, &d);
                let t = transport(&base.normal, &fq.n, &base.ex).unwrap_or(fq.t);
                let beta = fq.b.dot(&t).atan2(fq.t.dot(&t));
                m.add(x, -beta, w);
            }
            let x = m.x / m.w;
            let theta = m.dir.y.atan2(m.dir.x);
            if x.iter().all(|c| c.is_finite()) && theta.is_finite() {
                placed.insert(q, (x, theta));
            }
        }
        let r = base.radius;
        let mut entries: Vec<(u32, Vector2<f64>, f64)> =
            placed.into_iter().map(|(v, (x, t))| (v as u32, x / r, t)).collect();
        entries.sort_unstable_by_key(|e| e.0);
        Chart { entries }
    }

    fn find(&self, v: usize) -> Option<&(u32, Vector2<f64>, f64)> {
        let i = self.entries.binary_search_by_key(&(v as u32), |e| e.0).ok()?;
        self.entries.get(i)
    }

    /// Chart coordinates of vertex `v` (units of r), if it is in the chart.
    pub fn coords(&self, v: usize) -> Option<Vector2<f64>> {
        self.find(v).map(|e| e.1)
    }

    /// Chart components of the tangent vector `w` at vertex `v` of frame `frame` (its
    /// tangential part; zero when `v` is not in the chart).
    pub fn vector_to_chart(&self, v: usize, frame: &Frame, w: &Vector3<f64>) -> Vector2<f64> {
        self.find(v).map_or(Vector2::zeros(), |e| rotate(e.2, &frame.to_local(w)))
    }

    /// The tangent vector at vertex `v` whose chart components are `c`.
    pub fn vector_from_chart(&self, v: usize, frame: &Frame, c: &Vector2<f64>) -> Vector3<f64> {
        let theta = self.find(v).map_or(0.0, |e| e.2);
        frame.to_world(&rotate(-theta, c))
    }

    /// Every (vertex, chart coordinates), sorted by vertex.
    pub fn points(&self) -> Vec<(u32, [f64; 2])> {
        self.entries.iter().map(|e| (e.0, [e.1.x, e.1.y])).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of points on the sphere of radius `big_r` around the north pole, with radial
    /// normals and the convention's frames, and its 4-neighbour grid adjacency.
    fn cap(big_r: f64, n: usize, extent: f64) -> (Vec<Vector3<f64>>, Vec<Frame>, usize) {
        let mut pos = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (
                    extent * (2.0 * i as f64 / (n - 1) as f64 - 1.0),
                    extent * (2.0 * j as f64 / (n - 1) as f64 - 1.0),
                );
                // Geodesic polar coordinates (ρ, α) = (|(x, y)|, atan2): the exact log map.
                let rho = x.hypot(y);
                let a = y.atan2(x);
                let s = rho / big_r;
                pos.push(Vector3::new(s.sin() * a.cos(), s.sin() * a.sin(), s.cos()) * big_r);
            }
        }
        let frames = pos.iter().map(|p| Frame::from_normal(p.normalize())).collect();
        (pos, frames, n)
    }

    fn grid_neighbours(n: usize) -> impl Fn(usize) -> Vec<usize> {
        move |v| {
            let (i, j) = (v % n, v / n);
            let mut out = Vec::new();
            for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1), (1, 1), (-1, -1)] {
                let (a, b) = (i as i64 + di, j as i64 + dj);
                if a >= 0 && b >= 0 && (a as usize) < n && (b as usize) < n {
                    out.push(b as usize * n + a as usize);
                }
            }
            out
        }
    }

    fn chart_of(pos: &[Vector3<f64>], frames: &[Frame], n: usize, r: f64) -> Chart {
        let centre = (n / 2) * n + n / 2;
        let mut order: Vec<usize> = (0..pos.len()).collect();
        order.sort_by(|&a, &b| {
            let da = (pos[a] - pos[centre]).norm();
            let db = (pos[b] - pos[centre]).norm();
            da.total_cmp(&db).then(a.cmp(&b))
        });
        let seeds = [(centre, 0.0)];
        let base = Base {
            origin: pos[centre],
            ex: Vector3::x(),
            ey: Vector3::y(),
            normal: Vector3::z(),
            seeds: &seeds,
            radius: r,
        };
        Chart::new(pos, frames, grid_neighbours(n), &base, &order)
    }

    #[test]
    fn on_a_plane_the_chart_is_the_plane() {
        let n = 21;
        let pos: Vec<Vector3<f64>> = (0..n * n)
            .map(|v| Vector3::new((v % n) as f64 * 0.1 - 1.0, (v / n) as f64 * 0.1 - 1.0, 0.3))
            .collect();
        let frames: Vec<Frame> = pos.iter().map(|_| Frame::from_normal(Vector3::z())).collect();
        let c = chart_of(&pos, &frames, n, 2.0);
        for (v, p) in pos.iter().enumerate() {
            let x = c.coords(v).unwrap() * 2.0;
            assert!((x - Vector2::new(p.x, p.y)).norm() < 1e-12, "{v}: {x:?} vs {p:?}");
        }
        // Vectors: the chart components of a world tangent vector are its (x, y).
        let w = Vector3::new(0.3, -0.7, 0.0);
        let cw = c.vector_to_chart(7, &frames[7], &w);
        assert!((cw - Vector2::new(0.3, -0.7)).norm() < 1e-12);
        assert!((c.vector_from_chart(7, &frames[7], &cw) - w).norm() < 1e-12);
    }

    /// On a sphere the exact log map of the grid point (x, y) is (x, y) itself (the grid is
    /// built in geodesic polar coordinates): the discrete map stays within a small multiple of
    /// (r/R)² r of it, far better than the orthogonal projection, which shortens the rim by
    /// R(ρ/R − sin(ρ/R)).
    #[test]
    fn on_a_sphere_the_chart_follows_the_log_map() {
        let (big_r, extent, n) = (1.0, 0.6, 41);
        let (pos, frames, n) = cap(big_r, n, extent);
        let c = chart_of(&pos, &frames, n, 1.0);
        let mut worst: f64 = 0.0;
        let mut worst_plane: f64 = 0.0;
        for j in 0..n {
            for i in 0..n {
                let v = j * n + i;
                let exact = Vector2::new(
                    extent * (2.0 * i as f64 / (n - 1) as f64 - 1.0),
                    extent * (2.0 * j as f64 / (n - 1) as f64 - 1.0),
                );
                if exact.norm() > extent {
                    continue;
                }
                worst = worst.max((c.coords(v).unwrap() - exact).norm());
                worst_plane = worst_plane.max((Vector2::new(pos[v].x, pos[v].y) - exact).norm());
            }
        }
        // ρ = 0.6 R: the projection is off by 0.6 − sin 0.6 = 0.035 R at the rim.
        assert!(worst_plane > 0.03, "{worst_plane}");
        assert!(worst < 0.5 * worst_plane && worst < 0.015, "chart {worst} vs plane {worst_plane}");
        // The frames' angles: a vector along the meridian at each point maps to the radial
        // chart direction.
        for v in [3 * n + 5, 20 * n + 33, 30 * n + 9] {
            let x = c.coords(v).unwrap();
            let meridian = {
                let p = pos[v].normalize();
                let down = (Vector3::z() - p * p.z).normalize();
                -down
            };
            let cw = c.vector_to_chart(v, &frames[v], &meridian);
            let ang = (cw.normalize().dot(&x.normalize())).clamp(-1.0, 1.0).acos();
            assert!(ang < 0.03, "vertex {v}: {ang} rad off the radial direction");
        }
    }

    /// A scan's noise does not stretch the chart: the cap of the log-map test with every point
    /// moved along its normal by uniform noise of RMS height 0.3 spacings (the frames are the
    /// sphere's, as a fit over a ball gives them). Rescaling each step to its 3D length made the
    /// chart 5–8 % too large there, so a warp moved the highlight that much less on the part
    /// than in the chart.
    #[test]
    fn noise_along_the_normals_does_not_stretch_the_chart() {
        let (big_r, extent, n) = (1.0, 0.6, 41);
        let (mut pos, frames, n) = cap(big_r, n, extent);
        let spacing = 2.0 * extent / (n - 1) as f64;
        let half_width = 0.3 * 3f64.sqrt() * spacing;
        let mut s = 7u64;
        for p in &mut pos {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let u = (s >> 11) as f64 / (1u64 << 53) as f64;
            *p += p.normalize() * half_width * (2.0 * u - 1.0);
        }
        let c = chart_of(&pos, &frames, n, 1.0);
        let mut worst: f64 = 0.0;
        let mut ratios = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let exact = Vector2::new(
                    extent * (2.0 * i as f64 / (n - 1) as f64 - 1.0),
                    extent * (2.0 * j as f64 / (n - 1) as f64 - 1.0),
                );
                if exact.norm() > extent {
                    continue;
                }
                let x = c.coords(j * n + i).unwrap();
                worst = worst.max((x - exact).norm());
                if exact.norm() > 0.3 {
                    ratios.push(x.norm() / exact.norm());
                }
            }
        }
        ratios.sort_by(f64::total_cmp);
        let median = ratios[ratios.len() / 2];
        assert!((median - 1.0).abs() < 0.005, "radial scale {median}");
        assert!(worst < 0.03, "{worst}");
    }

    #[test]
    fn over_a_fold_the_chart_unrolls() {
        // A strip bent through 180° around a half-cylinder of radius 0.2: both flat sides and
        // the round, with normals. In a plane the two sides overlap; unrolled, the arc length
        // along the strip is the chart's x.
        let (rad, m) = (0.2, 61usize);
        let mut pos = Vec::new();
        let mut nor = Vec::new();
        let s_of = |k: usize| -1.0 + 2.0 * k as f64 / (m - 1) as f64; // arc length in [−1, 1]
        let half = std::f64::consts::PI * rad;
        for j in 0..3 {
            for k in 0..m {
                let s = s_of(k) * (0.5 + half);
                let y = j as f64 * 0.05;
                // s ∈ [0, πr] goes round the cylinder; beyond it the far side runs back.
                let (p, n) = if s <= 0.0 {
                    (Vector3::new(s, y, 0.0), Vector3::z())
                } else if s <= half {
                    let a = s / rad;
                    (
                        Vector3::new(rad * a.sin(), y, rad * (1.0 - a.cos())),
                        Vector3::new(-a.sin(), 0.0, a.cos()),
                    )
                } else {
                    (Vector3::new(-(s - half), y, 2.0 * rad), -Vector3::z())
                };
                pos.push(p);
                nor.push(n);
            }
        }
        let frames: Vec<Frame> = nor.iter().map(|&n| Frame::from_normal(n)).collect();
        let centre = (m - 1) / 2;
        let nb = move |v: usize| {
            let (k, j) = (v % m, v / m);
            let mut out = Vec::new();
            if k > 0 {
                out.push(v - 1);
            }
            if k + 1 < m {
                out.push(v + 1);
            }
            if j > 0 {
                out.push(v - m);
            }
            if j < 2 {
                out.push(v + m);
            }
            out
        };
        let mut order: Vec<usize> = (0..pos.len()).collect();
        let geo = |v: usize| (s_of(v % m).abs(), (v / m) as f64);
        order.sort_by(|&a, &b| geo(a).partial_cmp(&geo(b)).unwrap().then(a.cmp(&b)));
        let seeds = [(centre, 0.0)];
        let base = Base {
            origin: pos[centre],
            ex: Vector3::x(),
            ey: Vector3::y(),
            normal: Vector3::z(),
            seeds: &seeds,
            radius: 1.0,
        };
        let c = Chart::new(&pos, &frames, nb, &base, &order);
        for v in 0..m {
            let s = s_of(v) * (0.5 + half);
            let x = c.coords(v).unwrap();
            assert!((x.x - s).abs() < 0.02 && x.y.abs() < 1e-9, "{v}: s {s}, chart {x:?}");
        }
    }
}
