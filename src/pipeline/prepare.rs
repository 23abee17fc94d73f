//! The field stage: load the part (or mesh its outline), make its UV layout when the
//! toolpaths need one, refine it inside the edits' brushes, and compute the geometry, the
//! initial field and its highlights.

use nalgebra::Vector3;

use super::plan::{check_scene_work, StagePlan};
use super::Stages;
use crate::field::{compute_field, read_directions, FieldOptions, FieldResult};
use crate::highlight::Lighting;
use crate::mesh::Mesh;
use crate::scene::{InitKind, LoadedScene};
use crate::{Error, Result};

/// The part, its geometry and the initial field with its highlights.
pub struct Prepared {
    /// The mesh (loaded from OBJ or meshed from an outline).
    pub mesh: Mesh,
    /// The mesh's source as written in the scene.
    pub mesh_name: String,
    /// The options the field was computed with.
    pub field_options: FieldOptions,
    /// Geometry, φ, h, ℓ, critical points.
    pub field: FieldResult,
    /// The UV layout made for the part ([`prepare_with`] with `layout: true`), if one was.
    pub layout: Option<crate::layout::LayoutReport>,
    /// The refinement made inside the edits' brushes (`mesh.refine`), if any.
    pub refinement: Option<RefinementReport>,
    /// The part's split into smooth patches (`mesh.patches`), if any vertex was split.
    pub patches: Option<PatchReport>,
    /// The part's noise (`field.noise: "auto"`) and the fit radius it chose; `None` with
    /// `field.noise: "off"` or a `field.fit_radius` given.
    pub noise: Option<crate::geometry::noise::NoiseEstimate>,
    /// The surfaces recognized on the part (`mesh.surfaces`) and its vertices on them, if any.
    pub surfaces: Option<RecognizedPart>,
}

/// The surfaces a CAD part was read as ([`crate::geometry::surfaces`]), and per vertex of the
/// part as prepared (cut into patches, refined) the surfaces it lies on.
#[derive(Clone, Debug)]
pub struct RecognizedPart {
    /// The surfaces, numbering the faces of the part as loaded (and cut into patches, which
    /// keeps the faces' order).
    pub surfaces: crate::geometry::surfaces::Surfaces,
    /// Per vertex, its surfaces.
    pub vertices: crate::geometry::surfaces::VertexSurfaces,
    /// What the run report says of them (on the part as loaded and cut into patches).
    pub report: crate::geometry::surfaces::SurfaceReport,
}

impl RecognizedPart {
    /// The surface of each face of `mesh` (the part as prepared) with the primitives
    /// ([`crate::geometry::surfaces::VertexSurfaces::face_surfaces`]).
    pub fn on_faces(&self, mesh: &Mesh) -> crate::geometry::surfaces::FaceSurfaces {
        crate::geometry::surfaces::FaceSurfaces {
            primitives: self.surfaces.surfaces.iter().map(|s| s.primitive).collect(),
            of: self.vertices.face_surfaces(mesh, &self.surfaces),
        }
    }

    /// Per face of `mesh`, whether it lies on a curved surface.
    pub fn curved_faces(&self, mesh: &Mesh) -> Vec<bool> {
        let on = self.on_faces(mesh);
        (0..on.of.len()).map(|f| on.curved(f).is_some()).collect()
    }
}

/// The highlight model's key light as the scene gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KeyLight {
    /// A distant light: the direction towards it.
    Directional(Vector3<f64>),
    /// A point light at this position.
    Point(Vector3<f64>),
}

impl KeyLight {
    /// The [`Lighting`] of this key light and `view` for the mesh `mesh` (a point light's
    /// nominal direction is taken from the centre of the mesh's bounding box).
    pub fn lighting(&self, view: crate::highlight::View, mesh: &Mesh) -> Result<Lighting> {
        match *self {
            KeyLight::Directional(d) => Lighting::new(d, view),
            KeyLight::Point(p) => {
                Lighting::point(p, crate::highlight::lighting::centre_of(&mesh.positions), view)
            }
        }
    }
}

