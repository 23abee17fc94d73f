//! The scene's `toolpaths` section ([`ToolpathSection`]): the files to write, the UV field and
//! layout options, and the toolpaths crate's placement, plan, coverage, SVG and G-code options
//! in the scene's units; and the toolpaths crate's errors named by their key in the section
//! ([`toolpath_error`]).

use grainline_toolpaths::{
    CoverageOptions, GcodeOptions, JobOptions, JobOutput, LengthUnit, PlacementOptions,
    PlanOptions, SvgOptions, ToolpathError,
};
use serde::{Deserialize, Serialize};

use crate::mesh::Units;
use crate::uvfield::UvFieldOptions;
use crate::{Error, Result};

/// The scene's `toolpaths` section: which files to write and how to place, plan and export
/// the strokes. Output paths are as written in the scene; the caller resolves them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ToolpathSection {
    /// SVG of the strokes on the UV layout; none by default.
    pub svg: Option<String>,
    /// G-code program; none by default.
    pub gcode: Option<String>,
    /// Strokes JSON; none by default.
    pub strokes_json: Option<String>,
    /// From the grain field to the UV field mesh (defaults: see [`UvFieldOptions`]).
    pub uv_field: UvFieldOptions,
    /// The UV layout made for a part without one (defaults: see
    /// [`LayoutOptions`](crate::layout::LayoutOptions)).
    pub layout: crate::layout::LayoutOptions,
    /// Even-spacing placement (brush width, overlap, …). Lengths in scene units on the part.
    pub placement: PlacementOptions,
    /// Orientation, ordering, leads, Z.
    pub plan: PlanOptions,
    /// Coverage measurement; none (not measured) by default.
    pub coverage: Option<CoverageOptions>,
    /// SVG options, used when `svg` is set.
    pub svg_options: SvgOptions,
    /// G-code options, used when `gcode` is set.
    pub gcode_options: GcodeOptions,
    /// Whether a run measures each bend, expand and curve edit on the grain rebuilt from the
    /// strokes (the run report's `as_brushed.fidelity`, FIELD.json's
    /// `meta.diagnostics.fidelity`); default `auto`.
    pub as_brushed_fidelity: AsBrushedFidelity,
    /// Whether the placement leaves each bend, expand and curve edit's designed highlight
    /// between two strokes where it runs along the grain (docs/math.md §10, "Strokes that
    /// carry the edit"); default `off`.
    pub carry_edits: CarryEdits,
}

/// `toolpaths.as_brushed_fidelity`: whether a run measures its edits as brushed.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum AsBrushedFidelity {
    /// Whenever a run traces strokes and has a bend, expand or curve edit: the grain is
    /// rebuilt from the strokes and each edit measured on it (docs/math.md §10, "As brushed").
    #[default]
    Auto,
    /// Never (the grain is still rebuilt when a render effect or the export asks for it).
    Off,
}

/// `toolpaths.carry_edits`: whether the placement straddles the edits' highlights.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum CarryEdits {
    /// Evenly spaced strokes from the part's centre; the edits do not steer the placement.
    #[default]
    Off,
    /// Where a bend, expand or curve edit's designed key highlight runs within 30° of the
    /// grain, a stroke is placed half a spacing to either side of it before any other (most
    /// nearly parallel first), so the highlight lies between two strokes. On the corpus it
    /// moves the curves' as-brushed figures by −4 to +7 points (docs/benchmarks.md, "As
    /// brushed"): not the default.
    Straddle,
}

/// The section's key path of a toolpaths crate key: the crate names `svg.*`/`gcode.*` after
/// `JobOptions`; this section calls them `svg_options`/`gcode_options`.
fn section_key(name: &str) -> String {
    if let Some(rest) = name.strip_prefix("svg.") {
        format!("svg_options.{rest}")
    } else if let Some(rest) = name.strip_prefix("gcode.") {
        format!("gcode_options.{rest}")
    } else {
        name.to_string()
    }
}

/// A toolpaths error as a grainline error: option errors keep their key path, relative to
/// the `toolpaths` section (`gcode_options.safe_z`; [`crate::scene::prefix`] adds
/// `toolpaths.`).
pub fn toolpath_error(e: ToolpathError) -> Error {
    match e {
        ToolpathError::InvalidOption { name, value, reason } => Error::setting(
            section_key(name),
            format!("{reason}, got {}", crate::error::fmt_num(value)),
        ),
        ToolpathError::Gcode { key, message } => Error::setting(section_key(key), message),
        ToolpathError::Budget { key, message } => Error::setting(section_key(key), message),
        ToolpathError::Rotary { key, message } => Error::setting(section_key(key), message),
        e @ ToolpathError::OutsideEnvelope { .. } => {
            Error::setting("gcode_options.envelope", e.to_string())
        }
        e @ ToolpathError::BelowFloor { .. } => {
            Error::setting("gcode_options.z_floor", e.to_string())
        }
        e @ ToolpathError::EmptyProgram { .. } => Error::setting(
            "gcode",
            e.to_string().replace(
                "`allow_empty: true` in the G-code options",
                "`gcode_options.allow_empty: true`",
            ),
        ),
        e @ ToolpathError::TiltExceeded { .. } => {
            Error::setting("plan.z_mode.max_tilt_deg", e.to_string())
        }
        e => Error::Numerical { stage: "toolpaths", message: e.to_string() },
    }
}

