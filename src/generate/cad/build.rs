//! Building a [`CadPart`] face by face: rims (closed loops of rim vertices shared by the faces
//! on either side), planar faces ear-clipped from their rims, walls swept between two rims and
//! strips between two rings, each triangle tagged with its analytic face.

use nalgebra::{Vector2, Vector3};

use super::{earcut, AnalyticFace, CadPart, FaceTolerance};
use crate::mesh::Units;

type V3 = Vector3<f64>;

/// `(cos a, sin a)`, exact at multiples of 90° so that tangent points land exactly on the
/// planes the arcs meet.
pub(super) fn unit(a: f64) -> (f64, f64) {
    let q = a / std::f64::consts::FRAC_PI_2;
    let k = q.round();
    if (q - k).abs() < 1e-12 {
        match (k as i64).rem_euclid(4) {
            0 => (1.0, 0.0),
            1 => (0.0, 1.0),
            2 => (-1.0, 0.0),
            _ => (0.0, -1.0),
        }
    } else {
        (a.cos(), a.sin())
    }
}

/// Chords needed for an arc of `sweep` radians at a chordal step of at most `step`.
pub(super) fn segments(sweep: f64, step: f64) -> usize {
    ((sweep.abs() / step) - 1e-9).ceil().max(1.0) as usize
}

/// A closed loop of rim vertices; edge `i` runs from `pts[i]` to `pts[i + 1]` (cyclically).
#[derive(Clone, Debug, Default)]
pub(super) struct Rim {
    /// The vertices, in order.
    pub pts: Vec<V3>,
    /// The face a wall swept from edge `i` lies on.
    pub face: Vec<u32>,
    /// Radius of the arc edge `i` is a chord of (0 for a straight edge).
    pub radius: Vec<f64>,
}

impl Rim {
    /// Appends vertex `p`; the edge from it to the next vertex lies on `face` and is a chord of
    /// an arc of radius `radius` (0: straight).
    pub fn push(&mut self, p: V3, face: u32, radius: f64) {
        self.pts.push(p);
        self.face.push(face);
        self.radius.push(radius);
    }

    /// The same rim with every vertex moved by `f` (faces and radii kept).
    pub fn mapped(&self, f: impl Fn(V3) -> V3) -> Rim {
        Rim { pts: self.pts.iter().map(|&p| f(p)).collect(), ..self.clone() }
    }

    /// A rim of `n` vertices on the circle of radius `r` about `c` in the plane spanned by the
    /// unit vectors `e1`, `e2`: `c + r (cos θ e1 + sin θ e2)`, θ = 2πj/n, every edge on `face`.
    pub fn circle(c: V3, e1: V3, e2: V3, r: f64, n: usize, face: u32) -> Rim {
        let mut rim = Rim::default();
        for j in 0..n {
            let (cos, sin) = unit(std::f64::consts::TAU * j as f64 / n as f64);
            rim.push(c + (e1 * cos + e2 * sin) * r, face, r);
        }
        rim
    }

    /// Appends the interior vertices of the arc `c + r (cos φ e₀ + sin φ e₁)`, φ from `a[0]` to
    /// `a[1]` in `n` chords (j = 1 … n − 1: the caller pushes the ends, exactly where the
    /// neighbouring faces need them); the edges from them lie on `face`.
    pub fn arc(&mut self, c: V3, e: [V3; 2], r: f64, a: [f64; 2], n: usize, face: u32) {
        for j in 1..n {
            let (cos, sin) = unit(a[0] + (a[1] - a[0]) * j as f64 / n as f64);
            self.push(c + (e[0] * cos + e[1] * sin) * r, face, r);
        }
    }

    /// Twice the vector area of the loop, `Σ pᵢ × pᵢ₊₁`.
    fn vector_area(&self) -> V3 {
        let n = self.pts.len();
        (0..n).map(|i| self.pts[i].cross(&self.pts[(i + 1) % n])).sum()
    }

    /// Σ over arc edges of the circular segment between chord and arc, `r²(α − sin α)/2`
    /// with α = 2 asin(c / 2r): how far a planar face bounded by this rim may differ in area
    /// from its analytic outline.
    fn segment_area(&self) -> f64 {
        let n = self.pts.len();
        (0..n)
            .filter(|&i| self.radius[i] > 0.0)
            .map(|i| {
                let (r, c) = (self.radius[i], (self.pts[(i + 1) % n] - self.pts[i]).norm());
                let a = 2.0 * (0.5 * c / r).min(1.0).asin();
                0.5 * r * r * (a - a.sin())
            })
            .sum()
    }
}

/// A part under construction.
pub(super) struct Builder {
    part: CadPart,
    step: f64,
}

impl Builder {
    /// An empty part whose curved faces are tessellated at a chordal step of at most `step`
    /// radians.
    pub fn new(name: &str, units: Units, step: f64) -> Self {
        let part = CadPart {
            name: name.to_owned(),
            units,
            triangles: Vec::new(),
            face_of: Vec::new(),
            faces: Vec::new(),
            tolerances: Vec::new(),
            volume: 0.0,
        };
        Builder { part, step }
    }

