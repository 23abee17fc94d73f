//! The potential highlight tangent ℓ(φ) (the paper's Eq. 7, conventions of math.md §1).
//!
//! In the vertex frame [t, b, n], with ū = (cos φ, sin φ), v̄ = (−sin φ, cos φ), h̄ = [t b]ᵀh:
//!
//! ```text
//! m = (v̄ᵀh̄) ∇φ + (nᵀh) W ū,        ℓ = m₁ b − m₂ t                      (Eq. 7)
//! ```
//!
//! Equivalently ℓ = n × ∇_S(hᵀu): ℓ is tangent to the level sets of hᵀu, so on the ideal
//! highlight {hᵀu = 0} it is the highlight curve's tangent. ℓ is not normalized: |ℓ| → 0 is the
//! degenerate "highlight region" of the paper's Fig. 2b, handled by [`super::tensor`].
//!
//! Eq. 7 holds h fixed. For a point eye or a point light h varies over the surface, and
//! ∇_S(hᵀu) gains (∇h)ᵀu = G ū (G from [`super::lighting::h_gradients`], docs/math.md §2.1):
//!
//! ```text
//! m = (v̄ᵀh̄) ∇φ + ((nᵀh) W + G) ū                                       (Eq. 7 + near term)
//! ```
//!
//! [`highlight_field_near`] and [`m_vector_near`] take G as an `Option`; `None` (a distant light
//! and view) is Eq. 7 exactly, bit for bit.

use nalgebra::{Matrix2, Vector2, Vector3};
use rayon::prelude::*;

use super::Symmetry;
use crate::geometry::{Frame, Geometry, GradientForm};

/// m of Eq. 7 in the frame coordinates (ℓ = R m, a quarter turn).
#[inline]
pub fn m_vector(
    frame: &Frame,
    w: &Matrix2<f64>,
    grad: &Vector2<f64>,
    phi: f64,
    h: &Vector3<f64>,
) -> Vector2<f64> {
    let (s, c) = phi.sin_cos();
    let u = Vector2::new(c, s);
    let v = Vector2::new(-s, c);
    let hb = frame.to_local(h);
    grad * v.dot(&hb) + w * u * frame.n.dot(h)
}

/// m of Eq. 7 plus the near term G ū when `g` is given (module documentation); with `None`
/// exactly [`m_vector`].
#[inline]
pub fn m_vector_near(
    frame: &Frame,
    w: &Matrix2<f64>,
    grad: &Vector2<f64>,
    phi: f64,
    h: &Vector3<f64>,
    g: Option<&Matrix2<f64>>,
) -> Vector2<f64> {
    let m = m_vector(frame, w, grad, phi, h);
    match g {
        None => m,
        Some(g) => m + g * Vector2::new(phi.cos(), phi.sin()),
    }
}

/// ℓ in world coordinates from m: `ℓ = m₁ b − m₂ t`.
#[inline]
pub fn ell_from_m(frame: &Frame, m: &Vector2<f64>) -> Vector3<f64> {
    frame.b * m.x - frame.t * m.y
}

/// ℓ and ∇φ at every vertex.
#[derive(Clone, Debug)]
pub struct HighlightField {
    /// ∇φ in each vertex frame.
    pub gradient: Vec<Vector2<f64>>,
    /// m of Eq. 7 in each vertex frame.
    pub m: Vec<Vector2<f64>>,
    /// ℓ in world coordinates (not normalized).
    pub ell: Vec<Vector3<f64>>,
}

/// Evaluates Eq. 7 at every vertex for the angle field `phi` and per-vertex half vectors `h`,
/// holding h fixed: exact for a distant light and view. With a point eye or a point light use
/// [`highlight_field_near`].
pub fn highlight_field(
    geom: &Geometry,
    phi: &[f64],
    symmetry: Symmetry,
    form: GradientForm,
    h: &[Vector3<f64>],
) -> HighlightField {
    highlight_field_near(geom, phi, symmetry, form, h, None)
}

/// Eq. 7 with the near term: `h_gradient` is G per vertex from
/// [`super::lighting::h_gradients`] (`None` for a distant light and view: [`highlight_field`]).
pub fn highlight_field_near(
    geom: &Geometry,
    phi: &[f64],
    symmetry: Symmetry,
    form: GradientForm,
    h: &[Vector3<f64>],
    h_gradient: Option<&[Matrix2<f64>]>,
) -> HighlightField {
    let gradient = geom.stencil.gradient(phi, symmetry.k(), form);
    let m: Vec<Vector2<f64>> = (0..geom.num_vertices())
        .into_par_iter()
        .map(|i| {
            let (f, w) = (&geom.frames[i], &geom.weingarten[i]);
            m_vector_near(f, w, &gradient[i], phi[i], &h[i], h_gradient.map(|g| &g[i]))
        })
        .collect();
    let ell = m.par_iter().zip(&geom.frames).map(|(m, f)| ell_from_m(f, m)).collect();
    HighlightField { gradient, m, ell }
}
