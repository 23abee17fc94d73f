//! G-code export for `grbl`, `linuxcnc` and `plain` (plotter) dialects, with a safety check.
//!
//! Program shape: a comment header naming the job; `G21 G90 G17 G94` (mm, absolute, XY
//! plane, feed per minute); `G0 Z<safe>`; spindle/tool on (`M3 S…` or a configured
//! snippet); per pass `G0 X Y` at safe Z, `G1 Z… F<plunge>`, then `G1`/`G2`/`G3` cutting
//! moves at `F<feed>`, then `G0 Z<safe>`; finally tool off (`M5`), and `M2` (`M30` for grbl).
//! Every number is printed with a fixed number of decimals (`-0` normalized to `0`), so
//! output is byte-stable and free of float noise such as `9.999999999998`.
//!
//! Before anything is written, every position the program visits — including arc extremes
//! and the safe-Z travel — is checked against the machine envelope and the Z floor; a
//! violation is an error that says by how much (nothing is clipped).

use std::fmt::Write;

use serde::{Deserialize, Serialize};

use crate::error::{finite, positive, Result, ToolpathError};
use crate::geom::{Vec2, Vec3};
use crate::plan::Plan;
use crate::simplify::Segment;

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
    /// Configured lines (e.g. a brush motor relay).
    Snippet {
        /// Lines emitted to turn the tool on.
        on: String,
        /// Lines emitted to turn it off.
        off: String,
    },
}

/// Axis-aligned machine envelope (mm).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct Envelope {
    /// Minimum X, Y, Z.
    pub min: Vec3,
    /// Maximum X, Y, Z.
    pub max: Vec3,
}

/// G-code options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct GcodeOptions {
    /// Dialect. Default linuxcnc.
    pub dialect: Dialect,
    /// Job name for the header comment. Default "grainline".
    pub job: String,
    /// Cutting feed, mm/min (> 0). Default 1000.
    pub feed: f64,
    /// Plunge feed, mm/min (> 0). Default 300.
    pub plunge_feed: f64,
    /// Safe Z for travel, mm. Default 5.
    pub safe_z: f64,
    /// Tool on/off. Default `M3 S1000`.
    pub spindle: Spindle,
    /// Machine envelope to enforce. Default none.
    pub envelope: Option<Envelope>,
    /// Lowest Z the tool may reach. Default none.
    pub z_floor: Option<f64>,
    /// Decimals for coordinates (1..=6). Default 3.
    pub decimals: usize,
}

impl Default for GcodeOptions {
    fn default() -> Self {
        GcodeOptions {
            dialect: Dialect::LinuxCnc,
            job: "grainline".into(),
            feed: 1000.0,
            plunge_feed: 300.0,
            safe_z: 5.0,
            spindle: Spindle::Speed(1000.0),
            envelope: None,
            z_floor: None,
            decimals: 3,
        }
    }
}

