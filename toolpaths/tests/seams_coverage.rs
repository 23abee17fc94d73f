//! Crossing UV seams, and the coverage report.

mod common;

use common::{field_mesh, rect_mesh};
use grainline_toolpaths::*;

/// One 10 × 4 mm strip cut into two charts at u = 5; the right chart is laid out rotated by
/// 90° and moved away. The field runs along the strip (+u on the part).
fn two_charts() -> FieldMesh {
    let (ua, ta) = rect_mesh(5.0, 4.0, 10, 8);
    let (ub, tb) = rect_mesh(5.0, 4.0, 10, 8);
    let n = ua.len() as u32;
    // Chart B: part point (5 + x, y) ↦ UV (30 − y, 10 + x): rotated +90°.
    let map_b = |p: Vec2| [30.0 - p[1], 10.0 + p[0]];
    let mut uv = ua.clone();
    uv.extend(ub.iter().map(|&p| map_b(p)));
    let mut tris = ta;
    tris.extend(tb.iter().map(|t| t.map(|v| v + n)));
    let mut dirs = vec![[1.0, 0.0]; ua.len()];
    dirs.extend(std::iter::repeat_n([0.0, 1.0], ub.len()));
    // Seam: A's right edge (u = 5) is B's left edge (x = 0), vertex by vertex.
    let a_right = |j: u32| j * 11 + 10;
    let b_left = |j: u32| n + j * 11;
    let seams = (0..8)
        .map(|j| SeamPair { a: [a_right(j), a_right(j + 1)], b: [b_left(j), b_left(j + 1)] })
        .collect();
    FieldMesh::new(uv, tris, Directions::Vectors(dirs), Symmetry::Line).with_seams(seams)
}

#[test]
fn strokes_continue_across_a_seam_when_asked() {
    let dom = Domain::new(two_charts()).unwrap();
    let stop = TraceOptions::default();
    let s = trace_streamline(&dom, [2.5, 1.3], &stop).unwrap().unwrap();
    assert!((s.length - 5.0).abs() < 1e-6, "length {}", s.length);
    assert!(s.breaks.is_empty());
    let cross = TraceOptions { cross_seams: true, ..Default::default() };
    let s = trace_streamline(&dom, [2.5, 1.3], &cross).unwrap().unwrap();
    assert!((s.length - 10.0).abs() < 1e-6, "length {}", s.length);
    assert_eq!(s.breaks.len(), 1);
    assert_eq!((s.start, s.end), (StopReason::Boundary, StopReason::Boundary));
    // On chart B the stroke is the image of y = 1.3: u = 30 − 1.3.
    let b = s.breaks[0];
    assert!((s.uv[b][0] - 28.7).abs() < 1e-9 && (s.uv[b][1] - 10.0).abs() < 1e-9, "{:?}", s.uv[b]);
    for p in &s.uv[b..] {
        assert!((p[0] - 28.7).abs() < 1e-9, "{p:?}");
    }
    // Flat export splits at the seam: two SVG paths per stroke, two G-code passes.
    let pl =
        place_strokes(&dom, &PlacementOptions { trace: cross, ..PlacementOptions::new(1.0, 0.0) })
            .unwrap();
    let plan = plan_toolpath(&dom, &pl, &PlanOptions::default()).unwrap();
    assert_eq!(plan.passes.len(), 2 * pl.strokes.len());
}

/// Parallel strokes `d_sep` apart cover the whole rectangle; the largest gap is `d_sep`
/// (the disc between two neighbours).
#[test]
fn coverage_of_parallel_strokes() {
    let mesh = field_mesh(rect_mesh(10.3, 6.0, 23, 17), Symmetry::Line, |_| [0.0, 1.0]);
    let dom = Domain::new(mesh).unwrap();
    let opts = PlacementOptions::new(1.0, 0.2);
    let pl = place_strokes(&dom, &opts).unwrap();
    let cov = coverage(&dom, &pl, &CoverageOptions::default()).unwrap();
    let map = cov.map.as_ref().unwrap();
    assert!(cov.fraction > 0.999, "coverage {}", cov.fraction);
    assert!((cov.largest_gap - opts.d_sep()).abs() < 2.0 * map.pixel, "gap {}", cov.largest_gap);
    assert_eq!(map.distance.len(), map.width * map.height);
    // Dropping every other stroke opens gaps of 2 d_sep and halves coverage roughly.
    let mut sparse = pl.clone();
    sparse.strokes.sort_by(|a, b| a.uv[0][0].total_cmp(&b.uv[0][0]));
    sparse.strokes = sparse.strokes.into_iter().step_by(2).collect();
    let cov2 = coverage(&dom, &sparse, &CoverageOptions::default()).unwrap();
    assert!(cov2.fraction < 0.6 && cov2.fraction > 0.4, "coverage {}", cov2.fraction);
    assert!(
        (cov2.largest_gap - 2.0 * opts.d_sep()).abs() < 2.0 * map.pixel,
        "gap {}",
        cov2.largest_gap
    );
}
