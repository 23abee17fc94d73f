//! Recognized surfaces: the planes, cylinders, cones, spheres and tori a CAD export
//! approximates with strips of chords (docs/math.md §3, "Recognized surfaces").
//!
//! A CAD system writes a curved face as strips of planar chords whose corners lie *on* the
//! surface: a fillet as quads between rulings, a turned face as bands of trapezoids between
//! parallels. Averaged facet normals and jet fits read those strips, not the surface: normals
//! lean towards neighbouring faces, a shallow chamfer's edge is smoothed over, and the
//! highlights show the strips. So the part's planar regions ([`crate::mesh::planar`]) are
//! grown into surfaces, each a set of regions whose vertices one primitive passes through
//! within the file's rounding ([`Surfaces::tolerance`]):
//!
//! 1. **Seeds** are regions of at least two faces (a quad, not a scan's lone triangle), the
//!    regular ones first: a strip whose two neighbours, as wide as it, turn by the same angle
//!    (an inner strip of a fillet, a band's trapezoid) before one at a surface's end; a seed
//!    whose growth fails is tried again without the partner it took first ([`SEED_TRIES`]).
//! 2. **Growth** (`grow.rs`) adds neighbouring quads across edges of at most [`MAX_STEP_DEG`],
//!    those as wide as the seed first, then those that continue a run of strips (met at the
//!    angle another neighbour as wide meets the same region) before a lone crossing, the
//!    smoothest first. Until three regions fix a cylinder or
//!    a cone, any primitive through the set is accepted; then a region joins only if its
//!    vertices lie on that surface and the surface's normal at each of them is within
//!    [`MAX_CHORD_DEVIATION_DEG`] of the chord's. A growth is kept as a cylinder (three strips
//!    or more) or a cone band that stands off its own plane by ten tolerances at least.
//!    Regions the model refused are tried again against a fit to the whole set when the queue
//!    runs dry, and neighbouring cylinders or cones that one surface passes through are
//!    joined (`profile::merge_pieces`).
//! 3. **Profiles** (`profile.rs`): coaxial bands in a chain (open, or a closed loop: a full
//!    torus), with a pole's fan as one more profile point, become the sphere (three profile
//!    points or more) or the torus (four or more) that passes through all their rings, or, with
//!    fewer, the one a tangent neighbour fixes (`tangent.rs`: a round of two strips, a crown of
//!    one fan); a surface whose regions all lie on a larger neighbour joins it
//!    (`profile::subsume`).
//! 4. **Free forms**: a band's cone is exact on any turned surface, so coaxial surfaces that
//!    meet at a turn neither tangent nor beyond the export's step are a free profile (a
//!    kettle, a vase: all of a chain of three or more, each single band of a chain of two);
//!    adjacent tangent surfaces of one kind and nearly one size are a free form (a dome's rows
//!    of quads, each a cylinder within the rounding).
//! 5. **Absorption**: regions on no surface (a pole's fan) join a neighbouring surface they
//!    lie on.
//! 6. **Planes** are the remaining planar regions of at least two faces that are
//!    [`crate::mesh::planar::WIDER`] times wider than every unrecognized region they meet
//!    smoothly (a face of the part, not a strip of a curved face the growth could not fix).
//! 7. **Closure**: a small curved surface that unrecognized regions continue smoothly on more
//!    than [`MAX_OPEN_SHARE`] of its rim is a coincidence of a free-form face, and is dropped;
//!    so is any curved surface, or plane of fewer than [`SMALL_SURFACE_REGIONS`] triangles,
//!    whose rim runs for more than [`MAX_OPEN_LENGTH_SHARE`] of its length along unrecognized
//!    faces met smoothly.
//!
//! Two surfaces meet at a **crease** when their normals differ along the edge they share by
//! more than [`G1_TOLERANCE_DEG`] ([`Surfaces::crease_between`]): a chamfer's 26.6° edge is a
//! crease, a fillet meeting a plate tangentially is not, whatever the strips' angles.
//!
//! Limits: a surface meshed with too few strips to over-determine it and no tangent neighbour
//! (a fillet exported at 45° chords, a torus of two strips between creases) is not recognized;
//! a crease inside a chain of three or more single bands of a turned part that turns by less
//! than the export's angular step is read as a free profile's strip edge.

pub mod ambient;
mod fit;
mod grow;
pub mod primitive;
mod profile;
pub mod revolution;
mod tangent;

use nalgebra::{Matrix3, Vector3};

pub use primitive::{Primitive, SurfaceKind};