    /// Adds an analytic face. Its area tolerance follows from the chordal step δ ≤ step. A
    /// cylinder's strip of chords is `ρδ − 2ρ sin(δ/2) ≤ ρδ³/24` narrower per chord than the
    /// arc: a relative error of at most δ²/24, allowed as δ²/12. A turned face (cone, torus) is
    /// made of planar trapezoids between rings: δ²/24 around, δ²/24 along a curved profile,
    /// and up to `1 − cos(δ/2) ≤ δ²/8` more because a trapezoid's height is measured between
    /// chords, not arcs; allowed as δ²/4. Its sagitta is set by [`finish`](Self::finish).
    pub fn face(&mut self, face: AnalyticFace) -> u32 {
        let rel = match face {
            AnalyticFace::Plane { .. } => 0.0,
            AnalyticFace::Cylinder { .. } => 1.0 / 12.0,
            AnalyticFace::Cone { .. }
            | AnalyticFace::Torus { .. }
            | AnalyticFace::Sphere { .. } => 0.25,
        };
        let area = face.area() * self.step * self.step * rel;
        self.part.faces.push(face);
        self.part.tolerances.push(FaceTolerance { sagitta: 0.0, area });
        (self.part.faces.len() - 1) as u32
    }

    /// The chordal step, radians.
    pub fn step(&self) -> f64 {
        self.step
    }

    /// Whether `face` is a plane.
    pub fn is_planar(&self, face: u32) -> bool {
        self.part.faces[face as usize].is_planar()
    }

    /// One triangle on `face`, counter-clockwise around the outward normal.
    pub fn tri(&mut self, t: [V3; 3], face: u32) {
        self.part.triangles.push(t);
        self.part.face_of.push(face);
    }

    /// The quad `abcd` (counter-clockwise around the outward normal) as `abc`, `acd`.
    pub fn quad(&mut self, [a, b, c, d]: [V3; 4], face: u32) {
        self.tri([a, b, c], face);
        self.tri([a, c, d], face);
    }

    /// The planar `face` bounded by `rims[0]` with holes `rims[1..]` (any orientation),
    /// ear-clipped with no interior vertex (see [`earcut`]). Its area tolerance becomes the
    /// circular segments of its arc edges.
    pub fn planar(&mut self, face: u32, rims: &[&Rim]) {
        let AnalyticFace::Plane { normal, .. } = self.part.faces[face as usize] else {
            unreachable!("planar() on a curved face");
        };
        let helper = if normal.x.abs() < 0.9 { V3::x() } else { V3::y() };
        let u = normal.cross(&helper).normalize();
        let v = normal.cross(&u);
        let (mut pts3, mut loops) = (Vec::new(), Vec::new());
        for rim in rims {
            loops.push((pts3.len()..pts3.len() + rim.pts.len()).collect::<Vec<_>>());
            pts3.extend_from_slice(&rim.pts);
        }
        let pts2: Vec<Vector2<f64>> =
            pts3.iter().map(|p| Vector2::new(p.dot(&u), p.dot(&v))).collect();
        for [a, b, c] in earcut::triangulate(&pts2, &loops) {
            self.tri([pts3[a], pts3[b], pts3[c]], face);
        }
        self.part.tolerances[face as usize].area +=
            rims.iter().map(|r| r.segment_area()).sum::<f64>();
    }

    /// The walls swept from each edge of `r0` to the same edge of `r1` (the same rim moved),
    /// one quad per edge on the edge's face; edges on a face in `skip` are left out (faces
    /// built by [`planar`](Self::planar)). `hole`: the material lies outside the rim (the walls
    /// face inwards) instead of inside.
    pub fn walls(&mut self, r0: &Rim, r1: &Rim, hole: bool, skip: &[u32]) {
        let n = r0.pts.len();
        // Seen from the side r1 lies on, a counter-clockwise outer rim has its material on the
        // left of each edge and its walls' normals, edge × offset, on the right: outwards.
        let ccw = r0.vector_area().dot(&(r1.pts[0] - r0.pts[0])) > 0.0;
        for i in (0..n).filter(|&i| !skip.contains(&r0.face[i])) {
            let j = (i + 1) % n;
            let q = if ccw != hole {
                [r0.pts[i], r0.pts[j], r1.pts[j], r1.pts[i]]
            } else {
                [r0.pts[j], r0.pts[i], r1.pts[i], r1.pts[j]]
            };
            self.quad(q, r0.face[i]);
        }
    }

    /// The strip of quads `(aⱼ, aⱼ₊₁, bⱼ₊₁, bⱼ)` between two closed rings of equal length.
    pub fn strip(&mut self, a: &Rim, b: &Rim, face: u32) {
        let n = a.pts.len();
        for j in 0..n {
            let k = (j + 1) % n;
            self.quad([a.pts[j], a.pts[k], b.pts[k], b.pts[j]], face);
        }
    }

    /// The finished part with its analytic `volume`. Each curved face's sagitta is the
    /// farthest a chord of angle δ ≤ step stands off its arc, `ρ (1 − cos(δ/2))`, with ρ the
    /// largest distance of the face's vertices from the axis (plus the same for the minor
    /// circle of a torus).
    pub fn finish(mut self, volume: f64) -> CadPart {
        let s = 1.0 - (0.5 * self.step).cos();
        let mut rho = vec![0.0f64; self.part.faces.len()];
        for (t, &f) in self.part.triangles.iter().zip(&self.part.face_of) {
            for p in t {
                rho[f as usize] = rho[f as usize].max(self.part.faces[f as usize].axis_distance(p));
            }
        }
        for (f, face) in self.part.faces.iter().enumerate() {
            let minor = match face {
                AnalyticFace::Torus { minor_radius, .. } => *minor_radius,
                AnalyticFace::Sphere { radius, .. } => *radius,
                _ => 0.0,
            };
            self.part.tolerances[f].sagitta = (rho[f] + minor) * s;
        }
        self.part.volume = volume;
        self.part
    }
}
