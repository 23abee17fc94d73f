//! Options of the toolpath planner ([`PlanOptions`]: Z mode, tilt policy, tolerance, leads,
//! overtravel and ordering), read by `plan.rs` and by `passes.rs`.

use serde::{Deserialize, Serialize};

use crate::budget::lead_length;
use crate::error::{finite, positive, Result, ToolpathError};
use crate::geom::Vec2;
use crate::order::{Direction, OrderOptions};
use crate::rotary::AxisSpec;

/// What to do with a stroke whose surface tilts beyond the limit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub enum TiltPolicy {
    /// Refuse the whole job with [`ToolpathError::TiltExceeded`].
    #[default]
    Error,
    /// Leave the stroke out and list it in [`Plan::skipped_tilt`](crate::Plan::skipped_tilt).
    Skip,
}

/// How Z is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "mode")]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub enum ZMode {
    /// A flat sheet at height `surface_z`; XY = UV.
    Flat {
        /// Z of the sheet's top surface, mm.
        surface_z: f64,
    },
    /// Follow the 3D lift (needs positions in the input).
    SurfaceFollowing {
        /// Largest allowed angle between the surface normal and +Z, degrees.
        max_tilt_deg: f64,
        /// What to do beyond it.
        on_tilt: TiltPolicy,
    },
    /// A turned part on a rotary (A) axis along machine X, the tool along machine Z at the
    /// surface's distance from the axis (4-axis; needs positions in the input). See
    /// [`crate::rotary`] for the mapping and the sign of A.
    Rotary {
        /// The part's axis: `"auto"` (found from a body of revolution, the default) or
        /// `{"point", "direction", "zero"}` in part coordinates.
        #[serde(default)]
        axis: AxisSpec,
        /// Largest allowed angle between the surface normal and the radial direction (the
        /// tool axis once the point is turned to the top), degrees.
        max_tilt_deg: f64,
        /// What to do beyond it. Default `error`.
        #[serde(default)]
        on_tilt: TiltPolicy,
    },
}

/// How the charts are grouped into sheets (set-ups) in flat mode.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub enum Sheets {
    /// One sheet, except where charts overlap in UV (greedy colouring of the overlap graph).
    #[default]
    Overlap,
    /// Every chart that holds strokes is a sheet of its own, in chart order: each face of a
    /// part cut into patches (a CAD part's flat faces) brushed as the shop fixtures it.
    Chart,
}

/// Options of [`plan_toolpath`](crate::plan_toolpath). Lengths in mm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct PlanOptions {
    /// Global orientation. Default `along`.
    pub direction: Direction,
    /// Reference direction (UV) for orienting line-field strokes. Default +U.
    pub reference: Vec2,
    /// Simplification tolerance, mm (RDP and arc fitting). Default 0.01.
    pub tolerance: f64,
    /// Fit G2/G3 arcs (flat mode, or surface mode where Z is constant). Default false.
    pub arcs: bool,
    /// How far below the surface the brush presses, mm (≥ 0). Default 0.
    pub contact_depth: f64,
    /// Flat or surface-following Z. Default flat at Z = 0.
    pub z_mode: ZMode,
    /// Lead-in length, mm. Default 0.
    pub lead_in: f64,
    /// Lead-out length, mm. Default 0.
    pub lead_out: f64,
    /// Height of the lead ramps above the cutting Z at their free ends, mm. Default 0.
    pub ramp_height: f64,
    /// Extension past the part edge at strokes that end on a chart boundary, mm, along the
    /// machine path's tangent (Z included); the stroke's own run-out
    /// (`PlacementOptions::overtravel`) when that is longer. Default 0.
    pub overtravel: f64,
    /// Ordering options.
    pub order: OrderOptions,
    /// How charts are grouped into sheets in flat mode. Default `overlap`; surface following
    /// is always one sheet.
    pub sheets: Sheets,
    /// The tool's minimum turning radius, mm (> 0; default none): stroke ends at a boundary or
    /// a singularity's exclusion zone that turn tighter within two brush widths of the end are
    /// cut back before coverage and planning ([`crate::cut_tight_ends`]; the report counts
    /// the cuts). grainline sets it from `solver.constraints.turning_radius`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_turning_radius: Option<f64>,
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            direction: Direction::Along,
            reference: [1.0, 0.0],
            tolerance: 0.01,
            arcs: false,
            contact_depth: 0.0,
            z_mode: ZMode::Flat { surface_z: 0.0 },
            lead_in: 0.0,
            lead_out: 0.0,
            ramp_height: 0.0,
            overtravel: 0.0,
            order: OrderOptions::default(),
            sheets: Sheets::Overlap,
            min_turning_radius: None,
        }
    }
}

impl PlanOptions {
    /// Reject NaN and out-of-range values.
    pub fn validate(&self) -> Result<()> {
        finite("plan.reference[0]", self.reference[0])?;
        finite("plan.reference[1]", self.reference[1])?;
        if self.reference == [0.0, 0.0] {
            return Err(ToolpathError::InvalidOption {
                name: "plan.reference",
                value: 0.0,
                reason: "must be a non-zero vector",
            });
        }
        positive("plan.tolerance", self.tolerance)?;
        if let Some(r) = self.min_turning_radius {
            positive("plan.min_turning_radius", r)?;
        }
        lead_length("plan.contact_depth", self.contact_depth)?;
        lead_length("plan.lead_in", self.lead_in)?;
        lead_length("plan.lead_out", self.lead_out)?;
        lead_length("plan.ramp_height", self.ramp_height)?;
        lead_length("plan.overtravel", self.overtravel)?;
        finite("plan.order.home[0]", self.order.home[0])?;
        finite("plan.order.home[1]", self.order.home[1])?;
        crate::budget::check_neighbours(self.order.neighbours)?;
        match self.z_mode {
            ZMode::Flat { surface_z } => {
                finite("plan.z_mode.surface_z", surface_z)?;
            }
            ZMode::SurfaceFollowing { max_tilt_deg, .. } | ZMode::Rotary { max_tilt_deg, .. } => {
                crate::error::in_range(
                    "plan.z_mode.max_tilt_deg",
                    max_tilt_deg,
                    0.0,
                    180.0,
                    "must be in [0, 180) degrees",
                )?;
            }
        }
        if let ZMode::Rotary { axis, .. } = self.z_mode {
            if self.arcs {
                return Err(ToolpathError::Rotary {
                    key: "plan.arcs",
                    message: "G2/G3 arcs lie in the XY plane and a rotary program has no Y: set \
                              arcs to false (a linear X A Z move already follows a helix on the \
                              part)"
                        .into(),
                });
            }
            if let AxisSpec::Given(a) = axis {
                crate::rotary::check_axis(&a)?;
            }
        }
        Ok(())
    }
}
