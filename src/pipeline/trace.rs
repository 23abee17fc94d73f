//! The trace stage: the strokes of a field on the part's UV layout, the one way `grainline
//! run`, `trace`, `render`, `export` and the editor trace them — the toolpaths section as the
//! run reads it, the grain carried into the UV layout ([`field_mesh`]), the toolpaths crate's
//! job, and on request the coverage gaps per vertex, the as-brushed grain and the stroke-level
//! constraint figures.

use nalgebra::Vector3;
use serde::Serialize;

use crate::fidelity::carry::StraddlePoint;
use crate::geometry::surfaces::FaceSurfaces;
use crate::geometry::Geometry;
use crate::highlight::Symmetry;
use crate::mesh::Mesh;
use crate::pipeline::prepare::RecognizedPart;
use crate::scene::toolpaths::{toolpath_error, ToolpathSection};
use crate::solve::settings::Constraints;
use crate::uvfield::{as_brushed, field_mesh, AsBrushed, UvFieldReport};
use crate::Result;

/// Figures of the toolpath stage.
#[derive(Clone, Debug, Serialize)]
pub struct ToolpathFigures {
    /// The toolpaths crate's report (strokes, lengths, coverage, stop reasons).
    pub job: grainline_toolpaths::Report,
    /// UV triangles, flipped and degenerate faces, seams.
    pub uv_vertices: usize,
    /// Triangles handed to the toolpaths crate.
    pub triangles: usize,
    /// Faces left out (degenerate UV).
    pub degenerate_faces: usize,
    /// Mirrored or flipped UV triangles (kept, directions carried without turning over).
    pub flipped_faces: usize,
    /// Seam pairs.
    pub seam_pairs: usize,
    /// Scale from the mesh's UV layout to the flat SVG / G-code coordinates (scene units).
    pub uv_scale: f64,
    /// The scene's fabrication constraints (`solver.constraints`) measured on the traced
    /// strokes: turning radius, spread between neighbours, deviation through each lock
    /// (`grainline_toolpaths::check_strokes`; issue 17). Absent when the scene has none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stroke_constraints: Option<grainline_toolpaths::StrokeChecks>,
}

/// The toolpaths section a run traces with: `toolpaths` (the scene's) or the defaults, keeping
/// the coverage map when `keep_map` (the gap effect), the tool's turning radius from
/// `constraints` (the scene's `solver.constraints`) as the plan's unless the section sets its
/// own, checked in the mesh's `units`.
pub fn toolpath_section(
    toolpaths: Option<&ToolpathSection>,
    constraints: &Constraints,
    units: crate::mesh::Units,
    keep_map: bool,
) -> Result<ToolpathSection> {
    let mut section = toolpaths.cloned().unwrap_or_else(|| ToolpathSection::default_in(units));
    if keep_map {
        let mut c = section.coverage.clone().unwrap_or_default();
        c.keep_map = true;
        section.coverage = Some(c);
    }
    // The tool's turning radius also cuts back stroke ends that turn tighter near a
    // boundary or a singularity, unless the section sets its own.
    if section.plan.min_turning_radius.is_none() {
        section.plan.min_turning_radius = constraints.turning_radius.as_ref().map(|t| t.radius);
    }
    section.validate_in(units).map_err(|e| crate::scene::prefix("toolpaths", e))?;
    Ok(section)
}

