//! `grainline run`: every stage the scene's outputs need, and only those.

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::Vector3;
use serde::Serialize;

use super::optimize::{optimize_stage, optimized_field_file, OptimizeStageReport};
use super::{output_path, prepare_with, Observer, StageTime, Stages};
use crate::highlight::highlight_field_near;
use crate::output::{json_compact, json_pretty, OutputPlan, Staged};
use crate::render::{render, Camera, EditOverlay, RenderInput, RenderReport};
use crate::scene::LoadedScene;
use crate::uvfield::{as_brushed, field_mesh, toolpath_error, UvFieldReport};
use crate::Result;

/// Options of [`run`].
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Every relative output path of the scene lands under this directory (default: the scene
    /// file's directory).
    pub out_dir: Option<PathBuf>,
    /// Take the grain from this FIELD.json (the output of `grainline optimize` or `grainline
    /// field` on the same mesh) instead of computing it: no edits, no solve.
    pub field: Option<PathBuf>,
    /// Also write the run report (pretty JSON) here, after every other output.
    pub report: Option<PathBuf>,
}

/// Which stages a scene needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct StagePlan {
    /// The scene has edits: apply them and solve.
    pub solve: bool,
    /// A toolpath output or a strokes / as-brushed / gap effect needs the strokes.
    pub trace: bool,
    /// The scene has a `render` section.
    pub render: bool,
    /// The as-brushed field is needed (as-brushed effect, or `export.as_brushed`).
    pub as_brushed: bool,
    /// The scene asks for a glTF export (`export.glb`).
    pub export: bool,
}

impl StagePlan {
    /// The stages `scene` needs.
    pub fn of(scene: &crate::scene::Scene) -> StagePlan {
        let fx = scene.render.as_ref().map(|r| &r.effects);
        let ex = scene.export.as_ref().filter(|e| e.glb.is_some());
        let export_needs_strokes = ex.is_some_and(|e| e.strokes || e.as_brushed);
        let as_brushed =
            fx.is_some_and(|f| f.as_brushed.is_some()) || ex.is_some_and(|e| e.as_brushed);
        let render_needs_strokes =
            fx.is_some_and(|f| f.strokes.is_some() || f.as_brushed.is_some() || f.gap.is_some());
        let toolpath_outputs = scene
            .toolpaths
            .as_ref()
            .is_some_and(|t| t.svg.is_some() || t.gcode.is_some() || t.strokes_json.is_some());
        StagePlan {
            solve: !scene.edits.is_empty(),
            trace: toolpath_outputs || render_needs_strokes || export_needs_strokes,
            render: scene.render.is_some(),
            as_brushed,
            export: ex.is_some(),
        }
    }
}

/// Figures of the toolpath stage.
#[derive(Clone, Debug, Serialize)]
pub struct ToolpathFigures {
    /// The toolpaths crate's report (strokes, lengths, coverage, stop reasons).
    pub job: grainline_toolpaths::Report,
    /// UV triangles, flipped and degenerate faces, seams.
    pub uv_vertices: usize,
    /// Triangles handed to the toolpaths crate.
    pub triangles: usize,
    /// Faces left out (degenerate UV).
    pub degenerate_faces: usize,
    /// Mirrored or flipped UV triangles (kept, directions carried without turning over).
    pub flipped_faces: usize,
    /// Seam pairs.
    pub seam_pairs: usize,
    /// Scale from the mesh's UV layout to the flat SVG / G-code coordinates (scene units).
    pub uv_scale: f64,
    /// The scene's fabrication constraints (`solver.constraints`) measured on the traced
    /// strokes: turning radius, spread between neighbours, deviation through each lock
    /// (`grainline_toolpaths::check_strokes`; issue 17). Absent when the scene has none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stroke_constraints: Option<grainline_toolpaths::StrokeChecks>,
}

/// The as-brushed fidelity: the grain rebuilt from the strokes against the designed grain.
#[derive(Clone, Debug, Serialize)]
pub struct AsBrushedFigures {
    /// Vertices compared.
    pub compared: usize,
    /// Median angle between designed and as-brushed u, degrees.
    pub median_deg: f64,
    /// 95th percentile of that angle, degrees.
    pub p95_deg: f64,
    /// Largest angle, degrees.
    pub max_deg: f64,
}

