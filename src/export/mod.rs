//! The part and its grain as glTF 2.0 binary (.glb) with `KHR_materials_anisotropy`, for the
//! designer's own viewer (three.js, Babylon.js, Blender, ...). docs/gltf.md has the format, the
//! material mapping and the conventions; in short:
//!
//! - the triangle mesh with POSITION, NORMAL, TEXCOORD_0 (the part's UVs in texture space,
//!   [`crate::texmap::TextureSpace`]), TANGENT (MikkTSpace from those UVs: what a viewer
//!   computes when the file has none) and indices, in the scene's length unit; the node's
//!   `scale` turns it into metres (0.001 for mm) and its `rotation` turns the scene's `view.up`
//!   axis into glTF's +Y;
//! - one metallic material with `KHR_materials_anisotropy` { `anisotropyStrength`,
//!   `anisotropyRotation` = 0, `anisotropyTexture` }: the texture's RG is the anisotropy
//!   direction in the tangent frame — the grain turned by the material's rotation, n × u for a
//!   lobe narrow along the grain: where the extension *raises* the roughness, across the
//!   grooves ([`material`]) —, baked per UV triangle ([`crate::texmap`]), B = 1;
//! - a line field (k = 2) oriented per triangle before it is baked ([`orient`]);
//! - optionally the brush strokes as a second node of LINES;
//! - deterministic bytes: no time stamp, fixed key order, face order kept.
//!
//! The caller writes the bytes atomically (`output::Staged`).

pub mod glb;
mod glb_build;
pub mod material;
pub use crate::texmap::orient;
mod vertices;

use nalgebra::{Vector2, Vector3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::appearance::Material;
use crate::highlight::Symmetry;
use crate::mesh::{CornerAttribute, Units};
use crate::texmap::{BakeInput, TextureSpace};
use crate::{Error, Result};

pub use material::{gltf_material, GltfMaterial};

/// The scene's `export` section: files for other programs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ExportSection {
    /// glTF 2.0 binary (.glb) of the part with its grain as tangents and an anisotropic
    /// material (`KHR_materials_anisotropy`), written by `grainline run` and `grainline export`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glb: Option<String>,
    /// Also write the brush strokes as a second node of line primitives (needs `toolpaths`).
    #[serde(default)]
    pub strokes: bool,
    /// Write the grain rebuilt from the strokes (the as-brushed field) instead of the designed
    /// one (needs `toolpaths`).
    #[serde(default)]
    pub as_brushed: bool,
    /// Texels per side of the glb's `anisotropyTexture` and of the maps (`maps`): a power of
    /// two in [16, 8192]. Default: chosen for the part, the smallest power of two in
    /// [1024, 4096] at which the shortest 5 % of the UV edges span 8 texels (1024 for the
    /// kettle and the dome, 2048 for the panel) and every chord of a recognized curved surface
    /// spans 8 texels and one per degree of its surface's turn along its middle edge.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anisotropy_texture_size: Option<u32>,
    /// A directory for the grain as 16-bit PNG maps in UV space (`grain-direction.png`,
    /// `grain-angle.png`; docs/formats.md, "Grain maps"), written by `grainline run` and
    /// `grainline export --maps`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub maps: Option<String>,
}

impl ExportSection {
    /// Range checks; keys are relative to this section.
    pub fn validate(&self) -> Result<()> {
        match self.anisotropy_texture_size {
            Some(n) => crate::texmap::check_size("anisotropy_texture_size", n),
            None => Ok(()),
        }
    }
}

/// What [`export_glb`] exports: the mesh and its per-vertex fields, borrowed.
#[derive(Clone, Copy, Debug)]
pub struct ExportInput<'a> {
    /// Vertex positions, in the scene's unit.
    pub positions: &'a [Vector3<f64>],
    /// Triangles, counter-clockwise around their outward normal.
    pub faces: &'a [[u32; 3]],
    /// Unit vertex normals.
    pub normals: &'a [Vector3<f64>],
    /// The grain per vertex (tangent; projected and normalized here).
    pub u: &'a [Vector3<f64>],
    /// k = 1 (oriented) or k = 2 (line field: oriented per triangle, vertices split).
    pub symmetry: Symmetry,
    /// Faces of non-zero index (`highlight::singularities`), isolated when k = 2.
    pub singular_faces: &'a [u32],
    /// Brush strokes (3D polylines, scene unit), written as a second node when given.
    pub strokes: Option<&'a [Vec<Vector3<f64>>]>,
    /// The part's UV layout (its own, or one made by `layout::flatten`): TEXCOORD_0, the
    /// tangent frames and the texture's domain.
    pub uv: &'a CornerAttribute<Vector2<f64>>,
    /// Per face, whether it lies on a recognized curved surface (`mesh.surfaces`): its
    /// corners' grain is extended off the surface before baking
    /// ([`crate::geometry::surfaces::ambient`]), so each texel carries the surface's grain
    /// between the chords, not the chords' blend. `None`: no face is.
    pub curved_faces: Option<&'a [bool]>,
}

