//! The grain rasterized per UV triangle, then dilated over the whole image.

use nalgebra::{Vector2, Vector3};

use super::mikk::CornerFrames;
use super::{lerp_frame, png_io, BakeInput};
use crate::Result;

/// The grain in texture space: per texel (rows top to bottom) the unit grain (x, y) in the
/// texel's tangent frame and the frame's sign w (module docs of [`super`]).
#[derive(Clone, Debug, PartialEq)]
pub struct GrainImage {
    /// Texels per side.
    pub size: usize,
    /// The unit grain per texel, (u·T, u·B).
    pub grain: Vec<[f32; 2]>,
    /// The sign w of the texel's frame (±1).
    pub sign: Vec<f32>,
    /// Texels whose centre lies inside a UV triangle (the others are dilated).
    pub covered: usize,
    /// The share of the texel the grain reaches, in [0, 1]: the corners with a grain (not the
    /// zero vector: a vertex no stroke brushed) interpolated at the texel's centre; 1 for a
    /// field with a grain everywhere. Written as the anisotropy texture's strength (B).
    pub strength: Vec<f32>,
}

/// Barycentric coordinates of `q` in the triangle `p` (pixel space), or `None` outside it
/// (a little slack, so texel centres on a shared edge are not lost to rounding).
fn barycentric(p: &[Vector2<f64>; 3], q: Vector2<f64>) -> Option<[f64; 3]> {
    let area = (p[1] - p[0]).perp(&(p[2] - p[0]));
    if area.abs() < 1e-12 || !area.is_finite() {
        return None;
    }
    let b1 = (q - p[0]).perp(&(p[2] - p[0])) / area;
    let b2 = (p[1] - p[0]).perp(&(q - p[0])) / area;
    let b0 = 1.0 - b1 - b2;
    const SLACK: f64 = -1e-9;
    (b0 >= SLACK && b1 >= SLACK && b2 >= SLACK).then_some([b0, b1, b2])
}

/// The grain at barycentric `b` of face `f`, in the interpolated frame: (x, y) unit and w.
fn texel_value(
    input: &BakeInput,
    frames: &CornerFrames,
    f: usize,
    b: [f64; 3],
) -> Option<([f32; 2], f32)> {
    let normals = input.faces[f].map(|v| input.normals[v as usize]);
    let (t, bt, _, w) = lerp_frame(&normals, &frames.tangents[f], b)?;
    let u: Vector3<f64> = (0..3).map(|c| b[c] * input.grain[f][c]).sum();
    let (x, y) = (u.dot(&t), u.dot(&bt));
    let len = x.hypot(y);
    (len > 1e-12 && len.is_finite()).then(|| ([(x / len) as f32, (y / len) as f32], w as f32))
}

/// Rasterizes every UV triangle (texel centres inside it; a later face overwrites an earlier
/// one where UV triangles overlap), then dilates.
pub(super) fn rasterize(
    input: &BakeInput,
    st: &[[Vector2<f64>; 3]],
    frames: &CornerFrames,
) -> GrainImage {
    let n = input.size as usize;
    let nf = n as f64;
    let mut img = GrainImage {
        size: n,
        grain: vec![[0.0; 2]; n * n],
        sign: vec![0.0; n * n],
        covered: 0,
        strength: vec![1.0; n * n],
    };
    // Texels whose strength a triangle set (the others take their neighbours').
    let mut set = vec![false; n * n];
    for (f, corners) in st.iter().enumerate() {
        let p = corners.map(|q| Vector2::new(q.x * nf, (1.0 - q.y) * nf));
        if !p.iter().all(|q| q.x.is_finite() && q.y.is_finite()) {
            continue;
        }
        let lo = p.iter().fold(Vector2::repeat(f64::INFINITY), |a, q| a.inf(q));
        let hi = p.iter().fold(Vector2::repeat(f64::NEG_INFINITY), |a, q| a.sup(q));
        let i0 = (lo.x - 0.5).ceil().max(0.0) as usize;
        let j0 = (lo.y - 0.5).ceil().max(0.0) as usize;
        let i1 = ((hi.x - 0.5).floor().min(nf - 1.0)).max(-1.0);
        let j1 = ((hi.y - 0.5).floor().min(nf - 1.0)).max(-1.0);
        if i1 < 0.0 || j1 < 0.0 {
            continue;
        }
        for j in j0..=j1 as usize {
            for i in i0..=i1 as usize {
                let q = Vector2::new(i as f64 + 0.5, j as f64 + 0.5);
                let Some(b) = barycentric(&p, q) else { continue };
                let k = j * n + i;
                let reached: f64 = (0..3)
                    .filter(|&c| input.grain[f][c].norm_squared() > 0.0)
                    .map(|c| b[c].clamp(0.0, 1.0))
                    .sum();
                img.strength[k] = reached.clamp(0.0, 1.0) as f32;
                set[k] = true;
                if let Some((g, w)) = texel_value(input, frames, f, b) {
                    img.grain[k] = g;
                    img.sign[k] = w;
                }
            }
        }
    }
    img.covered = img.sign.iter().filter(|&&w| w != 0.0).count();
    dilate(&mut img, input.line);
    dilate_strength(&mut img.strength, set, n);
    img
}

