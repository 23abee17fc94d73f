//! G-code export for `grbl`, `linuxcnc` and `plain` (plotter) dialects, with a safety check.
//!
//! Program shape: a comment header naming the job and the units; `G21 G90 G17 G94` (mm,
//! absolute, XY plane, feed per minute); `G64 P<plan.tolerance>` (linuxcnc); `G0 Z<safe>`;
//! spindle/tool on (`M3 S…` or a configured snippet); per pass `G0 X Y` at safe Z,
//! `G1 Z… F<plunge>`, then `G1`/`G2`/`G3` cutting moves at `F<feed>`, then `G0 Z<safe>`;
//! finally tool off (`M5`), and `M2` (`M30` for grbl). The header states the estimated
//! cycle time ([`CycleTime`]), computed from the same printed moves.
//!
//! **Units.** The program is always in millimetres (`G21`). The plan and every length option
//! (`safe_z`, `clearance`, `envelope`, `z_floor`, feeds per minute, the blending tolerance)
//! are in [`GcodeOptions::units`] and are multiplied by its size in mm when printed; the
//! header says so (`units: mm, G21; lengths converted from in x25.4`).
//!
//! Every number is printed with a fixed number of decimals (`-0` normalized to `0`), so
//! output is byte-stable and free of float noise such as `9.999999999998`.
//!
//! **Safety is checked on the program as printed.** The program is first built as the
//! numbers the controller will read (coordinates rounded to `decimals`, arc centres from
//! the printed I/J), then, before anything is written:
//! * travel (`safe_z`, as printed) must clear the highest printed cutting point by at least
//!   `clearance` (> 0), else `gcode.safe_z` is refused with the highest point;
//! * every position the program visits — plunge points, all move ends, arc extremes, the
//!   safe-Z travel and home — must lie in the envelope and above the Z floor (nothing is
//!   clipped; the error says by how much);
//! * every printed feed and spindle speed must be > 0;
//! * `G64 P` must not print as zero;
//! * snippets may hold only spindle, coolant and dwell words (see [`Spindle::Snippet`]);
//! * a program without passes is refused unless `allow_empty` is set.

use std::fmt::Write;

use serde::{Deserialize, Serialize};

use crate::error::{finite, positive, short, Result, ToolpathError};
pub use crate::geom::LengthUnit;
use crate::geom::{Vec2, Vec3};
use crate::plan::Plan;
use crate::rotary::{rotary_move_length, Fixture};
use crate::simplify::Segment;
use crate::snippet::{check_snippet, snippet_dwell};

/// Target controller.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub enum Dialect {
    /// Grbl 1.1 (hobby mills, laser/brush heads): no `G64`, ends with `M30`.
    Grbl,
    /// LinuxCNC: adds `G64 P<tolerance>` path blending, ends with `M2`.
    #[default]
    LinuxCnc,
    /// Plotters: no spindle commands, ends with `M2`.
    Plain,
}

/// Turning the tool on and off.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub enum Spindle {
    /// No spindle commands.
    None,
    /// `M3 S<rpm>` / `M5`.
    Speed(f64),
    /// Configured lines (e.g. a brush motor relay). Each line may hold only the words
    /// `M3`, `M4`, `M5` (spindle), `M7`, `M8`, `M9` (coolant), `S<number>`, `G4 P<number>`
    /// (dwell, seconds) and comments (`( … )` or `; …`, not LinuxCNC's active comments such
    /// as `(MSG, …)` or `(LOGOPEN, …)`); at most one spindle and one coolant word, one `S`
    /// and one dwell per line. Anything else (motion, `M2`, `M30`, offsets, `N` numbers,
    /// parameters) is refused, naming the line and the word.
    Snippet {
        /// Lines emitted to turn the tool on.
        on: String,
        /// Lines emitted to turn it off.
        off: String,
    },
}

/// Axis-aligned machine envelope (in [`GcodeOptions::units`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct Envelope {
    /// Minimum X, Y, Z.
    pub min: Vec3,
    /// Maximum X, Y, Z.
    pub max: Vec3,
}

