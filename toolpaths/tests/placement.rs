//! Even spacing: truth from geometry known in closed form.

mod common;

use common::{annulus_mesh, field_mesh, rect_mesh};
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
    // Both ends are on the part's edge: each stroke runs out one width (1 mm) past it,
    // straight on (issue 31, item 3).
    for s in &pl.strokes {
        let x0 = s.uv[0][0];
        let (a, b) = (s.run_out[0].unwrap(), s.run_out[1].unwrap());
        let (lo, hi) = if a[1] < b[1] { (a, b) } else { (b, a) };
        assert!((lo[0] - x0).abs() < 1e-9 && (hi[0] - x0).abs() < 1e-9, "{lo:?} {hi:?}");
        assert!((lo[1] + 1.0).abs() < 1e-6 && (hi[1] - (h + 1.0)).abs() < 1e-6, "{lo:?} {hi:?}");
        assert!((s.brushed_length() - (h + 2.0)).abs() < 1e-6);
    }
    // Strokes shorter than min_length are dropped and counted: without run-outs all of them
    // (6 mm on the part) for 6.5 mm; with the run-outs (a stroke from air to air, 8 mm
    // brushed, 6 on the part) none for 6.5 mm, all for 8.5 mm.
    let no_run_out =
        PlacementOptions { min_length: Some(6.5), overtravel: Some(0.0), ..opts.clone() };
    let pl = place_strokes(&dom, &no_run_out).unwrap();
    assert!(pl.strokes.is_empty() && pl.dropped_short > 0);
    let kept = place_strokes(&dom, &PlacementOptions { min_length: Some(6.5), ..opts.clone() });
    assert_eq!(kept.unwrap().strokes.len(), xs.len());
    let short = PlacementOptions { min_length: Some(8.5), ..opts };
    let pl = place_strokes(&dom, &short).unwrap();
    assert!(pl.strokes.is_empty() && pl.dropped_short > 0);
}

/// A spiral (a focus with slight outflow) never closes: strokes must stop before running
/// into their own earlier turns rather than winding on to the length limit.
#[test]
fn spirals_stop_before_meeting_themselves() {
    let (uv, tris) = common::rect_mesh(20.3, 20.0, 41, 40);
    let uv: Vec<_> = uv.into_iter().map(|p| [p[0] - 10.0, p[1] - 10.0]).collect();
    let mesh =
        field_mesh((uv, tris), Symmetry::Vector, |p| [-p[1] + 0.005 * p[0], p[0] + 0.005 * p[1]]);
    let dom = Domain::new(mesh).unwrap();
    let opts = PlacementOptions::new(1.0, 0.0);
    let (d_sep, d_test) = (opts.d_sep(), opts.d_test());
    let pl = place_strokes(&dom, &opts).unwrap();
    let total: f64 = pl.strokes.iter().map(|s| s.length).sum();
    // Evenly spaced strokes cover the 406 mm² square with about area / d_sep of length.
    assert!(total < 2.0 * 406.0 / d_sep, "total length {total}");
    for s in &pl.strokes {
        assert_ne!(s.end, StopReason::MaxLength);
        let mut arc = vec![0.0];
        for w in s.uv.windows(2) {
            arc.push(arc.last().unwrap() + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]));
        }
        for i in 0..s.uv.len() {
            for j in i + 1..s.uv.len() {
                // Along a closed loop the arc distance is the shorter way round.
                let along = arc[j] - arc[i];
                let along =
                    if s.is_closed() { along.min(arc[arc.len() - 1] - along) } else { along };
                if along > 1.2 * std::f64::consts::PI * d_test {
                    let d = (s.uv[i][0] - s.uv[j][0]).hypot(s.uv[i][1] - s.uv[j][1]);
                    assert!(d >= d_test * 0.999, "stroke comes back to itself at {d}");
                }
            }
        }
    }
}