impl GcodeOptions {
    /// Reject zero, negative or NaN feeds and other bad values.
    pub fn validate(&self) -> Result<()> {
        positive("gcode.feed", self.feed)?;
        positive("gcode.plunge_feed", self.plunge_feed)?;
        finite("gcode.safe_z", self.safe_z)?;
        if let Spindle::Speed(s) = self.spindle {
            positive("gcode.spindle.speed", s)?;
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

fn check_point(o: &GcodeOptions, p: Vec3, stroke: Option<usize>) -> Result<()> {
    if !p.iter().all(|x| x.is_finite()) {
        return Err(ToolpathError::Internal(format!("non-finite coordinate in stroke {stroke:?}")));
    }
    if let Some(floor) = o.z_floor {
        if p[2] < floor - 1e-9 {
            return Err(ToolpathError::BelowFloor { z: p[2], floor, by: floor - p[2], stroke });
        }
    }
    if let Some(e) = o.envelope {
        for (k, axis) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            let (lo, hi, v) = (e.min[k], e.max[k], p[k]);
            if v < lo - 1e-9 || v > hi + 1e-9 {
                let by = if v < lo { lo - v } else { v - hi };
                return Err(ToolpathError::OutsideEnvelope {
                    axis,
                    value: v,
                    min: lo,
                    max: hi,
                    by,
                    stroke,
                });
            }
        }
    }
    Ok(())
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

/// Check the whole program against the envelope and floor.
pub fn check_safety(plan: &Plan, o: &GcodeOptions) -> Result<()> {
    o.validate()?;
    let mut top = f64::NEG_INFINITY;
    for (i, pass) in plan.passes.iter().enumerate() {
        let s = Some(i);
        check_point(o, [pass.start[0], pass.start[1], o.safe_z], s)?;
        check_point(o, pass.start, s)?;
        top = top.max(pass.start[2]);
        let mut cur = pass.start;
        for (_, m) in &pass.moves {
            match *m {
                Segment::Line { to } => check_point(o, to, s)?,
                Segment::Arc { to, center, ccw } => {
                    for p in arc_extremes(cur, to, center, ccw) {
                        check_point(o, p, s)?;
                    }
                }
            }
            top = top.max(m.end()[2]);
            cur = m.end();
        }
    }
    if top > o.safe_z {
        return Err(ToolpathError::InvalidOption {
            name: "gcode.safe_z",
            value: o.safe_z,
            reason: "is below the highest point of a pass; travel would collide",
        });
    }
    check_point(o, [plan.home[0], plan.home[1], o.safe_z], None)
}

fn sanitize(s: &str) -> String {
    s.chars().map(|c| if c == '(' || c == ')' || c.is_control() { ' ' } else { c }).collect()
}

/// Write the plan as G-code. Refuses (with an error) programs that break the envelope or
/// the floor; see the module docs for the program shape.
pub fn write_gcode(plan: &Plan, o: &GcodeOptions) -> Result<String> {
    check_safety(plan, o)?;
    let dp = o.decimals;
    let n = |x: f64| num(x, dp);
    let f = |x: f64| num(x, 1);
    let mut g = String::new();
    let dialect = match o.dialect {
        Dialect::Grbl => "grbl",
        Dialect::LinuxCnc => "linuxcnc",
        Dialect::Plain => "plain",
    };
    let w = &mut g;
    let _ = writeln!(w, "(grainline-toolpaths job: {})", sanitize(&o.job));
    let _ = writeln!(w, "(dialect: {dialect}; passes: {}; units: mm)", plan.passes.len());
    let _ = writeln!(w, "G21 G90 G17 G94");
    if o.dialect == Dialect::LinuxCnc {
        let _ = writeln!(w, "G64 P{}", n(10f64.powi(-(dp as i32)) * 10.0));
    }
    let _ = writeln!(w, "G0 Z{}", n(o.safe_z));
    if o.dialect != Dialect::Plain {
        match &o.spindle {
            Spindle::None => {}
            Spindle::Speed(s) => {
                let _ = writeln!(w, "M3 S{}", num(*s, 0));
            }
            Spindle::Snippet { on, .. } => {
                let _ = writeln!(w, "{}", on.trim_end());
            }
        }
    }
    for (i, pass) in plan.passes.iter().enumerate() {
        let _ = writeln!(w, "(pass {i}: stroke {})", pass.stroke);
        let _ = writeln!(w, "G0 X{} Y{}", n(pass.start[0]), n(pass.start[1]));
        let _ = writeln!(w, "G1 Z{} F{}", n(pass.start[2]), f(o.plunge_feed));
        let mut cur = pass.start;
        let mut first = true;
        for (_, m) in &pass.moves {
            let feed = if first { format!(" F{}", f(o.feed)) } else { String::new() };
            match *m {
                Segment::Line { to } => {
                    let _ = writeln!(w, "G1 X{} Y{} Z{}{feed}", n(to[0]), n(to[1]), n(to[2]));
                }
                Segment::Arc { to, center, ccw } => {
                    let _ = writeln!(
                        w,
                        "{} X{} Y{} Z{} I{} J{}{feed}",
                        if ccw { "G3" } else { "G2" },
                        n(to[0]),
                        n(to[1]),
                        n(to[2]),
                        num(center[0] - rounded(cur[0], dp), dp + 1),
                        num(center[1] - rounded(cur[1], dp), dp + 1)
                    );
                }
            }
            first = false;
            cur = m.end();
        }
        let _ = writeln!(w, "G0 Z{}", n(o.safe_z));
    }
    if o.dialect != Dialect::Plain {
        match &o.spindle {
            Spindle::None => {}
            Spindle::Speed(_) => {
                let _ = writeln!(w, "M5");
            }
            Spindle::Snippet { off, .. } => {
                let _ = writeln!(w, "{}", off.trim_end());
            }
        }
    }
    let _ = writeln!(w, "{}", if o.dialect == Dialect::Grbl { "M30" } else { "M2" });
    Ok(g)
}
