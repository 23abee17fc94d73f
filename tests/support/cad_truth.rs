//! Truth about CAD parts computed from their STL files alone, without grainline: the large
//! planar faces (faces of the part, not triangles), the grain a world direction gives on each
//! (docs/scene.md, `field.init: "world"`: the direction projected onto the plane; on a face
//! within 2° of facing it, the world axis least aligned with it, made perpendicular to it,
//! projected), and two figures measured on grainline's outputs against them: the share of
//! the strokes' length on a face that runs within 1° of that grain, and the share of a face's
//! area whose three corners in the glb carry the plane's normal (1°) and the grain (1°), read
//! as a viewer does from the `anisotropyTexture` at TEXCOORD_0 in the TANGENT frame
//! ([`glb_grain`]).
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::Path;

#[path = "glb_texture.rs"]
mod glb_texture;

pub type P = [f64; 3];

/// An edge keyed by its two ends' bits (smaller first).
type EdgeKey = ([u64; 3], [u64; 3]);

pub fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn cross(a: P, b: P) -> P {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
pub fn norm(a: P) -> f64 {
    dot(a, a).sqrt()
}
pub fn unit(a: P) -> P {
    let n = norm(a);
    [a[0] / n, a[1] / n, a[2] / n]
}
/// The angle between two directions in degrees (as lines when `line`).
pub fn angle_deg(a: P, b: P, line: bool) -> f64 {
    let c = dot(a, b) / (norm(a) * norm(b));
    let c = if line { c.abs() } else { c };
    c.clamp(-1.0, 1.0).acos().to_degrees()
}

/// The triangles of a binary or ASCII STL file.
pub fn read_stl(path: &Path) -> Vec<[P; 3]> {
    let b = std::fs::read(path).unwrap();
    let binary = b.len() >= 84 && {
        let n = u32::from_le_bytes([b[80], b[81], b[82], b[83]]) as usize;
        b.len() == 84 + 50 * n
    };
    if binary {
        let n = (b.len() - 84) / 50;
        let f = |o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as f64;
        (0..n)
            .map(|i| {
                let o = 84 + 50 * i + 12;
                [0, 1, 2].map(|k| [0, 1, 2].map(|c| f(o + 12 * k + 4 * c)))
            })
            .collect()
    } else {
        let text = String::from_utf8_lossy(&b);
        let v: Vec<P> = text
            .lines()
            .filter_map(|l| {
                let mut w = l.split_whitespace();
                (w.next() == Some("vertex")).then(|| {
                    let mut c = w.map(|x| x.parse::<f32>().unwrap() as f64);
                    [c.next().unwrap(), c.next().unwrap(), c.next().unwrap()]
                })
            })
            .collect();
        v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
    }
}

/// A planar face of a part: the triangles of one plane joined across shared edges.
pub struct PlanarFace {
    pub normal: P,
    pub offset: f64,
    pub tris: Vec<[P; 3]>,
    pub area: f64,
}

impl PlanarFace {
    /// Whether `p` lies on the face (within `tol` of its plane and inside a triangle).
    pub fn contains(&self, p: P, tol: f64) -> bool {
        if (dot(self.normal, p) - self.offset).abs() > tol {
            return false;
        }
        self.tris.iter().any(|t| {
            let s = |a: P, b: P| dot(cross(sub(b, a), sub(p, a)), self.normal);
            let (x, y, z) = (s(t[0], t[1]), s(t[1], t[2]), s(t[2], t[0]));
            let e = tol * tol;
            (x >= -e && y >= -e && z >= -e) || (x <= e && y <= e && z <= e)
        })
    }

    /// The grain `field.init: "world"` with direction `w` gives on this plane.
    pub fn world_grain(&self, w: P) -> P {
        let n = self.normal;
        let wu = unit(w);
        let d = if dot(wu, n).abs() > 2f64.to_radians().cos() {
            // The world axis least aligned with w, made perpendicular to w.
            let mut k = 0;
            for j in 1..3 {
                if w[j].abs() < w[k].abs() {
                    k = j;
                }
            }
            let mut a = [0.0; 3];
            a[k] = 1.0;
            let s = dot(w, a) / dot(w, w);
            [a[0] - w[0] * s, a[1] - w[1] * s, a[2] - w[2] * s]
        } else {
            w
        };
        let s = dot(d, n);
        unit([d[0] - n[0] * s, d[1] - n[1] * s, d[2] - n[2] * s])
    }
}

/// The part's planar faces of at least `share` of its area, largest first. Triangles are in
/// one face when they share an edge (exactly welded vertices) and their normals agree within
/// 10⁻³ rad.
pub fn large_planar_faces(tris: &[[P; 3]], share: f64) -> Vec<PlanarFace> {
    let key = |p: P| p.map(f64::to_bits);
    let mut edges: HashMap<EdgeKey, Vec<usize>> = HashMap::new();
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
            edges.entry((a.min(b), a.max(b))).or_default().push(f);
        }
    }
    let normal = |t: &[P; 3]| {
        let c = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        (norm(c) > 0.0).then(|| unit(c))
    };
    let area = |t: &[P; 3]| 0.5 * norm(cross(sub(t[1], t[0]), sub(t[2], t[0])));
    let total: f64 = tris.iter().map(area).sum();
    let mut seen = vec![false; tris.len()];
    let mut faces = Vec::new();
    for seed in 0..tris.len() {
        let Some(n) = normal(&tris[seed]) else { continue };
        if seen[seed] {
            continue;
        }
        seen[seed] = true;
        let mut stack = vec![seed];
        let mut members = Vec::new();
        while let Some(f) = stack.pop() {
            members.push(f);
            let t = &tris[f];
            for k in 0..3 {
                let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
                for &g in &edges[&(a.min(b), a.max(b))] {
                    if !seen[g] && normal(&tris[g]).is_some_and(|m| dot(m, n) > 1.0 - 5e-7) {
                        seen[g] = true;
                        stack.push(g);
                    }
                }
            }
        }
        let a: f64 = members.iter().map(|&f| area(&tris[f])).sum();
        if a >= share * total {
            let ft: Vec<[P; 3]> = members.iter().map(|&f| tris[f]).collect();
            let offset =
                ft.iter().flatten().map(|p| dot(n, *p)).sum::<f64>() / (3 * ft.len()) as f64;
            faces.push(PlanarFace { normal: n, offset, tris: ft, area: a });
        }
    }
    faces.sort_by(|a, b| b.area.total_cmp(&a.area));
    faces
}

