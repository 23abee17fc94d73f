//! CAD parts as CAD systems export them: an ASCII STL plate with a hole, no UVs, its flat
//! faces triangulated from rim to rim (slivers fanned from the hole to the plate's corners),
//! every vertex on a sharp edge. With `field.init: "world"` and no edit, the truth is analytic
//! (computed here, not by grainline): on the top face the grain is the world direction
//! projected onto the plane, exactly; on a side that faces the world direction, the world
//! axis least aligned with it; the strokes on the top run straight along it; the glb's
//! normals on the top are the plane's.

use std::f64::consts::PI;
use std::path::Path;
use std::process::Command;

#[path = "support/cad_truth.rs"]
mod cad_truth;

const W: f64 = 100.0;
const H: f64 = 60.0;
const T: f64 = 10.0;
const HOLE: (f64, f64, f64) = (50.0, 30.0, 10.0);
const SEGMENTS: usize = 32;

type P = [f64; 3];

/// The plate's triangles, outward, as a CAD export fans them.
fn plate() -> Vec<[P; 3]> {
    let corners = [[0.0, 0.0], [W, 0.0], [W, H], [0.0, H]];
    let hole: Vec<[f64; 2]> = (0..SEGMENTS)
        .map(|i| {
            // Half a step off the axes, so no rim vertex lies on a fan's boundary.
            let a = -PI + (i as f64 + 0.5) * 2.0 * PI / SEGMENTS as f64;
            [HOLE.0 + HOLE.2 * a.cos(), HOLE.1 + HOLE.2 * a.sin()]
        })
        .collect();
    // The corner each rim vertex fans to (0: bottom-left … 3: top-left): the one of its
    // quadrant about the hole's centre, which sees it from outside.
    let quadrant = |p: [f64; 2]| {
        let a = (p[1] - HOLE.1).atan2(p[0] - HOLE.0);
        ((a + PI) / (0.5 * PI)) as usize % 4
    };
    let mut top: Vec<[[f64; 2]; 3]> = Vec::new();
    for i in 0..SEGMENTS {
        let (a, b) = (hole[i], hole[(i + 1) % SEGMENTS]);
        let (qa, qb) = (quadrant(a), quadrant(b));
        top.push([b, a, corners[qa]]);
        if qa != qb {
            top.push([corners[qa], corners[qb], b]);
        }
    }
    let mut tris = Vec::new();
    for t in &top {
        tris.push(t.map(|p| [p[0], p[1], T]));
        tris.push([t[0], t[2], t[1]].map(|p| [p[0], p[1], 0.0]));
    }
    let quad = |tris: &mut Vec<[P; 3]>, a: P, b: P, c: P, d: P| {
        tris.push([a, b, c]);
        tris.push([a, c, d]);
    };
    for k in 0..4 {
        let (p, q) = (corners[k], corners[(k + 1) % 4]);
        quad(&mut tris, [p[0], p[1], 0.0], [q[0], q[1], 0.0], [q[0], q[1], T], [p[0], p[1], T]);
    }
    for i in 0..SEGMENTS {
        let (p, q) = (hole[i], hole[(i + 1) % SEGMENTS]);
        // The hole's wall faces its axis.
        quad(&mut tris, [q[0], q[1], 0.0], [p[0], p[1], 0.0], [p[0], p[1], T], [q[0], q[1], T]);
    }
    tris
}

fn write_stl(path: &Path, tris: &[[P; 3]]) {
    let mut s = String::from("solid plate\n");
    for t in tris {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for p in t {
            s += &format!("      vertex {} {} {}\n", p[0] as f32, p[1] as f32, p[2] as f32);
        }
        s += "    endloop\n  endfacet\n";
    }
    s += "endsolid plate\n";
    std::fs::write(path, s).unwrap();
}

fn vec3(v: &serde_json::Value) -> [f64; 3] {
    [0, 1, 2].map(|k| v[k].as_f64().unwrap())
}

