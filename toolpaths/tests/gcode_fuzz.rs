//! Property test (128 cases) of the G-code writer over its options (safe Z, clearance, decimals 1–6,
//! units, feeds, spindle snippets, envelopes, Z floors, dialects) on two small plans (a
//! rectangle with leads, ramps and overtravel; an annulus of arcs):
//! * every accepted program is read by LinuxCNC's rs274 (`../shared/tools/check-gcode
//!   --canon`), and in its canonical moves no rapid is below the travel height, the travel
//!   height clears every cutting point by the clearance, no point (arcs sampled every degree)
//!   leaves the envelope or goes below the floor, and every feed is > 0;
//! * every refused one names one of the fuzzed keys, and the refusal is justified by an
//!   independent check (the printed numbers, the snippet list, or rs274's moves of the same
//!   program without the envelope).

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use common::{
    annulus_mesh, canon_points, field_mesh, parse_canon_moves, rect_mesh, run_tool, scratch,
    shared_tool, CanonMove,
};
use grainline_toolpaths::*;
use proptest::prelude::*;

/// The two plans (rectangle, annulus), planned once.
fn plans() -> &'static [Plan; 2] {
    static PLANS: OnceLock<[Plan; 2]> = OnceLock::new();
    PLANS.get_or_init(|| {
        let plan = |mesh: FieldMesh, arcs: bool| {
            let dom = Domain::new(mesh).unwrap();
            let pl = place_strokes(&dom, &PlacementOptions::new(1.5, 0.0)).unwrap();
            let o = PlanOptions {
                arcs,
                contact_depth: 0.2,
                lead_in: 1.0,
                lead_out: 1.0,
                ramp_height: 0.5,
                overtravel: 0.5,
                ..Default::default()
            };
            plan_toolpath(&dom, &pl, &o).unwrap()
        };
        let rect = field_mesh(rect_mesh(12.0, 8.0, 24, 16), Symmetry::Line, |p| {
            let a = 0.3 + 0.05 * p[0];
            [a.cos(), a.sin()]
        });
        let annulus =
            field_mesh(annulus_mesh(3.0, 9.0, 8, 64), Symmetry::Vector, |p| [-p[1], p[0]]);
        let a = plan(annulus, true);
        assert!(a
            .passes
            .iter()
            .any(|p| p.moves.iter().any(|m| matches!(m.1, Segment::Arc { .. }))));
        [plan(rect, false), a]
    })
}

/// Spindle snippets: (on, off, allowed).
const SNIPPETS: [(&str, &str, bool); 10] = [
    ("M3 S8000", "M5", true),
    ("M4 S500\nG4 P0.5", "M9\nM5", true),
    ("M8\nM3 S1200 (brush on)", "G4 P0.2\nM5 ; off", true),
    ("m7", "m9", true),
    ("M3 S1000\nG0 X-500 Y-500 Z-50", "M5", false),
    ("M3", "M2", false),
    ("M30", "M5", false),
    ("(LOGOPEN,/tmp/victim)\nM3", "M5", false),
    ("M3 M4", "M5", false),
    ("G4", "M5", false),
];

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..hi.ln()).prop_map(f64::exp)
}

fn units() -> impl Strategy<Value = LengthUnit> {
    prop_oneof![Just(LengthUnit::Mm), Just(LengthUnit::In), Just(LengthUnit::Cm)]
}

fn spindle() -> impl Strategy<Value = (Spindle, Option<bool>)> {
    prop_oneof![
        Just((Spindle::None, None)),
        (1.0..30000.0f64).prop_map(|s| (Spindle::Speed(s.round()), None)),
        (0..SNIPPETS.len()).prop_map(|i| {
            let (on, off, ok) = SNIPPETS[i];
            (Spindle::Snippet { on: on.into(), off: off.into() }, Some(ok))
        }),
    ]
}

fn envelope() -> impl Strategy<Value = Option<Envelope>> {
    let lo = (-12.0..0.5f64, -12.0..0.5f64, -1.0..0.0f64);
    let hi = (9.0..16.0f64, 9.0..16.0f64, 0.0..10.0f64);
    prop_oneof![
        Just(None),
        (lo, hi).prop_map(|(a, b)| Some(Envelope { min: [a.0, a.1, a.2], max: [b.0, b.1, b.2] })),
    ]
}

