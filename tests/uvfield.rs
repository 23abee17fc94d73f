//! The grain field carried into UV (src/uvfield.rs), checked on surfaces whose UV map is known
//! in closed form: a plane (UV = XY scaled), its mirror image, and an unrolled cylinder.

use std::f64::consts::PI;

use grainline::generate::{cylinder, plane, Grid};
use grainline::geometry::{Geometry, GeometryOptions};
use grainline::highlight::Symmetry;
use grainline::mesh::Mesh;
use grainline::pipeline::trace::{trace, TraceInput};
use grainline::scene::toolpaths::ToolpathSection;
use grainline::solve::settings::Constraints;
use grainline::uvfield::{as_brushed, field_mesh, UvFieldOptions};
use grainline_toolpaths::{
    generate, Directions, JobOptions, PlacementOptions, StopReason, SvgOptions,
};
use nalgebra::Vector3;

fn setup(mesh: &Mesh, u: impl Fn(&Vector3<f64>) -> Vector3<f64>) -> (Geometry, Vec<f64>) {
    let g = Geometry::compute(mesh, &GeometryOptions::default());
    let dirs: Vec<Vector3<f64>> = mesh.positions.iter().map(u).collect();
    let phi = g.angles_of(&dirs);
    (g, phi)
}

fn vectors(d: &Directions) -> &[[f64; 2]] {
    match d {
        Directions::Vectors(v) => v,
        Directions::Angles(_) => panic!("expected vectors"),
    }
}

fn unit(v: [f64; 2]) -> [f64; 2] {
    let n = v[0].hypot(v[1]);
    assert!(n > 0.0 && n.is_finite(), "{v:?}");
    [v[0] / n, v[1] / n]
}

const A: f64 = 0.6;

fn uniform(_: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(A.cos(), A.sin(), 0.0)
}

#[test]
fn plane_constant_u_is_a_constant_uv_direction() {
    // plane(10): X = 20 s − 10, Y = 20 t − 10, so UV = XY / 20 + ½ and the metric is 400·I.
    let mesh = plane(10.0, Grid::new(8, 8));
    let (g, phi) = setup(&mesh, uniform);
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        let (fm, rep) = field_mesh(&mesh, &g, &phi, sym, &UvFieldOptions::default()).unwrap();
        assert_eq!(rep.uv_vertices, 81);
        assert_eq!(rep.triangles, 128);
        assert!(rep.degenerate_faces.is_empty() && rep.flipped_faces == 0);
        assert_eq!(rep.seam_pairs, 0);
        for d in vectors(&fm.directions) {
            let d = unit(*d);
            let (c, s) = (A.cos(), A.sin());
            let err = if sym == Symmetry::Line {
                (d[0] * s - d[1] * c).abs() // parallel up to sign
            } else {
                (d[0] - c).hypot(d[1] - s)
            };
            assert!(err < 1e-9, "{d:?}");
        }
        // The layout is scaled so one UV unit is one scene unit (s = 20): the metric becomes I.
        assert!((rep.uv_scale - 20.0).abs() < 1e-9, "{}", rep.uv_scale);
        for m in fm.metric.as_ref().unwrap() {
            assert!((m.e - 1.0).abs() < 1e-9 && m.f.abs() < 1e-9 && (m.g - 1.0).abs() < 1e-9);
        }
    }
}

