//! Writes the generated scans and sculpted parts (`grainline::generate::scan`) the way a
//! scanner or a sculpting tool exports them — the scans as binary PLY, the sculpted parts as
//! OBJ (the UV-mapped head with its UVs) — and prints their counts.
//!
//! ```text
//! cargo run --release --example generate_scans [DIR]     # DIR defaults to target/scan-parts
//! ```

use grainline::generate::scan::{self, ScanOptions, SculptOptions};
use grainline::mesh::Mesh;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "target/scan-parts".to_owned());
    let dir = std::path::Path::new(&dir);
    std::fs::create_dir_all(dir)?;
    let scan = ScanOptions::default();
    let rock = ScanOptions { cell: 1.4, noise: 0.06, ..ScanOptions::default() };
    // A rougher scanner: 0.25 mm of noise at the same 1 mm spacing (facet dihedrals of about
    // 35° RMS, docs/math.md §3, "Creases on a noisy part").
    let rough = ScanOptions { noise: 0.25, seed: 2, ..ScanOptions::default() };
    let sculpt = SculptOptions::default();
    // Deeper, tighter folds on a smaller creature: slopes of about 45°, dozens of critical
    // points of the key light's half vector under one brush (docs/benchmarks.md).
    let deep =
        SculptOptions { cell: 0.9, wrinkle_height: 0.5, wrinkle_wavelength: 3.0, scale: 0.8 };
    let parts: [(&str, Mesh, bool); 6] = [
        ("bust_scan", scan::bust_scan(&scan)?, true),
        ("bust_scan_rough", scan::bust_scan(&rough)?, true),
        ("rock_scan", scan::rock_scan(&rock)?, true),
        ("sculpt_creature", scan::sculpt_creature(&sculpt)?, false),
        ("sculpt_creature_deep", scan::sculpt_creature(&deep)?, false),
        ("uv_character", scan::uv_character(&sculpt)?, false),
    ];
    for (name, mesh, ply) in &parts {
        let path = if *ply {
            let path = dir.join(format!("{name}.ply"));
            grainline::output::write_atomic(&path, &ply_binary(mesh, name))?;
            path
        } else {
            let path = dir.join(format!("{name}.obj"));
            let text = grainline::mesh::write::obj_string(
                mesh,
                &format!("grainline generate::scan {name} (examples/generate_scans.rs)"),
            );
            grainline::output::write_atomic(&path, text.as_bytes())?;
            path
        };
        let (lo, hi) = mesh.bounding_box().ok_or("empty mesh")?;
        let edges: f64 = mesh
            .faces
            .iter()
            .map(|f| {
                (0..3)
                    .map(|k| {
                        (mesh.positions[f[k] as usize] - mesh.positions[f[(k + 1) % 3] as usize])
                            .norm()
                    })
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (3 * mesh.num_faces()) as f64;
        println!(
            "{}: {} vertices, {} triangles, mean edge {:.2} mm, box {:.0} × {:.0} × {:.0} mm{}",
            path.display(),
            mesh.num_vertices(),
            mesh.num_faces(),
            edges,
            hi.x - lo.x,
            hi.y - lo.y,
            hi.z - lo.z,
            if mesh.uv.is_some() { ", UVs" } else { "" }
        );
    }
    Ok(())
}

/// The mesh as a binary little-endian PLY (float32 positions, uchar-counted int32 faces), as
/// scanners write them.
fn ply_binary(mesh: &Mesh, name: &str) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment grainline generate::scan {name}\n\
         comment units: mm\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.num_vertices(),
        mesh.num_faces()
    );
    let mut out = header.into_bytes();
    for p in &mesh.positions {
        for k in 0..3 {
            out.extend_from_slice(&(p[k] as f32).to_le_bytes());
        }
    }
    for f in &mesh.faces {
        out.push(3);
        for &i in f {
            out.extend_from_slice(&(i as i32).to_le_bytes());
        }
    }
    out
}
