//! CAD-like test parts with their analytic truth: closed solids tessellated the way CAD
//! systems export STL, each triangle tagged with the exact surface it lies on.
//!
//! A CAD exporter adds no vertex it does not need. Its meshes have no UVs and:
//!
//! * **planar faces** triangulated from their outline only (ear clipping, holes bridged to the
//!   outer loop as earcut does; see `earcut.rs`), so they are fans of long slivers from rim to
//!   rim and every vertex of a flat face sits on one of its edges;
//! * **curved faces** (fillets, bends, hole walls, chamfers) as strips of quads, two triangles
//!   each, one chord per chordal step (default 12°, `step_deg`) and no subdivision along the
//!   rulings;
//! * **shared rims**: neighbouring faces use the same vertices bit for bit, so welding exact
//!   positions closes the part (no crack, no T-junction).
//!
//! The parts (each from an options struct with real-world defaults):
//!
//! | part | units | faces |
//! |---|---|---|
//! | [`housing`] | mm | a 120 × 80 × 40 block: four filleted vertical edges (R 8, tangent to the walls), a 90 × 50 × 10 pocket with filleted corners (R 6) and a flat floor, two round holes through the floor |
//! | [`plate`] | in | an 8 × 12 × 0.5 in plate (203.2 × 304.8 × 12.7 mm) with five round through-holes |
//! | [`bracket`] | mm | a 2 mm sheet bent at 90° (inner radius 3) into 40 × 60 and 30 × 60 flanges, a hole in one, a slot in the other |
//! | [`turned`] | mm | a shaft about z: Ø40 collar, shoulder, fillet (torus), Ø24 shank, 45° chamfer, flat ends |
//!
//! The truth comes with each part: its faces as [`AnalyticFace`]s with their exact areas, the
//! enclosed volume, and per face the [`FaceTolerance`] the chords allow. The tessellation
//! differs from the truth only by its chords: a planar face bounded by arcs loses (or, for a
//! hole, gains) the circular segments between chord and arc, `r²(α − sin α)/2` each; a curved
//! face stands at most its sagitta `ρ (1 − cos(δ/2))` off its surface between vertices; the
//! volume differs by at most Σ sagitta × area over the curved faces. Every vertex lies exactly
//! (to rounding) on the surfaces of all faces around it.

mod bracket;
mod build;
mod earcut;
mod knob;
mod prismatic;
mod turned;

pub use bracket::{bracket, BracketOptions};
pub use knob::{knob, KnobOptions};
pub use prismatic::{housing, plate, HousingOptions, PlateOptions};
pub use turned::{turned, TurnedOptions};

use std::collections::HashMap;

use nalgebra::Vector3;

use crate::mesh::{Mesh, Units};

/// The analytic surface a face of a [`CadPart`] lies on, with the face's exact area (of the
/// bounded face, not of the whole surface). Directions are unit vectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnalyticFace {
    /// The plane `(p − point) · normal = 0`; `normal` points out of the material.
    Plane {
        /// Outward unit normal.
        normal: Vector3<f64>,
        /// A point of the plane.
        point: Vector3<f64>,
        /// Area of the face.
        area: f64,
    },
    /// The cylinder `|(p − axis_point) × axis_dir| = radius`: fillets, bends, hole walls.
    Cylinder {
        /// A point on the axis.
        axis_point: Vector3<f64>,
        /// Unit direction of the axis.
        axis_dir: Vector3<f64>,
        /// Radius.
        radius: f64,
        /// Area of the face.
        area: f64,
    },
    /// The cone of half-angle `half_angle` with its apex at `apex` opening along `axis_dir`:
    /// `ρ = h tan(half_angle)` with `h = (p − apex) · axis_dir ≥ 0` and ρ the distance from
    /// the axis (a chamfer).
    Cone {
        /// The apex.
        apex: Vector3<f64>,
        /// Unit direction the cone opens along.
        axis_dir: Vector3<f64>,
        /// Angle between the axis and the surface's rulings, radians.
        half_angle: f64,
        /// Area of the face.
        area: f64,
    },
    /// The torus `(ρ − major_radius)² + h² = minor_radius²`, with `h = (p − center) · axis_dir`
    /// and ρ the distance from the axis through `center` (a fillet turned about an axis).
    Torus {
        /// Centre of the torus, on its axis.
        center: Vector3<f64>,
        /// Unit direction of the axis.
        axis_dir: Vector3<f64>,
        /// Radius of the circle of tube centres.
        major_radius: f64,
        /// Radius of the tube.
        minor_radius: f64,
        /// Area of the face.
        area: f64,
    },
    /// The sphere `|p − center| = radius` (a knob's crown).
    Sphere {
        /// Centre.
        center: Vector3<f64>,
        /// Radius.
        radius: f64,
        /// Area of the face.
        area: f64,
    },
}

