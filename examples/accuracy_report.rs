//! What accuracy costs in time: writes `docs/accuracy-vs-time.md` and its plots
//! (`docs/img/accuracy-*.svg`), every figure measured against an analytic truth.
//!
//! ```text
//! cargo run --release --example accuracy_report [-- --quick]
//! ```
//!
//! 1. Mesh resolution against the angle error of ℓ (Eq. 7) on a quadric patch, where the exact
//!    ℓ = n × ∇_S(hᵀu) of the smooth surface is known, and the time of geometry + ℓ.
//! 2. Solver iterations and stopping tolerance against the residual energy, the angle error
//!    against the known field, and the time (recovery of a perturbed field, math.md §3).
//! 3. Integration tolerance against the streamline error on an annulus (circles known), and
//!    stroke spacing against coverage and time.
//! 4. Preview supersampling against the image error relative to a high-sample reference.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use grainline::generate::{self, Grid, GridPattern};
use grainline::geometry::connection::wrap_angle;
use grainline::geometry::{Geometry, GeometryOptions, GradientForm};
use grainline::highlight::{highlight_field, initial_field, InitialField, Symmetry};
use grainline::solve::{solve, HighlightTerm, LmOptions};
use nalgebra::{Matrix2, Vector2, Vector3};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs `f` `reps` times; returns the last result and the median seconds.
fn timed<T>(reps: usize, mut f: impl FnMut() -> T) -> (T, f64) {
    let mut times = Vec::new();
    let mut out = None;
    for _ in 0..reps {
        let t = Instant::now();
        out = Some(f());
        times.push(t.elapsed().as_secs_f64());
    }
    (out.expect("reps > 0"), median(times))
}

// ---------------------------------------------------------------- analytic quadric truth

const C: [f64; 3] = [0.8, -0.3, 0.5];
const AB: (f64, f64) = (0.9, 0.5);

fn slope(x: f64, y: f64) -> (f64, f64) {
    (C[0] * x + C[1] * y, C[1] * x + C[2] * y)
}

fn grain(x: f64, y: f64) -> Vector3<f64> {
    let th = AB.0 * x + AB.1 * y;
    let (zx, zy) = slope(x, y);
    let n = Vector3::new(-zx, -zy, 1.0).normalize();
    let w = Vector3::new(th.cos(), th.sin(), 0.0);
    (w - n * n.dot(&w)).normalize()
}

/// ℓ = n × ∇_S(hᵀu) of the smooth surface (math.md §1).
fn exact_ell(h: &Vector3<f64>, x: f64, y: f64) -> Vector3<f64> {
    let f = |x: f64, y: f64| h.dot(&grain(x, y));
    let e = 1e-5;
    let (fx, fy) =
        ((f(x + e, y) - f(x - e, y)) / (2.0 * e), (f(x, y + e) - f(x, y - e)) / (2.0 * e));
    let (zx, zy) = slope(x, y);
    let (xx, xy) = (Vector3::new(1.0, 0.0, zx), Vector3::new(0.0, 1.0, zy));
    let g = Matrix2::new(xx.dot(&xx), xx.dot(&xy), xy.dot(&xx), xy.dot(&xy));
    let coef = g.try_inverse().expect("regular metric") * Vector2::new(fx, fy);
    Vector3::new(-zx, -zy, 1.0).normalize().cross(&(xx * coef.x + xy * coef.y))
}

fn line_angle(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b).abs())
}

struct Row {
    cells: Vec<String>,
}

fn table(out: &mut String, head: &[&str], rows: &[Row]) {
    let _ = writeln!(out, "| {} |", head.join(" | "));
    let _ = writeln!(out, "|{}|", head.iter().map(|_| "---").collect::<Vec<_>>().join("|"));
    for r in rows {
        let _ = writeln!(out, "| {} |", r.cells.join(" | "));
    }
    out.push('\n');
}

// ---------------------------------------------------------------- plots (SVG, log-log)

struct Series {
    name: String,
    points: Vec<(f64, f64)>,
}