/// The highlight model's light: the first directional or point light marked `"key": true`,
/// else the first directional light, else the first point light
/// ([`crate::render::key_light_index`]).
pub fn key_light(scene: &crate::scene::Scene) -> Result<KeyLight> {
    let none = || Error::setting("lights", "needs a directional or point light");
    let i = crate::render::key_light_index(&scene.lights).ok_or_else(none)?;
    match &scene.lights[i] {
        crate::render::LightSpec::Directional { direction, .. } => {
            Ok(KeyLight::Directional(Vector3::from(*direction)))
        }
        crate::render::LightSpec::Point { position, .. } => {
            Ok(KeyLight::Point(Vector3::from(*position)))
        }
        _ => Err(none()),
    }
}

/// A point key light at `position` that gives no direction from the part's centre (the
/// centre of its bounding box, where the nominal direction is taken from), named at its
/// `lights[i].position`.
fn point_key_error(scene: &crate::scene::Scene, position: Vector3<f64>, mesh: &Mesh) -> Error {
    let i = crate::render::key_light_index(&scene.lights).unwrap_or(0);
    let c = crate::highlight::lighting::centre_of(&mesh.positions);
    let at = crate::error::fmt_vec3(&position.into());
    let centre = crate::error::fmt_vec3(&c.into());
    let message = if position == c {
        format!(
            "{at} is the centre of the part's bounding box, where a point key light gives no \
             direction; move the light away from the part's centre"
        )
    } else {
        format!("{at} is too far from the part's centre {centre} for a finite direction")
    };
    Error::setting(format!("lights[{i}].position"), message)
}

/// Loads the part and computes the geometry, the initial field and its highlights: the field
/// alone, with no UV layout made for the scene's outputs.
pub fn prepare(s: &LoadedScene, stages: &mut Stages) -> Result<Prepared> {
    let plan = StagePlan { uv_layout: false, ..StagePlan::of(&s.scene) };
    prepare_with(s, stages, &plan)
}

/// [`prepare`] for a run's `plan`: when [`StagePlan::uv_layout`] is set the part's UV layout
/// is checked, or made, right after loading and before any long stage ([`ensure_layout`]).
pub fn prepare_with(s: &LoadedScene, stages: &mut Stages, plan: &StagePlan) -> Result<Prepared> {
    let part = load_stage(s, stages, plan)?;
    prepare_part(s, part, stages)
}

/// The part as loaded, before any refinement for the edits: what [`prepare_part`] starts
/// from. The editor keeps one and prepares it again for each set of edits it commits.
#[derive(Clone)]
pub struct LoadedPart {
    /// The mesh as loaded (with the UV layout made for the toolpaths, if one was).
    pub mesh: Mesh,
    /// The mesh's source as written in the scene.
    pub mesh_name: String,
    /// The key light and the view for this mesh.
    pub lighting: Lighting,
    /// Directions read per vertex (`field.init: "directions"`).
    pub directions: Option<Vec<Vector3<f64>>>,
    /// The grain map read (`field.init: "map"`).
    pub map: Option<crate::texmap::GrainMap>,
    /// The UV layout made for the part, if one was.
    pub layout: Option<crate::layout::LayoutReport>,
    /// The part's split into smooth patches (`mesh.patches`), if any vertex was split.
    pub patches: Option<PatchReport>,
    /// The part's noise (`field.noise: "auto"`), estimated on the part cut at its creases;
    /// `None` with `field.noise: "off"` or a `field.fit_radius` given.
    pub noise: Option<crate::geometry::noise::NoiseEstimate>,
    /// The surfaces recognized on the part, if any.
    pub surfaces: Option<RecognizedPart>,
}

