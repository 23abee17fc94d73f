//! Issue 13's acceptance test ("Edits that land") on a small, fast subset of the corpus
//! (tests/corpus/mod.rs): the coarse generated body of revolution, curved panel and flat sheet
//! (5k–10k vertices), each with a bend, an expand and a curve placed on its key highlight by
//! code. The full corpus is `examples/bench_fidelity.rs`.
//!
//! The goals: within ≥ 0.9, p95 ≤ 0.10 r, no new singular triangle, converged in at
//! most 15 iterations, energy never rising, with the default position energy; and sanity checks
//! (everything runs, no NaN, figures in range).

mod corpus;

use corpus::{Outcome, Size};

/// The subset, solved with the default energy ("position").
fn outcomes() -> Vec<Outcome> {
    let energy = "position";
    assert!(corpus::solver_settings(energy).expect("settings").is_some());
    let names: Vec<String> = ["body", "panel", "sheet"].iter().map(|s| s.to_string()).collect();
    let cases = corpus::generated_cases(Size::Small, Some(&names)).expect("generated parts");
    assert_eq!(cases.len(), 3);
    let mut out = Vec::new();
    for case in &cases {
        let p = corpus::prepare_case(case).expect("field");
        let pl = p.placement.as_ref().unwrap_or_else(|e| panic!("{}: placement: {e}", case.name));
        assert!(pl.curve.len() > 10, "{}: curve of {} points", case.name, pl.curve.len());
        for tool in corpus::TOOLS {
            let o = corpus::run_edit(case, &p, tool, energy).expect("run").expect("energy");
            out.push(o);
        }
    }
    out
}

/// Placement from outside the code: on the flat sheet with the UV field u = x̂, a light with no
/// x component and a point eye at x = 21, hᵀu = 0 exactly where the eye direction has no x
/// component, i.e. on the line x = 21 (up to the linear interpolation of g between grid lines
/// 2 mm apart: the half vector's length changes by a few 1e-3 over a cell). The brush centre must lie on it, the highlight's tangent
/// along ŷ and the push direction along x̂.
#[test]
fn the_sheet_highlight_is_the_line_below_the_eye() {
    let names = vec!["sheet".to_string()];
    let cases = corpus::generated_cases(Size::Small, Some(&names)).expect("sheet");
    let p = corpus::prepare_case(&cases[0]).expect("field");
    let pl = p.placement.expect("placement");
    assert!((pl.point.x - 21.0).abs() < 0.02, "centre {:?}", pl.point);
    assert!(pl.point.z.abs() < 1e-9 && pl.point.y.abs() <= 75.0, "centre {:?}", pl.point);
    assert!(pl.along.y.abs() > 1.0 - 1e-4, "along {:?}", pl.along);
    assert!(pl.across.x.abs() > 1.0 - 1e-4, "across {:?}", pl.across);
    // 200 × 150 mm: diagonal 250 mm. The highlight crosses the sheet (150 mm); the stretch is
    // the part at least one warp radius (15 mm) from the boundary, measured at segment
    // midpoints: 150 − 2·15 mm, less a cell at each end.
    assert!((pl.diag - 250.0).abs() < 1e-9, "diag {}", pl.diag);
    assert!(pl.stretch >= 150.0 - 2.0 * (15.0 + 2.0), "stretch {}", pl.stretch);
    // The S-curve: 62.5 mm long on the sheet (it stays on the plane, far from the boundary).
    let len: f64 = pl.curve.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    assert!(len > 0.24 * 250.0 && len < 0.26 * 250.0 * 1.1, "curve length {len}");
    assert!(pl.curve.iter().all(|q| q.z.abs() < 1e-9), "curve leaves the sheet");
}

