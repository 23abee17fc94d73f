//! Line integral convolution of the highlight tangent field ℓ (B. Cabral, L. Leedom, "Imaging
//! Vector Fields Using Line Integral Convolution", SIGGRAPH 1993; the paper's Fig. 5).
//!
//! ℓ is projected to the image at every sample; white noise lives on the output pixel grid (so
//! the texture does not change with the supersampling factor); each sample averages the noise
//! along its streamline over ±L pixels (box kernel, unit Euler steps, the direction re-oriented
//! at every step since ℓ is a line field), stopping at the background and where ℓ vanishes
//! (critical points). The mean is stretched to a fixed contrast.

use rayon::prelude::*;

/// A screen direction per sample; `[0, 0]` where ℓ is undefined or the sample is background.
pub(crate) struct DirField {
    pub width: usize,
    pub height: usize,
    pub dirs: Vec<[f32; 2]>,
}

/// White noise in [0, 1) at output pixel (x, y): SplitMix64 of (seed, x, y).
pub(crate) fn noise(seed: u64, x: usize, y: usize) -> f32 {
    let mut z = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((x as u64) << 32 | y as u64)
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}

/// LIC values in [0, 1] per sample (0.5 on the background), with the noise values generated
/// and the steps taken.
pub(crate) fn lic(field: &DirField, s: usize, length_px: f64, seed: u64) -> (Vec<f32>, u64, u64) {
    let (w, h) = (field.width, field.height);
    let (ow, oh) = (w / s, h / s);
    // The noise image (on output pixels).
    let tex: Vec<f32> = (0..ow * oh).map(|k| noise(seed, k % ow, k / ow)).collect();
    let steps = (length_px * s as f64).round().max(1.0) as usize;
    let mut out = vec![0.5f32; w * h];
    let total_steps: u64 = out
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            let mut taken = 0u64;
            for (x, o) in row.iter_mut().enumerate() {
                let d0 = field.dirs[y * w + x];
                if d0 == [0.0, 0.0] {
                    continue;
                }
                let mut sum = tex[(y / s) * ow + x / s] as f64;
                let mut n = 1usize;
                for sign in [1.0f32, -1.0] {
                    let (mut px, mut py) = (x as f32 + 0.5, y as f32 + 0.5);
                    let mut d = [d0[0] * sign, d0[1] * sign];
                    for _ in 0..steps {
                        px += d[0];
                        py += d[1];
                        if px < 0.0 || py < 0.0 || px >= w as f32 || py >= h as f32 {
                            break;
                        }
                        let (cx, cy) = (px as usize, py as usize);
                        let nd = field.dirs[cy * w + cx];
                        if nd == [0.0, 0.0] {
                            break;
                        }
                        d = if nd[0] * d[0] + nd[1] * d[1] < 0.0 { [-nd[0], -nd[1]] } else { nd };
                        sum += tex[(cy / s) * ow + cx / s] as f64;
                        n += 1;
                        taken += 1;
                    }
                }
                // Mean of ≈ n/s independent uniforms has std 0.2887/√(n/s): stretch to 0.2.
                let gain = 0.2 / 0.2887 * (n as f64 / s as f64).sqrt();
                *o = (0.5 + (sum / n as f64 - 0.5) * gain).clamp(0.0, 1.0) as f32;
            }
            taken
        })
        .sum();
    (out, (ow * oh) as u64, total_steps)
}
