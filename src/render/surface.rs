//! Per-sample surface reconstruction: position, shading normal and grain direction from the
//! visibility buffer, with the grain interpolated as a vector (k = 1) or as a line (k = 2).

use nalgebra::Vector3;

use super::raster::{Sample, EMPTY};
use crate::geometry::surfaces::FaceSurfaces;
use crate::highlight::Symmetry;

/// The mesh data the passes read.
pub(crate) struct MeshData<'a> {
    pub positions: &'a [Vector3<f64>],
    pub faces: &'a [[u32; 3]],
    pub normals: &'a [Vector3<f64>],
    /// Per-corner shading normals, replacing `normals` when present.
    pub corner_normals: Option<&'a [[Vector3<f64>; 3]]>,
    /// The recognized surface of each face: on a curved one the shading normal is the
    /// surface's at the sample's nearest point, not the corners' blend.
    pub surfaces: Option<&'a FaceSurfaces>,
}

/// The surface seen at one sample.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Surf {
    pub face: usize,
    /// Barycentric weights of the face's three corners.
    pub w: [f64; 3],
    pub p: Vector3<f64>,
    /// Unit shading normal, facing the eye.
    pub n: Vector3<f64>,
    /// Unit direction towards the eye.
    pub wo: Vector3<f64>,
    /// A fixed tangent frame (t, b) at the sample (math.md §2's rule).
    pub t: Vector3<f64>,
    pub b: Vector3<f64>,
}

/// A unit tangent t ⟂ n from a fixed axis (x, or y when |xᵀn| > 0.9), and b = n × t.
pub(crate) fn tangent_frame(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let r = if n.x.abs() > 0.9 { Vector3::y() } else { Vector3::x() };
    let t = (r - n * n.dot(&r)).normalize();
    (t, n.cross(&t))
}

impl MeshData<'_> {
    /// The surface at a sample, `None` for the background.
    pub fn surf(&self, s: &Sample, eye: &Vector3<f64>) -> Option<Surf> {
        if s.face == EMPTY {
            return None;
        }
        let face = s.face as usize;
        let [i0, i1, i2] = self.faces[face].map(|i| i as usize);
        let (b1, b2) = (f64::from(s.b1), f64::from(s.b2));
        let w = [1.0 - b1 - b2, b1, b2];
        let ps = [self.positions[i0], self.positions[i1], self.positions[i2]];
        let p = ps[0] * w[0] + ps[1] * w[1] + ps[2] * w[2];
        let to_eye = eye - p;
        let d2 = to_eye.norm_squared();
        let wo = if d2 > 0.0 { to_eye / d2.sqrt() } else { Vector3::z() };
        // The geometric normal is needed only for its side (and as a fallback normal).
        let geo = (ps[1] - ps[0]).cross(&(ps[2] - ps[0]));
        let unit_geo = || if geo.norm() > 0.0 { geo.normalize() } else { wo };
        let cn = match self.corner_normals {
            Some(c) => c[face],
            None => [self.normals[i0], self.normals[i1], self.normals[i2]],
        };
        let ns = cn[0] * w[0] + cn[1] * w[1] + cn[2] * w[2];
        let mut n = if ns.norm() > 1e-12 && ns.iter().all(|c| c.is_finite()) {
            ns.normalize()
        } else {
            unit_geo()
        };
        // On a recognized curved surface, its own normal, oriented as the corners'.
        if let Some((_, m)) = self.surfaces.and_then(|s| s.project(face, &p)) {
            n = if m.dot(&n) < 0.0 { -m } else { m };
        }
        // Two-sided: a face seen from behind shades with its flipped normal.
        if geo.dot(&wo) < 0.0 {
            n = -n;
        }
        // A shading normal that faces away from the eye is bent just past the silhouette.
        let c = n.dot(&wo);
        if c < 0.01 {
            n = (n + wo * (0.01 - c)).normalize();
        }
        let (t, b) = tangent_frame(&n);
        Some(Surf { face, w, p, n, wo, t, b })
    }

    /// The three corner vertex indices of the sample's face.
    pub fn corners(&self, s: &Surf) -> [usize; 3] {
        self.faces[s.face].map(|i| i as usize)
    }
}

