//! The turning-radius hinge inside the triangles, on the field as the stroke tracer
//! interpolates it (issue 17, item 1).
//!
//! The vertex hinge ([`super::fabrication`]) bounds κ = ūᵀ∇φ at the vertices, with ∇φ from the
//! Eq. 10 stencil. The tracer (`grainline-toolpaths`, `field.rs`) instead follows, inside each
//! triangle, the barycentric blend of the corners' directions, normalized: streamlines of that
//! field can turn tighter than any vertex value says. This term bounds their curvature at
//! quadrature points of every triangle.
//!
//! In the plane of triangle f (orthonormal axes e₁ = (p₁ − p₀)/|p₁ − p₀|, e₂ = n_f × e₁), corner
//! i's direction uᵢ = cos φᵢ tᵢ + sin φᵢ bᵢ has the in-plane coordinates wᵢ = (e₁ᵀuᵢ, e₂ᵀuᵢ),
//! sign-aligned to corner 0 for a line field (ŵᵢ = sᵢwᵢ, sᵢ = sign(ŵ₀ᵀwᵢ)), and
//!
//! ```text
//! w(λ) = Σ λᵢ ŵᵢ,   G = ∂w/∂x = Σ ŵᵢ ∇λᵢᵀ (constant on f),   g = G w
//! κ = (w × g) / |w|³                                                        (F1)
//! ```
//!
//! is the signed curvature of the streamline of w/|w| through the point (the derivative of the
//! unit field along itself, crossed with it). The residual of quadrature point q of f is
//!
//! ```text
//! r = √(λ A_f / Q) · max(0, R′|κ| − 1),   R′ = R / (1 − margin)                (F2)
//! ```
//!
//! with Q = 4 points: the centroid and (⅔, ⅙, ⅙) and its permutations. The margin asks the
//! interpolated field for a little more than R, for the tracer's step and the spacing to keep.
//! With dᵢ = sᵢ(e₁ᵀvᵢ, e₂ᵀvᵢ) = ∂ŵᵢ/∂φᵢ (vᵢ = ∂uᵢ/∂φᵢ = −sin φᵢ tᵢ + cos φᵢ bᵢ):
//!
//! ```text
//! ∂w = λᵢ dᵢ,   ∂g = dᵢ(∇λᵢᵀw) + λᵢ G dᵢ,   ∂N = ∂w × g + w × ∂g   (N = w × g)
//! ∂κ/∂φᵢ = ∂N/|w|³ − 3κ (wᵀ∂w)/|w|²                                          (F3)
//! ∂r/∂φᵢ = √(λA_f/Q) R′ sign(κ) ∂κ/∂φᵢ   where the hinge is active.
//! ```
//!
//! The splay twin bounds the divergence of the same unit field, d ln δ/ds for neighbouring
//! strokes (math.md §7), by s_max·(1 − margin):
//!
//! ```text
//! σ = div(w/|w|) = tr G / |w| − wᵀG w / |w|³                                  (F4)
//! ∂σ/∂φᵢ = dᵢᵀ∇λᵢ/|w| − tr G (wᵀ∂w)/|w|³ − ∂M/|w|³ + 3M (wᵀ∂w)/|w|⁵,
//!          M = wᵀg, ∂M = ∂wᵀg + wᵀ∂g.
//! ```
//!
//! Where the blend nearly cancels (|w| < ¼ Σλᵢ|ŵᵢ|: corners more than ~150° apart, a singular
//! triangle) the row is inactive: the tracer stops there too. Rows keep their (zero) entries so
//! the Jacobian's pattern does not depend on φ.

use nalgebra::{Vector2, Vector3};

use super::fabrication::HingeKind;
use crate::geometry::Geometry;
use crate::highlight::Symmetry;
use crate::mesh::Mesh;

