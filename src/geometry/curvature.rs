//! The Weingarten map by a local quadric (jet) fit, and principal curvatures.
//!
//! In the tangent frame [t, b, n] of vertex i each neighbour gives local coordinates
//! (x, y, z) = [t b n]ᵀ(pⱼ − pᵢ), and we fit by least squares
//!
//! ```text
//! z = g₁x + g₂y + ½(W₁₁x² + 2W₁₂xy + W₂₂y²)        (the paper's §4.2, repaired: math.md §5.6)
//! ```
//!
//! with the columns scaled by the ring radius so the system is well conditioned at any scale.
//! W is the Weingarten map in the sign convention of math.md §1 (W = C for z = ½xᵀCx with n up);
//! the linear term g tilts the normal: n ← normalize(n − g₁t − g₂b), and the fit is repeated in
//! the new frame. The 1-ring is used for interior vertices of valence ≥ 6; boundary and
//! low-valence vertices (valence 5 would be exactly determined) use the 2-ring, and a vertex
//! whose ring is still degenerate (collinear neighbours, slivers) grows it up to the 4-ring —
//! and so does one whose fit leans the normal by more than [`MAX_FIT_TILT_DEG`] or whose slope
//! the part's height noise would tilt by more than [`MAX_NOISE_TILT_DEG`]
//! ([`MAX_SLOPE_VARIANCE`]): the marks of a ring too thin to tell the plane. A 1-ring much
//! smaller than its neighbours' ([`MIN_RING_SHARE`]) is not taken either: it samples a mesher's
//! micro-feature, not the part.
//! A vertex with no usable ring gets W = 0 and is counted.

use nalgebra::{Matrix2, Vector3};

use super::frames::Frame;
use super::rings::gather_ring;
use crate::mesh::Adjacency;

/// Result of the jet fit at one vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JetFit {
    /// Weingarten map in the vertex frame (math.md §1 convention).
    pub w: Matrix2<f64>,
    /// Gradient of the height function (the normal's tilt) in the vertex frame.
    pub slope: [f64; 2],
    /// Ring depth that was used (0 when no ring could be fitted).
    pub ring: u8,
}

/// The fit of `z = g·x + ½xᵀWx` over the given neighbours, or `None` when their tangential
/// positions do not determine a quadric.
pub fn fit_quadric(
    positions: &[Vector3<f64>],
    i: usize,
    frame: &Frame,
    ring: &[u32],
) -> Option<(Matrix2<f64>, [f64; 2])> {
    let mut d = Vec::new();
    let inv_h = scaled_offsets(positions, i, ring, &mut d)?;
    fit_scaled(&d, inv_h, frame)
}

/// The neighbours' offsets pⱼ − pᵢ divided by the ring radius h into `out`; returns 1/h, or
/// `None` when the ring is too small or h is not a positive finite number. Independent of the
/// frame, so the normal-refinement refit reuses it.
fn scaled_offsets(
    positions: &[Vector3<f64>],
    i: usize,
    ring: &[u32],
    out: &mut Vec<Vector3<f64>>,
) -> Option<f64> {
    out.clear();
    if ring.len() < 5 {
        return None;
    }
    let pi = positions[i];
    let mut r2 = 0.0;
    for &j in ring {
        r2 += (positions[j as usize] - pi).norm_squared();
    }
    let h = (r2 / ring.len() as f64).sqrt();
    if !(h > 0.0 && h.is_finite()) {
        return None;
    }
    let inv_h = 1.0 / h;
    out.extend(ring.iter().map(|&j| (positions[j as usize] - pi) * inv_h));
    Some(inv_h)
}

/// The least-squares quadric over scaled offsets `d` (from [`scaled_offsets`]) in `frame`.
///
/// The 5×5 normal equations are accumulated in packed lower-triangular form and solved by a
/// Cholesky factorization written out for this size (nalgebra's generic one was 11 % of the
/// 1M-vertex core benchmark).
fn fit_scaled(d: &[Vector3<f64>], inv_h: f64, frame: &Frame) -> Option<(Matrix2<f64>, [f64; 2])> {
    fit_scaled_checked(d, inv_h, frame, false).map(|(w, slope, _)| (w, slope))
}