fn plot(path: &Path, title: &str, xlabel: &str, ylabel: &str, series: &[Series]) {
    let (w, h, m) = (640.0, 400.0, 60.0);
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
        .collect();
    if all.is_empty() {
        return;
    }
    let lx: Vec<f64> = all.iter().map(|p| p.0.log10()).collect();
    let ly: Vec<f64> = all.iter().map(|p| p.1.log10()).collect();
    let (x0, x1) = (
        lx.iter().cloned().fold(f64::MAX, f64::min).floor(),
        lx.iter().cloned().fold(f64::MIN, f64::max).ceil(),
    );
    let (y0, y1) = (
        ly.iter().cloned().fold(f64::MAX, f64::min).floor(),
        ly.iter().cloned().fold(f64::MIN, f64::max).ceil(),
    );
    let (x1, y1) = (x1.max(x0 + 1.0), y1.max(y0 + 1.0));
    let px = |x: f64| m + (x.log10() - x0) / (x1 - x0) * (w - 2.0 * m);
    let py = |y: f64| h - m - (y.log10() - y0) / (y1 - y0) * (h - 2.0 * m);
    let colors = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"];
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">{title}</text>\n",
        w / 2.0
    );
    for d in x0 as i32..=x1 as i32 {
        let x = m + (d as f64 - x0) / (x1 - x0) * (w - 2.0 * m);
        let _ = writeln!(s, "<line x1=\"{x:.1}\" y1=\"{m}\" x2=\"{x:.1}\" y2=\"{}\" stroke=\"#ddd\"/><text x=\"{x:.1}\" y=\"{}\" text-anchor=\"middle\">1e{d}</text>", h - m, h - m + 16.0);
    }
    for d in y0 as i32..=y1 as i32 {
        let y = h - m - (d as f64 - y0) / (y1 - y0) * (h - 2.0 * m);
        let _ = writeln!(s, "<line x1=\"{m}\" y1=\"{y:.1}\" x2=\"{}\" y2=\"{y:.1}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">1e{d}</text>", w - m, m - 4.0, y + 4.0);
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{xlabel}</text>",
        w / 2.0,
        h - 12.0
    );
    let _ = writeln!(s, "<text x=\"14\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 14 {})\">{ylabel}</text>", h / 2.0, h / 2.0);
    for (k, ser) in series.iter().enumerate() {
        let c = colors[k % colors.len()];
        let pts: Vec<String> = ser
            .points
            .iter()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
            .map(|&(x, y)| format!("{:.1},{:.1}", px(x), py(y)))
            .collect();
        let _ = writeln!(
            s,
            "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"2\" points=\"{}\"/>",
            pts.join(" ")
        );
        for p in &pts {
            let (x, y) = p.split_once(',').expect("x,y");
            let _ = writeln!(s, "<circle cx=\"{x}\" cy=\"{y}\" r=\"3\" fill=\"{c}\"/>");
        }
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" fill=\"{c}\">{}</text>",
            w - m - 150.0,
            m + 16.0 * (k as f64 + 1.0),
            ser.name
        );
    }
    s.push_str("</svg>\n");
    grainline::output::write_atomic(path, s.as_bytes()).expect("write plot");
}

// ---------------------------------------------------------------- 1. mesh resolution

