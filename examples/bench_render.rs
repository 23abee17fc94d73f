//! Benchmark of the preview renderer (docs/benchmarks.md, "Render").
//!
//!     cargo run --release --example bench_render
//!
//! 1. 1024 × 1024, three directional lights, Ashikhmin–Shirley, a 134,144-vertex torus (mesh
//!    generation excluded), supersample 1 (and 2 for information): min / median / max of 5 runs.
//! 2. The same with LIC of ℓ: the `lic` pass time.
//! 3. Supersampling factor and environment sample count against image error (vs a high-sample
//!    reference) and time, on smaller images.

use std::time::Instant;

use grainline::highlight::Symmetry;
use grainline::render::settings::LicSettings;
use grainline::render::{
    render, Camera, LightSpec, Material, RenderInput, RenderSettings, ToneMap,
};
use nalgebra::Vector3;

struct Torus {
    pos: Vec<Vector3<f64>>,
    faces: Vec<[u32; 3]>,
    normals: Vec<Vector3<f64>>,
    u: Vec<Vector3<f64>>,
    ell: Vec<Vector3<f64>>,
}

fn torus(n_major: usize, n_minor: usize) -> Torus {
    let m = grainline::generate::torus(2.0, 0.7, n_major, n_minor);
    let normals: Vec<Vector3<f64>> = m
        .positions
        .iter()
        .map(|p| (p - Vector3::new(p.x, p.y, 0.0).normalize() * 2.0).normalize())
        .collect();
    // A grain that winds around the tube: a mix of the two principal directions.
    let u: Vec<Vector3<f64>> = m
        .positions
        .iter()
        .zip(&normals)
        .map(|(p, n)| {
            let t = Vector3::new(-p.y, p.x, 0.0).normalize();
            (t * 0.8 + n.cross(&t) * 0.6).normalize()
        })
        .collect();
    let ell = normals.iter().zip(&u).map(|(n, u)| n.cross(u)).collect();
    Torus { pos: m.positions.clone(), faces: m.faces.clone(), normals, u, ell }
}

fn camera() -> Camera {
    Camera {
        eye: Vector3::new(0.0, -5.5, 3.5),
        target: Vector3::zeros(),
        up: Vector3::z(),
        fov_deg: 45.0,
    }
}

fn three_lights() -> Vec<LightSpec> {
    let d = |direction: [f64; 3], irradiance: f64, key: bool| LightSpec::Directional {
        direction,
        irradiance,
        colour: [1.0; 3],
        key,
    };
    vec![
        d([0.3, -0.6, 1.0], 2.0, true),
        d([-1.0, 0.2, 0.4], 0.8, false),
        d([0.6, 0.8, -0.2], 0.5, false),
    ]
}

/// CPU time of the whole process (all threads, user + system) in ms, from /proc/self/stat
/// (clock ticks of 10 ms); `None` where unavailable.
fn cpu_ms() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which is in parentheses): utime and stime are 14 and 15.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let (u, s): (f64, f64) = (f.get(11)?.parse().ok()?, f.get(12)?.parse().ok()?);
    Some((u + s) * 10.0)
}

/// The 1-minute load average.
fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|l| l.split_whitespace().next().unwrap_or("?").to_string())
        .unwrap_or_else(|_| "?".into())
}

fn stats(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2], v[v.len() - 1])
}

fn timed(
    label: &str,
    runs: usize,
    f: impl Fn() -> grainline::render::RenderOutput,
    pass: Option<&str>,
) {
    let mut total = Vec::new();
    let mut cpu = Vec::new();
    let mut pass_ms = Vec::new();
    let mut last = None;
    let load_before = load();
    for _ in 0..runs {
        let c0 = cpu_ms();
        let t = Instant::now();
        let out = f();
        total.push(t.elapsed().as_secs_f64() * 1e3);
        if let (Some(a), Some(b)) = (c0, cpu_ms()) {
            cpu.push(b - a);
        }
        if let Some(p) = pass {
            pass_ms.push(out.report.passes.iter().find(|x| x.name == p).map_or(0.0, |x| x.ms));
        }
        last = Some(out);
    }
    let (a, b, c) = stats(total);
    println!(
        "{label}: total min {a:.0} / median {b:.0} / max {c:.0} ms (load {load_before} → {})",
        load()
    );
    if cpu.len() == runs {
        let (a, b, c) = stats(cpu);
        println!("    CPU time, all threads: min {a:.0} / median {b:.0} / max {c:.0} ms");
    }
    if let Some(p) = pass {
        let (a, b, c) = stats(pass_ms);
        println!("    pass `{p}`: min {a:.0} / median {b:.0} / max {c:.0} ms");
    }
    if let Some(out) = last {
        let passes: Vec<String> =
            out.report.passes.iter().map(|p| format!("{} {:.0}", p.name, p.ms)).collect();
        println!("    last run passes (ms): {}", passes.join(", "));
        let c = &out.report.counters;
        println!(
            "    triangles in {}, culled {}, screen {}",
            c.triangles_in, c.triangles_culled, c.screen_triangles
        );
    }
}

