//! Fresnel factors: none, Schlick, and the exact unpolarized conductor formula with presets.

use crate::appearance::Fresnel;

/// Aluminium η, k at (650, 550, 450) nm (Rakić 1995, as tabulated by PBRT/Mitsuba).
pub const ALUMINIUM: ([f64; 3], [f64; 3]) =
    ([1.65746, 0.880369, 0.521229], [9.22387, 6.26952, 4.837]);
/// Steel, approximated by iron (Fe) η, k at (650, 550, 450) nm.
pub const STEEL: ([f64; 3], [f64; 3]) = ([2.9114, 2.9497, 2.5845], [3.0893, 2.9318, 2.767]);
/// Bronze: an approximation chosen so R₀ = ((η−1)² + k²)/((η+1)² + k²) ≈ (0.72, 0.55, 0.33).
pub const BRONZE: ([f64; 3], [f64; 3]) = ([0.45, 0.75, 1.1], [2.0799, 1.8985, 1.4687]);

/// A Fresnel factor ready to evaluate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FresnelTerm {
    /// F = 1.
    One,
    /// Schlick with F₀.
    Schlick([f64; 3]),
    /// Conductor (η, k).
    Conductor([f64; 3], [f64; 3]),
}

impl FresnelTerm {
    /// From the material's `fresnel` setting.
    pub fn new(f: &Fresnel) -> Self {
        match f {
            Fresnel::None => FresnelTerm::One,
            Fresnel::Schlick { f0 } => FresnelTerm::Schlick(*f0),
            Fresnel::Conductor { eta, k } => FresnelTerm::Conductor(*eta, *k),
            Fresnel::Aluminium => FresnelTerm::Conductor(ALUMINIUM.0, ALUMINIUM.1),
            Fresnel::Steel => FresnelTerm::Conductor(STEEL.0, STEEL.1),
            Fresnel::Bronze => FresnelTerm::Conductor(BRONZE.0, BRONZE.1),
        }
    }

    /// F(cos θ), cos θ clamped to [0, 1].
    pub fn eval(&self, cos: f64) -> [f64; 3] {
        let c = cos.clamp(0.0, 1.0);
        match self {
            FresnelTerm::One => [1.0; 3],
            FresnelTerm::Schlick(f0) => {
                let w = (1.0 - c).powi(5);
                f0.map(|f| f + (1.0 - f) * w)
            }
            FresnelTerm::Conductor(eta, k) => [0, 1, 2].map(|i| conductor(c, eta[i], k[i])),
        }
    }
}

/// Exact unpolarized reflectance of a conductor with index η + ik at incidence cos θ
/// (e.g. PBRT 3rd ed. §8.2.1, "FrConductor").
pub fn conductor(cos: f64, eta: f64, k: f64) -> f64 {
    let c2 = cos * cos;
    let s2 = 1.0 - c2;
    let t0 = eta * eta - k * k - s2;
    let a2b2 = (t0 * t0 + 4.0 * eta * eta * k * k).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t1 = a2b2 + c2;
    let t2 = 2.0 * cos * a;
    let rs = (t1 - t2) / (t1 + t2).max(1e-300);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4).max(1e-300);
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}
