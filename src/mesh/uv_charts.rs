//! UV charts, seams and flipped UV triangles.
//!
//! * A **seam edge** is a manifold edge (two faces, consistently oriented) whose two faces do
//!   not share the UV of both its ends. Boundary and non-manifold edges are never seams.
//! * A **chart** is a maximal set of faces connected across non-seam manifold edges.
//! * The **signed UV area** of face (a, b, c) is ½ (u_b − u_a) × (u_c − u_a) (2D cross product);
//!   a face is **flipped** when it is negative. A chart is **mirrored** when more than half of
//!   its faces are flipped (its UV layout is a mirror image: tangent frames built from it
//!   change handedness). Faces whose sign disagrees with their chart's majority are counted
//!   apart (`faces_against_chart`).

use rayon::prelude::*;
use serde::Serialize;

use super::halfedge::{EdgeKind, HalfEdges};
use super::union_find::UnionFind;
use super::{CornerAttribute, FaceId};
use nalgebra::Vector2;

/// One UV chart.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Chart {
    /// Faces in the chart.
    pub faces: usize,
    /// Faces with negative signed UV area.
    pub flipped: usize,
    /// Faces with zero UV area.
    pub degenerate: usize,
    /// More than half of the faces are flipped.
    pub mirrored: bool,
}

/// The UV charts of a mesh (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct UvCharts {
    face_chart: Vec<u32>,
    charts: Vec<Chart>,
    signed_area: Vec<f64>,
    seam: Vec<bool>,
    seam_edges: usize,
}

impl UvCharts {
    /// Computes charts, seams and UV orientation from per-corner UVs.
    pub fn new(he: &HalfEdges, uv: &CornerAttribute<Vector2<f64>>) -> Self {
        let nh = he.num_halfedges() as u32;
        let corner = |h: u32| uv.corners[(h / 3) as usize][(h % 3) as usize];
        let seam: Vec<bool> = (0..nh)
            .into_par_iter()
            .map(|h| match he.twin(h) {
                Some(t) if he.kind(h) == EdgeKind::Manifold => {
                    corner(h) != corner(HalfEdges::next(t))
                        || corner(HalfEdges::next(h)) != corner(t)
                }
                _ => false,
            })
            .collect();
        let mut uf = UnionFind::new(uv.corners.len());
        let mut seam_edges = 0;
        for h in 0..nh {
            let Some(t) = he.twin(h) else { continue };
            if h < t {
                if seam[h as usize] {
                    seam_edges += 1;
                } else {
                    uf.union(h / 3, t / 3);
                }
            }
        }
        let (face_chart, n) = uf.labels();
        let signed_area: Vec<f64> = (0..uv.corners.len())
            .into_par_iter()
            .map(|f| {
                let [a, b, c] = uv.face(f);
                0.5 * (b - a).perp(&(c - a))
            })
            .collect();
        let mut charts = vec![Chart { faces: 0, flipped: 0, degenerate: 0, mirrored: false }; n];
        for (f, &c) in face_chart.iter().enumerate() {
            let ch = &mut charts[c as usize];
            ch.faces += 1;
            ch.flipped += (signed_area[f] < 0.0) as usize;
            ch.degenerate += (signed_area[f] == 0.0) as usize;
        }
        for ch in &mut charts {
            ch.mirrored = 2 * ch.flipped > ch.faces;
        }
        UvCharts { face_chart, charts, signed_area, seam, seam_edges }
    }

    /// The charts, numbered by their first face.
    pub fn charts(&self) -> &[Chart] {
        &self.charts
    }

    /// The chart of face `f`.
    pub fn chart_of(&self, f: FaceId) -> usize {
        self.face_chart[f.index()] as usize
    }

    /// Number of seam edges.
    pub fn num_seam_edges(&self) -> usize {
        self.seam_edges
    }

    /// True when the edge of half-edge `h` is a seam.
    pub fn is_seam(&self, h: u32) -> bool {
        self.seam[h as usize]
    }

    /// Signed UV area of face `f`.
    pub fn signed_area(&self, f: FaceId) -> f64 {
        self.signed_area[f.index()]
    }

    /// Faces with negative signed UV area.
    pub fn num_flipped_faces(&self) -> usize {
        self.charts.iter().map(|c| c.flipped).sum()
    }

    /// Faces with zero UV area.
    pub fn num_degenerate_faces(&self) -> usize {
        self.charts.iter().map(|c| c.degenerate).sum()
    }

    /// Faces whose UV orientation disagrees with the majority of their chart (zero-area faces
    /// excluded).
    pub fn num_faces_against_chart(&self) -> usize {
        self.charts
            .iter()
            .map(|c| {
                let positive = c.faces - c.flipped - c.degenerate;
                if c.mirrored {
                    positive
                } else {
                    c.flipped
                }
            })
            .sum()
    }
}
