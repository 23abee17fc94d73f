//! Boundary first flattening (`toolpaths.layout.method = "bff"`, issue 14 item 5; math.md
//! §11.6): parts whose flattening is known from outside the code.
//!
//! * A flat disk has zero angle defects, so BFF's target boundary is the boundary itself and
//!   the (cotan, linearly precise) extension reproduces the part up to a rigid motion and the
//!   layout's scale.
//! * A developable sheet is flat in its intrinsic metric: the same holds.
//! * A spherical cap is flattened conformally; with u = 0 on the boundary its rim keeps its
//!   length, and by symmetry the image of a rotationally symmetric cap is a round disk.
//! * A chart that is not a disk falls back (to LSCM), counted, without a panic.
//!
//! Lengths, areas and angles are recomputed here from the positions and the UVs.

use std::f64::consts::{PI, TAU};
use std::path::PathBuf;
use std::process::Command;

use grainline::generate::Grid;
use grainline::layout::{flatten, Layout, LayoutOptions, Method};
use grainline::mesh::load::{load_obj, LoadOptions};
use grainline::mesh::{CornerAttribute, Mesh};
use nalgebra::{Matrix2, Vector2, Vector3};

fn options(method: Method) -> LayoutOptions {
    LayoutOptions { method, ..LayoutOptions::default() }
}

fn uv_area(q: [Vector2<f64>; 3]) -> f64 {
    0.5 * (q[1] - q[0]).perp(&(q[2] - q[0]))
}

/// The scale that makes the UV area the surface area, computed here.
fn area_scale(mesh: &Mesh, uv: &CornerAttribute<Vector2<f64>>) -> f64 {
    let a2: f64 = (0..mesh.num_faces()).map(|f| uv_area(uv.face(f)).abs()).sum();
    (mesh.area() / a2).sqrt()
}

/// Largest |s ℓ_uv − ℓ| / ℓ over every edge of every face (s the area scale).
fn max_edge_error(mesh: &Mesh, uv: &CornerAttribute<Vector2<f64>>) -> f64 {
    let s = area_scale(mesh, uv);
    let mut worst = 0.0f64;
    for f in 0..mesh.num_faces() {
        let (p, q) = (mesh.face_positions(f), uv.face(f));
        for c in 0..3 {
            let l3 = (p[(c + 1) % 3] - p[c]).norm();
            worst = worst.max((s * (q[(c + 1) % 3] - q[c]).norm() - l3).abs() / l3);
        }
    }
    worst
}

/// Per face: area factor σ₁σ₂ (after the area scale) and angle distortion σ₁/σ₂, from the
/// first fundamental form of the map UV → 3D; and the face's 3D area.
fn face_factors(mesh: &Mesh, layout: &Layout) -> Vec<(f64, f64, f64)> {
    let s = area_scale(mesh, &layout.uv);
    (0..mesh.num_faces())
        .map(|f| {
            let p = mesh.face_positions(f);
            let q = layout.uv.face(f).map(|v| v * s);
            let a3 = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            let e = Matrix2::from_columns(&[q[1] - q[0], q[2] - q[0]]);
            let inv = e.try_inverse().expect("a UV triangle is degenerate");
            let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
            let x_u = e1 * inv[(0, 0)] + e2 * inv[(1, 0)];
            let x_v = e1 * inv[(0, 1)] + e2 * inv[(1, 1)];
            let (ee, ff, gg) = (x_u.dot(&x_u), x_u.dot(&x_v), x_v.dot(&x_v));
            let (tr, disc) = (ee + gg, ((ee - gg).powi(2) + 4.0 * ff * ff).sqrt());
            (uv_area(q) / a3, ((tr + disc) / (tr - disc)).sqrt(), a3)
        })
        .collect()
}

/// Area-weighted mean angle distortion σ₁/σ₂ and the spread max/min of the area factor.
fn distortion(mesh: &Mesh, layout: &Layout) -> (f64, f64) {
    let f = face_factors(mesh, layout);
    let area: f64 = f.iter().map(|x| x.2).sum();
    let mean = f.iter().map(|x| x.1 * x.2).sum::<f64>() / area;
    let (lo, hi) = f.iter().fold((f64::MAX, 0.0f64), |(lo, hi), x| (lo.min(x.0), hi.max(x.0)));
    (mean, hi / lo)
}

