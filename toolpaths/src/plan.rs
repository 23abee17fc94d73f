//! From placed strokes to machine passes: orientation, machine coordinates (flat or
//! surface-following), tilt checks, simplification/arcs, ordering, lead-in/out and
//! overtravel.
//!
//! Machine coordinates:
//! * **Flat** — `X = u`, `Y = v`, `Z = surface_z − contact_depth` (UV is the sheet, mm).
//! * **Surface following** — `(X, Y, Z) = lift(u, v) − (0, 0, contact_depth)`: the part lies
//!   on the table in its own 3D coordinates and Z follows it along each stroke (3-axis).
//!   Strokes whose surface normal tilts more than `max_tilt_deg` from +Z are refused or
//!   skipped ([`TiltPolicy`]).
//! * **Rotary** — `(X, A, Z)`: the part turns about its axis on machine X, the tool stands at
//!   the surface's distance from the axis minus `contact_depth` ([`crate::rotary`]). The
//!   passes hold `[x, A in degrees, z]`, A unwrapped along each pass and between passes; the
//!   tilt is measured from the radial direction.
//!
//! A pass is: (lead-in ramp) → (overtravel before, if the stroke starts on the chart
//! boundary) → the stroke → (overtravel after) → (lead-out ramp). Overtravel (the larger of
//! `overtravel` and the stroke's run-out past the part's edge) continues the machine path
//! along its tangent, Z included (`passes.rs`, R1). Leads are tangent extensions in XY of
//! length `lead_in`/`lead_out`, rising `ramp_height` above the cutting Z at their free end, so
//! the tool touches down while moving.

use crate::error::{Result, ToolpathError};
use crate::geom::{cross, Vec2, Vec3};
use crate::locate::barycentric;
use crate::mesh::{Domain, Symmetry};
use crate::order::{order_strokes, Direction, Ends};
use crate::passes::{make_pass, Item};
pub use crate::passes::{MoveKind, Pass};
use crate::place::Placement;
pub use crate::plan_options::{PlanOptions, Sheets, TiltPolicy, ZMode};
use crate::rotary::{fit_axis, nearest_equivalent, unwrap_developed, AxisSpec, Fixture};
use crate::simplify::Segment;
use crate::trace::{StopReason, Stroke};

/// The ordered passes.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Passes in cutting order.
    pub passes: Vec<Pass>,
    /// Strokes left out because the surface tilts too far (stroke index, tilt in degrees).
    pub skipped_tilt: Vec<(usize, f64)>,
    /// XY travel between passes (plus from home to the first), mm.
    pub travel: f64,
    /// XY travel between passes only, mm.
    pub travel_between: f64,
    /// Travel after greedy ordering, before 2-opt, mm.
    pub travel_greedy: f64,
    /// Brush width, mm (for SVG stroke width).
    pub width: f64,
    /// Tool home (machine XY).
    pub home: Vec2,
    /// The simplification tolerance the passes were made with (`PlanOptions::tolerance`);
    /// LinuxCNC's `G64 P` path blending uses it.
    pub tolerance: f64,
    /// The rotary fixture when `z_mode` is `rotary` (the passes are then `[x, A°, z]` and
    /// `home` is `(X, A°)`); none otherwise.
    pub rotary: Option<Fixture>,
}

/// Most entry candidates offered to the orderer per closed loop.
const RING_POINTS: usize = 64;

/// Machine-point index of ring vertex `v` of a loop with `n` points (last = first).
fn ring_index(n: usize, v: usize) -> usize {
    let step = (n - 1).div_ceil(RING_POINTS).max(1);
    v * step
}

/// The orderer's view of an item: closed single-piece loops may be entered anywhere.
fn ends_of(it: &Item) -> Ends {
    let m = &it.machine;
    let xy = |p: &Vec3| [p[0], p[1]];
    let closed = it.stops[0] == StopReason::ClosedLoop && it.uv.len() == 1 && m.len() > 3;
    if closed {
        let step = (m.len() - 1).div_ceil(RING_POINTS).max(1);
        Ends::ring(m[..m.len() - 1].iter().step_by(step).map(xy).collect())
    } else {
        Ends::open(xy(&m[0]), xy(&m[m.len() - 1]))
    }
}

/// Start a closed loop at point `k` (the loop's last point repeats its first).
fn rotate_loop(it: &mut Item, k: usize) {
    if k == 0 || it.uv.len() != 1 {
        return;
    }
    fn rot<T: Copy>(v: &mut Vec<T>, k: usize) {
        v.pop();
        v.rotate_left(k);
        v.push(v[0]);
    }
    rot(&mut it.machine, k);
    rot(&mut it.uv[0], k);
    rot(&mut it.faces[0], k);
}

