//! A bent sheet-metal L bracket. The sheet's profile in the xz plane is swept along y:
//!
//! ```text
//!   z                    ┌┐ ← flange B's end (z = b)
//!   │                    ││   flange B: x ∈ [a + r, a + r + t]
//!   │                    ││   (a slot through it, along x)
//!   │  bend: centre (a, r + t), inner radius r, outer r + t
//!   │ ┌──────────────────╯│
//!   │ └───────────────────╯  flange A: x ∈ [0, a], z ∈ [0, t] (a hole through it, along z)
//!   └──────────────────────── x
//! ```
//!
//! with `a = flange_a − (r + t)` so that the outer faces measure `flange_a` along x and
//! `flange_b` along z. The bend's inner and outer faces are quarter cylinders about the axis
//! through `(a, ·, r + t)` along y, tangent (G1) to both flanges on both sides of the sheet;
//! the thin faces (the flanges' ends and the two sides y = 0, y = width) meet the big faces at
//! sharp 90° edges. The sides are planar faces bounded by the whole L profile, arcs included.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::Vector3;

use super::build::{segments, unit, Builder, Rim};
use super::prismatic::{cylinder, plane, positive, require, step_of};
use super::CadPart;
use crate::mesh::Units;
use crate::Result;

type V3 = Vector3<f64>;

/// Options of [`bracket`]. Lengths in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct BracketOptions {
    /// Sheet thickness t.
    pub thickness: f64,
    /// Inner bend radius r.
    pub bend_radius: f64,
    /// Width of the sheet along y (the bend's length).
    pub width: f64,
    /// Outer length of flange A along x (the base), bend included.
    pub flange_a: f64,
    /// Outer height of flange B along z, bend included.
    pub flange_b: f64,
    /// Radius of the round hole through flange A, centred on its flat part.
    pub hole_radius: f64,
    /// Slot through flange B, centred on its flat part: `[length along y, width along z]`.
    pub slot: [f64; 2],
    /// Chordal step of the curved faces, degrees.
    pub step_deg: f64,
}

impl Default for BracketOptions {
    fn default() -> Self {
        BracketOptions {
            thickness: 2.0,
            bend_radius: 3.0,
            width: 60.0,
            flange_a: 40.0,
            flange_b: 30.0,
            hole_radius: 3.0,
            slot: [16.0, 6.0],
            step_deg: 12.0,
        }
    }
}

fn check(o: &BracketOptions) -> Result<()> {
    let (t, r) = (o.thickness, o.bend_radius);
    for (name, v) in [("thickness", t), ("bend_radius", r), ("width", o.width)] {
        positive(name, v)?;
    }
    positive("hole_radius", o.hole_radius)?;
    positive("slot", o.slot[0].min(o.slot[1]))?;
    let (a, fb) = (o.flange_a - r - t, o.flange_b - r - t);
    require(a > 0.0 && fb > 0.0, "flange_a", "flanges must be longer than the bend's r + t")?;
    require(2.0 * o.hole_radius < a.min(o.width), "hole_radius", "hole must fit in flange A")?;
    require(o.slot[0] > o.slot[1], "slot", "a slot is longer than wide")?;
    require(o.slot[0] < o.width && o.slot[1] < fb, "slot", "slot must fit in flange B")
}

/// A bent L bracket (see the module docs): two flanges joined by a 90° bend, a round hole in
/// flange A and a slot (two planes and two half cylinders) in flange B.
///
/// Volume: `W (a t + π((r + t)² − r²)/4 + t (b − r − t)) − π ρ² t − ((L − s) s + π s²/4) t`
/// for hole radius ρ and an L × s slot.
pub fn bracket(o: &BracketOptions) -> Result<CadPart> {
    check(o)?;
    let step = step_of(o.step_deg)?;
    let (t, r, w) = (o.thickness, o.bend_radius, o.width);
    let ro = r + t;
    let a = o.flange_a - ro;
    let (xi, xo, zb, top) = (a + r, a + ro, ro, o.flange_b);
    let (slot_len, slot_w) = (o.slot[0], o.slot[1]);
    let hole = PI * o.hole_radius * o.hole_radius;
    let slot_area = (slot_len - slot_w) * slot_w + 0.25 * PI * slot_w * slot_w;
    let profile_area = a * t + 0.25 * PI * (ro * ro - r * r) + t * (top - zb);
    let fb_area = (top - zb) * w - slot_area;
    let mut b = Builder::new("bracket", Units::Mm, step);
    let axis = V3::new(a, 0.0, zb);
    let a_bottom = b.face(plane(-V3::z(), V3::zeros(), a * w - hole));
    let a_end = b.face(plane(-V3::x(), V3::zeros(), t * w));
    let a_top = b.face(plane(V3::z(), V3::new(0.0, 0.0, t), a * w - hole));
    let bend_in = b.face(cylinder(axis, V3::y(), r, 0.25 * TAU * r * w));
    let b_in = b.face(plane(-V3::x(), V3::new(xi, 0.0, zb), fb_area));
    let b_end = b.face(plane(V3::z(), V3::new(xi, 0.0, top), t * w));
    let b_out = b.face(plane(V3::x(), V3::new(xo, 0.0, zb), fb_area));
    let bend_out = b.face(cylinder(axis, V3::y(), ro, 0.25 * TAU * ro * w));
    let side0 = b.face(plane(-V3::y(), V3::zeros(), profile_area));
    let side1 = b.face(plane(V3::y(), V3::new(0.0, w, 0.0), profile_area));
    // The profile at y = 0; arcs about the bend's axis, φ measured from +x towards +z.
    let n90 = segments(FRAC_PI_2, step);
    let (ex, ez) = (V3::x(), V3::z());
    let mut p0 = Rim::default();
    p0.push(V3::new(a, 0.0, 0.0), a_bottom, 0.0);
    p0.push(V3::new(0.0, 0.0, 0.0), a_end, 0.0);
    p0.push(V3::new(0.0, 0.0, t), a_top, 0.0);
    p0.push(V3::new(a, 0.0, t), bend_in, r);
    p0.arc(axis, [ex, ez], r, [-FRAC_PI_2, 0.0], n90, bend_in);
    p0.push(V3::new(xi, 0.0, zb), b_in, 0.0);
    p0.push(V3::new(xi, 0.0, top), b_end, 0.0);
    p0.push(V3::new(xo, 0.0, top), b_out, 0.0);
    p0.push(V3::new(xo, 0.0, zb), bend_out, ro);
    p0.arc(axis, [ex, ez], ro, [0.0, -FRAC_PI_2], n90, bend_out);
    let p1 = p0.mapped(|p| V3::new(p.x, w, p.z));
    b.walls(&p0, &p1, false, &[a_bottom, a_top, b_in, b_out]);
    b.planar(side0, &[&p0]);
    b.planar(side1, &[&p1]);
    flange_a_faces(&mut b, o, a, [a_bottom, a_top]);
    flange_b_faces(&mut b, o, [xi, xo, zb], [b_in, b_out]);
    let volume = w * profile_area - hole * t - slot_area * t;
    Ok(b.finish(volume))
}

