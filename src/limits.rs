//! Budgets: every bound grainline puts on its input's size or magnitude, in one place
//! (documented in docs/scene.md, "Limits", and docs/formats.md).

/// Largest accepted |coordinate| of an OBJ `v` after `scale` (1e75, in the mesh's units).
///
/// Geometry multiplies up to four coordinates: with every |c| ≤ B an edge vector's components
/// are ≤ 2B, a face's cross product `(b − a) × (c − a)` (twice its area) has components ≤ 8B²
/// and squared norm ≤ 192·B⁴. That stays below `f64::MAX` ≈ 1.8e308 for B ≤ 9.8e76; 1e75 keeps
/// a margin of 10⁶ for sums over faces and unit conversions. Larger coordinates are refused
/// (naming the line and vertex) instead of turning areas into infinity or NaN and faces into
/// false zero-area ones.
pub const MAX_COORDINATE: f64 = 1e75;

/// Smallest accepted size of a part: its bounding box's diagonal, after `scale`, at least
/// 1e-60 (in the mesh's units).
///
/// Degenerate faces are found by their shape alone (a face's size does not matter), but the
/// geometry divides by lengths: curvatures are about 1/L and the jet fit and the smoothest
/// field raise them to the fourth power. A part 1e-100 across failed in the smoothest field's
/// factorization and one 1e-80 across came out with spurious critical points; 1e-60 keeps
/// 1/L⁴ ≤ 1e240, a margin of 10⁶⁸ below `f64::MAX`.
pub const MIN_PART_SIZE: f64 = 1e-60;

/// The range of `mesh.scale` (`--scale`): [10⁻¹², 10¹²]. Areas multiply two scaled
/// coordinates, so a scale of 1e-300 made every area underflow to zero (and was reported as
/// faces degenerate in UV); unit conversions need factors of 10⁻⁶…10⁶ at most.
pub const MESH_SCALE_RANGE: (f64, f64) = (1e-12, 1e12);

/// Most triangles (after splitting polygons) a mesh file may hold: 1e9. Corners are indexed by
/// `u32` and the half-edge structure needs 3·F < 2³² − 1, so 1.43e9 is the hard ceiling; 1e9
/// keeps a margin (and is 50 GB of binary STL). STL and PLY counts are checked against it, and
/// against the file's size, before anything is allocated for them.
pub const MAX_FILE_TRIANGLES: usize = 1_000_000_000;

/// Most vertices a mesh file may hold: 3·[`MAX_FILE_TRIANGLES`] (an STL lists three per
/// triangle), below `u32::MAX` so every vertex has a `u32` index.
pub const MAX_FILE_VERTICES: usize = 3 * MAX_FILE_TRIANGLES;

/// Most corners one face may list: 1e6, in a PLY face list or an OBJ `f` line (a polygon is
/// split into triangles; a count beyond this is taken for a corrupt file rather than read, and
/// an OBJ line is refused at its 10⁶+1-th corner).
pub const MAX_POLYGON_CORNERS: usize = 1_000_000;

/// Most faces one edge of a mesh may join: 64 (a manifold edge has two, a fin three or four).
/// The crease-aware normals compare the faces along each edge pairwise, so an edge shared by
/// N faces (a file repeating `f 1 2 3` N times, or one polygon of N corners over three
/// vertices) costs N²: 20,000 such faces took 8 s. With at most 64 per edge that work is at
/// most 32 comparisons per face. Checked when the edges are classified (linear), before any
/// geometry, for every mesh file (also under `--allow-nonmanifold` and in `inspect`).
pub const MAX_EDGE_FACES: usize = 64;

/// Most triangles a panel (`outline`, `grainline panel`) may be estimated to get:
/// 4 × 10⁶ (the refinement's own guard adds at most 2 × 10⁶ vertices, about as many
/// triangles again). The estimate, made from the outline before any triangle is built, is
/// `A / (½ · √3/4 · e²) + P / e` for an outline of area `A` and perimeter `P` meshed with a
/// longest edge `e`: the refinement's area bound per triangle, plus the boundary splits.
pub const MAX_PANEL_TRIANGLES: f64 = 4e6;

