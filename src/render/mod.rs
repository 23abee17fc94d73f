//! The CPU preview renderer (docs/render.md).
//!
//! A deterministic, multithreaded triangle rasterizer with a depth buffer and a pinhole camera,
//! anisotropic BRDFs oriented by the grain field, directional, point and environment lights,
//! optional shadows, and passes that draw what the highlight model says: LIC of ℓ, highlight
//! curves hᵀu = 0, critical points, edit overlays, strokes, the as-brushed comparison and the
//! coverage gap map. Each pass runs only if the settings list it, and the [`RenderReport`]
//! proves which ran. The renderer reads the mesh and the model's outputs; it never calls the
//! solver or the toolpaths.

pub use crate::appearance::brdf;
mod bvh;
pub mod camera;
mod displace;
pub mod env;
mod frame;
pub mod image;
mod lic;
mod overlay;
mod raster;
pub mod report;
pub mod settings;
mod shade;
mod surface;

use std::time::Instant;

use nalgebra::Vector3;

pub use camera::Camera;
pub use env::EnvMap;
pub use report::{AngleStats, AsBrushedStats, PassTime, RenderCounters, RenderReport};
pub use settings::{
    key_light_index, validate_lights, AsBrushedMode, BrdfSpec, Effects, Fresnel, LightSpec,
    Material, RenderSettings, ToneMap,
};

use crate::highlight::Symmetry;
use crate::{Error, Result};
use camera::Projector;
use overlay::{Canvas, Ctx, PointProjector};
use shade::{Light, Shader};
use surface::MeshData;

/// Brush supports and target tangents of the edits, for the edit overlay.
#[derive(Clone, Debug, Default)]
pub struct EditOverlay {
    /// Per-vertex support weight in [0, 1] (0 outside every brush), or empty.
    pub support: Vec<f64>,
    /// Target tangents: (position, direction) pairs drawn as arrows.
    pub targets: Vec<(Vector3<f64>, Vector3<f64>)>,
}

/// The mesh and the per-vertex fields to render. Every per-vertex slice has one entry per
/// position.
#[derive(Clone, Copy, Debug)]
pub struct RenderInput<'a> {
    /// Vertex positions.
    pub positions: &'a [Vector3<f64>],
    /// Triangles (vertex indices).
    pub faces: &'a [[u32; 3]],
    /// Vertex normals (need not be unit; zero falls back to the face normal).
    pub normals: &'a [Vector3<f64>],
    /// Shading normals per face corner (one `[n0, n1, n2]` per face, in the face's vertex
    /// order), e.g. the crease-aware [`corner_normals`](crate::geometry::normals::corner_normals);
    /// when given they replace `normals` for shading.
    pub corner_normals: Option<&'a [[Vector3<f64>; 3]]>,
    /// The recognized surface of each face (`mesh.surfaces`): on a curved face the shading
    /// normal is the surface's per sample (docs/math.md §3, "Recognized surfaces").
    pub surfaces: Option<&'a crate::geometry::surfaces::FaceSurfaces>,
    /// The designed grain u per vertex (3D; projected to the tangent plane per sample).
    pub u: &'a [Vector3<f64>],
    /// k = 1 or k = 2 (the grain is then interpolated as a line, paper §4.4).
    pub symmetry: Symmetry,
    /// The highlight tangent ℓ per vertex (needed by LIC).
    pub ell: Option<&'a [Vector3<f64>]>,
    /// Critical vertices (drawn as rings by the critical-points pass).
    pub critical: Option<&'a [bool]>,
    /// 3D stroke polylines (for the strokes pass).
    pub strokes: Option<&'a [Vec<Vector3<f64>>]>,
    /// The as-brushed grain per vertex.
    pub brushed_u: Option<&'a [Vector3<f64>]>,
    /// The as-brushed highlight tangent per vertex (for statistics).
    pub brushed_ell: Option<&'a [Vector3<f64>]>,
    /// Edit overlays.
    pub edits: Option<&'a EditOverlay>,
    /// Coverage gap per vertex (≥ 0; shown red up to `effects.gap.max`).
    pub gap: Option<&'a [f64]>,
}