/// Flange A's bottom and top (rectangles `[0, a] × [0, W]` at z = 0 and t) with the round hole
/// between them and its wall.
fn flange_a_faces(b: &mut Builder, o: &BracketOptions, a: f64, faces: [u32; 2]) {
    let (t, w, hr) = (o.thickness, o.width, o.hole_radius);
    let c = V3::new(0.5 * a, 0.5 * w, 0.0);
    let wall = b.face(cylinder(c, V3::z(), hr, TAU * hr * t));
    let h0 = Rim::circle(c, V3::x(), V3::y(), hr, segments(TAU, b.step()), wall);
    let h1 = h0.mapped(|p| V3::new(p.x, p.y, t));
    b.walls(&h0, &h1, true, &[]);
    for (face, z, hole) in [(faces[0], 0.0, &h0), (faces[1], t, &h1)] {
        let mut rect = Rim::default();
        for (x, y) in [(0.0, 0.0), (a, 0.0), (a, w), (0.0, w)] {
            rect.push(V3::new(x, y, z), face, 0.0);
        }
        b.planar(face, &[&rect, hole]);
    }
}

/// Flange B's inner and outer faces (`[0, W] × [r + t, b]` at x = a + r and a + r + t) with
/// the slot between them: its two flat sides (planes z = z₀ ± s/2 facing into the slot) and
/// its two rounded ends (half cylinders along x of radius s/2).
fn flange_b_faces(b: &mut Builder, o: &BracketOptions, [xi, xo, zb]: [f64; 3], faces: [u32; 2]) {
    let (t, w, top) = (o.thickness, o.width, o.flange_b);
    let (len, s) = (o.slot[0], 0.5 * o.slot[1]);
    let (zc, half) = (0.5 * (zb + top), 0.5 * (len - o.slot[1]));
    let ends = [V3::new(xi, 0.5 * w + half, zc), V3::new(xi, 0.5 * w - half, zc)];
    let side_area = 2.0 * half * t;
    let upper = b.face(plane(-V3::z(), V3::new(xi, 0.5 * w, zc + s), side_area));
    let lower = b.face(plane(V3::z(), V3::new(xi, 0.5 * w, zc - s), side_area));
    let n180 = segments(PI, b.step());
    let mut slot0 = Rim::default();
    for (k, (c, next)) in [(ends[0], upper), (ends[1], lower)].into_iter().enumerate() {
        let end = b.face(cylinder(c, V3::x(), s, PI * s * t));
        // φ from −90° + 180°k, measured from +y towards +z, round the slot's end.
        let a0 = -FRAC_PI_2 + PI * k as f64;
        let at = |a: f64| {
            let (cos, sin) = unit(a);
            c + (V3::y() * cos + V3::z() * sin) * s
        };
        slot0.push(at(a0), end, s);
        slot0.arc(c, [V3::y(), V3::z()], s, [a0, a0 + PI], n180, end);
        slot0.push(at(a0 + PI), next, 0.0);
    }
    let slot1 = slot0.mapped(|p| V3::new(xo, p.y, p.z));
    b.walls(&slot0, &slot1, true, &[]);
    for (face, x, slot) in [(faces[0], xi, &slot0), (faces[1], xo, &slot1)] {
        let mut rect = Rim::default();
        for (y, z) in [(0.0, zb), (w, zb), (w, top), (0.0, top)] {
            rect.push(V3::new(x, y, z), face, 0.0);
        }
        b.planar(face, &[&rect, slot]);
    }
}