/// Options of [`export_glb`].
#[derive(Clone, Debug)]
pub struct ExportOptions {
    /// The scene's material, mapped to glTF ([`gltf_material`]).
    pub material: Material,
    /// The unit of the positions (the node's scale turns it into metres).
    pub units: Units,
    /// The scene's up direction (`view.up`), turned into glTF's +Y by the node's rotation
    /// when it is closest to a coordinate axis.
    pub up: [f64; 3],
    /// The name of the mesh, node and material.
    pub name: String,
    /// The scene's camera, written as a glTF perspective camera (a node `view`), so a viewer
    /// can open on the designed view.
    pub camera: Option<ViewCamera>,
    /// The key light: direction towards it (scene coordinates) and irradiance, written as a
    /// `KHR_lights_punctual` directional light (a node `key light`).
    pub key_light: Option<([f64; 3], f64)>,
    /// Texels per side of the `anisotropyTexture` (a power of two in
    /// [`crate::texmap::TEXTURE_SIZE_RANGE`]).
    pub texture_size: u32,
}

/// The scene's pinhole camera, in scene coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewCamera {
    /// Eye position.
    pub eye: [f64; 3],
    /// The point at the image centre.
    pub target: [f64; 3],
    /// Up direction.
    pub up: [f64; 3],
    /// Vertical field of view, degrees.
    pub fov_deg: f64,
}

/// `q` applied to `v` (q = (x, y, z, w), unit): v + 2w(q×v) + 2q×(q×v).
fn rotate(q: [f64; 4], v: Vector3<f64>) -> Vector3<f64> {
    let qv = Vector3::new(q[0], q[1], q[2]);
    let t = 2.0 * qv.cross(&v);
    v + q[3] * t + qv.cross(&t)
}

/// The unit quaternion (x, y, z, w) of the rotation whose matrix has columns `x`, `y`, `z`
/// (orthonormal, right-handed), by Shepperd's method.
fn quaternion_of(x: Vector3<f64>, y: Vector3<f64>, z: Vector3<f64>) -> [f64; 4] {
    let (m00, m11, m22) = (x.x, y.y, z.z);
    let tr = m00 + m11 + m22;
    let q = if tr > 0.0 {
        let s = 2.0 * (tr + 1.0).sqrt();
        [(y.z - z.y) / s, (z.x - x.z) / s, (x.y - y.x) / s, 0.25 * s]
    } else if m00 > m11 && m00 > m22 {
        let s = 2.0 * (1.0 + m00 - m11 - m22).sqrt();
        [0.25 * s, (y.x + x.y) / s, (z.x + x.z) / s, (y.z - z.y) / s]
    } else if m11 > m22 {
        let s = 2.0 * (1.0 + m11 - m00 - m22).sqrt();
        [(y.x + x.y) / s, 0.25 * s, (z.y + y.z) / s, (z.x - x.z) / s]
    } else {
        let s = 2.0 * (1.0 + m22 - m00 - m11).sqrt();
        [(z.x + x.z) / s, (z.y + y.z) / s, 0.25 * s, (x.y - y.x) / s]
    };
    let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    q.map(|c| c / n)
}

/// Figures of an export.
#[derive(Clone, Debug, Serialize)]
pub struct ExportReport {
    /// glTF vertices written (mesh vertices plus the split copies).
    pub vertices: usize,
    /// Mesh vertices.
    pub mesh_vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Mesh vertices written more than once (UV seams, MikkTSpace tangent splits).
    pub split_vertices: usize,
    /// Faces whose grain is oriented on their own in the texture (inconsistent or singular,
    /// k = 2).
    pub isolated_faces: usize,
    /// Vertices whose grain was zero or along the normal (grain set to an arbitrary
    /// perpendicular).
    pub fallback_tangents: usize,
    /// Face corners MikkTSpace gave no tangent (degenerate UV triangles with no neighbour):
    /// TANGENT from the face's UV Jacobian, or any perpendicular.
    pub fallback_uv_tangents: usize,
    /// Texels per side of the `anisotropyTexture`.
    pub texture_size: u32,
    /// Texels whose centre lies inside a UV triangle (the rest is dilated padding).
    pub texture_covered: usize,
    /// The map from the part's UVs to TEXCOORD_0's texture space (st = (uv − offset)/scale).
    pub texture_space: TextureSpace,
    /// Strokes written as lines (0 without the strokes node).
    pub strokes: usize,
    /// Line segments of the strokes node.
    pub stroke_segments: usize,
    /// The node's uniform scale (scene unit → metres).
    pub scale: f64,
    /// The node's rotation quaternion (x, y, z, w).
    pub rotation: [f64; 4],
    /// The material as written.
    pub material: GltfMaterial,
    /// Size of the .glb.
    pub bytes: usize,
}

