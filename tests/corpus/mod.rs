//! The acceptance corpus of issue 13 ("Edits that land"), shared by `tests/edit_fidelity.rs`
//! and `examples/bench_fidelity.rs` (which includes this file with `#[path]`).
//!
//! - **Parts**: generated millimetre parts (a kettle-like body of revolution, a gently doubly
//!   curved panel, a flat sheet seen by a near eye, and each with a 0.15 mm ripple of 8 mm
//!   wavelength) and the meshes of `../shared/meshes` that have smooth regions, scaled to a
//!   200 mm bounding-box diagonal.
//! - **Lighting** (deterministic, from the part's bounding box; nothing tuned per edit): the
//!   generated parts have a fixed eye and key light per family; a shared mesh is seen from its
//!   thinnest bounding-box axis a₃ tilted towards the middle one a₂ (eye 1.5 diagonals away), lit
//!   from a₃ + a₂, with the initial field along its longest axis a₁ (or its UVs). Then the key
//!   highlight C0 = {hᵀu = 0} runs across the part's front.
//! - **Placement** ([`place`]): C0 is chained into polylines; a *stretch* is a run of C0 facing
//!   the eye, turning by less than 30° between the chords a quarter warp radius before and after
//!   each point, and at least one warp radius away from boundaries, critical points, creases
//!   (dihedral > 45°; on a part the run finds noisy, between the faces' fitted corner normals)
//!   and the initial field's singular triangles. On the longest stretch the brush centre is the
//!   point with the largest clearance (capped at half the curve's length), preferring the middle. Bend and expand: strength 0.8,
//!   radius 6 % of the diagonal, centred there, pushing across C0. Curve: an S-curve 25 % of the
//!   diagonal long through the centre, crossing C0 at about 50°, radius 2 % of the diagonal, traced
//!   on the surface as a 3D polyline.
//! - **Measure**: `grainline::fidelity` — the figures the optimize stage reports per edit
//!   (`OptimizeStageReport::fidelity`), from the shape the edit tool recorded.
#![allow(dead_code)]

use std::path::PathBuf;
use std::time::Instant;

use grainline::fidelity::EditFidelity;
use grainline::generate::{curved_panel, kettle_body, Ripple};
use grainline::mesh::Mesh;
use grainline::pipeline::optimize::optimize_stage;
use grainline::pipeline::{prepare, Prepared, Silent, Stages};
use grainline::scene::{LoadedScene, Scene};
use grainline::solve::SolverSettings;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Warp brush radius, share of the bounding-box diagonal.
pub const WARP_RADIUS: f64 = 0.06;
/// Warp strength.
pub const WARP_STRENGTH: f64 = 0.8;
/// Curve length, share of the diagonal.
pub const CURVE_LENGTH: f64 = 0.25;
/// Curve brush radius, share of the diagonal.
pub const CURVE_RADIUS: f64 = 0.02;

/// How fine the generated parts are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// 20k–60k vertices (the benchmark).
    Full,
    /// 5k–10k vertices (the test).
    Small,
}

/// The initial field of a case.
#[derive(Clone, Copy, Debug)]
pub enum Init {
    /// The part's UVs (`field.init: "uv"`).
    Uv,
    /// A world direction (`field.init: "world"`).
    World(V3),
}

/// One part of the corpus with its lighting.
#[derive(Clone, Debug)]
pub struct Case {
    /// Short name (the table's first column).
    pub name: String,
    /// The OBJ file.
    pub obj: PathBuf,
    /// `mesh.scale`.
    pub scale: f64,
    /// `mesh.weld`.
    pub weld: Option<f64>,
    /// `mesh.allow_nonmanifold`.
    pub nonmanifold: bool,
    /// The initial field.
    pub init: Init,
    /// The eye (scene units, after scaling).
    pub eye: V3,
    /// The point looked at.
    pub target: V3,
    /// Direction towards the key light.
    pub light: V3,
}

/// The directory of the generated OBJ files and scenes (one for every run, so nothing piles up
/// in the temporary directory).
pub fn scratch_dir() -> PathBuf {
    let d = std::env::temp_dir().join("grainline-corpus");
    let _ = std::fs::create_dir_all(&d);
    d
}