/// G-code options. Lengths are in [`GcodeOptions::units`] (the plan's unit).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct GcodeOptions {
    /// Dialect. Default linuxcnc.
    pub dialect: Dialect,
    /// Job name for the header comment. Default "grainline".
    pub job: String,
    /// Cutting feed, length units per minute (> 0, and > 0 once printed in mm/min with one
    /// decimal). Default 1000.
    pub feed: f64,
    /// Plunge feed, length units per minute (same rules). Default 300.
    pub plunge_feed: f64,
    /// Rapid (`G0`) rate of the machine in mm/min whatever `units` (> 0 and at least
    /// 0.1 mm/min), for the cycle time only: it is not printed as a feed. Default none:
    /// [`DEFAULT_RAPID_MM_MIN`].
    pub rapid_rate_mm_min: Option<f64>,
    /// Safe Z for travel. As printed, it must clear the highest printed cutting point by at
    /// least `clearance`. Default 5.
    pub safe_z: f64,
    /// Smallest gap between the travel height and the highest cutting point, both as
    /// printed (> 0). Default 1.
    pub clearance: f64,
    /// Tool on/off. Default `M3 S1000`.
    pub spindle: Spindle,
    /// Machine envelope to enforce. Default none.
    pub envelope: Option<Envelope>,
    /// Lowest Z the tool may reach. Default none.
    pub z_floor: Option<f64>,
    /// Decimals of the printed coordinates in mm (1..=6). Default 3.
    pub decimals: usize,
    /// Write a program without passes (every stroke skipped) instead of refusing it; the
    /// job report then carries a warning. Default false.
    pub allow_empty: bool,
    /// Length unit of the plan and of the options above; not a key of the options file
    /// (grainline sets it from the scene's `units`). Default mm.
    #[serde(skip)]
    pub units: LengthUnit,
}

impl Default for GcodeOptions {
    fn default() -> Self {
        GcodeOptions {
            dialect: Dialect::LinuxCnc,
            job: "grainline".into(),
            feed: 1000.0,
            plunge_feed: 300.0,
            rapid_rate_mm_min: None,
            safe_z: 5.0,
            clearance: 1.0,
            spindle: Spindle::Speed(1000.0),
            envelope: None,
            z_floor: None,
            decimals: 3,
            allow_empty: false,
            units: LengthUnit::Mm,
        }
    }
}

/// Decimals of printed feeds (mm/min).
const FEED_DECIMALS: usize = 1;

/// Most decimals `G64 P` is printed with.
const MAX_BLEND_DECIMALS: usize = 6;

impl GcodeOptions {
    /// Reject zero, negative or NaN feeds, feeds and speeds that print as zero, forbidden
    /// snippet words and other bad values.
    pub fn validate(&self) -> Result<()> {
        let (k, u) = (self.units.in_mm(), self.units.as_str());
        for (key, v) in [("gcode.feed", self.feed), ("gcode.plunge_feed", self.plunge_feed)] {
            positive(key, v)?;
            if v * k > MAX_FEED_MM_MIN {
                return Err(ToolpathError::Gcode {
                    key,
                    message: format!(
                        "{} {u}/min is over {} mm/min, faster than any machine moves",
                        short(v),
                        short(MAX_FEED_MM_MIN)
                    ),
                });
            }
            if rounded(v * k, FEED_DECIMALS) <= 0.0 {
                return Err(ToolpathError::Gcode {
                    key,
                    message: format!(
                        "{} {u}/min prints as F{} (feeds are printed in mm/min with {FEED_DECIMALS} \
                         decimal); the smallest printable feed is F0.1 = {} {u}/min",
                        short(v),
                        num(v * k, FEED_DECIMALS),
                        short(0.1 / k)
                    ),
                });
            }
        }
        if let Some(r) = self.rapid_rate_mm_min {
            positive("gcode.rapid_rate_mm_min", r)?;
            // Below 0.1 the rate used to be rounded up to 0.1 in silence.
            if !(MIN_RAPID_MM_MIN..=MAX_FEED_MM_MIN).contains(&r) {
                return Err(ToolpathError::Gcode {
                    key: "gcode.rapid_rate_mm_min",
                    message: format!(
                        "{} mm/min is outside [{MIN_RAPID_MM_MIN}, {}] mm/min (the rate is \
                         taken in mm/min with {FEED_DECIMALS} decimal)",
                        short(r),
                        short(MAX_FEED_MM_MIN)
                    ),
                });
            }
        }
        finite("gcode.safe_z", self.safe_z)?;
        crate::budget::lead_length("gcode.safe_z", self.safe_z.abs())
            .map_err(|_| out_of_reach("gcode.safe_z", self.safe_z))?;
        positive("gcode.clearance", self.clearance)?;
        crate::budget::lead_length("gcode.clearance", self.clearance)?;
        match &self.spindle {
            Spindle::None => {}
            Spindle::Speed(s) => {
                positive("gcode.spindle.speed", *s)?;
                if rounded(*s, 0) <= 0.0 {
                    return Err(ToolpathError::Gcode {
                        key: "gcode.spindle.speed",
                        message: format!(
                            "{} prints as S0 (speeds are printed in whole rpm); use at least 1",
                            short(*s)
                        ),
                    });
                }
            }
            Spindle::Snippet { on, off } => {
                check_snippet("gcode.spindle.snippet.on", on)?;
                check_snippet("gcode.spindle.snippet.off", off)?;
            }
        }
        if !(1..=6).contains(&self.decimals) {
            return Err(ToolpathError::InvalidOption {
                name: "gcode.decimals",
                value: self.decimals as f64,
                reason: "must be between 1 and 6",
            });
        }
        if let Some(e) = self.envelope {
            for k in 0..3 {
                finite("gcode.envelope.min", e.min[k])?;
                finite("gcode.envelope.max", e.max[k])?;
                for (key, v) in [("gcode.envelope.min", e.min[k]), ("gcode.envelope.max", e.max[k])]
                {
                    crate::budget::lead_length(key, v.abs()).map_err(|_| out_of_reach(key, v))?;
                }
                if e.min[k] > e.max[k] {
                    return Err(ToolpathError::InvalidOption {
                        name: "gcode.envelope",
                        value: e.min[k],
                        reason: "min must not exceed max",
                    });
                }
            }
        }
        if let Some(z) = self.z_floor {
            finite("gcode.z_floor", z)?;
            crate::budget::lead_length("gcode.z_floor", z.abs())
                .map_err(|_| out_of_reach("gcode.z_floor", z))?;
        }
        Ok(())
    }
}

