//! Stroke-level fabrication figures (issue 17) against fields whose streamlines are known by
//! hand: concentric circles (turning radius ρ = r), logarithmic spirals at an angle α to the
//! radius (ρ = r / sin α, spread d ln δ/ds = cos α / r), rays (spread 1/r), latitude circles
//! on a sphere (geodesic turning radius R cot φ, not the 3D radius R cos φ), and a constant
//! field through a lock turned by a known angle. The strokes JSON is also measured here with
//! this file's own circumradius code, which shares nothing with the crate.

mod common;

use common::{annulus_mesh, field_mesh, rect_mesh};
use grainline_toolpaths::*;

fn job(mesh: FieldMesh, width: f64) -> JobOutput {
    let opts = JobOptions {
        placement: PlacementOptions::new(width, 0.0),
        strokes_json: true,
        ..Default::default()
    };
    generate(mesh, &opts).unwrap()
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn r2(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1]).sqrt()
}

/// Circumradius of three points (this file's own code: |ab||bc||ca| / (2|ab × ac|)).
fn circumradius(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ac = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let bc = [c[0] - b[0], c[1] - b[1], c[2] - b[2]];
    let x = [
        ab[1] * ac[2] - ab[2] * ac[1],
        ab[2] * ac[0] - ab[0] * ac[2],
        ab[0] * ac[1] - ab[1] * ac[0],
    ];
    norm(ab) * norm(bc) * norm(ac) / (2.0 * norm(x))
}

fn lifted_annulus(r0: f64, r1: f64, nr: usize, nt: usize, f: impl Fn(Vec2) -> Vec2) -> FieldMesh {
    let m = field_mesh(annulus_mesh(r0, r1, nr, nt), Symmetry::Line, f);
    let pos = m.uv.iter().map(|p| [p[0], p[1], 0.0]).collect();
    m.with_lift(pos, None)
}

/// Concentric circles on a flat annulus (lifted to z = 0): every sample's turning radius is
/// its distance from the centre, and the share below a limit R is the share of the length of
/// the circles smaller than R, counted from the strokes JSON.
#[test]
fn concentric_circles_turn_at_their_radius() {
    let out = job(lifted_annulus(4.0, 30.0, 52, 240, |p| [-p[1], p[0]]), 2.0);
    let file: StrokesFile = serde_json::from_str(out.strokes_json.as_deref().unwrap()).unwrap();
    // Each stroke's mean distance from the centre and its length, from the JSON.
    let mut rings: Vec<(f64, f64)> = file
        .strokes
        .iter()
        .map(|s| {
            let pts: Vec<[f64; 3]> = s.xyz.as_ref().unwrap().concat();
            (pts.iter().map(|p| r2(*p)).sum::<f64>() / pts.len() as f64, s.length_mm)
        })
        .collect();
    rings.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(rings.len() >= 10, "{} strokes", rings.len());
    assert!(file.strokes.iter().all(|s| s.closed), "circles close");
    // A limit halfway between two rings.
    let k = rings.len() / 2;
    let limit = 0.5 * (rings[k - 1].0 + rings[k].0);
    let total: f64 = rings.iter().map(|r| r.1).sum();
    let want: f64 = rings.iter().filter(|r| r.0 < limit).map(|r| r.1).sum::<f64>() / total;
    let o = StrokeCheckOptions {
        turning_radius: Some(limit),
        step: Some(1.5),
        keep_samples: true,
        ..Default::default()
    };
    let c = check_strokes(&out.domain, &out.placement, &o).unwrap();
    assert!(c.on_surface);
    let t = c.turning.as_ref().unwrap();
    assert!(t.samples > 500, "{} samples", t.samples);
    for s in &c.samples {
        let r = r2(s.at.xyz);
        let rho = s.turning_radius.expect("a circle turns");
        assert!((rho - r).abs() <= 0.01 * r, "ρ {rho} at r {r}");
    }
    assert!(
        (t.below_radius.length_fraction - want).abs() < 0.01,
        "{} vs {want}",
        t.below_radius.length_fraction
    );
    let smallest = rings[0].0;
    let m = t.min_radius_mm.unwrap();
    assert!((m - smallest).abs() < 0.01 * smallest, "tightest {m}, smallest ring {smallest}");
    assert!(c.warnings().iter().any(|w| w.contains("tighter than the turning radius")));
    // The JSON's own polylines (simplified vertices lie on the traced curve): this file's
    // circumradius of vertices about 1.5 mm apart is the ring's radius too.
    for s in &file.strokes {
        for piece in s.xyz.as_ref().unwrap() {
            let mut arc = vec![0.0];
            for w in piece.windows(2) {
                let d = [w[1][0] - w[0][0], w[1][1] - w[0][1], w[1][2] - w[0][2]];
                arc.push(arc.last().unwrap() + norm(d));
            }
            for i in 0..piece.len() {
                let (Some(a), Some(c)) = (
                    (0..i).rev().find(|&j| arc[i] - arc[j] >= 1.5),
                    (i + 1..piece.len()).find(|&j| arc[j] - arc[i] >= 1.5),
                ) else {
                    continue;
                };
                let r = r2(piece[i]);
                let rho = circumradius(piece[a], piece[i], piece[c]);
                assert!((rho - r).abs() <= 0.01 * r, "JSON: ρ {rho} at r {r}");
            }
        }
    }
}

