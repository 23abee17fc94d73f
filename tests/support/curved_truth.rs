//! Truth about the curved faces of a generated CAD part (`grainline::generate::cad`): each
//! triangle's analytic face (cylinder, cone, torus, sphere) is known from the generator, so
//! the true normal anywhere on a face is the surface's, and a world grain `w` there is `w`
//! projected onto the true tangent plane. Three figures are measured against them on
//! grainline's outputs, per curved face:
//! - the strokes (`toolpaths.strokes_json`'s `xyz`): the share of their length whose segments
//!   run within 1° of the grain at their midpoint, and how far their points stand off the
//!   surface;
//! - the glb as a viewer reads it ([`GlbView`]): the share of corner normals within 1° of the
//!   true normal; the share of the face's area whose fragments show the grain within 1° (the
//!   `anisotropyTexture` in the interpolated TANGENT frame, 36 fragments per triangle, against
//!   `w` projected onto the tangent plane the viewer shades the fragment with); and the share
//!   whose interpolated normal is within 1° of the true normal at the nearest surface point
//!   (a chord's fragment stands off the surface; on a thin torus its nearest point and the
//!   viewer's interpolation disagree by a few degrees near the strip's middle).
//!
//! Where `w` is within [`NEAR_NORMAL_DEG`] of the surface normal the grain is the world
//! direction's projection near its vanishing point (a sphere's or a torus's pole towards `w`):
//! those points are counted apart, not judged.
#![allow(dead_code)]

use grainline::generate::cad::{AnalyticFace, CadPart};
use nalgebra::Vector3;

use super::cad_truth::{angle_deg, cross, dot, norm, sub, unit, GlbView, P};

/// Points whose true normal is within this angle of ±w are not judged (the projected world
/// direction vanishes there).
pub const NEAR_NORMAL_DEG: f64 = 10.0;

/// A generated part's curved faces and where its triangles lie.
pub struct CurvedTruth {
    pub faces: Vec<AnalyticFace>,
    /// Per face, its triangles' bounding box `[lo, hi]`.
    boxes: Vec<[P; 2]>,
    /// Per face, how far a point of its triangles may stand off it (sagitta and float32).
    slack: Vec<f64>,
    /// The face of each triangle, keyed by its corners as float32 (sorted): a glb triangle
    /// is one of the part's.
    by_corners: std::collections::HashMap<[[u32; 3]; 3], usize>,
}

/// A triangle's corners as float32 bits, sorted.
fn corner_key(t: [[f32; 3]; 3]) -> [[u32; 3]; 3] {
    let mut k = t.map(|p| p.map(f32::to_bits));
    k.sort();
    k
}

/// Per curved face: what was measured.
#[derive(Clone, Debug, Default)]
pub struct FaceFigures {
    /// Stroke length on the face (judged), and of it within 1° of the grain.
    pub stroke_len: f64,
    pub stroke_ok: f64,
    /// Stroke length near the vanishing point, not judged.
    pub stroke_skipped: f64,
    /// Largest distance of a stroke point from the surface.
    pub stroke_off: f64,
    /// glb corners on the face, of which with the true normal within 1°.
    pub corners: usize,
    pub corners_ok: usize,
    /// glb area on the face (judged), of which showing the grain within 1°.
    pub area: f64,
    pub area_ok: f64,
    /// Of that area, the share whose interpolated normal is within 1° of the true normal at
    /// the fragment's nearest surface point.
    pub area_normal_ok: f64,
}

fn v(p: P) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

fn a(p: Vector3<f64>) -> P {
    [p.x, p.y, p.z]
}

