//! Streamline tracing against fields whose streamlines are known in closed form.

mod common;

use common::{annulus_mesh, field_mesh, rect_mesh};
use grainline_toolpaths::*;

fn shifted_square(half: f64, n: usize) -> (Vec<Vec2>, Vec<[u32; 3]>) {
    // Slightly asymmetric so the origin falls strictly inside a triangle.
    let (uv, tris) = rect_mesh(2.0 * half + 0.3, 2.0 * half, n + 1, n);
    (uv.into_iter().map(|p| [p[0] - half, p[1] - half]).collect(), tris)
}

/// Circular field on an annulus: streamlines are circles; the traced radius stays within
/// the integration tolerance and the loop is detected as closed.
#[test]
fn annulus_circles_within_tolerance_and_closed() {
    let mesh = field_mesh(annulus_mesh(2.0, 10.0, 8, 64), Symmetry::Vector, |p| [-p[1], p[0]]);
    let dom = Domain::new(mesh).unwrap();
    for tol in [1e-4, 1e-6] {
        for r in [2.5, 5.0, 9.5] {
            let opts = TraceOptions { tolerance: tol, max_step: 2.0, ..Default::default() };
            let s = trace_streamline(&dom, [r, 0.0], &opts).unwrap().expect("seed in domain");
            assert_eq!((s.start, s.end), (StopReason::ClosedLoop, StopReason::ClosedLoop));
            // Vertices and chord midpoints: the polyline itself stays within tolerance.
            let mut err: f64 = 0.0;
            for w in s.uv.windows(2) {
                let m = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
                for p in [w[0], m] {
                    err = err.max((p[0].hypot(p[1]) - r).abs());
                }
            }
            assert!(err < tol, "r = {r}, tol = {tol}: radius error {err}");
            let len_err = (s.length - 2.0 * std::f64::consts::PI * r).abs();
            assert!(len_err < 2.0 * std::f64::consts::PI * r * 1e-2, "length {}", s.length);
            // It goes round once, counter-clockwise, never backwards.
            for w in s.uv.windows(2) {
                assert!(w[0][0] * w[1][1] - w[0][1] * w[1][0] > 0.0);
            }
        }
    }
}

/// A line field whose corner vectors have random-looking signs still traces as one smooth
/// straight stroke that never reverses.
#[test]
fn line_field_with_flipped_corners_is_smooth() {
    let (uv, tris) = rect_mesh(10.0, 6.0, 20, 12);
    let dir = [0.8f64.cos(), 0.8f64.sin()];
    let d: Vec<Vec2> = (0..uv.len())
        .map(|i| if (i * 7 + i / 3) % 3 == 0 { [-dir[0], -dir[1]] } else { dir })
        .collect();
    let dom =
        Domain::new(FieldMesh::new(uv, tris, Directions::Vectors(d), Symmetry::Line)).unwrap();
    let s = trace_streamline(&dom, [5.0, 3.0], &TraceOptions::default()).unwrap().unwrap();
    assert_eq!((s.start, s.end), (StopReason::Boundary, StopReason::Boundary));
    let first = [s.uv[1][0] - s.uv[0][0], s.uv[1][1] - s.uv[0][1]];
    for w in s.uv.windows(2) {
        let seg = [w[1][0] - w[0][0], w[1][1] - w[0][1]];
        assert!(seg[0] * first[0] + seg[1] * first[1] > 0.0, "stroke reversed");
        // Distance from the line through the seed along `dir`.
        let off = (w[1][0] - 5.0) * dir[1] - (w[1][1] - 3.0) * dir[0];
        assert!(off.abs() < 1e-9, "not straight: {off}");
    }
}

type Field = Box<dyn Fn(Vec2) -> Vec2>;

/// Vortex (+1), saddle (−1) and trisector (−½, line field): each is found with its index,
/// placement terminates, no stroke enters the exclusion radius, and strokes that stop at the
/// singularity stop on the exclusion circle.
#[test]
fn singularities_stop_strokes_at_exclusion_radius() {
    let trisector = |p: Vec2| {
        let a = -0.5 * p[1].atan2(p[0]);
        [a.cos(), a.sin()]
    };
    let cases: [(&str, Symmetry, f64, Field); 3] = [
        ("vortex", Symmetry::Vector, 1.0, Box::new(|p: Vec2| [-p[1], p[0]])),
        ("saddle", Symmetry::Vector, -1.0, Box::new(|p: Vec2| [p[0], -p[1]])),
        ("trisector", Symmetry::Line, -0.5, Box::new(trisector)),
    ];
    let r_ex = 0.8;
    for (name, sym, index, f) in cases {
        let dom = Domain::new(field_mesh(shifted_square(5.0, 30), sym, f)).unwrap();
        let sing = singularities(&dom);
        assert_eq!(sing.len(), 1, "{name}: {sing:?}");
        assert_eq!(sing[0].index, index, "{name}");
        assert!(sing[0].uv[0].hypot(sing[0].uv[1]) < 0.35, "{name}: at {:?}", sing[0].uv);
        let c = sing[0].uv;
        let opts =
            PlacementOptions { exclusion_radius: Some(r_ex), ..PlacementOptions::new(0.7, 0.0) };
        let pl = place_strokes(&dom, &opts).unwrap();
        assert!(pl.strokes.len() > 10, "{name}");
        let mut stopped = 0;
        for s in &pl.strokes {
            for p in &s.uv {
                let d = (p[0] - c[0]).hypot(p[1] - c[1]);
                assert!(d >= r_ex * (1.0 - 1e-9), "{name}: point at {d} from the singularity");
            }
            for (reason, p) in [(s.start, s.uv[0]), (s.end, s.uv[s.uv.len() - 1])] {
                if reason == StopReason::Singularity {
                    stopped += 1;
                    let d = (p[0] - c[0]).hypot(p[1] - c[1]);
                    assert!((d - r_ex).abs() < 1e-6 * r_ex, "{name}: stopped at {d}");
                }
            }
        }
        if name != "vortex" {
            assert!(stopped > 0, "{name}: no stroke stopped at the singularity");
        }
    }
}

/// Regression: on a vector field the backward half runs against the arrows, so a stroke
/// through the middle spans the whole rectangle and follows the field from start to end.
#[test]
fn vector_field_traces_both_ways_from_the_seed() {
    let dom = Domain::new(field_mesh(rect_mesh(8.0, 4.0, 16, 8), Symmetry::Vector, |_| [1.0, 0.0]))
        .unwrap();
    let s = trace_streamline(&dom, [4.0, 2.1], &TraceOptions::default()).unwrap().unwrap();
    assert!(s.uv[0][0].abs() < 1e-9 && (s.uv[s.uv.len() - 1][0] - 8.0).abs() < 1e-9);
    assert!(s.uv.windows(2).all(|w| w[1][0] > w[0][0]), "stroke does not follow the field");
    assert!((s.length - 8.0).abs() < 1e-9);
}
