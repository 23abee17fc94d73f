//! The noise estimate and the fit radius it picks (`field.noise: "auto"`, docs/math.md §5.6,
//! "Noise scale"), against spheres of known noise: the noise's height, the normal error of the
//! fit at the chosen radius against the analytic normal, the constant K of the error model, and
//! clean parts (smooth or coarse) that must keep the 1-ring.

use std::process::Command;

use grainline::geometry::noise::{estimate, NORMAL_ERROR_CONSTANT};
use grainline::geometry::{Geometry, GeometryOptions};
use grainline::mesh::Mesh;

/// An icosphere of radius 50 with uniform radial noise of half-width `a` (RMS a/√3), from a
/// fixed LCG.
fn noisy_sphere(subdivisions: u32, a: f64, seed: u64) -> Mesh {
    let mut m = grainline::generate::icosphere(50.0, subdivisions);
    let mut s = seed;
    for p in &mut m.positions {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (s >> 11) as f64 / (1u64 << 53) as f64;
        *p *= 1.0 + a * (2.0 * u - 1.0) / 50.0;
    }
    m
}

/// The 95th-percentile angle (degrees) between the fitted normals and the sphere's.
fn normal_p95(m: &Mesh, fit_radius: Option<f64>) -> f64 {
    let g = Geometry::compute(m, &GeometryOptions { fit_radius, ..Default::default() });
    let mut e: Vec<f64> = g
        .frames
        .iter()
        .zip(&m.positions)
        .map(|(f, p)| f.n.angle(&p.normalize()).to_degrees())
        .collect();
    e.sort_by(f64::total_cmp);
    e[(e.len() as f64 * 0.95) as usize]
}

#[test]
fn the_noise_height_is_found_within_15_percent() {
    for (sub, a, seed) in [(5, 0.1, 1), (5, 0.2, 2), (5, 0.4, 3), (6, 0.1, 4)] {
        let e = estimate(&noisy_sphere(sub, a, seed));
        let truth = a / 3f64.sqrt();
        assert!((e.sigma / truth - 1.0).abs() < 0.15, "ico{sub} ±{a}: σ {} vs {truth}", e.sigma);
        assert!(e.samples > 2000, "{e:?}");
    }
}

#[test]
fn the_chosen_radius_brings_the_normal_error_down() {
    let m = noisy_sphere(5, 0.2, 7);
    let e = estimate(&m);
    let r = e.fit_radius.expect("a noisy sphere asks for a wider fit");
    let (ring, auto) = (normal_p95(&m, None), normal_p95(&m, Some(r)));
    assert!(auto < 1.0 && auto * 5.0 < ring, "1-ring {ring:.2}°, radius {r:.2}: {auto:.2}°");
}

/// K in θ₉₅ ≈ K σ s / ρ², re-measured at two radii.
#[test]
fn the_error_model_constant_holds() {
    let m = noisy_sphere(5, 0.2, 11);
    let e = estimate(&m);
    for rho in [6.0, 10.0] {
        let k = normal_p95(&m, Some(rho)) * rho * rho / (e.sigma * e.spacing);
        assert!((k / NORMAL_ERROR_CONSTANT - 1.0).abs() < 0.3, "ρ {rho}: K {k:.1}");
    }
}

/// Clean parts keep the 1-ring, however coarse: a smooth sphere, a coarse torus (its quadric
/// misfits the 2-ring, but neighbouring residuals are alike, not noise), a coarse body of
/// revolution, a plane.
#[test]
fn clean_parts_keep_the_one_ring() {
    let parts = [
        ("sphere", grainline::generate::icosphere(50.0, 5)),
        ("coarse torus", grainline::generate::torus(60.0, 15.0, 24, 10)),
        ("coarse kettle", grainline::generate::kettle_body(24, 12, None)),
        ("plane", grainline::generate::plane(50.0, grainline::generate::Grid::new(30, 30))),
    ];
    for (name, m) in parts {
        let e = estimate(&m);
        assert_eq!(e.fit_radius, None, "{name}: {e:?}");
    }
}

fn write_obj(m: &Mesh, path: &std::path::Path) {
    std::fs::write(path, grainline::mesh::write::obj_string(m, "noisy sphere")).unwrap();
}

fn run(dir: &std::path::Path, field: &str) -> serde_json::Value {
    let scene = format!(
        r#"{{"mesh": "part.obj", "view": {{"eye": [0, -300, 0]}},
            "lights": [{{"type": "directional", "direction": [0.3, -0.5, 1]}}],
            "field": {{"output": "field.json"{field}}}}}"#
    );
    std::fs::write(dir.join("scene.json"), scene).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["run", "scene.json", "--quiet", "--report", "report.json"])
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

/// The run report carries the estimate; `field.fit_radius` overrides it and `field.noise:
/// "off"` turns it off.
#[test]
fn the_run_report_states_the_estimate() {
    let dir = std::env::temp_dir().join(format!("grainline-noise-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_obj(&noisy_sphere(5, 0.3, 5), &dir.join("part.obj"));
    let auto = run(&dir, "");
    let noise = &auto["noise"];
    let sigma = noise["sigma"].as_f64().unwrap();
    assert!((sigma / (0.3 / 3f64.sqrt()) - 1.0).abs() < 0.2, "{noise}");
    assert!(noise["fit_radius"].as_f64().unwrap() > 2.5 * noise["spacing"].as_f64().unwrap());
    assert!(run(&dir, r#", "noise": "off""#).get("noise").is_none());
    assert!(run(&dir, r#", "fit_radius": 6"#).get("noise").is_none());
    std::fs::remove_dir_all(&dir).ok();
}
