//! Ear clipping of a planar face's outline, the way CAD exporters triangulate flat faces: no
//! vertex is added, so every triangle spans the face from rim to rim and long slivers are the
//! rule, not the exception.
//!
//! * **Holes** are joined to the outer loop by a *bridge* (as earcut does): the shortest segment
//!   from a hole vertex to a vertex of the outer loop (holes already joined included) that
//!   crosses no edge, touches no other vertex and runs through the face's material (its
//!   midpoint has winding number 1). The loop then walks the outer loop to the bridge, once
//!   around the hole and back over the bridge: one weakly simple polygon whose two bridge
//!   vertices appear twice.
//! * **Ears**: vertex `b` with neighbours `a`, `c` is an ear when the turn is strictly
//!   counter-clockwise, `(b − a) × (c − b) > 0`, and no other vertex of the remaining polygon
//!   lies in the closed triangle `abc` (vertices at the same position as `a`, `b` or `c`, the
//!   bridge's second copies, are not counted). After clipping `b` the search resumes at `c`, so
//!   the next ear is `(a, c, d)`: the triangles fan out of one rim vertex for as long as it
//!   can see, which is what CAD tessellators produce.
//!
//! Cost: O(n²) per ear in the worst case, O(n³) per face; faces here have at most a few
//! hundred rim vertices.

use nalgebra::Vector2;

type P = Vector2<f64>;

/// z of the cross product `(b − a) × (c − a)`: twice the signed area of `abc`.
fn orient(a: P, b: P, c: P) -> f64 {
    (b - a).perp(&(c - a))
}

/// Twice the signed area of a closed polygon (positive when counter-clockwise).
pub(super) fn signed_area(pts: &[P], idx: &[usize]) -> f64 {
    let n = idx.len();
    (0..n).map(|i| pts[idx[i]].perp(&pts[idx[(i + 1) % n]])).sum()
}

/// Triangulates the face whose outer loop is `loops[0]` and whose holes are `loops[1..]`,
/// each a list of indices into `pts`. Loops may come in either orientation: the outer one is
/// made counter-clockwise and the holes clockwise. Returns counter-clockwise triangles as
/// index triples; n rim vertices and h holes give n + 2h − 2 triangles.
pub(super) fn triangulate(pts: &[P], loops: &[Vec<usize>]) -> Vec<[usize; 3]> {
    let mut outer = loops[0].clone();
    if signed_area(pts, &outer) < 0.0 {
        outer.reverse();
    }
    let mut holes: Vec<Vec<usize>> = loops[1..].to_vec();
    for h in &mut holes {
        if signed_area(pts, h) > 0.0 {
            h.reverse();
        }
    }
    // Holes farthest along +x first (earcut's order): earlier bridges never fence later holes.
    let max_x = |h: &Vec<usize>| h.iter().map(|&i| pts[i].x).fold(f64::MIN, f64::max);
    holes.sort_by(|a, b| max_x(b).total_cmp(&max_x(a)));
    while !holes.is_empty() {
        let hole = holes.remove(0);
        outer = bridge(pts, &outer, &hole, &holes);
    }
    clip_ears(pts, outer)
}