use crate::mesh::planar::{NO_REGION, WIDER};
use crate::mesh::Mesh;

type V3 = Vector3<f64>;

/// The largest angle between two planar regions that growth crosses, degrees: a CAD export's
/// chordal step is at most 30°; a chamfer strip may meet its neighbour at 45°.
pub const MAX_STEP_DEG: f64 = 46.0;

/// The most a chord's normal may differ from the surface's at its corners, degrees: half an
/// export's coarsest step (30°) along both directions of a turned face's trapezoid, with
/// room. A region whose corners all lie on a surface but far apart on it (a disk whose
/// vertices are all on its rim, against any surface through that rim) is no chord of it.
pub const MAX_CHORD_DEVIATION_DEG: f64 = 25.0;

/// Two surfaces whose normals differ by more than this along a shared edge meet at a crease
/// (degrees). Tangent (G1) junctions agree to the file's rounding.
pub const G1_TOLERANCE_DEG: f64 = 2.0;

/// The distance within which a vertex lies on a surface, as a multiple of the part's largest
/// coordinate: float32 STL rounds to 6·10⁻⁸ of it, six-digit ASCII to 5·10⁻⁷.
pub const RELATIVE_TOLERANCE: f64 = 4e-6;

/// How many times a seed is grown, each time without the first partner a failed growth took.
pub const SEED_TRIES: usize = 4;

/// No surface: a face of an unrecognized region (a free-form face, a scan).
pub const NO_SURFACE: u32 = u32::MAX;

/// One recognized surface.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Surface {
    /// The primitive and its parameters.
    pub primitive: Primitive,
    /// Its faces (triangles).
    pub faces: usize,
    /// Its area (of the triangles).
    pub area: f64,
    /// RMS distance of its vertices from the primitive.
    pub rms_residual: f64,
    /// Largest distance of its vertices from the primitive.
    pub max_residual: f64,
}

/// The surfaces of a part.
#[derive(Clone, Debug, PartialEq)]
pub struct Surfaces {
    /// Per face, its surface, or [`NO_SURFACE`].
    pub face_surface: Vec<u32>,
    /// The surfaces, numbered in the order of their first faces.
    pub surfaces: Vec<Surface>,
    /// The distance within which a vertex counted as on a surface (scene units).
    pub tolerance: f64,
}

/// Recognizes the surfaces of `mesh` (module docs). Linear in the faces for a scan (no region
/// of two faces seeds anything); O(F log F) on a CAD part.
pub fn recognize(mesh: &Mesh) -> Surfaces {
    let nf = mesh.num_faces();
    let tol = tolerance(mesh);
    if nf == 0 || tol.is_nan() || tol <= 0.0 {
        return Surfaces { face_surface: vec![NO_SURFACE; nf], surfaces: vec![], tolerance: tol };
    }
    let (tol, eps) = rounding_tolerance(mesh, tol);
    let g = grow::RegionGraph::new(mesh, eps);
    let nr = g.regions.normal.len();
    let mut seeds: Vec<(bool, u32)> = (0..nr as u32)
        .filter(|&r| g.regions.faces[r as usize] >= 2)
        .map(|r| (!g.is_regular(r), r))
        .collect();
    seeds.sort_unstable();
    let mut taken = vec![false; nr];
    let mut stamp = vec![u32::MAX; mesh.num_vertices()];
    let mut seen = vec![u32::MAX; nr];
    let mut grown: Vec<profile::Grown> = Vec::new();
    let mut attempt = 0u32;
    for (_, seed) in seeds {
        if taken[seed as usize] {
            continue;
        }
        // A seed is tried again without the partner a failed growth took first, up to
        // [`SEED_TRIES`] times (a quad has four neighbours).
        let mut banned: Vec<u32> = Vec::new();
        for _ in 0..SEED_TRIES {
            let id = attempt;
            attempt += 1;
            let found =
                grow::grow(&g, mesh, &taken, (&mut stamp, &mut seen), (seed, id, &banned), tol);
            match found {
                Ok((regions, prim)) => {
                    for &r in &regions {
                        taken[r as usize] = true;
                    }
                    grown.push((prim, regions));
                    break;
                }
                Err(Some(partner)) => banned.push(partner),
                Err(None) => break,
            }
        }
    }
    let grown = profile::merge_pieces(&g, mesh, grown, tol);
    let grown = profile::join_bands(&g, mesh, grown, tol);
    let grown = profile::subsume(&g, mesh, grown, tol);
    let grown = profile::free_profiles(&g, mesh, grown, tol);
    let grown = profile::twins(&g, mesh, grown, tol);
    let mut grown = profile::subsume(&g, mesh, grown, tol);
    let mut region_surface = owners(&grown, nr);
    grow::absorb(&g, mesh, &mut grown, &mut region_surface, tol);
    // Absorbed regions join surfaces they lie on both: a torus's flat top ring (a planar
    // annulus between the outer and the inner half) makes the halves neighbours.
    let mut grown = profile::subsume(&g, mesh, grown, tol);
    let mut region_surface = owners(&grown, nr);
    add_planes(&g, mesh, &mut grown, &mut region_surface);
    close_off(&g, &grown, &mut region_surface);
    close_off_by_length(mesh, &g, &grown, &mut region_surface);
    finish(mesh, &g, grown, &region_surface, tol)
}