/// The run report.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Always `"grainline-run-report"`.
    pub format: &'static str,
    /// Format version (1).
    pub version: u32,
    /// The scene file.
    pub scene: String,
    /// Length unit of every length below.
    pub units: String,
    /// The stages the scene needed.
    pub plan: StagePlan,
    /// Every stage with its wall time; they add up to `wall_seconds`.
    pub stages: Vec<StageTime>,
    /// Wall time of the whole run.
    pub wall_seconds: f64,
    /// Mesh vertices and faces.
    pub vertices: usize,
    /// Mesh faces.
    pub faces: usize,
    /// Critical points (hᵀn above the threshold) of the final field.
    pub critical_points: usize,
    /// The UV layout made for a part without one (charts, seams, distortion); absent when
    /// the part's own UVs were used or no toolpaths were traced.
    pub layout: Option<crate::layout::LayoutReport>,
    /// Edits and the solve (iterations, energies, constraint violations, singularities).
    pub optimize: Option<OptimizeStageReport>,
    /// Strokes, coverage, lengths.
    pub toolpaths: Option<ToolpathFigures>,
    /// Designed against as-brushed grain.
    pub as_brushed: Option<AsBrushedFigures>,
    /// The preview's passes, times and counters.
    pub render: Option<RenderReport>,
    /// The glTF export: vertices, splits, the material written (`export.glb`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub export: Option<crate::export::ExportReport>,
    /// Files written.
    pub outputs: Vec<String>,
}

fn write_out(staged: &mut Staged, path: &Path, bytes: &[u8]) -> Result<()> {
    staged.add(path, bytes)
}

/// The files a run of `s` writes (with their scene keys) and the files it reads, for
/// [`OutputPlan::check`]: no output may be a directory, a device, a FIFO or a link, two
/// outputs may not share a file, and no output may overwrite an input.
pub fn output_plan(s: &LoadedScene, options: &RunOptions) -> OutputPlan {
    let scene = &s.scene;
    let out = |p: &str| output_path(s, options.out_dir.as_deref(), p);
    let mut plan = OutputPlan::new();
    if let Some(p) = &scene.field.output {
        plan.output("field.output", out(p));
    }
    let needs = StagePlan::of(scene);
    if let Some(t) = scene.toolpaths.as_ref().filter(|_| needs.trace) {
        for (key, p) in [
            ("toolpaths.svg", &t.svg),
            ("toolpaths.gcode", &t.gcode),
            ("toolpaths.strokes_json", &t.strokes_json),
        ] {
            if let Some(p) = p {
                plan.output(key, out(p));
            }
        }
    }
    if let Some(r) = &scene.render {
        plan.output("render.output", out(&r.output));
        if let Some(p) = &r.linear {
            plan.output("render.linear", out(p));
        }
    }
    if let Some(p) = scene.export.as_ref().and_then(|e| e.glb.as_ref()) {
        plan.output("export.glb", out(p));
    }
    if let Some(p) = &options.report {
        plan.output("the run report", p.clone());
    }
    scene_inputs(s, &mut plan);
    if let Some(p) = &options.field {
        plan.input("--field", p.clone());
    }
    plan
}

/// Adds the files a scene reads to `plan`: the scene file, the mesh or outline, the
/// directions file, curve edits' SVGs and environment images.
pub fn scene_inputs(s: &LoadedScene, plan: &mut OutputPlan) {
    let scene = &s.scene;
    plan.input("the scene file", s.path.clone());
    if let Some(m) = &scene.mesh {
        plan.input("mesh", s.input(&m.0.path));
    }
    if let Some(o) = &scene.outline {
        plan.input("outline", s.input(&o.path));
    }
    if let Some(p) = &scene.field.directions {
        plan.input("field.directions", s.input(p));
    }
    for (i, e) in scene.edits.iter().enumerate() {
        if let crate::edit::Edit::Curve(c) = e {
            if let Some(p) = &c.svg {
                plan.input(format!("edits[{i}].svg"), s.input(p));
            }
        }
    }
    for (i, l) in scene.lights.iter().enumerate() {
        if let crate::render::LightSpec::Environment { file, .. } = l {
            plan.input(format!("lights[{i}].file"), s.input(file));
        }
    }
}