/// Gives every texel no triangle covers the mean strength of its neighbours set in earlier
/// layers, layer by layer outwards (a breadth-first dilation in scan order, as [`dilate`]); all 1
/// when no texel was set.
fn dilate_strength(strength: &mut [f32], set: Vec<bool>, n: usize) {
    if !set.iter().any(|&s| s) {
        strength.iter_mut().for_each(|x| *x = 1.0);
        return;
    }
    let mut done = set;
    let mut queued = done.clone();
    let mut layer: Vec<usize> = Vec::new();
    for (k, q) in queued.iter_mut().enumerate() {
        if !*q && neighbours(n, k).any(|m| done[m]) {
            *q = true;
            layer.push(k);
        }
    }
    while !layer.is_empty() {
        let values: Vec<f32> = layer
            .iter()
            .map(|&k| {
                let (sum, count) = neighbours(n, k)
                    .filter(|&m| done[m])
                    .fold((0.0f32, 0u32), |(s, c), m| (s + strength[m], c + 1));
                if count > 0 {
                    sum / count as f32
                } else {
                    1.0
                }
            })
            .collect();
        for (&k, &v) in layer.iter().zip(&values) {
            strength[k] = v;
            done[k] = true;
        }
        layer = next_layer(n, &layer, &mut queued);
    }
}

/// The texels next to `layer` not queued yet, now queued: the next layer of a dilation.
fn next_layer(n: usize, layer: &[usize], queued: &mut [bool]) -> Vec<usize> {
    let mut next = Vec::new();
    for &k in layer {
        for m in neighbours(n, k) {
            if !queued[m] {
                queued[m] = true;
                next.push(m);
            }
        }
    }
    next
}

/// The 8 neighbours of texel `k` inside an `n`² image.
fn neighbours(n: usize, k: usize) -> impl Iterator<Item = usize> {
    let (i, j) = ((k % n) as i64, (k / n) as i64);
    let n = n as i64;
    [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)]
        .into_iter()
        .map(move |(di, dj)| (i + di, j + dj))
        .filter(move |&(a, b)| a >= 0 && b >= 0 && a < n && b < n)
        .map(move |(a, b)| (b * n + a) as usize)
}

/// Fills every empty texel (sign 0) from its filled neighbours, layer by layer outwards (a
/// breadth-first dilation in scan order, deterministic): the mean of the neighbours filled in
/// earlier layers, their signs aligned to the first one's for a line field; w of the first.
/// An image with no filled texel becomes the grain (1, 0), w = 1.
fn dilate(img: &mut GrainImage, line: bool) {
    let n = img.size;
    if img.covered == 0 {
        img.grain.iter_mut().for_each(|g| *g = [1.0, 0.0]);
        img.sign.iter_mut().for_each(|w| *w = 1.0);
        return;
    }
    let mut queued: Vec<bool> = img.sign.iter().map(|&w| w != 0.0).collect();
    let mut layer: Vec<usize> = Vec::new();
    for (k, q) in queued.iter_mut().enumerate() {
        if !*q && neighbours(n, k).any(|m| img.sign[m] != 0.0) {
            *q = true;
            layer.push(k);
        }
    }
    while !layer.is_empty() {
        let values: Vec<([f32; 2], f32)> = layer
            .iter()
            .map(|&k| {
                let mut first: Option<([f32; 2], f32)> = None;
                let (mut x, mut y) = (0.0f64, 0.0f64);
                for m in neighbours(n, k).filter(|&m| img.sign[m] != 0.0) {
                    let g = img.grain[m];
                    let (a, b) = (f64::from(g[0]), f64::from(g[1]));
                    let f = *first.get_or_insert((g, img.sign[m]));
                    let s = if line && a * f64::from(f.0[0]) + b * f64::from(f.0[1]) < 0.0 {
                        -1.0
                    } else {
                        1.0
                    };
                    x += s * a;
                    y += s * b;
                }
                let (g0, w0) = first.unwrap_or(([1.0, 0.0], 1.0));
                let len = x.hypot(y);
                if len > 1e-6 {
                    ([(x / len) as f32, (y / len) as f32], w0)
                } else {
                    (g0, w0)
                }
            })
            .collect();
        for (&k, &(g, w)) in layer.iter().zip(&values) {
            img.grain[k] = g;
            img.sign[k] = w;
        }
        layer = next_layer(n, &layer, &mut queued);
    }
}