/// Largest |coordinate| of a panel outline (`outline`, `grainline panel`), after the SVG's
/// units and viewBox: 10⁶ mm (1 km), beyond any sheet. A 10³⁰ mm rect took 15 s and 1.2 GB
/// to refine (the triangulator's predicates lose every digit of a 0.1 mm feature there) and
/// wrote triangles with 0.00° angles. Refused naming the file, the line and the element.
pub const MAX_PANEL_COORDINATE_MM: f64 = 1e6;

/// Most bytes a render may be estimated to hold (4 GiB): the per-sample buffers
/// (visibility, radiance, overlay layers, LIC, highlight curves, the as-brushed shading) and
/// the per-pixel ones, from [`crate::render::RenderSettings::memory_estimate`].
pub const MAX_RENDER_BYTES: u64 = 4 << 30;

/// Most bytes a sparse Cholesky factor (the smoothest field, the stencil blend, the harmonic
/// fill, the solve's normal equations) may take: 8 GiB. Its size is known from the symbolic
/// analysis (linear in the matrix) before the numeric factorization allocates it.
pub const MAX_FACTOR_BYTES: u64 = 8 << 30;

/// Most points an SVG (outline or curve edit) may flatten to: 10⁷ (160 MB). Counted while
/// flattening, so a drawing past it stops there (arcs of radius 10³⁰ at a 0.01 mm tolerance
/// would otherwise give billions).
pub const MAX_SVG_POINTS: usize = 10_000_000;

/// Largest magnitude of a number in an SVG's shapes (path data, `points`, `x`, `width`, `r`,
/// …) and transforms: 1e30. usvg keeps points as `f32` (largest 3.4e38), so a larger number
/// became infinity and its shape vanished ("no closed outline"); 1e30 leaves 10⁸ for the
/// transforms and units. Refused naming the file, the line, the element and the attribute.
pub const MAX_SVG_NUMBER: f64 = 1e30;

/// Most elements an SVG may hold: 10⁵ (usvg's own limit is 10⁶). Counted on the parsed
/// document before usvg resolves it; 2 × 10⁴ separate rects took 32 s in `panel`.
pub const MAX_SVG_ELEMENTS: usize = 100_000;

/// Deepest nesting of an SVG's elements: 256 (10⁵ nested groups kept usvg busy past 20 s).
pub const MAX_SVG_DEPTH: usize = 256;

/// Most steps an SVG's `<style>` selectors may be estimated to take to match: 10⁸. A
/// selector with k descendant combinators (a space) and j general-sibling ones (`~`) may try
/// S(D + 1, k) · S(W + 1, j) chains of ancestors and siblings for each of the N elements (D
/// the deepest nesting, W the most children of one element); the estimate sums
/// N · S(D + 1, k) · S(W + 1, j) over the selectors, S(n, k) = Σ_{i ≤ k} C(n, i) (2ⁿ when
/// k ≥ n: a selector longer than the nesting tries every prefix before it fails).
pub const MAX_SVG_SELECTOR_WORK: f64 = 1e8;

/// Most stroke samples a placement may be estimated to take (`A / (d_sep · h)`; see
/// [`grainline_toolpaths::budget`]).
pub use grainline_toolpaths::budget::MAX_STROKE_SAMPLES;

/// Largest `toolpaths.plan.order.neighbours`.
pub use grainline_toolpaths::budget::MAX_NEIGHBOURS;

/// Largest `solver.smoothness` λ_s: 10⁶. λ_s is relative (the Dirichlet energy is multiplied by
/// λ_s × the surface area, and by up to 1000 × that with `continuation`); past 10⁶ the edits
/// have long stopped mattering, and at 10³⁰⁰ the energy overflows to infinity mid-solve.
pub const MAX_SMOOTHNESS: f64 = 1e6;

/// Most iterations the solve may be given (`solver.max_iterations`): twenty times the default
/// 50, which the solve rarely uses up; each iteration costs a factorization of the part's
/// normal equations, so the cap bounds a run's solve at 1,000 of them.
pub const MAX_SOLVER_ITERATIONS: usize = 1_000;

/// Largest `solver.constraints.turning_radius.radius`: 10⁹ scene units (1000 km in mm). The
/// hinge divides the streamlines' curvature by the bound 1/R, so a radius far beyond any part
/// only turns the hinge's residuals into infinity.
pub const MAX_TURNING_RADIUS: f64 = 1e9;