impl CurvedTruth {
    pub fn new(part: &CadPart) -> Self {
        let n = part.faces.len();
        let mut boxes = vec![[[f64::MAX; 3], [f64::MIN; 3]]; n];
        for (t, &f) in part.triangles.iter().zip(&part.face_of) {
            for p in t {
                for c in 0..3 {
                    boxes[f as usize][0][c] = boxes[f as usize][0][c].min(p[c]);
                    boxes[f as usize][1][c] = boxes[f as usize][1][c].max(p[c]);
                }
            }
        }
        let size = boxes.iter().fold(0.0f64, |m, b| m.max(norm(sub(b[1], b[0]))));
        let slack = part.tolerances.iter().map(|t| t.sagitta + 1e-5 * size).collect();
        let by_corners = part
            .triangles
            .iter()
            .zip(&part.face_of)
            .map(|(t, &f)| {
                (corner_key(t.map(|p| [p.x as f32, p.y as f32, p.z as f32])), f as usize)
            })
            .collect();
        CurvedTruth { faces: part.faces.clone(), boxes, slack, by_corners }
    }

    /// The face `p` lies on (within its slack and its triangles' box), nearest first.
    pub fn face_at(&self, p: P) -> Option<usize> {
        let mut best: Option<(usize, f64)> = None;
        for (k, f) in self.faces.iter().enumerate() {
            let s = self.slack[k];
            let b = &self.boxes[k];
            if (0..3).any(|c| p[c] < b[0][c] - s || p[c] > b[1][c] + s) {
                continue;
            }
            let d = f.distance(&v(p));
            if d <= s && best.is_none_or(|(_, e)| d < e) {
                best = Some((k, d));
            }
        }
        best.map(|(k, _)| k)
    }

