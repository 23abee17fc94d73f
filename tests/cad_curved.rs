//! Curved CAD faces read as the surfaces they approximate: the generated parts with fillets,
//! a bend, turned profiles with chamfers and grooves, a torus round and a spherical crown
//! (`grainline::generate::cad`), exported as float32 STL at 10°, 15° and 30° chords, run with
//! a world grain and no edit. On every curved face, against the analytic surface
//! (tests/support/curved_truth.rs, not grainline's recognition): ≥ 99 % of the stroke length
//! within 1° of the world direction projected onto the true tangent plane, the strokes' points
//! on the surface (within the plan tolerance), ≥ 99 % of the glb's corner normals within 1° of
//! the true normal and ≥ 99 % of the face's glb area carrying the grain within 1°.

#[path = "support/cad_truth.rs"]
mod cad_truth;
mod common;
#[path = "support/curved_truth.rs"]
mod curved_truth;

use std::path::Path;
use std::process::Command;

use curved_truth::{share, FaceFigures};
use grainline::generate::cad::{self, CadPart};

/// A world direction along no axis of the parts.
const WORLD: cad_truth::P = [0.2, 1.0, 0.3];

fn parts(step_deg: f64) -> Vec<CadPart> {
    vec![
        cad::housing(&cad::HousingOptions { step_deg, ..Default::default() }).unwrap(),
        cad::bracket(&cad::BracketOptions { step_deg, ..Default::default() }).unwrap(),
        cad::turned(&cad::TurnedOptions { step_deg, ..Default::default() }).unwrap(),
        cad::knob(&cad::KnobOptions { step_deg, ..Default::default() }).unwrap(),
    ]
}

fn measure(part: &CadPart, step: f64, root: &Path) -> Vec<FaceFigures> {
    let dir = root.join(format!("{}-{step}", part.name));
    std::fs::create_dir_all(&dir).unwrap();
    let stl = dir.join("part.stl");
    std::fs::write(&stl, part.stl_binary()).unwrap();
    curved_truth::run_and_measure(part, &stl, &dir, WORLD)
}

#[test]
fn curved_faces_are_brushed_and_exported_as_the_surfaces_they_approximate() {
    let root = std::env::temp_dir().join(format!("grainline-curved-{}", std::process::id()));
    let mut failures = Vec::new();
    for step in steps() {
        for part in parts(step) {
            if std::env::var("CURVED_PARTS").is_ok_and(|p| !p.split(',').any(|n| n == part.name)) {
                continue;
            }
            let figures = measure(&part, step, &root);
            for (k, f) in figures.iter().enumerate() {
                if part.faces[k].is_planar() {
                    continue;
                }
                // A face the recognition documents as left unread at this step keeps its
                // chords (tests/surfaces.rs); it is listed, not judged.
                let unread = curved_truth::may_be_unread(&part, step, k);
                let s = share(f.stroke_ok, f.stroke_len);
                let n = share(f.corners_ok as f64, f.corners as f64);
                let g = share(f.area_ok, f.area);
                let line = format!(
                    "{} {step}° face {k} ({}): strokes {:.1} % of {:.1} within 1° ({:.1} \
                     near the pole), off the surface ≤ {:.2e}; glb normals {:.1} % of {}, \
                     grain {:.1} % of {:.1} (interior normals {:.1} %){}",
                    part.name,
                    kind(&part.faces[k]),
                    100.0 * s,
                    f.stroke_len,
                    f.stroke_skipped,
                    f.stroke_off,
                    100.0 * n,
                    f.corners,
                    100.0 * g,
                    f.area,
                    100.0 * share(f.area_normal_ok, f.area),
                    if unread { " — documented as unread" } else { "" }
                );
                eprintln!("{line}");
                let short = [("strokes", s), ("normals", n), ("grain", g)]
                    .into_iter()
                    .filter(|&(_, x)| x < 0.99);
                if !unread && short.count() > 0 {
                    failures.push(line);
                }
            }
        }
    }
    std::fs::remove_dir_all(&root).ok();
    assert!(failures.is_empty(), "{failures:#?}");
}

fn kind(f: &cad::AnalyticFace) -> &'static str {
    match f {
        cad::AnalyticFace::Plane { .. } => "plane",
        cad::AnalyticFace::Cylinder { .. } => "cylinder",
        cad::AnalyticFace::Cone { .. } => "cone",
        cad::AnalyticFace::Torus { .. } => "torus",
        cad::AnalyticFace::Sphere { .. } => "sphere",
    }
}

