//! The grain as a texture in UV space: baked for the glb's `anisotropyTexture` and for the
//! maps of `export.maps`, and read back for `field.init: "map"` (docs/formats.md, "Grain
//! maps"; docs/gltf.md).
//!
//! Conventions, shared by everything this module writes and reads:
//!
//! - **Texture space.** A corner's texture coordinates are st = (uv − offset) / scale
//!   ([`TextureSpace`]): the part's UVs as they are when they all lie in [0, 1]², else the one
//!   offset and uniform scale that put the lower-left corner of their bounding box at (0, 0) and
//!   its longer side at 1 (a panel's UVs are millimetres). t grows upwards (OBJ's and Blender's
//!   V); image row 0 is the top: texel (i, j) of an N × M image has its centre at
//!   s = (i + ½)/N, t = 1 − (j + ½)/M. glTF's TEXCOORD_0 is (s, 1 − t).
//! - **Tangent frame.** At each face corner, T and its sign w are MikkTSpace's (computed from
//!   the positions, the unit vertex normals N and st, [`mikk`]); the bitangent is
//!   B = w·(N × T), glTF's. A texel's frame is the corners' T, N and w interpolated
//!   barycentrically, T made perpendicular to N — what a viewer does per fragment.
//! - **Grain.** The grain u at a texel is (x, y) = (u·T, u·B), unit: its angle is measured from
//!   T towards B.
//!
//! [`bake`] rasterizes the grain per UV triangle and fills every texel outside the triangles
//! from its nearest filled neighbours (a breadth-first dilation over the whole image), so that
//! bilinear and mipmapped sampling near a chart's border reads the chart's own grain.
//! [`GrainImage`] encodes it ([`GrainImage::direction_png16`], [`GrainImage::angle_png16`],
//! [`GrainImage::anisotropy_png16`]); [`read_map`] and [`corner_grain`] read a map back.

mod fit;
pub mod mikk;
pub mod orient;
pub mod png_io;
mod raster;

use nalgebra::{Vector2, Vector3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::mesh::CornerAttribute;
use crate::{Error, Result};

pub use png_io::read_map;
pub use raster::GrainImage;

/// The smallest and largest texture size (texels per side) grainline writes.
pub const TEXTURE_SIZE_RANGE: (u32, u32) = (16, 8192);

/// The range of the texture size chosen when the scene gives none ([`auto_size`]).
pub const AUTO_SIZE_RANGE: (u32, u32) = (1024, 4096);

/// Texels the shortest 5 % of the UV edges span at least, at the size [`auto_size`] picks.
pub const AUTO_TEXELS_PER_EDGE: f64 = 8.0;

/// The texture size when the scene gives none: the smallest power of two in
/// [`AUTO_SIZE_RANGE`] at which the 5th percentile of the UV edge lengths (in texture space)
/// spans [`AUTO_TEXELS_PER_EDGE`] texels — so that the grain, linear inside each triangle, is
/// held at eight texels or more per edge (the round trip of every example within 0.5°,
/// tests/texture_maps.rs).
pub fn auto_size(uv: &CornerAttribute<Vector2<f64>>) -> u32 {
    auto_size_with(uv, None)
}

/// [`auto_size`], and every face of a recognized curved surface held to texels of its own:
/// inside such a chord the grain is the surface's, not linear, turning by up to the angle
/// `turn_deg[f]` between the surface's normals at its corners, and the texture alone carries
/// it between them; so the chord's middle edge spans [`AUTO_TEXELS_PER_EDGE`] texels, and at
/// least one per degree of that turn (the wall of a 3 mm hole written with 30° strips showed
/// the grain within 1° on 97 % of its area at twelve texels a chord, on all of it at
/// forty-eight). The middle edge, so that a sliver's shortest edge does not decide.
pub fn auto_size_with(uv: &CornerAttribute<Vector2<f64>>, turn_deg: Option<&[f64]>) -> u32 {
    let space = TextureSpace::of(uv);
    let tris = space.corners(uv);
    let mut lengths: Vec<f64> = tris
        .iter()
        .flat_map(|t| [(t[1] - t[0]).norm(), (t[2] - t[1]).norm(), (t[0] - t[2]).norm()])
        .filter(|l| *l > 0.0 && l.is_finite())
        .collect();
    let (lo, hi) = AUTO_SIZE_RANGE;
    lengths.sort_by(f64::total_cmp);
    let all = (!lengths.is_empty()).then(|| AUTO_TEXELS_PER_EDGE / lengths[lengths.len() / 20]);
    let middle = |t: &[Vector2<f64>; 3]| {
        let mut e = [(t[1] - t[0]).norm(), (t[2] - t[1]).norm(), (t[0] - t[2]).norm()];
        e.sort_by(f64::total_cmp);
        e[1]
    };
    let on_curves = turn_deg.and_then(|turns| {
        (0..tris.len())
            .filter_map(|f| {
                let turn = turns.get(f).copied().filter(|t| *t > 0.0 && t.is_finite())?;
                let l = middle(&tris[f]);
                (l > 0.0 && l.is_finite()).then(|| AUTO_TEXELS_PER_EDGE.max(turn) / l)
            })
            .reduce(f64::max)
    });
    let Some(need) = [all, on_curves].into_iter().flatten().reduce(f64::max) else {
        return lo;
    };
    let need = need.min(f64::from(hi));
    (need.ceil() as u32).next_power_of_two().clamp(lo, hi)
}

/// The map from a part's UVs to texture space: st = (uv − offset) / scale.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TextureSpace {
    /// Subtracted from every UV.
    pub offset: [f64; 2],
    /// The UVs are divided by it after the offset.
    pub scale: f64,
}