/// sRGB 8-bit pixels of a PNG.
fn decode(png: &[u8]) -> Vec<[u8; 3]> {
    let pm = tiny_skia::Pixmap::decode_png(png).expect("png");
    pm.data().chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect()
}

/// RMS difference in 8-bit sRGB units, and the 99th percentile of the per-pixel maximum.
fn error(a: &[[u8; 3]], b: &[[u8; 3]]) -> (f64, f64) {
    let mut sq = 0.0;
    let mut per: Vec<f64> = Vec::with_capacity(a.len());
    for (x, y) in a.iter().zip(b) {
        let mut m = 0.0f64;
        for c in 0..3 {
            let d = f64::from(x[c]) - f64::from(y[c]);
            sq += d * d;
            m = m.max(d.abs());
        }
        per.push(m);
    }
    per.sort_by(f64::total_cmp);
    ((sq / (3 * a.len()) as f64).sqrt(), per[per.len() * 99 / 100])
}

/// A sky: a gradient plus a small bright sun, written as a flat RGBE file.
fn write_sky(path: &std::path::Path) {
    let (w, h) = (256usize, 128usize);
    let mut bytes = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes();
    for j in 0..h {
        for i in 0..w {
            let th = std::f64::consts::PI * (j as f64 + 0.5) / h as f64;
            let ph = std::f64::consts::TAU * (i as f64 + 0.5) / w as f64 - std::f64::consts::PI;
            let d = Vector3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
            let sun = Vector3::new(0.4, -0.5, 0.75).normalize();
            let mut c =
                if d.z > 0.0 { [0.4, 0.55, 0.9].map(|x| x * (0.4 + d.z)) } else { [0.15; 3] };
            if d.dot(&sun) > 0.995 {
                c = [40.0, 38.0, 34.0];
            }
            let m = c.iter().cloned().fold(0.0f64, f64::max);
            let e = m.log2().floor() as i32 + 1;
            let s = 256.0 / 2f64.powi(e);
            bytes.extend_from_slice(&[
                (c[0] * s) as u8,
                (c[1] * s) as u8,
                (c[2] * s) as u8,
                (e + 128) as u8,
            ]);
        }
    }
    std::fs::write(path, bytes).expect("write sky");
}