fn angle_deg(a: [f64; 3], b: [f64; 3], line: bool) -> f64 {
    let n = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (n(a) * n(b));
    let c = if line { c.abs() } else { c };
    c.clamp(-1.0, 1.0).acos().to_degrees()
}

/// Runs `scene` from `dir`; returns its FIELD.json (`field.output`).
fn run_for_field(dir: &Path, scene: &str) -> serde_json::Value {
    std::fs::write(dir.join("scene.json"), scene).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(dir.join("scene.json"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&std::fs::read(dir.join("FIELD.json")).unwrap()).unwrap()
}

/// Runs the plate's scene; returns the directory with its outputs.
fn run_plate(name: &str, patches: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("grainline-cad-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_stl(&dir.join("plate.stl"), &plate());
    let scene = format!(
        r#"{{"mesh": {{"path": "plate.stl", "patches": "{patches}"}}, "units": "mm",
            "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
            "view": {{"eye": [50, -150, 200], "target": [50, 30, 5]}},
            "field": {{"init": "world", "world": [0, 1, 0], "output": "FIELD.json"}},
            "toolpaths": {{"strokes_json": "strokes.json", "placement": {{"width": 4}}}},
            "export": {{"glb": "plate.glb"}}}}"#
    );
    std::fs::write(dir.join("scene.json"), scene).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(dir.join("scene.json"))
        .arg("--report")
        .arg(dir.join("report.json"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    dir
}

#[test]
fn a_plates_flat_faces_carry_the_projected_world_grain_exactly() {
    let dir = run_plate("field", "split");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
    // Top, bottom, four sides and the hole's wall.
    assert_eq!(report["patches"]["patches"], 7, "{}", report["patches"]);
    let f: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("FIELD.json")).unwrap()).unwrap();
    let (pos, nrm, u) = (
        f["position"].as_array().unwrap(),
        f["normal"].as_array().unwrap(),
        f["u"].as_array().unwrap(),
    );
    let (mut top, mut front) = (0, 0);
    for i in 0..u.len() {
        let (p, n, u) = (vec3(&pos[i]), vec3(&nrm[i]), vec3(&u[i]));
        if (p[2] - T).abs() < 1e-4 && angle_deg(n, [0.0, 0.0, 1.0], false) < 1e-3 {
            top += 1;
            // The world direction (0, 1, 0) lies in the plane: the grain is it.
            assert!(angle_deg(u, [0.0, 1.0, 0.0], true) < 1e-3, "top vertex {i}: u {u:?}");
        }
        if p[1].abs() < 1e-4 && angle_deg(n, [0.0, -1.0, 0.0], false) < 1e-3 {
            front += 1;
            // The side faces the world direction: the grain runs along x.
            assert!(angle_deg(u, [1.0, 0.0, 0.0], true) < 1e-3, "front vertex {i}: u {u:?}");
        }
    }
    // Every vertex of the top face (4 corners + the hole's rim) has the plane's normal.
    assert_eq!(top, 4 + SEGMENTS);
    assert_eq!(front, 4);
    std::fs::remove_dir_all(&dir).ok();
}

/// The share of the strokes' length on the top face that runs within 1° of the world
/// direction.
fn straight_share(dir: &Path) -> f64 {
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("strokes.json")).unwrap()).unwrap();
    let (mut straight, mut total) = (0.0, 0.0);
    for stroke in s["strokes"].as_array().unwrap() {
        // Each stroke is a list of polylines on the part.
        for piece in stroke["xyz"].as_array().unwrap() {
            let xyz: Vec<[f64; 3]> = piece.as_array().unwrap().iter().map(vec3).collect();
            for w in xyz.windows(2) {
                let on_top = (w[0][2] - T).abs() < 1e-3 && (w[1][2] - T).abs() < 1e-3;
                let d = [w[1][0] - w[0][0], w[1][1] - w[0][1], w[1][2] - w[0][2]];
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if on_top && len > 0.0 {
                    total += len;
                    if angle_deg(d, [0.0, 1.0, 0.0], true) < 1.0 {
                        straight += len;
                    }
                }
            }
        }
    }
    assert!(total > 0.0, "no stroke on the top face");
    eprintln!(
        "{}: {:.1} % of {total:.0} mm on the top within 1°",
        dir.display(),
        100.0 * straight / total
    );
    straight / total
}

