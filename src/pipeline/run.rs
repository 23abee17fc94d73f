//! `grainline run`: every stage the scene's outputs need, and only those — the sequencer
//! of the stages in [`super::plan`], [`mod@super::prepare`], [`super::optimize`],
//! [`super::trace`], [`super::preview`] and [`super::export`].

use std::path::Path;
use std::time::Instant;

use nalgebra::{Matrix2, Vector3};
use serde::Serialize;

use super::brush_width::{carrying_widths, CarryingWidth};
use super::optimize::{
    field_file_angles, optimize_stage, optimized_field_file, OptimizeStageReport, Optimized,
};
pub use super::plan::{output_plan, scene_inputs, RunOptions, StagePlan};
pub use super::trace::{toolpath_section, ToolpathFigures};
use super::trace::{trace, TraceInput};
use super::{output_path, prepare_with, Observer, Prepared, StageTime, Stages};
use crate::fidelity::{
    beyond_reach_in_support, brushed_fidelity_of_edits, BrushedEditFidelity, FidelityOptions,
};
use crate::field::FieldFile;
use crate::highlight::{highlight_field_near, Lighting};
use crate::output::{json_compact, json_pretty, Staged};
use crate::render::RenderReport;
use crate::scene::LoadedScene;
use crate::uvfield::AsBrushed;
use crate::Result;

/// The as-brushed fidelity: the grain rebuilt from the strokes against the designed grain.
#[derive(Clone, Debug, Serialize)]
pub struct AsBrushedFigures {
    /// Each bend, expand and curve edit measured on the designed grain and on the grain
    /// rebuilt from the strokes ([`crate::fidelity::brushed_fidelity`]); absent when the run
    /// measured none (`toolpaths.as_brushed_fidelity`, docs/scene.md).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub fidelity: Vec<BrushedEditFidelity>,
    /// For each edit that lands as designed but not as brushed, the brush widths tried again
    /// and the widest that carries it ([`super::brush_width`]); absent when every measured edit
    /// lands as brushed.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub carrying_width: Vec<CarryingWidth>,
    /// Vertices compared.
    pub compared: usize,
    /// Vertices farther than half the brush's width from the stroke whose direction they take
    /// (on the part): gaps the brush never passed over (added after 0.2.0).
    pub beyond_reach_vertices: usize,
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
    /// The part cut into smooth patches along its sharp edges (`mesh.patches`); absent when
    /// no vertex was split.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub patches: Option<super::PatchReport>,
    /// The part's noise and the fit radius it chose (`field.noise: "auto"`); absent when the
    /// scene sets `field.fit_radius` or `field.noise: "off"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise: Option<crate::geometry::noise::NoiseEstimate>,
    /// The surfaces the part was read as (`mesh.surfaces: "recognize"`): planes, cylinders,
    /// cones, spheres and tori with their parameters, area and fit residual, and the creases
    /// between them; absent when none was recognized (a free-form part, a scan) or with
    /// `mesh.surfaces: "off"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surfaces: Option<crate::geometry::surfaces::SurfaceReport>,
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

/// Runs the scene: the stages its outputs need, each timed. Before any work the output paths
/// are checked ([`output_plan`]); every output is written into a temporary beside its target
/// as it is computed, and all of them are renamed into place only once the last one is ready,
/// the report (when [`RunOptions::report`] is set) last of all ([`Staged::commit`]). A run
/// that fails part-way leaves every earlier output as it was and writes none.
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
    let plan = StagePlan::for_run(&s.scene, options);
    let given = options.field.as_deref().map(FieldFile::read).transpose()?;
    output_plan(s, &plan, options)?.check()?;
    let mut stages = Stages::new(observer);
    let mut staged = Staged::new();
    let prepared = prepare_for_field(s, given.as_ref(), &plan, &mut stages)?;
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
    let given_phi = match (&given, options.field.as_deref()) {
        (Some(f), Some(path)) => {
            stages.start("read field");
            Some(given_angles(f, path, &prepared)?)
        }
        _ => None,
    };
    let shown = ShownField::of(&prepared, optimized.as_ref(), given_phi, plan.render);
    let mut out = Outputs { s, options, staged: &mut staged };
    let traced = if plan.trace {
        Some(trace_stage(&mut out, &prepared, &shown, plan, &mut stages)?)
    } else {
        None
    };
    if let Some(p) = &s.scene.field.output {
        stages.start("write field");
        let fidelity = traced.as_ref().map_or(&[][..], |t| t.fidelity.as_slice());
        write_field(&mut out, p, &prepared, optimized.as_ref(), fidelity)?;
    }
    let field =
        ShownAndTraced { plan, prepared: &prepared, shown: &shown, traced: traced.as_ref() };
    let render_report = render_stage(&mut out, &field, &mut stages)?;
    let export_report = export_stage(&mut out, &field, &mut stages)?;
    let brushed = traced.as_ref().and_then(|t| t.brushed.as_ref().map(|b| (b, t)));
    let as_brushed_figures = brushed.map(|(b, t)| AsBrushedFigures {
        fidelity: t.fidelity.clone(),
        carrying_width: t.carrying.clone(),
        compared: b.compared,
        beyond_reach_vertices: b.beyond_reach,
        median_deg: b.median_deg,
        p95_deg: b.p95_deg,
        max_deg: b.max_deg,
    });
    let critical_points = shown.critical(&prepared).iter().filter(|&&c| c).count();
    // Every output is computed and staged: the report is staged last and all of them are
    // put in place together (a failed run replaces none of them).
    let outputs: Vec<String> = staged.targets().map(|p| p.display().to_string()).collect();
    let report = RunReport {
        format: "grainline-run-report",
        version: 1,
        scene: s.path.display().to_string(),
        units: prepared.mesh.units.as_str().into(),
        plan,
        stages: stages.into_times(),
        wall_seconds: start.elapsed().as_secs_f64(),
        vertices: prepared.mesh.num_vertices(),
        faces: prepared.mesh.num_faces(),
        critical_points,
        layout: prepared.layout.clone(),
        patches: prepared.patches.clone(),
        noise: prepared.noise,
        surfaces: prepared.surfaces.as_ref().map(|r| r.report.clone()),
        optimize: optimized.map(|o| o.report),
        toolpaths: traced.map(|t| t.figures),
        as_brushed: as_brushed_figures,
        render: render_report,
        export: export_report,
        outputs,
    };
    if let Some(p) = &options.report {
        staged.add(p, &json_pretty(&report)?)?;
    }
    staged.commit()?;
    Ok(report)
}

