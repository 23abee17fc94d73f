//! Pairing a design's singular faces, so that each pair can be turned away in a tube around the
//! path that joins it (a tube around a pair of opposite charges has no net winding on its rim,
//! a grown ring around a lone charge has).
//!
//! Each face carries a charge, its index less the field's before the edits (in units of 1/k).
//! Greedily, nearest first: from every positive unit charge a breadth-first search over the
//! region's vertices (at most [`MAX_VISITS`] visits in all) finds the negative ones, and the pairs
//! are taken by increasing distance (ties by the faces' order), each charge once. A pair's path
//! is the search's shortest path between the two faces' corners.

use super::Context;

/// Vertex visits of all the searches together, at most: the work of pairing is bounded
/// whatever the number of charges (those not reached stay unpaired).
pub const MAX_VISITS: usize = 20_000_000;

/// Unit charges beyond which no pairing is tried (the work is charges × a search).
pub const MAX_CHARGES: usize = 4096;

/// The vertices of the path joining each pair of opposite charges among `faces` (charges
/// `charge(f)`), the two faces' corners included; pairs nearest first.
pub(super) fn pair_paths(
    ctx: &Context,
    region: &[bool],
    faces: &[usize],
    charge: impl Fn(usize) -> i32,
) -> Vec<Vec<u32>> {
    let mut pos = Vec::new();
    let mut neg = Vec::new();
    for &f in faces {
        let q = charge(f);
        let list = if q > 0 { &mut pos } else { &mut neg };
        list.extend(std::iter::repeat_n(f, q.unsigned_abs() as usize));
    }
    if pos.is_empty() || neg.is_empty() || pos.len() + neg.len() > MAX_CHARGES {
        return Vec::new();
    }
    // Every (positive, negative) pair a search reached, with its distance and path (a charge's
    // partner may have to be far: a part holding one unpaired charge has no bounded turn).
    let mut candidates: Vec<(usize, usize, usize, Vec<u32>)> = Vec::new();
    let mut budget = MAX_VISITS;
    let mut searched: Vec<usize> = pos.clone();
    searched.dedup();
    for &p in &searched {
        for (d, n, path) in search(ctx, region, p, &neg, &mut budget) {
            candidates.push((d, p, n, path));
        }
    }
    candidates.sort_by_key(|a| (a.0, a.1, a.2));
    let mut left_pos = counts(&pos);
    let mut left_neg = counts(&neg);
    let mut out = Vec::new();
    for (_, p, n, path) in candidates {
        let (Some(a), Some(b)) = (left_pos.get_mut(&p), left_neg.get_mut(&n)) else { continue };
        let take = (*a).min(*b);
        if take == 0 {
            continue;
        }
        *a -= take;
        *b -= take;
        out.push(path);
    }
    out
}

/// Unit charges per face.
fn counts(faces: &[usize]) -> std::collections::BTreeMap<usize, usize> {
    let mut m = std::collections::BTreeMap::new();
    for &f in faces {
        *m.entry(f).or_insert(0) += 1;
    }
    m
}

/// From face `from`'s corners, breadth first over `region`: every face of `targets` met (while
/// the `budget` of visits lasts), with its distance and the path to it.
fn search(
    ctx: &Context,
    region: &[bool],
    from: usize,
    targets: &[usize],
    budget: &mut usize,
) -> Vec<(usize, usize, Vec<u32>)> {
    let adj = &ctx.geom.adjacency;
    let mut parent: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    let mut front: Vec<u32> = ctx.mesh.faces[from].to_vec();
    for &v in &front {
        parent.insert(v, v);
    }
    let mut found = Vec::new();
    let mut wanted: Vec<usize> = targets.to_vec();
    wanted.sort_unstable();
    wanted.dedup();
    for d in 0.. {
        wanted.retain(|&f| {
            let Some(&hit) = ctx.mesh.faces[f].iter().find(|v| parent.contains_key(v)) else {
                return true;
            };
            let mut path: Vec<u32> = ctx.mesh.faces[f].to_vec();
            let mut v = hit;
            while parent[&v] != v {
                path.push(v);
                v = parent[&v];
            }
            path.extend_from_slice(&ctx.mesh.faces[from]);
            found.push((d, f, path));
            false
        });
        if wanted.is_empty() {
            break;
        }
        let mut next = Vec::new();
        for &v in &front {
            for &w in adj.neighbors(v as usize) {
                if region[w as usize] && *budget > 0 && !parent.contains_key(&w) {
                    *budget -= 1;
                    parent.insert(w, v);
                    next.push(w);
                }
            }
        }
        if next.is_empty() {
            break;
        }
        front = next;
    }
    found
}