/// Per region, the index of the surface that holds it, or [`NO_SURFACE`].
fn owners(grown: &[profile::Grown], regions: usize) -> Vec<u32> {
    let mut region_surface = vec![NO_SURFACE; regions];
    for (k, (_, rs)) in grown.iter().enumerate() {
        for &r in rs {
            region_surface[r as usize] = k as u32;
        }
    }
    region_surface
}

/// The most the tolerance may be, [`RELATIVE_TOLERANCE`] of `mesh`'s largest coordinate.
pub fn tolerance(mesh: &Mesh) -> f64 {
    let m = mesh.positions.iter().map(|p| p.amax()).fold(0.0, f64::max);
    let (lo, hi) = mesh.bounding_box().unwrap_or((V3::zeros(), V3::zeros()));
    let t = RELATIVE_TOLERANCE * m + 1e-9 * (hi - lo).norm();
    if t.is_finite() {
        t
    } else {
        0.0
    }
}

/// How many times the file's rounding a vertex may stand off its surface.
pub const ROUNDING_MARGIN: f64 = 16.0;

/// The relative rounding of `mesh`'s coordinates, read from the numbers themselves: 2⁻²⁴
/// when every coordinate is a float32 (a binary STL), ½·10¹⁻ᵈ when d significant digits
/// write every coordinate (an ASCII STL, an OBJ, a PLY), and `None` when the numbers need
/// all of a double's digits (coordinates computed in double precision, or scaled after
/// loading), whose rounding they do not tell.
pub fn relative_rounding(mesh: &Mesh) -> Option<f64> {
    let step = (mesh.positions.len() / 4096).max(1);
    let sample: Vec<f64> = mesh
        .positions
        .iter()
        .step_by(step)
        .flat_map(|p| [p.x, p.y, p.z])
        .filter(|c| *c != 0.0 && c.is_finite())
        .collect();
    if sample.iter().all(|&c| (c as f32) as f64 == c) {
        return Some(2f64.powi(-24));
    }
    let digits = |c: f64| {
        (1..=17usize)
            .find(|&d| format!("{:.*e}", d - 1, c).parse::<f64>().ok() == Some(c))
            .unwrap_or(17)
    };
    let d = sample.iter().map(|&c| digits(c)).max().unwrap_or(17);
    (d <= 15).then(|| 0.5 * 10f64.powi(1 - d as i32))
}

/// The distance within which a vertex counts as on a surface, and the distance from a plane
/// within which a face lies on it when grouping planar regions.
///
/// In a float32 file (a binary STL) the first is [`ROUNDING_MARGIN`] times its rounding
/// ([`relative_rounding`]) of the largest coordinate, at most `ceiling` ([`tolerance`]); the
/// second is 0 (the rounding tilts no chord's normal by [`crate::mesh::planar::FLAT_COS`]).
/// In a file of decimal digits (an ASCII STL, an OBJ, a PLY) the vertices stand off their
/// surface by up to √3 half units of the last digit written: both are [`DIGIT_MARGIN`] half
/// units of the typical coordinate's last digit (the 95th percentile of their magnitudes:
/// an exact 1 in a file of six digits says nothing), or the float32 rule's if larger. When
/// the rounding is not known, `ceiling` and 0.
fn rounding_tolerance(mesh: &Mesh, ceiling: f64) -> (f64, f64) {
    let m = mesh.positions.iter().map(|p| p.amax()).fold(0.0, f64::max);
    match relative_rounding(mesh) {
        Some(rel) if rel > 2f64.powi(-24) => {
            let unit = rel * 10f64.powf(typical_magnitude(mesh).log10().floor());
            let t = (ROUNDING_MARGIN * rel * m).clamp(1e-3 * ceiling, ceiling);
            let digits = DIGIT_MARGIN * unit;
            (t.max(digits), digits)
        }
        Some(rel) => ((ROUNDING_MARGIN * rel * m).clamp(1e-3 * ceiling, ceiling), 0.0),
        None => (ceiling, 0.0),
    }
}

