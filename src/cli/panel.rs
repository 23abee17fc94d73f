//! `grainline panel`: a flat sheet-metal blank from an SVG outline, meshed and written as OBJ.

use std::path::PathBuf;

use clap::Args;
use grainline::panel::{panel_from_svg, PanelOptions};

/// Arguments of `grainline panel`.
#[derive(Debug, Args)]
pub struct PanelArgs {
    /// The outline SVG: closed paths (holes by the even-odd rule), in its own units.
    pub outline: PathBuf,
    /// Output OBJ (mm, UV = XY), written atomically.
    #[arg(long, value_name = "PANEL.obj")]
    out: PathBuf,
    /// Longest triangle edge, mm (default: no limit).
    #[arg(long, value_name = "MM")]
    max_edge: Option<f64>,
    /// Smallest triangle angle the refinement aims for, degrees (0–34).
    #[arg(long, value_name = "DEG", default_value_t = 25.0)]
    min_angle: f64,
    /// Curve flattening tolerance, mm.
    #[arg(long, value_name = "MM", default_value_t = 0.01)]
    tolerance: f64,
}

/// Runs `grainline panel`.
pub fn run(args: PanelArgs, quiet: bool) -> anyhow::Result<()> {
    grainline::output::OutputPlan::new()
        .output("--out", &args.out)
        .input("the outline", &args.outline)
        .check()?;
    let opts = PanelOptions {
        max_edge: args.max_edge,
        min_angle_deg: args.min_angle,
        tolerance: args.tolerance,
        ..Default::default()
    };
    let r = panel_from_svg(&args.outline, &opts).map_err(|e| match e {
        grainline::Error::Setting { key, message } => {
            let flag = match key.as_str() {
                "max_edge" => "--max-edge",
                "min_angle_deg" => "--min-angle",
                "tolerance" => "--tolerance",
                k => k,
            };
            grainline::Error::invalid_arg(flag, message)
        }
        e => e,
    })?;
    let comment = format!(
        "grainline panel from {}\nmax edge {}, min angle {} deg, tolerance {} mm",
        args.outline.display(),
        args.max_edge.map_or_else(|| "unlimited".to_string(), |e| format!("{e} mm")),
        args.min_angle,
        args.tolerance
    );
    let text = grainline::mesh::write::obj_string(&r.mesh, &comment);
    grainline::output::write_atomic(&args.out, text.as_bytes())?;
    if !quiet {
        eprintln!(
            "{}: {} vertices, {} triangles, {} loop(s), area {:.3} mm^2, min angle {:.2} deg, \
             max edge {:.3} mm{}",
            args.out.display(),
            r.mesh.num_vertices(),
            r.mesh.num_faces(),
            r.loops,
            r.mesh.area(),
            r.min_angle_deg,
            r.max_edge,
            if r.refinement_complete { "" } else { " (refinement incomplete: vertex budget)" }
        );
    }
    Ok(())
}