/// Sanity: every edit of the subset runs, and every figure is finite and in range.
#[test]
fn the_subset_runs_and_its_figures_are_in_range() {
    for o in outcomes() {
        let what = format!("{} {} ({})", o.case, o.edit, o.energy);
        assert!(o.error.is_none(), "{what}: {:?}", o.error);
        let f = o.figures.as_ref().expect("figures");
        assert!(f.samples > 0, "{what}: nothing measured: {:?}", f.note);
        assert!((0.0..=1.0).contains(&f.within), "{what}: within {}", f.within);
        assert!(f.p95.is_finite() && f.p95 >= 0.0, "{what}: p95 {}", f.p95);
        assert!(f.median.is_finite() && f.median >= 0.0 && f.median <= f.p95, "{what}");
        assert!(o.iterations <= o.max_iterations, "{what}");
        assert!(o.energies.iter().all(|e| e.is_finite() && *e >= 0.0), "{what}: {:?}", o.energies);
        assert!(o.seconds.is_finite(), "{what}");
    }
}

/// Issue 13's goals on every edit of the subset.
#[test]
fn the_edits_land() {
    let mut missed = Vec::new();
    for o in outcomes() {
        let Some(f) = o.figures.clone() else {
            missed.push(format!("{} {}: {:?}", o.case, o.edit, o.error));
            continue;
        };
        let what = format!(
            "{} {} ({}): within {:.1} %, p95 {:.3} r, singular {} → {}, {} iterations ({}){}",
            o.case,
            o.edit,
            o.energy,
            100.0 * f.within,
            f.p95,
            f.singular_before,
            f.singular_after,
            o.iterations,
            o.stop,
            if o.energy_monotone() { "" } else { ", energy rose" }
        );
        // The coarse body's curve (edges ≈ its radius) was a known open case (88 % within,
        // p95 0.23 r) until the curve tool refined its tube to r/8 (session 12): it meets the
        // goal now, like every other edit of the subset.
        let (goal_within, goal_p95) = (0.9, 0.10);
        let ok = o.error.is_none()
            && f.samples > 0
            && f.within >= goal_within
            && f.p95 <= goal_p95
            && f.singular_after <= f.singular_before
            && o.iterations <= 15
            && o.stop != "IterationCap"
            && o.energy_monotone();
        if !ok {
            missed.push(what);
        }
    }
    assert!(missed.is_empty(), "edits that missed:\n{}", missed.join("\n"));
}

/// The generated parts are the sizes the corpus promises, against their formulas: the panel's
/// corner height (100² / 600 + 75² / 400) / 2 = 15.365 mm, the 0.15 mm ripple (the 2 mm grid
/// has x = 2 mm, where sin(2π·2/8) = 1), the body's end radii 38 + 40 sin(0.1π) and
/// 38 + 20 sin(0.85π), and the vertex counts of both sizes.
#[test]
fn the_generated_parts_match_their_formulas() {
    use grainline::generate::{curved_panel, kettle_body, Ripple};
    let panel = curved_panel(200.0, 150.0, 600.0, 400.0, 100, 75, None);
    let corner = panel.positions.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
    assert!((corner - 0.5 * (100.0f64.powi(2) / 600.0 + 75.0f64.powi(2) / 400.0)).abs() < 1e-9);
    let rippled = curved_panel(200.0, 150.0, 600.0, 400.0, 100, 75, Some(Ripple::CORPUS));
    let dev = panel
        .positions
        .iter()
        .zip(&rippled.positions)
        .map(|(a, b)| (b.z - a.z).abs())
        .fold(0.0, f64::max);
    assert!((dev - 0.15).abs() < 1e-9, "ripple amplitude {dev}");
    let sheet = curved_panel(200.0, 150.0, f64::INFINITY, f64::INFINITY, 100, 75, None);
    assert!(sheet.positions.iter().all(|p| p.z == 0.0 && p.x.abs() <= 100.0 && p.y.abs() <= 75.0));
    let body = kettle_body(80, 80, None);
    let radius_at = |z: f64| {
        let r: Vec<f64> = body
            .positions
            .iter()
            .filter(|p| (p.z - z).abs() < 1e-9)
            .map(|p| p.x.hypot(p.y))
            .collect();
        assert_eq!(r.len(), 80, "one ring at z = {z}");
        r.iter().sum::<f64>() / r.len() as f64
    };
    let pi = std::f64::consts::PI;
    assert!((radius_at(0.0) - (38.0 + 40.0 * (0.1 * pi).sin())).abs() < 1e-9);
    assert!((radius_at(180.0) - (38.0 + 20.0 * (0.85 * pi).sin())).abs() < 1e-9);
    assert_eq!(body.num_vertices(), 80 * 81);
    assert_eq!(kettle_body(200, 200, None).num_vertices(), 40_200);
    assert_eq!(curved_panel(200.0, 150.0, 600.0, 400.0, 240, 180, None).num_vertices(), 43_621);
    assert_eq!(panel.num_vertices(), 101 * 76);
}