impl TextureSpace {
    /// Identity when every UV the faces use lies in [0, 1]²; else the offset and uniform scale
    /// that fit their bounding box into [0, 1]² at the lower left (module docs).
    pub fn of(uv: &CornerAttribute<Vector2<f64>>) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &c in uv.corners.iter().flatten() {
            let p = uv.values[c as usize];
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let identity = TextureSpace { offset: [0.0, 0.0], scale: 1.0 };
        if !(lo.iter().chain(&hi).all(|c| c.is_finite())) {
            return identity;
        }
        if lo.iter().all(|&c| c >= 0.0) && hi.iter().all(|&c| c <= 1.0) {
            return identity;
        }
        let scale = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        if scale > 0.0 && scale.is_finite() {
            TextureSpace { offset: lo, scale }
        } else {
            TextureSpace { offset: lo, scale: 1.0 }
        }
    }

    /// The texture coordinates of `uv`.
    pub fn st(&self, uv: Vector2<f64>) -> Vector2<f64> {
        Vector2::new((uv.x - self.offset[0]) / self.scale, (uv.y - self.offset[1]) / self.scale)
    }

    /// The texture coordinates of every face corner.
    pub fn corners(&self, uv: &CornerAttribute<Vector2<f64>>) -> Vec<[Vector2<f64>; 3]> {
        (0..uv.corners.len()).map(|f| uv.face(f).map(|p| self.st(p))).collect()
    }
}

/// What a map holds (`field.map.kind`, docs/formats.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema, Hash)]
#[serde(rename_all = "snake_case")]
pub enum MapKind {
    /// RG: the direction across the grain, n × u, in the tangent frame, [−1, 1] → [0, 1]
    /// (glTF's `anisotropyTexture`, Marmoset's direction map); B: 1.
    #[default]
    Direction,
    /// Grey: the grain's angle from T towards B in [0, π), encoded θ/π (Blender's and
    /// Substance's angle maps).
    Angle,
}

/// A map read back: per texel, rows top to bottom, a vector in the tangent frame — for a
/// direction map the direction across the grain as stored, for an angle map the grain
/// (cos θ, sin θ).
#[derive(Clone, Debug, PartialEq)]
pub struct GrainMap {
    /// What the map holds.
    pub kind: MapKind,
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The vectors, `width × height`, row 0 at the top.
    pub texels: Vec<[f32; 2]>,
}

impl GrainMap {
    /// The vector at texture coordinates `st`, bilinear between the four nearest texel
    /// centres (clamped at the edges). A line field (`oriented` false) is averaged by its
    /// doubled angle, so u and −u add up; an oriented one as vectors. `None` when the four
    /// cancel.
    pub fn sample(&self, st: Vector2<f64>, oriented: bool) -> Option<Vector2<f64>> {
        let (w, h) = (self.width as f64, self.height as f64);
        let x = (st.x * w - 0.5).clamp(0.0, w - 1.0);
        let y = ((1.0 - st.y) * h - 0.5).clamp(0.0, h - 1.0);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let mut acc = Vector2::zeros();
        for (i, j, wt) in [
            (x0, y0, (1.0 - fx) * (1.0 - fy)),
            (x1, y0, fx * (1.0 - fy)),
            (x0, y1, (1.0 - fx) * fy),
            (x1, y1, fx * fy),
        ] {
            let t = self.texels[j * self.width + i];
            let v = Vector2::new(f64::from(t[0]), f64::from(t[1]));
            let len2 = v.norm_squared();
            if len2.is_nan() || len2 <= 1e-12 {
                continue;
            }
            acc += wt
                * if oriented {
                    v / len2.sqrt()
                } else {
                    Vector2::new(v.x * v.x - v.y * v.y, 2.0 * v.x * v.y) / len2
                };
        }
        let len = acc.norm();
        if len.is_nan() || len <= 1e-9 {
            return None;
        }
        Some(if oriented {
            acc / len
        } else {
            let a = 0.5 * acc.y.atan2(acc.x);
            Vector2::new(a.cos(), a.sin())
        })
    }
}