/// The first half of [`prepare_with`]: loads the part (or meshes its outline), checks the
/// work the `plan` asks for, makes the UV layout when [`StagePlan::uv_layout`] is set and reads
/// the per-vertex directions. Nothing here depends on the scene's edits.
pub fn load_stage(s: &LoadedScene, stages: &mut Stages, plan: &StagePlan) -> Result<LoadedPart> {
    let scene = &s.scene;
    let key = key_light(scene).map_err(|e| s.wrap(e))?;
    if let KeyLight::Directional(d) = key {
        // A bad direction is reported before the part is loaded, as it always was.
        Lighting::new(d, scene.view.view())?;
    }
    stages.start("load");
    let (mut mesh, mesh_name) = load_part(s)?;
    // The work the scene asks for, estimated before any of it starts (issue 15, item 12).
    check_scene_work(scene, plan, &mesh)?;
    let surfaces = recognize_surfaces(s, &mesh);
    // The part cut at its creases and its noise estimated there (a CAD face's vertices all
    // sit on sharp edges, which would read as noise on the part uncut); a part found noisy is
    // cut again where its creases are more than its noise could make.
    let mut split = split_into_patches(s, &mesh, 0.0, surfaces.as_ref());
    let noise = estimate_noise(s, split.as_ref().map_or(&mesh, |(m, _)| m));
    let noisy = noise.filter(|n| n.fit_radius.is_some()).map(|n| n.sigma);
    if let (Some(sigma), Some(_)) = (noisy, &split) {
        split = split_into_patches(s, &mesh, sigma, surfaces.as_ref());
    }
    let patches = split.map(|(m, report)| {
        mesh = m;
        report
    });
    let surfaces = surfaces.map(|surfaces| RecognizedPart {
        vertices: crate::geometry::surfaces::VertexSurfaces::new(&mesh, &surfaces),
        report: surfaces.report(&mesh),
        surfaces,
    });
    let lighting = key.lighting(scene.view.view(), &mesh).map_err(|e| match (key, e) {
        (KeyLight::Point(p), Error::InvalidArgument { name, .. })
            if name == "light position − part centre" =>
        {
            s.wrap(point_key_error(scene, p, &mesh))
        }
        (_, e) => e,
    })?;
    // `field.init: "uv"` reads the part's own UVs, never a layout made for the toolpaths.
    if matches!(scene.field.init, InitKind::Uv) && mesh.uv.is_none() {
        return Err(s.wrap(Error::setting(
            "field.init",
            format!("\"uv\" needs UVs, and {mesh_name} has none"),
        )));
    }
    // A grain map lives in the UVs: a part without them gets the layout the export would make.
    let layout = plan.uv_layout || matches!(scene.field.init, InitKind::Map);
    let layout_report = if layout {
        let options = scene.toolpaths.as_ref().map(|t| t.layout.clone()).unwrap_or_default();
        ensure_layout(&mut mesh, &mesh_name, &options, stages)?
    } else {
        None
    };
    let directions = match (&scene.field.init, &scene.field.directions) {
        (InitKind::Directions, Some(p)) => {
            // Read per vertex of the file; a patch's copy of a vertex takes its direction.
            let own = patches.as_ref().map_or(mesh.num_vertices(), |r| r.vertices_before);
            let mut d = read_directions(&s.input(p), own)?;
            if let Some(r) = &patches {
                let copies: Vec<_> = r.copies_of.iter().map(|&v| d[v as usize]).collect();
                d.extend(copies);
            }
            Some(d)
        }
        _ => None,
    };
    let map = match (&scene.field.init, &scene.field.map) {
        (InitKind::Map, Some(m)) => Some(crate::texmap::read_map(&s.input(&m.path), m.kind)?),
        _ => None,
    };
    let layout = layout_report;
    Ok(LoadedPart { mesh, mesh_name, lighting, directions, map, layout, patches, noise, surfaces })
}

