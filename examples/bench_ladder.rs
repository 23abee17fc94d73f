//! The scale ladder (issue 48, item 5): a whole `grainline run` — a bend, strokes (SVG), the
//! as-brushed measure, no render — on parts of 10⁴, 10⁵ and 10⁶ vertices, each stage's time
//! and the process's peak resident memory per stage (the run report's `stages`), printed as a
//! markdown table.
//!
//! ```text
//! cargo build --profile test --bin grainline --example bench_ladder
//! target/debug/examples/bench_ladder [--scan 1e4,1e5] [--cylinder 1e4,1e5,1e6]
//! ```
//!
//! Parts: `scan` is `generate::scan::bust_scan` with its grid cell set for the vertex count
//! (the noise scaled with the cell), written as OBJ without UVs, so the run makes a layout;
//! `cylinder` is `generate::cylinder` (r 30, h 80) with its own UVs. The bend sits on the
//! key light's side of the part, radius 8 % of the diagonal; the brush is 0.8 % of the
//! diagonal, overlap 0.1. Each run is a fresh `grainline` process (the binary beside this
//! example), so its memory is its own.

use std::path::{Path, PathBuf};

use grainline::mesh::Mesh;

fn main() {
    let mut scan = vec![1e4, 1e5];
    let mut cylinder = vec![1e4, 1e5, 1e6];
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let list = |s: Option<String>| -> Vec<f64> {
            s.unwrap_or_default().split(',').filter_map(|x| x.trim().parse().ok()).collect()
        };
        match a.as_str() {
            "--scan" => scan = list(args.next()),
            "--cylinder" => cylinder = list(args.next()),
            _ => {
                eprintln!("usage: bench_ladder [--scan N,...] [--cylinder N,...]");
                std::process::exit(2);
            }
        }
    }
    let exe = std::env::current_exe().unwrap();
    let grainline = exe.parent().and_then(Path::parent).unwrap().join("grainline");
    let dir = std::env::temp_dir().join(format!("grainline-ladder-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let stages = ["load", "layout", "refine", "field", "edits", "solve", "toolpaths", "as-brushed"];
    println!(
        "| part | vertices | {} | wall s | peak resident MB (stage) | KB per vertex |",
        stages.join(" s | ") + " s"
    );
    println!("|---|---:|{}---:|---|---:|", "---:|".repeat(stages.len() + 1));
    let parts = scan.iter().map(|&n| ("scan", n)).chain(cylinder.iter().map(|&n| ("cylinder", n)));
    for (kind, n) in parts {
        let mesh = part(kind, n);
        let name = format!("{kind}-{n:.0}");
        let scene = write_scene(&dir, &name, &mesh);
        let report = dir.join(format!("{name}-report.json"));
        let status = std::process::Command::new(&grainline)
            .args(["--quiet", "run"])
            .arg(&scene)
            .arg("--report")
            .arg(&report)
            .status()
            .expect("the grainline binary beside this example (cargo build --bin grainline)");
        if !status.success() {
            println!("| {kind} | {} | run failed ({status}) |", mesh.num_vertices());
            continue;
        }
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        let all = r["stages"].as_array().cloned().unwrap_or_default();
        let secs = |s: &str| -> String {
            let t: f64 =
                all.iter().filter(|x| x["stage"] == s).filter_map(|x| x["seconds"].as_f64()).sum();
            if all.iter().any(|x| x["stage"] == s) {
                format!("{t:.2}")
            } else {
                "–".into()
            }
        };
        let peak = all
            .iter()
            .filter_map(|x| Some((x["peak_rss_mb"].as_f64()?, x["stage"].as_str()?.to_owned())))
            .max_by(|a, b| a.0.total_cmp(&b.0));
        let v = r["vertices"].as_f64().unwrap_or(0.0);
        let (peak_s, per_v) = match &peak {
            Some((mb, st)) => (format!("{mb:.0} ({st})"), format!("{:.2}", mb * 1e3 / v)),
            None => ("–".into(), "–".into()),
        };
        let cols: Vec<String> = stages.iter().map(|s| secs(s)).collect();
        println!(
            "| {kind} | {v:.0} | {} | {:.2} | {peak_s} | {per_v} |",
            cols.join(" | "),
            r["wall_seconds"].as_f64().unwrap_or(0.0)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The part of `kind` with about `n` vertices.
fn part(kind: &str, n: f64) -> Mesh {
    if kind == "scan" {
        use grainline::generate::scan::{bust_scan, ScanOptions};
        // 1.5 mm cells give 59,740 vertices; the count goes as 1 / cell².
        let cell = 1.5 * (59_740.0 / n).sqrt();
        let o = ScanOptions { cell, noise: 0.08 * cell / 1.5, ..ScanOptions::default() };
        bust_scan(&o).expect("a bust scan")
    } else {
        // 2π·30 around, 80 along, square cells: around·along ≈ n.
        let along = (n * 80.0 / (std::f64::consts::TAU * 30.0)).sqrt().round().max(2.0);
        let around = (n / along).round().max(8.0);
        grainline::generate::cylinder(30.0, 80.0, around as usize, along as usize)
    }
}

/// Writes the part as OBJ and its scene beside it; returns the scene's path.
fn write_scene(dir: &Path, name: &str, mesh: &Mesh) -> PathBuf {
    let obj = dir.join(format!("{name}.obj"));
    std::fs::write(&obj, grainline::mesh::write::obj_string(mesh, name)).unwrap();
    let (lo, hi) =
        mesh.positions.iter().fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(lo, hi), p| {
            ([0, 1, 2].map(|k| lo[k].min(p[k])), [0, 1, 2].map(|k| hi[k].max(p[k])))
        });
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    // The vertex farthest towards the eye (−y) at mid height: the bend's centre.
    let mid = 0.5 * (lo[2] + hi[2]);
    let c = mesh
        .positions
        .iter()
        .filter(|p| (p[2] - mid).abs() < 0.1 * (hi[2] - lo[2]))
        .min_by(|a, b| a[1].total_cmp(&b[1]))
        .unwrap_or(&mesh.positions[0]);
    let scene = serde_json::json!({
        "mesh": obj.file_name().unwrap().to_string_lossy(),
        "units": "mm",
        "lights": [{"type": "directional", "key": true, "direction": [0.3, -0.6, 0.7]}],
        "view": {"eye": [0.5 * (lo[0] + hi[0]), lo[1] - 2.0 * diag, mid],
                 "target": [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), mid]},
        "edits": [{"tool": "bend", "centre": {"point": [c[0], c[1], c[2]]},
                   "radius": 0.08 * diag, "strength": 0.8, "direction": [0, 0, 1]}],
        "toolpaths": {"svg": format!("{name}.svg"),
                      "placement": {"width": 0.008 * diag, "overlap": 0.1}}
    });
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path
}
