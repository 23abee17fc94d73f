//! Overlay passes. Per-sample layers (highlight curves, critical points, gap map, brush
//! supports) are composited "over" in premultiplied RGBA at the sample resolution and box-filtered
//! with the image; vector overlays (strokes, target tangents, critical-vertex rings) are drawn
//! with tiny-skia's anti-aliased strokes on the final pixels.

use nalgebra::Vector3;
use rayon::prelude::*;

use super::camera::Projector;
use super::raster::VisBuffer;
use super::shade::Light;
use super::surface::{MeshData, Surf};
use crate::highlight::Symmetry;

/// What the per-sample passes read.
pub(crate) struct Ctx<'a> {
    pub mesh: MeshData<'a>,
    pub vis: &'a VisBuffer,
    pub eye: Vector3<f64>,
    pub symmetry: Symmetry,
}

impl Ctx<'_> {
    /// The surface at sample `k`.
    pub fn surf(&self, k: usize) -> Option<Surf> {
        self.mesh.surf(&self.vis.samples[k], &self.eye)
    }

    /// The grain at a surface sample: the corners' blend, or on a recognized curved face the
    /// corners' grain extended off the surface first ([`crate::geometry::surfaces::ambient`]),
    /// so that the blend projected onto the sample's normal is the surface's grain.
    pub fn grain(&self, s: &Surf, grain: &[Vector3<f64>]) -> Vector3<f64> {
        let c = self.mesh.corners(s);
        let mut u = c.map(|i| grain[i]);
        if self.mesh.surfaces.is_some_and(|f| f.curved(s.face).is_some()) {
            if self.symmetry == Symmetry::Line {
                for k in 1..3 {
                    if u[k].dot(&u[0]) < 0.0 {
                        u[k] = -u[k];
                    }
                }
            }
            let n = match self.mesh.corner_normals {
                Some(cn) => cn[s.face],
                None => c.map(|i| self.mesh.normals[i]),
            };
            let unit = |v: Vector3<f64>| v.try_normalize(1e-300).unwrap_or(v);
            let n = n.map(unit);
            let uu = [0, 1, 2].map(|k| unit(u[k] - n[k] * n[k].dot(&u[k])));
            if let Some(a) = crate::geometry::surfaces::ambient::extend(uu, n) {
                let b = a[0] * s.w[0] + a[1] * s.w[1] + a[2] * s.w[2];
                let t = b - s.n * s.n.dot(&b);
                if t.norm() > 1e-9 * b.norm() {
                    return t.normalize();
                }
            }
        }
        s.grain(u, self.symmetry)
    }

    /// Runs `f` on every covered sample, row-parallel; returns the sum of `f`'s counts.
    pub fn for_samples<T: Send>(
        &self,
        out: &mut [T],
        f: impl Fn(usize, &Surf, &mut T) -> u64 + Sync,
    ) -> u64 {
        let w = self.vis.width;
        out.par_chunks_mut(w)
            .enumerate()
            .map(|(y, row)| {
                let mut n = 0;
                for (x, o) in row.iter_mut().enumerate() {
                    let k = y * w + x;
                    if let Some(s) = self.surf(k) {
                        n += f(k, &s, o);
                    }
                }
                n
            })
            .sum()
    }
}

/// Premultiplied "over".
pub(crate) fn over(dst: &mut [f32; 4], rgb: [f32; 3], alpha: f32) {
    let a = alpha.clamp(0.0, 1.0);
    for c in 0..3 {
        dst[c] = rgb[c] * a + dst[c] * (1.0 - a);
    }
    dst[3] = a + dst[3] * (1.0 - a);
}

/// Colours of successive highlight curves (sRGB).
pub(crate) const CURVE_COLOURS: [[f32; 3]; 4] =
    [[1.0, 0.85, 0.1], [0.1, 0.9, 1.0], [1.0, 0.3, 0.8], [0.5, 1.0, 0.3]];

/// The curves hᵀu = 0 of `light`, anti-aliased analytically: with g = hᵀu per sample and its
/// screen gradient by (sign-aligned) finite differences, the distance to the zero set is
/// ≈ |g|/|∇g| samples and the coverage is clamp(w/2 + ½ − |g|/|∇g|, 0, 1). Only lit samples
/// (nᵀω_in > 0) count. Returns the samples touched.
pub(crate) fn highlight_curves(
    ctx: &Ctx,
    grain: &[Vector3<f64>],
    light: &Light,
    colour: [f32; 3],
    half_width: f64,
    layer: &mut [[f32; 4]],
) -> u64 {
    let dist = zero_distances(ctx, grain, light);
    layer
        .par_iter_mut()
        .zip(dist.par_iter())
        .map(|(o, d)| {
            let cov = (half_width + 0.5 - *d).clamp(0.0, 1.0);
            if cov > 0.0 {
                over(o, colour, cov as f32);
                1
            } else {
                0
            }
        })
        .sum()
}

