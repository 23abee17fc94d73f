//! Benchmark of the core: load + all geometry + ℓ for a generated 1M-vertex mesh, and peak memory.
//!
//! ```text
//! cargo run --release --example bench_core [-- N]
//! ```
//!
//! Generates an N×N-vertex height field (default N = 1000: 1M vertices, 2M triangles) as an OBJ
//! in a child process (so its memory is not counted), then times, in this process: loading the
//! OBJ, the geometry (adjacency, normals, jet fit, areas, connection, Eq. 10 stencils), and the
//! highlight field ℓ of a world-direction initial field. Peak memory is the process's VmHWM.
//! `BENCH_TOBJ=1` loads with tobj (the reference reader) instead of the parallel parser.

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::io::Write;
use std::time::Instant;

use grainline::field::{compute_field, FieldOptions};
use grainline::highlight::{InitialField, Lighting, View};
use grainline::mesh::load::{load_obj_with, LoadOptions, ObjParser};
use nalgebra::Vector3;

fn write_heightfield(path: &std::path::Path, n: usize) {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).expect("create OBJ"));
    let h = 100.0 / (n - 1) as f64;
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 * h, j as f64 * h);
            let z = 5.0 * (0.07 * x).sin() * (0.05 * y).cos();
            writeln!(out, "v {x:.6} {y:.6} {z:.6}").unwrap();
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            let (b, c, d) = (a + 1, a + n + 1, a + n);
            writeln!(out, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
        }
    }
}

fn peak_rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .map(|l| l.split_whitespace().nth(1).unwrap_or("0").parse().unwrap_or(0))
        })
        .unwrap_or(0)
}

