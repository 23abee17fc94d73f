//! The noise estimate (`field.fit_radius: "auto"`, docs/math.md §5.6, "Noise scale") on meshes
//! and on noisy spheres of known noise.
//!
//! ```text
//! cargo run --release --example bench_noise -- [MESH ...]
//! ```
//!
//! Prints, per mesh (scaled to a 200 mm diagonal, as the edit corpus places parts), the noise's
//! RMS height σ, the vertex spacing s, the noise radius, the feature radius and the fit radius
//! chosen; then, for icospheres of radius 50 with uniform radial noise of known RMS height, σ
//! against the truth and the 95th-percentile normal error of the fit at the chosen radius.

use grainline::geometry::noise::{estimate, NoiseEstimate};
use grainline::geometry::{Geometry, GeometryOptions};
use grainline::mesh::Mesh;
use nalgebra::Vector3;

fn row(name: &str, v: usize, e: &NoiseEstimate, extra: &str) {
    let f = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.2}"));
    println!(
        "| {name} | {v} | {:.4} | {:.3} | {:.3} | {:.2} | {} | {} |{extra}",
        e.sigma,
        e.spacing,
        e.sigma / e.spacing,
        e.noise_radius,
        f(e.feature_radius),
        f(e.fit_radius)
    );
}

fn scaled(mut m: Mesh) -> Mesh {
    let (mut lo, mut hi) = (Vector3::repeat(f64::MAX), Vector3::repeat(f64::MIN));
    for p in &m.positions {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let k = 200.0 / (hi - lo).norm();
    for p in &mut m.positions {
        *p *= k;
    }
    m
}

/// Uniform radial noise of half-width `a` (RMS a/√3), from a fixed LCG.
fn noisy_sphere(sub: u32, a: f64) -> Mesh {
    let mut m = grainline::generate::icosphere(50.0, sub);
    let mut s: u64 = 0x2545_F491_4F6C_DD1D;
    for p in &mut m.positions {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (s >> 11) as f64 / (1u64 << 53) as f64;
        *p *= 1.0 + a * (2.0 * u - 1.0) / 50.0;
    }
    m
}

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

/// The quadric's bias: the 95th-percentile normal error of a fit over ρ on a clean ellipsoid
/// 60 × 45 × 35, against (ρ/R)², R its 90th-percentile radius of curvature.
fn bias_table() {
    let (a, b, c) = (60.0, 45.0, 35.0);
    let mut m = grainline::generate::icosphere(50.0, 6);
    for p in &mut m.positions {
        *p = Vector3::new(p.x * a / 50.0, p.y * b / 50.0, p.z * c / 50.0);
    }
    let truth: Vec<Vector3<f64>> = m
        .positions
        .iter()
        .map(|p| Vector3::new(p.x / (a * a), p.y / (b * b), p.z / (c * c)).normalize())
        .collect();
    let e = estimate(&m);
    println!();
    println!("ellipsoid: s {:.3}, feature radius at 8 mm: see rows", e.spacing);
    println!("| ρ | p95 normal error (°) | B = error / (ρ/R)², R = 60²/35 |");
    for rho in [2.0, 4.0, 8.0, 12.0, 16.0] {
        let g =
            Geometry::compute(&m, &GeometryOptions { fit_radius: Some(rho), ..Default::default() });
        let mut err: Vec<f64> =
            g.frames.iter().zip(&truth).map(|(f, t)| f.n.angle(t).to_degrees()).collect();
        err.sort_by(f64::total_cmp);
        let p95 = err[(err.len() as f64 * 0.95) as usize];
        let r = a * a / c;
        println!("| {rho} | {p95:.3} | {:.2} |", p95 / (rho / r).powi(2));
    }
}

fn main() {
    if std::env::var_os("BENCH_NOISE_BIAS").is_some() {
        bias_table();
        return;
    }
    println!("| mesh | V | σ | s | σ/s | noise radius | feature radius | fit radius |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    for path in std::env::args().skip(1) {
        let options =
            grainline::mesh::load::LoadOptions { allow_nonmanifold: true, ..Default::default() };
        match grainline::mesh::load::load_mesh(std::path::Path::new(&path), &options) {
            Ok(l) => {
                let m = scaled(l.mesh);
                let t = std::time::Instant::now();
                let e = estimate(&m);
                let name = std::path::Path::new(&path).file_stem().unwrap().to_string_lossy();
                row(&name, m.num_vertices(), &e, &format!(" {:.3} s", t.elapsed().as_secs_f64()));
            }
            Err(e) => println!("{path}: {e}"),
        }
    }
    println!();
    println!("| sphere | V | σ | s | σ/s | noise radius | feature radius | fit radius | true σ | p95 normal error 1-ring → auto (°) |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (sub, a) in [(4, 0.0), (5, 0.0), (4, 0.2), (5, 0.05), (5, 0.2), (5, 0.4), (6, 0.1)] {
        let m = noisy_sphere(sub, a);
        let e = estimate(&m);
        let extra = format!(
            " {:.4} | {:.2} → {:.2} |",
            a / 3f64.sqrt(),
            normal_p95(&m, None),
            normal_p95(&m, e.fit_radius)
        );
        row(&format!("ico{sub} ±{a}"), m.num_vertices(), &e, &extra);
    }
}
