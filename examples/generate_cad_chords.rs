//! Writes the generated CAD parts with curved faces (`grainline::generate::cad`: housing,
//! bracket, turned shaft, knob) as binary STL at several chordal steps, the same part at each:
//! `cargo run --release --example generate_cad_chords -- DIR [STEP_DEG ...]` (default steps 1, 10,
//! 15 and 30), as `DIR/NAME-STEP.stl`.

use grainline::generate::cad;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = args.next().unwrap_or_else(|| "target/cad-chords".to_owned());
    let steps: Vec<f64> = args.map(|a| a.parse()).collect::<Result<_, _>>()?;
    let steps = if steps.is_empty() { vec![1.0, 10.0, 15.0, 30.0] } else { steps };
    let dir = std::path::Path::new(&dir);
    std::fs::create_dir_all(dir)?;
    for &step_deg in &steps {
        let parts = [
            cad::housing(&cad::HousingOptions { step_deg, ..Default::default() })?,
            cad::bracket(&cad::BracketOptions { step_deg, ..Default::default() })?,
            cad::turned(&cad::TurnedOptions { step_deg, ..Default::default() })?,
            cad::knob(&cad::KnobOptions { step_deg, ..Default::default() })?,
        ];
        for part in &parts {
            let path = dir.join(format!("{}-{step_deg}.stl", part.name));
            grainline::output::write_atomic(&path, &part.stl_binary())?;
            println!("{}: {} triangles", path.display(), part.triangles.len());
        }
    }
    Ok(())
}
