//! The cycle time (issue 31, item 2): the report's `cycle_time_s` and the program header's
//! figure against a hand-computed pass, and against the time recomputed from LinuxCNC's
//! canonical moves (rs274) for flat jobs with leads, ramps, overtravel, arcs, several passes
//! and sheets, and for a surface-following job.

mod common;

use common::{annulus_mesh, field_mesh, parse_canon_moves, rect_mesh, CanonMove};
use grainline_toolpaths::*;

/// One pass by hand: from home (−3, 4) to (0, 0) at Z 5, plunge to Z −0.2, 10 mm along +X,
/// retract.
fn one_pass(scale: f64) -> Plan {
    let p = |v: [f64; 3]| v.map(|x| x / scale);
    Plan {
        passes: vec![Pass {
            stroke: 0,
            reversed: false,
            start: p([0.0, 0.0, -0.2]),
            moves: vec![(MoveKind::Cut, Segment::Line { to: p([10.0, 0.0, -0.2]) })],
            uv: vec![vec![[0.0, 0.0], [10.0 / scale, 0.0]]],
            xyz: None,
            stops: [StopReason::Boundary; 2],
            length: 10.0,
            sheet: 0,
        }],
        skipped_tilt: Vec::new(),
        travel: 5.0,
        travel_between: 0.0,
        travel_greedy: 5.0,
        width: 1.0,
        home: [-3.0 / scale, 4.0 / scale],
        tolerance: 0.01 / scale,
        rotary: None,
    }
}

fn hand_options(unit: LengthUnit) -> GcodeOptions {
    let k = unit.in_mm();
    GcodeOptions {
        feed: 1000.0 / k,
        plunge_feed: 300.0 / k,
        rapid_rate_mm_min: Some(6000.0),
        safe_z: 5.0 / k,
        clearance: 1.0 / k,
        spindle: Spindle::Snippet {
            on: "M3 S9000\nG4 P1.5 (spin up)".into(),
            off: "M5 G4 P0.5".into(),
        },
        units: unit,
        ..Default::default()
    }
}

/// Hand-computed: rapid 5 mm at 6000 mm/min (0.05 s), plunge 5.2 mm at 300 (1.04 s), cut 10
/// mm at 1000 (0.6 s), retract 5.2 mm at 6000 (0.052 s), dwell 1.5 + 0.5 s: 3.742 s. The same
/// job in inches (lengths and feeds in inches, the rapid rate in mm/min as always) takes the same time.
#[test]
fn one_straight_pass_is_timed_exactly() {
    for unit in [LengthUnit::Mm, LengthUnit::In] {
        let plan = one_pass(unit.in_mm());
        let o = hand_options(unit);
        let t = cycle_time(&plan, &o).unwrap();
        let want =
            [(t.rapid_s, 0.05 + 0.052), (t.plunge_s, 1.04), (t.cut_s, 0.6), (t.dwell_s, 2.0)];
        for (got, w) in want {
            assert!((got - w).abs() < 1e-9, "{unit:?}: {t:?}");
        }
        assert!((t.total_s - 3.742).abs() < 1e-9, "{unit:?}: {t:?}");
        assert_eq!((t.pauses, t.rapid_mm_min), (0, 6000.0));
        let g = write_gcode(&plan, &o).unwrap();
        assert!(
            g.contains(
                "(cycle time: 3.7 s at rapid 6000 mm/min: cutting 0.6 s, plunges 1.0 s, rapids \
                 0.1 s, dwell 2.0 s; no acceleration, M0 pauses not counted)"
            ),
            "{g}"
        );
        // The plain dialect prints no snippets: no dwell.
        let plain = GcodeOptions { dialect: Dialect::Plain, ..o };
        assert!((cycle_time(&plan, &plain).unwrap().total_s - 1.742).abs() < 1e-9);
    }
    // Without the key: 5000 mm/min, whatever the units.
    let o = GcodeOptions { rapid_rate_mm_min: None, ..hand_options(LengthUnit::In) };
    let t = cycle_time(&one_pass(25.4), &o).unwrap();
    assert_eq!(t.rapid_mm_min, DEFAULT_RAPID_MM_MIN);
    assert!((t.rapid_s - 60.0 * 10.2 / 5000.0).abs() < 1e-9, "{t:?}");
}

