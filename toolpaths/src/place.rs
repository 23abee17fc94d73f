//! Evenly spaced streamline placement (Jobard & Lefer, *Creating evenly-spaced streamlines
//! of arbitrary density*, 1997).
//!
//! * `d_sep = width · (1 − overlap)`: the distance between neighbouring strokes;
//!   `d_test = ratio · d_sep` (default ratio ½): a stroke being traced stops when it comes
//!   closer than `d_test` to an accepted stroke (§3) — after a run-on of `end_run · d_test`
//!   of arc length (default 1) during which it stays `d_test / 2` away, so the wedge
//!   beyond its end, between its neighbours, is brushed too (`end_run = 0`: the classic
//!   stop).
//! * Candidate seeds sit `d_sep` to either side of every sample of every accepted stroke,
//!   in the order strokes were accepted (a FIFO queue, §3, "seed point selection"); a seed is
//!   valid when it lies in the domain, outside every singularity's exclusion radius, and at
//!   least `d_sep` from all strokes.
//! * When the queue runs dry (another chart, a region cut off by singularities), a raster of
//!   fallback seeds with pitch `d_sep` is scanned in row order. Everything is sequential and
//!   deterministic.
//!
//! * Every chart (connected piece of the UV layout) is its own sheet: the fallback raster
//!   scans each chart's UV box and locates its points in that chart only, so charts that
//!   overlap in UV (a mirrored half face laid over the other half) all get strokes.
//! * **Straddled points** (tried before any seed): a point the caller wants left *between*
//!   two strokes — where the grain rebuilt from the strokes changes from one stroke to the
//!   next, as an edit's highlight running along the grain must — seeds a stroke `d_sep / 2`
//!   on the surface to either side of it across the field, each traced when it lies `d_sep`
//!   from every stroke so far. The two run along the grain on either side of the point; their
//!   neighbours are seeded from the queue as any stroke's.
//! * **Gap filling** (after the queue and the raster): beside every stroke, at every
//!   candidate, a point that is farther than `d_sep / 2` from all strokes (uncovered) seeds
//!   a *fill* stroke traced with the same `d_test`: the strip between the last stroke and a
//!   chart edge that runs along the strokes (the seed sits in the middle of the uncovered
//!   part of the strip), and the wider gaps between diverging strokes (the seed sits midway).
//!   Fill strokes are marked ([`Stroke::fill`]) and counted, and do not seed further strokes.
//! * **Run-outs** (issue 31, item 3): an end on the part's real edge (a chart boundary that is
//!   not a UV seam: the metal ends there) runs `overtravel` (default one width) past it along
//!   its tangent ([`Stroke::run_out`]), so the edge beside it is brushed without a short corner
//!   or gap stroke; fill seeds are not placed where a run-out brushes. Ends on a seam get none
//!   (the surface goes on across it: a run-out would brush the other side).
//! * **No dabs** (D1): a stroke with an end on the metal (not run out) must lie on the part for
//!   `min_length` (default twice the brush width); a stroke run out at both ends (in from past
//!   the edge and out past it again, no plunge or lift-off mark on the metal) must be brushed
//!   `min_length` in all, run-outs included, and lie on the part for half of it. Shorter ones
//!   are dropped and counted; `0` keeps all.
//!
//! Distances are measured on the part's 3D lift when there is one ([`crate::Spacing`],
//! `spacing.rs`), else with the metric, or in UV for [`Spacing::Uv`]. The sideways offset of
//! a seed is `d_sep` **on the surface**: a march along the surface normal of the stroke
//! ([`Metric::unit_normal`]) across the triangles, each with its own metric
//! (`locate::march`), so a stretched or sheared layout does not change where seeds land.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use crate::error::{in_range, non_negative, positive, Result, ToolpathError};
use crate::field::Singularity;
use crate::geom::{dot3, norm3, scale, sub, sub3, Metric, Vec2, Vec3};
use crate::grid::Grid3;
use crate::locate::{march, walk, March, Walk};
use crate::mesh::Domain;
use crate::spacing::{typical_stretch, Probe, Spacing, StrokeIndex};
use crate::trace::{StopReason, Stroke, TraceOptions, Tracer};

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
    /// The shortest stroke kept (mm, on the part; shorter ones are dropped and counted in the
    /// report): a stroke with an end on the metal must lie on the part for this long; one run
    /// out past the part's edge at both ends must be brushed this long in all
    /// ([`Stroke::brushed_length`]) and lie on the part for half of it. Default (`None`):
    /// twice the brush width; `0` keeps every stroke.
    pub min_length: Option<f64>,
    /// How far a stroke that stops on the part's edge (a chart boundary that is not a UV
    /// seam) runs past it, along its tangent (mm on the part): the brush then brushes the edge
    /// beside the stroke's end instead of a short corner or gap stroke doing it
    /// ([`Stroke::run_out`]). Default (`None`): the brush width; `0`: strokes stop at the
    /// edge.
    pub overtravel: Option<f64>,
    /// Exclusion radius around singularities, mm; `None` means `d_sep`.
    pub exclusion_radius: Option<f64>,
    /// Run-on past the first approach, as a multiple of `d_test` (arc length): a stroke
    /// that comes within `d_test` of another keeps going for up to `end_run · d_test` as
    /// long as it stays `d_test / 2` away, so the wedge beyond its end, between its two
    /// neighbours, is brushed too. `0` stops at `d_test` (Jobard & Lefer). Default 1.
    pub end_run: f64,
    /// Fill the gaps left by the even spacing (module docs): strips along chart edges and
    /// gaps wider than `1.1 d_sep`. Default true.
    pub fill_gaps: bool,
    /// Seeds tried first, in order (UV). Default: the centre of the UV bounding box.
    pub seeds: Vec<Vec2>,
    /// Points to be left midway between two neighbouring strokes (UV), tried in order before
    /// any seed: from each, a seed `d_sep / 2` on the surface to either side across the
    /// field, each traced when it lies `d_sep` from every stroke so far (module docs,
    /// "Straddled points"). Set by the caller from what the strokes must carry (grainline:
    /// an edit's highlight where it runs along the grain); not a scene key.
    #[serde(skip)]
    #[cfg_attr(feature = "schemars", schemars(skip))]
    pub straddle: Vec<Vec2>,
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
            min_length: None,
            overtravel: None,
            exclusion_radius: None,
            end_run: 1.0,
            fill_gaps: true,
            seeds: Vec::new(),
            straddle: Vec::new(),
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

    /// The minimum length in force (see the field): `min_length`, else `2 · width`.
    pub fn min_length(&self) -> f64 {
        self.min_length.unwrap_or(2.0 * self.width)
    }

    /// The run-out past chart edges in force: `overtravel`, else `width`.
    pub fn overtravel(&self) -> f64 {
        self.overtravel.unwrap_or(self.width)
    }

    /// Reject NaN and out-of-range values with a clear error.
    pub fn validate(&self) -> Result<()> {
        positive("placement.width", self.width)?;
        // At most budget::MAX_LEAD_LENGTH (written out: budget uses this file).
        if self.width > 1e6 {
            return Err(ToolpathError::InvalidOption {
                name: "placement.width",
                value: self.width,
                reason: "must be in (0, 1e6] scene units (budget::MAX_LEAD_LENGTH)",
            });
        }
        in_range("placement.overlap", self.overlap, 0.0, 1.0, "must be in [0, 1)")?;
        positive("placement.test_ratio", self.test_ratio)?;
        if self.test_ratio > 1.0 {
            return Err(ToolpathError::InvalidOption {
                name: "placement.test_ratio",
                value: self.test_ratio,
                reason: "must be in (0, 1]",
            });
        }
        if let Some(l) = self.min_length {
            non_negative("placement.min_length", l)?;
        }
        if let Some(l) = self.overtravel {
            non_negative("placement.overtravel", l)?;
        }
        if let Some(r) = self.exclusion_radius {
            non_negative("placement.exclusion_radius", r)?;
        }
        non_negative("placement.end_run", self.end_run)?;
        for (i, s) in self.seeds.iter().enumerate() {
            if !(s[0].is_finite() && s[1].is_finite()) {
                return Err(ToolpathError::NonFinite { what: "placement.seeds", index: i });
            }
        }
        for (i, s) in self.straddle.iter().enumerate() {
            if !(s[0].is_finite() && s[1].is_finite()) {
                return Err(ToolpathError::NonFinite { what: "placement.straddle", index: i });
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
    /// The minimum stroke length used, mm.
    pub min_length: f64,
    /// Accepted strokes that are gap-filling strokes ([`Stroke::fill`]).
    pub fill_strokes: usize,
    /// Seeds that passed the validity tests and were traced.
    pub seeds_traced: usize,
    /// Strokes traced from [`PlacementOptions::straddle`] points (among `strokes`).
    pub straddle_strokes: usize,
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
    let index = StrokeIndex::new(dom, d_test + 0.5 * topts.max_step, opts.spacing);
    let st_lift = index.lifted();
    let own_cell = if index.lifted() {
        3.0 * d_test
    } else {
        3.0 * d_test / typical_stretch(dom, opts.spacing)
    };
    let mut st = State {
        dom,
        tracer: Tracer::new(dom, sing, &topts),
        index,
        strokes: Vec::new(),
        queue: VecDeque::new(),
        d_sep,
        d_test,
        min_length: opts.min_length(),
        overtravel: opts.overtravel(),
        run_outs: RunOuts::new(pitch_of(dom, d_sep, opts.spacing), RUN_OUT_REACH * d_sep),
        end_run: opts.end_run,
        dropped_short: 0,
        seeds_traced: 0,
        own: OwnPoints {
            grid: Grid3::new(crate::spacing::embedding_box(dom, st_lift), own_cell),
            pts: Vec::new(),
            closure: crate::trace::closure_radius(&topts),
        },
    };
    let mut straddle_strokes = 0;
    for &p in &opts.straddle {
        straddle_strokes += st.straddle(p);
    }
    // Their neighbours before any other seed: the sheet is spaced from them.
    st.drain();
    let mut initial: Vec<Vec2> = opts.seeds.clone();
    if initial.is_empty() {
        let b = dom.bbox;
        initial.push([(b[0][0] + b[1][0]) * 0.5, (b[0][1] + b[1][1]) * 0.5]);
    }
    for p in initial {
        if let Some((f, _)) = dom.grid.locate(dom, p) {
            st.try_seed(p, f, SEED_SLACK);
            st.drain();
        }
    }
    // Fallback raster of seeds, row by row, chart by chart (overlapping charts are
    // separate sheets: each raster point is located in its own chart).
    let pitch = d_sep / typical_stretch(dom, opts.spacing);
    for (chart, b) in dom.chart_bbox.iter().enumerate() {
        let chart = chart as u32;
        let nx = (((b[1][0] - b[0][0]) / pitch).ceil() as usize).min(1 << 14) + 1;
        let ny = (((b[1][1] - b[0][1]) / pitch).ceil() as usize).min(1 << 14) + 1;
        let mut hint: Option<u32> = None;
        for j in 0..ny {
            for i in 0..nx {
                let p = [b[0][0] + (i as f64 + 0.5) * pitch, b[0][1] + (j as f64 + 0.5) * pitch];
                // No face's box meets the grid cell of `p`: outside the domain. (Skips the
                // walk, which from a hint far along the row would cross the chart first.)
                if dom.grid.faces_near(p).is_empty() {
                    continue;
                }
                let located = match hint {
                    Some(h) => match walk(dom, h, dom_centroid(dom, h), p) {
                        Walk::Inside { face, .. } => Some(face),
                        Walk::Exit { .. } => dom.grid.locate_in(dom, p, Some(chart)).map(|x| x.0),
                    },
                    None => dom.grid.locate_in(dom, p, Some(chart)).map(|x| x.0),
                };
                let Some(f) = located else { continue };
                hint = Some(f);
                st.try_seed(p, f, SEED_SLACK);
                st.drain();
            }
        }
    }
    let fill_strokes = if opts.fill_gaps { st.fill() } else { 0 };
    Ok(Placement {
        width: opts.width,
        d_sep,
        d_test,
        spacing: opts.spacing,
        exclusion_radius: exclusion,
        dropped_short: st.dropped_short,
        min_length: st.min_length,
        fill_strokes,
        seeds_traced: st.seeds_traced,
        straddle_strokes,
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
    /// [`PlacementOptions::overtravel`].
    overtravel: f64,
    /// The run-outs of the accepted strokes.
    run_outs: RunOuts,
    /// [`PlacementOptions::end_run`].
    end_run: f64,
    dropped_short: usize,
    seeds_traced: usize,
    own: OwnPoints,
}

/// The points of the stroke being traced, for the self-approach test: a stroke stops when
/// it comes within `d_test` of its own points more than `π · d_test` away along it (a
/// spiral, or a loop that does not close exactly), except on the final approach to its
/// start, where the tracer closes the loop. Points are kept in the spacing measure's space
/// (3D with a lift, UV with the query's metric without).
struct OwnPoints {
    grid: Grid3,
    /// Position in the grid's space, UV, arc length.
    pts: Vec<(Vec3, Vec2, f64)>,
    /// The tracer's loop-closure radius.
    closure: f64,
}

impl OwnPoints {
    /// Forget the previous stroke in time proportional to its size.
    fn clear(&mut self) {
        for &(x, _, _) in &self.pts {
            self.grid.clear_at(x);
        }
        self.pts.clear();
    }

    /// Whether `q` (at arc length `arc`) is within `r` (grid radius `r_visit`) of an own
    /// point far along the stroke; then records `q`. Own points within `2r` of the seed that
    /// lie ahead of `q` within `closure` of its track are exempt: the stroke is about to
    /// close.
    fn approaches(&mut self, q: &Probe, lifted: bool, arc: f64, r: f64, r_visit: f64) -> bool {
        let skip = std::f64::consts::PI * r;
        let (pts, closure) = (&self.pts, self.closure);
        // (vector to an own point, heading) → (distance, component along the heading).
        let measure = |x: Vec3, uv: Vec2| -> (f64, Option<f64>) {
            let last = pts.last();
            if lifted {
                // Own points across a UV seam (far in UV, near in 3D: a stroke that went
                // round a closed part and is back at its own start) do not stop it: the
                // stroke ends at the seam as without a lift.
                if q.m.length(sub(uv, q.uv)) > 4.0 * r {
                    return (f64::INFINITY, None);
                }
                let v = sub3(x, q.x);
                let dist = norm3(v);
                let along = last.and_then(|&(lx, _, _)| {
                    let h = sub3(q.x, lx);
                    let lh = norm3(h);
                    (lh > 0.0).then(|| dot3(v, h) / lh)
                });
                (dist, along)
            } else {
                let v = sub(uv, q.uv);
                let dist = q.m.length(v);
                let along = last.and_then(|&(_, luv, _)| {
                    let h = sub(q.uv, luv);
                    let lh = q.m.length(h);
                    (lh > 0.0).then(|| q.m.inner(v, h) / lh)
                });
                (dist, along)
            }
        };
        let mut hit = false;
        self.grid.visit(q.x, r_visit, |i| {
            let (x, uv, s) = pts[i as usize];
            if (s - arc).abs() <= skip {
                return true;
            }
            let (dist, along) = measure(x, uv);
            if dist >= r {
                return true;
            }
            if s.abs() <= 2.0 * r * (1.0 + TIE) {
                if let Some(along) = along {
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
            self.grid.insert(q.x, self.pts.len() as u32);
            self.pts.push((q.x, q.uv, arc));
        }
        hit
    }
}

impl State<'_> {
    /// Trace from `p` (in face `f`) if it lies at least `d_sep · slack` from every stroke
    /// and outside the exclusion zones; accept the stroke if long enough.
    fn try_seed(&mut self, p: Vec2, f: u32, slack: f64) {
        if self.index.within(self.dom, p, f, self.d_sep * slack) {
            return;
        }
        if let Some(s) = self.trace(p, f, false) {
            self.queue.push_back(self.strokes.len());
            self.strokes.push(s);
        }
    }

    /// Trace from a seed already found clear of the strokes; the stroke gets its run-outs
    /// and is inserted into the index unless it is a dab ([`is_dab`]; counted as dropped).
    fn trace(&mut self, p: Vec2, f: u32, fill: bool) -> Option<Stroke> {
        let (dom, d_test) = (self.dom, self.d_test);
        if self.tracer.near_singularity(p, f).is_some() {
            return None;
        }
        let idx = &self.index;
        let own = &mut self.own;
        own.clear();
        let lifted = idx.lifted();
        // Where each half first came within d_test of another stroke (signed arc length):
        // the stroke runs on for up to `end_run · d_test` while it stays `d_test / 2` away,
        // so the wedge beyond its end, between its two neighbours, is brushed too.
        let mut first: [Option<f64>; 2] = [None, None];
        let run = self.end_run * d_test;
        let mut s = self.tracer.trace_both(p, f, |q, fq, arc, vertex| {
            let pr = idx.probe(dom, q, fq);
            let close = idx.within_probe(dom, &pr, fq, d_test) && {
                let half = usize::from(arc < 0.0);
                let at = *first[half].get_or_insert(arc);
                (arc - at).abs() >= run * (1.0 - TIE)
                    || idx.within_probe(dom, &pr, fq, 0.5 * d_test)
            };
            close
                || vertex && {
                    let rv = idx.visit_radius(dom, fq, d_test);
                    own.approaches(&pr, lifted, arc, d_test, rv)
                }
        })?;
        self.seeds_traced += 1;
        if s.uv.len() < 2 {
            self.dropped_short += 1;
            return None;
        }
        let index = &self.index;
        let metric = |g: u32| index.metric(dom, g);
        add_run_outs(dom, &mut s, metric, self.overtravel);
        if is_dab(&s, self.min_length) {
            self.dropped_short += 1;
            return None;
        }
        s.fill = fill;
        self.run_outs.add_stroke(dom, &s, metric);
        self.index.insert(dom, &s);
        Some(s)
    }

    /// Seeds `d_sep / 2` on the surface to either side of `p` across the field (module docs,
    /// "Straddled points"), each traced when it lies `d_sep` from every stroke; returns the
    /// strokes accepted. Their neighbours are seeded later, when the queue is drained.
    fn straddle(&mut self, p: Vec2) -> usize {
        let dom = self.dom;
        let Some((f, bary)) = dom.grid.locate(dom, p) else { return 0 };
        let Some(t) = crate::field::sample(dom, f, bary, None) else { return 0 };
        let n = self.index.metric(dom, f).unit_normal(t);
        let index = &self.index;
        let metric = |g: u32| index.metric(dom, g);
        let sides: Vec<(Vec2, u32)> = [1.0, -1.0]
            .into_iter()
            .filter_map(|side| match march(dom, metric, f, p, scale(n, side), 0.5 * self.d_sep) {
                March::Inside { p: q, face } => Some((q, face)),
                March::Exit { .. } => None,
            })
            .collect();
        let before = self.strokes.len();
        for (q, face) in sides {
            self.try_seed(q, face, SIDE_SLACK);
        }
        self.strokes.len() - before
    }

    /// Seed beside every queued stroke until the queue is empty.
    fn drain(&mut self) {
        while let Some(si) = self.queue.pop_front() {
            for (p, f) in side_seeds(self.dom, &self.strokes[si], &self.index, self.d_sep) {
                self.try_seed(p, f, SIDE_SLACK);
            }
        }
    }

    /// Gap filling (module docs): returns the number of fill strokes accepted.
    fn fill(&mut self) -> usize {
        let (dom, d) = (self.dom, self.d_sep);
        let mut count = 0;
        let n0 = self.strokes.len();
        for si in 0..n0 {
            let cands = candidates(dom, &self.strokes[si], &self.index, d);
            for (p, f, n) in cands {
                for side in [1.0, -1.0] {
                    let dir = scale(n, side);
                    let metric = |g: u32| self.index.metric(dom, g);
                    let at = match march(dom, metric, f, p, dir, d) {
                        March::Inside { p: q, face } => {
                            let nd = self.index.nearest(dom, q, face, d);
                            if nd >= d * SIDE_SLACK || nd <= FILL_MIN * d {
                                continue;
                            }
                            0.5 * (d + nd)
                        }
                        March::Exit { travelled, .. } => {
                            if travelled <= 0.5 * d * (1.0 + FILL_MIN) {
                                continue;
                            }
                            0.5 * (travelled + 0.5 * d)
                        }
                    };
                    let March::Inside { p: q, face } = march(dom, metric, f, p, dir, at) else {
                        continue;
                    };
                    let clear = 0.5 * d * (1.0 + FILL_MIN);
                    if self.index.within(dom, q, face, clear)
                        || self.run_outs.distance(dom.chart[face as usize], q) <= clear
                    {
                        continue;
                    }
                    // Around a singularity the gap is the exclusion zone, left on purpose.
                    let ex = self.tracer.opts.exclusion_radius;
                    if self.tracer.near_singularity_within(q, face, ex + d).is_some() {
                        continue;
                    }
                    if let Some(s) = self.trace(q, face, true) {
                        self.strokes.push(s);
                        count += 1;
                    }
                }
            }
        }
        count
    }
}

/// A seed counts as `d_sep` away when at least `d_sep · SEED_SLACK` away (round-off).
const SEED_SLACK: f64 = 1.0 - 1e-6;

/// Side seeds are marched `d_sep` on the surface; the index measures the distance back to
/// the stroke from 3D chords and normals (eq. S1), which agrees to about 1e-4 relative, so
/// side seeds get this looser test.
const SIDE_SLACK: f64 = 1.0 - 1e-3;

/// Relative margin of comparisons between lengths summed along a stroke and a threshold that
/// can be an exact multiple of them: far above the rounding of the sums (10⁻¹⁵ relative per
/// step), so a part in inches and the same part in millimetres take the same branch.
const TIE: f64 = 1e-9;

/// Gap filling ignores uncovered bands narrower than this fraction of `d_sep`.
const FILL_MIN: f64 = 0.1;

/// Run-outs are found by [`RunOuts::distance`] within this multiple of `d_sep`.
const RUN_OUT_REACH: f64 = 0.5 * (1.0 + FILL_MIN);

/// UV pitch of about `d_sep` on the part.
fn pitch_of(dom: &Domain, d_sep: f64, spacing: Spacing) -> f64 {
    d_sep / typical_stretch(dom, spacing)
}

/// Whether `s` is a dab, too short to keep (eq. D1): a stroke that starts or ends on the metal
/// must brush `min_length` on the part; one that enters and leaves the part over its edge
/// (run-outs at both ends: no plunge or lift-off mark on the metal) must brush `min_length`
/// in all, run-outs included, and lie on the part for half of it.
fn is_dab(s: &Stroke, min_length: f64) -> bool {
    let through = s.run_out[0].is_some() && s.run_out[1].is_some();
    if through {
        s.brushed_length() < min_length || s.length < 0.5 * min_length
    } else {
        s.length < min_length
    }
}

/// Give the ends of `s` that stopped on the part's real edge ([`Domain::on_part_edge`]: not
/// on a UV seam, where the surface goes on) a run-out of `length` mm on the part: straight on
/// in UV along the end's tangent, `length / |t|_M` UV units for the end face's metric `M` and
/// the unit UV tangent `t`.
fn add_run_outs(dom: &Domain, s: &mut Stroke, metric: impl Fn(u32) -> Metric, length: f64) {
    let n = s.uv.len();
    if length <= 0.0 || n < 2 || s.is_closed() {
        return;
    }
    for k in 0..2 {
        let stop = if k == 0 { s.start } else { s.end };
        let (end, face) =
            if k == 0 { (s.uv[0], s.faces[0]) } else { (s.uv[n - 1], s.faces[n - 1]) };
        if stop != StopReason::Boundary || !dom.on_part_edge(face, end) {
            continue;
        }
        // The first point back from the end that is not on top of it gives the tangent.
        let back = (1..n).map(|i| if k == 0 { s.uv[i] } else { s.uv[n - 1 - i] }).find(|q| {
            let t = sub(end, *q);
            t[0].hypot(t[1]) > 1e-9 * (1.0 + end[0].abs() + end[1].abs())
        });
        let Some(q) = back else { continue };
        let t = sub(end, q);
        let m = metric(face).length(t);
        if m.is_nan() || m <= 0.0 {
            continue;
        }
        s.run_out[k] = Some([end[0] + t[0] * length / m, end[1] + t[1] * length / m]);
        s.overtravel[k] = length;
    }
}

/// The run-outs of the strokes ([`Stroke::run_out`]) as UV segments with the metric of
/// their end face, bucketed on a UV grid for distance queries within a reach (mm).
pub(crate) struct RunOuts {
    cell: f64,
    reach: f64,
    segs: Vec<(Vec2, Vec2, Metric)>,
    buckets: std::collections::HashMap<(u32, i64, i64), Vec<u32>>,
}

impl RunOuts {
    /// Empty, with buckets of `cell` UV units and queries answered within `reach` mm.
    pub(crate) fn new(cell: f64, reach: f64) -> RunOuts {
        RunOuts { cell, reach, segs: Vec::new(), buckets: Default::default() }
    }

    /// The run-outs of all `strokes`.
    pub(crate) fn of(
        dom: &Domain,
        strokes: &[Stroke],
        d_sep: f64,
        spacing: Spacing,
        metric: impl Fn(u32) -> Metric,
    ) -> RunOuts {
        let mut r = RunOuts::new(pitch_of(dom, d_sep, spacing), RUN_OUT_REACH * d_sep);
        for s in strokes {
            r.add_stroke(dom, s, &metric);
        }
        r
    }

    /// Add the run-outs of `s` (each found only from its end's chart: charts may overlap
    /// in UV).
    pub(crate) fn add_stroke(&mut self, dom: &Domain, s: &Stroke, metric: impl Fn(u32) -> Metric) {
        let n = s.uv.len();
        for (k, (end, face)) in
            [(s.uv[0], s.faces[0]), (s.uv[n - 1], s.faces[n - 1])].into_iter().enumerate()
        {
            if let Some(p) = s.run_out[k] {
                self.add(dom.chart[face as usize], end, p, metric(face));
            }
        }
    }

    fn add(&mut self, chart: u32, a: Vec2, b: Vec2, m: Metric) {
        // Smallest eigenvalue of the metric: a UV step of 1 is at least √λ mm on the part.
        let h = 0.5 * (m.e - m.g);
        let lambda = 0.5 * (m.e + m.g) - (h * h + m.f * m.f).sqrt();
        let pad = self.reach / lambda.max(1e-12).sqrt();
        let id = self.segs.len() as u32;
        self.segs.push((a, b, m));
        let c = |x: f64| (x / self.cell).floor() as i64;
        let (i0, i1) = (c(a[0].min(b[0]) - pad), c(a[0].max(b[0]) + pad));
        let (j0, j1) = (c(a[1].min(b[1]) - pad), c(a[1].max(b[1]) + pad));
        if (i1 - i0 + 1).saturating_mul(j1 - j0 + 1) > 1 << 16 {
            return; // a degenerate metric: not found by queries (they only under-count).
        }
        for i in i0..=i1 {
            for j in j0..=j1 {
                self.buckets.entry((chart, i, j)).or_default().push(id);
            }
        }
    }

    /// Distance on the part (the run-out's metric) from `p` on chart `chart` to the nearest
    /// run-out of that chart; exact when it is within the reach, else a distance to some
    /// run-out or infinity.
    pub(crate) fn distance(&self, chart: u32, p: Vec2) -> f64 {
        let c = |x: f64| (x / self.cell).floor() as i64;
        let key = (chart, c(p[0]), c(p[1]));
        let Some(ids) = self.buckets.get(&key) else { return f64::INFINITY };
        let mut best = f64::INFINITY;
        for &id in ids {
            let (a, b, m) = self.segs[id as usize];
            let (ab, ap) = (sub(b, a), sub(p, a));
            let t = (m.inner(ap, ab) / m.inner(ab, ab).max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            best = best.min(m.length(sub(ap, scale(ab, t))));
        }
        best
    }
}

fn dom_centroid(dom: &Domain, f: u32) -> Vec2 {
    let c = dom.corners(f);
    [(c[0][0] + c[1][0] + c[2][0]) / 3.0, (c[0][1] + c[1][1] + c[2][1]) / 3.0]
}

/// Candidate points of `s`: every `d_sep / 2` of arc length (plus both ends of each piece),
/// with their face and the unit surface normal of the stroke there (UV, unit in the
/// spacing metric of the face).
fn candidates(dom: &Domain, s: &Stroke, index: &StrokeIndex, d_sep: f64) -> Vec<(Vec2, u32, Vec2)> {
    let mut out = Vec::new();
    for piece in s.pieces() {
        let pts = &s.uv[piece.clone()];
        if pts.len() < 2 {
            continue;
        }
        // A seed anywhere in a gap grows both ways, so denser candidates only repeat the
        // same tests.
        let mut since = f64::INFINITY;
        for i in 0..pts.len() {
            let k = piece.start + i;
            if i > 0 {
                since += index.metric(dom, s.faces[k]).length(sub(pts[i], pts[i - 1]));
            }
            // The pitch is often a whole number of full tracing steps (a 6 mm brush traced
            // in 1 mm steps): `TIE` decides such ties the same way at any scale (units).
            if since < 0.5 * d_sep * (1.0 - TIE) && i + 1 < pts.len() {
                continue;
            }
            since = 0.0;
            let f = s.faces[k];
            let m: Metric = index.metric(dom, f);
            // The chord between the neighbours, widened past (nearly) repeated points: a
            // stroke can end with its point on the chart edge repeated within rounding, whose
            // chord has no direction (`TIE · d_sep`: a length relative to the part, so the
            // same chord is taken in any unit).
            let chord = |w: usize| {
                let t = sub(pts[(i + w).min(pts.len() - 1)], pts[i.saturating_sub(w)]);
                (t, m.length(t))
            };
            let Some((t, l)) = (1..pts.len()).map(chord).find(|&(_, l)| l > TIE * d_sep) else {
                continue;
            };
            out.push((pts[i], f, m.unit_normal(scale(t, 1.0 / l))));
        }
    }
    out
}

/// Candidate seeds `d_sep` on the surface to the left and right of the candidate points of
/// `s`, located (points beyond the chart edge are left out).
fn side_seeds(dom: &Domain, s: &Stroke, index: &StrokeIndex, d_sep: f64) -> Vec<(Vec2, u32)> {
    let mut out = Vec::new();
    let metric = |g: u32| index.metric(dom, g);
    for (p, f, n) in candidates(dom, s, index, d_sep) {
        for side in [1.0, -1.0] {
            if let March::Inside { p: q, face } = march(dom, metric, f, p, scale(n, side), d_sep) {
                out.push((q, face));
            }
        }
    }
    out
}
