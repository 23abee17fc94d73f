//! Prismatic parts: every face is a plane or a cylinder swept straight along one axis, so
//! each part is built from rims (outlines) at the two ends of a sweep, the walls between them
//! and the planar faces they bound.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::Vector3;

use super::build::{segments, unit, Builder, Rim};
use super::{AnalyticFace, CadPart};
use crate::mesh::Units;
use crate::{Error, Result};

type V3 = Vector3<f64>;

/// Rejects a non-finite or non-positive option.
pub(super) fn positive(name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid_arg(name, format!("must be a positive number, not {v}")))
    }
}

/// Rejects options whose geometry does not close (`ok` false), naming the rule.
pub(super) fn require(ok: bool, name: &str, rule: &str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::invalid_arg(name, rule.to_owned()))
    }
}

/// The chordal step in radians from `step_deg` (1° to 45°).
pub(super) fn step_of(step_deg: f64) -> Result<f64> {
    require((1.0..=45.0).contains(&step_deg), "step_deg", "must lie in [1, 45] degrees")?;
    Ok(step_deg.to_radians())
}

/// Area of a w × h rectangle whose corners are rounded to radius r: `wh − (4 − π) r²`.
fn rounded_rect_area(w: f64, h: f64, r: f64) -> f64 {
    w * h - (4.0 - PI) * r * r
}

pub(super) fn plane(normal: V3, point: V3, area: f64) -> AnalyticFace {
    AnalyticFace::Plane { normal, point, area }
}

pub(super) fn cylinder(axis_point: V3, axis_dir: V3, radius: f64, area: f64) -> AnalyticFace {
    AnalyticFace::Cylinder { axis_point, axis_dir, radius, area }
}

/// Options of [`housing`]. Lengths in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct HousingOptions {
    /// Outer size x × y × z (the block stands on z = 0, centred on the z axis).
    pub size: [f64; 3],
    /// Radius of the fillets on the four vertical edges.
    pub corner_radius: f64,
    /// Pocket size x × y, centred in the top face.
    pub pocket: [f64; 2],
    /// Pocket depth.
    pub pocket_depth: f64,
    /// Radius of the pocket's vertical corner fillets.
    pub pocket_corner_radius: f64,
    /// Radii of the two holes through the pocket's floor, at x = ∓`pocket[0]`/4, y = 0.
    pub hole_radii: [f64; 2],
    /// Chordal step of the curved faces, degrees.
    pub step_deg: f64,
}

impl Default for HousingOptions {
    fn default() -> Self {
        HousingOptions {
            size: [120.0, 80.0, 40.0],
            corner_radius: 8.0,
            pocket: [90.0, 50.0],
            pocket_depth: 10.0,
            pocket_corner_radius: 6.0,
            hole_radii: [5.0, 3.5],
            step_deg: 12.0,
        }
    }
}

/// A rounded rectangle's rim at height z, counter-clockwise seen from +z: corner k (centre
/// `(±(hx − r), ±(hy − r))`, k = 0..3 from (+, −) round to (−, −)) is the arc
/// `c + r (cos φ, sin φ)`, φ from (k − 1)·90° to k·90°, on face `corners[k]`; then the
/// straight side to the next corner, on face `sides[k]` (outward normal at k·90°).
fn rounded_rect(h: [f64; 2], r: f64, z: f64, n: usize, sides: [u32; 4], corners: [u32; 4]) -> Rim {
    let sign = [(1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0)];
    let mut rim = Rim::default();
    for k in 0..4 {
        let c = V3::new(sign[k].0 * (h[0] - r), sign[k].1 * (h[1] - r), z);
        let a0 = (k as f64 - 1.0) * FRAC_PI_2;
        let at = |a: f64| {
            let (cos, sin) = unit(a);
            c + V3::new(cos, sin, 0.0) * r
        };
        rim.push(at(a0), corners[k], r);
        rim.arc(c, [V3::x(), V3::y()], r, [a0, a0 + FRAC_PI_2], n, corners[k]);
        rim.push(at(a0 + FRAC_PI_2), sides[k], 0.0);
    }
    rim
}