/// The 95th percentile of the magnitudes of `mesh`'s non-zero coordinates (a sample of
/// them), or 1 when there are none.
fn typical_magnitude(mesh: &Mesh) -> f64 {
    let step = (mesh.positions.len() / 4096).max(1);
    let mut mags: Vec<f64> = mesh
        .positions
        .iter()
        .step_by(step)
        .flat_map(|p| [p.x.abs(), p.y.abs(), p.z.abs()])
        .filter(|c| *c > 0.0 && c.is_finite())
        .collect();
    if mags.is_empty() {
        return 1.0;
    }
    mags.sort_by(f64::total_cmp);
    mags[(mags.len() - 1) * 95 / 100]
}

/// How many times the half unit of the largest coordinate's last written digit a vertex may
/// stand off its surface: rounding each of three coordinates moves a point by up to √3 of it,
/// and a fit through rounded points takes some more.
pub const DIGIT_MARGIN: f64 = 4.0;

/// The share of a small curved surface's neighbouring regions that may continue it
/// smoothly without being recognized.
pub const MAX_OPEN_SHARE: f64 = 0.1;

/// A curved surface of fewer chords than this is small enough to be a coincidence of a
/// free-form face (three quads of a scan fit a cylinder within its rounding); a larger one
/// is not, whatever meets it.
pub const SMALL_SURFACE_REGIONS: usize = 12;

/// Module docs, step 7: a small curved surface (fewer than [`SMALL_SURFACE_REGIONS`]
/// chords) whose neighbours continue it smoothly (across less than [`MAX_STEP_DEG`]) without
/// being recognized, on more than [`MAX_OPEN_SHARE`] of its rim, is a piece of a free-form
/// face that happens to fit a circle within the file's rounding (a few quads of a scan or of
/// a spline surface), not a face of the part: it is left to the jet fit, and so, in turn, are
/// the surfaces that then lie open.
fn close_off(g: &grow::RegionGraph, grown: &[profile::Grown], region_surface: &mut [u32]) {
    let max_step = MAX_STEP_DEG.to_radians();
    loop {
        let mut changed = false;
        for (k, (prim, regions)) in grown.iter().enumerate() {
            if prim.kind() == SurfaceKind::Plane
                || regions.len() >= SMALL_SURFACE_REGIONS
                || regions.first().is_none_or(|&r| region_surface[r as usize] != k as u32)
            {
                continue;
            }
            let (mut open, mut rim) = (0usize, 0usize);
            for &r in regions {
                for &(s, angle) in g.neighbours(r) {
                    if region_surface[s as usize] == k as u32 {
                        continue;
                    }
                    rim += 1;
                    if region_surface[s as usize] == NO_SURFACE && angle <= max_step {
                        open += 1;
                    }
                }
            }
            if open as f64 > MAX_OPEN_SHARE * rim as f64 {
                for &r in regions {
                    region_surface[r as usize] = NO_SURFACE;
                }
                changed = true;
            }
        }
        if !changed {
            return;
        }
    }
}

/// The share of a curved surface's rim, by length, that unrecognized faces may continue
/// smoothly: a face of a CAD part ends at creases or at the faces it blends into, which are
/// recognized; a patch of a free-form face that a primitive passes through within the
/// rounding (ruling strips of a developable written with six digits) is bounded mostly by
/// more of that face.
pub const MAX_OPEN_LENGTH_SHARE: f64 = 0.5;

