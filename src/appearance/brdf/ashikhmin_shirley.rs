//! The Ashikhmin–Shirley anisotropic Phong BRDF \[AS00\]: M. Ashikhmin, P. Shirley, "An
//! Anisotropic Phong BRDF Model", Journal of Graphics Tools 5(1), 2000, Eqs. 4–5.
//!
//! With h the half vector, k = ω_in, in the frame (u, v, n):
//!
//! ρ_s = √((n_u+1)(n_v+1)) / (8π) · (n·h)^((n_u (h·u)² + n_v (h·v)²) / (1 − (h·n)²))
//!       / ((h·k) · max(n·k₁, n·k₂)) · F(k·h),   F(c) = R_s + (1 − R_s)(1 − c)⁵
//!
//! ρ_d = 28 R_d / (23π) · (1 − R_s) · (1 − (1 − n·k₁/2)⁵) · (1 − (1 − n·k₂/2)⁵)
//!
//! The exponent is evaluated as (n_u h_u² + n_v h_v²)/(h_u² + h_v²), equal for a unit h and
//! defined (the power is 1) at h = n.
//!
//! [`Brdf::eval_f32`] evaluates the same formula in f32 without cancellation near the lobe: with
//! s = k₁ + k₂ (unnormalized), 1 − h·n = (s_u² + s_v²) / (|s| (|s| + s_n)) exactly, so
//! (h·n)^e = exp(e · ln(1 − δ)), δ = 1 − h·n, keeps its relative accuracy where h ≈ n (ln(1 − δ)
//! by its series for δ < 2⁻⁷).

use nalgebra::Vector3;

use super::{half, Brdf};

/// Ashikhmin–Shirley with exponents along u and v, R_s and R_d per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AshikhminShirley {
    /// Exponent n_u along the grain.
    pub nu: f64,
    /// Exponent n_v along v.
    pub nv: f64,
    /// Specular reflectance at normal incidence.
    pub rs: [f64; 3],
    /// Diffuse reflectance.
    pub rd: [f64; 3],
}

impl Brdf for AshikhminShirley {
    fn eval(&self, wi: &Vector3<f64>, wo: &Vector3<f64>) -> [f64; 3] {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return [0.0; 3];
        }
        let pi = std::f64::consts::PI;
        let dw = |c: f64| 1.0 - (1.0 - 0.5 * c).powi(5);
        let diffuse_geo = 28.0 / (23.0 * pi) * dw(wi.z) * dw(wo.z);
        let spec_geo = match half(wi, wo) {
            Some(h) => {
                let t2 = h.x * h.x + h.y * h.y;
                let e = if t2 > 1e-300 {
                    (self.nu * h.x * h.x + self.nv * h.y * h.y) / t2
                } else {
                    0.0
                };
                let hk = h.dot(wi).max(1e-12);
                ((self.nu + 1.0) * (self.nv + 1.0)).sqrt() / (8.0 * pi) * h.z.max(0.0).powf(e)
                    / (hk * wi.z.max(wo.z))
            }
            None => 0.0,
        };
        let c5 = half(wi, wo).map_or(1.0, |h| (1.0 - h.dot(wi).clamp(0.0, 1.0)).powi(5));
        [0, 1, 2].map(|i| {
            let f = self.rs[i] + (1.0 - self.rs[i]) * c5;
            spec_geo * f + diffuse_geo * self.rd[i] * (1.0 - self.rs[i])
        })
    }

    fn eval_f32(&self, wi: [f32; 3], wo: [f32; 3]) -> [f32; 3] {
        if wi[2] <= 0.0 || wo[2] <= 0.0 {
            return [0.0; 3];
        }
        let dw = |c: f32| 1.0 - (1.0 - 0.5 * c).powi(5);
        let diffuse_geo = (28.0 / (23.0 * std::f64::consts::PI)) as f32 * dw(wi[2]) * dw(wo[2]);
        let s = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
        let t2 = s[0] * s[0] + s[1] * s[1];
        let l = (t2 + s[2] * s[2]).sqrt();
        let (spec_geo, c5) = if l > 1e-12 {
            let hk_raw = (s[0] * wi[0] + s[1] * wi[1] + s[2] * wi[2]) / l;
            // (h·n)^e with e = (n_u h_u² + n_v h_v²)/(h_u² + h_v²) (scale-free in s); 1 at h = n.
            let pow = if t2 > 0.0 {
                let e = (self.nu as f32 * s[0] * s[0] + self.nv as f32 * s[1] * s[1]) / t2;
                let delta = t2 / (l * (l + s[2]));
                // ln(1 − δ): its series where δ is small (truncation ≈ δ⁵/5, below 1e-9
                // relative), else ln directly (there (h·n)^e is small wherever e is large).
                let ln_hn = if delta < 1.0 / 128.0 {
                    -delta * (1.0 + delta * (0.5 + delta * (1.0 / 3.0 + delta * 0.25)))
                } else {
                    (1.0 - delta).ln()
                };
                (e * ln_hn).exp()
            } else {
                1.0
            };
            let k =
                (((self.nu + 1.0) * (self.nv + 1.0)).sqrt() / (8.0 * std::f64::consts::PI)) as f32;
            let geo = k * pow / (hk_raw.max(1e-12) * wi[2].max(wo[2]));
            (geo, (1.0 - hk_raw.clamp(0.0, 1.0)).powi(5))
        } else {
            (0.0, 1.0)
        };
        [0, 1, 2].map(|i| {
            let rs = self.rs[i] as f32;
            let f = rs + (1.0 - rs) * c5;
            spec_geo * f + diffuse_geo * self.rd[i] as f32 * (1.0 - rs)
        })
    }
}
