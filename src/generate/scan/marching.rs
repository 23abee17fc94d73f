//! Marching tetrahedra over an implicit surface, as a scanner's mesher meshes its volume: the
//! grid's cubes each split into the six tetrahedra of the Kuhn (Freudenthal) triangulation
//! around their main diagonal, one vertex per grid edge the surface crosses.
//!
//! The Kuhn triangulation is the same in every cube, so neighbouring tetrahedra share their
//! faces and the surface's pieces meet edge to edge: the mesh is closed and 2-manifold wherever
//! the implicit is positive on the grid's border. Triangles are oriented from the tetrahedra's
//! combinatorics (never from a geometric test), counter-clockwise around the direction in
//! which the implicit grows. A vertex lies where the implicit is zero along its edge (two
//! Illinois steps from the linear guess), kept within 2 % of the edge's ends so that no two
//! vertices coincide.

use std::collections::HashMap;

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::mesh::Mesh;
use crate::{Error, Result};

type V3 = Vector3<f64>;

/// Most grid nodes [`polygonize`] evaluates (a 400³ grid).
pub const MAX_NODES: usize = 64_000_000;

/// Share of an edge kept between a vertex and the edge's ends.
const END_MARGIN: f64 = 0.02;

/// The six tetrahedra of a cube in the Kuhn triangulation, as cube-corner bits (x = 1, y = 2,
/// z = 4): the monotone paths from corner 0 to corner 7, one per order of the three axes.
const KUHN: [[usize; 4]; 6] =
    [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// Even permutations of a tetrahedron's corners that bring corner `m` first.
const FIRST: [[usize; 4]; 4] = [[0, 1, 2, 3], [1, 0, 3, 2], [2, 0, 1, 3], [3, 0, 2, 1]];

/// The grid the implicit is sampled on.
struct Grid {
    lo: V3,
    cell: f64,
    n: [usize; 3],
}

impl Grid {
    fn node(&self, id: usize) -> V3 {
        let (i, j, k) =
            (id % self.n[0], (id / self.n[0]) % self.n[1], id / (self.n[0] * self.n[1]));
        self.lo + V3::new(i as f64, j as f64, k as f64) * self.cell
    }

    fn id(&self, i: usize, j: usize, k: usize) -> usize {
        (k * self.n[1] + j) * self.n[0] + i
    }

    fn on_border(&self, id: usize) -> bool {
        let (i, j, k) =
            (id % self.n[0], (id / self.n[0]) % self.n[1], id / (self.n[0] * self.n[1]));
        i == 0 || j == 0 || k == 0 || i + 1 == self.n[0] || j + 1 == self.n[1] || k + 1 == self.n[2]
    }
}

/// The surface `f = 0` inside the box `[lo, hi]` (grown by two cells), sampled on cubes of
/// edge `cell`; `f < 0` inside the solid. Fails when the grid would pass [`MAX_NODES`], when
/// `f` is not finite or not positive on the grid's border (the surface leaves the box), or
/// when the surface misses every node.
pub fn polygonize(f: &(dyn Fn(&V3) -> f64 + Sync), lo: V3, hi: V3, cell: f64) -> Result<Mesh> {
    if !(cell.is_finite() && cell > 0.0) {
        return Err(Error::invalid_arg("cell", format!("must be a positive number, not {cell}")));
    }
    let lo = lo - V3::repeat(2.0 * cell);
    let span = (hi + V3::repeat(2.0 * cell) - lo) / cell;
    let n = [0, 1, 2].map(|a| span[a].ceil().max(1.0) as usize + 1);
    let total = n[0].saturating_mul(n[1]).saturating_mul(n[2]);
    if !span.iter().all(|s| s.is_finite()) || total > MAX_NODES {
        return Err(Error::invalid_arg(
            "cell",
            format!("a grid of {n:?} nodes passes the limit of {MAX_NODES}: choose a larger cell"),
        ));
    }
    let grid = Grid { lo, cell, n };
    let values: Vec<f64> = (0..total).into_par_iter().map(|id| f(&grid.node(id))).collect();
    if let Some(id) = (0..total).find(|&id| !values[id].is_finite()) {
        return Err(Error::invalid_arg("surface", format!("not finite at {:?}", grid.node(id))));
    }
    if let Some(id) = (0..total).find(|&id| grid.on_border(id) && values[id] <= 0.0) {
        return Err(Error::invalid_arg(
            "surface",
            format!("reaches the grid's border at {:?}", grid.node(id)),
        ));
    }
    let mut out = Builder {
        grid: &grid,
        values: &values,
        f,
        index: HashMap::new(),
        positions: Vec::new(),
        faces: Vec::new(),
    };
    for k in 0..n[2] - 1 {
        for j in 0..n[1] - 1 {
            for i in 0..n[0] - 1 {
                out.cube(i, j, k);
            }
        }
    }
    if out.faces.is_empty() {
        return Err(Error::invalid_arg(
            "surface",
            "crosses no edge of the grid: choose a smaller cell",
        ));
    }
    Ok(Mesh::from_triangles(out.positions, out.faces))
}

/// The mesh being built: one vertex per crossed grid edge.
struct Builder<'a> {
    grid: &'a Grid,
    values: &'a [f64],
    f: &'a (dyn Fn(&V3) -> f64 + Sync),
    index: HashMap<(u32, u32), u32>,
    positions: Vec<V3>,
    faces: Vec<[u32; 3]>,
}