impl AnalyticFace {
    /// The exact area of the face.
    pub fn area(&self) -> f64 {
        match *self {
            AnalyticFace::Plane { area, .. }
            | AnalyticFace::Cylinder { area, .. }
            | AnalyticFace::Cone { area, .. }
            | AnalyticFace::Torus { area, .. }
            | AnalyticFace::Sphere { area, .. } => area,
        }
    }

    /// Whether the face is a plane.
    pub fn is_planar(&self) -> bool {
        matches!(self, AnalyticFace::Plane { .. })
    }

    /// Distance of `p` from the (unbounded) surface: `|(p − point)·n|` for a plane,
    /// `|ρ − radius|` for a cylinder, `|ρ cos α − h sin α|` for a cone (distance to the
    /// ruling's line in the (ρ, h) half-plane), `|√((ρ − R)² + h²) − r|` for a torus.
    pub fn distance(&self, p: &Vector3<f64>) -> f64 {
        match *self {
            AnalyticFace::Plane { normal, point, .. } => (p - point).dot(&normal).abs(),
            AnalyticFace::Cylinder { radius, .. } => (self.axis_distance(p) - radius).abs(),
            AnalyticFace::Cone { apex, axis_dir, half_angle, .. } => {
                let h = (p - apex).dot(&axis_dir);
                let rho = self.axis_distance(p);
                (rho * half_angle.cos() - h * half_angle.sin()).abs()
            }
            AnalyticFace::Torus { center, axis_dir, major_radius, minor_radius, .. } => {
                let h = (p - center).dot(&axis_dir);
                let rho = self.axis_distance(p);
                ((rho - major_radius).hypot(h) - minor_radius).abs()
            }
            AnalyticFace::Sphere { center, radius, .. } => ((p - center).norm() - radius).abs(),
        }
    }

    /// The surface's unit normal at (or nearest to) `p`, up to sign: for the curved faces, the
    /// direction from the nearest point of the axis (cylinder), of the tube's core circle
    /// (torus) or of the apex's ruling frame (cone) towards `p`.
    pub fn normal_at(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let radial = |o: Vector3<f64>, d: Vector3<f64>| {
            let v = p - o;
            (v - d * v.dot(&d)).normalize()
        };
        match *self {
            AnalyticFace::Plane { normal, .. } => normal,
            AnalyticFace::Cylinder { axis_point, axis_dir, .. } => radial(axis_point, axis_dir),
            AnalyticFace::Cone { apex, axis_dir, half_angle, .. } => {
                // Outward from the axis and tilted back along it by the half-angle.
                radial(apex, axis_dir) * half_angle.cos() - axis_dir * half_angle.sin()
            }
            AnalyticFace::Torus { center, axis_dir, major_radius, .. } => {
                let core = center + radial(center, axis_dir) * major_radius;
                (p - core).normalize()
            }
            AnalyticFace::Sphere { center, .. } => (p - center).normalize(),
        }
    }

    /// Distance of `p` from the surface's axis (0 for a plane).
    pub fn axis_distance(&self, p: &Vector3<f64>) -> f64 {
        let (o, d) = match *self {
            AnalyticFace::Plane { .. } | AnalyticFace::Sphere { .. } => return 0.0,
            AnalyticFace::Cylinder { axis_point, axis_dir, .. } => (axis_point, axis_dir),
            AnalyticFace::Cone { apex, axis_dir, .. } => (apex, axis_dir),
            AnalyticFace::Torus { center, axis_dir, .. } => (center, axis_dir),
        };
        (p - o).cross(&d).norm()
    }
}

/// How far a face's tessellation may stand off its analytic truth.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FaceTolerance {
    /// Largest distance between a triangle and the surface (0 for planes): the sagitta
    /// `ρ (1 − cos(δ/2))` of a chord of angle δ on a circle of radius ρ.
    pub sagitta: f64,
    /// Largest `|Σ triangle areas − area|`: for a plane, the circular segments between its arc
    /// edges and their chords (0 for a face bounded by straight edges only, whose triangles
    /// cover it exactly); for a curved face, `area · δ²/12` (cylinders) or `area · δ²/4`
    /// (cones and tori, turned), δ the chordal step.
    pub area: f64,
}

