//! Boundary first flattening (Sawhney & Crane 2017, "Boundary First Flattening", ACM TOG
//! 37(1)), with the boundary condition of minimal area distortion (scale factors u = 0 on
//! the boundary), for one disk chart. math.md §11.6 gives the derivation (Eq. B1–B6) and the
//! sign conventions. B1–B6 are this project's numbers, cited to the paper's steps (the
//! Cherrier formula and the Dirichlet-to-Neumann map, the best-fit closed curve, the
//! extension); the paper's own equation numbers were not at hand to check.
//!
//! With L the cotangent Laplacian (positive semi-definite, as in LSCM's Eq. L1), Θ_v the sum of
//! the 3D corner angles at vertex v, K = 2π − Θ the angle defect of an interior vertex and
//! k = π − Θ the geodesic curvature (turning angle) of a boundary vertex:
//!
//! ```text
//! (B1) L_II u_I = −K_I − L_IB u_B,   u_B = 0            interior scale factors (Yamabe, linear)
//! (B2) κ̃_B = k_B + (L u)_B = k_B − h,  h = −(L_BI u_I)    target turning angles (Neumann data h)
//! (B3) l*_ij = e^{(u_i + u_j)/2} ℓ_ij = ℓ_ij             target boundary lengths (u_B = 0)
//! (B4) φ_m = Σ_{j ≤ m} κ̃_j, T_m = (cos φ_m, sin φ_m)     tangents of the boundary polygon
//! (B5) l̃ = l* − N⁻¹ Tᵀ (T N⁻¹ Tᵀ)⁻¹ T l*,  N = diag(1/ℓ) closing: min ‖l̃ − l*‖²_N, Σ l̃_m T_m = 0
//! (B6) γ_m = Σ_{j < m} l̃_j T_j, then the interior by extension: harmonic in both
//!      coordinates (L_II x_I = −L_IB γ_B), or conformal: x harmonic, y its discrete harmonic
//!      conjugate (L y = g, g_b = ½ (x_prev − x_next) on the boundary, the Hilbert transform)
//! ```
//!
//! One factorization of L_II serves the scale factors (B1) and the harmonic extensions (B6);
//! the conformal extension factors L once more (one vertex pinned). The boundary loop
//! runs counter-clockwise (the direction of the chart's faces), so Σ κ̃ = 2π and γ is
//! counter-clockwise.

use nalgebra::{Matrix2, Vector2, Vector3};

use super::charts::ChartMesh;
use super::linsys::Spd;
use super::lscm::push_laplacian;
use crate::{Error, Result};

/// How [`bff`] extends the boundary polygon to the interior (B6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Extension {
    /// Both coordinates harmonic: the boundary is exactly the closed polygon γ.
    Harmonic,
    /// One coordinate harmonic, the other its harmonic conjugate: conformal, with a boundary
    /// close to γ.
    Conformal,
}

const STAGE: &str = "layout (BFF)";

fn numerical(message: impl Into<String>) -> Error {
    Error::Numerical { stage: STAGE, message: message.into() }
}

/// The chart's boundary vertices in order, counter-clockwise (each boundary edge `[i, j]` runs
/// in the direction of its face); `None` unless the boundary is one simple loop through every
/// boundary edge.
pub(crate) fn boundary_loop(chart: &ChartMesh) -> Option<Vec<u32>> {
    let n = chart.num_vertices();
    let mut next = vec![u32::MAX; n];
    for &[i, j] in &chart.boundary {
        if next[i as usize] != u32::MAX {
            return None; // a vertex where two boundary pieces meet
        }
        next[i as usize] = j;
    }
    let start = chart.boundary.first()?[0];
    let mut order = vec![start];
    let mut v = next[start as usize];
    while v != start {
        if v == u32::MAX || order.len() > chart.boundary.len() {
            return None;
        }
        order.push(v);
        v = next[v as usize];
    }
    (order.len() == chart.boundary.len()).then_some(order)
}

