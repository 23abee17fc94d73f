//! The scene sections owned by the core: `mesh`, `outline`, `view` and `field`.

use std::borrow::Cow;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::geometry::{GradientForm, NormalSource};
use crate::highlight::critical::DEFAULT_CRITICAL_THRESHOLD;
use crate::highlight::{InitialField, Symmetry, View};
use crate::mesh::load::{DegeneratePolicy, LoadOptions};
use crate::{Error, Result};

/// `mesh`: a mesh file (OBJ, STL or PLY), written as a path (`"mesh": "kettle.obj"`) or as an
/// object with load options.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeshFull {
    /// The mesh file (OBJ, STL binary or ASCII, PLY ASCII or binary), relative to the scene file.
    pub path: String,
    /// Load only the object or group with this name (default: merge all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object: Option<String>,
    /// Weld vertices closer than this (file units) before anything else (an STL is welded
    /// exactly, at 0, when this is not given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weld: Option<f64>,
    /// Uniform scale applied after loading (default 1).
    #[serde(default = "one")]
    pub scale: f64,
    /// Accept non-manifold edges and vertices (default false).
    #[serde(default)]
    pub allow_nonmanifold: bool,
    /// Refuse zero-area faces instead of dropping them (default false).
    #[serde(default)]
    pub strict_degenerate: bool,
    /// Crease angle in degrees, in [0, 180] (default 40): the preview does not average vertex
    /// normals across an edge whose faces' normals differ by more than this (docs/math.md §3,
    /// "Creases"); 180 turns it off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crease_angle: Option<f64>,
    /// `split` (the default) cuts the part along its sharp edges (those above `crease_angle`)
    /// into smooth patches, each with its own vertices, normals, frames and grain
    /// (docs/math.md §3, "Patches"); `none` keeps the part whole, averaging across sharp edges.
    #[serde(default, skip_serializing_if = "PatchMode::is_default")]
    pub patches: PatchMode,
    /// `recognize` (the default) reads a CAD export's curved faces as the planes, cylinders,
    /// cones, spheres and tori they approximate, and takes normals, frames and curvatures
    /// from those surfaces (docs/math.md §3, "Recognized surfaces"); `off` reads the facets.
    #[serde(default, skip_serializing_if = "SurfaceMode::is_default")]
    pub surfaces: SurfaceMode,
    /// Refinement of the part inside the edits' brushes (default: where an edit needs it;
    /// docs/math.md §12).
    #[serde(default, skip_serializing_if = "RefineSettings::is_default")]
    pub refine: RefineSettings,
}

/// `mesh.patches`: whether the part is cut into smooth patches along its sharp edges.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum PatchMode {
    /// Cut along every sharp edge that separates two patches (the default).
    #[default]
    Split,
    /// Keep the part whole.
    None,
}

impl PatchMode {
    fn is_default(&self) -> bool {
        *self == PatchMode::Split
    }
}

/// `mesh.surfaces`: whether the part's surfaces are recognized.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceMode {
    /// Recognize planes, cylinders, cones, spheres and tori (the default).
    #[default]
    Recognize,
    /// Read the facets as they are.
    Off,
}

impl SurfaceMode {
    fn is_default(&self) -> bool {
        *self == SurfaceMode::Recognize
    }
}

/// `mesh.refine`: a brush or a drawn curve finer than the part's triangles cannot be followed
/// by a grain that lives on vertices, so the triangles inside each bend, expand and curve are
/// split (new vertices appended; the part's own keep their indices) until no edge is longer
/// than `edge` × the brush radius (for a curve, × the smaller of its radius and width).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RefineSettings {
    /// `edits` (the default) refines inside the edits' brushes; `none` keeps the part's
    /// triangles as they are.
    #[serde(default)]
    pub mode: RefineMode,
    /// The longest edge allowed inside a brush, as a fraction of its radius (default 1/3; a
    /// curve: ⅜ of this fraction of the smaller of its radius and `width`, r/8 by default).
    #[serde(default = "default_refine_edge")]
    pub edge: f64,
    /// Most vertices refinement may add (default 2,000,000); past it the scene is refused.
    #[serde(default = "default_refine_budget")]
    pub max_vertices: usize,
    /// The largest turn, in degrees, of the key light's half vector (its tangent part) along
    /// an edge inside a bend, expand or curve (default 20): faces along which it turns more
    /// are split further, down to ⅛ of the edge `edge` asks for. 180 asks for nothing.
    #[serde(default = "default_refine_turn")]
    pub turn: f64,
}

