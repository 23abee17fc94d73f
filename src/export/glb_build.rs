//! The glTF document and binary buffer of [`export_glb`](super::export_glb), built part by
//! part: the mesh's buffers, its material, mesh and node, the strokes, the camera and the key
//! light.

use nalgebra::Vector3;
use serde_json::{json, Value};

use super::orient::Oriented;
use super::{glb, perpendicular, quaternion_of, rotate, ExportInput, GltfMaterial, ViewCamera};
use crate::{Error, Result};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

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

fn unit32(v: &Vector3<f64>) -> [f32; 3] {
    // Renormalized in f32 so the stored vector is unit to f32 precision.
    let w = f32s(v);
    let l = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    [w[0] / l, w[1] / l, w[2] / l]
}

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
}

impl Gltf {
    /// A buffer view of `bin_slice` (offset, length); its index.
    fn view(&mut self, bin_slice: (usize, usize), target: u32) -> usize {
        self.views.push(json!({
            "buffer": 0, "byteOffset": bin_slice.0, "byteLength": bin_slice.1, "target": target
        }));
        self.views.len() - 1
    }

    /// The part's POSITION, NORMAL, TANGENT and index accessors (0 to 3); the number of glTF
    /// vertices.
    pub fn push_part_buffers(
        &mut self,
        input: &ExportInput,
        oriented: &Oriented,
        normals: &[Vector3<f64>],
        tangents: &[Vector3<f64>],
    ) -> usize {
        // POSITION with its bounds (required by the spec).
        let pos: Vec<[f32; 3]> =
            oriented.vertex.iter().map(|&v| f32s(&input.positions[v as usize])).collect();
        let (lo, hi) = bounds(&pos);
        let count = pos.len();
        let s = self.bin.push_f32(pos.iter().flatten().copied());
        let v_pos = self.view(s, ARRAY_BUFFER);
        self.accessors.push(json!({
            "bufferView": v_pos, "componentType": FLOAT, "count": count, "type": "VEC3",
            "min": lo, "max": hi
        }));
        let nrm: Vec<[f32; 3]> =
            oriented.vertex.iter().map(|&v| unit32(&normals[v as usize])).collect();
        let s = self.bin.push_f32(nrm.iter().flatten().copied());
        let v_nrm = self.view(s, ARRAY_BUFFER);
        self.accessors.push(json!({
            "bufferView": v_nrm, "componentType": FLOAT, "count": count, "type": "VEC3"
        }));
        let tan: Vec<[f32; 4]> = oriented
            .vertex
            .iter()
            .zip(&oriented.sign)
            .map(|(&v, &s)| {
                let t = unit32(&(tangents[v as usize] * s));
                [t[0], t[1], t[2], 1.0]
            })
            .collect();
        let s = self.bin.push_f32(tan.iter().flatten().copied());
        let v_tan = self.view(s, ARRAY_BUFFER);
        self.accessors.push(json!({
            "bufferView": v_tan, "componentType": FLOAT, "count": count, "type": "VEC4"
        }));
        let s = self.bin.push_u32(oriented.faces.iter().flatten().copied());
        let v_idx = self.view(s, ELEMENT_ARRAY_BUFFER);
        self.accessors.push(json!({
            "bufferView": v_idx, "componentType": UNSIGNED_INT, "count": 3 * oriented.faces.len(),
            "type": "SCALAR"
        }));
        count
    }

    /// The part's material (anisotropic), mesh and node.
    pub fn push_part(&mut self, name: &str, m: &GltfMaterial, scale: f64, rotation: [f64; 4]) {
        self.materials.push(json!({
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [m.base_color[0], m.base_color[1], m.base_color[2], 1.0],
                "metallicFactor": m.metallic,
                "roughnessFactor": m.roughness
            },
            "extensions": { "KHR_materials_anisotropy": {
                "anisotropyStrength": m.anisotropy_strength,
                "anisotropyRotation": m.anisotropy_rotation
            } }
        }));
        self.meshes.push(json!({
            "name": name,
            "primitives": [{
                "attributes": { "POSITION": 0, "NORMAL": 1, "TANGENT": 2 },
                "indices": 3, "material": 0, "mode": 4
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
        let Gltf { bin, views, accessors, materials, meshes, nodes, cameras, lights } = self;
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
