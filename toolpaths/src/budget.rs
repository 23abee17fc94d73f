//! Work budgets: the cost of a job estimated from its options and the domain's area before any
//! stroke is traced, and refused past a documented bound (issue 15, item 12).
//!
//! * **Placement.** Evenly spaced strokes `d_sep` apart cover an area `A` with a total length
//!   `L ≈ A / d_sep` (the strokes are the lanes of a `d_sep`-wide ribbon); each is sampled
//!   every `h = min(trace.max_step, d_test / 2)` (placement caps the step there), so the
//!   samples number `N ≈ A / (d_sep · h)`. Memory and time grow with `N` (about 100 bytes and
//!   a few microseconds per sample); `N` is refused above [`MAX_STROKE_SAMPLES`].
//! * **Ordering.** `plan.order.neighbours` lists that many candidates per stroke end
//!   (`(2n + 1) · 2k` slots): refused above [`MAX_NEIGHBOURS`], and clamped to the stroke
//!   count where it is used.

use crate::error::{Result, ToolpathError};
use crate::place::PlacementOptions;

/// Most stroke samples a placement may be estimated to take (`A / (d_sep · h)`): 2 × 10⁷,
/// about 2 GB and a few minutes. The kettle example (84 732 mm²) at a 0.25 mm brush is about
/// 5.4 × 10⁶.
pub const MAX_STROKE_SAMPLES: f64 = 2e7;

/// Largest `plan.lead_in`, `lead_out`, `ramp_height`, `overtravel` and `contact_depth`: 10⁶
/// scene units (1 km in mm), far beyond any machine's travel. 1e300 used to pass and print a
/// 300-digit coordinate, or fail as a `gcode.safe_z` error.
pub const MAX_LEAD_LENGTH: f64 = 1e6;

/// Largest `plan.order.neighbours` (candidate neighbours per stroke end). Default 10.
pub const MAX_NEIGHBOURS: usize = 256;

/// The placement's work, estimated from the area it covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacementEstimate {
    /// Area covered (mm², in the spacing's metric).
    pub area: f64,
    /// `d_sep = width · (1 − overlap)`.
    pub d_sep: f64,
    /// Sample spacing along a stroke: `min(trace.max_step, d_test / 2)`.
    pub step: f64,
    /// Total stroke length, `area / d_sep`.
    pub stroke_length: f64,
    /// Stroke samples, `area / (d_sep · step)`.
    pub samples: f64,
}

impl PlacementOptions {
    /// The work of placing strokes over `area` (mm² in the spacing's metric); see the
    /// [module docs](crate::budget).
    pub fn estimate(&self, area: f64) -> PlacementEstimate {
        let d_sep = self.d_sep();
        let step = self.trace.max_step.min(0.5 * self.d_test());
        let area = area.max(0.0);
        PlacementEstimate {
            area,
            d_sep,
            step,
            stroke_length: area / d_sep,
            samples: area / (d_sep * step),
        }
    }

    /// Refuses a placement whose estimate ([`Self::estimate`]) exceeds
    /// [`MAX_STROKE_SAMPLES`], naming the option that makes it so large.
    pub fn check_budget(&self, area: f64) -> Result<PlacementEstimate> {
        let e = self.estimate(area);
        if e.samples.is_finite() && e.samples <= MAX_STROKE_SAMPLES {
            return Ok(e);
        }
        // The key to change: the step cap when it alone is below d_test / 2, else test_ratio
        // when below its default it alone makes the step so fine, else overlap when it shrinks
        // d_sep more than half, else the width.
        let default_ratio = PlacementOptions::default().test_ratio;
        let at_default_ratio = PlacementOptions { test_ratio: default_ratio, ..self.clone() };
        let key = if self.trace.max_step < 0.5 * self.d_test() {
            "placement.trace.max_step"
        } else if self.test_ratio < default_ratio
            && at_default_ratio.estimate(area).samples <= MAX_STROKE_SAMPLES
        {
            "placement.test_ratio"
        } else if self.overlap >= 0.5 {
            "placement.overlap"
        } else {
            "placement.width"
        };
        Err(ToolpathError::Budget {
            key,
            message: format!(
                "placing strokes {} mm apart (width {} × (1 − overlap {})) sampled every {} mm \
                 over {} mm² is about {} mm of strokes in {:.2e} samples, beyond the budget of \
                 {:.0e} samples; widen placement.width, lower placement.overlap, raise \
                 placement.test_ratio, or brush a smaller part",
                g(e.d_sep),
                g(self.width),
                g(self.overlap),
                g(e.step),
                g(e.area),
                g(e.stroke_length),
                e.samples,
                MAX_STROKE_SAMPLES
            ),
        })
    }
}