/// Quadrature points (barycentric) per triangle.
pub const QUADRATURE: [[f64; 3]; 4] = [
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
    [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
    [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
];

/// Below this share of Σλᵢ|ŵᵢ| the blend counts as cancelling (row inactive).
const CANCEL: f64 = 0.25;

/// One triangle's fixed data: its plane's axes, the gradients of its barycentric coordinates
/// in them, and its area.
#[derive(Clone, Copy, Debug)]
pub struct FaceFrame {
    /// Corner vertices.
    pub corners: [u32; 3],
    /// In-plane axes e₁, e₂.
    pub axes: [Vector3<f64>; 2],
    /// ∇λᵢ in (e₁, e₂) coordinates.
    pub grad_bary: [Vector2<f64>; 3],
    /// Area.
    pub area: f64,
}

impl FaceFrame {
    /// The frame of face `corners` of `mesh`, or `None` for a degenerate triangle.
    pub fn new(mesh: &Mesh, corners: [u32; 3]) -> Option<FaceFrame> {
        let p = corners.map(|v| mesh.positions[v as usize]);
        let (a, b) = (p[1] - p[0], p[2] - p[0]);
        let n = a.cross(&b);
        let area2 = n.norm();
        let la = a.norm();
        if !(area2 > 0.0 && la > 0.0 && area2.is_finite()) || area2 <= 1e-14 * la * la {
            return None;
        }
        let e1 = a / la;
        let e2 = (n / area2).cross(&e1);
        let q = p.map(|x| Vector2::new(e1.dot(&(x - p[0])), e2.dot(&(x - p[0]))));
        // ∇λᵢ = perp(q_{i+2} − q_{i+1}) / (2·signed area), perp(x, y) = (−y, x)... in the
        // plane's own orientation the signed area is area2 / 2 > 0.
        let grad = [0, 1, 2].map(|i| {
            let e = q[(i + 2) % 3] - q[(i + 1) % 3];
            Vector2::new(-e.y, e.x) / area2
        });
        Some(FaceFrame { corners, axes: [e1, e2], grad_bary: grad, area: 0.5 * area2 })
    }
}

/// The per-triangle turning hinge (F1–F3), or its splay twin (F4).
#[derive(Clone, Debug)]
pub struct FaceTurningHinge<'a> {
    /// The surface (vertex frames).
    pub geometry: &'a Geometry,
    /// k = 1 or 2.
    pub symmetry: Symmetry,
    /// The triangles' frames.
    pub faces: Vec<FaceFrame>,
    /// Turning (κ, F1) or splay (σ, F4).
    pub kind: HingeKind,
    /// The inverse bound: R′ = R/(1 − margin) for turning, 1/(s_max·(1 − margin)) for splay;
    /// the hinge is max(0, radius·|x| − 1).
    pub radius: f64,
    /// The weight λ.
    pub weight: f64,
}

/// Corner values of one face: ŵᵢ and dᵢ.
fn corners(
    g: &Geometry,
    f: &FaceFrame,
    phi: &[f64],
    line: bool,
) -> ([Vector2<f64>; 3], [Vector2<f64>; 3]) {
    let mut w = [Vector2::zeros(); 3];
    let mut d = [Vector2::zeros(); 3];
    for i in 0..3 {
        let v = f.corners[i] as usize;
        let fr = &g.frames[v];
        let (s, c) = phi[v].sin_cos();
        let u = fr.t * c + fr.b * s;
        let du = fr.b * c - fr.t * s;
        w[i] = Vector2::new(f.axes[0].dot(&u), f.axes[1].dot(&u));
        d[i] = Vector2::new(f.axes[0].dot(&du), f.axes[1].dot(&du));
    }
    if line {
        for i in 1..3 {
            if w[0].dot(&w[i]) < 0.0 {
                w[i] = -w[i];
                d[i] = -d[i];
            }
        }
    }
    (w, d)
}

fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

impl FaceTurningHinge<'_> {
    /// Frames of every non-degenerate face of `mesh`.
    pub fn frames(mesh: &Mesh) -> Vec<FaceFrame> {
        mesh.faces.iter().filter_map(|&t| FaceFrame::new(mesh, t)).collect()
    }

    /// Number of rows (faces × quadrature points).
    pub fn rows(&self) -> usize {
        self.faces.len() * QUADRATURE.len()
    }

    /// κ (F1) or σ (F4) at quadrature point `q` of face `face`, or `None` where the blend
    /// cancels.
    pub fn curvature(&self, phi: &[f64], face: usize, q: usize) -> Option<f64> {
        self.eval(phi, face, q, None)
    }

    fn eval(&self, phi: &[f64], face: usize, q: usize, jac: Option<&mut [f64; 3]>) -> Option<f64> {
        let f = &self.faces[face];
        let (w, d) = corners(self.geometry, f, phi, self.symmetry == Symmetry::Line);
        let l = QUADRATURE[q];
        let wq = w[0] * l[0] + w[1] * l[1] + w[2] * l[2];
        let mag: f64 = (0..3).map(|i| l[i] * w[i].norm()).sum();
        let len = wq.norm();
        if !(len > CANCEL * mag && len > 0.0) {
            return None;
        }
        let gl: [f64; 3] = [0, 1, 2].map(|i| f.grad_bary[i].dot(&wq));
        let g = w[0] * gl[0] + w[1] * gl[1] + w[2] * gl[2];
        let l2 = len * len;
        let l3 = l2 * len;
        match self.kind {
            HingeKind::Turning => {
                let n = cross(&wq, &g);
                let kappa = n / l3;
                if let Some(out) = jac {
                    for i in 0..3 {
                        let dw = d[i] * l[i];
                        // G x = Σⱼ ŵⱼ (∇λⱼᵀ x)
                        let gd: Vector2<f64> =
                            (0..3).map(|j| w[j] * f.grad_bary[j].dot(&d[i])).sum();
                        let dg = d[i] * gl[i] + gd * l[i];
                        let dn = cross(&dw, &g) + cross(&wq, &dg);
                        out[i] = dn / l3 - 3.0 * kappa * wq.dot(&dw) / l2;
                    }
                }
                Some(kappa)
            }
            HingeKind::Splay => {
                // σ = tr G / |w| − wᵀGw / |w|³ (F4).
                let tr: f64 = (0..3).map(|i| w[i].dot(&f.grad_bary[i])).sum();
                let m = wq.dot(&g);
                let sigma = tr / len - m / l3;
                if let Some(out) = jac {
                    for i in 0..3 {
                        let dw = d[i] * l[i];
                        let gd: Vector2<f64> =
                            (0..3).map(|j| w[j] * f.grad_bary[j].dot(&d[i])).sum();
                        let dg = d[i] * gl[i] + gd * l[i];
                        let dtr = d[i].dot(&f.grad_bary[i]);
                        let dm = dw.dot(&g) + wq.dot(&dg);
                        let wdw = wq.dot(&dw);
                        out[i] = dtr / len - tr * wdw / l3 - dm / l3 + 3.0 * m * wdw / (l3 * l2);
                    }
                }
                Some(sigma)
            }
        }
    }

    fn scale(&self, face: usize) -> f64 {
        (self.weight * self.faces[face].area / QUADRATURE.len() as f64).max(0.0).sqrt()
    }

    /// The residual (F2) of row `row` (= face × Q + q).
    pub fn residual(&self, phi: &[f64], row: usize) -> f64 {
        let (face, q) = (row / QUADRATURE.len(), row % QUADRATURE.len());
        match self.eval(phi, face, q, None) {
            Some(k) => self.scale(face) * (self.radius * k.abs() - 1.0).max(0.0),
            None => 0.0,
        }
    }

    /// The residual of row `row` and its Jacobian entries (the face's three corners, in corner
    /// order, zeros where inactive) written to `entries` (cleared first).
    pub fn jacobian(&self, phi: &[f64], row: usize, entries: &mut Vec<(u32, f64)>) -> f64 {
        let (face, q) = (row / QUADRATURE.len(), row % QUADRATURE.len());
        let f = &self.faces[face];
        let mut dk = [0.0; 3];
        let kappa = self.eval(phi, face, q, Some(&mut dk));
        entries.clear();
        let s = self.scale(face);
        let (r, factor) = match kappa {
            Some(k) if self.radius * k.abs() > 1.0 => {
                (s * (self.radius * k.abs() - 1.0), s * self.radius * k.signum())
            }
            _ => (0.0, 0.0),
        };
        entries.extend(f.corners.iter().zip(dk).map(|(&v, d)| (v, factor * d)));
        r
    }
}
