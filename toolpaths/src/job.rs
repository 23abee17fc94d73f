//! One call for the whole job: place, measure coverage, plan, and write the requested
//! outputs, timing each phase.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::coverage::{coverage, Coverage, CoverageOptions};
use crate::error::Result;
use crate::gcode::{write_gcode_timed, GcodeOptions};
use crate::geom::LengthUnit;
use crate::json::strokes_json;
use crate::mesh::{Domain, FieldMesh};
use crate::place::{place_strokes, Placement, PlacementOptions};
use crate::plan::{plan_toolpath, Plan, PlanOptions};
use crate::report::{PhaseTime, Report};
use crate::svg_out::{write_svg, SvgOptions};

/// Everything a job needs; `None` skips an output.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct JobOptions {
    /// Even-spacing placement (defaults: see [`PlacementOptions`]).
    pub placement: PlacementOptions,
    /// Orientation, ordering, leads, Z mode (defaults: see [`PlanOptions`]).
    pub plan: PlanOptions,
    /// Coverage measurement. Default none (not measured).
    pub coverage: Option<CoverageOptions>,
    /// SVG output. Default none.
    pub svg: Option<SvgOptions>,
    /// G-code output. Default none.
    pub gcode: Option<GcodeOptions>,
    /// Strokes JSON output. Default false.
    pub strokes_json: bool,
}

/// Outputs of [`generate`].
#[derive(Clone, Debug)]
pub struct JobOutput {
    /// The placed strokes.
    pub placement: Placement,
    /// The ordered passes.
    pub plan: Plan,
    /// Coverage (with the gap map), when requested.
    pub coverage: Option<Coverage>,
    /// SVG text.
    pub svg: Option<String>,
    /// G-code text.
    pub gcode: Option<String>,
    /// Strokes JSON text.
    pub strokes_json: Option<String>,
    /// The report.
    pub report: Report,
    /// Each stroke lifted onto the part (3D points, one per UV point), when the field mesh
    /// has a lift; empty otherwise. Seam jumps are not marked.
    pub strokes_3d: Vec<Vec<crate::geom::Vec3>>,
    /// The validated domain the strokes were traced on (for [`crate::check_strokes`]).
    pub domain: std::sync::Arc<Domain>,
}

fn timed<T>(t: &mut Vec<PhaseTime>, phase: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let start = Instant::now();
    let r = f()?;
    t.push(PhaseTime { phase: phase.into(), seconds: start.elapsed().as_secs_f64() });
    Ok(r)
}

impl JobOptions {
    /// Check every option; errors name the key path (`placement.width`, `gcode.feed`, …).
    pub fn validate(&self) -> Result<()> {
        self.placement.validate()?;
        self.plan.validate()?;
        if let Some(c) = &self.coverage {
            c.validate()?;
        }
        if let Some(s) = &self.svg {
            s.validate()?;
        }
        if let Some(g) = &self.gcode {
            g.validate()?;
        }
        Ok(())
    }
}

/// The option keys (from [`JobOptions`]) whose default is a length or a feed, with that
/// default in millimetres (per minute for the feeds); [`JobOptions::default_lengths_in`] turns
/// them into another unit. Every other length option defaults to 0, none or a multiple of the
/// brush width.
pub const LENGTH_DEFAULTS_MM: [(&str, f64); 12] = [
    ("placement.width", 1.0),
    ("placement.trace.tolerance", 1e-3),
    ("placement.trace.max_step", 1.0),
    ("placement.trace.min_step", 1e-6),
    ("placement.trace.max_length", 10_000.0),
    ("placement.trace.exclusion_radius", 1.0),
    ("plan.tolerance", 0.01),
    ("gcode.feed", 1000.0),
    ("gcode.plunge_feed", 300.0),
    ("gcode.safe_z", 5.0),
    ("gcode.clearance", 1.0),
    ("svg.margin", 2.0),
];

