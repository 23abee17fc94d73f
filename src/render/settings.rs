//! The renderer's scene sections: `material`, `lights` and `render` (docs/render.md).
//!
//! Every type derives `Serialize`, `Deserialize` and `JsonSchema`, refuses unknown keys, and has a
//! `validate` that range-checks every number with a message naming its key (relative to the
//! section; the scene loader adds the prefix).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::{Error, Result};

fn one() -> f64 {
    1.0
}
fn white() -> [f64; 3] {
    [1.0; 3]
}
fn yes() -> bool {
    true
}

/// Checks a finite number in `[lo, hi]`.
pub(crate) fn check_range(key: &str, x: f64, lo: f64, hi: f64) -> Result<()> {
    if x.is_finite() && x >= lo && x <= hi {
        Ok(())
    } else {
        Err(Error::setting(
            key,
            format!("must be a number in [{lo}, {hi}], got {}", crate::error::fmt_num(x)),
        ))
    }
}

/// Checks a finite number in `(lo, hi]`.
pub(crate) fn check_open(key: &str, x: f64, lo: f64, hi: f64) -> Result<()> {
    if x.is_finite() && x > lo && x <= hi {
        Ok(())
    } else {
        Err(Error::setting(
            key,
            format!("must be a number in ({lo}, {hi}], got {}", crate::error::fmt_num(x)),
        ))
    }
}

fn check_colour(key: &str, c: &[f64; 3], hi: f64) -> Result<()> {
    for (i, x) in c.iter().enumerate() {
        check_range(&format!("{key}[{i}]"), *x, 0.0, hi)?;
    }
    Ok(())
}

fn check_vec(key: &str, v: &[f64; 3], nonzero: bool) -> Result<()> {
    if v.iter().any(|x| !x.is_finite()) {
        return Err(Error::setting(
            key,
            format!("components must be finite, got {}", crate::error::fmt_vec3(v)),
        ));
    }
    if nonzero && v.iter().all(|x| *x == 0.0) {
        return Err(Error::setting(key, "must not be the zero vector"));
    }
    let norm = nalgebra::Vector3::from(*v).norm();
    if nonzero && !(norm.is_finite() && norm > f64::MIN_POSITIVE) {
        // Its length under- or overflows: it cannot be made a unit vector.
        return Err(Error::setting(
            key,
            format!(
                "{} cannot be normalized (its length {} in f64); scale it towards 1",
                crate::error::fmt_vec3(v),
                if norm.is_finite() { "underflows" } else { "overflows" }
            ),
        ));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// material

/// The `material` section: a specular BRDF, its Fresnel factor and a diffuse term.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// The specular model (default: Ashikhmin–Shirley, n_u = 1000, n_v = 10, R_s = 0.9).
    #[serde(default)]
    pub brdf: BrdfSpec,
    /// Fresnel factor of Ward and GGX (default `none`, i.e. F = 1). Ashikhmin–Shirley carries
    /// its own Schlick term built from `rs`, so it must be `none` there.
    #[serde(default)]
    pub fresnel: Fresnel,
    /// Diffuse albedo, linear RGB in [0, 1] (default 0.05 grey). For Ashikhmin–Shirley this is
    /// its R_d (the coupled diffuse term of \[AS00\]); for the others a Lambert term ρ_d/π.
    #[serde(default = "default_diffuse")]
    pub diffuse: [f64; 3],
}

fn default_diffuse() -> [f64; 3] {
    [0.05; 3]
}

impl Default for Material {
    fn default() -> Self {
        Material { brdf: BrdfSpec::default(), fresnel: Fresnel::None, diffuse: default_diffuse() }
    }
}

/// The specular BRDF and its parameters. Roughness "along u" is the lobe width in the grain
/// direction: the paper's highlights (hᵀu = 0) need a lobe narrow along u, i.e. a large n_u or a
/// small α_u.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum BrdfSpec {
    /// Ashikhmin–Shirley \[AS00\] (`brdf::ashikhmin_shirley`).
    AshikhminShirley {
        /// Phong exponent along the grain u (> 0).
        nu: f64,
        /// Phong exponent along v = n × u (> 0).
        nv: f64,
        /// Specular reflectance at normal incidence R_s, linear RGB in [0, 1].
        rs: [f64; 3],
    },
    /// Ward \[War92\] (`brdf::ward`).
    Ward {
        /// Slope roughness along u (> 0).
        alpha_x: f64,
        /// Slope roughness along v (> 0).
        alpha_y: f64,
        /// Specular weight ρ_s in [0, 1].
        rho_s: f64,
    },
    /// Anisotropic GGX with height-correlated Smith masking–shadowing (`brdf::ggx`).
    Ggx {
        /// Roughness along u (> 0).
        alpha_u: f64,
        /// Roughness along v (> 0).
        alpha_v: f64,
    },
}

