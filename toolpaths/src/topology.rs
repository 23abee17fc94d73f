//! Building a [`Domain`](crate::Domain)'s derived data: per-triangle metrics, edge
//! adjacency and seam links.

use std::collections::BTreeMap;

use crate::error::{Result, ToolpathError};
use crate::geom::{Metric, Vec2, Vec3};
use crate::mesh::{SeamLink, SeamPair, NONE};

pub(crate) fn build_metric(
    uv: &[Vec2],
    tris: &[[u32; 3]],
    given: Option<Vec<Metric>>,
    positions: Option<&[Vec3]>,
) -> Result<Vec<Metric>> {
    let metric = match (given, positions) {
        (Some(m), _) => {
            if m.len() != tris.len() {
                return Err(ToolpathError::InvalidMesh(format!(
                    "{} metrics for {} triangles",
                    m.len(),
                    tris.len()
                )));
            }
            m
        }
        (None, Some(p)) => tris
            .iter()
            .map(|t| {
                Metric::from_triangle(t.map(|v| uv[v as usize]), t.map(|v| p[v as usize]))
                    .unwrap_or(Metric { e: 0.0, f: 0.0, g: 0.0 })
            })
            .collect(),
        (None, None) => vec![Metric::IDENTITY; tris.len()],
    };
    if let Some(f) = metric.iter().position(|m| !m.is_valid()) {
        return Err(ToolpathError::InvalidMesh(format!(
            "triangle {f}: first fundamental form is not positive definite (degenerate lift?)"
        )));
    }
    Ok(metric)
}

/// Adjacency across edges by sorting (min, max) vertex keys: deterministic, O(n log n).
pub(crate) fn build_adjacency(tris: &[[u32; 3]]) -> Result<Vec<[u32; 3]>> {
    let mut edges: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(tris.len() * 3);
    for (f, t) in tris.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (t[(i + 1) % 3], t[(i + 2) % 3]);
            edges.push((a.min(b), a.max(b), f as u32, i as u8));
        }
    }
    edges.sort_unstable();
    let mut nb = vec![[NONE; 3]; tris.len()];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
            j += 1;
        }
        match j - i {
            1 => {}
            2 => {
                let (e0, e1) = (edges[i], edges[i + 1]);
                nb[e0.2 as usize][e0.3 as usize] = e1.2;
                nb[e1.2 as usize][e1.3 as usize] = e0.2;
            }
            _ => {
                return Err(ToolpathError::InvalidMesh(format!(
                    "edge ({}, {}) is shared by {} triangles (non-manifold UV)",
                    edges[i].0,
                    edges[i].1,
                    j - i
                )))
            }
        }
        i = j;
    }
    Ok(nb)
}

pub(crate) fn build_seams(
    uv: &[Vec2],
    tris: &[[u32; 3]],
    nb: &[[u32; 3]],
    seams: &[SeamPair],
) -> Result<BTreeMap<(u32, u8), SeamLink>> {
    let mut out = BTreeMap::new();
    if seams.is_empty() {
        return Ok(out);
    }
    let mut boundary: BTreeMap<(u32, u32), (u32, u8)> = BTreeMap::new();
    for (f, t) in tris.iter().enumerate() {
        for i in 0..3 {
            if nb[f][i] == NONE {
                let (a, b) = (t[(i + 1) % 3], t[(i + 2) % 3]);
                boundary.insert((a.min(b), a.max(b)), (f as u32, i as u8));
            }
        }
    }
    let find = |e: [u32; 2]| {
        boundary.get(&(e[0].min(e[1]), e[0].max(e[1]))).copied().ok_or_else(|| {
            ToolpathError::InvalidMesh(format!(
                "seam edge ({}, {}) is not a boundary edge",
                e[0], e[1]
            ))
        })
    };
    for s in seams {
        let (fa, ia) = find(s.a)?;
        let (fb, ib) = find(s.b)?;
        let ua = s.a.map(|v| uv[v as usize]);
        let ub = s.b.map(|v| uv[v as usize]);
        out.insert((fa, ia), SeamLink { face: fb, from: ua, to: ub });
        out.insert((fb, ib), SeamLink { face: fa, from: ub, to: ua });
    }
    Ok(out)
}

/// Chart pairs whose UV triangles overlap: some face's centroid lies inside a face of
/// another chart (tested through the location grid's cell of the centroid).
pub(crate) fn overlapping_charts(dom: &crate::mesh::Domain) -> Vec<(usize, usize)> {
    use crate::locate::barycentric;
    let mut pairs = std::collections::BTreeSet::new();
    if dom.chart_count() < 2 {
        return Vec::new();
    }
    for f in 0..dom.tris.len() as u32 {
        let c = dom.corners(f);
        let p = [(c[0][0] + c[1][0] + c[2][0]) / 3.0, (c[0][1] + c[1][1] + c[2][1]) / 3.0];
        let cf = dom.chart[f as usize];
        for &g in dom.grid.faces_near(p) {
            let cg = dom.chart[g as usize];
            if cg == cf || pairs.contains(&(cf.min(cg), cf.max(cg))) {
                continue;
            }
            // A centroid inside or on the closed triangle: the open triangle of `f` meets
            // the chart of `g` in interior points either way.
            let b = barycentric(dom.corners(g), p);
            if b.iter().all(|&x| x >= -1e-12) {
                pairs.insert((cf.min(cg), cf.max(cg)));
            }
        }
    }
    pairs.into_iter().map(|(a, b)| (a as usize, b as usize)).collect()
}
