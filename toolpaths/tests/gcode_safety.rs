//! Regression tests of the G-code writer's safety rules, one per item of issue 15 (G-code):
//! checks on the program *as printed*, units, snippets, printed feeds, `G64 P`, and empty
//! programs. Programs that are accepted are also read back by LinuxCNC's rs274.

mod common;

use common::{
    canon_lengths, canon_points, field_mesh, parse_canon_moves, rect_mesh, run_tool, scratch,
    shared_tool, CanonMove,
};
use grainline_toolpaths::*;

/// A 10 × 5 sheet with strokes along +X (so every cut is at X ∈ [0, 10], Y ∈ [0, 5]).
fn sheet(scale: f64) -> FieldMesh {
    field_mesh(rect_mesh(10.0 * scale, 5.0 * scale, 10, 5), Symmetry::Line, |_| [1.0, 0.0])
}

fn job(plan: PlanOptions, gcode: GcodeOptions) -> JobOptions {
    JobOptions {
        placement: PlacementOptions::new(1.0, 0.0),
        plan,
        gcode: Some(gcode),
        ..Default::default()
    }
}

/// Cutting at Z = −depth on a flat sheet at Z = 0.
fn flat(depth: f64) -> PlanOptions {
    PlanOptions { contact_depth: depth, ..Default::default() }
}

fn run(plan: PlanOptions, gcode: GcodeOptions) -> Result<JobOutput> {
    generate(sheet(1.0), &job(plan, gcode))
}

/// The key an error names, and its text.
fn refused(r: Result<JobOutput>) -> (String, String) {
    match r {
        Ok(_) => panic!("expected the program to be refused"),
        Err(e) => {
            let key = match &e {
                ToolpathError::InvalidOption { name, .. } => name.to_string(),
                ToolpathError::Gcode { key, .. } => key.to_string(),
                ToolpathError::OutsideEnvelope { .. } => "gcode.envelope".into(),
                ToolpathError::BelowFloor { .. } => "gcode.z_floor".into(),
                ToolpathError::EmptyProgram { .. } => "gcode".into(),
                other => panic!("an error without a key: {other}"),
            };
            (key, e.to_string())
        }
    }
}

/// The words of a program with a given letter, as numbers.
fn words(g: &str, letter: char) -> Vec<f64> {
    g.lines()
        .filter(|l| !l.starts_with('('))
        .flat_map(|l| l.split_whitespace())
        .filter_map(|w| w.strip_prefix(letter))
        .filter_map(|v| v.parse().ok())
        .collect()
}

/// Runs rs274 on `programs` and returns each one's canon moves (None when ../shared is
/// absent: the test then skips that part with a message).
fn rs274(name: &str, programs: &[(&str, &str)]) -> Option<Vec<(Vec<CanonMove>, bool)>> {
    let tool = shared_tool("check-gcode")?;
    let dir = scratch(name);
    let canon = dir.join("canon");
    let mut paths = Vec::new();
    for (n, g) in programs {
        let p = dir.join(format!("{n}.ngc"));
        std::fs::write(&p, g).unwrap();
        paths.push(p);
    }
    let mut args: Vec<&std::path::Path> = vec![std::path::Path::new("--canon"), &canon];
    args.extend(paths.iter().map(|p| p.as_path()));
    let (ok, text) = run_tool(&tool, &args);
    assert!(ok, "check-gcode rejected a program:\n{text}");
    Some(
        paths
            .iter()
            .map(|p| {
                let c = canon.join(format!("{}.canon", p.file_name().unwrap().to_string_lossy()));
                parse_canon_moves(&std::fs::read_to_string(c).unwrap())
            })
            .collect(),
    )
}

