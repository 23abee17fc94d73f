//! Flattening every mesh of ../shared/meshes with each method: time, charts, seams and
//! distortion (docs/benchmarks.md, "Flattening").
//!
//! ```text
//! cargo run --release --example bench_layout [-- RUNS]
//! ```
//!
//! `GRAINLINE_SHARED` overrides where ../shared is; `BENCH_MESH=NAME` runs only the meshes
//! whose file name contains NAME. Each mesh is loaded with the default options (blub's quads split, teapot welded at 1e-6 so
//! its patches join, its one non-manifold vertex accepted). Times are the median of RUNS runs (default 3).

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::path::PathBuf;

use grainline::layout::{flatten, LayoutOptions, Method};
use grainline::mesh::load::{load_obj, LoadOptions};

fn main() {
    let runs: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(3);
    let shared = std::env::var_os("GRAINLINE_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let dir = shared.join("meshes");
    if !dir.exists() {
        eprintln!("skipping: {} not found", dir.display());
        return;
    }
    println!(
        "| mesh | faces | method | time s | charts | seam edges | area dist. mean / p95 | angle dist. mean / p95 | angle error ° mean | edge-length error mean / max | fallbacks (ARAP / BFF, not disk) | BFF harmonic | largest chart | cuts (creases / cones / bisections / merges) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let only = std::env::var("BENCH_MESH").ok();
    for name in [
        "paper-crumpled2.obj",
        "spot_triangulated.obj",
        "blub_quadrangulated.obj",
        "teapot.obj",
        "fandisk.obj",
        "rocker-arm.obj",
        "oloid4096_tri.obj",
        "stanford-bunny.obj",
    ] {
        if only.as_deref().is_some_and(|o| !name.contains(o)) {
            continue;
        }
        let mut options = LoadOptions::default();
        if name == "teapot.obj" {
            options = LoadOptions { weld: Some(1e-6), allow_nonmanifold: true, ..options };
        }
        let mesh = load_obj(&dir.join(name), &options).expect(name).mesh;
        for method in [Method::Lscm, Method::Arap, Method::Bff] {
            let opts = LayoutOptions { method, ..LayoutOptions::default() };
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..runs.max(1) {
                let l = flatten(&mesh, &opts).expect(name);
                times.push(l.report.seconds);
                last = Some(l.report);
            }
            times.sort_by(f64::total_cmp);
            let r = last.expect("one run");
            println!(
                "| {name} | {} | {} | {:.3} | {} | {} | {:.3} / {:.3} | {:.3} / {:.3} | {:.2} | {:.2e} / {:.2e} | {} / {} ({}) | {} | {} | {} / {} / {} / {} |",
                mesh.num_faces(),
                method.as_str(),
                times[times.len() / 2],
                r.charts,
                r.seam_edges,
                r.area_distortion.mean,
                r.area_distortion.p95,
                r.angle_distortion.mean,
                r.angle_distortion.p95,
                r.angle_error_deg.mean,
                r.edge_length_error.mean,
                r.edge_length_error.max,
                r.arap_fallbacks,
                r.bff_fallbacks,
                r.bff_not_disk,
                r.bff_harmonic,
                r.largest_chart_faces,
                r.cuts.creases,
                r.cuts.cones,
                r.cuts.bisections,
                r.cuts.merges,
            );
        }
    }
}
