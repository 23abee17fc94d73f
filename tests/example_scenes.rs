//! The bundled example scenes run end to end and write their SVG, G-code and PNG
//! (the spot scene needs ../shared and is skipped with a message without it). Each G-code
//! program is read by LinuxCNC's rs274 (`../shared/tools/check-gcode --canon`, which installs
//! rs274 on first use): accepted, no rapid below the travel height, travel above every
//! cutting point, every feed > 0.

mod common;

use std::path::PathBuf;
use std::process::Command;

fn run_example(name: &str, outputs: &[&str]) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("examples").join(name).join("scene.json");
    let out = std::env::temp_dir().join(format!("grainline-example-{name}-{}", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(&scene)
        .arg("--out-dir")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    for f in outputs {
        let bytes = std::fs::read(out.join(f)).unwrap_or_default();
        assert!(bytes.len() > 100, "{name}: {f} missing or empty");
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run-report.json")).unwrap()).unwrap();
    assert!(report["toolpaths"]["job"]["stroke_count"].as_u64().unwrap() > 0, "{name}: no strokes");
    for f in outputs.iter().filter(|f| f.ends_with(".ngc")) {
        check_gcode(name, &out.join(f), &out.join("canon"));
    }
    std::fs::remove_dir_all(&out).ok();
}

/// `../shared/tools/check-gcode` (or under `$GRAINLINE_SHARED`), or None with a message.
fn check_gcode_tool() -> Option<PathBuf> {
    let shared = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let p = shared.join("tools/check-gcode");
    if p.exists() {
        common::ensure_rs274(&p);
        Some(p)
    } else {
        eprintln!("skipping the rs274 check: {} not found (../shared is absent)", p.display());
        None
    }
}

/// rs274 accepts the program; its canonical moves never rapid below the travel height, the
/// travel height is above every cutting point, and every feed is > 0.
fn check_gcode(name: &str, ngc: &std::path::Path, canon: &std::path::Path) {
    let Some(tool) = check_gcode_tool() else { return };
    let (ok, text) =
        common::run_checker(&tool, &["--canon".as_ref(), canon.as_os_str(), ngc.as_os_str()]);
    assert!(ok, "{name}: check-gcode rejected {}:\n{text}", ngc.display());
    let file = canon.join(format!("{}.canon", ngc.file_name().unwrap().to_string_lossy()));
    let c = std::fs::read_to_string(file).unwrap();
    let args = |l: &str| -> Vec<f64> {
        let a = &l[l.find('(').unwrap() + 1..l.rfind(')').unwrap()];
        a.split(',').filter_map(|x| x.trim().parse().ok()).collect()
    };
    let (mut rapid_z, mut cut_z, mut feed, mut feeds) = (Vec::new(), Vec::new(), 0.0, 0);
    for l in c.lines() {
        if l.contains("USE_LENGTH_UNITS(") {
            assert!(l.contains("CANON_UNITS_MM"), "{name}: {l}");
        } else if l.contains("SET_FEED_RATE(") {
            feed = args(l)[0];
        } else if l.contains("STRAIGHT_TRAVERSE(") {
            rapid_z.push(args(l)[2]);
        } else if l.contains("STRAIGHT_FEED(") || l.contains("ARC_FEED(") {
            let a = args(l);
            cut_z.push(if l.contains("ARC_FEED(") { a[5] } else { a[2] });
            assert!(feed > 0.0, "{name}: a cutting move at feed {feed}: {l}");
            feeds += 1;
        }
    }
    assert!(feeds > 10, "{name}: only {feeds} cutting moves");
    let travel = rapid_z[0];
    let top = cut_z.iter().cloned().fold(f64::MIN, f64::max);
    assert!(rapid_z.iter().all(|&z| (z - travel).abs() < 1e-4), "{name}: a rapid below travel");
    assert!(travel > top, "{name}: travel {travel} not above the highest cut {top}");
}

#[test]
fn kettle_bend() {
    run_example("kettle", &["kettle.svg", "kettle.ngc", "kettle.png"]);
}

#[test]
fn panel_curve() {
    run_example("panel", &["panel.svg", "panel.ngc", "panel.png"]);
}

#[test]
fn dome_bend() {
    run_example("dome", &["dome.svg", "dome.ngc", "dome.png"]);
}

#[test]
fn light_tool() {
    run_example("light", &["light.svg", "light.ngc", "light.png"]);
}

#[test]
fn spot_stencil() {
    let mesh =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes/spot_triangulated.obj");
    if !mesh.exists() {
        eprintln!("skipping: {} not found (../shared is absent)", mesh.display());
        return;
    }
    run_example("spot", &["spot.svg", "spot.ngc", "spot.png"]);
}
