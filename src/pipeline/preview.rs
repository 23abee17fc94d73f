//! The preview stage: the scene's render with the field that is shown, its highlights, the
//! strokes and the overlays its effects ask for, lit by the scene's lights (the key light
//! where the edits moved it).

use nalgebra::{Matrix2, Vector3};

use super::optimize::Optimized;
use super::Prepared;
use crate::appearance::LightSpec;
use crate::highlight::{highlight_field_near, Lighting};
use crate::render::{render, Camera, EditOverlay, RenderInput, RenderOutput, RenderSettings};
use crate::scene::LoadedScene;
use crate::Result;

/// The field a preview shows, and what the trace stage made of it.
pub struct PreviewInput<'a> {
    /// The scene and its render section.
    pub scene: &'a LoadedScene,
    /// The render section.
    pub settings: &'a RenderSettings,
    /// The part and its initial field.
    pub prepared: &'a Prepared,
    /// The edits and the solve, if the scene has edits.
    pub optimized: Option<&'a Optimized>,
    /// The grain angles shown.
    pub phi: &'a [f64],
    /// Half vectors of the lighting shown.
    pub h: &'a [Vector3<f64>],
    /// The near term's G per vertex of that lighting.
    pub h_gradient: Option<&'a [Matrix2<f64>]>,
    /// ℓ of the field shown.
    pub ell: &'a [Vector3<f64>],
    /// Critical points of the field shown.
    pub critical: &'a [bool],
    /// The highlight model's lighting (the key light where the edits moved it).
    pub lighting: Lighting,
    /// The strokes on the part (empty when none were traced).
    pub strokes_3d: &'a [Vec<Vector3<f64>>],
    /// The as-brushed grain per vertex, if traced.
    pub brushed_u: Option<&'a [[f64; 3]]>,
    /// The coverage gap per vertex, if traced.
    pub gap: Option<&'a [f64]>,
}

/// Renders the preview ([`render`]).
pub fn preview(p: &PreviewInput) -> Result<RenderOutput> {
    let (s, settings, prepared) = (p.scene, p.settings, p.prepared);
    let scene = &s.scene;
    let g = &prepared.field.geometry;
    let symmetry = prepared.field_options.symmetry;
    let normals: Vec<Vector3<f64>> = g.frames.iter().map(|f| f.n).collect();
    // Shading normals split at creases (math.md §3, "Creases"); smooth vertices keep the
    // solver's normal. A part cut into patches (`mesh.patches: "split"`, the default) is
    // already split at every crease that separates two of them; a sharp edge left inside a
    // patch — a crease that fades out, a sliver's fold on a scan or a sculpt — is not cut
    // again here (it would show as a speck of the sliver's facet in the shading).
    let crease_angle = match scene.mesh.as_ref() {
        None => crate::geometry::normals::DEFAULT_CREASE_ANGLE_DEG,
        Some(m) if m.0.patches == crate::scene::PatchMode::Split => 180.0,
        Some(m) => m.crease_angle(),
    };
    let corner = {
        let m = &prepared.mesh;
        let vf = crate::mesh::VertexFaces::new(m);
        let fd = crate::geometry::normals::face_data(m);
        crate::geometry::normals::corner_normals(m, &vf, &fd, &normals, crease_angle)
    };
    let u = g.directions_of(p.phi);
    let mut input =
        RenderInput::new(&prepared.mesh.positions, &prepared.mesh.faces, &normals, &u, symmetry);
    input.corner_normals = Some(&corner.corners);
    let on_faces = prepared.surfaces.as_ref().map(|r| r.on_faces(&prepared.mesh));
    input.surfaces = on_faces.as_ref();
    input.ell = Some(p.ell);
    input.critical = Some(p.critical);
    if settings.effects.strokes.is_some() {
        input.strokes = Some(p.strokes_3d);
    }
    let brushed_u: Option<Vec<Vector3<f64>>> =
        p.brushed_u.map(|b| b.iter().map(|v| Vector3::from(*v)).collect());
    let brushed_ell = brushed_u.as_ref().map(|bu| {
        let bphi = g.angles_of(bu);
        let form = prepared.field_options.gradient_form;
        highlight_field_near(g, &bphi, symmetry, form, p.h, p.h_gradient).ell
    });
    input.brushed_u = brushed_u.as_deref();
    input.brushed_ell = brushed_ell.as_deref();
    let overlay = p.optimized.map(|o| edit_overlay(prepared, o));
    if settings.effects.gap.is_some() {
        input.gap = p.gap;
    }
    if settings.effects.edits.is_some() {
        input.edits = overlay.as_ref();
    }
    let camera = Camera {
        eye: scene.view.eye.into(),
        target: scene.view.target.into(),
        up: scene.view.up.into(),
        fov_deg: scene.view.fov_deg,
    };
    let lights = preview_lights(s, &p.lighting);
    render(&input, &scene.material, &lights, &camera, settings).map_err(|e| s.wrap(e))
}

/// The edits' overlay: their support and the target ℓ* inside it.
fn edit_overlay(prepared: &Prepared, o: &Optimized) -> EditOverlay {
    EditOverlay {
        support: o.support.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect(),
        targets: o
            .target_ell
            .iter()
            .enumerate()
            .filter(|(i, t)| t.is_some() && o.support[*i])
            .map(|(i, t)| (prepared.mesh.positions[i], t.expect("filtered")))
            .collect(),
    }
}

/// The scene's lights for the preview: environment images relative to the scene file, the key
/// light where the edits may have moved it.
fn preview_lights(s: &LoadedScene, lighting: &Lighting) -> Vec<LightSpec> {
    let scene = &s.scene;
    let key = crate::appearance::key_light_index(&scene.lights);
    scene
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| match l {
            LightSpec::Environment { file, scale, samples, rotation_deg } => {
                LightSpec::Environment {
                    file: s.input(file).display().to_string(),
                    scale: *scale,
                    samples: *samples,
                    rotation_deg: *rotation_deg,
                }
            }
            LightSpec::Directional { irradiance, colour, key: k, .. } if Some(i) == key => {
                LightSpec::Directional {
                    direction: [lighting.light.x, lighting.light.y, lighting.light.z],
                    irradiance: *irradiance,
                    colour: *colour,
                    key: *k,
                }
            }
            LightSpec::Point { position, intensity, colour, key: k } if Some(i) == key => {
                LightSpec::Point {
                    position: lighting.light_position.map_or(*position, |p| [p.x, p.y, p.z]),
                    intensity: *intensity,
                    colour: *colour,
                    key: *k,
                }
            }
            other => other.clone(),
        })
        .collect()
}