/// The outer loop with `hole` spliced in through the shortest admissible bridge.
fn bridge(pts: &[P], outer: &[usize], hole: &[usize], rest: &[Vec<usize>]) -> Vec<usize> {
    let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(hole.len() * outer.len());
    for (hi, &h) in hole.iter().enumerate() {
        for (oi, &o) in outer.iter().enumerate() {
            pairs.push(((pts[h] - pts[o]).norm_squared(), hi, oi));
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut loops: Vec<&[usize]> = vec![outer, hole];
    loops.extend(rest.iter().map(|h| h.as_slice()));
    let (_, hi, oi) = *pairs
        .iter()
        .find(|&&(_, hi, oi)| visible(pts, &loops, pts[hole[hi]], pts[outer[oi]]))
        .expect("a hole inside its face always sees a vertex of the outer loop");
    let mut merged = Vec::with_capacity(outer.len() + hole.len() + 2);
    merged.extend_from_slice(&outer[..=oi]);
    merged.extend((0..=hole.len()).map(|k| hole[(hi + k) % hole.len()]));
    merged.extend_from_slice(&outer[oi..]);
    merged
}

/// Whether the segment `p–q` is a bridge: it crosses no edge of `loops`, passes through no
/// vertex other than its ends, and its midpoint lies in the material (winding number 1 with
/// the outer loop counter-clockwise and the holes clockwise).
fn visible(pts: &[P], loops: &[&[usize]], p: P, q: P) -> bool {
    let len2 = (q - p).norm_squared();
    for l in loops {
        for k in 0..l.len() {
            let (a, b) = (pts[l[k]], pts[l[(k + 1) % l.len()]]);
            if a != p && a != q {
                // A vertex on the open segment.
                let t = (a - p).dot(&(q - p)) / len2;
                if t > 0.0 && t < 1.0 && orient(p, q, a).abs() <= 1e-12 * len2 {
                    return false;
                }
            }
            let touches = a == p || a == q || b == p || b == q;
            if !touches && crosses(p, q, a, b) {
                return false;
            }
        }
    }
    winding(pts, loops, (p + q) * 0.5) == 1
}

/// Whether the segments `p–q` and `a–b` cross at a point interior to both.
fn crosses(p: P, q: P, a: P, b: P) -> bool {
    let (d1, d2) = (orient(p, q, a), orient(p, q, b));
    let (d3, d4) = (orient(a, b, p), orient(a, b, q));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Winding number of the closed loops around `x`.
fn winding(pts: &[P], loops: &[&[usize]], x: P) -> i32 {
    let mut w = 0;
    for l in loops {
        for k in 0..l.len() {
            let (a, b) = (pts[l[k]], pts[l[(k + 1) % l.len()]]);
            if a.y <= x.y && b.y > x.y && orient(a, b, x) > 0.0 {
                w += 1;
            } else if a.y > x.y && b.y <= x.y && orient(a, b, x) < 0.0 {
                w -= 1;
            }
        }
    }
    w
}

/// Clips ears off the counter-clockwise (weakly simple) polygon `poly` until one triangle is
/// left. The search resumes after each clip at the clipped vertex's successor (fans, see the
/// module docs). A polygon with no strict ear left (only possible with collinear runs) gives
/// up its most convex vertex.
fn clip_ears(pts: &[P], mut poly: Vec<usize>) -> Vec<[usize; 3]> {
    let mut tris = Vec::with_capacity(poly.len().saturating_sub(2));
    let mut i = 0;
    let mut misses = 0;
    while poly.len() > 3 {
        let n = poly.len();
        let turn =
            |k: usize| orient(pts[poly[(k + n - 1) % n]], pts[poly[k]], pts[poly[(k + 1) % n]]);
        let forced = misses >= n;
        if forced {
            debug_assert!(false, "ear clipping found no ear in {n} vertices");
            i = (0..n).max_by(|&x, &y| turn(x).total_cmp(&turn(y))).unwrap_or(0);
        }
        let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
        if forced || is_ear(pts, &poly, a, b, c) {
            tris.push([a, b, c]);
            poly.remove(i);
            if i == poly.len() {
                i = 0;
            }
            misses = 0;
        } else {
            i = (i + 1) % n;
            misses += 1;
        }
    }
    tris.push([poly[0], poly[1], poly[2]]);
    tris
}

/// Whether `abc` (consecutive in `poly`) is an ear: a strict left turn with no other vertex of
/// `poly` in the closed triangle (copies of `a`, `b`, `c` excepted).
fn is_ear(pts: &[P], poly: &[usize], a: usize, b: usize, c: usize) -> bool {
    let (pa, pb, pc) = (pts[a], pts[b], pts[c]);
    if orient(pa, pb, pc) <= 0.0 {
        return false;
    }
    poly.iter().all(|&k| {
        let x = pts[k];
        if x == pa || x == pb || x == pc {
            return true;
        }
        !(orient(pa, pb, x) >= 0.0 && orient(pb, pc, x) >= 0.0 && orient(pc, pa, x) >= 0.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(pts: &[P], tris: &[[usize; 3]]) -> f64 {
        tris.iter().map(|t| 0.5 * orient(pts[t[0]], pts[t[1]], pts[t[2]])).sum()
    }

    #[test]
    fn a_convex_polygon_is_fanned_from_one_vertex() {
        let pts: Vec<P> = (0..12)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 12.0;
                P::new(a.cos(), a.sin())
            })
            .collect();
        let tris = triangulate(&pts, &[(0..12).collect()]);
        assert_eq!(tris.len(), 10);
        // Every triangle has the first clipped ear's apex (vertex 11) as a corner: a fan.
        assert!(tris.iter().all(|t| t.contains(&11)), "{tris:?}");
        assert!(
            (area(&pts, &tris) - 0.5 * signed_area(&pts, &(0..12).collect::<Vec<_>>())).abs()
                < 1e-12
        );
    }

    #[test]
    fn a_square_with_two_holes_is_bridged_and_covered_exactly() {
        let mut pts =
            vec![P::new(0.0, 0.0), P::new(10.0, 0.0), P::new(10.0, 6.0), P::new(0.0, 6.0)];
        let mut loops = vec![vec![0, 1, 2, 3]];
        for (cx, cy) in [(3.0, 3.0), (7.0, 3.0)] {
            let start = pts.len();
            for k in 0..8 {
                let a = std::f64::consts::TAU * k as f64 / 8.0;
                pts.push(P::new(cx + a.cos(), cy + a.sin()));
            }
            loops.push((start..start + 8).collect());
        }
        let tris = triangulate(&pts, &loops);
        assert_eq!(tris.len(), 4 + 16 + 4 - 2);
        let holes = 2.0 * 0.5 * signed_area(&pts, &loops[1]);
        assert!((area(&pts, &tris) - (60.0 - holes)).abs() < 1e-9);
        assert!(tris.iter().all(|t| orient(pts[t[0]], pts[t[1]], pts[t[2]]) > 0.0));
    }
}
