//! Distances from a point to the strokes placed so far.
//!
//! * **On the part** ([`Spacing::Surface`]) with a 3D lift: stroke samples are stored with
//!   their 3D positions and unit normals in a hashed 3D grid, and a query lifts its point and
//!   measures the 3D distance to the nearby polyline segments, corrected from chord to arc
//!   length with the normal curvature along the chord: for a chord `Δx` between points
//!   whose normals differ by `Δn`, `κ_n |Δx| ≈ Δn·Δx / |Δx|` (Weingarten: `dN/ds · T =
//!   −κ_n`), and the arc of a circle of curvature `κ` over a chord `c` is `c (1 + κ²c²/24 +
//!   O(c⁴))`, so `d ≈ c + (Δn·Δx)² / (24 c)` (eq. S1). Samples whose normal differs from the
//!   query's by more than 60° are ignored: they lie on another face of a thin wall or across
//!   a sharp crease, not beside the stroke on the surface. The measure does not depend on the
//!   UV layout, however stretched.
//! * **On the part without a lift** (a given metric only): UV differences measured with the
//!   first fundamental form of the query point's triangle (exact where the metric is
//!   constant over `d_sep`).
//! * **In UV** ([`Spacing::Uv`]): plain UV distances.
//!
//! Without a lift, only samples on the query point's chart count: charts that overlap in UV
//! are separate sheets. A query measures the distance to the segments next to each nearby
//! sample, so the result is the true point-to-polyline distance as long as the segments are
//! shorter than the query radius.

use serde::{Deserialize, Serialize};

use crate::geom::{dot3, norm3, point_segment_distance, segment_foot3, sub3, Metric, Vec2, Vec3};
use crate::grid::Grid3;
use crate::locate::barycentric;
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

/// Samples whose unit normal makes a smaller cosine than this with the query's are on
/// another sheet of the part (cos 60°).
const NORMAL_MIN: f64 = 0.5;

/// A query point, lifted once: UV, face, chart, metric, and (with a lift) 3D position and
/// unit normal.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Probe {
    pub uv: Vec2,
    pub chart: u32,
    pub m: Metric,
    /// 3D position (lift mode) or `[u, v, 0]`.
    pub x: Vec3,
    pub n: Vec3,
}

/// Stroke samples in a grid, for distance queries.
pub(crate) struct StrokeIndex {
    grid: Grid3,
    pos: Vec<Vec3>,
    uv: Vec<Vec2>,
    nrm: Vec<Vec3>,
    chart: Vec<u32>,
    link: Vec<u8>,
    spacing: Spacing,
    lift: bool,
    /// Longest segment inserted so far (in the spacing measure).
    max_seg: f64,
}

/// Whether distances are measured on the 3D lift.
pub(crate) fn uses_lift(dom: &Domain, spacing: Spacing) -> bool {
    spacing == Spacing::Surface && dom.spacing_normals.is_some()
}

/// The box of the points a grid in the spacing space holds: the lift's box, or the UV box
/// at z = 0.
pub(crate) fn embedding_box(dom: &Domain, lift: bool) -> [[f64; 3]; 2] {
    match (&dom.positions, lift) {
        (Some(p), true) => {
            let mut b = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
            for x in p {
                for k in 0..3 {
                    b[0][k] = b[0][k].min(x[k]);
                    b[1][k] = b[1][k].max(x[k]);
                }
            }
            b
        }
        _ => {
            let u = dom.bbox;
            [[u[0][0], u[0][1], 0.0], [u[1][0], u[1][1], 0.0]]
        }
    }
}

/// A query point at `p` in face `f`.
pub(crate) fn probe(dom: &Domain, spacing: Spacing, p: Vec2, f: u32) -> Probe {
    let chart = dom.chart[f as usize];
    let m = match spacing {
        Spacing::Surface => dom.metric[f as usize],
        Spacing::Uv => Metric::IDENTITY,
    };
    if uses_lift(dom, spacing) {
        let b = barycentric(dom.corners(f), p);
        let t = dom.tris[f as usize];
        let pos = dom.positions.as_deref().unwrap_or_default();
        let ns = dom.spacing_normals.as_deref().unwrap_or_default();
        let mut x = [0.0; 3];
        let mut n = [0.0; 3];
        for i in 0..3 {
            let v = t[i] as usize;
            for k in 0..3 {
                x[k] += b[i] * pos[v][k];
                n[k] += b[i] * ns[v][k];
            }
        }
        let l = norm3(n);
        let n = if l > 0.0 { n.map(|c| c / l) } else { [0.0; 3] };
        Probe { uv: p, chart, m, x, n }
    } else {
        Probe { uv: p, chart, m, x: [p[0], p[1], 0.0], n: [0.0; 3] }
    }
}

/// Eq. S1: surface distance from the chord `x → y` and the normals at both ends.
pub(crate) fn arc_from_chord(x: Vec3, nx: Vec3, y: Vec3, ny: Vec3) -> f64 {
    let dx = sub3(y, x);
    let c = norm3(dx);
    if c <= 0.0 {
        return 0.0;
    }
    let k = dot3(sub3(ny, nx), dx);
    c + k * k / (24.0 * c)
}

