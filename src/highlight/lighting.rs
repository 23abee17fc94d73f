//! Light and view directions, and the half vector h = normalize(ω_in + ω_out).
//!
//! Both ω_in (towards the light) and ω_out (towards the viewer) point away from the surface.
//! The light is distant (a direction) or a point light (per-vertex ω_in); the view is distant
//! (a direction) or a point eye (per-vertex ω_out).
//!
//! For a point light or a point eye h varies over the surface even where n does not, and ℓ gains
//! the term (∇h)ᵀu (docs/math.md §2.1): [`h_gradients`] gives it per vertex as a 2×2 matrix G in
//! the vertex frame, (∇_S h)ᵀu = G ū, with
//!
//! ```text
//! s = ω_in + ω_out,  h = s/|s|,  ∂ω/∂p = −(I − ωωᵀ)/d  (d the distance; 0 when distant)
//! ∂h/∂p = (I − hhᵀ) S / |s|,  S = ∂ω_in/∂p + ∂ω_out/∂p  (symmetric)
//! G = [t b]ᵀ S (I − hhᵀ) [t b] / |s|                           (G_ab = (∂_a h)ᵀ e_b)
//! ```

use nalgebra::{Matrix2, Matrix3, Vector3};
use rayon::prelude::*;

use crate::geometry::Frame;
use crate::{Error, Result};

/// Where the viewer is.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    /// A distant viewer in this direction (from the surface towards the viewer).
    Direction(Vector3<f64>),
    /// A point eye at this position (scene units).
    Eye(Vector3<f64>),
}

/// The key light (distant or a point) and a view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Unit direction from the surface towards the light. For a point light: the direction
    /// from the reference point given to [`Lighting::point`] (the part's centre) towards the
    /// light, used only where one direction stands for the light (reports, FIELD.json's
    /// `meta.light`).
    pub light: Vector3<f64>,
    /// The viewer.
    pub view: View,
    /// The position of a point light (scene units); `None` for a distant light in `light`.
    pub light_position: Option<Vector3<f64>>,
}

impl Lighting {
    /// A distant light. Validates and normalizes: directions must be finite and non-zero, the
    /// eye finite.
    pub fn new(light: Vector3<f64>, view: View) -> Result<Self> {
        let light = unit("light", light)?;
        Ok(Lighting { light, view: checked_view(view)?, light_position: None })
    }

    /// A point light at `position`; `reference` (a point of the part, e.g. its bounding box's
    /// centre) only fixes the nominal direction `light`. Errors if either is not finite or
    /// they coincide.
    pub fn point(position: Vector3<f64>, reference: Vector3<f64>, view: View) -> Result<Self> {
        if !position.iter().chain(reference.iter()).all(|c| c.is_finite()) {
            return Err(Error::invalid_arg("light position", "coordinates must be finite"));
        }
        let light = unit("light position − part centre", position - reference)?;
        Ok(Lighting { light, view: checked_view(view)?, light_position: Some(position) })
    }

    /// The same kind of light moved so that ω_in at `p` is `direction`: a distant light in that
    /// direction, or a point light at the same distance from `p` as before (its nominal
    /// direction is then taken from `p`). What the light tools switch to.
    pub fn moved(&self, p: &Vector3<f64>, direction: Vector3<f64>) -> Result<Self> {
        match self.light_distance(p) {
            None => Lighting::new(direction, self.view),
            Some(d) => {
                if !(d > 0.0 && d.is_finite()) {
                    return Err(Error::invalid_arg(
                        "light position",
                        "the point light is at the vertex itself",
                    ));
                }
                Lighting::point(p + unit("light", direction)? * d, *p, self.view)
            }
        }
    }

    /// True when h varies with position only through n, i.e. both the light and the view are
    /// distant: then the (∇h)ᵀu term of ℓ vanishes.
    pub fn is_distant(&self) -> bool {
        self.light_position.is_none() && matches!(self.view, View::Direction(_))
    }

    /// ω_in at position `p` (unit; for a point light at `p` itself, ω_out is used, and for an
    /// eye there too, the nominal direction `light`).
    pub fn omega_in(&self, p: &Vector3<f64>) -> Vector3<f64> {
        match self.light_position {
            None => self.light,
            Some(l) => towards(&l, p).unwrap_or_else(|| match self.view {
                View::Direction(d) => d,
                View::Eye(e) => towards(&e, p).unwrap_or(self.light),
            }),
        }
    }

    /// ω_out at position `p` (unit; for an eye at `p` itself, ω_in is used).
    pub fn omega_out(&self, p: &Vector3<f64>) -> Vector3<f64> {
        match self.view {
            View::Direction(d) => d,
            View::Eye(e) => towards(&e, p).unwrap_or_else(|| match self.light_position {
                None => self.light,
                Some(l) => towards(&l, p).unwrap_or(self.light),
            }),
        }
    }

    /// The distance from `p` to the light (`None` for a distant light).
    pub fn light_distance(&self, p: &Vector3<f64>) -> Option<f64> {
        self.light_position.map(|l| (l - p).norm())
    }

    /// The distance from `p` to the eye (`None` for a distant view).
    pub fn eye_distance(&self, p: &Vector3<f64>) -> Option<f64> {
        match self.view {
            View::Direction(_) => None,
            View::Eye(e) => Some((e - p).norm()),
        }
    }
}