/// The faces of a rounded rectangle's walls: four planes (normal `±` the side's outward
/// direction) and four quarter cylinders, all `height` tall.
fn rounded_rect_faces(
    b: &mut Builder,
    h: [f64; 2],
    r: f64,
    z0: f64,
    height: f64,
    out: f64,
) -> ([u32; 4], [u32; 4]) {
    let sign = [(1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0)];
    let mut sides = [0; 4];
    let mut corners = [0; 4];
    for k in 0..4 {
        let c = V3::new(sign[k].0 * (h[0] - r), sign[k].1 * (h[1] - r), z0);
        let area = 0.25 * TAU * r * height;
        corners[k] = b.face(cylinder(c, V3::z(), r, area));
        let (cos, sin) = unit(k as f64 * FRAC_PI_2);
        let n = V3::new(cos, sin, 0.0);
        let len = 2.0 * (if k % 2 == 0 { h[1] } else { h[0] } - r);
        sides[k] = b.face(plane(n * out, V3::new(cos * h[0], sin * h[1], z0), len * height));
    }
    (sides, corners)
}

/// A machined housing (see the module table): a block of `size` whose four vertical edges are
/// filleted (the side walls run tangentially into the fillets; top and bottom edges are sharp),
/// a pocket with filleted corners and a flat floor cut into the top, and two round holes from
/// the pocket's floor through the bottom.
///
/// Volume: `A(w, h, R)·H − A(pw, ph, r)·d − π(r₁² + r₂²)(H − d)` with
/// `A(w, h, r) = wh − (4 − π)r²` the rounded rectangle's area.
pub fn housing(o: &HousingOptions) -> Result<CadPart> {
    let [w, h, height] = o.size;
    let ([pw, ph], d, (r, pr)) =
        (o.pocket, o.pocket_depth, (o.corner_radius, o.pocket_corner_radius));
    for (name, v) in [("size", w.min(h).min(height)), ("corner_radius", r), ("pocket", pw.min(ph))]
    {
        positive(name, v)?;
    }
    for (name, v) in [("pocket_depth", d), ("pocket_corner_radius", pr)] {
        positive(name, v)?;
    }
    positive("hole_radii", o.hole_radii[0].min(o.hole_radii[1]))?;
    require(2.0 * r < w.min(h), "corner_radius", "must be less than half the smaller side")?;
    require(pw < w - 2.0 * r && ph < h - 2.0 * r, "pocket", "must fit inside the fillets")?;
    require(2.0 * pr < pw.min(ph) && d < height, "pocket", "corner radius or depth too large")?;
    let hr = o.hole_radii[0].max(o.hole_radii[1]);
    require(hr < pw / 4.0 - pr && hr < ph / 2.0 - pr, "hole_radii", "holes must fit in the floor")?;
    let step = step_of(o.step_deg)?;
    let mut b = Builder::new("housing", Units::Mm, step);
    let (half, phalf) = ([0.5 * w, 0.5 * h], [0.5 * pw, 0.5 * ph]);
    let floor = height - d;
    let holes = [(-0.25 * pw, o.hole_radii[0]), (0.25 * pw, o.hole_radii[1])];
    let hole_area: f64 = holes.iter().map(|(_, r)| PI * r * r).sum();
    let (outer_a, pocket_a) = (rounded_rect_area(w, h, r), rounded_rect_area(pw, ph, pr));
    let bottom = b.face(plane(-V3::z(), V3::zeros(), outer_a - hole_area));
    let top = b.face(plane(V3::z(), V3::new(0.0, 0.0, height), outer_a - pocket_a));
    let floor_f = b.face(plane(V3::z(), V3::new(0.0, 0.0, floor), pocket_a - hole_area));
    let (sides, corners) = rounded_rect_faces(&mut b, half, r, 0.0, height, 1.0);
    let (psides, pcorners) = rounded_rect_faces(&mut b, phalf, pr, floor, d, -1.0);
    let n90 = segments(FRAC_PI_2, step);
    let outer0 = rounded_rect(half, r, 0.0, n90, sides, corners);
    let outer1 = outer0.mapped(|p| V3::new(p.x, p.y, height));
    let pocket1 = rounded_rect(phalf, pr, height, n90, psides, pcorners);
    let pocket0 = pocket1.mapped(|p| V3::new(p.x, p.y, floor));
    b.walls(&outer0, &outer1, false, &[]);
    b.walls(&pocket0, &pocket1, true, &[]);
    let n360 = segments(TAU, step);
    let mut rims0 = Vec::new();
    let mut rims1 = Vec::new();
    for (x, hr) in holes {
        let f = b.face(cylinder(V3::new(x, 0.0, 0.0), V3::z(), hr, TAU * hr * floor));
        let rim0 = Rim::circle(V3::new(x, 0.0, 0.0), V3::x(), V3::y(), hr, n360, f);
        let rim1 = rim0.mapped(|p| V3::new(p.x, p.y, floor));
        b.walls(&rim0, &rim1, true, &[]);
        rims0.push(rim0);
        rims1.push(rim1);
    }
    b.planar(bottom, &[&outer0, &rims0[0], &rims0[1]]);
    b.planar(top, &[&outer1, &pocket1]);
    b.planar(floor_f, &[&pocket0, &rims1[0], &rims1[1]]);
    Ok(b.finish(outer_a * height - pocket_a * d - hole_area * floor))
}