/// What [`trace`] traces: a field on a part, as a scene asks.
pub struct TraceInput<'a> {
    /// The scene's `toolpaths` section; `None`: the defaults in the mesh's units.
    pub toolpaths: Option<&'a ToolpathSection>,
    /// The scene's fabrication constraints (`solver.constraints`): the turning radius cuts
    /// back stroke ends, and every constraint is measured on the strokes ([`TracedStrokes::figures`]).
    pub constraints: &'a Constraints,
    /// The part, with its UV layout.
    pub mesh: &'a Mesh,
    /// The part's geometry (frames).
    pub geometry: &'a Geometry,
    /// The grain angles in the geometry's frames.
    pub phi: &'a [f64],
    /// Line or vector field.
    pub symmetry: Symmetry,
    /// Keep the coverage map, for the gaps per vertex ([`TracedStrokes::gap`]).
    pub keep_map: bool,
    /// Keep the field mesh, for [`TracedStrokes::gap`] and [`TracedStrokes::as_brushed`].
    pub keep_field_mesh: bool,
    /// The surfaces recognized on the part (`mesh.surfaces`): the strokes' 3D points are put
    /// on them rather than on the chords, and the field inside a curved chord is
    /// the surface's (docs/math.md §3, "Recognized surfaces").
    pub surfaces: Option<&'a RecognizedPart>,
    /// Points of the edits' designed highlight to leave between two strokes
    /// ([`crate::fidelity::carry`]; `toolpaths.carry_edits`), most important first; empty:
    /// the placement alone decides.
    pub straddle: &'a [StraddlePoint],
}

/// The recognized surface of each triangle handed to the toolpaths crate, which lifts the
/// strokes onto it (`grainline_toolpaths::SurfaceLift`): a chord point goes to the nearest
/// point of its cylinder, cone, sphere or torus (`p − n · d(p)`, the primitive's normal `n`
/// and signed distance `d`; docs/math.md §3, "Recognized surfaces"). Planes and unrecognized
/// faces keep their chords. Its faces are the field mesh's triangles.
struct OnSurfaces(FaceSurfaces);

impl grainline_toolpaths::SurfaceLift for OnSurfaces {
    fn project(&self, face: u32, p: [f64; 3]) -> Option<([f64; 3], [f64; 3])> {
        let (q, n) = self.0.project(face as usize, &Vector3::from(p))?;
        Some((q.into(), n.into()))
    }
}

impl OnSurfaces {
    /// The hook on the field mesh's triangles (the mesh's faces in order, less the ones the UV
    /// field left out: `degenerate`, ascending) and their surfaces; `None` when no triangle is
    /// on a curved one.
    fn hook(
        rec: &RecognizedPart,
        mesh: &Mesh,
        degenerate: &[u32],
    ) -> Option<(grainline_toolpaths::SurfaceHook, FaceSurfaces)> {
        let faces = rec.on_faces(mesh);
        let mut skip = degenerate.iter().peekable();
        let of: Vec<u32> = (0..faces.of.len() as u32)
            .filter(|f| skip.next_if_eq(&f).is_none())
            .map(|f| faces.of[f as usize])
            .collect();
        let on = FaceSurfaces { primitives: faces.primitives, of };
        (0..on.of.len()).any(|f| on.curved(f).is_some()).then(|| {
            let hook =
                grainline_toolpaths::SurfaceHook(std::sync::Arc::new(OnSurfaces(on.clone())));
            (hook, on)
        })
    }
}

/// A rotary fixture's `axis: "auto"` on a part read as a body of revolution: the axis of its
/// largest one ([`crate::geometry::surfaces::revolution`]), exact, rather than the axis
/// fitted to the normals (`grainline_toolpaths::fit_axis`), which other parts keep.
fn recognized_rotary_axis(
    options: &mut grainline_toolpaths::JobOptions,
    rec: &RecognizedPart,
    mesh: &Mesh,
) {
    use grainline_toolpaths::{rotary::Auto, AxisSpec, RotaryAxis, ZMode};
    let ZMode::Rotary { axis, .. } = &mut options.plan.z_mode else { return };
    if *axis != AxisSpec::Auto(Auto::Auto) {
        return;
    }
    let Some((lo, hi)) = mesh.bounding_box() else { return };
    let found = crate::geometry::surfaces::revolution::largest_body_of_revolution(
        &rec.surfaces,
        (hi - lo).norm(),
        mesh.area(),
    );
    if let Some(b) = found {
        *axis = AxisSpec::Given(RotaryAxis {
            point: b.point.into(),
            direction: b.direction.into(),
            zero: None,
        });
    }
}