/// A mirrored UV chart (every triangle clockwise) places the same strokes, mirrored.
#[test]
fn mirrored_chart_gives_mirrored_strokes() {
    let (uv, tris) = common::rect_mesh(10.3, 6.0, 23, 17);
    let mirrored: Vec<_> = uv.iter().map(|p| [-p[0], p[1]]).collect();
    let place = |uv: Vec<[f64; 2]>, d: [f64; 2]| {
        let dom = Domain::new(field_mesh((uv, tris.clone()), Symmetry::Line, |_| d)).unwrap();
        place_strokes(&dom, &PlacementOptions::new(1.0, 0.0)).unwrap()
    };
    let a = place(uv, [0.3, 1.0]);
    let b = place(mirrored, [-0.3, 1.0]);
    assert_eq!(a.strokes.len(), b.strokes.len());
    let total =
        |p: &grainline_toolpaths::Placement| p.strokes.iter().map(|s| s.length).sum::<f64>();
    assert!((total(&a) - total(&b)).abs() < 1e-6 * total(&a));
    assert!(b.singularities.is_empty());
    for (sa, sb) in a.strokes.iter().zip(&b.strokes) {
        for (p, q) in sa.uv.iter().zip(&sb.uv) {
            assert!((p[0] + q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9);
        }
    }
}

/// Straddled points (module docs of `place`): a point to be left between two strokes gets
/// one stroke `d_sep / 2` to either side across the field — on a constant field two straight
/// strokes at x₀ ± d_sep / 2, and the rest of the sheet spaced `d_sep` from them; a second
/// point closer than `d_sep / 2` to those strokes adds none.
#[test]
fn a_straddled_point_lies_midway_between_two_strokes() {
    let (w, h) = (10.3, 6.0);
    let mesh = field_mesh(rect_mesh(w, h, 23, 17), Symmetry::Line, |_| [0.0, 1.0]);
    let dom = Domain::new(mesh).unwrap();
    let x0 = 3.37;
    let opts = PlacementOptions {
        straddle: vec![[x0, 2.9], [x0 + 0.2, 4.0]],
        ..PlacementOptions::new(1.0, 0.2)
    };
    let d_sep = opts.d_sep();
    let pl = place_strokes(&dom, &opts).unwrap();
    assert_eq!(pl.straddle_strokes, 2);
    let xs: Vec<f64> = pl.strokes.iter().map(|s| s.uv[0][0]).collect();
    // The surface normal of the stroke is turned counter-clockwise from the field: left first.
    assert!((xs[0] - (x0 - 0.5 * d_sep)).abs() < 1e-6, "{xs:?}");
    assert!((xs[1] - (x0 + 0.5 * d_sep)).abs() < 1e-6, "{xs:?}");
    // Every evenly spaced stroke d_sep from the next (fill strokes brush the side strips).
    let mut xs: Vec<f64> = pl.strokes.iter().filter(|s| !s.fill).map(|s| s.uv[0][0]).collect();
    xs.sort_by(f64::total_cmp);
    for pair in xs.windows(2) {
        let gap = pair[1] - pair[0];
        assert!((gap - d_sep).abs() < 1e-6 * d_sep, "gap {gap} vs d_sep {d_sep}: {xs:?}");
    }
    assert!(xs[0] < d_sep && w - xs[xs.len() - 1] < d_sep, "xs = {xs:?}");
}

/// On a circular field (an annulus brushed round), the two strokes straddling a point at
/// radius r are the circles r ± d_sep / 2: the marches to either side follow the surface
/// normal of the field, not a fixed UV direction.
#[test]
fn straddled_circles_lie_half_a_spacing_either_side() {
    let mesh = field_mesh(annulus_mesh(2.0, 9.0, 28, 160), Symmetry::Line, |p| [-p[1], p[0]]);
    let dom = Domain::new(mesh).unwrap();
    let r0 = 5.3;
    let a = 0.7f64;
    let opts = PlacementOptions {
        straddle: vec![[r0 * a.cos(), r0 * a.sin()]],
        ..PlacementOptions::new(1.0, 0.1)
    };
    let d_sep = opts.d_sep();
    let pl = place_strokes(&dom, &opts).unwrap();
    assert_eq!(pl.straddle_strokes, 2);
    for (k, want) in [r0 - 0.5 * d_sep, r0 + 0.5 * d_sep].into_iter().enumerate() {
        let s = &pl.strokes[k];
        // Polygonal annulus: the field is exactly tangent only at the mesh vertices; the
        // stroke stays within the chord sag of a 160-gon (r (1 − cos(π/160)) ≈ 1e-3).
        for p in &s.uv {
            let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
            assert!((r - want).abs() < 2e-2, "stroke {k}: r = {r}, want {want}");
        }
    }
}
