//! `grainline inspect`: prints the library's [`InspectReport`] as text or JSON.
//!
//! Inspect is a diagnostic: it loads with every structural problem tolerated (non-manifold
//! elements, inconsistent orientation) and reports them; only unreadable files fail.

use clap::Args;
use grainline::geometry::surfaces::{Primitive, SurfaceReport};
use grainline::mesh::report::{InspectReport, QualityReport};
use grainline::mesh::topology::Topology;
use grainline::mesh::uv_charts::UvCharts;

use super::MeshArgs;

/// Arguments of `grainline inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    #[command(flatten)]
    mesh: MeshArgs,
    /// Print JSON instead of text (fields in docs/formats.md, "inspect --json").
    #[arg(long)]
    json: bool,
    /// Do not recognize the part's surfaces (planes, cylinders, cones, spheres, tori).
    #[arg(long)]
    no_surfaces: bool,
}

/// Runs `grainline inspect`.
pub fn run(args: InspectArgs, _quiet: bool) -> anyhow::Result<()> {
    let path = &args.mesh.mesh;
    let loaded = grainline::mesh::load::load_mesh(path, &args.mesh.load_options().tolerant())?;
    let topo = Topology::new(&loaded.mesh)?;
    let charts = loaded.mesh.uv.as_ref().map(|uv| UvCharts::new(topo.halfedges(), uv));
    let report =
        InspectReport::new(path, &loaded, &topo, charts.as_ref(), QualityReport::new(&loaded));
    let surfaces = recognize(&loaded.mesh, args.no_surfaces);
    if args.json {
        let out = InspectOutput { report: &report, surfaces: surfaces.as_ref() };
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print!("{}", text(&report));
        if let Some(s) = &surfaces {
            print!("{}", surfaces_text(s, report.units));
        }
    }
    Ok(())
}

/// `inspect --json`: the mesh report, and the surfaces recognized on the part.
#[derive(serde::Serialize)]
struct InspectOutput<'a> {
    #[serde(flatten)]
    report: &'a InspectReport,
    /// Absent with `--no-surfaces`.
    #[serde(skip_serializing_if = "Option::is_none")]
    surfaces: Option<&'a SurfaceReport>,
}

fn recognize(mesh: &grainline::mesh::Mesh, off: bool) -> Option<SurfaceReport> {
    (!off).then(|| grainline::geometry::surfaces::recognize(mesh).report(mesh))
}

fn surfaces_text(r: &SurfaceReport, u: impl std::fmt::Display) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    if r.surfaces.is_empty() {
        let _ = writeln!(
            s,
            "  surfaces: none recognized (no planes, cylinders, cones, spheres or tori: a \
             free-form part, a scan or a sculpt; its geometry is fitted to its vertices)"
        );
        return s;
    }
    let _ = writeln!(
        s,
        "  surfaces: {} recognized (within {:.3e} {u}); {} face(s), {:.1} % of the area, on none",
        r.surfaces.len(),
        r.tolerance,
        r.unrecognized_faces,
        100.0 * r.unrecognized_area_share
    );
    for (i, x) in r.surfaces.iter().enumerate() {
        let _ = writeln!(
            s,
            "    #{i} {}: {} faces, area {:.6} {u}^2, residual rms {:.2e} max {:.2e} {u}",
            describe(&x.primitive, &u),
            x.faces,
            x.area,
            x.rms_residual,
            x.max_residual
        );
    }
    let _ = writeln!(s, "  creases between surfaces: {}", r.creases.len());
    for c in &r.creases {
        let _ = writeln!(
            s,
            "    #{} | #{}: {} edge(s), length {:.6} {u}, normals {:.2}° apart",
            c.surfaces[0], c.surfaces[1], c.edges, c.length, c.angle_deg
        );
    }
    s
}

fn describe(p: &Primitive, u: &impl std::fmt::Display) -> String {
    let v = |a: &[f64; 3]| format!("[{:.6}, {:.6}, {:.6}]", a[0], a[1], a[2]);
    match p {
        Primitive::Plane { normal, offset } => {
            format!("plane, normal {}, offset {offset:.6} {u}", v(normal))
        }
        Primitive::Cylinder { point, axis, radius } => {
            format!("cylinder, radius {radius:.6} {u}, axis {} through {}", v(axis), v(point))
        }
        Primitive::Cone { apex, axis, half_angle } => format!(
            "cone, half-angle {:.4}°, axis {} from apex {}",
            half_angle.to_degrees(),
            v(axis),
            v(apex)
        ),
        Primitive::Sphere { center, radius } => {
            format!("sphere, radius {radius:.6} {u}, centre {}", v(center))
        }
        Primitive::Torus { center, axis, major, minor } => format!(
            "torus, tube radius {minor:.6} {u}, major radius {major:.6} {u}, axis {} through {}",
            v(axis),
            v(center)
        ),
    }
}