/// Module docs, step 7, by length: a curved surface, or a plane of a few triangles, whose rim
/// runs for more than [`MAX_OPEN_LENGTH_SHARE`] of its length along unrecognized faces met
/// smoothly (across less than [`MAX_STEP_DEG`]) is left to the jet fit, repeatedly. Linear in
/// the edges per round.
fn close_off_by_length(
    mesh: &Mesh,
    g: &grow::RegionGraph,
    grown: &[profile::Grown],
    region_surface: &mut [u32],
) {
    let cos_step = MAX_STEP_DEG.to_radians().cos();
    let surface_of = |f: u32, rs: &[u32]| {
        let r = g.regions.face_region[f as usize];
        if r == NO_REGION {
            NO_SURFACE
        } else {
            rs[r as usize]
        }
    };
    loop {
        let (mut open, mut rim) = (vec![0.0; grown.len()], vec![0.0; grown.len()]);
        for &(f, h, len) in &g.face_pairs {
            let (a, b) = (surface_of(f, region_surface), surface_of(h, region_surface));
            if a == b {
                continue;
            }
            let smooth =
                face_normal(mesh, f as usize).dot(&face_normal(mesh, h as usize)) >= cos_step;
            for (s, other) in [(a, b), (b, a)] {
                if s != NO_SURFACE {
                    rim[s as usize] += len;
                    if other == NO_SURFACE && smooth {
                        open[s as usize] += len;
                    }
                }
            }
        }
        let mut changed = false;
        for (k, (prim, regions)) in grown.iter().enumerate() {
            let held = regions.first().is_some_and(|&r| region_surface[r as usize] == k as u32);
            // A plane is a face of the part however it is bounded, unless it is a speck (fewer
            // than [`SMALL_SURFACE_REGIONS`] triangles: two chords of a finely exported torus
            // that happen to be coplanar).
            let faces: usize = regions.iter().map(|&r| g.regions.faces[r as usize] as usize).sum();
            let plane = prim.kind() == SurfaceKind::Plane;
            if (plane && faces >= SMALL_SURFACE_REGIONS) || !held {
                continue;
            }
            if open[k] > MAX_OPEN_LENGTH_SHARE * rim[k] {
                for &r in regions {
                    region_surface[r as usize] = NO_SURFACE;
                }
                changed = true;
            }
        }
        if !changed {
            return;
        }
    }
}

/// Module docs, step 6: the remaining planar regions that are faces of the part.
fn add_planes(
    g: &grow::RegionGraph,
    mesh: &Mesh,
    prims: &mut Vec<(Primitive, Vec<u32>)>,
    region_surface: &mut [u32],
) {
    let max_step = MAX_STEP_DEG.to_radians();
    let nr = g.regions.normal.len();
    let mut planes = Vec::new();
    for r in 0..nr as u32 {
        if region_surface[r as usize] != NO_SURFACE || g.regions.faces[r as usize] < 2 {
            continue;
        }
        let w = g.regions.width[r as usize];
        let face = g.neighbours(r).iter().all(|&(s, angle)| {
            angle > max_step
                || region_surface[s as usize] != NO_SURFACE
                || w >= WIDER * g.regions.width[s as usize]
        });
        if face {
            planes.push(r);
        }
    }
    for r in planes {
        let n = g.regions.normal[r as usize];
        let p = mesh.positions[g.verts(r)[0] as usize];
        region_surface[r as usize] = prims.len() as u32;
        prims.push((Primitive::Plane { normal: n.into(), offset: n.dot(&p) }, vec![r]));
    }
}

/// Numbers the surfaces in the order of their first faces and measures them.
fn finish(
    mesh: &Mesh,
    g: &grow::RegionGraph,
    prims: Vec<(Primitive, Vec<u32>)>,
    region_surface: &[u32],
    tol: f64,
) -> Surfaces {
    let nf = mesh.num_faces();
    let mut label = vec![NO_SURFACE; prims.len()];
    let mut order = Vec::new();
    let mut face_surface = vec![NO_SURFACE; nf];
    for (f, out) in face_surface.iter_mut().enumerate() {
        let r = g.regions.face_region[f];
        if r == NO_REGION || region_surface[r as usize] == NO_SURFACE {
            continue;
        }
        let k = region_surface[r as usize] as usize;
        if label[k] == NO_SURFACE {
            label[k] = order.len() as u32;
            order.push(k);
        }
        *out = label[k];
    }
    let mut faces = vec![0usize; order.len()];
    let mut area = vec![0.0; order.len()];
    let mut verts: Vec<Vec<u32>> = vec![Vec::new(); order.len()];
    for (f, &s) in face_surface.iter().enumerate() {
        if s == NO_SURFACE {
            continue;
        }
        let [a, b, c] = mesh.face_positions(f);
        faces[s as usize] += 1;
        area[s as usize] += 0.5 * (b - a).cross(&(c - a)).norm();
        verts[s as usize].extend(mesh.faces[f]);
    }
    let surfaces = order
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let vs = &mut verts[i];
            vs.sort_unstable();
            vs.dedup();
            let pts: Vec<V3> = vs.iter().map(|&v| mesh.positions[v as usize]).collect();
            let prim = prims[k].0;
            Surface {
                primitive: prim,
                faces: faces[i],
                area: area[i],
                rms_residual: fit::rms_residual(&prim, &pts),
                max_residual: fit::max_residual(&prim, &pts),
            }
        })
        .collect();
    Surfaces { face_surface, surfaces, tolerance: tol }
}

