//! The scene file: one JSON document that says the mesh, units, material, lights and view, the
//! initial field, the edits, the solver settings, and the toolpath and render requests
//! (docs/scene.md; the JSON Schema is `grainline schema`, published as docs/scene.schema.json).
//!
//! Scenes are written by hand, so reading one is strict and explains itself:
//! - an unknown key is an error naming its path (`edits[2].radious: unknown field ...`);
//! - a syntax or type error names the line and the key path;
//! - every number is range-checked by the section's `validate`, with the key path;
//! - relative paths are relative to the scene file.

mod sections;
pub mod toolpaths;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use sections::{
    FieldSection, InitKind, MapSource, MeshFull, MeshSection, NoiseMode, OutlineSection, PatchMode,
    RefineMode, RefineSettings, SurfaceMode, SymmetryKind, ViewModel, ViewSection,
};

use crate::{Error, Result};

/// A scene, as written in the file (paths not yet resolved; see [`LoadedScene`]).
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// The part: an OBJ file with UVs (a path, or an object with load options). Exactly one of
    /// `mesh` and `outline` must be given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<MeshSection>,
    /// A flat sheet-metal blank: a closed outline (and holes) in an SVG file, meshed by
    /// constrained Delaunay triangulation with UV = XY in millimetres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outline: Option<OutlineSection>,
    /// Length unit of the mesh coordinates and of every length in the scene (default `mm`).
    #[serde(default)]
    pub units: crate::mesh::Units,
    /// The brushed material (BRDF and its parameters) used by the preview.
    #[serde(default)]
    pub material: crate::render::Material,
    /// The lights. The highlight model uses the key light: the first directional light marked
    /// `"key": true`, else the first directional light.
    #[serde(default)]
    pub lights: Vec<crate::render::LightSpec>,
    /// The viewer: the eye of the highlight model and the preview's camera.
    pub view: ViewSection,
    /// The initial grain field and the highlight model's settings.
    #[serde(default)]
    pub field: FieldSection,
    /// Highlight edits, applied in order.
    #[serde(default)]
    pub edits: Vec<crate::edit::Edit>,
    /// The optimizer: energies, fabrication constraints, stopping rules.
    #[serde(default)]
    pub solver: crate::solve::SolverSettings,
    /// Brush strokes and their exports (SVG, G-code); absent: no tracing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub toolpaths: Option<toolpaths::ToolpathSection>,
    /// The preview image; absent: no rendering.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub render: Option<crate::render::RenderSettings>,
    /// Files for other programs: the part with its grain as glTF 2.0 binary
    /// (`export.glb`, docs/gltf.md); absent: no export.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub export: Option<crate::export::ExportSection>,
}

