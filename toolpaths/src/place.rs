//! Evenly spaced streamline placement (Jobard & Lefer, *Creating evenly-spaced streamlines
//! of arbitrary density*, 1997).
//!
//! * `d_sep = width · (1 − overlap)`: the distance between neighbouring strokes;
//!   `d_test = ratio · d_sep` (default ratio ½): a stroke being traced stops when it comes
//!   closer than `d_test` to an accepted stroke (§3).
//! * Candidate seeds sit `d_sep` to either side of every sample of every accepted stroke,
//!   in the order strokes were accepted (a FIFO queue, §3, "seed point selection"); a seed is
//!   valid when it lies in the domain, outside every singularity's exclusion radius, and at
//!   least `d_sep` from all strokes.
//! * When the queue runs dry (another chart, a region cut off by singularities), a raster of
//!   fallback seeds with pitch `d_sep` is scanned in row order. Everything is sequential and
//!   deterministic.
//!
//! Distances use the surface metric unless [`Spacing::Uv`] is chosen; the sideways offset of
//! a seed is `d_sep` along the metric normal of the stroke ([`Metric::unit_normal`]).

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use crate::error::{in_range, non_negative, positive, Result, ToolpathError};
use crate::field::Singularity;
use crate::geom::{add, scale, sub, Metric, Vec2};
use crate::grid::PointGrid;
use crate::locate::{walk, Walk};
use crate::mesh::Domain;
use crate::spacing::{typical_stretch, Spacing, StrokeIndex};
use crate::trace::{Stroke, TraceOptions, Tracer};

/// Options of the even-spacing placement. Lengths in mm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct PlacementOptions {
    /// Brush width, mm. Default 1.
    pub width: f64,
    /// Overlap of neighbouring passes as a fraction of the width, in [0, 1). Default 0.
    pub overlap: f64,
    /// `d_test / d_sep`, in (0, 1]. Default 0.5.
    pub test_ratio: f64,
    /// Where spacing is measured. Default [`Spacing::Surface`].
    pub spacing: Spacing,
    /// Strokes shorter than this (mm) are dropped. Default 0 (keep all).
    pub min_length: f64,
    /// Exclusion radius around singularities, mm; `None` means `d_sep`.
    pub exclusion_radius: Option<f64>,
    /// Seeds tried first, in order (UV). Default: the centre of the UV bounding box.
    pub seeds: Vec<Vec2>,
    /// Integration options. `max_step` is capped at `d_test / 2`; `exclusion_radius` is
    /// replaced by the one above.
    pub trace: TraceOptions,
}

impl Default for PlacementOptions {
    fn default() -> Self {
        PlacementOptions {
            width: 1.0,
            overlap: 0.0,
            test_ratio: 0.5,
            spacing: Spacing::Surface,
            min_length: 0.0,
            exclusion_radius: None,
            seeds: Vec::new(),
            trace: TraceOptions::default(),
        }
    }
}

impl PlacementOptions {
    /// Options for a brush `width` mm wide with the given `overlap` fraction.
    pub fn new(width: f64, overlap: f64) -> PlacementOptions {
        PlacementOptions { width, overlap, ..Default::default() }
    }

    /// `d_sep = width · (1 − overlap)`.
    pub fn d_sep(&self) -> f64 {
        self.width * (1.0 - self.overlap)
    }

    /// `d_test = test_ratio · d_sep`.
    pub fn d_test(&self) -> f64 {
        self.test_ratio * self.d_sep()
    }

    /// Reject NaN and out-of-range values with a clear error.
    pub fn validate(&self) -> Result<()> {
        positive("placement.width", self.width)?;
        in_range("placement.overlap", self.overlap, 0.0, 1.0, "must be in [0, 1)")?;
        positive("placement.test_ratio", self.test_ratio)?;
        if self.test_ratio > 1.0 {
            return Err(ToolpathError::InvalidOption {
                name: "placement.test_ratio",
                value: self.test_ratio,
                reason: "must be in (0, 1]",
            });
        }
        non_negative("placement.min_length", self.min_length)?;
        if let Some(r) = self.exclusion_radius {
            non_negative("placement.exclusion_radius", r)?;
        }
        for (i, s) in self.seeds.iter().enumerate() {
            if !(s[0].is_finite() && s[1].is_finite()) {
                return Err(ToolpathError::NonFinite { what: "placement.seeds", index: i });
            }
        }
        self.trace.validate()
    }
}