/// Item 1: travel must clear the highest cutting point as printed by `clearance`.
#[test]
fn gcode_safe_z_equal_to_cut_height_is_refused() {
    // Cutting at Z = 0: safe Z 0 (the old check was ≥) is refused, naming the highest point.
    let (key, msg) = refused(run(flat(0.0), GcodeOptions { safe_z: 0.0, ..Default::default() }));
    assert_eq!(key, "gcode.safe_z");
    assert!(msg.contains("highest cutting point Z0.000") && msg.contains("clearance 1"), "{msg}");
    // 0.0004 with 3 decimals and 0.04 with 1 decimal both print as Z0.0: refused.
    for (safe_z, decimals) in [(0.0004, 3), (0.04, 1)] {
        let o = GcodeOptions { safe_z, decimals, clearance: 1e-6, ..Default::default() };
        let (key, msg) = refused(run(flat(0.0), o));
        assert_eq!(key, "gcode.safe_z", "{msg}");
        assert!(msg.contains("prints as Z0.0"), "{msg}");
    }
    // The default clearance is 1: safe Z 0.999 above a cut at 0 is refused, 1 accepted, and
    // with a cut at −0.5 (contact depth) safe Z 0.5 is exactly enough.
    assert_eq!(GcodeOptions::default().clearance, 1.0);
    let (key, msg) = refused(run(flat(0.0), GcodeOptions { safe_z: 0.999, ..Default::default() }));
    assert_eq!(key, "gcode.safe_z");
    assert!(msg.contains("at least 1 mm"), "{msg}");
    assert!(run(flat(0.0), GcodeOptions { safe_z: 1.0, ..Default::default() }).is_ok());
    assert!(run(flat(0.5), GcodeOptions { safe_z: 0.5, ..Default::default() }).is_ok());
    // As printed: 0.9996 prints as 1.000 with 3 decimals (clears by 1); with 4 decimals it
    // prints as 0.9996 and is refused.
    assert!(run(flat(0.0), GcodeOptions { safe_z: 0.9996, ..Default::default() }).is_ok());
    let o = GcodeOptions { safe_z: 0.9996, decimals: 4, ..Default::default() };
    assert_eq!(refused(run(flat(0.0), o)).0, "gcode.safe_z");
    // The clearance must be > 0.
    for c in [0.0, -1.0, f64::NAN] {
        let o = GcodeOptions { clearance: c, ..Default::default() };
        assert_eq!(refused(run(flat(0.0), o)).0, "gcode.clearance");
    }
    // The Z floor and the envelope are compared with the printed Z too: a cut at −0.0006
    // prints as −0.001 with 3 decimals, below a floor (or envelope) at −0.0008 …
    let (key, msg) =
        refused(run(flat(0.0006), GcodeOptions { z_floor: Some(-0.0008), ..Default::default() }));
    assert_eq!(key, "gcode.z_floor");
    assert!(msg.contains("Z = -0.001 mm (as printed)"), "{msg}");
    let env = Envelope { min: [-1.0, -1.0, -0.0008], max: [11.0, 6.0, 6.0] };
    let o = GcodeOptions { envelope: Some(env), ..Default::default() };
    assert!(matches!(run(flat(0.0006), o), Err(ToolpathError::OutsideEnvelope { axis: 'Z', .. })));
    // … while a cut at −0.0004 prints as 0.000, above a floor at −0.0003.
    assert!(
        run(flat(0.0004), GcodeOptions { z_floor: Some(-0.0003), ..Default::default() }).is_ok()
    );
    // The program rs274 reads never rapids below travel height + clearance over the part.
    let g =
        run(flat(0.5), GcodeOptions { safe_z: 0.5, ..Default::default() }).unwrap().gcode.unwrap();
    if let Some(c) = rs274("safe-z", &[("safe", &g)]) {
        let pts = canon_points(&c[0].0, [0.0; 3]);
        let top = pts.iter().filter(|p| !p.1).map(|p| p.0[2]).fold(f64::MIN, f64::max);
        assert!((top + 0.5).abs() < 1e-9, "highest cut {top}");
        for (p, rapid) in pts.iter().skip(1) {
            if *rapid {
                assert!(p[2] >= top + 1.0 - 1e-9, "rapid at {p:?}");
            }
        }
    }
}

