//! `grainline flatten`: a UV layout for a part without one, written as OBJ with `vt`.

use std::path::PathBuf;

use clap::Args;
use grainline::layout::{flatten, LayoutOptions, LayoutReport, Method};
use serde::Serialize;

use super::MeshArgs;

/// Arguments of `grainline flatten`.
#[derive(Debug, Args)]
pub struct FlattenArgs {
    #[command(flatten)]
    mesh: MeshArgs,
    /// Output OBJ: the part's positions and faces with the new UVs (`vt`), written atomically.
    #[arg(long, value_name = "OUT.obj")]
    out: PathBuf,
    /// How each chart is flattened: arap (default), lscm or bff (boundary first flattening).
    #[arg(long, default_value = "arap")]
    method: Method,
    /// Edges whose dihedral angle exceeds this are the first seams tried, degrees.
    #[arg(long, value_name = "DEG", default_value_t = 40.0)]
    crease_angle: f64,
    /// Keep a chart when the stretch of 95 % of its area is at most this (≥ 1).
    #[arg(long, value_name = "X", default_value_t = 2.0)]
    max_stretch: f64,
    /// Also write the layout report (JSON: charts, seams, distortion) here.
    #[arg(long, value_name = "R.json")]
    report: Option<PathBuf>,
}

/// The file `--report` writes.
#[derive(Serialize)]
struct FlattenReport<'a> {
    format: &'static str,
    version: u32,
    mesh: String,
    units: &'static str,
    vertices: usize,
    faces: usize,
    layout: &'a LayoutReport,
}

/// Runs `grainline flatten`.
pub fn run(args: FlattenArgs, quiet: bool) -> anyhow::Result<()> {
    let path = &args.mesh.mesh;
    let mut plan = grainline::output::OutputPlan::new();
    plan.output("--out", &args.out).input("the mesh", path);
    if let Some(r) = &args.report {
        plan.output("--report", r);
    }
    plan.check()?;
    let options = LayoutOptions {
        method: args.method,
        crease_angle_deg: args.crease_angle,
        max_stretch: args.max_stretch,
        ..LayoutOptions::default()
    };
    options.validate().map_err(|e| match e {
        grainline::Error::Setting { key, message } => {
            let flag = match key.as_str() {
                "crease_angle_deg" => "--crease-angle",
                "max_stretch" => "--max-stretch",
                k => k,
            };
            grainline::Error::invalid_arg(flag, message)
        }
        e => e,
    })?;
    let mut mesh = grainline::mesh::load::load_mesh(path, &args.mesh.load_options())?.mesh;
    let layout = flatten(&mesh, &options)?;
    mesh.uv = Some(layout.uv);
    let r = &layout.report;
    let comment = format!(
        "grainline flatten {} ({}): {} chart(s), {} seam edges",
        path.display(),
        r.method.as_str(),
        r.charts,
        r.seam_edges
    );
    let mut staged = grainline::output::Staged::new();
    let text = grainline::mesh::write::obj_string(&mesh, &comment);
    staged.add(&args.out, text.as_bytes())?;
    if let Some(p) = &args.report {
        let report = FlattenReport {
            format: "grainline-layout-report",
            version: 1,
            mesh: path.display().to_string(),
            units: mesh.units.as_str(),
            vertices: mesh.num_vertices(),
            faces: mesh.num_faces(),
            layout: r,
        };
        staged.add(p, &grainline::output::json_pretty(&report)?)?;
    }
    staged.commit()?;
    if !quiet {
        eprintln!(
            "{}: {} chart(s), {} seam edges ({:.3} {u} of seams), area distortion mean {:.3} \
             (max {:.3}), angle distortion mean {:.3} (max {:.3}), edge-length error mean {:.2e} \
             (max {:.2e}), {:.2} s",
            args.out.display(),
            r.charts,
            r.seam_edges,
            r.seam_length,
            r.area_distortion.mean,
            r.area_distortion.max,
            r.angle_distortion.mean,
            r.angle_distortion.max,
            r.edge_length_error.mean,
            r.edge_length_error.max,
            r.seconds,
            u = mesh.units.as_str(),
        );
    }
    Ok(())
}
