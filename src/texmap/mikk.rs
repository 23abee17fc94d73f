//! Tangent frames from the UVs, as viewers compute them when a file has no TANGENT: MikkTSpace
//! (Mikkelsen 2008), by the `bevy_mikktspace` crate, a safe Rust port that gives the same
//! results as the reference C code Blender and three.js (its WebAssembly build) run.
//!
//! The input is what a glb holds: f32 positions, f32 unit normals and the texture coordinates
//! with t growing upwards, so the sign w comes out as glTF wants it (three.js negates w when it
//! runs MikkTSpace on glTF's downward v; the bitangent B = w·(N × T) then points to +t).

use nalgebra::{Vector2, Vector3};

/// MikkTSpace tangents per face corner.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CornerFrames {
    /// Per face, per corner: (Tx, Ty, Tz, w), T unit and perpendicular to the corner's normal,
    /// w = ±1.
    pub tangents: Vec<[[f32; 4]; 3]>,
    /// Corners MikkTSpace gave no tangent (degenerate faces with no neighbour to borrow
    /// from): they take T from the face's UV Jacobian, or any perpendicular to N.
    pub fallback: usize,
}

struct Input<'a> {
    positions: &'a [Vector3<f64>],
    faces: &'a [[u32; 3]],
    normals: &'a [Vector3<f64>],
    st: &'a [[Vector2<f64>; 3]],
    out: Vec<[Option<[f32; 4]>; 3]>,
}

fn f32s(v: &Vector3<f64>) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// A unit vector in f32, renormalized in f32 (as the glb stores normals).
pub fn unit32(v: &Vector3<f64>) -> [f32; 3] {
    let w = f32s(v);
    let l = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    if l > 0.0 && l.is_finite() {
        [w[0] / l, w[1] / l, w[2] / l]
    } else {
        [0.0, 0.0, 1.0]
    }
}

impl bevy_mikktspace::Geometry for Input<'_> {
    fn num_faces(&self) -> usize {
        self.faces.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        f32s(&self.positions[self.faces[face][vert] as usize])
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        unit32(&self.normals[self.faces[face][vert] as usize])
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let p = self.st[face][vert];
        [p.x as f32, p.y as f32]
    }
    fn set_tangent(
        &mut self,
        tangent_space: Option<bevy_mikktspace::TangentSpace>,
        face: usize,
        vert: usize,
    ) {
        self.out[face][vert] = tangent_space.map(|t| t.tangent_encoded());
    }
}

/// A fallback tangent at corner `c` of face `f`: the face's ∂p/∂s made perpendicular to the
/// corner's normal, else any perpendicular; w = the sign of the face's st area.
fn fallback(input: &Input, f: usize, c: usize) -> [f32; 4] {
    let [a, b, d] = input.faces[f].map(|v| input.positions[v as usize]);
    let [sa, sb, sd] = input.st[f];
    let (e1, e2) = (sb - sa, sd - sa);
    let det = e1.perp(&e2);
    let n = input.normals[input.faces[f][c] as usize].try_normalize(1e-12).unwrap_or(Vector3::z());
    let mut t = if det != 0.0 && det.is_finite() {
        ((b - a) * e2.y - (d - a) * e1.y) / det
    } else {
        Vector3::zeros()
    };
    t -= n * n.dot(&t);
    let t = t.try_normalize(1e-12).unwrap_or_else(|| {
        let axis = if n.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        n.cross(&axis).normalize()
    });
    let w = if det < 0.0 { -1.0 } else { 1.0 };
    let t = unit32(&t);
    [t[0], t[1], t[2], w]
}

/// MikkTSpace tangents of every face corner (module docs). `normals` are per vertex; `st` per
/// face corner.
pub fn corner_frames(
    positions: &[Vector3<f64>],
    faces: &[[u32; 3]],
    normals: &[Vector3<f64>],
    st: &[[Vector2<f64>; 3]],
) -> CornerFrames {
    let mut input = Input { positions, faces, normals, st, out: vec![[None; 3]; faces.len()] };
    // MikkTSpace's only error is a mesh too large for its 32-bit indices; every corner then
    // takes the fallback.
    let _ = bevy_mikktspace::generate_tangents(&mut input);
    let mut fallback_count = 0;
    let tangents = (0..faces.len())
        .map(|f| {
            [0, 1, 2].map(|c| match input.out[f][c] {
                Some(t) if t.iter().all(|x| x.is_finite()) && t[..3].iter().any(|&x| x != 0.0) => {
                    let l = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
                    [t[0] / l, t[1] / l, t[2] / l, t[3]]
                }
                _ => {
                    fallback_count += 1;
                    fallback(&input, f, c)
                }
            })
        })
        .collect();
    CornerFrames { tangents, fallback: fallback_count }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat square with st = (x, y): T = +x, w = +1 (B = N × T = +y = +t); mirrored in s,
    /// T = −x and w = −1 (B still points to +t).
    #[test]
    fn square_frames() {
        let p = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
        ];
        let n = [Vector3::z(); 4];
        let faces = [[0, 1, 2], [2, 1, 3]];
        let st_of = |m: f64| -> Vec<[Vector2<f64>; 3]> {
            faces
                .iter()
                .map(|f| f.map(|v| Vector2::new(m * p[v as usize].x, p[v as usize].y)))
                .collect()
        };
        let fr = corner_frames(&p, &faces, &n, &st_of(1.0));
        assert_eq!(fr.fallback, 0);
        for t in fr.tangents.iter().flatten() {
            assert!((t[0] - 1.0).abs() < 1e-6 && t[3] == 1.0, "{t:?}");
        }
        let fr = corner_frames(&p, &faces, &n, &st_of(-1.0));
        for t in fr.tangents.iter().flatten() {
            assert!((t[0] + 1.0).abs() < 1e-6 && t[3] == -1.0, "{t:?}");
        }
    }
}