#[test]
fn rapid_rate_mm_min_must_be_positive() {
    for bad in [0.0, -100.0, f64::NAN, 0.01] {
        let o = GcodeOptions { rapid_rate_mm_min: Some(bad), ..Default::default() };
        let e = o.validate().unwrap_err();
        let key = match &e {
            ToolpathError::InvalidOption { name, .. } => *name,
            ToolpathError::Gcode { key, .. } => *key,
            other => panic!("{other}"),
        };
        assert_eq!(key, "gcode.rapid_rate_mm_min", "{bad}: {e}");
    }
}

/// The time of a program from rs274's canonical moves, starting where rs274 starts (the
/// origin): feed moves at the feed in force, arcs by their helical length, traverses at
/// `rapid` mm/min, plus every `DWELL`.
fn canon_time(text: &str, rapid: f64) -> f64 {
    let (moves, mm) = parse_canon_moves(text);
    assert!(mm, "canon not in mm");
    let d = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let mut cur = [0.0; 3];
    let mut t = 0.0;
    for m in moves {
        match m {
            CanonMove::Traverse(p) => {
                t += 60.0 * d(cur, p) / rapid;
                cur = p;
            }
            CanonMove::Line(p, f) => {
                assert!(f > 0.0);
                t += 60.0 * d(cur, p) / f;
                cur = p;
            }
            CanonMove::Arc { end, center, ccw, feed } => {
                let a0 = (cur[1] - center[1]).atan2(cur[0] - center[0]);
                let a1 = (end[1] - center[1]).atan2(end[0] - center[0]);
                let r = ((cur[0] - center[0]).powi(2) + (cur[1] - center[1]).powi(2)).sqrt();
                let tau = std::f64::consts::TAU;
                let sweep = if ccw { (a1 - a0).rem_euclid(tau) } else { (a0 - a1).rem_euclid(tau) };
                let len = ((r * sweep).powi(2) + (end[2] - cur[2]).powi(2)).sqrt();
                t += 60.0 * len / feed;
                cur = end;
            }
        }
    }
    let dwell: f64 = text
        .lines()
        .filter_map(|l| l.split_once("DWELL(").map(|(_, a)| a))
        .filter_map(|a| a.trim_end_matches(')').trim().parse::<f64>().ok())
        .sum();
    t + dwell
}

/// Two faces side by side (cut as two sheets) with a fan of directions.
fn two_sheets() -> FieldMesh {
    let (mut uv, mut tris) = (Vec::new(), Vec::new());
    for (w, u0) in [(30.0, 0.0), (20.0, 40.0)] {
        let (g, t) = rect_mesh(w, 20.0, 30, 20);
        let base = uv.len() as u32;
        uv.extend(g.iter().map(|p| [p[0] + u0, p[1]]));
        tris.extend(t.iter().map(|tr| tr.map(|v| v + base)));
    }
    let d = uv.iter().map(|p| [1.0, 0.02 * (p[1] - 10.0)]).collect();
    FieldMesh::new(uv, tris, Directions::Vectors(d), Symmetry::Line)
}

/// A 30 × 20 sheet bent into a bump `z = 4 sin(πu/30)`, grain along U.
fn bump() -> FieldMesh {
    let (uv, tris) = rect_mesh(30.0, 20.0, 30, 20);
    let pos: Vec<Vec3> =
        uv.iter().map(|p| [p[0], p[1], 4.0 * (std::f64::consts::PI * p[0] / 30.0).sin()]).collect();
    let d = uv.iter().map(|_| [1.0, 0.1]).collect();
    FieldMesh::new(uv, tris, Directions::Vectors(d), Symmetry::Line).with_lift(pos, None)
}

fn plan(arcs: bool, z_mode: ZMode) -> PlanOptions {
    PlanOptions {
        arcs,
        contact_depth: 0.2,
        lead_in: 2.0,
        lead_out: 1.5,
        ramp_height: 0.5,
        overtravel: 0.5,
        z_mode,
        sheets: Sheets::Chart,
        ..Default::default()
    }
}

