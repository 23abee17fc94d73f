//! Environment light: an equirectangular image (Radiance .hdr or PNG), z up, integrated with a
//! fixed, deterministic sample set drawn in proportion to the image's luminance.
//!
//! Direction of texel centre (i, j) of a W × H image: φ = 2π (i + ½)/W − π + rotation,
//! θ = π (j + ½)/H, d = (sin θ cos φ, sin θ sin φ, cos θ).

use std::path::Path;

use nalgebra::Vector3;

use crate::{Error, Result};

/// A linear RGB equirectangular image.
#[derive(Clone, Debug)]
pub struct EnvMap {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Row-major texels, top row first (θ = 0, +z).
    pub texels: Vec<[f32; 3]>,
}

/// One sample of the environment: a direction and its radiance divided by pdf and count.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EnvSample {
    pub dir: Vector3<f64>,
    pub weight: [f64; 3],
}

impl EnvMap {
    /// Reads a `.hdr` (Radiance RGBE) or `.png` (sRGB, decoded by tiny-skia) file.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes =
            std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
        let is_png = bytes.starts_with(b"\x89PNG");
        let is_hdr = bytes.starts_with(b"#?RADIANCE") || bytes.starts_with(b"#?RGBE");
        let r = match (is_png, is_hdr) {
            (true, _) => parse_png(&bytes),
            (_, true) => parse_hdr(&bytes),
            _ => Err("not an image: an environment light reads a Radiance .hdr (starting \
                      `#?RADIANCE` or `#?RGBE`) or a PNG"
                .into()),
        };
        // No line: an image has none.
        r.map_err(|message| Error::Scene { path: path.to_path_buf(), line: None, message })
    }

    /// A deterministic set of `n` samples: texels chosen by inverting the luminance × sin θ
    /// distribution at the points of a Hammersley set, weights L·Δω / (p·n) so that
    /// Σ f(d) L(d) (nᵀd)⁺ · weight estimates ∫ f L cos dω.
    pub(crate) fn samples(&self, n: usize, scale: f64, rotation_deg: f64) -> Vec<EnvSample> {
        let (w, h) = (self.width, self.height);
        let lum = |t: &[f32; 3]| 0.2126 * t[0] as f64 + 0.7152 * t[1] as f64 + 0.0722 * t[2] as f64;
        let sin_t = |j: usize| (std::f64::consts::PI * (j as f64 + 0.5) / h as f64).sin();
        let mean = self.texels.iter().map(lum).sum::<f64>() / (w * h) as f64;
        let floor = 0.01 * mean + 1e-12;
        let pmf: Vec<f64> =
            (0..w * h).map(|k| (lum(&self.texels[k]) + floor) * sin_t(k / w)).collect();
        let mut cdf = Vec::with_capacity(pmf.len());
        let mut acc = 0.0;
        for p in &pmf {
            acc += p;
            cdf.push(acc);
        }
        let total = acc;
        let texel_omega = |j: usize| {
            (std::f64::consts::TAU / w as f64) * (std::f64::consts::PI / h as f64) * sin_t(j)
        };
        let rot = rotation_deg.to_radians();
        (0..n)
            .map(|s| {
                let x = (s as f64 + 0.5) / n as f64;
                let y = radical_inverse(s as u32);
                let k = cdf.partition_point(|c| *c < x * total).min(pmf.len() - 1);
                let (i, j) = (k % w, k / w);
                // Jitter within the texel by the second coordinate (deterministic).
                let fi = (i as f64 + y) / w as f64;
                let phi = std::f64::consts::TAU * fi - std::f64::consts::PI + rot;
                let theta = std::f64::consts::PI * (j as f64 + 0.5) / h as f64;
                let dir =
                    Vector3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                let p = pmf[k] / total;
                let t = self.texels[k];
                let c = scale * texel_omega(j) / (p * n as f64);
                EnvSample { dir, weight: [t[0] as f64 * c, t[1] as f64 * c, t[2] as f64 * c] }
            })
            .collect()
    }
}

/// Van der Corput radical inverse in base 2.
fn radical_inverse(i: u32) -> f64 {
    f64::from(i.reverse_bits()) / 4_294_967_296.0
}

