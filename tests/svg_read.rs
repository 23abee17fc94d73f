//! Issue 15, item 16: one SVG reader (usvg, src/svg_read.rs) for panel outlines and designer
//! curves. Every expected coordinate below is derived by hand from the SVG text.

use std::f64::consts::PI;
use std::path::Path;

use grainline::edit::curve::parse_svg_polylines;
use grainline::panel::{read_svg_loops, Loop};

/// Loops of `body` inside a 100 × 100 mm root (viewBox 0 0 100 100: one user unit = 1 mm,
/// Y = 100 − y).
fn loops(body: &str, tol: f64) -> Vec<Loop> {
    let text = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"100mm\" height=\"100mm\" \
         viewBox=\"0 0 100 100\">\n{body}\n</svg>"
    );
    read_svg_loops(&text, Path::new("t.svg"), tol).unwrap()
}

fn error(text: &str) -> String {
    read_svg_loops(text, Path::new("bad.svg"), 0.01).unwrap_err().to_string()
}

/// Every point of `l` is within `eps` of one of `want`, and every one of `want` is met.
fn same_points(l: &[[f64; 2]], want: &[[f64; 2]], eps: f64) {
    assert_eq!(l.len(), want.len(), "{l:?} vs {want:?}");
    for w in want {
        assert!(
            l.iter().any(|p| (p[0] - w[0]).hypot(p[1] - w[1]) < eps),
            "{w:?} missing from {l:?}"
        );
    }
}

fn area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| p[i][0] * p[(i + 1) % n][1] - p[(i + 1) % n][0] * p[i][1]).sum::<f64>()
}

#[test]
fn item16_nested_group_transforms_are_composed() {
    // translate(50 50) ∘ rotate(90) ∘ scale(2) of the unit square's corner (1, 0):
    // scale → (2, 0), rotate 90° (x' = −y, y' = x) → (0, 2), translate → (50, 52);
    // SVG (50, 52) is panel (50, 100 − 52) = (50, 48).
    let l = loops(
        r#"<g transform="translate(50 50)"><g transform="rotate(90)">
           <rect transform="scale(2)" x="0" y="0" width="1" height="1"/></g></g>"#,
        0.01,
    );
    assert_eq!(l.len(), 1);
    // Corners (0,0) (1,0) (1,1) (0,1) → SVG (50,50) (50,52) (48,52) (48,50).
    same_points(&l[0].points, &[[50.0, 50.0], [50.0, 48.0], [48.0, 48.0], [48.0, 50.0]], 1e-4);
    // A matrix() and a skewX on the root's child: matrix(1 0 0 1 10 20) then skewX(45)
    // maps (x, y) to (x + y + 10, y + 20).
    let l = loops(
        r#"<g transform="matrix(1 0 0 1 10 20) skewX(45)"><polygon points="0,0 10,0 10,10"/></g>"#,
        0.01,
    );
    // (0,0) → (10,20); (10,0) → (20,20); (10,10) → (30,30); Y = 100 − y.
    same_points(&l[0].points, &[[10.0, 80.0], [20.0, 80.0], [30.0, 70.0]], 1e-4);
}

