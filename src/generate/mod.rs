//! Meshes generated in code: analytic surfaces for tests, examples and benchmarks.
//!
//! Every surface is a parametric grid whose (s, t) ∈ [0, 1]² parameters are its UVs, so each
//! generated mesh is also a UV-mapped part. Closed directions (a cylinder's circumference, a
//! torus) share vertices across the wrap and carry a UV seam there. [`cad`] makes closed
//! CAD-like parts instead: no UVs, tessellated as CAD exports STL, with their analytic faces.
//! [`scan`] makes scanned and sculpted parts: marching tetrahedra over implicit surfaces, with a
//! scan's noise or a sculpt's fine detail.

pub mod cad;
pub mod scan;

use nalgebra::{Vector2, Vector3};

use crate::mesh::{CornerAttribute, Mesh};

/// How each grid quad is split into triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridPattern {
    /// Every quad split along the same diagonal (valence 6 inside).
    Regular,
    /// Diagonals alternating like a chequerboard (valences 4 and 8).
    CrissCross,
    /// Regular, with interior parameters moved by up to `amount` of a cell (deterministic).
    Jittered {
        /// Fraction of a cell (0 ≤ amount < 0.5).
        amount: f64,
        /// Seed of the deterministic generator.
        seed: u64,
    },
}

/// A parametric surface grid of `ns × nt` cells.
#[derive(Clone, Copy, Debug)]
pub struct Grid {
    /// Cells along s.
    pub ns: usize,
    /// Cells along t.
    pub nt: usize,
    /// s wraps around (the last column is the first).
    pub closed_s: bool,
    /// t wraps around.
    pub closed_t: bool,
    /// Triangulation pattern.
    pub pattern: GridPattern,
}

impl Grid {
    /// An open `ns × nt` grid with the regular pattern.
    pub fn new(ns: usize, nt: usize) -> Self {
        Grid { ns, nt, closed_s: false, closed_t: false, pattern: GridPattern::Regular }
    }

    /// Builds the mesh of `surface(s, t)` over this grid, with (s, t) as UVs.
    pub fn build(&self, surface: impl Fn(f64, f64) -> Vector3<f64>) -> Mesh {
        let (ns, nt) = (self.ns.max(1), self.nt.max(1));
        let cols = if self.closed_s { ns } else { ns + 1 };
        let rows = if self.closed_t { nt } else { nt + 1 };
        let mut rng = SplitMix(match self.pattern {
            GridPattern::Jittered { seed, .. } => seed,
            _ => 0,
        });
        let mut params = Vec::with_capacity(cols * rows);
        for j in 0..rows {
            for i in 0..cols {
                let (mut s, mut t) = (i as f64 / ns as f64, j as f64 / nt as f64);
                if let GridPattern::Jittered { amount, .. } = self.pattern {
                    let inner_s = self.closed_s || (i > 0 && i < ns);
                    let inner_t = self.closed_t || (j > 0 && j < nt);
                    if inner_s {
                        s += amount * (2.0 * rng.next() - 1.0) / ns as f64;
                    }
                    if inner_t {
                        t += amount * (2.0 * rng.next() - 1.0) / nt as f64;
                    }
                }
                params.push(Vector2::new(s, t));
            }
        }
        let positions = params.iter().map(|p| surface(p.x, p.y)).collect();
        // UV values: one per grid node including the wrap copies, so seams are real seams.
        let uv_cols = ns + 1;
        let mut uv_values = Vec::with_capacity((ns + 1) * (nt + 1));
        for j in 0..=nt {
            for i in 0..=ns {
                let wrap_i = if self.closed_s && i == ns { 0 } else { i };
                let wrap_j = if self.closed_t && j == nt { 0 } else { j };
                let mut p = params[wrap_j.min(rows - 1) * cols + wrap_i.min(cols - 1)];
                if self.closed_s && i == ns {
                    p.x += 1.0;
                }
                if self.closed_t && j == nt {
                    p.y += 1.0;
                }
                uv_values.push(p);
            }
        }
        let vid = |i: usize, j: usize| ((j % rows) * cols + (i % cols)) as u32;
        let uid = |i: usize, j: usize| (j * uv_cols + i) as u32;
        let mut faces = Vec::with_capacity(2 * ns * nt);
        let mut corners = Vec::with_capacity(2 * ns * nt);
        for j in 0..nt {
            for i in 0..ns {
                let flip = matches!(self.pattern, GridPattern::CrissCross) && (i + j) % 2 == 1;
                let quad = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
                let tris: [[usize; 3]; 2] =
                    if flip { [[0, 1, 3], [1, 2, 3]] } else { [[0, 1, 2], [0, 2, 3]] };
                for tri in tris {
                    faces.push(tri.map(|k| vid(quad[k].0, quad[k].1)));
                    corners.push(tri.map(|k| uid(quad[k].0, quad[k].1)));
                }
            }
        }
        let mut mesh = Mesh::from_triangles(positions, faces);
        mesh.uv = Some(CornerAttribute { values: uv_values, corners });
        mesh
    }
}

/// A square patch of the quadric `z = (c20 x² + 2 c11 xy + c02 y²)/2` over [−half, half]².
pub fn quadric_patch(c: [f64; 3], half: f64, grid: Grid) -> Mesh {
    grid.build(|s, t| {
        let (x, y) = ((2.0 * s - 1.0) * half, (2.0 * t - 1.0) * half);
        Vector3::new(x, y, 0.5 * (c[0] * x * x + 2.0 * c[1] * x * y + c[2] * y * y))
    })
}

/// A flat square [−half, half]² in the z = 0 plane.
pub fn plane(half: f64, grid: Grid) -> Mesh {
    quadric_patch([0.0; 3], half, grid)
}

