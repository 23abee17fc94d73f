//! `grainline panel` and its library (src/panel.rs): outlines from SVG, meshed flat.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::Command;

use grainline::panel::{panel_from_svg, read_svg_loops, PanelOptions};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn triangle_stats(mesh: &grainline::mesh::Mesh) -> (f64, f64, f64) {
    let (mut min_angle, mut max_edge, mut area) = (f64::INFINITY, 0.0f64, 0.0);
    for f in 0..mesh.num_faces() {
        let p = mesh.face_positions(f);
        let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
        assert!(n.z > 0.0, "face {f} is not counter-clockwise seen from +Z");
        area += 0.5 * n.z;
        for k in 0..3 {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            let ang = (b - a).angle(&(c - a)).to_degrees();
            min_angle = min_angle.min(ang);
            max_edge = max_edge.max((b - a).norm());
        }
    }
    (min_angle, max_edge, area)
}

#[test]
fn square_with_a_round_hole() {
    let tol = 0.01;
    for (max_edge, min_angle) in [(5.0, 25.0), (2.0, 30.0), (20.0, 20.0)] {
        let opts = PanelOptions {
            max_edge: Some(max_edge),
            min_angle_deg: min_angle,
            tolerance: tol,
            ..Default::default()
        };
        let r = panel_from_svg(&data("panel_square_hole.svg"), &opts).unwrap();
        assert_eq!(r.loops, 2);
        assert!(r.refinement_complete);
        let (a_min, e_max, area) = triangle_stats(&r.mesh);
        // 100 × 60 minus a disc of radius 15; the flattened hole lies within `tol` inside the
        // circle, so the area error is at most its perimeter times tol.
        let exact = 100.0 * 60.0 - PI * 15.0 * 15.0;
        assert!((area - exact).abs() <= 2.0 * PI * 15.0 * tol, "area {area} vs {exact}");
        assert!(area > exact, "chords cut the hole short: the plate gains area");
        assert!((r.outline_area - area).abs() < 1e-6 * exact);
        assert!(a_min >= min_angle - 1e-6, "min angle {a_min} < {min_angle}");
        assert!(e_max <= max_edge * (1.0 + 1e-9), "max edge {e_max} > {max_edge}");
        assert_eq!(r.min_angle_deg.to_bits(), r.min_angle_deg.to_bits());
        // UV = XY (mm), positions in the z = 0 plane, Y up (the SVG's y flipped).
        let uv = r.mesh.uv.as_ref().unwrap();
        for f in 0..r.mesh.num_faces() {
            let p = r.mesh.face_positions(f);
            let t = uv.face(f);
            for k in 0..3 {
                assert_eq!((p[k].x, p[k].y, p[k].z), (t[k].x, t[k].y, 0.0));
            }
        }
        let (lo, hi) = r.mesh.bounding_box().unwrap();
        assert!(lo.x.abs() < 1e-9 && lo.y.abs() < 1e-9);
        assert!((hi.x - 100.0).abs() < 1e-9 && (hi.y - 60.0).abs() < 1e-9);
        // No vertex inside the hole (centre (30, 30) in SVG, y = 60 − 30 = 30 flipped).
        for p in &r.mesh.positions {
            assert!((p.x - 30.0).hypot(p.y - 30.0) > 15.0 - tol - 1e-9, "{p:?}");
        }
    }
}

