//! The mesh's angles and sharp edges for `grainline inspect` ([`QualityReport`]): the face
//! angles and the creases of [`super::normals::corner_normals`].

use super::normals::{self, DEFAULT_CREASE_ANGLE_DEG};
use crate::mesh::load::LoadedMesh;
use crate::mesh::report::{face_name, QualityReport, SLIVER_ANGLE_DEG};

impl QualityReport {
    /// Angles and creases of a loaded mesh.
    pub fn new(loaded: &LoadedMesh) -> Self {
        let mesh = &loaded.mesh;
        let fd = normals::face_data(mesh);
        let mut min = (f64::INFINITY, 0usize);
        let mut slivers = 0;
        for (f, d) in fd.iter().enumerate() {
            let a = d.angles.iter().copied().fold(f64::INFINITY, f64::min).to_degrees();
            if a < min.0 {
                min = (a, f);
            }
            slivers += usize::from(a < SLIVER_ANGLE_DEG);
        }
        let vf = crate::mesh::VertexFaces::new(mesh);
        let vn = vec![nalgebra::Vector3::zeros(); mesh.num_vertices()];
        let c = normals::corner_normals(mesh, &vf, &fd, &vn, DEFAULT_CREASE_ANGLE_DEG);
        let patches = super::patches::patches(mesh, DEFAULT_CREASE_ANGLE_DEG);
        let split = super::patches::split_patches(mesh, &patches);
        QualityReport {
            min_angle_deg: if min.0.is_finite() { min.0 } else { 0.0 },
            min_angle_face: face_name(&loaded.report, min.1),
            sliver_angle_deg: SLIVER_ANGLE_DEG,
            slivers,
            crease_angle_deg: DEFAULT_CREASE_ANGLE_DEG,
            crease_edges: c.crease_edges,
            split_vertices: c.split_vertices,
            patches: patches.count,
            patch_copies: split.map_or(0, |s| s.copies_of.len()),
        }
    }
}
