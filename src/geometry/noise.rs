//! The noise of a scanned or sculpted surface, estimated from the mesh alone, and the fit radius
//! it asks for (`field.fit_radius: "auto"`, docs/math.md §5.6, "Noise scale").
//!
//! A jet fit over the 1-ring follows a scan's noise: its normal error is about the noise's
//! height over the edge length. Least squares over the vertices within ρ averages it: the
//! normal error falls as σ·s/ρ² (σ the noise's RMS height, s the vertex spacing; N ∝ ρ²/s²
//! points, each tilting the plane by about σ/ρ), while the quadric's own bias grows as ρ²/R² of
//! the curvature 1/R. So:
//!
//! 1. **σ**: at sampled interior vertices i and a neighbour j of each, the height dᵢ of the
//!    vertex above the least-squares quadric `z = c + g·x + ½xᵀAx` fitted to its 2-ring without
//!    it. White noise makes dᵢ and dⱼ independent, so ½(dᵢ − dⱼ)² (the residuals' variogram
//!    at one edge) is about σ² ([`VARIOGRAM_FACTOR`]); a smooth part too coarse for its quadric
//!    makes neighbouring residuals alike, and is not mistaken for noise. σ is from the median
//!    over the samples, so creases, rims and a sculpted detail here and there do not count.
//! 2. **The noise radius** ρₙ = √(K σ s / θ*), the radius at which a fit's 95th-percentile
//!    normal error falls to θ* = [`TARGET_NORMAL_ERROR_DEG`]. K = [`NORMAL_ERROR_CONSTANT`] was
//!    measured on spheres with uniform radial noise (tests/geometry_noise.rs re-measures it),
//!    and ρₙ is kept within [`DIAGONAL_FRACTION`] of the part's diagonal.
//! 3. **The feature radius** R: 1 / the 90th percentile of max(|k₁|, |k₂|) over the samples,
//!    fitted over ρₙ. The quadric's own normal error grows as B·(ρ/R)² ([`BIAS_CONSTANT`]);
//!    where it would pass the noise's, ρ is cut to the balance ρ = (K σ s R² / B)^¼.
//! 4. A radius under [`RING_FACTOR`] spacings is no wider than the 2-ring: the 1-ring fit is
//!    kept (a clean mesh is computed exactly as without the estimate).

use nalgebra::{Matrix6, Vector3, Vector6};
use rayon::prelude::*;

use super::curvature::{JetRings, Principal};
use super::frames::Frame;
use super::normals::{self, NormalSource, VertexFaces};
use super::rings::gather_ring;
use crate::mesh::{Adjacency, Mesh};

/// The 95th-percentile normal error the automatic fit radius aims at, degrees. A normal off by
/// θ moves a highlight on a part of radius R by about R·θ: 0.4° is 0.007 R.
pub const TARGET_NORMAL_ERROR_DEG: f64 = 0.4;

/// K in θ₉₅ ≈ K·σ·s/ρ² (degrees): the 95th-percentile normal error of a fit over radius ρ on a
/// surface with RMS noise σ at vertex spacing s.
pub const NORMAL_ERROR_CONSTANT: f64 = 140.0;

/// B in the quadric's bias θ₉₅ ≈ B·(ρ/R)² (degrees): the 95th-percentile normal error of a fit
/// over ρ on a clean surface whose smallest radius of curvature is R (an ellipsoid
/// 60 × 45 × 35: 2.97–3.06 at ρ = 2–8, `BENCH_NOISE_BIAS=1 cargo run --release --example
/// bench_noise`).
pub const BIAS_CONSTANT: f64 = 3.0;

/// The automatic radius stays within this fraction of the part's bounding-box diagonal: below
/// the scale of any brush (edits' radii are a few per cent of the diagonal), however coarse
/// and rough the part.
pub const DIAGONAL_FRACTION: f64 = 0.04;

