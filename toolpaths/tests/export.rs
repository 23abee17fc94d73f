//! SVG and G-code accepted by independent readers (vpype + resvg, LinuxCNC's rs274), and the
//! machine moves they imply checked against the settings.

mod common;

use common::{
    annulus_mesh, field_mesh, parse_canon, rect_mesh, run_tool, scratch, shared_tool, Canon,
};
use grainline_toolpaths::*;

fn job(arcs: bool, dialect: Dialect) -> JobOptions {
    JobOptions {
        placement: PlacementOptions::new(1.0, 0.1),
        plan: PlanOptions {
            arcs,
            contact_depth: 0.2,
            lead_in: 1.0,
            lead_out: 1.0,
            ramp_height: 0.5,
            overtravel: 0.5,
            ..Default::default()
        },
        coverage: Some(CoverageOptions::default()),
        svg: Some(SvgOptions { travel: true, ..Default::default() }),
        gcode: Some(GcodeOptions {
            dialect,
            feed: 1200.0,
            plunge_feed: 250.0,
            safe_z: 4.0,
            z_floor: Some(-1.0),
            ..Default::default()
        }),
        strokes_json: true,
    }
}

fn annulus() -> FieldMesh {
    field_mesh(annulus_mesh(3.0, 9.0, 12, 96), Symmetry::Vector, |p| [-p[1], p[0]])
}

fn rectangle() -> FieldMesh {
    field_mesh(rect_mesh(12.0, 8.0, 24, 16), Symmetry::Line, |p| {
        let a = 0.3 + 0.05 * p[0];
        [a.cos(), a.sin()]
    })
}

/// Feeds, safe Z and the floor, from the canonical moves.
fn check_canon(moves: &[Canon], o: &GcodeOptions) {
    assert!(moves.iter().any(|m| matches!(m, Canon::Feed(..))), "no feed moves");
    let mut prev = [0.0, 0.0, 0.0];
    for m in moves {
        match *m {
            Canon::Traverse(p) => {
                let moves_xy = (p[0] - prev[0]).abs() > 1e-9 || (p[1] - prev[1]).abs() > 1e-9;
                if moves_xy {
                    assert!((p[2] - o.safe_z).abs() < 1e-6, "XY rapid below safe Z: {p:?}");
                    assert!((prev[2] - o.safe_z).abs() < 1e-6, "XY rapid started below safe Z");
                }
                prev = p;
            }
            Canon::Feed(p, f) => {
                assert!(f > 0.0, "cutting move without feed at {p:?}");
                assert!(f == o.feed || f == o.plunge_feed, "unexpected feed {f}");
                assert!(p[2] >= o.z_floor.unwrap() - 1e-9, "below floor: {p:?}");
                prev = p;
            }
        }
    }
}

#[test]
fn gcode_accepted_by_linuxcnc_and_moves_are_safe() {
    let Some(tool) = shared_tool("check-gcode") else { return };
    let dir = scratch("gcode");
    let mut files = Vec::new();
    for (name, mesh, arcs) in [("annulus", annulus(), true), ("rect", rectangle(), false)] {
        for dialect in [Dialect::Grbl, Dialect::LinuxCnc, Dialect::Plain] {
            let o = job(arcs, dialect);
            let out = generate(mesh.clone(), &o).unwrap();
            let g = out.gcode.unwrap();
            assert!(!g.contains("NaN") && !g.contains("inf"));
            if arcs {
                assert!(g.contains("G2 ") || g.contains("G3 "), "no arcs fitted");
            }
            let path = dir.join(format!("{name}-{dialect:?}.ngc"));
            std::fs::write(&path, &g).unwrap();
            files.push((path, o.gcode.unwrap()));
        }
    }
    let canon = dir.join("canon");
    let mut args: Vec<&std::path::Path> = vec![std::path::Path::new("--canon"), &canon];
    args.extend(files.iter().map(|(p, _)| p.as_path()));
    let (ok, text) = run_tool(&tool, &args);
    assert!(ok, "check-gcode rejected a program:\n{text}");
    for (p, o) in &files {
        let c = canon.join(format!("{}.canon", p.file_name().unwrap().to_string_lossy()));
        check_canon(&parse_canon(&std::fs::read_to_string(c).unwrap()), o);
    }
}