/// The unit frame (T, B, N) of a corner or texel from an interpolated normal, tangent and sign:
/// N normalized, T made perpendicular to it, B = w·(N × T). `None` when degenerate.
pub fn frame(
    n: Vector3<f64>,
    t: Vector3<f64>,
    w: f64,
) -> Option<(Vector3<f64>, Vector3<f64>, Vector3<f64>)> {
    let n = n.try_normalize(1e-12)?;
    let t = (t - n * n.dot(&t)).try_normalize(1e-12)?;
    let w = if w < 0.0 { -1.0 } else { 1.0 };
    Some((t, n.cross(&t) * w, n))
}

/// A frame (T, B, N) and its sign w.
pub(crate) type LerpFrame = (Vector3<f64>, Vector3<f64>, Vector3<f64>, f64);

/// The frame (T, B, N) and sign w at barycentric `b` of a face whose corners have unit normals
/// `normals` and MikkTSpace `tangents`: N, T and w interpolated, then [`frame`] — what a viewer
/// does per fragment and what the baker writes each texel in. `None` when degenerate.
pub(crate) fn lerp_frame(
    normals: &[Vector3<f64>; 3],
    tangents: &[[f32; 4]; 3],
    b: [f64; 3],
) -> Option<LerpFrame> {
    let (mut n, mut t, mut w) = (Vector3::zeros(), Vector3::zeros(), 0.0);
    for (c, bc) in b.iter().enumerate() {
        let tc = tangents[c];
        n += *bc * normals[c];
        t += *bc * Vector3::new(f64::from(tc[0]), f64::from(tc[1]), f64::from(tc[2]));
        w += *bc * f64::from(tc[3]);
    }
    let (t, bt, n) = frame(n, t, w)?;
    Some((t, bt, n, if w < 0.0 { -1.0 } else { 1.0 }))
}

/// What [`bake`] needs: the part, its unit normals, its UVs and the grain per face corner,
/// already oriented per triangle for a line field ([`orient`]).
#[derive(Clone, Copy, Debug)]
pub struct BakeInput<'a> {
    /// Vertex positions.
    pub positions: &'a [Vector3<f64>],
    /// Triangles.
    pub faces: &'a [[u32; 3]],
    /// Unit vertex normals.
    pub normals: &'a [Vector3<f64>],
    /// The part's UVs (mapped to texture space by [`TextureSpace::of`]).
    pub uv: &'a CornerAttribute<Vector2<f64>>,
    /// The grain at each face corner (3D, any length; signs agreeing within a face).
    pub grain: &'a [[Vector3<f64>; 3]],
    /// Texels per side.
    pub size: u32,
    /// The grain is a line field (k = 2): the dilation aligns signs before averaging.
    pub line: bool,
}

/// The grain baked into texture space and the frames it was baked in.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The texels.
    pub image: GrainImage,
    /// The texture space of the part's UVs.
    pub space: TextureSpace,
    /// Texture coordinates per face corner.
    pub st: Vec<[Vector2<f64>; 3]>,
    /// MikkTSpace tangents per face corner ([`mikk::corner_frames`]).
    pub frames: mikk::CornerFrames,
}

/// Checks a texture size: a power of two in [`TEXTURE_SIZE_RANGE`].
pub fn check_size(key: &str, size: u32) -> Result<()> {
    let (lo, hi) = TEXTURE_SIZE_RANGE;
    if size.is_power_of_two() && (lo..=hi).contains(&size) {
        Ok(())
    } else {
        Err(Error::setting(key, format!("must be a power of two in [{lo}, {hi}], got {size}")))
    }
}