    /// The face whose surface passes nearest `p` (a point near the part).
    pub fn nearest_face(&self, p: P) -> Option<usize> {
        (0..self.faces.len())
            .map(|k| (k, self.faces[k].distance(&v(p))))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _)| k)
    }

    /// The true normal of face `k` at (or nearest) `p`.
    pub fn normal(&self, k: usize, p: P) -> P {
        a(self.faces[k].normal_at(&v(p)))
    }

    /// The grain `w` gives at `p` on face `k`: `w` projected onto the true tangent plane;
    /// `None` within [`NEAR_NORMAL_DEG`] of the normal.
    pub fn grain(&self, k: usize, p: P, w: P) -> Option<P> {
        let n = self.normal(k, p);
        if angle_deg(n, w, true) < NEAR_NORMAL_DEG {
            return None;
        }
        let s = dot(w, n);
        Some(unit([w[0] - n[0] * s, w[1] - n[1] * s, w[2] - n[2] * s]))
    }

    /// The figures of the strokes of `strokes_json` (per face, curved faces only).
    pub fn strokes(&self, strokes_json: &std::path::Path, w: P, out: &mut [FaceFigures]) {
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(strokes_json).unwrap()).unwrap();
        let v3 = |v: &serde_json::Value| [0, 1, 2].map(|k| v[k].as_f64().unwrap());
        for stroke in s["strokes"].as_array().unwrap() {
            for piece in stroke["xyz"].as_array().unwrap() {
                let xyz: Vec<P> = piece.as_array().unwrap().iter().map(v3).collect();
                for seg in xyz.windows(2) {
                    self.stroke_segment(seg[0], seg[1], w, out);
                }
            }
        }
    }

    fn stroke_segment(&self, p: P, q: P, w: P, out: &mut [FaceFigures]) {
        let d = sub(q, p);
        let len = norm(d);
        let m = [0, 1, 2].map(|c| 0.5 * (p[c] + q[c]));
        // A segment belongs to a face when its ends lie on it and its middle lies nearer to it
        // than to any other face: a straight stroke across a plate may end on the rim of the
        // fillet beyond it (its middle within the fillet's sagitta, but on the plate).
        let (Some(k), Some(l)) = (self.face_at(p), self.face_at(q)) else { return };
        if k != l || self.nearest_face(m) != Some(k) || self.faces[k].is_planar() || len == 0.0 {
            return;
        }
        let f = &mut out[k];
        for x in [p, q] {
            f.stroke_off = f.stroke_off.max(self.faces[k].distance(&v(x)));
        }
        match self.grain(k, m, w) {
            None => f.stroke_skipped += len,
            Some(g) => {
                f.stroke_len += len;
                if angle_deg(d, g, true) < 1.0 {
                    f.stroke_ok += len;
                } else if std::env::var("CURVED_DEBUG").is_ok_and(|v| v == k.to_string()) {
                    eprintln!(
                        "  face {k}: segment {p:.3?} → {q:.3?} ({len:.3}) off {:.2}°",
                        angle_deg(d, g, true)
                    );
                }
            }
        }
    }

    /// The figures of a glb (per face, curved faces only): its corner normals, and the grain
    /// a viewer shows over the face's area — at the centroids of each triangle's 6 × 6
    /// subdivision ([`GlbView::fragment`]), against the grain at the fragment's point.
    pub fn glb(&self, glb: &std::path::Path, w: P, out: &mut [FaceFigures]) {
        let g = GlbView::read(glb);
        let d = |x: [f32; 3]| x.map(f64::from);
        const N: usize = 6;
        let mut samples = Vec::new();
        for i in 0..N {
            for j in 0..N - i {
                let b = |di: f64, dj: f64| {
                    let (x, y) = ((i as f64 + di) / N as f64, (j as f64 + dj) / N as f64);
                    [1.0 - x - y, x, y]
                };
                samples.push(b(1.0 / 3.0, 1.0 / 3.0));
                if i + j + 1 < N {
                    samples.push(b(2.0 / 3.0, 2.0 / 3.0));
                }
            }
        }
        for tri in g.idx.chunks(3) {
            let tri = [tri[0], tri[1], tri[2]];
            let q: Vec<P> = tri.iter().map(|&i| d(g.p[i as usize])).collect();
            let c = [0, 1, 2].map(|k| (q[0][k] + q[1][k] + q[2][k]) / 3.0);
            // The part's own triangle when the glb kept it; else the face nearest its centroid.
            let own = self.by_corners.get(&corner_key(tri.map(|i| g.p[i as usize]))).copied();
            let Some(k) = own.or_else(|| self.face_at(c)) else { continue };
            if self.faces[k].is_planar() {
                continue;
            }
            let f = &mut out[k];
            for &i in &tri {
                let (p, nv) = (d(g.p[i as usize]), d(g.n[i as usize]));
                f.corners += 1;
                if angle_deg(nv, self.normal(k, p), true) < 1.0 {
                    f.corners_ok += 1;
                } else if std::env::var("CURVED_DEBUG").is_ok_and(|v| v == k.to_string()) {
                    let off = angle_deg(nv, self.normal(k, p), true);
                    eprintln!("  face {k}: glb corner {p:.3?} normal off {off:.2}°");
                }
            }
            let area = 0.5 * norm(cross(sub(q[1], q[0]), sub(q[2], q[0]))) / samples.len() as f64;
            for &b in &samples {
                let (p, n, u) = g.fragment(tri, b);
                if angle_deg(n, w, true) < NEAR_NORMAL_DEG {
                    continue;
                }
                // The grain in the tangent plane the viewer shades with (its interpolated
                // normal; how far that is from the true one is `area_normal_ok`).
                let s = dot(w, n);
                let t = unit([w[0] - n[0] * s, w[1] - n[1] * s, w[2] - n[2] * s]);
                f.area += area;
                if angle_deg(n, self.normal(k, p), true) < 1.0 {
                    f.area_normal_ok += area;
                }
                let off = angle_deg(u, t, true);
                if off < 1.0 {
                    f.area_ok += area;
                } else if std::env::var("CURVED_DEBUG").is_ok_and(|v| v == k.to_string()) {
                    eprintln!("  face {k}: glb fragment {p:.3?} grain off {off:.2}°");
                }
            }
        }
    }
}

/// Whether face `k` of `part` exported at `step` degrees may be left unrecognized: no face
/// of the generated corpus may, at any step measured.
pub fn may_be_unread(_part: &CadPart, _step: f64, _k: usize) -> bool {
    false
}

