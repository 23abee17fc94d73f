//! Welding coincident positions (`--weld TOL`).
//!
//! Two vertices are welded when their distance is at most `tol`; welding is transitive (a chain
//! of close pairs forms one cluster). Every cluster is represented by its vertex that comes
//! first in the file, so the order of the surviving vertices is the file order and a welded
//! vertex maps to the first occurrence of its cluster.
//!
//! Candidates are found on a grid of cell size `tol`: a vertex is compared with the vertices
//! of the 27 cells around its own. With `tol == 0` only identical positions weld (bit-identical
//! coordinates, −0 counting as +0).

use nalgebra::Vector3;
use rayon::prelude::*;

use super::union_find::UnionFind;

/// For every vertex, the vertex it welds to (itself if it survives). Only vertices with
/// `used[i]` take part; the others map to themselves.
pub fn weld_map(pos: &[Vector3<f64>], used: &[bool], tol: f64) -> Vec<u32> {
    let ids: Vec<u32> = (0..pos.len() as u32).filter(|&i| used[i as usize]).collect();
    let cell = if tol > 0.0 { tol } else { 1.0 };
    let key = |p: &Vector3<f64>| -> [i64; 3] {
        if tol > 0.0 {
            [0, 1, 2].map(|k| (p[k] / cell).floor() as i64)
        } else {
            // −0 + 0 = +0: the two zeros are one position (distance 0).
            [0, 1, 2].map(|k| (p[k] + 0.0).to_bits() as i64)
        }
    };
    let mut keyed: Vec<([i64; 3], u32)> =
        ids.par_iter().map(|&i| (key(&pos[i as usize]), i)).collect();
    keyed.par_sort_unstable();
    let pairs: Vec<(u32, u32)> = if tol > 0.0 {
        near_pairs(pos, &keyed, tol)
    } else {
        keyed.windows(2).filter(|w| w[0].0 == w[1].0).map(|w| (w[0].1, w[1].1)).collect()
    };
    let mut uf = UnionFind::new(pos.len());
    for (a, b) in pairs {
        uf.union(a, b);
    }
    (0..pos.len() as u32).map(|i| uf.find(i)).collect()
}

/// Pairs `(a, b)`, `a < b`, at distance at most `tol`, from the sorted cell keys.
fn near_pairs(pos: &[Vector3<f64>], keyed: &[([i64; 3], u32)], tol: f64) -> Vec<(u32, u32)> {
    let tol2 = tol * tol;
    keyed
        .par_iter()
        .flat_map_iter(|&(k, a)| {
            let pa = pos[a as usize];
            let mut found = Vec::new();
            for dx in -1..=1i64 {
                for dy in -1..=1i64 {
                    for dz in -1..=1i64 {
                        let nk = [
                            k[0].saturating_add(dx),
                            k[1].saturating_add(dy),
                            k[2].saturating_add(dz),
                        ];
                        let lo = keyed.partition_point(|e| e.0 < nk);
                        for &(ek, b) in &keyed[lo..] {
                            if ek != nk {
                                break;
                            }
                            if a < b && (pos[b as usize] - pa).norm_squared() <= tol2 {
                                found.push((a, b));
                            }
                        }
                    }
                }
            }
            found
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chain_welds_to_first() {
        let pos = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(5.0, 0.0, 0.0),
            Vector3::new(0.05, 0.0, 0.0),
            Vector3::new(0.1, 0.0, 0.0),
        ];
        let map = weld_map(&pos, &[true; 4], 0.06);
        assert_eq!(map, vec![0, 1, 0, 0]);
        let exact = weld_map(&pos, &[true; 4], 0.0);
        assert_eq!(exact, vec![0, 1, 2, 3]);
        // −0 and +0 are at distance 0: they weld at tolerance 0.
        let zeros = vec![Vector3::new(0.0, -0.0, 1.0), Vector3::new(-0.0, 0.0, 1.0)];
        assert_eq!(weld_map(&zeros, &[true; 2], 0.0), vec![0, 0]);
    }
}