impl Surf {
    /// The interpolated grain (unit, tangent). k = 1: the projected linear interpolation. k = 2:
    /// the angle-doubled vector (cos 2φ, sin 2φ)·|u| in the sample's frame is interpolated (the
    /// tensor u uᵀ, paper §4.4), so u and −u at corners agree. Falls back to t where undefined.
    pub fn grain(&self, corner: [Vector3<f64>; 3], symmetry: Symmetry) -> Vector3<f64> {
        match symmetry {
            Symmetry::Oriented => {
                let u = corner[0] * self.w[0] + corner[1] * self.w[1] + corner[2] * self.w[2];
                let u = u - self.n * self.n.dot(&u);
                if u.norm() > 1e-12 {
                    u.normalize()
                } else {
                    self.t
                }
            }
            Symmetry::Line => self.line(corner).map_or(self.t, |(u, _)| u),
        }
    }

    /// Interpolates a line field (sign ignored) given per corner: the unit direction and the
    /// interpolated length, `None` where the doubled-angle average vanishes.
    pub fn line(&self, corner: [Vector3<f64>; 3]) -> Option<(Vector3<f64>, f64)> {
        let (mut zx, mut zy, mut mag) = (0.0, 0.0, 0.0);
        for (k, c) in corner.iter().enumerate() {
            let x = c.dot(&self.t);
            let y = c.dot(&self.b);
            let r2 = x * x + y * y;
            if !(r2 > 0.0 && r2.is_finite()) {
                continue;
            }
            zx += self.w[k] * (x * x - y * y) / r2.sqrt();
            zy += self.w[k] * 2.0 * x * y / r2.sqrt();
            mag += self.w[k] * r2.sqrt();
        }
        let z = (zx * zx + zy * zy).sqrt();
        if z.is_nan() || z <= 1e-9 * mag.max(1e-300) || !z.is_finite() {
            return None;
        }
        // Half the angle of (zx, zy), φ = ½·atan2(zy, zx) ∈ (−π/2, π/2], without trigonometry:
        // (cos φ, sin φ) ∝ (z + zx, zy) when zx ≥ 0, else ∝ (zy, z − zx) (the same line, better
        // conditioned; its sign chosen so cos φ ≥ 0, as atan2 gives).
        let (c, s) = if zx >= 0.0 {
            (z + zx, zy)
        } else if zy >= 0.0 {
            (zy, z - zx)
        } else {
            (-zy, zx - z)
        };
        let r = (c * c + s * s).sqrt();
        Some((self.t * (c / r) + self.b * (s / r), mag))
    }

    /// Barycentric interpolation of a per-vertex scalar.
    pub fn scalar(&self, corner: [f64; 3]) -> f64 {
        corner[0] * self.w[0] + corner[1] * self.w[1] + corner[2] * self.w[2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The half-angle reconstruction of `line` against φ = ½·atan2 with cos and sin.
    #[test]
    fn line_direction_is_half_the_doubled_angle() {
        let n = Vector3::new(0.2, -0.3, 0.9).normalize();
        let (t, b) = tangent_frame(&n);
        let mut state = 12345u64;
        let mut rnd = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..20000 {
            let corner = [0; 3].map(|_| t * rnd() + b * rnd() + n * rnd());
            let (w1, w2) = (rnd().abs(), rnd().abs());
            let (w1, w2) = if w1 + w2 > 1.0 { (1.0 - w1, 1.0 - w2) } else { (w1, w2) };
            let s =
                Surf { face: 0, w: [1.0 - w1 - w2, w1, w2], p: Vector3::zeros(), n, wo: n, t, b };
            let (mut zx, mut zy) = (0.0, 0.0);
            for (k, c) in corner.iter().enumerate() {
                let (x, y) = (c.dot(&t), c.dot(&b));
                let r = x.hypot(y);
                zx += s.w[k] * (x * x - y * y) / r;
                zy += s.w[k] * 2.0 * x * y / r;
            }
            let phi = 0.5 * zy.atan2(zx);
            let want = t * phi.cos() + b * phi.sin();
            let (got, _) = s.line(corner).expect("defined");
            assert!((got - want).norm() < 1e-12, "{got:?} vs {want:?} at φ = {phi}");
        }
    }
}
