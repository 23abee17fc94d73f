//! UV polylines lifted to 3D through the mesh's UV map (the curve tool's `uv` / `svg` curves,
//! for the fidelity measure's target).

use nalgebra::{Vector2, Vector3};

use crate::mesh::{CornerAttribute, Mesh};

/// A UV triangle of the mesh: its face, its UV corners and its Jacobian scale |J|_F.
type UvTriangle = (usize, [Vector2<f64>; 3], f64);

/// Whether both coordinates of `p` are finite.
fn finite(p: &Vector2<f64>) -> bool {
    p.x.is_finite() && p.y.is_finite()
}

/// The bounding box of the polylines' finite points, or `None` when there is none.
fn curves_box(lines: &[Vec<Vector2<f64>>]) -> Option<(Vector2<f64>, Vector2<f64>)> {
    let mut lo = Vector2::repeat(f64::INFINITY);
    let mut hi = Vector2::repeat(f64::NEG_INFINITY);
    for p in lines.iter().flatten().filter(|p| finite(p)) {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    if !(lo.x <= hi.x && lo.y <= hi.y) {
        return None;
    }
    Some((lo, hi))
}

/// The valid, non-degenerate UV triangles of `mesh` whose UV box overlaps `[lo, hi]`, in face
/// order, and the UV length of each one's first edge.
fn overlapping_triangles(
    mesh: &Mesh,
    uv: &CornerAttribute<Vector2<f64>>,
    lo: Vector2<f64>,
    hi: Vector2<f64>,
) -> (Vec<UvTriangle>, Vec<f64>) {
    // UV triangles overlapping the curves' box, with their Jacobian scale |J|_F.
    let n = mesh.num_vertices();
    let mut tris: Vec<UvTriangle> = Vec::new();
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
    (tris, edges)
}

/// The subdivision step: a quarter of the median UV edge, at least the polylines' total length
/// over 200 000 (and 1e-12). `edges` must not be empty.
fn subdivision_step(mut edges: Vec<f64>, lines: &[Vec<Vector2<f64>>]) -> f64 {
    edges.sort_unstable_by(f64::total_cmp);
    let median_edge = edges[edges.len() / 2];
    let total: f64 = lines
        .iter()
        .flat_map(|l| l.windows(2))
        .map(|s| (s[1] - s[0]).norm())
        .filter(|d| d.is_finite())
        .sum();
    (0.25 * median_edge).max(total / 200_000.0).max(1e-12)
}

/// A uniform grid over the triangles' UV boxes, for locating UV points.
struct UvGrid<'a> {
    mesh: &'a Mesh,
    tris: Vec<UvTriangle>,
    blo: Vector2<f64>,
    bhi: Vector2<f64>,
    dim: usize,
    cell: f64,
    /// Per cell (row-major), the indices into `tris` of the triangles whose box meets it.
    cells: Vec<Vec<u32>>,
}

impl<'a> UvGrid<'a> {
    fn new(mesh: &'a Mesh, tris: Vec<UvTriangle>) -> Self {
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
        let mut grid = UvGrid { mesh, tris, blo, bhi, dim, cell, cells: Vec::new() };
        let mut cells = vec![Vec::<u32>::new(); dim * dim];
        for (k, (_, t, _)) in grid.tris.iter().enumerate() {
            let (a, b) = (
                grid.cell_of(&t[0].inf(&t[1]).inf(&t[2])),
                grid.cell_of(&t[0].sup(&t[1]).sup(&t[2])),
            );
            for j in a.1..=b.1 {
                for i in a.0..=b.0 {
                    cells[j * dim + i].push(k as u32);
                }
            }
        }
        grid.cells = cells;
        grid
    }

    /// The (column, row) of the cell holding `p`, clamped to the grid.
    fn cell_of(&self, p: &Vector2<f64>) -> (usize, usize) {
        let f = |x: f64| {
            let c = (x / self.cell).floor();
            if c.is_finite() && c > 0.0 {
                (c as usize).min(self.dim - 1)
            } else {
                0
            }
        };
        (f(p.x - self.blo.x), f(p.y - self.blo.y))
    }

