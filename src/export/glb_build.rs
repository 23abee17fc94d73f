//! The glTF document and binary buffer of [`export_glb`](super::export_glb), built part by
//! part: the mesh's buffers, its material, mesh and node, the strokes, the camera and the key
//! light.

use nalgebra::Vector3;
use serde_json::{json, Value};

use super::vertices::GltfVertices;
use super::{glb, perpendicular, quaternion_of, rotate, GltfMaterial, ViewCamera};
use crate::{Error, Result};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const LINEAR: u32 = 9729;
const LINEAR_MIPMAP_LINEAR: u32 = 9987;
const CLAMP_TO_EDGE: u32 = 33071;

fn f32s(v: &Vector3<f64>) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// Component-wise minimum and maximum (required by the spec for POSITION).
fn bounds(p: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for q in p {
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    (lo, hi)
}

use crate::texmap::mikk::unit32;

/// A node of `mesh`, scaled and rotated into glTF's world.
fn node(mesh: usize, name: String, scale: f64, rotation: [f64; 4]) -> Value {
    json!({ "name": name, "mesh": mesh, "scale": [scale, scale, scale], "rotation": rotation })
}

/// The document's arrays and the binary buffer, in the order written.
#[derive(Default)]
pub(super) struct Gltf {
    bin: glb::Bin,
    views: Vec<Value>,
    accessors: Vec<Value>,
    materials: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    cameras: Vec<Value>,
    lights: Vec<Value>,
    images: Vec<Value>,
}

impl Gltf {
    /// A buffer view of `bin_slice` (offset, length); its index.
    fn view(&mut self, bin_slice: (usize, usize), target: u32) -> usize {
        self.views.push(json!({
            "buffer": 0, "byteOffset": bin_slice.0, "byteLength": bin_slice.1, "target": target
        }));
        self.views.len() - 1
    }

    /// A VEC`n` f32 accessor of `values` (n = 2, 3 or 4); its index.
    fn push_vec<const N: usize>(&mut self, values: &[[f32; N]], extra: Value) -> usize {
        let s = self.bin.push_f32(values.iter().flatten().copied());
        let view = self.view(s, ARRAY_BUFFER);
        let mut a = json!({
            "bufferView": view, "componentType": FLOAT, "count": values.len(),
            "type": format!("VEC{N}")
        });
        if let (Some(a), Some(e)) = (a.as_object_mut(), extra.as_object()) {
            a.extend(e.clone());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// The part's POSITION, NORMAL, TANGENT, TEXCOORD_0 and index accessors (0 to 4); the
    /// number of glTF vertices.
    pub fn push_part_buffers(
        &mut self,
        positions: &[Vector3<f64>],
        normals: &[Vector3<f64>],
        verts: &GltfVertices,
    ) -> usize {
        // POSITION with its bounds (required by the spec).
        let pos: Vec<[f32; 3]> =
            verts.vertex.iter().map(|&v| f32s(&positions[v as usize])).collect();
        let (lo, hi) = bounds(&pos);
        self.push_vec(&pos, json!({ "min": lo, "max": hi }));
        let nrm: Vec<[f32; 3]> =
            verts.vertex.iter().map(|&v| unit32(&normals[v as usize])).collect();
        self.push_vec(&nrm, json!({}));
        self.push_vec(&verts.tangent, json!({}));
        self.push_vec(&verts.texcoord, json!({}));
        let s = self.bin.push_u32(verts.faces.iter().flatten().copied());
        let v_idx = self.view(s, ELEMENT_ARRAY_BUFFER);
        self.accessors.push(json!({
            "bufferView": v_idx, "componentType": UNSIGNED_INT, "count": 3 * verts.faces.len(),
            "type": "SCALAR"
        }));
        pos.len()
    }

    /// The part's material (anisotropic, its direction in the embedded PNG `texture`), mesh
    /// and node.
    pub fn push_part(
        &mut self,
        name: &str,
        m: &GltfMaterial,
        texture: &[u8],
        scale: f64,
        rotation: [f64; 4],
    ) {
        let s = self.bin.push_bytes(texture);
        self.views.push(json!({ "buffer": 0, "byteOffset": s.0, "byteLength": s.1 }));
        self.images.push(json!({
            "name": "anisotropy", "bufferView": self.views.len() - 1, "mimeType": "image/png"
        }));
        self.materials.push(json!({
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [m.base_color[0], m.base_color[1], m.base_color[2], 1.0],
                "metallicFactor": m.metallic,
                "roughnessFactor": m.roughness
            },
            "extensions": { "KHR_materials_anisotropy": {
                "anisotropyStrength": m.anisotropy_strength,
                "anisotropyRotation": 0.0,
                "anisotropyTexture": { "index": 0 }
            } }
        }));
        self.meshes.push(json!({
            "name": name,
            "primitives": [{
                "attributes": { "POSITION": 0, "NORMAL": 1, "TANGENT": 2, "TEXCOORD_0": 3 },
                "indices": 4, "material": 0, "mode": 4
            }]
        }));
        self.nodes.push(node(0, name.to_string(), scale, rotation));
    }

    /// The strokes as line primitives of a second mesh and node (none when no stroke has two
    /// distinct points); the strokes and segments written. Refuses a non-finite point.
    pub fn push_strokes(
        &mut self,
        strokes: &[Vec<Vector3<f64>>],
        scale: f64,
        rotation: [f64; 4],
    ) -> Result<(usize, usize)> {
        let (mut n_strokes, mut n_segments) = (0, 0);
        let mut pts: Vec<[f32; 3]> = Vec::new();
        let mut idx: Vec<u32> = Vec::new();
        for (s, line) in strokes.iter().enumerate() {
            let mut q: Vec<[f32; 3]> = Vec::with_capacity(line.len());
            for (j, p) in line.iter().enumerate() {
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(Error::invalid_arg(
                        "export input",
                        format!("stroke {s}, point {j} is not finite"),
                    ));
                }
                // Repeated points would be left unused (a validator notes unused data).
                if q.last() != Some(&f32s(p)) {
                    q.push(f32s(p));
                }
            }
            if q.len() < 2 {
                continue;
            }
            let k0 = pts.len() as u32;
            for j in 1..q.len() as u32 {
                idx.extend([k0 + j - 1, k0 + j]);
            }
            pts.extend(q);
            n_strokes += 1;
        }
        if !idx.is_empty() {
            // Only the points the segments use are kept (a validator warns about unused ones).
            let (lo, hi) = bounds(&pts);
            let s = self.bin.push_f32(pts.iter().flatten().copied());
            let vp = self.view(s, ARRAY_BUFFER);
            self.accessors.push(json!({
                "bufferView": vp, "componentType": FLOAT, "count": pts.len(), "type": "VEC3",
                "min": lo, "max": hi
            }));
            let s = self.bin.push_u32(idx.iter().copied());
            let vi = self.view(s, ELEMENT_ARRAY_BUFFER);
            self.accessors.push(json!({
                "bufferView": vi, "componentType": UNSIGNED_INT, "count": idx.len(),
                "type": "SCALAR"
            }));
            n_segments = idx.len() / 2;
            self.materials.push(json!({
                "name": "strokes",
                "pbrMetallicRoughness": {
                    "baseColorFactor": [0.9, 0.35, 0.05, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 1.0
                }
            }));
            let a = self.accessors.len();
            self.meshes.push(json!({
                "name": "strokes",
                "primitives": [{
                    "attributes": { "POSITION": a - 2 }, "indices": a - 1, "material": 1,
                    "mode": 1
                }]
            }));
            self.nodes.push(node(1, "strokes".into(), scale, rotation));
        } else {
            n_strokes = 0;
        }
        Ok((n_strokes, n_segments))
    }

    /// The camera, in glTF's world (metres, +Y up): the part node's transform applied to the
    /// scene's coordinates. Skipped when its view direction is zero or along its up.
    pub fn push_camera(&mut self, camera: Option<ViewCamera>, scale: f64, rotation: [f64; 4]) {
        let world_dir = |v: [f64; 3]| rotate(rotation, Vector3::from(v));
        if let Some(c) = camera.filter(|c| {
            let f = Vector3::from(c.target) - Vector3::from(c.eye);
            f.norm() > 0.0 && f.cross(&Vector3::from(c.up)).norm() > 1e-9 * f.norm()
        }) {
            let fwd = world_dir(c.target) - world_dir(c.eye);
            let dist = fwd.norm() * scale;
            let back = -fwd.normalize();
            let right = fwd.cross(&world_dir(c.up)).normalize();
            let up = back.cross(&right);
            let eye = world_dir(c.eye) * scale;
            self.cameras.push(json!({
                "name": "view", "type": "perspective",
                "perspective": { "yfov": c.fov_deg.to_radians(), "znear": 1e-3 * dist }
            }));
            self.nodes.push(json!({
                "name": "view", "camera": 0, "translation": [eye.x, eye.y, eye.z],
                "rotation": quaternion_of(right, up, back)
            }));
        }
    }

    /// The key light (direction towards it, irradiance), in glTF's world like the camera.
    /// Skipped when its irradiance is not finite and ≥ 0 or its direction is zero.
    pub fn push_key_light(&mut self, key_light: Option<([f64; 3], f64)>, rotation: [f64; 4]) {
        let world_dir = |v: [f64; 3]| rotate(rotation, Vector3::from(v));
        if let Some((d, irradiance)) =
            key_light.filter(|(d, e)| e.is_finite() && *e >= 0.0 && Vector3::from(*d).norm() > 0.0)
        {
            // The light shines along its node's −Z: +Z points towards the light.
            let z = world_dir(d).normalize();
            let x = perpendicular(&z);
            let y = z.cross(&x);
            self.lights.push(json!({
                "name": "key", "type": "directional", "color": [1.0, 1.0, 1.0],
                "intensity": irradiance
            }));
            self.nodes.push(json!({
                "name": "key light", "rotation": quaternion_of(x, y, z),
                "extensions": { "KHR_lights_punctual": { "light": 0 } }
            }));
        }
    }

    /// The document (one scene of every node, named `name`) and the buffer as a .glb.
    pub fn into_glb(self, name: &str) -> Result<Vec<u8>> {
        let Gltf { bin, views, accessors, materials, meshes, nodes, cameras, lights, images } =
            self;
        let node_ids: Vec<usize> = (0..nodes.len()).collect();
        let mut used = vec!["KHR_materials_anisotropy"];
        if !lights.is_empty() {
            used.push("KHR_lights_punctual");
        }
        let mut doc = json!({
            "asset": {
                "version": "2.0",
                "generator": concat!("grainline ", env!("CARGO_PKG_VERSION"))
            },
            "extensionsUsed": used,
            "scene": 0,
            "scenes": [{ "name": name, "nodes": node_ids }],
            "nodes": nodes,
            "meshes": meshes,
            "materials": materials,
            "accessors": accessors,
            "bufferViews": views,
            "buffers": [{ "byteLength": bin.bytes.len() }]
        });
        if !images.is_empty() {
            doc["images"] = json!(images);
            doc["samplers"] = json!([{
                "magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR,
                "wrapS": CLAMP_TO_EDGE, "wrapT": CLAMP_TO_EDGE
            }]);
            doc["textures"] = json!((0..images.len())
                .map(|i| json!({ "sampler": 0, "source": i }))
                .collect::<Vec<_>>());
        }
        if !cameras.is_empty() {
            doc["cameras"] = json!(cameras);
        }
        if !lights.is_empty() {
            doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": lights } });
        }
        let text = serde_json::to_vec(&doc)
            .map_err(|e| Error::Numerical { stage: "glTF JSON", message: e.to_string() })?;
        Ok(glb::container(&text, &bin.bytes))
    }
}