impl<'a> RenderInput<'a> {
    /// The required fields, every optional one `None`.
    pub fn new(
        positions: &'a [Vector3<f64>],
        faces: &'a [[u32; 3]],
        normals: &'a [Vector3<f64>],
        u: &'a [Vector3<f64>],
        symmetry: Symmetry,
    ) -> Self {
        RenderInput {
            positions,
            faces,
            normals,
            corner_normals: None,
            surfaces: None,
            u,
            symmetry,
            ell: None,
            critical: None,
            strokes: None,
            brushed_u: None,
            brushed_ell: None,
            edits: None,
            gap: None,
        }
    }

    /// Checks lengths, indices and finiteness.
    pub fn validate(&self) -> Result<()> {
        let n = self.positions.len();
        let bad = |what: &str, msg: String| Error::invalid_arg(format!("render input {what}"), msg);
        let finite = |what: &str, v: &[Vector3<f64>]| -> Result<()> {
            if v.len() != n {
                return Err(bad(what, format!("has {} entries for {n} vertices", v.len())));
            }
            match v.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
                Some(i) => Err(bad(what, format!("vertex {i} is not finite"))),
                None => Ok(()),
            }
        };
        finite("positions", self.positions)?;
        finite("normals", self.normals)?;
        finite("u", self.u)?;
        for (name, v) in
            [("ell", self.ell), ("brushed_u", self.brushed_u), ("brushed_ell", self.brushed_ell)]
        {
            if let Some(v) = v {
                finite(name, v)?;
            }
        }
        if let Some(cn) = self.corner_normals {
            if cn.len() != self.faces.len() {
                return Err(bad(
                    "corner_normals",
                    format!("has {} entries for {} faces", cn.len(), self.faces.len()),
                ));
            }
            if let Some(f) = cn.iter().position(|c| c.iter().flatten().any(|x| !x.is_finite())) {
                return Err(bad("corner_normals", format!("face {f} is not finite")));
            }
        }
        if let Some(f) = self.faces.iter().position(|f| f.iter().any(|&i| i as usize >= n)) {
            return Err(bad("faces", format!("face {f} refers to a vertex ≥ {n}")));
        }
        if let Some(c) = self.critical {
            if c.len() != n {
                return Err(bad("critical", format!("has {} entries for {n} vertices", c.len())));
            }
        }
        let scalars = [("gap", self.gap), ("edits.support", self.edits.map(|e| &e.support[..]))];
        for (name, v) in scalars {
            if let Some(v) = v {
                if !v.is_empty() && v.len() != n {
                    return Err(bad(name, format!("has {} entries for {n} vertices", v.len())));
                }
                if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                    return Err(bad(name, format!("vertex {i} is not finite")));
                }
            }
        }
        let polylines = self.strokes.into_iter().flatten().flatten();
        let targets =
            self.edits.into_iter().flat_map(|e| e.targets.iter().flat_map(|(p, d)| [p, d]));
        if polylines.chain(targets).any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(bad("strokes/targets", "a point is not finite".into()));
        }
        Ok(())
    }
}

/// What [`render`] returns. The caller writes the files (atomically).
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// 8-bit sRGB PNG bytes.
    pub png: Vec<u8>,
    /// Linear radiance as PFM bytes, when `settings.linear` is set.
    pub linear: Option<Vec<u8>>,
    /// What ran, how long, and what was not computed.
    pub report: RenderReport,
}

/// Radiance and overlay layer of one half of the image, per sample.
type Half = (Vec<[f32; 3]>, Vec<[f32; 4]>);

/// A [`Half`] resolved to pixels: borrowed at supersample 1, box-filtered otherwise.
type HalfRef<'a> = (std::borrow::Cow<'a, [[f32; 3]]>, std::borrow::Cow<'a, [[f32; 4]]>);

/// Times passes into the report.
struct Timer<'r> {
    report: &'r mut RenderReport,
}

impl Timer<'_> {
    fn run<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let r = f();
        self.report
            .passes
            .push(PassTime { name: name.into(), ms: t.elapsed().as_secs_f64() * 1e3 });
        r
    }
}