/// Fixed-precision number, never `-0.000`.
pub(crate) fn num(x: f64, decimals: usize) -> String {
    let s = format!("{:.*}", decimals, x);
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// `x` as the controller reads it back after printing with `decimals`.
fn rounded(x: f64, decimals: usize) -> f64 {
    num(x, decimals).parse().unwrap_or(x)
}

/// One machine move as printed (mm, rounded to `decimals`).
#[derive(Clone, Copy, Debug)]
enum Move {
    /// `G0` to a point.
    Rapid(Vec3),
    /// `G1` to a point at a feed (mm/min, as printed; in a rotary program the inverse-time
    /// `F`, 1/min, printed with `fdec` decimals); `first` prints the feed word.
    Line { to: Vec3, feed: f64, first: bool, fdec: usize },
    /// `G2`/`G3` to a point around `center` (printed start + printed I/J).
    Arc { to: Vec3, center: Vec2, ij: Vec2, ccw: bool, feed: f64, first: bool },
}

/// The program as the controller reads it.
struct Program {
    /// `G64 P` value (mm, printed) and its decimals; none for grbl and plain.
    blend: Option<(f64, usize)>,
    /// Travel height (printed).
    safe_z: f64,
    /// Per pass: the stroke index and its moves (rapid to XY, plunge, cuts, retract).
    passes: Vec<(usize, Vec<Move>)>,
    /// A rotary program: points are `[X, A°, Z]`, feeds are inverse time (`G93`).
    rotary: bool,
}

/// Points an XY arc reaches at its extremes (axis crossings within the sweep), plus its end.
fn arc_extremes(from: Vec3, to: Vec3, c: Vec2, ccw: bool) -> Vec<Vec3> {
    let r = ((from[0] - c[0]).powi(2) + (from[1] - c[1]).powi(2)).sqrt();
    let a0 = (from[1] - c[1]).atan2(from[0] - c[0]);
    let a1 = (to[1] - c[1]).atan2(to[0] - c[0]);
    let tau = std::f64::consts::TAU;
    let sweep = if ccw { (a1 - a0).rem_euclid(tau) } else { (a0 - a1).rem_euclid(tau) };
    let mut out = vec![to];
    for q in 0..4 {
        let a = q as f64 * std::f64::consts::FRAC_PI_2;
        let off = if ccw { (a - a0).rem_euclid(tau) } else { (a0 - a).rem_euclid(tau) };
        if off <= sweep {
            let z = from[2] + (to[2] - from[2]) * off / sweep.max(1e-300);
            out.push([c[0] + r * a.cos(), c[1] + r * a.sin(), z]);
        }
    }
    out
}

/// The `G64 P` value: `plan.tolerance` in mm, printed with the coordinate decimals or more
/// (up to 6) until it is within 5 % of the tolerance; refused if it prints as zero.
fn blend_tolerance(tolerance: f64, o: &GcodeOptions) -> Result<(f64, usize)> {
    let t = tolerance * o.units.in_mm();
    let mut d = o.decimals;
    while d < MAX_BLEND_DECIMALS && (rounded(t, d) - t).abs() > 0.05 * t {
        d += 1;
    }
    let p = rounded(t, d);
    if p.is_nan() || p <= 0.0 {
        return Err(ToolpathError::Gcode {
            key: "plan.tolerance",
            message: format!(
                "{} {} prints as G64 P0 even with {MAX_BLEND_DECIMALS} decimals (P is in mm); the \
                 smallest printable blending tolerance is 0.000001 mm",
                short(tolerance),
                o.units.as_str()
            ),
        });
    }
    Ok((p, d))
}

/// Build the program as printed.
fn build(plan: &Plan, o: &GcodeOptions) -> Result<Program> {
    if let Some(f) = &plan.rotary {
        return build_rotary(plan, o, f);
    }
    let (k, dp) = (o.units.in_mm(), o.decimals);
    let p = |x: f64| rounded(x * k, dp);
    let p3 = |v: Vec3| [p(v[0]), p(v[1]), p(v[2])];
    let feed = rounded(o.feed * k, FEED_DECIMALS);
    let plunge = rounded(o.plunge_feed * k, FEED_DECIMALS);
    let safe_z = p(o.safe_z);
    let blend = if o.dialect == Dialect::LinuxCnc {
        Some(blend_tolerance(plan.tolerance, o)?)
    } else {
        None
    };
    let mut passes = Vec::with_capacity(plan.passes.len());
    for pass in &plan.passes {
        let start = p3(pass.start);
        if !start.iter().all(|x| x.is_finite()) {
            return Err(ToolpathError::Internal(format!(
                "non-finite coordinate in stroke {}",
                pass.stroke
            )));
        }
        let mut moves = vec![
            Move::Rapid([start[0], start[1], safe_z]),
            Move::Line { to: start, feed: plunge, first: true, fdec: FEED_DECIMALS },
        ];
        let mut cur = start;
        let mut first = true;
        for (_, m) in &pass.moves {
            let to = p3(m.end());
            if !to.iter().all(|x| x.is_finite()) {
                return Err(ToolpathError::Internal(format!(
                    "non-finite coordinate in stroke {}",
                    pass.stroke
                )));
            }
            let mv = match *m {
                Segment::Arc { center, ccw, .. } if (to[0], to[1]) != (cur[0], cur[1]) => {
                    // The centre on the bisector of the printed chord (so both printed ends
                    // are on one circle), nearest to the fitted centre; I/J get one decimal
                    // more than the coordinates.
                    let c = [center[0] * k, center[1] * k];
                    let mid = [(cur[0] + to[0]) / 2.0, (cur[1] + to[1]) / 2.0];
                    let (dx, dy) = (to[0] - cur[0], to[1] - cur[1]);
                    let len = (dx * dx + dy * dy).sqrt();
                    let n = [-dy / len, dx / len];
                    let t = (c[0] - mid[0]) * n[0] + (c[1] - mid[1]) * n[1];
                    let c = [mid[0] + t * n[0], mid[1] + t * n[1]];
                    let ij = [rounded(c[0] - cur[0], dp + 1), rounded(c[1] - cur[1], dp + 1)];
                    let center = [cur[0] + ij[0], cur[1] + ij[1]];
                    Move::Arc { to, center, ij, ccw, feed, first }
                }
                // A line, or an arc whose printed ends coincide in XY (a controller would
                // read that as a full circle): a straight move.
                _ => Move::Line { to, feed, first, fdec: FEED_DECIMALS },
            };
            moves.push(mv);
            first = false;
            cur = to;
        }
        moves.push(Move::Rapid([cur[0], cur[1], safe_z]));
        passes.push((pass.stroke, moves));
    }
    Ok(Program { blend, safe_z, passes, rotary: false })
}

/// The inverse-time `F` (1/min) of a move of `len_mm` at `feed_mm_min`, printed with the
/// fewest decimals (at least one, at most 6) that keep it within 10⁻⁴ of its value.
fn inverse_time(len_mm: f64, feed_mm_min: f64) -> Result<(f64, usize)> {
    let f = feed_mm_min / len_mm;
    let mut d = FEED_DECIMALS;
    while d < MAX_BLEND_DECIMALS && (rounded(f, d) - f).abs() > 1e-4 * f {
        d += 1;
    }
    let p = rounded(f, d);
    if !(p.is_finite() && p > 0.0) {
        return Err(ToolpathError::Gcode {
            key: "gcode.feed",
            message: format!(
                "a move of {} mm at {} mm/min takes {} min: its inverse-time feed F{} prints as 0",
                short(len_mm),
                short(feed_mm_min),
                short(len_mm / feed_mm_min),
                num(f, d)
            ),
        });
    }
    Ok((p, d))
}

/// Build a rotary program as printed: `[X, A°, Z]` (X and Z in mm, A in degrees, both with
/// `decimals`), every feed move with its inverse-time `F` = feed / (the contact point's path
/// length on the part, [`rotary_move_length`]); moves that print as no motion are left out.
fn build_rotary(plan: &Plan, o: &GcodeOptions, f: &Fixture) -> Result<Program> {
    let (k, dp) = (o.units.in_mm(), o.decimals);
    let p3 = |v: Vec3| [rounded(v[0] * k, dp), rounded(v[1], dp), rounded(v[2] * k, dp)];
    let feed = rounded(o.feed * k, FEED_DECIMALS);
    let plunge = rounded(o.plunge_feed * k, FEED_DECIMALS);
    let depth = f.contact_depth * k;
    let safe_z = rounded(o.safe_z * k, dp);
    let blend = if o.dialect == Dialect::LinuxCnc {
        Some(blend_tolerance(plan.tolerance, o)?)
    } else {
        None
    };
    let mut passes = Vec::with_capacity(plan.passes.len());
    for pass in &plan.passes {
        let start = p3(pass.start);
        let ends = pass.moves.iter().map(|(_, m)| p3(m.end()));
        if !std::iter::once(start).chain(ends).flatten().all(f64::is_finite) {
            return Err(ToolpathError::Internal(format!(
                "non-finite coordinate in stroke {}",
                pass.stroke
            )));
        }
        let (fp, fdec) = inverse_time((safe_z - start[2]).abs(), plunge)?;
        let mut moves = vec![
            Move::Rapid([start[0], start[1], safe_z]),
            Move::Line { to: start, feed: fp, first: true, fdec },
        ];
        let mut cur = start;
        for (_, m) in &pass.moves {
            let to = p3(m.end());
            if to == cur {
                continue;
            }
            let (fp, fdec) = inverse_time(rotary_move_length(cur, to, depth), feed)?;
            moves.push(Move::Line { to, feed: fp, first: true, fdec });
            cur = to;
        }
        moves.push(Move::Rapid([cur[0], cur[1], safe_z]));
        passes.push((pass.stroke, moves));
    }
    Ok(Program { blend, safe_z, passes, rotary: true })
}

/// Smallest `gcode.rapid_rate_mm_min`: 0.1 mm/min, the smallest rate printed with one
/// decimal (a smaller one is refused, not rounded up).
pub const MIN_RAPID_MM_MIN: f64 = 0.1;

/// Largest feed, plunge feed and rapid rate: 10⁶ mm/min (1 km/min), beyond any machine.
pub const MAX_FEED_MM_MIN: f64 = 1e6;

/// The error of a coordinate option (`gcode.safe_z`, …) beyond ±[`crate::budget::MAX_LEAD_LENGTH`].
fn out_of_reach(key: &'static str, v: f64) -> ToolpathError {
    ToolpathError::Gcode {
        key,
        message: format!(
            "{} is beyond ±{} scene units (budget::MAX_LEAD_LENGTH), outside any machine's travel",
            short(v),
            short(crate::budget::MAX_LEAD_LENGTH)
        ),
    }
}

/// Rapid rate (mm/min) when [`GcodeOptions::rapid_rate_mm_min`] is not set: a modest hobby or
/// light-industrial machine (5 m/min); set the key to your machine's `G0` rate.
pub const DEFAULT_RAPID_MM_MIN: f64 = 5000.0;

/// How long a program runs, estimated from its moves as printed ([`cycle_time`]).
///
/// Each move takes its length over its rate: `t = 60 · L / F` seconds for `L` in mm and `F`
/// in mm/min. Feed moves (`G1`, and `G2`/`G3` by their helical length) run at their printed
/// `F`, rapids (`G0`, straight lines in XYZ) at the rapid rate. The tool starts at the plan's
/// home at the travel height (the program's first `G0 Z`, from wherever the tool is, is not
/// counted). Acceleration, path blending (`G64`) and the controller's look-ahead are not
/// modelled, so short moves run slower than this on a real machine; the operator's `M0`
/// pauses between sheets count as zero (their number is given).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CycleTime {
    /// Total, seconds: the sum of the four parts below.
    pub total_s: f64,
    /// Cutting moves at the cutting feed (leads, overtravel and the strokes), seconds.
    pub cut_s: f64,
    /// Plunges (`G1 Z` at the plunge feed), seconds.
    pub plunge_s: f64,
    /// Rapids (`G0`: to each pass at the travel height and the retracts), seconds.
    pub rapid_s: f64,
    /// Dwell (`G4 P<s>` in the spindle snippets, each time a snippet runs), seconds.
    pub dwell_s: f64,
    /// Operator pauses (`M0` between sheets), not counted in `total_s`.
    pub pauses: usize,
    /// The rapid rate used, mm/min.
    pub rapid_mm_min: f64,
}