#[test]
fn svg_read_by_vpype_and_resvg() {
    let Some(tool) = shared_tool("check-svg") else { return };
    let dir = scratch("svg");
    let out = generate(annulus(), &job(false, Dialect::Grbl)).unwrap();
    let svg = out.svg.unwrap();
    assert!(svg.contains("inkscape:groupmode=\"layer\""));
    assert!(svg.contains("width=\"22.000mm\"") && svg.contains("viewBox=\"0 0 22.000 22.000\""));
    let path = dir.join("annulus.svg");
    std::fs::write(&path, &svg).unwrap();
    let (ok, text) = run_tool(&tool, &[&path]);
    assert!(ok, "check-svg rejected the SVG:\n{text}");
    // vpype's pen-down length counts strokes, outlines and the travel layer: at least the
    // strokes' UV length (the annulus has an identity metric).
    let down: f64 = text
        .split_whitespace()
        .find_map(|w| w.strip_prefix("pen_down_mm="))
        .and_then(|v| v.parse().ok())
        .unwrap();
    assert!(
        down >= 0.99 * out.report.pen_down_length_mm,
        "{down} vs {}",
        out.report.pen_down_length_mm
    );
}

#[test]
fn outputs_are_byte_identical_across_runs() {
    let o = job(true, Dialect::LinuxCnc);
    let a = generate(rectangle(), &o).unwrap();
    let b = generate(rectangle(), &o).unwrap();
    assert_eq!(a.svg, b.svg);
    assert_eq!(a.gcode, b.gcode);
    assert_eq!(a.strokes_json, b.strokes_json);
    let report = serde_json::to_string(&a.report).unwrap();
    assert!(report.contains("\"stroke_count\"") && !report.contains("NaN"));
    let json: serde_json::Value = serde_json::from_str(a.strokes_json.as_ref().unwrap()).unwrap();
    assert_eq!(json["format"], "grainline-strokes");
    assert_eq!(json["strokes"].as_array().unwrap().len(), a.plan.passes.len());
}

/// Dialect details: grbl ends with M30, plain has no spindle commands, a snippet replaces
/// M3/M5, and every number has the configured fixed precision.
#[test]
fn dialects_and_number_format() {
    let run = |dialect, spindle| {
        let mut o = job(false, dialect);
        o.gcode.as_mut().unwrap().spindle = spindle;
        generate(rectangle(), &o).unwrap().gcode.unwrap()
    };
    let grbl = run(Dialect::Grbl, Spindle::Speed(12000.0));
    assert!(grbl.contains("M3 S12000\n") && grbl.contains("M5\n") && grbl.ends_with("M30\n"));
    assert!(!grbl.contains("G64"));
    let plain = run(Dialect::Plain, Spindle::Speed(12000.0));
    assert!(!plain.contains("M3") && !plain.contains("M5") && plain.ends_with("M2\n"));
    let lcnc = run(Dialect::LinuxCnc, Spindle::Snippet { on: "M7".into(), off: "M9".into() });
    assert!(lcnc.contains("G64 P") && lcnc.contains("M7\n") && lcnc.contains("M9\n"));
    assert!(
        lcnc.starts_with("(grainline-toolpaths job: grainline)\nG21 G90 G17 G94")
            || lcnc.contains("G21 G90 G17 G94\n")
    );
    // Every X/Y/Z word has exactly three decimals.
    for w in lcnc.split_whitespace().filter(|w| w.starts_with(['X', 'Y', 'Z'])) {
        let frac = w.split('.').nth(1).unwrap_or("");
        assert_eq!(frac.len(), 3, "{w}");
        assert!(!w.contains("-0.000"), "{w}");
    }
}
