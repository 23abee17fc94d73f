//! A turned knob: a profile in the (ρ, z) half-plane revolved about the z axis, as
//! [`super::turned`] builds it (rings of n = ⌈360° / step⌉ vertices, strips of trapezoids,
//! planar annuli and disks ear-clipped), with the faces a knob's designer brushes: a skirt
//! that meets a *shallow* chamfer (a 26.6° edge, below a crease angle of 40°), a boss whose
//! top edge is rounded by a convex torus, and a spherical crown tangent to that round.
//!
//! ```text
//!  z            ╭──╮  ← crown: sphere centred on the axis, tangent to the round
//!               │  │  ← round: torus, tube centre (R_b − r, z_b), minor radius r, 0° … θ
//!    z_b ┤      │  │  boss: cylinder ρ = R_b
//!        │   ┌──┘  │ ← shoulder: annulus z = H + 2c
//!        │  ╱      ← chamfer: cone, 26.6° from the skirt (ρ falls by c as z rises by 2c)
//!      H ┤ │       skirt: cylinder ρ = R
//!      0 ┤ └────── bottom disk
//! ```

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::Vector3;

use super::build::{segments, unit, Builder, Rim};
use super::prismatic::{cylinder, plane, positive, require, step_of};
use super::{AnalyticFace, CadPart};
use crate::mesh::Units;
use crate::Result;

type V3 = Vector3<f64>;

/// Options of [`knob`]. Lengths in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct KnobOptions {
    /// Radius R of the skirt.
    pub skirt_radius: f64,
    /// Height H of the skirt.
    pub skirt_height: f64,
    /// Radial leg c of the chamfer (it rises by 2c: 26.57° from the skirt).
    pub chamfer: f64,
    /// Radius R_b of the boss.
    pub boss_radius: f64,
    /// Height of the boss above the shoulder.
    pub boss_height: f64,
    /// Radius r of the round at the boss's top edge.
    pub round_radius: f64,
    /// Angle θ the round turns through before the crown takes over, degrees.
    pub round_sweep_deg: f64,
    /// Chordal step around the axis and along the round and the crown, degrees.
    pub step_deg: f64,
}

impl Default for KnobOptions {
    fn default() -> Self {
        KnobOptions {
            skirt_radius: 20.0,
            skirt_height: 12.0,
            chamfer: 1.0,
            boss_radius: 12.0,
            boss_height: 6.0,
            round_radius: 3.0,
            round_sweep_deg: 60.0,
            step_deg: 12.0,
        }
    }
}

/// The knob's profile, derived from its options.
struct Profile {
    r: f64,
    h: f64,
    c: f64,
    rb: f64,
    /// z of the boss's top (the round starts there).
    zb: f64,
    rr: f64,
    theta: f64,
    /// The crown: its centre's z and its radius.
    zc: f64,
    rs: f64,
}

impl Profile {
    fn new(o: &KnobOptions) -> Self {
        let theta = o.round_sweep_deg.to_radians();
        let zb = o.skirt_height + 2.0 * o.chamfer + o.boss_height;
        let core = o.boss_radius - o.round_radius;
        // The crown's normal at the round's end runs through the tube centre to the axis.
        let zc = zb - core * theta.tan();
        let rs = core / theta.cos() + o.round_radius;
        Profile {
            r: o.skirt_radius,
            h: o.skirt_height,
            c: o.chamfer,
            rb: o.boss_radius,
            zb,
            rr: o.round_radius,
            theta,
            zc,
            rs,
        }
    }

    /// The crown's polar angle at the round's end (from the axis).
    fn crown_angle(&self) -> f64 {
        FRAC_PI_2 - self.theta
    }
}

fn check(o: &KnobOptions) -> Result<()> {
    for (name, v) in [
        ("skirt_radius", o.skirt_radius),
        ("skirt_height", o.skirt_height),
        ("chamfer", o.chamfer),
        ("boss_radius", o.boss_radius),
        ("boss_height", o.boss_height),
        ("round_radius", o.round_radius),
    ] {
        positive(name, v)?;
    }
    require(
        o.boss_radius < o.skirt_radius - o.chamfer,
        "boss_radius",
        "the boss must be narrower than the chamfer's top",
    )?;
    require(o.round_radius < o.boss_radius, "round_radius", "must be smaller than the boss")?;
    require(
        (10.0..=80.0).contains(&o.round_sweep_deg),
        "round_sweep_deg",
        "must lie in [10, 80] degrees",
    )
}