/// The rapid rate in mm/min: the option rounded like a printed feed, or
/// [`DEFAULT_RAPID_MM_MIN`].
fn rapid_mm_min(o: &GcodeOptions) -> f64 {
    o.rapid_rate_mm_min.map_or(DEFAULT_RAPID_MM_MIN, |r| rounded(r, FEED_DECIMALS))
}

/// Passes that start a new sheet (each one an `M0` pause with the spindle stopped).
fn sheet_changes(plan: &Plan) -> usize {
    plan.passes.windows(2).filter(|w| w[0].sheet != w[1].sheet).count()
}

/// The cycle time of a program as printed (see [`CycleTime`]).
fn program_time(plan: &Plan, o: &GcodeOptions, prog: &Program) -> CycleTime {
    let rapid = rapid_mm_min(o);
    let secs = |len: f64, rate: f64| if rate > 0.0 { 60.0 * len / rate } else { 0.0 };
    let mut t = CycleTime { rapid_mm_min: rapid, ..Default::default() };
    let mut cur = home(plan, o, prog);
    // A rotary program's A moves count as the arc they turn at the mean height of the move.
    let dist = |a: Vec3, b: Vec3| {
        if prog.rotary {
            let arc = 0.5 * (a[2] + b[2]) * (b[1] - a[1]).to_radians();
            ((b[0] - a[0]).powi(2) + (b[2] - a[2]).powi(2) + arc * arc).sqrt()
        } else {
            crate::geom::norm3(crate::geom::sub3(b, a))
        }
    };
    for (_, moves) in &prog.passes {
        for (j, m) in moves.iter().enumerate() {
            match *m {
                Move::Rapid(to) => {
                    t.rapid_s += secs(dist(cur, to), rapid);
                    cur = to;
                }
                Move::Line { to, feed, .. } => {
                    // Inverse time (G93): the move takes 1/F minutes.
                    let dt = if prog.rotary {
                        60.0 / feed
                    } else {
                        secs(crate::geom::norm3(crate::geom::sub3(to, cur)), feed)
                    };
                    // The move after the rapid to the pass's start is its plunge.
                    if j == 1 {
                        t.plunge_s += dt;
                    } else {
                        t.cut_s += dt;
                    }
                    cur = to;
                }
                Move::Arc { to, center, ccw, feed, .. } => {
                    t.cut_s += secs(crate::geom::helix_length(cur, to, center, ccw), feed);
                    cur = to;
                }
            }
        }
    }
    t.pauses = sheet_changes(plan);
    if let (Dialect::LinuxCnc | Dialect::Grbl, Spindle::Snippet { on, off }) =
        (o.dialect, &o.spindle)
    {
        // The spindle starts once and after each pause, and stops before each and at the end.
        t.dwell_s = (t.pauses + 1) as f64 * (snippet_dwell(on) + snippet_dwell(off));
    }
    t.total_s = t.cut_s + t.plunge_s + t.rapid_s + t.dwell_s;
    t
}