/// Bakes the grain into a `size`² image (module docs): MikkTSpace frames per corner, the grain
/// rasterized per UV triangle in the interpolated frame, the rest of the image dilated.
pub fn bake(input: &BakeInput) -> Result<Baked> {
    check_size("texture size", input.size)?;
    let nf = input.faces.len();
    if input.uv.corners.len() != nf || input.grain.len() != nf {
        return Err(Error::invalid_arg(
            "bake input",
            format!(
                "{nf} faces, {} UV faces and {} grain faces: they must match",
                input.uv.corners.len(),
                input.grain.len()
            ),
        ));
    }
    let space = TextureSpace::of(input.uv);
    let st = space.corners(input.uv);
    let frames = mikk::corner_frames(input.positions, input.faces, input.normals, &st);
    let image = raster::rasterize(input, &st, &frames);
    Ok(Baked { image, space, st, frames })
}

/// The grain a map gives at every face corner, in 3D (unit, in the corner's tangent plane):
/// the field fitted to the texels inside the face (the `fit` module), or where that fails the map
/// sampled at the corner's texture coordinates ([`GrainMap::sample`]) in the corner's
/// MikkTSpace frame. A direction map's vector is the direction across the grain, n × u, so
/// u = (n × u) × n. `None` where the map's texels cancel or the frame is degenerate.
pub fn corner_grain(
    positions: &[Vector3<f64>],
    faces: &[[u32; 3]],
    normals: &[Vector3<f64>],
    uv: &CornerAttribute<Vector2<f64>>,
    map: &GrainMap,
    oriented: bool,
) -> CornerGrain {
    let st = TextureSpace::of(uv).corners(uv);
    let frames = mikk::corner_frames(positions, faces, normals, &st);
    let mut fitted = vec![false; faces.len()];
    let grain = (0..faces.len())
        .map(|f| {
            let face = fit::Face {
                normals: faces[f].map(|v| normals[v as usize]),
                tangents: &frames.tangents[f],
                line: !oriented,
            };
            if let Some(u) = fit::fit_face(&face, map, &st[f]) {
                fitted[f] = true;
                return u.map(Some);
            }
            [0, 1, 2].map(|c| {
                let t = frames.tangents[f][c];
                let n = normals[faces[f][c] as usize];
                let tv = Vector3::new(f64::from(t[0]), f64::from(t[1]), f64::from(t[2]));
                let (t, b, n) = frame(n, tv, f64::from(t[3]))?;
                let d = map.sample(st[f][c], oriented)?;
                let v = t * d.x + b * d.y;
                Some(match map.kind {
                    MapKind::Angle => v,
                    MapKind::Direction => v.cross(&n),
                })
            })
        })
        .collect();
    CornerGrain { grain, fitted }
}

/// What [`corner_grain`] reads: the grain per face corner, and per face whether it was fitted
/// to the face's own texels (else sampled bilinearly at each corner).
#[derive(Clone, Debug)]
pub struct CornerGrain {
    /// Per face, per corner: the unit grain, `None` where the map gives none.
    pub grain: Vec<[Option<Vector3<f64>>; 3]>,
    /// Per face: read by the fit.
    pub fitted: Vec<bool>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// UVs inside the unit square are kept; a panel's millimetres are fitted at the lower
    /// left with their aspect kept.
    #[test]
    fn texture_space() {
        let attr = |v: Vec<[f64; 2]>| CornerAttribute {
            values: v.iter().map(|p| Vector2::new(p[0], p[1])).collect(),
            corners: vec![[0, 1, 2]],
        };
        let s = TextureSpace::of(&attr(vec![[0.0, 0.0], [1.0, 0.2], [0.5, 1.0]]));
        assert_eq!(s, TextureSpace { offset: [0.0, 0.0], scale: 1.0 });
        let s = TextureSpace::of(&attr(vec![[10.0, 20.0], [170.0, 20.0], [10.0, 100.0]]));
        assert_eq!(s, TextureSpace { offset: [10.0, 20.0], scale: 160.0 });
        assert_eq!(s.st(Vector2::new(170.0, 100.0)), Vector2::new(1.0, 0.5));
    }

    /// Sampling a line field across a sign flip reads the line, not the cancelled vector.
    #[test]
    fn line_sampling_ignores_signs() {
        let a = 0.3f32;
        let map = GrainMap {
            kind: MapKind::Angle,
            width: 2,
            height: 1,
            texels: vec![[a.cos(), a.sin()], [-a.cos(), -a.sin()]],
        };
        let v = map.sample(Vector2::new(0.5, 0.5), false).unwrap();
        assert!((v.y.atan2(v.x) - 0.3).abs() < 1e-6, "{v:?}");
        assert!(map.sample(Vector2::new(0.5, 0.5), true).is_none());
    }
}