/// Renders the mesh. Validates everything first (material, lights, settings, camera, input);
/// environment images are read from the paths in `lights` as given.
pub fn render(
    input: &RenderInput,
    material: &Material,
    lights: &[LightSpec],
    camera: &Camera,
    settings: &RenderSettings,
) -> Result<RenderOutput> {
    render_with(input, material, lights, camera, settings, Precision::Fast)
}

/// How the shading pass evaluates the BRDF.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Precision {
    /// Frame and BRDF in f32 ([`brdf::Brdf::eval_f32`]), what [`render`] uses.
    Fast,
    /// Everything in f64 ([`brdf::Brdf::eval`]): the reference the fast path is tested against.
    #[cfg_attr(not(test), allow(dead_code))]
    Reference,
}

/// [`render`] with the shading precision chosen.
pub(crate) fn render_with(
    input: &RenderInput,
    material: &Material,
    lights: &[LightSpec],
    camera: &Camera,
    settings: &RenderSettings,
    precision: Precision,
) -> Result<RenderOutput> {
    let start = Instant::now();
    let (curve_lights, critical_lights, departure_light) =
        validate_render(input, material, lights, camera, settings)?;
    let fx = &settings.effects;

    let (w, h, s) =
        (settings.width as usize, settings.height as usize, settings.supersample as usize);
    let (sw, sh) = (w * s, h * s);
    let mut report = RenderReport {
        width: settings.width,
        height: settings.height,
        supersample: settings.supersample,
        ..Default::default()
    };
    let mut counters = RenderCounters::default();
    let mut warnings = Vec::new();
    let proj = Projector::new(camera, sw, sh);
    let mut timer = Timer { report: &mut report };

    let vis = frame::rasterize(&proj, input, (sw, sh), &mut counters, &mut warnings, &mut timer);
    let ctx = Ctx {
        mesh: MeshData {
            positions: input.positions,
            faces: input.faces,
            normals: input.normals,
            corner_normals: input.corner_normals,
            surfaces: input.surfaces,
        },
        vis: &vis,
        eye: camera.eye,
        symmetry: input.symmetry,
    };
    let bvh = if fx.shadows {
        let b = timer.run("bvh", || bvh::Bvh::build(input.positions, input.faces));
        counters.bvh_nodes = b.num_nodes() as u64;
        Some(b)
    } else {
        None
    };
    let env_samples = frame::environment(fx, lights, &mut counters, &mut timer)?;
    let brdf = brdf::from_material(material);
    let diag = bbox_diagonal(input.positions);
    let shade_lights: Vec<Light> = Light::prepare(lights).into_iter().flatten().collect();
    let shader = Shader {
        brdf: brdf.as_ref(),
        lights32: Shader::single_precision(&shade_lights),
        lights: shade_lights,
        env: &env_samples,
        bvh: bvh.as_ref(),
        eps: 1e-4 * diag,
    };
    let bare_brdf = brdf::from_material(&material.unbrushed());
    let bare = Shader {
        brdf: bare_brdf.as_ref(),
        lights: shader.lights.clone(),
        lights32: shader.lights32.clone(),
        env: &env_samples,
        bvh: bvh.as_ref(),
        eps: shader.eps,
    };
    let frame = frame::Frame {
        input,
        settings,
        fx,
        camera,
        ctx,
        shader: &shader,
        bare: &bare,
        precision,
        curve_lights,
        critical_lights,
        departure_light,
        w,
        h,
        s,
        sw,
        sh,
    };

    let shading_name = if fx.shading { "shading" } else { "clay" };
    let designed = timer.run(shading_name, || frame.radiance(input.u, &mut counters));
    let brushed = match (&fx.as_brushed, input.brushed_u) {
        (Some(a), Some(bu)) if a.mode != AsBrushedMode::Highlights => {
            counters.as_brushed_shadings += 1;
            Some(timer.run("as_brushed", || frame.radiance(bu, &mut counters)))
        }
        _ => None,
    };
    let lic_values = frame.lic_values(&proj, &mut counters, &mut timer);
    let halves = frame.halves(designed, brushed, &mut counters, &mut timer);

    let out_w = w * halves.len();
    let (rgb8, linear_px) = timer.run("resolve", || frame.resolve(&halves, lic_values.as_deref()));
    let rgb8 = frame.vector_overlays(rgb8, halves.len(), &mut counters, &mut timer)?;

    let as_brushed = input
        .brushed_u
        .filter(|_| fx.as_brushed.is_some())
        .map(|bu| timer.run("as_brushed_stats", || as_brushed_stats(input, bu)));

    let png = timer.run("encode_png", || image::encode_png(&rgb8, out_w, h))?;
    let linear = settings
        .linear
        .as_ref()
        .map(|_| timer.run("encode_pfm", || image::encode_pfm(&linear_px, out_w, h)));
    report.width = out_w as u32;
    report.counters = counters;
    report.as_brushed = as_brushed;
    report.warnings = warnings;
    report.total_ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(RenderOutput { png, linear, report })
}