/// A radius of fewer spacings than this is no wider than the 2-ring: the 1-ring fit is kept.
pub const RING_FACTOR: f64 = 2.5;

/// Most vertices the estimate samples (every k-th vertex, in index order).
pub const MAX_SAMPLES: usize = 4096;

/// The median of ½(dᵢ − dⱼ)² over neighbours, for white noise of RMS height σ, is this times
/// σ² (dᵢ the vertex's height above the quadric fitted to its 2-ring without it; measured on
/// spheres with uniform radial noise, tests/geometry_noise.rs).
pub const VARIOGRAM_FACTOR: f64 = 0.78;

/// Fewest 2-ring points a sample needs (six unknowns, and some redundancy).
const MIN_RING_POINTS: usize = 10;

/// What [`estimate`] found.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NoiseEstimate {
    /// The noise's RMS height, scene units (the median of the samples' quadric residuals).
    pub sigma: f64,
    /// The vertex spacing s (median of the samples' mean edge lengths), scene units.
    pub spacing: f64,
    /// Vertices sampled.
    pub samples: usize,
    /// ρₙ, the radius at which the noise's normal error falls to the target.
    pub noise_radius: f64,
    /// The surface's radius of curvature at that scale (1 / the 90th percentile of the larger
    /// principal curvature), when it is curved.
    pub feature_radius: Option<f64>,
    /// The radius chosen: ρₙ, capped by the feature radius; `None` when it is no wider than
    /// the 2-ring (the 1-ring fit is kept).
    pub fit_radius: Option<f64>,
}

/// Estimates `mesh`'s noise and the fit radius it asks for (see the module docs). Deterministic
/// at any thread count; linear in the mesh (at most [`MAX_SAMPLES`] bounded fits).
pub fn estimate(mesh: &Mesh) -> NoiseEstimate {
    let vf = VertexFaces::new(mesh);
    let adjacency = Adjacency::from_vertex_faces(&mesh.faces, &vf);
    let (normals, _) = normals::vertex_normals(mesh, &vf, NormalSource::AngleWeighted);
    let nv = mesh.num_vertices();
    let stride = nv.div_ceil(MAX_SAMPLES).max(1);
    let candidates: Vec<usize> = (0..nv)
        .step_by(stride)
        .filter(|&i| adjacency.valence(i) >= 3 && !adjacency.is_boundary_vertex(i))
        .collect();
    // Each sample and its first neighbour: half the squared difference of their heights above
    // their fits (the residuals' variogram at one edge). White noise makes neighbours'
    // residuals independent; a smooth surface too coarse for its quadric makes them alike.
    let fits: Vec<(usize, f64, f64)> = candidates
        .par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(ring, scratch), &i| {
                let p = &mesh.positions;
                let (hi, spacing) = height_above_fit(p, &adjacency, &normals[i], i, ring, scratch)?;
                let j = *adjacency.neighbors(i).first()? as usize;
                let (hj, _) = height_above_fit(p, &adjacency, &normals[j], j, ring, scratch)?;
                Some((i, 0.5 * (hi - hj) * (hi - hj), spacing))
            },
        )
        .flatten()
        .collect();
    let samples = fits.len();
    let sigma = (median(fits.iter().map(|f| f.1).collect()) / VARIOGRAM_FACTOR).sqrt();
    let spacing = median(fits.iter().map(|f| f.2).collect());
    let noise_radius = if sigma > 0.0 && spacing > 0.0 {
        (NORMAL_ERROR_CONSTANT * sigma * spacing / TARGET_NORMAL_ERROR_DEG).sqrt()
    } else {
        0.0
    };
    let diagonal = bounding_diagonal(&mesh.positions);
    let mut out = NoiseEstimate {
        sigma,
        spacing,
        samples,
        noise_radius,
        feature_radius: None,
        fit_radius: None,
    };
    let wide = |r: f64| r >= RING_FACTOR * spacing && r.is_finite();
    let reach = noise_radius.min(DIAGONAL_FRACTION * diagonal);
    if !wide(reach) {
        return out;
    }
    let sampled: Vec<usize> = fits.iter().map(|f| f.0).collect();
    out.feature_radius = feature_radius(mesh, &adjacency, &normals, &sampled, reach);
    // Noise and bias balance where K σ s / ρ² = B ρ² / R².
    let balance =
        |r: f64| (NORMAL_ERROR_CONSTANT * sigma * spacing * r * r / BIAS_CONSTANT).sqrt().sqrt();
    let radius = out.feature_radius.map_or(reach, |r| reach.min(balance(r)));
    out.fit_radius = wide(radius).then_some(radius);
    out
}

