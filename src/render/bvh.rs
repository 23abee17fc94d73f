//! A bounding-volume hierarchy over the triangles, for shadow rays (any-hit queries).
//!
//! Built by recursive median splits of the centroids along the longest axis (deterministic);
//! leaves hold at most [`LEAF`] triangles. Built only when shadows are asked for.

use nalgebra::Vector3;

const LEAF: usize = 4;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Leaf: first triangle in `order`; inner: index of the right child (left is next).
    start: u32,
    /// Leaf: triangle count; inner: 0.
    count: u32,
}

/// The hierarchy.
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    tris: Vec<[Vector3<f64>; 3]>,
}

impl Bvh {
    /// Builds the hierarchy of a triangle mesh.
    pub fn build(positions: &[Vector3<f64>], faces: &[[u32; 3]]) -> Self {
        let tris: Vec<[Vector3<f64>; 3]> =
            faces.iter().map(|f| f.map(|i| positions[i as usize])).collect();
        let centroids: Vec<Vector3<f64>> =
            tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF + 1);
        if !tris.is_empty() {
            build_node(&tris, &centroids, &mut order, 0, &mut nodes);
        }
        Bvh { nodes, order, tris }
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// True if the segment `origin + t·dir`, 0 < t < `t_max`, hits any triangle.
    pub fn occluded(&self, origin: &Vector3<f64>, dir: &Vector3<f64>, t_max: f64) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let inv = dir.map(|d| 1.0 / d);
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let idx = stack[sp] as usize;
            let node = &self.nodes[idx];
            if !hit_box(node, origin, &inv, t_max) {
                continue;
            }
            if node.count > 0 {
                let s = node.start as usize;
                for &t in &self.order[s..s + node.count as usize] {
                    if hit_tri(&self.tris[t as usize], origin, dir, t_max) {
                        return true;
                    }
                }
            } else if sp + 2 <= stack.len() {
                // The left child immediately follows its parent; `start` is the right child.
                stack[sp] = node.start;
                stack[sp + 1] = idx as u32 + 1;
                sp += 2;
            }
        }
        false
    }
}

fn build_node(
    tris: &[[Vector3<f64>; 3]],
    cen: &[Vector3<f64>],
    order: &mut [u32],
    offset: usize,
    nodes: &mut Vec<Node>,
) -> usize {
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    let (mut clo, mut chi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for &t in order.iter() {
        for p in &tris[t as usize] {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let c = cen[t as usize];
        for a in 0..3 {
            clo[a] = clo[a].min(c[a]);
            chi[a] = chi[a].max(c[a]);
        }
    }
    let me = nodes.len();
    nodes.push(Node { lo, hi, start: offset as u32, count: order.len() as u32 });
    if order.len() <= LEAF {
        return me;
    }
    let axis = (0..3).max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b]))).unwrap_or(0);
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        cen[a as usize][axis].total_cmp(&cen[b as usize][axis]).then(a.cmp(&b))
    });
    let (left, right) = order.split_at_mut(mid);
    build_node(tris, cen, left, offset, nodes);
    let r = build_node(tris, cen, right, offset + mid, nodes);
    nodes[me].start = r as u32;
    nodes[me].count = 0;
    me
}

fn hit_box(n: &Node, o: &Vector3<f64>, inv: &Vector3<f64>, t_max: f64) -> bool {
    let (mut t0, mut t1) = (0.0f64, t_max);
    for a in 0..3 {
        let mut ta = (n.lo[a] - o[a]) * inv[a];
        let mut tb = (n.hi[a] - o[a]) * inv[a];
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        // NaN (0 · ∞ on a slab face) leaves the interval unchanged.
        if ta > t0 {
            t0 = ta;
        }
        if tb < t1 {
            t1 = tb;
        }
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Möller–Trumbore.
fn hit_tri(t: &[Vector3<f64>; 3], o: &Vector3<f64>, d: &Vector3<f64>, t_max: f64) -> bool {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(&e2);
    let det = e1.dot(&p);
    if det.abs() < 1e-18 {
        return false;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(&p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(&e1);
    let v = d.dot(&q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let tt = e2.dot(&q) * inv;
    tt > 0.0 && tt < t_max
}
