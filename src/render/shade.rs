//! Direct lighting: Σ_lights f(ω_in, ω_out) E (nᵀω_in)⁺, plus the environment's sample set.

use nalgebra::Vector3;

use super::brdf::Brdf;
use super::bvh::Bvh;
use super::env::EnvSample;
use super::settings::LightSpec;
use super::surface::Surf;

/// A light ready to shade with.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Light {
    /// Unit direction towards the light and irradiance × colour.
    Directional { dir: Vector3<f64>, e: [f64; 3] },
    /// Position and intensity × colour.
    Point { pos: Vector3<f64>, i: [f64; 3] },
}

impl Light {
    /// Index-aligned with `lights`; environment entries give `None`.
    pub fn prepare(lights: &[LightSpec]) -> Vec<Option<Light>> {
        lights
            .iter()
            .map(|l| match l {
                LightSpec::Directional { direction, irradiance, colour, .. } => {
                    Some(Light::Directional {
                        dir: Vector3::from(*direction).normalize(),
                        e: colour.map(|c| c * irradiance),
                    })
                }
                LightSpec::Point { position, intensity, colour, .. } => Some(Light::Point {
                    pos: Vector3::from(*position),
                    i: colour.map(|c| c * intensity),
                }),
                LightSpec::Environment { .. } => None,
            })
            .collect()
    }

    /// Direction towards the light from `p`, irradiance on a facing surface, and the distance
    /// (∞ for a directional light); `None` at the light's own position.
    pub fn incident(&self, p: &Vector3<f64>) -> Option<(Vector3<f64>, [f64; 3], f64)> {
        match self {
            Light::Directional { dir, e } => Some((*dir, *e, f64::INFINITY)),
            Light::Point { pos, i } => {
                let d = pos - p;
                let r2 = d.norm_squared();
                (r2 > 1e-24).then(|| {
                    let r = r2.sqrt();
                    (d / r, i.map(|c| c / r2), r)
                })
            }
        }
    }
}

/// Everything shading needs.
pub(crate) struct Shader<'a> {
    pub brdf: &'a dyn Brdf,
    pub lights: Vec<Light>,
    pub env: &'a [EnvSample],
    pub bvh: Option<&'a Bvh>,
    /// Offset of shadow-ray origins along n.
    pub eps: f64,
    /// Per entry of `lights`: a directional light's direction and irradiance in f32 (for
    /// [`Shader::shade_f32`]), `None` for a point light. See [`Shader::single_precision`].
    pub lights32: Vec<Option<([f32; 3], [f32; 3])>>,
}

impl Shader<'_> {
    /// The f32 copies of the directional lights, index-aligned with `lights`.
    pub fn single_precision(lights: &[Light]) -> Vec<Option<([f32; 3], [f32; 3])>> {
        lights
            .iter()
            .map(|l| match l {
                Light::Directional { dir, e } => {
                    Some(([dir.x as f32, dir.y as f32, dir.z as f32], e.map(|c| c as f32)))
                }
                Light::Point { .. } => None,
            })
            .collect()
    }
}

/// Counts of one shading call.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ShadeCount {
    pub brdf_evals: u64,
    pub shadow_rays: u64,
}

impl Shader<'_> {
    /// Outgoing radiance at `s` with grain `u` (unit, tangent).
    pub fn shade(&self, s: &Surf, u: &Vector3<f64>, count: &mut ShadeCount) -> [f64; 3] {
        let v = s.n.cross(u);
        let local = |w: &Vector3<f64>| Vector3::new(w.dot(u), w.dot(&v), w.dot(&s.n));
        let wo = local(&s.wo);
        let mut out = [0.0; 3];
        let origin = s.p + s.n * self.eps;
        let mut add = |wi: &Vector3<f64>, e: &[f64; 3], dist: f64, count: &mut ShadeCount| {
            let cos = wi.dot(&s.n);
            if cos <= 0.0 {
                return;
            }
            if let Some(bvh) = self.bvh {
                count.shadow_rays += 1;
                if bvh.occluded(&origin, wi, dist) {
                    return;
                }
            }
            count.brdf_evals += 1;
            let f = self.brdf.eval(&local(wi), &wo);
            for c in 0..3 {
                out[c] += f[c] * e[c] * cos;
            }
        };
        for l in &self.lights {
            if let Some((wi, e, dist)) = l.incident(&s.p) {
                add(&wi, &e, dist, count);
            }
        }
        for smp in self.env {
            add(&smp.dir, &smp.weight, f64::INFINITY, count);
        }
        out.map(|c| if c.is_finite() { c.max(0.0) } else { 0.0 })
    }

    /// [`Shader::shade`] with the frame and the BRDF in f32 ([`Brdf::eval_f32`]): the same
    /// lights, visibility decisions and shadow rays (in f64), the sum over lights in f32.
    pub fn shade_f32(&self, s: &Surf, u: &Vector3<f64>, count: &mut ShadeCount) -> [f32; 3] {
        let f = |w: &Vector3<f64>| [w.x as f32, w.y as f32, w.z as f32];
        let dot = |a: &[f32; 3], b: &[f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (n, uf) = (f(&s.n), f(u));
        let v =
            [n[1] * uf[2] - n[2] * uf[1], n[2] * uf[0] - n[0] * uf[2], n[0] * uf[1] - n[1] * uf[0]];
        let local = |w: &[f32; 3]| [dot(w, &uf), dot(w, &v), dot(w, &n)];
        let wo = local(&f(&s.wo));
        // Summed in f64: an environment adds thousands of terms.
        let mut out = [0.0f64; 3];
        let origin = s.p + s.n * self.eps;
        let mut add = |wi: &Vector3<f64>,
                       wi32: &[f32; 3],
                       e: &[f32; 3],
                       dist: f64,
                       count: &mut ShadeCount| {
            let cos = dot(wi32, &n);
            if cos <= 0.0 {
                return;
            }
            if let Some(bvh) = self.bvh {
                count.shadow_rays += 1;
                if bvh.occluded(&origin, wi, dist) {
                    return;
                }
            }
            count.brdf_evals += 1;
            let fr = self.brdf.eval_f32(local(wi32), wo);
            for c in 0..3 {
                out[c] += f64::from(fr[c] * cos * e[c]);
            }
        };
        for (l, l32) in self.lights.iter().zip(&self.lights32) {
            match (l, l32) {
                (Light::Directional { dir, .. }, Some((d32, e32))) => {
                    add(dir, d32, e32, f64::INFINITY, count);
                }
                _ => {
                    if let Some((wi, e, dist)) = l.incident(&s.p) {
                        add(&wi, &f(&wi), &e.map(|c| c as f32), dist, count);
                    }
                }
            }
        }
        for smp in self.env {
            add(&smp.dir, &f(&smp.dir), &smp.weight.map(|c| c as f32), f64::INFINITY, count);
        }
        out.map(|c| if c.is_finite() { c.max(0.0) as f32 } else { 0.0 })
    }
}
