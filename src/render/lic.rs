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

/// White noise at output pixel (x, y) as a 24-bit integer: SplitMix64 of (seed, x, y).
fn noise_bits(seed: u64, x: usize, y: usize) -> u32 {
    let mut z = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((x as u64) << 32 | y as u64)
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as u32
}

/// White noise in [0, 1) at output pixel (x, y): [`noise_bits`] / 2²⁴.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) fn noise(seed: u64, x: usize, y: usize) -> f32 {
    noise_bits(seed, x, y) as f32 / (1u64 << 24) as f32
}

/// A sample's direction and the noise of its output pixel, side by side (one load per step).
#[derive(Clone, Copy)]
struct Cell {
    dir: [f32; 2],
    noise: u32,
}

/// Streamlines traced at once: both directions of two neighbouring samples. Each step depends
/// on the direction loaded by the previous one, so independent streamlines interleaved keep
/// the loads overlapping.
const CHAINS: usize = 4;

/// LIC values in [0, 1] per sample (0.5 on the background), with the noise values generated
/// and the steps taken. The noise is summed as 24-bit integers (exact, so the order of the
/// steps does not matter); the mean is the same number as a sum of the values in [0, 1).
pub(crate) fn lic(field: &DirField, s: usize, length_px: f64, seed: u64) -> (Vec<f32>, u64, u64) {
    let (w, h) = (field.width, field.height);
    let (ow, oh) = (w / s, h / s);
    // The noise image (on output pixels), then spread to the samples beside the directions.
    let tex: Vec<u32> =
        (0..ow * oh).into_par_iter().map(|k| noise_bits(seed, k % ow, k / ow)).collect();
    let cells: Vec<Cell> = field
        .dirs
        .par_iter()
        .enumerate()
        .map(|(k, &dir)| Cell { dir, noise: tex[(k / w / s) * ow + (k % w) / s] })
        .collect();
    let steps = (length_px * s as f64).round().max(1.0) as usize;
    let (wf, hf) = (w as f32, h as f32);
    let mut out = vec![0.5f32; w * h];
    let total_steps: u64 = out
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            let mut taken = 0u64;
            let line = &cells[y * w..(y + 1) * w];
            for (x0, pair) in row.chunks_mut(2).enumerate() {
                let x0 = 2 * x0;
                // Chain 2i + j: sample x0 + i, direction (1, −1)[j].
                let mut pos = [[0.0f32; 2]; CHAINS];
                let mut dir = [[0.0f32; 2]; CHAINS];
                let mut alive = [false; CHAINS];
                let mut sum = [0u64; 2];
                let mut n = [0u64; 2];
                for i in 0..pair.len() {
                    let c = line[x0 + i];
                    if c.dir == [0.0, 0.0] {
                        continue;
                    }
                    sum[i] = u64::from(c.noise);
                    n[i] = 1;
                    for (j, sign) in [1.0f32, -1.0].into_iter().enumerate() {
                        let k = 2 * i + j;
                        pos[k] = [(x0 + i) as f32 + 0.5, y as f32 + 0.5];
                        dir[k] = [c.dir[0] * sign, c.dir[1] * sign];
                        alive[k] = true;
                    }
                }
                for _ in 0..steps {
                    if alive == [false; CHAINS] {
                        break;
                    }
                    for k in 0..CHAINS {
                        if !alive[k] {
                            continue;
                        }
                        let (px, py) = (pos[k][0] + dir[k][0], pos[k][1] + dir[k][1]);
                        pos[k] = [px, py];
                        if px < 0.0 || py < 0.0 || px >= wf || py >= hf {
                            alive[k] = false;
                            continue;
                        }
                        let c = cells[py as usize * w + px as usize];
                        if c.dir == [0.0, 0.0] {
                            alive[k] = false;
                            continue;
                        }
                        let d = dir[k];
                        dir[k] = if c.dir[0] * d[0] + c.dir[1] * d[1] < 0.0 {
                            [-c.dir[0], -c.dir[1]]
                        } else {
                            c.dir
                        };
                        sum[k / 2] += u64::from(c.noise);
                        n[k / 2] += 1;
                        taken += 1;
                    }
                }
                for (i, o) in pair.iter_mut().enumerate() {
                    if n[i] == 0 {
                        continue;
                    }
                    let mean = sum[i] as f64 / (1u64 << 24) as f64 / n[i] as f64;
                    // Mean of ≈ n/s independent uniforms has std 0.2887/√(n/s): stretch to 0.2.
                    let gain = 0.2 / 0.2887 * (n[i] as f64 / s as f64).sqrt();
                    *o = (0.5 + (mean - 0.5) * gain).clamp(0.0, 1.0) as f32;
                }
            }
            taken
        })
        .sum();
    (out, (ow * oh) as u64, total_steps)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The old per-sample loop (one streamline at a time, noise summed in f64), as the
    /// reference for the interleaved one.
    fn lic_one_at_a_time(field: &DirField, s: usize, length_px: f64, seed: u64) -> Vec<f32> {
        let (w, h) = (field.width, field.height);
        let steps = (length_px * s as f64).round().max(1.0) as usize;
        let mut out = vec![0.5f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let d0 = field.dirs[y * w + x];
                if d0 == [0.0, 0.0] {
                    continue;
                }
                let mut sum = noise(seed, x / s, y / s) as f64;
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
                        let nd = field.dirs[py as usize * w + px as usize];
                        if nd == [0.0, 0.0] {
                            break;
                        }
                        d = if nd[0] * d[0] + nd[1] * d[1] < 0.0 { [-nd[0], -nd[1]] } else { nd };
                        sum += noise(seed, px as usize / s, py as usize / s) as f64;
                        n += 1;
                    }
                }
                let gain = 0.2 / 0.2887 * (n as f64 / s as f64).sqrt();
                out[y * w + x] = (0.5 + (sum / n as f64 - 0.5) * gain).clamp(0.0, 1.0) as f32;
            }
        }
        out
    }

    #[test]
    fn interleaved_streamlines_give_the_same_values_as_one_at_a_time() {
        // A swirl with a hole (critical point) and a background corner, odd width.
        for s in [1usize, 2] {
            let (w, h) = (37 * s, 29 * s);
            let dirs = (0..w * h)
                .map(|k| {
                    let (x, y) =
                        ((k % w) as f32 - 15.0 * s as f32, (k / w) as f32 - 12.0 * s as f32);
                    let r = x.hypot(y);
                    if r < 2.0 || (k % w < 4 && k / w < 5) {
                        [0.0, 0.0]
                    } else {
                        [-y / r, x / r]
                    }
                })
                .collect();
            let field = DirField { width: w, height: h, dirs };
            let (got, _, steps) = lic(&field, s, 6.0, 3);
            assert!(steps > 0);
            assert_eq!(got, lic_one_at_a_time(&field, s, 6.0, 3), "s = {s}");
        }
    }
}