fn parse_png(bytes: &[u8]) -> std::result::Result<EnvMap, String> {
    let pm = tiny_skia::Pixmap::decode_png(bytes).map_err(|e| format!("PNG: {e}"))?;
    let (w, h) = (pm.width() as usize, pm.height() as usize);
    let texels = pm
        .pixels()
        .iter()
        .map(|p| {
            let c = p.demultiply();
            [c.red(), c.green(), c.blue()].map(|v| super::image::srgb_to_linear(v) as f32)
        })
        .collect();
    Ok(EnvMap { width: w, height: h, texels })
}

/// Parses a Radiance RGBE file (flat or new-style run-length encoded scanlines, `-Y H +X W`).
pub fn parse_hdr(bytes: &[u8]) -> std::result::Result<EnvMap, String> {
    if !(bytes.starts_with(b"#?RADIANCE") || bytes.starts_with(b"#?RGBE")) {
        return Err("not a Radiance file (no #?RADIANCE or #?RGBE header)".into());
    }
    let mut pos = 0;
    let next_line = |pos: &mut usize| -> std::result::Result<String, String> {
        let rest = &bytes[*pos..];
        let end = rest.iter().position(|&b| b == b'\n').ok_or("truncated header")?;
        *pos += end + 1;
        Ok(String::from_utf8_lossy(&rest[..end]).trim().to_string())
    };
    loop {
        let line = next_line(&mut pos)?;
        if line.is_empty() {
            break;
        }
        if let Some(f) = line.strip_prefix("FORMAT=") {
            if f != "32-bit_rle_rgbe" {
                return Err(format!("unsupported FORMAT={f}"));
            }
        }
    }
    let res = next_line(&mut pos)?;
    let parts: Vec<&str> = res.split_whitespace().collect();
    let (h, w) = match parts.as_slice() {
        ["-Y", h, "+X", w] => (
            h.parse::<usize>().map_err(|_| "bad height")?,
            w.parse::<usize>().map_err(|_| "bad width")?,
        ),
        _ => return Err(format!("unsupported resolution line {res:?} (only -Y H +X W)")),
    };
    if w == 0 || h == 0 || w > 1 << 15 || h > 1 << 15 {
        return Err(format!("bad size {w} × {h}"));
    }
    let data = &bytes[pos..];
    let mut p = 0;
    let mut texels = Vec::with_capacity(w * h);
    let mut scan = vec![[0u8; 4]; w];
    for _ in 0..h {
        let get = |p: usize| data.get(p).copied().ok_or_else(|| "truncated pixel data".to_string());
        let rle = (8..0x8000).contains(&w)
            && get(p)? == 2
            && get(p + 1)? == 2
            && (get(p + 2)? & 0x80) == 0
            && ((get(p + 2)? as usize) << 8 | get(p + 3)? as usize) == w;
        if rle {
            p += 4;
            for c in 0..4 {
                let mut x = 0;
                while x < w {
                    let count = get(p)? as usize;
                    p += 1;
                    if count > 128 {
                        let n = count - 128;
                        let v = get(p)?;
                        p += 1;
                        if x + n > w {
                            return Err("run overflows the scanline".into());
                        }
                        for s in &mut scan[x..x + n] {
                            s[c] = v;
                        }
                        x += n;
                    } else {
                        if count == 0 || x + count > w {
                            return Err("bad run length".into());
                        }
                        for s in &mut scan[x..x + count] {
                            s[c] = get(p)?;
                            p += 1;
                        }
                        x += count;
                    }
                }
            }
        } else {
            for s in scan.iter_mut() {
                for (c, v) in s.iter_mut().enumerate() {
                    *v = get(p + c)?;
                }
                p += 4;
            }
        }
        texels.extend(scan.iter().map(|&[r, g, b, e]| rgbe(r, g, b, e)));
    }
    Ok(EnvMap { width: w, height: h, texels })
}

/// RGBE → linear RGB: (c + ½) · 2^(e − 136), zero for e = 0.
fn rgbe(r: u8, g: u8, b: u8, e: u8) -> [f32; 3] {
    if e == 0 {
        return [0.0; 3];
    }
    let f = 2f64.powi(i32::from(e) - 136);
    [r, g, b].map(|c| ((f64::from(c) + 0.5) * f) as f32)
}
