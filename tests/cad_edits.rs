//! Edits on CAD faces (issue 29, item 5): a bend and a drawn curve on a flat face (the plate's
//! top, in inches), on a fillet that meets its walls tangentially (the housing's vertical R8
//! fillet) and on a cylinder (the turned part's Ø40 collar) of the generated CAD parts
//! (`grainline::generate::cad`, written as binary STL as CAD exports them). Each lands by the
//! run report's fidelity with no new singular triangle, and the strokes more than two brush
//! radii from the brush still run within 1° of the world grain projected onto the analytic
//! surface there — the truth is the part's analytic face, computed here, not grainline's
//! output. A geodesic brush stops at a sharp edge: a bend next to the housing's top edge leaves
//! the wall's grain as it was.

#[path = "support/cad_truth.rs"]
mod cad_truth;

use std::path::{Path, PathBuf};
use std::process::Command;

use cad_truth::{
    angle_deg, dot, edit_site, eye_on_highlight, norm, segment_distance, sub, unit, P,
};
use grainline::generate::cad::{self, AnalyticFace, CadPart};
use nalgebra::Vector3;

const WORLD: P = [0.2, 1.0, 0.3];

fn v(p: P) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}
fn a(p: &Vector3<f64>) -> P {
    [p.x, p.y, p.z]
}

/// The closest point of a plane or a cylinder to `p`.
fn onto(face: &AnalyticFace, p: P) -> P {
    match *face {
        AnalyticFace::Plane { normal, point, .. } => {
            a(&(v(p) - normal * (v(p) - point).dot(&normal)))
        }
        AnalyticFace::Cylinder { axis_point, axis_dir, radius, .. } => {
            let q = v(p) - axis_point;
            let along = axis_dir * q.dot(&axis_dir);
            a(&(axis_point + along + (q - along).normalize() * radius))
        }
        _ => unreachable!("planes and cylinders only"),
    }
}

/// The outward normal of the part at `p` on `face`.
fn outward(part: &CadPart, face: usize, p: P) -> P {
    let n = part.faces[face].normal_at(&v(p));
    // Oriented like the triangles of the face (counter-clockwise around the outward normal).
    let t = part.face_of.iter().position(|&f| f as usize == face).unwrap();
    let tri = &part.triangles[t];
    let tn = (tri[1] - tri[0]).cross(&(tri[2] - tri[0]));
    a(&if tn.dot(&n) < 0.0 { -n } else { n })
}

/// The world grain projected onto the tangent plane of normal `n`.
fn grain(n: P, w: P) -> P {
    let s = dot(w, n);
    unit([w[0] - s * n[0], w[1] - s * n[1], w[2] - s * n[2]])
}

/// A point of `face` far from its boundary (the best projected triangle centroid) and that
/// distance.
fn deep_point(part: &CadPart, face: usize) -> (P, f64) {
    let tris: Vec<[P; 3]> = (0..part.triangles.len())
        .filter(|&t| part.face_of[t] as usize == face)
        .map(|t| part.triangles[t].map(|q| a(&q)))
        .collect();
    let key = |p: P| p.map(f64::to_bits);
    let mut count = std::collections::HashMap::new();
    for t in &tris {
        for k in 0..3 {
            let (x, y) = (key(t[k]), key(t[(k + 1) % 3]));
            count.entry((x.min(y), x.max(y))).or_insert((t[k], t[(k + 1) % 3], 0)).2 += 1;
        }
    }
    let boundary: Vec<(P, P)> =
        count.into_values().filter(|e| e.2 == 1).map(|e| (e.0, e.1)).collect();
    let mut best = ([0.0; 3], -1.0);
    for t in &tris {
        let c = onto(&part.faces[face], [0, 1, 2].map(|k| (t[0][k] + t[1][k] + t[2][k]) / 3.0));
        let d = boundary.iter().map(|e| segment_distance(c, e.0, e.1)).fold(f64::MAX, f64::min);
        if d > best.1 {
            best = (c, d);
        }
    }
    best
}