/// The second half of [`prepare_with`]: refines `part` inside the scene's edits' brushes
/// (`mesh.refine`, [`refine_request`], [`crate::mesh::refine`]) and computes the geometry, the
/// initial field and its highlights on the result.
pub fn prepare_part(s: &LoadedScene, part: LoadedPart, stages: &mut Stages) -> Result<Prepared> {
    let scene = &s.scene;
    let LoadedPart {
        mut mesh,
        mesh_name,
        lighting,
        mut directions,
        map,
        layout,
        patches,
        noise,
        mut surfaces,
    } = part;
    let fit_radius = scene.field.fit_radius.or(noise.and_then(|e| e.fit_radius));
    let height_noise = noise.map_or(0.0, |e| e.sigma);
    let refinement = refine_for_edits(s, &mut mesh, (fit_radius, height_noise), stages)?;
    if let (Some(r), Some(rec)) = (&refinement, surfaces.as_mut()) {
        // New vertices inside a recognized surface are moved onto it (the midpoints of its
        // chords stand off it by the chords' sagitta).
        rec.vertices.extend(&r.refined.parents);
        rec.vertices.project(&mut mesh, &rec.surfaces, r.report.vertices_before);
    }
    if let (Some(r), Some(d)) = (&refinement, directions.as_mut()) {
        // A line or vector field read per vertex: each new vertex gets the mean of its edge's
        // two directions (aligned first, so a line field's ±u do not cancel).
        r.refined.extend(d, |a, b| {
            let s = if a.dot(b) < 0.0 { a - b } else { a + b };
            s.try_normalize(1e-300).unwrap_or(*a)
        });
    }
    stages.start("field");
    crate::cancel::checkpoint("field")?;
    let mut field_options = FieldOptions::new(lighting);
    field_options.init = scene.field.initial_field(directions, map);
    field_options.symmetry = scene.field.symmetry.symmetry();
    field_options.gradient_form = scene.field.gradient_form;
    field_options.geometry.normals = scene.field.normals;
    field_options.geometry.fit_radius = fit_radius;
    field_options.geometry.height_noise = height_noise;
    field_options.critical_threshold = scene.field.critical_threshold;
    if let Some(r) = &refinement {
        field_options.kept_normals = r.kept_normals.clone();
    }
    if let Some(rec) = &surfaces {
        field_options.surface_points = rec.vertices.points(&mesh, &rec.surfaces);
    }
    let field = compute_field(&mesh, &field_options)?;
    let refinement = refinement.map(|r| r.report);
    Ok(Prepared {
        mesh,
        mesh_name,
        field_options,
        field,
        layout,
        refinement,
        patches,
        noise,
        surfaces,
    })
}

/// The part's noise and the fit radius it asks for (`field.noise: "auto"`, docs/math.md §5.6,
/// "Noise scale"), estimated on the part as loaded and cut at its creases (a part found noisy
/// is then cut again, its noise's folds told from creases: [`split_into_patches`]), before any
/// refinement;
/// `None` when the scene sets `field.fit_radius` or `field.noise: "off"`. Its time (about
/// 0.1 s for 100k vertices) counts in the `load` stage.
fn estimate_noise(s: &LoadedScene, mesh: &Mesh) -> Option<crate::geometry::noise::NoiseEstimate> {
    let field = &s.scene.field;
    if field.fit_radius.is_some() || field.noise == crate::scene::NoiseMode::Off {
        return None;
    }
    Some(crate::geometry::noise::estimate(mesh))
}

/// The part cut into smooth patches along its sharp edges (`mesh.patches`, docs/math.md §3,
/// "Patches").
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PatchReport {
    /// Vertices of the part as loaded (they keep their indices).
    pub vertices_before: usize,
    /// Smooth patches.
    pub patches: usize,
    /// Sharp edges between two patches.
    pub sharp_edges: usize,
    /// For each vertex appended after the part's own, the part's vertex it copies (in
    /// FIELD.json as `patch_copies`).
    #[serde(skip)]
    pub copies_of: Vec<u32>,
    /// Vertices appended: one per extra patch a vertex of the part lies on.
    pub vertices_added: usize,
    /// The patches narrower than the brush (`toolpaths.placement.width`), which no stroke can
    /// brush; absent when the scene traces no strokes or every patch is wide enough.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub narrow: Option<NarrowPatches>,
}

/// Patches narrower than the brush ([`PatchReport::narrow`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct NarrowPatches {
    /// The brush width they are compared with (scene units).
    pub brush_width: f64,
    /// How many patches are narrower than it.
    pub count: usize,
    /// Their share of the part's area.
    pub area_share: f64,
    /// The largest of them: its number (patches are numbered in the order of their first
    /// faces), area and width (twice its area over its perimeter).
    pub largest: NarrowPatch,
}

/// One patch narrower than the brush.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct NarrowPatch {
    /// The patch's number.
    pub patch: usize,
    /// Its area, scene units².
    pub area: f64,
    /// Its width, scene units.
    pub width: f64,
}