#[test]
fn item16_arcs_and_circles_lie_on_their_circles() {
    // Two half arcs about (50, 50) of radius 20, one absolute, one relative.
    let tol = 0.005;
    let l = loops(r#"<path d="M 70 50 A 20 20 0 0 1 30 50 a 20 20 0 0 1 40 0 z"/>"#, tol);
    assert_eq!(l.len(), 1);
    // The cubic approximation of an arc is within 2.7e-4 of its radius.
    let eps = tol + 2.8e-4 * 20.0;
    for p in &l[0].points {
        let r = (p[0] - 50.0).hypot(p[1] - 50.0);
        assert!((r - 20.0).abs() < eps, "{p:?} at radius {r}");
    }
    // The disc's area πr², less at most the chords' sagitta times the perimeter.
    let a = area(&l[0].points).abs();
    assert!((a - PI * 400.0).abs() < 2.0 * PI * 20.0 * eps, "{a}");
    // A circle element and an ellipse.
    let l =
        loops(r#"<circle cx="30" cy="40" r="10"/><ellipse cx="70" cy="70" rx="20" ry="5"/>"#, tol);
    assert_eq!(l.len(), 2);
    for p in &l[0].points {
        assert!(((p[0] - 30.0).hypot(p[1] - 60.0) - 10.0).abs() < tol + 2.8e-3, "{p:?}");
    }
    let a = area(&l[1].points).abs();
    assert!((a - PI * 100.0).abs() < 2.0 * PI * 20.0 * (tol + 5.6e-3), "{a}");
}

#[test]
fn item16_relative_and_smooth_commands() {
    // m 10,10 → (10,10); h 30 → (40,10); v 20 → (40,30); l -30,0 → (10,30); z.
    let l = loops(r#"<path d="m 10,10 h 30 v 20 l -30,0 z"/>"#, 0.01);
    same_points(&l[0].points, &[[10.0, 90.0], [40.0, 90.0], [40.0, 70.0], [10.0, 70.0]], 1e-4);
    // A quadratic and its smooth reflection (T): from (10,50) Q(20,30) to (30,50), then T to
    // (50,50) with the control reflected to (40,70). The first peaks at y = ¼·50 + ½·30 +
    // ¼·50 = 40 (panel Y 60), the second at y = 60 (panel Y 40); then back along y = 80.
    let l = loops(r#"<path d="M10,50 q10,-20 20,0 t20,0 V80 H10 Z"/>"#, 0.001);
    let max_y = l[0].points.iter().map(|p| p[1]).fold(f64::MIN, f64::max);
    let min_y = l[0].points.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
    assert!((max_y - 60.0).abs() < 0.002, "{max_y}");
    assert!((min_y - 20.0).abs() < 1e-4, "{min_y}");
    // Vertices lie on the curve: near an extremum the closest is within 2·tol of it.
    let second = l[0].points.iter().filter(|p| p[0] > 30.0 && p[0] < 50.0 && p[1] > 30.0);
    let low = second.map(|p| p[1]).fold(f64::MAX, f64::min);
    assert!((low - 40.0).abs() < 0.002, "{low}");
}

#[test]
fn item16_use_instances_and_rounded_rects() {
    // A rect in defs drawn twice by <use>, shifted by (x, y) and by a transform.
    let l = loops(
        r##"<defs><rect id="r" width="10" height="5"/></defs>
            <use href="#r" x="20" y="30"/><use href="#r" transform="translate(60 60)"/>"##,
        0.01,
    );
    assert_eq!(l.len(), 2);
    same_points(&l[0].points, &[[20.0, 70.0], [30.0, 70.0], [30.0, 65.0], [20.0, 65.0]], 1e-4);
    same_points(&l[1].points, &[[60.0, 40.0], [70.0, 40.0], [70.0, 35.0], [60.0, 35.0]], 1e-4);
    // Instances are named after their <use>.
    assert_eq!(l[0].element, "use element on line 3 (href \"#r\")");
    // rx on a rect: four quarter-circle corners, area w·h − (4 − π) r².
    let tol = 0.001;
    let l = loops(r#"<rect x="10" y="10" width="40" height="20" rx="5"/>"#, tol);
    let a = area(&l[0].points).abs();
    let exact = 40.0 * 20.0 - (4.0 - PI) * 25.0;
    // Chords (≤ tol over the 31.4 mm of corners) and the cubic corners (≤ 2.7e-4 · 5 mm):
    // within 0.1 mm² of the exact area, where square corners would add 21.5 mm².
    assert!((a - exact).abs() < 0.1, "{a} vs {exact}");
}

#[test]
fn item16_units_and_view_boxes() {
    // 2 in × 1 in (50.8 × 25.4 mm) over a 200 × 100 viewBox: 0.254 mm per unit.
    let text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="2in" height="1in"
        viewBox="0 0 200 100"><rect x="100" y="0" width="100" height="50"/></svg>"#;
    let l = read_svg_loops(text, Path::new("u.svg"), 0.01).unwrap();
    same_points(&l[0].points, &[[25.4, 25.4], [50.8, 25.4], [50.8, 12.7], [25.4, 12.7]], 1e-4);
    // No viewBox: user units are px (25.4 / 96 mm); 96 px = 1 in; height 96 px.
    let text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="96" height="96">
        <polygon points="0,96 96,96 48,0"/></svg>"#;
    let l = read_svg_loops(text, Path::new("u.svg"), 0.01).unwrap();
    same_points(&l[0].points, &[[0.0, 0.0], [25.4, 0.0], [12.7, 25.4]], 1e-4);
    // cm with an offset viewBox: 10 cm × 5 cm over "-50 -25 100 50" (1 mm per unit).
    let text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="10cm" height="5cm"
        viewBox="-50 -25 100 50"><rect x="-10" y="-5" width="20" height="10"/></svg>"#;
    let l = read_svg_loops(text, Path::new("u.svg"), 0.01).unwrap();
    // x + 50; Y = 50 − (y + 25).
    same_points(&l[0].points, &[[40.0, 30.0], [60.0, 30.0], [60.0, 20.0], [40.0, 20.0]], 1e-4);
    // Aspect ratios that differ: xMidYMid meet centres a 100 × 100 viewBox in 200 × 100 mm
    // (1 mm per unit, 50 mm margins left and right).
    let text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="100mm"
        viewBox="0 0 100 100"><rect width="100" height="100"/></svg>"#;
    let l = read_svg_loops(text, Path::new("u.svg"), 0.01).unwrap();
    same_points(&l[0].points, &[[50.0, 0.0], [150.0, 0.0], [150.0, 100.0], [50.0, 100.0]], 1e-4);
}

#[test]
fn item16_hidden_elements_character_references_and_styles() {
    // display:none (attribute and style) and everything in defs draw nothing.
    let l = loops(
        r#"<rect width="10" height="10"/>
           <rect x="20" width="10" height="10" display="none"/>
           <g style="display:none"><rect x="40" width="10" height="10"/></g>
           <defs><rect x="60" width="10" height="10"/></defs>"#,
        0.01,
    );
    assert_eq!(l.len(), 1);
    // Character references in attributes are decoded: "&#49;&#48;" is "10".
    let l = loops(r#"<rect id="a&amp;b" width="&#49;&#48;" height="5"/>"#, 0.01);
    same_points(&l[0].points, &[[0.0, 100.0], [10.0, 100.0], [10.0, 95.0], [0.0, 95.0]], 1e-4);
    assert!(l[0].element.contains("(id \"a&b\")"), "{}", l[0].element);
    // A <style> sheet's transform-free rules apply (display: none by class).
    let l = loops(
        r#"<style>.gone { display: none }</style>
           <rect width="10" height="10"/><rect class="gone" x="50" width="10" height="10"/>"#,
        0.01,
    );
    assert_eq!(l.len(), 1);
}

#[test]
fn item16_malformed_svgs_are_typed_errors_naming_file_line_and_element() {
    // An XML syntax error: its line.
    let e = error(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"1mm\" height=\"1mm\">\n<rect>\n</svg>",
    );
    assert!(e.starts_with("bad.svg:3: not a readable SVG"), "{e}");
    // A negative rect width (usvg would skip it): the element and its line.
    let e = error(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"9mm\" height=\"9mm\">\n\n\
         <rect id=\"w\" width=\"-4\" height=\"3\"/></svg>",
    );
    assert_eq!(e, "bad.svg:3: rect element on line 3 (id \"w\"): width=\"-4\" is negative");
    let e = error(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="9mm" height="9mm"><circle r="-1"/></svg>"#,
    );
    assert!(e.contains("circle element on line 1: r=\"-1\" is negative"), "{e}");
    // No size at all: units unknown.
    let e = error(r#"<svg xmlns="http://www.w3.org/2000/svg"><rect width="1" height="1"/></svg>"#);
    assert!(e.starts_with("bad.svg:1: the <svg> element has neither a viewBox"), "{e}");
    // Not SVG.
    let e = error("<html><body/></html>");
    assert!(e.contains("the root element is <html>"), "{e}");
    // A hole crossing its outline, both subpaths of one path: named apart.
    let text = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"20mm\" height=\"20mm\" \
                viewBox=\"0 0 20 20\">\n<path d=\"M0 0 H10 V10 H0 Z M5 5 H15 V15 H5 Z\"/></svg>";
    let l = read_svg_loops(text, Path::new("h.svg"), 0.01).unwrap();
    let e = grainline::panel::mesh_loops(&l, Path::new("h.svg"), &Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(
            "h.svg:2: subpath 1 of path element on line 2 crosses or touches subpath 2 of path \
             element on line 2"
        ),
        "{e}"
    );
}

#[test]
fn item16_curves_read_transforms_arcs_and_shapes_in_uv() {
    // viewBox 0 0 100 100 → u = x / 100, v = 1 − y / 100; a translated group and a line.
    let text = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
        <g transform="translate(10 0)"><path d="M0 0 L10 10" fill="none" stroke="red"/></g>
        <line x1="0" y1="50" x2="100" y2="50" stroke="black"/></svg>"#;
    let c = parse_svg_polylines(text, 1e-3).unwrap();
    assert_eq!(c.len(), 2);
    assert!((c[0][0] - nalgebra::Vector2::new(0.1, 1.0)).norm() < 1e-6, "{:?}", c[0]);
    assert!((c[0][1] - nalgebra::Vector2::new(0.2, 0.9)).norm() < 1e-6, "{:?}", c[0]);
    assert!((c[1][0] - nalgebra::Vector2::new(0.0, 0.5)).norm() < 1e-6, "{:?}", c[1]);
    assert!((c[1][1] - nalgebra::Vector2::new(1.0, 0.5)).norm() < 1e-6, "{:?}", c[1]);
    // The viewBox fills the UV square whatever the root's aspect ratio (as before usvg):
    // 200 × 100 px over "0 0 10 10": (5, 5) is the centre, (10, 0) the corner (1, 1).
    let text = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="100"
        viewBox="0 0 10 10" preserveAspectRatio="xMinYMin slice">
        <path d="M5 5 L10 0"/></svg>"#;
    let c = parse_svg_polylines(text, 1e-3).unwrap();
    assert!((c[0][0] - nalgebra::Vector2::new(0.5, 0.5)).norm() < 1e-6, "{:?}", c[0]);
    assert!((c[0][1] - nalgebra::Vector2::new(1.0, 1.0)).norm() < 1e-6, "{:?}", c[0]);
}