/// Where the run's outputs go: staged beside their targets, under `--out-dir` or the scene's
/// directory.
struct Outputs<'a> {
    s: &'a LoadedScene,
    options: &'a RunOptions,
    staged: &'a mut Staged,
}

impl Outputs<'_> {
    /// Stages `bytes` for the output `key` at the scene's path `p`.
    fn write(&mut self, key: &str, p: &str, bytes: &[u8]) -> Result<()> {
        let path = output_path(self.s, self.options.out_dir.as_deref(), key, p)?;
        self.staged.add(&path, bytes)
    }
}

/// The part prepared for the run. A given field of the part as loaded (written with
/// `mesh.refine.mode: "none"`, or before refinement existed) is traced on the part's own
/// triangles.
fn prepare_for_field(
    s: &LoadedScene,
    given: Option<&FieldFile>,
    plan: &StagePlan,
    stages: &mut Stages,
) -> Result<Prepared> {
    let prepared = prepare_with(s, stages, plan)?;
    match (given, &prepared.refinement) {
        (Some(f), Some(r)) if f.u.len() == r.vertices_before => {
            let mut own = s.clone();
            if let Some(m) = own.scene.mesh.as_mut() {
                m.0.refine.mode = crate::scene::RefineMode::None;
            }
            prepare_with(&own, stages, plan)
        }
        _ => Ok(prepared),
    }
}