impl NarrowPatches {
    /// The patches of `sizes` narrower than `brush_width`, or `None` when there are none.
    fn of(sizes: &crate::geometry::patches::PatchSizes, brush_width: f64) -> Option<Self> {
        let total: f64 = sizes.area.iter().sum();
        let narrow: Vec<usize> =
            (0..sizes.area.len()).filter(|&p| sizes.width[p] < brush_width).collect();
        let largest = narrow
            .iter()
            .copied()
            .max_by(|&a, &b| sizes.area[a].total_cmp(&sizes.area[b]).then(b.cmp(&a)))?;
        let area: f64 = narrow.iter().map(|&p| sizes.area[p]).sum();
        Some(NarrowPatches {
            brush_width,
            count: narrow.len(),
            area_share: if total > 0.0 { area / total } else { 0.0 },
            largest: NarrowPatch {
                patch: largest,
                area: sizes.area[largest],
                width: sizes.width[largest],
            },
        })
    }

    /// The warning `grainline run` prints.
    pub fn warning(&self) -> String {
        // Four significant digits: a size, not a coordinate.
        let short = |x: f64| {
            let k = 3 - x.abs().log10().floor() as i32;
            let scale = 10f64.powi(k.clamp(-300, 300));
            crate::error::fmt_num((x * scale).round() / scale)
        };
        format!(
            "{} patch(es), {:.1} % of the part's area, are narrower than the brush ({}): the \
             strokes may miss them; the largest is patch {} (area {}, width {}); a narrower \
             `toolpaths.placement.width` reaches them",
            self.count,
            100.0 * self.area_share,
            short(self.brush_width),
            self.largest.patch,
            short(self.largest.area),
            short(self.largest.width)
        )
    }
}

/// `mesh` cut into its smooth patches (`mesh.patches: "split"`, the default, at
/// `mesh.crease_angle`); `None` when nothing was split (a smooth part, an outline's panel, or
/// `mesh.patches: "none"`). With `height_noise` (the RMS height of a part found noisy, else 0)
/// a dihedral the noise can make is not a crease (docs/math.md §3, "Creases on a noisy
/// part"). With a `toolpaths` section, the patches narrower than its brush are reported.
fn split_into_patches(
    s: &LoadedScene,
    mesh: &Mesh,
    height_noise: f64,
    surfaces: Option<&crate::geometry::surfaces::Surfaces>,
) -> Option<(Mesh, PatchReport)> {
    let m = s.scene.mesh.as_ref()?;
    if m.0.patches == crate::scene::PatchMode::None {
        return None;
    }
    let options =
        crate::geometry::patches::PatchOptions { crease_angle_deg: m.crease_angle(), height_noise };
    let patches = crate::geometry::patches::patches_on_surfaces(mesh, &options, surfaces);
    let split = crate::geometry::patches::split_patches(mesh, &patches)?;
    let narrow = s
        .scene
        .toolpaths
        .as_ref()
        .and_then(|t| NarrowPatches::of(&patches.sizes(mesh), t.placement.width));
    let report = PatchReport {
        vertices_before: mesh.num_vertices(),
        patches: patches.count,
        sharp_edges: patches.sharp_edges,
        vertices_added: split.copies_of.len(),
        copies_of: split.copies_of,
        narrow,
    };
    Some((split.mesh, report))
}

/// The surfaces of a part loaded from a mesh file (`mesh.surfaces: "recognize"`, the
/// default; docs/math.md §3, "Recognized surfaces"); `None` for an outline's panel, with
/// `mesh.surfaces: "off"`, or when nothing was recognized (a scan, a sculpt).
fn recognize_surfaces(s: &LoadedScene, mesh: &Mesh) -> Option<crate::geometry::surfaces::Surfaces> {
    let m = s.scene.mesh.as_ref()?;
    if m.0.surfaces == crate::scene::SurfaceMode::Off {
        return None;
    }
    let surfaces = crate::geometry::surfaces::recognize(mesh);
    (!surfaces.is_empty()).then_some(surfaces)
}

/// FIELD.json of the initial field of `p`, with its patches' copies.
pub fn initial_field_file(p: &Prepared) -> Result<crate::field::FieldFile> {
    let mut file = crate::field::FieldFile::new(&p.mesh, &p.mesh_name, &p.field_options, &p.field)?;
    file.patch_copies = p.patches.as_ref().map(|r| r.copies_of.clone());
    file.surfaces = p.surfaces.as_ref().map(|r| r.report.clone());
    Ok(file)
}