/// The placed strokes and what happened on the way.
#[derive(Clone, Debug)]
pub struct Placement {
    /// Accepted strokes, in acceptance order.
    pub strokes: Vec<Stroke>,
    /// Brush width, mm.
    pub width: f64,
    /// Separating distance used, mm.
    pub d_sep: f64,
    /// Test distance used, mm.
    pub d_test: f64,
    /// Where spacing was measured.
    pub spacing: Spacing,
    /// Singularities of the field (exclusion zones).
    pub singularities: Vec<Singularity>,
    /// Exclusion radius used, mm.
    pub exclusion_radius: f64,
    /// Strokes traced but dropped for being shorter than `min_length`.
    pub dropped_short: usize,
    /// Seeds that passed the validity tests and were traced.
    pub seeds_traced: usize,
    /// Field evaluations (Runge–Kutta stages).
    pub field_evaluations: u64,
}

/// Place evenly spaced strokes over the domain (see the module docs).
///
/// The work is estimated first ([`PlacementOptions::check_budget`], over the domain's area in
/// the spacing's metric) and refused past [`crate::budget::MAX_STROKE_SAMPLES`].
pub fn place_strokes(dom: &Domain, opts: &PlacementOptions) -> Result<Placement> {
    opts.validate()?;
    let area = match opts.spacing {
        Spacing::Surface => dom.surface_area(),
        Spacing::Uv => (0..dom.face_count() as u32).map(|f| dom.uv_area(f)).sum(),
    };
    opts.check_budget(area)?;
    let d_sep = opts.d_sep();
    let d_test = opts.d_test();
    let exclusion = opts.exclusion_radius.unwrap_or(d_sep);
    let mut topts = opts.trace.clone();
    topts.max_step = topts.max_step.min(0.5 * d_test);
    topts.min_step = topts.min_step.min(topts.max_step);
    topts.exclusion_radius = exclusion;
    let sing = dom.singularities();
    let mut st = State {
        dom,
        tracer: Tracer::new(dom, sing, &topts),
        index: StrokeIndex::new(dom, d_test + 0.5 * topts.max_step, opts.spacing),
        strokes: Vec::new(),
        queue: VecDeque::new(),
        d_sep,
        d_test,
        min_length: opts.min_length,
        dropped_short: 0,
        seeds_traced: 0,
        own: OwnPoints {
            grid: PointGrid::new(dom.bbox, 3.0 * d_test / typical_stretch(dom, opts.spacing)),
            pts: Vec::new(),
            closure: crate::trace::closure_radius(&topts),
        },
    };
    let mut initial: Vec<Vec2> = opts.seeds.clone();
    if initial.is_empty() {
        let b = dom.bbox;
        initial.push([(b[0][0] + b[1][0]) * 0.5, (b[0][1] + b[1][1]) * 0.5]);
    }
    for p in initial {
        if let Some((f, _)) = dom.grid.locate(dom, p) {
            st.try_seed(p, f);
            st.drain();
        }
    }
    // Fallback raster of seeds, row by row.
    let pitch = d_sep / typical_stretch(dom, opts.spacing);
    let b = dom.bbox;
    let nx = (((b[1][0] - b[0][0]) / pitch).ceil() as usize).min(1 << 14) + 1;
    let ny = (((b[1][1] - b[0][1]) / pitch).ceil() as usize).min(1 << 14) + 1;
    let mut hint: Option<u32> = None;
    for j in 0..ny {
        for i in 0..nx {
            let p = [b[0][0] + (i as f64 + 0.5) * pitch, b[0][1] + (j as f64 + 0.5) * pitch];
            let located = match hint {
                Some(h) => match walk(dom, h, dom_centroid(dom, h), p) {
                    Walk::Inside { face, .. } => Some(face),
                    Walk::Exit { .. } => dom.grid.locate(dom, p).map(|x| x.0),
                },
                None => dom.grid.locate(dom, p).map(|x| x.0),
            };
            let Some(f) = located else { continue };
            hint = Some(f);
            st.try_seed(p, f);
            st.drain();
        }
    }
    Ok(Placement {
        width: opts.width,
        d_sep,
        d_test,
        spacing: opts.spacing,
        exclusion_radius: exclusion,
        dropped_short: st.dropped_short,
        seeds_traced: st.seeds_traced,
        field_evaluations: st.tracer.evals,
        strokes: st.strokes,
        singularities: sing.to_vec(),
    })
}

/// Working state of the placement loop.
struct State<'a> {
    dom: &'a Domain,
    tracer: Tracer<'a>,
    index: StrokeIndex,
    strokes: Vec<Stroke>,
    queue: VecDeque<usize>,
    d_sep: f64,
    d_test: f64,
    min_length: f64,
    dropped_short: usize,
    seeds_traced: usize,
    own: OwnPoints,
}

/// The points of the stroke being traced, for the self-approach test: a stroke stops when
/// it comes within `d_test` of its own points more than `π · d_test` away along it (a
/// spiral, or a loop that does not close exactly), except on the final approach to its
/// start, where the tracer closes the loop.
struct OwnPoints {
    grid: PointGrid,
    pts: Vec<(Vec2, f64)>,
    /// The tracer's loop-closure radius.
    closure: f64,
}