/// The exact geometry at a point of a recognized surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The unit normal, oriented as the faces around the vertex.
    pub normal: V3,
    /// The shape operator dn/dp of that normal (world, zero along it; module
    /// [`primitive`]'s docs).
    pub shape: Matrix3<f64>,
}

impl Surfaces {
    /// Whether any surface was recognized.
    pub fn is_empty(&self) -> bool {
        self.surfaces.is_empty()
    }

    /// Surface `s`'s normal at `p`, oriented along `towards`, and its shape operator.
    pub fn point(&self, s: u32, p: &V3, towards: &V3) -> SurfacePoint {
        let prim = &self.surfaces[s as usize].primitive;
        let n = prim.normal_at(p);
        let s = prim.shape_at(p);
        if n.dot(towards) < 0.0 {
            SurfacePoint { normal: -n, shape: -s }
        } else {
            SurfacePoint { normal: n, shape: s }
        }
    }

    /// Whether the faces `f` and `g` of `mesh`, which share the edge (`u`, `v`), meet at a
    /// crease: `Some(true)` when both lie on recognized surfaces whose normals differ there by
    /// more than [`G1_TOLERANCE_DEG`] (at either end), `Some(false)` when they lie on one
    /// surface or on two that meet tangentially, `None` when either face is unrecognized.
    pub fn crease_between(&self, mesh: &Mesh, f: usize, g: usize, u: u32, v: u32) -> Option<bool> {
        let (a, b) = (self.face_surface[f], self.face_surface[g]);
        if a == NO_SURFACE || b == NO_SURFACE {
            return None;
        }
        if a == b {
            return Some(false);
        }
        let (nf, ng) = (face_normal(mesh, f), face_normal(mesh, g));
        let cos = G1_TOLERANCE_DEG.to_radians().cos();
        let crease = [u, v].iter().any(|&w| {
            let p = mesh.positions[w as usize];
            let (pa, pb) = (self.point(a, &p, &nf), self.point(b, &p, &ng));
            pa.normal.dot(&pb.normal) < cos
        });
        Some(crease)
    }
}

fn face_normal(mesh: &Mesh, f: usize) -> V3 {
    let [a, b, c] = mesh.face_positions(f);
    (b - a).cross(&(c - a)).try_normalize(0.0).unwrap_or_else(V3::z)
}

/// The most surfaces a vertex is taken to lie on (tangent surfaces meeting at a corner).
const MAX_VERTEX_SURFACES: usize = 4;

/// Per vertex, the recognized surfaces its faces lie on (up to four, tangent to each other),
/// or none when any face around it is unrecognized or two of them meet at a crease there (a
/// vertex a patch split does not separate).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexSurfaces {
    /// Per vertex, its surfaces ([`NO_SURFACE`] in the unused slots; all of them for a vertex
    /// not on recognized surfaces alone).
    pub of: Vec<[u32; MAX_VERTEX_SURFACES]>,
}

impl VertexSurfaces {
    /// The surfaces of each vertex of `mesh`, whose faces `surfaces` numbers (a part cut into
    /// patches keeps its faces' order).
    pub fn new(mesh: &Mesh, surfaces: &Surfaces) -> Self {
        let nv = mesh.num_vertices();
        let mut of = vec![[NO_SURFACE; MAX_VERTEX_SURFACES]; nv];
        let mut mixed = vec![false; nv];
        for (f, t) in mesh.faces.iter().enumerate() {
            let s = surfaces.face_surface.get(f).copied().unwrap_or(NO_SURFACE);
            for &v in t {
                let v = v as usize;
                if s == NO_SURFACE {
                    mixed[v] = true;
                    continue;
                }
                let slots = &mut of[v];
                if !slots.contains(&s) {
                    match slots.iter_mut().find(|x| **x == NO_SURFACE) {
                        Some(x) => *x = s,
                        None => mixed[v] = true,
                    }
                }
            }
        }
        let normals = face_normals_at(mesh);
        let cos = G1_TOLERANCE_DEG.to_radians().cos();
        for v in 0..nv {
            let slots = of[v];
            let n = normals[v];
            let p = mesh.positions[v];
            let first = slots[0];
            let tangent = first != NO_SURFACE
                && slots.iter().filter(|&&s| s != NO_SURFACE).all(|&s| {
                    surfaces.point(s, &p, &n).normal.dot(&surfaces.point(first, &p, &n).normal)
                        >= cos
                });
            if mixed[v] || !tangent {
                of[v] = [NO_SURFACE; MAX_VERTEX_SURFACES];
            }
        }
        VertexSurfaces { of }
    }

