//! Resolving samples to pixels, tone mapping, sRGB, and the PNG and PFM encoders.

use rayon::prelude::*;

use super::settings::ToneMap;
use crate::{Error, Result};

/// sRGB transfer function, linear [0, 1] → encoded [0, 1] (IEC 61966-2-1).
pub fn linear_to_srgb(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse sRGB transfer function for an 8-bit value.
pub fn srgb_to_linear(v: u8) -> f64 {
    let c = f64::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Tone maps one linear radiance value to display-linear [0, 1].
pub fn tone_map(x: f64, map: ToneMap, exposure: f64) -> f64 {
    let x = if x.is_finite() { x.max(0.0) } else { 0.0 };
    match map {
        ToneMap::None => x.min(1.0),
        ToneMap::Exposure => (x * exposure.exp2()).min(1.0),
        ToneMap::Reinhard => {
            let y = x * exposure.exp2();
            y / (1.0 + y)
        }
    }
}

/// The 8-bit sRGB code of one tone-mapped radiance value, computed directly:
/// `round(255 · clamp(srgb(tone_map(v))))`.
pub(crate) fn encode8(v: f32, map: ToneMap, exposure: f64) -> u8 {
    (linear_to_srgb(tone_map(f64::from(v), map, exposure)).clamp(0.0, 1.0) * 255.0).round() as u8
}

/// [`encode8`] as a table of thresholds: `thresholds[k − 1]` is the smallest finite f32 whose
/// code is ≥ k, so the code of a finite v is the number of thresholds ≤ v (a binary search of
/// 8 steps instead of a `powf`). Exact because the code is non-decreasing in v (tone map and
/// sRGB are monotone); non-finite values go through [`encode8`].
pub(crate) struct Srgb8Table {
    thresholds: [f32; 255],
    map: ToneMap,
    exposure: f64,
}

impl Srgb8Table {
    /// Builds the table by bisection on the bit patterns of non-negative f32s (ordered as
    /// integers): 255 × 31 evaluations.
    pub fn new(map: ToneMap, exposure: f64) -> Self {
        let mut thresholds = [f32::INFINITY; 255];
        let top = f32::MAX.to_bits();
        for (k, t) in thresholds.iter_mut().enumerate() {
            let code = (k + 1) as u8;
            if encode8(f32::MAX, map, exposure) < code {
                continue;
            }
            // Invariant: encode8(lo) < code ≤ encode8(hi).
            let (mut lo, mut hi) = (0u32, top);
            if encode8(0.0, map, exposure) >= code {
                *t = 0.0;
                continue;
            }
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if encode8(f32::from_bits(mid), map, exposure) >= code {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            *t = f32::from_bits(hi);
        }
        Srgb8Table { thresholds, map, exposure }
    }

    /// The code of `v`, equal to [`encode8`]`(v, map, exposure)`.
    #[inline]
    pub fn encode(&self, v: f32) -> u8 {
        if !v.is_finite() {
            return encode8(v, self.map, self.exposure);
        }
        self.thresholds.partition_point(|t| *t <= v) as u8
    }
}

/// Box-filters `s × s` blocks of a `(w·s) × (h·s)` buffer of N-channel values.
pub(crate) fn downsample<const N: usize>(
    src: &[[f32; N]],
    w: usize,
    h: usize,
    s: usize,
) -> Vec<[f32; N]> {
    if s == 1 {
        return src.to_vec();
    }
    let sw = w * s;
    let norm = 1.0 / (s * s) as f32;
    let mut out = vec![[0.0f32; N]; w * h];
    out.par_chunks_mut(w.max(1)).enumerate().for_each(|(y, line)| {
        for (x, o) in line.iter_mut().enumerate() {
            let mut acc = [0.0f32; N];
            for dy in 0..s {
                let row = &src[(y * s + dy) * sw + x * s..(y * s + dy) * sw + x * s + s];
                for v in row {
                    for c in 0..N {
                        acc[c] += v[c];
                    }
                }
            }
            *o = acc.map(|a| a * norm);
        }
    });
    out
}

/// Encodes opaque 8-bit sRGB pixels as an RGB PNG with the `png` crate's fast setting
/// (fdeflate, fixed filter): deterministic, faster than tiny-skia's default level (which also
/// copies to premultiplied RGBA), for a somewhat larger file.
pub(crate) fn encode_png(rgb: &[[u8; 3]], w: usize, h: usize) -> Result<Vec<u8>> {
    let err =
        |e: png::EncodingError| Error::Numerical { stage: "PNG encoding", message: e.to_string() };
    let (Ok(pw), Ok(ph)) = (u32::try_from(w), u32::try_from(h)) else {
        return Err(Error::setting("width", format!("image {w} × {h} cannot be encoded")));
    };
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, pw, ph);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut writer = enc.write_header().map_err(err)?;
        writer.write_image_data(rgb.as_flattened()).map_err(err)?;
        writer.finish().map_err(err)?;
    }
    Ok(out)
}

/// A little-endian colour PFM of linear radiance (rows bottom to top, as the format says).
pub(crate) fn encode_pfm(rgb: &[[f32; 3]], w: usize, h: usize) -> Vec<u8> {
    let mut out = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    out.reserve(12 * w * h);
    for y in (0..h).rev() {
        for c in &rgb[y * w..(y + 1) * w] {
            for v in c {
                let v = if v.is_finite() { *v } else { 0.0 };
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}

/// Decodes a PFM written by the renderer (or any little- or big-endian colour PFM) into
/// top-to-bottom rows: `(width, height, pixels)`.
pub fn decode_pfm(bytes: &[u8]) -> Option<(usize, usize, Vec<[f32; 3]>)> {
    let mut fields = Vec::new();
    let mut p = 0;
    while fields.len() < 4 {
        while p < bytes.len() && bytes[p].is_ascii_whitespace() {
            p += 1;
        }
        let s = p;
        while p < bytes.len() && !bytes[p].is_ascii_whitespace() {
            p += 1;
        }
        fields.push(std::str::from_utf8(&bytes[s..p]).ok()?.to_string());
    }
    p += 1;
    if fields[0] != "PF" {
        return None;
    }
    let w: usize = fields[1].parse().ok()?;
    let h: usize = fields[2].parse().ok()?;
    let scale: f64 = fields[3].parse().ok()?;
    let data = bytes.get(p..p + 12 * w * h)?;
    let mut px = vec![[0.0f32; 3]; w * h];
    for (k, ch) in data.chunks_exact(4).enumerate() {
        let b = [ch[0], ch[1], ch[2], ch[3]];
        let v = if scale < 0.0 { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) };
        let (row, rest) = (k / (3 * w), k % (3 * w));
        px[(h - 1 - row) * w + rest / 3][rest % 3] = v;
    }
    Some((w, h, px))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The threshold table gives the directly computed code for every value tried: all codes'
    /// boundaries (± 1 ulp) and a dense sweep, for each tone map.
    #[test]
    fn srgb_table_matches_direct_encoding() {
        for (map, exposure) in
            [(ToneMap::Reinhard, 0.0), (ToneMap::Exposure, 1.5), (ToneMap::None, -2.0)]
        {
            let table = Srgb8Table::new(map, exposure);
            let mut values = vec![0.0f32, -1.0, f32::NAN, f32::INFINITY, f32::MAX, 1e-30];
            for t in table.thresholds.iter().filter(|t| t.is_finite() && **t > 0.0) {
                let b = t.to_bits();
                values.extend([f32::from_bits(b - 1), *t, f32::from_bits(b + 1)]);
            }
            values.extend((0..200_000).map(|i| (i as f32 * 1e-4).powi(2)));
            for v in values {
                assert_eq!(table.encode(v), encode8(v, map, exposure), "{map:?} at {v}");
            }
        }
    }
}