/// Largest brush radius (and curve width) of an edit: 10⁹ scene units (1000 km in mm), as
/// [`MAX_TURNING_RADIUS`]. A brush far larger than any part holds the whole part and its
/// weights (a Gaussian of the distance over the radius) are all 1; 1e30 was accepted by the
/// scene and the editor alike.
pub const MAX_EDIT_RADIUS: f64 = 1e9;

/// Largest weight of an edit (`weight`, `outside_weight`, …): 10⁶, as
/// [`MAX_SMOOTHNESS`]. Weights are relative to the smoothness term; at 10³⁰⁸ the solve's
/// energy overflowed and failed as a "numerical failure" naming no key.
pub const MAX_EDIT_WEIGHT: f64 = 1e6;

/// Longest output path a scene may give: 4096 bytes (Linux's `PATH_MAX`). A longer one is
/// refused naming its key, and echoed shortened ([`crate::error::shorten`]).
pub const MAX_OUTPUT_PATH_BYTES: usize = 4096;

/// Most lights a scene may have: 64. Every light is evaluated at every preview sample (an
/// environment light at `samples` directions), so 10⁴ lights keep a render busy for minutes.
pub const MAX_LIGHTS: usize = 64;

/// Most points one curve edit may hold (`uv` or `points` inline, or an SVG's flattened paths):
/// 10⁵. Each point's segment is searched against the part, so 10⁶ points take tens of seconds
/// and hundreds of MB.
pub const MAX_CURVE_POINTS: usize = 100_000;

/// Largest scene file: 64 MiB (a curve edit of [`MAX_CURVE_POINTS`] inline points is about
/// 5 MB). Checked from the file's metadata before it is read, with the file's type (a FIFO,
/// a device or a directory is refused unread).
pub const MAX_SCENE_BYTES: u64 = 64 << 20;

/// Largest SVG file (an outline or a curve edit's drawing): 64 MiB, checked as
/// [`MAX_SCENE_BYTES`].
pub const MAX_SVG_BYTES: u64 = 64 << 20;

/// Most edits a scene may list: 1000. Each edit costs work over its support and the solve
/// grows with them (1000 bends took 4 s, 10⁴ over 30 s); refused with the scene, before the
/// part is loaded.
pub const MAX_EDITS: usize = 1000;

/// Most samples the fidelity figures take along one curve edit: 10⁵. The curve is sampled
/// every `FidelityOptions::sample_spacing` (0.01) × its radius, or more sparsely when that would give more
/// (each sample searches the solved highlight's segments around it: a zigzag of 2,000 points
/// spent most of a 24 s run there).
pub const MAX_FIDELITY_SAMPLES: usize = 100_000;

/// `--threads` is capped at this many worker threads per available core.
pub const THREADS_PER_CORE: usize = 4;

/// The number of worker threads used for a `--threads` request: at least 1, at most
/// [`THREADS_PER_CORE`] × the available cores (results never depend on the count; more threads
/// than that only cost memory and scheduling). Returns the count and whether it was capped.
pub fn worker_threads(requested: usize, available_cores: usize) -> (usize, bool) {
    let cap = THREADS_PER_CORE * available_cores.max(1);
    (requested.clamp(1, cap), requested > cap)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn item12_threads_are_capped_at_four_per_core() {
        assert_eq!(worker_threads(100_000, 2), (8, true));
        assert_eq!(worker_threads(8, 2), (8, false));
        assert_eq!(worker_threads(0, 2), (1, false));
        assert_eq!(worker_threads(3, 0), (3, false));
    }

    #[test]
    fn file_counts_fit_u32_indices() {
        // Every corner and every vertex needs a u32 index; half-edges need 3·F < u32::MAX.
        assert!(MAX_FILE_VERTICES < u32::MAX as usize);
        assert!(3 * MAX_FILE_TRIANGLES < u32::MAX as usize);
    }

    #[test]
    fn coordinate_bound_keeps_the_cross_product_finite() {
        // The worst case of the bound's derivation: 192·B⁴ is finite, and so at 10·B it is not.
        let b = MAX_COORDINATE;
        assert!((192.0 * b * b * b * b).is_finite());
        let b10 = 10.0 * b;
        assert!(!(192.0 * b10 * b10 * b10 * b10 * 1e6).is_finite());
    }
}