/// The lights of the effects: the highlight curves', the critical points' and the key light
/// of the as-brushed departure overlay (`as_brushed.mode: "highlights"`).
type EffectLights = (Vec<Light>, Vec<Light>, Option<Light>);

/// The checks of [`render_with`] before any work: material, lights, settings, camera and
/// input, the effects' lights (returned), and the per-vertex fields the listed effects need.
fn validate_render(
    input: &RenderInput,
    material: &Material,
    lights: &[LightSpec],
    camera: &Camera,
    settings: &RenderSettings,
) -> Result<EffectLights> {
    material.validate().map_err(|e| prefix(e, "material"))?;
    validate_lights(lights).map_err(|e| prefix(e, "lights"))?;
    settings.validate().map_err(|e| prefix(e, "render"))?;
    camera.validate()?;
    input.validate()?;
    let fx = &settings.effects;
    let effect = effect_lights(fx, lights)?;
    if fx.lic.is_some() && input.ell.is_none() {
        return Err(Error::setting("render.effects.lic", "needs ℓ per vertex (RenderInput::ell)"));
    }
    if fx.as_brushed.is_some() && input.brushed_u.is_none() {
        return Err(Error::setting(
            "render.effects.as_brushed",
            "needs the as-brushed grain (RenderInput::brushed_u)",
        ));
    }
    Ok(effect)
}

/// The lights chosen by `effects.highlight_curves.lights` and `effects.critical_points.lights`
/// (an empty list: the key light). Each index must be a directional or point light of
/// `lights`; the error's key is `render.effects.<effect>.lights[k]`.
fn effect_lights(fx: &Effects, lights: &[LightSpec]) -> Result<EffectLights> {
    let prepared = Light::prepare(lights);
    let chosen = |list: &[usize], key: &str| -> Result<Vec<Light>> {
        if list.is_empty() {
            return Ok(key_light_index(lights).and_then(|i| prepared[i]).into_iter().collect());
        }
        list.iter()
            .enumerate()
            .map(|(k, &i)| {
                let bad = |message: String| {
                    Error::setting(format!("render.effects.{key}.lights[{k}]"), message)
                };
                match (lights.get(i), prepared.get(i).copied().flatten()) {
                    (_, Some(l)) => Ok(l),
                    (None, _) => Err(bad(format!(
                        "{i} is not the index of a light: the scene has {} light(s), \
                         lights[0] to lights[{}]",
                        lights.len(),
                        lights.len().saturating_sub(1)
                    ))),
                    (Some(_), None) => Err(bad(format!(
                        "lights[{i}] is an environment light; give a directional or point light"
                    ))),
                }
            })
            .collect()
    };
    let curves = match &fx.highlight_curves {
        Some(h) => chosen(&h.lights, "highlight_curves")?,
        None => Vec::new(),
    };
    let critical = match &fx.critical_points {
        Some(c) => chosen(&c.lights, "critical_points")?,
        None => Vec::new(),
    };
    let departure = match &fx.as_brushed {
        Some(a) if a.mode == AsBrushedMode::Highlights => {
            Some(chosen(&[], "as_brushed")?.into_iter().next().ok_or_else(|| {
                Error::setting(
                    "render.effects.as_brushed.mode",
                    "\"highlights\" draws the key light's highlight: the scene needs a \
                     directional or point key light",
                )
            })?)
        }
        _ => None,
    };
    Ok((curves, critical, departure))
}