/// Whether a stroke should be reversed to satisfy `direction` (before ordering).
fn wants_reverse(sym: Symmetry, dir: Direction, s: &Stroke, reference: Vec2) -> bool {
    let along_reversed = match sym {
        Symmetry::Vector => false,
        Symmetry::Line => {
            let a = s.uv[0];
            let b = s.uv[s.uv.len() - 1];
            let chord = [b[0] - a[0], b[1] - a[1]];
            let len = (chord[0] * chord[0] + chord[1] * chord[1]).sqrt();
            if s.is_closed() || len < 1e-9 {
                signed_area(&s.uv) < 0.0
            } else {
                let dp = chord[0] * reference[0] + chord[1] * reference[1];
                if dp.abs() > 1e-12 * len {
                    dp < 0.0
                } else {
                    cross(reference, chord) < 0.0
                }
            }
        }
    };
    match dir {
        Direction::Along | Direction::Alternate => along_reversed,
        Direction::Against => !along_reversed,
    }
}

fn signed_area(p: &[Vec2]) -> f64 {
    let n = p.len();
    (0..n).map(|i| cross(p[i], p[(i + 1) % n])).sum::<f64>() * 0.5
}

/// The oriented items of a placement (one per stroke piece), the strokes skipped for tilt
/// and the rotary fixture.
type Items = (Vec<Item>, Vec<(usize, f64)>, Option<Fixture>);

/// The rotary fixture of `z_mode: rotary`: the given axis, or the one found from the lift.
fn fixture(dom: &Domain, opts: &PlanOptions) -> Result<Option<Fixture>> {
    let ZMode::Rotary { axis, .. } = opts.z_mode else { return Ok(None) };
    let (Some(points), Some(normals)) = (&dom.positions, &dom.spacing_normals) else {
        return Err(ToolpathError::MissingInput(
            "a rotary program needs per-vertex 3D positions in the field mesh",
        ));
    };
    let axis = match axis {
        AxisSpec::Given(a) => a,
        AxisSpec::Auto(_) => fit_axis(points, normals)?.axis,
    };
    Fixture::new(axis, points, opts.contact_depth).map(Some)
}

fn plan_items(dom: &Domain, placement: &Placement, opts: &PlanOptions) -> Result<Items> {
    opts.validate()?;
    let surface = !matches!(opts.z_mode, ZMode::Flat { .. });
    if surface && !dom.has_lift() {
        return Err(ToolpathError::MissingInput(
            "surface-following Z needs per-vertex 3D positions in the field mesh",
        ));
    }
    let rot = fixture(dom, opts)?;
    let mut items = Vec::new();
    let mut skipped_tilt = Vec::new();
    for (si, s) in placement.strokes.iter().enumerate() {
        let rev = wants_reverse(dom.symmetry, opts.direction, s, opts.reference);
        if let ZMode::SurfaceFollowing { max_tilt_deg, on_tilt }
        | ZMode::Rotary { max_tilt_deg, on_tilt, .. } = opts.z_mode
        {
            let tilt = max_tilt(dom, s, rot.as_ref());
            if tilt > max_tilt_deg {
                match on_tilt {
                    TiltPolicy::Error => {
                        return Err(ToolpathError::TiltExceeded {
                            stroke: si,
                            angle_deg: tilt,
                            limit_deg: max_tilt_deg,
                            by_deg: tilt - max_tilt_deg,
                        })
                    }
                    TiltPolicy::Skip => {
                        skipped_tilt.push((si, tilt));
                        continue;
                    }
                }
            }
        }
        items.extend(make_items(dom, si, s, rev, rot.as_ref(), opts));
    }
    Ok((items, skipped_tilt, rot))
}

/// What the orderer of [`plan_toolpath`] sees: the machine-XY entry and exit of every oriented
/// stroke piece (closed loops: up to 64 candidate entry vertices), in the order it receives
/// them. For benchmarks and travel bounds ([`crate::travel_bound`]) on exactly the planned
/// problem.
pub fn ordering_ends(dom: &Domain, placement: &Placement, opts: &PlanOptions) -> Result<Vec<Ends>> {
    Ok(plan_items(dom, placement, opts)?.0.iter().map(ends_of).collect())
}