/// Item 2: a plan in inches is printed in millimetres under G21, and every length option is
/// in inches; the machine moves are physically the same as the same part in mm.
#[test]
fn gcode_units_in_emits_consistent_program() {
    let mm = GcodeOptions {
        safe_z: 5.08,
        feed: 1016.0,
        plunge_feed: 254.0,
        z_floor: Some(-1.27),
        envelope: Some(Envelope { min: [-2.54, -2.54, -2.54], max: [254.0, 254.0, 25.4] }),
        ..Default::default()
    };
    let inch = GcodeOptions {
        safe_z: 0.2,
        clearance: 1.0 / 25.4,
        feed: 40.0,
        plunge_feed: 10.0,
        z_floor: Some(-0.05),
        envelope: Some(Envelope { min: [-0.1, -0.1, -0.1], max: [10.0, 10.0, 1.0] }),
        units: LengthUnit::In,
        ..Default::default()
    };
    let plan =
        |s: f64| PlanOptions { contact_depth: 0.5 * s, tolerance: 0.01 * s, ..Default::default() };
    let s = 1.0 / 25.4;
    let jm = job(plan(1.0), mm.clone());
    let mut ji = job(plan(s), inch.clone());
    ji.placement = PlacementOptions::new(s, 0.0);
    ji.placement.trace.max_step *= s;
    ji.placement.trace.min_step *= s;
    ji.placement.trace.tolerance *= s;
    let gm = generate(sheet(1.0), &jm).unwrap().gcode.unwrap();
    let gi = generate(sheet(s), &ji).unwrap().gcode.unwrap();
    // The header says what was done; G21 and never G20.
    assert!(gi.contains("units: mm, G21; lengths converted from in x25.4"), "{gi}");
    assert!(gi.contains("G21 G90 G17 G94") && !gi.contains("G20"));
    // Feeds in in/min are printed in mm/min, safe Z 0.2 in as 5.080 mm.
    assert_eq!(words(&gi, 'F'), words(&gm, 'F'));
    assert!(words(&gi, 'F').contains(&1016.0) && words(&gi, 'F').contains(&254.0));
    assert!(gi.contains("G0 Z5.080\n"));
    // The sheet is 10 mm = 0.3937 in wide and the strokes along X run out one width (1 mm,
    // 1/25.4 in) past its edges: X reaches 11 mm in both programs.
    for g in [&gi, &gm] {
        let xmax = words(g, 'X').into_iter().fold(f64::MIN, f64::max);
        assert!((xmax - 11.0).abs() < 1e-9, "{xmax}");
    }
    // The envelope is in inches: X ≤ 0.43 in is left by 0.0031 in, and the message says so.
    let mut tight = ji.clone();
    tight.gcode.as_mut().unwrap().envelope =
        Some(Envelope { min: [-0.1, -0.1, -0.1], max: [0.43, 10.0, 1.0] });
    match generate(sheet(s), &tight) {
        Err(e @ ToolpathError::OutsideEnvelope { axis: 'X', .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("X = 0.433071 in (as printed)") && msg.contains("by 0.003071 in"),
                "{msg}"
            );
        }
        other => panic!("expected an envelope error, got {:?}", other.map(|o| o.report)),
    }
    // The floor is in inches: −0.01 in is above the cut at −0.5 mm = −0.0197 in.
    let mut floor = ji.clone();
    floor.gcode.as_mut().unwrap().z_floor = Some(-0.01);
    assert!(matches!(generate(sheet(s), &floor), Err(ToolpathError::BelowFloor { .. })));
    // rs274: the same machine moves, length for length.
    if let Some(c) = rs274("units", &[("mm", &gm), ("in", &gi)]) {
        assert!(c[0].1 && c[1].1, "rs274 did not run in mm");
        let (fm, rm) = canon_lengths(&c[0].0, [0.0; 3]);
        let (fi, ri) = canon_lengths(&c[1].0, [0.0; 3]);
        assert!(fm > 60.0, "cut length {fm}");
        assert!((fm - fi).abs() < 1e-3 * fm, "cut {fm} mm vs {fi} mm");
        assert!((rm - ri).abs() < 1e-3 * rm, "rapid {rm} mm vs {ri} mm");
        let bbox = |m: &[CanonMove]| {
            let pts = canon_points(m, [0.0; 3]);
            let xs: Vec<f64> = pts.iter().map(|p| p.0[0]).collect();
            (
                xs.iter().cloned().fold(f64::MAX, f64::min),
                xs.iter().cloned().fold(f64::MIN, f64::max),
            )
        };
        let (a, b) = (bbox(&c[0].0), bbox(&c[1].0));
        assert!((a.0 - b.0).abs() < 2e-3 && (a.1 - 11.0).abs() < 2e-3 && (b.1 - 11.0).abs() < 2e-3);
    }
}

