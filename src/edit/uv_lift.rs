//! UV polylines lifted to 3D through the mesh's UV map (the curve tool's `uv` / `svg` curves,
//! for the fidelity measure's target).

use nalgebra::{Vector2, Vector3};

use crate::mesh::Mesh;

/// UV polylines lifted to 3D through the mesh's UV map: each polyline is subdivided (steps of a
/// quarter of the median UV edge), every point located in a UV triangle (among overlapping
/// triangles, the one whose lift is nearest the previous point, else the lowest face) and
/// lifted by its barycentric coordinates. Points outside the UV layout are dropped and split
/// the polyline, and so does a jump across a seam (a 3D step more than four times what the
/// triangles' UV Jacobians allow); pieces of fewer than two points are dropped. Empty without
/// UVs.
pub fn lift_uv_polylines(mesh: &Mesh, lines: &[Vec<Vector2<f64>>]) -> Vec<Vec<Vector3<f64>>> {
    let Some(uv) = mesh.uv.as_ref() else { return Vec::new() };
    let finite = |p: &Vector2<f64>| p.x.is_finite() && p.y.is_finite();
    let mut lo = Vector2::repeat(f64::INFINITY);
    let mut hi = Vector2::repeat(f64::NEG_INFINITY);
    for p in lines.iter().flatten().filter(|p| finite(p)) {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    if !(lo.x <= hi.x && lo.y <= hi.y) {
        return Vec::new();
    }
    // UV triangles overlapping the curves' box, with their Jacobian scale |J|_F.
    let n = mesh.num_vertices();
    let mut tris: Vec<(usize, [Vector2<f64>; 3], f64)> = Vec::new();
    let mut edges: Vec<f64> = Vec::new();
    for f in 0..mesh.num_faces() {
        if f >= uv.corners.len()
            || uv.corners[f].iter().any(|&c| c as usize >= uv.values.len())
            || mesh.faces[f].iter().any(|&v| v as usize >= n)
        {
            continue;
        }
        let t = uv.face(f);
        if !t.iter().all(finite) {
            continue;
        }
        let (a, b) = (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2]));
        if b.x < lo.x || b.y < lo.y || a.x > hi.x || a.y > hi.y {
            continue;
        }
        let [p0, p1, p2] = mesh.face_positions(f);
        let (e1, e2, d1, d2) = (p1 - p0, p2 - p0, t[1] - t[0], t[2] - t[0]);
        let det = d1.x * d2.y - d2.x * d1.y;
        if !(det.abs() > 1e-14 * (d1.norm_squared() + d2.norm_squared())) {
            continue;
        }
        let ju = (e1 * d2.y - e2 * d1.y) / det;
        let jv = (e2 * d1.x - e1 * d2.x) / det;
        let scale = (ju.norm_squared() + jv.norm_squared()).sqrt();
        if !scale.is_finite() {
            continue;
        }
        edges.push(d1.norm());
        tris.push((f, t, scale));
    }
    if tris.is_empty() {
        return Vec::new();
    }
    edges.sort_unstable_by(f64::total_cmp);
    let median_edge = edges[edges.len() / 2];
    let total: f64 = lines
        .iter()
        .flat_map(|l| l.windows(2))
        .map(|s| (s[1] - s[0]).norm())
        .filter(|d| d.is_finite())
        .sum();
    let step = (0.25 * median_edge).max(total / 200_000.0).max(1e-12);
    // A uniform grid over the triangles' UV boxes.
    let mut blo = Vector2::repeat(f64::INFINITY);
    let mut bhi = Vector2::repeat(f64::NEG_INFINITY);
    for (_, t, _) in &tris {
        for p in t {
            blo = blo.inf(p);
            bhi = bhi.sup(p);
        }
    }
    let dim = ((tris.len() as f64).sqrt().ceil() as usize).clamp(1, 1024);
    let cell = ((bhi - blo).max() / dim as f64).max(1e-15);
    let cell_of = |p: &Vector2<f64>| {
        let f = |x: f64| {
            let c = (x / cell).floor();
            if c.is_finite() && c > 0.0 {
                (c as usize).min(dim - 1)
            } else {
                0
            }
        };
        (f(p.x - blo.x), f(p.y - blo.y))
    };
    let mut cells = vec![Vec::<u32>::new(); dim * dim];
    for (k, (_, t, _)) in tris.iter().enumerate() {
        let (a, b) = (cell_of(&t[0].inf(&t[1]).inf(&t[2])), cell_of(&t[0].sup(&t[1]).sup(&t[2])));
        for j in a.1..=b.1 {
            for i in a.0..=b.0 {
                cells[j * dim + i].push(k as u32);
            }
        }
    }
    // Lift one UV point: (3D point, Jacobian scale), nearest `prev` among overlapping charts.
    let lift = |q: &Vector2<f64>, prev: Option<&Vector3<f64>>| -> Option<(Vector3<f64>, f64)> {
        if q.x < blo.x || q.y < blo.y || q.x > bhi.x || q.y > bhi.y {
            return None;
        }
        let (i, j) = cell_of(q);
        let mut best: Option<(f64, Vector3<f64>, f64)> = None;
        for &k in &cells[j * dim + i] {
            let (f, t, scale) = &tris[k as usize];
            let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], q - t[0]);
            let det = e1.x * e2.y - e1.y * e2.x;
            let v = (d.x * e2.y - d.y * e2.x) / det;
            let w = (e1.x * d.y - e1.y * d.x) / det;
            let b = [1.0 - v - w, v, w];
            if !b.iter().all(|&x| x >= -1e-9) {
                continue;
            }
            let [p0, p1, p2] = mesh.face_positions(*f);
            let p = p0 * b[0] + p1 * b[1] + p2 * b[2];
            let rank = prev.map_or(0.0, |x| (p - x).norm_squared());
            if best.as_ref().is_none_or(|x| rank < x.0) {
                best = Some((rank, p, *scale));
            }
        }
        best.map(|(_, p, s)| (p, s))
    };
    let mut out = Vec::new();
    let flush = |out: &mut Vec<Vec<Vector3<f64>>>, piece: &mut Vec<Vector3<f64>>| {
        if piece.len() >= 2 {
            out.push(std::mem::take(piece));
        }
        piece.clear();
    };
    for line in lines {
        // The subdivided polyline; `None` marks a break (a non-finite point).
        let mut points: Vec<Option<Vector2<f64>>> = Vec::new();
        for (k, s) in line.windows(2).enumerate() {
            let (a, b) = (s[0], s[1]);
            if !(finite(&a) && finite(&b)) {
                points.push(None);
                continue;
            }
            let m = ((b - a).norm() / step).ceil().clamp(1.0, 1e6) as usize;
            for j in usize::from(k > 0)..=m {
                points.push(Some(a + (b - a) * (j as f64 / m as f64)));
            }
        }
        let mut piece: Vec<Vector3<f64>> = Vec::new();
        let mut last: Option<(Vector2<f64>, Vector3<f64>, f64)> = None;
        for q in points {
            let lifted =
                q.and_then(|q| lift(&q, last.as_ref().map(|x| &x.1)).map(|(p, s)| (q, p, s)));
            match lifted {
                None => {
                    flush(&mut out, &mut piece);
                    last = None;
                }
                Some((q, p, scale)) => {
                    if let Some((q0, p0, s0)) = last {
                        let allowed = 4.0 * (q - q0).norm() * scale.max(s0);
                        if (p - p0).norm() > allowed + 1e-12 * (1.0 + p.norm()) {
                            flush(&mut out, &mut piece);
                        }
                    }
                    piece.push(p);
                    last = Some((q, p, scale));
                }
            }
        }
        flush(&mut out, &mut piece);
    }
    out
}