/// Sum of the 3D corner angles at each chart vertex (Θ_v).
fn angle_sums(chart: &ChartMesh, pos: &[Vector3<f64>]) -> Vec<f64> {
    let mut theta = vec![0.0; chart.num_vertices()];
    for t in &chart.tris {
        for k in 0..3 {
            let a = pos[t[(k + 1) % 3] as usize] - pos[t[k] as usize];
            let b = pos[t[(k + 2) % 3] as usize] - pos[t[k] as usize];
            theta[t[k] as usize] += a.cross(&b).norm().atan2(a.dot(&b));
        }
    }
    theta
}

/// The closing step (B5): the lengths l̃ nearest to `target` in the norm Σ (l̃ − l*)² / ℓ
/// (`mass[m]` = ℓ_m, the original lengths) such that the polygon of edges l̃_m T_m closes.
/// `None` when the tangents do not span the plane (T N⁻¹ Tᵀ singular).
pub(crate) fn close_lengths(
    target: &[f64],
    mass: &[f64],
    tangents: &[Vector2<f64>],
) -> Option<Vec<f64>> {
    let mut m = Matrix2::zeros(); // T N⁻¹ Tᵀ
    let mut gap = Vector2::zeros(); // T l*: how far the polygon of target lengths is from closing
    for ((&l, &w), t) in target.iter().zip(mass).zip(tangents) {
        m += w * t * t.transpose();
        gap += l * t;
    }
    let scale = m.trace();
    let spans = scale.is_finite() && scale > 0.0 && m.determinant() > 1e-12 * scale * scale;
    if !spans {
        return None;
    }
    let lambda = m.try_inverse()? * gap;
    Some(
        target.iter().zip(mass).zip(tangents).map(|((&l, &w), t)| l - w * t.dot(&lambda)).collect(),
    )
}

/// The polygon with edge lengths `lengths` turning by `turning[m]` at its vertex `m` (B4, B6):
/// vertex 0 at the origin, edge 0 along φ_0 = κ̃_0. Returns the vertices and the tangents.
pub(crate) fn polygon(turning: &[f64], lengths: &[f64]) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let mut phi = 0.0;
    let tangents: Vec<Vector2<f64>> = turning
        .iter()
        .map(|&k| {
            phi += k;
            Vector2::new(phi.cos(), phi.sin())
        })
        .collect();
    let mut p = Vector2::zeros();
    let points = tangents
        .iter()
        .zip(lengths)
        .map(|(t, &l)| {
            let q = p;
            p += l * t;
            q
        })
        .collect();
    (points, tangents)
}

/// The blocks of L split into interior (I) and boundary (B) unknowns.
struct Blocks {
    /// For each chart vertex, its index among the interior or the boundary vertices.
    slot: Vec<usize>,
    /// Whether each chart vertex is on the boundary.
    on_boundary: Vec<bool>,
    /// L_II, factored; `None` when the chart has no interior vertex.
    ii: Option<Spd>,
    /// Entries (interior row, boundary column, value) of L_IB.
    ib: Vec<(usize, usize, f64)>,
    n_interior: usize,
}

impl Blocks {
    fn new(chart: &ChartMesh, pos: &[Vector3<f64>], order: &[u32]) -> Result<Blocks> {
        let n = chart.num_vertices();
        let mut on_boundary = vec![false; n];
        let mut slot = vec![0; n];
        for (k, &v) in order.iter().enumerate() {
            on_boundary[v as usize] = true;
            slot[v as usize] = k;
        }
        let mut n_interior = 0;
        for v in 0..n {
            if !on_boundary[v] {
                slot[v] = n_interior;
                n_interior += 1;
            }
        }
        let mut entries = Vec::with_capacity(chart.tris.len() * 12);
        push_laplacian(chart, pos, 0, 1, &mut entries);
        let (mut ii, mut ib) = (Vec::new(), Vec::new());
        for (r, c, v) in entries {
            match (on_boundary[r], on_boundary[c]) {
                (false, false) => ii.push((slot[r], slot[c], v)),
                (false, true) => ib.push((slot[r], slot[c], v)),
                _ => {}
            }
        }
        let ii = if n_interior > 0 { Some(Spd::factor(n_interior, ii, STAGE)?) } else { None };
        Ok(Blocks { slot, on_boundary, ii, ib, n_interior })
    }