/// Writes a generated part (to a temporary name first, then renamed: tests running at the same
/// time never read a half-written file).
fn write_obj(mesh: &Mesh, name: &str) -> Result<PathBuf, String> {
    let dir = scratch_dir();
    let p = dir.join(format!("{name}-{}v.obj", mesh.num_vertices()));
    let tmp = dir.join(format!(
        "{name}-{}v.{}.{:?}.tmp",
        mesh.num_vertices(),
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::write(&tmp, grainline::mesh::write::obj_string(mesh, name))
        .and_then(|_| std::fs::rename(&tmp, &p))
        .map_err(|e| format!("{}: {e}", p.display()))?;
    Ok(p)
}

/// The generated parts: `body`, `panel`, `sheet` and their rippled variants `*-ripple`.
pub fn generated_cases(size: Size, names: Option<&[String]>) -> Result<Vec<Case>, String> {
    let wanted = |n: &str| names.is_none_or(|l| l.iter().any(|x| x == n));
    let (around, profile, nx, ny) = match size {
        Size::Full => (200, 200, 240, 180),
        Size::Small => (80, 80, 100, 75),
    };
    let mut out = Vec::new();
    for ripple in [None, Some(Ripple::CORPUS)] {
        let tail = if ripple.is_some() { "-ripple" } else { "" };
        // The body of revolution, UV field around it; eye in front, light above right.
        let name = format!("body{tail}");
        if wanted(&name) {
            let mesh = kettle_body(around, profile, ripple);
            out.push(Case {
                obj: write_obj(&mesh, &name)?,
                name,
                scale: 1.0,
                weld: None,
                nonmanifold: false,
                init: Init::Uv,
                eye: V3::new(0.0, -420.0, 170.0),
                target: V3::new(0.0, 0.0, 90.0),
                light: V3::new(0.35, -0.6, 0.7),
            });
        }
        // Panel and sheet: 200 × 150 mm, UV field along x, light from the front, eye 600 mm
        // (panel) or 300 mm (sheet) away. On the panel the grain tilts with the slope x/R;
        // seen from 300 mm that tilt cancels the view's change across the part and hᵀu has no
        // zero on it (the highlight is off the panel), from 600 mm it is at x ≈ −26 mm.
        for (base, r, eye) in [
            ("panel", (600.0, 400.0), V3::new(21.0, -300.0, 520.0)),
            ("sheet", (f64::INFINITY, f64::INFINITY), V3::new(21.0, -150.0, 260.0)),
        ] {
            let name = format!("{base}{tail}");
            if wanted(&name) {
                let mesh = curved_panel(200.0, 150.0, r.0, r.1, nx, ny, ripple);
                out.push(Case {
                    obj: write_obj(&mesh, &name)?,
                    name,
                    scale: 1.0,
                    weld: None,
                    nonmanifold: false,
                    init: Init::Uv,
                    eye,
                    target: V3::zeros(),
                    light: V3::new(0.0, -0.35, 1.0),
                });
            }
        }
    }
    Ok(out)
}

/// The shared meshes of the corpus (file, whether it has UVs, weld distance in file units,
/// non-manifold vertices accepted). The teapot's patches are welded, which leaves one
/// non-manifold vertex (its spout's tip).
pub const SHARED: [(&str, bool, Option<f64>, bool); 6] = [
    ("spot_triangulated.obj", true, None, false),
    ("blub_quadrangulated.obj", true, None, false),
    ("stanford-bunny.obj", false, None, false),
    ("fandisk.obj", false, None, false),
    ("rocker-arm.obj", false, None, false),
    ("teapot.obj", false, Some(1e-6), true),
];

/// `../shared/meshes` (or `$GRAINLINE_SHARED/meshes`), if present.
pub fn shared_dir() -> Option<PathBuf> {
    let root = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let d = root.join("meshes");
    d.exists().then_some(d)
}

/// The shared meshes' cases (scaled to a 200 mm diagonal); a message when `../shared` is absent,
/// and one per mesh that does not load.
pub fn shared_cases(names: Option<&[String]>) -> Result<Vec<Case>, String> {
    let Some(dir) = shared_dir() else {
        eprintln!("skipping the shared meshes: ../shared/meshes not found (set GRAINLINE_SHARED)");
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for (file, uv, weld, nonmanifold) in SHARED {
        let name = file.split(['_', '.']).next().unwrap_or(file).to_string();
        let name = name.strip_prefix("stanford-").unwrap_or(&name).to_string();
        if !names.is_none_or(|l| l.contains(&name)) {
            continue;
        }
        match mesh_case(&name, &dir.join(file), uv, weld, nonmanifold) {
            Ok(c) => out.push(c),
            Err(e) => eprintln!("skipping {name}: {e}"),
        }
    }
    Ok(out)
}

/// The case of any mesh file (OBJ, STL or PLY), lit and placed as the shared meshes are: scaled
/// to a 200 mm diagonal, seen from its thinnest bounding-box axis a₃ tilted towards a₂, lit
/// from a₃ + a₂, the initial field along a₁ (or its UVs when `uv` and it has them). This is how
/// a part the corpus has never seen is measured (`bench_fidelity --mesh FILE`).
pub fn mesh_case(
    name: &str,
    path: &std::path::Path,
    uv: bool,
    weld: Option<f64>,
    nonmanifold: bool,
) -> Result<Case, String> {
    let options = grainline::mesh::load::LoadOptions {
        weld,
        allow_nonmanifold: nonmanifold,
        ..Default::default()
    };
    let mesh = grainline::mesh::load::load_mesh(path, &options).map_err(|e| e.to_string())?.mesh;
    let (lo, hi) = bbox(&mesh.positions);
    let scale = 200.0 / (hi - lo).norm();
    if !(scale.is_finite() && scale > 0.0) {
        return Err(format!("{}: the mesh has no extent", path.display()));
    }
    let (lo, hi) = (lo * scale, hi * scale);
    let (c, ext) = ((lo + hi) * 0.5, hi - lo);
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| ext[b].total_cmp(&ext[a]).then(a.cmp(&b)));
    let unit = |k: usize| {
        let mut v = V3::zeros();
        v[k] = 1.0;
        v
    };
    let (a1, a2, a3) = (unit(axes[0]), unit(axes[1]), unit(axes[2]));
    let view = (a3 + 0.3 * a2).normalize();
    let uv = uv && mesh.uv.is_some();
    Ok(Case {
        name: name.to_string(),
        obj: path.to_path_buf(),
        scale,
        weld,
        nonmanifold,
        init: if uv { Init::Uv } else { Init::World(a1) },
        eye: c + 300.0 * view,
        target: c,
        light: (a3 + a2).normalize(),
    })
}

/// The scene of a case, without edits.
pub fn scene(case: &Case) -> Result<LoadedScene, String> {
    let json = scene_json(case);
    let path = scratch_dir().join(format!("{}.json", case.name));
    let scene = Scene::from_str(&json.to_string(), &path).map_err(|e| e.to_string())?;
    Ok(LoadedScene { base: scratch_dir(), path, scene })
}

/// The scene file of a case, without edits, as JSON (the mesh path absolute).
pub fn scene_json(case: &Case) -> serde_json::Value {
    let arr = |v: &V3| [v.x, v.y, v.z];
    let mut mesh =
        serde_json::json!({ "path": case.obj.display().to_string(), "scale": case.scale });
    if let Some(w) = case.weld {
        mesh["weld"] = w.into();
    }
    if case.nonmanifold {
        mesh["allow_nonmanifold"] = true.into();
    }
    let mut field = match case.init {
        Init::Uv => serde_json::json!({ "init": "uv", "symmetry": "line" }),
        Init::World(d) => {
            serde_json::json!({ "init": "world", "world": arr(&d), "symmetry": "line" })
        }
    };
    // `GRAINLINE_CORPUS_FIELD` (a JSON object of further `field` keys, the bench's `--field`,
    // e.g. `{"fit_radius": 8}`) is merged in, for experiments; a malformed one is ignored here
    // and refused by the bench before any case runs.
    if let Some(extra) = std::env::var("GRAINLINE_CORPUS_FIELD")
        .ok()
        .and_then(|e| serde_json::from_str::<serde_json::Value>(&e).ok())
    {
        for (k, v) in extra.as_object().into_iter().flatten() {
            field[k] = v.clone();
        }
    }
    serde_json::json!({
        "mesh": mesh,
        "units": "mm",
        "lights": [{ "type": "directional", "key": true, "direction": arr(&case.light) }],
        "view": { "eye": arr(&case.eye), "target": arr(&case.target) },
        "field": field,
    })
}

/// The solver settings for an energy: `Ok(None)` when this build's scene loader does not know
/// `solver.highlight_energy` and the energy is not today's ("tensor").
///
/// `GRAINLINE_CORPUS_SOLVER` (a JSON object of further `solver` keys, the bench's `--solver`)
/// is merged in, for experiments.
pub fn solver_settings(energy: &str) -> Result<Option<(SolverSettings, bool)>, String> {
    let mut json = serde_json::json!({ "highlight_energy": energy });
    if let Ok(extra) = std::env::var("GRAINLINE_CORPUS_SOLVER") {
        let extra: serde_json::Value =
            serde_json::from_str(&extra).map_err(|e| format!("GRAINLINE_CORPUS_SOLVER: {e}"))?;
        for (k, v) in extra.as_object().into_iter().flatten() {
            json[k] = v.clone();
        }
    }
    match serde_json::from_value::<SolverSettings>(json) {
        Ok(s) => Ok(Some((s, true))),
        Err(e) if e.to_string().contains("unknown field") => {
            Ok((energy == "tensor").then(|| (SolverSettings::default(), false)))
        }
        Err(e) => Err(format!("solver.highlight_energy = {energy:?}: {e}")),
    }
}

pub(crate) fn bbox(p: &[V3]) -> (V3, V3) {
    let mut lo = V3::repeat(f64::INFINITY);
    let mut hi = V3::repeat(f64::NEG_INFINITY);
    for q in p {
        lo = lo.inf(q);
        hi = hi.sup(q);
    }
    (lo, hi)
}

mod brushed;
mod placement;

#[allow(unused_imports)]
pub use brushed::{brushed_scene_json, run_brushed, BrushedOutcome, BRUSH_OVERLAP, BRUSH_WIDTH};
#[allow(unused_imports)]
pub use placement::{edits, edits_json, place, Placement};

// ---------------------------------------------------------------------------------------------
// Running a case

/// One row of the table.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The case.
    pub case: String,
    /// bend / expand / curve.
    pub edit: String,
    /// The highlight energy asked for.
    pub energy: String,
    /// Whether the scene loader knew `solver.highlight_energy` (false: today's solver ran).
    pub energy_key: bool,
    /// Vertices of the part.
    pub vertices: usize,
    /// The figures (`None` when the edit did not run).
    pub figures: Option<EditFidelity>,
    /// Accepted iterations.
    pub iterations: usize,
    /// The iteration cap.
    pub max_iterations: usize,
    /// Why the solver stopped.
    pub stop: String,
    /// Wall seconds of the edits and the solve.
    pub seconds: f64,
    /// Wall seconds of preparing the part with the edit (load, refinement, field).
    pub prepare_seconds: f64,
    /// Vertices the refinement added inside the brush (`mesh.refine`).
    pub vertices_added: usize,
    /// Total energy of the start and after each accepted iteration.
    pub energies: Vec<f64>,
    /// Continuation stage of each accepted iteration.
    pub stages: Vec<usize>,
    /// Why the edit did not run (its error), if it did not.
    pub error: Option<String>,
}

impl Outcome {
    /// The energy never rose (within a continuation stage; 1e-12 relative slack).
    pub fn energy_monotone(&self) -> bool {
        let mut prev = self.energies.first().copied().unwrap_or(0.0);
        for (k, &e) in self.energies.iter().enumerate().skip(1) {
            let same_stage = k < 2 || self.stages[k - 1] == self.stages[k - 2];
            if same_stage && e > prev * (1.0 + 1e-12) + 1e-300 {
                return false;
            }
            prev = e;
        }
        true
    }
}

/// A case prepared once: the scene, the initial field and the placement.
pub struct PreparedCase {
    /// The scene without edits.
    pub scene: LoadedScene,
    /// The initial field.
    pub prepared: Prepared,
    /// Where the edits go.
    pub placement: Result<Placement, String>,
}

/// Loads a case, computes its initial field and places its edits.
pub fn prepare_case(case: &Case) -> Result<PreparedCase, String> {
    let scene = scene(case)?;
    let mut stages = Stages::new(&Silent);
    let prepared = prepare(&scene, &mut stages).map_err(|e| format!("{}: {e}", case.name))?;
    let placement = place(&prepared.mesh, &prepared, &case.eye);
    Ok(PreparedCase { scene, prepared, placement })
}

/// Runs one edit of a prepared case with one energy; `None` when the energy is not available.
pub fn run_edit(
    case: &Case,
    p: &PreparedCase,
    tool: &str,
    energy: &str,
) -> Result<Option<Outcome>, String> {
    run_edit_with(case, p, tool, energy, &|_| {})
}

/// [`run_edit`] with the solver settings changed by `adjust`.
pub fn run_edit_with(
    case: &Case,
    p: &PreparedCase,
    tool: &str,
    energy: &str,
    adjust: &dyn Fn(&mut grainline::solve::SolverSettings),
) -> Result<Option<Outcome>, String> {
    let Some((mut settings, key)) = solver_settings(energy)? else { return Ok(None) };
    adjust(&mut settings);
    let pl = p.placement.as_ref().map_err(|e| format!("{}: {e}", case.name))?;
    let (_, edit) = edits(pl).into_iter().find(|(n, _)| *n == tool).ok_or("unknown tool")?;
    let mut scene = p.scene.clone();
    scene.scene.edits = vec![edit];
    scene.scene.solver = settings;
    // The part is prepared again with the edit in the scene, as `grainline run` does: the
    // mesh is refined inside the brush where its triangles are too coarse (`mesh.refine`).
    let t = Instant::now();
    let refined = prepare(&scene, &mut Stages::new(&Silent)).map_err(|e| e.to_string())?;
    let prepare_seconds = t.elapsed().as_secs_f64();
    let mesh = &refined.mesh;
    let mut out = Outcome {
        case: case.name.clone(),
        edit: tool.into(),
        energy: energy.into(),
        energy_key: key,
        vertices: mesh.num_vertices(),
        figures: None,
        iterations: 0,
        max_iterations: scene.scene.solver.max_iterations,
        stop: String::new(),
        seconds: 0.0,
        prepare_seconds,
        vertices_added: refined.refinement.as_ref().map_or(0, |r| r.vertices_added),
        energies: Vec::new(),
        stages: Vec::new(),
        error: None,
    };
    let mut stages = Stages::new(&Silent);
    let t = Instant::now();
    let o = match optimize_stage(&scene, &refined, &mut stages) {
        Ok(o) => o,
        Err(e) => {
            out.error = Some(e.to_string());
            return Ok(Some(out));
        }
    };
    out.seconds = t.elapsed().as_secs_f64();
    let r = &o.report.solver;
    out.iterations = r.iterations.len();
    out.stop = format!("{:?}", r.stop);
    out.energies = std::iter::once(r.initial_energy.total())
        .chain(r.iterations.iter().map(|i| i.energies.total()))
        .collect();
    out.stages = r.iterations.iter().map(|i| i.stage).collect();
    out.figures = o.report.fidelity.first().cloned();
    if out.figures.is_none() {
        out.error = Some("the optimize report has no fidelity for the edit".into());
    }
    Ok(Some(out))
}

/// The tools of the corpus, in table order.
pub const TOOLS: [&str; 3] = ["bend", "expand", "curve"];
