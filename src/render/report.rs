//! The render report: which passes ran and how long they took, counters that show what was and
//! was not computed, and the as-brushed statistics.

use serde::Serialize;

/// One pass that ran.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PassTime {
    /// Pass name (`raster`, `shading`, `lic`, ...).
    pub name: String,
    /// Wall time, milliseconds.
    pub ms: f64,
}

/// Work counters. A zero proves a stage did not run (e.g. `bvh_nodes == 0` without shadows).
#[derive(Clone, Debug, Default, Serialize, PartialEq, Eq)]
pub struct RenderCounters {
    /// Faces given.
    pub triangles_in: u64,
    /// Faces that gave no screen triangle (behind the near plane or off-screen).
    pub triangles_culled: u64,
    /// Faces cut by the near plane.
    pub triangles_clipped: u64,
    /// Screen triangles rasterized (after clipping and off-screen rejection).
    pub screen_triangles: u64,
    /// Samples (width × height × s², times 2 side by side).
    pub samples: u64,
    /// Samples covered by the mesh.
    pub covered_samples: u64,
    /// BRDF evaluations.
    pub brdf_evals: u64,
    /// BVH nodes built (0 unless shadows ran).
    pub bvh_nodes: u64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Environment texels read to build the sample set (0 without an environment pass).
    pub env_texels: u64,
    /// Environment samples per shading point.
    pub env_samples: u64,
    /// White-noise values generated for LIC (0 without LIC).
    pub lic_noise_values: u64,
    /// Streamline steps taken by LIC.
    pub lic_steps: u64,
    /// Samples touched by a highlight curve.
    pub highlight_curve_samples: u64,
    /// Samples marked critical.
    pub critical_samples: u64,
    /// Samples tinted by the gap map.
    pub gap_samples: u64,
    /// Samples tinted by an edit's brush support.
    pub support_samples: u64,
    /// Target-tangent arrows drawn.
    pub target_arrows: u64,
    /// Stroke segments drawn (visible ones).
    pub stroke_segments: u64,
    /// Critical-vertex markers drawn.
    pub critical_markers: u64,
    /// Second (as-brushed) shadings.
    pub as_brushed_shadings: u64,
    /// `as_brushed.mode: "highlights"`: samples on the as-brushed key highlight.
    pub brushed_highlight_samples: u64,
    /// Of those, the samples farther than `departure_px` from the designed key highlight.
    pub departed_highlight_samples: u64,
}

/// Median, 95th percentile and maximum of a set of angles.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct AngleStats {
    /// Values used.
    pub count: usize,
    /// Values skipped (a zero or non-finite vector).
    pub skipped: usize,
    /// Median, degrees.
    pub median_deg: f64,
    /// 95th percentile (nearest rank), degrees.
    pub p95_deg: f64,
    /// Maximum, degrees.
    pub max_deg: f64,
}

impl AngleStats {
    /// Statistics of `values` (degrees), `skipped` counted apart.
    pub fn of(mut values: Vec<f64>, skipped: usize) -> Self {
        values.sort_by(f64::total_cmp);
        let rank = |q: f64| {
            if values.is_empty() {
                0.0
            } else {
                let k = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len());
                values[k - 1]
            }
        };
        AngleStats {
            count: values.len(),
            skipped,
            median_deg: rank(0.5),
            p95_deg: rank(0.95),
            max_deg: values.last().copied().unwrap_or(0.0),
        }
    }
}

/// Designed versus as-brushed, per vertex.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct AsBrushedStats {
    /// Angle between designed and as-brushed u (modulo 180° for k = 2).
    pub u_angle: AngleStats,
    /// Angle between the two ℓ as lines (modulo 180°), when both were given.
    pub ell_angle: Option<AngleStats>,
}

/// What a render did.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct RenderReport {
    /// Output width (doubled side by side).
    pub width: u32,
    /// Output height.
    pub height: u32,
    /// Supersampling factor.
    pub supersample: u32,
    /// The passes that ran, in order.
    pub passes: Vec<PassTime>,
    /// Total wall time, milliseconds.
    pub total_ms: f64,
    /// Work counters.
    pub counters: RenderCounters,
    /// As-brushed statistics, when the pass ran.
    pub as_brushed: Option<AsBrushedStats>,
    /// Things the user should know (an empty image, a skipped light, ...).
    pub warnings: Vec<String>,
}

impl RenderReport {
    /// True if a pass of that name ran.
    pub fn ran(&self, name: &str) -> bool {
        self.passes.iter().any(|p| p.name == name)
    }
}
