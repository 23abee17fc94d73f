//! The passes of [`render_with`](super::render_with), one function each: rasterization, the
//! environment, shading, the overlay layers, LIC, the resolve to pixels and the vector
//! overlays. [`Frame`] holds what they share.

use nalgebra::Vector3;
use rayon::prelude::*;

use super::overlay::{self, Canvas, Ctx, PointProjector};
use super::shade::{Light, ShadeCount, Shader};
use super::{
    draw_vectors, env, image, lic, lic_field, raster, resolve_pixel, AsBrushedMode, Camera,
    Effects, EnvMap, Half, HalfRef, LightSpec, Precision, RenderCounters, RenderInput,
    RenderSettings, Timer,
};
use crate::render::camera::Projector;
use crate::render::displace::Displacement;
use crate::{Error, Result};

/// Rasterizes the mesh at `sw` × `sh` samples and counts what it did; warns when the mesh
/// covers no sample.
pub(super) fn rasterize(
    proj: &Projector,
    input: &RenderInput,
    (sw, sh): (usize, usize),
    counters: &mut RenderCounters,
    warnings: &mut Vec<String>,
    timer: &mut Timer,
) -> raster::VisBuffer {
    let (vis, rstats) = timer.run("raster", || {
        let mesh = (input.positions, input.faces);
        let displace =
            input.surfaces.and_then(|s| Displacement::new(input.positions, input.faces, s));
        raster::rasterize(proj, mesh, displace.as_ref(), sw, sh)
    });
    counters.triangles_in = rstats.triangles_in as u64;
    counters.triangles_culled = rstats.triangles_culled as u64;
    counters.triangles_clipped = rstats.triangles_clipped as u64;
    counters.screen_triangles = rstats.screen_triangles as u64;
    counters.samples = (sw * sh) as u64;
    counters.covered_samples =
        vis.samples.iter().filter(|x| x.face != raster::EMPTY).count() as u64;
    if counters.covered_samples == 0 {
        warnings.push("the mesh covers no pixel: check the view".to_string());
    }
    vis
}

/// The samples of every environment light, when shading with the environment (else none).
pub(super) fn environment(
    fx: &Effects,
    lights: &[LightSpec],
    counters: &mut RenderCounters,
    timer: &mut Timer,
) -> Result<Vec<env::EnvSample>> {
    let mut env_samples = Vec::new();
    let has_env = lights.iter().any(|l| matches!(l, LightSpec::Environment { .. }));
    if fx.shading && fx.environment && has_env {
        env_samples = timer.run("environment", || -> Result<Vec<env::EnvSample>> {
            let mut all = Vec::new();
            for l in lights {
                if let LightSpec::Environment { file, scale, samples, rotation_deg } = l {
                    let map = EnvMap::load(std::path::Path::new(file))?;
                    counters.env_texels += (map.width * map.height) as u64;
                    all.extend(map.samples(*samples as usize, *scale, *rotation_deg));
                }
            }
            Ok(all)
        })?;
        counters.env_samples = env_samples.len() as u64;
    }
    Ok(env_samples)
}

/// What the per-sample passes share: the input, the settings, the visible surface, the
/// shader, the effects' lights and the image sizes (`w` × `h` pixels of `s` × `s` samples,
/// `sw` × `sh` samples).
pub(super) struct Frame<'a> {
    pub input: &'a RenderInput<'a>,
    pub settings: &'a RenderSettings,
    pub fx: &'a Effects,
    pub camera: &'a Camera,
    pub ctx: Ctx<'a>,
    pub shader: &'a Shader<'a>,
    /// The same lights on the metal where no brush passed ([`crate::appearance::Material::unbrushed`]):
    /// shades the as-brushed grain's zero corners.
    pub bare: &'a Shader<'a>,
    pub precision: Precision,
    pub curve_lights: Vec<Light>,
    pub critical_lights: Vec<Light>,
    /// The key light of the as-brushed departure overlay (`as_brushed.mode: "highlights"`).
    pub departure_light: Option<Light>,
    pub w: usize,
    pub h: usize,
    pub s: usize,
    pub sw: usize,
    pub sh: usize,
}