/// Estimate how long the program [`write_gcode`] writes for `plan` runs (see
/// [`CycleTime`]). The options are validated and the program is built as printed (rounded
/// coordinates, printed feeds and arc centres) but not checked for safety.
pub fn cycle_time(plan: &Plan, o: &GcodeOptions) -> Result<CycleTime> {
    o.validate()?;
    check_dialect(plan, o)?;
    let prog = build(plan, o)?;
    Ok(program_time(plan, o, &prog))
}

/// The plan's home at the travel height, as printed (`[X, A°, Z]` in a rotary program).
fn home(plan: &Plan, o: &GcodeOptions, prog: &Program) -> Vec3 {
    let k = o.units.in_mm();
    let a = if prog.rotary { plan.home[1] } else { plan.home[1] * k };
    [rounded(plan.home[0] * k, o.decimals), rounded(a, o.decimals), prog.safe_z]
}

/// Check the printed program against the envelope, the floor and the clearance.
fn check_program(plan: &Plan, o: &GcodeOptions, prog: &Program) -> Result<()> {
    let k = o.units.in_mm();
    let unit = o.units.as_str();
    // Limits are compared with the printed numbers in mm; a relative 1e-9 absorbs the unit
    // conversion of the limits themselves.
    let eps = |x: f64| 1e-9 * x.abs().max(1.0);
    let check = |q: Vec3, stroke: Option<usize>| -> Result<()> {
        if let Some(floor) = o.z_floor {
            let f = floor * k;
            if q[2] < f - eps(f) {
                return Err(ToolpathError::BelowFloor {
                    z: q[2] / k,
                    floor,
                    by: (f - q[2]) / k,
                    unit,
                    stroke,
                });
            }
        }
        if let Some(e) = o.envelope {
            for (a, axis) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                // A rotary program's second coordinate is A (no Y moves).
                if prog.rotary && a == 1 {
                    continue;
                }
                let (lo, hi, v) = (e.min[a] * k, e.max[a] * k, q[a]);
                if v < lo - eps(lo) || v > hi + eps(hi) {
                    let by = if v < lo { lo - v } else { v - hi };
                    return Err(ToolpathError::OutsideEnvelope {
                        axis,
                        value: v / k,
                        min: e.min[a],
                        max: e.max[a],
                        by: by / k,
                        unit,
                        stroke,
                    });
                }
            }
        }
        Ok(())
    };
    let mut top = f64::NEG_INFINITY;
    for (stroke, moves) in &prog.passes {
        let s = Some(*stroke);
        let mut cur = [f64::NAN; 3];
        for m in moves {
            match *m {
                Move::Rapid(q) => check(q, None)?,
                Move::Line { to, .. } => {
                    check(to, s)?;
                    top = top.max(to[2]);
                }
                Move::Arc { to, center, ccw, .. } => {
                    for q in arc_extremes(cur, to, center, ccw) {
                        check(q, s)?;
                    }
                    top = top.max(to[2]).max(cur[2]);
                }
            }
            cur = match *m {
                Move::Rapid(q) => q,
                Move::Line { to, .. } | Move::Arc { to, .. } => to,
            };
        }
    }
    let c = o.clearance * k;
    if top.is_finite() && prog.safe_z - top < c - eps(c) {
        return Err(ToolpathError::Gcode {
            key: "gcode.safe_z",
            message: format!(
                "{} {unit} prints as Z{} mm, {} mm above the highest cutting point Z{} mm (as \
                 printed; {} {unit}); travel must clear it by the clearance {} {unit}: set \
                 safe_z to at least {} {unit}",
                short(o.safe_z),
                num(prog.safe_z, o.decimals),
                short(prog.safe_z - top),
                num(top, o.decimals),
                short(top / k),
                short(o.clearance),
                short((top + c) / k)
            ),
        });
    }
    check(home(plan, o, prog), None)
}