    /// Lift one UV point: (3D point, Jacobian scale), nearest `prev` among overlapping charts.
    fn lift(&self, q: &Vector2<f64>, prev: Option<&Vector3<f64>>) -> Option<(Vector3<f64>, f64)> {
        let (blo, bhi) = (self.blo, self.bhi);
        if q.x < blo.x || q.y < blo.y || q.x > bhi.x || q.y > bhi.y {
            return None;
        }
        let (i, j) = self.cell_of(q);
        let mut best: Option<(f64, Vector3<f64>, f64)> = None;
        for &k in &self.cells[j * self.dim + i] {
            let (f, t, scale) = &self.tris[k as usize];
            let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], q - t[0]);
            let det = e1.x * e2.y - e1.y * e2.x;
            let v = (d.x * e2.y - d.y * e2.x) / det;
            let w = (e1.x * d.y - e1.y * d.x) / det;
            let b = [1.0 - v - w, v, w];
            if !b.iter().all(|&x| x >= -1e-9) {
                continue;
            }
            let [p0, p1, p2] = self.mesh.face_positions(*f);
            let p = p0 * b[0] + p1 * b[1] + p2 * b[2];
            let rank = prev.map_or(0.0, |x| (p - x).norm_squared());
            if best.as_ref().is_none_or(|x| rank < x.0) {
                best = Some((rank, p, *scale));
            }
        }
        best.map(|(_, p, s)| (p, s))
    }
}

/// The polyline subdivided in steps of at most `step`; `None` marks a break (a non-finite
/// point).
fn subdivide(line: &[Vector2<f64>], step: f64) -> Vec<Option<Vector2<f64>>> {
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
    points
}

/// Moves `piece` to `out` when it has at least two points; leaves it empty.
fn flush(out: &mut Vec<Vec<Vector3<f64>>>, piece: &mut Vec<Vector3<f64>>) {
    if piece.len() >= 2 {
        out.push(std::mem::take(piece));
    }
    piece.clear();
}

/// Lifts the subdivided `points` of one polyline through `grid` and appends the pieces to
/// `out`, splitting at breaks, at points outside the layout and at seam jumps.
fn lift_points(
    grid: &UvGrid<'_>,
    points: Vec<Option<Vector2<f64>>>,
    out: &mut Vec<Vec<Vector3<f64>>>,
) {
    let mut piece: Vec<Vector3<f64>> = Vec::new();
    let mut last: Option<(Vector2<f64>, Vector3<f64>, f64)> = None;
    for q in points {
        let lifted =
            q.and_then(|q| grid.lift(&q, last.as_ref().map(|x| &x.1)).map(|(p, s)| (q, p, s)));
        match lifted {
            None => {
                flush(out, &mut piece);
                last = None;
            }
            Some((q, p, scale)) => {
                if let Some((q0, p0, s0)) = last {
                    let allowed = 4.0 * (q - q0).norm() * scale.max(s0);
                    if (p - p0).norm() > allowed + 1e-12 * (1.0 + p.norm()) {
                        flush(out, &mut piece);
                    }
                }
                piece.push(p);
                last = Some((q, p, scale));
            }
        }
    }
    flush(out, &mut piece);
}

/// UV polylines lifted to 3D through the mesh's UV map: each polyline is subdivided (steps of a
/// quarter of the median UV edge), every point located in a UV triangle (among overlapping
/// triangles, the one whose lift is nearest the previous point, else the lowest face) and
/// lifted by its barycentric coordinates. Points outside the UV layout are dropped and split
/// the polyline, and so does a jump across a seam (a 3D step more than four times what the
/// triangles' UV Jacobians allow); pieces of fewer than two points are dropped. Empty without
/// UVs.
pub fn lift_uv_polylines(mesh: &Mesh, lines: &[Vec<Vector2<f64>>]) -> Vec<Vec<Vector3<f64>>> {
    let Some(uv) = mesh.uv.as_ref() else { return Vec::new() };
    let Some((lo, hi)) = curves_box(lines) else { return Vec::new() };
    let (tris, edges) = overlapping_triangles(mesh, uv, lo, hi);
    if tris.is_empty() {
        return Vec::new();
    }
    let step = subdivision_step(edges, lines);
    let grid = UvGrid::new(mesh, tris);
    let mut out = Vec::new();
    for line in lines {
        lift_points(&grid, subdivide(line, step), &mut out);
    }
    out
}