/// A generated CAD part: triangles as an STL stores them (three vertices each, outward and
/// counter-clockwise), each on one analytic face.
#[derive(Clone, Debug)]
pub struct CadPart {
    /// Short name (`housing`, `plate`, …).
    pub name: String,
    /// Unit of the coordinates.
    pub units: Units,
    /// Triangles, counter-clockwise around their outward normal.
    pub triangles: Vec<[Vector3<f64>; 3]>,
    /// For each triangle, the index in `faces` of the face it lies on.
    pub face_of: Vec<u32>,
    /// The analytic faces.
    pub faces: Vec<AnalyticFace>,
    /// For each face, how far its tessellation may differ from it.
    pub tolerances: Vec<FaceTolerance>,
    /// The exact enclosed volume of the analytic solid.
    pub volume: f64,
}

impl CadPart {
    /// The part as an indexed mesh, welded exactly (bit-identical positions, −0 = +0), with
    /// the triangles in order.
    pub fn mesh(&self) -> Mesh {
        let mut index: HashMap<[u64; 3], u32> = HashMap::new();
        let mut positions = Vec::new();
        let mut faces = Vec::with_capacity(self.triangles.len());
        for t in &self.triangles {
            faces.push(t.map(|p| {
                let key = [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits());
                *index.entry(key).or_insert_with(|| {
                    positions.push(p);
                    (positions.len() - 1) as u32
                })
            }));
        }
        let mut mesh = Mesh::from_triangles(positions, faces);
        mesh.units = self.units;
        mesh
    }

    /// The part as a binary STL, the way CAD writes it: an 80-byte header naming the part and
    /// its unit, the triangle count, then per triangle its unit normal and three vertices as
    /// little-endian float32 and a zero attribute word.
    pub fn stl_binary(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(84 + 50 * self.triangles.len());
        let header = format!("grainline generate::cad {} ({})", self.name, self.units.as_str());
        let mut h = header.into_bytes();
        h.resize(80, b' ');
        out.extend_from_slice(&h);
        out.extend_from_slice(&(self.triangles.len() as u32).to_le_bytes());
        for [a, b, c] in &self.triangles {
            let n = (b - a).cross(&(c - a)).normalize();
            for v in [n, *a, *b, *c] {
                for k in 0..3 {
                    out.extend_from_slice(&(v[k] as f32).to_le_bytes());
                }
            }
            out.extend_from_slice(&[0, 0]);
        }
        out
    }

    /// The volume the triangles enclose, by the divergence theorem: `Σ a · (b × c) / 6`.
    pub fn enclosed_volume(&self) -> f64 {
        self.triangles.iter().map(|[a, b, c]| a.dot(&b.cross(c)) / 6.0).sum()
    }

    /// How far the enclosed volume may differ from [`volume`](Self::volume): Σ sagitta × area
    /// over the faces.
    pub fn volume_tolerance(&self) -> f64 {
        self.faces.iter().zip(&self.tolerances).map(|(f, t)| t.sagitta * f.area()).sum()
    }

    /// Σ of the areas of each face's triangles.
    pub fn face_areas(&self) -> Vec<f64> {
        let mut areas = vec![0.0; self.faces.len()];
        for (t, &f) in self.triangles.iter().zip(&self.face_of) {
            areas[f as usize] += triangle_area(t);
        }
        areas
    }

    /// The smallest interior angle of triangle `t`, degrees.
    pub fn smallest_angle_deg(&self, t: usize) -> f64 {
        let p = &self.triangles[t];
        (0..3)
            .map(|k| {
                let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
                (b - a).angle(&(c - a)).to_degrees()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Triangles on planar faces whose smallest angle is below `degrees`.
    pub fn planar_slivers(&self, degrees: f64) -> usize {
        (0..self.triangles.len())
            .filter(|&t| self.faces[self.face_of[t] as usize].is_planar())
            .filter(|&t| self.smallest_angle_deg(t) < degrees)
            .count()
    }
}

fn triangle_area([a, b, c]: &[Vector3<f64>; 3]) -> f64 {
    0.5 * (b - a).cross(&(c - a)).norm()
}
