//! Times `load_obj` and the topology on a generated 1000 × 1000 grid (1M vertices, 2M
//! triangles, with UVs), written as OBJ to a temporary directory; or, with `layouts`, loading
//! and the field (what `grainline field` computes) on the face layouts that used to be
//! quadratic: one face repeated, one huge polygon, a fan, at 10⁴, 10⁵ and 10⁶, and each one
//! past its budget (docs/benchmarks.md, "Mesh loading and topology").
//!
//! Run: `cargo run --release --example bench_load [N]` (N = grid side, default 1000), or
//! `cargo run --release --example bench_load layouts`.

use std::io::Write;
use std::time::Instant;

use grainline::mesh::load::{load_obj, load_obj_with, LoadOptions, ObjParser};
use grainline::mesh::topology::Topology;
use grainline::mesh::uv_charts::UvCharts;

fn write_grid(path: &std::path::Path, n: usize) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let h = 1.0 / (n - 1) as f64;
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 * h, j as f64 * h);
            let z = 0.1 * (6.0 * x).sin() * (5.0 * y).cos();
            writeln!(w, "v {x:.6} {y:.6} {z:.6}")?;
        }
    }
    for j in 0..n {
        for i in 0..n {
            writeln!(w, "vt {:.6} {:.6}", i as f64 * h, j as f64 * h)?;
        }
    }
    let id = |i: usize, j: usize| j * n + i + 1;
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            writeln!(w, "f {a}/{a} {b}/{b} {c}/{c}")?;
            writeln!(w, "f {a}/{a} {c}/{c} {d}/{d}")?;
        }
    }
    w.flush()
}

/// An OBJ of one face layout at size `n`: `repeated` (three vertices, `f 1 2 3` n times),
/// `polygon` (one convex face of n corners on a slightly warped circle), `fan` (n triangles
/// around a centre vertex, a disk).
fn layout(kind: &str, n: usize) -> String {
    use std::fmt::Write as _;
    let mut s = String::with_capacity(40 * n);
    let ring = |s: &mut String, n: usize| {
        for i in 0..n {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            let _ = writeln!(s, "v {:.9} {:.9} {:.9}", t.cos(), t.sin(), 0.1 * (2.0 * t).cos());
        }
    };
    match kind {
        "repeated" => s += &format!("v 0 0 0\nv 1 0 0\nv 0 1 0\n{}", "f 1 2 3\n".repeat(n)),
        "polygon" => {
            ring(&mut s, n);
            s += "f";
            for i in 1..=n {
                let _ = write!(s, " {i}");
            }
            s += "\n";
        }
        _ => {
            s += "v 0 0 0.2\n";
            ring(&mut s, n);
            for i in 0..n {
                let _ = writeln!(s, "f 1 {} {}", i + 2, (i + 1) % n + 2);
            }
        }
    }
    s
}

/// One row of the layouts table: load, then the field, each timed (or the refusal and its time).
fn layout_row(
    dir: &std::path::Path,
    kind: &str,
    n: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    use grainline::field::{compute_field, FieldOptions};
    use grainline::highlight::{Lighting, View};
    use nalgebra::Vector3;
    let path = dir.join(format!("{kind}-{n}.obj"));
    std::fs::write(&path, layout(kind, n))?;
    let mb = std::fs::metadata(&path)?.len() as f64 / 1e6;
    let t0 = Instant::now();
    // Repeated faces are non-manifold: accepted as `inspect` and `--allow-nonmanifold` do.
    let options = LoadOptions { allow_nonmanifold: kind == "repeated", ..Default::default() };
    let loaded = grainline::mesh::load::load_mesh(&path, &options);
    let t_load = t0.elapsed().as_secs_f64();
    let loaded = match loaded {
        Ok(l) => l,
        Err(e) => {
            let e = e.to_string();
            let why = e.split(": ").skip(1).collect::<Vec<_>>().join(": ");
            let why: String = why.chars().take(70).collect();
            println!("| {kind} | {n} | {mb:.1} | refused in {t_load:.2} s: {why}… | — |");
            return Ok(());
        }
    };
    let lighting =
        Lighting::new(Vector3::new(0.3, 0.2, 1.0), View::Direction(Vector3::new(0.0, -1.0, 1.0)))?;
    if kind == "repeated" {
        println!("| {kind} | {n} | {mb:.1} | {t_load:.2} s ({} F) | — |", loaded.mesh.num_faces());
        return Ok(());
    }
    let t1 = Instant::now();
    let field = compute_field(&loaded.mesh, &FieldOptions::new(lighting))?;
    let t_field = t1.elapsed().as_secs_f64();
    assert!(field.phi.iter().all(|x| x.is_finite()));
    println!(
        "| {kind} | {n} | {mb:.1} | {t_load:.2} s ({} V, {} F) | {t_field:.2} s |",
        loaded.mesh.num_vertices(),
        loaded.mesh.num_faces()
    );
    Ok(())
}