/// Logarithmic spirals at α = 60° to the radius (no lift: measured in UV): the turning
/// radius is r / sin α (a log spiral's curvature is sin α / r) and the spread between
/// neighbouring spirals is d ln δ/ds = cos α / r (the family is self-similar, so δ ∝ r, and
/// dr/ds = cos α).
#[test]
fn log_spirals_turn_and_spread_as_derived() {
    let alpha = 60f64.to_radians();
    let (ca, sa) = (alpha.cos(), alpha.sin());
    let mesh = field_mesh(annulus_mesh(5.0, 35.0, 60, 300), Symmetry::Line, |p| {
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        let (er, et) = ([p[0] / r, p[1] / r], [-p[1] / r, p[0] / r]);
        [ca * er[0] + sa * et[0], ca * er[1] + sa * et[1]]
    });
    let out = job(mesh, 2.0);
    let o = StrokeCheckOptions {
        turning_radius: Some(20.0),
        splay: Some(0.05),
        step: Some(1.5),
        keep_samples: true,
        ..Default::default()
    };
    let c = check_strokes(&out.domain, &out.placement, &o).unwrap();
    assert!(!c.on_surface);
    let mut turning_errors = Vec::new();
    let mut spread_errors = Vec::new();
    for s in &c.samples {
        let r = r2(s.at.xyz);
        let rho = s.turning_radius.expect("a spiral turns");
        turning_errors.push((rho - r / sa).abs() / (r / sa));
        for rate in s.spread.iter().flatten() {
            spread_errors.push((rate - ca / r).abs() / (ca / r));
        }
    }
    turning_errors.sort_by(f64::total_cmp);
    spread_errors.sort_by(f64::total_cmp);
    let q = |v: &[f64], f: f64| v[((v.len() - 1) as f64 * f) as usize];
    assert!(turning_errors.len() > 500 && spread_errors.len() > 500);
    assert!(q(&turning_errors, 1.0) < 0.02, "turning: worst {}", q(&turning_errors, 1.0));
    assert!(q(&spread_errors, 0.5) < 0.02, "spread: median {}", q(&spread_errors, 0.5));
    assert!(q(&spread_errors, 0.95) < 0.10, "spread: p95 {}", q(&spread_errors, 0.95));
    // Spreading, not converging: every rate is positive along the tracing direction or
    // negative against it, and |rate| ≈ cos α / r; the worst is at the inner rim.
    let s = c.splay.as_ref().unwrap();
    let inner = 0.5 / (5.0 + 2.0);
    assert!(s.max_rate > 0.8 * inner && s.max_rate < 1.1 * ca / 5.0, "{}", s.max_rate);
    // The bound 0.05 holds beyond r = cos α / 0.05 = 10 only.
    let frac_inside: f64 = {
        let rates: Vec<f64> = c
            .samples
            .iter()
            .flat_map(|x| x.spread.iter().flatten().map(move |_| r2(x.at.xyz)))
            .collect();
        rates.iter().filter(|&&r| r < 10.0).count() as f64 / rates.len() as f64
    };
    assert!((s.above_bound.sample_fraction - frac_inside).abs() < 0.03);
}

