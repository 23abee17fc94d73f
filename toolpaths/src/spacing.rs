//! Distances from a point to the strokes placed so far, measured on the surface (first
//! fundamental form of the query point's triangle) or in UV. Strokes are stored as their
//! polyline samples in a [`PointGrid`]; a query measures the distance to the segments next
//! to each nearby sample, so the result is the true point-to-polyline distance as long as
//! the segments are shorter than the query radius.

use serde::{Deserialize, Serialize};

use crate::geom::{point_segment_distance, Metric, Vec2};
use crate::grid::PointGrid;
use crate::mesh::Domain;
use crate::trace::Stroke;

/// How distances between strokes are measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub enum Spacing {
    /// On the part, with the first fundamental form (the default: the part is what gets
    /// brushed).
    #[default]
    Surface,
    /// In UV units (flat-sheet work).
    Uv,
}

const LINK_PREV: u8 = 1;
const LINK_NEXT: u8 = 2;

/// Stroke samples in a grid, for distance queries.
pub(crate) struct StrokeIndex {
    grid: PointGrid,
    pos: Vec<Vec2>,
    link: Vec<u8>,
    spacing: Spacing,
    /// Longest segment inserted so far (in the spacing metric).
    max_seg: f64,
}

impl StrokeIndex {
    /// An empty index over the domain with cells of about `d` surface mm (`d_test` is a
    /// good choice: the frequent test then visits 3 × 3 small cells).
    pub fn new(dom: &Domain, d: f64, spacing: Spacing) -> StrokeIndex {
        let stretch = typical_stretch(dom, spacing);
        StrokeIndex {
            grid: PointGrid::new(dom.bbox, d / stretch),
            pos: Vec::new(),
            link: Vec::new(),
            spacing,
            max_seg: 0.0,
        }
    }

    fn metric_at(&self, dom: &Domain, f: u32) -> Metric {
        self.metric(dom, f)
    }

    /// The metric distances are measured with at face `f`.
    pub fn metric(&self, dom: &Domain, f: u32) -> Metric {
        match self.spacing {
            Spacing::Surface => dom.metric[f as usize],
            Spacing::Uv => Metric::IDENTITY,
        }
    }

    /// UV radius that contains every point within distance `r` of a point in face `f`.
    pub fn uv_radius(&self, dom: &Domain, f: u32, r: f64) -> f64 {
        match self.spacing {
            Spacing::Surface => r / dom.min_stretch[f as usize],
            Spacing::Uv => r,
        }
    }

    /// Add a stroke's points.
    pub fn insert(&mut self, dom: &Domain, s: &Stroke) {
        let n = s.uv.len();
        let mut bi = 0;
        for (i, &p) in s.uv.iter().enumerate() {
            while bi < s.breaks.len() && s.breaks[bi] < i {
                bi += 1;
            }
            let jump_before = bi < s.breaks.len() && s.breaks[bi] == i;
            let jump_after = s.breaks.binary_search(&(i + 1)).is_ok();
            let mut l = 0;
            if i > 0 && !jump_before {
                l |= LINK_PREV;
            }
            if i + 1 < n && !jump_after {
                l |= LINK_NEXT;
            }
            if l & LINK_PREV != 0 {
                let m = self.metric_at(dom, s.faces[i]);
                self.max_seg = self.max_seg.max(m.length(crate::geom::sub(p, s.uv[i - 1])));
            }
            let id = self.pos.len() as u32;
            self.pos.push(p);
            self.link.push(l);
            self.grid.insert(p, id);
        }
    }

    /// Distance from `p` to the polyline around sample `i`; `r` lets far samples skip the
    /// segment tests (a segment next to `q` is at most `max_seg` long, so it cannot come
    /// within `r` of `p` when `|p − q| ≥ r + max_seg`).
    fn sample_distance(&self, m: &Metric, p: Vec2, i: usize, r: f64) -> f64 {
        let q = self.pos[i];
        let mut d = m.length(crate::geom::sub(q, p));
        if d >= r + self.max_seg {
            return d;
        }
        if self.link[i] & LINK_NEXT != 0 {
            d = d.min(point_segment_distance(m, p, q, self.pos[i + 1]));
        }
        if self.link[i] & LINK_PREV != 0 {
            d = d.min(point_segment_distance(m, p, self.pos[i - 1], q));
        }
        d
    }

    /// Whether some stroke passes within distance `r` of `p` (in face `f`).
    pub fn within(&self, dom: &Domain, p: Vec2, f: u32, r: f64) -> bool {
        let m = self.metric(dom, f);
        let mut hit = false;
        // A segment within r of p has an end within r + max_seg / 2.
        self.grid.visit(p, self.uv_radius(dom, f, r + 0.5 * self.max_seg), |i| {
            if self.sample_distance(&m, p, i as usize, r) < r {
                hit = true;
                false
            } else {
                true
            }
        });
        hit
    }

    /// Distance from `p` to the nearest stroke, capped at `r` (returns `r` when none is
    /// closer).
    pub fn nearest(&self, dom: &Domain, p: Vec2, f: u32, r: f64) -> f64 {
        let m = self.metric(dom, f);
        let mut best = r;
        self.grid.visit(p, self.uv_radius(dom, f, r + 0.5 * self.max_seg), |i| {
            best = best.min(self.sample_distance(&m, p, i as usize, best));
            true
        });
        best
    }
}

/// Median of `√λ_max` over faces (1 for UV spacing): surface mm per UV unit, used to size
/// grid cells and raster steps.
pub(crate) fn typical_stretch(dom: &Domain, spacing: Spacing) -> f64 {
    if spacing == Spacing::Uv {
        return 1.0;
    }
    let step = (dom.metric.len() / 4096).max(1);
    let mut s: Vec<f64> =
        dom.metric.iter().step_by(step).map(|m| m.eigen_range().1.sqrt()).collect();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2].max(1e-12)
}