/// The checks of [`render`] that involve the scene's lights and not only the `render`
/// section: the effects' light indices. Keys start with `render.`. The scene check calls
/// this, so a bad index is refused before any work.
pub fn validate_with_lights(settings: &RenderSettings, lights: &[LightSpec]) -> Result<()> {
    effect_lights(&settings.effects, lights).map(|_| ())
}

/// Puts a section name in front of a setting's key.
fn prefix(e: Error, section: &str) -> Error {
    match e {
        Error::Setting { key, message } if key.starts_with('[') => {
            Error::setting(format!("{section}{key}"), message)
        }
        Error::Setting { key, message } => Error::setting(format!("{section}.{key}"), message),
        e => e,
    }
}

/// Length of the bounding-box diagonal (1 for an empty or degenerate mesh).
fn bbox_diagonal(p: &[Vector3<f64>]) -> f64 {
    let mut lo = Vector3::repeat(f64::MAX);
    let mut hi = Vector3::repeat(f64::MIN);
    for q in p {
        lo = lo.inf(q);
        hi = hi.sup(q);
    }
    let d = (hi - lo).norm();
    if d.is_finite() && d > 0.0 {
        d
    } else {
        1.0
    }
}

/// The screen direction of ℓ at every sample (ℓ interpolated as a line field).
fn lic_field(ctx: &Ctx, proj: &Projector, ell: &[Vector3<f64>]) -> lic::DirField {
    let mut dirs = vec![[0.0f32; 2]; ctx.vis.width * ctx.vis.height];
    ctx.for_samples(&mut dirs, |_, s, o| {
        let c = ctx.mesh.corners(s);
        if let Some((l, _)) = s.line(c.map(|i| ell[i])) {
            let depth = (s.p - proj.eye).dot(&proj.fwd);
            let a = proj.project(&s.p);
            let b = proj.project(&(s.p + l * (1e-3 * depth)));
            if let (Some((a, _)), Some((b, _))) = (a, b) {
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let n = dx.hypot(dy);
                if n > 1e-12 && n.is_finite() {
                    *o = [(dx / n) as f32, (dy / n) as f32];
                }
            }
        }
        0
    });
    lic::DirField { width: ctx.vis.width, height: ctx.vis.height, dirs }
}