/// The chordal steps measured (`CURVED_STEPS=30,15` for a part of the run; `CURVED_PARTS=knob`
/// for some parts, `CURVED_DEBUG=K` prints what fails on face K).
fn steps() -> Vec<f64> {
    std::env::var("CURVED_STEPS")
        .map(|s| s.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or_else(|_| vec![10.0, 15.0, 30.0])
}

/// The preview of a part exported at 10°, 15° and 30° chords against the preview of the same
/// part at 1° (same scene: an anisotropic metal, a key light, a world grain): the share of the
/// part's pixels (part in either image) whose luminance (after a 1/2.2 gamma) is within 0.04
/// must be 99 % at least (the goal). The curved chords are drawn on their surfaces
/// and shade with their normal and grain per sample. Measured: bracket 100 % at every step,
/// knob 100 % at 10° and 15°, 99.5 % at 30°; drawing the chords flat the knob at 15° kept
/// 97.7 % (one-pixel lines along its rims), blending the chords' normals and grain 96.4 %.
#[test]
fn the_preview_of_a_coarse_export_matches_the_fine_export() {
    let root = std::env::temp_dir().join(format!("grainline-curved-px-{}", std::process::id()));
    let bracket = |step_deg| cad::bracket(&cad::BracketOptions { step_deg, ..Default::default() });
    let knob = |step_deg| cad::knob(&cad::KnobOptions { step_deg, ..Default::default() });
    let views =
        [([90.0, -60.0, 70.0], [20.0, 30.0, 10.0]), ([60.0, -90.0, 70.0], [0.0, 0.0, 12.0])];
    let mut failures = Vec::new();
    for (make, (eye, target)) in [(&bracket as &dyn Fn(f64) -> _, views[0]), (&knob, views[1])] {
        let fine: cad::CadPart = make(1.0).unwrap();
        let b = preview(&root, &fine, (eye, target));
        for step in [10.0, 15.0, 30.0] {
            let coarse: cad::CadPart = make(step).unwrap();
            let a = preview(&root, &coarse, (eye, target));
            let (share, part) = curved_truth::preview_agreement(&a, &b);
            let line = format!(
                "{} at {step}°: {:.2} % of {part} part pixels within 0.04",
                coarse.name,
                100.0 * share
            );
            eprintln!("{line}");
            if share < 0.99 {
                failures.push(line);
            }
        }
    }
    std::fs::remove_dir_all(&root).ok();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The linear preview of `part` (written as STL under `root`) from `eye` towards `target`.
fn preview(root: &Path, part: &cad::CadPart, view: ([f64; 3], [f64; 3])) -> Vec<[f32; 3]> {
    let dir = root.join(format!("{}-{}", part.name, part.triangles.len()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("part.stl"), part.stl_binary()).unwrap();
    curved_truth::render_preview(&dir, ("part.stl", part.units.as_str()), view, PX)
}

/// Preview size of [`the_preview_of_a_coarse_export_matches_the_fine_export`].
const PX: usize = 384;

/// A rotary program of the turned shaft at 15° chords with `axis: "auto"`: the fixture is the
/// shaft's recognized axis, z through the origin, exactly as the program prints it (the axis
/// fitted to the chords' normals, with `mesh.surfaces: "off"`, is 0.01° and 0.007 mm off), and
/// LinuxCNC's rs274 reads the program.
#[test]
fn a_rotary_program_holds_a_turned_part_on_its_recognized_axis() {
    let dir = std::env::temp_dir().join(format!("grainline-curved-rot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let part = cad::turned(&cad::TurnedOptions { step_deg: 15.0, ..Default::default() }).unwrap();
    std::fs::write(dir.join("part.stl"), part.stl_binary()).unwrap();
    let scene = serde_json::json!({
        "mesh": "part.stl", "units": "mm",
        "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
        "view": {"eye": [100, -200, 150], "target": [0, 0, 30]},
        "field": {"init": "world", "world": [0, 0, 1]},
        "toolpaths": {"gcode": "p.ngc", "placement": {"width": 2},
                      "gcode_options": {"safe_z": 30},
                      "plan": {"z_mode": {"mode": "rotary", "axis": "auto", "max_tilt_deg": 60,
                                          "on_tilt": "skip"}}}
    });
    std::fs::write(dir.join("scene.json"), scene.to_string()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(dir.join("scene.json"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let gcode = std::fs::read_to_string(dir.join("p.ngc")).unwrap();
    let header = gcode.lines().find(|l| l.starts_with("(rotary: point ")).unwrap();
    let words: Vec<&str> = header.trim_end_matches(')').split(' ').collect();
    let nums = |w: &str| -> Vec<f64> { w.split(',').map(|x| x.parse().unwrap()).collect() };
    let (point, direction) = (nums(words[2]), nums(words[4]));
    assert!(point[0].abs() < 1e-3 && point[1].abs() < 1e-3, "{header}");
    assert!(direction[0].abs() < 1e-6 && direction[1].abs() < 1e-6, "{header}");
    // The program, its points on the surfaces, read by LinuxCNC's rs274.
    let shared = std::env::var_os("GRAINLINE_SHARED")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let tool = shared.join("tools/check-gcode");
    if tool.exists() {
        common::ensure_rs274(&tool);
        let ngc = dir.join("p.ngc");
        let (ok, text) = common::run_checker(&tool, &[ngc.as_os_str()]);
        assert!(ok, "check-gcode rejected the rotary program:\n{text}");
    } else {
        eprintln!("skipping the rs274 check: {} not found", tool.display());
    }
    std::fs::remove_dir_all(&dir).ok();
}
