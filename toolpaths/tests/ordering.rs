//! Orientation, ordering and lead geometry.

mod common;

use common::{field_mesh, rect_mesh};
use grainline_toolpaths::*;

fn wavy() -> Domain {
    let mesh = field_mesh(rect_mesh(40.0, 20.0, 40, 20), Symmetry::Line, |p| {
        let a = 0.5 * (p[0] / 6.0).sin() + 0.3;
        [a.cos(), a.sin()]
    });
    Domain::new(mesh).unwrap()
}

fn chord(p: &Pass) -> Vec2 {
    let a = p.uv[0][0];
    let l = p.uv.last().unwrap();
    let b = l[l.len() - 1];
    [b[0] - a[0], b[1] - a[1]]
}

/// `along`/`against` give every stroke one global direction and are kept by the orderer;
/// ordering beats the placement order; `alternate` may flip and is no longer than `along`.
#[test]
fn orientation_is_global_and_ordering_shortens_travel() {
    let dom = wavy();
    let pl = place_strokes(&dom, &PlacementOptions::new(1.0, 0.0)).unwrap();
    let along = plan_toolpath(&dom, &pl, &PlanOptions::default()).unwrap();
    assert!(along.passes.iter().all(|p| chord(p)[0] > 0.0), "a stroke runs against +U");
    let against = plan_toolpath(
        &dom,
        &pl,
        &PlanOptions { direction: Direction::Against, ..Default::default() },
    )
    .unwrap();
    assert!(against.passes.iter().all(|p| chord(p)[0] < 0.0));
    // Travel of the strokes in placement order, same orientation, from home.
    let ends: Vec<Ends> = {
        let mut by_stroke: Vec<&Pass> = along.passes.iter().collect();
        by_stroke.sort_by_key(|p| p.stroke);
        by_stroke
            .iter()
            .map(|p| {
                let l = p.uv.last().unwrap();
                Ends::open(p.uv[0][0], l[l.len() - 1])
            })
            .collect()
    };
    let identity: Vec<usize> = (0..ends.len()).collect();
    let unordered = tour_length(&ends, &identity, &vec![false; ends.len()], [0.0, 0.0]);
    assert!(along.travel < 0.9 * unordered, "{} vs {unordered}", along.travel);
    let alt = plan_toolpath(
        &dom,
        &pl,
        &PlanOptions { direction: Direction::Alternate, ..Default::default() },
    )
    .unwrap();
    assert!(alt.travel < along.travel);
    assert!(alt.passes.iter().any(|p| chord(p)[0] < 0.0), "alternate never flipped");
}

/// Lead-in starts `lead_in + overtravel` before the stroke along its tangent, `ramp_height`
/// above the cutting depth; lead-out mirrors it at the end. The overtravel is the plan's
/// (strokes placed without run-outs), or the strokes' run-outs (one width) when longer.
#[test]
fn leads_and_overtravel_geometry() {
    let mesh = field_mesh(rect_mesh(10.0, 6.0, 10, 6), Symmetry::Vector, |_| [0.0, 1.0]);
    let dom = Domain::new(mesh).unwrap();
    let bare = PlacementOptions { overtravel: Some(0.0), ..PlacementOptions::new(2.0, 0.0) };
    leads_and_overtravel(&dom, &place_strokes(&dom, &bare).unwrap(), 0.5);
    leads_and_overtravel(
        &dom,
        &place_strokes(&dom, &PlacementOptions::new(2.0, 0.0)).unwrap(),
        2.0,
    );
}

