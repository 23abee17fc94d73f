//! The `field` job: geometry, an initial grain field and its highlight field, and the FIELD.json
//! file format (docs/formats.md).

use std::path::Path;

use nalgebra::{Matrix2, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::geometry::{Geometry, GeometryDiagnostics, GeometryOptions, GradientForm};
use crate::highlight::critical::{critical_points, DEFAULT_CRITICAL_THRESHOLD};
use crate::highlight::{
    h_gradients, half_vectors, highlight_field_near, initial_field, HighlightField, InitialField,
    Lighting, Symmetry, View,
};
use crate::mesh::Mesh;
use crate::{Error, Result};

/// Options of [`compute_field`].
#[derive(Clone, Debug)]
pub struct FieldOptions {
    /// Light and view.
    pub lighting: Lighting,
    /// The initial grain field.
    pub init: InitialField,
    /// k = 1 or 2.
    pub symmetry: Symmetry,
    /// Which Eq. 10 regression.
    pub gradient_form: GradientForm,
    /// Geometry options.
    pub geometry: GeometryOptions,
    /// hᵀn above which a vertex is a critical point.
    pub critical_threshold: f64,
    /// The normals of the first vertices, kept as given ([`Geometry::compute_keeping`]): a
    /// part refined inside the brushes keeps its own vertices' normals from before the
    /// refinement, and its new vertices the ones the refinement interpolated. Empty: every
    /// normal computed.
    pub kept_normals: Vec<Vector3<f64>>,
    /// The exact geometry of the vertices on recognized surfaces
    /// ([`crate::geometry::surfaces`], [`Geometry::compute_exact`]); applied after
    /// `kept_normals`. Empty: none.
    pub surface_points: Vec<Option<crate::geometry::surfaces::SurfacePoint>>,
}

impl FieldOptions {
    /// Default options for a lighting.
    pub fn new(lighting: Lighting) -> Self {
        FieldOptions {
            lighting,
            init: InitialField::Smooth,
            symmetry: Symmetry::Oriented,
            gradient_form: GradientForm::Angle,
            geometry: GeometryOptions::default(),
            critical_threshold: DEFAULT_CRITICAL_THRESHOLD,
            kept_normals: Vec::new(),
            surface_points: Vec::new(),
        }
    }
}

/// Everything [`compute_field`] computes.
#[derive(Clone, Debug)]
pub struct FieldResult {
    /// Per-vertex geometry.
    pub geometry: Geometry,
    /// The grain angle per vertex (in the geometry's frames).
    pub phi: Vec<f64>,
    /// Half vectors.
    pub h: Vec<Vector3<f64>>,
    /// The near term's G per vertex (a point eye or light; `None` when both are distant):
    /// [`crate::highlight::h_gradients`].
    pub h_gradient: Option<Vec<Matrix2<f64>>>,
    /// ∇φ, m and ℓ (Eq. 7 with the near term).
    pub highlight: HighlightField,
    /// Critical points.
    pub critical: Vec<bool>,
    /// Vertices where the initial field needed a fallback.
    pub fallback_vertices: Vec<u32>,
}

/// Computes geometry, the initial field, and its highlight field.
pub fn compute_field(mesh: &Mesh, options: &FieldOptions) -> Result<FieldResult> {
    if !(options.critical_threshold.is_finite() && options.critical_threshold <= 1.0) {
        return Err(Error::invalid_arg("critical-threshold", "must be a finite number ≤ 1"));
    }
    let geometry = Geometry::compute_exact(
        mesh,
        &options.geometry,
        &options.kept_normals,
        &options.surface_points,
    )
    .0;
    crate::cancel::checkpoint("field")?;
    let init = initial_field(mesh, &geometry, &options.init, options.symmetry)?;
    let normals: Vec<Vector3<f64>> = geometry.frames.par_iter().map(|f| f.n).collect();
    let h = half_vectors(&options.lighting, &mesh.positions, &normals);
    let h_gradient = h_gradients(&options.lighting, &mesh.positions, &geometry.frames);
    let highlight = highlight_field_near(
        &geometry,
        &init.phi,
        options.symmetry,
        options.gradient_form,
        &h,
        h_gradient.as_deref(),
    );
    let critical = critical_points(&h, normals.into_iter(), options.critical_threshold);
    Ok(FieldResult {
        geometry,
        phi: init.phi,
        h,
        h_gradient,
        highlight,
        critical,
        fallback_vertices: init.fallback_vertices,
    })
}

/// The `meta` object of FIELD.json.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FieldMeta {
    /// The mesh file as given.
    pub mesh: String,
    /// Length unit of every position, area (unit²) and curvature (1/unit).
    pub units: String,
    /// Direction towards the light (unit). For a point light: the direction from the part's
    /// bounding-box centre towards `light_position`.
    pub light: [f64; 3],
    /// The position of a point key light; absent for a distant light.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light_position: Option<[f64; 3]>,
    /// Direction towards a distant viewer (unit), or null with an eye.
    pub view: Option<[f64; 3]>,
    /// Eye position, or null for a distant view.
    pub eye: Option<[f64; 3]>,
    /// True for a line field (k = 2).
    pub symmetric: bool,
    /// How the initial field was made.
    pub init: String,
    /// Vertices whose initial direction used the documented fallback.
    pub fallback_vertices: Vec<u32>,
    /// The critical-point threshold on hᵀn.
    pub critical_threshold: f64,
    /// Vertex count.
    pub vertices: usize,
    /// Geometry fallbacks, and the edits measured as brushed.
    pub diagnostics: FieldDiagnostics,
    /// The grainline version that wrote the file.
    pub grainline_version: String,
}