/// The .glb and its figures.
#[derive(Clone, Debug)]
pub struct ExportOutput {
    /// The .glb file's bytes.
    pub glb: Vec<u8>,
    /// Figures.
    pub report: ExportReport,
}

/// The quaternion (x, y, z, w) turning the coordinate axis closest to `up` into +Y
/// (identity when `up` is closest to +Y or is not finite).
pub fn up_rotation(up: [f64; 3]) -> [f64; 4] {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let a = up.map(f64::abs);
    if !up.iter().all(|c| c.is_finite()) || a == [0.0; 3] {
        return [0.0, 0.0, 0.0, 1.0];
    }
    if a[2] > a[0] && a[2] > a[1] {
        // −90° about x takes +z to +y; +90° takes −z to +y.
        if up[2] > 0.0 {
            [-h, 0.0, 0.0, h]
        } else {
            [h, 0.0, 0.0, h]
        }
    } else if a[0] > a[1] {
        // +90° about z takes +x to +y.
        if up[0] > 0.0 {
            [0.0, 0.0, h, h]
        } else {
            [0.0, 0.0, -h, h]
        }
    } else if up[1] > 0.0 {
        [0.0, 0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0, 0.0]
    }
}

/// A unit vector perpendicular to the unit `n` (deterministic).
fn perpendicular(n: &Vector3<f64>) -> Vector3<f64> {
    let a = n.map(f64::abs);
    let axis = if a.x <= a.y && a.x <= a.z {
        Vector3::x()
    } else if a.y <= a.z {
        Vector3::y()
    } else {
        Vector3::z()
    };
    n.cross(&axis).normalize()
}

fn check_finite(what: &str, i: usize, v: &Vector3<f64>) -> Result<()> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(Error::invalid_arg("export input", format!("vertex {i}: {what} is not finite")))
    }
}

/// The grain of an export baked into texture space ([`grain_texture`]).
#[derive(Clone, Debug)]
pub struct GrainTexture {
    /// The texels, the texture space and the MikkTSpace frames.
    pub baked: crate::texmap::Baked,
    /// The unit normals the frames were computed with.
    pub normals: Vec<Vector3<f64>>,
    /// Vertices whose grain was zero or along the normal.
    pub fallback: usize,
    /// Faces oriented on their own (k = 2).
    pub isolated_faces: usize,
}

/// The grain of `input` baked into a `size`² texture: unit normals and grain, a line field
/// oriented per triangle ([`orient`]), then [`crate::texmap::bake`]. What the glb's
/// `anisotropyTexture` and the maps of `export.maps` are encoded from.
pub fn grain_texture(input: &ExportInput, size: u32) -> Result<GrainTexture> {
    check_input(input)?;
    let nv = input.positions.len();
    // Unit normals and unit grain in the tangent plane.
    let UnitFrames { normals, tangents, fallback } = unit_frames(input)?;
    let oriented = match input.symmetry {
        Symmetry::Line => orient::orient_line_field(input.faces, &tangents, input.singular_faces),
        Symmetry::Oriented => orient::identity(input.faces, nv),
    };
    let grain: Vec<[Vector3<f64>; 3]> = oriented
        .faces
        .iter()
        .enumerate()
        .map(|(face, f)| {
            let g = f.map(|k| {
                tangents[oriented.vertex[k as usize] as usize] * oriented.sign[k as usize]
            });
            let g = if input.curved_faces.is_none_or(|c| c.get(face) != Some(&true)) {
                g
            } else {
                let n = input.faces[face].map(|v| normals[v as usize]);
                crate::geometry::surfaces::ambient::extend(g, n).unwrap_or(g)
            };
            // A vertex given no grain at all (the zero vector: metal the brush never passed
            // over) keeps none: the texture's strength falls to zero there.
            let mut g = g;
            for (c, &v) in input.faces[face].iter().enumerate() {
                if input.u[v as usize] == Vector3::zeros() {
                    g[c] = Vector3::zeros();
                }
            }
            g
        })
        .collect();
    let baked = crate::texmap::bake(&BakeInput {
        positions: input.positions,
        faces: input.faces,
        normals: &normals,
        uv: input.uv,
        grain: &grain,
        size,
        line: input.symmetry == Symmetry::Line,
    })?;
    Ok(GrainTexture { baked, normals, fallback, isolated_faces: oriented.isolated_faces })
}