/// Rays from the centre spread at exactly 1/r, and do not turn.
#[test]
fn rays_spread_at_one_over_r() {
    let mesh = field_mesh(annulus_mesh(5.0, 35.0, 60, 300), Symmetry::Line, |p| p);
    let out = job(mesh, 2.0);
    let o = StrokeCheckOptions {
        turning_radius: Some(10.0),
        splay: Some(0.5),
        keep_samples: true,
        ..Default::default()
    };
    let c = check_strokes(&out.domain, &out.placement, &o).unwrap();
    let mut n = 0;
    for s in &c.samples {
        let r = r2(s.at.xyz);
        for rate in s.spread.iter().flatten() {
            n += 1;
            assert!((rate.abs() - 1.0 / r).abs() < 0.05 / r, "rate {rate} at r {r}");
        }
        if let Some(rho) = s.turning_radius {
            assert!(rho > 1e3, "a ray turned at {rho}");
        }
    }
    assert!(n > 300, "{n} spread measurements");
    let t = c.turning.unwrap();
    assert_eq!(t.below_radius.samples, 0);
    assert!(c.splay.unwrap().above_bound.samples == 0);
}

/// Latitude circles on a sphere of radius 20: the geodesic turning radius R cot φ, not the
/// circle's 3D radius R cos φ (the projection into the tangent plane removes the sphere's own
/// bending). The facets of the 0.2 mm grid bend the lifted strokes by up to ~3e-4 / mm, so
/// only latitudes ≥ 0.3 rad (ρ ≤ 65 mm) are held to 3 %.
#[test]
fn latitude_circles_turn_at_their_geodesic_radius() {
    const R: f64 = 20.0;
    let (uv, tris) = rect_mesh(1.2, 1.2, 120, 120);
    let uv: Vec<Vec2> = uv.into_iter().map(|p| [p[0] - 0.6, p[1] - 0.6]).collect();
    let sphere = |lon: f64, lat: f64| -> Vec3 {
        [R * lat.cos() * lon.sin(), R * lat.sin(), R * lat.cos() * lon.cos()]
    };
    let pos: Vec<Vec3> = uv.iter().map(|p| sphere(p[0], p[1])).collect();
    let nrm: Vec<Vec3> = pos.iter().map(|p| p.map(|x| x / R)).collect();
    let d = vec![[1.0, 0.0]; uv.len()];
    let mesh =
        FieldMesh::new(uv, tris, Directions::Vectors(d), Symmetry::Line).with_lift(pos, Some(nrm));
    let out = job(mesh, 1.0);
    let o = StrokeCheckOptions {
        turning_radius: Some(50.0),
        step: Some(1.0),
        keep_samples: true,
        ..Default::default()
    };
    let c = check_strokes(&out.domain, &out.placement, &o).unwrap();
    let mut n = 0;
    let mut worst = 0.0f64;
    for s in &c.samples {
        let lat = (s.at.xyz[1] / R).asin();
        if lat.abs() < 0.3 {
            // Nearly straight: the flat facets' kinks (a 0.4 mm grid) are a few per cent of
            // such a slight turn.
            continue;
        }
        n += 1;
        let want = R / lat.abs().tan();
        let rho = s.turning_radius.unwrap();
        worst = worst.max((rho - want).abs() / want);
        assert!(rho > 1.2 * R * lat.cos(), "the 3D radius leaked in: {rho}");
    }
    assert!(n > 200, "{n} samples");
    assert!(worst < 0.03, "worst relative error {worst}");
}

/// A constant field along +U through a lock region: a lock along +U is followed to 0°, one
/// turned by 10° is missed by 10°.
#[test]
fn lock_deviation_is_the_angle_to_the_lock() {
    let m = field_mesh(rect_mesh(40.0, 20.0, 40, 20), Symmetry::Line, |_| [1.0, 0.0]);
    let pos = m.uv.iter().map(|p| [p[0], p[1], 0.0]).collect();
    let locked: Vec<u32> =
        m.uv.iter()
            .enumerate()
            .filter(|(_, p)| (p[0] - 20.0).hypot(p[1] - 10.0) <= 6.0)
            .map(|(i, _)| i as u32)
            .collect();
    let out = job(m.with_lift(pos, None), 1.0);
    let a = 10f64.to_radians();
    let probe = |name: &str, d: Vec3| LockProbe {
        name: name.into(),
        vertices: locked.clone(),
        directions: vec![d; locked.len()],
    };
    let o = StrokeCheckOptions {
        locks: vec![probe("along", [1.0, 0.0, 0.0]), probe("turned", [a.cos(), a.sin(), 0.0])],
        ..Default::default()
    };
    let c = check_strokes(&out.domain, &out.placement, &o).unwrap();
    let (along, turned) = (&c.locks[0], &c.locks[1]);
    assert!(along.samples > 20 && along.strokes >= 5, "{along:?}");
    assert!(along.max_deviation_deg < 1e-6, "{}", along.max_deviation_deg);
    assert_eq!(turned.samples, along.samples);
    assert!((turned.max_deviation_deg - 10.0).abs() < 1e-6);
    assert!((turned.mean_deviation_deg - 10.0).abs() < 1e-6);
    let w = c.warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("turned"));
}