/// Per triangle of the field mesh on a curved surface, its corners' grain extended off the
/// surface ([`crate::geometry::surfaces::ambient`]); the toolpaths crate blends it and
/// projects it onto the surface inside the triangle. A line field's corners are aligned to
/// the first's.
fn ambient_corners(
    input: &TraceInput,
    tris: &[[u32; 3]],
    uv_to_vertex: &[u32],
    on: &FaceSurfaces,
) -> Vec<Option<[[f64; 3]; 3]>> {
    let u3 = input.geometry.directions_of(input.phi);
    tris.iter()
        .enumerate()
        .map(|(f, t)| {
            on.curved(f)?;
            let v = t.map(|c| uv_to_vertex[c as usize] as usize);
            let mut u = v.map(|v| u3[v]);
            if input.symmetry == Symmetry::Line {
                for i in 1..3 {
                    if u[i].dot(&u[0]) < 0.0 {
                        u[i] = -u[i];
                    }
                }
            }
            let n = v.map(|v| input.geometry.normal(v));
            crate::geometry::surfaces::ambient::extend(u, n).map(|a| a.map(Into::into))
        })
        .collect()
}

/// The straddled points in the field mesh's UV: each face's triangle (the faces in order, less
/// the `degenerate` ones, ascending) at the point's barycentric coordinates. Points on a left-out
/// face are dropped.
fn straddle_uv(
    points: &[StraddlePoint],
    fm: &grainline_toolpaths::FieldMesh,
    degenerate: &[u32],
) -> Vec<[f64; 2]> {
    points
        .iter()
        .filter_map(|p| {
            let f = u32::try_from(p.face).ok()?;
            let skipped = match degenerate.binary_search(&f) {
                Ok(_) => return None,
                Err(k) => k,
            };
            let tri = fm.triangles.get(p.face - skipped)?;
            let mut q = [0.0; 2];
            for (c, w) in tri.iter().zip(p.bary) {
                let uv = fm.uv.get(*c as usize)?;
                q[0] += w * uv[0];
                q[1] += w * uv[1];
            }
            q.iter().all(|x| x.is_finite()).then_some(q)
        })
        .collect()
}

/// The traced strokes and what the later steps of the stage read.
pub struct TracedStrokes {
    /// The toolpaths section traced with ([`toolpath_section`]).
    pub section: ToolpathSection,
    /// The toolpaths crate's job: strokes, SVG, G-code, strokes JSON, report.
    pub job: grainline_toolpaths::JobOutput,
    /// The field mesh handed to the job, when [`TraceInput::keep_field_mesh`].
    pub field_mesh: Option<grainline_toolpaths::FieldMesh>,
    /// The UV field's report (UV vertices, seams, the UV → vertex map).
    pub uv: UvFieldReport,
    /// The strokes on the part, scene units.
    pub strokes_3d: Vec<Vec<Vector3<f64>>>,
}

/// Traces the strokes of `input`'s field: the one trace stage of `grainline run`, its
/// commands and the editor, and the library's way to make strokes. Errors found while tracing
/// name their key from the scene's top (`toolpaths.…`).
pub fn trace(input: &TraceInput) -> Result<TracedStrokes> {
    let units = input.mesh.units;
    let section = toolpath_section(input.toolpaths, input.constraints, units, input.keep_map)?;
    let (mut fm, uv) =
        field_mesh(input.mesh, input.geometry, input.phi, input.symmetry, &section.uv_field)?;
    if let Some(rec) = input.surfaces {
        if let Some((hook, on)) = OnSurfaces::hook(rec, input.mesh, &uv.degenerate_faces) {
            let ambient = ambient_corners(input, &fm.triangles, &uv.uv_to_vertex, &on);
            fm = fm.with_surface(hook, ambient);
        }
    }
    let field_mesh = if input.keep_field_mesh { Some(fm.clone()) } else { None };
    let mut options = section.job_options(units);
    options.placement.straddle = straddle_uv(input.straddle, &fm, &uv.degenerate_faces);
    if let Some(rec) = input.surfaces {
        recognized_rotary_axis(&mut options, rec, input.mesh);
    }
    let mut job = grainline_toolpaths::generate(fm, &options)
        .map_err(|e| crate::scene::prefix("toolpaths", toolpath_error(e)))?;
    section.time_job(&mut job, units);
    let strokes_3d =
        job.strokes_3d.iter().map(|s| s.iter().map(|p| Vector3::from(*p)).collect()).collect();
    Ok(TracedStrokes { section, job, field_mesh, uv, strokes_3d })
}