impl Default for BrdfSpec {
    fn default() -> Self {
        BrdfSpec::AshikhminShirley { nu: 1000.0, nv: 10.0, rs: [0.9; 3] }
    }
}

/// The Fresnel factor F(cos θ_d), θ_d the angle between ω_in and h.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Fresnel {
    /// F = 1.
    #[default]
    None,
    /// Schlick's approximation F₀ + (1 − F₀)(1 − cos θ)⁵.
    Schlick {
        /// Reflectance at normal incidence, linear RGB in [0, 1].
        f0: [f64; 3],
    },
    /// Exact unpolarized Fresnel of a conductor with complex index η + ik (per RGB channel).
    Conductor {
        /// Real part η (> 0).
        eta: [f64; 3],
        /// Extinction k (≥ 0).
        k: [f64; 3],
    },
    /// Conductor preset: aluminium (η, k at 650/550/450 nm from the usual tables).
    Aluminium,
    /// Conductor preset: steel, approximated by iron's η, k.
    Steel,
    /// Conductor preset: bronze, an approximation with R₀ ≈ (0.72, 0.55, 0.33).
    Bronze,
}

impl Material {
    /// Range-checks every parameter.
    pub fn validate(&self) -> Result<()> {
        match &self.brdf {
            BrdfSpec::AshikhminShirley { nu, nv, rs } => {
                check_open("brdf.nu", *nu, 0.0, 1e7)?;
                check_open("brdf.nv", *nv, 0.0, 1e7)?;
                check_colour("brdf.rs", rs, 1.0)?;
                if self.fresnel != Fresnel::None {
                    return Err(Error::setting(
                        "fresnel",
                        "must be none for ashikhmin_shirley (its Schlick term uses brdf.rs)",
                    ));
                }
            }
            BrdfSpec::Ward { alpha_x, alpha_y, rho_s } => {
                check_open("brdf.alpha_x", *alpha_x, 0.0, 10.0)?;
                check_open("brdf.alpha_y", *alpha_y, 0.0, 10.0)?;
                check_range("brdf.rho_s", *rho_s, 0.0, 1.0)?;
            }
            BrdfSpec::Ggx { alpha_u, alpha_v } => {
                check_open("brdf.alpha_u", *alpha_u, 0.0, 10.0)?;
                check_open("brdf.alpha_v", *alpha_v, 0.0, 10.0)?;
            }
        }
        match &self.fresnel {
            Fresnel::Schlick { f0 } => check_colour("fresnel.f0", f0, 1.0)?,
            Fresnel::Conductor { eta, k } => {
                for i in 0..3 {
                    check_open(&format!("fresnel.eta[{i}]"), eta[i], 0.0, 100.0)?;
                    check_range(&format!("fresnel.k[{i}]"), k[i], 0.0, 100.0)?;
                }
            }
            _ => {}
        }
        check_colour("diffuse", &self.diffuse, 1.0)
    }
}

// ---------------------------------------------------------------------------------------------
// lights