/// The toolpaths crate's length unit for a scene unit.
pub fn length_unit(units: Units) -> LengthUnit {
    match units {
        Units::Mm => LengthUnit::Mm,
        Units::Cm => LengthUnit::Cm,
        Units::M => LengthUnit::M,
        Units::In => LengthUnit::In,
    }
}

impl ToolpathSection {
    /// The toolpaths crate's job options for this section, in a scene of `units` (every
    /// length of the section is in the scene's units; the G-code is printed in mm).
    pub fn job_options(&self, units: Units) -> JobOptions {
        let mut gcode = self.gcode_options.clone();
        gcode.units = length_unit(units);
        JobOptions {
            placement: self.placement.clone(),
            plan: self.plan.clone(),
            coverage: self.coverage.clone(),
            svg: self.svg.as_ref().map(|_| self.svg_options.clone()),
            gcode: self.gcode.as_ref().map(|_| gcode),
            strokes_json: self.strokes_json.is_some(),
        }
    }

    /// Sets every length option of the section that the scene file does not give (`given`
    /// answers for a key path relative to the section: `placement.width`,
    /// `gcode_options.clearance`, …) to its default as a physical length in `units`
    /// ([`grainline_toolpaths::LENGTH_DEFAULTS_MM`]: a 1 mm clearance, a 1000 mm/min feed,
    /// whatever the units). Values the file gives keep their meaning, in the scene's units.
    pub fn default_lengths_in(&mut self, units: Units, given: &dyn Fn(&str) -> bool) {
        let mut all = self.job_options(units);
        all.svg = Some(self.svg_options.clone());
        all.gcode = Some(self.gcode_options.clone());
        all.default_lengths_in(length_unit(units), &|key| given(&section_key(key)));
        self.placement = all.placement;
        self.plan = all.plan;
        if let Some(s) = all.svg {
            self.svg_options = s;
        }
        if let Some(mut g) = all.gcode {
            g.units = self.gcode_options.units;
            self.gcode_options = g;
        }
    }

    /// The section a scene without one traces with: the defaults, lengths in `units` (see
    /// [`Self::default_lengths_in`]).
    pub fn default_in(units: Units) -> ToolpathSection {
        let mut s = ToolpathSection::default();
        s.default_lengths_in(units, &|_| false);
        s
    }

    /// Sets the job report's `cycle_time_s` when no G-code program was written (the toolpaths
    /// crate times only the program it writes): the plan timed with this section's
    /// `gcode_options`, so the report always says how long the program would run. A plan the
    /// options cannot print (a refused blending tolerance) leaves it unset.
    pub fn time_job(&self, job: &mut JobOutput, units: Units) {
        if job.report.cycle_time_s.is_none() {
            let mut gcode = self.gcode_options.clone();
            gcode.units = length_unit(units);
            job.report.cycle_time_s =
                grainline_toolpaths::cycle_time(&job.plan, &gcode).ok().map(|t| t.total_s);
        }
    }

    /// Range-checks every setting for a scene in millimetres; see [`Self::validate_in`].
    pub fn validate(&self) -> Result<()> {
        self.validate_in(Units::Mm)
    }

    /// Range-checks every setting for a scene in `units` (whether a feed prints as zero
    /// depends on them); keys are relative to the section (`placement.width`,
    /// `gcode_options.feed`, `svg`, …).
    pub fn validate_in(&self, units: Units) -> Result<()> {
        for (key, v) in
            [("svg", &self.svg), ("gcode", &self.gcode), ("strokes_json", &self.strokes_json)]
        {
            if v.as_deref().is_some_and(|s| s.trim().is_empty()) {
                return Err(Error::setting(key, "must be a file name, got an empty string"));
            }
        }
        self.uv_field.validate().map_err(|e| match e {
            Error::Setting { key, message } => Error::setting(format!("uv_field.{key}"), message),
            e => e,
        })?;
        self.layout.validate().map_err(|e| match e {
            Error::Setting { key, message } => Error::setting(format!("layout.{key}"), message),
            e => e,
        })?;
        let mut all = self.job_options(units);
        all.svg = Some(self.svg_options.clone());
        let mut gcode = self.gcode_options.clone();
        gcode.units = length_unit(units);
        all.gcode = Some(gcode);
        all.validate().map_err(toolpath_error)
    }
}
