//! Rendered images against truth from outside the renderer: the BRDF formulas by hand on a flat
//! quad, the highlight line of a cylinder where the model (hᵀu = 0) puts it, the k = 2 grain
//! symmetry, determinism across thread counts, shadows, the environment integral, and the report
//! counters that prove what did not run.

use std::f64::consts::PI;

use grainline::generate::{cylinder, plane, Grid};
use grainline::highlight::Symmetry;
use grainline::render::image::decode_pfm;
use grainline::render::settings::{HighlightCurveSettings, LicSettings};
use grainline::render::{
    render, BrdfSpec, Camera, Fresnel, LightSpec, Material, RenderInput, RenderOutput,
    RenderSettings, ToneMap,
};
use nalgebra::Vector3;

type V3 = Vector3<f64>;
/// A BRDF formula written out by hand, f(ω_in, ω_out) in the frame (u, v, n).
type Formula<'a> = &'a dyn Fn(V3, V3) -> f64;
/// Positions, faces, normals, grain, ℓ.
type TorusData = (Vec<V3>, Vec<[u32; 3]>, Vec<V3>, Vec<V3>, Vec<V3>);

fn settings(w: u32, h: u32, ss: u32) -> RenderSettings {
    RenderSettings {
        width: w,
        height: h,
        supersample: ss,
        tone_map: ToneMap::None,
        linear: Some("out.pfm".into()),
        ..Default::default()
    }
}

fn dir_light(d: [f64; 3], e: f64) -> LightSpec {
    LightSpec::Directional { direction: d, irradiance: e, colour: [1.0; 3], key: true }
}

fn pixels(out: &RenderOutput) -> (usize, usize, Vec<[f32; 3]>) {
    decode_pfm(out.linear.as_ref().expect("pfm")).expect("valid pfm")
}

/// The flat quad z = 0, normals +z, grain +x.
struct Quad {
    pos: Vec<Vector3<f64>>,
    faces: Vec<[u32; 3]>,
    normals: Vec<Vector3<f64>>,
    u: Vec<Vector3<f64>>,
}

fn quad(n: usize, u: Vector3<f64>) -> Quad {
    let m = plane(1.0, Grid::new(n, n));
    let k = m.positions.len();
    Quad {
        pos: m.positions.clone(),
        faces: m.faces.clone(),
        normals: vec![Vector3::z(); k],
        u: vec![u; k],
    }
}

/// The ray through the centre of pixel (i, j) of a w × h image, hitting z = 0.
fn pixel_point(cam: &Camera, w: usize, h: usize, i: usize, j: usize) -> Vector3<f64> {
    let fwd = (cam.target - cam.eye).normalize();
    let right = fwd.cross(&cam.up).normalize();
    let up = right.cross(&fwd);
    let f = 0.5 * h as f64 / (0.5 * cam.fov_deg.to_radians()).tan();
    let d = fwd + right * ((i as f64 + 0.5 - 0.5 * w as f64) / f)
        - up * ((j as f64 + 0.5 - 0.5 * h as f64) / f);
    let t = -cam.eye.z / d.z;
    cam.eye + d * t
}

