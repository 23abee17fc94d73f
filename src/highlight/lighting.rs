//! Light and view directions, and the half vector h = normalize(ω_in + ω_out).
//!
//! Both ω_in (towards the light) and ω_out (towards the viewer) point away from the surface.
//! The light is distant; the view is distant (a direction) or a point eye (per-vertex ω_out).

use nalgebra::Vector3;
use rayon::prelude::*;

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

/// A distant light and a view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Unit direction from the surface towards the light.
    pub light: Vector3<f64>,
    /// The viewer.
    pub view: View,
}

impl Lighting {
    /// Validates and normalizes: directions must be finite and non-zero, the eye finite.
    pub fn new(light: Vector3<f64>, view: View) -> Result<Self> {
        let light = unit("light", light)?;
        let view = match view {
            View::Direction(d) => View::Direction(unit("view", d)?),
            View::Eye(e) if e.iter().all(|c| c.is_finite()) => View::Eye(e),
            View::Eye(_) => return Err(Error::invalid_arg("eye", "coordinates must be finite")),
        };
        Ok(Lighting { light, view })
    }

    /// ω_out at position `p` (unit; for an eye at `p` itself, the light direction is used).
    pub fn omega_out(&self, p: &Vector3<f64>) -> Vector3<f64> {
        match self.view {
            View::Direction(d) => d,
            View::Eye(e) => {
                let d = e - p;
                let n = d.norm();
                if n > 0.0 && n.is_finite() {
                    d / n
                } else {
                    self.light
                }
            }
        }
    }
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
        .map(|(p, n)| half_vector(&lighting.light, &lighting.omega_out(p), n))
        .collect()
}