/// The toolpaths section a run traces with: the scene's (or the defaults), keeping the
/// coverage map when `keep_map` (the gap effect), the tool's turning radius as the plan's
/// (issue 17, item 4) unless the section sets its own, checked in the mesh's `units`.
pub fn toolpath_section(
    scene: &crate::scene::Scene,
    units: crate::mesh::Units,
    keep_map: bool,
) -> Result<crate::uvfield::ToolpathSection> {
    let mut section = scene.toolpaths.clone().unwrap_or_default();
    if keep_map {
        let mut c = section.coverage.clone().unwrap_or_default();
        c.keep_map = true;
        section.coverage = Some(c);
    }
    // The tool's turning radius also cuts back stroke ends that turn tighter near a
    // boundary or a singularity, unless the section sets its own.
    if section.plan.min_turning_radius.is_none() {
        section.plan.min_turning_radius =
            scene.solver.constraints.turning_radius.as_ref().map(|t| t.radius);
    }
    section.validate_in(units).map_err(|e| crate::scene::prefix("toolpaths", e))?;
    Ok(section)
}

/// Runs the scene: the stages its outputs need, each timed. Before any work the output paths
/// are checked ([`output_plan`]); every output is written into a temporary beside its target
/// as it is computed, and all of them are renamed into place only once the last one is ready,
/// the report (when [`RunOptions::report`] is set) last of all. A run that fails part-way
/// leaves every earlier output as it was.
///
/// ```
/// use grainline::pipeline::{run::{run, RunOptions}, Silent};
/// use grainline::scene::LoadedScene;
///
/// let dir = std::env::temp_dir().join(format!("grainline-doc-run-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let cylinder = grainline::generate::cylinder(30.0, 80.0, 32, 8);
/// std::fs::write(dir.join("part.obj"), grainline::mesh::write::obj_string(&cylinder, "doc")).unwrap();
/// std::fs::write(
///     dir.join("scene.json"),
///     r#"{"mesh": "part.obj", "view": {"eye": [0, -300, 0]},
///         "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
///         "field": {"init": "uv"},
///         "toolpaths": {"svg": "strokes.svg", "placement": {"width": 5}}}"#,
/// )
/// .unwrap();
/// let scene = LoadedScene::read(&dir.join("scene.json"))?;
/// let report = run(&scene, &RunOptions::default(), &Silent)?;
/// // No edits and no render section: no solve and no preview, only the strokes.
/// let stages: Vec<&str> = report.stages.iter().map(|s| s.stage.as_str()).collect();
/// assert_eq!(stages, ["load", "field", "toolpaths", "write toolpaths"]);
/// assert!(dir.join("strokes.svg").exists());
/// # std::fs::remove_dir_all(&dir).ok();
/// # Ok::<(), grainline::Error>(())
/// ```
pub fn run(s: &LoadedScene, options: &RunOptions, observer: &dyn Observer) -> Result<RunReport> {
    let start = Instant::now();
    let scene = &s.scene;
    let mut plan = StagePlan::of(scene);
    if options.field.is_some() {
        plan.solve = false;
    }
    let out = |p: &str| output_path(s, options.out_dir.as_deref(), p);
    output_plan(s, options).check()?;
    let mut stages = Stages::new(observer);
    let mut staged = Staged::new();
    // The layout is checked (or made) right after loading: a part that cannot get one is
    // refused before the field, the solve or the preview run.
    let mut prepared = prepare_with(s, &mut stages, plan.trace)?;
    if let (Some(path), Some(r)) = (&options.field, &prepared.refinement) {
        // A given field of the part as loaded (written with `mesh.refine.mode: "none"`, or
        // before refinement existed) is traced on the part's own triangles.
        let n = crate::field::FieldFile::read(path).map(|f| f.u.len());
        if n.is_ok_and(|n| n == r.vertices_before) {
            let mut own = s.clone();
            if let Some(m) = own.scene.mesh.as_mut() {
                m.0.refine.mode = crate::scene::RefineMode::None;
            }
            prepared = prepare_with(&own, &mut stages, plan.trace)?;
        }
    }
    let g = &prepared.field.geometry;
    let symmetry = prepared.field_options.symmetry;
    if plan.trace && prepared.mesh.uv.is_none() {
        // Checked before the solve, not after it.
        return Err(crate::Error::setting(
            "toolpaths",
            format!(
                "{} has no UV coordinates (OBJ `vt`); toolpaths need a UV layout",
                prepared.mesh_name
            ),
        ));
    }
    // The field after edits and the solve, or the initial one.
    let optimized =
        if plan.solve { Some(optimize_stage(s, &prepared, &mut stages)?) } else { None };
    let given_phi = match &options.field {
        Some(path) => {
            stages.start("read field");
            let f = crate::field::FieldFile::read(path)?;
            if f.u.len() != prepared.mesh.num_vertices() {
                return Err(crate::Error::Parse {
                    path: path.clone(),
                    line: 0,
                    message: format!(
                        "has {} vertices, the scene's mesh has {}{}",
                        f.u.len(),
                        prepared.mesh.num_vertices(),
                        match &prepared.refinement {
                            Some(r) => format!(
                                " ({} of the part's own and {} added inside the edits' \
                                 brushes, `mesh.refine`)",
                                r.vertices_before, r.vertices_added
                            ),
                            None => String::new(),
                        }
                    ),
                });
            }
            let u: Vec<Vector3<f64>> = f.u.iter().map(|v| Vector3::from(*v)).collect();
            Some(g.angles_of(&u))
        }
        None => None,
    };
    // The solved angles as FIELD.json states them (u = direction(φ), read back by atan2), so
    // that tracing a written FIELD.json (`--field`) gives these outputs bit for bit: the solver's
    // own φ may differ from them by whole turns, and cos/sin of φ + 2π by an ulp.
    let solved_phi = optimized.as_ref().map(|o| g.angles_of(&g.directions_of(&o.phi)));
    let (phi, h, h_gradient, ell, critical, lighting) = match (&optimized, &solved_phi) {
        (Some(o), Some(phi)) => {
            (phi, &o.h, &o.h_gradient, &o.highlight.ell, &o.critical, o.lighting)
        }
        _ => (
            given_phi.as_ref().unwrap_or(&prepared.field.phi),
            &prepared.field.h,
            &prepared.field.h_gradient,
            &prepared.field.highlight.ell,
            &prepared.field.critical,
            prepared.field_options.lighting,
        ),
    };
    if let Some(p) = &scene.field.output {
        stages.start("write field");
        let file = match &optimized {
            Some(o) => optimized_field_file(&prepared, o)?,
            None => crate::field::FieldFile::new(
                &prepared.mesh,
                &prepared.mesh_name,
                &prepared.field_options,
                &prepared.field,
            )?,
        };
        write_out(&mut staged, &out(p), &json_compact(&file)?)?;
    }
    let mut toolpaths = None;
    let mut brushed = None;
    let mut gap: Option<Vec<f64>> = None;
    let mut strokes_3d: Vec<Vec<Vector3<f64>>> = Vec::new();
    if plan.trace {
        stages.start("toolpaths");
        let want_gap = scene.render.as_ref().is_some_and(|r| r.effects.gap.is_some());
        let units = prepared.mesh.units;
        let section = toolpath_section(scene, units, want_gap)?;
        // Errors found while tracing name their key from the scene's top (`toolpaths.…`).
        let in_section = |e| crate::scene::prefix("toolpaths", e);
        let (fm, uvr): (_, UvFieldReport) =
            field_mesh(&prepared.mesh, g, phi, symmetry, &section.uv_field)?;
        let fm_copy = if plan.as_brushed || want_gap { Some(fm.clone()) } else { None };
        let job = grainline_toolpaths::generate(fm, &section.job_options(units))
            .map_err(|e| in_section(toolpath_error(e)))?;
        strokes_3d =
            job.strokes_3d.iter().map(|s| s.iter().map(|p| Vector3::from(*p)).collect()).collect();
        stages.start("write toolpaths");
        for (name, text) in [
            (&section.svg, &job.svg),
            (&section.gcode, &job.gcode),
            (&section.strokes_json, &job.strokes_json),
        ] {
            if let (Some(p), Some(t)) = (name, text) {
                write_out(&mut staged, &out(p), t.as_bytes())?;
            }
        }
        if let (true, Some(fm), Some(map)) =
            (want_gap, &fm_copy, job.coverage.as_ref().and_then(|c| c.map.as_ref()))
        {
            // The coverage gap map sampled at each mesh vertex's UV positions (the nearest
            // pixel; the largest distance where a vertex has several UV positions).
            let mut g = vec![0.0f64; prepared.mesh.num_vertices()];
            for (k, q) in fm.uv.iter().enumerate() {
                let px = ((q[0] - map.origin[0]) / map.pixel).floor();
                let py = ((q[1] - map.origin[1]) / map.pixel).floor();
                let (px, py) = (
                    (px.max(0.0) as usize).min(map.width.saturating_sub(1)),
                    (py.max(0.0) as usize).min(map.height.saturating_sub(1)),
                );
                let d = f64::from(map.distance[py * map.width + px]).max(0.0);
                let v = uvr.uv_to_vertex[k] as usize;
                g[v] = g[v].max(d);
            }
            gap = Some(g);
        }
        if let (true, Some(fm)) = (plan.as_brushed, fm_copy) {
            stages.start("as-brushed");
            let ab = as_brushed(&prepared.mesh, g, phi, symmetry, &fm, &uvr, &job.placement)?;
            brushed = Some(ab);
        }
        let stroke_constraints = match super::stroke_constraints::check_options(
            &prepared.mesh,
            g,
            &scene.solver.constraints,
            &uvr.uv_to_vertex,
            symmetry.k(),
        )? {
            Some(o) => Some(
                grainline_toolpaths::check_strokes(&job.domain, &job.placement, &o)
                    .map_err(|e| in_section(toolpath_error(e)))?,
            ),
            None => None,
        };
        toolpaths = Some(ToolpathFigures {
            job: job.report.clone(),
            uv_vertices: uvr.uv_vertices,
            triangles: uvr.triangles,
            degenerate_faces: uvr.degenerate_faces.len(),
            flipped_faces: uvr.flipped_faces,
            seam_pairs: uvr.seam_pairs,
            uv_scale: uvr.uv_scale,
            stroke_constraints,
        });
    }
    let mut render_report = None;
    if let Some(settings) = &scene.render {
        stages.start("render");
        let normals: Vec<Vector3<f64>> = g.frames.iter().map(|f| f.n).collect();
        // Shading normals split at creases (math.md §3, "Creases"); smooth vertices keep the
        // solver's normal.
        let crease_angle = scene
            .mesh
            .as_ref()
            .map_or(crate::geometry::normals::DEFAULT_CREASE_ANGLE_DEG, |m| m.crease_angle());
        let corner = {
            let m = &prepared.mesh;
            let vf = crate::mesh::VertexFaces::new(m);
            let fd = crate::geometry::normals::face_data(m);
            crate::geometry::normals::corner_normals(m, &vf, &fd, &normals, crease_angle)
        };
        let u = g.directions_of(phi);
        let mut input = RenderInput::new(
            &prepared.mesh.positions,
            &prepared.mesh.faces,
            &normals,
            &u,
            symmetry,
        );
        input.corner_normals = Some(&corner.corners);
        input.ell = Some(ell);
        input.critical = Some(critical);
        if settings.effects.strokes.is_some() {
            input.strokes = Some(&strokes_3d);
        }
        let brushed_u: Option<Vec<Vector3<f64>>> =
            brushed.as_ref().map(|b| b.u.iter().map(|v| Vector3::from(*v)).collect());
        let brushed_ell = brushed_u.as_ref().map(|bu| {
            let bphi = g.angles_of(bu);
            let form = prepared.field_options.gradient_form;
            highlight_field_near(g, &bphi, symmetry, form, h, h_gradient.as_deref()).ell
        });
        input.brushed_u = brushed_u.as_deref();
        input.brushed_ell = brushed_ell.as_deref();
        let overlay = optimized.as_ref().map(|o| EditOverlay {
            support: o.support.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect(),
            targets: o
                .target_ell
                .iter()
                .enumerate()
                .filter(|(i, t)| t.is_some() && o.support[*i])
                .map(|(i, t)| (prepared.mesh.positions[i], t.expect("filtered")))
                .collect(),
        });
        if settings.effects.gap.is_some() {
            input.gap = gap.as_deref();
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
        // Environment images are relative to the scene file; the key light may have moved.
        let lights: Vec<crate::render::LightSpec> = scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, l)| match l {
                crate::render::LightSpec::Environment { file, scale, samples, rotation_deg } => {
                    crate::render::LightSpec::Environment {
                        file: s.input(file).display().to_string(),
                        scale: *scale,
                        samples: *samples,
                        rotation_deg: *rotation_deg,
                    }
                }
                crate::render::LightSpec::Directional { irradiance, colour, key, .. }
                    if Some(i) == crate::render::key_light_index(&scene.lights) =>
                {
                    crate::render::LightSpec::Directional {
                        direction: [lighting.light.x, lighting.light.y, lighting.light.z],
                        irradiance: *irradiance,
                        colour: *colour,
                        key: *key,
                    }
                }
                crate::render::LightSpec::Point { position, intensity, colour, key }
                    if Some(i) == crate::render::key_light_index(&scene.lights) =>
                {
                    crate::render::LightSpec::Point {
                        position: lighting.light_position.map_or(*position, |p| [p.x, p.y, p.z]),
                        intensity: *intensity,
                        colour: *colour,
                        key: *key,
                    }
                }
                other => other.clone(),
            })
            .collect();
        let r =
            render(&input, &scene.material, &lights, &camera, settings).map_err(|e| s.wrap(e))?;
        stages.start("write render");
        write_out(&mut staged, &out(&settings.output), &r.png)?;
        if let (Some(p), Some(bytes)) = (&settings.linear, &r.linear) {
            write_out(&mut staged, &out(p), bytes)?;
        }
        render_report = Some(r.report);
    }
    let mut export_report = None;
    if let Some((e, p)) = scene.export.as_ref().and_then(|e| e.glb.as_ref().map(|p| (e, p))) {
        stages.start("export");
        let normals: Vec<Vector3<f64>> = g.frames.iter().map(|f| f.n).collect();
        let (u, phi_e) = match (&brushed, e.as_brushed) {
            (Some(b), true) => {
                let u: Vec<Vector3<f64>> = b.u.iter().map(|v| Vector3::from(*v)).collect();
                let phi_b = g.angles_of(&u);
                (u, phi_b)
            }
            _ => (g.directions_of(phi), phi.clone()),
        };
        let singular: Vec<u32> = match symmetry {
            crate::highlight::Symmetry::Line => {
                crate::solve::singularities::singularities(&prepared.mesh, g, &phi_e, 2)
                    .iter()
                    .map(|s| s.face)
                    .collect()
            }
            crate::highlight::Symmetry::Oriented => Vec::new(),
        };
        let input = crate::export::ExportInput {
            positions: &prepared.mesh.positions,
            faces: &prepared.mesh.faces,
            normals: &normals,
            u: &u,
            symmetry,
            singular_faces: &singular,
            strokes: e.strokes.then_some(strokes_3d.as_slice()),
        };
        let name = Path::new(&prepared.mesh_name)
            .file_stem()
            .map_or_else(|| "part".to_string(), |s| s.to_string_lossy().into_owned());
        let options = crate::export::ExportOptions {
            material: scene.material.clone(),
            units: prepared.mesh.units,
            up: scene.view.up,
            name,
            camera: Some(crate::export::ViewCamera {
                eye: scene.view.eye,
                target: scene.view.target,
                up: scene.view.up,
                fov_deg: scene.view.fov_deg,
            }),
            // The key light as the highlight model used it (a light edit may have moved it).
            key_light: crate::render::key_light_index(&scene.lights).and_then(|i| {
                match &scene.lights[i] {
                    crate::render::LightSpec::Directional { irradiance, .. } => {
                        Some(([lighting.light.x, lighting.light.y, lighting.light.z], *irradiance))
                    }
                    _ => None,
                }
            }),
        };
        let x = crate::export::export_glb(&input, &options)?;
        write_out(&mut staged, &out(p), &x.glb)?;
        export_report = Some(x.report);
    }
    let as_brushed_figures = brushed.as_ref().map(|b| AsBrushedFigures {
        compared: b.compared,
        median_deg: b.median_deg,
        p95_deg: b.p95_deg,
        max_deg: b.max_deg,
    });
    // Every output is computed and staged: put them in place, then the report.
    let outputs: Vec<String> = staged.commit()?.iter().map(|p| p.display().to_string()).collect();
    let times = stages.into_times();
    let report = RunReport {
        format: "grainline-run-report",
        version: 1,
        scene: s.path.display().to_string(),
        units: prepared.mesh.units.as_str().into(),
        plan,
        stages: times,
        wall_seconds: start.elapsed().as_secs_f64(),
        vertices: prepared.mesh.num_vertices(),
        faces: prepared.mesh.num_faces(),
        critical_points: critical.iter().filter(|&&c| c).count(),
        layout: prepared.layout.clone(),
        optimize: optimized.map(|o| o.report),
        toolpaths,
        as_brushed: as_brushed_figures,
        render: render_report,
        export: export_report,
        outputs,
    };
    if let Some(p) = &options.report {
        crate::output::write_atomic(p, &json_pretty(&report)?)?;
    }
    Ok(report)
}