/// Per sample, the distance in samples to the curve hᵀu = 0 of `light` (see
/// [`highlight_curves`]); infinite where there is no value (unlit, background, flat g).
fn zero_distances(ctx: &Ctx, grain: &[Vector3<f64>], light: &Light) -> Vec<f64> {
    let (w, h) = (ctx.vis.width, ctx.vis.height);
    // g and u per sample; g = ∞ marks "no value".
    let mut gu = vec![[f32::INFINITY, 0.0, 0.0, 0.0]; w * h];
    ctx.for_samples(&mut gu, |_, s, o| {
        let u = ctx.grain(s, grain);
        if let Some((wi, _, _)) = light.incident(&s.p) {
            if wi.dot(&s.n) > 0.0 {
                let hv = wi + s.wo;
                if hv.norm() > 1e-12 {
                    let hv = hv.normalize();
                    *o = [hv.dot(&u) as f32, u.x as f32, u.y as f32, u.z as f32];
                }
            }
        }
        0
    });
    let at = |x: isize, y: isize, c: &[f32; 4]| -> Option<f32> {
        if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
            return None;
        }
        let n = gu[y as usize * w + x as usize];
        if !n[0].is_finite() {
            return None;
        }
        let dot = n[1] * c[1] + n[2] * c[2] + n[3] * c[3];
        Some(if dot < 0.0 { -n[0] } else { n[0] })
    };
    let diff = |x: isize, y: isize, dx: isize, dy: isize, c: &[f32; 4]| -> f32 {
        match (at(x + dx, y + dy, c), at(x - dx, y - dy, c)) {
            (Some(a), Some(b)) => 0.5 * (a - b),
            (Some(a), None) => a - c[0],
            (None, Some(b)) => c[0] - b,
            (None, None) => 0.0,
        }
    };
    let mut dist = vec![f64::INFINITY; w * h];
    dist.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let c = gu[y * w + x];
            if !c[0].is_finite() {
                continue;
            }
            let (xi, yi) = (x as isize, y as isize);
            let grad = diff(xi, yi, 1, 0, &c).hypot(diff(xi, yi, 0, 1, &c)) as f64;
            if grad.is_nan() || grad <= 1e-12 {
                continue;
            }
            *o = (c[0] as f64).abs() / grad;
        }
    });
    dist
}

/// Colour of the designed key highlight in the departure overlay (white).
pub(crate) const DESIGNED_COLOUR: [f32; 3] = [1.0, 1.0, 1.0];
/// Colour of the as-brushed key highlight where it lies on the designed one (green).
pub(crate) const KEPT_COLOUR: [f32; 3] = [0.15, 0.95, 0.3];
/// Colour of the as-brushed key highlight where it departs from the designed one (red).
pub(crate) const DEPARTED_COLOUR: [f32; 3] = [1.0, 0.12, 0.1];

