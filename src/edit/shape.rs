//! What an edit asked for ([`EditShape`]), recorded by the edit tools in
//! [`super::EditReport::shape`] for the fidelity measure (`crate::fidelity`).

use nalgebra::Vector3;

use super::support::Support;
use super::WarpKind;

/// What an edit asked for, recorded by the edit tools (src/edit) in `EditReport::shape`.
#[derive(Clone, Debug, PartialEq)]
pub enum EditShape {
    /// bend / expand: the brush plane of src/edit/support.rs (origin o, unit axes ex, ey), the
    /// brush chart (geodesic polar coordinates in units of r, about the unit disk) and the warp.
    Warp {
        /// Bend or expand.
        kind: WarpKind,
        /// The warp strength s.
        strength: f64,
        /// The brush radius r, scene units.
        radius: f64,
        /// The plane's origin o (the centre projected onto the plane).
        origin: Vector3<f64>,
        /// The plane's unit x axis.
        ex: Vector3<f64>,
        /// The plane's unit y axis (the way the warp pushes).
        ey: Vector3<f64>,
        /// The support's vertices, ascending.
        support: Vec<u32>,
        /// Chart coordinates (units of r) of the vertices of the faces around the support,
        /// sorted by vertex: the brush chart of src/edit/chart.rs, in which the warp acts. Empty:
        /// the plane's coordinates [ex ey]ᵀ(p − o)/radius (a flat brush given by hand).
        chart: Vec<(u32, [f64; 2])>,
    },
    /// curve: the drawn curves as 3D polylines on the surface (UV curves lifted through the
    /// mesh's UV map), the brush radius, and the support (vertices that got a target).
    Curve {
        /// The brush radius r, scene units.
        radius: f64,
        /// The curves, scene units.
        polylines: Vec<Vec<Vector3<f64>>>,
        /// The vertices within r of a curve, ascending.
        support: Vec<u32>,
    },
}

impl EditShape {
    /// The brush radius r.
    pub fn radius(&self) -> f64 {
        match self {
            EditShape::Warp { radius, .. } | EditShape::Curve { radius, .. } => *radius,
        }
    }

    /// The support's vertices.
    pub fn support(&self) -> &[u32] {
        match self {
            EditShape::Warp { support, .. } | EditShape::Curve { support, .. } => support,
        }
    }
}

/// The shape of a bend or expand edit on `support`.
pub fn warp_shape(kind: WarpKind, strength: f64, support: &Support) -> EditShape {
    EditShape::Warp {
        kind,
        strength,
        radius: support.radius,
        origin: support.origin,
        ex: support.ex,
        ey: support.ey,
        support: support.vertices.iter().map(|&v| v as u32).collect(),
        chart: support.chart.points(),
    }
}