/// The diagonal of the triangles' bounding box.
pub fn diagonal(tris: &[[P; 3]]) -> f64 {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in tris.iter().flatten() {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    norm(sub(hi, lo))
}

/// Per face: (length of strokes on the face, of which within 1° of its grain) from a strokes
/// JSON (`toolpaths.strokes_json`).
pub fn stroke_straightness(
    strokes: &Path,
    faces: &[PlanarFace],
    w: P,
    tol: f64,
) -> Vec<(f64, f64)> {
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(strokes).unwrap()).unwrap();
    let v3 = |v: &serde_json::Value| [0, 1, 2].map(|k| v[k].as_f64().unwrap());
    let grains: Vec<P> = faces.iter().map(|f| f.world_grain(w)).collect();
    let mut out = vec![(0.0, 0.0); faces.len()];
    for stroke in s["strokes"].as_array().unwrap() {
        for piece in stroke["xyz"].as_array().unwrap() {
            let xyz: Vec<P> = piece.as_array().unwrap().iter().map(v3).collect();
            for seg in xyz.windows(2) {
                let d = sub(seg[1], seg[0]);
                let len = norm(d);
                if len == 0.0 {
                    continue;
                }
                let m = [0, 1, 2].map(|c| 0.5 * (seg[0][c] + seg[1][c]));
                for (k, f) in faces.iter().enumerate() {
                    let on = |p: P| (dot(f.normal, p) - f.offset).abs() <= tol;
                    if on(seg[0]) && on(seg[1]) && f.contains(m, tol) {
                        out[k].0 += len;
                        if angle_deg(d, grains[k], true) < 1.0 {
                            out[k].1 += len;
                        }
                        break;
                    }
                }
            }
        }
    }
    out
}

/// The part's primitive of a grainline glb as a viewer reads it: positions, normals, triangles,
/// and per vertex the grain u = d × n, d the anisotropy direction — the `anisotropyTexture`'s
/// RG (× 2 − 1) sampled bilinearly at TEXCOORD_0 (clamped), in the frame (T, w·(N × T)) of
/// TANGENT, turned by `anisotropyRotation` (docs/gltf.md, "Convention").
pub struct GlbGrain {
    pub p: Vec<[f32; 3]>,
    pub n: Vec<[f32; 3]>,
    pub u: Vec<P>,
    pub idx: Vec<u32>,
}

