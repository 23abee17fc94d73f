//! Anisotropic GGX (Trowbridge–Reitz) with the height-correlated Smith masking–shadowing term:
//! E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2),
//! 2014, Eqs. 85–86 and 99; B. Burley, "Physically-Based Shading at Disney", 2012.
//!
//! D(h) = 1 / (π α_u α_v ((h_u/α_u)² + (h_v/α_v)² + h_n²)²)
//! Λ(ω) = (−1 + √(1 + (α_u² ω_u² + α_v² ω_v²)/ω_n²)) / 2
//! G₂(ω_in, ω_out) = 1 / (1 + Λ(ω_in) + Λ(ω_out))          (height-correlated form)
//! f = ρ_d/π + F(ω_in·h) D(h) G₂ / (4 (n·ω_in)(n·ω_out))

use nalgebra::Vector3;

use super::fresnel::FresnelTerm;
use super::{add_scaled, half, lambert, Brdf};

/// Anisotropic GGX with roughnesses along u and v.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// α_u along the grain.
    pub alpha_u: f64,
    /// α_v along v.
    pub alpha_v: f64,
    /// Fresnel factor.
    pub fresnel: FresnelTerm,
    /// Diffuse albedo.
    pub diffuse: [f64; 3],
}

impl Ggx {
    /// The Smith Λ of a direction (Heitz Eq. 86).
    fn lambda(&self, w: &Vector3<f64>) -> f64 {
        let t = (self.alpha_u * w.x).powi(2) + (self.alpha_v * w.y).powi(2);
        0.5 * ((1.0 + t / (w.z * w.z)).sqrt() - 1.0)
    }
}

impl Brdf for Ggx {
    fn eval(&self, wi: &Vector3<f64>, wo: &Vector3<f64>) -> [f64; 3] {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return [0.0; 3];
        }
        let d = lambert(&self.diffuse);
        let Some(h) = half(wi, wo) else { return d };
        let q = (h.x / self.alpha_u).powi(2) + (h.y / self.alpha_v).powi(2) + h.z * h.z;
        let dist = 1.0 / (std::f64::consts::PI * self.alpha_u * self.alpha_v * q * q);
        let g2 = 1.0 / (1.0 + self.lambda(wi) + self.lambda(wo));
        let s = dist * g2 / (4.0 * wi.z * wo.z);
        add_scaled(d, s, self.fresnel.eval(h.dot(wi)))
    }
}