/// Build the ordered passes from a placement (see the module docs).
pub fn plan_toolpath(dom: &Domain, placement: &Placement, opts: &PlanOptions) -> Result<Plan> {
    let (items, skipped_tilt, rot) = plan_items(dom, placement, opts)?;
    // Sheets: in flat mode (XY = UV) charts that overlap in UV cannot be cut on one sheet;
    // each sheet is ordered on its own, from home, and cut in sheet order.
    let sheet_of_chart = match (opts.z_mode, opts.sheets) {
        (ZMode::Flat { .. }, Sheets::Overlap) => sheets(dom),
        (ZMode::Flat { .. }, Sheets::Chart) => (0..dom.chart_count()).collect(),
        (ZMode::SurfaceFollowing { .. } | ZMode::Rotary { .. }, _) => vec![0; dom.chart_count()],
    };
    let mut item_sheet: Vec<usize> = items
        .iter()
        .map(|it| {
            it.faces
                .iter()
                .flatten()
                .next()
                .map_or(0, |&f| sheet_of_chart[dom.chart[f as usize] as usize])
        })
        .collect();
    if opts.sheets == Sheets::Chart {
        // One sheet per chart that holds strokes, numbered 0, 1, … in chart order.
        let mut used: Vec<usize> = item_sheet.clone();
        used.sort_unstable();
        used.dedup();
        for s in &mut item_sheet {
            *s = used.binary_search(s).expect("listed");
        }
    }
    let n_sheets = item_sheet.iter().copied().max().map_or(1, |m| m + 1);
    // Rotary: the orderer works in (X, A developed at r_ref); home is (X, A°).
    let mut order = opts.order.clone();
    if let Some(f) = &rot {
        order.home[1] = order.home[1].to_radians() * f.r_ref;
    }
    let period = rot.as_ref().map(Fixture::period);
    let mut passes = Vec::with_capacity(items.len());
    let (mut travel, mut travel_between, mut travel_greedy) = (0.0, 0.0, 0.0);
    for sheet in 0..n_sheets {
        let ids: Vec<usize> = (0..items.len()).filter(|&k| item_sheet[k] == sheet).collect();
        if ids.is_empty() {
            continue;
        }
        let ends: Vec<Ends> = ids.iter().map(|&k| ends_of(&items[k])).collect();
        let ordering = order_strokes(&ends, opts.direction == Direction::Alternate, &order);
        for &j in &ordering.order {
            let mut it = items[ids[j]].clone();
            if let Some(v) = ordering.entry[j] {
                let at = ring_index(it.machine.len(), v);
                rotate_loop(&mut it, at);
            }
            let flip = ordering.flipped[j];
            let mut pass = make_pass(dom, &it, flip, opts, period);
            pass.sheet = sheet;
            passes.push(pass);
        }
        travel += ordering.travel;
        travel_between += ordering.travel_between;
        travel_greedy += ordering.travel_greedy;
    }
    if let Some(f) = &rot {
        rotary_passes(&mut passes, f, opts.order.home[1]);
    }
    Ok(Plan {
        passes,
        skipped_tilt,
        travel,
        travel_between,
        travel_greedy,
        width: placement.width,
        home: opts.order.home,
        tolerance: opts.tolerance,
        rotary: rot,
    })
}

/// Rotary passes from developed `[x, s, z]` to `[x, A°, z]`: each pass shifted by whole turns
/// to start at the equivalent of its start nearest where the previous pass ended (the first:
/// nearest `home_a_deg`), so A never jumps by a turn (A is unwrapped).
fn rotary_passes(passes: &mut [Pass], f: &Fixture, home_a_deg: f64) {
    let period = f.period();
    let mut prev = home_a_deg.to_radians() * f.r_ref;
    for p in passes {
        let shift = nearest_equivalent(p.start[1], prev, period) - p.start[1];
        let last = p.moves.last().map_or(p.start, |(_, m)| m.end());
        prev = last[1] + shift;
        let deg = |q: Vec3| [q[0], ((q[1] + shift) / f.r_ref).to_degrees(), q[2]];
        p.start = deg(p.start);
        for (_, m) in &mut p.moves {
            match m {
                Segment::Line { to } | Segment::Arc { to, .. } => *to = deg(*to),
            }
        }
    }
}

