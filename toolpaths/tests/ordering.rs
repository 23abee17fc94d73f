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
/// above the cutting depth; lead-out mirrors it at the end.
#[test]
fn leads_and_overtravel_geometry() {
    let mesh = field_mesh(rect_mesh(10.0, 6.0, 10, 6), Symmetry::Vector, |_| [0.0, 1.0]);
    let dom = Domain::new(mesh).unwrap();
    let pl = place_strokes(&dom, &PlacementOptions::new(2.0, 0.0)).unwrap();
    let o = PlanOptions {
        contact_depth: 0.25,
        lead_in: 2.0,
        lead_out: 3.0,
        ramp_height: 1.0,
        overtravel: 0.5,
        z_mode: ZMode::Flat { surface_z: 10.0 },
        ..Default::default()
    };
    let plan = plan_toolpath(&dom, &pl, &o).unwrap();
    for p in &plan.passes {
        let x = p.uv[0][0][0];
        // Strokes run +V from v = 0 to v = 6.
        let close = |a: Vec3, b: Vec3| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9);
        assert!(close(p.start, [x, -2.5, 10.75]), "{:?}", p.start);
        let kinds: Vec<MoveKind> = p.moves.iter().map(|m| m.0).collect();
        assert_eq!(kinds.first(), Some(&MoveKind::LeadIn));
        assert_eq!(kinds.last(), Some(&MoveKind::LeadOut));
        assert!(close(p.moves[0].1.end(), [x, -0.5, 9.75]));
        assert!(close(p.moves.last().unwrap().1.end(), [x, 9.5, 10.75]));
        for (k, m) in &p.moves {
            if *k == MoveKind::Cut {
                assert_eq!(m.end()[2], 9.75);
            }
        }
    }
}
