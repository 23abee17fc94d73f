//! Differential geometry of a triangle mesh: normals, tangent frames, vertex areas, the discrete
//! connection, the Weingarten map (by jet fit) and the covariant gradient of angle fields (Eq. 10).
//!
//! Conventions are those of docs/math.md §1: frames [t, b, n] are right-handed, W is taken with
//! respect to the same n that enters hᵀn, and reported principal curvatures are the
//! eigenvalues of −W (positive on a sphere with outward normals).

pub mod areas;
pub mod connection;
pub mod curvature;
pub mod frames;
pub mod gradient;
pub mod laplacian;
pub mod normals;
pub mod rings;

use nalgebra::{Matrix2, Vector3};
use rayon::prelude::*;

pub use curvature::Principal;
pub use frames::Frame;
pub use gradient::{GradientForm, GradientStencil};
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
}

impl Default for GeometryOptions {
    fn default() -> Self {
        GeometryOptions {
            normals: NormalSource::AngleWeighted,
            normal_refinements: 1,
            frame_twist_seed: None,
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
        let adjacency = Adjacency::from_faces(mesh.num_vertices(), &mesh.faces);
        let vf = VertexFaces::new(mesh);
        let (normals, fallback_normals) = normals::vertex_normals(mesh, &vf, options.normals);
        let refinements = if options.normals == NormalSource::File && mesh.normals.is_some() {
            0
        } else {
            options.normal_refinements
        };
        let fits: Vec<(Frame, curvature::JetFit)> = normals
            .par_iter()
            .enumerate()
            .map_init(
                || (Vec::new(), Vec::new()),
                |bufs, (i, n)| {
                    let mut frame = Frame::from_normal(*n);
                    let mut fit = curvature::jet_fit(&mesh.positions, &adjacency, i, &frame, bufs);
                    for _ in 0..refinements {
                        if fit.ring == 0 {
                            break;
                        }
                        let tilted = frame.n - frame.t * fit.slope[0] - frame.b * fit.slope[1];
                        frame = Frame::from_normal(normals::normalize_or(tilted, frame.n));
                        fit = curvature::jet_fit(&mesh.positions, &adjacency, i, &frame, bufs);
                    }
                    if let Some(seed) = options.frame_twist_seed {
                        frame = Frame::with_tangent(frame.n, frame.direction(twist_angle(seed, i)));
                        fit = curvature::jet_fit(&mesh.positions, &adjacency, i, &frame, bufs);
                    }
                    (frame, fit)
                },
            )
            .collect();
        let frames: Vec<Frame> = fits.iter().map(|f| f.0).collect();
        let weingarten: Vec<Matrix2<f64>> = fits.iter().map(|f| f.1.w).collect();
        let extended_jet_rings = fits.iter().filter(|f| f.1.ring > 1).count();
        let failed_jet_fits = fits.iter().filter(|f| f.1.ring == 0).count();
        // Free the fits (128 MB at 1M vertices) before the stencils, where memory peaks.
        drop(fits);
        let principal = weingarten.par_iter().map(Principal::from_weingarten).collect();
        let areas = areas::vertex_areas(mesh, &vf);
        drop(vf);
        let transport = connection::edge_transport(&adjacency, &frames);
        let stencil = GradientStencil::new(&mesh.positions, &adjacency, &frames, &transport);
        let diagnostics = GeometryDiagnostics {
            fallback_normals,
            extended_jet_rings,
            failed_jet_fits,
            extended_gradient_stencils: stencil.extended,
            empty_gradient_stencils: stencil.empty,
        };
        Geometry {
            adjacency,
            frames,
            areas,
            weingarten,
            principal,
            transport,
            stencil,
            diagnostics,
        }
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