/// `mesh.refine.mode`.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum RefineMode {
    /// Refine inside the edits' brushes where the triangles are too coarse.
    #[default]
    Edits,
    /// Never refine.
    None,
}

fn default_refine_edge() -> f64 {
    1.0 / 3.0
}

fn default_refine_turn() -> f64 {
    crate::edit::resolution::DEFAULT_MAX_TURN_DEG
}

fn default_refine_budget() -> usize {
    2_000_000
}

impl Default for RefineSettings {
    fn default() -> Self {
        RefineSettings {
            mode: RefineMode::Edits,
            edge: default_refine_edge(),
            max_vertices: default_refine_budget(),
            turn: default_refine_turn(),
        }
    }
}

impl RefineSettings {
    fn is_default(&self) -> bool {
        *self == RefineSettings::default()
    }

    /// Range-checks `edge` (in [0.05, 2]) and `turn` (in [5, 180]); keys are relative to
    /// `mesh.refine`.
    pub fn validate(&self) -> Result<()> {
        if !(self.edge.is_finite() && (0.05..=2.0).contains(&self.edge)) {
            return Err(Error::setting(
                "edge",
                format!("must be within [0.05, 2], got {}", crate::error::fmt_num(self.edge)),
            ));
        }
        if !(self.turn.is_finite() && (5.0..=180.0).contains(&self.turn)) {
            return Err(Error::setting(
                "turn",
                format!(
                    "must be within [5, 180] degrees, got {}",
                    crate::error::fmt_num(self.turn)
                ),
            ));
        }
        Ok(())
    }
}

fn one() -> f64 {
    1.0
}

/// The `mesh` section (see [`MeshFull`]; a bare string is its `path`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub struct MeshSection(pub MeshFull);

impl<'de> Deserialize<'de> for MeshSection {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = MeshSection;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a path to a mesh file (OBJ, STL, PLY), or an object with `path` and load \
                     options",
                )
            }
            fn visit_str<E: serde::de::Error>(
                self,
                s: &str,
            ) -> std::result::Result<Self::Value, E> {
                Ok(MeshSection(MeshFull { path: s.into(), scale: 1.0, ..MeshFull::default() }))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<Self::Value, A::Error> {
                MeshFull::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(MeshSection)
            }
        }
        d.deserialize_any(V)
    }
}

impl schemars::JsonSchema for MeshSection {
    fn schema_name() -> Cow<'static, str> {
        "MeshSection".into()
    }
    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let full = generator.subschema_for::<MeshFull>();
        schemars::json_schema!({
            "description": "A mesh file (OBJ, STL or PLY): a path relative to the scene, or an object with load options.",
            "anyOf": [{ "type": "string" }, full]
        })
    }
}

impl MeshSection {
    /// Range checks.
    pub fn validate(&self) -> Result<()> {
        let m = &self.0;
        if m.path.trim().is_empty() {
            return Err(Error::setting("path", "is empty"));
        }
        if let Some(w) = m.weld {
            if !(w.is_finite() && w >= 0.0) {
                return Err(Error::setting(
                    "weld",
                    format!("must be a finite number ≥ 0, got {}", crate::error::fmt_num(w)),
                ));
            }
        }
        if let Some(a) = m.crease_angle {
            if !(a.is_finite() && (0.0..=180.0).contains(&a)) {
                return Err(Error::setting(
                    "crease_angle",
                    format!("must be in [0, 180] degrees, got {}", crate::error::fmt_num(a)),
                ));
            }
        }
        m.refine.validate().map_err(|e| crate::scene::prefix("refine", e))?;
        let (lo, hi) = crate::limits::MESH_SCALE_RANGE;
        if !(m.scale.is_finite() && (lo..=hi).contains(&m.scale)) {
            return Err(Error::setting(
                "scale",
                format!(
                    "must be in [1e-12, 1e12] (limits::MESH_SCALE_RANGE), got {}",
                    crate::error::fmt_num(m.scale)
                ),
            ));
        }
        Ok(())
    }