/// The centre of the bounding box of `positions` (the origin when empty): the reference point
/// of a point light's nominal direction.
pub fn centre_of(positions: &[Vector3<f64>]) -> Vector3<f64> {
    let mut it = positions.iter();
    let Some(first) = it.next() else { return Vector3::zeros() };
    let (lo, hi) = it.fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    (lo + hi) * 0.5
}

fn checked_view(view: View) -> Result<View> {
    match view {
        View::Direction(d) => Ok(View::Direction(unit("view", d)?)),
        View::Eye(e) if e.iter().all(|c| c.is_finite()) => Ok(View::Eye(e)),
        View::Eye(_) => Err(Error::invalid_arg("eye", "coordinates must be finite")),
    }
}

/// The unit vector from `p` towards `q`, `None` if they coincide (or the distance overflows).
fn towards(q: &Vector3<f64>, p: &Vector3<f64>) -> Option<Vector3<f64>> {
    let d = q - p;
    let n = d.norm();
    (n > 0.0 && n.is_finite()).then(|| d / n)
}

fn unit(name: &str, v: Vector3<f64>) -> Result<Vector3<f64>> {
    let n = v.norm();
    if !(n.is_finite() && n > 0.0) {
        return Err(Error::invalid_arg(
            name,
            format!(
                "direction {} must be finite and non-zero",
                crate::error::fmt_vec3(&[v.x, v.y, v.z])
            ),
        ));
    }
    Ok(v / n)
}

/// The half vector of `w_in` and `w_out`, both unit.
///
/// When the two are opposite the half vector is not defined; then the unit vector ⟂ `w_in`
/// closest to the normal `n` is used (and, if `n` is parallel to `w_in` too, any fixed vector
/// ⟂ `w_in`), so the result is always a finite unit vector.
pub fn half_vector(w_in: &Vector3<f64>, w_out: &Vector3<f64>, n: &Vector3<f64>) -> Vector3<f64> {
    let s = w_in + w_out;
    let len = s.norm();
    if len > 1e-9 {
        return s / len;
    }
    let perp = n - w_in * w_in.dot(n);
    if perp.norm() > 1e-9 {
        return perp.normalize();
    }
    let axis = if w_in.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    (axis - w_in * w_in.dot(&axis)).normalize()
}

/// The half vector at every vertex.
pub fn half_vectors(
    lighting: &Lighting,
    positions: &[Vector3<f64>],
    normals: &[Vector3<f64>],
) -> Vec<Vector3<f64>> {
    positions
        .par_iter()
        .zip(normals)
        .map(|(p, n)| half_vector(&lighting.omega_in(p), &lighting.omega_out(p), n))
        .collect()
}

/// ∂ω/∂p = −(I − ωωᵀ)/d for the unit vector ω from p towards a point at distance d.
fn direction_jacobian(omega: &Vector3<f64>, d: f64) -> Matrix3<f64> {
    if !(d > 0.0 && d.is_finite()) {
        return Matrix3::zeros();
    }
    -(Matrix3::identity() - omega * omega.transpose()) / d
}

/// The matrix G of the (∇h)ᵀu term at one point (module documentation): for a tangent field u
/// with frame coordinates ū, the surface gradient of p ↦ h(p)ᵀu (u held fixed) is G ū in the
/// frame. Zero where the half vector is not defined (ω_in = −ω_out).
pub fn h_gradient(lighting: &Lighting, p: &Vector3<f64>, frame: &Frame) -> Matrix2<f64> {
    let (w_in, w_out) = (lighting.omega_in(p), lighting.omega_out(p));
    h_gradient_of(&w_in, &w_out, lighting.light_distance(p), lighting.eye_distance(p), frame)
}

/// G from ω_in and ω_out (unit) and the distances to the light and the eye (`None`: distant).
pub fn h_gradient_of(
    w_in: &Vector3<f64>,
    w_out: &Vector3<f64>,
    light_distance: Option<f64>,
    eye_distance: Option<f64>,
    frame: &Frame,
) -> Matrix2<f64> {
    let s = w_in + w_out;
    let len = s.norm();
    if len.is_nan() || len <= 1e-9 {
        return Matrix2::zeros();
    }
    let h = s / len;
    let mut sum = Matrix3::zeros();
    if let Some(d) = light_distance {
        sum += direction_jacobian(w_in, d);
    }
    if let Some(d) = eye_distance {
        sum += direction_jacobian(w_out, d);
    }
    // G_ab = e_aᵀ S (I − hhᵀ) e_b / |s| = (∂_a h)ᵀ e_b, since ∂_a h = (I − hhᵀ) S e_a / |s| and
    // S = Sᵀ.
    let axes = [frame.t, frame.b];
    let proj = axes.map(|e| e - h * h.dot(&e));
    let g = Matrix2::from_fn(|a, b| axes[a].dot(&(sum * proj[b])) / len);
    if g.iter().all(|x| x.is_finite()) {
        g
    } else {
        Matrix2::zeros()
    }
}

/// G at every vertex (see [`h_gradient`]), or `None` when the light and the view are both
/// distant: then the term vanishes and Eq. 7 is used exactly as printed (bit-identical).
pub fn h_gradients(
    lighting: &Lighting,
    positions: &[Vector3<f64>],
    frames: &[Frame],
) -> Option<Vec<Matrix2<f64>>> {
    if lighting.is_distant() {
        return None;
    }
    Some(positions.par_iter().zip(frames).map(|(p, f)| h_gradient(lighting, p, f)).collect())
}
