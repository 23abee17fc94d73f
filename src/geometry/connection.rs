//! The discrete Levi-Civita connection: how angles compare between neighbouring tangent planes.
//!
//! For an edge i–j, the transport angle ρᵢⱼ turns φⱼ (measured in frame j) into the frame of i:
//! the neighbour's direction seen from i has angle φⱼ + ρᵢⱼ. It is
//! `ρᵢⱼ = atan2(bᵢᵀt̃ⱼ, tᵢᵀt̃ⱼ)`, t̃ⱼ being tⱼ carried by the minimal rotation that takes nⱼ to
//! nᵢ (math.md §2): `w ↦ w + a×w + a×(a×w)/(1 + nⱼᵀnᵢ)`, `a = nⱼ × nᵢ`. It is O(h³)-accurate per
//! edge, ρⱼᵢ = −ρᵢⱼ exactly, and around a closed loop the transports compose to the loop's
//! holonomy (the enclosed Gaussian curvature; for the loop of face normals around a vertex, its
//! angle defect exactly).

use nalgebra::Vector3;

use super::frames::Frame;
use crate::mesh::Adjacency;

/// Rotates `w` by the minimal rotation taking unit vector `from` to unit vector `to`.
///
/// When the two are (nearly) opposite the minimal rotation is not unique; then the half-turn
/// about the axis of `w`'s own tangential part is used, which keeps the result finite and
/// tangent to `to` up to rounding.
#[inline]
pub fn minimal_rotation(w: &Vector3<f64>, from: &Vector3<f64>, to: &Vector3<f64>) -> Vector3<f64> {
    let c = from.dot(to);
    if c > -1.0 + 1e-9 {
        let a = from.cross(to);
        w + a.cross(w) + a.cross(&a.cross(w)) / (1.0 + c)
    } else {
        // Half-turn: reflect the normal part, keep the tangential part (a π rotation about the
        // axis ⟂ to `from` that contains w's tangential direction maps w to itself there).
        let wt = w - from * from.dot(w);
        wt - from * from.dot(w)
    }
}

/// The transport angle ρᵢⱼ from frame `j` to frame `i`.
#[inline]
pub fn transport_angle(fi: &Frame, fj: &Frame) -> f64 {
    let tj = minimal_rotation(&fj.t, &fj.n, &fi.n);
    fi.b.dot(&tj).atan2(fi.t.dot(&tj))
}

/// ρᵢⱼ for every directed edge (adjacency slot) `i → j`, with ρⱼᵢ = −ρᵢⱼ exactly.
pub fn edge_transport(adj: &Adjacency, frames: &[Frame]) -> Vec<f64> {
    // Each undirected edge is evaluated once (i < j); the reverse slot takes the exact negation
    // (ρⱼᵢ = −ρᵢⱼ), so the cost is half of evaluating every slot.
    let mut forward = vec![0.0; adj.num_slots()];
    adj.fill_slots(&mut forward, |i, s| {
        let j = adj.target(s);
        if i < j {
            transport_angle(&frames[i], &frames[j])
        } else {
            0.0
        }
    });
    let mut out = vec![0.0; adj.num_slots()];
    adj.fill_slots(
        &mut out,
        |i, s| {
            if i < adj.target(s) {
                forward[s]
            } else {
                -forward[adj.reverse(s)]
            }
        },
    );
    out
}

/// Wraps an angle to (−π, π].
#[inline]
pub fn wrap_angle(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = a - t * (a / t).round();
    if r <= -std::f64::consts::PI {
        r + t
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimal_rotation_maps_normal() {
        let from = Vector3::new(0.2, 0.1, 1.0).normalize();
        let to = Vector3::new(-0.5, 0.4, 0.8).normalize();
        let r = minimal_rotation(&from, &from, &to);
        assert!((r - to).norm() < 1e-14);
        let w = Vector3::new(1.0, 2.0, 3.0);
        assert!((minimal_rotation(&w, &from, &to).norm() - w.norm()).abs() < 1e-13);
    }

    #[test]
    fn transport_is_antisymmetric() {
        let fi = Frame::from_normal(Vector3::new(0.3, -0.2, 1.0).normalize());
        let fj = Frame::from_normal(Vector3::new(-0.1, 0.5, 1.0).normalize());
        assert!((transport_angle(&fi, &fj) + transport_angle(&fj, &fi)).abs() < 1e-14);
    }

    #[test]
    fn wrap() {
        assert!((wrap_angle(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap_angle(-0.5) + 0.5).abs() < 1e-15);
    }
}
