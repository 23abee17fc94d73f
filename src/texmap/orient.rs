//! Per-vertex tangents for a glTF viewer, which interpolates TANGENT linearly across a triangle.
//!
//! A line field (k = 2) is defined up to sign at every vertex: a triangle whose corners carry
//! u and −u would interpolate through zero and turn the lobe by 90° inside the face. So every
//! triangle is oriented on its own and the mesh vertices are split where neighbouring triangles
//! chose opposite signs (docs/gltf.md, "Tangents"):
//!
//! 1. Edge signs σ_ab = sign(u_a · u_b) (+ on a tie): the sign that makes the two corners of an
//!    edge agree. A face is *consistent* when σ_ab σ_bc σ_ca = +1: then signs (1, σ_ab, σ_ac)
//!    make all three pairs agree.
//! 2. Faces that are not consistent (the line field turns by about π around them), and the
//!    given singular faces (non-zero index, `highlight::singularities`), get three vertices of their
//!    own, so their turn does not leak into the neighbours.
//! 3. The global sign ε_f of every consistent face is chosen by a breadth-first walk over the
//!    faces (in face order, through shared edges, between consistent faces), so that the shared
//!    corners agree. Where two walks meet with opposite signs (a cut out of a half-integer
//!    singularity) the vertex is split: each mesh vertex has at most one copy per sign plus one
//!    per isolated face using it.
//!
//! For an oriented field (k = 1) nothing is split: TANGENT = u at every vertex.

use std::collections::VecDeque;

use nalgebra::Vector3;

/// The split mesh: every output vertex is a mesh vertex with a sign of its u.
#[derive(Clone, Debug, Default)]
pub struct Oriented {
    /// Per output vertex: the mesh vertex.
    pub vertex: Vec<u32>,
    /// Per output vertex: +1 or −1, the sign of u.
    pub sign: Vec<f64>,
    /// Triangles in output vertices (face order kept).
    pub faces: Vec<[u32; 3]>,
    /// Faces that could not be oriented consistently or are singular (given vertices of their
    /// own).
    pub isolated_faces: usize,
    /// Mesh vertices with more than one output vertex.
    pub split_vertices: usize,
}

/// Orients the line field `u` (k = 2) per triangle and splits vertices (module docs). `singular`
/// lists faces to isolate in any case.
pub fn orient_line_field(faces: &[[u32; 3]], u: &[Vector3<f64>], singular: &[u32]) -> Oriented {
    let nf = faces.len();
    let edge_sign = |a: u32, b: u32| -> f64 {
        if u[a as usize].dot(&u[b as usize]) >= 0.0 {
            1.0
        } else {
            -1.0
        }
    };
    // Corner signs relative to corner 0, and consistency.
    let mut isolated = vec![false; nf];
    let mut rel = vec![[1.0f64; 3]; nf];
    for (f, t) in faces.iter().enumerate() {
        let s01 = edge_sign(t[0], t[1]);
        let s02 = edge_sign(t[0], t[2]);
        let s12 = edge_sign(t[1], t[2]);
        rel[f] = [1.0, s01, s02];
        if s01 * s12 * s02 < 0.0 {
            isolated[f] = true;
        }
    }
    for &f in singular {
        if let Some(x) = isolated.get_mut(f as usize) {
            *x = true;
        }
    }
    // Faces around each undirected edge, for the walk.
    let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * nf);
    for (f, t) in faces.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            edges.push((a.min(b), a.max(b), f as u32));
        }
    }
    edges.sort_unstable();
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); nf];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i;
        while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
            j += 1;
        }
        for x in i..j {
            for y in i..j {
                if x != y {
                    neighbours[edges[x].2 as usize].push(edges[y].2);
                }
            }
        }
        i = j;
    }
    // Global sign per consistent face by breadth-first walks.
    let mut eps = vec![0.0f64; nf];
    let corner_sign = |f: usize, v: u32, eps: &[f64], rel: &[[f64; 3]]| -> Option<f64> {
        faces[f].iter().position(|&w| w == v).map(|c| eps[f] * rel[f][c])
    };
    let mut queue = VecDeque::new();
    for start in 0..nf {
        if isolated[start] || eps[start] != 0.0 {
            continue;
        }
        eps[start] = 1.0;
        queue.push_back(start);
        while let Some(f) = queue.pop_front() {
            for &g in &neighbours[f] {
                let g = g as usize;
                if isolated[g] || eps[g] != 0.0 {
                    continue;
                }
                // A shared vertex of f and g.
                let Some(&v) = faces[g].iter().find(|v| faces[f].contains(v)) else { continue };
                let sf = corner_sign(f, v, &eps, &rel).unwrap_or(1.0);
                let cg = faces[g].iter().position(|&w| w == v).unwrap_or(0);
                eps[g] = sf * rel[g][cg];
                queue.push_back(g);
            }
        }
    }
    // Output vertices: (mesh vertex, sign) shared by consistent faces; isolated faces' own.
    let nv = u.len();
    let mut slot = vec![[u32::MAX; 2]; nv];
    let mut copies = vec![0u32; nv];
    let mut out = Oriented::default();
    for (f, t) in faces.iter().enumerate() {
        let mut tri = [0u32; 3];
        for c in 0..3 {
            let v = t[c];
            let s = if isolated[f] { rel[f][c] } else { eps[f] * rel[f][c] };
            let new = |out: &mut Oriented| {
                out.vertex.push(v);
                out.sign.push(s);
                (out.vertex.len() - 1) as u32
            };
            tri[c] = if isolated[f] {
                copies[v as usize] += 1;
                new(&mut out)
            } else {
                let k = usize::from(s < 0.0);
                if slot[v as usize][k] == u32::MAX {
                    slot[v as usize][k] = new(&mut out);
                    copies[v as usize] += 1;
                }
                slot[v as usize][k]
            };
        }
        out.faces.push(tri);
    }
    out.isolated_faces = isolated.iter().filter(|&&x| x).count();
    out.split_vertices = copies.iter().filter(|&&c| c > 1).count();
    out
}