/// Item 3: snippets hold only spindle, coolant and dwell words.
#[test]
fn gcode_snippet_with_motion_or_program_end_is_refused() {
    let snip = |on: &str, off: &str| GcodeOptions {
        spindle: Spindle::Snippet { on: on.into(), off: off.into() },
        ..Default::default()
    };
    let (key, msg) = refused(run(flat(0.0), snip("M3 S1000\nG0 X-500 Y-500 Z-50", "M5")));
    assert_eq!(key, "gcode.spindle.snippet.on");
    assert!(msg.contains("line 2 `G0 X-500 Y-500 Z-50`") && msg.contains("`G0`"), "{msg}");
    let (key, msg) = refused(run(flat(0.0), snip("M3", "M2")));
    assert_eq!(key, "gcode.spindle.snippet.off");
    assert!(msg.contains("line 1 `M2`") && msg.contains("`M2`"), "{msg}");
    for bad in [
        "M30",
        "M3 S1000 G1 X5",
        "G4",
        "P2",
        "M3 M5",
        "S100 S200",
        "N10 M3",
        "#1=5",
        "M3 (unclosed",
        "(LOGOPEN,/tmp/victim)",
        "(msg, hello)",
        "M64 P0",
        "S-5",
        "G4 P-1",
        "M3 S1e3",
        "G92 X0",
        "%",
        "M3 X",
    ] {
        let (key, msg) = refused(run(flat(0.0), snip(bad, "M5")));
        assert_eq!(key, "gcode.spindle.snippet.on", "{bad}: {msg}");
        assert!(msg.contains("line 1"), "{bad}: {msg}");
    }
    // Allowed: spindle, coolant, S, dwell, comments, blank lines, any case.
    let good = snip("M3 S12000\n\nG4 P1.5 (spin up)\nm8 ; coolant", "M9\nM5 (stop)");
    let g = run(flat(0.0), good).unwrap().gcode.unwrap();
    assert!(g.contains("M3 S12000\nG4 P1.5 (spin up)\nm8 ; coolant\n"), "{g}");
    assert!(g.contains("M9\nM5 (stop)\nM2\n"));
    if let Some(c) = rs274("snippet", &[("good", &g)]) {
        assert!(!c[0].0.is_empty());
    }
}

/// Item 4: every printed feed is > 0.
#[test]
fn gcode_feed_that_prints_as_zero_is_refused() {
    let (key, msg) = refused(run(flat(0.0), GcodeOptions { feed: 0.04, ..Default::default() }));
    assert_eq!(key, "gcode.feed");
    assert!(msg.contains("prints as F0.0") && msg.contains("smallest printable feed is F0.1"));
    let o = GcodeOptions { plunge_feed: 0.01, ..Default::default() };
    assert_eq!(refused(run(flat(0.0), o)).0, "gcode.plunge_feed");
    // Spindle speeds are printed in whole rpm: 0.4 would print S0.
    let o = GcodeOptions { spindle: Spindle::Speed(0.4), ..Default::default() };
    assert_eq!(refused(run(flat(0.0), o)).0, "gcode.spindle.speed");
    // 0.06 mm/min prints as F0.1; 0.04 in/min is 1.016 mm/min and prints as F1.0.
    let g =
        run(flat(0.0), GcodeOptions { feed: 0.06, ..Default::default() }).unwrap().gcode.unwrap();
    assert!(g.contains(" F0.1\n"));
    let mut j =
        job(flat(0.0), GcodeOptions { feed: 0.04, units: LengthUnit::In, ..Default::default() });
    j.gcode.as_mut().unwrap().plunge_feed = 10.0;
    j.gcode.as_mut().unwrap().safe_z = 2.0;
    let g = generate(sheet(1.0), &j).unwrap().gcode.unwrap();
    assert!(g.contains(" F1.0\n") && words(&g, 'F').iter().all(|&f| f > 0.0));
}