pub fn glb_grain(glb: &Path) -> GlbGrain {
    let v = GlbView::read(glb);
    let u = (0..v.p.len()).map(|k| v.grain_at_vertex(k)).collect();
    GlbGrain { p: v.p.clone(), n: v.n.clone(), u, idx: v.idx.clone() }
}

/// The part's primitive of a grainline glb and its `anisotropyTexture`, read as a viewer
/// reads them: per fragment the interpolated NORMAL, TANGENT and TEXCOORD_0, the texture
/// sampled bilinearly there (clamped), its RG (× 2 − 1) turned by `anisotropyRotation` in the
/// frame (T, w·(N × T)) the anisotropy direction d, and the grain u = d × n.
pub struct GlbView {
    pub p: Vec<[f32; 3]>,
    pub n: Vec<[f32; 3]>,
    pub t: Vec<[f32; 4]>,
    pub uv: Vec<[f32; 2]>,
    pub idx: Vec<u32>,
    /// The `anisotropyTexture`.
    texture: glb_texture::Texture,
    rot: f64,
}

impl GlbView {
    pub fn read(glb: &Path) -> Self {
        let bytes = std::fs::read(glb).unwrap();
        let g = gltf::Gltf::from_slice(&bytes).unwrap();
        let blob = g.blob.as_deref().unwrap();
        let doc = glb_texture::glb_json(&bytes);
        let ext = &doc["materials"][0]["extensions"]["KHR_materials_anisotropy"];
        let rot = ext["anisotropyRotation"].as_f64().unwrap_or(0.0);
        let index = ext["anisotropyTexture"]["index"].as_u64().unwrap() as usize;
        let texture = glb_texture::read_texture(&doc, blob, index);
        let prim = g.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|_| Some(blob));
        GlbView {
            p: reader.read_positions().unwrap().collect(),
            n: reader.read_normals().unwrap().collect(),
            t: reader.read_tangents().unwrap().collect(),
            uv: reader.read_tex_coords(0).unwrap().into_f32().collect(),
            idx: reader.read_indices().unwrap().into_u32().collect(),
            texture,
            rot,
        }
    }

    /// The texture's RG at TEXCOORD_0 `st`, bilinear between the four nearest texel centres.
    fn sample(&self, st: [f64; 2]) -> [f64; 2] {
        self.texture.sample(st)
    }

    /// Position, unit normal and grain at barycentric `b` of the triangle `tri` (vertex
    /// indices), as a fragment shader interpolates them.
    pub fn fragment(&self, tri: [u32; 3], b: [f64; 3]) -> (P, P, P) {
        let lerp3 = |f: &dyn Fn(usize) -> P| {
            let mut o = [0.0; 3];
            for (c, &v) in tri.iter().enumerate() {
                let x = f(v as usize);
                for k in 0..3 {
                    o[k] += b[c] * x[k];
                }
            }
            o
        };
        let p = lerp3(&|v| self.p[v].map(f64::from));
        let n = unit(lerp3(&|v| self.n[v].map(f64::from)));
        let t = lerp3(&|v| [0, 1, 2].map(|k| f64::from(self.t[v][k])));
        let w: f64 = tri.iter().zip(b).map(|(&v, bc)| bc * f64::from(self.t[v as usize][3])).sum();
        let st = lerp3(&|v| [f64::from(self.uv[v][0]), f64::from(self.uv[v][1]), 0.0]);
        let tt = unit(sub(t, n.map(|c| c * dot(n, t))));
        let bt = cross(n, tt).map(|c| c * w.signum());
        let [dx, dy] = self.sample([st[0], st[1]]);
        let a = dy.atan2(dx) + self.rot;
        let d = [0, 1, 2].map(|c| a.cos() * tt[c] + a.sin() * bt[c]);
        (p, n, cross(d, n))
    }

    /// The grain at vertex `k` (the texture sampled at its TEXCOORD_0 in its own frame).
    pub fn grain_at_vertex(&self, k: usize) -> P {
        let nn = self.n[k].map(f64::from);
        let tt = [self.t[k][0], self.t[k][1], self.t[k][2]].map(f64::from);
        let b = cross(nn, tt).map(|c| c * f64::from(self.t[k][3]));
        let [dx, dy] = self.sample([f64::from(self.uv[k][0]), f64::from(self.uv[k][1])]);
        let a = dy.atan2(dx) + self.rot;
        let d = [0, 1, 2].map(|c| a.cos() * tt[c] + a.sin() * b[c]);
        cross(d, nn)
    }
}

