//! k-ring neighbourhoods gathered from the adjacency.

use crate::mesh::Adjacency;

/// A ring grown past the 1-ring does not pass through a vertex of more than this many
/// neighbours (docs/math.md §5.6, "Bounded rings"): the vertices of a fan's rim would otherwise
/// each gather all of the hub's neighbours, n² work for a fan or polygon of n triangles.
pub const MAX_RING_VALENCE: usize = 128;

/// A ring grown past the 1-ring stops at this many vertices (or at the 1-ring's size, if that
/// is larger), taking each new depth's vertices by increasing index.
pub const MAX_RING_POINTS: usize = 512;

/// Fills `out` with the vertices at graph distance 1..=`depth` from `i` (not `i` itself), sorted
/// by index. `scratch` is reused between calls to avoid allocation.
///
/// Bounded (docs/math.md §5.6): past the 1-ring, a vertex of more than [`MAX_RING_VALENCE`]
/// neighbours is not passed through, and the ring stops at [`MAX_RING_POINTS`] vertices (or the
/// 1-ring's size). On a mesh without such vertices this is the plain k-ring.
pub fn gather_ring(
    adj: &Adjacency,
    i: usize,
    depth: usize,
    out: &mut Vec<u32>,
    scratch: &mut Vec<u32>,
) {
    out.clear();
    out.extend_from_slice(adj.neighbors(i));
    let cap = MAX_RING_POINTS.max(out.len());
    let mut frontier_start = 0;
    for _ in 1..depth {
        let frontier_end = out.len();
        scratch.clear();
        for &v in &out[frontier_start..frontier_end] {
            let around = adj.neighbors(v as usize);
            if around.len() <= MAX_RING_VALENCE {
                scratch.extend_from_slice(around);
            }
        }
        frontier_start = frontier_end;
        scratch.sort_unstable();
        scratch.dedup();
        let mut known = out.clone();
        known.sort_unstable();
        for &v in scratch.iter() {
            if out.len() >= cap {
                break;
            }
            if v as usize != i && known.binary_search(&v).is_err() {
                out.push(v);
            }
        }
    }
    out.sort_unstable();
}
