//! BRDFs in the local frame of the grain: x = u (the grain), y = v = n × u, z = n.
//!
//! Each model lives in its own module and implements [`Brdf`]; adding a model is adding a module
//! and a [`BrdfSpec`] variant. All are centrally symmetric
//! (f(−x, −y) = f(x, y)), so a grain line field (k = 2, the paper's §4.4) renders them exactly.

pub mod ashikhmin_shirley;
pub mod fresnel;
pub mod ggx;
pub mod ward;

use nalgebra::Vector3;

use super::{BrdfSpec, Material};

/// A BRDF f(ω_in, ω_out), both unit vectors in the local frame, pointing away from the surface.
pub trait Brdf: Send + Sync {
    /// f in linear RGB (1/sr). Zero when either direction is below the surface. Never NaN.
    fn eval(&self, wi: &Vector3<f64>, wo: &Vector3<f64>) -> [f64; 3];

    /// [`Brdf::eval`] in single precision, for the shading pass (docs/render.md, "Precision").
    /// The default widens to [`Brdf::eval`]; a model may override it with an f32 evaluation that
    /// stays within a relative 1e-4 of the f64 one wherever f is not negligible.
    fn eval_f32(&self, wi: [f32; 3], wo: [f32; 3]) -> [f32; 3] {
        let w = |v: [f32; 3]| Vector3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
        self.eval(&w(wi), &w(wo)).map(|c| c as f32)
    }
}

/// The BRDF of a (validated) material, diffuse term included.
pub fn from_material(m: &Material) -> Box<dyn Brdf> {
    match m.brdf {
        BrdfSpec::AshikhminShirley { nu, nv, rs } => {
            Box::new(ashikhmin_shirley::AshikhminShirley { nu, nv, rs, rd: m.diffuse })
        }
        BrdfSpec::Ward { alpha_x, alpha_y, rho_s } => Box::new(ward::Ward {
            alpha_x,
            alpha_y,
            rho_s,
            fresnel: fresnel::FresnelTerm::new(&m.fresnel),
            diffuse: m.diffuse,
        }),
        BrdfSpec::Ggx { alpha_u, alpha_v } => Box::new(ggx::Ggx {
            alpha_u,
            alpha_v,
            fresnel: fresnel::FresnelTerm::new(&m.fresnel),
            diffuse: m.diffuse,
        }),
    }
}

/// The unnormalized half vector ω_in + ω_out, normalized; `None` when they are opposite.
pub(crate) fn half(wi: &Vector3<f64>, wo: &Vector3<f64>) -> Option<Vector3<f64>> {
    let s = wi + wo;
    let l = s.norm();
    (l > 1e-12).then(|| s / l)
}

/// The Lambert term ρ_d / π.
pub(crate) fn lambert(diffuse: &[f64; 3]) -> [f64; 3] {
    diffuse.map(|d| d * std::f64::consts::FRAC_1_PI)
}

/// a + s·b per channel.
pub(crate) fn add_scaled(a: [f64; 3], s: f64, b: [f64; 3]) -> [f64; 3] {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}
