//! The run report's stroke-level constraint figures (issue 17) and the CLI's warning, on a flat
//! square whose grain is concentric circles about a point: every stroke turns at its own
//! radius, so the share of stroke length tighter than a limit R is the share of the rings
//! smaller than R — counted here from the strokes JSON with this file's own code, never from
//! the solver's energy or the crate's measure.

use std::path::{Path, PathBuf};
use std::process::Command;

use grainline::generate::{plane, Grid};
use grainline::mesh::write::obj_string;

const C: [f64; 2] = [0.37, -0.21];

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir()
        .join(format!("grainline-stroke-constraints-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 60 × 60 mm square on a 0.5 mm grid (UV = its own coordinates) with circles about `C` as the grain.
fn write_part(d: &Path, constraints: &str) -> PathBuf {
    write_part_about(d, constraints, C)
}

/// [`write_part`] with the circles about `c`.
fn write_part_about(d: &Path, constraints: &str, c: [f64; 2]) -> PathBuf {
    let mesh = plane(30.0, Grid::new(120, 120));
    std::fs::write(d.join("plane.obj"), obj_string(&mesh, "plane")).unwrap();
    let u: Vec<[f64; 3]> =
        mesh.positions.iter().map(|p| [-(p.y - c[1]), p.x - c[0], 0.0]).collect();
    std::fs::write(d.join("dirs.json"), serde_json::json!({ "u": u }).to_string()).unwrap();
    let s = format!(
        r#"{{
  "mesh": "plane.obj",
  "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
  "view": {{"eye": [0, -200, 80], "target": [0, 0, 0]}},
  "field": {{"init": "directions", "directions": "dirs.json", "symmetry": "line"}},
  "solver": {{"constraints": {constraints}}},
  "toolpaths": {{"strokes_json": "o/s.json", "placement": {{"width": 2}}}}
}}"#
    );
    let p = d.join("scene.json");
    std::fs::write(&p, s).unwrap();
    p
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

fn grainline(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_grainline")).args(args).output().unwrap()
}

#[test]
fn the_run_report_measures_the_turning_radius_on_the_strokes() {
    let d = dir("turning");
    let scene = write_part(&d, r#"{"turning_radius": {"radius": 12}}"#);
    let report = d.join("report.json");
    let out = grainline(&["run", scene.to_str().unwrap(), "--report", report.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let r = json(&report);
    let t = &r["toolpaths"]["stroke_constraints"]["turning"];
    assert_eq!(t["radius"], 12.0);
    // The rings from the strokes JSON: mean distance from C, length. Closed circles only
    // (strokes cut by the square's edge are arcs of the same radius, counted too).
    let strokes = json(&d.join("o/s.json"));
    let mut rings = Vec::new();
    for s in strokes["strokes"].as_array().unwrap() {
        let pts: Vec<[f64; 2]> = s["xyz"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|piece| piece.as_array().unwrap().iter())
            .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
            .collect();
        let r =
            pts.iter().map(|p| (p[0] - C[0]).hypot(p[1] - C[1])).sum::<f64>() / pts.len() as f64;
        rings.push((r, s["length_mm"].as_f64().unwrap(), s["closed"].as_bool().unwrap()));
    }
    let closed: Vec<f64> = rings.iter().filter(|r| r.2).map(|r| r.0).collect();
    assert!(closed.len() >= 5, "{} closed rings", closed.len());
    let smallest = closed.iter().copied().fold(f64::INFINITY, f64::min);
    let m = t["min_radius_mm"].as_f64().unwrap();
    assert!((m - smallest).abs() < 0.02 * smallest, "tightest {m}, smallest ring {smallest}");
    // Length share below R, with each stroke's measured length less two trims (open) or all
    // of it (closed) — the report's samples cover the same.
    let trim = r["toolpaths"]["stroke_constraints"]["trim_mm"].as_f64().unwrap();
    let kept = |x: &(f64, f64, bool)| if x.2 { x.1 } else { (x.1 - 2.0 * trim).max(0.0) };
    let total: f64 = rings.iter().map(kept).sum();
    let below: f64 = rings.iter().filter(|x| x.0 < 12.0).map(kept).sum();
    let got = t["below_radius"]["length_fraction"].as_f64().unwrap();
    assert!((got - below / total).abs() < 0.02, "{got} vs {}", below / total);
    assert!(t["below_80"]["samples"].as_u64().unwrap() > 0);
    // The CLI says so.
    assert!(stderr.contains("strokes turn tighter than the turning radius"), "{stderr}");
    // The field-level figures stay where they were: no edits, no solve.
    assert!(r["optimize"].is_null());
}

#[test]
fn no_constraint_no_stroke_figures_and_no_warning() {
    let d = dir("none");
    let scene = write_part(&d, "{}");
    let report = d.join("report.json");
    let out = grainline(&["run", scene.to_str().unwrap(), "--report", report.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let r = json(&report);
    assert!(r["toolpaths"].get("stroke_constraints").is_none());
    assert!(!stderr.contains("turning radius"), "{stderr}");
}

#[test]
fn a_lock_along_the_circles_is_followed_and_one_across_them_is_not() {
    let d = dir("lock");
    // At x ≈ 20 on C's row the circles run along ±y: a lock along y is nearly followed, one
    // along x is nearly 90° off.
    let scene = write_part(
        &d,
        r#"{"locks": [
            {"region": {"center": [20, -0.21, 0], "radius": 4}, "direction": [0, 1, 0]},
            {"region": {"center": [20, -0.21, 0], "radius": 4}, "direction": [1, 0, 0]}]}"#,
    );
    let report = d.join("report.json");
    let out = grainline(&["run", scene.to_str().unwrap(), "--report", report.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let r = json(&report);
    let locks = r["toolpaths"]["stroke_constraints"]["locks"].as_array().unwrap();
    assert_eq!(locks.len(), 2);
    assert_eq!(locks[0]["name"], "solver.constraints.locks[0]");
    assert!(locks[0]["samples"].as_u64().unwrap() > 10, "{locks:?}");
    // At (20 + dx, dy) from C's row the circle runs at atan(|dy| / (19.63 + dx)) to +y: at most
    // atan(4 / 15.63) = 14.4° inside the ball; the lock along x is the complement, sample by
    // sample, so the two means add up to 90°.
    let max0 = locks[0]["max_deviation_deg"].as_f64().unwrap();
    assert!(max0 < 14.4, "{max0}");
    let mean0 = locks[0]["mean_deviation_deg"].as_f64().unwrap();
    let mean1 = locks[1]["mean_deviation_deg"].as_f64().unwrap();
    assert_eq!(locks[0]["samples"], locks[1]["samples"]);
    assert!((mean0 + mean1 - 90.0).abs() < 1e-6, "{mean0} + {mean1}");
    assert!(stderr.contains("strokes through the lock solver.constraints.locks[1]"), "{stderr}");
}

/// Circles about a point 3 mm below the square's lower edge: the arcs that cross the square end
/// on that edge, and those tighter than R = 12 get both ends cut back (the solver's turning
/// radius becomes `toolpaths.plan.min_turning_radius`); arcs looser than R are not.
#[test]
fn tight_arcs_ending_on_the_edge_are_cut_back() {
    let d = dir("cuts");
    let c = [0.0, -33.0];
    let scene = write_part_about(&d, r#"{"turning_radius": {"radius": 12}}"#, c);
    let report = d.join("report.json");
    let out = grainline(&["run", scene.to_str().unwrap(), "--report", report.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r = json(&report);
    let cuts = r["toolpaths"]["job"]["tight_end_cuts"].as_u64().unwrap_or(0);
    let strokes = json(&d.join("o/s.json"));
    let mut tight = 0;
    for s in strokes["strokes"].as_array().unwrap() {
        let pts: Vec<[f64; 2]> = s["xyz"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|piece| piece.as_array().unwrap().iter())
            .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
            .collect();
        let rho =
            pts.iter().map(|p| (p[0] - c[0]).hypot(p[1] - c[1])).sum::<f64>() / pts.len() as f64;
        if rho < 0.95 * 12.0 && s["start"] == "boundary" && s["end"] == "boundary" {
            tight += 1;
        }
    }
    assert!(tight >= 2, "{tight} tight arcs");
    assert!(cuts >= 2 * tight, "{cuts} cuts for {tight} tight arcs");
}
