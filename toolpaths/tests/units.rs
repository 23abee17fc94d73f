//! Units (issue 31, item 4): the same job in millimetres and in inches — positions and every
//! length option divided by 25.4, the rest left to the defaults resolved in the unit
//! (`JobOptions::default_lengths_in`) — gives the same program, printed in mm.

mod common;

use grainline_toolpaths::*;

/// A 160 × 120 mm dome (radii 400 and 600 mm) on a 48 × 36 grid, UV in [0, 1]², positions
/// divided by `k`; a constant UV grain at 17°.
fn dome(k: f64) -> FieldMesh {
    let (uv, tris) = common::rect_mesh(1.0, 1.0, 48, 36);
    let pos = uv
        .iter()
        .map(|p| {
            let (x, y) = (160.0 * p[0] - 80.0, 120.0 * p[1] - 60.0);
            [x / k, y / k, -(x * x / 800.0 + y * y / 1200.0) / k]
        })
        .collect();
    let a = 17f64.to_radians();
    let mut fm = common::field_mesh((uv, tris), Symmetry::Line, |_| [a.cos(), a.sin()]);
    fm.positions = Some(pos);
    fm
}

fn job(unit: LengthUnit) -> JobOptions {
    let k = unit.in_mm();
    let mut o = JobOptions {
        placement: PlacementOptions { width: 6.0 / k, ..Default::default() },
        plan: PlanOptions {
            z_mode: ZMode::SurfaceFollowing { max_tilt_deg: 30.0, on_tilt: TiltPolicy::Error },
            ..Default::default()
        },
        gcode: Some(GcodeOptions { safe_z: 12.7 / k, units: unit, ..Default::default() }),
        ..Default::default()
    };
    o.default_lengths_in(unit, &|key| key == "placement.width" || key == "gcode.safe_z");
    o
}

#[test]
fn length_defaults_are_millimetres_in_any_unit() {
    let o = job(LengthUnit::In);
    let g = o.gcode.as_ref().unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b;
    assert!(close(g.clearance * 25.4, 1.0) && close(g.feed * 25.4, 1000.0));
    assert!(close(g.plunge_feed * 25.4, 300.0) && close(o.plan.tolerance * 25.4, 0.01));
    assert!(close(o.placement.trace.max_step * 25.4, 1.0));
    // Given values keep theirs.
    assert_eq!((g.safe_z, o.placement.width), (0.5, 6.0 / 25.4));
    // The table is the structs' defaults, in mm.
    let mut mm = JobOptions {
        gcode: Some(Default::default()),
        svg: Some(Default::default()),
        ..Default::default()
    };
    let before = mm.clone();
    mm.default_lengths_in(LengthUnit::Mm, &|_| false);
    assert_eq!(mm, before);
}

/// Same words on every line, every number within one unit of its last printed digit;
/// comment lines are skipped (the inch program's header says `converted from in x25.4`).
fn same_program(a: &str, b: &str) -> usize {
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    assert_eq!(la.len(), lb.len());
    let mut numbers = 0;
    for (x, y) in la.iter().zip(&lb).filter(|(x, _)| !x.starts_with('(')) {
        let (wx, wy): (Vec<&str>, Vec<&str>) =
            (x.split_whitespace().collect(), y.split_whitespace().collect());
        assert_eq!(wx.len(), wy.len(), "`{x}` vs `{y}`");
        for (p, q) in wx.iter().zip(&wy) {
            assert_eq!(p[..1], q[..1], "`{x}` vs `{y}`");
            let (u, v): (f64, f64) = (p[1..].parse().unwrap(), q[1..].parse().unwrap());
            let digits = p.split('.').nth(1).map_or(0, str::len) as i32;
            assert!((u - v).abs() <= 1.01 * 10f64.powi(-digits), "`{x}` vs `{y}`");
            numbers += 1;
        }
    }
    numbers
}