fn assert_positive(name: &str, mesh: &Mesh, uv: &CornerAttribute<Vector2<f64>>) {
    for f in 0..mesh.num_faces() {
        let a = uv_area(uv.face(f));
        assert!(a > 0.0, "{name}: face {f} flipped or degenerate in UV ({a})");
        assert!(uv.face(f).iter().all(|p| p.x.is_finite() && p.y.is_finite()), "{name}: NaN");
    }
}

/// A disk of `rings` rings (6k vertices on ring k, a centre vertex), the ring of radius k/rings
/// mapped by `map(radius, angle)`; triangles counter-clockwise in (radius, angle).
fn ring_disk(rings: usize, map: impl Fn(f64, f64) -> Vector3<f64>) -> Mesh {
    let mut positions = vec![map(0.0, 0.0)];
    let mut ring_ids: Vec<Vec<u32>> = vec![vec![0]];
    for k in 1..=rings {
        let n = 6 * k;
        let ids = (0..n)
            .map(|j| {
                positions.push(map(k as f64 / rings as f64, TAU * j as f64 / n as f64));
                (positions.len() - 1) as u32
            })
            .collect();
        ring_ids.push(ids);
    }
    let mut faces = Vec::new();
    for k in 1..=rings {
        let (inner, outer) = (&ring_ids[k - 1], &ring_ids[k]);
        let (ni, no) = (inner.len(), outer.len());
        if ni == 1 {
            faces.extend((0..no).map(|j| [inner[0], outer[j], outer[(j + 1) % no]]));
            continue;
        }
        // Walk both rings by angle, always advancing the one whose next vertex comes first.
        let (mut i, mut j) = (0, 0);
        while i < ni || j < no {
            let outer_first = (j + 1) as f64 / no as f64 <= (i + 1) as f64 / ni as f64;
            if j < no && (i == ni || outer_first) {
                faces.push([inner[i % ni], outer[j], outer[(j + 1) % no]]);
                j += 1;
            } else {
                faces.push([inner[i], outer[j % no], inner[(i + 1) % ni]]);
                i += 1;
            }
        }
    }
    Mesh::from_triangles(positions, faces)
}

/// A flat, irregular disk: rings jittered in radius and angle, then a smooth injective warp of
/// the plane (Jacobian determinant ≥ 0.74 on the unit disk).
fn flat_disk() -> Mesh {
    ring_disk(12, |r, a| {
        let jr = if r > 0.0 && r < 1.0 { 0.02 * (7.0 * a + 13.0 * r).sin() } else { 0.0 };
        let ja = if r > 0.0 { 0.03 * (5.0 * r + 3.0 * a).cos() / (1.0 + 12.0 * r) } else { 0.0 };
        let (x, y) = ((r + jr) * (a + ja).cos(), (r + jr) * (a + ja).sin());
        Vector3::new(10.0 * (x + 0.15 * y * y), 10.0 * y * (1.0 + 0.2 * x), 0.0)
    })
}

/// A spherical cap of radius `radius` and polar angle `theta_max`, `rings` rings of equal polar
/// angle.
fn cap(rings: usize, theta_max: f64, radius: f64) -> Mesh {
    ring_disk(rings, |r, a| {
        let t = r * theta_max;
        radius * Vector3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos())
    })
}

#[test]
fn the_ring_disk_is_a_disk_of_positive_triangles() {
    let m = ring_disk(12, |r, a| Vector3::new(r * a.cos(), r * a.sin(), 0.0));
    let v = m.num_vertices() as i64;
    let f = m.num_faces() as i64;
    assert_eq!(v, 1 + 3 * 12 * 13);
    // A disk: V − E + F = 1 with E = (3F + boundary) / 2, boundary = 72 edges.
    assert_eq!(v - (3 * f + 72) / 2 + f, 1);
    for t in &m.faces {
        let p = t.map(|i| m.positions[i as usize]);
        assert!((p[1] - p[0]).cross(&(p[2] - p[0])).z > 0.0, "{t:?}");
    }
}