/// Options of [`plate`]. Lengths in inches.
#[derive(Clone, Debug, PartialEq)]
pub struct PlateOptions {
    /// Size x × y × z (corner at the origin, thickness along z).
    pub size: [f64; 3],
    /// Through-holes along z as `[x, y, radius]`.
    pub holes: Vec<[f64; 3]>,
    /// Chordal step of the hole walls, degrees.
    pub step_deg: f64,
}

impl Default for PlateOptions {
    /// 8 × 12 × 0.5 in (203.2 × 304.8 × 12.7 mm) with five holes of diameters ¼, ⅜, ½, ¾ and
    /// 1½ in.
    fn default() -> Self {
        PlateOptions {
            size: [8.0, 12.0, 0.5],
            holes: vec![
                [1.5, 1.5, 0.125],
                [6.5, 1.5, 0.1875],
                [1.25, 10.75, 0.25],
                [6.5, 10.5, 0.375],
                [3.75, 6.25, 0.75],
            ],
            step_deg: 12.0,
        }
    }
}

/// A flat plate in inches with round through-holes: its top and bottom are one planar face
/// each, ear-clipped from the rectangle and the holes' rims (every triangle a sliver from a
/// corner or a rim to another rim); four sides of two triangles; each hole wall one strip.
///
/// Volume: `(w h − Σ π rᵢ²) t`.
pub fn plate(o: &PlateOptions) -> Result<CadPart> {
    let [w, h, t] = o.size;
    positive("size", w.min(h).min(t))?;
    for (i, &[x, y, r]) in o.holes.iter().enumerate() {
        positive("holes", r)?;
        let inside = x - r > 0.0 && x + r < w && y - r > 0.0 && y + r < h;
        let apart = o.holes[..i].iter().all(|q| (x - q[0]).hypot(y - q[1]) > r + q[2]);
        require(inside && apart, "holes", "holes must lie inside the plate and apart")?;
    }
    let step = step_of(o.step_deg)?;
    let mut b = Builder::new("plate", Units::In, step);
    let hole_area: f64 = o.holes.iter().map(|q| PI * q[2] * q[2]).sum();
    let bottom = b.face(plane(-V3::z(), V3::zeros(), w * h - hole_area));
    let top = b.face(plane(V3::z(), V3::new(0.0, 0.0, t), w * h - hole_area));
    let corners = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)];
    let mut outer0 = Rim::default();
    for (k, &(x, y)) in corners.iter().enumerate() {
        let (cos, sin) = unit((k as f64 - 1.0) * FRAC_PI_2);
        let len = if k % 2 == 0 { w } else { h };
        let f = b.face(plane(V3::new(cos, sin, 0.0), V3::new(x, y, 0.0), len * t));
        outer0.push(V3::new(x, y, 0.0), f, 0.0);
    }
    let outer1 = outer0.mapped(|p| V3::new(p.x, p.y, t));
    b.walls(&outer0, &outer1, false, &[]);
    let n360 = segments(TAU, step);
    let (mut rims0, mut rims1) = (vec![outer0], vec![outer1]);
    for &[x, y, r] in &o.holes {
        let c = V3::new(x, y, 0.0);
        let f = b.face(cylinder(c, V3::z(), r, TAU * r * t));
        let rim0 = Rim::circle(c, V3::x(), V3::y(), r, n360, f);
        let rim1 = rim0.mapped(|p| V3::new(p.x, p.y, t));
        b.walls(&rim0, &rim1, true, &[]);
        rims0.push(rim0);
        rims1.push(rim1);
    }
    b.planar(bottom, &rims0.iter().collect::<Vec<_>>());
    b.planar(top, &rims1.iter().collect::<Vec<_>>());
    Ok(b.finish((w * h - hole_area) * t))
}