/// The identity orientation (k = 1): output vertex i is mesh vertex i with sign +1.
pub fn identity(faces: &[[u32; 3]], nv: usize) -> Oriented {
    Oriented {
        vertex: (0..nv as u32).collect(),
        sign: vec![1.0; nv],
        faces: faces.to_vec(),
        isolated_faces: 0,
        split_vertices: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing an edge, u and −u at alternating vertices of a uniform field: no
    /// triangle interpolates opposite tangents and nothing is split.
    #[test]
    fn sign_flips_are_undone_without_splitting() {
        let faces = [[0, 1, 2], [2, 1, 3]];
        let x = Vector3::x();
        let u = [x, -x, x, -x];
        let o = orient_line_field(&faces, &u, &[]);
        assert_eq!(o.vertex.len(), 4);
        assert_eq!(o.split_vertices, 0);
        for t in &o.faces {
            let d: Vec<Vector3<f64>> =
                t.iter().map(|&k| u[o.vertex[k as usize] as usize] * o.sign[k as usize]).collect();
            assert!(d[0].dot(&d[1]) > 0.0 && d[0].dot(&d[2]) > 0.0 && d[1].dot(&d[2]) > 0.0);
        }
    }

    /// A half-turn (index ½) around the centre of a fan: the directions of the six rim
    /// vertices turn by π/2 between neighbours' doubled angles, so the walk meets itself with
    /// opposite signs; the mismatch is resolved by splitting, never by an opposite pair.
    #[test]
    fn half_turn_fan_is_split() {
        // Centre 0, rim 1..=8 at angles θ_i; u at angle θ/2 (a ½-index line field).
        let n = 8;
        let mut u = vec![Vector3::new(0.0, 0.0, 0.0)];
        let mut faces = Vec::new();
        for i in 0..n {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            u.push(Vector3::new((t / 2.0).cos(), (t / 2.0).sin(), 0.0));
            faces.push([0, 1 + i as u32, 1 + ((i + 1) % n) as u32]);
        }
        // The centre vertex has no direction: give it the first rim's.
        u[0] = u[1];
        let o = orient_line_field(&faces, &u, &[]);
        let mut opposite = 0;
        for t in &o.faces {
            let d: Vec<Vector3<f64>> =
                t.iter().map(|&k| u[o.vertex[k as usize] as usize] * o.sign[k as usize]).collect();
            if d[1].dot(&d[2]) < 0.0 || d[0].dot(&d[1]) < 0.0 || d[0].dot(&d[2]) < 0.0 {
                opposite += 1;
            }
        }
        // Only the isolated (inconsistent) faces may hold an opposite pair.
        assert!(opposite <= o.isolated_faces, "{opposite} > {}", o.isolated_faces);
        assert!(o.split_vertices >= 1, "the walk around the singularity must split");
    }
}
