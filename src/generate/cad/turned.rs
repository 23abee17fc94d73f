//! A turned part: a profile in the (ρ, z) half-plane revolved about the z axis. Each profile
//! vertex becomes a ring of n = ⌈360° / step⌉ vertices at the same angles θⱼ = 2πj/n, so
//! neighbouring faces share their rings; a profile segment becomes one strip of quads
//! between two rings (cylinder, cone), several segments one strip each (the fillet's arc), a
//! segment at constant z a planar annulus ear-clipped from its two rings, and the end rings
//! planar disks ear-clipped from their rim (fans of slivers out of one rim vertex).
//!
//! ```text
//!  z
//!  L ┤      ┌─╮  ← top disk ρ ≤ R₂ − c, 45° chamfer (cone) below it
//!    │      │ │  shank: cylinder ρ = R₂
//!    │      │ │
//!    │      │ ╰──╮ ← fillet: torus about z, tube centre (R₂ + f, h + f), minor radius f
//!  h ┤      │    │ ← shoulder: annulus z = h, R₂ + f ≤ ρ ≤ R₁
//!    │      │    │  collar: cylinder ρ = R₁
//!  0 ┤      └────┘ ← bottom disk ρ ≤ R₁
//!    └──────┴────┴── ρ
//! ```

use std::f64::consts::{FRAC_PI_2, PI, SQRT_2, TAU};

use nalgebra::Vector3;

use super::build::{segments, unit, Builder, Rim};
use super::prismatic::{cylinder, plane, positive, require, step_of};
use super::{AnalyticFace, CadPart};
use crate::mesh::Units;
use crate::Result;

type V3 = Vector3<f64>;

/// Options of [`turned`]. Lengths in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct TurnedOptions {
    /// Radius R₁ of the collar (the wide cylinder at the bottom).
    pub collar_radius: f64,
    /// Height h of the collar: the shoulder is the plane z = h.
    pub collar_length: f64,
    /// Radius R₂ of the shank (the narrow cylinder above the shoulder).
    pub shank_radius: f64,
    /// Overall length L along z.
    pub length: f64,
    /// Radius f of the fillet between the shoulder and the shank.
    pub fillet_radius: f64,
    /// Leg c of the 45° chamfer at the shank's top edge.
    pub chamfer: f64,
    /// Chordal step around the axis and along the fillet, degrees.
    pub step_deg: f64,
}

impl Default for TurnedOptions {
    fn default() -> Self {
        TurnedOptions {
            collar_radius: 20.0,
            collar_length: 25.0,
            shank_radius: 12.0,
            length: 60.0,
            fillet_radius: 2.0,
            chamfer: 1.5,
            step_deg: 12.0,
        }
    }
}

fn check(o: &TurnedOptions) -> Result<()> {
    for (name, v) in [
        ("collar_radius", o.collar_radius),
        ("collar_length", o.collar_length),
        ("shank_radius", o.shank_radius),
        ("fillet_radius", o.fillet_radius),
        ("chamfer", o.chamfer),
    ] {
        positive(name, v)?;
    }
    let (r2, f, c) = (o.shank_radius, o.fillet_radius, o.chamfer);
    require(
        r2 + f < o.collar_radius,
        "shank_radius",
        "shank + fillet must be narrower than the collar",
    )?;
    require(c < r2, "chamfer", "chamfer must be smaller than the shank's radius")?;
    require(
        o.collar_length + f + c < o.length,
        "length",
        "too short for collar, fillet and chamfer",
    )
}