/// The angles of a given field (`--field`), which must be of the prepared part.
fn given_angles(f: &FieldFile, path: &Path, prepared: &Prepared) -> Result<Vec<f64>> {
    if f.u.len() != prepared.mesh.num_vertices() {
        return Err(crate::Error::Parse {
            path: path.to_path_buf(),
            line: 0,
            message: format!(
                "has {} vertices, the scene's mesh has {}{}",
                f.u.len(),
                prepared.mesh.num_vertices(),
                match &prepared.refinement {
                    Some(r) => format!(
                        " ({} of the part's own and {} added inside the edits' brushes, \
                         `mesh.refine`)",
                        r.vertices_before, r.vertices_added
                    ),
                    None => String::new(),
                }
            ),
        });
    }
    let u: Vec<Vector3<f64>> = f.u.iter().map(|v| Vector3::from(*v)).collect();
    Ok(prepared.field.geometry.angles_of(&u))
}

/// The field the run's outputs show: the solved one, a given one, or the initial one.
struct ShownField<'a> {
    optimized: Option<&'a Optimized>,
    /// The solved angles as FIELD.json states them ([`field_file_angles`]), else the given
    /// field's angles.
    phi: Option<Vec<f64>>,
    /// ℓ (Eq. 7) of the given field (`--field`) under the scene's lighting, for the preview's
    /// LIC and statistics (issue 33, item 4: they showed the initial field's ℓ).
    given_ell: Option<Vec<Vector3<f64>>>,
}

impl<'a> ShownField<'a> {
    /// The field shown; `render`: ℓ of a given field is computed for the preview.
    fn of(
        p: &Prepared,
        optimized: Option<&'a Optimized>,
        given: Option<Vec<f64>>,
        render: bool,
    ) -> Self {
        let g = &p.field.geometry;
        let (symmetry, form) = (p.field_options.symmetry, p.field_options.gradient_form);
        let given_ell = match (optimized, &given) {
            (None, Some(phi)) if render => {
                let hg = p.field.h_gradient.as_deref();
                Some(highlight_field_near(g, phi, symmetry, form, &p.field.h, hg).ell)
            }
            _ => None,
        };
        let phi = match optimized {
            Some(o) => Some(field_file_angles(g, &o.phi)),
            None => given,
        };
        ShownField { optimized, phi, given_ell }
    }
    fn phi<'b>(&'b self, p: &'b Prepared) -> &'b [f64] {
        self.phi.as_deref().unwrap_or(&p.field.phi)
    }
    fn h<'b>(&'b self, p: &'b Prepared) -> &'b [Vector3<f64>] {
        self.optimized.map_or(&p.field.h, |o| &o.h)
    }
    fn h_gradient<'b>(&'b self, p: &'b Prepared) -> Option<&'b [Matrix2<f64>]> {
        self.optimized.map_or(&p.field.h_gradient, |o| &o.h_gradient).as_deref()
    }
    fn ell<'b>(&'b self, p: &'b Prepared) -> &'b [Vector3<f64>] {
        match (self.optimized, &self.given_ell) {
            (Some(o), _) => &o.highlight.ell,
            (None, Some(ell)) => ell,
            (None, None) => &p.field.highlight.ell,
        }
    }
    fn critical<'b>(&'b self, p: &'b Prepared) -> &'b [bool] {
        self.optimized.map_or(&p.field.critical, |o| &o.critical)
    }
    fn lighting(&self, p: &Prepared) -> Lighting {
        self.optimized.map_or(p.field_options.lighting, |o| o.lighting)
    }
}

/// What the run keeps of the trace stage.
struct RunTraced {
    strokes_3d: Vec<Vec<Vector3<f64>>>,
    gap: Option<Vec<f64>>,
    brushed: Option<AsBrushed>,
    /// The edits measured as brushed (empty unless [`StagePlan::brushed_fidelity`]).
    fidelity: Vec<BrushedEditFidelity>,
    /// The brush that carries each edit the strokes lose.
    carrying: Vec<CarryingWidth>,
    figures: ToolpathFigures,
}

