//! k-ring neighbourhoods gathered from the adjacency.

use crate::mesh::Adjacency;

/// Fills `out` with the vertices at graph distance 1..=`depth` from `i` (not `i` itself), sorted
/// by index. `scratch` is reused between calls to avoid allocation.
pub fn gather_ring(
    adj: &Adjacency,
    i: usize,
    depth: usize,
    out: &mut Vec<u32>,
    scratch: &mut Vec<u32>,
) {
    out.clear();
    out.extend_from_slice(adj.neighbors(i));
    let mut frontier_start = 0;
    for _ in 1..depth {
        let frontier_end = out.len();
        scratch.clear();
        for &v in &out[frontier_start..frontier_end] {
            scratch.extend_from_slice(adj.neighbors(v as usize));
        }
        frontier_start = frontier_end;
        scratch.sort_unstable();
        scratch.dedup();
        let mut known = out.clone();
        known.sort_unstable();
        for &v in scratch.iter() {
            if v as usize != i && known.binary_search(&v).is_err() {
                out.push(v);
            }
        }
    }
    out.sort_unstable();
}