fn diagonal(part: &CadPart) -> f64 {
    let (mut lo, mut hi) = (Vector3::repeat(f64::MAX), Vector3::repeat(f64::MIN));
    for p in part.triangles.iter().flatten() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (hi - lo).norm()
}

struct Edit {
    p0: P,
    r: f64,
    curve: Vec<P>,
}

/// Runs `part` with `edits` from `dir`; returns the run report.
fn run(
    part: &CadPart,
    dir: &Path,
    eye: P,
    p0: P,
    l: P,
    edits: serde_json::Value,
    width: f64,
) -> serde_json::Value {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("part.stl"), part.stl_binary()).unwrap();
    let scene = serde_json::json!({
        "mesh": "part.stl",
        "units": part.units.as_str(),
        "lights": [{"type": "directional", "direction": l}],
        "view": {"eye": eye, "target": p0},
        "field": {"init": "world", "world": WORLD, "output": "FIELD.json"},
        "edits": edits,
        "toolpaths": {"strokes_json": "strokes.json", "placement": {"width": width}},
    });
    std::fs::write(dir.join("scene.json"), serde_json::to_string(&scene).unwrap()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(dir.join("scene.json"))
        .arg("--report")
        .arg(dir.join("report.json"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}: {}", dir.display(), String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap()
}

/// (length, within 1°) of the stroke segments on `face` (both ends within `tol` of its
/// surface) that `keep` accepts, against the grain of the analytic normal there.
fn far_straightness(
    strokes: &Path,
    part: &CadPart,
    face: usize,
    tol: f64,
    keep: &dyn Fn(P) -> bool,
) -> (f64, f64) {
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(strokes).unwrap()).unwrap();
    let v3 = |x: &serde_json::Value| [0, 1, 2].map(|k| x[k].as_f64().unwrap());
    let (mut total, mut good) = (0.0, 0.0);
    for stroke in s["strokes"].as_array().unwrap() {
        for piece in stroke["xyz"].as_array().unwrap() {
            let xyz: Vec<P> = piece.as_array().unwrap().iter().map(v3).collect();
            for seg in xyz.windows(2) {
                let on = |p: P| part.faces[face].distance(&v(p)) <= tol;
                let d = sub(seg[1], seg[0]);
                let len = norm(d);
                if len == 0.0 || !on(seg[0]) || !on(seg[1]) || !keep(seg[0]) || !keep(seg[1]) {
                    continue;
                }
                let m = [0, 1, 2].map(|k| 0.5 * (seg[0][k] + seg[1][k]));
                total += len;
                // The stroke lies on a facet, whose plane leans from the surface's by up to half
                // a strip's step: its direction seen in the surface's tangent plane there (the
                // two projections differ by the square of that lean, 0.3° at 6°).
                let n = outward(part, face, m);
                if angle_deg(grain(n, d), grain(n, WORLD), true) < 1.0 {
                    good += len;
                }
            }
        }
    }
    (total, good)
}

