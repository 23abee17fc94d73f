//! grainline as a library: load a part, compute its highlight field, bend a highlight, solve,
//! and trace the brush strokes — the same stages as `grainline run`, called directly.
//!
//! ```text
//! cargo run --release --example api
//! ```

use grainline::edit::{apply_edits, Edit, EditInput, EditOptions};
use grainline::field::{compute_field, FieldOptions};
use grainline::highlight::tensor::default_epsilon;
use grainline::highlight::{highlight_field_near, InitialField, Lighting, Symmetry, View};
use grainline::mesh::load::{load_obj, LoadOptions};
use grainline::pipeline::trace::{trace, TraceInput};
use grainline::scene::toolpaths::ToolpathSection;
use grainline::solve::{optimize, SolverSettings};
use nalgebra::Vector3;

fn main() -> grainline::Result<()> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/kettle.obj");
    let mesh = load_obj(&path, &LoadOptions::default())?.mesh;

    // Geometry, an initial grain along the UV layout, and its highlight field (Eq. 7).
    let lighting =
        Lighting::new(Vector3::new(0.3, -0.5, 1.0), View::Eye(Vector3::new(0.0, -480.0, 260.0)))?;
    let mut options = FieldOptions::new(lighting);
    options.init = InitialField::Uv;
    options.symmetry = Symmetry::Line;
    let field = compute_field(&mesh, &options)?;
    let g = &field.geometry;

    // A bend edit (paper §5) read from JSON, exactly as a scene holds it.
    let bend: Edit = serde_json::from_str(
        r#"{"tool": "bend", "centre": {"point": [0, -80, 100]}, "radius": 45, "strength": 0.6}"#,
    )
    .expect("a valid edit");
    let input = EditInput {
        mesh: &mesh,
        geometry: g,
        phi: &field.phi,
        lighting: &lighting,
        h: &field.h,
        symmetry: options.symmetry,
        gradient_form: options.gradient_form,
    };
    let edited = apply_edits(&input, &[bend], &EditOptions::default())?;

    // The highlight energy (Eq. 8) with the edit's targets, solved by sparse LM.
    let m: Vec<f64> = field.highlight.m.iter().map(|m| m.norm()).collect();
    let epsilon = default_epsilon(&m);
    let settings = SolverSettings::default();
    let term = edited.highlight_term(
        g,
        options.symmetry,
        options.gradient_form,
        settings.highlight_energy,
        epsilon,
    );
    let solved = optimize(&mesh, &term, &edited.phi, &edited.support, &settings)?;
    let after = highlight_field_near(
        g,
        &solved.phi,
        options.symmetry,
        options.gradient_form,
        &edited.h,
        edited.h_gradient.as_deref(),
    );
    println!(
        "{} vertices edited, {} unknowns, {} iterations ({:?}); |ℓ| median {:.3e}",
        solved.report.edited,
        solved.report.unknowns,
        solved.report.iterations.len(),
        solved.report.stop,
        {
            let mut n: Vec<f64> = after.ell.iter().map(|l| l.norm()).collect();
            n.sort_by(f64::total_cmp);
            n[n.len() / 2]
        }
    );

    // Brush strokes 4 mm wide on the part, exported as G-code: the trace stage of `grainline
    // run`, with the solver's fabrication constraints (none here) measured on the strokes.
    let mut section: ToolpathSection =
        serde_json::from_str(r#"{"placement": {"width": 4}}"#).expect("a valid toolpaths section");
    section.gcode = Some("kettle.ngc".into());
    let traced = trace(&TraceInput {
        toolpaths: Some(&section),
        constraints: &settings.constraints,
        mesh: &mesh,
        geometry: g,
        phi: &solved.phi,
        symmetry: options.symmetry,
        keep_map: false,
        keep_field_mesh: false,
        surfaces: None,
        straddle: &[],
    })?;
    let (job, uv) = (&traced.job, &traced.uv);
    println!(
        "{} strokes, {:.0} mm brushed on the part, flat layout scale {:.1}, G-code {} lines",
        job.report.stroke_count,
        job.report.cut_length_mm,
        uv.uv_scale,
        job.gcode.as_deref().map_or(0, |g| g.lines().count())
    );
    Ok(())
}
