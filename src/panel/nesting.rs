//! The area a panel's loops enclose under the even-odd rule, in time about linear in the loops
//! (issue 46: testing every loop against every other took most of a `grainline panel` run on
//! 2 × 10⁴ separate rects).
//!
//! A loop's sign is the parity of its nesting depth, the number of other loops holding its
//! first point (the loops neither cross nor touch: `check_loops`), found by ray casting: the
//! edges `a → b` of a loop crossed by the horizontal ray to the right of `p`,
//!
//! ```text
//! (a.y > p.y) ≠ (b.y > p.y)  and  p.x < a.x + (p.y − a.y) / (b.y − a.y) · (b.x − a.x),
//! ```
//!
//! are odd in number exactly when `p` is inside. Two indexes keep the work near the point:
//!
//! * the loops' bounding boxes in a uniform grid, so that `p` is tested against the loops whose
//!   box holds it only. Outside a box the count is even whatever the rounding: below or above
//!   it no edge straddles `p.y`; to its right (by more than the margin below) none is crossed;
//!   to its left every straddling edge is, and a closed loop has an even number of those;
//! * a long loop's edges in slabs of y, so that the ray meets only the edges of its slab (an
//!   edge is listed in every slab its y range meets; slabs and cells are found by monotone
//!   functions of the coordinates, so no edge that straddles `p.y` is missed).
//!
//! Every count that can be odd is made with the same predicate as testing every pair, so the
//! area is that one bit for bit. The work is the loops, their edges, and for each loop the
//! boxes holding its first point (its depth, plus boxes that hold it without the loop): linear
//! for separate loops, a hole in each and islands in those.

use super::{signed_area, Loop};

/// Loops with at most this many points are tested edge by edge, without slabs.
const DIRECT_POINTS: usize = 32;

/// The margin by which a box is grown along x, relative to its largest |x| (+ 1 mm): it covers
/// the rounding of the crossing's abscissa `a.x + t · (b.x − a.x)`, t ∈ [0, 1], a few units in
/// the last place (2⁻⁵² relative each).
const X_MARGIN: f64 = 1e-9;

/// Area enclosed by the loops under the even-odd rule (holes subtract, islands add): each
/// loop's |area| with the sign of its nesting depth's parity (module docs).
pub fn even_odd_area(loops: &[Loop]) -> f64 {
    let boxes: Vec<Box2> = loops.iter().map(|l| Box2::of(&l.points)).collect();
    let grid = BoxGrid::new(&boxes);
    let slabs: Vec<Option<Slabs>> = loops
        .iter()
        .zip(&boxes)
        .map(|(l, b)| (l.points.len() > DIRECT_POINTS).then(|| Slabs::new(&l.points, b)))
        .collect();
    loops
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let p = l.points[0];
            let odd = grid
                .candidates(p)
                .iter()
                .map(|&j| j as usize)
                .filter(|&j| j != i && boxes[j].holds(p))
                .filter(|&j| match &slabs[j] {
                    Some(s) => s.inside(p, &loops[j].points),
                    None => inside(p, &loops[j].points),
                })
                .count()
                % 2
                == 1;
            let a = signed_area(&l.points).abs();
            if odd {
                -a
            } else {
                a
            }
        })
        .sum()
}

/// Whether the edge `a → b` crosses the horizontal ray to the right of `p` (module docs).
fn crosses(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    (a[1] > p[1]) != (b[1] > p[1]) && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
}

/// Whether `p` is inside `poly`: an odd number of its edges cross the ray.
fn inside(p: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let n = poly.len();
    (0..n).filter(|&i| crosses(p, poly[i], poly[(i + 1) % n])).count() % 2 == 1
}

/// A loop's bounding box, grown along x by the margin ([`X_MARGIN`]).
#[derive(Clone, Copy, Debug)]
struct Box2 {
    lo: [f64; 2],
    hi: [f64; 2],
}

impl Box2 {
    fn of(points: &[[f64; 2]]) -> Box2 {
        let mut b = Box2 { lo: [f64::INFINITY; 2], hi: [f64::NEG_INFINITY; 2] };
        for p in points {
            b.lo = [b.lo[0].min(p[0]), b.lo[1].min(p[1])];
            b.hi = [b.hi[0].max(p[0]), b.hi[1].max(p[1])];
        }
        let m = X_MARGIN * (1.0 + b.lo[0].abs().max(b.hi[0].abs()));
        b.lo[0] -= m;
        b.hi[0] += m;
        b
    }