fn bounding_diagonal(positions: &[Vector3<f64>]) -> f64 {
    let Some(first) = positions.first() else { return 0.0 };
    let (lo, hi) = positions.iter().fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
    (hi - lo).norm()
}

/// The height of vertex `i` above the quadric with a constant term fitted to its 2-ring
/// without it (its leave-one-out residual), and the mean length of its edges; `None` when the
/// ring does not determine the quadric.
fn height_above_fit(
    positions: &[Vector3<f64>],
    adj: &Adjacency,
    n: &Vector3<f64>,
    i: usize,
    ring: &mut Vec<u32>,
    scratch: &mut Vec<u32>,
) -> Option<(f64, f64)> {
    let pi = positions[i];
    let near = adj.neighbors(i);
    if near.is_empty() {
        return None;
    }
    let spacing =
        near.iter().map(|&j| (positions[j as usize] - pi).norm()).sum::<f64>() / near.len() as f64;
    gather_ring(adj, i, 2, ring, scratch);
    if ring.len() < MIN_RING_POINTS || !(spacing > 0.0 && spacing.is_finite()) {
        return None;
    }
    let frame = Frame::from_normal(*n);
    // Coordinates in units of the spacing: the 6×6 normal equations stay well conditioned.
    let mut a = Matrix6::zeros();
    let mut b = Vector6::zeros();
    for &j in ring.iter() {
        let d = (positions[j as usize] - pi) / spacing;
        let (x, y, z) = (frame.t.dot(&d), frame.b.dot(&d), frame.n.dot(&d));
        let row = Vector6::new(1.0, x, y, 0.5 * x * x, x * y, 0.5 * y * y);
        a += row * row.transpose();
        b += row * z;
    }
    let c = a.cholesky()?.solve(&b);
    // The fit's height at the vertex is c₀; the vertex is at height 0.
    let height = -c[0] * spacing;
    height.is_finite().then_some((height, spacing))
}

/// 1 / the 90th percentile of max(|k₁|, |k₂|) at the sampled vertices, fitted over `radius`;
/// `None` on a flat part.
fn feature_radius(
    mesh: &Mesh,
    adjacency: &Adjacency,
    normals: &[Vector3<f64>],
    sampled: &[usize],
    radius: f64,
) -> Option<f64> {
    let curvatures: Vec<f64> = sampled
        .par_iter()
        .map_init(JetRings::default, |rings, &i| {
            rings.start(i);
            let fit = rings.fit_in_ball(
                &mesh.positions,
                adjacency,
                &Frame::from_normal(normals[i]),
                radius,
            );
            let p = Principal::from_weingarten(&fit.w);
            p.k1.abs().max(p.k2.abs())
        })
        .collect();
    let k90 = percentile(curvatures, 0.9);
    (k90 > 0.0 && k90.is_finite()).then(|| 1.0 / k90)
}

fn median(v: Vec<f64>) -> f64 {
    percentile(v, 0.5)
}

/// The `q`-quantile (nearest rank) of `v`; 0 for an empty `v`.
fn percentile(mut v: Vec<f64>, q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let k = ((v.len() - 1) as f64 * q).round() as usize;
    v[k]
}
