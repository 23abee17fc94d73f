//! Spacing on a curved part (sphere patch given by its first fundamental form), surface-
//! following Z, and tilt checks.

mod common;

use common::rect_mesh;
use grainline_toolpaths::*;

const R: f64 = 20.0;

fn sphere(lon: f64, lat: f64) -> Vec3 {
    [R * lat.cos() * lon.sin(), R * lat.sin(), R * lat.cos() * lon.cos()]
}

/// A sphere patch, longitude × latitude ∈ [−0.6, 0.6]², with the exact first fundamental
/// form `E = R² cos² lat, F = 0, G = R²` at each triangle's centroid, the lift and normals
/// (pointing up, +Z is the tool axis).
fn sphere_patch(n: usize, f: impl Fn(Vec2) -> Vec2) -> FieldMesh {
    let (uv, tris) = rect_mesh(1.2, 1.2, n, n);
    let uv: Vec<Vec2> = uv.into_iter().map(|p| [p[0] - 0.6, p[1] - 0.6]).collect();
    let metric = tris
        .iter()
        .map(|t| {
            let lat = t.iter().map(|&v| uv[v as usize][1]).sum::<f64>() / 3.0;
            Metric { e: R * R * lat.cos().powi(2), f: 0.0, g: R * R }
        })
        .collect();
    let pos: Vec<Vec3> = uv.iter().map(|p| sphere(p[0], p[1])).collect();
    let nrm: Vec<Vec3> = pos.iter().map(|p| p.map(|x| x / R)).collect();
    let d = uv.iter().map(|&p| f(p)).collect();
    FieldMesh::new(uv, tris, Directions::Vectors(d), Symmetry::Line)
        .with_lift(pos, Some(nrm))
        .with_metric(metric)
}