    /// Solves L_II x_I = rhs − L_IB x_B for the interior values (B1, B6).
    fn dirichlet(&self, mut rhs: Vec<f64>, boundary: &[f64]) -> Vec<f64> {
        for &(r, c, v) in &self.ib {
            rhs[r] -= v * boundary[c];
        }
        if let Some(ii) = &self.ii {
            let mut cols = vec![rhs];
            ii.solve(&mut cols);
            rhs = cols.pop().unwrap_or_default();
        }
        rhs
    }

    /// The values of a function given on the interior and the boundary, per chart vertex.
    fn gather(&self, interior: &[f64], boundary: &[f64]) -> Vec<f64> {
        (0..self.slot.len())
            .map(
                |v| {
                    if self.on_boundary[v] {
                        boundary[self.slot[v]]
                    } else {
                        interior[self.slot[v]]
                    }
                },
            )
            .collect()
    }
}

/// The target turning angles κ̃ of the boundary (B1–B2), in the order of `order`.
fn target_curvature(blocks: &Blocks, order: &[u32], theta: &[f64]) -> Vec<f64> {
    use std::f64::consts::{PI, TAU};
    let mut minus_k = vec![0.0; blocks.n_interior];
    for (v, &t) in theta.iter().enumerate() {
        if !blocks.on_boundary[v] {
            minus_k[blocks.slot[v]] = t - TAU; // −K = Θ − 2π
        }
    }
    let u_b = vec![0.0; order.len()];
    let u_i = blocks.dirichlet(minus_k, &u_b); // (B1)
    let mut kappa: Vec<f64> = order.iter().map(|&v| PI - theta[v as usize]).collect();
    for &(r, c, v) in &blocks.ib {
        kappa[c] += v * u_i[r]; // (B2): κ̃ = k + L_BI u_I (L symmetric)
    }
    kappa
}

/// The harmonic conjugate of `x` (B6): L y = g with g_b = ½ (x_prev − x_next) at the boundary
/// vertices, zero inside; the first boundary vertex is pinned at 0 (g sums to zero, so the
/// pinned system has the Neumann solution).
fn conjugate(
    chart: &ChartMesh,
    pos: &[Vector3<f64>],
    order: &[u32],
    x: &[f64],
) -> Result<Vec<f64>> {
    let n = chart.num_vertices();
    let pin = order[0] as usize;
    let idx = |v: usize| if v < pin { v } else { v - 1 };
    let mut entries = Vec::with_capacity(chart.tris.len() * 12);
    push_laplacian(chart, pos, 0, 1, &mut entries);
    let free: Vec<(usize, usize, f64)> = entries
        .into_iter()
        .filter(|&(r, c, _)| r != pin && c != pin)
        .map(|(r, c, v)| (idx(r), idx(c), v))
        .collect();
    let spd = Spd::factor(n - 1, free, STAGE)?;
    let mut g = vec![0.0; n - 1];
    let m = order.len();
    for (k, &v) in order.iter().enumerate() {
        let (prev, next) = (order[(k + m - 1) % m] as usize, order[(k + 1) % m] as usize);
        if v as usize != pin {
            g[idx(v as usize)] = 0.5 * (x[prev] - x[next]);
        }
    }
    let mut cols = vec![g];
    spd.solve(&mut cols);
    let y = &cols[0];
    Ok((0..n).map(|v| if v == pin { 0.0 } else { y[idx(v)] }).collect())
}