/// Check that `value` is finite, ≥ 0 and at most [`MAX_LEAD_LENGTH`].
pub(crate) fn lead_length(name: &'static str, value: f64) -> Result<f64> {
    if (0.0..=MAX_LEAD_LENGTH).contains(&value) {
        Ok(value)
    } else {
        let reason = "must be in [0, 1e6] scene units (budget::MAX_LEAD_LENGTH)";
        Err(ToolpathError::InvalidOption { name, value, reason })
    }
}

/// Refuses `plan.order.neighbours` above [`MAX_NEIGHBOURS`].
pub(crate) fn check_neighbours(k: usize) -> Result<()> {
    if k > MAX_NEIGHBOURS {
        return Err(ToolpathError::Budget {
            key: "plan.order.neighbours",
            message: format!(
                "{k} candidate neighbours per stroke end would take {} bytes per stroke; at \
                 most {MAX_NEIGHBOURS} (default 10: more only slow the search down)",
                g(16.0 * k as f64)
            ),
        });
    }
    Ok(())
}

/// A number in messages: 4 decimals, exponent form from 10⁷ and below 10⁻³.
fn g(x: f64) -> String {
    if x != 0.0 && (x.abs() >= 1e7 || x.abs() < 1e-3) {
        format!("{x:.3e}")
    } else {
        let s = format!("{:.4}", x);
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s.is_empty() {
            "0".into()
        } else {
            s.into()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn item12_the_estimate_is_area_over_d_sep_and_step() {
        // 100 × 100 mm at a 1 mm brush: 10 000 mm of strokes sampled every 0.25 mm
        // (d_test = 0.5, h = d_test / 2).
        let e = PlacementOptions::new(1.0, 0.0).estimate(1e4);
        assert_eq!((e.d_sep, e.step, e.stroke_length, e.samples), (1.0, 0.25, 1e4, 4e4));
        // Overlap ½: d_sep 0.5, h 0.125.
        let e = PlacementOptions::new(1.0, 0.5).estimate(1e4);
        assert_eq!((e.stroke_length, e.samples), (2e4, 1.6e5));
    }

    #[test]
    fn item12_a_fine_brush_is_refused_naming_the_key() {
        // The kettle's 84 732 mm² at 0.01 mm: 8.5e6 mm of strokes, 3.4e9 samples.
        let err = PlacementOptions::new(0.01, 0.0).check_budget(84_732.0).unwrap_err();
        let ToolpathError::Budget { key, message } = &err else { panic!("{err:?}") };
        assert_eq!(*key, "placement.width");
        assert!(message.contains("3.39e9 samples"), "{message}");
        let err = PlacementOptions::new(4.0, 0.999999).check_budget(84_732.0).unwrap_err();
        assert!(err.to_string().starts_with("placement.overlap: "), "{err}");
        assert!(PlacementOptions::new(0.25, 0.0).check_budget(84_732.0).is_ok());
    }

    #[test]
    fn item12_neighbours_are_bounded() {
        assert!(check_neighbours(MAX_NEIGHBOURS).is_ok());
        let err = check_neighbours(4_294_967_295).unwrap_err().to_string();
        assert!(err.starts_with("plan.order.neighbours: 4294967295 candidate"), "{err}");
    }
}