/// Strokes, target arrows and critical-vertex rings.
fn draw_vectors(
    canvas: &mut Canvas,
    pp: &PointProjector,
    input: &RenderInput,
    fx: &Effects,
    counters: &mut RenderCounters,
) {
    if let (Some(st), Some(strokes)) = (&fx.strokes, input.strokes) {
        for line in strokes {
            // Draw runs of consecutive visible points.
            let mut run: Vec<[f64; 2]> = Vec::new();
            let flush =
                |run: &mut Vec<[f64; 2]>, canvas: &mut Canvas, counters: &mut RenderCounters| {
                    if run.len() >= 2 {
                        canvas.polyline(run, [255, 255, 255], st.width_px);
                        counters.stroke_segments += (run.len() - 1) as u64;
                    }
                    run.clear();
                };
            for p in line {
                match pp.visible(p) {
                    Some(xy) => run.push(xy),
                    None => flush(&mut run, canvas, counters),
                }
            }
            flush(&mut run, canvas, counters);
        }
    }
    if let (Some(es), Some(e)) = (&fx.edits, input.edits) {
        // One arrow per screen cell of ¾ of an arrow's length, first come first drawn: a dense
        // (or refined) brush shows its target directions instead of a solid blot.
        let cell = 0.75 * es.arrow_px;
        let mut taken = std::collections::HashSet::new();
        for (p, d) in &e.targets {
            let (Some(a), Some((b, _))) = (pp.visible(p), pp.out.project(&(p + d * 1e-3))) else {
                continue;
            };
            if !taken.insert(((a[0] / cell).floor() as i64, (a[1] / cell).floor() as i64)) {
                continue;
            }
            let b = [b[0] + pp.x0, b[1]];
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let n = dx.hypot(dy);
            if !(n > 1e-12 && n.is_finite()) {
                continue;
            }
            let (ux, uy) = (dx / n, dy / n);
            let l = es.arrow_px;
            let tip = [a[0] + ux * l, a[1] + uy * l];
            let head = 0.3 * l;
            let left = [tip[0] - head * (ux - 0.5 * uy), tip[1] - head * (uy + 0.5 * ux)];
            let right = [tip[0] - head * (ux + 0.5 * uy), tip[1] - head * (uy - 0.5 * ux)];
            canvas.polyline(&[a, tip], [80, 255, 120], 2.0);
            canvas.polyline(&[left, tip, right], [80, 255, 120], 2.0);
            counters.target_arrows += 1;
        }
    }
    if let (Some(_), Some(crit)) = (&fx.critical_points, input.critical) {
        for (p, _) in input.positions.iter().zip(crit).filter(|(_, c)| **c) {
            if let Some(xy) = pp.visible(p) {
                canvas.ring(xy, 4.0, [255, 0, 255], 1.5);
                counters.critical_markers += 1;
            }
        }
    }
}

/// Angle in degrees between two vectors, as lines (`line`) or oriented; `None` for a zero or
/// non-finite vector.
fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>, line: bool) -> Option<f64> {
    let (na, nb) = (a.norm(), b.norm());
    if !(na > 1e-12 && nb > 1e-12 && na.is_finite() && nb.is_finite()) {
        return None;
    }
    let c = (a.dot(b) / (na * nb)).clamp(-1.0, 1.0);
    Some(if line { c.abs() } else { c }.acos().to_degrees())
}

/// Per-vertex angles between the designed and as-brushed fields.
fn as_brushed_stats(input: &RenderInput, bu: &[Vector3<f64>]) -> AsBrushedStats {
    let stats = |a: &[Vector3<f64>], b: &[Vector3<f64>], line: bool| {
        let all: Vec<Option<f64>> = a.iter().zip(b).map(|(x, y)| angle_deg(x, y, line)).collect();
        let skipped = all.iter().filter(|x| x.is_none()).count();
        AngleStats::of(all.into_iter().flatten().collect(), skipped)
    };
    AsBrushedStats {
        u_angle: stats(input.u, bu, input.symmetry == Symmetry::Line),
        ell_angle: match (input.ell, input.brushed_ell) {
            (Some(a), Some(b)) => Some(stats(a, b, true)),
            _ => None,
        },
    }
}