/// The interpolated share of the sample's face corners that carry grain: 1 where every corner
/// has a direction (every designed field), 0 where none does (a gap no brush passed over,
/// [`crate::uvfield::AsBrushed`]) — the glb's anisotropy strength, interpolated the same way.
fn brushed_share(s: &super::surface::Surf, corners: [usize; 3], grain: &[Vector3<f64>]) -> f64 {
    let bare = |i: usize| grain[i] == Vector3::zeros();
    if !corners.iter().any(|&i| bare(i)) {
        return 1.0;
    }
    (0..3).filter(|&k| !bare(corners[k])).map(|k| s.w[k]).sum::<f64>().clamp(0.0, 1.0)
}

impl Frame<'_> {
    /// Radiance of one grain field, per sample.
    pub fn radiance(&self, grain: &[Vector3<f64>], counters: &mut RenderCounters) -> Vec<[f32; 3]> {
        let (ctx, fx, shader, precision) = (&self.ctx, self.fx, self.shader, self.precision);
        let mut rad = vec![[0.0f32; 3]; self.sw * self.sh];
        let w_ = self.sw;
        let counts: Vec<ShadeCount> = rad
            .par_chunks_mut(w_)
            .enumerate()
            .map(|(y, row)| {
                let mut c = ShadeCount::default();
                for (x, o) in row.iter_mut().enumerate() {
                    if let Some(surf) = ctx.surf(y * w_ + x) {
                        *o = if fx.shading {
                            let u = ctx.grain(&surf, grain);
                            let shade = |sh: &Shader, c: &mut ShadeCount| match precision {
                                Precision::Fast => sh.shade_f32(&surf, &u, c),
                                Precision::Reference => sh.shade(&surf, &u, c).map(|v| v as f32),
                            };
                            let t = brushed_share(&surf, ctx.mesh.corners(&surf), grain);
                            if t < 1.0 {
                                // Unbrushed corners (zero grain): the bare metal, blended
                                // by the interpolated share of brushed corners.
                                let (a, b) = (shade(shader, &mut c), shade(self.bare, &mut c));
                                let t = t as f32;
                                [0, 1, 2].map(|k| t * a[k] + (1.0 - t) * b[k])
                            } else {
                                shade(shader, &mut c)
                            }
                        } else {
                            // Clay: a grey Lambert surface lit from the eye.
                            [(0.18 * surf.n.dot(&surf.wo).max(0.0)) as f32; 3]
                        };
                    }
                }
                c
            })
            .collect();
        for c in counts {
            counters.brdf_evals += c.brdf_evals;
            counters.shadow_rays += c.shadow_rays;
        }
        rad
    }

    /// Per-sample overlay layers of one half.
    fn overlays(
        &self,
        grain: &[Vector3<f64>],
        counters: &mut RenderCounters,
        timer: &mut Timer,
    ) -> Vec<[f32; 4]> {
        let (ctx, fx, input, s) = (&self.ctx, self.fx, self.input, self.s);
        let mut layer = vec![[0.0f32; 4]; self.sw * self.sh];
        if let (Some(g), Some(values)) = (&fx.gap, input.gap) {
            counters.gap_samples += timer.run("gap", || {
                overlay::scalar_tint(ctx, values, g.max, [1.0, 0.1, 0.1], 0.7, &mut layer)
            });
        }
        if let (Some(_), Some(e)) = (&fx.edits, input.edits) {
            if !e.support.is_empty() {
                counters.support_samples += timer.run("edit_support", || {
                    overlay::scalar_tint(ctx, &e.support, 1.0, [0.2, 0.45, 1.0], 0.35, &mut layer)
                });
            }
        }
        if let Some(c) = &fx.critical_points {
            counters.critical_samples += timer.run("critical_points", || {
                overlay::critical(ctx, &self.critical_lights, c.threshold, &mut layer)
            });
        }
        if let Some(hc) = &fx.highlight_curves {
            let half = 0.5 * hc.width_px * s as f64;
            counters.highlight_curve_samples += timer.run("highlight_curves", || {
                self.curve_lights
                    .iter()
                    .enumerate()
                    .map(|(i, l)| {
                        let col = overlay::CURVE_COLOURS[i % overlay::CURVE_COLOURS.len()];
                        overlay::highlight_curves(ctx, grain, l, col, half, &mut layer)
                    })
                    .sum::<u64>()
            });
        }
        layer
    }

    /// The LIC image of ℓ on output pixels, when the effect is on.
    pub fn lic_values(
        &self,
        proj: &Projector,
        counters: &mut RenderCounters,
        timer: &mut Timer,
    ) -> Option<Vec<[f32; 1]>> {
        let (w, h, s) = (self.w, self.h, self.s);
        match (&self.fx.lic, self.input.ell) {
            (Some(l), Some(ell)) => {
                let (vals, noise, steps) = timer.run("lic", || {
                    let field = lic_field(&self.ctx, proj, ell);
                    lic::lic(&field, s, l.length_px, l.seed)
                });
                counters.lic_noise_values = noise;
                counters.lic_steps = steps;
                Some(image::downsample(&vals.iter().map(|v| [*v]).collect::<Vec<_>>(), w, h, s))
            }
            _ => None,
        }
    }

    /// Halves: the designed grain, and the as-brushed one side by side. Each with its
    /// overlay layer; in difference mode the first half's radiance is the difference.
    pub fn halves(
        &self,
        designed: Vec<[f32; 3]>,
        brushed: Option<Vec<[f32; 3]>>,
        counters: &mut RenderCounters,
        timer: &mut Timer,
    ) -> Vec<Half> {
        let (fx, input) = (self.fx, self.input);
        let side_by_side = matches!(&fx.as_brushed, Some(a) if a.mode == AsBrushedMode::SideBySide)
            && brushed.is_some();
        let mut halves: Vec<Half> = Vec::new();
        let mut layer = self.overlays(input.u, counters, timer);
        if let (Some(a), Some(bu), Some(l)) =
            (&fx.as_brushed, input.brushed_u, &self.departure_light)
        {
            let s = self.s as f64;
            let (on, departed) = timer.run("as_brushed_highlights", || {
                overlay::highlight_departure(
                    &self.ctx,
                    (input.u, bu),
                    l,
                    0.5 * a.width_px * s,
                    a.departure_px * s,
                    &mut layer,
                )
            });
            counters.brushed_highlight_samples += on;
            counters.departed_highlight_samples += departed;
        }
        let main_rad = match (&fx.as_brushed, &brushed) {
            (Some(a), Some(b)) if a.mode == AsBrushedMode::Difference => {
                let gain = a.gain as f32;
                designed
                    .iter()
                    .zip(b)
                    .map(|(x, y)| [0, 1, 2].map(|c| (x[c] - y[c]).abs() * gain))
                    .collect()
            }
            _ => designed,
        };
        halves.push((main_rad, layer));
        if side_by_side {
            if let (Some(b), Some(bu)) = (brushed, input.brushed_u) {
                let layer = self.overlays(bu, counters, timer);
                halves.push((b, layer));
            }
        }
        halves
    }

    /// Resolve: box filter, tone map, LIC modulation, overlays, background. At supersample 1
    /// the buffers are used as they are (no copies); a covered pixel without overlay or LIC is
    /// encoded through the exact threshold table. Returns the 8-bit image and, when
    /// `settings.linear` is set, the linear one (else empty).
    pub fn resolve(
        &self,
        halves: &[Half],
        lic_values: Option<&[[f32; 1]]>,
    ) -> (Vec<[u8; 3]>, Vec<[f32; 3]>) {
        let (w, h, s, settings, vis) = (self.w, self.h, self.s, self.settings, self.ctx.vis);
        let out_w = w * halves.len();
        let want_linear = settings.linear.is_some();
        let boxed = |v: &[[f32; 1]]| image::downsample(v, w, h, s);
        let coverage: Option<Vec<[f32; 1]>> = (s > 1).then(|| {
            boxed(
                &vis.samples
                    .iter()
                    .map(|x| [f32::from(u8::from(x.face != raster::EMPTY))])
                    .collect::<Vec<_>>(),
            )
        });
        let resolved: Vec<HalfRef> = halves
            .iter()
            .map(|(rad, layer)| {
                if s == 1 {
                    (rad[..].into(), layer[..].into())
                } else {
                    (
                        image::downsample(rad, w, h, s).into(),
                        image::downsample(layer, w, h, s).into(),
                    )
                }
            })
            .collect();
        let table = image::Srgb8Table::new(settings.tone_map, settings.exposure);
        let mut rgb8 = vec![[0u8; 3]; out_w * h];
        let mut linear_px = vec![[0.0f32; 3]; if want_linear { out_w * h } else { 0 }];
        let lin_row = if want_linear { out_w } else { 1 };
        let mut lin_chunks: Vec<&mut [[f32; 3]]> = if want_linear {
            linear_px.chunks_mut(lin_row).collect()
        } else {
            (0..h).map(|_| &mut [][..]).collect()
        };
        rgb8.par_chunks_mut(out_w).zip(lin_chunks.par_iter_mut()).enumerate().for_each(
            |(y, (row8, rowl))| {
                for (hi, (rad, layer)) in resolved.iter().enumerate() {
                    for x in 0..w {
                        let k = y * w + x;
                        let o = hi * w + x;
                        if want_linear {
                            rowl[o] = rad[k];
                        }
                        let lic = lic_values.filter(|_| hi == 0).map(|v| v[k][0]);
                        let cov = match &coverage {
                            Some(c) => c[k][0],
                            None => f32::from(u8::from(vis.samples[k].face != raster::EMPTY)),
                        };
                        row8[o] = if cov == 1.0 && lic.is_none() && layer[k] == [0.0; 4] {
                            rad[k].map(|v| table.encode(v))
                        } else {
                            resolve_pixel(rad[k], layer[k], cov, lic, settings)
                        };
                    }
                }
            },
        );
        drop(lin_chunks);
        (rgb8, linear_px)
    }

    /// Vector overlays (strokes, target arrows, critical rings) drawn over the 8-bit image of
    /// `n_halves` halves, when any is listed and has its input.
    pub fn vector_overlays(
        &self,
        rgb8: Vec<[u8; 3]>,
        n_halves: usize,
        counters: &mut RenderCounters,
        timer: &mut Timer,
    ) -> Result<Vec<[u8; 3]>> {
        let (fx, input, w, h, s) = (self.fx, self.input, self.w, self.h, self.s);
        let out_w = w * n_halves;
        let want_vectors = (fx.strokes.is_some() && input.strokes.is_some())
            || (fx.edits.is_some() && input.edits.is_some_and(|e| !e.targets.is_empty()))
            || (fx.critical_points.is_some() && input.critical.is_some());
        Ok(if want_vectors {
            timer.run("vector_overlays", || -> Result<Vec<[u8; 3]>> {
                let mut canvas = Canvas::new(&rgb8, out_w, h)
                    .ok_or_else(|| Error::setting("render.width", "image cannot be allocated"))?;
                for hi in 0..n_halves {
                    let pp = PointProjector {
                        out: Projector::new(self.camera, w, h),
                        vis: self.ctx.vis,
                        s,
                        x0: (hi * w) as f64,
                    };
                    draw_vectors(&mut canvas, &pp, input, fx, counters);
                }
                Ok(canvas.into_rgb())
            })?
        } else {
            rgb8
        })
    }
}
