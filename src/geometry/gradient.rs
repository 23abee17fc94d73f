//! The covariant gradient ∇φ of an angle field by local regression (the paper's Eq. 10).
//!
//! At vertex i, each neighbour j contributes a row pⱼ = [tᵢ bᵢ]ᵀ(pⱼ − pᵢ) (its position projected
//! onto the tangent plane) and the angle difference Δᵢⱼ = φⱼ + ρᵢⱼ − φᵢ after parallel
//! transport ([`super::connection`]). With Pᵢ⁺ = (PᵢᵀPᵢ)⁻¹Pᵢᵀ precomputed,
//!
//! ```text
//! ∇φᵢ = (1/k) Pᵢ⁺ [sin kΔᵢⱼ]ⱼ              (Eq. 10, GradientForm::Sine)
//! ∇φᵢ =       Pᵢ⁺ [wrap_{2π/k}(Δᵢⱼ)]ⱼ      (GradientForm::Angle, the default)
//! ```
//!
//! The angle form is the sine form without its cubic error term (math.md §2): it is exact for a
//! field whose angle is linear on a plane. k = 1 for oriented fields, k = 2 for line fields
//! (symmetric BRDFs, φ defined modulo π). The 1-ring is used unless its projected positions are
//! degenerate (fewer than two, or collinear), in which case the ring grows (up to the 3-ring).

use nalgebra::{Matrix2, Vector2, Vector3};
use rayon::prelude::*;

use super::connection::transport_angle;
use super::frames::Frame;
use super::rings::gather_ring;
use crate::mesh::Adjacency;

/// Which regression of Eq. 10 to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GradientForm {
    /// Regress the wrapped angle difference (exact for linear φ; the default).
    #[default]
    Angle,
    /// Regress `sin kΔ / k`, exactly as printed in Eq. 10.
    Sine,
}

/// The precomputed regression stencil of every vertex: neighbours, transport angles and the
/// columns of Pᵢ⁺. Its sparsity is the pattern of the optimizer's Jacobian.
#[derive(Clone, Debug, Default)]
pub struct GradientStencil {
    offsets: Vec<u32>,
    /// Neighbour vertex of each entry.
    pub neighbor: Vec<u32>,
    /// Transport angle ρᵢⱼ of each entry.
    pub rho: Vec<f64>,
    /// Column j of Pᵢ⁺ for each entry.
    pub pinv: Vec<[f64; 2]>,
    /// Vertices whose stencil needed more than the 1-ring.
    pub extended: usize,
    /// Vertices with no usable stencil (∇φ is reported as 0 there).
    pub empty: usize,
}

impl GradientStencil {
    /// Builds the stencil. `transport` holds ρᵢⱼ per adjacency slot.
    pub fn new(
        positions: &[Vector3<f64>],
        adj: &Adjacency,
        frames: &[Frame],
        transport: &[f64],
    ) -> Self {
        let per_vertex: Vec<StencilEntries> = (0..positions.len())
            .into_par_iter()
            .map_init(
                || (Vec::new(), Vec::new()),
                |bufs, i| stencil_at(positions, adj, frames, transport, i, bufs),
            )
            .collect();
        let mut st = GradientStencil {
            offsets: Vec::with_capacity(positions.len() + 1),
            ..Default::default()
        };
        st.offsets.push(0);
        for (entries, depth) in per_vertex {
            match depth {
                0 => st.empty += 1,
                1 => {}
                _ => st.extended += 1,
            }
            for (j, rho, col) in entries {
                st.neighbor.push(j);
                st.rho.push(rho);
                st.pinv.push(col);
            }
            st.offsets.push(st.neighbor.len() as u32);
        }
        st
    }

    /// Entry range of vertex `i`.
    #[inline]
    pub fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// ∇φ at vertex `i` in its frame, for symmetry `k` (1 or 2).
    #[inline]
    pub fn gradient_at(&self, phi: &[f64], k: u32, form: GradientForm, i: usize) -> Vector2<f64> {
        let kf = k as f64;
        let mut g = Vector2::zeros();
        for e in self.range(i) {
            let d = kf * (phi[self.neighbor[e] as usize] + self.rho[e] - phi[i]);
            let r = match form {
                GradientForm::Angle => super::connection::wrap_angle(d) / kf,
                GradientForm::Sine => d.sin() / kf,
            };
            g += Vector2::new(self.pinv[e][0], self.pinv[e][1]) * r;
        }
        g
    }

    /// ∇φ at every vertex.
    pub fn gradient(&self, phi: &[f64], k: u32, form: GradientForm) -> Vec<Vector2<f64>> {
        (0..self.num_vertices())
            .into_par_iter()
            .map(|i| self.gradient_at(phi, k, form, i))
            .collect()
    }
}

type StencilEntries = (Vec<(u32, f64, [f64; 2])>, u8);

fn stencil_at(
    positions: &[Vector3<f64>],
    adj: &Adjacency,
    frames: &[Frame],
    transport: &[f64],
    i: usize,
    bufs: &mut (Vec<u32>, Vec<u32>),
) -> StencilEntries {
    let f = &frames[i];
    for depth in 1..=3usize {
        let ring: Vec<u32> = if depth == 1 {
            adj.neighbors(i).to_vec()
        } else {
            gather_ring(adj, i, depth, &mut bufs.0, &mut bufs.1);
            bufs.0.clone()
        };
        if let Some(cols) = pseudo_inverse(positions, f, i, &ring) {
            let entries = ring
                .iter()
                .zip(cols)
                .map(|(&j, col)| {
                    let rho = if depth == 1 {
                        transport[adj.slot(i, j).expect("1-ring neighbour")]
                    } else {
                        transport_angle(f, &frames[j as usize])
                    };
                    (j, rho, col)
                })
                .collect();
            return (entries, depth as u8);
        }
    }
    (Vec::new(), 0)
}

/// Columns of (PᵀP)⁻¹Pᵀ for the projected neighbour positions, or `None` when PᵀP is singular
/// relative to its scale (fewer than two neighbours, or all on one line through pᵢ).
fn pseudo_inverse(
    positions: &[Vector3<f64>],
    f: &Frame,
    i: usize,
    ring: &[u32],
) -> Option<Vec<[f64; 2]>> {
    if ring.len() < 2 {
        return None;
    }
    let rows: Vec<Vector2<f64>> =
        ring.iter().map(|&j| f.to_local(&(positions[j as usize] - positions[i]))).collect();
    let mut ptp = Matrix2::zeros();
    for r in &rows {
        ptp += r * r.transpose();
    }
    let tr = ptp.trace();
    let det = ptp.determinant();
    if !(tr > 0.0 && tr.is_finite()) || det <= 1e-10 * tr * tr {
        return None;
    }
    let inv = ptp.try_inverse()?;
    Some(
        rows.iter()
            .map(|r| {
                let c = inv * r;
                [c.x, c.y]
            })
            .collect(),
    )
}