/// Item 5: `G64 P` follows `plan.tolerance`, with enough decimals, never P0.
#[test]
fn gcode_g64_follows_plan_tolerance() {
    let p = |tolerance: f64, decimals: usize, units: LengthUnit| {
        let mut j = job(
            PlanOptions { tolerance, ..Default::default() },
            GcodeOptions { decimals, units, safe_z: 2.0, ..Default::default() },
        );
        j.gcode.as_mut().unwrap().clearance = 0.01;
        generate(sheet(1.0), &j).map(|o| o.gcode.unwrap())
    };
    // The default tolerance 0.01 with 1 decimal: P0.01 (not 1 mm, not P0.0).
    assert!(p(0.01, 1, LengthUnit::Mm).unwrap().contains("\nG64 P0.01\n"));
    assert!(p(0.01, 3, LengthUnit::Mm).unwrap().contains("\nG64 P0.010\n"));
    assert!(p(0.25, 3, LengthUnit::Mm).unwrap().contains("\nG64 P0.250\n"));
    assert!(p(0.0123, 1, LengthUnit::Mm).unwrap().contains("\nG64 P0.012\n"));
    // In inches: 0.001 in = 0.0254 mm, within 5 % at 3 decimals.
    assert!(p(0.001, 3, LengthUnit::In).unwrap().contains("\nG64 P0.025\n"));
    // Too small to print even with 6 decimals: refused, naming plan.tolerance.
    let e = p(1e-8, 3, LengthUnit::Mm).unwrap_err();
    assert!(matches!(e, ToolpathError::Gcode { key: "plan.tolerance", .. }), "{e}");
    // grbl and plain have no G64.
    let mut j = job(flat(0.0), GcodeOptions { dialect: Dialect::Grbl, ..Default::default() });
    j.plan.tolerance = 1e-8;
    assert!(!generate(sheet(1.0), &j).unwrap().gcode.unwrap().contains("G64"));
}

/// A 10 × 5 plane tilted 45° about the Y axis (every stroke tilts 45°).
fn tilted() -> FieldMesh {
    let (uv, tris) = rect_mesh(10.0, 5.0, 10, 5);
    let pos: Vec<Vec3> = uv.iter().map(|p| [p[0], p[1], p[0]]).collect();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let nrm = vec![[-h, 0.0, h]; pos.len()];
    let d = uv.iter().map(|_| [1.0, 0.0]).collect();
    FieldMesh::new(uv, tris, Directions::Vectors(d), Symmetry::Line).with_lift(pos, Some(nrm))
}

/// Item 6: every stroke skipped for tilt gives an empty program: refused by default, written
/// with `allow_empty` and then said in the report.
#[test]
fn gcode_empty_program_is_refused() {
    let plan = PlanOptions {
        z_mode: ZMode::SurfaceFollowing { max_tilt_deg: 30.0, on_tilt: TiltPolicy::Skip },
        ..Default::default()
    };
    let o = GcodeOptions { safe_z: 20.0, ..Default::default() };
    let (key, msg) = refused(generate(tilted(), &job(plan.clone(), o.clone())));
    assert_eq!(key, "gcode");
    assert!(
        msg.contains("no passes")
            && msg.contains("skipped for tilt")
            && msg.contains("allow_empty")
    );
    // At 50° the strokes are kept: a program with passes.
    let mut ok = job(plan.clone(), o.clone());
    ok.plan.z_mode = ZMode::SurfaceFollowing { max_tilt_deg: 50.0, on_tilt: TiltPolicy::Skip };
    let out = generate(tilted(), &ok).unwrap();
    assert!(out.plan.passes.len() > 1 && out.report.warnings.is_empty());
    // Opted out: written, without a single cutting move, and the report says so.
    let out = generate(tilted(), &job(plan, GcodeOptions { allow_empty: true, ..o })).unwrap();
    let g = out.gcode.unwrap();
    assert!(out.plan.passes.is_empty() && !g.lines().any(|l| l.starts_with("G1 ")), "{g}");
    assert_eq!(out.report.warnings.len(), 1);
    assert!(out.report.warnings[0].contains("no passes"), "{:?}", out.report.warnings);
    let json = serde_json::to_value(&out.report).unwrap();
    assert!(json["warnings"][0].as_str().unwrap().contains("allow_empty"));
}