impl StrokeIndex {
    /// An empty index over the domain with cells of about `2 d` surface mm (`d` = the usual
    /// query radius: a query then visits at most 2 cells per axis).
    pub fn new(dom: &Domain, d: f64, spacing: Spacing) -> StrokeIndex {
        let lift = uses_lift(dom, spacing);
        let stretch = if lift { 1.0 } else { typical_stretch(dom, spacing) };
        StrokeIndex {
            grid: Grid3::new(embedding_box(dom, lift), 2.0 * d / stretch),
            pos: Vec::new(),
            uv: Vec::new(),
            nrm: Vec::new(),
            chart: Vec::new(),
            link: Vec::new(),
            spacing,
            lift,
            max_seg: 0.0,
        }
    }

    /// Whether distances are measured on the 3D lift.
    pub fn lifted(&self) -> bool {
        self.lift
    }

    /// The metric UV lengths are measured with at face `f`.
    pub fn metric(&self, dom: &Domain, f: u32) -> Metric {
        match self.spacing {
            Spacing::Surface => dom.metric[f as usize],
            Spacing::Uv => Metric::IDENTITY,
        }
    }

    /// UV radius that contains every point within distance `r` of a point in face `f`
    /// (where the metric is that of `f`).
    pub fn uv_radius(&self, dom: &Domain, f: u32, r: f64) -> f64 {
        match self.spacing {
            Spacing::Surface => r / dom.min_stretch[f as usize],
            Spacing::Uv => r,
        }
    }

    /// The query point at `p` in face `f`.
    pub fn probe(&self, dom: &Domain, p: Vec2, f: u32) -> Probe {
        probe(dom, self.spacing, p, f)
    }

    /// Radius of the grid visit that finds every sample within `r` of `q`.
    pub fn visit_radius(&self, dom: &Domain, f: u32, r: f64) -> f64 {
        if self.lift {
            r
        } else {
            self.uv_radius(dom, f, r)
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
            let pr = self.probe(dom, p, s.faces[i]);
            if l & LINK_PREV != 0 {
                let seg = if self.lift {
                    norm3(sub3(pr.x, self.pos[self.pos.len() - 1]))
                } else {
                    pr.m.length(crate::geom::sub(p, s.uv[i - 1]))
                };
                self.max_seg = self.max_seg.max(seg);
            }
            let id = self.pos.len() as u32;
            self.pos.push(pr.x);
            self.uv.push(p);
            if self.lift {
                self.nrm.push(pr.n);
            }
            self.chart.push(pr.chart);
            self.link.push(l);
            self.grid.insert(pr.x, id);
        }
    }

    /// Distance from the probe to the polyline around sample `i`; `r` lets far samples skip
    /// the segment tests (a segment next to `q` is at most `max_seg` long, so it cannot come
    /// within `r` of `p` when `|p − q| ≥ r + max_seg`). Samples on another sheet (another
    /// chart without a lift; a normal more than 60° away with one) are infinitely far.
    fn sample_distance(&self, q: &Probe, i: usize, r: f64) -> f64 {
        if self.lift {
            let y = self.pos[i];
            let c = norm3(sub3(y, q.x));
            // A far sample is far either way (its chord, or infinity on another sheet, are
            // both ≥ r): the normal test below is needed only for near ones.
            if c >= r + self.max_seg {
                return c;
            }
            let ny = self.nrm[i];
            // (Zero normals — a degenerate corner or given zero vectors — filter nothing.)
            if dot3(ny, q.n) < NORMAL_MIN && dot3(ny, ny) > 0.5 && dot3(q.n, q.n) > 0.5 {
                return f64::INFINITY;
            }
            let mut best = y;
            let mut bc = c;
            for (flag, j) in [(LINK_NEXT, i + 1), (LINK_PREV, i.wrapping_sub(1))] {
                if self.link[i] & flag != 0 {
                    let (_, f) = segment_foot3(q.x, y, self.pos[j]);
                    let d = norm3(sub3(f, q.x));
                    if d < bc {
                        (bc, best) = (d, f);
                    }
                }
            }
            arc_from_chord(q.x, q.n, best, ny)
        } else {
            if self.chart[i] != q.chart {
                return f64::INFINITY;
            }
            let m = &q.m;
            let y = self.uv[i];
            let mut d = m.length(crate::geom::sub(y, q.uv));
            if d >= r + self.max_seg {
                return d;
            }
            if self.link[i] & LINK_NEXT != 0 {
                d = d.min(point_segment_distance(m, q.uv, y, self.uv[i + 1]));
            }
            if self.link[i] & LINK_PREV != 0 {
                d = d.min(point_segment_distance(m, q.uv, self.uv[i - 1], y));
            }
            d
        }
    }

    /// Whether some stroke passes within distance `r` of `p` (in face `f`).
    pub fn within(&self, dom: &Domain, p: Vec2, f: u32, r: f64) -> bool {
        let q = self.probe(dom, p, f);
        self.within_probe(dom, &q, f, r)
    }

    /// [`StrokeIndex::within`] for a lifted query.
    pub fn within_probe(&self, dom: &Domain, q: &Probe, f: u32, r: f64) -> bool {
        let mut hit = false;
        // A segment within r of p has an end within r + max_seg / 2.
        self.grid.visit(q.x, self.visit_radius(dom, f, r + 0.5 * self.max_seg), |i| {
            if self.sample_distance(q, i as usize, r) < r {
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
        let q = self.probe(dom, p, f);
        let mut best = r;
        self.grid.visit(q.x, self.visit_radius(dom, f, r + 0.5 * self.max_seg), |i| {
            best = best.min(self.sample_distance(&q, i as usize, best));
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