/// The part as glTF 2.0 binary (module docs). Errors name the vertex or face of a bad input.
pub fn export_glb(input: &ExportInput, options: &ExportOptions) -> Result<ExportOutput> {
    let nv = input.positions.len();
    let GrainTexture { baked, normals, fallback, isolated_faces } =
        grain_texture(input, options.texture_size)?;
    let verts = vertices::gltf_vertices(input.faces, &baked.st, &baked.frames, nv);
    let m = gltf_material(&options.material);
    let texture = baked.image.anisotropy_png16(m.anisotropy_rotation)?;
    let mut gltf = glb_build::Gltf::default();
    let count = gltf.push_part_buffers(input.positions, &normals, &verts);
    let scale = options.units.in_mm() / 1000.0;
    let rotation = up_rotation(options.up);
    let name = &options.name;
    gltf.push_part(name, &m, &texture, scale, rotation);
    let (n_strokes, n_segments) = match input.strokes {
        Some(strokes) => gltf.push_strokes(strokes, scale, rotation)?,
        None => (0, 0),
    };
    gltf.push_camera(options.camera, scale, rotation);
    gltf.push_key_light(options.key_light, rotation);
    let bytes = gltf.into_glb(name)?;
    let report = ExportReport {
        vertices: count,
        mesh_vertices: nv,
        triangles: verts.faces.len(),
        split_vertices: verts.split_vertices,
        isolated_faces,
        fallback_tangents: fallback,
        fallback_uv_tangents: baked.frames.fallback,
        texture_size: options.texture_size,
        texture_covered: baked.image.covered,
        texture_space: baked.space,
        strokes: n_strokes,
        stroke_segments: n_segments,
        scale,
        rotation,
        material: m,
        bytes: bytes.len(),
    };
    Ok(ExportOutput { glb: bytes, report })
}

/// The checks of [`export_glb`]'s input sizes and face indices.
fn check_input(input: &ExportInput) -> Result<()> {
    let nv = input.positions.len();
    if input.normals.len() != nv || input.u.len() != nv {
        return Err(Error::invalid_arg(
            "export input",
            format!(
                "{nv} positions, {} normals and {} grain vectors: they must match",
                input.normals.len(),
                input.u.len()
            ),
        ));
    }
    if input.faces.is_empty() {
        return Err(Error::invalid_arg("export input", "no triangles"));
    }
    for (f, t) in input.faces.iter().enumerate() {
        if let Some(&v) = t.iter().find(|&&v| v as usize >= nv) {
            return Err(Error::invalid_arg(
                "export input",
                format!("face {f} refers to vertex {v}, the mesh has {nv}"),
            ));
        }
    }
    if input.uv.corners.len() != input.faces.len()
        || input.uv.corners.iter().flatten().any(|&c| c as usize >= input.uv.values.len())
    {
        return Err(Error::invalid_arg(
            "export input",
            format!(
                "{} UV faces for {} faces, or a UV index out of range",
                input.uv.corners.len(),
                input.faces.len()
            ),
        ));
    }
    Ok(())
}

/// Unit normals and unit tangents in the tangent plane, per vertex, and the number of
/// fallback tangents. Refuses non-finite input and positions too large for f32.
fn unit_frames(input: &ExportInput) -> Result<UnitFrames> {
    let nv = input.positions.len();
    let mut normals = Vec::with_capacity(nv);
    let mut tangents = Vec::with_capacity(nv);
    let mut fallback = 0;
    for i in 0..nv {
        check_finite("position", i, &input.positions[i])?;
        check_finite("normal", i, &input.normals[i])?;
        check_finite("grain", i, &input.u[i])?;
        if input.positions[i].iter().any(|c| c.abs() > f64::from(f32::MAX) / 2.0) {
            return Err(Error::invalid_arg(
                "export input",
                format!("vertex {i}: position too large for 32-bit floats"),
            ));
        }
        let n = input.normals[i];
        let n = if n.norm() > 1e-12 { n.normalize() } else { Vector3::z() };
        let u = input.u[i] - n * n.dot(&input.u[i]);
        let t = if u.norm() > 1e-9 * (1.0 + input.u[i].norm()) {
            u.normalize()
        } else {
            fallback += 1;
            perpendicular(&n)
        };
        normals.push(n);
        tangents.push(t);
    }
    Ok(UnitFrames { normals, tangents, fallback })
}