/// The corpus edits on the shared meshes that missed until session 12 of issue 13 land: the
/// curves whose old target (a blend of ĝ) left singular pairs in the ring (rocker-arm, teapot;
/// spot's too, the hardest design), and blub's bend, which put two on the far side of its fin
/// before the warp pulled back the grain's angle rather than ĝ. Needs ../shared (CI has it):
/// without it the test says so and checks nothing.
#[test]
fn the_shared_meshes_hard_edits_land() {
    let names: Vec<String> =
        ["spot", "blub", "rocker-arm", "teapot"].iter().map(|s| s.to_string()).collect();
    let cases = corpus::shared_cases(Some(&names)).expect("shared cases");
    if cases.is_empty() {
        eprintln!("skipping the shared meshes' hard edits: ../shared/meshes not found");
        return;
    }
    assert_eq!(cases.len(), 4, "a shared mesh did not load");
    let mut missed = Vec::new();
    for case in &cases {
        let p = corpus::prepare_case(case).expect("field");
        let tools: &[&str] = if case.name == "blub" { &["bend", "curve"] } else { &["curve"] };
        for &tool in tools {
            let o = corpus::run_edit(case, &p, tool, "position").expect("run").expect("energy");
            let f = o.figures.as_ref().unwrap_or_else(|| panic!("{}: {:?}", case.name, o.error));
            let ok = f.landed && o.iterations <= 15 && o.energy_monotone();
            if !ok {
                missed.push(format!(
                    "{} {tool}: within {:.1} %, p95 {:.3} r, singular {} → {}, {} iterations",
                    case.name,
                    100.0 * f.within,
                    f.p95,
                    f.singular_before,
                    f.singular_after,
                    o.iterations
                ));
            }
        }
    }
    assert!(missed.is_empty(), "edits that missed:\n{}", missed.join("\n"));
}