fn leads_and_overtravel(dom: &Domain, pl: &Placement, over: f64) {
    let o = PlanOptions {
        contact_depth: 0.25,
        lead_in: 2.0,
        lead_out: 3.0,
        ramp_height: 1.0,
        overtravel: 0.5,
        z_mode: ZMode::Flat { surface_z: 10.0 },
        ..Default::default()
    };
    let plan = plan_toolpath(dom, pl, &o).unwrap();
    assert!(!plan.passes.is_empty());
    for p in &plan.passes {
        let x = p.uv[0][0][0];
        // Strokes run +V from v = 0 to v = 6.
        let close = |a: Vec3, b: Vec3| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9);
        assert!(close(p.start, [x, -2.0 - over, 10.75]), "{:?}", p.start);
        let kinds: Vec<MoveKind> = p.moves.iter().map(|m| m.0).collect();
        assert_eq!(kinds.first(), Some(&MoveKind::LeadIn));
        assert_eq!(kinds.last(), Some(&MoveKind::LeadOut));
        assert!(close(p.moves[0].1.end(), [x, -over, 9.75]));
        assert!(close(p.moves.last().unwrap().1.end(), [x, 9.0 + over, 10.75]));
        for (k, m) in &p.moves {
            if *k == MoveKind::Cut {
                assert_eq!(m.end()[2], 9.75);
            }
        }
    }
}