#[test]
fn strokes_on_the_plates_top_run_straight_along_the_grain() {
    let dir = run_plate("strokes", "split");
    let share = straight_share(&dir);
    assert!(share >= 0.99, "{:.1} % of the top's strokes within 1° of y", 100.0 * share);
    std::fs::remove_dir_all(&dir).ok();
    // Kept whole, the rim's normals average across the 90° edges and the grain wanders: the
    // split is what makes the top straight.
    let dir = run_plate("whole", "none");
    let share = straight_share(&dir);
    assert!(share < 0.9, "{:.1} % straight without patches", 100.0 * share);
    std::fs::remove_dir_all(&dir).ok();
}

/// The share of the top face's area, in the glb, whose three corners carry the plane's normal
/// (within 1°) and the grain (within 0.5°, read from the `anisotropyTexture` as a viewer does:
/// `cad_truth::glb_grain`). The buffers are in the part's coordinates (the node's transform
/// turns them to glTF's +Y up).
fn glb_flat_share(dir: &Path) -> f64 {
    let cad_truth::GlbGrain { p, n, u, idx } = cad_truth::glb_grain(&dir.join("plate.glb"));
    let d = |v: [f32; 3]| v.map(f64::from);
    let (mut good, mut total) = (0.0, 0.0);
    for tri in idx.chunks(3) {
        let q: Vec<[f64; 3]> = tri.iter().map(|&i| d(p[i as usize])).collect();
        if q.iter().any(|v| (v[2] - T).abs() > 1e-3) {
            continue;
        }
        let (a, b) =
            ([q[1][0] - q[0][0], q[1][1] - q[0][1]], [q[2][0] - q[0][0], q[2][1] - q[0][1]]);
        let area = 0.5 * (a[0] * b[1] - a[1] * b[0]).abs();
        total += area;
        let ok = tri.iter().all(|&i| {
            angle_deg(d(n[i as usize]), [0.0, 0.0, 1.0], false) < 1.0
                && angle_deg(u[i as usize], [0.0, 1.0, 0.0], true) < 0.5
        });
        if ok {
            good += area;
        }
    }
    assert!(total > 0.0);
    good / total
}

#[test]
fn the_glb_carries_the_plates_normal_and_grain_on_its_top() {
    let dir = run_plate("glb", "split");
    let share = glb_flat_share(&dir);
    eprintln!("glb: {:.1} % of the top's area flat and along the grain", 100.0 * share);
    assert!(share >= 0.99, "{:.1} %", 100.0 * share);
    std::fs::remove_dir_all(&dir).ok();
    let dir = run_plate("glb-whole", "none");
    let share = glb_flat_share(&dir);
    eprintln!("glb, kept whole: {:.1} %", 100.0 * share);
    assert!(share < 0.5, "{:.1} % without patches", 100.0 * share);
    std::fs::remove_dir_all(&dir).ok();
}

