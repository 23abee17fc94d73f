//! Degenerate faces: which faces loading drops (or refuses, under
//! [`DegeneratePolicy::Error`](super::load::DegeneratePolicy)), and how messages name them.
//!
//! A face is degenerate when two of its corners are one vertex (after welding), when its
//! corners are collinear or coincide in `f64` (cross product exactly zero), or when it is a
//! **sliver**: |(b − a) × (c − a)| ≤ 10⁻¹²·ℓ², ℓ its longest edge — its height is at most
//! 10⁻¹² of ℓ (twice 5·10⁻¹³), so its corners are collinear up to rounding even where its area
//! is large (a needle 10⁷⁵ long and 10⁻³⁷ high has an area of 5·10³⁷).
//!
//! The test is computed on the edges divided by their largest component, so it neither
//! overflows for coordinates up to [`MAX_COORDINATE`](crate::limits::MAX_COORDINATE) nor
//! underflows for tiny ones: it depends on the face's shape only, never on its size.

use nalgebra::Vector3;

/// Height over longest edge (times two) at or below which a face is a sliver.
pub const SLIVER_RATIO: f64 = 1e-12;

/// Why a face is degenerate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Degeneracy {
    /// Two corners are the same vertex (after welding).
    RepeatedVertex,
    /// The corners are collinear or coincide in `f64`: the cross product is exactly zero.
    Collinear,
    /// Its height is at most [`SLIVER_RATIO`] × its longest edge.
    Sliver,
}

/// Whether face `v` (vertex indices into `pos`) is degenerate, and why.
pub(crate) fn classify(v: [u32; 3], pos: &[Vector3<f64>]) -> Option<Degeneracy> {
    if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
        return Some(Degeneracy::RepeatedVertex);
    }
    let [a, b, c] = v.map(|i| pos[i as usize]);
    let (cross, l2, _) = scaled_shape(a, b, c);
    if cross == 0.0 {
        Some(Degeneracy::Collinear)
    } else if cross <= SLIVER_RATIO * l2 {
        Some(Degeneracy::Sliver)
    } else {
        None
    }
}

/// The face's |(b − a) × (c − a)| and longest squared edge, both for the edges divided by
/// their largest absolute component `s` (returned third; 0 when the corners coincide).
fn scaled_shape(a: Vector3<f64>, b: Vector3<f64>, c: Vector3<f64>) -> (f64, f64, f64) {
    let (e1, e2) = (b - a, c - a);
    let s = e1.amax().max(e2.amax());
    if s == 0.0 || !s.is_finite() {
        return (0.0, 0.0, s);
    }
    let (u1, u2) = (e1 / s, e2 / s);
    let u3 = u2 - u1;
    let l2 = u1.norm_squared().max(u2.norm_squared()).max(u3.norm_squared());
    (u1.cross(&u2).norm(), l2, s)
}

/// A face's area, computed without overflow for coordinates within the bound (the product
/// `½ |u₁ × u₂| · s²` of the scaled shape and the scale).
pub(crate) fn area(a: Vector3<f64>, b: Vector3<f64>, c: Vector3<f64>) -> f64 {
    let (cross, _, s) = scaled_shape(a, b, c);
    0.5 * cross * s * s
}

/// The degenerate faces of a mesh, by kind, for messages.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Counts {
    /// Faces of zero area: a repeated vertex or collinear corners.
    pub zero_area: usize,
    /// Slivers.
    pub slivers: usize,
    /// The largest area among the slivers.
    pub largest_sliver: f64,
}

impl Counts {
    /// Counts face `v`'s kind (with its area, for a sliver).
    pub fn add(&mut self, kind: Degeneracy, v: [u32; 3], pos: &[Vector3<f64>]) {
        match kind {
            Degeneracy::Sliver => {
                self.slivers += 1;
                let [a, b, c] = v.map(|i| pos[i as usize]);
                self.largest_sliver = self.largest_sliver.max(area(a, b, c));
            }
            _ => self.zero_area += 1,
        }
    }

    /// All degenerate faces.
    pub fn total(&self) -> usize {
        self.zero_area + self.slivers
    }

    /// What the faces are, after a count or "all N faces": `have zero area` when every one has,
    /// else `are degenerate (A with zero area, S slivers …)`.
    pub fn describe(&self) -> String {
        if self.slivers == 0 {
            return "have zero area".to_string();
        }
        let zero = match self.zero_area {
            0 => String::new(),
            n => format!("{n} with zero area, "),
        };
        format!(
            "are degenerate ({zero}{} sliver(s) whose height is at most {SLIVER_RATIO:e} of \
             their longest edge: collinear up to rounding, though of area up to {})",
            self.slivers,
            crate::error::fmt_num(self.largest_sliver)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kind(p: [[f64; 3]; 3]) -> Option<Degeneracy> {
        let pos: Vec<Vector3<f64>> = p.iter().map(|q| Vector3::from(*q)).collect();
        classify([0, 1, 2], &pos)
    }

    #[test]
    fn shape_decides_not_size() {
        let tri = |s: f64| [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0]];
        for s in [1e-150, 1e-9, 1.0, 1e19, 1e75] {
            assert_eq!(kind(tri(s)), None, "{s}");
        }
        assert_eq!(kind([[0.0; 3], [1e75, 0.0, 0.0], [0.0, 1e-37, 0.0]]), Some(Degeneracy::Sliver));
        assert_eq!(kind([[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]), Some(Degeneracy::Collinear));
        assert_eq!(kind([[1e74; 3], [1e74; 3], [1e74; 3]]), Some(Degeneracy::Collinear));
    }

    #[test]
    fn area_does_not_overflow() {
        let a = Vector3::new(-1e75, -1e75, -1e75);
        let b = Vector3::new(1e75, -1e75, 1e75);
        let c = Vector3::new(1e75, 1e75, -1e75);
        let x = area(a, b, c);
        assert!(x.is_finite() && x > 1e150, "{x}");
        let needle =
            area(Vector3::zeros(), Vector3::new(1e75, 0.0, 0.0), Vector3::new(0.0, 1e-37, 0.0));
        assert!((needle / 5e37 - 1.0).abs() < 1e-12, "{needle}");
    }
}