impl OwnPoints {
    /// Forget the previous stroke in time proportional to its size.
    fn clear(&mut self) {
        for &(p, _) in &self.pts {
            self.grid.clear_at(p);
        }
        self.pts.clear();
    }

    /// Whether `p` (at arc length `arc`) is within `r` (UV radius `r_uv`) of an own point
    /// far along the stroke; then records `p`. Own points within `2r` of the seed that lie
    /// ahead of `p` within `closure` of its track are exempt: the stroke is about to close.
    fn approaches(&mut self, m: &Metric, p: Vec2, arc: f64, r: f64, r_uv: f64) -> bool {
        let skip = std::f64::consts::PI * r;
        let heading = self.pts.last().map(|&(q, _)| sub(p, q));
        let (pts, closure) = (&self.pts, self.closure);
        let mut hit = false;
        self.grid.visit(p, r_uv, |i| {
            let (q, s) = pts[i as usize];
            let v = sub(q, p);
            let dist = m.length(v);
            if (s - arc).abs() <= skip || dist >= r {
                return true;
            }
            if s.abs() <= 2.0 * r {
                if let Some(h) = heading.filter(|h| m.length(*h) > 0.0) {
                    let along = m.inner(v, h) / m.length(h);
                    let across = (dist * dist - along * along).max(0.0).sqrt();
                    if along > 0.0 && across < closure {
                        return true;
                    }
                }
            }
            hit = true;
            false
        });
        if !hit {
            self.grid.insert(p, self.pts.len() as u32);
            self.pts.push((p, arc));
        }
        hit
    }
}

impl State<'_> {
    /// Trace from `p` (in face `f`) if it is a valid seed; accept the stroke if long enough.
    fn try_seed(&mut self, p: Vec2, f: u32) {
        let (dom, d_test) = (self.dom, self.d_test);
        if self.index.within(dom, p, f, self.d_sep * SEED_SLACK)
            || self.tracer.near_singularity(p, f).is_some()
        {
            return;
        }
        let idx = &self.index;
        let own = &mut self.own;
        own.clear();
        let Some(s) = self.tracer.trace_both(p, f, |q, fq, arc, vertex| {
            idx.within(dom, q, fq, d_test)
                || vertex && {
                    let m = idx.metric(dom, fq);
                    own.approaches(&m, q, arc, d_test, idx.uv_radius(dom, fq, d_test))
                }
        }) else {
            return;
        };
        self.seeds_traced += 1;
        if s.length < self.min_length || s.uv.len() < 2 {
            self.dropped_short += 1;
            return;
        }
        self.index.insert(dom, &s);
        self.queue.push_back(self.strokes.len());
        self.strokes.push(s);
    }

    /// Seed beside every queued stroke until the queue is empty.
    fn drain(&mut self) {
        while let Some(si) = self.queue.pop_front() {
            for (p, f) in side_seeds(self.dom, &self.strokes[si], &self.index, self.d_sep) {
                self.try_seed(p, f);
            }
        }
    }
}

/// A seed counts as `d_sep` away when at least `d_sep · SEED_SLACK` away (round-off).
const SEED_SLACK: f64 = 1.0 - 1e-6;

fn dom_centroid(dom: &Domain, f: u32) -> Vec2 {
    let c = dom.corners(f);
    [(c[0][0] + c[1][0] + c[2][0]) / 3.0, (c[0][1] + c[1][1] + c[2][1]) / 3.0]
}

/// Candidate seeds `d_sep` to the left and right of every sample of `s`, located.
fn side_seeds(dom: &Domain, s: &Stroke, index: &StrokeIndex, d_sep: f64) -> Vec<(Vec2, u32)> {
    let mut out = Vec::with_capacity(2 * s.uv.len());
    for piece in s.pieces() {
        let pts = &s.uv[piece.clone()];
        if pts.len() < 2 {
            continue;
        }
        // Candidates every d_sep / 2 of arc length (plus both ends): a seed anywhere in a
        // gap grows both ways, so denser candidates only repeat the same tests.
        let mut since = f64::INFINITY;
        for i in 0..pts.len() {
            let k = piece.start + i;
            if i > 0 {
                since += index.metric(dom, s.faces[k]).length(sub(pts[i], pts[i - 1]));
            }
            if since < 0.5 * d_sep && i + 1 < pts.len() {
                continue;
            }
            since = 0.0;
            let f = s.faces[k];
            let m: Metric = index.metric(dom, f);
            let t = sub(pts[(i + 1).min(pts.len() - 1)], pts[i.saturating_sub(1)]);
            let l = m.length(t);
            if l <= 0.0 {
                continue;
            }
            let n = m.unit_normal(scale(t, 1.0 / l));
            for side in [1.0, -1.0] {
                let q = add(pts[i], scale(n, side * d_sep));
                if let Walk::Inside { face, .. } = walk(dom, f, pts[i], q) {
                    out.push((q, face));
                }
            }
        }
    }
    out
}