#[derive(Debug, Clone)]
struct Case {
    plan: usize,
    options: GcodeOptions,
    snippet_ok: Option<bool>,
}

fn case() -> impl Strategy<Value = Case> {
    let dialect = prop_oneof![Just(Dialect::LinuxCnc), Just(Dialect::Grbl), Just(Dialect::Plain)];
    (
        (0..2usize, units(), 1..=6usize, -1.0..8.0f64, log_uniform(1e-4, 3.0)),
        (log_uniform(1e-2, 3000.0), log_uniform(1e-2, 3000.0), spindle(), dialect),
        (envelope(), prop::option::of(-1.0..0.5f64)),
    )
        .prop_map(|(a, b, c)| {
            let (plan, units, decimals, safe_z, clearance) = a;
            let (feed, plunge_feed, (spindle, snippet_ok), dialect) = b;
            let (envelope, z_floor) = c;
            Case {
                plan,
                options: GcodeOptions {
                    dialect,
                    feed,
                    plunge_feed,
                    safe_z,
                    clearance,
                    spindle,
                    envelope,
                    z_floor,
                    decimals,
                    units,
                    ..Default::default()
                },
                snippet_ok,
            }
        })
}

/// rs274's canon moves of a program, or None without ../shared.
fn canon(dir: &Path, name: &str, g: &str) -> Option<Vec<CanonMove>> {
    static TOOL: OnceLock<Option<PathBuf>> = OnceLock::new();
    let tool = TOOL.get_or_init(|| shared_tool("check-gcode")).as_ref()?;
    let path = dir.join(format!("{name}.ngc"));
    std::fs::write(&path, g).unwrap();
    let cdir = dir.join("canon");
    let (ok, text) = run_tool(tool, &[Path::new("--canon"), &cdir, &path]);
    assert!(ok, "rs274 rejected {}:\n{text}\n{g}", path.display());
    let c = std::fs::read_to_string(cdir.join(format!("{name}.ngc.canon"))).unwrap();
    let (moves, mm) = parse_canon_moves(&c);
    assert!(mm, "rs274 not in mm");
    Some(moves)
}

fn scratch_dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| scratch("gcode-fuzz"))
}

/// Printed number as the controller reads it.
fn printed(x: f64, d: usize) -> f64 {
    format!("{x:.d$}").parse().unwrap()
}

/// Whether a point lies outside the envelope/floor (mm) by more than `slack`.
fn outside(p: [f64; 3], o: &GcodeOptions, k: f64, slack: f64, cutting: bool) -> Option<String> {
    if let Some(e) = o.envelope {
        for a in 0..3 {
            if p[a] < e.min[a] * k - slack || p[a] > e.max[a] * k + slack {
                return Some(format!("{p:?} outside the envelope {e:?} (x{k})"));
            }
        }
    }
    match o.z_floor {
        Some(f) if cutting && p[2] < f * k - slack => Some(format!("{p:?} below the floor {f}")),
        _ => None,
    }
}