impl GrainImage {
    /// The grain turned by `angle` towards B in each texel's frame: what `anisotropyTexture`
    /// holds with the material's `anisotropyRotation` folded in (π/2 turns u into n × u).
    pub fn turned(&self, k: usize, angle: f64) -> [f64; 2] {
        let (x, y) = (f64::from(self.grain[k][0]), f64::from(self.grain[k][1]));
        let w = f64::from(self.sign[k]);
        let (c, s) = (angle.cos(), angle.sin());
        // n × u in (T, B) is w·(−y, x): B = w (N × T) gives N × T = w B and N × B = −w T.
        [c * x - s * w * y, c * y + s * w * x]
    }

    /// The direction map (docs/formats.md): 16-bit RGB, RG = n × u in the tangent frame
    /// mapped from [−1, 1] to [0, 1], B = 1 (full strength).
    pub fn direction_png16(&self) -> Result<Vec<u8>> {
        self.anisotropy_png16(std::f64::consts::FRAC_PI_2)
    }

    /// The angle map (docs/formats.md): 16-bit grey, the grain's angle θ ∈ [0, π) from T
    /// towards B, encoded θ/π (65535 ≙ π).
    pub fn angle_png16(&self) -> Result<Vec<u8>> {
        let px: Vec<u16> = self
            .grain
            .iter()
            .map(|g| {
                let a = f64::from(g[1]).atan2(f64::from(g[0])).rem_euclid(std::f64::consts::PI);
                (a / std::f64::consts::PI * 65535.0).round() as u16
            })
            .collect();
        png_io::encode16(self.size, self.size, png_io::Channels::Grey, &px)
    }

    /// The glb's `anisotropyTexture`: 16-bit RGB, RG = the grain turned by `rotation` (the
    /// material's `anisotropyRotation`, written as 0 in the file), B = the texel's
    /// [`GrainImage::strength`] × 65535 (1 wherever the field has a grain; 0 where the brush
    /// never passed, which a viewer shows isotropic), times `anisotropyStrength`. 16 bits: an 8-bit direction is off by up to 0.3°; a browser reads
    /// it at 8 bits, Blender at 16.
    pub fn anisotropy_png16(&self, rotation: f64) -> Result<Vec<u8>> {
        let n = self.size;
        let q = |v: f64| ((v.clamp(-1.0, 1.0) + 1.0) * 0.5 * 65535.0).round() as u16;
        let mut px = Vec::with_capacity(3 * n * n);
        for k in 0..n * n {
            let d = self.turned(k, rotation);
            let strength = (f64::from(self.strength[k]).clamp(0.0, 1.0) * 65535.0).round() as u16;
            px.extend([q(d[0]), q(d[1]), strength]);
        }
        png_io::encode16(n, n, png_io::Channels::Rgb, &px)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A texel inside one triangle of two, and the dilation fills the rest deterministically.
    #[test]
    fn dilation_fills_everything() {
        let mut img = GrainImage {
            size: 8,
            grain: vec![[0.0; 2]; 64],
            sign: vec![0.0; 64],
            covered: 1,
            strength: vec![1.0; 64],
        };
        img.grain[27] = [0.6, 0.8];
        img.sign[27] = 1.0;
        dilate(&mut img, true);
        assert!(img.sign.iter().all(|&w| w == 1.0));
        assert!(img.grain.iter().all(|g| (g[0] - 0.6).abs() < 1e-6 && (g[1] - 0.8).abs() < 1e-6));
    }

    /// Barycentric coordinates inside, on an edge and outside.
    #[test]
    fn barycentric_inside() {
        let p = [Vector2::new(0.0, 0.0), Vector2::new(4.0, 0.0), Vector2::new(0.0, 4.0)];
        let b = barycentric(&p, Vector2::new(1.0, 1.0)).unwrap();
        assert!((b[0] - 0.5).abs() < 1e-12 && (b[1] - 0.25).abs() < 1e-12);
        assert!(barycentric(&p, Vector2::new(2.0, 2.0)).is_some());
        assert!(barycentric(&p, Vector2::new(3.0, 3.0)).is_none());
    }
}