impl Scene {
    /// Parses a scene from JSON text. `path` is only used in messages.
    ///
    /// ```
    /// use std::path::Path;
    /// use grainline::scene::Scene;
    ///
    /// let ok = Scene::from_str(
    ///     r#"{"mesh": "part.obj", "view": {"eye": [0, -300, 100]},
    ///         "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}]}"#,
    ///     Path::new("scene.json"),
    /// )?;
    /// assert_eq!(ok.view.fov_deg, 35.0); // a documented default
    ///
    /// // Unknown keys are refused with their key path and line.
    /// let err = Scene::from_str(
    ///     "{\"mesh\": {\"path\": \"part.obj\",\n \"sclae\": 2}, \"view\": {\"eye\": [0, -3, 1]}}",
    ///     Path::new("scene.json"),
    /// )
    /// .unwrap_err()
    /// .to_string();
    /// assert!(err.starts_with("scene.json:2: mesh.sclae: unknown field `sclae`"), "{err}");
    /// # Ok::<(), grainline::Error>(())
    /// ```
    pub fn from_str(text: &str, path: &Path) -> Result<Scene> {
        // A UTF-8 byte-order mark (as some Windows editors write) is read past.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut de = serde_json::Deserializer::from_str(text);
        let scene: Scene = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            // `?`: serde_path_to_error's name for a key not read yet (a truncated file).
            let key = Some(e.path().to_string()).filter(|k| k != "?").unwrap_or_default();
            let inner = e.into_inner();
            let line = (inner.line() > 0).then_some(inner.line());
            let message = in_scene_terms(text, &key, &strip_position(&inner.to_string()));
            let message =
                if key.is_empty() || key == "." { message } else { format!("{key}: {message}") };
            Error::Scene { path: path.to_path_buf(), line, message }
        })?;
        let mut scene = scene;
        scene.default_lengths(text);
        // Trailing characters are reported by serde_json above; check the settings.
        scene.validate().map_err(|e| Error::Scene {
            path: path.to_path_buf(),
            line: None,
            message: e.to_string(),
        })?;
        Ok(scene)
    }

    /// The toolpaths section's length defaults as physical lengths in the scene's units, for
    /// the keys `text` (the scene file, already parsed) does not give (issue 31, item 4).
    fn default_lengths(&mut self, text: &str) {
        let Some(t) = &mut self.toolpaths else { return };
        let raw: serde_json::Value = serde_json::from_str(text).unwrap_or_default();
        let given =
            |key: &str| raw.pointer(&format!("/toolpaths/{}", key.replace('.', "/"))).is_some();
        t.default_lengths_in(self.units, &given);
    }

    /// Range and consistency checks of every section, naming the key path.
    pub fn validate(&self) -> Result<()> {
        match (&self.mesh, &self.outline) {
            (Some(m), None) => m.validate().map_err(|e| prefix("mesh", e))?,
            (None, Some(o)) => o.validate().map_err(|e| prefix("outline", e))?,
            (Some(_), Some(_)) => {
                return Err(Error::setting("outline", "give either `mesh` or `outline`, not both"))
            }
            (None, None) => {
                return Err(Error::setting(
                    "mesh",
                    "missing: give `mesh` (an OBJ file) or `outline` (an SVG outline)",
                ))
            }
        }
        self.view.validate().map_err(|e| prefix("view", e))?;
        self.field.validate().map_err(|e| prefix("field", e))?;
        self.material.validate().map_err(|e| prefix("material", e))?;
        crate::render::validate_lights(&self.lights).map_err(|e| prefix("lights", e))?;
        if crate::render::key_light_index(&self.lights).is_none() {
            return Err(Error::setting(
                "lights",
                "needs a directional or point light: the highlight model's key light \
                 (`\"key\": true` picks one when there are several)",
            ));
        }
        check_key_light_faces_the_view(&self.lights, &self.view)?;
        crate::edit::validate_edits(&self.edits).map_err(|e| prefix("edits", e))?;
        if let Some(t) = &self.toolpaths {
            t.validate_in(self.units).map_err(|e| prefix("toolpaths", e))?;
        }
        if let Some(r) = &self.render {
            r.validate().map_err(|e| prefix("render", e))?;
            crate::render::validate_with_lights(r, &self.lights)?;
        }
        self.solver.validate().map_err(|e| prefix("solver", e))?;
        if let Some(e) = &self.export {
            e.validate().map_err(|err| prefix("export", err))?;
            if (e.strokes || e.as_brushed) && self.toolpaths.is_none() {
                let key = if e.strokes { "export.strokes" } else { "export.as_brushed" };
                return Err(Error::setting(
                    key,
                    "needs the strokes: add a `toolpaths` section (its placement sets them)",
                ));
            }
        }
        Ok(())
    }
}

/// Refuses a directional key light that points straight away from the eye (within 0.8° of
/// the direction target → eye reversed): the half vector ω_in + ω_out vanishes at the target,
/// so the highlight the model shapes is undefined there. A light from behind or below the part
/// at any other angle is a light like any other.
fn check_key_light_faces_the_view(
    lights: &[crate::render::LightSpec],
    view: &ViewSection,
) -> Result<()> {
    use crate::render::LightSpec;
    let Some(i) = crate::render::key_light_index(lights) else { return Ok(()) };
    let LightSpec::Directional { direction, .. } = &lights[i] else { return Ok(()) };
    let d = nalgebra::Vector3::from(*direction);
    let out = nalgebra::Vector3::from(view.eye) - nalgebra::Vector3::from(view.target);
    let (dn, on) = (d.norm(), out.norm());
    if dn > 0.0 && on > 0.0 && d.dot(&out) / (dn * on) < -0.9999 {
        return Err(Error::setting(
            format!("lights[{i}].direction"),
            "the key light points straight away from the eye (opposite view.eye − \
             view.target): the half vector of light and view vanishes, so there is no highlight \
             to shape; turn the light towards the eye's side",
        ));
    }
    Ok(())
}

/// Prefixes a setting error's key path with its section.
pub fn prefix(section: &str, e: Error) -> Error {
    match e {
        Error::Setting { key, message } => {
            let key = if key.is_empty() {
                section.to_string()
            } else if key.starts_with('[') {
                format!("{section}{key}")
            } else {
                format!("{section}.{key}")
            };
            Error::Setting { key, message }
        }
        other => other,
    }
}