/// `meta.diagnostics`: the counts of the geometry's fallbacks ([`GeometryDiagnostics`]) and,
/// version 3, the edits measured as brushed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FieldDiagnostics {
    /// Vertices with no usable normal (isolated or only zero-area faces): normal set to +Z.
    pub fallback_normals: usize,
    /// Vertices whose jet fit needed more than the 1-ring.
    pub extended_jet_rings: usize,
    /// Vertices where no quadric could be fitted (W = 0).
    pub failed_jet_fits: usize,
    /// Vertices whose Eq. 10 stencil needed more than the 1-ring.
    pub extended_gradient_stencils: usize,
    /// Vertices with no Eq. 10 stencil (∇φ = 0).
    pub empty_gradient_stencils: usize,
    /// Version 3, `grainline run` with strokes traced and a bend, expand or curve edit
    /// (`toolpaths.as_brushed_fidelity`): each such edit's fidelity on the designed grain and
    /// on the grain rebuilt from the strokes, as the run report's `as_brushed.fidelity` gives
    /// it (docs/formats.md). Held as JSON here: the measure is the `fidelity` module's, a layer
    /// above this one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fidelity: Option<serde_json::Value>,
}

impl From<GeometryDiagnostics> for FieldDiagnostics {
    fn from(g: GeometryDiagnostics) -> Self {
        FieldDiagnostics {
            fallback_normals: g.fallback_normals,
            extended_jet_rings: g.extended_jet_rings,
            failed_jet_fits: g.failed_jet_fits,
            extended_gradient_stencils: g.extended_gradient_stencils,
            empty_gradient_stencils: g.empty_gradient_stencils,
            fidelity: None,
        }
    }
}

/// The FIELD.json version [`FieldFile::new`] writes: 3, which added
/// `meta.diagnostics.fidelity` to version 2 (which added `faces` to version 1).
/// [`FieldFile::read`] reads all three.
pub const FIELD_VERSION: u32 = 3;

/// FIELD.json: one array per quantity, one entry per vertex, world coordinates, and the
/// triangles the field lives on.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FieldFile {
    /// Always `"grainline-field"`.
    pub format: String,
    /// Format version: [`FIELD_VERSION`] when written; 1 (no `faces`), 2 or 3 when read.
    pub version: u32,
    /// Where the data came from.
    pub meta: FieldMeta,
    /// Vertex positions.
    pub position: Vec<[f64; 3]>,
    /// Version 2: the triangles of the mesh the field lives on (after the patch split and the
    /// refinement), as vertex indices counter-clockwise around the outward normal. Absent in
    /// a version-1 file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub faces: Option<Vec<[u32; 3]>>,
    /// Unit vertex normals (jet-refined).
    pub normal: Vec<[f64; 3]>,
    /// Unit grain directions.
    pub u: Vec<[f64; 3]>,
    /// The Eq. 7 highlight tangent (not normalized; with the near term for a point eye or light).
    pub ell: Vec<[f64; 3]>,
    /// Maximum principal curvature (positive on a sphere with outward normals).
    pub k1: Vec<f64>,
    /// Minimum principal curvature.
    pub k2: Vec<f64>,
    /// Mixed Voronoi areas.
    pub area: Vec<f64>,
    /// hᵀn above the threshold.
    pub critical: Vec<bool>,
    /// `grainline optimize`: the grain directions before the solve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_before: Option<Vec<[f64; 3]>>,
    /// `grainline optimize`: the grain angles before the solve (radians, in the tangent frames).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phi_before: Option<Vec<f64>>,
    /// `grainline optimize`: the grain angles after the solve (radians, in the tangent frames).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phi: Option<Vec<f64>>,
    /// `grainline optimize`: the target highlight tangent ℓ* per vertex (null where none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_ell: Option<Vec<Option<[f64; 3]>>>,
    /// The part cut into smooth patches (`mesh.patches`): for each vertex appended after the
    /// part's own `n` (index `n + k`), the part's vertex it copies. Absent when no vertex was
    /// split; vertices after these are the refinement's (`mesh.refine`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patch_copies: Option<Vec<u32>>,
    /// The surfaces a CAD part was read as (`mesh.surfaces`; docs/formats.md, "Recognized
    /// surfaces"). Absent when none was recognized.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surfaces: Option<crate::geometry::surfaces::SurfaceReport>,
}