/// One entry of the `lights` list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightSpec {
    /// A distant light.
    Directional {
        /// Direction from the surface towards the light (normalized on use).
        direction: [f64; 3],
        /// Irradiance on a surface facing the light (default 1).
        #[serde(default = "one")]
        irradiance: f64,
        /// Linear RGB colour (default white).
        #[serde(default = "white")]
        colour: [f64; 3],
        /// Marks the light of the highlight model (default false).
        #[serde(default)]
        key: bool,
    },
    /// A point light: irradiance I·cos θ / d².
    Point {
        /// Position (scene units).
        position: [f64; 3],
        /// Intensity I (default 1).
        #[serde(default = "one")]
        intensity: f64,
        /// Linear RGB colour (default white).
        #[serde(default = "white")]
        colour: [f64; 3],
        /// Marks the light of the highlight model (default false): the half vector then uses
        /// ω_in = normalize(position − p) per vertex.
        #[serde(default)]
        key: bool,
    },
    /// Light from an equirectangular image (Radiance .hdr or PNG) around the scene, z up.
    Environment {
        /// The image file, as a path the caller has resolved.
        file: String,
        /// Radiance scale (default 1).
        #[serde(default = "one")]
        scale: f64,
        /// Size of the fixed, deterministic sample set (default 256).
        #[serde(default = "default_env_samples")]
        samples: u32,
        /// Rotation of the image about the z axis, degrees (default 0).
        #[serde(default)]
        rotation_deg: f64,
    },
}

fn default_env_samples() -> u32 {
    256
}

impl LightSpec {
    /// Range-checks every parameter.
    pub fn validate(&self) -> Result<()> {
        match self {
            LightSpec::Directional { direction, irradiance, colour, .. } => {
                check_vec("direction", direction, true)?;
                check_range("irradiance", *irradiance, 0.0, 1e9)?;
                check_colour("colour", colour, 1e9)
            }
            LightSpec::Point { position, intensity, colour, .. } => {
                check_vec("position", position, false)?;
                check_range("intensity", *intensity, 0.0, 1e12)?;
                check_colour("colour", colour, 1e9)
            }
            LightSpec::Environment { file, scale, samples, rotation_deg } => {
                if file.is_empty() {
                    return Err(Error::setting("file", "must name an image file"));
                }
                check_range("scale", *scale, 0.0, 1e9)?;
                check_range("samples", f64::from(*samples), 1.0, 65536.0)?;
                check_range("rotation_deg", *rotation_deg, -3600.0, 3600.0)
            }
        }
    }
}

/// Validates a `lights` list, naming the entry (`[2].irradiance`).
pub fn validate_lights(lights: &[LightSpec]) -> Result<()> {
    for (i, l) in lights.iter().enumerate() {
        l.validate().map_err(|e| match e {
            Error::Setting { key, message } => Error::setting(format!("[{i}].{key}"), message),
            e => e,
        })?;
    }
    Ok(())
}

/// The light of the highlight model: the first directional or point light with `key: true`,
/// else the first directional light, else the first point light.
pub fn key_light_index(lights: &[LightSpec]) -> Option<usize> {
    let keyed = |l: &LightSpec| {
        matches!(l, LightSpec::Directional { key: true, .. } | LightSpec::Point { key: true, .. })
    };
    let dir = |l: &LightSpec| matches!(l, LightSpec::Directional { .. });
    let point = |l: &LightSpec| matches!(l, LightSpec::Point { .. });
    lights
        .iter()
        .position(keyed)
        .or_else(|| lights.iter().position(dir))
        .or_else(|| lights.iter().position(point))
}

// ---------------------------------------------------------------------------------------------
// render

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
    /// 12 for the as-brushed radiance and 12 more for its difference, 32 for LIC
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
            per_sample += 12;
            if a.mode == AsBrushedMode::Difference {
                per_sample += 12;
            }
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
        }
        if let Some(c) = &self.critical_points {
            check_range("effects.critical_points.threshold", c.threshold, -1.0, 1.0)?;
        }
        if let Some(e) = &self.edits {
            check_open("effects.edits.arrow_px", e.arrow_px, 0.0, 1000.0)?;
        }
        if let Some(s) = &self.strokes {
            check_open("effects.strokes.width_px", s.width_px, 0.0, 50.0)?;
        }
        if let Some(a) = &self.as_brushed {
            check_open("effects.as_brushed.gain", a.gain, 0.0, 1e6)?;
        }
        if let Some(g) = &self.gap {
            check_open("effects.gap.max", g.max, 0.0, 1e12)?;
        }
        Ok(())
    }
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
}

fn default_gain() -> f64 {
    4.0
}

/// Coverage-gap settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GapSettings {
    /// Gap value shown fully red (default 1).
    #[serde(default = "one")]
    pub max: f64,
}
