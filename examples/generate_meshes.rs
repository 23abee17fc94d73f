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
    // A gently doubly curved panel (160 × 120 mm, principal radii 400 and 600 mm, convex
    // towards +z); UVs = (s, t) over the grid, i.e. x and y scaled to [0, 1].
    let dome = generate::Grid::new(96, 72).build(|s, t| {
        let (x, y) = (160.0 * s - 80.0, 120.0 * t - 60.0);
        nalgebra::Vector3::new(x, y, -(x * x / 800.0 + y * y / 1200.0))
    });
    let text = obj_string(
        &dome,
        "grainline example: a doubly curved panel, radii 400 and 600 mm (examples/generate_meshes.rs)",
    );
    grainline::output::write_atomic(&dir.join("dome.obj"), text.as_bytes())?;
    println!(
        "wrote examples/data/dome.obj ({} vertices, {} faces)",
        dome.num_vertices(),
        dome.num_faces()
    );
    Ok(())
}