/// `field.init: "smooth"` on the plate: on each flat face the smoothest field is one
/// direction, holes or not (a parallel field has zero Dirichlet energy on a plane, and the
/// patches do not couple the faces).
#[test]
fn the_smoothest_field_on_a_flat_face_with_a_hole_is_parallel() {
    let dir = std::env::temp_dir().join(format!("grainline-cad-smooth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_stl(&dir.join("plate.stl"), &plate());
    let scene = r#"{"mesh": "plate.stl", "units": "mm",
        "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
        "view": {"eye": [50, -150, 200], "target": [50, 30, 5]},
        "field": {"init": "smooth", "output": "FIELD.json"}}"#;
    let f = run_for_field(&dir, scene);
    let (pos, nrm, u) = (
        f["position"].as_array().unwrap(),
        f["normal"].as_array().unwrap(),
        f["u"].as_array().unwrap(),
    );
    for (z, nz) in [(T, 1.0), (0.0, -1.0)] {
        let on: Vec<[f64; 3]> = (0..u.len())
            .filter(|&i| {
                (vec3(&pos[i])[2] - z).abs() < 1e-4
                    && angle_deg(vec3(&nrm[i]), [0.0, 0.0, nz], false) < 1e-3
            })
            .map(|i| vec3(&u[i]))
            .collect();
        assert_eq!(on.len(), 4 + SEGMENTS, "vertices of the face z = {z}");
        let spread = on.iter().map(|v| angle_deg(*v, on[0], true)).fold(0.0, f64::max);
        assert!(spread < 0.01, "face z = {z}: the grain turns by {spread}°");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A round bar as CAD writes it (the side as 40 strips of two triangles, the end disks fanned
/// from one rim vertex): with `field.init: "world"` every vertex of the side carries the world
/// direction projected onto the cylinder's tangent plane there, w − (w·n)n with n radial.
#[test]
fn a_world_grain_on_a_cylinder_is_the_analytic_projection() {
    const R: f64 = 12.5;
    const L: f64 = 80.0;
    const N: usize = 40;
    let ring: Vec<[f64; 2]> = (0..N)
        .map(|i| {
            let a = 2.0 * PI * i as f64 / N as f64;
            [R * a.cos(), R * a.sin()]
        })
        .collect();
    let mut tris: Vec<[P; 3]> = Vec::new();
    for i in 0..N {
        let (p, q) = (ring[i], ring[(i + 1) % N]);
        tris.push([[p[0], p[1], 0.0], [q[0], q[1], 0.0], [q[0], q[1], L]]);
        tris.push([[p[0], p[1], 0.0], [q[0], q[1], L], [p[0], p[1], L]]);
    }
    for i in 1..N - 1 {
        let (a, b, c) = (ring[0], ring[i], ring[i + 1]);
        tris.push([[a[0], a[1], L], [b[0], b[1], L], [c[0], c[1], L]]);
        tris.push([[a[0], a[1], 0.0], [c[0], c[1], 0.0], [b[0], b[1], 0.0]]);
    }
    let dir = std::env::temp_dir().join(format!("grainline-cad-bar-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_stl(&dir.join("bar.stl"), &tris);
    let w = [0.3, 0.4, 1.0];
    let scene = format!(
        r#"{{"mesh": "bar.stl", "units": "mm",
            "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
            "view": {{"eye": [0, -200, 40], "target": [0, 0, 40]}},
            "field": {{"init": "world", "world": [{}, {}, {}], "output": "FIELD.json"}}}}"#,
        w[0], w[1], w[2]
    );
    let f = run_for_field(&dir, &scene);
    let (pos, nrm, u) = (
        f["position"].as_array().unwrap(),
        f["normal"].as_array().unwrap(),
        f["u"].as_array().unwrap(),
    );
    let mut side = 0;
    for i in 0..u.len() {
        let (p, n) = (vec3(&pos[i]), vec3(&nrm[i]));
        let radial = [p[0] / R, p[1] / R, 0.0];
        if angle_deg(n, radial, false) > 45.0 {
            continue; // an end disk's copy of a rim vertex
        }
        side += 1;
        assert!(angle_deg(n, radial, false) < 1e-3, "vertex {i}: normal {n:?}");
        let s = w[0] * radial[0] + w[1] * radial[1];
        let expected = [w[0] - s * radial[0], w[1] - s * radial[1], w[2]];
        let off = angle_deg(vec3(&u[i]), expected, true);
        assert!(off < 1e-3, "vertex {i} at {p:?}: the grain is {off}° off the projection");
    }
    assert_eq!(side, 2 * N);
    std::fs::remove_dir_all(&dir).ok();
}
