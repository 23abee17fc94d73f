//! The renderer's scene section `render` (docs/render.md); `material` and `lights` are in
//! [`crate::appearance`] and re-exported here.
//!
//! Every type derives `Serialize`, `Deserialize` and `JsonSchema`, refuses unknown keys, and has a
//! `validate` that range-checks every number with a message naming its key (relative to the
//! section; the scene loader adds the prefix).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::appearance::{check_colour, check_open, check_range, one, yes};
pub use crate::appearance::{
    key_light_index, validate_lights, BrdfSpec, Fresnel, LightSpec, Material,
};
use crate::{Error, Result};

/// How radiance becomes display values (before the sRGB curve).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ToneMap {
    /// Clamp to [0, 1].
    None,
    /// Multiply by 2^exposure, then clamp.
    Exposure,
    /// 2^exposure, then Reinhard x / (1 + x).
    #[default]
    Reinhard,
}

/// The `render` section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RenderSettings {
    /// Image width in pixels (default 1024).
    #[serde(default = "default_width")]
    pub width: u32,
    /// Image height in pixels (default 768).
    #[serde(default = "default_height")]
    pub height: u32,
    /// Supersampling factor s: s × s samples per pixel, box-filtered (default 2).
    #[serde(default = "default_ss")]
    pub supersample: u32,
    /// Tone mapping (default `reinhard`).
    #[serde(default)]
    pub tone_map: ToneMap,
    /// Exposure in stops for `exposure` and `reinhard` (default 0).
    #[serde(default)]
    pub exposure: f64,
    /// Background colour, sRGB in [0, 1] (default dark grey).
    #[serde(default = "default_background")]
    pub background: [f64; 3],
    /// The PNG file name, as written by the caller (default `render.png`).
    #[serde(default = "default_output")]
    pub output: String,
    /// A linear radiance PFM file name, or null for none (default null).
    #[serde(default)]
    pub linear: Option<String>,
    /// Which passes run.
    #[serde(default)]
    pub effects: Effects,
}

fn default_width() -> u32 {
    1024
}
fn default_height() -> u32 {
    768
}
fn default_ss() -> u32 {
    2
}
fn default_background() -> [f64; 3] {
    [0.12, 0.12, 0.13]
}
fn default_output() -> String {
    "render.png".into()
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: default_width(),
            height: default_height(),
            supersample: default_ss(),
            tone_map: ToneMap::default(),
            exposure: 0.0,
            background: default_background(),
            output: default_output(),
            linear: None,
            effects: Effects::default(),
        }
    }
}

/// Largest number of samples (width × height × s²) one render may hold.
pub const MAX_SAMPLES: u64 = 1 << 26;

impl RenderSettings {
    /// Range-checks every setting.
    pub fn validate(&self) -> Result<()> {
        check_range("width", f64::from(self.width), 1.0, 16384.0)?;
        check_range("height", f64::from(self.height), 1.0, 16384.0)?;
        check_range("supersample", f64::from(self.supersample), 1.0, 8.0)?;
        let n = u64::from(self.width) * u64::from(self.height) * u64::from(self.supersample).pow(2);
        if n > MAX_SAMPLES {
            return Err(Error::setting(
                "supersample",
                format!("width × height × supersample² = {n} exceeds {MAX_SAMPLES}"),
            ));
        }
        let bytes = self.memory_estimate();
        let (per_sample, per_pixel) = self.memory_per_sample_and_pixel();
        let budget = crate::limits::MAX_RENDER_BYTES;
        if bytes > budget {
            let gib = |b: u64| format!("{:.2} GiB", b as f64 / f64::from(1u32 << 30));
            return Err(Error::setting(
                "",
                format!(
                    "width × height × supersample² = {} × {} × {}² = {n} samples would hold \
                     about {} ({per_sample} bytes per sample and {per_pixel} per pixel with these \
                     effects), beyond the budget of {}; lower render.width, render.height or \
                     render.supersample, or drop an effect (lic, highlight_curves, as_brushed)",
                    self.width,
                    self.height,
                    self.supersample,
                    gib(bytes),
                    gib(budget)
                ),
            ));
        }
        check_range("exposure", self.exposure, -40.0, 40.0)?;
        check_colour("background", &self.background, 1.0)?;
        if self.output.is_empty() {
            return Err(Error::setting("output", "must name a file"));
        }
        if self.linear.as_deref() == Some("") {
            return Err(Error::setting("linear", "must name a file or be null"));
        }
        self.effects.validate()
    }
}