#[test]
fn a_flat_disk_comes_back_isometric() {
    let mesh = flat_disk();
    let l = flatten(&mesh, &options(Method::Bff)).unwrap();
    assert_eq!(l.report.charts, 1);
    assert_eq!(l.report.bff_fallbacks, 0, "BFF itself made the chart");
    assert_positive("flat disk", &mesh, &l.uv);
    let e = max_edge_error(&mesh, &l.uv);
    assert!(e < 1e-6, "an edge length changes by {e} (relative)");
}

/// A half cylinder (R = 20, H = 30), 24 × 10 cells.
fn half_cylinder() -> Mesh {
    let mut m = Grid::new(24, 10).build(|s, t| {
        let a = PI * s;
        Vector3::new(20.0 * a.cos(), 20.0 * a.sin(), 30.0 * t)
    });
    m.uv = None;
    m
}

#[test]
fn developable_sheets_flatten_isometrically() {
    let mut meshes = vec![("half cylinder", half_cylinder())];
    let shared = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let paper = shared.join("meshes/paper-crumpled2.obj");
    if paper.exists() {
        meshes.push(("paper-crumpled2", load_obj(&paper, &LoadOptions::default()).unwrap().mesh));
    } else {
        eprintln!("skipping paper-crumpled2: {} not found", paper.display());
    }
    for (name, mesh) in meshes {
        let l = flatten(&mesh, &options(Method::Bff)).unwrap();
        assert_eq!(l.report.charts, 1, "{name}: a developable disk is one chart");
        assert_eq!(l.report.bff_fallbacks, 0, "{name}");
        assert_positive(name, &mesh, &l.uv);
        let e = max_edge_error(&mesh, &l.uv);
        assert!(e < 1e-3, "{name}: an edge length changes by {e} (relative)");
    }
}

/// The UV rim of a cap (the ring-disk's last `6 rings` vertices) at the layout's area scale.
fn rim(mesh: &Mesh, l: &Layout, rings: usize) -> Vec<Vector2<f64>> {
    let s = area_scale(mesh, &l.uv);
    let first = mesh.num_vertices() - 6 * rings;
    let mut at = vec![Vector2::zeros(); mesh.num_vertices()];
    for f in 0..mesh.num_faces() {
        for (c, &v) in mesh.faces[f].iter().enumerate() {
            at[v as usize] = l.uv.face(f)[c] * s;
        }
    }
    at[first..].to_vec()
}