impl Builder<'_> {
    fn cube(&mut self, i: usize, j: usize, k: usize) {
        let corner = |b: usize| self.grid.id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        let ids: [usize; 8] = std::array::from_fn(corner);
        let inside: [bool; 8] = std::array::from_fn(|b| self.values[ids[b]] < 0.0);
        if inside.iter().all(|&x| x) || inside.iter().all(|&x| !x) {
            return;
        }
        for tet in KUHN {
            // Kuhn tetrahedra with an odd axis order are negatively oriented: swap two corners.
            let t = if positive(tet) { tet } else { [tet[0], tet[1], tet[3], tet[2]] };
            self.tetrahedron(t.map(|b| ids[b]), t.map(|b| inside[b]));
        }
    }

    /// One positively oriented tetrahedron.
    fn tetrahedron(&mut self, v: [usize; 4], inside: [bool; 4]) {
        let count = inside.iter().filter(|&&x| x).count();
        match count {
            1 | 3 => {
                // The lone corner first, orientation kept; the triangle faces away from it.
                let m = (0..4).find(|&m| inside[m] == (count == 1)).unwrap_or(0);
                let p = FIRST[m].map(|c| v[c]);
                let e = [self.vertex(p[0], p[1]), self.vertex(p[0], p[2]), self.vertex(p[0], p[3])];
                self.faces.push(if count == 1 { e } else { [e[0], e[2], e[1]] });
            }
            2 => {
                // The two inside corners first, orientation kept.
                let mut order: Vec<usize> = (0..4).filter(|&c| inside[c]).collect();
                order.extend((0..4).filter(|&c| !inside[c]));
                if permutation_odd(&order) {
                    order.swap(2, 3);
                }
                let p = [v[order[0]], v[order[1]], v[order[2]], v[order[3]]];
                let (a, b) = (self.vertex(p[0], p[2]), self.vertex(p[0], p[3]));
                let (c, d) = (self.vertex(p[1], p[3]), self.vertex(p[1], p[2]));
                self.faces.push([a, b, c]);
                self.faces.push([a, c, d]);
            }
            _ => {}
        }
    }

    /// The vertex on grid edge (a, b), created the first time it is asked for.
    fn vertex(&mut self, a: usize, b: usize) -> u32 {
        let key = (a.min(b) as u32, a.max(b) as u32);
        if let Some(&v) = self.index.get(&key) {
            return v;
        }
        let p = self.crossing(a, b);
        self.positions.push(p);
        let v = (self.positions.len() - 1) as u32;
        self.index.insert(key, v);
        v
    }

    /// Where `f` is zero between nodes a and b (one inside, one not): the linear guess, two
    /// Illinois steps, kept [`END_MARGIN`] from the ends.
    fn crossing(&self, a: usize, b: usize) -> V3 {
        let (pa, pb) = (self.grid.node(a), self.grid.node(b));
        let (mut t0, mut t1) = (0.0, 1.0);
        let (mut f0, mut f1) = (self.values[a], self.values[b]);
        let mut t = f0 / (f0 - f1);
        for _ in 0..2 {
            let ft = (self.f)(&(pa + (pb - pa) * t));
            if !ft.is_finite() || ft == 0.0 {
                break;
            }
            if (ft < 0.0) == (f0 < 0.0) {
                (t0, f0) = (t, ft);
                f1 *= 0.5;
            } else {
                (t1, f1) = (t, ft);
                f0 *= 0.5;
            }
            t = t0 + (t1 - t0) * f0 / (f0 - f1);
        }
        let t = if t.is_finite() { t } else { 0.5 };
        pa + (pb - pa) * t.clamp(END_MARGIN, 1.0 - END_MARGIN)
    }
}

/// Whether a Kuhn tetrahedron (cube-corner bits) has a positive orientation.
fn positive(t: [usize; 4]) -> bool {
    let p = t.map(|b| V3::new((b & 1) as f64, ((b >> 1) & 1) as f64, ((b >> 2) & 1) as f64));
    (p[1] - p[0]).cross(&(p[2] - p[0])).dot(&(p[3] - p[0])) > 0.0
}

/// Whether a permutation of 0..4 is odd.
fn permutation_odd(p: &[usize]) -> bool {
    let mut inversions = 0;
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            inversions += (p[i] > p[j]) as usize;
        }
    }
    inversions % 2 == 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sphere_is_closed_and_outward() {
        let m = polygonize(&|p: &V3| p.norm() - 10.0, V3::repeat(-10.0), V3::repeat(10.0), 1.3)
            .unwrap();
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for f in &m.faces {
            for k in 0..3 {
                *edges.entry((f[k], f[(k + 1) % 3])).or_default() += 1;
            }
        }
        // Every directed edge once, and its reverse once: closed and consistently oriented.
        assert!(edges.iter().all(|(&(a, b), &c)| c == 1 && edges.get(&(b, a)) == Some(&1)));
        let volume: f64 = m
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| m.positions[i as usize]);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum();
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 1000.0;
        assert!((volume - exact).abs() < 0.02 * exact, "{volume} vs {exact}");
        // On the surface, but for the vertices kept 2 % of a grid edge (at most a cube's
        // diagonal, 1.3·√3) from its ends.
        let off: Vec<f64> = m.positions.iter().map(|p| (p.norm() - 10.0).abs()).collect();
        assert!(off.iter().all(|&d| d < END_MARGIN * 1.3 * 3f64.sqrt()));
        let mut sorted = off.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        assert!(median < 1e-2, "median {median}; p90 {}", sorted[sorted.len() * 9 / 10]);
    }

    #[test]
    fn a_surface_leaving_the_grid_is_refused() {
        let r = polygonize(&|p: &V3| p.z, V3::repeat(-1.0), V3::repeat(1.0), 0.5);
        assert!(r.is_err());
    }
}