fn layouts(dir: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    use grainline::limits::{MAX_EDGE_FACES, MAX_POLYGON_CORNERS};
    println!("| layout | n | MB | load | field |\n|---|---|---|---|---|");
    for kind in ["repeated", "polygon", "fan"] {
        for n in [10_000, 100_000, 1_000_000] {
            layout_row(dir, kind, n)?;
        }
    }
    // At and one past the budgets: 64 faces per edge, 10⁶ corners per face.
    layout_row(dir, "repeated", MAX_EDGE_FACES)?;
    layout_row(dir, "polygon", MAX_POLYGON_CORNERS + 1)?;
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = std::env::args().nth(1);
    if arg.as_deref() == Some("layouts") {
        let dir = std::env::temp_dir().join(format!("grainline-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        layouts(&dir)?;
        std::fs::remove_dir_all(&dir)?;
        return Ok(());
    }
    let n: usize = arg.map_or(Ok(1000), |s| s.parse())?;
    let dir = std::env::temp_dir().join(format!("grainline-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("grid.obj");
    write_grid(&path, n)?;
    let bytes = std::fs::metadata(&path)?.len();
    println!("grid {n}x{n}: {} MB, {} threads", bytes / 1_000_000, rayon::current_num_threads());

    for run in 0..3 {
        let t0 = Instant::now();
        let tobj_only =
            tobj::load_obj(&path, &tobj::LoadOptions { triangulate: true, ..Default::default() })?;
        let t_tobj = t0.elapsed();
        drop(tobj_only);
        let t0 = Instant::now();
        let reference = load_obj_with(&path, &LoadOptions::default(), ObjParser::Tobj)?;
        let t_reference = t0.elapsed();
        drop(reference);
        let t0 = Instant::now();
        let loaded = load_obj(&path, &LoadOptions::default())?;
        let t_load = t0.elapsed();
        let t1 = Instant::now();
        let topo = Topology::new(&loaded.mesh)?;
        let t_topo = t1.elapsed();
        let t2 = Instant::now();
        let charts = loaded.mesh.uv.as_ref().map(|uv| UvCharts::new(topo.halfedges(), uv));
        let t_uv = t2.elapsed();
        println!(
            "run {run}: tobj alone {:.0} ms | load_obj with tobj {:.0} ms | load_obj {:.0} ms | topology {:.0} ms | uv charts {:.0} ms | \
             load+topology+charts {:.0} ms  ({} V, {} F, genus {:?}, {} loops, {} charts)",
            t_tobj.as_secs_f64() * 1e3,
            t_reference.as_secs_f64() * 1e3,
            t_load.as_secs_f64() * 1e3,
            t_topo.as_secs_f64() * 1e3,
            t_uv.as_secs_f64() * 1e3,
            (t_load + t_topo + t_uv).as_secs_f64() * 1e3,
            loaded.mesh.num_vertices(),
            loaded.mesh.num_faces(),
            topo.genus(),
            topo.num_boundary_loops(),
            charts.map_or(0, |c| c.charts().len()),
        );
    }
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