/// A short name for an initial field.
pub fn init_name(init: &InitialField) -> String {
    match init {
        InitialField::Uv => "uv".into(),
        InitialField::Smooth => "smooth".into(),
        InitialField::CurvatureMin => "curvature-min".into(),
        InitialField::CurvatureMax => "curvature-max".into(),
        InitialField::World(w) => format!("world:{},{},{}", w.x, w.y, w.z),
        InitialField::Directions(_) => "directions".into(),
        InitialField::Map(_) => "map".into(),
    }
}

/// `meta.light`: the distant light's direction, or for a point light the direction from the
/// centre of the part's bounding box towards it (the lighting's own nominal direction where
/// the light sits at that centre).
fn nominal_light(lighting: &Lighting, mesh: &Mesh) -> Vector3<f64> {
    match lighting.light_position {
        None => lighting.light,
        Some(l) => {
            let d = l - crate::highlight::lighting::centre_of(&mesh.positions);
            let n = d.norm();
            if n > 0.0 && n.is_finite() {
                d / n
            } else {
                lighting.light
            }
        }
    }
}

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

impl FieldFile {
    /// Builds the file contents; fails (naming the quantity and vertex) if anything is not
    /// finite, so no NaN or Inf is ever written.
    pub fn new(
        mesh: &Mesh,
        mesh_name: &str,
        options: &FieldOptions,
        r: &FieldResult,
    ) -> Result<Self> {
        let g = &r.geometry;
        let (view, eye) = match options.lighting.view {
            View::Direction(d) => (Some(arr(&d)), None),
            View::Eye(e) => (None, Some(arr(&e))),
        };
        let file = FieldFile {
            format: "grainline-field".into(),
            version: FIELD_VERSION,
            meta: FieldMeta {
                mesh: mesh_name.into(),
                units: mesh.units.as_str().into(),
                light: arr(&nominal_light(&options.lighting, mesh)),
                light_position: options.lighting.light_position.as_ref().map(arr),
                view,
                eye,
                symmetric: options.symmetry == Symmetry::Line,
                init: init_name(&options.init),
                fallback_vertices: r.fallback_vertices.clone(),
                critical_threshold: options.critical_threshold,
                vertices: mesh.num_vertices(),
                diagnostics: g.diagnostics.into(),
                grainline_version: env!("CARGO_PKG_VERSION").into(),
            },
            position: mesh.positions.iter().map(arr).collect(),
            faces: Some(mesh.faces.clone()),
            normal: g.frames.iter().map(|f| arr(&f.n)).collect(),
            u: g.directions_of(&r.phi).iter().map(arr).collect(),
            ell: r.highlight.ell.iter().map(arr).collect(),
            k1: g.principal.iter().map(|p| p.k1).collect(),
            k2: g.principal.iter().map(|p| p.k2).collect(),
            area: g.areas.clone(),
            critical: r.critical.clone(),
            u_before: None,
            phi_before: None,
            phi: None,
            target_ell: None,
            patch_copies: None,
            surfaces: None,
        };
        file.check_finite()?;
        Ok(file)
    }

