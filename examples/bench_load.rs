//! Times `load_obj` and the topology on a generated 1000 × 1000 grid (1M vertices, 2M
//! triangles, with UVs), written as OBJ to a temporary directory.
//!
//! Run: `cargo run --release --example bench_load [N]` (N = grid side, default 1000).

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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args().nth(1).map_or(Ok(1000), |s| s.parse())?;
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