/// Report and header against rs274's canonical moves: within 10 % (the bar); in
/// fact within 0.5 %, all of it rs274's start at the origin (one `G0 Z` from Z 0 that the
/// estimate leaves out): without it, within 1e-9.
#[test]
fn cycle_time_matches_rs274_canonical_moves() {
    let flat = ZMode::Flat { surface_z: 0.0 };
    let surface = ZMode::SurfaceFollowing { max_tilt_deg: 60.0, on_tilt: TiltPolicy::Error };
    let annulus = field_mesh(annulus_mesh(3.0, 9.0, 12, 96), Symmetry::Vector, |p| [-p[1], p[0]]);
    let snippet = Spindle::Snippet { on: "M3 S12000\nG4 P2".into(), off: "M5\nG4 P1".into() };
    let cases = [
        ("sheets", two_sheets(), plan(false, flat), Some(4000.0), snippet),
        ("annulus-arcs", annulus, plan(true, flat), None, Spindle::Speed(1000.0)),
        ("bump-surface", bump(), plan(false, surface), Some(8000.0), Spindle::Speed(1000.0)),
    ];
    let mut programs = Vec::new();
    for (name, mesh, plan, rapid_rate, spindle) in cases {
        let gcode = GcodeOptions {
            feed: 1200.0,
            plunge_feed: 250.0,
            rapid_rate_mm_min: rapid_rate,
            safe_z: 10.0,
            spindle,
            ..Default::default()
        };
        let o = JobOptions {
            placement: PlacementOptions::new(1.0, 0.0),
            plan,
            gcode: Some(gcode.clone()),
            ..Default::default()
        };
        let out = generate(mesh, &o).unwrap();
        assert!(out.plan.passes.len() > 5, "{name}: {} passes", out.plan.passes.len());
        let t = cycle_time(&out.plan, &gcode).unwrap();
        assert_eq!(out.report.cycle_time_s, Some(t.total_s), "{name}");
        let g = out.gcode.unwrap();
        let head = format!("(cycle time: {:.1} s at rapid", t.total_s);
        assert!(g.lines().any(|l| l.starts_with(&head)), "{name}: {head}");
        if name == "sheets" {
            assert!(t.pauses >= 1 && t.dwell_s == 3.0 * (t.pauses + 1) as f64, "{t:?}");
        }
        if name == "annulus-arcs" {
            assert!(g.contains("G2 ") || g.contains("G3 "), "no arcs");
        }
        programs.push((name, g, t));
    }
    let Some(tool) = common::shared_tool("check-gcode") else { return };
    let dir = common::scratch("cycle-time");
    let canon = dir.join("canon");
    let paths: Vec<_> = programs.iter().map(|(n, ..)| dir.join(format!("{n}.ngc"))).collect();
    for (p, (_, g, _)) in paths.iter().zip(&programs) {
        std::fs::write(p, g).unwrap();
    }
    let mut args: Vec<&std::path::Path> = vec![std::path::Path::new("--canon"), &canon];
    args.extend(paths.iter().map(|p| p.as_path()));
    let (ok, text) = common::run_tool(&tool, &args);
    assert!(ok, "check-gcode rejected a program:\n{text}");
    for (p, (name, _, t)) in paths.iter().zip(&programs) {
        let c = canon.join(format!("{}.canon", p.file_name().unwrap().to_string_lossy()));
        let want = canon_time(&std::fs::read_to_string(c).unwrap(), t.rapid_mm_min);
        let rel = (t.total_s - want).abs() / want;
        // rs274 starts at Z 0, the estimate at the travel height (Z 10): the first `G0 Z10`.
        let first = 60.0 * 10.0 / t.rapid_mm_min;
        let rest = (t.total_s + first - want).abs() / want;
        eprintln!(
            "{name}: report {:.4} s, rs274 {want:.4} s: {:.4} %, {:.2e} without the first G0 Z",
            t.total_s,
            100.0 * rel,
            rest
        );
        assert!(rel < 0.10, "{name}: {} s vs rs274 {want} s", t.total_s);
        assert!(rel < 0.005, "{name}: {} s vs rs274 {want} s (expected far closer)", t.total_s);
        assert!(rest < 1e-9, "{name}: {} + {first} s vs rs274 {want} s", t.total_s);
    }
}