    /// Extends the vertices' surfaces to the vertices a refinement added, each the midpoint
    /// of its `parents` edge: the surfaces both ends lie on.
    pub fn extend(&mut self, parents: &[[u32; 2]]) {
        for p in parents {
            let (a, b) = (self.of[p[0] as usize], self.of[p[1] as usize]);
            let mut slots = [NO_SURFACE; MAX_VERTEX_SURFACES];
            let common = a.iter().filter(|&&s| s != NO_SURFACE && b.contains(&s));
            for (slot, s) in slots.iter_mut().zip(common) {
                *slot = *s;
            }
            self.of.push(slots);
        }
    }

    /// The exact geometry at each vertex of `mesh` on recognized surfaces: the mean of its
    /// surfaces' normals there (tangent surfaces agree to [`G1_TOLERANCE_DEG`]) oriented as
    /// its faces, and the mean of their shape operators (a curvature that jumps at a tangent
    /// junction, a plate meeting a fillet, is read as the mean of its two sides).
    pub fn points(&self, mesh: &Mesh, surfaces: &Surfaces) -> Vec<Option<SurfacePoint>> {
        let normals = face_normals_at(mesh);
        (0..mesh.num_vertices())
            .map(|v| {
                let slots = self.of.get(v)?;
                let on: Vec<u32> = slots.iter().copied().filter(|&s| s != NO_SURFACE).collect();
                if on.is_empty() {
                    return None;
                }
                let p = mesh.positions[v];
                let mut n = V3::zeros();
                let mut shape = Matrix3::zeros();
                for &s in &on {
                    let q = surfaces.point(s, &p, &normals[v]);
                    n += q.normal;
                    shape += q.shape;
                }
                let n = n.try_normalize(0.0)?;
                let shape = shape / on.len() as f64;
                // Tangent part only (the mean of tangent surfaces' operators, projected).
                let proj = Matrix3::identity() - n * n.transpose();
                Some(SurfacePoint { normal: n, shape: proj * shape * proj })
            })
            .collect()
    }

    /// The surface each face of `mesh` lies on: the one its corners' surfaces share (corners
    /// on none ignored), the one whose normal at the face's centroid is nearest the face's
    /// when they share several, [`NO_SURFACE`] when they share none or no corner is on any.
    pub fn face_surfaces(&self, mesh: &Mesh, surfaces: &Surfaces) -> Vec<u32> {
        (0..mesh.num_faces())
            .map(|f| {
                let lists: Vec<&[u32; MAX_VERTEX_SURFACES]> = mesh.faces[f]
                    .iter()
                    .filter_map(|&v| self.of.get(v as usize))
                    .filter(|l| l[0] != NO_SURFACE)
                    .collect();
                let Some(first) = lists.first() else { return NO_SURFACE };
                let shared = first
                    .iter()
                    .copied()
                    .filter(|&s| s != NO_SURFACE && lists.iter().all(|l| l.contains(&s)));
                let [a, b, c] = mesh.face_positions(f);
                let (centroid, n) = ((a + b + c) / 3.0, face_normal(mesh, f));
                let fit = |s: u32| surfaces.point(s, &centroid, &n).normal.dot(&n);
                shared.max_by(|&s, &t| fit(s).total_cmp(&fit(t))).unwrap_or(NO_SURFACE)
            })
            .collect()
    }

    /// Moves each vertex that lies on one surface alone (not at a junction) onto it: a
    /// refinement's midpoints of chords land on the surface they approximate.
    pub fn project(&self, mesh: &mut Mesh, surfaces: &Surfaces, from: usize) {
        for v in from..mesh.num_vertices().min(self.of.len()) {
            let slots = self.of[v];
            if slots[0] == NO_SURFACE || slots[1] != NO_SURFACE {
                continue;
            }
            let prim = &surfaces.surfaces[slots[0] as usize].primitive;
            let p = mesh.positions[v];
            let q = prim.nearest(&p, &prim.normal_at(&p));
            if q.iter().all(|x| x.is_finite()) {
                mesh.positions[v] = q;
            }
        }
    }
}

/// The recognized surface of each face of a part as prepared: what the strokes are lifted onto
/// and the preview shades with per sample.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FaceSurfaces {
    /// The surfaces' primitives.
    pub primitives: Vec<Primitive>,
    /// Per face, its surface ([`NO_SURFACE`] for none).
    pub of: Vec<u32>,
}

