//! Rotary (4-axis) programs (issue 31, item 1), checked from outside the code: LinuxCNC's rs274
//! reads the program; every feed move, mapped back through the fixture the program's header
//! states, lies on the analytic surface of revolution it was made for; the strokes on the part
//! match the run's 3D strokes; A never jumps; feeds are inverse time from the true surface
//! length; the cycle time agrees with rs274's canonical moves.

mod common;

use common::{run_tool, scratch, shared_tool};
use grainline_toolpaths::*;

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn unit(a: V3) -> V3 {
    let l = norm(a);
    a.map(|x| x / l)
}

/// A surface of revolution `ρ = r(h)`, `h ∈ [0, len]`, about the axis through `c` along `d`,
/// with the angle measured from `e1` towards `e2 = d × e1`.
struct Body {
    c: V3,
    d: V3,
    e1: V3,
    len: f64,
    r: fn(f64) -> f64,
    dr: fn(f64) -> f64,
}

fn cylinder_r(_: f64) -> f64 {
    20.0
}
fn cylinder_dr(_: f64) -> f64 {
    0.0
}
/// A bottle: a 24 mm body narrowing to a 15 mm neck.
fn bottle_r(h: f64) -> f64 {
    19.5 + 4.5 * (std::f64::consts::PI * h / 70.0).cos()
}
fn bottle_dr(h: f64) -> f64 {
    -4.5 * std::f64::consts::PI / 70.0 * (std::f64::consts::PI * h / 70.0).sin()
}

impl Body {
    fn tilted(r: fn(f64) -> f64, dr: fn(f64) -> f64, len: f64) -> Body {
        let d = unit([1.0, 2.0, 0.5]);
        let e1 = unit(cross(d, [0.0, 0.0, 1.0]));
        Body { c: [5.0, -3.0, 10.0], d, e1, len, r, dr }
    }

    fn e2(&self) -> V3 {
        cross(self.d, self.e1)
    }

    fn point(&self, h: f64, t: f64) -> V3 {
        let (s, c) = t.sin_cos();
        let (e2, r) = (self.e2(), (self.r)(h));
        [0, 1, 2].map(|k| self.c[k] + h * self.d[k] + r * (c * self.e1[k] + s * e2[k]))
    }

    fn normal(&self, h: f64, t: f64) -> V3 {
        let (s, c) = t.sin_cos();
        let e2 = self.e2();
        let radial = [0, 1, 2].map(|k| c * self.e1[k] + s * e2[k]);
        unit([0, 1, 2].map(|k| radial[k] - (self.dr)(h) * self.d[k]))
    }

