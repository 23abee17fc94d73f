//! Differential geometry of a triangle mesh: normals, tangent frames, vertex areas, the discrete
//! connection, the Weingarten map (by jet fit) and the covariant gradient of angle fields (Eq. 10).
//!
//! Conventions are those of docs/math.md §1: frames [t, b, n] are right-handed, W is taken with
//! respect to the same n that enters hᵀn, and reported principal curvatures are the
//! eigenvalues of −W (positive on a sphere with outward normals).

pub mod areas;
pub(crate) mod cells;
pub mod connection;
pub mod curvature;
pub mod frames;
pub mod gradient;
pub mod laplacian;
pub mod noise;
pub mod normals;
pub mod patches;
pub mod quality;
pub mod rings;
pub mod surfaces;

use nalgebra::{Matrix2, Vector3};
use rayon::prelude::*;

pub use curvature::Principal;
pub use frames::Frame;
pub use gradient::{GradientForm, GradientStencil};
use normals::FALLBACK_NORMAL;
pub use normals::{NormalSource, VertexFaces};

use crate::mesh::{Adjacency, Mesh};

/// Options of [`Geometry::compute`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometryOptions {
    /// Where the initial vertex normals come from.
    pub normals: NormalSource,
    /// How many times the jet fit's linear term refines the normal before the final fit
    /// (math.md §2: one refinement, i.e. two fits, suffices). Ignored for file normals.
    pub normal_refinements: u32,
    /// Turn every tangent frame about its normal by a pseudo-random angle drawn from this seed.
    /// Every quantity grainline reports is independent of the frames; this exists to test
    /// that, and to make frame-dependent bugs visible.
    pub frame_twist_seed: Option<u64>,
    /// Fit the jets over the vertices within this distance (scene units) rather than the
    /// 1-ring (`field.fit_radius`, docs/math.md §5.6): a scan's noise averaged out at that
    /// scale. `None` (the default): the 1-ring, grown only where it is degenerate.
    pub fit_radius: Option<f64>,
    /// The RMS height error of the vertices (scene units), the noise estimate's σ
    /// ([`noise::NoiseEstimate`]); 0 (the default) takes positions as exact. A ring fit whose
    /// slope that error would tilt by more than [`curvature::MAX_NOISE_TILT_DEG`] grows.
    pub height_noise: f64,
}

impl Default for GeometryOptions {
    fn default() -> Self {
        GeometryOptions {
            normals: NormalSource::AngleWeighted,
            normal_refinements: 1,
            frame_twist_seed: None,
            fit_radius: None,
            height_noise: 0.0,
        }
    }
}

/// A pseudo-random angle in [0, 2π) for vertex `i` (SplitMix64 of seed and index).
fn twist_angle(seed: u64, i: usize) -> f64 {
    let mut z = seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    std::f64::consts::TAU * ((z >> 11) as f64 / (1u64 << 53) as f64)
}

/// Vertices per parallel work item of the jet-fit pass (fixed: the same result at any thread
/// count).
const FIT_CHUNK: usize = 4096;

/// The jet fit at vertex `i` from initial normal `n`: `refinements` normal refinements, then the
/// optional frame twist (math.md §2). The rings and their scaled offsets are gathered once.
fn fit_vertex(
    mesh: &Mesh,
    adjacency: &Adjacency,
    options: &GeometryOptions,
    refinements: u32,
    n: &Vector3<f64>,
    i: usize,
    rings: &mut curvature::JetRings,
) -> (Frame, curvature::JetFit) {
    rings.start(i);
    rings.height_noise = options.height_noise;
    let fit_in = |rings: &mut curvature::JetRings, frame: &Frame| match options.fit_radius {
        Some(r) => rings.fit_in_ball(&mesh.positions, adjacency, frame, r),
        None => rings.fit(&mesh.positions, adjacency, frame),
    };
    let mut frame = Frame::from_normal(*n);
    let mut fit = fit_in(rings, &frame);
    for _ in 0..refinements {
        if fit.ring == 0 {
            break;
        }
        let tilted = frame.n - frame.t * fit.slope[0] - frame.b * fit.slope[1];
        frame = Frame::from_normal(normals::normalize_or(tilted, frame.n));
        fit = fit_in(rings, &frame);
    }
    if let Some(seed) = options.frame_twist_seed {
        frame = Frame::with_tangent(frame.n, frame.direction(twist_angle(seed, i)));
        fit = fit_in(rings, &frame);
    }
    (frame, fit)
}