impl RenderSettings {
    /// Bytes the render is estimated to hold at once, counted from the buffers it allocates.
    /// Per supersample: 16 (visibility), 12 (radiance), 16 per image half (overlay layer),
    /// 12 for the as-brushed radiance and 12 more for its difference (48 for the two
    /// highlights' buffers in `highlights` mode, which shades once), 32 for LIC
    /// (directions, cells, values), 16 for highlight curves (g and u), 8 for the coverage
    /// resolve when supersampled. Per output pixel and half: 28 (resolved radiance and
    /// layer), 3 (8-bit image), 3 (PNG), 12 with a linear output; 4 more for LIC.
    pub fn memory_estimate(&self) -> u64 {
        let (per_sample, per_pixel) = self.memory_per_sample_and_pixel();
        let s = u64::from(self.supersample);
        let pixels = u64::from(self.width) * u64::from(self.height);
        let samples = pixels * s * s;
        samples.saturating_mul(per_sample).saturating_add(pixels.saturating_mul(per_pixel))
    }

    /// Bytes per supersample and per output pixel ([`Self::memory_estimate`]).
    pub fn memory_per_sample_and_pixel(&self) -> (u64, u64) {
        let fx = &self.effects;
        let s = u64::from(self.supersample);
        let halves: u64 = match &fx.as_brushed {
            Some(a) if a.mode == AsBrushedMode::SideBySide => 2,
            _ => 1,
        };
        let mut per_sample = 16 + 12 + 16 * halves;
        if let Some(a) = &fx.as_brushed {
            per_sample += match a.mode {
                AsBrushedMode::SideBySide => 12,
                AsBrushedMode::Difference => 24,
                // Two g-and-u buffers (16 bytes) and two distance buffers (8), no second
                // shading.
                AsBrushedMode::Highlights => 48,
            };
        }
        if fx.lic.is_some() {
            per_sample += 32;
        }
        if fx.highlight_curves.is_some() {
            per_sample += 16;
        }
        if s > 1 {
            per_sample += 8;
        }
        let mut per_pixel = halves * (28 + 3 + 3 + if self.linear.is_some() { 12 } else { 0 });
        if fx.lic.is_some() {
            per_pixel += 4;
        }
        (per_sample, per_pixel)
    }
}

/// The passes to run, each off unless listed (shading is on by default).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Effects {
    /// Shade with the material and the lights (default true); false gives a grey clay image.
    #[serde(default = "yes")]
    pub shading: bool,
    /// Cast shadows from directional, point and environment lights (default false).
    #[serde(default)]
    pub shadows: bool,
    /// Use environment lights (default true when one is listed).
    #[serde(default = "yes")]
    pub environment: bool,
    /// Line integral convolution of the highlight tangent ℓ.
    #[serde(default)]
    pub lic: Option<LicSettings>,
    /// Curves hᵀu = 0 of chosen lights.
    #[serde(default)]
    pub highlight_curves: Option<HighlightCurveSettings>,
    /// Markers where hᵀn exceeds a threshold.
    #[serde(default)]
    pub critical_points: Option<CriticalSettings>,
    /// Brush supports and target tangents of the edits.
    #[serde(default)]
    pub edits: Option<EditOverlaySettings>,
    /// The given 3D stroke polylines.
    #[serde(default)]
    pub strokes: Option<StrokeSettings>,
    /// The as-brushed grain next to, or differenced with, the designed grain.
    #[serde(default)]
    pub as_brushed: Option<AsBrushedSettings>,
    /// The coverage gap map.
    #[serde(default)]
    pub gap: Option<GapSettings>,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            shading: true,
            shadows: false,
            environment: true,
            lic: None,
            highlight_curves: None,
            critical_points: None,
            edits: None,
            strokes: None,
            as_brushed: None,
            gap: None,
        }
    }
}

