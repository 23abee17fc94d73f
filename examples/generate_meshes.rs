//! Regenerates the meshes bundled under `examples/data/` from grainline's own generators.
//!
//! ```text
//! cargo run --release --example generate_meshes
//! ```

use grainline::generate;
use grainline::mesh::write::obj_string;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data");
    std::fs::create_dir_all(&dir)?;
    // A kettle-like body of revolution, 180 mm tall, in mm; UVs = (angle / 2π, profile t).
    let kettle = generate::revolve(
        |t| {
            let r = 55.0 + 30.0 * (std::f64::consts::PI * (0.15 + 0.8 * t)).sin() - 18.0 * t * t;
            (r, 180.0 * t)
        },
        96,
        48,
    );
    let text = obj_string(
        &kettle,
        "grainline example: a kettle body of revolution (examples/generate_meshes.rs)",
    );
    grainline::output::write_atomic(&dir.join("kettle.obj"), text.as_bytes())?;
    println!(
        "wrote examples/data/kettle.obj ({} vertices, {} faces)",
        kettle.num_vertices(),
        kettle.num_faces()
    );
    Ok(())
}
