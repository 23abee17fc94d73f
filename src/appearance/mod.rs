//! How the part looks: the scene's `material` and `lights` sections (docs/render.md) and the
//! BRDFs they name, shared by the preview (`crate::render`) and the glTF export
//! (`crate::export`).
//!
//! Every type derives `Serialize`, `Deserialize` and `JsonSchema`, refuses unknown keys, and has a
//! `validate` that range-checks every number with a message naming its key (relative to the
//! section; the scene loader adds the prefix).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::{Error, Result};

pub mod brdf;

pub(crate) fn one() -> f64 {
    1.0
}
fn white() -> [f64; 3] {
    [1.0; 3]
}
pub(crate) fn yes() -> bool {
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

pub(crate) fn check_colour(key: &str, c: &[f64; 3], hi: f64) -> Result<()> {
    for (i, x) in c.iter().enumerate() {
        check_range(&format!("{key}[{i}]"), *x, 0.0, hi)?;
    }
    Ok(())
}

pub(crate) fn check_vec(key: &str, v: &[f64; 3], nonzero: bool) -> Result<()> {
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
    /// The same metal where no brush passed (docs/render.md, "Unbrushed metal"): isotropic,
    /// with the narrower of the grain's two lobes in both directions — what a glTF viewer
    /// shows at anisotropy strength 0 (roughness r² = α along the grain, docs/gltf.md,
    /// Eq. G1).
    pub fn unbrushed(&self) -> Material {
        let brdf = match self.brdf {
            BrdfSpec::AshikhminShirley { nu, nv, rs } => {
                let n = nu.max(nv);
                BrdfSpec::AshikhminShirley { nu: n, nv: n, rs }
            }
            BrdfSpec::Ward { alpha_x, alpha_y, rho_s } => {
                let a = alpha_x.min(alpha_y);
                BrdfSpec::Ward { alpha_x: a, alpha_y: a, rho_s }
            }
            BrdfSpec::Ggx { alpha_u, alpha_v } => {
                let a = alpha_u.min(alpha_v);
                BrdfSpec::Ggx { alpha_u: a, alpha_v: a }
            }
        };
        Material { brdf, ..self.clone() }
    }

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

/// Validates a `lights` list, naming the entry (`[2].irradiance`). At most one light may be
/// marked `"key": true` (a second one is refused at its `[i].key`), and the list holds at most
/// [`crate::limits::MAX_LIGHTS`].
pub fn validate_lights(lights: &[LightSpec]) -> Result<()> {
    let max = crate::limits::MAX_LIGHTS;
    if lights.len() > max {
        return Err(Error::setting(
            "",
            format!("holds {} lights, more than the {max} a scene may have", lights.len()),
        ));
    }
    let mut first_key: Option<usize> = None;
    for (i, l) in lights.iter().enumerate() {
        l.validate().map_err(|e| match e {
            Error::Setting { key, message } => Error::setting(format!("[{i}].{key}"), message),
            e => e,
        })?;
        if is_keyed(l) {
            if let Some(j) = first_key {
                return Err(Error::setting(
                    format!("[{i}].key"),
                    format!(
                        "lights[{j}] is already the key light; the highlight model uses one \
                         light: mark only one `\"key\": true`"
                    ),
                ));
            }
            first_key = Some(i);
        }
    }
    Ok(())
}

/// Whether `l` is a directional or point light marked `"key": true`.
fn is_keyed(l: &LightSpec) -> bool {
    matches!(l, LightSpec::Directional { key: true, .. } | LightSpec::Point { key: true, .. })
}

/// The light of the highlight model: the first directional or point light with `key: true`,
/// else the first directional light, else the first point light.
pub fn key_light_index(lights: &[LightSpec]) -> Option<usize> {
    let dir = |l: &LightSpec| matches!(l, LightSpec::Directional { .. });
    let point = |l: &LightSpec| matches!(l, LightSpec::Point { .. });
    lights
        .iter()
        .position(is_keyed)
        .or_else(|| lights.iter().position(dir))
        .or_else(|| lights.iter().position(point))
}