fn dist_point_segment(p: Vec3, a: Vec3, b: Vec3) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let l2 = ab.iter().map(|x| x * x).sum::<f64>();
    let t = if l2 > 0.0 {
        (ap.iter().zip(&ab).map(|(x, y)| x * y).sum::<f64>() / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (0..3).map(|k| (ap[k] - t * ab[k]).powi(2)).sum::<f64>().sqrt()
}

/// Neighbouring strokes are ≥ d_test apart everywhere and ≤ 1.5 d_sep apart over ≥ 95 % of
/// their length, measured in 3D on the sphere (independently of the crate's metric code).
#[test]
fn spacing_statistics_on_a_sphere_patch() {
    let mesh = sphere_patch(60, |p| {
        let a = 0.4 + 2.5 * p[0] * p[0] + 1.5 * p[1];
        [a.cos(), a.sin()]
    });
    let dom = Domain::new(mesh).unwrap();
    // The classic Jobard–Lefer stop (no run-on past d_test): strokes stay d_test apart.
    let opts = PlacementOptions { end_run: 0.0, ..PlacementOptions::new(1.0, 0.0) };
    let (d_sep, d_test) = (opts.d_sep(), opts.d_test());
    let pl = place_strokes(&dom, &opts).unwrap();
    assert!(pl.strokes.len() > 10);
    // With the default run-on, stroke ends come no closer than d_test / 2.
    let run_on = place_strokes(&dom, &PlacementOptions::new(1.0, 0.0)).unwrap();
    let lifted: Vec<Vec<Vec3>> =
        run_on.strokes.iter().map(|s| s.uv.iter().map(|p| sphere(p[0], p[1])).collect()).collect();
    for (i, s) in lifted.iter().enumerate() {
        for p in s {
            for (j, o) in lifted.iter().enumerate() {
                if j != i {
                    for w in o.windows(2) {
                        let d = dist_point_segment(*p, w[0], w[1]);
                        assert!(d >= 0.5 * d_test * (1.0 - 1e-3), "run-on ends {d} apart");
                    }
                }
            }
        }
    }
    let lifted: Vec<Vec<Vec3>> =
        pl.strokes.iter().map(|s| s.uv.iter().map(|p| sphere(p[0], p[1])).collect()).collect();
    let (mut ok_len, mut total_len) = (0.0, 0.0);
    let mut min_d = f64::INFINITY;
    for (i, s) in lifted.iter().enumerate() {
        for k in 0..s.len() {
            let mut d = f64::INFINITY;
            for (j, o) in lifted.iter().enumerate() {
                if j == i {
                    continue;
                }
                for w in o.windows(2) {
                    d = d.min(dist_point_segment(s[k], w[0], w[1]));
                }
            }
            let seg = |a: usize, b: usize| dist_point_segment(s[a], s[b], s[b]);
            let wgt = 0.5
                * (if k > 0 { seg(k, k - 1) } else { 0.0 }
                    + if k + 1 < s.len() { seg(k, k + 1) } else { 0.0 });
            total_len += wgt;
            if d <= 1.5 * d_sep {
                ok_len += wgt;
            }
            min_d = min_d.min(d);
        }
    }
    // 3D chords are shorter than surface distances by < d²/(24R²) relative: ~1e-4 here.
    assert!(min_d >= d_test * (1.0 - 1e-3), "closest approach {min_d} < d_test {d_test}");
    let frac = ok_len / total_len;
    eprintln!(
        "{} strokes, min distance {min_d:.4} (d_test {d_test}), {:.2}% within 1.5 d_sep",
        pl.strokes.len(),
        100.0 * frac
    );
    assert!(
        frac >= 0.95,
        "only {:.1}% of the length has a neighbour within 1.5 d_sep",
        100.0 * frac
    );
}

/// Surface-following Z is the lifted height minus the contact depth; tilt beyond the limit
/// is an error or a skip, by option.
#[test]
fn surface_following_z_and_tilt() {
    let mesh = sphere_patch(30, |_| [1.0, 0.0]);
    let dom = Domain::new(mesh).unwrap();
    let pl = place_strokes(&dom, &PlacementOptions::new(2.0, 0.0)).unwrap();
    let plan_opts = |max_tilt_deg: f64, on_tilt| PlanOptions {
        contact_depth: 0.3,
        tolerance: 0.001,
        z_mode: ZMode::SurfaceFollowing { max_tilt_deg, on_tilt },
        ..Default::default()
    };
    let plan = plan_toolpath(&dom, &pl, &plan_opts(60.0, TiltPolicy::Error)).unwrap();
    let mut run_outs = 0;
    for pass in &plan.passes {
        let mut from = pass.start;
        let mut cut = false;
        for (kind, m) in &pass.moves {
            let p = m.end();
            if *kind == MoveKind::Overtravel {
                // A run-out past the patch's edge (both ends of every stroke are on it): it
                // runs 2 mm (one width) from the stroke's end on the sphere along the sphere's
                // tangent, so it is perpendicular to the normal there, leaves the patch and
                // lies above the sphere by at most √(R² + 2²) − R (0.0998 mm).
                let (on, off) = if cut { (from, p) } else { (p, from) };
                let lift = |q: Vec3| [q[0], q[1], q[2] + 0.3];
                let (on, off) = (lift(on), lift(off));
                let d = [off[0] - on[0], off[1] - on[1], off[2] - on[2]];
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                assert!((len - 2.0).abs() < 1e-9, "run-out {len} mm long");
                // The mesh's facets span 0.04 rad: the lifted stroke's tangent is within
                // 0.03 rad of the sphere's tangent plane, the run-out's end within 2 × 0.03 mm.
                let n_dot = (d[0] * on[0] + d[1] * on[1] + d[2] * on[2]) / (len * R);
                assert!(n_dot.abs() < 0.03, "run-out leaves the tangent plane: cos {n_dot}");
                let r = (off[0].powi(2) + off[1].powi(2) + off[2].powi(2)).sqrt();
                assert!(r > R - 0.06 && r < (R * R + 4.0).sqrt() + 0.06, "run-out end at {r}");
                let (lat, lon) = ((off[1] / r).asin(), off[0].atan2(off[2]));
                assert!(lat.abs().max(lon.abs()) > 0.6 + 0.05, "run-out ends on the patch");
                run_outs += 1;
            } else {
                cut = cut || *kind == MoveKind::Cut;
                // Find the sphere height above this XY: z = sqrt(R² − x² − y²).
                let z = (R * R - p[0] * p[0] - p[1] * p[1]).sqrt() - 0.3;
                // Chords of a 1.2-rad patch on a 30 × 30 mesh sit below the sphere by < 0.06.
                assert!((p[2] - z).abs() < 0.06, "Z {} vs surface {}", p[2], z);
            }
            from = p;
        }
    }
    assert_eq!(run_outs, 2 * plan.passes.len(), "every stroke runs out past both edges");
    // The patch tilts up to ~45° at its corners.
    match plan_toolpath(&dom, &pl, &plan_opts(20.0, TiltPolicy::Error)) {
        Err(ToolpathError::TiltExceeded { by_deg, .. }) => assert!(by_deg > 0.0),
        other => panic!("expected a tilt error, got {other:?}"),
    }
    let skipped = plan_toolpath(&dom, &pl, &plan_opts(20.0, TiltPolicy::Skip)).unwrap();
    assert!(!skipped.skipped_tilt.is_empty());
    assert_eq!(skipped.passes.len() + skipped.skipped_tilt.len(), plan.passes.len());
    assert!(skipped.skipped_tilt.iter().all(|&(_, t)| t > 20.0));
}

/// Surface-following programs pass LinuxCNC's interpreter too.
#[test]
fn surface_following_gcode_accepted() {
    let Some(tool) = common::shared_tool("check-gcode") else { return };
    let mesh = sphere_patch(30, |_| [1.0, 0.0]);
    let opts = JobOptions {
        placement: PlacementOptions::new(2.0, 0.0),
        plan: PlanOptions {
            contact_depth: 0.3,
            lead_in: 1.0,
            lead_out: 1.0,
            ramp_height: 1.0,
            z_mode: ZMode::SurfaceFollowing { max_tilt_deg: 60.0, on_tilt: TiltPolicy::Error },
            ..Default::default()
        },
        gcode: Some(GcodeOptions { safe_z: 30.0, ..Default::default() }),
        ..Default::default()
    };
    let opts = JobOptions { strokes_json: true, ..opts };
    let out = generate(mesh, &opts).unwrap();
    // The strokes JSON carries the 3D lift: points on the sphere of radius R.
    let json: serde_json::Value = serde_json::from_str(out.strokes_json.as_ref().unwrap()).unwrap();
    for s in json["strokes"].as_array().unwrap() {
        for piece in s["xyz"].as_array().expect("xyz present") {
            for p in piece.as_array().unwrap() {
                let r = (0..3).map(|k| p[k].as_f64().unwrap().powi(2)).sum::<f64>().sqrt();
                assert!((r - R).abs() < 0.1, "|p| = {r}");
            }
        }
    }
    let dir = common::scratch("surface-gcode");
    let path = dir.join("sphere.ngc");
    std::fs::write(&path, out.gcode.unwrap()).unwrap();
    let (ok, text) = common::run_tool(&tool, &[&path]);
    assert!(ok, "{text}");
}