/// What [`refine_for_edits`] did.
struct Refinement {
    refined: crate::mesh::refine::Refined,
    report: RefinementReport,
    /// The normals the geometry keeps: the part's own vertices' before the refinement, then
    /// the new vertices' as the refinement interpolated them.
    kept_normals: Vec<nalgebra::Vector3<f64>>,
}

/// The mesh refinement made for the edits (`mesh.refine`, docs/math.md §12).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RefinementReport {
    /// Vertices of the part as loaded.
    pub vertices_before: usize,
    /// Vertices added (appended after the part's own, which keep their indices).
    pub vertices_added: usize,
    /// Faces of the part that were split.
    pub faces_split: usize,
    /// Levels of splitting.
    pub levels: usize,
    /// The longest edge allowed inside the finest brush, scene units.
    pub finest_edge: f64,
    /// Faces of the part that the key light's half vector turns across by more than
    /// `mesh.refine.turn` inside a brush, and that asked for finer edges than the brush does.
    pub turned_faces: usize,
}

/// The edge length each face of `mesh` needs for the scene's edits
/// ([`crate::edit::resolution::edit_resolution`] with `mesh.refine.edge`): the refinement's
/// request. `None` when nothing would be refined (`mesh.refine.mode: "none"`, no edits, or no
/// face asks for an edge). Two scenes whose requests are equal refine the part the same way.
pub fn refine_request(
    s: &LoadedScene,
    mesh: &Mesh,
) -> Result<Option<crate::edit::resolution::Resolution>> {
    let settings = s.scene.mesh.as_ref().map(|m| m.0.refine.clone()).unwrap_or_default();
    if settings.mode == crate::scene::RefineMode::None || s.scene.edits.is_empty() {
        return Ok(None);
    }
    let Some(mut target) = checked_resolution(s, mesh, &settings)? else { return Ok(None) };
    if settings.turn < 180.0 {
        let lighting = key_light(&s.scene)?.lighting(s.scene.view.view(), mesh)?;
        let max_turn = settings.turn.to_radians();
        target.turn = Some(crate::edit::resolution::HalfVectorTurn { lighting, max_turn });
    }
    Ok(Some(target))
}

/// Refuses the scene's edits when refining the part for them is estimated past
/// `mesh.refine.max_vertices` (the check [`refine_request`] makes before any split, without
/// the rest of the request): the editor asks it of each edit from the page when it arrives.
pub fn check_refine_budget(s: &LoadedScene, mesh: &Mesh) -> Result<()> {
    let settings = s.scene.mesh.as_ref().map(|m| m.0.refine.clone()).unwrap_or_default();
    if settings.mode == crate::scene::RefineMode::None || s.scene.edits.is_empty() {
        return Ok(());
    }
    checked_resolution(s, mesh, &settings).map(|_| ())
}

/// The edits' resolution on `mesh` with its estimate checked against the budget (`None`
/// when nothing is finer than the part).
fn checked_resolution(
    s: &LoadedScene,
    mesh: &Mesh,
    settings: &crate::scene::RefineSettings,
) -> Result<Option<crate::edit::resolution::Resolution>> {
    let edits = super::optimize::resolved_edits(s);
    let key = |e: Error| crate::scene::prefix("edits", e);
    let target =
        crate::edit::resolution::edit_resolution(mesh, &edits, settings.edge).map_err(key)?;
    if !target.finest().is_finite() {
        return Ok(None);
    }
    check_refine_estimate(&target, &edits, settings.max_vertices)?;
    Ok(Some(target))
}

