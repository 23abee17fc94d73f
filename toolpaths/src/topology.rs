//! Building a [`Domain`](crate::Domain)'s derived data: per-triangle metrics, edge
//! adjacency and seam links.

use std::collections::BTreeMap;

use crate::error::{Result, ToolpathError};
use crate::geom::{Metric, Vec2, Vec3};
use crate::input::SeamPair;

/// Sentinel for "no neighbour" in [`Domain`](crate::Domain) adjacency.
pub(crate) const NONE: u32 = u32::MAX;

/// Where a boundary edge continues across a UV seam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SeamLink {
    /// Face on the other side.
    pub face: u32,
    /// UV of the two glued vertices on this side, then on the other side.
    pub from: [Vec2; 2],
    pub to: [Vec2; 2],
}

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