/// A bend and a curve at the deepest point of `face` of `part`, seen so that the key
/// highlight passes there: both land, add no singular triangle, and the strokes beyond 2 r
/// keep the grain.
fn edits_land(part: &CadPart, face: usize, tag: &str) {
    let d = diagonal(part);
    let (p0, clearance) = deep_point(part, face);
    let r = (0.04 * d).min(0.6 * clearance);
    let n = outward(part, face, p0);
    let u = grain(n, WORLD);
    let site = edit_site(p0, n, u, r, d);
    let (l, eye, push) = (site.light, site.eye, site.push);
    let curve: Vec<P> = site.curve.iter().map(|&q| onto(&part.faces[face], q)).collect();
    let edit = Edit { p0, r, curve };
    // The same scene without the edit: the strokes and grain the edit must leave alone.
    let base = scratch(&format!("{tag}-base"));
    run(part, &base, eye, p0, l, serde_json::json!([]), edit.r / 6.0);
    let planar = part.faces[face].is_planar();
    for tool in ["bend", "curve"] {
        let edits = match tool {
            "bend" => {
                serde_json::json!([{"tool": "bend", "centre": {"point": edit.p0}, "radius": edit.r,
                                           "strength": 0.8, "direction": push}])
            }
            _ => {
                serde_json::json!([{"tool": "curve", "points": [edit.curve], "radius": edit.r / 3.0}])
            }
        };
        let dir = scratch(&format!("{tag}-{tool}"));
        let report = run(part, &dir, eye, p0, l, edits, edit.r / 6.0);
        let f = &report["optimize"]["fidelity"][0];
        eprintln!(
            "{tag} {tool}: r {:.3}, within {:.1} %, p95 {:.3} r, singular {} → {}, +{} vertices",
            edit.r,
            100.0 * f["within"].as_f64().unwrap(),
            f["p95"].as_f64().unwrap(),
            f["singular_before"],
            f["singular_after"],
            report["optimize"]["refinement"]["vertices_added"]
        );
        assert_eq!(f["landed"], true, "{tag} {tool}: {f}");
        assert!(f["singular_after"].as_u64() <= f["singular_before"].as_u64(), "{tag} {tool}: {f}");
        let far = |p: P| match tool {
            "bend" => norm(sub(p, edit.p0)) > 2.0 * edit.r,
            _ => edit.curve.windows(2).all(|s| segment_distance(p, s[0], s[1]) > 2.0 * edit.r),
        };
        let (total, good) = far_straightness(&dir.join("strokes.json"), part, face, 1e-3 * d, &far);
        let (t0, g0) = far_straightness(&base.join("strokes.json"), part, face, 1e-3 * d, &far);
        let (share, before) = (good / total, g0 / t0);
        eprintln!(
            "{tag} {tool}: {:.1} % of {total:.1} beyond 2 r within 1° ({:.1} % without the edit)",
            100.0 * share,
            100.0 * before
        );
        assert!(total > 10.0 * edit.r, "{tag} {tool}: only {total} of strokes beyond 2 r");
        // On a plane the grain is one direction and the strokes follow it exactly; a curved
        // face's strokes follow the grain interpolated across its strips (a 12° strip of a
        // helical grain turns it by degrees), and the edit must not make that worse.
        if planar {
            assert!(share >= 0.99, "{tag} {tool}: {:.1} %", 100.0 * share);
        } else {
            assert!(
                share >= before - 0.01,
                "{tag} {tool}: {:.1} % < {:.1} %",
                100.0 * share,
                100.0 * before
            );
        }
        // The grain of the part's own vertices beyond 2 r is as it was.
        let turned = far_grain_change(&base, &dir, &far);
        assert!(turned < 1e-3, "{tag} {tool}: the grain beyond 2 r turned by {turned}°");
        std::fs::remove_dir_all(&dir).ok();
    }
    std::fs::remove_dir_all(&base).ok();
}

/// The largest angle (degrees, as lines) between the grain of the part's own vertices that
/// `far` accepts in two runs' FIELD.json (the edited one has the refinement's vertices after
/// the part's own).
fn far_grain_change(base: &Path, edited: &Path, far: &dyn Fn(P) -> bool) -> f64 {
    let read = |d: &Path| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(d.join("FIELD.json")).unwrap()).unwrap()
    };
    let (a, b) = (read(base), read(edited));
    let v3 = |x: &serde_json::Value| [0, 1, 2].map(|k| x[k].as_f64().unwrap());
    let (pa, ua, ub) =
        (a["position"].as_array().unwrap(), a["u"].as_array().unwrap(), b["u"].as_array().unwrap());
    (0..ua.len())
        .filter(|&i| far(v3(&pa[i])))
        .map(|i| angle_deg(v3(&ua[i]), v3(&ub[i]), true))
        .fold(0.0, f64::max)
}

fn scratch(tag: &str) -> PathBuf {
    std::env::temp_dir().join(format!("grainline-cad-edits-{tag}-{}", std::process::id()))
}

/// The index of the first face of `part` that `pick` accepts.
fn face_where(part: &CadPart, pick: impl Fn(&AnalyticFace) -> bool) -> usize {
    part.faces.iter().position(pick).expect("the part has that face")
}