    /// The crease angle in degrees (`crease_angle`, default
    /// [`DEFAULT_CREASE_ANGLE_DEG`](crate::geometry::normals::DEFAULT_CREASE_ANGLE_DEG)).
    pub fn crease_angle(&self) -> f64 {
        self.0.crease_angle.unwrap_or(crate::geometry::normals::DEFAULT_CREASE_ANGLE_DEG)
    }

    /// The loader's options for this section and the scene's units.
    pub fn load_options(&self, units: crate::mesh::Units) -> LoadOptions {
        let m = &self.0;
        LoadOptions {
            object: m.object.clone(),
            weld: m.weld,
            units,
            scale: m.scale,
            allow_nonmanifold: m.allow_nonmanifold,
            degenerate: if m.strict_degenerate {
                DegeneratePolicy::Error
            } else {
                DegeneratePolicy::Drop
            },
            ..LoadOptions::default()
        }
    }
}

/// `outline`: a flat blank from an SVG outline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutlineSection {
    /// The SVG file whose paths are the closed outline and its holes.
    pub path: String,
    /// Longest triangle edge in millimetres (default: none, the angle criterion alone decides);
    /// refused when the panel would get more than about 4 × 10⁶ triangles.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_edge: Option<f64>,
    /// Smallest triangle angle in degrees sought by the refinement (default 25, at most 30).
    #[serde(default = "default_min_angle")]
    pub min_angle: f64,
}

fn default_min_angle() -> f64 {
    25.0
}

impl OutlineSection {
    /// Range checks.
    pub fn validate(&self) -> Result<()> {
        if self.path.trim().is_empty() {
            return Err(Error::setting("path", "is empty"));
        }
        if let Some(e) = self.max_edge {
            if !(e.is_finite() && e > 0.0) {
                return Err(Error::setting(
                    "max_edge",
                    format!("must be > 0, got {}", crate::error::fmt_num(e)),
                ));
            }
        }
        if !(self.min_angle.is_finite() && (0.0..=30.0).contains(&self.min_angle)) {
            return Err(Error::setting(
                "min_angle",
                format!(
                    "must be in [0, 30] degrees, got {}",
                    crate::error::fmt_num(self.min_angle)
                ),
            ));
        }
        Ok(())
    }
}

/// How the highlight model sees the viewer.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum ViewModel {
    /// A point eye at `eye`: each vertex sees its own view direction (the default; it matches
    /// the preview's perspective camera).
    #[default]
    Point,
    /// A distant viewer in the direction `eye − target` (the paper's setting).
    Distant,
}

/// `view`: the viewer of the highlight model and the preview's camera.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ViewSection {
    /// Eye position (scene units).
    pub eye: [f64; 3],
    /// The point looked at (default the origin).
    #[serde(default)]
    pub target: [f64; 3],
    /// The camera's up direction (default +Z).
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Vertical field of view of the preview camera, degrees, in (0, 179] (default 35).
    #[serde(default = "default_fov")]
    pub fov_deg: f64,
    /// `point` (default) or `distant`.
    #[serde(default)]
    pub model: ViewModel,
}

fn default_up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

fn default_fov() -> f64 {
    35.0
}

fn finite3(key: &str, v: &[f64; 3]) -> Result<Vector3<f64>> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vector3::new(v[0], v[1], v[2]))
    } else {
        Err(Error::setting(
            key,
            format!("must be three finite numbers, got {}", crate::error::fmt_vec3(v)),
        ))
    }
}

