//! Writes the five generated CAD parts (`grainline::generate::cad`) as binary STL, the way CAD
//! systems export them, and prints their counts.
//!
//! ```text
//! cargo run --release --example generate_cad [DIR]     # DIR defaults to target/cad-parts
//! ```

use grainline::generate::cad::{self, CadPart};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "target/cad-parts".to_owned());
    let dir = std::path::Path::new(&dir);
    std::fs::create_dir_all(dir)?;
    let parts: [CadPart; 5] = [
        cad::housing(&Default::default())?,
        cad::plate(&Default::default())?,
        cad::bracket(&Default::default())?,
        cad::turned(&Default::default())?,
        cad::knob(&Default::default())?,
    ];
    for part in &parts {
        let path = dir.join(format!("{}.stl", part.name));
        grainline::output::write_atomic(&path, &part.stl_binary())?;
        let mesh = part.mesh();
        let smallest = (0..part.triangles.len())
            .map(|t| part.smallest_angle_deg(t))
            .fold(f64::INFINITY, f64::min);
        println!(
            "{}: {} vertices, {} triangles, {} analytic faces, units {}, smallest angle {:.2}°, \
             {} planar slivers (< 5°); volume {:.6} (analytic {:.6})",
            path.display(),
            mesh.num_vertices(),
            mesh.num_faces(),
            part.faces.len(),
            part.units.as_str(),
            smallest,
            part.planar_slivers(5.0),
            part.enclosed_volume(),
            part.volume,
        );
    }
    Ok(())
}
