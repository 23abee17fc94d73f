//! The crate's single error type.
//!
//! User errors (bad input, bad options, a program that would be unsafe to run) are
//! separated from internal errors (a broken invariant). Early stops of algorithms (a
//! streamline hitting a boundary, a stroke skipped for tilt) are *not* errors: they are
//! reported in result structs.

use thiserror::Error;

/// Everything that can go wrong in `grainline-toolpaths`.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ToolpathError {
    /// A numeric option is NaN, infinite, or outside its allowed range.
    #[error("{name}: {reason}, got {}", exact(*value))]
    InvalidOption {
        /// The option's key path from [`crate::JobOptions`] (e.g. `gcode.feed`,
        /// `placement.width`), as in a scene file's `toolpaths` section.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// What the value must satisfy.
        reason: &'static str,
    },
    /// The input mesh or field is malformed.
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    /// A UV triangle has (near) zero area, so barycentric coordinates are undefined.
    #[error("triangle {face} is degenerate in UV (signed area {area:e})")]
    DegenerateTriangle {
        /// Face index.
        face: usize,
        /// Signed UV area.
        area: f64,
    },
    /// A non-finite number (NaN or infinity) in the input.
    #[error("non-finite value in {what} at index {index}")]
    NonFinite {
        /// Which array held it.
        what: &'static str,
        /// Element index.
        index: usize,
    },
    /// The program would move outside the configured machine envelope. Values are the
    /// coordinates as printed (after rounding to `decimals`), in the option's length unit.
    #[error(
        "{axis} = {} {unit} (as printed) leaves the machine envelope [{}, {}] {unit} by {} \
         {unit} ({})",
        short(*.value), short(*.min), short(*.max), short(*.by), at_stroke(*.stroke)
    )]
    OutsideEnvelope {
        /// Axis name (`X`, `Y` or `Z`).
        axis: char,
        /// Offending coordinate.
        value: f64,
        /// Envelope minimum on that axis.
        min: f64,
        /// Envelope maximum on that axis.
        max: f64,
        /// Distance outside the envelope.
        by: f64,
        /// Length unit of the numbers (`mm`, `in`, …).
        unit: &'static str,
        /// Stroke index (in [`crate::Placement::strokes`]) of the pass the move belongs to;
        /// none for travel.
        stroke: Option<usize>,
    },
    /// The program would drive the tool below the Z floor (values as printed).
    #[error(
        "Z = {} {unit} (as printed) goes below the Z floor {} {unit} by {} {unit} ({})",
        short(*.z), short(*.floor), short(*.by), at_stroke(*.stroke)
    )]
    BelowFloor {
        /// Offending Z.
        z: f64,
        /// Configured floor.
        floor: f64,
        /// How far below.
        by: f64,
        /// Length unit of the numbers (`mm`, `in`, …).
        unit: &'static str,
        /// Stroke index of the pass the move belongs to; none for travel.
        stroke: Option<usize>,
    },
    /// A G-code option gives a program that would be unsafe or would not print as asked
    /// (safe Z too close to the part as printed, a feed that prints as zero, a snippet with
    /// a forbidden word, …). `key` is the option's key path (`gcode.safe_z`, …).
    #[error("{key}: {message}")]
    Gcode {
        /// The option's key path from [`crate::JobOptions`].
        key: &'static str,
        /// What is wrong, with the values involved.
        message: String,
    },
    /// Every stroke was left out (e.g. skipped for tilt): the G-code program would have no
    /// passes. Refused unless `gcode.allow_empty` is set.
    #[error(
        "the G-code program would have no passes (no stroke was placed, or every stroke was \
         left out: {skipped_tilt} skipped for tilt); refusing to write an empty program (set \
         `allow_empty: true` in the G-code options to write it anyway)"
    )]
    EmptyProgram {
        /// Strokes skipped for tilt.
        skipped_tilt: usize,
    },
    /// The job's estimated work exceeds a documented budget ([`crate::budget`]); `key` is the
    /// option to change (`placement.width`, `plan.order.neighbours`, …) and the message gives
    /// the estimate and the budget.
    #[error("{key}: {message}")]
    Budget {
        /// The option's key path from [`crate::JobOptions`].
        key: &'static str,
        /// The estimate, the budget and what to change.
        message: String,
    },
    /// In surface-following mode the surface normal tilts too far from the tool axis.
    #[error(
        "stroke {stroke}: surface normal tilts {angle_deg:.2}° from the tool axis, above the \
         limit {limit_deg:.2}° by {by_deg:.2}°"
    )]
    TiltExceeded {
        /// Stroke index in the plan.
        stroke: usize,
        /// Largest tilt on the stroke, degrees.
        angle_deg: f64,
        /// Configured limit, degrees.
        limit_deg: f64,
        /// Excess, degrees.
        by_deg: f64,
    },
    /// A rotary (4-axis) option that cannot be used: an axis that is not one, a part that is
    /// not near a body of revolution for `"auto"`, a dialect without an A axis. `key` is the
    /// option's key path (`plan.z_mode.axis`, `gcode.dialect`, …).
    #[error("{key}: {message}")]
    Rotary {
        /// The option's key path from [`crate::JobOptions`].
        key: &'static str,
        /// What is wrong, with the values involved.
        message: String,
    },
    /// A feature needs data the input does not have (e.g. surface following without a lift).
    #[error("missing input: {0}")]
    MissingInput(&'static str),
    /// Serialization failed (strokes JSON, report).
    #[error("serialization failed: {0}")]
    Serialize(String),
    /// A broken internal invariant; a bug in this crate.
    #[error("internal error: {0}")]
    Internal(String),
}

/// A length for messages: at most 6 decimals, trailing zeros removed (`10`, `0.25`); from
/// 10¹⁵ on in exponent form (`-1e300`, not 300 digits).
pub(crate) fn short(x: f64) -> String {
    if x.abs() >= 1e15 {
        return format!("{x:e}");
    }
    let s = format!("{x:.6}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { &s };
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

fn at_stroke(stroke: Option<usize>) -> String {
    match stroke {
        Some(s) => format!("stroke {s}"),
        None => "travel at safe Z".into(),
    }
}

/// Result alias for this crate.
pub type Result<T> = std::result::Result<T, ToolpathError>;

/// Check that `value` is finite and strictly positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ToolpathError::InvalidOption { name, value, reason: "must be finite and > 0" })
    }
}

/// An option's value as messages print it: the shortest text that reads back as the same
/// `f64`, in exponent form when very small or large (`1e300`, not 300 digits), without a
/// trailing `.0`.
pub(crate) fn exact(x: f64) -> String {
    let s = format!("{x:?}");
    match s.strip_suffix(".0") {
        Some(t) => t.to_string(),
        None => s,
    }
}

/// Check that `value` is finite and ≥ 0.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ToolpathError::InvalidOption { name, value, reason: "must be finite and >= 0" })
    }
}

/// Check that `value` is finite.
pub(crate) fn finite(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ToolpathError::InvalidOption { name, value, reason: "must be finite" })
    }
}

/// Check that `value` lies in `[lo, hi)`; `reason` says so in words (e.g. "must be in [0, 1)").
pub(crate) fn in_range(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    reason: &'static str,
) -> Result<f64> {
    if value.is_finite() && value >= lo && value < hi {
        Ok(value)
    } else {
        Err(ToolpathError::InvalidOption { name, value, reason })
    }
}