/// The Weingarten map of math.md §1 in `frame` of a surface whose normal has the shape
/// operator `shape` = dn/dp (world): W = −[tᵀSt tᵀSb; bᵀSt bᵀSb].
fn surface_weingarten(frame: &Frame, shape: &nalgebra::Matrix3<f64>) -> Matrix2<f64> {
    let (t, b) = (frame.t, frame.b);
    let (st, sb) = (shape * t, shape * b);
    let off = -0.5 * (t.dot(&sb) + b.dot(&st));
    Matrix2::new(-t.dot(&st), off, off, -b.dot(&sb))
}

/// Counts of vertices where a fallback was used, so degenerate input is visible, never silent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct GeometryDiagnostics {
    /// Vertices with no usable normal (isolated or only zero-area faces): normal set to +Z.
    pub fallback_normals: usize,
    /// Vertices whose jet fit needed more than the 1-ring.
    pub extended_jet_rings: usize,
    /// Vertices where no quadric could be fitted (W = 0).
    pub failed_jet_fits: usize,
    /// Vertices whose Eq. 10 stencil needed more than the 1-ring.
    pub extended_gradient_stencils: usize,
    /// Vertices with no Eq. 10 stencil (∇φ = 0).
    pub empty_gradient_stencils: usize,
}

/// Per-vertex differential geometry of a mesh.
#[derive(Clone, Debug)]
pub struct Geometry {
    /// Vertex adjacency.
    pub adjacency: Adjacency,
    /// Tangent frames [t, b, n] (n is the refined vertex normal).
    pub frames: Vec<Frame>,
    /// Mixed Voronoi areas.
    pub areas: Vec<f64>,
    /// Weingarten maps in each vertex frame.
    pub weingarten: Vec<Matrix2<f64>>,
    /// Principal curvatures and directions.
    pub principal: Vec<Principal>,
    /// Transport angle ρᵢⱼ per adjacency slot.
    pub transport: Vec<f64>,
    /// The Eq. 10 regression stencils.
    pub stencil: GradientStencil,
    /// Where fallbacks were needed.
    pub diagnostics: GeometryDiagnostics,
}

impl Geometry {
    /// Computes everything for `mesh`. Every output is finite for any finite input mesh.
    pub fn compute(mesh: &Mesh, options: &GeometryOptions) -> Self {
        Self::compute_timed(mesh, options).0
    }