/// The bound on the glb's grain at a corner ([`glb_flatness`]): 1°. It was 0.5° while TANGENT
/// carried u exactly; read from the texture (issue 33) the corners of a few large faces of the
/// generated housing are off by up to 0.68° (a bilinear sample at the corner of a triangle
/// that spans hundreds of texels, 16-bit).
pub const GLB_GRAIN_DEG: f64 = 1.0;

/// Per face: (area of the glb's triangles on the face, of which with the plane's normal
/// within 1° and the grain ([`glb_grain`]) within [`GLB_GRAIN_DEG`] at all three corners).
pub fn glb_flatness(glb: &Path, faces: &[PlanarFace], w: P, tol: f64) -> Vec<(f64, f64)> {
    let GlbGrain { p, n, u: grain, idx } = glb_grain(glb);
    let d = |v: [f32; 3]| v.map(f64::from);
    let grains: Vec<P> = faces.iter().map(|f| f.world_grain(w)).collect();
    let mut out = vec![(0.0, 0.0); faces.len()];
    for tri in idx.chunks(3) {
        let q: Vec<P> = tri.iter().map(|&i| d(p[i as usize])).collect();
        let c = [0, 1, 2].map(|k| (q[0][k] + q[1][k] + q[2][k]) / 3.0);
        // A triangle on the face faces the way it does: a part touching another (a lid on
        // its box) has coplanar faces facing each other.
        let facing = cross(sub(q[1], q[0]), sub(q[2], q[0]));
        let Some(k) = faces.iter().position(|f| {
            dot(facing, f.normal) > 0.0
                && q.iter().all(|v| (dot(f.normal, *v) - f.offset).abs() <= tol)
                && f.contains(c, tol)
        }) else {
            continue;
        };
        let area = 0.5 * norm(cross(sub(q[1], q[0]), sub(q[2], q[0])));
        out[k].0 += area;
        let ok = tri.iter().all(|&i| {
            let nv = d(n[i as usize]);
            angle_deg(nv, faces[k].normal, false) < 1.0
                && angle_deg(grain[i as usize], grains[k], true) < GLB_GRAIN_DEG
        });
        if ok {
            out[k].1 += area;
        } else if std::env::var("CAD_DEBUG").is_ok() {
            for &i in tri {
                let nv = d(n[i as usize]);
                eprintln!(
                    "  face {k} corner {:?}: normal off {:.3}°, grain off {:.3}°",
                    p[i as usize],
                    angle_deg(nv, faces[k].normal, false),
                    angle_deg(grain[i as usize], grains[k], true)
                );
            }
        }
    }
    out
}

impl PlanarFace {
    /// The face's boundary edges: edges of one of its triangles only.
    pub fn boundary(&self) -> Vec<[P; 2]> {
        let key = |p: P| p.map(f64::to_bits);
        let mut count: HashMap<EdgeKey, ([P; 2], usize)> = HashMap::new();
        for t in &self.tris {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let e =
                    count.entry((key(a).min(key(b)), key(a).max(key(b)))).or_insert(([a, b], 0));
                e.1 += 1;
            }
        }
        let mut out: Vec<[P; 2]> =
            count.into_values().filter(|(_, n)| *n == 1).map(|(e, _)| e).collect();
        out.sort_by(|x, y| x[0].partial_cmp(&y[0]).unwrap().then(x[1].partial_cmp(&y[1]).unwrap()));
        out
    }

    /// A point of the face far from its boundary (the best of a 48 × 48 grid over the face's
    /// extent) and its distance to the boundary.
    pub fn deep_point(&self) -> (P, f64) {
        let n = self.normal;
        let a = unit(if n[0].abs() < 0.9 {
            cross(n, [1.0, 0.0, 0.0])
        } else {
            cross(n, [0.0, 1.0, 0.0])
        });
        let b = cross(n, a);
        let pts: Vec<P> = self.tris.iter().flatten().copied().collect();
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for p in &pts {
            let c = [dot(*p, a), dot(*p, b)];
            for k in 0..2 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        let edges = self.boundary();
        let tol = 1e-9 * norm(sub([hi[0], hi[1], 0.0], [lo[0], lo[1], 0.0]));
        let mut best = (pts[0], 0.0);
        for i in 0..48 {
            for j in 0..48 {
                let (s, t) = ((i as f64 + 0.5) / 48.0, (j as f64 + 0.5) / 48.0);
                let (x, y) = (lo[0] + s * (hi[0] - lo[0]), lo[1] + t * (hi[1] - lo[1]));
                let p = [0, 1, 2].map(|k| a[k] * x + b[k] * y + n[k] * self.offset);
                if !self.contains(p, tol) {
                    continue;
                }
                let d =
                    edges.iter().map(|e| segment_distance(p, e[0], e[1])).fold(f64::MAX, f64::min);
                if d > best.1 {
                    best = (p, d);
                }
            }
        }
        best
    }
}

