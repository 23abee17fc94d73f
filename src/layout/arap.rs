//! As-rigid-as-possible flattening (Liu, Zhang, Xu, Gotsman & Gortler 2008, "A local/global
//! approach to mesh parameterization", Eq. 3–9), started from the LSCM map.
//!
//! Each triangle T has its isometric flattening x_T (corners in a frame of its plane). The
//! energy (math.md, Eq. A1)
//!
//! ```text
//! E(u, R) = Σ_T Σ_k w_k |(u_i − u_j) − R_T (x_i − x_j)|²,   w_k = ½ cot θ_k,
//! ```
//!
//! is minimized alternately over the rotations R_T (local step: the rotation closest to
//! S_T = Σ_k w_k (u_i − u_j)(x_i − x_j)ᵀ, angle atan2(S₁₀ − S₀₁, S₀₀ + S₁₁), Eq. A2) and over
//! the positions u (global step: L u = b with L the cotangent Laplacian and
//! b_i = Σ w_k R_T (x_i − x_j), Eq. A3). Each step cannot increase E; L is factored once with
//! one vertex pinned (the energy is invariant to translations only).

use nalgebra::{Matrix2, Vector2, Vector3};

use super::charts::ChartMesh;
use super::linsys::Spd;
use super::lscm::{half_cotangents, local_frame, push_laplacian};
use crate::{Error, Result};

/// The rotations closest to each triangle's map (local step, Eq. A2).
#[allow(clippy::needless_range_loop)] // k indexes the corners, the frames and the weights
fn local_step(
    chart: &ChartMesh,
    frames: &[[Vector2<f64>; 3]],
    weights: &[[f64; 3]],
    uv: &[Vector2<f64>],
) -> Vec<Matrix2<f64>> {
    chart
        .tris
        .iter()
        .enumerate()
        .map(|(t, tri)| {
            let mut s = Matrix2::zeros();
            for k in 0..3 {
                let (a, b) = ((k + 1) % 3, (k + 2) % 3);
                let du = uv[tri[a] as usize] - uv[tri[b] as usize];
                let dx = frames[t][a] - frames[t][b];
                s += weights[t][k] * du * dx.transpose();
            }
            let th = (s[(1, 0)] - s[(0, 1)]).atan2(s[(0, 0)] + s[(1, 1)]);
            let (sn, cs) = th.sin_cos();
            Matrix2::new(cs, -sn, sn, cs)
        })
        .collect()
}

/// The ARAP energy of `uv` with rotations `r` (Eq. A1).
#[allow(clippy::needless_range_loop)] // k indexes the corners, the frames and the weights
fn energy(
    chart: &ChartMesh,
    frames: &[[Vector2<f64>; 3]],
    weights: &[[f64; 3]],
    r: &[Matrix2<f64>],
    uv: &[Vector2<f64>],
) -> f64 {
    let mut e = 0.0;
    for (t, tri) in chart.tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            let d =
                (uv[tri[a] as usize] - uv[tri[b] as usize]) - r[t] * (frames[t][a] - frames[t][b]);
            e += weights[t][k] * d.norm_squared();
        }
    }
    e
}

/// What [`arap`] did.
pub(crate) struct ArapRun {
    /// The flattening.
    pub uv: Vec<Vector2<f64>>,
    /// Local/global iterations done.
    pub iterations: usize,
}

/// ARAP flattening of a chart from the start `init` (see the module documentation), at most
/// `iterations` local/global rounds, stopping when the energy falls by less than `1e-8`
/// relatively.
pub(crate) fn arap(
    chart: &ChartMesh,
    pos: &[Vector3<f64>],
    init: &[Vector2<f64>],
    iterations: usize,
) -> Result<ArapRun> {
    let n = chart.num_vertices();
    let frames: Vec<[Vector2<f64>; 3]> =
        chart.tris.iter().map(|t| local_frame(t.map(|v| pos[v as usize]))).collect();
    let weights: Vec<[f64; 3]> =
        chart.tris.iter().map(|t| half_cotangents(t.map(|v| pos[v as usize]))).collect();
    if n < 3 || chart.tris.len() == 1 {
        return Ok(ArapRun { uv: init.to_vec(), iterations: 0 });
    }
    let mut entries = Vec::with_capacity(chart.tris.len() * 12);
    push_laplacian(chart, pos, 0, 1, &mut entries);
    let pin = chart.boundary.first().map_or(0, |e| e[0] as usize);
    let idx: Vec<usize> = (0..n)
        .map(|i| {
            if i < pin {
                i
            } else if i == pin {
                usize::MAX
            } else {
                i - 1
            }
        })
        .collect();
    let mut coupling = Vec::new(); // (free row, weight) of entries in the pinned column
    let free: Vec<(usize, usize, f64)> = entries
        .into_iter()
        .filter_map(|(r, c, v)| match (idx[r], idx[c]) {
            (usize::MAX, _) => None,
            (fr, usize::MAX) => {
                coupling.push((fr, v));
                None
            }
            (fr, fc) => Some((fr, fc, v)),
        })
        .collect();
    let spd = Spd::factor(n - 1, free, "layout (ARAP)")?;
    let mut uv = init.to_vec();
    let mut r = local_step(chart, &frames, &weights, &uv);
    let mut e_prev = energy(chart, &frames, &weights, &r, &uv);
    let mut done = 0;
    for _ in 0..iterations {
        done += 1;
        let mut b = vec![vec![0.0; n - 1], vec![0.0; n - 1]];
        for (t, tri) in chart.tris.iter().enumerate() {
            for k in 0..3 {
                let (a, c) = (tri[(k + 1) % 3] as usize, tri[(k + 2) % 3] as usize);
                let g = weights[t][k] * (r[t] * (frames[t][(k + 1) % 3] - frames[t][(k + 2) % 3]));
                if idx[a] != usize::MAX {
                    b[0][idx[a]] += g.x;
                    b[1][idx[a]] += g.y;
                }
                if idx[c] != usize::MAX {
                    b[0][idx[c]] -= g.x;
                    b[1][idx[c]] -= g.y;
                }
            }
        }
        let up = uv[pin];
        for &(fr, v) in &coupling {
            b[0][fr] -= v * up.x;
            b[1][fr] -= v * up.y;
        }
        spd.solve(&mut b);
        for i in 0..n {
            if idx[i] != usize::MAX {
                uv[i] = Vector2::new(b[0][idx[i]], b[1][idx[i]]);
            }
        }
        if uv.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(Error::Numerical {
                stage: "layout (ARAP)",
                message: "the global step gave a coordinate that is not finite".into(),
            });
        }
        r = local_step(chart, &frames, &weights, &uv);
        let e = energy(chart, &frames, &weights, &r, &uv);
        let small = (e_prev - e).abs() <= 1e-8 * e_prev.max(f64::MIN_POSITIVE);
        e_prev = e;
        if small {
            break;
        }
    }
    Ok(ArapRun { uv, iterations: done })
}