/// Writes an OBJ (positions, optional per-vertex UVs, triangles) to the test's scratch folder.
fn write_obj(
    name: &str,
    pos: &[[f64; 3]],
    uv: Option<&[[f64; 2]]>,
    faces: &[[usize; 3]],
) -> std::path::PathBuf {
    use std::fmt::Write as _;
    let dir = std::env::temp_dir().join(format!("grainline-edit-fidelity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut s = String::new();
    for p in pos {
        writeln!(s, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for t in uv.unwrap_or(&[]) {
        writeln!(s, "vt {} {}", t[0], t[1]).unwrap();
    }
    for f in faces {
        let [a, b, c] = f.map(|v| v + 1);
        if uv.is_some() {
            writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}").unwrap();
        } else {
            writeln!(s, "f {a} {b} {c}").unwrap();
        }
    }
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, s).unwrap();
    path
}

/// Two kinds of part session 13 found missing or marred, generated here and run through the
/// bench's placement (the key highlight, a bend, an expand and a curve): a doubly curved panel
/// whose UVs fold at x = 0 (u = |x|; its key highlight lies on the fold, where the UV grain
/// used to come out at 90°: a bend 43 % within, 0 → 4 singular triangles), and a CAD puck whose
/// flat top is a fan of slivers from its centre next to a 5 mm fillet (the curve's refinement
/// used to lift the fan; `tests/refine_geometry.rs` checks the plane). Every edit must land.
#[test]
fn a_mirrored_fold_and_a_cad_sliver_fan_take_every_edit() {
    // The mirrored panel: 160 × 100, z = x²/400 + y²/600, 80 × 50 cells.
    let (nx, ny) = (80usize, 50usize);
    let (mut pos, mut uv, mut faces) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) =
                (-80.0 + 160.0 * i as f64 / nx as f64, -50.0 + 100.0 * j as f64 / ny as f64);
            pos.push([x, y, x * x / 400.0 + y * y / 600.0]);
            uv.push([x.abs() / 80.0, (y + 50.0) / 100.0]);
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            let a = j * (nx + 1) + i;
            faces.push([a, a + 1, a + nx + 2]);
            faces.push([a, a + nx + 2, a + nx + 1]);
        }
    }
    let panel = write_obj("mirror_panel", &pos, Some(&uv), &faces);
    // The puck: R 40, height 20, fillet 5 (8 rings), 96 segments; the top a fan.
    let (r, h, fr, n) = (40.0f64, 20.0f64, 5.0f64, 96usize);
    let mut prof = vec![(r, 0.0), (r, h - fr)];
    for k in 1..=8 {
        let a = std::f64::consts::FRAC_PI_2 * k as f64 / 8.0;
        prof.push((r - fr + fr * a.cos(), h - fr + fr * a.sin()));
    }
    let (mut pos, mut faces) = (Vec::new(), Vec::new());
    for &(rr, z) in &prof {
        for i in 0..n {
            let ph = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            pos.push([rr * ph.cos(), rr * ph.sin(), z]);
        }
    }
    for k in 0..prof.len() - 1 {
        for i in 0..n {
            let (p0, p1, q0, q1) =
                (k * n + i, k * n + (i + 1) % n, (k + 1) * n + i, (k + 1) * n + (i + 1) % n);
            faces.push([p0, p1, q1]);
            faces.push([p0, q1, q0]);
        }
    }
    let (top, bottom) = (pos.len(), pos.len() + 1);
    pos.push([0.0, 0.0, h]);
    pos.push([0.0, 0.0, 0.0]);
    let last = (prof.len() - 1) * n;
    for i in 0..n {
        faces.push([last + i, last + (i + 1) % n, top]);
        faces.push([(i + 1) % n, i, bottom]);
    }
    let puck = write_obj("cad_puck", &pos, None, &faces);

    let mut missed = Vec::new();
    for (name, path, uv) in [("mirror_panel", &panel, true), ("cad_puck", &puck, false)] {
        let case = corpus::mesh_case(name, path, uv, None, false).expect("case");
        let p = corpus::prepare_case(&case).expect("field");
        for tool in corpus::TOOLS {
            let o = corpus::run_edit(&case, &p, tool, "position").expect("run").expect("energy");
            let f = o.figures.as_ref().unwrap_or_else(|| panic!("{name} {tool}: {:?}", o.error));
            eprintln!(
                "{name} {tool}: within {:.1} %, p95 {:.3} r, singular {} → {}",
                100.0 * f.within,
                f.p95,
                f.singular_before,
                f.singular_after
            );
            if !(f.landed && o.iterations <= 15 && o.energy_monotone()) {
                missed.push(format!(
                    "{name} {tool}: {:.1} %, {} → {}",
                    100.0 * f.within,
                    f.singular_before,
                    f.singular_after
                ));
            }
        }
    }
    assert!(missed.is_empty(), "edits that missed:\n{}", missed.join("\n"));
}