/// [`fit_scaled`], and when `check`, the fit's [`slope_variance`] (else 0).
fn fit_scaled_checked(
    d: &[Vector3<f64>],
    inv_h: f64,
    frame: &Frame,
    check: bool,
) -> Option<(Matrix2<f64>, [f64; 2], f64)> {
    // a[tri(r, c)] = Σ row_r row_c for c ≤ r.
    let mut a = [0.0; 15];
    let mut b = [0.0; 5];
    for d in d {
        let (x, y, z) = (frame.t.dot(d), frame.b.dot(d), frame.n.dot(d));
        let row = [x, y, 0.5 * x * x, x * y, 0.5 * y * y];
        // Written out (the loop over a triangle did not unroll).
        let [r0, r1, r2, r3, r4] = row;
        a[0] += r0 * r0;
        a[1] += r1 * r0;
        a[2] += r1 * r1;
        a[3] += r2 * r0;
        a[4] += r2 * r1;
        a[5] += r2 * r2;
        a[6] += r3 * r0;
        a[7] += r3 * r1;
        a[8] += r3 * r2;
        a[9] += r3 * r3;
        a[10] += r4 * r0;
        a[11] += r4 * r1;
        a[12] += r4 * r2;
        a[13] += r4 * r3;
        a[14] += r4 * r4;
        for (b, r) in b.iter_mut().zip(row) {
            *b += r * z;
        }
    }
    let (l, inv) = cholesky5(&a)?;
    let c = solve_factored5(&l, &inv, &b)?;
    // Undo the scaling: x' = x/h, z' = z/h ⇒ slopes unchanged, second derivatives × 1/h.
    let w = Matrix2::new(c[2], c[3], c[3], c[4]) * inv_h;
    let variance = if check { slope_variance(&l, &inv) } else { 0.0 };
    Some((w, [c[0], c[1]], variance))
}

/// Index of entry (r, c), c ≤ r, in a packed lower triangle stored row by row.
#[inline(always)]
const fn tri(r: usize, c: usize) -> usize {
    r * (r + 1) / 2 + c
}

/// The Cholesky factor `A = LLᵀ` of a symmetric 5×5 `A` given by its packed lower triangle,
/// with the reciprocals of its diagonal. `None` when `A` is rank-deficient: a pivot L_kk²
/// below 1e-10 × A_kk means the neighbours do not span the quadric's monomials.
fn cholesky5(a: &[f64; 15]) -> Option<([f64; 15], [f64; 5])> {
    let mut l = [0.0; 15];
    // 1 / L_jj: one division per column, multiplications elsewhere.
    let mut inv = [0.0; 5];
    for j in 0..5 {
        let mut djj = a[tri(j, j)];
        for k in 0..j {
            djj -= l[tri(j, k)] * l[tri(j, k)];
        }
        // (Also refuses a NaN pivot: the comparison is false.)
        if !(djj >= 1e-10 * a[tri(j, j)].max(1e-300) && djj > 0.0) {
            return None;
        }
        let ljj = djj.sqrt();
        l[tri(j, j)] = ljj;
        inv[j] = 1.0 / ljj;
        for i in j + 1..5 {
            let mut s = a[tri(i, j)];
            for k in 0..j {
                s -= l[tri(i, k)] * l[tri(j, k)];
            }
            l[tri(i, j)] = s * inv[j];
        }
    }
    Some((l, inv))
}

