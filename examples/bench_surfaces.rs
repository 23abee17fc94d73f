//! Surface recognition (`grainline::geometry::surfaces`) timed on the generated CAD parts at
//! several chordal steps and on the meshes of `../shared/meshes` (or `GRAINLINE_SHARED`): per
//! part its vertices, the surfaces and creases found, the share of the area on none, and the
//! median time of five runs.
//!
//! ```text
//! cargo run --release --example bench_surfaces
//! ```

use std::path::PathBuf;
use std::time::Instant;

use grainline::generate::cad;
use grainline::geometry::surfaces::recognize;
use grainline::mesh::load::{load_mesh, LoadOptions};
use grainline::mesh::Mesh;

/// The part as a float32 STL stores it, welded.
fn stl_mesh(part: &cad::CadPart) -> Mesh {
    let mut p = part.clone();
    for t in &mut p.triangles {
        for v in t.iter_mut() {
            *v = v.map(|c| c as f32 as f64);
        }
    }
    p.mesh()
}

fn row(name: &str, mesh: &Mesh) {
    let mut times: Vec<f64> = (0..5)
        .map(|_| {
            let t = Instant::now();
            let s = recognize(mesh);
            std::hint::black_box(&s);
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    let s = recognize(mesh);
    let r = s.report(mesh);
    let nv = mesh.num_vertices();
    println!(
        "| {name} | {nv} | {} | {} | {:.1} % | {:.1} | {:.3} |",
        r.surfaces.len(),
        r.creases.len(),
        100.0 * r.unrecognized_area_share,
        1e3 * times[2],
        1e4 * times[2] / nv.max(1) as f64,
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("| part | vertices | surfaces | creases | area on none | ms | s per 10k vertices |");
    println!("|---|---|---|---|---|---|---|");
    for step_deg in [1.0, 10.0, 15.0, 30.0] {
        let parts = [
            cad::housing(&cad::HousingOptions { step_deg, ..Default::default() })?,
            cad::bracket(&cad::BracketOptions { step_deg, ..Default::default() })?,
            cad::turned(&cad::TurnedOptions { step_deg, ..Default::default() })?,
            cad::knob(&cad::KnobOptions { step_deg, ..Default::default() })?,
        ];
        for part in &parts {
            row(&format!("{} at {step_deg}°", part.name), &stl_mesh(part));
        }
    }
    let shared = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("../shared"))
        .join("meshes");
    let mut files: Vec<PathBuf> = ["", "cad"]
        .iter()
        .filter_map(|d| std::fs::read_dir(shared.join(d)).ok())
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("").to_lowercase();
            matches!(ext.as_str(), "obj" | "stl" | "ply")
        })
        .collect();
    files.sort();
    for f in files {
        let loaded = load_mesh(&f, &LoadOptions::default().tolerant())?;
        let name = f.file_name().and_then(|n| n.to_str()).unwrap_or("?");
        row(name, &loaded.mesh);
    }
    Ok(())
}