/// What [`unit_frames`] returns.
struct UnitFrames {
    normals: Vec<Vector3<f64>>,
    tangents: Vec<Vector3<f64>>,
    fallback: usize,
}

#[cfg(test)]
mod tests {
    use serde_json::{json, Value};

    use super::*;

    /// Shepperd's quaternion rotates the basis vectors onto the matrix's columns.
    #[test]
    fn quaternion_of_a_frame() {
        for (a, b) in [(0.3, -0.5), (2.0, 1.0), (-3.0, 0.2), (0.0, 3.1)] {
            let z = Vector3::new(f64::cos(a) * f64::sin(b), f64::sin(a) * f64::sin(b), f64::cos(b));
            let x = perpendicular(&z);
            let y = z.cross(&x);
            let q = quaternion_of(x, y, z);
            assert!((rotate(q, Vector3::x()) - x).norm() < 1e-12);
            assert!((rotate(q, Vector3::y()) - y).norm() < 1e-12);
            assert!((rotate(q, Vector3::z()) - z).norm() < 1e-12);
        }
    }

    /// The rotations take their axis to +Y (checked by rotating the vector by hand:
    /// v' = v + 2w(q×v) + 2q×(q×v)).
    #[test]
    fn up_axis_goes_to_y() {
        let rot = |q: [f64; 4], v: Vector3<f64>| {
            let qv = Vector3::new(q[0], q[1], q[2]);
            let t = 2.0 * qv.cross(&v);
            v + q[3] * t + qv.cross(&t)
        };
        for up in [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -2.0],
            [1.0, 0.1, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.1, 1.0, 0.2],
        ] {
            let q = up_rotation(up);
            let a = up.map(f64::abs);
            let k = if a[2] > a[0] && a[2] > a[1] {
                2
            } else if a[0] > a[1] {
                0
            } else {
                1
            };
            let mut axis = Vector3::zeros();
            axis[k] = up[k].signum();
            let r = rot(q, axis);
            assert!((r - Vector3::y()).norm() < 1e-12, "{up:?} → {r:?}");
        }
    }

    /// A square of two triangles with k = 2 signs flipped at alternate vertices: a valid GLB
    /// whose JSON names the extension, and a bad face index is an error naming the face.
    #[test]
    fn square() {
        let p = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(10.0, 0.0, 0.0),
            Vector3::new(0.0, 10.0, 0.0),
            Vector3::new(10.0, 10.0, 0.0),
        ];
        let n = [Vector3::z(); 4];
        let u = [Vector3::x(), -Vector3::x(), Vector3::x(), -Vector3::x()];
        let faces = [[0, 1, 2], [2, 1, 3]];
        let uv = CornerAttribute {
            values: p.iter().map(|q| Vector2::new(q.x / 10.0, q.y / 10.0)).collect(),
            corners: faces.to_vec(),
        };
        let input = ExportInput {
            positions: &p,
            faces: &faces,
            normals: &n,
            u: &u,
            symmetry: Symmetry::Line,
            singular_faces: &[],
            strokes: None,
            uv: &uv,
            curved_faces: None,
        };
        let options = ExportOptions {
            material: Material::default(),
            units: Units::Mm,
            up: [0.0, 0.0, 1.0],
            name: "square".into(),
            camera: None,
            key_light: None,
            texture_size: 16,
        };
        let out = export_glb(&input, &options).unwrap();
        assert_eq!(out.report.vertices, 4);
        assert_eq!(out.report.scale, 0.001);
        let json_len = u32::from_le_bytes(out.glb[12..16].try_into().unwrap()) as usize;
        let doc: Value = serde_json::from_slice(&out.glb[20..20 + json_len]).unwrap();
        assert_eq!(doc["extensionsUsed"][0], "KHR_materials_anisotropy");
        assert_eq!(doc["accessors"][0]["max"], json!([10.0, 10.0, 0.0]));
        // Same input, same bytes.
        assert_eq!(export_glb(&input, &options).unwrap().glb, out.glb);
        let bad = [[0, 1, 7]];
        let e = export_glb(&ExportInput { faces: &bad, ..input }, &options).unwrap_err();
        assert!(e.to_string().contains("face 0 refers to vertex 7"), "{e}");
    }
}