/// The distance from `p` to the segment `a`–`b`.
pub fn segment_distance(p: P, a: P, b: P) -> f64 {
    let ab = sub(b, a);
    let t = (dot(sub(p, a), ab) / dot(ab, ab).max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    norm(sub(p, [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]]))
}

/// An eye `dist` from `p0` that puts the key highlight of a grain `u` (unit, tangent at `p0`)
/// through `p0` under a directional light `l` (unit, above the surface): the view direction is
/// `l` mirrored across the plane normal to `u`, so (l + v)·u = 0 there and h·u = 0.
pub fn eye_on_highlight(p0: P, u: P, l: P, dist: f64) -> P {
    let s = 2.0 * dot(l, u);
    let v = [l[0] - s * u[0], l[1] - s * u[1], l[2] - s * u[2]];
    [p0[0] + dist * v[0], p0[1] + dist * v[1], p0[2] + dist * v[2]]
}

/// The direction across the key highlight at `p0` on a surface of normal `n` with a uniform
/// grain `u`: the tangential gradient of g(p) = h(p)·u, h = normalize(l + normalize(eye − p))
/// (a directional light `l`, a point eye), by central differences in the tangent plane.
pub fn across_highlight(p0: P, n: P, u: P, l: P, eye: P, step: f64) -> P {
    let g = |p: P| {
        let v = unit(sub(eye, p));
        dot(unit([l[0] + v[0], l[1] + v[1], l[2] + v[2]]), u)
    };
    let a =
        unit(if n[0].abs() < 0.9 { cross(n, [1.0, 0.0, 0.0]) } else { cross(n, [0.0, 1.0, 0.0]) });
    let b = cross(n, a);
    let at = |d: P, s: f64| [p0[0] + d[0] * s, p0[1] + d[1] * s, p0[2] + d[2] * s];
    let (ga, gb) = ((g(at(a, step)) - g(at(a, -step))), (g(at(b, step)) - g(at(b, -step))));
    unit([a[0] * ga + b[0] * gb, a[1] * ga + b[1] * gb, a[2] * ga + b[2] * gb])
}

/// Where and how a test edit is seen: a key light above the surface, an eye that puts the key
/// highlight through the brush's centre, the push across that highlight (for a bend), and a
/// drawn S-curve (tangent-plane points, for a curve).
pub struct EditSite {
    pub light: P,
    pub eye: P,
    pub push: P,
    pub curve: Vec<P>,
}

/// The [`EditSite`] at `p0` on a surface of normal `n` with grain `u`, for a brush of radius
/// `r` on a part of diagonal `d`: the light (0.3, −0.5, 1) unless it grazes the surface (then
/// one 37° from the normal), the eye 1.5 d away ([`eye_on_highlight`]), and an S-curve 2.5 r
/// long at 45° to the grain, of amplitude 0.2 r, in the tangent plane.
pub fn edit_site(p0: P, n: P, u: P, r: f64, d: f64) -> EditSite {
    let s = cross(n, u);
    let mut light = unit([0.3, -0.5, 1.0]);
    if dot(light, n) < 0.2 {
        light = unit([0.8 * n[0] + 0.6 * s[0], 0.8 * n[1] + 0.6 * s[1], 0.8 * n[2] + 0.6 * s[2]]);
    }
    let eye = eye_on_highlight(p0, u, light, 1.5 * d);
    let push = across_highlight(p0, n, u, light, eye, 1e-3 * d);
    let a = unit([u[0] + s[0], u[1] + s[1], u[2] + s[2]]);
    let b = cross(n, a);
    let curve = (0..=40)
        .map(|i| {
            let t = i as f64 / 20.0 - 1.0;
            let w = 0.2 * r * (std::f64::consts::PI * t).sin();
            [0, 1, 2].map(|k| p0[k] + a[k] * 1.25 * r * t + b[k] * w)
        })
        .collect();
    EditSite { light, eye, push, curve }
}