    /// [`Geometry::compute`], also returning the wall time of each stage in seconds, in order
    /// (`vertex_faces` (with the face normals), `adjacency`, `normals`, `jet_fits`, `areas`, `transport`, `stencils`).
    /// The outputs are identical to `compute`'s.
    pub fn compute_timed(
        mesh: &Mesh,
        options: &GeometryOptions,
    ) -> (Self, Vec<(&'static str, f64)>) {
        Self::compute_keeping(mesh, options, &[])
    }

    /// [`Geometry::compute_timed`] with the first `kept.len()` vertices' normals given (their
    /// jet fits do not tilt them): a part refined inside the brushes keeps its own vertices'
    /// normals as they were before the refinement, and its new vertices the normalised means
    /// the refinement carried to them (docs/math.md §12), however the split faces around them
    /// lie.
    pub fn compute_keeping(
        mesh: &Mesh,
        options: &GeometryOptions,
        kept: &[Vector3<f64>],
    ) -> (Self, Vec<(&'static str, f64)>) {
        Self::compute_exact(mesh, options, kept, &[])
    }

    /// [`Geometry::compute_keeping`] with the exact geometry of the vertices that lie on
    /// recognized surfaces (`exact[i]`, docs/math.md §3, "Recognized surfaces"): their normal
    /// is the surface's, not fitted, and their Weingarten map the surface's shape operator
    /// in their frame (W = −[tᵀSt tᵀSb; bᵀSt bᵀSb]). `exact` may be shorter than the
    /// vertices, or empty.
    pub fn compute_exact(
        mesh: &Mesh,
        options: &GeometryOptions,
        kept: &[Vector3<f64>],
        exact: &[Option<surfaces::SurfacePoint>],
    ) -> (Self, Vec<(&'static str, f64)>) {
        let mut timings = Vec::with_capacity(7);
        let mut clock = std::time::Instant::now();
        let mut lap = |name: &'static str| {
            let now = std::time::Instant::now();
            timings.push((name, now.duration_since(clock).as_secs_f64()));
            clock = now;
        };
        // The incidence is a sequential counting sort: the face normals use the other threads.
        let (vf, face_n) = rayon::join(|| VertexFaces::new(mesh), || normals::face_data(mesh));
        lap("vertex_faces");
        let adjacency = Adjacency::from_vertex_faces(&mesh.faces, &vf);
        lap("adjacency");
        let (mut normals, fallback_normals) =
            normals::vertex_normals_from_faces(mesh, &vf, &face_n, options.normals);
        // Vertices whose normal the flat faces around them fix (math.md §3, "Flat regions"):
        // their normal is that plane's and the jet fit does not tilt it.
        let mut pinned = if options.normals == NormalSource::File && mesh.normals.is_some() {
            vec![false; normals.len()]
        } else {
            normals::pin_flat_normals(mesh, &vf, &adjacency, &face_n, &mut normals)
        };
        for (i, n) in kept.iter().enumerate().take(normals.len()) {
            normals[i] = *n;
            pinned[i] = true;
        }
        for (i, e) in exact.iter().enumerate().take(normals.len()) {
            if let Some(e) = e {
                normals[i] = e.normal;
                pinned[i] = true;
            }
        }
        drop(face_n);
        lap("normals");
        let refinements = if options.normals == NormalSource::File && mesh.normals.is_some() {
            0
        } else {
            options.normal_refinements
        };
        // One pass per vertex: fit (math.md §2: refine the normal, refit), then the principal
        // curvatures, written straight into the output arrays (no intermediate per-vertex
        // tuple array, no second pass).
        let nv = normals.len();
        // Placeholders written in parallel (first-touch page faults are costly on one thread).
        let placeholder = Frame::from_normal(FALLBACK_NORMAL);
        let mut frames: Vec<Frame> = (0..nv).into_par_iter().map(|_| placeholder).collect();
        let mut weingarten: Vec<Matrix2<f64>> =
            (0..nv).into_par_iter().map(|_| Matrix2::zeros()).collect();
        let mut principal: Vec<Principal> = (0..nv)
            .into_par_iter()
            .map(|_| Principal { k1: 0.0, k2: 0.0, d1: [1.0, 0.0] })
            .collect();
        let mut rings = vec![0u8; nv];
        let radii = curvature::ring_radii(&mesh.positions, &adjacency);
        frames
            .par_chunks_mut(FIT_CHUNK)
            .zip(weingarten.par_chunks_mut(FIT_CHUNK))
            .zip(principal.par_chunks_mut(FIT_CHUNK))
            .zip(rings.par_chunks_mut(FIT_CHUNK))
            .enumerate()
            .for_each_init(curvature::JetRings::default, |bufs, (c, (((fr, w), pr), rg))| {
                for k in 0..fr.len() {
                    let i = c * FIT_CHUNK + k;
                    let refine = if pinned[i] { 0 } else { refinements };
                    // A normal fixed by its flat faces (or kept) is not fitted: its 1-ring is not
                    // judged against its neighbours' (a CAD face's fans are all sizes).
                    bufs.neighbour_radius = if pinned[i] {
                        0.0
                    } else {
                        curvature::neighbour_radius(&radii, &adjacency, i)
                    };
                    let (frame, fit) =
                        fit_vertex(mesh, &adjacency, options, refine, &normals[i], i, bufs);
                    fr[k] = frame;
                    w[k] = match exact.get(i) {
                        Some(Some(e)) => surface_weingarten(&frame, &e.shape),
                        _ => fit.w,
                    };
                    pr[k] = Principal::from_weingarten(&w[k]);
                    rg[k] = fit.ring;
                }
            });
        drop(normals);
        let extended_jet_rings = rings.iter().filter(|&&r| r > 1).count();
        let failed_jet_fits = rings.iter().filter(|&&r| r == 0).count();
        drop(rings);
        lap("jet_fits");
        let areas = areas::vertex_areas(mesh, &vf);
        drop(vf);
        lap("areas");
        let transport = connection::edge_transport(&adjacency, &frames);
        lap("transport");
        let stencil = GradientStencil::new(&mesh.positions, &adjacency, &frames, &transport);
        lap("stencils");
        let diagnostics = GeometryDiagnostics {
            fallback_normals,
            extended_jet_rings,
            failed_jet_fits,
            extended_gradient_stencils: stencil.extended,
            empty_gradient_stencils: stencil.empty,
        };
        let geometry = Geometry {
            adjacency,
            frames,
            areas,
            weingarten,
            principal,
            transport,
            stencil,
            diagnostics,
        };
        (geometry, timings)
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.frames.len()
    }

    /// The unit normal of vertex `i`.
    #[inline]
    pub fn normal(&self, i: usize) -> Vector3<f64> {
        self.frames[i].n
    }

    /// Angles φ of world directions `u` in the vertex frames (tangential part; see
    /// [`Frame::angle_of`]).
    pub fn angles_of(&self, u: &[Vector3<f64>]) -> Vec<f64> {
        self.frames.iter().zip(u).map(|(f, u)| f.angle_of(u)).collect()
    }

    /// World unit directions of angles φ.
    pub fn directions_of(&self, phi: &[f64]) -> Vec<Vector3<f64>> {
        self.frames.iter().zip(phi).map(|(f, &p)| f.direction(p)).collect()
    }
}