impl JobOptions {
    /// Sets every option of [`LENGTH_DEFAULTS_MM`] that is not `given` (by its key path) to its
    /// default as a physical length in `unit`: a scene in inches gets a 1 mm clearance, not
    /// 1 inch. Options the caller gave keep their value (in `unit`). A no-op for millimetres.
    pub fn default_lengths_in(&mut self, unit: LengthUnit, given: &dyn Fn(&str) -> bool) {
        let k = unit.in_mm();
        for (key, mm) in LENGTH_DEFAULTS_MM {
            if given(key) {
                continue;
            }
            let v = mm / k;
            match key {
                "placement.width" => self.placement.width = v,
                "placement.trace.tolerance" => self.placement.trace.tolerance = v,
                "placement.trace.max_step" => self.placement.trace.max_step = v,
                "placement.trace.min_step" => self.placement.trace.min_step = v,
                "placement.trace.max_length" => self.placement.trace.max_length = v,
                "placement.trace.exclusion_radius" => self.placement.trace.exclusion_radius = v,
                "plan.tolerance" => self.plan.tolerance = v,
                _ => {}
            }
            if let Some(g) = &mut self.gcode {
                match key {
                    "gcode.feed" => g.feed = v,
                    "gcode.plunge_feed" => g.plunge_feed = v,
                    "gcode.safe_z" => g.safe_z = v,
                    "gcode.clearance" => g.clearance = v,
                    _ => {}
                }
            }
            if let (Some(s), "svg.margin") = (&mut self.svg, key) {
                s.margin = v;
            }
        }
    }
}

/// Run the whole pipeline on a field mesh. Options are validated before any work.
pub fn generate(mesh: FieldMesh, o: &JobOptions) -> Result<JobOutput> {
    o.validate()?;
    let mut t = Vec::new();
    let dom = timed(&mut t, "domain", || Domain::new(mesh))?;
    let mut placement = timed(&mut t, "placement", || place_strokes(&dom, &o.placement))?;
    let cuts = o
        .plan
        .min_turning_radius
        .map(|r| crate::stroke_checks::cut_tight_ends(&dom, &mut placement, r))
        .unwrap_or_default();
    crate::surface::densify(&dom, &mut placement, o.plan.tolerance);
    let cov = match &o.coverage {
        Some(c) => Some(timed(&mut t, "coverage", || coverage(&dom, &placement, c))?),
        None => None,
    };
    let plan = timed(&mut t, "plan", || plan_toolpath(&dom, &placement, &o.plan))?;
    let svg = match &o.svg {
        Some(s) => Some(timed(&mut t, "svg", || write_svg(&dom, &plan, s))?),
        None => None,
    };
    let (gcode, cycle) = match &o.gcode {
        Some(g) => {
            let (text, time) = timed(&mut t, "gcode", || write_gcode_timed(&plan, g))?;
            (Some(text), Some(time))
        }
        None => (None, None),
    };
    let json = if o.strokes_json {
        Some(timed(&mut t, "json", || strokes_json(&placement, &plan))?)
    } else {
        None
    };
    let mut report = Report::new(&placement, &plan, cov.as_ref(), t);
    report.charts = dom.chart_count();
    report.cycle_time_s = cycle.map(|c| c.total_s);
    report.tight_end_cuts = cuts.cuts;
    report.tight_end_dropped = cuts.dropped;
    let mut with = vec![false; dom.chart_count()];
    for s in &placement.strokes {
        for &f in &s.faces {
            with[dom.chart[f as usize] as usize] = true;
        }
    }
    report.charts_with_strokes = with.iter().filter(|&&w| w).count();
    if gcode.is_some() && plan.passes.is_empty() {
        report.warnings.push(format!(
            "the G-code program has no passes ({} strokes placed, {} skipped for tilt); written \
             because gcode.allow_empty is set",
            placement.strokes.len(),
            plan.skipped_tilt.len()
        ));
    }
    let strokes_3d = if dom.has_lift() {
        placement
            .strokes
            .iter()
            .map(|s| {
                s.uv.iter()
                    .zip(&s.faces)
                    .filter_map(|(p, &f)| {
                        dom.lift(f, crate::locate::barycentric(dom.corners(f), *p))
                    })
                    .collect()
            })
            .collect()
    } else {
        Vec::new()
    };
    Ok(JobOutput {
        placement,
        plan,
        coverage: cov,
        svg,
        gcode,
        strokes_json: json,
        report,
        strokes_3d,
        domain: std::sync::Arc::new(dom),
    })
}
