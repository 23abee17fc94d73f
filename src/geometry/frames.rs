//! The fixed tangent frames [t, b, n].
//!
//! `t = normalize((I − nnᵀ) r)` for a fixed world axis `r` (x, switching to y where
//! |rᵀn| > 0.9), `b = n × t`, so [t, b, n] is orthonormal and right-handed (docs/math.md §1).
//! The frame is arbitrary; every quantity grainline reports is independent of it.

use nalgebra::{Vector2, Vector3};

/// An orthonormal, right-handed tangent frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent axis.
    pub t: Vector3<f64>,
    /// Second tangent axis, `n × t`.
    pub b: Vector3<f64>,
    /// Unit normal.
    pub n: Vector3<f64>,
}

impl Frame {
    /// The frame of grainline's convention around unit normal `n`.
    pub fn from_normal(n: Vector3<f64>) -> Self {
        let r = if n.x.abs() > 0.9 { Vector3::y() } else { Vector3::x() };
        let t = (r - n * n.dot(&r)).normalize();
        Frame { t, b: n.cross(&t), n }
    }

    /// A frame around `n` whose first axis is `t` (already orthogonal to `n`, unit length).
    pub fn with_tangent(n: Vector3<f64>, t: Vector3<f64>) -> Self {
        Frame { t, b: n.cross(&t), n }
    }

    /// Tangential coordinates `[t b]ᵀ w`.
    #[inline]
    pub fn to_local(&self, w: &Vector3<f64>) -> Vector2<f64> {
        Vector2::new(self.t.dot(w), self.b.dot(w))
    }

    /// The world vector `x t + y b`.
    #[inline]
    pub fn to_world(&self, w: &Vector2<f64>) -> Vector3<f64> {
        self.t * w.x + self.b * w.y
    }

    /// The world direction of angle φ: `cos φ t + sin φ b` (Eq. 6).
    #[inline]
    pub fn direction(&self, phi: f64) -> Vector3<f64> {
        self.t * phi.cos() + self.b * phi.sin()
    }

    /// The angle φ of a tangent vector `u`: `atan2(bᵀu, tᵀu)` (the paper's `polar`, the inverse
    /// of Eq. 6; see math.md §5.2). Zero for a vector with no tangential part.
    #[inline]
    pub fn angle_of(&self, u: &Vector3<f64>) -> f64 {
        self.b.dot(u).atan2(self.t.dot(u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_handed_orthonormal() {
        for n in
            [Vector3::x(), Vector3::y(), Vector3::z(), Vector3::new(1.0, -2.0, 0.5).normalize()]
        {
            let f = Frame::from_normal(n);
            assert!((f.t.norm() - 1.0).abs() < 1e-14);
            assert!(f.t.dot(&f.n).abs() < 1e-14);
            assert!((f.t.cross(&f.b) - f.n).norm() < 1e-14);
            let phi = 0.7;
            assert!((f.angle_of(&f.direction(phi)) - phi).abs() < 1e-14);
        }
    }
}