/// The key highlight of the designed grain and of the as-brushed one (`render.effects.
/// as_brushed.mode: "highlights"`): the designed curve hᵀu = 0 in white, the as-brushed curve
/// over it in green where the designed one is within `departure` samples of it and in red, twice
/// as wide, where it is farther — where the part as brushed shows its highlight elsewhere than
/// designed.
/// Distances are the curves' screen distances ≈ |g|/|∇g| ([`highlight_curves`]). Returns the
/// samples on the as-brushed curve (its centre line, within half a sample) and those of them
/// that depart.
pub(crate) fn highlight_departure(
    ctx: &Ctx,
    (designed, brushed): (&[Vector3<f64>], &[Vector3<f64>]),
    light: &Light,
    half_width: f64,
    departure: f64,
    layer: &mut [[f32; 4]],
) -> (u64, u64) {
    let d_designed = zero_distances(ctx, designed, light);
    let d_brushed = zero_distances(ctx, brushed, light);
    layer
        .par_iter_mut()
        .enumerate()
        .map(|(k, o)| {
            let (dd, db) = (d_designed[k], d_brushed[k]);
            let cov_d = (half_width + 0.5 - dd).clamp(0.0, 1.0);
            if cov_d > 0.0 {
                over(o, DESIGNED_COLOUR, cov_d as f32);
            }
            // A departing stretch is drawn twice as wide, so that it shows at a glance.
            // dd is a distance or ∞ (no designed highlight near), never NaN.
            let departs = dd > departure;
            let width = if departs { 2.0 * half_width } else { half_width };
            let cov_b = (width + 0.5 - db).clamp(0.0, 1.0);
            if cov_b > 0.0 {
                let colour = if departs { DEPARTED_COLOUR } else { KEPT_COLOUR };
                over(o, colour, cov_b as f32);
            }
            if db <= 0.5 {
                (1, u64::from(departs))
            } else {
                (0, 0)
            }
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// Marks samples where hᵀn > threshold for any of `lights`.
pub(crate) fn critical(ctx: &Ctx, lights: &[Light], threshold: f64, layer: &mut [[f32; 4]]) -> u64 {
    ctx.for_samples(layer, |_, s, o| {
        let hit = lights.iter().any(|l| {
            l.incident(&s.p).is_some_and(|(wi, _, _)| {
                let hv = wi + s.wo;
                hv.norm() > 1e-12 && hv.normalize().dot(&s.n) > threshold
            })
        });
        if hit {
            over(o, [1.0, 0.0, 1.0], 0.85);
        }
        u64::from(hit)
    })
}

/// Tints samples by an interpolated per-vertex scalar: alpha = `max_alpha` · clamp(value/max).
pub(crate) fn scalar_tint(
    ctx: &Ctx,
    values: &[f64],
    max: f64,
    colour: [f32; 3],
    max_alpha: f32,
    layer: &mut [[f32; 4]],
) -> u64 {
    ctx.for_samples(layer, |_, s, o| {
        let c = ctx.mesh.corners(s);
        let v = s.scalar(c.map(|i| values[i])) / max;
        let a = if v.is_finite() { v.clamp(0.0, 1.0) as f32 * max_alpha } else { 0.0 };
        if a > 0.0 {
            over(o, colour, a);
            1
        } else {
            0
        }
    })
}

/// Draws on final 8-bit pixels with tiny-skia.
pub(crate) struct Canvas {
    pub pixmap: tiny_skia::Pixmap,
}

impl Canvas {
    /// A canvas holding `rgb` (opaque).
    pub fn new(rgb: &[[u8; 3]], w: usize, h: usize) -> Option<Self> {
        let mut pixmap = tiny_skia::Pixmap::new(w as u32, h as u32)?;
        for (px, c) in pixmap.data_mut().chunks_exact_mut(4).zip(rgb) {
            px.copy_from_slice(&[c[0], c[1], c[2], 255]);
        }
        Some(Canvas { pixmap })
    }

    /// Back to opaque RGB.
    pub fn into_rgb(self) -> Vec<[u8; 3]> {
        self.pixmap.data().chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect()
    }

    /// An anti-aliased polyline (pixel coordinates).
    pub fn polyline(&mut self, pts: &[[f64; 2]], rgb: [u8; 3], width: f64) {
        let mut pb = tiny_skia::PathBuilder::new();
        for (i, p) in pts.iter().enumerate() {
            if i == 0 {
                pb.move_to(p[0] as f32, p[1] as f32);
            } else {
                pb.line_to(p[0] as f32, p[1] as f32);
            }
        }
        let Some(path) = pb.finish() else { return };
        let mut paint = tiny_skia::Paint::default();
        paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
        paint.anti_alias = true;
        let stroke = tiny_skia::Stroke { width: width as f32, ..Default::default() };
        self.pixmap.stroke_path(&path, &paint, &stroke, tiny_skia::Transform::identity(), None);
    }

    /// An anti-aliased ring.
    pub fn ring(&mut self, c: [f64; 2], r: f64, rgb: [u8; 3], width: f64) {
        let Some(path) = tiny_skia::PathBuilder::from_circle(c[0] as f32, c[1] as f32, r as f32)
        else {
            return;
        };
        let mut paint = tiny_skia::Paint::default();
        paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
        paint.anti_alias = true;
        let stroke = tiny_skia::Stroke { width: width as f32, ..Default::default() };
        self.pixmap.stroke_path(&path, &paint, &stroke, tiny_skia::Transform::identity(), None);
    }
}

/// Projects world points for the vector overlays and tells which are visible.
pub(crate) struct PointProjector<'a> {
    /// The projector at output resolution.
    pub out: Projector,
    pub vis: &'a VisBuffer,
    pub s: usize,
    /// x offset of this half in the output image.
    pub x0: f64,
}

impl PointProjector<'_> {
    /// Output pixel position of `p` if it is in front of the eye and not hidden by the mesh
    /// (its depth within 0.5 % of the largest depth in the 3 × 3 samples around it).
    pub fn visible(&self, p: &Vector3<f64>) -> Option<[f64; 2]> {
        let (xy, z) = self.out.project(p)?;
        let (w, h) = (self.vis.width as isize, self.vis.height as isize);
        let (sx, sy) = ((xy[0] * self.s as f64) as isize, (xy[1] * self.s as f64) as isize);
        if sx < 0 || sy < 0 || sx >= w || sy >= h {
            return None;
        }
        let mut max_depth = 0.0f64;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (x, y) = ((sx + dx).clamp(0, w - 1), (sy + dy).clamp(0, h - 1));
                max_depth = max_depth.max(f64::from(self.vis.samples[(y * w + x) as usize].depth));
            }
        }
        (z <= max_depth * 1.005).then_some([xy[0] + self.x0, xy[1]])
    }
}