#[test]
fn mesh_without_uvs_is_a_clear_error() {
    let mut mesh = plane(1.0, Grid::new(2, 2));
    let (g, phi) = setup(&mesh, uniform);
    mesh.uv = None;
    let e = field_mesh(&mesh, &g, &phi, Symmetry::Line, &UvFieldOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no UV coordinates"), "{e}");
}

#[test]
fn cylinder_axial_grain_runs_along_the_axis_at_the_requested_surface_spacing() {
    // cylinder: UV = (angle / 2π, z / h + ½); the axis is the +V direction.
    let (r, h) = (10.0, 40.0);
    let mesh = cylinder(r, h, 64, 16);
    let (g, phi) = setup(&mesh, |_| Vector3::z());
    let (fm, rep) =
        field_mesh(&mesh, &g, &phi, Symmetry::Line, &UvFieldOptions::default()).unwrap();
    assert_eq!(rep.seam_pairs, 16, "one seam edge per row");
    // The geometry's jet-refined normals tilt by a few µrad near the rims.
    for d in vectors(&fm.directions) {
        let d = unit(*d);
        assert!(d[0].abs() < 1e-4, "{d:?}");
    }
    let width = 2.0;
    // The evenly spaced strokes only: gap-filling strokes (issue 14) are not d_sep apart.
    let placement = PlacementOptions { fill_gaps: false, ..PlacementOptions::new(width, 0.0) };
    let opts = JobOptions { placement, ..Default::default() };
    let out = generate(fm, &opts).unwrap();
    // Each stroke is a line of constant s; neighbouring strokes are Δs · 2πr apart on the part.
    let mut s: Vec<f64> = out
        .placement
        .strokes
        .iter()
        .map(|st| {
            let s0 = st.uv[0][0];
            assert!(st.uv.iter().all(|p| (p[0] - s0).abs() < 1e-6), "stroke not axial");
            assert!((st.length - h).abs() < 1e-6 * h, "length {}", st.length);
            s0
        })
        .collect();
    s.sort_by(f64::total_cmp);
    let mut gaps: Vec<f64> =
        s.windows(2).map(|w| (w[1] - w[0]) / rep.uv_scale * 2.0 * PI * r).collect();
    gaps.sort_by(f64::total_cmp);
    assert!(gaps.len() >= 25, "{} strokes", s.len());
    let median = gaps[gaps.len() / 2];
    // The mesh is a 64-gon: its perimeter is 0.04 % short of 2πr.
    assert!((median - width).abs() < 0.01 * width, "median gap {median}");
    assert!(gaps[0] > 0.5 * width && gaps[gaps.len() - 1] < 1.01 * width, "{gaps:?}");
}

#[test]
fn mirrored_chart_does_not_turn_the_grain_over() {
    // UV s → −s: every UV triangle is flipped; X = 20 s − 10 = −20 s' − 10.
    let mut mesh = plane(10.0, Grid::new(8, 8));
    for t in &mut mesh.uv.as_mut().unwrap().values {
        t.x = -t.x;
    }
    let (g, phi) = setup(&mesh, uniform);
    let (fm, rep) =
        field_mesh(&mesh, &g, &phi, Symmetry::Oriented, &UvFieldOptions::default()).unwrap();
    assert_eq!(rep.flipped_faces, 128);
    for d in vectors(&fm.directions) {
        let d = unit(*d);
        assert!((d[0] + A.cos()).abs() < 1e-9 && (d[1] - A.sin()).abs() < 1e-9, "{d:?}");
    }
    let opts = JobOptions { placement: PlacementOptions::new(1.5, 0.0), ..Default::default() };
    let out = generate(fm, &opts).unwrap();
    assert!(out.placement.strokes.len() > 5);
    let u = uniform(&Vector3::zeros());
    for st in &out.placement.strokes {
        for w in st.uv.windows(2) {
            let t = Vector3::new(-20.0 * (w[1][0] - w[0][0]), 20.0 * (w[1][1] - w[0][1]), 0.0);
            if t.norm() > 1e-9 {
                assert!(t.normalize().dot(&u) > (1f64).to_radians().cos(), "{t:?}");
            }
        }
    }
}

fn around(p: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(-p.y, p.x, 0.0).normalize()
}

#[test]
fn strokes_cross_the_seam_when_asked_and_stop_cleanly_otherwise() {
    let mesh = cylinder(10.0, 20.0, 48, 8);
    let (g, phi) = setup(&mesh, around);
    let (fm, rep) =
        field_mesh(&mesh, &g, &phi, Symmetry::Oriented, &UvFieldOptions::default()).unwrap();
    let sc = rep.uv_scale;
    for d in vectors(&fm.directions) {
        let d = unit(*d);
        assert!((d[0] - 1.0).abs() < 1e-9, "circumferential is +U: {d:?}");
    }
    let mut opts = JobOptions { placement: PlacementOptions::new(2.0, 0.0), ..Default::default() };
    let stop = generate(fm.clone(), &opts).unwrap();
    // Strokes on the rims (t = 0, 1) leave through the rim within a few mm: the geometry's
    // jet-refined rim normals tilt the field off the rim by µrad. The others go round once.
    let interior = |st: &grainline_toolpaths::Stroke| {
        st.uv.iter().all(|p| p[1] > 0.02 * sc && p[1] < 0.98 * sc)
    };
    let mut n_interior = 0;
    for st in &stop.placement.strokes {
        assert!(st.breaks.is_empty());
        assert_eq!((st.start, st.end), (StopReason::Boundary, StopReason::Boundary));
        if !interior(st) {
            continue;
        }
        n_interior += 1;
        // Ends on the two sides of the seam, s = 0 and s = 1.
        let (a, b) = (st.uv[0][0], st.uv[st.uv.len() - 1][0]);
        assert!(a.min(b) < 1e-6 * sc && a.max(b) > (1.0 - 1e-6) * sc, "{a} {b}");
    }
    opts.placement.trace.cross_seams = true;
    let cross = generate(fm, &opts).unwrap();
    assert!(n_interior >= 8, "{n_interior}");
    let mut n_cross = 0;
    for st in &cross.placement.strokes {
        if !interior(st) {
            continue;
        }
        n_cross += 1;
        assert!(!st.breaks.is_empty(), "no seam crossing");
        assert!(st.start != StopReason::Boundary && st.end != StopReason::Boundary);
        // Once around: 2π r on the part (the 48-gon is 0.2 % shorter).
        assert!((st.length - 2.0 * PI * 10.0).abs() < 0.01 * 2.0 * PI * 10.0, "{}", st.length);
    }
    assert!(n_cross >= 8, "{n_cross}");
}

#[test]
fn degenerate_uv_triangles_are_reported_and_skipped() {
    let mut mesh = plane(10.0, Grid::new(4, 4));
    let uv = mesh.uv.as_mut().unwrap();
    let c = uv.corners[5][0];
    uv.corners[5] = [c, c, c];
    let (g, phi) = setup(&mesh, uniform);
    let (fm, rep) =
        field_mesh(&mesh, &g, &phi, Symmetry::Line, &UvFieldOptions::default()).unwrap();
    assert_eq!(rep.degenerate_faces, vec![5]);
    assert_eq!(rep.triangles, 31);
    assert!(vectors(&fm.directions).iter().all(|d| d[0].is_finite() && d[1].is_finite()));
    generate(fm, &JobOptions::default()).unwrap();
}

#[test]
fn as_brushed_recovers_a_uniform_field() {
    let mesh = plane(10.0, Grid::new(16, 16));
    let (g, phi) = setup(&mesh, uniform);
    for sym in [Symmetry::Oriented, Symmetry::Line] {
        let (fm, rep) = field_mesh(&mesh, &g, &phi, sym, &UvFieldOptions::default()).unwrap();
        let opts = JobOptions { placement: PlacementOptions::new(1.0, 0.0), ..Default::default() };
        let out = generate(fm.clone(), &opts).unwrap();
        let b = as_brushed(&mesh, &g, &phi, sym, &fm, &rep, &out.placement).unwrap();
        // Every vertex but a corner or two (where the strokes too short to keep were dropped:
        // beyond the brush's reach, left without grain) takes its stroke's direction.
        assert!(b.beyond_reach <= 4, "{}", b.beyond_reach);
        assert_eq!(b.compared + b.beyond_reach, mesh.num_vertices());
        assert!(b.median_deg < 1.0 && b.p95_deg < 1.0, "{} {}", b.median_deg, b.p95_deg);
        assert!(b.u.iter().all(|u| u.iter().all(|x| x.is_finite())));
    }
}

#[test]
fn as_brushed_sees_a_field_that_was_not_brushed() {
    // Designed u along +X; strokes placed for a field along +Y: 90° everywhere.
    let mesh = plane(10.0, Grid::new(8, 8));
    let (g, phi) = setup(&mesh, |_| Vector3::x());
    let (_, phi_y) = setup(&mesh, |_| Vector3::y());
    let (fm, rep) =
        field_mesh(&mesh, &g, &phi_y, Symmetry::Line, &UvFieldOptions::default()).unwrap();
    let out = generate(fm.clone(), &JobOptions::default()).unwrap();
    let b = as_brushed(&mesh, &g, &phi, Symmetry::Line, &fm, &rep, &out.placement).unwrap();
    assert!((b.median_deg - 90.0).abs() < 1.0, "{}", b.median_deg);
}

#[test]
fn toolpath_section_refuses_unknown_keys_and_names_bad_ones() {
    let e = serde_json::from_str::<ToolpathSection>(r#"{"placement": {"widht": 1}}"#).unwrap_err();
    assert!(e.to_string().contains("unknown field"), "{e}");
    let e = serde_json::from_str::<ToolpathSection>(r#"{"svg_option": {}}"#).unwrap_err();
    assert!(e.to_string().contains("unknown field"), "{e}");
    let s: ToolpathSection =
        serde_json::from_str(r#"{"placement": {"width": -1}, "svg": "a.svg"}"#).unwrap();
    assert_eq!(
        s.validate().unwrap_err().to_string(),
        "placement.width: must be finite and > 0, got -1"
    );
    let s: ToolpathSection = serde_json::from_str(r#"{"gcode_options": {"feed": 0}}"#).unwrap();
    assert!(s.validate().unwrap_err().to_string().starts_with("gcode_options.feed: "));
    let s: ToolpathSection = serde_json::from_str(r#"{"gcode": " "}"#).unwrap();
    assert!(s.validate().unwrap_err().to_string().starts_with("gcode: "));
    let s: ToolpathSection =
        serde_json::from_str(r#"{"uv_field": {"degenerate_ratio": -1}}"#).unwrap();
    assert!(s.validate().unwrap_err().to_string().starts_with("uv_field.degenerate_ratio: "));
    let schema = schemars::schema_for!(ToolpathSection);
    let text = serde_json::to_string(&schema).unwrap();
    assert!(text.contains("test_ratio") && text.contains("surface_following"));
}

/// The trace stage on `section` with no fabrication constraint.
fn trace_with(mesh: &Mesh, g: &Geometry, phi: &[f64], section: &ToolpathSection) -> TraceOut {
    let constraints = Constraints::default();
    let t = trace(&TraceInput {
        toolpaths: Some(section),
        constraints: &constraints,
        mesh,
        geometry: g,
        phi,
        symmetry: Symmetry::Line,
        keep_map: false,
        keep_field_mesh: false,
        surfaces: None,
        straddle: &[],
    })
    .unwrap();
    (t.job, t.uv)
}

type TraceOut = (grainline_toolpaths::JobOutput, grainline::uvfield::UvFieldReport);

#[test]
fn the_trace_stage_writes_the_requested_outputs() {
    let mesh = plane(10.0, Grid::new(8, 8));
    let (g, phi) = setup(&mesh, uniform);
    let section = ToolpathSection {
        svg: Some("out.svg".into()),
        gcode: Some("out.ngc".into()),
        svg_options: SvgOptions { title: "t".into(), ..Default::default() },
        ..Default::default()
    };
    let (out, rep) = trace_with(&mesh, &g, &phi, &section);
    assert_eq!(rep.triangles, 128);
    assert!(out.svg.is_some() && out.gcode.is_some() && out.strokes_json.is_none());
    // The cycle time is in the report with or without a program (then from gcode_options).
    let written = out.report.cycle_time_s.unwrap();
    let none = ToolpathSection { gcode: None, ..section };
    let (out, _) = trace_with(&mesh, &g, &phi, &none);
    assert!(out.gcode.is_none());
    assert_eq!(out.report.cycle_time_s, Some(written));
}

/// The brush's reach (`AsBrushed::beyond_reach`): the vertices of a plane brushed straight
/// (overlap 0.2) farther than half a width from every stroke — found by brute force over the
/// strokes' segments on the plane (UV = XY + 10 after the layout's scale) — are exactly those
/// counted: a few in the corners, where the strokes too short to keep were dropped, and more
/// than fifty once every other stroke is taken away.
#[test]
fn as_brushed_counts_the_vertices_beyond_the_brush_s_reach() {
    let mesh = plane(10.0, Grid::new(24, 24));
    let (g, phi) = setup(&mesh, uniform);
    let (fm, rep) =
        field_mesh(&mesh, &g, &phi, Symmetry::Line, &UvFieldOptions::default()).unwrap();
    assert!((rep.uv_scale - 20.0).abs() < 1e-9, "{}", rep.uv_scale);
    let opts = JobOptions { placement: PlacementOptions::new(1.0, 0.2), ..Default::default() };
    let out = generate(fm.clone(), &opts).unwrap();
    let segment = |p: [f64; 2], a: [f64; 2], c: [f64; 2]| {
        let d = [c[0] - a[0], c[1] - a[1]];
        let l2 = d[0] * d[0] + d[1] * d[1];
        let t = if l2 > 0.0 {
            (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        ((p[0] - a[0] - t * d[0]).powi(2) + (p[1] - a[1] - t * d[1]).powi(2)).sqrt()
    };
    let far = |pl: &grainline_toolpaths::Placement| {
        mesh.positions
            .iter()
            .filter(|x| {
                let p = [x.x + 10.0, x.y + 10.0];
                let d = pl
                    .strokes
                    .iter()
                    .flat_map(|s| s.uv.windows(2).map(move |w| (w[0], w[1])))
                    .map(|(a, c)| segment(p, a, c))
                    .fold(f64::INFINITY, f64::min);
                d > 0.5 + 1e-6
            })
            .count()
    };
    let b = as_brushed(&mesh, &g, &phi, Symmetry::Line, &fm, &rep, &out.placement).unwrap();
    let full = far(&out.placement);
    assert!(full < 10, "{full}");
    assert_eq!(b.beyond_reach, full);

    let mut sparse = out.placement.clone();
    let mut k = 0;
    sparse.strokes.retain(|_| {
        k += 1;
        k % 2 == 0
    });
    let b = as_brushed(&mesh, &g, &phi, Symmetry::Line, &fm, &rep, &sparse).unwrap();
    let gaps = far(&sparse);
    assert!(gaps > 50, "{gaps}");
    assert_eq!(b.beyond_reach, gaps);
}
