//! The scene's BRDF as a glTF metallic–roughness material with `KHR_materials_anisotropy`
//! (docs/gltf.md, "Material").
//!
//! The extension's lobe is an anisotropic GGX with, along the *anisotropy direction* d
//! (TANGENT turned by `anisotropyRotation`), α_t = mix(r², 1, s²) and, across it, α_b = r²
//! (r = `roughness`, s = `anisotropyStrength`; KHR_materials_anisotropy, "Anisotropy"). The
//! roughness is *raised* along d, so d is the direction of the wider lobe. grainline's lobes
//! are narrow along the grain u (highlights where hᵀu = 0), so d = v = n × u and
//!
//! ```text
//! α_b = α_u  →  r = √α_u                                   (G1)
//! α_t = α_v  →  s = √((α_v − α_u)/(1 − α_u))                (G2, inverse of α_t = r² + (1 − r²) s²)
//! ```
//!
//! with α_u, α_v the GGX roughnesses equivalent to the scene's BRDF:
//! GGX: α directly; Ward: its slope roughness α_x, α_y (a Beckmann width, matched to GGX near
//! the peak); Ashikhmin–Shirley: α = √(2/(n + 2)) (Walter et al. 2007, Eq. 32 / the
//! Phong–Beckmann correspondence).

use serde::Serialize;

use crate::appearance::{BrdfSpec, Fresnel, Material};

/// The glTF material of a scene's BRDF.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GltfMaterial {
    /// `pbrMetallicRoughness.baseColorFactor` (linear RGB; F₀ of the metal).
    pub base_color: [f64; 3],
    /// `pbrMetallicRoughness.metallicFactor` (always 1: the scene's materials are metals).
    pub metallic: f64,
    /// `pbrMetallicRoughness.roughnessFactor` r (Eq. G1).
    pub roughness: f64,
    /// `KHR_materials_anisotropy.anisotropyStrength` s (Eq. G2).
    pub anisotropy_strength: f64,
    /// `KHR_materials_anisotropy.anisotropyRotation`, radians: π/2 when the lobe is wider
    /// across the grain (d = n × u for TANGENT = u), 0 when it is wider along it.
    pub anisotropy_rotation: f64,
    /// The GGX-equivalent roughness along the grain u.
    pub alpha_u: f64,
    /// The GGX-equivalent roughness across the grain (along v = n × u).
    pub alpha_v: f64,
    /// What the mapping could not carry (an α above 1 clamped, a diffuse term dropped).
    pub notes: Vec<String>,
}

/// GGX-equivalent α of a Phong exponent: Beckmann α = √(2/(n + 2)) (Walter et al. 2007).
pub fn phong_alpha(n: f64) -> f64 {
    (2.0 / (n + 2.0)).sqrt()
}

/// F₀ of the Fresnel setting (normal incidence), linear RGB.
fn f0(f: &Fresnel) -> [f64; 3] {
    let term = crate::appearance::brdf::fresnel::FresnelTerm::new(f);
    term.eval(1.0)
}

/// The glTF material of a validated scene material (Eqs. G1–G2).
pub fn gltf_material(m: &Material) -> GltfMaterial {
    let mut notes = Vec::new();
    let (alpha_u, alpha_v, base) = match m.brdf {
        BrdfSpec::AshikhminShirley { nu, nv, rs } => (phong_alpha(nu), phong_alpha(nv), rs),
        BrdfSpec::Ward { alpha_x, alpha_y, rho_s } => {
            (alpha_x, alpha_y, f0(&m.fresnel).map(|c| c * rho_s))
        }
        BrdfSpec::Ggx { alpha_u, alpha_v } => (alpha_u, alpha_v, f0(&m.fresnel)),
    };
    if m.diffuse.iter().any(|&d| d > 0.0) {
        notes.push(format!(
            "material.diffuse {:?} dropped: a glTF metal (metallic 1) has no diffuse term",
            m.diffuse
        ));
    }
    let clamp = |a: f64, name: &str, notes: &mut Vec<String>| {
        if a > 1.0 {
            notes.push(format!("{name} = {a:.4} clamped to 1 (the extension's largest α)"));
            1.0
        } else {
            a
        }
    };
    let au = clamp(alpha_u, "alpha along u", &mut notes);
    let av = clamp(alpha_v, "alpha across u", &mut notes);
    let (lo, hi, rotation) =
        if av >= au { (au, av, std::f64::consts::FRAC_PI_2) } else { (av, au, 0.0) };
    let roughness = lo.sqrt();
    let strength = if lo < 1.0 { ((hi - lo) / (1.0 - lo)).max(0.0).sqrt().min(1.0) } else { 0.0 };
    GltfMaterial {
        base_color: base.map(|c| c.clamp(0.0, 1.0)),
        metallic: 1.0,
        roughness,
        anisotropy_strength: strength,
        anisotropy_rotation: rotation,
        alpha_u,
        alpha_v,
        notes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spec's forward formulas (α_b = r², α_t = mix(r², 1, s²)) give back the α's.
    #[test]
    fn mapping_inverts_the_extension() {
        let m = Material {
            brdf: BrdfSpec::Ggx { alpha_u: 0.04, alpha_v: 0.4 },
            fresnel: Fresnel::None,
            diffuse: [0.0; 3],
        };
        let g = gltf_material(&m);
        let r2 = g.roughness * g.roughness;
        let s2 = g.anisotropy_strength * g.anisotropy_strength;
        assert!((r2 - 0.04).abs() < 1e-12);
        assert!((r2 * (1.0 - s2) + s2 - 0.4).abs() < 1e-12);
        assert_eq!(g.anisotropy_rotation, std::f64::consts::FRAC_PI_2);
        assert_eq!(g.base_color, [1.0; 3]);
        assert!(g.notes.is_empty());
        // A lobe wider along u: the anisotropy direction is u itself.
        let m = Material { brdf: BrdfSpec::Ggx { alpha_u: 0.5, alpha_v: 0.1 }, ..m };
        let g = gltf_material(&m);
        assert_eq!(g.anisotropy_rotation, 0.0);
        assert!((g.roughness.powi(2) - 0.1).abs() < 1e-12);
    }

    /// Ashikhmin–Shirley n = 800: α = √(2/802) ≈ 0.0499 by hand.
    #[test]
    fn phong_exponent() {
        assert!((phong_alpha(800.0) - 0.049_937_6).abs() < 1e-6);
        assert!((phong_alpha(0.0) - 1.0).abs() < 1e-15);
    }

    /// Aluminium's conductor F₀ by the Fresnel formula at normal incidence,
    /// ((η−1)² + k²)/((η+1)² + k²) at 550 nm: η = 0.880369, k = 6.26952 → 0.9163.
    #[test]
    fn conductor_base_colour() {
        let m = Material {
            brdf: BrdfSpec::Ggx { alpha_u: 0.04, alpha_v: 0.4 },
            fresnel: Fresnel::Aluminium,
            diffuse: [0.05; 3],
        };
        let g = gltf_material(&m);
        let (e, k) = (0.880369f64, 6.26952f64);
        let r0 = ((e - 1.0).powi(2) + k * k) / ((e + 1.0).powi(2) + k * k);
        assert!((g.base_color[1] - r0).abs() < 1e-9, "{:?} {r0}", g.base_color);
        assert_eq!(g.notes.len(), 1);
    }
}