#[test]
fn units_transforms_and_y_up() {
    // 2 in × 1 in drawn in a 200 × 100 viewBox with a translated group.
    let r = panel_from_svg(&data("panel_inches.svg"), &PanelOptions::default()).unwrap();
    let (lo, hi) = r.mesh.bounding_box().unwrap();
    assert!(lo.x.abs() < 1e-9 && lo.y.abs() < 1e-9, "{lo:?}");
    assert!((hi.x - 50.8).abs() < 1e-9 && (hi.y - 25.4).abs() < 1e-9, "{hi:?}");
    // px without a viewBox: 96 px = 1 in; a triangle with its apex at the top of the page.
    let text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="96" height="96">
        <path d="M0 96 L96 96 L48 0 z"/></svg>"#;
    let l = read_svg_loops(text, Path::new("t.svg"), 0.01).unwrap();
    let ys: Vec<f64> = l[0].points.iter().map(|p| p[1]).collect();
    assert!(ys.iter().any(|y| (y - 25.4).abs() < 1e-9) && ys.iter().any(|y| y.abs() < 1e-9));
    // Relative commands, a cubic and a quadratic within tolerance of their curves.
    let text = r#"<svg width="100mm" height="100mm" viewBox="0 0 100 100">
        <path d="m 10,10 h 80 v 40 c 0,20 -80,20 -80,0 z"/></svg>"#;
    let l = read_svg_loops(text, Path::new("t.svg"), 0.001).unwrap();
    // The cubic from (90, 50) to (10, 50) bulges 15 below y = 50 (SVG), i.e. y = 35 flipped.
    let min_y = l[0].points.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    assert!((min_y - 35.0).abs() < 0.002, "{min_y}");
}

#[test]
fn bad_outlines_are_errors_naming_the_file_and_element() {
    let o = PanelOptions::default();
    let e = panel_from_svg(&data("panel_open.svg"), &o).unwrap_err().to_string();
    // The line of the element (issue 15, item 16: no more `:0:`).
    assert!(
        e.starts_with(&format!(
            "{}:2: path element on line 2 (id \"edge\")",
            data("panel_open.svg").display()
        )),
        "{e}"
    );
    assert!(e.contains("open"), "{e}");
    let e = panel_from_svg(&data("panel_bowtie.svg"), &o).unwrap_err().to_string();
    assert!(e.contains("panel_bowtie.svg:3: polygon element on line 3 (id \"bowtie\")"), "{e}");
    assert!(e.contains("crosses or touches itself"), "{e}");
    let e = panel_from_svg(&data("panel_empty.svg"), &o).unwrap_err().to_string();
    assert!(e.contains("panel_empty.svg") && e.contains("no closed outline"), "{e}");
    // Two outlines that cross each other.
    let text = r#"<svg width="10mm" height="10mm" viewBox="0 0 10 10">
        <rect width="6" height="6"/><rect id="b" x="3" y="3" width="6" height="6"/></svg>"#;
    let loops = read_svg_loops(text, Path::new("two.svg"), 0.01).unwrap();
    let e = grainline::panel::mesh_loops(&loops, Path::new("two.svg"), &o).unwrap_err().to_string();
    assert!(
        e.contains("two.svg:2: rect element on line 2 crosses or touches rect element on line 2 (id \"b\")"),
        "{e}"
    );
    let e = read_svg_loops("not svg", Path::new("x.svg"), 0.01).unwrap_err().to_string();
    assert!(e.starts_with("x.svg"), "{e}");
    let bad = PanelOptions { min_angle_deg: 40.0, ..Default::default() };
    let e = panel_from_svg(&data("panel_square_hole.svg"), &bad).unwrap_err().to_string();
    assert!(e.starts_with("min_angle_deg: "), "{e}");
}