/// Bad options are errors that name the option.
#[test]
fn bad_options_are_named() {
    let out = job(field_mesh(rect_mesh(10.0, 10.0, 4, 4), Symmetry::Line, |_| [1.0, 0.0]), 1.0);
    let o = StrokeCheckOptions { step: Some(f64::NAN), ..Default::default() };
    let e = check_strokes(&out.domain, &out.placement, &o).unwrap_err().to_string();
    assert!(e.contains("checks.step"), "{e}");
    let o = StrokeCheckOptions { turning_radius: Some(-1.0), ..Default::default() };
    let e = check_strokes(&out.domain, &out.placement, &o).unwrap_err().to_string();
    assert!(e.contains("checks.turning_radius"), "{e}");
}

/// Arcs of circles about c = (0, −5) across a 20 × 10 mm sheet, ending on its edges: with a
/// tool radius R = 8, every arc tighter than R has both ends cut back by two brush widths (to
/// within one step), or is dropped when less than a width would be left; looser arcs are kept
/// whole, and the cuts are counted.
#[test]
fn tight_ends_at_the_boundary_are_cut_back() {
    let c = [0.0, -5.0];
    let m = field_mesh(rect_mesh(20.0, 10.0, 80, 40), Symmetry::Line, |p| {
        let p = [p[0] - 10.0, p[1]];
        [-(p[1] - c[1]), p[0] - c[0]]
    });
    let dom = Domain::new(m).unwrap();
    let width = 0.5;
    let pl = place_strokes(&dom, &PlacementOptions::new(width, 0.0)).unwrap();
    let mut cut = pl.clone();
    let r_lim = 8.0;
    let counts = cut_tight_ends(&dom, &mut cut, r_lim);
    let radius = |s: &Stroke| {
        s.uv.iter().map(|p| (p[0] - 10.0 - c[0]).hypot(p[1] - c[1])).sum::<f64>()
            / s.uv.len() as f64
    };
    let (mut k, mut tight, mut dropped) = (0, 0, 0);
    for s in &pl.strokes {
        let rho = radius(s);
        let same = cut.strokes.get(k).is_some_and(|t| s.uv.iter().any(|p| *p == t.uv[0]));
        let both_ends_on_edge = s.start == StopReason::Boundary && s.end == StopReason::Boundary;
        if rho < 0.95 * r_lim && both_ends_on_edge {
            tight += 1;
            if !same {
                dropped += 1;
                assert!(s.length < 4.0 * width + 2.0 * width, "dropped a {} mm arc", s.length);
                continue;
            }
            let t = &cut.strokes[k];
            let removed = s.length - t.length;
            assert!(
                (removed - 4.0 * width).abs() <= 1.0 * width,
                "ρ {rho}: {} → {} mm",
                s.length,
                t.length
            );
        } else if rho > 1.05 * r_lim {
            assert!(same && cut.strokes[k].uv == s.uv, "a loose arc (ρ {rho}) was cut");
        }
        if same {
            k += 1;
        }
    }
    assert!(tight >= 3, "{tight} tight arcs");
    assert_eq!(counts.dropped, dropped);
    assert!(counts.cuts >= 2 * tight, "{counts:?} for {tight} tight arcs");
    assert_eq!(cut.strokes.len() + counts.dropped, pl.strokes.len());
    // Through the job: the report counts the same.
    let m = field_mesh(rect_mesh(20.0, 10.0, 80, 40), Symmetry::Line, |p| {
        let p = [p[0] - 10.0, p[1]];
        [-(p[1] - c[1]), p[0] - c[0]]
    });
    let opts = JobOptions {
        placement: PlacementOptions::new(width, 0.0),
        plan: PlanOptions { min_turning_radius: Some(r_lim), ..Default::default() },
        ..Default::default()
    };
    let out = generate(m, &opts).unwrap();
    assert_eq!(out.report.tight_end_cuts, counts.cuts);
    assert_eq!(out.report.tight_end_dropped, counts.dropped);
    assert_eq!(out.placement.strokes.len(), cut.strokes.len());
}
