//! Least-squares conformal maps (Lévy, Petitjean, Ray & Maillot 2002, "Least squares
//! conformal maps for automatic texture atlas generation"), in the form of Mullen, Tong,
//! Alliez & Desbrun 2008 ("Spectral conformal parameterization", Eq. 3–4).
//!
//! A map x = (u, v) of the chart to the plane is conformal where ∇v = n × ∇u. Its conformal
//! energy is the Dirichlet energy minus the signed area of the image (math.md, Eq. L1–L3):
//!
//! ```text
//! E_C(x) = E_D(u) + E_D(v) − A(x),
//! E_D(u) = ¼ Σ_T Σ_k cot θ_k (u_i − u_j)²            (θ_k the angle of T opposite edge ij)
//! A(x)   = ½ Σ_{boundary edges i→j} (u_i v_j − u_j v_i)
//! ```
//!
//! E_C ≥ 0, with equality exactly for conformal maps; on each triangle it is
//! A_T·|∇v − n × ∇u|² / 2 ≥ 0, so the quadratic form ½ xᵀ Q x = E_C is positive semi-definite
//! with the similarities as its kernel on a disk. Two boundary vertices far apart (a double
//! farthest-point sweep in 3D) are pinned at (0, 0) and (d, 0), d their distance; the free
//! coordinates solve Q_ff x_f = −Q_fp x_p (Eq. L4), a sparse SPD system. On a developable
//! disk the isometric flattening has zero energy, so it is the solution up to the scale the
//! pins impose; the layout rescales every chart so its area is the part's area.

use nalgebra::{Vector2, Vector3};

use super::charts::ChartMesh;
use super::linsys::Spd;
use crate::{Error, Result};

/// The three corners of a triangle in an orthonormal frame of its plane, counter-clockwise:
/// `(0, 0)`, `(|e₁|, 0)`, `(e₂·ê₁, |e₁ × e₂| / |e₁|)`.
pub(crate) fn local_frame(p: [Vector3<f64>; 3]) -> [Vector2<f64>; 3] {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let l = e1.norm();
    if l <= 0.0 || l.is_nan() {
        return [Vector2::zeros(), Vector2::zeros(), Vector2::new(0.0, e2.norm())];
    }
    let x = e2.dot(&e1) / l;
    let y = e1.cross(&e2).norm() / l;
    [Vector2::zeros(), Vector2::new(l, 0.0), Vector2::new(x, y)]
}

/// Half the cotangents of a triangle's angles, `w[k] = ½ cot θ_k` for the angle at corner
/// `k` (opposite edge `k+1 → k+2`). A nearly degenerate angle's cotangent is bounded at 1e12.
pub(crate) fn half_cotangents(p: [Vector3<f64>; 3]) -> [f64; 3] {
    let mut w = [0.0; 3];
    for k in 0..3 {
        let a = p[(k + 1) % 3] - p[k];
        let b = p[(k + 2) % 3] - p[k];
        let den = a.cross(&b).norm().max(1e-12 * a.norm() * b.norm());
        w[k] = if den > 0.0 { 0.5 * a.dot(&b) / den } else { 0.0 };
    }
    w
}

/// Adds the cotangent Laplacian of the chart (½ uᵀ L u = E_D(u)) to `entries`, for the
/// coordinate `d` (0 = u, 1 = v) of interleaved unknowns `2i + d`.
pub(crate) fn push_laplacian(
    chart: &ChartMesh,
    pos: &[Vector3<f64>],
    d: usize,
    stride: usize,
    entries: &mut Vec<(usize, usize, f64)>,
) {
    for t in &chart.tris {
        let p = t.map(|v| pos[v as usize]);
        let w = half_cotangents(p);
        for k in 0..3 {
            let i = stride * t[(k + 1) % 3] as usize + d;
            let j = stride * t[(k + 2) % 3] as usize + d;
            entries.extend([(i, i, w[k]), (j, j, w[k]), (i, j, -w[k]), (j, i, -w[k])]);
        }
    }
}

/// The two pinned vertices: a double farthest-point sweep over the boundary, in 3D.
fn pins(chart: &ChartMesh, pos: &[Vector3<f64>]) -> Option<(usize, usize)> {
    let b: Vec<usize> = chart.boundary.iter().map(|e| e[0] as usize).collect();
    let far = |from: usize| {
        let mut best = (from, -1.0);
        for &v in &b {
            let d = (pos[v] - pos[from]).norm_squared();
            if d > best.1 {
                best = (v, d);
            }
        }
        best.0
    };
    let p = far(*b.first()?);
    let q = far(p);
    (p != q && (pos[p] - pos[q]).norm() > 0.0).then_some((p, q))
}

/// The LSCM flattening of a disk chart (see the module documentation). `pos` are the chart
/// vertices' positions.
pub(crate) fn lscm(chart: &ChartMesh, pos: &[Vector3<f64>]) -> Result<Vec<Vector2<f64>>> {
    let n = chart.num_vertices();
    if chart.tris.len() == 1 {
        let t = chart.tris[0];
        let q = local_frame(t.map(|v| pos[v as usize]));
        let mut uv = vec![Vector2::zeros(); n];
        for c in 0..3 {
            uv[t[c] as usize] = q[c];
        }
        return Ok(uv);
    }
    let (p, q) = pins(chart, pos).ok_or_else(|| Error::Numerical {
        stage: "layout (LSCM)",
        message: "the chart has no two distinct boundary vertices to pin".into(),
    })?;
    let mut entries = Vec::with_capacity(chart.tris.len() * 24 + chart.boundary.len() * 4);
    push_laplacian(chart, pos, 0, 2, &mut entries);
    push_laplacian(chart, pos, 1, 2, &mut entries);
    // −A(x): the boundary's shoelace sum, edges counter-clockwise around the chart (Eq. L3).
    for &[i, j] in &chart.boundary {
        let (ui, vi, uj, vj) =
            (2 * i as usize, 2 * i as usize + 1, 2 * j as usize, 2 * j as usize + 1);
        entries.extend([(ui, vj, -0.5), (vj, ui, -0.5), (uj, vi, 0.5), (vi, uj, 0.5)]);
    }
    let mut x = vec![0.0; 2 * n];
    let d = (pos[p] - pos[q]).norm();
    x[2 * q] = d;
    let mut idx = vec![usize::MAX; 2 * n];
    let mut m = 0;
    for (k, slot) in idx.iter_mut().enumerate() {
        if k / 2 != p && k / 2 != q {
            *slot = m;
            m += 1;
        }
    }
    let mut rhs = vec![0.0; m];
    let mut free = Vec::with_capacity(entries.len());
    for (r, c, v) in entries {
        match (idx[r], idx[c]) {
            (usize::MAX, _) => {}
            (fr, usize::MAX) => rhs[fr] -= v * x[c],
            (fr, fc) => free.push((fr, fc, v)),
        }
    }
    let spd = Spd::factor(m, free, "layout (LSCM)")?;
    let mut cols = vec![rhs];
    spd.solve(&mut cols);
    for (k, &slot) in idx.iter().enumerate() {
        if slot != usize::MAX {
            x[k] = cols[0][slot];
        }
    }
    if let Some(k) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::Numerical {
            stage: "layout (LSCM)",
            message: format!("coordinate {k} of the solution is not finite"),
        });
    }
    Ok((0..n).map(|i| Vector2::new(x[2 * i], x[2 * i + 1])).collect())
}