impl ViewSection {
    /// Range checks.
    pub fn validate(&self) -> Result<()> {
        let eye = finite3("eye", &self.eye)?;
        let target = finite3("target", &self.target)?;
        let up = finite3("up", &self.up)?;
        for (key, v) in [("eye", &self.eye), ("target", &self.target), ("up", &self.up)] {
            if let Some(c) = v.iter().find(|c| c.abs() > crate::limits::MAX_COORDINATE) {
                return Err(Error::setting(
                    key,
                    format!(
                        "{} is beyond ±{:e} (limits::MAX_COORDINATE, the largest coordinate a \
                         part may have)",
                        crate::error::fmt_num(*c),
                        crate::limits::MAX_COORDINATE
                    ),
                ));
            }
        }
        // The preview camera's own check, so what the scene accepts the renderer accepts
        // (e.g. its field of view is at most 179°, the limit of its projection).
        let camera = crate::render::Camera { eye, target, up, fov_deg: self.fov_deg };
        camera.validate().map_err(|e| match e {
            Error::Setting { key, message } => {
                Error::setting(key.strip_prefix("view.").unwrap_or(&key).to_string(), message)
            }
            e => e,
        })?;
        let d = target - eye;
        if d.norm() <= 0.0 {
            return Err(Error::setting("target", "must differ from `eye`"));
        }
        if up.norm() <= 0.0 || d.cross(&up).norm() <= 1e-9 * d.norm() * up.norm() {
            return Err(Error::setting("up", "must be non-zero and not parallel to the view"));
        }
        Ok(())
    }

    /// The highlight model's view.
    pub fn view(&self) -> View {
        let eye = Vector3::from(self.eye);
        match self.model {
            ViewModel::Point => View::Eye(eye),
            ViewModel::Distant => View::Direction(eye - Vector3::from(self.target)),
        }
    }
}

/// The initial field's kind (`field.init`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum InitKind {
    /// The direction of increasing u of the UV map (needs UVs).
    Uv,
    /// The smoothest field (Knöppel et al. 2013), the default.
    #[default]
    Smooth,
    /// Minimum principal curvature directions.
    CurvatureMin,
    /// Maximum principal curvature directions.
    CurvatureMax,
    /// A world direction (`field.world`) projected into each tangent plane.
    World,
    /// Per-vertex directions read from `field.directions` (a JSON object whose `u` holds one
    /// [x, y, z] per vertex).
    Directions,
    /// A grain painted elsewhere: a direction or angle map in UV space (`field.map`,
    /// docs/formats.md "Grain maps"; needs UVs, or the layout grainline makes).
    Map,
}

/// A grain map read as the initial field (`field.map`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MapSource {
    /// The PNG, relative to the scene.
    pub path: String,
    /// `direction` (RG across the grain, as `export.maps` writes grain-direction.png and the
    /// glb's anisotropyTexture) or `angle` (the grain's angle in [0, π) encoded θ/π, as
    /// grain-angle.png).
    pub kind: crate::texmap::MapKind,
}

/// Whether the part's noise picks the fit radius (`field.noise`, docs/math.md §5.6, "Noise
/// scale").
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum NoiseMode {
    /// Estimate the noise from the mesh and fit normals and curvature over the radius it asks
    /// for; on a clean part that is the 1-ring, as with `off` (the default).
    #[default]
    Auto,
    /// Fit over the 1-ring (or `field.fit_radius` when set), whatever the noise.
    Off,
}

impl NoiseMode {
    /// The default, `auto`.
    pub fn is_auto(&self) -> bool {
        *self == NoiseMode::Auto
    }
}

/// The field's symmetry (`field.symmetry`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SymmetryKind {
    /// k = 2: u and −u are the same grain (every BRDF grainline renders is centrally
    /// symmetric; the default).
    #[default]
    Line,
    /// k = 1: an oriented field.
    Oriented,
}

impl SymmetryKind {
    /// The model's symmetry.
    pub fn symmetry(self) -> Symmetry {
        match self {
            SymmetryKind::Line => Symmetry::Line,
            SymmetryKind::Oriented => Symmetry::Oriented,
        }
    }
}