/// An open cylinder of radius `r` and height `h` around the z axis (outward normals).
pub fn cylinder(r: f64, h: f64, n_around: usize, n_along: usize) -> Mesh {
    let grid = Grid { closed_s: true, ..Grid::new(n_around, n_along) };
    grid.build(|s, t| {
        let a = std::f64::consts::TAU * s;
        Vector3::new(r * a.cos(), r * a.sin(), h * (t - 0.5))
    })
}

/// A torus with major radius `big_r` and minor radius `r` (outward normals).
pub fn torus(big_r: f64, r: f64, n_major: usize, n_minor: usize) -> Mesh {
    let grid = Grid { closed_s: true, closed_t: true, ..Grid::new(n_major, n_minor) };
    grid.build(|s, t| {
        let (a, b) = (std::f64::consts::TAU * s, std::f64::consts::TAU * t);
        let rho = big_r + r * b.cos();
        Vector3::new(rho * a.cos(), rho * a.sin(), r * b.sin())
    })
}

/// Analytic principal curvatures of [`torus`] at a point: (k1, k2) with outward normals.
pub fn torus_curvatures(big_r: f64, r: f64, p: &Vector3<f64>) -> (f64, f64) {
    let rho = p.x.hypot(p.y);
    let cos_b = ((rho - big_r) / r).clamp(-1.0, 1.0);
    let k_minor = 1.0 / r;
    let k_major = cos_b / (big_r + r * cos_b);
    (k_minor.max(k_major), k_minor.min(k_major))
}

/// A sphere of radius `r` from a subdivided icosahedron (no UVs; valences 5 and 6).
pub fn icosphere(r: f64, subdivisions: u32) -> Mesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pos: Vec<Vector3<f64>> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vector3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::BTreeMap::new();
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<Vector3<f64>>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push(((pos[a as usize] + pos[b as usize]) * 0.5).normalize());
                (pos.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let (ab, bc, ca) =
                (midpoint(a, b, &mut pos), midpoint(b, c, &mut pos), midpoint(c, a, &mut pos));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    Mesh::from_triangles(pos.into_iter().map(|p| p * r).collect(), faces)
}

/// A body of revolution: the profile `(radius(t), z(t))`, t ∈ [0, 1], turned about the z axis.
/// UVs are (angle / 2π, t). Normals point away from the axis when z increases with t.
pub fn revolve(profile: impl Fn(f64) -> (f64, f64), n_around: usize, n_profile: usize) -> Mesh {
    let grid = Grid { closed_s: true, ..Grid::new(n_around, n_profile) };
    grid.build(|s, t| {
        let a = std::f64::consts::TAU * s;
        let (r, z) = profile(t);
        Vector3::new(r * a.cos(), r * a.sin(), z)
    })
}

/// A ripple of the acceptance corpus (issue 13): `amplitude · sin(2π·x / wavelength)` along the
/// surface normal, x the coordinate the ripple runs across (millimetres on the corpus parts).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ripple {
    /// Amplitude, scene units (the corpus uses 0.15 mm).
    pub amplitude: f64,
    /// Wavelength, scene units (the corpus uses 8 mm).
    pub wavelength: f64,
}

impl Ripple {
    /// The corpus ripple: 0.15 mm amplitude, 8 mm wavelength.
    pub const CORPUS: Ripple = Ripple { amplitude: 0.15, wavelength: 8.0 };

    /// The offset at coordinate `x`.
    pub fn offset(&self, x: f64) -> f64 {
        self.amplitude * (std::f64::consts::TAU * x / self.wavelength).sin()
    }
}

/// A kettle-like body of revolution about the z axis, in millimetres: 180 mm tall, open at the
/// bottom (radius 50 mm) and at the neck (radius 47 mm), widest (about 68 mm) a little below
/// mid-height: r(z) = 38 + 40·sin(π·(0.1 + 0.75·s))·(1 − 0.5·s), s = z/180, smooth with
/// |∂r/∂z| < 0.6 everywhere. UVs are (angle / 2π, t) as in [`revolve`]; normals point outwards.
/// With `ripple`, the radius gains `ripple.offset(z)` (rings around the body).
pub fn kettle_body(n_around: usize, n_profile: usize, ripple: Option<Ripple>) -> Mesh {
    let height = 180.0;
    revolve(
        |t| {
            let z = height * t;
            let r = 38.0 + 40.0 * (std::f64::consts::PI * (0.1 + 0.75 * t)).sin() * (1.0 - 0.5 * t);
            (r + ripple.map_or(0.0, |w| w.offset(z)), z)
        },
        n_around,
        n_profile,
    )
}

/// A gently doubly curved panel `z = (x²/rx + y²/ry)/2` over the rectangle
/// [−width/2, width/2] × [−depth/2, depth/2] (scene units; normals +z at the centre), on an
/// `nx × ny`-cell grid whose (s, t) parameters are the UVs. With `ripple`, z gains
/// `ripple.offset(x)` (ridges along y). rx = ry = ∞ (`f64::INFINITY`) is a flat sheet.
pub fn curved_panel(
    width: f64,
    depth: f64,
    rx: f64,
    ry: f64,
    nx: usize,
    ny: usize,
    ripple: Option<Ripple>,
) -> Mesh {
    Grid::new(nx, ny).build(|s, t| {
        let (x, y) = ((s - 0.5) * width, (t - 0.5) * depth);
        let curved = 0.5 * (x * x / rx + y * y / ry);
        Vector3::new(x, y, curved + ripple.map_or(0.0, |w| w.offset(x)))
    })
}

/// SplitMix64: a tiny deterministic generator for jitter (not for anything cryptographic).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}
