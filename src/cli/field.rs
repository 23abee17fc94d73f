//! `grainline field`.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use grainline::field::{compute_field, read_directions, FieldFile, FieldOptions};
use grainline::geometry::NormalSource;
use grainline::highlight::{InitialField, Lighting, Symmetry, View};

use super::progress::Spinner;
use super::MeshArgs;

/// Arguments of `grainline field`.
#[derive(Debug, Args)]
pub struct FieldArgs {
    #[command(flatten)]
    mesh: MeshArgs,
    /// Direction towards the (distant) light, X,Y,Z (required unless --light-position is given).
    #[arg(
        long,
        value_name = "X,Y,Z",
        allow_hyphen_values = true,
        required_unless_present = "light_position"
    )]
    light: Option<String>,
    /// Position of a point light, X,Y,Z (per-vertex light directions; overrides --light).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    light_position: Option<String>,
    /// Direction towards a distant viewer, X,Y,Z (required unless --eye is given).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, required_unless_present = "eye")]
    view: Option<String>,
    /// Position of a point eye, X,Y,Z (per-vertex view directions; overrides --view).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    eye: Option<String>,
    /// Initial field: uv, smooth, curvature-min, curvature-max or world:X,Y,Z.
    #[arg(long, default_value = "smooth", conflicts_with = "directions")]
    init: String,
    /// Per-vertex directions: a JSON object whose `u` holds one [x, y, z] per vertex.
    #[arg(long, value_name = "FILE")]
    directions: Option<PathBuf>,
    /// Line field (k = 2) for centrally symmetric BRDFs; default oriented (k = 1).
    #[arg(long)]
    symmetric: bool,
    /// Initial vertex normals: angle-weighted, area-weighted or file.
    #[arg(long, default_value = "angle-weighted", value_parser = parse_normals)]
    normals: NormalSource,
    /// hᵀn above which a vertex is a critical point.
    #[arg(long, default_value_t = 0.9995)]
    critical_threshold: f64,
    /// Output FIELD.json.
    #[arg(long, value_name = "FIELD.json")]
    out: PathBuf,
}

fn parse_normals(s: &str) -> Result<NormalSource, String> {
    match s {
        "angle-weighted" => Ok(NormalSource::AngleWeighted),
        "area-weighted" => Ok(NormalSource::AreaWeighted),
        "file" => Ok(NormalSource::File),
        _ => Err(format!("{s:?}: expected angle-weighted, area-weighted or file")),
    }
}

/// Runs `grainline field`.
pub fn run(args: FieldArgs, quiet: bool) -> anyhow::Result<()> {
    let stages = Spinner::new(quiet);
    let view = match (&args.eye, &args.view) {
        (Some(e), _) => View::Eye(grainline::highlight::parse_vec3("eye", e)?),
        (None, Some(v)) => View::Direction(grainline::highlight::parse_vec3("view", v)?),
        (None, None) => anyhow::bail!("give --view X,Y,Z or --eye X,Y,Z"),
    };
    let light_position = match &args.light_position {
        Some(p) => Some(grainline::highlight::parse_vec3("light-position", p)?),
        None => None,
    };
    let light = match (&light_position, &args.light) {
        (Some(_), _) => None,
        (None, Some(l)) => {
            Some(Lighting::new(grainline::highlight::parse_vec3("light", l)?, view)?)
        }
        (None, None) => anyhow::bail!("give --light X,Y,Z or --light-position X,Y,Z"),
    };
    let mut plan = grainline::output::OutputPlan::new();
    plan.output("--out", &args.out).input("the mesh", &args.mesh.mesh);
    if let Some(d) = &args.directions {
        plan.input("--directions", d);
    }
    plan.check()?;
    stages.stage("loading mesh");
    let loaded = grainline::mesh::load::load_mesh(&args.mesh.mesh, &args.mesh.load_options())?;
    let mesh = loaded.mesh;
    let lighting = match (light, light_position) {
        (Some(l), _) => l,
        (None, Some(p)) => {
            let centre = grainline::highlight::lighting::centre_of(&mesh.positions);
            Lighting::point(p, centre, view)?
        }
        (None, None) => anyhow::bail!("give --light X,Y,Z or --light-position X,Y,Z"),
    };
    let init = match &args.directions {
        Some(path) => InitialField::Directions(read_directions(path, mesh.num_vertices())?),
        None => args.init.parse::<InitialField>()?,
    };
    let mut options = FieldOptions::new(lighting);
    options.init = init;
    options.symmetry = Symmetry::from_symmetric(args.symmetric);
    options.geometry.normals = args.normals;
    options.critical_threshold = args.critical_threshold;
    stages.stage("geometry, initial field and highlights");
    // A failure on the part names its file.
    let result =
        compute_field(&mesh, &options).with_context(|| args.mesh.mesh.display().to_string())?;
    let file = FieldFile::new(&mesh, &args.mesh.mesh.display().to_string(), &options, &result)
        .with_context(|| args.mesh.mesh.display().to_string())?;
    stages.stage("writing");
    grainline::output::write_json_compact_atomic(&args.out, &file)
        .with_context(|| format!("writing {}", args.out.display()))?;
    drop(stages);
    if !quiet {
        let crit = result.critical.iter().filter(|&&c| c).count();
        eprintln!(
            "wrote {} ({} vertices, {} critical, {} fallback directions; units {})",
            args.out.display(),
            mesh.num_vertices(),
            crit,
            result.fallback_vertices.len(),
            mesh.units.as_str()
        );
    }
    Ok(())
}