    /// Errors on the first non-finite number, naming the quantity and the vertex.
    pub fn check_finite(&self) -> Result<()> {
        let vecs = [
            ("position", &self.position),
            ("normal", &self.normal),
            ("u", &self.u),
            ("ell", &self.ell),
        ];
        for (name, v) in vecs {
            if let Some(i) = v.iter().position(|x| x.iter().any(|c| !c.is_finite())) {
                return Err(Error::Numerical {
                    stage: "field output",
                    message: format!("{name} of vertex {i} is not finite"),
                });
            }
        }
        let extras = [
            (
                "u_before",
                self.u_before
                    .as_ref()
                    .and_then(|v| v.iter().position(|x| x.iter().any(|c| !c.is_finite()))),
            ),
            (
                "phi_before",
                self.phi_before.as_ref().and_then(|v| v.iter().position(|c| !c.is_finite())),
            ),
            ("phi", self.phi.as_ref().and_then(|v| v.iter().position(|c| !c.is_finite()))),
            (
                "target_ell",
                self.target_ell.as_ref().and_then(|v| {
                    v.iter().position(|x| x.is_some_and(|x| x.iter().any(|c| !c.is_finite())))
                }),
            ),
        ];
        for (name, bad) in extras {
            if let Some(i) = bad {
                return Err(Error::Numerical {
                    stage: "field output",
                    message: format!("{name} of vertex {i} is not finite"),
                });
            }
        }
        for (name, v) in [("k1", &self.k1), ("k2", &self.k2), ("area", &self.area)] {
            if let Some(i) = v.iter().position(|c| !c.is_finite()) {
                return Err(Error::Numerical {
                    stage: "field output",
                    message: format!("{name} of vertex {i} is not finite"),
                });
            }
        }
        Ok(())
    }

    /// Reads a FIELD.json of version 1, 2 or 3, checking its format, its version, its array
    /// lengths, its faces (versions 2 and 3: present, every index a vertex) and that every number is
    /// finite.
    pub fn read(path: &Path) -> Result<Self> {
        let f: FieldFile = crate::output::read_json(path)?;
        let bad = |message: String| Error::Parse { path: path.to_path_buf(), line: 0, message };
        if f.format != "grainline-field" {
            return Err(bad(format!("format is {:?}, expected \"grainline-field\"", f.format)));
        }
        f.check_version_and_faces().map_err(bad)?;
        let n = f.position.len();
        let lens = [
            ("normal", f.normal.len()),
            ("u", f.u.len()),
            ("ell", f.ell.len()),
            ("k1", f.k1.len()),
            ("k2", f.k2.len()),
            ("area", f.area.len()),
            ("critical", f.critical.len()),
        ];
        for (name, len) in lens {
            if len != n {
                return Err(bad(format!("{name} has {len} entries, position has {n}")));
            }
        }
        f.check_finite().map_err(|e| bad(e.to_string()))?;
        Ok(f)
    }

    /// `version` is 1, 2 or 3; versions 2 and 3 have `faces`, and every face names three
    /// distinct vertices of the file. The message names the key.
    fn check_version_and_faces(&self) -> std::result::Result<(), String> {
        match (self.version, &self.faces) {
            (1, _) | (2 | 3, Some(_)) => {}
            (v @ (2 | 3), None) => {
                return Err(format!("version {v} needs `faces` (the mesh's triangles)"))
            }
            (v, _) => {
                return Err(format!(
                    "version is {v}; this grainline reads versions 1 to {FIELD_VERSION}"
                ))
            }
        }
        let n = self.position.len();
        let faces = self.faces.as_deref().unwrap_or_default();
        for (k, face) in faces.iter().enumerate() {
            if let Some(&v) = face.iter().find(|&&v| v as usize >= n) {
                return Err(format!("faces[{k}] names vertex {v}, position has {n}"));
            }
            if face[0] == face[1] || face[1] == face[2] || face[0] == face[2] {
                return Err(format!("faces[{k}] repeats a vertex: {face:?}"));
            }
        }
        Ok(())
    }
}

/// Reads a `--directions` file: a JSON object whose `u` holds one [x, y, z] per vertex.
pub fn read_directions(path: &Path, num_vertices: usize) -> Result<Vec<Vector3<f64>>> {
    #[derive(Deserialize)]
    struct Directions {
        u: Vec<[f64; 3]>,
    }
    let d: Directions = crate::output::read_json(path)?;
    if d.u.len() != num_vertices {
        return Err(Error::Parse {
            path: path.to_path_buf(),
            line: 0,
            message: format!(
                "`u` has {} directions but the mesh has {num_vertices} vertices",
                d.u.len()
            ),
        });
    }
    Ok(d.u.iter().map(|v| Vector3::new(v[0], v[1], v[2])).collect())
}