/// `field`: the initial grain field and the highlight model's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct FieldSection {
    /// The initial field (default `smooth`).
    pub init: InitKind,
    /// The world direction for `init: "world"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub world: Option<[f64; 3]>,
    /// The directions file for `init: "directions"`, relative to the scene.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub directions: Option<String>,
    /// The grain map for `init: "map"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map: Option<MapSource>,
    /// `line` (k = 2, default) or `oriented` (k = 1).
    pub symmetry: SymmetryKind,
    /// Which regression of Eq. 10 estimates ∇φ (default `angle`).
    pub gradient_form: GradientForm,
    /// Initial vertex normals (default `angle-weighted`).
    pub normals: NormalSource,
    /// hᵀn above which a vertex is a critical point (default 0.9995).
    pub critical_threshold: f64,
    /// Fit normals and curvature over the vertices within this distance (scene units) instead
    /// of each vertex's 1-ring: overrides the radius `noise: "auto"` picks (none by default;
    /// docs/math.md §5.6).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit_radius: Option<f64>,
    /// `auto` (default): estimate the part's noise and, on a scan or a sculpted part, fit over
    /// the radius it asks for (the estimate is in the run report's `noise`); `off`: the 1-ring.
    #[serde(skip_serializing_if = "NoiseMode::is_auto")]
    pub noise: NoiseMode,
    /// Where `grainline run` writes FIELD.json (none by default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output: Option<String>,
}

impl Default for FieldSection {
    fn default() -> Self {
        FieldSection {
            init: InitKind::Smooth,
            world: None,
            directions: None,
            map: None,
            symmetry: SymmetryKind::Line,
            gradient_form: GradientForm::default(),
            normals: NormalSource::default(),
            critical_threshold: DEFAULT_CRITICAL_THRESHOLD,
            fit_radius: None,
            noise: NoiseMode::Auto,
            output: None,
        }
    }
}

impl FieldSection {
    /// Range and consistency checks.
    pub fn validate(&self) -> Result<()> {
        match self.init {
            InitKind::World => {
                let w = finite3(
                    "world",
                    &self.world.ok_or_else(|| {
                        Error::setting("world", "is required by `init: \"world\"`")
                    })?,
                )?;
                if w.norm() <= 0.0 {
                    return Err(Error::setting("world", "must be non-zero"));
                }
            }
            InitKind::Directions if self.directions.is_none() => {
                return Err(Error::setting("directions", "is required by `init: \"directions\"`"));
            }
            InitKind::Map if self.map.is_none() => {
                return Err(Error::setting("map", "is required by `init: \"map\"`"));
            }
            _ => {}
        }
        if self.world.is_some() && self.init != InitKind::World {
            return Err(Error::setting("world", "is only used with `init: \"world\"`"));
        }
        if self.directions.is_some() && self.init != InitKind::Directions {
            return Err(Error::setting("directions", "is only used with `init: \"directions\"`"));
        }
        if self.map.is_some() && self.init != InitKind::Map {
            return Err(Error::setting("map", "is only used with `init: \"map\"`"));
        }
        if let Some(r) = self.fit_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::setting(
                    "fit_radius",
                    format!("must be a positive distance, got {}", crate::error::fmt_num(r)),
                ));
            }
        }
        let t = self.critical_threshold;
        if !(t.is_finite() && t > 0.0 && t <= 1.0) {
            return Err(Error::setting(
                "critical_threshold",
                format!("must be in (0, 1], got {}", crate::error::fmt_num(t)),
            ));
        }
        Ok(())
    }

    /// The initial field; `directions` are the already-read per-vertex directions when
    /// `init` is `directions`, `map` the map read when it is `map`.
    pub fn initial_field(
        &self,
        directions: Option<Vec<Vector3<f64>>>,
        map: Option<crate::texmap::GrainMap>,
    ) -> InitialField {
        match self.init {
            InitKind::Uv => InitialField::Uv,
            InitKind::Smooth => InitialField::Smooth,
            InitKind::CurvatureMin => InitialField::CurvatureMin,
            InitKind::CurvatureMax => InitialField::CurvatureMax,
            InitKind::World => {
                InitialField::World(Vector3::from(self.world.unwrap_or([1.0, 0.0, 0.0])))
            }
            InitKind::Directions => InitialField::Directions(directions.unwrap_or_default()),
            InitKind::Map => match map {
                Some(m) => InitialField::Map(m),
                None => InitialField::Directions(Vec::new()),
            },
        }
    }
}
