//! The export stage: the part and its grain as glTF 2.0 binary (`export.glb`,
//! docs/gltf.md) — the designed grain, or the as-brushed one with `export.as_brushed` — with
//! the scene's view and key light; and the same grain as 16-bit PNG maps in UV space
//! (`export.maps`, docs/formats.md, "Grain maps").

use std::path::Path;

use nalgebra::Vector3;

use super::Prepared;
use crate::appearance::LightSpec;
use crate::export::{
    export_glb, grain_texture, ExportInput, ExportOptions, ExportOutput, ExportSection, ViewCamera,
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

/// The file names of the maps inside `export.maps`.
pub const MAP_FILES: [&str; 2] = ["grain-direction.png", "grain-angle.png"];

/// The grain maps of `export.maps` (docs/formats.md, "Grain maps").
pub struct Maps {
    /// The direction map's PNG ([`MAP_FILES`]\[0\]).
    pub direction: Vec<u8>,
    /// The angle map's PNG ([`MAP_FILES`]\[1\]).
    pub angle: Vec<u8>,
}

/// The grain's maps: the glb's grain baked ([`grain_texture`]) and encoded as 16-bit PNGs.
pub fn maps(x: &ExportStageInput) -> Result<Maps> {
    let (normals, u, singular) = grain(x);
    let curved = x.prepared.surfaces.as_ref().map(|r| r.curved_faces(&x.prepared.mesh));
    let input = export_input(x, &normals, &u, &singular, &curved)?;
    let t = grain_texture(&input, texture_size(x.section, input.uv, x))?;
    Ok(Maps { direction: t.baked.image.direction_png16()?, angle: t.baked.image.angle_png16()? })
}

/// The part's normals, the grain exported (designed or as-brushed) and the singular faces of
/// its angles.
type Grain = (Vec<Vector3<f64>>, Vec<Vector3<f64>>, Vec<u32>);

/// The part's normals, the grain exported and its singular faces ([`Grain`]).
fn grain(x: &ExportStageInput) -> Grain {
    let (e, prepared) = (x.section, x.prepared);
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
        Symmetry::Line => crate::highlight::singularities(&prepared.mesh, g, &phi_e, 2)
            .iter()
            .map(|s| s.face)
            .collect(),
        Symmetry::Oriented => Vec::new(),
    };
    (normals, u, singular)
}

/// The export's input: the part, its normals and UVs, the grain `u` and its `singular` faces.
fn export_input<'a>(
    x: &'a ExportStageInput,
    normals: &'a [Vector3<f64>],
    u: &'a [Vector3<f64>],
    singular: &'a [u32],
    curved: &'a Option<Vec<bool>>,
) -> Result<ExportInput<'a>> {
    let prepared = x.prepared;
    let uv = prepared.mesh.uv.as_ref().ok_or_else(|| {
        crate::Error::setting(
            "export",
            format!("{} has no UV coordinates: the export needs a UV layout", prepared.mesh_name),
        )
    })?;
    Ok(ExportInput {
        positions: &prepared.mesh.positions,
        faces: &prepared.mesh.faces,
        normals,
        u,
        symmetry: prepared.field_options.symmetry,
        singular_faces: singular,
        strokes: x.section.strokes.then_some(x.strokes_3d),
        uv,
        curved_faces: curved.as_deref(),
    })
}

/// `export.anisotropy_texture_size`, or the size chosen for the part's UVs and its curved
/// chords ([`crate::texmap::auto_size_with`]).
fn texture_size(
    e: &ExportSection,
    uv: &crate::mesh::CornerAttribute<nalgebra::Vector2<f64>>,
    x: &ExportStageInput,
) -> u32 {
    e.anisotropy_texture_size.unwrap_or_else(|| {
        let mesh = &x.prepared.mesh;
        let turns = x.prepared.surfaces.as_ref().map(|r| chord_turns(&r.on_faces(mesh), mesh));
        crate::texmap::auto_size_with(uv, turns.as_deref())
    })
}

/// Per face of `mesh`, the largest angle (degrees) between its recognized curved surface's
/// normals at its corners; 0 on other faces.
fn chord_turns(on: &crate::geometry::surfaces::FaceSurfaces, mesh: &crate::mesh::Mesh) -> Vec<f64> {
    (0..mesh.num_faces())
        .map(|f| {
            let Some(prim) = on.curved(f) else { return 0.0 };
            let n = mesh.faces[f].map(|v| prim.normal_at(&mesh.positions[v as usize]));
            (0..3)
                .map(|k| n[k].dot(&n[(k + 1) % 3]).abs().min(1.0).acos().to_degrees())
                .filter(|a| a.is_finite())
                .fold(0.0, f64::max)
        })
        .collect()
}

/// Writes the glb ([`export_glb`]).
pub fn export(x: &ExportStageInput) -> Result<ExportOutput> {
    let (scene, prepared) = (x.scene, x.prepared);
    let (normals, u, singular) = grain(x);
    let curved = x.prepared.surfaces.as_ref().map(|r| r.curved_faces(&x.prepared.mesh));
    let input = export_input(x, &normals, &u, &singular, &curved)?;
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
        texture_size: texture_size(x.section, input.uv, x),
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