/// The trace stage of a run: the strokes, their files, the gaps and the as-brushed grain the
/// preview and the export ask for, and the stage's figures.
fn trace_stage(
    out: &mut Outputs,
    prepared: &Prepared,
    shown: &ShownField,
    plan: StagePlan,
    stages: &mut Stages,
) -> Result<RunTraced> {
    stages.start("toolpaths");
    let scene = &out.s.scene;
    let straddle = straddle_points(prepared, shown, scene);
    let input = TraceInput {
        toolpaths: scene.toolpaths.as_ref(),
        constraints: &scene.solver.constraints,
        mesh: &prepared.mesh,
        geometry: &prepared.field.geometry,
        phi: shown.phi(prepared),
        symmetry: prepared.field_options.symmetry,
        keep_map: plan.gap,
        keep_field_mesh: plan.keeps_field_mesh(),
        surfaces: prepared.surfaces.as_ref(),
        straddle: &straddle,
    };
    let t = trace(&input)?;
    let gap = if plan.gap { t.gap(prepared.mesh.num_vertices()) } else { None };
    let brushed = if plan.as_brushed {
        stages.start("as-brushed");
        t.as_brushed(&input)?
    } else {
        None
    };
    let (mut fidelity, mut carrying) = (Vec::new(), Vec::new());
    if let (Some(b), Some(o)) = (&brushed, shown.optimized.filter(|_| plan.brushed_fidelity)) {
        stages.start("as-brushed fidelity");
        fidelity = brushed_fidelity(prepared, o, input.phi, b)?;
        if fidelity.iter().any(|f| f.designed.landed && !f.as_brushed.landed) {
            // Before the program is written: the brush that would carry each edit it loses.
            stages.start("brush width");
            let measure = |b: &AsBrushed| brushed_fidelity(prepared, o, input.phi, b);
            carrying = carrying_widths(&input, &t.section, &fidelity, measure)?;
        }
    }
    stages.start("write toolpaths");
    for (key, p, text) in t.outputs() {
        out.write(key, p, text.as_bytes())?;
    }
    let figures = t.figures(&input)?;
    Ok(RunTraced { strokes_3d: t.strokes_3d, gap, brushed, fidelity, carrying, figures })
}

/// The points of the edits' designed key highlight the strokes straddle
/// (`toolpaths.carry_edits: "straddle"`, [`crate::fidelity::carry`]); none without an edit with
/// a shape or with `"off"` (the default).
fn straddle_points(
    p: &Prepared,
    shown: &ShownField,
    scene: &crate::scene::Scene,
) -> Vec<crate::fidelity::carry::StraddlePoint> {
    use crate::scene::toolpaths::CarryEdits;
    let carry = scene.toolpaths.as_ref().map_or(CarryEdits::Off, |t| t.carry_edits);
    let Some(o) = shown.optimized.filter(|_| carry == CarryEdits::Straddle) else {
        return Vec::new();
    };
    let u = p.field.geometry.directions_of(shown.phi(p));
    let sym = p.field_options.symmetry;
    crate::fidelity::carry::straddle_points(&p.mesh, &o.h, &u, sym, &o.report.edits)
}

/// Each bend, expand and curve edit of `o` measured on the designed grain `phi` (the angles
/// the strokes were traced from) and on the grain `b` rebuilt from the strokes.
fn brushed_fidelity(
    p: &Prepared,
    o: &Optimized,
    phi: &[f64],
    b: &AsBrushed,
) -> Result<Vec<BrushedEditFidelity>> {
    let u: Vec<Vector3<f64>> = b.u.iter().map(|v| Vector3::from(*v)).collect();
    let mut out = brushed_fidelity_of_edits(
        &p.mesh,
        &p.field.geometry,
        &o.h,
        p.field_options.symmetry,
        &o.phi_before,
        phi,
        &u,
        &o.report.edits,
        &FidelityOptions::default(),
    )?;
    let shapes = o.report.edits.iter().filter_map(|r| r.shape.as_ref());
    for (f, shape) in out.iter_mut().zip(shapes) {
        let reach = 0.5 * b.width;
        f.beyond_reach_vertices =
            beyond_reach_in_support(&p.mesh, shape, &b.stroke_distance, reach);
    }
    Ok(out)
}

