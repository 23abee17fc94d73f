//! Vertex-to-face incidence by a counting sort.

use super::Mesh;

/// For each vertex, the faces around it as `(face, corner)` pairs, in face order.
#[derive(Clone, Debug, Default)]
pub struct VertexFaces {
    offsets: Vec<u32>,
    entries: Vec<(u32, u8)>,
}

impl VertexFaces {
    /// Builds the vertex-to-face incidence of `mesh` (counting sort: linear time).
    pub fn new(mesh: &Mesh) -> Self {
        Self::from_faces(mesh.num_vertices(), &mesh.faces)
    }

    /// Builds the incidence of `nv` vertices from triangles.
    pub fn from_faces(nv: usize, faces: &[[u32; 3]]) -> Self {
        let mut offsets = vec![0u32; nv + 1];
        for f in faces {
            for &v in f {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..nv {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets.clone();
        let mut entries = vec![(0u32, 0u8); faces.len() * 3];
        for (fi, f) in faces.iter().enumerate() {
            for (c, &v) in f.iter().enumerate() {
                let slot = &mut fill[v as usize];
                entries[*slot as usize] = (fi as u32, c as u8);
                *slot += 1;
            }
        }
        VertexFaces { offsets, entries }
    }

    /// The start of each vertex's range in [`VertexFaces::entries`] (one more than vertices).
    #[inline]
    pub fn offsets(&self) -> &[u32] {
        &self.offsets
    }

    /// Every `(face, corner)` pair, grouped by vertex, in face order within a vertex.
    #[inline]
    pub fn entries(&self) -> &[(u32, u8)] {
        &self.entries
    }

    /// The `(face, corner)` pairs of vertex `v`.
    #[inline]
    pub fn of(&self, v: usize) -> &[(u32, u8)] {
        &self.entries[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}