    /// Whether the ray from `p` can cross the loop an odd number of times.
    fn holds(&self, p: [f64; 2]) -> bool {
        (0..2).all(|k| self.lo[k] <= p[k] && p[k] <= self.hi[k])
    }
}

/// The cell of `x` in `count` cells of size `cell` from `origin`: monotone in `x`.
fn cell_of(x: f64, origin: f64, cell: f64, count: usize) -> usize {
    let c = ((x - origin) / cell).floor();
    if c >= 0.0 {
        (c as usize).min(count - 1)
    } else {
        0
    }
}

/// The loops' boxes in a uniform grid: each box listed in every cell it meets (compressed rows).
struct BoxGrid {
    origin: [f64; 2],
    cell: f64,
    size: [usize; 2],
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl BoxGrid {
    /// Cells of about the mean box's size across the boxes' union (no more cells than 3 × the
    /// boxes + 1), doubled until the boxes meet at most 8 cells each on average.
    fn new(boxes: &[Box2]) -> BoxGrid {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for b in boxes {
            for k in 0..2 {
                lo[k] = lo[k].min(b.lo[k]);
                hi[k] = hi[k].max(b.hi[k]);
            }
        }
        let n = boxes.len().max(1) as f64;
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        let mut cell = (w * h / n).sqrt().max(w / n).max(h / n);
        let met = |b: &Box2, cell: f64| {
            let span = |k: usize| {
                ((b.hi[k] - lo[k]) / cell).floor() - ((b.lo[k] - lo[k]) / cell).floor() + 1.0
            };
            span(0) * span(1)
        };
        while cell.is_finite()
            && cell > 0.0
            && boxes.iter().map(|b| met(b, cell)).sum::<f64>() > 8.0 * n
        {
            cell *= 2.0;
        }
        if !(cell.is_finite() && cell > 0.0) {
            cell = f64::MAX;
        }
        let size =
            [0, 1].map(|k| ((hi[k] - lo[k]) / cell).floor().clamp(0.0, n * 3.0) as usize + 1);
        let mut grid = BoxGrid { origin: lo, cell, size, starts: Vec::new(), items: Vec::new() };
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); size[0] * size[1]];
        for (j, b) in boxes.iter().enumerate() {
            let (x0, y0) = grid.key(b.lo);
            let (x1, y1) = grid.key(b.hi);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    lists[y * size[0] + x].push(j as u32);
                }
            }
        }
        grid.starts.push(0);
        for l in lists {
            grid.items.extend(l);
            grid.starts.push(grid.items.len() as u32);
        }
        grid
    }

    fn key(&self, p: [f64; 2]) -> (usize, usize) {
        let c = |k: usize| cell_of(p[k], self.origin[k], self.cell, self.size[k]);
        (c(0), c(1))
    }

    /// The loops whose box meets the cell of `p` (every box that holds `p` among them).
    fn candidates(&self, p: [f64; 2]) -> &[u32] {
        let (x, y) = self.key(p);
        let c = y * self.size[0] + x;
        &self.items[self.starts[c] as usize..self.starts[c + 1] as usize]
    }
}

/// A loop's edges (edge `k` runs from point `k` to point `k + 1`) listed by slabs of y.
struct Slabs {
    y0: f64,
    height: f64,
    count: usize,
    starts: Vec<u32>,
    edges: Vec<u32>,
}