/// One output pixel: tone map, LIC modulation, background by coverage, overlay layer over.
fn resolve_pixel(
    rad: [f32; 3],
    layer: [f32; 4],
    coverage: f32,
    lic: Option<f32>,
    settings: &RenderSettings,
) -> [u8; 3] {
    let mut c = rad.map(|v| {
        image::linear_to_srgb(image::tone_map(f64::from(v), settings.tone_map, settings.exposure))
    });
    if let (Some(l), Some(lv)) = (&settings.effects.lic, lic) {
        let f = (1.0 - l.strength) + l.strength * 2.0 * f64::from(lv);
        c = c.map(|v| (v * f).clamp(0.0, 1.0));
    }
    // The surface's radiance was box-filtered with zeros outside: add the background by the
    // uncovered fraction.
    let a = f64::from(coverage);
    let bg = settings.background;
    let c = [0, 1, 2].map(|i| c[i] + (1.0 - a) * bg[i]);
    let c = [0, 1, 2].map(|i| f64::from(layer[i]) + c[i] * (1.0 - f64::from(layer[3])));
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bench scene (docs/benchmarks.md, "Render") at a quarter of the size: a torus with a
    /// grain winding around the tube, three directional lights, Ashikhmin–Shirley n_u = 1000.
    fn bench_like(
        precision: Precision,
        symmetry: Symmetry,
        material: &Material,
        s: u32,
    ) -> (Vec<[u8; 3]>, Vec<[f32; 3]>) {
        let m = crate::generate::torus(2.0, 0.7, 128, 66);
        let normals: Vec<Vector3<f64>> = m
            .positions
            .iter()
            .map(|p| (p - Vector3::new(p.x, p.y, 0.0).normalize() * 2.0).normalize())
            .collect();
        let u: Vec<Vector3<f64>> = m
            .positions
            .iter()
            .zip(&normals)
            .map(|(p, n)| {
                let t = Vector3::new(-p.y, p.x, 0.0).normalize();
                (t * 0.8 + n.cross(&t) * 0.6).normalize()
            })
            .collect();
        let input = RenderInput::new(&m.positions, &m.faces, &normals, &u, symmetry);
        let d = |direction: [f64; 3], irradiance: f64, key: bool| LightSpec::Directional {
            direction,
            irradiance,
            colour: [1.0; 3],
            key,
        };
        let lights = [
            d([0.3, -0.6, 1.0], 2.0, true),
            d([-1.0, 0.2, 0.4], 0.8, false),
            d([0.6, 0.8, -0.2], 0.5, false),
        ];
        let camera = Camera {
            eye: Vector3::new(0.0, -5.5, 3.5),
            target: Vector3::zeros(),
            up: Vector3::z(),
            fov_deg: 45.0,
        };
        let st = RenderSettings {
            width: 256,
            height: 256,
            supersample: s,
            tone_map: ToneMap::Reinhard,
            linear: Some("x.pfm".into()),
            ..Default::default()
        };
        let out = render_with(&input, material, &lights, &camera, &st, precision).unwrap();
        let pm = tiny_skia::Pixmap::decode_png(&out.png).unwrap();
        let rgb = pm.data().chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect();
        let (_, _, lin) = image::decode_pfm(out.linear.as_ref().unwrap()).unwrap();
        (rgb, lin)
    }

    /// The f32 shading path against the f64 one on the bench scene: every 8-bit code within 1,
    /// and the linear radiance within a relative 1e-4 (absolute 1e-6 near black).
    #[test]
    fn fast_shading_matches_the_f64_reference() {
        let ward = Material {
            brdf: BrdfSpec::Ward { alpha_x: 0.05, alpha_y: 0.3, rho_s: 0.8 },
            fresnel: Fresnel::Aluminium,
            diffuse: [0.05; 3],
        };
        for (name, m, k, s) in [
            ("AS, k = 2, ss 1", Material::default(), Symmetry::Line, 1),
            ("AS, k = 1, ss 2", Material::default(), Symmetry::Oriented, 2),
            ("Ward (f64 inside), k = 2, ss 1", ward, Symmetry::Line, 1),
        ] {
            let (a8, alin) = bench_like(Precision::Fast, k, &m, s);
            let (b8, blin) = bench_like(Precision::Reference, k, &m, s);
            let max8 = a8
                .iter()
                .zip(&b8)
                .flat_map(|(x, y)| (0..3).map(move |c| x[c].abs_diff(y[c])))
                .max()
                .unwrap();
            let off8 = a8.iter().zip(&b8).filter(|(x, y)| x != y).count();
            let mut worst = 0.0f64;
            for (x, y) in alin.iter().zip(&blin) {
                for c in 0..3 {
                    let (x, y) = (f64::from(x[c]), f64::from(y[c]));
                    worst = worst.max((x - y).abs() / y.abs().max(1e-2));
                }
            }
            let lit = blin.iter().filter(|p| p[0] > 0.01).count();
            eprintln!("{name}: max |Δ8| {max8} ({off8} pixels differ), max rel {worst:.2e}");
            assert!(lit > 5000, "{name}: the scene should cover the image ({lit} lit pixels)");
            assert!(max8 <= 1, "{name}: max |Δ| {max8} codes");
            assert!(worst <= 1e-4, "{name}: linear radiance off by a relative {worst:.2e}");
        }
    }
}