/// The exact volume, π ∫ ρ(z)² dz up the profile (the shoulder adds nothing): the skirt, the
/// chamfer's frustum and the boss in closed form, the round and the crown by Simpson's rule
/// on 2¹⁶ intervals (far below the chords' error).
fn volume(p: &Profile) -> f64 {
    let skirt = p.r * p.r * p.h;
    let top = p.r - p.c;
    let frustum = 2.0 * p.c / 3.0 * (p.r * p.r + p.r * top + top * top);
    let boss = p.rb * p.rb * (p.zb - p.h - 2.0 * p.c);
    let simpson = |f: &dyn Fn(f64) -> f64, a: f64, b: f64| {
        let n = 1 << 16;
        let h = (b - a) / n as f64;
        let s: f64 = (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * f(a + h * i as f64)
            })
            .sum();
        s * h / 3.0
    };
    let core = p.rb - p.rr;
    // The round: ρ = core + r cos φ, z = z_b + r sin φ, dz = r cos φ dφ.
    let round = simpson(&|f: f64| (core + p.rr * f.cos()).powi(2) * p.rr * f.cos(), 0.0, p.theta);
    let z0 = p.zb + p.rr * p.theta.sin();
    let crown = simpson(&|z: f64| p.rs * p.rs - (z - p.zc).powi(2), z0, p.zc + p.rs);
    PI * (skirt + frustum + boss + round + crown)
}

/// A knob turned about z (see the module docs): bottom disk, skirt, chamfer, shoulder, boss,
/// round, crown.
pub fn knob(o: &KnobOptions) -> Result<CadPart> {
    check(o)?;
    let step = step_of(o.step_deg)?;
    let p = Profile::new(o);
    let mut b = Builder::new("knob", Units::Mm, step);
    let z = V3::z();
    let (r, h, c, rb, zb, rr) = (p.r, p.h, p.c, p.rb, p.zb, p.rr);
    let core = rb - rr;
    let zs = h + 2.0 * c;
    let bottom = b.face(plane(-z, V3::zeros(), PI * r * r));
    let skirt = b.face(cylinder(V3::zeros(), z, r, TAU * r * h));
    let half_angle = (0.5f64).atan();
    let chamfer = b.face(AnalyticFace::Cone {
        // ρ = r − (z − h)/2 reaches 0 at z = h + 2r; the cone opens downwards.
        apex: V3::new(0.0, 0.0, h + 2.0 * r),
        axis_dir: -z,
        half_angle,
        area: PI * (r + r - c) * c * 5f64.sqrt(),
    });
    let shoulder = b.face(plane(z, V3::new(0.0, 0.0, zs), PI * ((r - c).powi(2) - rb * rb)));
    let boss = b.face(cylinder(V3::zeros(), z, rb, TAU * rb * (zb - zs)));
    let round = b.face(AnalyticFace::Torus {
        center: V3::new(0.0, 0.0, zb),
        axis_dir: z,
        major_radius: core,
        minor_radius: rr,
        area: TAU * rr * (core * p.theta + rr * p.theta.sin()),
    });
    let psi = p.crown_angle();
    let crown = b.face(AnalyticFace::Sphere {
        center: V3::new(0.0, 0.0, p.zc),
        radius: p.rs,
        area: TAU * p.rs * p.rs * (1.0 - psi.cos()),
    });
    let mut profile = vec![
        (r, 0.0, skirt),
        (r, h, chamfer),
        (r - c, zs, shoulder),
        (rb, zs, boss),
        (rb, zb, round),
    ];
    let nr = segments(p.theta, step);
    for j in 1..=nr {
        let (cos, sin) = unit(p.theta * j as f64 / nr as f64);
        profile.push((core + rr * cos, zb + rr * sin, if j == nr { crown } else { round }));
    }
    // The crown from its rim (polar angle ψ) towards the pole; the last ring closes in a fan.
    let nc = segments(psi, step);
    for j in 1..nc {
        let (cos, sin) = unit(psi * (1.0 - j as f64 / nc as f64));
        profile.push((p.rs * sin, p.zc + p.rs * cos, crown));
    }
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
    let pole = V3::new(0.0, 0.0, p.zc + p.rs);
    let last = &rings[profile.len() - 1];
    for j in 0..n {
        b.tri([last.pts[j], last.pts[(j + 1) % n], pole], crown);
    }
    b.planar(bottom, &[&rings[0]]);
    Ok(b.finish(volume(&p)))
}