/// Check the whole program (as printed) against the envelope, the floor, the clearance of
/// the travel height and the printable-number rules; see the module docs.
pub fn check_safety(plan: &Plan, o: &GcodeOptions) -> Result<()> {
    o.validate()?;
    check_dialect(plan, o)?;
    let prog = build(plan, o)?;
    check_program(plan, o, &prog)
}

fn sanitize(s: &str) -> String {
    s.chars().map(|c| if c == '(' || c == ')' || c.is_control() { ' ' } else { c }).collect()
}

/// Write the snippet's non-empty lines, trimmed.
fn snippet(w: &mut String, text: &str) {
    for l in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        let _ = writeln!(w, "{l}");
    }
}

/// Start the spindle (`M3 S…` or the `on` snippet; nothing in the plain dialect).
fn spindle_on(w: &mut String, o: &GcodeOptions) {
    if o.dialect != Dialect::Plain {
        match &o.spindle {
            Spindle::None => {}
            Spindle::Speed(s) => {
                let _ = writeln!(w, "M3 S{}", num(*s, 0));
            }
            Spindle::Snippet { on, .. } => snippet(w, on),
        }
    }
}

/// Stop the spindle (`M5` or the `off` snippet; nothing in the plain dialect).
fn spindle_off(w: &mut String, o: &GcodeOptions) {
    if o.dialect != Dialect::Plain {
        match &o.spindle {
            Spindle::None => {}
            Spindle::Speed(_) => {
                let _ = writeln!(w, "M5");
            }
            Spindle::Snippet { off, .. } => snippet(w, off),
        }
    }
}

