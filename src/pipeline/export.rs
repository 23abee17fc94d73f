//! The export stage: the part and its grain as glTF 2.0 binary (`export.glb`,
//! docs/gltf.md) — the designed grain, or the as-brushed one with `export.as_brushed` — with
//! the scene's view and key light.

use std::path::Path;

use nalgebra::Vector3;

use super::Prepared;
use crate::appearance::LightSpec;
use crate::export::{
    export_glb, ExportInput, ExportOptions, ExportOutput, ExportSection, ViewCamera,
};
use crate::highlight::{Lighting, Symmetry};
use crate::scene::Scene;
use crate::Result;

/// What the export stage writes.
pub struct ExportStageInput<'a> {
    /// The scene (material, view, lights).
    pub scene: &'a Scene,
    /// The `export` section.
    pub section: &'a ExportSection,
    /// The part and its geometry.
    pub prepared: &'a Prepared,
    /// The grain angles shown.
    pub phi: &'a [f64],
    /// The highlight model's lighting (the key light where the edits moved it).
    pub lighting: Lighting,
    /// The strokes on the part (empty when none were traced).
    pub strokes_3d: &'a [Vec<Vector3<f64>>],
    /// The as-brushed grain per vertex, if traced.
    pub brushed_u: Option<&'a [[f64; 3]]>,
}

/// Writes the glb ([`export_glb`]).
pub fn export(x: &ExportStageInput) -> Result<ExportOutput> {
    let (scene, e, prepared) = (x.scene, x.section, x.prepared);
    let g = &prepared.field.geometry;
    let symmetry = prepared.field_options.symmetry;
    let normals: Vec<Vector3<f64>> = g.frames.iter().map(|f| f.n).collect();
    let (u, phi_e) = match (x.brushed_u, e.as_brushed) {
        (Some(b), true) => {
            let u: Vec<Vector3<f64>> = b.iter().map(|v| Vector3::from(*v)).collect();
            let phi_b = g.angles_of(&u);
            (u, phi_b)
        }
        _ => (g.directions_of(x.phi), x.phi.to_vec()),
    };
    let singular: Vec<u32> = match symmetry {
        Symmetry::Line => crate::solve::singularities::singularities(&prepared.mesh, g, &phi_e, 2)
            .iter()
            .map(|s| s.face)
            .collect(),
        Symmetry::Oriented => Vec::new(),
    };
    let input = ExportInput {
        positions: &prepared.mesh.positions,
        faces: &prepared.mesh.faces,
        normals: &normals,
        u: &u,
        symmetry,
        singular_faces: &singular,
        strokes: e.strokes.then_some(x.strokes_3d),
    };
    let name = Path::new(&prepared.mesh_name)
        .file_stem()
        .map_or_else(|| "part".to_string(), |s| s.to_string_lossy().into_owned());
    let lighting = x.lighting;
    let options = ExportOptions {
        material: scene.material.clone(),
        units: prepared.mesh.units,
        up: scene.view.up,
        name,
        camera: Some(ViewCamera {
            eye: scene.view.eye,
            target: scene.view.target,
            up: scene.view.up,
            fov_deg: scene.view.fov_deg,
        }),
        // The key light as the highlight model used it (a light edit may have moved it).
        key_light: crate::appearance::key_light_index(&scene.lights).and_then(|i| {
            match &scene.lights[i] {
                LightSpec::Directional { irradiance, .. } => {
                    Some(([lighting.light.x, lighting.light.y, lighting.light.z], *irradiance))
                }
                _ => None,
            }
        }),
    };
    export_glb(&input, &options)
}