/// BFF flattening of a disk chart with u = 0 on the boundary (see the module documentation).
/// Fails (a typed error, for the caller to fall back) when the chart's boundary is not one
/// simple loop, the polygon cannot be closed, or a solve is not finite.
pub(crate) fn bff(
    chart: &ChartMesh,
    pos: &[Vector3<f64>],
    extension: Extension,
) -> Result<Vec<Vector2<f64>>> {
    if !chart.is_disk() {
        return Err(numerical("the chart is not a disk"));
    }
    let order = boundary_loop(chart).ok_or_else(|| numerical("the boundary is not one loop"))?;
    let m = order.len();
    let blocks = Blocks::new(chart, pos, &order)?;
    let theta = angle_sums(chart, pos);
    let kappa = target_curvature(&blocks, &order, &theta);
    // (B3) with u_B = 0: l* = ℓ; edge m runs from order[m] to order[m + 1].
    let len: Vec<f64> = (0..m)
        .map(|k| (pos[order[(k + 1) % m] as usize] - pos[order[k] as usize]).norm())
        .collect();
    // Vertex 0's turn is taken first, so edge m leaves vertex m along φ_m (B4).
    let (_, tangents) = polygon(&kappa, &len);
    let closed = close_lengths(&len, &len, &tangents)
        .ok_or_else(|| numerical("the boundary polygon cannot be closed"))?; // (B5)
    let (gamma, _) = polygon(&kappa, &closed); // (B6)
    let gx: Vec<f64> = gamma.iter().map(|p| p.x).collect();
    let gy: Vec<f64> = gamma.iter().map(|p| p.y).collect();
    let zero = vec![0.0; blocks.n_interior];
    let x = blocks.gather(&blocks.dirichlet(zero.clone(), &gx), &gx);
    let y = match extension {
        Extension::Harmonic => blocks.gather(&blocks.dirichlet(zero, &gy), &gy),
        Extension::Conformal => conjugate(chart, pos, &order, &x)?,
    };
    let uv: Vec<Vector2<f64>> = x.iter().zip(&y).map(|(&a, &b)| Vector2::new(a, b)).collect();
    if let Some(k) = uv.iter().position(|p| !(p.x.is_finite() && p.y.is_finite())) {
        return Err(numerical(format!("vertex {k} of the flattening is not finite")));
    }
    Ok(uv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn a_squares_turning_angles_give_a_closed_square() {
        let (pts, t) = polygon(&[FRAC_PI_2; 4], &[1.0; 4]);
        let closed = close_lengths(&[1.0; 4], &[1.0; 4], &t).unwrap();
        for l in &closed {
            assert!((l - 1.0).abs() < 1e-12, "a closed polygon is left as it is: {l}");
        }
        let end = pts[3] + t[3];
        assert!((end - pts[0]).norm() < 1e-12);
        // The four corners of a unit square, counter-clockwise.
        let want = [(0.0, 0.0), (0.0, 1.0), (-1.0, 1.0), (-1.0, 0.0)];
        for (p, w) in pts.iter().zip(want) {
            assert!((p - Vector2::new(w.0, w.1)).norm() < 1e-12, "{p:?} vs {w:?}");
        }
    }

    #[test]
    fn an_open_polygon_is_closed_with_the_least_change() {
        // A unit square's turns with one side 1.5 long: the gap is 0.5 along that side's
        // direction. With equal masses the least change (B5) shortens the long side and
        // lengthens the side opposite by 0.25 each (a Lagrange multiplier along that axis),
        // leaving the other two alone.
        let lengths = [1.5, 1.0, 1.0, 1.0];
        let (_, t) = polygon(&[FRAC_PI_2; 4], &lengths);
        let closed = close_lengths(&lengths, &[1.0; 4], &t).unwrap();
        let want = [1.25, 1.0, 1.25, 1.0];
        for (l, w) in closed.iter().zip(want) {
            assert!((l - w).abs() < 1e-12, "{closed:?}");
        }
        let sum: Vector2<f64> = closed.iter().zip(&t).map(|(&l, d)| l * d).sum();
        assert!(sum.norm() < 1e-12, "the polygon closes");
        // Heavier mass (a longer original edge) takes more of the change: with ℓ = (2, 1, 1, 1)
        // the multiplier λ solves (2 + 1) λ = 0.5 along that axis, so Δ = (−1/3, 0, +1/6, 0).
        let closed = close_lengths(&lengths, &[2.0, 1.0, 1.0, 1.0], &t).unwrap();
        let want = [1.5 - 1.0 / 3.0, 1.0, 1.0 + 1.0 / 6.0, 1.0];
        for (l, w) in closed.iter().zip(want) {
            assert!((l - w).abs() < 1e-12, "{closed:?}");
        }
    }

    /// The cap of an icosphere of radius 10 whose face centroids have z > 5 (about 60°), as a
    /// chart, with its positions.
    fn cap_chart() -> (ChartMesh, Vec<Vector3<f64>>) {
        let s = crate::generate::icosphere(10.0, 3);
        let faces: Vec<[u32; 3]> = s
            .faces
            .iter()
            .copied()
            .filter(|f| f.iter().map(|&v| s.positions[v as usize].z).sum::<f64>() > 15.0)
            .collect();
        let mesh = crate::mesh::Mesh::from_triangles(s.positions, faces);
        let he = crate::mesh::halfedge::HalfEdges::new(mesh.num_vertices(), &mesh.faces).unwrap();
        let ids: Vec<u32> = (0..mesh.num_faces() as u32).collect();
        let tag = vec![0u32; ids.len()];
        let chart = ChartMesh::new(&ids, &he, &mesh, &tag, &ids, 0);
        let pos = chart.positions(&mesh);
        (chart, pos)
    }

    /// Area-weighted mean σ₁/σ₂ of a flattening.
    fn mean_angle_distortion(chart: &ChartMesh, pos: &[Vector3<f64>], uv: &[Vector2<f64>]) -> f64 {
        let m = super::super::distortion::FaceMeasures::new(chart, pos, uv, 1.0);
        let total: f64 = m.area.iter().sum();
        m.sigma.iter().zip(&m.area).map(|(s, a)| s.0 / s.1 * a).sum::<f64>() / total
    }

    #[test]
    fn both_extensions_of_a_cap_are_valid_and_the_harmonic_one_keeps_the_polygon() {
        let (chart, pos) = cap_chart();
        assert!(chart.is_disk());
        let order = boundary_loop(&chart).unwrap();
        let conformal = bff(&chart, &pos, Extension::Conformal).unwrap();
        let harmonic = bff(&chart, &pos, Extension::Harmonic).unwrap();
        for uv in [&conformal, &harmonic] {
            assert_eq!(super::super::distortion::invalid(&chart, uv), None);
        }
        // u = 0 on the boundary and the closing changes lengths by the discretization only:
        // the harmonic image's rim is the 3D rim's length within 1 %.
        let rim = |p: &dyn Fn(usize) -> f64| (0..order.len()).map(p).sum::<f64>();
        let m = order.len();
        let at = |k: usize| order[k % m] as usize;
        let rim_3d = rim(&|k| (pos[at(k + 1)] - pos[at(k)]).norm());
        let rim_uv = rim(&|k| (harmonic[at(k + 1)] - harmonic[at(k)]).norm());
        assert!((rim_uv / rim_3d - 1.0).abs() < 0.01, "rim {rim_uv} vs {rim_3d}");
        let (c, h) = (
            mean_angle_distortion(&chart, &pos, &conformal),
            mean_angle_distortion(&chart, &pos, &harmonic),
        );
        eprintln!("cap 60°: mean σ₁/σ₂ conformal {c:.5}, harmonic {h:.5}");
        assert!(c < 1.05 && h < 1.05, "conformal {c}, harmonic {h}");
    }

    #[test]
    fn parallel_tangents_cannot_close() {
        let t = [Vector2::new(1.0, 0.0), Vector2::new(-1.0, 0.0)];
        assert!(close_lengths(&[1.0, 2.0], &[1.0, 1.0], &t).is_none());
    }
}
