//! The glTF vertices: one per distinct (mesh vertex, UV, MikkTSpace tangent) of the face
//! corners, numbered in order of first appearance (face by face, corner by corner), so a vertex
//! on a UV seam, or where MikkTSpace splits a tangent, is written once per side.

use std::collections::HashMap;

use nalgebra::Vector2;

use crate::texmap::mikk::CornerFrames;

/// The glTF vertices of the part and its triangles in them.
#[derive(Clone, Debug, Default)]
pub struct GltfVertices {
    /// Per glTF vertex: the mesh vertex.
    pub vertex: Vec<u32>,
    /// Per glTF vertex: TANGENT (xyz unit, w = ±1).
    pub tangent: Vec<[f32; 4]>,
    /// Per glTF vertex: TEXCOORD_0, glTF's (s, 1 − t).
    pub texcoord: Vec<[f32; 2]>,
    /// Triangles in glTF vertices (face order kept).
    pub faces: Vec<[u32; 3]>,
    /// Mesh vertices written more than once.
    pub split_vertices: usize,
}

/// The glTF vertices of `faces` with texture coordinates `st` and tangents `frames` per
/// corner (module docs).
pub fn gltf_vertices(
    faces: &[[u32; 3]],
    st: &[[Vector2<f64>; 3]],
    frames: &CornerFrames,
    num_vertices: usize,
) -> GltfVertices {
    let mut out = GltfVertices::default();
    let mut index: HashMap<(u32, [u32; 2], [u32; 4]), u32> = HashMap::new();
    let mut copies = vec![0u32; num_vertices];
    for (f, face) in faces.iter().enumerate() {
        let mut tri = [0u32; 3];
        for c in 0..3 {
            let v = face[c];
            let t = frames.tangents[f][c];
            let tc = [st[f][c].x as f32, (1.0 - st[f][c].y) as f32];
            let key = (v, tc.map(f32::to_bits), t.map(f32::to_bits));
            tri[c] = *index.entry(key).or_insert_with(|| {
                out.vertex.push(v);
                out.tangent.push(t);
                out.texcoord.push(tc);
                copies[v as usize] += 1;
                (out.vertex.len() - 1) as u32
            });
        }
        out.faces.push(tri);
    }
    out.split_vertices = copies.iter().filter(|&&c| c > 1).count();
    out
}