/// The program's head: job, dialect, passes, units and sheets as comments, the modal
/// state, path blending and the move to safe Z.
fn write_header(w: &mut String, plan: &Plan, o: &GcodeOptions, prog: &Program, t: &CycleTime) {
    let dialect = match o.dialect {
        Dialect::Grbl => "grbl",
        Dialect::LinuxCnc => "linuxcnc",
        Dialect::Plain => "plain",
    };
    let units = match o.units {
        LengthUnit::Mm => "units: mm, G21".to_string(),
        u => format!("units: mm, G21; lengths converted from {} x{}", u.as_str(), u.in_mm()),
    };
    let _ = writeln!(w, "(grainline-toolpaths job: {})", sanitize(&o.job));
    let _ = writeln!(w, "(dialect: {dialect}; passes: {}; {units})", plan.passes.len());
    let n_sheets = plan.passes.iter().map(|p| p.sheet + 1).max().unwrap_or(1);
    if n_sheets > 1 {
        let _ = writeln!(
            w,
            "(sheets: {n_sheets}, cut in order; the program pauses with M0 between them)"
        );
    }
    let _ = writeln!(
        w,
        "(cycle time: {} s at rapid {} mm/min: cutting {} s, plunges {} s, rapids {} s, dwell {} \
         s; no acceleration, M0 pauses not counted)",
        num(t.total_s, 1),
        short(t.rapid_mm_min),
        num(t.cut_s, 1),
        num(t.plunge_s, 1),
        num(t.rapid_s, 1),
        num(t.dwell_s, 1)
    );
    if let Some(f) = &plan.rotary {
        rotary_header(w, f, o.units.in_mm(), o.decimals);
    }
    let _ = writeln!(w, "G21 G90 G17 {}", if prog.rotary { "G93" } else { "G94" });
    if let Some((p, d)) = prog.blend {
        let _ = writeln!(w, "G64 P{}", num(p, d));
    }
    let _ = writeln!(w, "G0 Z{}", num(prog.safe_z, o.decimals));
}

/// The fixture of a rotary program as header comments: the line
/// `(rotary: point PX,PY,PZ direction DX,DY,DZ zero RX,RY,RZ)` (the point in mm, the unit
/// vectors with 6 decimals; part coordinates) and the convention in words.
fn rotary_header(w: &mut String, f: &Fixture, k: f64, dp: usize) {
    let v =
        |x: Vec3, s: f64, d: usize| x.iter().map(|c| num(c * s, d)).collect::<Vec<_>>().join(",");
    let _ = writeln!(
        w,
        "(rotary: point {} direction {} zero {})",
        v(f.point, k, dp),
        v(f.direction, 1.0, 6),
        v(f.zero, 1.0, 6)
    );
    for line in [
        "(A axis: the part's axis on machine X, X = 0 at the point, Z = distance from the axis)",
        "(A in degrees: positive turns the part counter-clockwise seen from +X towards the origin)",
        "(A = 0 turns zero to +Z; A is unwrapped: run A without WRAPPED_ROTARY)",
        "(feeds in inverse time, G93: each F is 1 / minutes of its move)",
    ] {
        let _ = writeln!(w, "{line}");
    }
}