fn dist(a: Vec2, b: Vec2) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Travel of an ordering recomputed from its order, flips and loop entries (from `home`
/// when given, else between strokes only).
fn travel_of(e: &[Ends], o: &Ordering, home: Option<Vec2>) -> f64 {
    let mut pos = home;
    let mut t = 0.0;
    for &s in &o.order {
        let (a, b) = match o.entry[s] {
            Some(v) => (e[s].ring[v], e[s].ring[v]),
            None if o.flipped[s] => (e[s].end, e[s].start),
            None => (e[s].start, e[s].end),
        };
        if let Some(p) = pos {
            t += dist(p, a);
        }
        pos = Some(b);
    }
    t
}

/// All orders (and loop entry vertices) of a few strokes: the exact optimum.
fn brute_force(e: &[Ends], home: Option<Vec2>) -> f64 {
    fn rec(e: &[Ends], used: &mut Vec<bool>, pos: Option<Vec2>, acc: f64, best: &mut f64) {
        if used.iter().all(|&u| u) {
            *best = best.min(acc);
            return;
        }
        for s in 0..e.len() {
            if used[s] {
                continue;
            }
            used[s] = true;
            let ways: Vec<(Vec2, Vec2)> = if e[s].ring.is_empty() {
                vec![(e[s].start, e[s].end)]
            } else {
                e[s].ring.iter().map(|&p| (p, p)).collect()
            };
            for (a, b) in ways {
                let step = pos.map_or(0.0, |p| dist(p, a));
                rec(e, used, Some(b), acc + step, best);
            }
            used[s] = false;
        }
    }
    let mut best = f64::INFINITY;
    rec(e, &mut vec![false; e.len()], home, 0.0, &mut best);
    best
}

/// Hand case: ends (1, 0) and (1, 2) both lie √2 from the start (2, 1) of the third stroke,
/// whose end (3, 1) is √10 from either other start. The nearest bound counts √2 twice
/// (2√2 after dropping the largest term, √10); the assignment must send one of them
/// elsewhere: √2 + √5, which is the optimum (orders 0-1-2 and 1-0-2). From home (0, −1)
/// the optimum is 1 + √5 + √2 (order 0-1-2) and the assignment H→0, 0→1, 1→2, 2→Z is tight.
#[test]
fn travel_bound_hand_case() {
    let e = vec![
        Ends::open([0.0, 0.0], [1.0, 0.0]),
        Ends::open([0.0, 2.0], [1.0, 2.0]),
        Ends::open([2.0, 1.0], [3.0, 1.0]),
    ];
    let (r2, r5) = (2f64.sqrt(), 5f64.sqrt());
    let b = travel_bound(&e, &BoundOptions::default());
    assert!((b.nearest - 2.0 * r2).abs() < 1e-12, "{b:?}");
    assert!((b.assignment.unwrap() - (r2 + r5)).abs() < 1e-9, "{b:?}");
    assert!((brute_force(&e, None) - (r2 + r5)).abs() < 1e-12);
    let home = BoundOptions { home: Some([0.0, -1.0]), ..Default::default() };
    let b = travel_bound(&e, &home);
    assert!((b.nearest - (2.0 * r2 + 1.0)).abs() < 1e-12, "{b:?}");
    assert!((b.assignment.unwrap() - (1.0 + r2 + r5)).abs() < 1e-9, "{b:?}");
    // The orderer finds that optimum.
    let o = order_strokes(&e, false, &OrderOptions { home: [0.0, -1.0], ..Default::default() });
    assert!((o.travel - (1.0 + r2 + r5)).abs() < 1e-9, "{o:?}");
}

fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Random strokes, some of them closed loops: nearest ≤ assignment ≤ the brute-force optimum
/// ≤ the orderer's travel, with and without a home; small lists (2 candidates) must still
/// give a valid bound.
#[test]
fn travel_bound_is_below_the_optimum() {
    let mut rnd = lcg(7);
    for case in 0..40 {
        let n = 2 + case % 5;
        let e: Vec<Ends> = (0..n)
            .map(|s| {
                let p = [10.0 * rnd(), 10.0 * rnd()];
                if s % 3 == 2 {
                    Ends::ring((0..3).map(|k| [p[0] + k as f64, p[1] + rnd()]).collect())
                } else {
                    Ends::open(p, [p[0] + 8.0 * rnd() - 2.0, p[1] + 3.0 * rnd()])
                }
            })
            .collect();
        for home in [None, Some([rnd() * 10.0, -1.0])] {
            for k in [2, 12] {
                let b = travel_bound(&e, &BoundOptions { home, neighbours: k });
                let opt = brute_force(&e, home);
                let a = b.assignment.unwrap();
                if k == 12 {
                    // Complete lists: the assignment is exact (dual = primal) and so at
                    // least the nearest bound, a feasible dual of the same problem.
                    assert!((b.assignment_primal.unwrap() - a).abs() < 1e-9, "case {case}: {b:?}");
                    assert!(b.nearest <= a + 1e-9, "case {case}: {b:?}");
                }
                assert!(a <= opt + 1e-9, "case {case} k {k}: bound {a} > optimum {opt}");
                assert!(b.assignment_primal.unwrap() >= a - 1e-9);
            }
            let o = order_strokes(
                &e,
                false,
                &OrderOptions { home: home.unwrap_or([0.0, 0.0]), ..Default::default() },
            );
            let t = travel_of(&e, &o, home.or(Some([0.0, 0.0])));
            assert!((t - o.travel).abs() < 1e-9, "reported {} vs {t}", o.travel);
            assert!(o.travel >= brute_force(&e, Some(home.unwrap_or([0.0, 0.0]))) - 1e-9);
        }
    }
}

/// A larger random field of open strokes and loops, with and without flips: the order is a
/// permutation, the reported travel matches the order, fixed orientation is kept, local
/// search never loses to greedy, the bound is below, and the result is reproducible.
#[test]
fn local_search_is_consistent_on_random_strokes() {
    let mut rnd = lcg(99);
    let e: Vec<Ends> = (0..600)
        .map(|s| {
            let p = [100.0 * rnd(), 60.0 * rnd()];
            if s % 4 == 0 {
                let r = 0.5 + rnd();
                Ends::ring(
                    (0..12)
                        .map(|k| {
                            let t = k as f64 * std::f64::consts::PI / 6.0;
                            [p[0] + r * t.cos(), p[1] + r * t.sin()]
                        })
                        .collect(),
                )
            } else {
                let a = 0.4 * rnd();
                let l = 2.0 + 10.0 * rnd();
                Ends::open(p, [p[0] + l * a.cos(), p[1] + l * a.sin()])
            }
        })
        .collect();
    for flip in [false, true] {
        let opts = OrderOptions::default();
        let o = order_strokes(&e, flip, &opts);
        let mut seen = o.order.clone();
        seen.sort();
        assert_eq!(seen, (0..e.len()).collect::<Vec<_>>());
        assert!((travel_of(&e, &o, Some(opts.home)) - o.travel).abs() < 1e-6);
        assert!(o.travel <= o.travel_greedy + 1e-9);
        assert!(o.travel < 0.9 * o.travel_greedy, "{} vs greedy {}", o.travel, o.travel_greedy);
        if !flip {
            assert!(o.flipped.iter().all(|&f| !f));
            let b = travel_bound(&e, &BoundOptions { home: Some(opts.home), neighbours: 12 });
            assert!(b.assignment.unwrap() <= o.travel + 1e-9);
        }
        assert_eq!(o, order_strokes(&e, flip, &opts));
    }
}
