//! The brush that carries an edit (issue 47, item 2; docs/math.md §10, "A brush too wide"):
//! when an edit lands as designed but not as brushed, the run traces the strokes again with
//! narrower brushes and reports the widest one tried with which it lands.
//!
//! A brush of width w leaves each point the grain of the stroke whose band holds it, so where
//! the designed highlight runs along the grain the as-brushed highlight can stand up to half a
//! band away from it, and every distance of the measure scales with w (math.md §10). The first
//! width tried is therefore the scaled one,
//!
//! ```text
//! w₁ = w · min(0.10 r / p95_b, 0.05 r / median_b, 1) · 0.9
//! ```
//!
//! (p95_b and median_b the as-brushed figures, in r; the goals 0.10 r and, as a proxy for 90 %
//! within 0.05 r, the median halved), each later one [`NEXT_WIDTH_FACTOR`] of the last, at most
//! [`MAX_TRIES`] widths and none below [`MIN_WIDTH_FACTOR`] w. Each try traces the strokes,
//! rebuilds the grain and measures the edit as the run did, and writes nothing; a width whose
//! strokes the work budget refuses ends the search (`grainline_toolpaths::budget`).

use serde::Serialize;

use super::trace::{trace, TraceInput};
use crate::fidelity::{BrushedEditFidelity, EditFidelity, GOAL_P95};
use crate::scene::toolpaths::ToolpathSection;
use crate::uvfield::AsBrushed;
use crate::Result;

/// Widths tried at most per edit.
pub const MAX_TRIES: usize = 3;
/// Each width tried after the first is this share of the last.
pub const NEXT_WIDTH_FACTOR: f64 = 0.7;
/// No width below this share of the scene's brush is tried.
pub const MIN_WIDTH_FACTOR: f64 = 0.125;

/// The brush width that carries one edit, as found by tracing again.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CarryingWidth {
    /// Position of the edit in the `edits` list.
    pub index: usize,
    /// The tool's name.
    pub tool: String,
    /// The widths traced and measured, widest first (scene units).
    pub tried: Vec<f64>,
    /// The widest width tried with which the edit lands as brushed; absent when none did.
    pub width: Option<f64>,
    /// The edit measured as brushed at `width` (or at the narrowest width tried, when none
    /// carried it).
    pub as_brushed: EditFidelity,
    /// Singular triangles the strokes of that width add in the support.
    pub singular_added: i64,
}

/// For every edit of `measured` that lands as designed but not as brushed, traces the strokes
/// again with narrower brushes (module docs) and measures each with `measure` (the as-brushed
/// fidelity of the run's edits on a rebuilt grain). `section` is the section the run traced
/// with.
pub fn carrying_widths(
    input: &TraceInput,
    section: &ToolpathSection,
    measured: &[BrushedEditFidelity],
    measure: impl Fn(&AsBrushed) -> Result<Vec<BrushedEditFidelity>>,
) -> Result<Vec<CarryingWidth>> {
    let width = section.placement.width;
    let mut out = Vec::new();
    for f in measured.iter().filter(|f| f.designed.landed && !f.as_brushed.landed) {
        let mut next = first_width(width, &f.as_brushed);
        let mut found = CarryingWidth {
            index: f.index,
            tool: f.tool.clone(),
            tried: Vec::new(),
            width: None,
            as_brushed: f.as_brushed.clone(),
            singular_added: f.singular_added,
        };
        while found.tried.len() < MAX_TRIES && next >= MIN_WIDTH_FACTOR * width {
            crate::cancel::checkpoint("brush width")?;
            let Some(g) = measure_at(input, section, next, f.index, &measure)? else { break };
            found.tried.push(next);
            found.as_brushed = g.as_brushed;
            found.singular_added = g.singular_added;
            if found.as_brushed.landed {
                found.width = Some(next);
                break;
            }
            next *= NEXT_WIDTH_FACTOR;
        }
        out.push(found);
    }
    Ok(out)
}

/// The first width tried (module docs).
fn first_width(width: f64, b: &EditFidelity) -> f64 {
    let tolerance = crate::fidelity::FidelityOptions::default().tolerance;
    let ratio = |goal: f64, x: f64| if x > goal { goal / x } else { 1.0 };
    let s = ratio(GOAL_P95, b.p95).min(ratio(tolerance, 2.0 * b.median));
    let s = if s.is_finite() { s } else { 1.0 };
    width * 0.9 * s.clamp(MIN_WIDTH_FACTOR, 1.0)
}

/// Edit `index` measured on the grain rebuilt from strokes of brush `width`, the rest of the
/// section unchanged and no file asked for.
fn measure_at(
    input: &TraceInput,
    section: &ToolpathSection,
    width: f64,
    index: usize,
    measure: &impl Fn(&AsBrushed) -> Result<Vec<BrushedEditFidelity>>,
) -> Result<Option<BrushedEditFidelity>> {
    let mut s = section.clone();
    s.placement.width = width;
    s.svg = None;
    s.gcode = None;
    s.strokes_json = None;
    s.coverage = None;
    let again =
        TraceInput { toolpaths: Some(&s), keep_map: false, keep_field_mesh: true, ..*input };
    // A narrower brush that the work budget refuses (more strokes) ends the search; the run
    // goes on with what it found.
    let t = match trace(&again) {
        Ok(t) => t,
        Err(e @ crate::Error::Cancelled { .. }) => return Err(e),
        Err(_) => return Ok(None),
    };
    let Some(b) = t.as_brushed(&again)? else { return Ok(None) };
    Ok(measure(&b)?.into_iter().find(|g| g.index == index))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn figures(p95: f64, median: f64) -> EditFidelity {
        EditFidelity {
            index: 0,
            tool: "curve".into(),
            radius: 1.0,
            samples: 10,
            within: 0.5,
            p95,
            median,
            singular_before: 0,
            singular_after: 0,
            critical_points: 0,
            singular_forced_before: 0,
            singular_forced_after: 0,
            landed: false,
            off_part: 0,
            note: None,
        }
    }

    #[test]
    fn the_first_width_scales_with_the_worse_figure() {
        // p95 twice the goal: half the width, less a tenth.
        assert!((first_width(2.0, &figures(0.2, 0.01)) - 0.9).abs() < 1e-12);
        // The median at 0.05 r (twice it over the tolerance): half the width too.
        assert!((first_width(2.0, &figures(0.08, 0.05)) - 0.9).abs() < 1e-12);
        // Never below the floor, never NaN.
        assert!((first_width(2.0, &figures(100.0, 0.0)) - 0.9 * 0.25).abs() < 1e-12);
        assert!((first_width(2.0, &figures(f64::NAN, f64::NAN)) - 1.8).abs() < 1e-12);
    }
}