/// Sheet of each chart: charts that overlap in UV get different sheets (greedy colouring
/// in chart order, lowest free sheet first); without overlaps every chart is on sheet 0.
pub(crate) fn sheets(dom: &Domain) -> Vec<usize> {
    let n = dom.chart_count();
    let mut sheet = vec![0usize; n];
    let pairs = dom.overlapping_charts();
    if pairs.is_empty() {
        return sheet;
    }
    let mut adj = vec![Vec::new(); n];
    for &(a, b) in &pairs {
        adj[a].push(b);
        adj[b].push(a);
    }
    for c in 0..n {
        let used: Vec<usize> = adj[c].iter().filter(|&&o| o < c).map(|&o| sheet[o]).collect();
        sheet[c] = (0..).find(|s| !used.contains(s)).unwrap_or(0);
    }
    sheet
}

/// Largest angle (degrees) between the surface normal and the tool axis along a stroke: +Z,
/// or the radial direction on a rotary fixture.
fn max_tilt(dom: &Domain, s: &Stroke, rot: Option<&Fixture>) -> f64 {
    let mut worst: f64 = 0.0;
    for (p, &f) in s.uv.iter().zip(&s.faces) {
        let b = barycentric(dom.corners(f), *p);
        if let Some(n) = dom.normal(f, b) {
            let tilt = match (rot, dom.lift(f, b)) {
                (Some(fx), Some(x)) => fx.tilt_deg(x, n),
                _ => n[2].clamp(-1.0, 1.0).acos().to_degrees(),
            };
            worst = worst.max(tilt);
        }
    }
    worst
}

/// Machine point of a stroke point: flat `[u, v, z]`, the lift, or on a rotary fixture the
/// developed `[x, r_ref · A, |r|]` (A in radians, unwrapped later), each minus the contact depth
/// in Z.
fn machine_point(dom: &Domain, p: Vec2, f: u32, rot: Option<&Fixture>, opts: &PlanOptions) -> Vec3 {
    let lift = || dom.lift(f, barycentric(dom.corners(f), p)).unwrap_or([p[0], p[1], 0.0]);
    match (opts.z_mode, rot) {
        (ZMode::Flat { surface_z }, _) => [p[0], p[1], surface_z - opts.contact_depth],
        (_, Some(fx)) => {
            let [x, a, r] = fx.cylindrical(lift());
            [x, fx.r_ref * a, r - opts.contact_depth]
        }
        _ => {
            let x = lift();
            [x[0], x[1], x[2] - opts.contact_depth]
        }
    }
}

/// Oriented items: one per stroke in surface mode; one per seam piece in flat mode.
fn make_items(
    dom: &Domain,
    si: usize,
    s: &Stroke,
    rev: bool,
    rot: Option<&Fixture>,
    opts: &PlanOptions,
) -> Vec<Item> {
    let surface = !matches!(opts.z_mode, ZMode::Flat { .. });
    let mut pieces: Vec<(Vec<Vec2>, Vec<u32>)> = s
        .pieces()
        .into_iter()
        .map(|r| (s.uv[r.clone()].to_vec(), s.faces[r].to_vec()))
        .filter(|(p, _)| p.len() >= 2)
        .collect();
    let mut stops = [s.start, s.end];
    let mut over = s.overtravel;
    if rev {
        over.swap(0, 1);
        pieces.reverse();
        for (p, f) in &mut pieces {
            p.reverse();
            f.reverse();
        }
        stops.swap(0, 1);
    }
    let np = pieces.len();
    let to_machine = |(p, f): &(Vec<Vec2>, Vec<u32>)| -> Vec<Vec3> {
        p.iter().zip(f).map(|(q, &ff)| machine_point(dom, *q, ff, rot, opts)).collect()
    };
    if surface {
        let mut machine: Vec<Vec3> = pieces.iter().flat_map(to_machine).collect();
        if let Some(fx) = rot {
            unwrap_developed(&mut machine, fx.period());
        }
        let (uv, faces) = pieces.into_iter().unzip();
        return vec![Item {
            stroke: si,
            reversed: rev,
            uv,
            faces,
            machine,
            stops,
            overtravel: over,
            length: s.length,
        }];
    }
    pieces
        .into_iter()
        .enumerate()
        .map(|(k, piece)| {
            let machine = to_machine(&piece);
            let st = [
                if k == 0 { stops[0] } else { StopReason::Boundary },
                if k + 1 == np { stops[1] } else { StopReason::Boundary },
            ];
            Item {
                stroke: si,
                reversed: rev,
                uv: vec![piece.0],
                faces: vec![piece.1],
                machine,
                stops: st,
                overtravel: [
                    if k == 0 { over[0] } else { 0.0 },
                    if k + 1 == np { over[1] } else { 0.0 },
                ],
                length: s.length,
            }
        })
        .collect()
}