fn main() {
    let t = Instant::now();
    let mesh = torus(512, 262);
    println!(
        "torus: {} vertices, {} faces (generated in {:.0} ms, excluded)",
        mesh.pos.len(),
        mesh.faces.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let mut input =
        RenderInput::new(&mesh.pos, &mesh.faces, &mesh.normals, &mesh.u, Symmetry::Line);
    input.ell = Some(&mesh.ell);
    let lights = three_lights();
    let material = Material::default();
    let base = RenderSettings {
        width: 1024,
        height: 1024,
        supersample: 1,
        tone_map: ToneMap::Reinhard,
        ..Default::default()
    };
    println!("threads: {}", rayon::current_num_threads());
    timed(
        "1024², 3 lights, AS, ss 1",
        5,
        || render(&input, &material, &lights, &camera(), &base).unwrap(),
        Some("shading"),
    );
    let ss2 = RenderSettings { supersample: 2, ..base.clone() };
    timed(
        "1024², 3 lights, AS, ss 2",
        3,
        || render(&input, &material, &lights, &camera(), &ss2).unwrap(),
        None,
    );
    let mut lic = base.clone();
    lic.effects.lic = Some(LicSettings { length_px: 12.0, strength: 0.6, seed: 1 });
    timed(
        "1024², 3 lights, AS, ss 1, + LIC (L = 12 px)",
        5,
        || render(&input, &material, &lights, &camera(), &lic).unwrap(),
        Some("lic"),
    );
    let mut sh = base.clone();
    sh.effects.shadows = true;
    timed(
        "1024², 3 lights, AS, ss 1, + shadows",
        3,
        || render(&input, &material, &lights, &camera(), &sh).unwrap(),
        Some("shading"),
    );

    // Optional pictures: GRAINLINE_RENDER_SAVE=DIR writes plain.png and overlays.png there.
    if let Ok(dir) = std::env::var("GRAINLINE_RENDER_SAVE") {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        let plain = render(&input, &material, &lights, &camera(), &ss2).unwrap();
        std::fs::write(dir.join("plain.png"), plain.png).unwrap();
        let mut st = ss2.clone();
        st.effects.lic = Some(LicSettings { length_px: 12.0, strength: 0.6, seed: 1 });
        st.effects.highlight_curves = Some(grainline::render::settings::HighlightCurveSettings {
            lights: vec![0, 1],
            width_px: 1.5,
        });
        st.effects.critical_points = Some(grainline::render::settings::CriticalSettings {
            threshold: 0.999,
            lights: vec![],
        });
        st.effects.shadows = true;
        let over = render(&input, &material, &lights, &camera(), &st).unwrap();
        std::fs::write(dir.join("overlays.png"), over.png).unwrap();
        println!("{}", serde_json::to_string_pretty(&over.report).unwrap());
    }

    if std::env::var("GRAINLINE_RENDER_QUICK").is_ok() {
        return;
    }

    accuracy_tables(&input, &material, &lights, &base);
}

/// Prints the supersampling factor against a reference at s = 8 (256²) and the environment
/// sample count against a reference at 8192 samples (128², ss 1).
fn accuracy_tables(
    input: &RenderInput,
    material: &Material,
    lights: &[LightSpec],
    base: &RenderSettings,
) {
    // Supersampling against a reference at s = 8 (256²).
    let small = RenderSettings { width: 256, height: 256, ..base.clone() };
    let reference = decode(
        &render(
            input,
            material,
            lights,
            &camera(),
            &RenderSettings { supersample: 8, ..small.clone() },
        )
        .unwrap()
        .png,
    );
    println!(
        "\n| supersample | RMS error (8-bit sRGB) | p99 pixel error | time, median of 3 (ms) |"
    );
    println!("|---|---|---|---|");
    for s in [1u32, 2, 3, 4] {
        let st = RenderSettings { supersample: s, ..small.clone() };
        let mut times = Vec::new();
        let mut img = Vec::new();
        for _ in 0..3 {
            let t = Instant::now();
            img = decode(&render(input, material, lights, &camera(), &st).unwrap().png);
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let (rms, p99) = error(&img, &reference);
        println!("| {s} | {rms:.2} | {p99:.0} | {:.0} |", stats(times).1);
    }

    // Environment sample count against a reference at 8192 samples (128², ss 1).
    let dir = std::env::temp_dir().join(format!("grainline-bench-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let sky = dir.join("sky.hdr");
    write_sky(&sky);
    let env = |n: u32| {
        vec![LightSpec::Environment {
            file: sky.to_string_lossy().into(),
            scale: 1.0,
            samples: n,
            rotation_deg: 0.0,
        }]
    };
    let tiny = RenderSettings { width: 128, height: 128, ..base.clone() };
    let reference = decode(&render(input, material, &env(8192), &camera(), &tiny).unwrap().png);
    println!("\n| environment samples | RMS error (8-bit sRGB) | p99 pixel error | time, median of 3 (ms) |");
    println!("|---|---|---|---|");
    for n in [16u32, 64, 256, 1024] {
        let mut times = Vec::new();
        let mut img = Vec::new();
        for _ in 0..3 {
            let t = Instant::now();
            img = decode(&render(input, material, &env(n), &camera(), &tiny).unwrap().png);
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let (rms, p99) = error(&img, &reference);
        println!("| {n} | {rms:.2} | {p99:.0} | {:.0} |", stats(times).1);
    }
    std::fs::remove_dir_all(&dir).ok();
}