fn resolution(out: &mut String, img: &Path, quick: bool) {
    let h = Vector3::new(0.3, 0.4, 1.0).normalize();
    let ns: &[usize] = if quick { &[8, 16, 32, 64] } else { &[8, 16, 32, 64, 128, 256, 512] };
    let mut rows = Vec::new();
    let mut series = Vec::new();
    for (name, pattern) in [
        ("regular", GridPattern::Regular),
        ("jittered 0.2", GridPattern::Jittered { amount: 0.2, seed: 3 }),
    ] {
        let mut pts = Vec::new();
        for &n in ns {
            let mesh = generate::quadric_patch(C, 0.5, Grid { pattern, ..Grid::new(n, n) });
            let dirs: Vec<Vector3<f64>> = mesh.positions.iter().map(|p| grain(p.x, p.y)).collect();
            let reps = if n >= 256 { 3 } else { 5 };
            let ((g, ell), secs) = timed(reps, || {
                let g = Geometry::compute(&mesh, &GeometryOptions::default());
                let phi = initial_field(
                    &mesh,
                    &g,
                    &InitialField::Directions(dirs.clone()),
                    Symmetry::Oriented,
                )
                .expect("directions")
                .phi;
                let hs = vec![h; mesh.num_vertices()];
                let f = highlight_field(&g, &phi, Symmetry::Oriented, GradientForm::Angle, &hs);
                (g, f.ell)
            });
            let errs: Vec<f64> = (0..mesh.num_vertices())
                .filter(|&i| !g.adjacency.is_boundary_vertex(i))
                .map(|i| {
                    let p = mesh.positions[i];
                    line_angle(&ell[i], &exact_ell(&h, p.x, p.y)).to_degrees()
                })
                .collect();
            let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
            let max = errs.iter().cloned().fold(0.0, f64::max);
            rows.push(Row {
                cells: vec![
                    name.into(),
                    format!("{n}×{n}"),
                    mesh.num_vertices().to_string(),
                    format!("{rms:.2e}"),
                    format!("{max:.2e}"),
                    format!("{:.2}", secs * 1e3),
                ],
            });
            pts.push((secs, rms));
            eprintln!("resolution {name} n={n}: rms {rms:.2e}° in {:.1} ms", secs * 1e3);
        }
        series.push(Series { name: name.into(), points: pts });
    }
    let _ = writeln!(out, "## 1. Mesh resolution → angle error of ℓ (Eq. 7) and time\n");
    let _ = writeln!(out, "Quadric patch z = ½(0.8x² − 0.6xy + 0.5y²) on [−½, ½]², grain θ = 0.9x + 0.5y projected onto the surface, h = normalize(0.3, 0.4, 1); error = angle between the discrete ℓ and the exact n × ∇_S(hᵀu) at interior vertices; time = geometry (frames, areas, connection, jet-fit W, Eq. 10 stencils) + ℓ, median of 3–5 runs.\n");
    table(out, &["grid", "n", "vertices", "RMS error (°)", "max error (°)", "time (ms)"], &rows);
    let _ = writeln!(out, "![ℓ error against time](img/accuracy-resolution.svg)\n");
    plot(
        &img.join("accuracy-resolution.svg"),
        "ℓ error against time (mesh resolution)",
        "time (s)",
        "RMS angle error of ℓ (°)",
        &series,
    );
}

// ---------------------------------------------------------------- 2. solver