impl Effects {
    /// Range-checks every member.
    pub fn validate(&self) -> Result<()> {
        if let Some(l) = &self.lic {
            check_open("effects.lic.length_px", l.length_px, 0.0, 200.0)?;
            check_range("effects.lic.strength", l.strength, 0.0, 1.0)?;
        }
        if let Some(h) = &self.highlight_curves {
            check_open("effects.highlight_curves.width_px", h.width_px, 0.0, 50.0)?;
            check_light_list("effects.highlight_curves.lights", &h.lights)?;
        }
        if let Some(c) = &self.critical_points {
            check_range("effects.critical_points.threshold", c.threshold, -1.0, 1.0)?;
            check_light_list("effects.critical_points.lights", &c.lights)?;
        }
        if let Some(e) = &self.edits {
            check_open("effects.edits.arrow_px", e.arrow_px, 0.0, 1000.0)?;
        }
        if let Some(s) = &self.strokes {
            check_open("effects.strokes.width_px", s.width_px, 0.0, 50.0)?;
        }
        if let Some(a) = &self.as_brushed {
            check_open("effects.as_brushed.gain", a.gain, 0.0, 1e6)?;
            check_open("effects.as_brushed.departure_px", a.departure_px, 0.0, 1000.0)?;
            check_open("effects.as_brushed.width_px", a.width_px, 0.0, 50.0)?;
        }
        if let Some(g) = &self.gap {
            check_open("effects.gap.max", g.max, 0.0, 1e12)?;
        }
        Ok(())
    }
}

/// Refuses an effect's list of light indices longer than [`crate::limits::MAX_LIGHTS`] (the
/// most lights a scene may have): each entry is a pass over every sample, so 10⁴ entries
/// kept a render busy for seconds.
fn check_light_list(key: &str, lights: &[usize]) -> Result<()> {
    let max = crate::limits::MAX_LIGHTS;
    if lights.len() > max {
        return Err(Error::setting(
            key,
            format!("lists {} lights, more than the {max} a scene may have", lights.len()),
        ));
    }
    Ok(())
}

/// LIC settings (Cabral & Leedom 1993).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LicSettings {
    /// Half length of the box kernel along the streamline, output pixels (default 12).
    #[serde(default = "default_lic_len")]
    pub length_px: f64,
    /// How much the LIC texture modulates the image, in [0, 1] (default 0.6).
    #[serde(default = "default_lic_strength")]
    pub strength: f64,
    /// Seed of the white noise (default 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
}

fn default_lic_len() -> f64 {
    12.0
}
fn default_lic_strength() -> f64 {
    0.6
}
fn default_seed() -> u64 {
    1
}

/// Highlight-curve settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HighlightCurveSettings {
    /// Indices into `lights` (directional or point); empty = the key light (default empty).
    #[serde(default)]
    pub lights: Vec<usize>,
    /// Line width in output pixels (default 1.5).
    #[serde(default = "default_line_width")]
    pub width_px: f64,
}

fn default_line_width() -> f64 {
    1.5
}

/// Critical-point settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CriticalSettings {
    /// hᵀn above which a point is critical (default 0.9995, the paper's).
    #[serde(default = "default_critical")]
    pub threshold: f64,
    /// Indices into `lights`; empty = the key light (default empty).
    #[serde(default)]
    pub lights: Vec<usize>,
}

fn default_critical() -> f64 {
    crate::highlight::critical::DEFAULT_CRITICAL_THRESHOLD
}

/// Edit-overlay settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EditOverlaySettings {
    /// Length of a target-tangent arrow, output pixels (default 24).
    #[serde(default = "default_arrow")]
    pub arrow_px: f64,
}

fn default_arrow() -> f64 {
    24.0
}

/// Stroke-overlay settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StrokeSettings {
    /// Line width, output pixels (default 1).
    #[serde(default = "default_stroke_width")]
    pub width_px: f64,
}

fn default_stroke_width() -> f64 {
    1.0
}

/// How the as-brushed grain is shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum AsBrushedMode {
    /// Designed on the left, as-brushed on the right (the image is twice as wide).
    #[default]
    SideBySide,
    /// |L_designed − L_as_brushed| × gain.
    Difference,
    /// The designed shading with the key highlight of the designed grain (white) and of the
    /// as-brushed grain over it: green where it lies within `departure_px` of the designed
    /// one, red where it departs (issue 47).
    Highlights,
}

/// As-brushed settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AsBrushedSettings {
    /// Side by side or difference (default side by side).
    #[serde(default)]
    pub mode: AsBrushedMode,
    /// Gain of the difference image (default 4).
    #[serde(default = "default_gain")]
    pub gain: f64,
    /// `highlights` mode: an as-brushed highlight farther than this from the designed one, in
    /// output pixels, is drawn as departing (default 2).
    #[serde(default = "default_departure")]
    pub departure_px: f64,
    /// `highlights` mode: line width of the two highlights, output pixels (default 1.5).
    #[serde(default = "default_line_width")]
    pub width_px: f64,
}

fn default_gain() -> f64 {
    4.0
}
fn default_departure() -> f64 {
    2.0
}

/// Coverage-gap settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GapSettings {
    /// Gap value shown fully red (default 1).
    #[serde(default = "one")]
    pub max: f64,
}