#[test]
fn flat_quad_radiance_is_the_brdf_formula() {
    let q = quad(4, Vector3::x());
    let input = RenderInput::new(&q.pos, &q.faces, &q.normals, &q.u, Symmetry::Line);
    let cam = Camera {
        eye: Vector3::new(0.3, -1.2, 2.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 40.0,
    };
    let l = Vector3::new(0.3, 0.5, 1.0).normalize();
    let e = 2.0;
    let (w, h) = (41usize, 31usize);
    let rs = 0.8;
    let (nu, nv) = (400.0, 30.0);
    let (ax, ay) = (0.12, 0.35);
    let d = 0.1;
    // Each model's formula, written from its paper, in the frame (u, v, n) = (x, y, z).
    let as_formula = |wi: Vector3<f64>, wo: Vector3<f64>| {
        let hh = (wi + wo).normalize();
        let fres = rs + (1.0 - rs) * (1.0 - hh.dot(&wi)).powi(5);
        let ex = (nu * hh.x * hh.x + nv * hh.y * hh.y) / (1.0 - hh.z * hh.z);
        let spec = ((nu + 1.0) * (nv + 1.0)).sqrt() / (8.0 * PI) * hh.z.powf(ex)
            / (hh.dot(&wi) * wi.z.max(wo.z))
            * fres;
        let dif = 28.0 * d / (23.0 * PI)
            * (1.0 - rs)
            * (1.0 - (1.0 - wi.z / 2.0).powi(5))
            * (1.0 - (1.0 - wo.z / 2.0).powi(5));
        spec + dif
    };
    let ward_formula = |wi: Vector3<f64>, wo: Vector3<f64>| {
        let hh = (wi + wo).normalize();
        let ex = -((hh.x / ax).powi(2) + (hh.y / ay).powi(2)) / (hh.z * hh.z);
        d / PI + 0.6 * ex.exp() / (4.0 * PI * ax * ay * (wi.z * wo.z).sqrt())
    };
    let ggx_formula = |wi: Vector3<f64>, wo: Vector3<f64>| {
        let hh = (wi + wo).normalize();
        let f0 = 0.9;
        let fres = f0 + (1.0 - f0) * (1.0 - hh.dot(&wi)).powi(5);
        let dd = 1.0
            / (PI * ax * ay * ((hh.x / ax).powi(2) + (hh.y / ay).powi(2) + hh.z * hh.z).powi(2));
        let lam = |w: Vector3<f64>| {
            0.5 * ((1.0 + ((ax * w.x).powi(2) + (ay * w.y).powi(2)) / (w.z * w.z)).sqrt() - 1.0)
        };
        d / PI + fres * dd / (1.0 + lam(wi) + lam(wo)) / (4.0 * wi.z * wo.z)
    };
    let cases: Vec<(Material, Formula)> = vec![
        (
            Material {
                brdf: BrdfSpec::AshikhminShirley { nu, nv, rs: [rs; 3] },
                fresnel: Fresnel::None,
                diffuse: [d; 3],
            },
            &as_formula,
        ),
        (
            Material {
                brdf: BrdfSpec::Ward { alpha_x: ax, alpha_y: ay, rho_s: 0.6 },
                fresnel: Fresnel::None,
                diffuse: [d; 3],
            },
            &ward_formula,
        ),
        (
            Material {
                brdf: BrdfSpec::Ggx { alpha_u: ax, alpha_v: ay },
                fresnel: Fresnel::Schlick { f0: [0.9; 3] },
                diffuse: [d; 3],
            },
            &ggx_formula,
        ),
    ];
    for (m, formula) in cases {
        let out =
            render(&input, &m, &[dir_light(l.into(), e)], &cam, &settings(w as u32, h as u32, 1))
                .unwrap();
        let (pw, ph, px) = pixels(&out);
        assert_eq!((pw, ph), (w, h));
        for (i, j) in [(20, 15), (14, 10), (27, 20), (24, 11)] {
            let p = pixel_point(&cam, w, h, i, j);
            assert!(p.x.abs() < 1.0 && p.y.abs() < 1.0, "pixel ({i},{j}) off the quad: {p:?}");
            let wo = (cam.eye - p).normalize();
            let want = formula(l, wo) * e * l.z;
            let got = f64::from(px[j * w + i][0]);
            assert!(
                (got - want).abs() <= 2e-4 * want.max(1e-3),
                "{:?} pixel ({i},{j}): {got} vs {want}",
                m.brdf
            );
        }
    }
}

/// Cylinder r = 1, height 4 about z, analytic normals.
fn cyl() -> (Vec<V3>, Vec<[u32; 3]>, Vec<V3>) {
    let m = cylinder(1.0, 4.0, 720, 64);
    let n = m.positions.iter().map(|p| Vector3::new(p.x, p.y, 0.0).normalize()).collect();
    (m.positions.clone(), m.faces.clone(), n)
}

fn project(cam: &Camera, w: usize, h: usize, p: &Vector3<f64>) -> [f64; 2] {
    let fwd = (cam.target - cam.eye).normalize();
    let right = fwd.cross(&cam.up).normalize();
    let up = right.cross(&fwd);
    let f = 0.5 * h as f64 / (0.5 * cam.fov_deg.to_radians()).tan();
    let d = p - cam.eye;
    let z = d.dot(&fwd);
    [0.5 * w as f64 + f * d.dot(&right) / z, 0.5 * h as f64 - f * d.dot(&up) / z]
}

fn sharp_as() -> Material {
    Material {
        brdf: BrdfSpec::AshikhminShirley { nu: 5000.0, nv: 20.0, rs: [0.9; 3] },
        fresnel: Fresnel::None,
        diffuse: [0.0; 3],
    }
}

#[test]
fn cylinder_circumferential_grain_gives_a_highlight_line_parallel_to_the_axis() {
    let (pos, faces, normals) = cyl();
    let u: Vec<Vector3<f64>> =
        pos.iter().map(|p| Vector3::new(-p.y, p.x, 0.0).normalize()).collect();
    let input = RenderInput::new(&pos, &faces, &normals, &u, Symmetry::Line);
    let cam = Camera {
        eye: Vector3::new(6.0, 0.0, 0.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 45.0,
    };
    let l = Vector3::new(0.8, 0.6, 0.0);
    let (w, h) = (161usize, 201usize);
    let out = render(
        &input,
        &sharp_as(),
        &[dir_light(l.into(), 1.0)],
        &cam,
        &settings(w as u32, h as u32, 1),
    )
    .unwrap();
    let (_, _, px) = pixels(&out);
    // The model: hᵀe_θ = 0 with h ∝ l + ω_out. At p = (cos θ, sin θ, z) and eye (6, 0, 0):
    // l·e_θ = −l_x sin θ + l_y cos θ and ω_out·e_θ = −6 sin θ / |e − p|, so
    // tan θ = l_y / (l_x + 6/|e − p|) (solved by fixed-point iteration).
    let mut cols = Vec::new();
    for k in 0..=12 {
        let z = -1.2 + 0.2 * f64::from(k);
        let mut th = 0.0f64;
        for _ in 0..50 {
            let dist = ((6.0 - th.cos()).powi(2) + th.sin().powi(2) + z * z).sqrt();
            th = (l.y / (l.x + 6.0 / dist)).atan();
        }
        let p = Vector3::new(th.cos(), th.sin(), z);
        let [x, y] = project(&cam, w, h, &p);
        let row = y.floor() as usize;
        let (best, _) = (0..w).map(|i| (i, px[row * w + i][0])).fold((0, -1.0f32), |a, b| {
            if b.1 > a.1 {
                b
            } else {
                a
            }
        });
        let got = best as f64 + 0.5;
        assert!((got - x).abs() <= 1.0, "z = {z}: brightest column {got}, model {x}");
        cols.push(x);
    }
    // The line is parallel to the axis in the image (within a pixel over its height).
    let spread = cols.iter().cloned().fold(f64::MIN, f64::max)
        - cols.iter().cloned().fold(f64::MAX, f64::min);
    assert!(spread < 1.0, "highlight columns spread over {spread} px");
}

#[test]
fn cylinder_axial_grain_gives_a_highlight_perpendicular_to_the_axis() {
    let (pos, faces, normals) = cyl();
    let u = vec![Vector3::z(); pos.len()];
    let input = RenderInput::new(&pos, &faces, &normals, &u, Symmetry::Line);
    let cam = Camera {
        eye: Vector3::new(6.0, 0.0, 0.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 45.0,
    };
    let l = Vector3::new(0.8, 0.3, 0.25).normalize();
    let (w, h) = (161usize, 201usize);
    let out = render(
        &input,
        &sharp_as(),
        &[dir_light(l.into(), 1.0)],
        &cam,
        &settings(w as u32, h as u32, 1),
    )
    .unwrap();
    let (_, _, px) = pixels(&out);
    // The model: hᵀz = 0 ⇔ l_z + ω_out,z = 0 ⇔ z = l_z |e − p|, i.e.
    // z = l_z √D / √(1 − l_z²) with D = (6 − cos θ)² + sin² θ.
    for k in 0..=8 {
        let th = -0.4 + 0.1 * f64::from(k);
        let dd = (6.0 - th.cos()).powi(2) + th.sin().powi(2);
        let z = l.z * dd.sqrt() / (1.0 - l.z * l.z).sqrt();
        let p = Vector3::new(th.cos(), th.sin(), z);
        let [x, y] = project(&cam, w, h, &p);
        let col = x.floor() as usize;
        let (best, _) = (0..h).map(|j| (j, px[j * w + col][0])).fold((0, -1.0f32), |a, b| {
            if b.1 > a.1 {
                b
            } else {
                a
            }
        });
        let got = best as f64 + 0.5;
        assert!((got - y).abs() <= 1.0, "θ = {th}: brightest row {got}, model {y}");
    }
}

#[test]
fn k2_grain_with_alternating_signs_renders_as_the_uniform_field() {
    // A grain turning across the quad, u = (cos 1.5x, sin 1.5x, 0), and the same with the sign
    // flipped at every other vertex.
    let mut q = quad(8, Vector3::x());
    q.u = q.pos.iter().map(|p| Vector3::new((1.5 * p.x).cos(), (1.5 * p.x).sin(), 0.0)).collect();
    let alt: Vec<Vector3<f64>> =
        q.u.iter().enumerate().map(|(k, u)| if k % 2 == 0 { *u } else { -u }).collect();
    let cam = Camera {
        eye: Vector3::new(0.2, -1.5, 1.6),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 50.0,
    };
    let m = Material {
        brdf: BrdfSpec::Ggx { alpha_u: 0.05, alpha_v: 0.4 },
        fresnel: Fresnel::None,
        diffuse: [0.0; 3],
    };
    let lights = [dir_light([0.2, 0.6, 1.0], 1.0)];
    let st = settings(64, 48, 2);
    let run = |u: &[Vector3<f64>], k: Symmetry| {
        let input = RenderInput::new(&q.pos, &q.faces, &q.normals, u, k);
        render(&input, &m, &lights, &cam, &st).unwrap()
    };
    let uniform = run(&q.u, Symmetry::Line);
    let alternating = run(&alt, Symmetry::Line);
    assert_eq!(uniform.png, alternating.png);
    assert_eq!(uniform.linear, alternating.linear);
    // Interpolated as oriented vectors (k = 1), the flipped corners cancel inside the faces and
    // the image changes: the test can tell the two interpolations apart.
    let (_, _, a) = pixels(&uniform);
    let (_, _, b) = pixels(&run(&alt, Symmetry::Oriented));
    let max_diff = a.iter().zip(&b).map(|(x, y)| (x[0] - y[0]).abs()).fold(0.0f32, f32::max);
    assert!(max_diff > 0.01, "k = 1 interpolation of the flipped field should differ ({max_diff})");
}

fn torus_input() -> TorusData {
    let m = grainline::generate::torus(2.0, 0.7, 96, 48);
    let (big_r, _) = (2.0, 0.7);
    let normals: Vec<Vector3<f64>> = m
        .positions
        .iter()
        .map(|p| {
            let c = Vector3::new(p.x, p.y, 0.0).normalize() * big_r;
            (p - c).normalize()
        })
        .collect();
    let u: Vec<Vector3<f64>> =
        m.positions.iter().map(|p| Vector3::new(-p.y, p.x, 0.0).normalize()).collect();
    let ell: Vec<Vector3<f64>> = normals.iter().zip(&u).map(|(n, u)| n.cross(u)).collect();
    (m.positions.clone(), m.faces.clone(), normals, u, ell)
}

fn torus_camera() -> Camera {
    Camera {
        eye: Vector3::new(0.0, -6.0, 4.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 45.0,
    }
}

#[test]
fn identical_bytes_with_one_and_two_threads() {
    let (pos, faces, normals, u, ell) = torus_input();
    let mut input = RenderInput::new(&pos, &faces, &normals, &u, Symmetry::Line);
    input.ell = Some(&ell);
    // One key light (two are refused), one fill light.
    let fill = LightSpec::Directional {
        direction: [-1.0, 0.2, 0.3],
        irradiance: 0.7,
        colour: [1.0; 3],
        key: false,
    };
    let lights = [dir_light([0.3, -0.5, 1.0], 1.5), fill];
    let mut st = settings(96, 72, 2);
    st.tone_map = ToneMap::Reinhard;
    st.effects.shadows = true;
    st.effects.lic = Some(LicSettings { length_px: 6.0, strength: 0.5, seed: 7 });
    st.effects.highlight_curves = Some(HighlightCurveSettings { lights: vec![], width_px: 1.5 });
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            render(&input, &Material::default(), &lights, &torus_camera(), &st).unwrap()
        })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.png, b.png);
    assert_eq!(a.linear, b.linear);
    assert_eq!(a.report.counters, b.report.counters);
    assert!(a.report.counters.highlight_curve_samples > 0);
}

#[test]
fn report_proves_what_was_not_computed() {
    let (pos, faces, normals, u, ell) = torus_input();
    let mut input = RenderInput::new(&pos, &faces, &normals, &u, Symmetry::Line);
    input.ell = Some(&ell);
    let lights = [dir_light([0.3, -0.5, 1.0], 1.0)];
    let plain =
        render(&input, &Material::default(), &lights, &torus_camera(), &settings(64, 48, 1))
            .unwrap();
    let r = &plain.report;
    assert!(r.ran("raster") && r.ran("shading") && r.ran("encode_png"));
    for pass in ["bvh", "lic", "highlight_curves", "critical_points", "environment", "as_brushed"] {
        assert!(!r.ran(pass), "{pass} ran without being asked");
    }
    let c = &r.counters;
    assert_eq!((c.bvh_nodes, c.shadow_rays), (0, 0));
    assert_eq!((c.lic_noise_values, c.lic_steps), (0, 0));
    assert_eq!((c.env_texels, c.env_samples), (0, 0));
    assert_eq!((c.highlight_curve_samples, c.critical_samples, c.as_brushed_shadings), (0, 0, 0));
    assert!(c.brdf_evals > 0 && c.covered_samples > 0);
    serde_json::to_string(r).unwrap();

    let mut st = settings(64, 48, 1);
    st.effects.shadows = true;
    st.effects.lic = Some(LicSettings { length_px: 5.0, strength: 0.5, seed: 1 });
    let full = render(&input, &Material::default(), &lights, &torus_camera(), &st).unwrap();
    let c = &full.report.counters;
    assert!(full.report.ran("bvh") && full.report.ran("lic"));
    assert!(c.bvh_nodes > 0 && c.shadow_rays > 0);
    assert_eq!(c.lic_noise_values, 64 * 48);
    assert!(c.lic_steps > 0);
}

#[test]
fn shadows_darken_the_occluded_point_only_when_asked() {
    // Floor z = 0 and a small roof over [−0.2, 0.2]² at z = 0.5; light from straight above.
    let floor = plane(1.0, Grid::new(2, 2));
    let roof = plane(0.2, Grid::new(1, 1));
    let mut pos = floor.positions.clone();
    let mut faces = floor.faces.clone();
    let off = pos.len() as u32;
    pos.extend(roof.positions.iter().map(|p| p + Vector3::new(0.0, 0.0, 0.5)));
    faces.extend(roof.faces.iter().map(|f| f.map(|i| i + off)));
    let normals = vec![Vector3::z(); pos.len()];
    let u = vec![Vector3::x(); pos.len()];
    let input = RenderInput::new(&pos, &faces, &normals, &u, Symmetry::Line);
    let cam = Camera {
        eye: Vector3::new(0.0, -3.0, 1.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 30.0,
    };
    let m = Material {
        brdf: BrdfSpec::Ward { alpha_x: 0.3, alpha_y: 0.3, rho_s: 0.0 },
        fresnel: Fresnel::None,
        diffuse: [0.5; 3],
    };
    let lights = [dir_light([0.0, 0.0, 1.0], 1.0)];
    let (w, h) = (31u32, 31u32);
    let centre = |out: &RenderOutput| pixels(out).2[15 * 31 + 15][0];
    let lit = render(&input, &m, &lights, &cam, &settings(w, h, 1)).unwrap();
    // Lambert: L = ρ/π · E · cos 0.
    assert!((f64::from(centre(&lit)) - 0.5 / PI).abs() < 1e-5);
    let mut st = settings(w, h, 1);
    st.effects.shadows = true;
    let shadowed = render(&input, &m, &lights, &cam, &st).unwrap();
    assert_eq!(centre(&shadowed), 0.0);
    // A floor point outside the roof's shadow is unchanged.
    assert_eq!(pixels(&lit).2[28 * 31 + 3], pixels(&shadowed).2[28 * 31 + 3]);
}

#[test]
fn uniform_environment_gives_the_lambert_integral() {
    // A hand-written flat RGBE file: every texel (128, 128, 128, e = 129) = 128.5 · 2⁻⁷.
    let dir = std::env::temp_dir().join(format!("grainline-render-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("white.hdr");
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16 +X 32\n".to_vec();
    for _ in 0..16 * 32 {
        bytes.extend_from_slice(&[128, 128, 128, 129]);
    }
    std::fs::write(&file, bytes).unwrap();
    let radiance = 128.5 / 128.0;
    let q = quad(2, Vector3::x());
    let input = RenderInput::new(&q.pos, &q.faces, &q.normals, &q.u, Symmetry::Line);
    let cam = Camera {
        eye: Vector3::new(0.0, -1.0, 2.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 30.0,
    };
    let m = Material {
        brdf: BrdfSpec::Ward { alpha_x: 0.3, alpha_y: 0.3, rho_s: 0.0 },
        fresnel: Fresnel::None,
        diffuse: [0.6; 3],
    };
    let lights = [LightSpec::Environment {
        file: file.to_string_lossy().into(),
        scale: 1.0,
        samples: 4096,
        rotation_deg: 0.0,
    }];
    let out = render(&input, &m, &lights, &cam, &settings(21, 21, 1)).unwrap();
    // ∫ ρ/π · L · cos dω over the upper hemisphere = ρ L.
    let got = f64::from(pixels(&out).2[10 * 21 + 10][0]);
    assert!((got - 0.6 * radiance).abs() < 0.01 * 0.6 * radiance, "{got} vs {}", 0.6 * radiance);
    assert_eq!(out.report.counters.env_samples, 4096);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_settings_name_their_key() {
    let q = quad(1, Vector3::x());
    let input = RenderInput::new(&q.pos, &q.faces, &q.normals, &q.u, Symmetry::Line);
    let cam = Camera {
        eye: Vector3::new(0.0, -1.0, 2.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 30.0,
    };
    let mut st = settings(10, 10, 1);
    st.supersample = 0;
    let e = render(&input, &Material::default(), &[], &cam, &st).unwrap_err().to_string();
    assert!(e.starts_with("render.supersample"), "{e}");
    let lights = [dir_light([0.0, 0.0, 0.0], 1.0)];
    let e = render(&input, &Material::default(), &lights, &cam, &settings(10, 10, 1))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("lights[0].direction"), "{e}");
    let m = Material { brdf: BrdfSpec::Ggx { alpha_u: -1.0, alpha_v: 0.1 }, ..Default::default() };
    let e = render(&input, &m, &[], &cam, &settings(10, 10, 1)).unwrap_err().to_string();
    assert!(e.starts_with("material.brdf.alpha_u"), "{e}");
    let json = r#"{"width": 10, "bogus": 1}"#;
    assert!(serde_json::from_str::<RenderSettings>(json).is_err());
    let json = r#"[{"type": "directional", "direction": [0, 0, 1], "key": true}, {"type": "point", "position": [1, 2, 3]}]"#;
    let l: Vec<LightSpec> = serde_json::from_str(json).unwrap();
    assert_eq!(grainline::render::key_light_index(&l), Some(0));
}

#[test]
fn as_brushed_statistics_and_layout() {
    use grainline::render::settings::{AsBrushedMode, AsBrushedSettings};
    let q = quad(10, Vector3::x());
    let n = q.pos.len(); // 121 vertices
                         // Vertex k's as-brushed grain is turned by k/4 degrees: the angles are 0, 0.25, ..., 30°.
    let brushed: Vec<Vector3<f64>> = (0..n)
        .map(|k| {
            let a = (k as f64 / 4.0).to_radians();
            // Every third one reversed: for k = 2 the sign does not count.
            let s = if k % 3 == 0 { -1.0 } else { 1.0 };
            Vector3::new(a.cos(), a.sin(), 0.0) * s
        })
        .collect();
    let mut input = RenderInput::new(&q.pos, &q.faces, &q.normals, &q.u, Symmetry::Line);
    input.brushed_u = Some(&brushed);
    let cam = Camera {
        eye: Vector3::new(0.0, -1.5, 2.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 40.0,
    };
    let lights = [dir_light([0.1, 0.4, 1.0], 1.0)];
    let mut st = settings(40, 30, 1);
    st.effects.as_brushed = Some(AsBrushedSettings {
        mode: AsBrushedMode::SideBySide,
        gain: 4.0,
        departure_px: 2.0,
        width_px: 1.5,
    });
    let out = render(&input, &Material::default(), &lights, &cam, &st).unwrap();
    let (w, h, px) = pixels(&out);
    assert_eq!((w, h), (80, 30), "side by side doubles the width");
    assert_eq!(out.report.width, 80);
    let stats = out.report.as_brushed.as_ref().expect("stats");
    // Nearest-rank median of k/4 for k = 0..120 is k = 60 → 15°; p95 is rank 115 → k = 114.
    assert_eq!(stats.u_angle.count, n);
    assert!((stats.u_angle.median_deg - 15.0).abs() < 1e-9, "{:?}", stats.u_angle);
    assert!((stats.u_angle.p95_deg - 28.5).abs() < 1e-9, "{:?}", stats.u_angle);
    assert!((stats.u_angle.max_deg - 30.0).abs() < 1e-9);
    assert!(stats.ell_angle.is_none());
    // The left half is the designed grain (vertex 0 agrees), so the two halves differ.
    assert!(px[15 * 80 + 20] != px[15 * 80 + 60]);
    // Difference mode with identical fields is black on the surface.
    input.brushed_u = Some(&q.u);
    st.effects.as_brushed = Some(AsBrushedSettings {
        mode: AsBrushedMode::Difference,
        gain: 4.0,
        departure_px: 2.0,
        width_px: 1.5,
    });
    let out = render(&input, &Material::default(), &lights, &cam, &st).unwrap();
    let (w, _, px) = pixels(&out);
    assert_eq!(w, 40);
    assert!(px.iter().all(|p| p[0] == 0.0));
    assert_eq!(out.report.as_brushed.unwrap().u_angle.max_deg, 0.0);
}

/// Where no brush passed (the as-brushed grain is zero at a vertex) the preview shades the bare
/// metal, as a glTF viewer does at anisotropy strength 0: the same metal, isotropic, with the
/// grain's narrower lobe in both directions (`Material::unbrushed`). A quad whose right half
/// has no grain: its as-brushed half is, pixel for pixel, the designed render with the bare
/// material on the faces whose corners all lack grain and the anisotropic render on those whose
/// corners all have it; every designed half is unchanged by the bare corners.
#[test]
fn unbrushed_metal_is_shaded_without_grain() {
    use grainline::render::settings::{AsBrushedMode, AsBrushedSettings};
    let q = quad(12, Vector3::x());
    let cam = Camera {
        eye: Vector3::new(0.0, -1.5, 2.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 40.0,
    };
    let lights = [dir_light([0.1, 0.4, 1.0], 1.0)];
    // Grain kept left of x = 0.2 (two columns of faces inside the bare side are mixed).
    let brushed: Vec<Vector3<f64>> = q
        .pos
        .iter()
        .zip(&q.u)
        .map(|(p, u)| if p.x < 0.2 { *u } else { Vector3::zeros() })
        .collect();
    let (w, h) = (60usize, 45usize);
    let mut st = settings(w as u32, h as u32, 1);
    let designed = |m: &Material| {
        let input = RenderInput::new(&q.pos, &q.faces, &q.normals, &q.u, Symmetry::Line);
        pixels(&render(&input, m, &lights, &cam, &st).unwrap()).2
    };
    let aniso = designed(&Material::default());
    let bare = designed(&Material::default().unbrushed());
    st.effects.as_brushed = Some(AsBrushedSettings {
        mode: AsBrushedMode::SideBySide,
        gain: 4.0,
        departure_px: 2.0,
        width_px: 1.5,
    });
    let mut input = RenderInput::new(&q.pos, &q.faces, &q.normals, &q.u, Symmetry::Line);
    input.brushed_u = Some(&brushed);
    let out = render(&input, &Material::default(), &lights, &cam, &st).unwrap();
    let (w2, _, both) = pixels(&out);
    assert_eq!(w2, 2 * w);
    let (mut on_bare, mut on_grain, mut differ) = (0, 0, 0);
    for j in 0..h {
        for i in 0..w {
            let p = pixel_point(&cam, w, h, i, j);
            let (left, right) = (both[j * w2 + i], both[j * w2 + w + i]);
            assert_eq!(left, aniso[j * w + i], "designed half at ({i}, {j})");
            if p.y.abs() > 0.95 || p.x.abs() > 0.95 {
                continue;
            }
            // Faces are 1/6 wide: x ≥ 1/3 + margin has only bare corners, x ≤ 0 only brushed.
            if p.x > 0.36 {
                assert_eq!(right, bare[j * w + i], "bare at ({i}, {j})");
                on_bare += 1;
                differ += usize::from(bare[j * w + i] != aniso[j * w + i]);
            } else if p.x < -0.02 {
                assert_eq!(right, aniso[j * w + i], "brushed at ({i}, {j})");
                on_grain += 1;
            }
        }
    }
    assert!(on_bare > 200 && on_grain > 200, "{on_bare} bare, {on_grain} brushed pixels");
    assert!(differ > on_bare / 2, "the bare metal looks different: {differ} of {on_bare}");
}

/// `as_brushed.mode: "highlights"` against the analytic key highlight of a flat quad: grain
/// +x designed, the as-brushed grain the same turned by α about the normal. With the eye's and
/// the light's positions, g = hᵀu(p) is known at every pixel's point of the plane
/// (`pixel_point`), so in every row the two highlights' crossings are known: where they lie
/// ≥ 5 px apart the as-brushed one is drawn red (departing), where they lie within 1 px (the
/// two cross) green. With the same grain nothing departs. One shading only (no second half).
#[test]
fn as_brushed_highlights_mark_where_the_brushed_highlight_departs() {
    use grainline::render::settings::{AsBrushedMode, AsBrushedSettings};
    let q = quad(24, Vector3::x());
    let cam = Camera {
        eye: Vector3::new(0.0, -1.5, 2.0),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 40.0,
    };
    let l = Vector3::new(0.1, 0.4, 1.0).normalize();
    let (w, h) = (200usize, 150usize);
    // The crossing of g = hᵀu along row j, for grain u, in pixels (inside the quad's margin).
    let crossing = |u: &Vector3<f64>, j: usize| -> Option<f64> {
        let g = |i: usize| {
            let p = pixel_point(&cam, w, h, i, j);
            (l + (cam.eye - p).normalize()).normalize().dot(u)
        };
        let i = (0..w - 1).find(|&i| g(i) * g(i + 1) <= 0.0)?;
        let p = pixel_point(&cam, w, h, i, j);
        (p.x.abs() < 0.9 && p.y.abs() < 0.9).then(|| i as f64 + g(i) / (g(i) - g(i + 1)))
    };
    let turned = |a: f64| Vector3::new(a.cos(), a.sin(), 0.0);
    let alpha = 15f64.to_radians();
    let lights = [dir_light([l.x, l.y, l.z], 1.0)];
    let mut st = settings(w as u32, h as u32, 1);
    st.effects.as_brushed = Some(AsBrushedSettings {
        mode: AsBrushedMode::Highlights,
        gain: 4.0,
        departure_px: 2.0,
        width_px: 1.5,
    });
    let run = |brushed: &[Vector3<f64>]| {
        let mut input = RenderInput::new(&q.pos, &q.faces, &q.normals, &q.u, Symmetry::Line);
        input.brushed_u = Some(brushed);
        let out = render(&input, &Material::default(), &lights, &cam, &st).unwrap();
        assert_eq!(out.report.width, w as u32, "one half");
        assert_eq!(out.report.counters.as_brushed_shadings, 0, "no second shading");
        let c = &out.report.counters;
        let mut reader = png::Decoder::new(std::io::Cursor::new(&out.png)).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buf).unwrap();
        (c.brushed_highlight_samples, c.departed_highlight_samples, buf)
    };
    let (on, departed, img) = run(&vec![turned(alpha); q.pos.len()]);
    assert!(on > 100 && departed > 20, "{on} samples on the as-brushed highlight, {departed}");
    let px = |i: usize, j: usize| {
        let k = 3 * (j * w + i);
        [img[k], img[k + 1], img[k + 2]]
    };
    let (mut far, mut near) = (0, 0);
    for j in 0..h {
        let (Some(cd), Some(cb)) = (crossing(&Vector3::x(), j), crossing(&turned(alpha), j)) else {
            continue;
        };
        let p = px(cb.round() as usize, j);
        if (cb - cd).abs() >= 5.0 {
            far += 1;
            assert!(p[0] > 200 && p[1] < 80, "row {j}: {:.1} px apart, {p:?}", cb - cd);
        } else if (cb - cd).abs() <= 1.0 {
            near += 1;
            assert!(p[1] > 150 && p[0] < 120, "row {j}: {:.1} px apart, {p:?}", cb - cd);
        }
    }
    assert!(far >= 20 && near >= 2, "rows far apart {far}, rows where they cross {near}");
    let (on, departed, _) = run(&q.u);
    assert!(on > 100 && departed == 0, "the same grain: {on} {departed}");
}

#[test]
fn strokes_are_drawn_where_visible_only() {
    use grainline::render::settings::StrokeSettings;
    let q = quad(2, Vector3::x());
    let mut st = settings(41, 41, 1);
    st.tone_map = ToneMap::None;
    st.effects.shading = false; // dark clay, so the white stroke stands out
    st.effects.strokes = Some(StrokeSettings { width_px: 2.0 });
    let cam = Camera {
        eye: Vector3::new(0.0, 0.0, 3.0),
        target: Vector3::zeros(),
        up: Vector3::y(),
        fov_deg: 40.0,
    };
    // On the quad (visible) and 0.5 below it (hidden by the quad).
    let on: Vec<Vec<Vector3<f64>>> =
        vec![(0..=10).map(|i| Vector3::new(-0.5 + 0.1 * f64::from(i), 0.0, 0.0)).collect()];
    let below: Vec<Vec<Vector3<f64>>> =
        vec![on[0].iter().map(|p| p - Vector3::new(0.0, 0.0, 0.5)).collect()];
    let run = |strokes: &[Vec<Vector3<f64>>]| {
        let mut input = RenderInput::new(&q.pos, &q.faces, &q.normals, &q.u, Symmetry::Line);
        input.strokes = Some(strokes);
        render(&input, &Material::default(), &[], &cam, &st).unwrap()
    };
    let a = run(&on);
    assert_eq!(a.report.counters.stroke_segments, 10);
    let img = tiny_skia::Pixmap::decode_png(&a.png).unwrap();
    // The stroke crosses the image centre row (y = 20); its middle pixel is white.
    let p = img.pixel(20, 20).unwrap();
    assert!(p.red() > 200 && p.green() > 200, "{p:?}");
    let b = run(&below);
    assert_eq!(b.report.counters.stroke_segments, 0);
}