#[test]
fn a_bend_and_a_curve_land_on_a_flat_face() {
    let plate = cad::plate(&Default::default()).unwrap();
    let top =
        face_where(&plate, |f| matches!(f, AnalyticFace::Plane { normal, .. } if normal.z > 0.999));
    edits_land(&plate, top, "plate-top");
}

#[test]
fn a_bend_and_a_curve_land_on_a_tangent_fillet() {
    let housing = cad::housing(&Default::default()).unwrap();
    let fillet = face_where(
        &housing,
        |f| matches!(f, AnalyticFace::Cylinder { axis_dir, radius, .. } if axis_dir.z.abs() > 0.999 && (radius - 8.0).abs() < 1e-9),
    );
    edits_land(&housing, fillet, "housing-fillet");
}

#[test]
fn a_bend_and_a_curve_land_on_a_cylinder() {
    let turned = cad::turned(&Default::default()).unwrap();
    let collar = face_where(
        &turned,
        |f| matches!(f, AnalyticFace::Cylinder { radius, .. } if (radius - 20.0).abs() < 1e-9),
    );
    edits_land(&turned, collar, "turned-collar");
}

/// A geodesic brush stops at a sharp edge: a bend on the housing's top whose ball reaches over
/// the 90° edge onto the front wall leaves every vertex of the wall (its own and those the
/// refinement adds there) with the world grain projected onto the wall's plane; the same bend
/// measured in straight lines (`metric: "euclidean"`) reaches the wall and turns it.
#[test]
fn a_geodesic_brush_stops_at_a_sharp_edge() {
    let housing = cad::housing(&Default::default()).unwrap();
    // The top (z = 40) 3 mm in from the front wall (y = −40), with a 6 mm brush.
    let (p0, r) = ([-30.0, -37.0, 40.0], 6.0);
    let (u, l) = (grain([0.0, 0.0, 1.0], WORLD), unit([0.3, -0.5, 1.0]));
    let eye = eye_on_highlight(p0, u, l, 300.0);
    let wall = grain([0.0, -1.0, 0.0], WORLD);
    let wall_turn = |metric: &str| {
        let dir = scratch(&format!("edge-{metric}"));
        let edits = serde_json::json!([{"tool": "bend", "centre": {"point": p0}, "radius": r,
                                        "strength": 0.8, "direction": u, "metric": metric}]);
        let report = run(&housing, &dir, eye, p0, l, edits, 1.0);
        let support = report["optimize"]["edited_vertices"].as_u64().unwrap();
        let f: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("FIELD.json")).unwrap()).unwrap();
        let v3 = |x: &serde_json::Value| [0, 1, 2].map(|k| x[k].as_f64().unwrap());
        let (pos, nrm, us) = (
            f["position"].as_array().unwrap(),
            f["normal"].as_array().unwrap(),
            f["u"].as_array().unwrap(),
        );
        let mut worst: f64 = 0.0;
        let mut count = 0;
        for i in 0..us.len() {
            let (p, n) = (v3(&pos[i]), v3(&nrm[i]));
            if (p[1] + 40.0).abs() < 1e-9
                && angle_deg(n, [0.0, -1.0, 0.0], false) < 1e-3
                && norm(sub(p, p0)) < 2.0 * r
            {
                count += 1;
                worst = worst.max(angle_deg(v3(&us[i]), wall, true));
            }
        }
        std::fs::remove_dir_all(&dir).ok();
        (worst, count, support)
    };
    let (geodesic, n_wall, s_geo) = wall_turn("geodesic");
    let (euclidean, _, s_euc) = wall_turn("euclidean");
    eprintln!(
        "the wall's grain near the brush: {geodesic}° off (geodesic, support {s_geo}), \
         {euclidean}° off (euclidean, support {s_euc}); {n_wall} wall vertices"
    );
    assert!(n_wall > 10, "the refinement put no vertex on the wall near the brush");
    assert!(geodesic < 1e-3, "a geodesic brush turned the wall's grain by {geodesic}°");
    // The straight-line ball does reach the wall: its support holds the wall's vertices too.
    assert!(s_euc > s_geo, "supports: {s_euc} (euclidean) ≤ {s_geo} (geodesic)");
}