#[test]
fn cli_writes_the_obj_and_fails_with_one_line() {
    let dir = std::env::temp_dir().join(format!("grainline-panel-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("panel.obj");
    let run = |svg: &str, extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_grainline"))
            .arg("panel")
            .arg(data(svg))
            .arg("--out")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run("panel_square_hole.svg", &["--max-edge", "10", "--min-angle", "28"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mesh = grainline::mesh::load::load_obj(&out, &Default::default()).unwrap().mesh;
    let (a_min, e_max, area) = triangle_stats(&mesh);
    assert!(a_min >= 28.0 - 1e-4 && e_max <= 10.0 + 1e-6, "{a_min} {e_max}");
    assert!((area - (6000.0 - PI * 225.0)).abs() < 2.0 * PI * 15.0 * 0.01);
    assert!(mesh.uv.is_some());
    let before = std::fs::read(&out).unwrap();
    for (svg, extra, what) in [
        ("panel_open.svg", &[][..], "open"),
        ("panel_bowtie.svg", &[][..], "itself"),
        ("panel_empty.svg", &[][..], "no closed outline"),
        ("no_such.svg", &[][..], "no_such.svg"),
        ("panel_square_hole.svg", &["--max-edge=-1"][..], "--max-edge"),
    ] {
        let o = run(svg, extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{svg}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{svg}: {err}");
        assert!(err.starts_with("grainline: error: ") && err.contains(what), "{svg}: {err}");
        assert!(!err.contains("panicked"));
    }
    assert_eq!(std::fs::read(&out).unwrap(), before, "a failed run must not touch the output");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn malformed_path_data_is_an_error_not_a_panic() {
    for d in [
        "M",
        "M 1",
        "L 1 2",
        "M1 2 A",
        "Z",
        "M 0 0 Q 1",
        "M 0 0 C 1 1 2 2",
        "M 0 0 X 1 1",
        "M 0 0 A 1 1 0 2 0 3 3",
        "M 0 0 L nan 1",
        "M 0 0 L 1e999 1",
        "M0 0h",
        "M 0 0 l 1 0 0 1 z m",
        "M 0,0 1,0 0,1 z z z",
    ] {
        let text =
            format!(r#"<svg width="10mm" height="10mm" viewBox="0 0 10 10"><path d="{d}"/></svg>"#);
        let r = std::panic::catch_unwind(|| read_svg_loops(&text, Path::new("m.svg"), 0.01));
        let r = r.unwrap_or_else(|_| panic!("{d:?} panicked"));
        if let Err(e) = r {
            assert!(e.to_string().starts_with("m.svg"), "{d:?}: {e}");
        }
    }
    // Implicit line-tos after a moveto and stacked Z are fine.
    let text = r#"<svg width="10mm" height="10mm" viewBox="0 0 10 10"><path d="M 0,0 4,0 0,4 z z"/></svg>"#;
    let l = read_svg_loops(text, Path::new("m.svg"), 0.01).unwrap();
    assert_eq!(l.len(), 1);
    assert_eq!(l[0].points.len(), 3);
}

/// Issue 46: the even-odd area of 2 × 10⁴ separate rects, a hole in every other one and an
/// island in every fourth hole, inside one long outline: exact (every coordinate dyadic), in
/// time about linear in the loops (each loop is tested against the boxes that hold it).
#[test]
fn the_even_odd_area_of_many_nested_loops_is_exact() {
    use grainline::panel::{even_odd_area, Loop};
    let square = |c: [f64; 2], r: f64, per_side: usize| {
        let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
        let mut points = Vec::new();
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            for s in 0..per_side {
                let t = s as f64 / per_side as f64;
                points.push([0, 1].map(|i| c[i] + r * (a[i] + t * (b[i] - a[i]))));
            }
        }
        Loop { points, element: format!("square at {c:?}"), line: 0 }
    };
    let (side, n) = (142usize, 142 * 142);
    let mut loops = vec![square([71.0, 71.0], 72.0, 64)];
    let (mut holes, mut islands) = (0, 0);
    for k in 0..n {
        let c = [(k % side) as f64 + 0.5, (k / side) as f64 + 0.5];
        loops.push(square(c, 0.25, 1));
        if k % 2 == 0 {
            loops.push(square(c, 0.125, 1));
            holes += 1;
            if k % 4 == 0 {
                loops.push(square(c, 0.0625, 1));
                islands += 1;
            }
        }
    }
    assert!(loops.len() > 30_000, "{}", loops.len());
    // The outline 144², minus the rects (¼ each), plus their holes (¹⁄₁₆), minus the islands
    // (¹⁄₆₄): every partial sum a multiple of ¹⁄₆₄, exact.
    let want = 144.0 * 144.0 - 0.25 * n as f64 + holes as f64 / 16.0 - islands as f64 / 64.0;
    assert_eq!(even_odd_area(&loops), want);
}