/// Runs `part` (written to `stl` already) with a world grain `w`, no edit, strokes of a brush of
/// a fiftieth of its diagonal and a glb into `dir`, and measures them on its curved faces.
pub fn run_and_measure(
    part: &CadPart,
    stl: &std::path::Path,
    dir: &std::path::Path,
    w: P,
) -> Vec<FaceFigures> {
    let tris: Vec<[P; 3]> = part.triangles.iter().map(|t| t.map(|p| [p.x, p.y, p.z])).collect();
    let scene = serde_json::json!({
        "mesh": {"path": stl},
        "units": part.units.as_str(),
        "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
        "view": {"eye": [1, -2, 1.5], "target": [0, 0, 0]},
        "field": {"init": "world", "world": w},
        "toolpaths": {"strokes_json": "strokes.json",
                      "placement": {"width": super::cad_truth::diagonal(&tris) / 50.0}},
        "export": {"glb": "part.glb"}
    });
    std::fs::write(dir.join("scene.json"), scene.to_string()).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(dir.join("scene.json"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}: {}", stl.display(), String::from_utf8_lossy(&out.stderr));
    let truth = CurvedTruth::new(part);
    let mut figures = vec![FaceFigures::default(); part.faces.len()];
    truth.strokes(&dir.join("strokes.json"), w, &mut figures);
    truth.glb(&dir.join("part.glb"), w, &mut figures);
    figures
}

/// `ok / all`, 1 when there is nothing.
pub fn share(ok: f64, all: f64) -> f64 {
    if all > 0.0 {
        ok / all
    } else {
        1.0
    }
}

/// Luminance after a 1/2.2 gamma.
pub fn lum(c: &[f32; 3]) -> f64 {
    let v = 0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2]);
    v.clamp(0.0, 1.0).powf(1.0 / 2.2)
}

/// grainline's PFM ("PF\nW H\n-1.0\n", f32 LE RGB): the pixels.
pub fn read_pfm(path: &std::path::Path) -> Vec<[f32; 3]> {
    let b = std::fs::read(path).unwrap();
    let start = b.iter().enumerate().filter(|(_, &c)| c == b'\n').nth(2).unwrap().0 + 1;
    b[start..]
        .chunks_exact(12)
        .map(|c| [0, 1, 2].map(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap())))
        .collect()
}

/// The share of the part's pixels (not the background, the first pixel's colour, in both
/// images) whose luminances ([`lum`]) are within 0.04, and how many pixels the part covers.
pub fn preview_agreement(a: &[[f32; 3]], b: &[[f32; 3]]) -> (f64, usize) {
    let (mut part, mut ok) = (0usize, 0usize);
    for (x, y) in a.iter().zip(b) {
        if x == &a[0] && y == &b[0] {
            continue;
        }
        part += 1;
        ok += usize::from((lum(x) - lum(y)).abs() <= 0.04);
    }
    (ok as f64 / part.max(1) as f64, part)
}

/// The linear preview (`render.linear`) of `mesh` (a file in `dir`) in the scene the
/// coarse-against-fine tests share: an anisotropic metal, a key light, a world grain, seen
/// from `eye` towards `target` at `px` × `px`.
pub fn render_preview(
    dir: &std::path::Path,
    (mesh, units): (&str, &str),
    (eye, target): ([f64; 3], [f64; 3]),
    px: usize,
) -> Vec<[f32; 3]> {
    let scene = serde_json::json!({
        "mesh": mesh, "units": units,
        "material": {"brdf": {"kind": "ashikhmin_shirley", "nu": 400, "nv": 10,
                              "rs": [0.9, 0.9, 0.92]}},
        "lights": [{"type": "directional", "key": true, "direction": [0.3, -0.5, 1],
                    "irradiance": 2.5}],
        "view": {"eye": eye, "target": target, "up": [0, 0, 1], "fov_deg": 40},
        "field": {"init": "world", "world": [0.6, 0.3, 0.74]},
        "render": {"width": px, "height": px, "output": "p.png", "linear": "p.pfm"}
    });
    std::fs::write(dir.join("scene.json"), scene.to_string()).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "render"])
        .arg(dir.join("scene.json"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    read_pfm(&dir.join("p.pfm"))
}
