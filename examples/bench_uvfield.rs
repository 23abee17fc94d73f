//! Benchmark of `uvfield::field_mesh` and `panel::mesh_loops` (min/median/max of in-process runs).
//!
//! ```text
//! cargo run --release --example bench_uvfield [-- RUNS]
//! ```
//!
//! * field_mesh: a cylinder r = 50, h = 100 with 512 × 256 quads (131 584 vertices, 262 144
//!   triangles, one seam), axial grain; geometry is computed once, untimed.
//! * panel: a 300 × 200 mm plate with 24 round holes (r = 8 mm, tolerance 0.01 mm), meshed with
//!   max edge 2 mm and min angle 25°.

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::path::Path;
use std::time::Instant;

use grainline::generate::cylinder;
use grainline::geometry::{Geometry, GeometryOptions};
use grainline::highlight::Symmetry;
use grainline::panel::{mesh_loops, read_svg_loops, PanelOptions};
use grainline::uvfield::{field_mesh, UvFieldOptions};
use nalgebra::Vector3;

fn stats(name: &str, mut t: Vec<f64>) {
    t.sort_by(f64::total_cmp);
    println!(
        "{name}: min {:.3} s, median {:.3} s, max {:.3} s ({} runs)",
        t[0],
        t[t.len() / 2],
        t[t.len() - 1],
        t.len()
    );
}

fn main() {
    let runs: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(5);
    let mesh = cylinder(50.0, 100.0, 512, 256);
    let g = Geometry::compute(&mesh, &GeometryOptions::default());
    let phi = g.angles_of(&vec![Vector3::z(); mesh.num_vertices()]);
    let mut t = Vec::new();
    for _ in 0..runs {
        let s = Instant::now();
        let (fm, rep) =
            field_mesh(&mesh, &g, &phi, Symmetry::Line, &UvFieldOptions::default()).unwrap();
        t.push(s.elapsed().as_secs_f64());
        assert_eq!(fm.triangles.len(), 262_144);
        assert_eq!(rep.seam_pairs, 256);
    }
    stats(&format!("field_mesh ({} vertices)", mesh.num_vertices()), t);

    let mut svg = String::from(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="300mm" height="200mm" viewBox="0 0 300 200"><rect width="300" height="200"/>"#,
    );
    for j in 0..4 {
        for i in 0..6 {
            let (x, y) = (30.0 + 48.0 * i as f64, 25.0 + 50.0 * j as f64);
            svg += &format!(r#"<circle cx="{x}" cy="{y}" r="8"/>"#);
        }
    }
    svg += "</svg>";
    let opts = PanelOptions { max_edge: Some(2.0), ..Default::default() };
    let loops = read_svg_loops(&svg, Path::new("bench.svg"), opts.tolerance).unwrap();
    let mut t = Vec::new();
    let mut faces = 0;
    for _ in 0..runs {
        let s = Instant::now();
        let r = mesh_loops(&loops, Path::new("bench.svg"), &opts).unwrap();
        t.push(s.elapsed().as_secs_f64());
        faces = r.mesh.num_faces();
    }
    stats(&format!("panel ({faces} triangles)"), t);
}
