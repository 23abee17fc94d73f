//! Traced strokes and why they stopped.

use serde::{Deserialize, Serialize};

use crate::geom::Vec2;

/// Why one end of a stroke stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// Reached a chart boundary (or a seam, when seams are not crossed).
    Boundary,
    /// Came within the exclusion radius of a singularity, or the field vanished or became
    /// incoherent.
    Singularity,
    /// Returned to its start: the stroke is a closed loop.
    ClosedLoop,
    /// Reached the maximum stroke length (or the step limit).
    MaxLength,
    /// Came within `d_test` of another stroke (even-spacing placement only).
    TooClose,
}

impl StopReason {
    /// All reasons, in report order.
    pub const ALL: [StopReason; 5] = [
        StopReason::Boundary,
        StopReason::Singularity,
        StopReason::ClosedLoop,
        StopReason::MaxLength,
        StopReason::TooClose,
    ];

    /// Snake-case name used in JSON and reports.
    pub fn name(self) -> &'static str {
        match self {
            StopReason::Boundary => "boundary",
            StopReason::Singularity => "singularity",
            StopReason::ClosedLoop => "closed_loop",
            StopReason::MaxLength => "max_length",
            StopReason::TooClose => "too_close",
        }
    }
}

/// One traced stroke: a polyline in UV with its faces and why each end stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct Stroke {
    /// UV points, in tracing order (the heading never reverses along them).
    pub uv: Vec<Vec2>,
    /// Face of each point.
    pub(crate) faces: Vec<u32>,
    /// Indices `i` where the segment `i−1 → i` is a jump across a UV seam (not drawn).
    pub breaks: Vec<usize>,
    /// Why the stroke stopped at its first point.
    pub start: StopReason,
    /// Why the stroke stopped at its last point.
    pub end: StopReason,
    /// Length on the surface, mm (seam jumps excluded).
    pub length: f64,
    /// A gap-filling stroke (placed after the evenly spaced ones to cover the strips along
    /// chart edges and the wider gaps between diverging strokes; see [`crate::place_strokes`]).
    pub fill: bool,
    /// Where the brush's centre runs to past each end (first, last), in UV: a straight run
    /// along the end's tangent, `PlacementOptions::overtravel` long on the part (measured
    /// with the end face's metric), at ends that stopped on the part's real edge (a chart
    /// boundary that is not a UV seam). The brush runs past the edge there so the whole edge
    /// beside the stroke is brushed; only the part of its swept band inside the part counts as
    /// coverage. The program runs it along the machine path's tangent (`passes.rs`, R1).
    /// `None` at other ends (inside the part, at a singularity, on a seam, closed loops).
    pub run_out: [Option<Vec2>; 2],
    /// Length of each run-out on the part, mm (0 without one).
    pub overtravel: [f64; 2],
}

impl Stroke {
    /// Length the brush runs at cutting feed: the stroke plus its run-outs, mm.
    pub fn brushed_length(&self) -> f64 {
        self.length + self.overtravel[0] + self.overtravel[1]
    }

    /// The UV polyline the brush's centre follows: the run-out points (when present) before
    /// the first and after the last point.
    pub fn brushed_uv(&self) -> Vec<Vec2> {
        let mut out = Vec::with_capacity(self.uv.len() + 2);
        out.extend(self.run_out[0]);
        out.extend_from_slice(&self.uv);
        out.extend(self.run_out[1]);
        out
    }

    /// Whether the stroke is a closed loop.
    pub fn is_closed(&self) -> bool {
        self.end == StopReason::ClosedLoop
    }

    /// The drawable pieces (split at seam jumps) as index ranges.
    pub fn pieces(&self) -> Vec<std::ops::Range<usize>> {
        let mut out = Vec::new();
        let mut s = 0;
        for &b in &self.breaks {
            out.push(s..b);
            s = b;
        }
        out.push(s..self.uv.len());
        out
    }
}

/// A traced half streamline (one direction from the seed).
pub(crate) struct Half {
    pub uv: Vec<Vec2>,
    pub faces: Vec<u32>,
    pub breaks: Vec<usize>,
    pub stop: StopReason,
    pub length: f64,
}

/// Join a backward half (reversed) and a forward half sharing their first point.
pub(crate) fn join(back: Half, fwd: Half) -> Stroke {
    let nb = back.uv.len();
    let mut uv: Vec<Vec2> = back.uv.iter().rev().copied().collect();
    let mut faces: Vec<u32> = back.faces.iter().rev().copied().collect();
    let mut breaks: Vec<usize> = back.breaks.iter().rev().map(|&j| nb - j).collect();
    uv.extend_from_slice(&fwd.uv[1..]);
    faces.extend_from_slice(&fwd.faces[1..]);
    breaks.extend(fwd.breaks.iter().map(|&j| j + nb - 1));
    Stroke {
        uv,
        faces,
        breaks,
        start: back.stop,
        end: fwd.stop,
        length: back.length + fwd.length,
        fill: false,
        run_out: [None; 2],
        overtravel: [0.0; 2],
    }
}