fn text(r: &InspectReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let u = r.units;
    let p = &r.problems;
    let b = &r.bounding_box;
    let _ = writeln!(s, "{} ({})", r.file, r.format.to_uppercase());
    let _ = writeln!(
        s,
        "  {} vertices ({} in the file), {} edges, {} triangles ({} polygons split)",
        r.vertices, r.file_vertices, r.edges, r.faces, r.polygons_split
    );
    if r.objects.len() > 1 {
        let _ = writeln!(s, "  objects: {}", r.objects.join(", "));
    }
    let _ = writeln!(
        s,
        "  bounding box: [{:.6}, {:.6}, {:.6}] to [{:.6}, {:.6}, {:.6}] {u} (size {:.6} x {:.6} x {:.6} {u})",
        b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2], b.size[0], b.size[1], b.size[2]
    );
    let _ = writeln!(s, "  area: {:.6} {u}^2", r.area);
    let genus = r.genus.map_or("undefined (non-manifold)".to_string(), |g| g.to_string());
    let _ = writeln!(
        s,
        "  components: {}, Euler characteristic: {}, genus: {genus}",
        r.components.len(),
        r.euler_characteristic
    );
    let lens: Vec<String> = r.boundary_loops.iter().take(20).map(|l| l.edges.to_string()).collect();
    let more = if r.boundary_loops.len() > 20 { ", ..." } else { "" };
    if r.boundary_loops.is_empty() {
        let _ = writeln!(s, "  boundary: none (closed)");
    } else {
        let _ = writeln!(
            s,
            "  boundary: {} loop(s) in {} connected piece(s), edges per loop: {}{more}; {} boundary vertices",
            r.boundary_loops.len(),
            r.boundary_components,
            lens.join(", "),
            r.boundary_vertices
        );
    }
    match &r.uv {
        None => {
            let _ = writeln!(s, "  UVs: none");
        }
        Some(uv) => {
            let mirrored: Vec<String> = uv
                .mirrored_charts
                .iter()
                .map(|c| format!("#{} ({} faces)", c.chart, c.faces))
                .collect();
            let _ = writeln!(
                s,
                "  UVs: {} chart(s), {} seam edges, {} flipped triangles, {} degenerate, {} against their chart",
                uv.charts, uv.seam_edges, uv.flipped_faces, uv.degenerate_faces, uv.faces_against_chart
            );
            let _ = writeln!(
                s,
                "  mirrored charts: {}{}; {} chart(s) with flipped triangles",
                if mirrored.is_empty() {
                    "none".to_string()
                } else {
                    format!("{} — ", uv.mirrored_chart_count)
                },
                mirrored.join(", "),
                uv.charts_with_flipped_faces
            );
            let pairs: Vec<String> =
                uv.overlapping_charts.iter().map(|[a, b]| format!("#{a} and #{b}")).collect();
            let more = if uv.overlapping_chart_pairs > pairs.len() { ", ..." } else { "" };
            let _ = writeln!(
                s,
                "  overlapping charts: {}",
                if pairs.is_empty() {
                    "none".to_string()
                } else {
                    format!(
                        "{} pair(s) — {}{more} (toolpaths trace each as its own sheet)",
                        uv.overlapping_chart_pairs,
                        pairs.join(", ")
                    )
                }
            );
        }
    }
    let _ = writeln!(
        s,
        "  normals: {}",
        if r.has_normals { "per corner, from the file" } else { "none" }
    );
    let q = &r.quality;
    let _ = writeln!(
        s,
        "  triangles: smallest angle {:.4}° ({}), {} sliver(s) with an angle below {}°; {} sharp \
         edge(s) (dihedral > {}°, the preview's normals split at {} vertices)",
        q.min_angle_deg,
        q.min_angle_face,
        q.slivers,
        q.sliver_angle_deg,
        q.crease_edges,
        q.crease_angle_deg,
        q.split_vertices
    );
    let _ = writeln!(
        s,
        "  problems: {} degenerate faces dropped, {} non-manifold edges, {} non-manifold vertices, \
         {} inconsistently oriented edges, {} unreferenced vertices, {} welded vertices",
        p.degenerate_faces,
        p.nonmanifold_edges,
        p.nonmanifold_vertices,
        p.inconsistent_orientation_edges,
        p.unreferenced_vertices,
        p.welded_vertices
    );
    s
}