/// The exact volume: collar, shank and frustum as cylinders and a cone, plus the fillet's
/// ring by Pappus, `2π · ∫ρ dA` over the corner square `[R₂, R₂ + f] × [h, h + f]` minus the
/// quarter disk of the tube: `f²(R₂ + f/2) − (πf²/4)(R₂ + f) + f³/3`.
fn volume(o: &TurnedOptions) -> f64 {
    let (r1, h, r2, len, f, c) =
        (o.collar_radius, o.collar_length, o.shank_radius, o.length, o.fillet_radius, o.chamfer);
    let collar = PI * r1 * r1 * h;
    let shank = PI * r2 * r2 * (len - c - h);
    let fillet = TAU * (f * f * (r2 + 0.5 * f) - 0.25 * PI * f * f * (r2 + f) + f * f * f / 3.0);
    let rc = r2 - c;
    let frustum = PI * c / 3.0 * (r2 * r2 + r2 * rc + rc * rc);
    collar + shank + fillet + frustum
}

/// A shaft turned about z (see the module docs): bottom disk, collar, shoulder, fillet,
/// shank, chamfer, top disk.
///
/// Areas: disks πρ², cylinders 2πρ·length, the shoulder π(R₁² − (R₂ + f)²), the chamfer's
/// frustum π(R₂ + R₂ − c)·c√2, the fillet (its tube circle swept from φ = 180° to 270° about
/// the tube centre, ρ = R + f cos φ with R = R₂ + f) `2π f ∫ρ dφ = 2π f (πR/2 − f)`.
pub fn turned(o: &TurnedOptions) -> Result<CadPart> {
    check(o)?;
    let step = step_of(o.step_deg)?;
    let (r1, h, r2, len, f, c) =
        (o.collar_radius, o.collar_length, o.shank_radius, o.length, o.fillet_radius, o.chamfer);
    let (rt, zc) = (r2 - c, len - c);
    let big = r2 + f;
    let mut b = Builder::new("turned", Units::Mm, step);
    let z = V3::z();
    let bottom = b.face(plane(-z, V3::zeros(), PI * r1 * r1));
    let collar = b.face(cylinder(V3::zeros(), z, r1, TAU * r1 * h));
    let shoulder = b.face(plane(z, V3::new(0.0, 0.0, h), PI * (r1 * r1 - big * big)));
    let fillet = b.face(AnalyticFace::Torus {
        center: V3::new(0.0, 0.0, h + f),
        axis_dir: z,
        major_radius: big,
        minor_radius: f,
        area: TAU * f * (0.5 * PI * big - f),
    });
    let shank = b.face(cylinder(V3::zeros(), z, r2, TAU * r2 * (zc - h - f)));
    let chamfer = b.face(AnalyticFace::Cone {
        apex: V3::new(0.0, 0.0, zc + r2),
        axis_dir: -z,
        half_angle: 0.25 * PI,
        area: PI * (r2 + rt) * c * SQRT_2,
    });
    let top = b.face(plane(z, V3::new(0.0, 0.0, len), PI * rt * rt));
    // The profile, bottom to top, with the face of the segment that follows each point.
    let mut profile = vec![(r1, 0.0, collar), (r1, h, shoulder), (big, h, fillet)];
    let n90 = segments(FRAC_PI_2, step);
    for j in 1..n90 {
        // φ from −90° down to −180° about the tube centre (R₂ + f, h + f).
        let (cos, sin) = unit(-FRAC_PI_2 - FRAC_PI_2 * j as f64 / n90 as f64);
        profile.push((big + f * cos, h + f + f * sin, fillet));
    }
    profile.extend([(r2, h + f, shank), (r2, zc, chamfer), (rt, len, top)]);
    let n = segments(TAU, step);
    let rings: Vec<Rim> = profile
        .iter()
        .map(|&(rho, zz, _)| Rim::circle(V3::new(0.0, 0.0, zz), V3::x(), V3::y(), rho, n, 0))
        .collect();
    for k in 0..profile.len() - 1 {
        let face = profile[k].2;
        if b.is_planar(face) {
            b.planar(face, &[&rings[k], &rings[k + 1]]);
        } else {
            b.strip(&rings[k], &rings[k + 1], face);
        }
    }
    b.planar(bottom, &[&rings[0]]);
    b.planar(top, &[&rings[profile.len() - 1]]);
    Ok(b.finish(volume(o)))
}