impl Slabs {
    /// Slabs of equal height over the loop's box, as many as the edges times the box's height
    /// over the edges' total rise (at most one per edge): an edge of rise `r` meets at most
    /// `r / height + 2` slabs, so at most 3 entries per edge in all.
    fn new(points: &[[f64; 2]], b: &Box2) -> Slabs {
        let n = points.len();
        let edge = |k: usize| (points[k], points[(k + 1) % n]);
        let rise: f64 = (0..n).map(|k| (edge(k).1[1] - edge(k).0[1]).abs()).sum();
        let span = b.hi[1] - b.lo[1];
        let count = ((n as f64 * span / rise).ceil().clamp(1.0, n as f64)) as usize;
        let height = if span > 0.0 { span / count as f64 } else { 1.0 };
        let mut s = Slabs { y0: b.lo[1], height, count, starts: Vec::new(), edges: Vec::new() };
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); count];
        for k in 0..n {
            let (a, c) = edge(k);
            let (first, last) = (s.slab(a[1].min(c[1])), s.slab(a[1].max(c[1])));
            for list in &mut lists[first..=last] {
                list.push(k as u32);
            }
        }
        s.starts.push(0);
        for l in lists {
            s.edges.extend(l);
            s.starts.push(s.edges.len() as u32);
        }
        s
    }

    fn slab(&self, y: f64) -> usize {
        cell_of(y, self.y0, self.height, self.count)
    }

    /// [`inside`] over the edges of `p`'s slab (all that can straddle `p.y`).
    fn inside(&self, p: [f64; 2], poly: &[[f64; 2]]) -> bool {
        let n = poly.len();
        let s = self.slab(p[1]);
        let edges = &self.edges[self.starts[s] as usize..self.starts[s + 1] as usize];
        edges.iter().filter(|&&k| crosses(p, poly[k as usize], poly[(k as usize + 1) % n])).count()
            % 2
            == 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(c: [f64; 2], r: f64, points_per_side: usize) -> Loop {
        let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
        let mut points = Vec::new();
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            for s in 0..points_per_side {
                let t = s as f64 / points_per_side as f64;
                let q = [0, 1].map(|i| c[i] + r * (a[i] + t * (b[i] - a[i])));
                points.push(q);
            }
        }
        Loop { points, element: String::new(), line: 0 }
    }

    /// Every pair tested, as before the indexes.
    fn brute_force(loops: &[Loop]) -> f64 {
        loops
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let depth = (0..loops.len())
                    .filter(|&j| j != i && inside(l.points[0], &loops[j].points))
                    .count();
                let a = signed_area(&l.points).abs();
                if depth % 2 == 0 {
                    a
                } else {
                    -a
                }
            })
            .sum()
    }

    #[test]
    fn nested_squares_give_the_pairwise_area_bit_for_bit() {
        // Rings of nested squares (long loops, with slabs, and short ones), with odd centres
        // so that no point lies on a cell or slab boundary by construction.
        let mut loops = Vec::new();
        for g in 0..30 {
            let c = [(g % 6) as f64 * 40.0 + 0.1 * g as f64, (g / 6) as f64 * 40.0 - 0.37];
            let depth = 1 + g % 5;
            for d in 0..depth {
                let per_side = if d % 2 == 0 { 20 } else { 2 };
                loops.push(square(c, 16.0 - 3.0 * d as f64, per_side));
            }
        }
        let want = brute_force(&loops);
        assert_eq!(even_odd_area(&loops).to_bits(), want.to_bits());
        // Depths 1..=5 alternate: squares of side 32, 26, 20, 14, 8 with signs + − + − +.
        let ring = |d: usize| (32.0 - 6.0 * d as f64).powi(2);
        let exact: f64 = (0..30)
            .map(|g| {
                (0..1 + g % 5).map(|d| if d % 2 == 0 { ring(d) } else { -ring(d) }).sum::<f64>()
            })
            .sum();
        assert!((want - exact).abs() <= 1e-9 * exact, "{want} {exact}");
    }

    #[test]
    fn rows_of_rects_with_holes_and_a_long_outline_give_the_pairwise_area() {
        // 200 rects of side ½ in one row (every first point's ray runs along its neighbours'
        // horizontal edges and through their corners), a hole in every third, all inside a
        // 512-point outline (dyadic: its area is exact); a second row outside it.
        let mut loops = vec![square([100.0, 0.5], 102.0, 128)];
        for row in [0.0, 300.0] {
            for k in 0..200 {
                let c = [k as f64 + 0.5, row + 0.5];
                loops.push(square(c, 0.25, 1));
                if k % 3 == 0 {
                    loops.push(square(c, 0.125, 1));
                }
            }
        }
        let want = brute_force(&loops);
        assert_eq!(even_odd_area(&loops).to_bits(), want.to_bits());
        // The row inside takes 200 · ¼ − 67 · ¹⁄₁₆ from the outline's 204², the row outside
        // adds as much back (every partial sum a multiple of ¹⁄₁₆: exact).
        assert_eq!(want, 204.0 * 204.0);
    }
}