impl TracedStrokes {
    /// The files the section asks for, with their scene keys and text: SVG, G-code, strokes
    /// JSON.
    pub fn outputs(&self) -> Vec<(&'static str, &str, &str)> {
        let s = &self.section;
        let j = &self.job;
        [
            ("toolpaths.svg", &s.svg, &j.svg),
            ("toolpaths.gcode", &s.gcode, &j.gcode),
            ("toolpaths.strokes_json", &s.strokes_json, &j.strokes_json),
        ]
        .into_iter()
        .filter_map(|(k, p, t)| Some((k, p.as_deref()?, t.as_deref()?)))
        .collect()
    }

    /// The coverage gap map sampled at each of the `vertices` mesh vertices' UV positions (the
    /// nearest pixel; the largest distance where a vertex has several UV positions). `None`
    /// without the map or the field mesh.
    pub fn gap(&self, vertices: usize) -> Option<Vec<f64>> {
        let map = self.job.coverage.as_ref().and_then(|c| c.map.as_ref())?;
        let fm = self.field_mesh.as_ref()?;
        let mut g = vec![0.0f64; vertices];
        for (k, q) in fm.uv.iter().enumerate() {
            let px = ((q[0] - map.origin[0]) / map.pixel).floor();
            let py = ((q[1] - map.origin[1]) / map.pixel).floor();
            let (px, py) = (
                (px.max(0.0) as usize).min(map.width.saturating_sub(1)),
                (py.max(0.0) as usize).min(map.height.saturating_sub(1)),
            );
            let d = f64::from(map.distance[py * map.width + px]).max(0.0);
            let v = self.uv.uv_to_vertex[k] as usize;
            g[v] = g[v].max(d);
        }
        Some(g)
    }

    /// The grain rebuilt from the strokes ([`as_brushed`]); `None` without the field mesh.
    pub fn as_brushed(&self, input: &TraceInput) -> Result<Option<AsBrushed>> {
        let Some(fm) = &self.field_mesh else { return Ok(None) };
        let (m, g, phi, sym) = (input.mesh, input.geometry, input.phi, input.symmetry);
        as_brushed(m, g, phi, sym, fm, &self.uv, &self.job.placement).map(Some)
    }

    /// The stage's figures for the run report, with the scene's fabrication constraints
    /// measured on the strokes (`solver.constraints`; none when the scene has none).
    pub fn figures(&self, input: &TraceInput) -> Result<ToolpathFigures> {
        let stroke_constraints = match super::stroke_constraints::check_options(
            input.mesh,
            input.geometry,
            input.constraints,
            &self.uv.uv_to_vertex,
            input.symmetry.k(),
        )? {
            Some(o) => Some(
                grainline_toolpaths::check_strokes(&self.job.domain, &self.job.placement, &o)
                    .map_err(|e| crate::scene::prefix("toolpaths", toolpath_error(e)))?,
            ),
            None => None,
        };
        let uvr = &self.uv;
        Ok(ToolpathFigures {
            job: self.job.report.clone(),
            uv_vertices: uvr.uv_vertices,
            triangles: uvr.triangles,
            degenerate_faces: uvr.degenerate_faces.len(),
            flipped_faces: uvr.flipped_faces,
            seam_pairs: uvr.seam_pairs,
            uv_scale: uvr.uv_scale,
            stroke_constraints,
        })
    }
}