fn main() {
    // As the `grainline` binary does (see grainline::allocator).
    grainline::allocator::keep_freed_memory();
    let args: Vec<String> = std::env::args().collect();
    if args.len() == 4 && args[1] == "generate" {
        write_heightfield(std::path::Path::new(&args[2]), args[3].parse().unwrap());
        return;
    }
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let dir = std::env::temp_dir().join(format!("grainline-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("heightfield.obj");
    let status = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["generate", path.to_str().unwrap(), &n.to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let size = std::fs::metadata(&path).unwrap().len();

    let lighting =
        Lighting::new(Vector3::new(0.3, 0.2, 1.0), View::Direction(Vector3::new(-0.2, 0.1, 1.0)))
            .unwrap();
    let mut options = FieldOptions::new(lighting);
    options.init = InitialField::World(Vector3::new(1.0, 0.3, 0.0));
    // Five runs in this process: this VM's first-touch page faults make single runs noisy.
    let mut runs = Vec::new();
    let mut summary = None;
    let mut peak = 0;
    let parser =
        if std::env::var_os("BENCH_TOBJ").is_some() { ObjParser::Tobj } else { ObjParser::Auto };
    for run in 0..5 {
        let t0 = Instant::now();
        let loaded = load_obj_with(&path, &LoadOptions::default(), parser).expect("load");
        let t_load = t0.elapsed().as_secs_f64();
        if run == 0 && std::env::var_os("BENCH_PEAK_AFTER_LOAD").is_some() {
            println!("peak after load     {:.0} MB", peak_rss_kb() as f64 / 1024.0);
        }
        let t1 = Instant::now();
        let result = compute_field(&loaded.mesh, &options).expect("field");
        let t_field = t1.elapsed().as_secs_f64();
        runs.push((t_load, t_field, t0.elapsed().as_secs_f64()));
        let finite = result.highlight.ell.iter().all(|l| l.iter().all(|c| c.is_finite()));
        summary = Some((loaded.mesh.num_vertices(), loaded.mesh.num_faces(), finite));
        if run == 0 {
            // Peak of one load + field, before later runs reuse (and the allocator keeps) pages.
            peak = peak_rss_kb();
        }
    }
    let (nv, nf, finite) = summary.unwrap();
    let stat = |k: usize| {
        let mut v: Vec<f64> = runs.iter().map(|r| [r.0, r.1, r.2][k]).collect();
        v.sort_by(f64::total_cmp);
        format!("min {:.3} s, median {:.3} s, max {:.3} s", v[0], v[v.len() / 2], v[v.len() - 1])
    };
    println!("vertices            {nv}");
    println!("faces               {nf}");
    println!("OBJ size            {:.1} MB", size as f64 / 1e6);
    println!("threads             {}", rayon::current_num_threads());
    println!("OBJ reader          {parser:?}");
    println!("load_obj            {}", stat(0));
    println!("geometry + init + ℓ {}", stat(1));
    println!("total               {}", stat(2));
    println!(
        "peak memory         {:.0} MB ({:.0} bytes/vertex)",
        peak as f64 / 1024.0,
        peak as f64 * 1024.0 / nv as f64
    );
    println!("all ℓ finite        {finite}");
    stage_breakdown(&path, &options);
    std::fs::remove_dir_all(&dir).ok();
    curvature_anchor();
}

/// One more load + field, timed stage by stage (Geometry::compute_timed, then the field's steps as
/// compute_field runs them).
fn stage_breakdown(path: &std::path::Path, options: &FieldOptions) {
    use grainline::geometry::Geometry;
    use grainline::highlight::{half_vectors, highlight_field, initial_field};
    let loaded = load_obj_with(path, &LoadOptions::default(), ObjParser::Auto).expect("load");
    let mesh = &loaded.mesh;
    let t0 = Instant::now();
    let (geometry, mut stages) = Geometry::compute_timed(mesh, &options.geometry);
    let mut clock = Instant::now();
    let mut lap = |stages: &mut Vec<(&'static str, f64)>, name: &'static str| {
        let now = Instant::now();
        stages.push((name, now.duration_since(clock).as_secs_f64()));
        clock = now;
    };
    let init = initial_field(mesh, &geometry, &options.init, options.symmetry).expect("init");
    lap(&mut stages, "init");
    let normals: Vec<Vector3<f64>> = geometry.frames.iter().map(|f| f.n).collect();
    let h = half_vectors(&options.lighting, &mesh.positions, &normals);
    lap(&mut stages, "h");
    let ell = highlight_field(&geometry, &init.phi, options.symmetry, options.gradient_form, &h);
    lap(&mut stages, "gradient + ell");
    let total = t0.elapsed().as_secs_f64();
    let parts: Vec<String> = stages.iter().map(|(n, s)| format!("{n} {:.3}", s)).collect();
    println!("stages (one run, s) {} | sum {total:.3}", parts.join(", "));
    drop(ell);
}

/// The issue's curvature anchor: libigl's principal_curvature (radius 2) takes 2.1 s on a
/// 134k-vertex closed scan and has a 3.5 % k1 error on a 128×32 torus (R = 2, r = 0.5).
fn curvature_anchor() {
    use grainline::geometry::{Geometry, GeometryOptions};
    let big = grainline::generate::torus(2.0, 0.5, 524, 256); // 134,144 vertices, closed
    let t = Instant::now();
    let g = Geometry::compute(&big, &GeometryOptions::default());
    let secs = t.elapsed().as_secs_f64();
    println!(
        "curvature (all geometry) on a closed {}-vertex torus: {:.3} s ({:.1}x faster than 2.1 s)",
        big.num_vertices(),
        secs,
        2.1 / secs
    );
    let (big_r, r) = (2.0, 0.5);
    let torus = grainline::generate::torus(big_r, r, 128, 32);
    let g2 = Geometry::compute(&torus, &GeometryOptions::default());
    let mut worst: f64 = 0.0;
    for (i, p) in torus.positions.iter().enumerate() {
        let (k1, _) = grainline::generate::torus_curvatures(big_r, r, p);
        worst = worst.max((g2.principal[i].k1 - k1).abs() / k1.abs());
    }
    println!("k1 max relative error on the 128x32 torus: {:.2} % (libigl: 3.5 %)", 100.0 * worst);
    drop(g);
}