/// The moves of one pass: the rapid to its start, the plunge, the cut, the retract. In a
/// rotary program the second axis is A and every feed move carries its inverse-time `F`.
fn write_moves(w: &mut String, moves: &[Move], dp: usize, rotary: bool) {
    let n = |x: f64| num(x, dp);
    let ax = if rotary { 'A' } else { 'Y' };
    for (j, m) in moves.iter().enumerate() {
        match *m {
            Move::Rapid(q) if j == 0 => {
                let _ = writeln!(w, "G0 X{} {ax}{}", n(q[0]), n(q[1]));
            }
            Move::Rapid(q) => {
                let _ = writeln!(w, "G0 Z{}", n(q[2]));
            }
            Move::Line { to, feed, fdec, .. } if j == 1 => {
                let _ = writeln!(w, "G1 Z{} F{}", n(to[2]), num(feed, fdec));
            }
            Move::Line { to, feed, first, fdec } => {
                let fw = if first { format!(" F{}", num(feed, fdec)) } else { String::new() };
                let _ = writeln!(w, "G1 X{} {ax}{} Z{}{fw}", n(to[0]), n(to[1]), n(to[2]));
            }
            Move::Arc { to, ij, ccw, feed, first, .. } => {
                let fw =
                    if first { format!(" F{}", num(feed, FEED_DECIMALS)) } else { String::new() };
                let _ = writeln!(
                    w,
                    "{} X{} Y{} Z{} I{} J{}{fw}",
                    if ccw { "G3" } else { "G2" },
                    n(to[0]),
                    n(to[1]),
                    n(to[2]),
                    num(ij[0], dp + 1),
                    num(ij[1], dp + 1)
                );
            }
        }
    }
}

/// A rotary plan needs a dialect with an A axis and inverse time: grbl 1.1 drives X, Y and Z
/// only, so rotary + grbl is refused.
fn check_dialect(plan: &Plan, o: &GcodeOptions) -> Result<()> {
    if plan.rotary.is_some() && o.dialect == Dialect::Grbl {
        return Err(ToolpathError::Rotary {
            key: "gcode.dialect",
            message: "grbl 1.1 drives three axes (X, Y, Z) and has no A axis for a rotary \
                      program; use linuxcnc (A axis, inverse-time G93 feeds)"
                .into(),
        });
    }
    Ok(())
}

/// Write the plan as G-code. Refuses (with an error) programs that break the envelope, the
/// floor or the clearance, snippets with forbidden words, numbers that print as zero, and
/// empty programs (unless `allow_empty`); see the module docs for the program shape.
pub fn write_gcode(plan: &Plan, o: &GcodeOptions) -> Result<String> {
    write_gcode_timed(plan, o).map(|(g, _)| g)
}

/// [`write_gcode`] and the program's [`CycleTime`] (the figure its header states).
pub(crate) fn write_gcode_timed(plan: &Plan, o: &GcodeOptions) -> Result<(String, CycleTime)> {
    o.validate()?;
    check_dialect(plan, o)?;
    if plan.passes.is_empty() && !o.allow_empty {
        return Err(ToolpathError::EmptyProgram { skipped_tilt: plan.skipped_tilt.len() });
    }
    let prog = build(plan, o)?;
    check_program(plan, o, &prog)?;
    let time = program_time(plan, o, &prog);
    let mut g = String::new();
    let w = &mut g;
    write_header(w, plan, o, &prog, &time);
    spindle_on(w, o);
    for (i, (stroke, moves)) in prog.passes.iter().enumerate() {
        // A new sheet (charts overlapping in UV, flat mode): the tool is at safe Z after
        // the previous pass; stop the spindle, pause for the operator to load the next
        // sheet (M0, resumed with cycle start), restart the spindle.
        let sheet = plan.passes.get(i).map_or(0, |p| p.sheet);
        if i > 0 && plan.passes.get(i - 1).is_some_and(|p| p.sheet != sheet) {
            let _ = writeln!(w, "(sheet {sheet}: load sheet {sheet}, then cycle start)");
            spindle_off(w, o);
            let _ = writeln!(w, "M0");
            spindle_on(w, o);
        }
        let _ = writeln!(w, "(pass {i}: stroke {stroke})");
        write_moves(w, moves, o.decimals, prog.rotary);
    }
    if prog.rotary {
        let _ = writeln!(w, "G94");
    }
    spindle_off(w, o);
    let _ = writeln!(w, "{}", if o.dialect == Dialect::Grbl { "M30" } else { "M2" });
    Ok((g, time))
}