    /// A closed grid (`n` around, `m` along) with the seam glued; UV = (angle × 20, h);
    /// a helical grain at `alpha` from U.
    fn field_mesh(&self, n: usize, m: usize, alpha: f64) -> FieldMesh {
        let (mut uv, mut pos, mut nor) = (Vec::new(), Vec::new(), Vec::new());
        for j in 0..=m {
            let h = self.len * j as f64 / m as f64;
            for i in 0..=n {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                uv.push([20.0 * t, h]);
                pos.push(self.point(h, t));
                nor.push(self.normal(h, t));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut tris = Vec::new();
        for j in 0..m {
            for i in 0..n {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let seams = (0..m)
            .map(|j| SeamPair { a: [id(n, j), id(n, j + 1)], b: [id(0, j), id(0, j + 1)] })
            .collect();
        let dirs = vec![[alpha.cos(), alpha.sin()]; uv.len()];
        let mut fm =
            FieldMesh::new(uv, tris, Directions::Vectors(dirs), Symmetry::Line).with_seams(seams);
        fm.positions = Some(pos);
        fm.normals = Some(nor);
        fm
    }

    /// The radius at `h`, the body continued past its rims by its tangent cones
    /// (`r(0) + r'(0) h` below 0, `r(len) + r'(len) (h − len)` above `len`): where a run-out
    /// past the rim goes on along the surface's tangent (docs/toolpaths.md, "Run-outs").
    fn r_ext(&self, h: f64) -> f64 {
        if h < 0.0 {
            (self.r)(0.0) + (self.dr)(0.0) * h
        } else if h > self.len {
            (self.r)(self.len) + (self.dr)(self.len) * (h - self.len)
        } else {
            (self.r)(h)
        }
    }

    /// Exact distance from `p` to the surface continued `RIM` past each rim by its tangent
    /// cone: min over h of the distance in the meridian half-plane of `p` (dense samples, then
    /// golden-section refinement).
    fn distance(&self, p: V3) -> f64 {
        let q = sub(p, self.c);
        let x = dot(q, self.d);
        let rho = norm([0, 1, 2].map(|k| q[k] - x * self.d[k]));
        let f = |h: f64| ((x - h).powi(2) + (rho - self.r_ext(h)).powi(2)).sqrt();
        let (h0, h1) = (-RIM, self.len + RIM);
        let n = 4000;
        let at = |i: usize| h0 + (h1 - h0) * i as f64 / n as f64;
        let k = (0..=n).min_by(|&a, &b| f(at(a)).total_cmp(&f(at(b)))).unwrap();
        let step = (h1 - h0) / n as f64;
        let (mut lo, mut hi) = ((at(k) - step).max(h0), (at(k) + step).min(h1));
        for _ in 0..60 {
            let (a, b) = (lo + 0.382 * (hi - lo), lo + 0.618 * (hi - lo));
            if f(a) < f(b) {
                hi = b;
            } else {
                lo = a;
            }
        }
        f(0.5 * (lo + hi))
    }

    /// How far past the rims `p` lies along the axis (0 on the part).
    fn past_rim(&self, p: V3) -> f64 {
        let x = dot(sub(p, self.c), self.d);
        (-x).max(x - self.len).max(0.0)
    }
}

/// How far the tangent continuation past the rims is allowed: the run-out (one brush width,
/// 3 mm) and some.
const RIM: f64 = 5.0;

/// The fixture as the program's header states it: `(rotary: point … direction … zero …)`.
struct Header {
    point: V3,
    dir: V3,
    zero: V3,
}

impl Header {
    fn parse(gcode: &str) -> Header {
        let line = gcode.lines().find(|l| l.starts_with("(rotary: point ")).expect("fixture line");
        let body = line.trim_start_matches("(rotary: ").trim_end_matches(')');
        let words: Vec<&str> = body.split(' ').collect();
        assert_eq!(words.len(), 6, "{line}");
        assert_eq!((words[0], words[2], words[4]), ("point", "direction", "zero"), "{line}");
        let v = |s: &str| -> V3 {
            let p: Vec<f64> = s.split(',').map(|x| x.parse().unwrap()).collect();
            [p[0], p[1], p[2]]
        };
        Header { point: v(words[1]), dir: v(words[3]), zero: v(words[5]) }
    }

    /// The part point under the tool point (x, 0, z) at A: the tool point turned by −A about
    /// machine X (right-hand rule), in the part frame (d, zero × d, zero) at the point.
    fn to_part(&self, x: f64, a_deg: f64, z: f64) -> V3 {
        let a = a_deg.to_radians();
        // Machine frame → frame of the part at A = 0: R_x(−A) · (x, 0, z).
        let (y0, z0) = (z * a.sin(), z * a.cos());
        let ey = cross(self.zero, self.dir);
        [0, 1, 2].map(|k| self.point[k] + x * self.dir[k] + y0 * ey[k] + z0 * self.zero[k])
    }
}

/// One program's feed moves in passes: `(stroke, [(X, A, Z, F)])`, the plunge left out.
fn passes_of(gcode: &str) -> Vec<(usize, Vec<[f64; 4]>)> {
    let mut out: Vec<(usize, Vec<[f64; 4]>)> = Vec::new();
    let word = |l: &str, c: char| -> Option<f64> {
        l.split(' ').find(|w| w.starts_with(c)).map(|w| w[1..].parse().unwrap())
    };
    for l in gcode.lines() {
        if let Some(rest) = l.strip_prefix("(pass ") {
            let k = rest.split("stroke ").nth(1).unwrap().trim_end_matches(')');
            out.push((k.parse().unwrap(), Vec::new()));
        } else if l.starts_with("G0 X") {
            let p = out.last_mut().unwrap();
            p.1.push([word(l, 'X').unwrap(), word(l, 'A').unwrap(), f64::NAN, f64::NAN]);
        } else if l.starts_with("G1 Z") {
            let p = out.last_mut().unwrap();
            p.1[0][2] = word(l, 'Z').unwrap();
        } else if l.starts_with("G1 X") {
            let p = out.last_mut().unwrap();
            let m = [
                word(l, 'X').unwrap(),
                word(l, 'A').unwrap(),
                word(l, 'Z').unwrap(),
                word(l, 'F').unwrap(),
            ];
            p.1.push(m);
        }
    }
    out
}

fn seg_dist(p: V3, a: V3, b: V3) -> f64 {
    let ab = sub(b, a);
    let t = (dot(sub(p, a), ab) / dot(ab, ab).max(1e-300)).clamp(0.0, 1.0);
    norm(sub(p, [0, 1, 2].map(|k| a[k] + t * ab[k])))
}

fn poly_dist(p: V3, line: &[V3]) -> f64 {
    line.windows(2).map(|w| seg_dist(p, w[0], w[1])).fold(f64::INFINITY, f64::min)
}

/// Points along a linear (X, A, Z) move, mapped to the part, `n` pieces.
fn along(h: &Header, a: [f64; 4], b: [f64; 4], n: usize, depth: f64) -> Vec<V3> {
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            let m = |k: usize| a[k] + t * (b[k] - a[k]);
            h.to_part(m(0), m(1), m(2) + depth)
        })
        .collect()
}

struct Figures {
    surface: f64,
    stroke_match: f64,
    worst_turn_excess: f64,
    max_da: f64,
    feed_error: f64,
    passes: usize,
}

const FEED: f64 = 1200.0;

fn job(depth: f64, axis: AxisSpec) -> JobOptions {
    JobOptions {
        placement: PlacementOptions {
            trace: TraceOptions { cross_seams: true, ..Default::default() },
            ..PlacementOptions::new(3.0, 0.0)
        },
        plan: PlanOptions {
            z_mode: ZMode::Rotary { axis, max_tilt_deg: 30.0, on_tilt: TiltPolicy::Error },
            contact_depth: depth,
            ..Default::default()
        },
        gcode: Some(GcodeOptions { feed: FEED, safe_z: 35.0, ..Default::default() }),
        ..Default::default()
    }
}

/// Measure one program against its body and its run's 3D strokes.
fn measure(body: &Body, out: &JobOutput, depth: f64) -> Figures {
    let g = out.gcode.as_ref().unwrap();
    let h = Header::parse(g);
    let passes = passes_of(g);
    let mut f = Figures {
        surface: 0.0,
        stroke_match: 0.0,
        worst_turn_excess: f64::NEG_INFINITY,
        max_da: 0.0,
        feed_error: 0.0,
        passes: passes.len(),
    };
    for (stroke, moves) in &passes {
        let s3 = &out.strokes_3d[*stroke];
        let mut path = Vec::new();
        for w in moves.windows(2) {
            // Fine enough that chords of the mapped path stay within 0.001 mm of it.
            let pieces = 16.max(((w[1][1] - w[0][1]).abs() / 0.5).ceil() as usize);
            let pts = along(&h, w[0], w[1], pieces, depth);
            for p in &pts {
                f.surface = f.surface.max(body.distance(*p));
                // On the part the path is the stroke; past a rim it is the stroke's run-out.
                if body.past_rim(*p) <= 1e-9 {
                    f.stroke_match = f.stroke_match.max(poly_dist(*p, s3));
                }
            }
            // The true path of the contact point and the time the inverse-time F gives it.
            let len: f64 = along(&h, w[0], w[1], 40 * pieces, depth)
                .windows(2)
                .map(|q| norm(sub(q[1], q[0])))
                .sum();
            f.feed_error = f.feed_error.max(((1.0 / w[1][3]) / (len / FEED) - 1.0).abs());
            // A turns no more than the arc the contact point runs allows.
            let da = (w[1][1] - w[0][1]).abs();
            let rho = w[0][2].min(w[1][2]) + depth;
            f.max_da = f.max_da.max(da);
            f.worst_turn_excess = f.worst_turn_excess.max(da.to_radians() * rho - len);
            path.extend(pts);
        }
        for p in s3 {
            f.stroke_match = f.stroke_match.max(poly_dist(*p, &path));
        }
    }
    f
}

/// rs274's canonical moves: (traverse?, [X, Y, Z, A], feed rate in force).
fn canon_feeds(text: &str) -> Vec<(bool, [f64; 4], f64)> {
    let mut rate = 0.0;
    let mut out = Vec::new();
    let args = |l: &str| -> Vec<f64> {
        let a = &l[l.find('(').unwrap() + 1..l.rfind(')').unwrap()];
        a.split(',').map(|x| x.trim().parse().unwrap()).collect()
    };
    for l in text.lines() {
        if l.contains("SET_FEED_RATE(") {
            rate = args(l)[0];
        } else if l.contains("STRAIGHT_TRAVERSE(") || l.contains("STRAIGHT_FEED(") {
            let a = args(l);
            out.push((l.contains("TRAVERSE"), [a[0], a[1], a[2], a[3]], rate));
        }
        assert!(!l.contains("ARC_FEED"), "{l}");
    }
    out
}

/// The program's time from rs274's canonical moves, from where rs274 starts (the origin):
/// a feed move takes its XYZ length (its A travel when it has none) over the rate rs274
/// derived from the inverse-time F; a traverse its length at `rapid`, A counting as the arc at
/// the mean height.
fn canon_time(text: &str, rapid: f64) -> f64 {
    let moves = canon_feeds(text);
    let mut cur = [0.0; 4];
    let mut t = 0.0;
    for (traverse, p, rate) in moves {
        let lin =
            ((p[0] - cur[0]).powi(2) + (p[1] - cur[1]).powi(2) + (p[2] - cur[2]).powi(2)).sqrt();
        if traverse {
            let arc = 0.5 * (p[2] + cur[2]) * (p[3] - cur[3]).to_radians();
            t += 60.0 * (lin * lin + arc * arc).sqrt() / rapid;
        } else {
            let len = if lin > 0.0 { lin } else { (p[3] - cur[3]).abs() };
            t += 60.0 * len / rate;
        }
        cur = p;
    }
    t
}

/// rs274 accepts the program; its cycle time agrees with the canon's; every canonical feed
/// move's end, mapped through the header's fixture, is within `tol` of the body.
fn check_with_rs274(name: &str, g: &str, report: &Report, body: &Body, depth: f64, tol: f64) {
    let Some(tool) = shared_tool("check-gcode") else { return };
    let dir = scratch(name);
    let path = dir.join(format!("{name}.ngc"));
    std::fs::write(&path, g).unwrap();
    let canon = dir.join("canon");
    let (ok, text) = run_tool(&tool, &[std::path::Path::new("--canon"), &canon, &path]);
    assert!(ok, "rs274 refused {name}: {text}");
    let c = std::fs::read_to_string(canon.join(format!("{name}.ngc.canon"))).unwrap();
    let ours = report.cycle_time_s.unwrap();
    let theirs = canon_time(&c, DEFAULT_RAPID_MM_MIN);
    eprintln!("{name}: cycle time {ours:.3} s, from rs274's canon {theirs:.3} s");
    assert!((ours - theirs).abs() <= 0.1 * theirs, "{ours} vs {theirs}");
    let h = Header::parse(g);
    let moves = canon_feeds(&c);
    let (mut worst, mut past): (f64, f64) = (0.0, 0.0);
    // Every feed move (the plunges, the cuts and the run-outs past the rims; no leads here)
    // ends on the part, or on its continuation past a rim by the tangent cone.
    for (_, p, _) in moves.iter().filter(|m| !m.0) {
        assert!(p[1] == 0.0, "a Y move in a rotary program");
        let q = h.to_part(p[0], p[3], p[2] + depth);
        worst = worst.max(body.distance(q));
        past = past.max(body.past_rim(q));
    }
    eprintln!(
        "{name}: rs274's feed moves mapped back lie within {worst:.4} mm of the part (continued \
         past the rims by its tangent cones); the run-outs reach {past:.3} mm past a rim"
    );
    assert!(worst <= tol, "{worst}");
    // Strokes ending on a rim run out past it (one width, 3 mm, along the helix: its axial
    // part), never farther.
    assert!(past > 0.5 && past <= 3.0 + tol, "run-outs past the rims: {past} mm");
}

fn run_body(name: &str, body: &Body, alpha: f64, depth: f64, axis: AxisSpec) -> Figures {
    let fm = body.field_mesh(256, 60, alpha);
    let out = generate(fm, &job(depth, axis)).unwrap();
    let g = out.gcode.as_ref().unwrap();
    assert!(g.contains("G21 G90 G17 G93"), "{}", &g[..600]);
    check_with_rs274(name, g, &out.report, body, depth, 0.05);
    let f = measure(body, &out, depth);
    eprintln!(
        "{name}: {} passes; feed moves to the surface ≤ {:.4} mm, to the run's 3D strokes ≤ \
         {:.4} mm; largest A per move {:.1}°, A beyond the arc run {:.2e} mm; inverse-time F \
         within {:.2e} of the true surface length",
        f.passes, f.surface, f.stroke_match, f.max_da, f.worst_turn_excess, f.feed_error
    );
    assert!(f.passes > 5);
    assert!(f.surface <= 0.05, "{name}: {}", f.surface);
    assert!(f.stroke_match <= 0.05, "{name}: {}", f.stroke_match);
    assert!(f.worst_turn_excess <= 0.01, "{name}: A jumps {}", f.worst_turn_excess);
    assert!(f.feed_error < 2e-3, "{name}: {}", f.feed_error);
    f
}

fn given(body: &Body) -> AxisSpec {
    AxisSpec::Given(RotaryAxis { point: body.c, direction: body.d, zero: Some(body.e1) })
}

#[test]
fn helix_on_a_tilted_cylinder_lies_on_the_part() {
    let body = Body::tilted(cylinder_r, cylinder_dr, 60.0);
    run_body("rotary-cylinder", &body, 20f64.to_radians(), 0.0, given(&body));
}

#[test]
fn bottle_with_contact_depth_and_the_axis_found() {
    let body = Body::tilted(bottle_r, bottle_dr, 70.0);
    run_body("rotary-bottle", &body, 35f64.to_radians(), 0.2, AxisSpec::default());
}

/// The sign of A: a part point on the part's `zero × direction` side (machine +Y at A = 0)
/// needs A = +90° to come to the top, as the right-hand rule about +X turns +Y to +Z (LinuxCNC:
/// positive A is counter-clockwise seen from +X towards the origin).
#[test]
fn a_is_right_handed_about_x() {
    let axis =
        RotaryAxis { point: [0.0; 3], direction: [1.0, 0.0, 0.0], zero: Some([0.0, 0.0, 1.0]) };
    let f = Fixture::new(axis, &[[0.0, 10.0, 0.0]], 0.0).unwrap();
    let [x, a, r] = f.cylindrical([3.0, 10.0, 0.0]);
    assert_eq!((x, r), (3.0, 10.0));
    assert!((a.to_degrees() - 90.0).abs() < 1e-12);
    // R_x(+90°) (counter-clockwise seen from +X) takes (0, 10, 0) to (0, 0, 10): the top.
    let rx =
        |p: V3, t: f64| [p[0], p[1] * t.cos() - p[2] * t.sin(), p[1] * t.sin() + p[2] * t.cos()];
    let top = rx([3.0, 10.0, 0.0], a);
    assert!(norm(sub(top, [3.0, 0.0, 10.0])) < 1e-12);
    // And back: the tool point (3, 0, 10) at A = 90° is the part point (3, 10, 0).
    assert!(norm(sub(f.to_part(3.0, 90.0, 10.0), [3.0, 10.0, 0.0])) < 1e-12);
}

#[test]
fn the_axis_of_a_body_of_revolution_is_found() {
    let body = Body::tilted(bottle_r, bottle_dr, 70.0);
    let fm = body.field_mesh(96, 30, 0.3);
    let fit = fit_axis(fm.positions.as_ref().unwrap(), fm.normals.as_ref().unwrap()).unwrap();
    let d = fit.axis.direction;
    assert!(dot(d, body.d) > (0.01f64).to_radians().cos(), "{d:?}");
    // The point is on the axis, at the part's end (h = 0).
    assert!(norm(sub(fit.axis.point, body.c)) < 1e-6, "{:?}", fit.axis.point);
    assert!(fit.miss_p95_deg < 0.01, "{}", fit.miss_p95_deg);
}

#[test]
fn a_part_that_is_not_turned_is_refused_by_auto() {
    // A saddle z = (x² − y²) / 60 over 60 × 40 mm.
    let (uv, _) = common::rect_mesh(60.0, 40.0, 30, 20);
    let pos: Vec<V3> =
        uv.iter().map(|p| [p[0], p[1], (p[0].powi(2) - p[1].powi(2)) / 60.0]).collect();
    let nor: Vec<V3> =
        uv.iter().map(|p| unit([-2.0 * p[0] / 60.0, 2.0 * p[1] / 60.0, 1.0])).collect();
    let e = fit_axis(&pos, &nor).unwrap_err();
    let text = e.to_string();
    assert!(
        text.starts_with("plan.z_mode.axis: auto: ")
            && text.contains("the part is not near a body of revolution"),
        "{text}"
    );
    // A flat plate fits an axis at infinity: refused too.
    let flat: Vec<V3> = uv.iter().map(|p| [p[0], p[1], 0.0]).collect();
    let up = vec![[0.0, 0.0, 1.0]; flat.len()];
    assert!(fit_axis(&flat, &up)
        .unwrap_err()
        .to_string()
        .contains("not near a body of revolution"));
}

#[test]
fn rotary_needs_an_a_axis_and_no_arcs() {
    let body = Body::tilted(cylinder_r, cylinder_dr, 60.0);
    let mut o = job(0.0, given(&body));
    o.gcode.as_mut().unwrap().dialect = Dialect::Grbl;
    let e = generate(body.field_mesh(64, 20, 0.3), &o).unwrap_err();
    assert!(e.to_string().starts_with("gcode.dialect: grbl 1.1 drives three axes"), "{e}");
    let mut o = job(0.0, given(&body));
    o.plan.arcs = true;
    assert!(o.validate().unwrap_err().to_string().starts_with("plan.arcs: "));
    let bad = AxisSpec::Given(RotaryAxis {
        point: [0.0; 3],
        direction: [0.0, 0.0, 1.0],
        zero: Some([0.0, 0.0, 2.0]),
    });
    let o = job(0.0, bad);
    assert!(o
        .validate()
        .unwrap_err()
        .to_string()
        .starts_with("plan.z_mode.axis: zero must not be parallel"));
}