impl FaceSurfaces {
    /// The curved primitive (not a plane) face `f` lies on, if any.
    pub fn curved(&self, f: usize) -> Option<&Primitive> {
        let s = *self.of.get(f)?;
        let prim = self.primitives.get(s as usize)?;
        (!matches!(prim, Primitive::Plane { .. })).then_some(prim)
    }

    /// The point of face `f`'s curved surface nearest `p` and the unit normal there (either
    /// sign), when `f` lies on one and both are finite.
    pub fn project(&self, f: usize, p: &V3) -> Option<(V3, V3)> {
        let prim = self.curved(f)?;
        let n = prim.normal_at(p);
        let q = prim.nearest(p, &n);
        (q.iter().chain(n.iter()).all(|x| x.is_finite())).then_some((q, n))
    }
}

/// Per vertex, the sum of its faces' unit normals (an orientation, not a normal).
fn face_normals_at(mesh: &Mesh) -> Vec<V3> {
    let mut out = vec![V3::zeros(); mesh.num_vertices()];
    for (f, t) in mesh.faces.iter().enumerate() {
        let n = face_normal(mesh, f);
        for &v in t {
            out[v as usize] += n;
        }
    }
    out
}

/// The surfaces of a part as `grainline inspect`, FIELD.json and the run report give them.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfaceReport {
    /// The distance within which a vertex counted as on a surface (scene units).
    pub tolerance: f64,
    /// The surfaces, numbered as [`Surfaces::surfaces`].
    pub surfaces: Vec<Surface>,
    /// Faces on no recognized surface (a free-form face, a scan's or a sculpt's triangles).
    pub unrecognized_faces: usize,
    /// Their share of the part's area.
    pub unrecognized_area_share: f64,
    /// The creases between two recognized surfaces, one entry per pair of surfaces.
    pub creases: Vec<CreaseReport>,
}

/// Where two recognized surfaces meet at a crease.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CreaseReport {
    /// The two surfaces.
    pub surfaces: [u32; 2],
    /// Mesh edges along it.
    pub edges: usize,
    /// Its length.
    pub length: f64,
    /// The largest angle between the surfaces' normals along it, degrees.
    pub angle_deg: f64,
}

impl Surfaces {
    /// The report of these surfaces of `mesh`.
    pub fn report(&self, mesh: &Mesh) -> SurfaceReport {
        let mut area = 0.0;
        let mut free_area = 0.0;
        let mut free = 0;
        for f in 0..mesh.num_faces() {
            let [a, b, c] = mesh.face_positions(f);
            let x = 0.5 * (b - a).cross(&(c - a)).norm();
            area += x;
            if self.face_surface.get(f).is_none_or(|&s| s == NO_SURFACE) {
                free += 1;
                free_area += x;
            }
        }
        let mut edges: Vec<(u32, u32, usize)> = Vec::with_capacity(3 * mesh.num_faces());
        for (f, t) in mesh.faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.push((a.min(b), a.max(b), f));
            }
        }
        edges.sort_unstable();
        let mut creases: Vec<CreaseReport> = Vec::new();
        for run in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
            let [x, y] = run else { continue };
            if self.crease_between(mesh, x.2, y.2, x.0, x.1) != Some(true) {
                continue;
            }
            let (a, b) = (self.face_surface[x.2], self.face_surface[y.2]);
            let pair = [a.min(b), a.max(b)];
            let (p, q) = (mesh.positions[x.0 as usize], mesh.positions[x.1 as usize]);
            let (na, nb) = (face_normal(mesh, x.2), face_normal(mesh, y.2));
            let angle = [p, q]
                .iter()
                .map(|w| self.point(a, w, &na).normal.angle(&self.point(b, w, &nb).normal))
                .fold(0.0, f64::max)
                .to_degrees();
            match creases.iter_mut().find(|c| c.surfaces == pair) {
                Some(c) => {
                    c.edges += 1;
                    c.length += (q - p).norm();
                    c.angle_deg = c.angle_deg.max(angle);
                }
                None => creases.push(CreaseReport {
                    surfaces: pair,
                    edges: 1,
                    length: (q - p).norm(),
                    angle_deg: angle,
                }),
            }
        }
        creases.sort_by_key(|c| c.surfaces);
        SurfaceReport {
            tolerance: self.tolerance,
            surfaces: self.surfaces.clone(),
            unrecognized_faces: free,
            unrecognized_area_share: if area > 0.0 { free_area / area } else { 0.0 },
            creases,
        }
    }
}