/// Refuses, before any split, a refinement estimated to add more than `budget` vertices
/// (`mesh.refine.max_vertices`; [`crate::edit::resolution::Resolution::estimates`]), naming the
/// edit that asks for the most: a curve zigzagging over the part with a small radius asks for
/// its whole trace at r/8, and used to be refined for seconds before the budget stopped it.
fn check_refine_estimate(
    target: &crate::edit::resolution::Resolution,
    edits: &[crate::edit::Edit],
    budget: usize,
) -> Result<()> {
    let estimates = target.estimates();
    let total: f64 = estimates.iter().map(|e| e.vertices).sum();
    let worst = estimates.iter().max_by(|a, b| a.vertices.total_cmp(&b.vertices));
    let Some(w) = worst.filter(|_| total > budget as f64) else { return Ok(()) };
    let tool = edits.get(w.edit).map_or("edit", |e| e.tool());
    let change = if tool == "curve" { "radius or `width`" } else { "radius" };
    Err(Error::setting(
        format!("edits[{}]", w.edit),
        format!(
            "refining the part for this {tool} would add about {:.2e} vertices ({:.2e} in all \
             for the edits), more than `mesh.refine.max_vertices` ({budget}): {} × the {:.3e} \
             units² it reaches / its edge {}². Give it a larger {change}, raise \
             `mesh.refine.edge` or `mesh.refine.max_vertices`, or set `mesh.refine.mode: \
             \"none\"`",
            w.vertices,
            total,
            crate::edit::resolution::VERTICES_PER_EDGE_SQUARE,
            w.area,
            crate::error::fmt_num(w.edge),
        ),
    ))
}

/// Refines the part inside the edits' brushes where its triangles are coarser than
/// `mesh.refine.edge` × the brush radius ([`refine_request`], [`crate::mesh::refine`]).
/// `None` when nothing was split (or `mesh.refine.mode: "none"`).
fn refine_for_edits(
    s: &LoadedScene,
    mesh: &mut Mesh,
    (fit_radius, height_noise): (Option<f64>, f64),
    stages: &mut Stages,
) -> Result<Option<Refinement>> {
    let settings = s.scene.mesh.as_ref().map(|m| m.0.refine.clone()).unwrap_or_default();
    let Some(target) = refine_request(s, mesh)? else {
        return Ok(None);
    };
    stages.start("refine");
    let options = crate::mesh::refine::RefineOptions {
        max_new_vertices: settings.max_vertices,
        budget_key: "mesh.refine.max_vertices",
        ..Default::default()
    };
    // The part's own vertices keep the normals they have without the refinement: a sliver
    // split near a brush must not turn the normal, and so the grain, of its far end.
    let geometry = crate::geometry::GeometryOptions {
        normals: s.scene.field.normals,
        fit_radius,
        height_noise,
        ..Default::default()
    };
    let kept_normals: Vec<nalgebra::Vector3<f64>> =
        crate::geometry::Geometry::compute(mesh, &geometry).frames.iter().map(|f| f.n).collect();
    // The faces a split makes are asked again where they are (a sliver's far children are
    // left alone: docs/math.md §12). The Phong points use those fitted normals, not the
    // facets' (a scan's noise and a mesher's slivers tilt those every way: math.md §12).
    // Inside a region, h̄ may turn by at most `mesh.refine.turn` along an edge (the request's
    // turn, on the fitted normals: math.md §12).
    let faces = target.turned_faces(mesh, &kept_normals);
    let retarget = |p: &[nalgebra::Vector3<f64>; 3], n: &[nalgebra::Vector3<f64>; 3], _: f64| {
        target.face_target(p, n)
    };
    let refined =
        crate::mesh::refine::refine_with(mesh, &faces, &options, &retarget, Some(&kept_normals))?;
    if refined.added() == 0 {
        return Ok(None);
    }
    let turned_faces = faces.iter().zip(&target.faces).filter(|(t, r)| t < r).count();
    let report = RefinementReport {
        vertices_before: mesh.num_vertices(),
        vertices_added: refined.added(),
        faces_split: refined.faces_split,
        levels: refined.levels,
        finest_edge: target.finest(),
        turned_faces,
    };
    // ... and the new vertices keep the normalised means of their edges' normals the Phong
    // points were placed with: fitted again, on split faces that can stand on edge around a
    // scan's new vertex or resolve a sculpt's folds past what the part's own fits saw, they
    // turned h̄ by more than the refinement was made to allow (math.md §12).
    let mut kept_normals = kept_normals;
    kept_normals.extend_from_slice(&refined.normals[mesh.num_vertices()..]);
    *mesh = refined.mesh.clone();
    Ok(Some(Refinement { refined, report, kept_normals }))
}