fn solver(out: &mut String, img: &Path) {
    let mesh = generate::quadric_patch([0.9, 0.2, -0.5], 1.0, Grid::new(30, 30));
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let n = mesh.num_vertices();
    let hv = vec![Vector3::new(0.3, 0.4, 1.0).normalize(); n];
    let world =
        |p: &Vector3<f64>| Vector3::new((0.8 * p.y).cos(), (0.8 * p.y).sin() + 0.3 * p.x, 0.1);
    let phi_true: Vec<f64> =
        (0..n).map(|i| g.frames[i].angle_of(&world(&mesh.positions[i]))).collect();
    let term = HighlightTerm::own_targets(&g, &hv, Symmetry::Line, GradientForm::Angle, &phi_true);
    let centre = Vector3::new(0.1, -0.1, 0.0);
    let brush: Vec<u32> =
        (0..n as u32).filter(|&i| (mesh.positions[i as usize] - centre).norm() < 0.45).collect();
    let mut phi0 = phi_true.clone();
    for &i in &brush {
        let d = (mesh.positions[i as usize] - centre).norm() / 0.45;
        phi0[i as usize] += 0.3 * (1.0 - d * d).powi(2);
    }
    let worst = |phi: &[f64]| {
        brush
            .iter()
            .map(|&i| (wrap_angle(2.0 * (phi[i as usize] - phi_true[i as usize])) / 2.0).abs())
            .fold(0.0, f64::max)
    };
    let mut rows = Vec::new();
    let mut pts = Vec::new();
    for its in 0..=8 {
        let opts = LmOptions { smoothness: 1e-4, max_iterations: its, ..Default::default() };
        let (r, secs) = timed(5, || solve(&mesh, &term, &phi0, &brush, &opts).expect("solve"));
        let e =
            r.iterations.last().map(|it| it.energies.total()).unwrap_or(r.initial_energy.total());
        let err = worst(&r.phi);
        rows.push(Row {
            cells: vec![
                its.to_string(),
                format!("{e:.3e}"),
                format!("{err:.2e}"),
                format!("{:.2}", secs * 1e3),
            ],
        });
        if its > 0 {
            pts.push((secs, err));
        }
    }
    let _ =
        writeln!(out, "## 2. Solver iterations and tolerance → residual, angle error and time\n");
    let _ = writeln!(out, "Recovery (math.md §3): a known smooth line field (k = 2) on a 31×31 quadric patch, targets L* = L(φ_true), φ perturbed by a 0.3 rad bump over the {} vertices of a brush of radius 0.45, which are the unknowns; λ_s = 1e-4. Error = largest |φ − φ_true| (mod π) over the brush. Time = whole solve, median of 5.\n", brush.len());
    table(out, &["iteration cap", "energy E_ℓ + E_s", "max angle error (rad)", "time (ms)"], &rows);
    let mut rows = Vec::new();
    for tol in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12] {
        let opts = LmOptions { smoothness: 1e-4, relative_decrease: tol, ..Default::default() };
        let (r, secs) = timed(5, || solve(&mesh, &term, &phi0, &brush, &opts).expect("solve"));
        rows.push(Row {
            cells: vec![
                format!("{tol:.0e}"),
                r.iterations.len().to_string(),
                format!("{:.2e}", worst(&r.phi)),
                format!("{:.2}", secs * 1e3),
            ],
        });
    }
    table(
        out,
        &["relative decrease tolerance", "iterations", "max angle error (rad)", "time (ms)"],
        &rows,
    );
    let _ = writeln!(out, "![solver error against time](img/accuracy-solver.svg)\n");
    plot(
        &img.join("accuracy-solver.svg"),
        "solver: angle error against time",
        "time (s)",
        "max angle error (rad)",
        &[Series { name: "iterations 1..8".into(), points: pts }],
    );
}

// ---------------------------------------------------------------- 3. streamlines