/// Solves `LLᵀ x = b` with the factor of [`cholesky5`]; `None` on a non-finite solution.
fn solve_factored5(l: &[f64; 15], inv: &[f64; 5], b: &[f64; 5]) -> Option<[f64; 5]> {
    // L y = b, then Lᵀ x = y.
    let mut x = *b;
    for i in 0..5 {
        for k in 0..i {
            x[i] -= l[tri(i, k)] * x[k];
        }
        x[i] *= inv[i];
    }
    for i in (0..5).rev() {
        for k in i + 1..5 {
            x[i] -= l[tri(k, i)] * x[k];
        }
        x[i] *= inv[i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Solves `A x = b` for a symmetric 5×5 `A` given by its packed lower triangle, by Cholesky
/// ([`cholesky5`]). `None` when `A` is rank-deficient or the solution is not finite.
#[cfg(test)]
fn solve_spd5(a: &[f64; 15], b: &[f64; 5]) -> Option<[f64; 5]> {
    let (l, inv) = cholesky5(a)?;
    solve_factored5(&l, &inv, b)
}

/// (A⁻¹)₀₀ + (A⁻¹)₁₁ from the factor of [`cholesky5`]: how much the fitted slope moves per
/// unit of the neighbours' height error (‖L⁻¹e₀‖² + ‖L⁻¹e₁‖², two forward substitutions).
fn slope_variance(l: &[f64; 15], inv: &[f64; 5]) -> f64 {
    let mut sum = 0.0;
    for unit in 0..2 {
        let mut y = [0.0; 5];
        y[unit] = 1.0;
        for i in 0..5 {
            for k in 0..i {
                y[i] -= l[tri(i, k)] * y[k];
            }
            y[i] *= inv[i];
        }
        sum += y.iter().map(|v| v * v).sum::<f64>();
    }
    sum
}

/// Per-vertex scratch of [`JetRings::fit`]: the scaled offsets of each ring depth tried so far
/// at the current vertex (they do not depend on the frame).
#[derive(Default)]
pub(crate) struct JetRings {
    vertex: usize,
    /// Depths 1..=4 → (1/h or None, scaled offsets); `valid[k]` says whether depth k+1 is cached.
    valid: [bool; 4],
    inv_h: [Option<f64>; 4],
    offsets: [Vec<Vector3<f64>>; 4],
    ring: Vec<u32>,
    grow: Vec<u32>,
    /// The ball of [`JetRings::fit_in_ball`] at the current vertex, once gathered: 1/h and the
    /// scaled offsets, or `None` when it holds too few vertices.
    ball: Option<Option<(f64, Vec<Vector3<f64>>)>>,
    seen: std::collections::HashSet<u32>,
    /// The RMS height error of the part's vertices (scene units; 0: exact), against which a
    /// ring's fit is judged ([`MAX_SLOPE_VARIANCE`]).
    pub height_noise: f64,
    /// The mean of the current vertex's neighbours' 1-ring radii ([`ring_radii`]), against which
    /// its own 1-ring is judged ([`MIN_RING_SHARE`]); 0: not judged.
    pub neighbour_radius: f64,
}

/// Most vertices a fit over a ball uses (`field.fit_radius`): the nearest in breadth-first
/// order. Bounds the work at 512 points per vertex however fine the mesh is against the radius.
pub const MAX_BALL_POINTS: usize = 512;

impl JetRings {
    /// Forgets the cached rings; the next fits are at vertex `i`.
    pub(crate) fn start(&mut self, i: usize) {
        self.vertex = i;
        self.valid = [false; 4];
        self.ball = None;
    }

    /// The jet fit over the vertices within `radius` of the current vertex (reached through
    /// edges between such vertices; at most [`MAX_BALL_POINTS`]), when they are more than its
    /// 2-ring; else, or when that fit fails, [`JetRings::fit`]. A fit over a ball a few edges
    /// wide averages out a scan's noise instead of fitting it (docs/math.md §5.6,
    /// `field.fit_radius`).
    pub(crate) fn fit_in_ball(
        &mut self,
        positions: &[Vector3<f64>],
        adj: &Adjacency,
        frame: &Frame,
        radius: f64,
    ) -> JetFit {
        if self.ball.is_none() {
            self.ball = Some(self.gather_ball(positions, adj, radius));
        }
        if let Some(Some((inv_h, offsets))) = &self.ball {
            if let Some((w, slope)) = fit_scaled(offsets, *inv_h, frame) {
                return JetFit { w, slope, ring: 1 };
            }
        }
        self.fit(positions, adj, frame)
    }

    fn gather_ball(
        &mut self,
        positions: &[Vector3<f64>],
        adj: &Adjacency,
        radius: f64,
    ) -> Option<(f64, Vec<Vector3<f64>>)> {
        let i = self.vertex;
        let pi = positions[i];
        let r2 = radius * radius;
        self.seen.clear();
        self.seen.insert(i as u32);
        self.ring.clear();
        let mut head = 0;
        let mut frontier = vec![i as u32];
        'grow: while head < frontier.len() {
            let v = frontier[head] as usize;
            head += 1;
            for &j in adj.neighbors(v) {
                let inside = (positions[j as usize] - pi).norm_squared() <= r2;
                if !inside || !self.seen.insert(j) {
                    continue;
                }
                self.ring.push(j);
                frontier.push(j);
                if self.ring.len() >= MAX_BALL_POINTS {
                    break 'grow;
                }
            }
        }
        gather_ring(adj, i, 2, &mut self.grow, &mut frontier);
        if self.ring.len() <= self.grow.len() {
            return None;
        }
        self.ring.sort_unstable();
        let mut offsets = Vec::new();
        let inv_h = scaled_offsets(positions, i, &self.ring, &mut offsets)?;
        Some((inv_h, offsets))
    }

    /// Exactly [`jet_fit`] at the current vertex, reusing the rings gathered by earlier fits at it.
    pub(crate) fn fit(
        &mut self,
        positions: &[Vector3<f64>],
        adj: &Adjacency,
        frame: &Frame,
    ) -> JetFit {
        let i = self.vertex;
        let start = if adj.valence(i) >= 6 && !adj.is_boundary_vertex(i) { 1 } else { 2 };
        for depth in start..=4 {
            let k = depth - 1;
            if !self.valid[k] {
                gather_ring(adj, i, depth, &mut self.ring, &mut self.grow);
                self.inv_h[k] = scaled_offsets(positions, i, &self.ring, &mut self.offsets[k]);
                self.valid[k] = true;
            }
            if let Some(inv_h) = self.inv_h[k] {
                // A 1-ring much smaller than its neighbours' is a micro-feature (module docs).
                if depth == 1 && MIN_RING_SHARE * self.neighbour_radius * inv_h > 1.0 {
                    continue;
                }
                // The slope variance matters only against a height noise (module docs).
                let check = depth < 4 && self.height_noise > 0.0;
                let fit = fit_scaled_checked(&self.offsets[k], inv_h, frame, check);
                if let Some((w, slope, variance)) = fit {
                    if depth == 4 || determined(slope, variance, self.height_noise * inv_h) {
                        return JetFit { w, slope, ring: depth as u8 };
                    }
                }
            }
        }
        JetFit { w: Matrix2::zeros(), slope: [0.0; 2], ring: 0 }
    }
}

/// The steepest tangent plane a ring's fit may give, relative to the normal it was made in:
/// 30°. The start normal (angle-weighted) is never that far from the surface's unless the
/// ring cannot tell the plane — a sculpt's or scan's slivers put a vertex's 1-ring neighbours
/// almost on a line, and five coefficients fitted through six such points tilt the normal
/// anywhere, even over. Such a fit is not taken: the next ring is (as for a ring that
/// determines no quadric at all).
pub const MAX_FIT_TILT_DEG: f64 = 30.0;

/// Above this slope variance (the fit's (A⁻¹)₀₀ + (A⁻¹)₁₁) a ring's fit is judged against the
/// part's height noise: the fitted slope moves by √variance times the neighbours' height errors
/// (in units of the ring's radius). A regular ring of six gives 2/3 and the 1-rings of the shared clean meshes at most
/// 6.4, so they are never judged; a mesher's slivers give up to 10³ (their neighbours bunch
/// along a line). A CAD part's strips bunch as much, but its positions are exact.
pub const MAX_SLOPE_VARIANCE: f64 = 10.0;

/// The smallest RMS radius of a 1-ring fit, as a share of the mean of its neighbours' 1-ring
/// radii: a mesher's micro-feature — a marching-cubes corner 0.03 mm across on a surface of
/// 0.7 mm edges, its six faces along the grid's axes — has a 1-ring twenty times smaller than
/// its neighbours' (more than ten times is the rule), whose fit gives the corner's diagonal as the normal (20° off the surface's
/// around it) and a speck in every highlight. Its 2-ring is the surface's. A regular mesh has
/// neighbours' rings of the vertex's own size, a graded one within a factor of two.
pub const MIN_RING_SHARE: f64 = 0.1;

/// The RMS distance of each vertex's 1-ring neighbours to it (0 for an isolated vertex): the
/// scale a vertex's [`neighbour_radius`] is taken from.
pub fn ring_radii(positions: &[Vector3<f64>], adj: &Adjacency) -> Vec<f64> {
    use rayon::prelude::*;
    (0..positions.len())
        .into_par_iter()
        .map(|i| {
            let n = adj.neighbors(i);
            let s: f64 =
                n.iter().map(|&j| (positions[j as usize] - positions[i]).norm_squared()).sum();
            if n.is_empty() {
                0.0
            } else {
                (s / n.len() as f64).sqrt()
            }
        })
        .collect()
}

/// The mean of `radii` over the neighbours of vertex `i` (0 without neighbours).
pub fn neighbour_radius(radii: &[f64], adj: &Adjacency, i: usize) -> f64 {
    let n = adj.neighbors(i);
    if n.is_empty() {
        return 0.0;
    }
    n.iter().map(|&j| radii[j as usize]).sum::<f64>() / n.len() as f64
}

/// The tilt the part's height noise may give a ring's fitted normal through its slope
/// variance, degrees; a ring that would tilt it more is not taken (the next ring is).
pub const MAX_NOISE_TILT_DEG: f64 = 1.0;

/// Whether a ring's fit determines the tangent plane: a slope within [`MAX_FIT_TILT_DEG`], and
/// a [`slope_variance`] within [`MAX_SLOPE_VARIANCE`] or, beyond it, a tilt from the height
/// noise (`relative_noise`: its RMS over the ring's radius) within [`MAX_NOISE_TILT_DEG`].
fn determined(slope: [f64; 2], variance: f64, relative_noise: f64) -> bool {
    let t = MAX_FIT_TILT_DEG.to_radians().tan();
    let noise_tilt = variance.sqrt() * relative_noise;
    slope[0] * slope[0] + slope[1] * slope[1] <= t * t
        && (variance <= MAX_SLOPE_VARIANCE || noise_tilt <= MAX_NOISE_TILT_DEG.to_radians().tan())
}

/// Jet fit at vertex `i`, growing the ring as needed (see the module docs).
pub fn jet_fit(
    positions: &[Vector3<f64>],
    adj: &Adjacency,
    i: usize,
    frame: &Frame,
    bufs: &mut (Vec<u32>, Vec<u32>),
) -> JetFit {
    let start = if adj.valence(i) >= 6 && !adj.is_boundary_vertex(i) { 1 } else { 2 };
    for depth in start..=4 {
        gather_ring(adj, i, depth, &mut bufs.0, &mut bufs.1);
        let mut d = Vec::new();
        let fit = scaled_offsets(positions, i, &bufs.0, &mut d)
            .and_then(|inv_h| fit_scaled_checked(&d, inv_h, frame, false));
        if let Some((w, slope, variance)) = fit {
            if depth == 4 || determined(slope, variance, 0.0) {
                return JetFit { w, slope, ring: depth as u8 };
            }
        }
    }
    JetFit { w: Matrix2::zeros(), slope: [0.0; 2], ring: 0 }
}

/// Principal curvatures and directions at a vertex.
///
/// k1 ≥ k2 are the eigenvalues of −W: positive where the surface bends away from its normal
/// (a sphere with outward normals has k1 = k2 = +1/r).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principal {
    /// Maximum principal curvature.
    pub k1: f64,
    /// Minimum principal curvature.
    pub k2: f64,
    /// Unit direction of k1 in the vertex frame (angle-doubled sign ambiguity: ±).
    pub d1: [f64; 2],
}

impl Principal {
    /// Eigen-decomposition of −W (closed form for a symmetric 2×2 matrix).
    ///
    /// The eigenvector of the larger eigenvalue k1 of [[a, b], [b, c]] is (k1 − c, b) =
    /// (½(a − c) + r, b), or equally (b, k1 − a) = (b, r − ½(a − c)), r = hypot(½(a − c), b):
    /// the first has no cancellation when a ≥ c, the second when a < c. Normalized with its first
    /// component ≥ 0 it is the direction at angle ½·atan2(2b, a − c) ∈ (−π/2, π/2] (to rounding),
    /// computed without trigonometric functions (an atan2 and a sin/cos per vertex cost 3 % of the
    /// 1M-vertex core benchmark). An umbilic (r = 0) gets (1, 0).
    pub fn from_weingarten(w: &Matrix2<f64>) -> Self {
        let (a, b, c) = (-w[(0, 0)], -0.5 * (w[(0, 1)] + w[(1, 0)]), -w[(1, 1)]);
        let mean = 0.5 * (a + c);
        let half_diff = 0.5 * (a - c);
        let r = half_diff.hypot(b);
        let (x, y) = if half_diff >= 0.0 { (half_diff + r, b) } else { (b, r - half_diff) };
        let (x, y) = if x < 0.0 { (-x, -y) } else { (x, y) };
        let len = x.hypot(y);
        let d1 = if len > 0.0 && len.is_finite() { [x / len, y / len] } else { [1.0, 0.0] };
        Principal { k1: mean + r, k2: mean - r, d1 }
    }

    /// Unit direction of k2 in the vertex frame (d1 turned by +90°).
    pub fn d2(&self) -> [f64; 2] {
        [-self.d1[1], self.d1[0]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offsets at unit radius around the vertex at the given angles (degrees), on z = 0.
    fn ring(angles: &[f64]) -> Vec<Vector3<f64>> {
        angles
            .iter()
            .map(|a| Vector3::new(a.to_radians().cos(), a.to_radians().sin(), 0.0))
            .collect()
    }

    #[test]
    fn a_regular_ring_is_taken_and_a_bunched_one_grows() {
        let frame = Frame::from_normal(Vector3::z());
        // Six neighbours evenly around: (A⁻¹)₀₀ = (A⁻¹)₁₁ = 1/Σx² = 1/3 (odd and even moments
        // decouple), so the slope variance is 2/3.
        let even = ring(&[0.0, 60.0, 120.0, 180.0, 240.0, 300.0]);
        let (_, slope, v) = fit_scaled_checked(&even, 1.0, &frame, true).unwrap();
        assert!((v - 2.0 / 3.0).abs() < 1e-12, "{v}");
        assert!(determined(slope, v, 0.01));
        // A sliver's ring: five of six neighbours within 6° of one line. The quadric is still
        // determined (Cholesky succeeds), but a height error moves the slope tens of times over:
        // with errors of 1 % of the ring's radius (a mesher's) it is not taken; exact (a CAD
        // part's strips), it is.
        let bunched = ring(&[0.0, 3.0, 90.0, 177.0, 180.0, 186.0]);
        let (_, slope, v) = fit_scaled_checked(&bunched, 1.0, &frame, true).unwrap();
        assert!(v > MAX_SLOPE_VARIANCE, "{v}");
        assert!(!determined(slope, v, 0.01));
        assert!(determined(slope, v, 0.0));
        // A plane tilted by 40° is not taken from a ring either.
        assert!(!determined([40f64.to_radians().tan(), 0.0], 1.0, 0.0));
    }

    #[test]
    fn principal_of_diagonal() {
        let p = Principal::from_weingarten(&Matrix2::new(-2.0, 0.0, 0.0, -0.5));
        assert!((p.k1 - 2.0).abs() < 1e-15 && (p.k2 - 0.5).abs() < 1e-15);
        assert!((p.d1[0].abs() - 1.0).abs() < 1e-15);
    }

    /// The trigonometry-free eigenvector against the angle formula θ = ½·atan2(2b, a − c) and
    /// against the eigen-equation, over random symmetric maps and the edge cases (umbilics,
    /// a = c, b = 0 with a < c, huge and tiny scales).
    #[test]
    fn principal_direction_matches_the_angle_formula() {
        let mut s = 11u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut cases: Vec<Matrix2<f64>> = (0..2000)
            .map(|_| {
                let b = rnd();
                Matrix2::new(rnd(), b, b, rnd()) * 10f64.powf(6.0 * rnd())
            })
            .collect();
        cases.extend([
            Matrix2::zeros(),
            Matrix2::identity(),
            Matrix2::new(0.5, 0.3, 0.3, 0.5),
            Matrix2::new(0.5, -0.3, -0.3, 0.5),
            Matrix2::new(-1.0, 0.0, 0.0, -3.0),
            Matrix2::new(-3.0, 0.0, 0.0, -1.0),
            Matrix2::new(-3.0, 1e-300, 1e-300, -1.0),
            Matrix2::new(1e300, 1e299, 1e299, -1e300),
        ]);
        for w in cases {
            let p = Principal::from_weingarten(&w);
            assert!(p.d1.iter().all(|v| v.is_finite()));
            assert!((p.d1[0].hypot(p.d1[1]) - 1.0).abs() < 1e-15);
            let (a, b, c) = (-w[(0, 0)], -0.5 * (w[(0, 1)] + w[(1, 0)]), -w[(1, 1)]);
            let theta = 0.5 * (2.0 * b).atan2(a - c);
            let scale = a.abs().max(b.abs()).max(c.abs());
            if (p.k1 - p.k2) > 1e-12 * scale {
                // As lines: at θ = ±π/2 the sign of a zero b picks the end (−π/2 or π/2).
                let err = [1.0, -1.0]
                    .map(|s: f64| {
                        (p.d1[0] - s * theta.cos()).abs().max((p.d1[1] - s * theta.sin()).abs())
                    })
                    .into_iter()
                    .fold(f64::INFINITY, f64::min);
                assert!(err < 1e-12, "{w}: {:?} against θ = {theta}", p.d1);
                // −W d1 = k1 d1.
                let m = -w * nalgebra::Vector2::new(p.d1[0], p.d1[1]);
                assert!((m.x - p.k1 * p.d1[0]).abs() <= 1e-12 * scale);
                assert!((m.y - p.k1 * p.d1[1]).abs() <= 1e-12 * scale);
            }
        }
    }

    #[test]
    fn spd5_solves_and_refuses_rank_deficient_systems() {
        // A = MᵀM + I for a fixed M, so A is SPD; x_true known, b = A x_true.
        let m: [[f64; 5]; 5] = std::array::from_fn(|r| {
            std::array::from_fn(|c| ((3 * r + 7 * c) % 11) as f64 / 5.0 - 1.0)
        });
        let full = |r: usize, c: usize| {
            (0..5).map(|k| m[k][r] * m[k][c]).sum::<f64>() + if r == c { 1.0 } else { 0.0 }
        };
        let mut a = [0.0; 15];
        for r in 0..5 {
            for c in 0..=r {
                a[tri(r, c)] = full(r, c);
            }
        }
        let x_true = [1.0, -2.0, 0.5, 3.0, -0.25];
        let b: [f64; 5] = std::array::from_fn(|r| (0..5).map(|c| full(r, c) * x_true[c]).sum());
        let x = solve_spd5(&a, &b).unwrap();
        for k in 0..5 {
            assert!((x[k] - x_true[k]).abs() < 1e-12, "{x:?}");
        }
        // Neighbours on one line do not determine a quadric.
        let pos: Vec<Vector3<f64>> =
            (0..7).map(|k| Vector3::new(0.1 * k as f64, 0.05 * k as f64, 0.0)).collect();
        let frame = Frame { t: Vector3::x(), b: Vector3::y(), n: Vector3::z() };
        assert!(fit_quadric(&pos, 0, &frame, &(1..7).collect::<Vec<u32>>()).is_none());
    }

    #[test]
    fn exact_on_a_quadric() {
        // z = g·x + ½xᵀCx is fitted exactly from any 5+ points in general position.
        let (g, c) = ([0.1, -0.3], Matrix2::new(0.7, 0.2, 0.2, -0.4));
        let mut pos = vec![Vector3::zeros()];
        for k in 0..7 {
            let a = k as f64 * 0.9;
            let (x, y) = (0.1 * a.cos(), 0.1 * (1.0 + 0.1 * k as f64) * a.sin());
            let z = g[0] * x
                + g[1] * y
                + 0.5 * (c[(0, 0)] * x * x + 2.0 * c[(0, 1)] * x * y + c[(1, 1)] * y * y);
            pos.push(Vector3::new(x, y, z));
        }
        let frame = Frame { t: Vector3::x(), b: Vector3::y(), n: Vector3::z() };
        let ring: Vec<u32> = (1..8).collect();
        let (w, s) = fit_quadric(&pos, 0, &frame, &ring).unwrap();
        assert!((w - c).norm() < 1e-10, "{w} vs {c}");
        assert!((s[0] - g[0]).abs() < 1e-12 && (s[1] - g[1]).abs() < 1e-12);
    }
}