/// Makes sure `mesh` has a UV layout the toolpaths can use, as `options.mode` says: `auto`
/// makes one when the part has no UVs, `always` replaces them, `never` refuses a part without
/// UVs. A part whose UVs are all degenerate is refused (unless `always`). Called right after
/// loading, so a part that cannot get a layout is refused before the field, the solve or the
/// preview run (issue 14, item 7). Returns the layout's report when one was made.
pub fn ensure_layout(
    mesh: &mut Mesh,
    mesh_name: &str,
    options: &crate::layout::LayoutOptions,
    stages: &mut Stages,
) -> Result<Option<crate::layout::LayoutReport>> {
    use crate::layout::LayoutMode;
    let key = |e: Error| crate::scene::prefix("toolpaths.layout", e);
    options.validate().map_err(key)?;
    match (options.mode, &mesh.uv) {
        (LayoutMode::Never, None) => {
            return Err(Error::setting(
                "toolpaths",
                format!(
                    "{mesh_name} has no UV coordinates (OBJ `vt`); toolpaths need a UV layout: \
                     remove `toolpaths.layout.mode: \"never\"` to have one made, or make one \
                     with `grainline flatten`"
                ),
            ));
        }
        (LayoutMode::Auto | LayoutMode::Never, Some(uv)) => {
            let any_area = (0..uv.corners.len()).any(|f| {
                let [a, b, c] = uv.face(f);
                (b - a).perp(&(c - a)) != 0.0
            });
            if !any_area {
                return Err(Error::setting(
                    "toolpaths",
                    format!(
                        "every face of {mesh_name} has zero area in UV: toolpaths need a UV \
                         layout; `toolpaths.layout.mode: \"always\"` replaces it with one made \
                         for the part"
                    ),
                ));
            }
            return Ok(None);
        }
        _ => {}
    }
    stages.start("layout");
    let layout = crate::layout::flatten(mesh, options).map_err(|e| match e {
        Error::Numerical { stage, message } => Error::Numerical {
            stage,
            message: format!("{message} (making a UV layout for {mesh_name})"),
        },
        e => e,
    })?;
    mesh.uv = Some(layout.uv);
    Ok(Some(layout.report))
}

/// Loads the scene's mesh (or meshes its outline).
pub fn load_part(s: &LoadedScene) -> Result<(Mesh, String)> {
    let scene = &s.scene;
    if let Some(m) = &scene.mesh {
        let path = s.input(&m.0.path);
        let loaded = crate::mesh::load::load_mesh(&path, &m.load_options(scene.units)).map_err(
            |e| match e {
                // Inside a scene the switch is a key, not the command-line flag.
                Error::NonManifold { path, message } => Error::NonManifold {
                    path,
                    message: message.replace(
                        crate::mesh::validate::NONMANIFOLD_HINT,
                        "`mesh.allow_nonmanifold: true` in the scene accepts them",
                    ),
                },
                e => e,
            },
        )?;
        return Ok((loaded.mesh, m.0.path.clone()));
    }
    let o = scene.outline.as_ref().ok_or_else(|| Error::Scene {
        path: s.path.clone(),
        line: None,
        message: "mesh: missing (give `mesh` or `outline`)".into(),
    })?;
    if scene.units != crate::mesh::Units::Mm {
        return Err(Error::Scene {
            path: s.path.clone(),
            line: None,
            message: "units: a panel from an outline is in millimetres; set `units` to \"mm\""
                .into(),
        });
    }
    let options = crate::panel::PanelOptions {
        max_edge: o.max_edge,
        min_angle_deg: o.min_angle,
        ..crate::panel::PanelOptions::default()
    };
    let panel = crate::panel::panel_from_svg(&s.input(&o.path), &options).map_err(|e| match e {
        // The panel's keys as the scene spells them.
        Error::Setting { key, message } => {
            let key = match key.as_str() {
                "min_angle_deg" => "min_angle".to_string(),
                k => k.to_string(),
            };
            crate::scene::prefix("outline", Error::Setting { key, message })
        }
        e => e,
    })?;
    Ok((panel.mesh, o.path.clone()))
}
