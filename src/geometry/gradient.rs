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
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
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

/// [`GradientStencil::users`]: the vertices whose stencil holds each vertex, in CSR form.
#[derive(Clone, Debug, Default)]
pub struct StencilUsers {
    offsets: Vec<u32>,
    users: Vec<u32>,
}

impl StencilUsers {
    /// The vertices whose stencil holds vertex `j` (ascending; a vertex may appear twice when
    /// its stencil holds `j` twice).
    pub fn of(&self, j: usize) -> &[u32] {
        &self.users[self.offsets[j] as usize..self.offsets[j + 1] as usize]
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }
}

impl GradientStencil {
    /// Builds the stencil. `transport` holds ρᵢⱼ per adjacency slot.
    pub fn new(
        positions: &[Vector3<f64>],
        adj: &Adjacency,
        frames: &[Frame],
        transport: &[f64],
    ) -> Self {
        // Fixed chunks of vertices, each filling flat arrays, joined in vertex order: the same
        // stencil at any thread count, without one allocation per vertex.
        let n = positions.len();
        let parts: Vec<Part> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map_init(Scratch::default, |scratch, c| {
                let (v0, v1) = (c * CHUNK, n.min((c + 1) * CHUNK));
                // The 1-ring sizes: exact unless a stencil has to grow.
                let cap = if v1 > v0 { adj.slots(v1 - 1).end - adj.slots(v0).start } else { 0 };
                let mut part = Part {
                    ends: Vec::with_capacity(v1 - v0),
                    depth: Vec::with_capacity(v1 - v0),
                    neighbor: Vec::with_capacity(cap),
                    rho: Vec::with_capacity(cap),
                    pinv: Vec::with_capacity(cap),
                };
                for i in v0..v1 {
                    let depth =
                        stencil_at(positions, adj, frames, transport, i, scratch, &mut part);
                    part.depth.push(depth);
                    part.ends.push(part.neighbor.len() as u32);
                }
                part
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0u32);
        let (mut extended, mut empty) = (0, 0);
        for part in &parts {
            let base = *offsets.last().unwrap_or(&0);
            offsets.extend(part.ends.iter().map(|&e| base + e));
            for &depth in &part.depth {
                match depth {
                    0 => empty += 1,
                    1 => {}
                    _ => extended += 1,
                }
            }
        }
        let total = *offsets.last().unwrap_or(&0) as usize;
        // Join the parts in parallel, each into its own disjoint range of the outputs.
        let (mut neighbor, mut rho, mut pinv) =
            (vec![0u32; total], vec![0.0f64; total], vec![[0.0f64; 2]; total]);
        {
            let mut pieces = Vec::with_capacity(parts.len());
            let (mut rest_n, mut rest_r, mut rest_p) =
                (&mut neighbor[..], &mut rho[..], &mut pinv[..]);
            for part in &parts {
                let len = part.neighbor.len();
                let (head_n, tail_n) = std::mem::take(&mut rest_n).split_at_mut(len);
                let (head_r, tail_r) = std::mem::take(&mut rest_r).split_at_mut(len);
                let (head_p, tail_p) = std::mem::take(&mut rest_p).split_at_mut(len);
                pieces.push((part, head_n, head_r, head_p));
                (rest_n, rest_r, rest_p) = (tail_n, tail_r, tail_p);
            }
            pieces.into_par_iter().for_each(|(part, n, r, p)| {
                n.copy_from_slice(&part.neighbor);
                r.copy_from_slice(&part.rho);
                p.copy_from_slice(&part.pinv);
            });
        }
        drop(parts);
        GradientStencil { offsets, neighbor, rho, pinv, extended, empty }
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

    /// The stencil transposed: for each vertex j, the vertices whose stencil holds j, in
    /// ascending order (what a solve over a few free vertices needs to find its rows without
    /// scanning the part).
    pub fn users(&self) -> StencilUsers {
        let n = self.num_vertices();
        let mut offsets = vec![0u32; n + 1];
        for &j in &self.neighbor {
            offsets[j as usize + 1] += 1;
        }
        for j in 0..n {
            offsets[j + 1] += offsets[j];
        }
        let mut next = offsets.clone();
        let mut users = vec![0u32; self.neighbor.len()];
        // Vertices in ascending order: each list comes out sorted.
        for i in 0..n {
            for e in self.range(i) {
                let j = self.neighbor[e] as usize;
                users[next[j] as usize] = i as u32;
                next[j] += 1;
            }
        }
        StencilUsers { offsets, users }
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

/// Vertices per chunk of [`GradientStencil::new`].
const CHUNK: usize = 4096;

/// The stencils of one chunk of vertices, flat.
#[derive(Default)]
struct Part {
    /// End of each vertex's entries (relative to the chunk).
    ends: Vec<u32>,
    /// Ring depth used by each vertex (0: none).
    depth: Vec<u8>,
    neighbor: Vec<u32>,
    rho: Vec<f64>,
    pinv: Vec<[f64; 2]>,
}

#[derive(Default)]
struct Scratch {
    ring: Vec<u32>,
    grow: Vec<u32>,
    rows: Vec<Vector2<f64>>,
}

fn stencil_at(
    positions: &[Vector3<f64>],
    adj: &Adjacency,
    frames: &[Frame],
    transport: &[f64],
    i: usize,
    scratch: &mut Scratch,
    out: &mut Part,
) -> u8 {
    let f = &frames[i];
    for depth in 1..=3usize {
        if depth == 1 {
            scratch.ring.clear();
            scratch.ring.extend_from_slice(adj.neighbors(i));
        } else {
            gather_ring(adj, i, depth, &mut scratch.ring, &mut scratch.grow);
        }
        let Some(inv) = normal_matrix_inverse(positions, f, i, &scratch.ring, &mut scratch.rows)
        else {
            continue;
        };
        let slots = adj.slots(i);
        for (k, (&j, r)) in scratch.ring.iter().zip(&scratch.rows).enumerate() {
            let rho = if depth == 1 {
                transport[slots.start + k]
            } else {
                transport_angle(f, &frames[j as usize])
            };
            let c = inv * r;
            out.neighbor.push(j);
            out.rho.push(rho);
            out.pinv.push([c.x, c.y]);
        }
        return depth as u8;
    }
    0
}

/// (PᵀP)⁻¹ for the projected neighbour positions (left in `rows`), or `None` when PᵀP is
/// singular relative to its scale (fewer than two neighbours, or all on one line through pᵢ).
fn normal_matrix_inverse(
    positions: &[Vector3<f64>],
    f: &Frame,
    i: usize,
    ring: &[u32],
    rows: &mut Vec<Vector2<f64>>,
) -> Option<Matrix2<f64>> {
    rows.clear();
    if ring.len() < 2 {
        return None;
    }
    rows.extend(ring.iter().map(|&j| f.to_local(&(positions[j as usize] - positions[i]))));
    let mut ptp = Matrix2::zeros();
    for r in rows.iter() {
        ptp += r * r.transpose();
    }
    let tr = ptp.trace();
    let det = ptp.determinant();
    if !(tr > 0.0 && tr.is_finite()) || det <= 1e-10 * tr * tr {
        return None;
    }
    ptp.try_inverse()
}