/// serde's wording of a type error said in the scene's terms: the Rust types it names
/// (`u32`, `f64`, `struct Scene`) as the JSON a scene writes, an enum given the wrong type with
/// the names it takes, an array with too many elements, and a scene that is not an object.
fn in_scene_terms(text: &str, key: &str, message: &str) -> String {
    let top = key.is_empty() || key == ".";
    if top && (message.starts_with("invalid type") || message.starts_with("invalid length")) {
        return "the scene must be a JSON object (`{\"mesh\": …, \"view\": …}`)".into();
    }
    if message == "trailing characters" && !top {
        return "holds more elements than it takes (an [x, y, z] takes three)".into();
    }
    if message == "expected value" && !top {
        return match enum_names(text, key) {
            Some(names) => format!("has the wrong type: expected {names}"),
            None => "has the wrong type (see docs/scene.md)".into(),
        };
    }
    if let Some(rest) = message.strip_prefix("invalid length ") {
        if rest.contains("expected struct") {
            return "must be a JSON object (`{…}`), not an array".into();
        }
        // "invalid length 4, expected an array of length 3" / "… expected 3 elements in
        // sequence": a vector with the wrong number of elements.
        if let Some((n, wanted)) = rest.split_once(", expected ") {
            let m: String = wanted.chars().filter(char::is_ascii_digit).collect();
            if !m.is_empty() {
                return format!("holds {n} elements; it takes {m}");
            }
        }
    }
    let mut out = message.to_string();
    for (rust, json) in [
        ("expected u8", "expected a whole number ≥ 0"),
        ("expected u16", "expected a whole number ≥ 0"),
        ("expected u32", "expected a whole number ≥ 0"),
        ("expected u64", "expected a whole number ≥ 0"),
        ("expected usize", "expected a whole number ≥ 0"),
        ("expected i32", "expected a whole number"),
        ("expected i64", "expected a whole number"),
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
        ("expected a boolean", "expected true or false"),
    ] {
        if let Some(head) = out.strip_suffix(rust) {
            out = format!("{head}{json}");
        }
    }
    if let Some(i) = out.find("expected struct ") {
        out = format!("{}expected a JSON object (`{{…}}`)", &out[..i]);
    }
    out
}

/// The names the enum at `key` takes, from serde's own message for an unknown name there
/// (the scene parsed again with a string at `key`).
fn enum_names(text: &str, key: &str) -> Option<String> {
    let mut value: serde_json::Value = serde_json::from_str(text).ok()?;
    let mut pointer = String::new();
    for part in key.split('.') {
        let (name, index) = match part.find('[') {
            Some(i) => (&part[..i], Some(&part[i..])),
            None => (part, None),
        };
        if !name.is_empty() {
            pointer.push('/');
            pointer.push_str(name);
        }
        for k in index.into_iter().flat_map(|s| s.split(['[', ']'])).filter(|s| !s.is_empty()) {
            pointer.push('/');
            pointer.push_str(k);
        }
    }
    *value.pointer_mut(&pointer)? = serde_json::Value::String("\u{1}".into());
    let err = serde_path_to_error::deserialize::<_, Scene>(value).err()?;
    let m = err.into_inner().to_string();
    let i = m.find("expected ")?;
    let names = &m[i + "expected ".len()..];
    (m.contains("unknown variant")).then(|| strip_position(names))
}

/// serde_json appends " at line L column C"; the scene error carries the line itself.
fn strip_position(s: &str) -> String {
    match s.rfind(" at line ") {
        Some(i) => s[..i].to_string(),
        None => s.to_string(),
    }
}

/// A scene read from a file, with the directory its relative paths are relative to.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene file.
    pub path: PathBuf,
    /// The scene.
    pub scene: Scene,
    /// The scene file's directory.
    pub base: PathBuf,
}

impl LoadedScene {
    /// Reads and checks a scene file.
    pub fn read(path: &Path) -> Result<LoadedScene> {
        // Refused unread when it is a FIFO, a device or a directory, or too big.
        let text =
            crate::output::read_bounded_text(path, crate::limits::MAX_SCENE_BYTES, "a scene file")?;
        let scene = Scene::from_str(&text, path)?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Ok(LoadedScene { path: path.to_path_buf(), scene, base })
    }

    /// A setting error found while running (e.g. an edit whose support holds no vertex),
    /// turned into an error that names the scene file.
    pub fn wrap(&self, e: Error) -> Error {
        match e {
            Error::Setting { key, message } => Error::Scene {
                path: self.path.clone(),
                line: None,
                message: format!("{key}: {message}"),
            },
            other => other,
        }
    }

    /// A path of the scene resolved against the scene file's directory.
    pub fn input(&self, p: &str) -> PathBuf {
        let p = Path::new(p);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base.join(p)
        }
    }
}

/// The JSON Schema of the scene file (draft 2020-12), for editors' completion and checking.
pub fn json_schema() -> serde_json::Value {
    let schema = schemars::schema_for!(Scene);
    serde_json::to_value(&schema).unwrap_or(serde_json::Value::Null)
}

/// The schema as pretty JSON text ending in a newline (what docs/scene.schema.json holds).
pub fn json_schema_text() -> String {
    let mut s = serde_json::to_string_pretty(&json_schema()).unwrap_or_default();
    s.push('\n');
    s
}