fn check_case(c: &Case, index: usize) -> std::result::Result<(), TestCaseError> {
    let plan = &plans()[c.plan];
    let o = &c.options;
    let k = o.units.in_mm();
    let dir = scratch_dir();
    let name = format!("case{index}");
    match write_gcode(plan, o) {
        Ok(g) => {
            prop_assert!(c.snippet_ok != Some(false), "a forbidden snippet was accepted");
            prop_assert!(!g.contains("NaN") && !g.contains("inf"));
            let Some(moves) = canon(dir, &name, &g) else { return Ok(()) };
            // The travel height as printed.
            let travel = g
                .lines()
                .find_map(|l| l.strip_prefix("G0 Z"))
                .and_then(|v| v.parse::<f64>().ok())
                .expect("a G0 Z line");
            prop_assert!((travel - printed(o.safe_z * k, o.decimals)).abs() < 1e-9);
            let pts = canon_points(&moves, [0.0; 3]);
            let top = pts.iter().filter(|p| !p.1).map(|p| p.0[2]).fold(f64::MIN, f64::max);
            prop_assert!(
                travel >= top + o.clearance * k - 1e-4,
                "travel {travel} does not clear the top {top} by {}",
                o.clearance * k
            );
            let mut prev = [0.0; 3];
            for m in &moves {
                match *m {
                    CanonMove::Traverse(p) => {
                        prop_assert!((p[2] - travel).abs() < 1e-4, "rapid at {p:?}");
                        let xy = (p[0] - prev[0]).abs() > 1e-9 || (p[1] - prev[1]).abs() > 1e-9;
                        prop_assert!(
                            !xy || (prev[2] - travel).abs() < 1e-4,
                            "XY rapid from {prev:?}"
                        );
                        prev = p;
                    }
                    CanonMove::Line(p, f) => {
                        prop_assert!(f > 0.0, "feed {f} at {p:?}");
                        prev = p;
                    }
                    CanonMove::Arc { end, feed, .. } => {
                        prop_assert!(feed > 0.0, "feed {feed} at {end:?}");
                        prev = end;
                    }
                }
            }
            for (p, rapid) in &pts {
                if let Some(why) = outside(*p, o, k, 1e-4, !rapid) {
                    return Err(TestCaseError::fail(why));
                }
            }
        }
        Err(e) => {
            let key = match &e {
                ToolpathError::InvalidOption { name, .. } => *name,
                ToolpathError::Gcode { key, .. } => *key,
                ToolpathError::OutsideEnvelope { .. } => "gcode.envelope",
                ToolpathError::BelowFloor { .. } => "gcode.z_floor",
                other => {
                    return Err(TestCaseError::fail(format!("refused without a key: {other}")))
                }
            };
            let msg = e.to_string();
            match key {
                "gcode.safe_z" => {
                    let top = plan
                        .passes
                        .iter()
                        .flat_map(|p| {
                            std::iter::once(p.start).chain(p.moves.iter().map(|m| m.1.end()))
                        })
                        .map(|q| printed(q[2] * k, o.decimals))
                        .fold(f64::MIN, f64::max);
                    let gap = printed(o.safe_z * k, o.decimals) - top;
                    prop_assert!(gap < o.clearance * k + 1e-9, "{msg}: gap {gap} is enough");
                    prop_assert!(msg.starts_with("gcode.safe_z: ") && msg.contains("highest"));
                }
                "gcode.feed" | "gcode.plunge_feed" => {
                    let f = if key == "gcode.feed" { o.feed } else { o.plunge_feed };
                    prop_assert!(printed(f * k, 1) <= 0.0, "{msg}");
                }
                "gcode.spindle.snippet.on" | "gcode.spindle.snippet.off" => {
                    prop_assert_eq!(c.snippet_ok, Some(false), "{}", msg);
                }
                "gcode.envelope" | "gcode.z_floor" => {
                    // The same program without the limits, read by rs274, goes outside them
                    // (or within rounding of them).
                    let free = GcodeOptions { envelope: None, z_floor: None, ..o.clone() };
                    match write_gcode(plan, &free) {
                        Ok(g) => {
                            if let Some(moves) = canon(dir, &format!("{name}-free"), &g) {
                                let pts = canon_points(&moves, [0.0; 3]);
                                prop_assert!(
                                    pts.iter().any(|(p, r)| outside(*p, o, k, -2e-4, !r).is_some()),
                                    "{msg}: rs274's moves stay inside"
                                );
                            }
                        }
                        // Checked in this order: the limits first, then the clearance.
                        Err(e) => prop_assert!(
                            matches!(e, ToolpathError::Gcode { key: "gcode.safe_z", .. }),
                            "{e}"
                        ),
                    }
                }
                _ => return Err(TestCaseError::fail(format!("unexpected key {key}: {msg}"))),
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 128,
        failure_persistence: None,
        max_shrink_iters: 64,
        ..ProptestConfig::default()
    })]

    #[test]
    fn gcode_options_fuzz_rs274_safe(c in case(), i in 0..1_000_000usize) {
        check_case(&c, i)?;
    }
}