/// A placement's lengths (stroke lengths and run-outs, width, spacing) divided by `k`: the
/// same strokes in a unit `k` mm long.
fn in_unit(pl: &Placement, k: f64) -> Placement {
    let mut pl = pl.clone();
    for s in &mut pl.strokes {
        s.length /= k;
        s.overtravel = s.overtravel.map(|x| x / k);
    }
    (pl.width, pl.d_sep, pl.d_test, pl.min_length) =
        (pl.width / k, pl.d_sep / k, pl.d_test / k, pl.min_length / k);
    pl.exclusion_radius /= k;
    pl
}

/// The strokes placed in millimetres (the dome's UV is the same in both units), planned and
/// written in millimetres and in inches: one program. Leads, ramps, overtravel and a contact
/// depth are given (in each unit); the plan tolerance, clearance and feeds are defaults.
#[test]
fn inch_and_millimetre_plans_of_one_placement_give_one_program() {
    let mm = generate(dome(1.0), &job(LengthUnit::Mm)).unwrap();
    let mut programs = Vec::new();
    for unit in [LengthUnit::Mm, LengthUnit::In] {
        let k = unit.in_mm();
        let o = job(unit);
        let plan_o = PlanOptions {
            lead_in: 3.0 / k,
            lead_out: 2.0 / k,
            ramp_height: 0.5 / k,
            overtravel: 1.5 / k,
            contact_depth: 0.1 / k,
            ..o.plan.clone()
        };
        let dom = Domain::new(dome(k)).unwrap();
        let plan = plan_toolpath(&dom, &in_unit(&mm.placement, k), &plan_o).unwrap();
        programs.push(write_gcode(&plan, o.gcode.as_ref().unwrap()).unwrap());
    }
    let n = same_program(&programs[0], &programs[1]);
    eprintln!("{} passes, {n} numbers within one printed digit", mm.plan.passes.len());
    assert!(n > 1000);
    for g in &programs {
        assert!(
            g.contains("\nG0 Z12.700\n")
                && g.contains(" F1000.0\n")
                && g.contains("\nG64 P0.010\n")
        );
    }
}

/// The whole job — placement, plan and program — on the dome in millimetres and on the dome
/// scaled by 1/25.4 in inches: the same strokes (point for point within 1e-9 mm), the same
/// passes and run-outs past the dome's edges (move for move within 1e-9 mm after × 25.4) and
/// one program, printed in mm, to the last digit.
#[test]
fn inch_and_millimetre_runs_of_one_part_give_one_program() {
    let mm = generate(dome(1.0), &job(LengthUnit::Mm)).unwrap();
    let inch = generate(dome(25.4), &job(LengthUnit::In)).unwrap();
    let (a, b) = (&mm.placement.strokes, &inch.placement.strokes);
    assert_eq!(a.len(), b.len(), "strokes");
    for (s, t) in a.iter().zip(b) {
        assert_eq!(s.uv.len(), t.uv.len());
        assert!((s.length - 25.4 * t.length).abs() < 1e-9, "{} vs {}", s.length, t.length);
        assert_eq!((s.start, s.end, s.fill), (t.start, t.end, t.fill));
    }
    let (p, q) = (&mm.plan.passes, &inch.plan.passes);
    assert_eq!(p.len(), q.len(), "passes");
    let mut run_outs = 0;
    for (x, y) in p.iter().zip(q) {
        assert_eq!((x.stroke, x.reversed, x.moves.len()), (y.stroke, y.reversed, y.moves.len()));
        for ((k, m), (l, n)) in x.moves.iter().zip(&y.moves) {
            assert_eq!(k, l);
            let (u, v) = (m.end(), n.end());
            assert!((0..3).all(|i| (u[i] - 25.4 * v[i]).abs() < 1e-9), "{u:?} vs {v:?} × 25.4");
            run_outs += usize::from(*k == MoveKind::Overtravel);
        }
    }
    let n = same_program(mm.gcode.as_ref().unwrap(), inch.gcode.as_ref().unwrap());
    eprintln!(
        "{} strokes, {} passes, {run_outs} run-outs, {n} numbers printed alike",
        a.len(),
        p.len()
    );
    assert!(run_outs > 10 && n > 1000);
}
