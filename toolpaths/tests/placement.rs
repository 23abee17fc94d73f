//! Even spacing: truth from geometry known in closed form.

mod common;

use common::{field_mesh, rect_mesh};
use grainline_toolpaths::{place_strokes, Domain, PlacementOptions, StopReason, Symmetry};

/// Constant field on a rectangle: straight vertical strokes exactly `d_sep` apart.
#[test]
fn constant_field_gives_parallel_strokes_d_sep_apart() {
    let (w, h) = (10.3, 6.0);
    let mesh = field_mesh(rect_mesh(w, h, 23, 17), Symmetry::Line, |_| [0.0, 1.0]);
    let dom = Domain::new(mesh).unwrap();
    let opts = PlacementOptions::new(1.0, 0.2);
    let d_sep = opts.d_sep();
    let pl = place_strokes(&dom, &opts).unwrap();
    let mut xs: Vec<f64> = Vec::new();
    for s in &pl.strokes {
        let x0 = s.uv[0][0];
        for p in &s.uv {
            assert!((p[0] - x0).abs() < 1e-9 * d_sep, "stroke not straight: {} vs {}", p[0], x0);
        }
        let ys: Vec<f64> = s.uv.iter().map(|p| p[1]).collect();
        let lo = ys.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = ys.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        assert!(lo < 1e-6 && hi > h - 1e-6, "stroke does not span the rectangle: {lo}..{hi}");
        assert_eq!(s.start, StopReason::Boundary);
        assert_eq!(s.end, StopReason::Boundary);
        xs.push(x0);
    }
    xs.sort_by(f64::total_cmp);
    for pair in xs.windows(2) {
        let gap = pair[1] - pair[0];
        assert!((gap - d_sep).abs() < 1e-6 * d_sep, "gap {gap} vs d_sep {d_sep}");
    }
    // Covering: the strips left at the sides are narrower than d_sep.
    assert!(xs[0] < d_sep && w - xs[xs.len() - 1] < d_sep, "xs = {xs:?}");
}
