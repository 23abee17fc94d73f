//! The job report: counts, lengths, coverage, stop reasons and time per phase.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::coverage::Coverage;
use crate::place::Placement;
use crate::plan::Plan;
use crate::simplify::Segment;
use crate::trace::StopReason;

/// Wall time of one phase.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhaseTime {
    /// Phase name (`placement`, `coverage`, `plan`, `svg`, `gcode`, `json`).
    pub phase: String,
    /// Seconds.
    pub seconds: f64,
}

/// Summary of a job. Times vary run to run; everything else is deterministic.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Strokes placed.
    pub stroke_count: usize,
    /// Passes in the program (strokes minus skipped, plus seam splits in flat mode).
    pub pass_count: usize,
    /// Stroke length on the surface, mm.
    pub pen_down_length_mm: f64,
    /// Machine-space length of cutting moves incl. leads and overtravel, mm.
    pub cut_length_mm: f64,
    /// XY travel from home through all passes, mm.
    pub travel_length_mm: f64,
    /// XY travel between passes only, mm (comparable with vpype's pen-up length).
    pub travel_between_mm: f64,
    /// Travel after the greedy phase only, mm.
    pub travel_greedy_mm: f64,
    /// Stroke spacing and test distance, mm.
    pub d_sep: f64,
    /// `d_test`, mm.
    pub d_test: f64,
    /// Coverage, if measured (the gap map is left out of the report).
    pub coverage: Option<Coverage>,
    /// How many stroke ends stopped for each reason (both ends counted; a closed loop once).
    pub stop_reasons: BTreeMap<String, usize>,
    /// Singularities found.
    pub singularities: usize,
    /// Strokes dropped as shorter than `min_length`.
    pub dropped_short: usize,
    /// The minimum stroke length used, mm (`placement.min_length`, default twice the width).
    #[serde(default)]
    pub min_length: f64,
    /// Gap-filling strokes among `stroke_count` (placed along chart edges and in wide gaps
    /// after the evenly spaced strokes).
    #[serde(default)]
    pub fill_strokes: usize,
    /// Strokes seeded to either side of a point to be left between two strokes
    /// (`PlacementOptions::straddle`; grainline: an edit's highlight where it runs along the
    /// grain); written when non-zero.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub straddle_strokes: usize,
    /// Charts (sheets) of the UV layout, and how many of them received strokes.
    #[serde(default)]
    pub charts: usize,
    /// Charts with at least one stroke.
    #[serde(default)]
    pub charts_with_strokes: usize,
    /// Stroke ends cut back because they turned tighter than `plan.min_turning_radius` near
    /// a boundary or a singularity ([`crate::cut_tight_ends`]); written when non-zero.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub tight_end_cuts: usize,
    /// Strokes dropped after such a cut (less than one brush width left); written when
    /// non-zero.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub tight_end_dropped: usize,
    /// Strokes skipped for tilt (stroke index, tilt in degrees).
    pub skipped_tilt: Vec<(usize, f64)>,
    /// Field evaluations during tracing.
    pub field_evaluations: u64,
    /// Time per phase.
    pub timings: Vec<PhaseTime>,
    /// Estimated run time of the G-code program, seconds: every printed move at its printed
    /// feed, rapids at the rapid rate, plus the spindle snippets' dwell; no acceleration, `M0`
    /// pauses counted as zero ([`crate::CycleTime`]). Set by [`crate::generate`] when G-code
    /// options are given; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cycle_time_s: Option<f64>,
    /// Things the job did that a user should know about although they are not errors (an
    /// empty G-code program written because `gcode.allow_empty` is set).
    #[serde(default)]
    pub warnings: Vec<String>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

fn seg_len(from: [f64; 3], s: &Segment) -> f64 {
    let to = s.end();
    match *s {
        Segment::Line { .. } => crate::geom::norm3(crate::geom::sub3(to, from)),
        Segment::Arc { center, ccw, .. } => crate::geom::helix_length(from, to, center, ccw),
    }
}

impl Report {
    /// Build a report from the pieces of a job.
    pub fn new(
        placement: &Placement,
        plan: &Plan,
        coverage: Option<&Coverage>,
        timings: Vec<PhaseTime>,
    ) -> Report {
        let mut stop_reasons: BTreeMap<String, usize> =
            StopReason::ALL.iter().map(|r| (r.name().to_string(), 0)).collect();
        for s in &placement.strokes {
            *stop_reasons.entry(s.end.name().into()).or_default() += 1;
            if !s.is_closed() {
                *stop_reasons.entry(s.start.name().into()).or_default() += 1;
            }
        }
        let mut cut = 0.0;
        for p in &plan.passes {
            let mut cur = p.start;
            for (_, m) in &p.moves {
                cut += match &plan.rotary {
                    // [x, A°, z]: the contact point's path on the part.
                    Some(f) => crate::rotary::rotary_move_length(cur, m.end(), f.contact_depth),
                    None => seg_len(cur, m),
                };
                cur = m.end();
            }
        }
        Report {
            stroke_count: placement.strokes.len(),
            pass_count: plan.passes.len(),
            pen_down_length_mm: placement.strokes.iter().map(|s| s.length).sum(),
            cut_length_mm: cut,
            travel_length_mm: plan.travel,
            travel_between_mm: plan.travel_between,
            travel_greedy_mm: plan.travel_greedy,
            d_sep: placement.d_sep,
            d_test: placement.d_test,
            coverage: coverage.map(|c| Coverage { map: None, ..c.clone() }),
            stop_reasons,
            singularities: placement.singularities.len(),
            dropped_short: placement.dropped_short,
            min_length: placement.min_length,
            fill_strokes: placement.fill_strokes,
            straddle_strokes: placement.straddle_strokes,
            charts: 0,
            charts_with_strokes: 0,
            tight_end_cuts: 0,
            tight_end_dropped: 0,
            skipped_tilt: plan.skipped_tilt.clone(),
            field_evaluations: placement.field_evaluations,
            timings,
            cycle_time_s: None,
            warnings: Vec::new(),
        }
    }
}
