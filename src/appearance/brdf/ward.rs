//! Ward's anisotropic Gaussian BRDF \[War92\]: G. Ward, "Measuring and Modeling Anisotropic
//! Reflection", SIGGRAPH 1992, Eq. 5a:
//!
//! f = ρ_d/π + ρ_s · F(ω_in·h) · exp(−((h·u/α_x)² + (h·v/α_y)²) / (h·n)²)
//!     / (4π α_x α_y √((n·ω_in)(n·ω_out)))
//!
//! with F = 1 unless the material asks for a Fresnel factor. The original normalization is kept:
//! it is reciprocal, but its albedo exceeds 1 near grazing incidence for rough lobes (a known
//! property of \[War92\]; docs/render.md gives the measured bound).

use nalgebra::Vector3;

use super::fresnel::FresnelTerm;
use super::{add_scaled, half, lambert, Brdf};

/// Ward with slope roughnesses along u and v.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ward {
    /// α_x along the grain.
    pub alpha_x: f64,
    /// α_y along v.
    pub alpha_y: f64,
    /// Specular weight.
    pub rho_s: f64,
    /// Fresnel factor.
    pub fresnel: FresnelTerm,
    /// Diffuse albedo.
    pub diffuse: [f64; 3],
}

impl Brdf for Ward {
    fn eval(&self, wi: &Vector3<f64>, wo: &Vector3<f64>) -> [f64; 3] {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return [0.0; 3];
        }
        let d = lambert(&self.diffuse);
        let Some(h) = half(wi, wo) else { return d };
        if h.z <= 0.0 {
            return d;
        }
        let (a, b) = (h.x / self.alpha_x, h.y / self.alpha_y);
        let e = (-(a * a + b * b) / (h.z * h.z)).exp();
        let s = self.rho_s * e
            / (4.0 * std::f64::consts::PI * self.alpha_x * self.alpha_y * (wi.z * wo.z).sqrt());
        add_scaled(d, s, self.fresnel.eval(h.dot(wi)))
    }
}