#[test]
fn a_spherical_cap_flattens_conformally_into_a_round_disk() {
    let (radius, theta) = (10.0, 70f64.to_radians());
    let mesh = cap(14, theta, radius);
    let bff = flatten(&mesh, &options(Method::Bff)).unwrap();
    let lscm = flatten(&mesh, &options(Method::Lscm)).unwrap();
    assert_eq!((bff.report.charts, bff.report.bff_fallbacks), (1, 0));
    assert_eq!(bff.report.flipped_faces, 0);
    assert_positive("cap (bff)", &mesh, &bff.uv);
    let (b_angle, b_area) = distortion(&mesh, &bff);
    let (l_angle, l_area) = distortion(&mesh, &lscm);
    eprintln!("cap 70°: angle distortion mean BFF {b_angle:.5}, LSCM {l_angle:.5}; area factor spread BFF {b_area:.4}, LSCM {l_area:.4}");
    // A piecewise-linear map of a curved mesh cannot be conformal on every triangle: the
    // figure is a discretization error, as large as LSCM's (which minimizes the conformal
    // energy over all maps), and it falls at least as fast as the edge length h when the cap is
    // refined (first order: halved with h; 0.6 leaves room for the rim's coarser angles).
    assert!(b_angle < 1.05, "BFF is conformal: mean σ₁/σ₂ {b_angle}");
    assert!(b_angle <= l_angle + 2e-3, "BFF {b_angle} vs LSCM {l_angle}");
    let fine = cap(28, theta, radius);
    let (f_angle, _) = distortion(&fine, &flatten(&fine, &options(Method::Bff)).unwrap());
    eprintln!("cap 70°, 28 rings: angle distortion mean BFF {f_angle:.5}");
    assert!(f_angle - 1.0 < 0.6 * (b_angle - 1.0), "refined: {f_angle} vs {b_angle}");
    // The smooth map is a rotationally symmetric conformal map onto a disk: the stereographic
    // projection, area factor ∝ 4/(1 + tan²(θ/2))², so areas spread by sec⁴(θ_max/2) between
    // pole and rim (allow 10 % for the discretization).
    let bound = 1.1 / (0.5 * theta).cos().powi(4);
    assert!(b_area < bound, "area factor spread {b_area}, bound {bound}");
    // A round image: every rim vertex at the same distance from the rim's centroid (1 %).
    let r = rim(&mesh, &bff, 14);
    let c: Vector2<f64> = r.iter().sum::<Vector2<f64>>() / r.len() as f64;
    let d: Vec<f64> = r.iter().map(|p| (p - c).norm()).collect();
    let (lo, hi) = d.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    assert!(hi / lo < 1.01, "rim radii from {lo} to {hi}");
    // u = 0 on the boundary: the rim keeps its 3D length ℓ_rim. The flat disk bounded by it
    // has area ℓ_rim² / 4π, and the layout scales the chart to the cap's area A, so the rim
    // comes out √(4π A) / ℓ_rim times its 3D length.
    let rim_uv: f64 = (0..r.len()).map(|k| (r[(k + 1) % r.len()] - r[k]).norm()).sum();
    let first = mesh.num_vertices() - 6 * 14;
    let p = &mesh.positions[first..];
    let rim_3d: f64 = (0..p.len()).map(|k| (p[(k + 1) % p.len()] - p[k]).norm()).sum();
    let want = (4.0 * PI * mesh.area()).sqrt() / rim_3d;
    let got = rim_uv / rim_3d;
    assert!((got - want).abs() < 0.01 * want, "rim scaled by {got}, expected {want}");
}

#[test]
fn charts_that_are_not_disks_fall_back_without_panic() {
    // A flat annulus: planar with one hole, flattened as it is, by LSCM.
    let annulus = Grid { closed_s: true, ..Grid::new(32, 4) }.build(|s, t| {
        let (a, r) = (TAU * s, 5.0 + 3.0 * t);
        Vector3::new(r * a.cos(), r * a.sin(), 0.0)
    });
    let l = flatten(&annulus, &options(Method::Bff)).unwrap();
    assert_eq!(l.report.charts, 1);
    assert!(l.report.bff_not_disk >= 1 && l.report.bff_fallbacks >= l.report.bff_not_disk);
    assert_positive("annulus", &annulus, &l.uv);
    assert!(max_edge_error(&annulus, &l.uv) < 1e-6, "LSCM keeps a flat annulus");
    // A closed sphere is cut into disks; every chart valid whatever the fallbacks.
    let sphere = grainline::generate::icosphere(10.0, 3);
    let l = flatten(&sphere, &options(Method::Bff)).unwrap();
    assert!(l.report.charts > 1);
    assert_eq!(l.report.flipped_faces, 0);
    assert_positive("sphere", &sphere, &l.uv);
}

#[test]
fn flatten_command_takes_method_bff() {
    let dir = std::env::temp_dir().join(format!("grainline-bff-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = cap(10, 60f64.to_radians(), 10.0);
    let input = dir.join("cap.obj");
    std::fs::write(&input, grainline::mesh::write::obj_string(&mesh, "cap")).unwrap();
    let (out, report) = (dir.join("cap-uv.obj"), dir.join("cap.json"));
    let o = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "flatten"])
        .arg(&input)
        .args(["--method", "bff", "--out"])
        .arg(&out)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(r["layout"]["method"], "bff");
    assert_eq!(r["layout"]["bff_fallbacks"], 0);
    let back = load_obj(&out, &LoadOptions::default()).unwrap().mesh;
    assert_positive("cap from the OBJ", &back, back.uv.as_ref().expect("vt"));
    std::fs::remove_dir_all(&dir).ok();
}