fn streamlines(out: &mut String, img: &Path) {
    use grainline_toolpaths::*;
    let (r0, r1, nr, nt) = (2.0, 10.0, 16, 128);
    let mut uv: Vec<Vec2> = Vec::new();
    for j in 0..=nr {
        let r = r0 + (r1 - r0) * j as f64 / nr as f64;
        for i in 0..nt {
            let t = 2.0 * std::f64::consts::PI * i as f64 / nt as f64;
            uv.push([r * t.cos(), r * t.sin()]);
        }
    }
    let id = |i: usize, j: usize| (j * nt + i % nt) as u32;
    let mut tris = Vec::new();
    for j in 0..nr {
        for i in 0..nt {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let d = uv.iter().map(|p| [-p[1], p[0]]).collect();
    let dom = Domain::new(FieldMesh::new(uv, tris, Directions::Vectors(d), Symmetry::Vector))
        .expect("domain");
    let mut rows = Vec::new();
    let mut pts = Vec::new();
    for tol in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
        let opts = TraceOptions { tolerance: tol, max_step: 1.0, ..Default::default() };
        let ((err, n), secs) = timed(5, || {
            let (mut err, mut n) = (0.0f64, 0usize);
            for k in 0..15 {
                let r = 2.5 + 0.5 * k as f64;
                let s = trace_streamline(&dom, [r, 0.0], &opts).expect("trace").expect("stroke");
                n += s.uv.len();
                for w in s.uv.windows(2) {
                    let m = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
                    for p in [w[0], m] {
                        err = err.max((p[0].hypot(p[1]) - r).abs());
                    }
                }
            }
            (err, n)
        });
        rows.push(Row {
            cells: vec![
                format!("{tol:.0e}"),
                format!("{err:.2e}"),
                n.to_string(),
                format!("{:.3}", secs * 1e3),
            ],
        });
        pts.push((secs, err));
    }
    let _ = writeln!(
        out,
        "## 3. Integration tolerance and spacing → streamline error, coverage and time\n"
    );
    let _ = writeln!(out, "Annulus r ∈ [2, 10] mm (2 × 16 × 128 triangles) with the circular field u = (−y, x): every streamline is a circle. 15 streamlines from r = 2.5 … 9.5 mm; error = largest distance of a polyline vertex or chord midpoint from its circle. Median of 5.\n");
    table(out, &["tolerance (mm)", "max radius error (mm)", "points", "time (ms)"], &rows);
    let mut rows = Vec::new();
    let mut cov_pts = Vec::new();
    for width in [2.0, 1.0, 0.5, 0.25] {
        let popts = PlacementOptions::new(width, 0.0);
        let ((frac, gap, strokes), secs) = timed(3, || {
            let p = place_strokes(&dom, &popts).expect("placement");
            let c = coverage(&dom, &p, &CoverageOptions::default()).expect("coverage");
            (c.fraction, c.largest_gap, p.strokes.len())
        });
        rows.push(Row {
            cells: vec![
                format!("{width}"),
                strokes.to_string(),
                format!("{:.4}", frac),
                format!("{gap:.3}"),
                format!("{:.1}", secs * 1e3),
            ],
        });
        cov_pts.push((secs, (1.0 - frac).max(1e-6)));
    }
    let _ = writeln!(out, "Spacing on the same annulus: brush width w (spacing d_sep = w, no overlap), Jobard–Lefer placement + coverage (area fraction within d_sep/2 of a stroke). Median of 3.\n");
    table(
        out,
        &["brush width (mm)", "strokes", "coverage", "largest gap (mm)", "time (ms)"],
        &rows,
    );
    let _ = writeln!(out, "![streamline error against time](img/accuracy-streamlines.svg)\n");
    plot(
        &img.join("accuracy-streamlines.svg"),
        "streamlines: error and uncovered fraction against time",
        "time (s)",
        "radius error (mm) / uncovered fraction",
        &[
            Series { name: "tolerance sweep".into(), points: pts },
            Series { name: "spacing sweep (1 − coverage)".into(), points: cov_pts },
        ],
    );
}

// ---------------------------------------------------------------- 4. preview

/// A tiny Radiance .hdr sky (flat RGBE scanlines): a dim gradient and a bright sun.
fn write_sky(path: &Path) {
    let (w, h) = (64usize, 32usize);
    let mut bytes = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes();
    for j in 0..h {
        for i in 0..w {
            let (dx, dy) = (i as f64 - 20.0, j as f64 - 8.0);
            let sun = 40.0 * (-(dx * dx + dy * dy) / 4.0).exp();
            let sky = 0.3 * (1.0 - j as f64 / h as f64) + 0.05;
            let c = [sky + sun, sky + 0.9 * sun, sky * 1.2 + 0.8 * sun];
            let v = c.iter().cloned().fold(0.0f64, f64::max);
            let e = v.log2().floor() + 1.0;
            let scale = 256.0 / 2f64.powf(e);
            bytes.extend(c.iter().map(|x| (x * scale).min(255.0) as u8));
            bytes.push((e + 128.0) as u8);
        }
    }
    std::fs::write(path, bytes).expect("write sky");
}

fn preview(out: &mut String, img: &Path) {
    use grainline::render::{self, Camera, LightSpec, Material, RenderInput, RenderSettings};
    let mesh = generate::torus(1.0, 0.4, 96, 48);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi =
        initial_field(&mesh, &g, &InitialField::CurvatureMax, Symmetry::Line).expect("field").phi;
    let u = g.directions_of(&phi);
    let normals: Vec<Vector3<f64>> = g.frames.iter().map(|f| f.n).collect();
    let input = RenderInput::new(&mesh.positions, &mesh.faces, &normals, &u, Symmetry::Line);
    let material = Material::default();
    let camera = Camera {
        eye: Vector3::new(0.0, -3.5, 2.2),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 35.0,
    };
    let dir = |d: [f64; 3], e: f64| LightSpec::Directional {
        direction: d,
        irradiance: e,
        colour: [1.0; 3],
        key: false,
    };
    let lights =
        vec![dir([0.3, -0.5, 1.0], 2.0), dir([-0.8, -0.3, 0.4], 0.7), dir([0.2, 1.0, 0.3], 0.5)];
    let linear = |lights: &[LightSpec], ss: u32| -> (Vec<[f32; 3]>, f64) {
        let settings: RenderSettings = serde_json::from_str(&format!(
            r#"{{"width": 256, "height": 256, "supersample": {ss}, "output": "x.png", "linear": "x.pfm"}}"#
        ))
        .expect("settings");
        let (r, secs) = timed(3, || {
            render::render(&input, &material, lights, &camera, &settings).expect("render")
        });
        let (_, _, px) =
            render::image::decode_pfm(r.linear.as_ref().expect("pfm")).expect("decode");
        (px, secs)
    };
    let rel_err = |a: &[[f32; 3]], b: &[[f32; 3]]| {
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for (p, q) in a.iter().zip(b) {
            for c in 0..3 {
                num += (f64::from(p[c]) - f64::from(q[c])).powi(2);
                den += f64::from(q[c]).powi(2);
            }
        }
        (num / den.max(f64::MIN_POSITIVE)).sqrt()
    };
    let (reference, _) = linear(&lights, 8);
    let mut rows = Vec::new();
    let mut pts = Vec::new();
    for ss in [1u32, 2, 3, 4, 6] {
        let (px, secs) = linear(&lights, ss);
        let e = rel_err(&px, &reference);
        rows.push(Row {
            cells: vec![ss.to_string(), format!("{e:.2e}"), format!("{:.1}", secs * 1e3)],
        });
        pts.push((secs, e));
    }
    let _ = writeln!(
        out,
        "## 4. Preview supersampling and environment samples → image error and time\n"
    );
    let _ = writeln!(out, "Torus (R = 1, r = 0.4, 9,216 vertices) with circumferential grain, Ashikhmin–Shirley (n_u = 1000, n_v = 10), three directional lights, 256² pixels. Error = relative RMS difference of the linear radiance (PFM) from the supersample-8 render. Median of 3.\n");
    table(out, &["supersample", "relative RMS error", "time (ms)"], &rows);
    let sky = std::env::temp_dir().join(format!("grainline-acc-sky-{}.hdr", std::process::id()));
    write_sky(&sky);
    let env = |n: u32| {
        vec![LightSpec::Environment {
            file: sky.display().to_string(),
            scale: 1.0,
            samples: n,
            rotation_deg: 0.0,
        }]
    };
    let (env_ref, _) = linear(&env(16384), 1);
    let mut rows = Vec::new();
    let mut env_pts = Vec::new();
    for n in [16u32, 64, 256, 1024, 4096] {
        let (px, secs) = linear(&env(n), 1);
        let e = rel_err(&px, &env_ref);
        rows.push(Row {
            cells: vec![n.to_string(), format!("{e:.2e}"), format!("{:.1}", secs * 1e3)],
        });
        env_pts.push((secs, e));
    }
    std::fs::remove_file(&sky).ok();
    let _ = writeln!(out, "Environment light only (a procedural 64×32 Radiance sky with a small bright sun), supersample 1; error against 16,384 samples.\n");
    table(out, &["environment samples", "relative RMS error", "time (ms)"], &rows);
    let _ = writeln!(out, "![preview error against time](img/accuracy-preview.svg)\n");
    plot(
        &img.join("accuracy-preview.svg"),
        "preview: image error against time",
        "time (s)",
        "relative RMS error",
        &[
            Series { name: "supersample 1..6".into(), points: pts },
            Series { name: "env samples 16..4096".into(), points: env_pts },
        ],
    );
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    format!("{cpu}, {cores} cores")
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let img = root.join("docs/img");
    std::fs::create_dir_all(&img).expect("docs/img");
    let mut out = String::new();
    let _ = writeln!(out, "# Accuracy against time\n");
    let _ = writeln!(out, "Generated by `cargo run --release --example accuracy_report` (do not edit by hand; regenerate when the code changes). Machine: {}. Every error is measured against an analytic truth, not against grainline's own output.\n", machine());
    resolution(&mut out, &img, quick);
    solver(&mut out, &img);
    streamlines(&mut out, &img);
    preview(&mut out, &img);
    grainline::output::write_atomic(&root.join("docs/accuracy-vs-time.md"), out.as_bytes())
        .expect("write report");
    eprintln!("wrote docs/accuracy-vs-time.md");
}