/// Writes FIELD.json (`field.output`): the solved field with the field before the edits, or
/// the initial one; with the edits measured as brushed, if any, in `meta.diagnostics`.
fn write_field(
    out: &mut Outputs,
    p: &str,
    prepared: &Prepared,
    optimized: Option<&Optimized>,
    fidelity: &[BrushedEditFidelity],
) -> Result<()> {
    let mut file = match optimized {
        Some(o) => optimized_field_file(prepared, o)?,
        None => super::prepare::initial_field_file(prepared)?,
    };
    if !fidelity.is_empty() {
        file.meta.diagnostics.fidelity = Some(serde_json::to_value(fidelity).map_err(|e| {
            crate::Error::Numerical { stage: "field output", message: e.to_string() }
        })?);
    }
    out.write("field.output", p, &json_compact(&file)?)
}

/// The field a run shows and what its trace stage made.
struct ShownAndTraced<'a> {
    plan: StagePlan,
    prepared: &'a Prepared,
    shown: &'a ShownField<'a>,
    traced: Option<&'a RunTraced>,
}

impl ShownAndTraced<'_> {
    fn strokes_3d(&self) -> &[Vec<Vector3<f64>>] {
        self.traced.map_or(&[][..], |t| t.strokes_3d.as_slice())
    }
    fn brushed_u(&self) -> Option<&[[f64; 3]]> {
        self.traced.and_then(|t| t.brushed.as_ref()).map(|b| b.u.as_slice())
    }
}

/// The preview stage of a run (`render`), when the scene has a render section.
fn render_stage(
    out: &mut Outputs,
    f: &ShownAndTraced,
    stages: &mut Stages,
) -> Result<Option<RenderReport>> {
    let Some(settings) = out.s.scene.render.as_ref().filter(|_| f.plan.render) else {
        return Ok(None);
    };
    stages.start("render");
    let (p, shown) = (f.prepared, f.shown);
    let r = super::preview::preview(&super::preview::PreviewInput {
        scene: out.s,
        settings,
        prepared: p,
        optimized: shown.optimized,
        phi: shown.phi(p),
        h: shown.h(p),
        h_gradient: shown.h_gradient(p),
        ell: shown.ell(p),
        critical: shown.critical(p),
        lighting: shown.lighting(p),
        strokes_3d: f.strokes_3d(),
        brushed_u: f.brushed_u(),
        gap: f.traced.and_then(|t| t.gap.as_deref()),
    })?;
    stages.start("write render");
    out.write("render.output", &settings.output, &r.png)?;
    if let (Some(path), Some(bytes)) = (&settings.linear, &r.linear) {
        out.write("render.linear", path, bytes)?;
    }
    Ok(Some(r.report))
}

/// The export stage of a run (`export.glb`, `export.maps`).
fn export_stage(
    out: &mut Outputs,
    f: &ShownAndTraced,
    stages: &mut Stages,
) -> Result<Option<crate::export::ExportReport>> {
    let scene = &out.s.scene;
    let Some(e) = scene.export.as_ref().filter(|_| f.plan.export || f.plan.maps) else {
        return Ok(None);
    };
    stages.start("export");
    let x = super::export::ExportStageInput {
        scene,
        section: e,
        prepared: f.prepared,
        phi: f.shown.phi(f.prepared),
        lighting: f.shown.lighting(f.prepared),
        strokes_3d: f.strokes_3d(),
        brushed_u: f.brushed_u(),
    };
    if let Some(dir) = &e.maps {
        let maps = super::export::maps(&x)?;
        let files = super::export::MAP_FILES;
        let dir = super::plan::output_dir_path(
            out.s,
            out.options.out_dir.as_deref(),
            "export.maps",
            dir,
        )?;
        out.staged.add(&dir.join(files[0]), &maps.direction)?;
        out.staged.add(&dir.join(files[1]), &maps.angle)?;
    }
    let Some(path) = &e.glb else { return Ok(None) };
    let glb = super::export::export(&x)?;
    out.write("export.glb", path, &glb.glb)?;
    Ok(Some(glb.report))
}
