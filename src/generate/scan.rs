//! Scanned and sculpted test parts, meshed as a scanner's or a sculpting tool's mesher writes
//! them: marching tetrahedra over an implicit surface (`marching.rs`), so the triangles are
//! irregular, of every shape and size down to 2 % of a cell, and no vertex sits on a lattice of
//! the surface's parameters. Every part is closed, 2-manifold, outward and in millimetres.
//!
//! | part | size (mm) | what it has |
//! |---|---|---|
//! | [`bust_scan`] | 110 × 70 × 125 | a head (with a nose and brow), neck and shoulders blended smoothly; Gaussian noise along the normal (default RMS 0.08 mm) |
//! | [`rock_scan`] | 100 × 80 × 65 | a boulder: an ellipsoid with low-frequency lobes; the same noise (default 0.06 mm) |
//! | [`sculpt_creature`] | 150 × 60 × 85 | a four-legged creature (body, head, legs, tail) with sculpted skin folds on its back and neck (default 0.3 mm high, 4 mm wavelength); no noise |
//! | [`uv_character`] | 110 × 90 × 130 | a sculpted head with a nose, brow, cheeks and forehead wrinkles, UV-mapped by latitude and longitude about its vertical axis: a seam at the back, the poles on top and under the chin |
//!
//! Everything is deterministic: the implicit is a pure function, the mesh is walked in grid
//! order on one thread, and the noise of vertex i is drawn from (seed, i) alone.

mod marching;

pub use marching::{polygonize, MAX_NODES};

use std::f64::consts::{PI, TAU};

use nalgebra::{Vector2, Vector3};

use crate::mesh::{CornerAttribute, Mesh};
use crate::{Error, Result};

type V3 = Vector3<f64>;

/// Options of the scans ([`bust_scan`], [`rock_scan`]). Lengths in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanOptions {
    /// Edge of the marching grid's cubes. The mesh's mean edge is about 0.7 of it.
    pub cell: f64,
    /// RMS height of the Gaussian noise along the normal (0: none).
    pub noise: f64,
    /// Uniform scale of the part (1: the sizes in the module table).
    pub scale: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for ScanOptions {
    /// A 1.5 mm grid (about 1 mm between vertices), 0.08 mm noise, full size, seed 1.
    fn default() -> Self {
        ScanOptions { cell: 1.5, noise: 0.08, scale: 1.0, seed: 1 }
    }
}

/// Options of the sculpted parts ([`sculpt_creature`], [`uv_character`]). Lengths in
/// millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct SculptOptions {
    /// Edge of the marching grid's cubes.
    pub cell: f64,
    /// Height of the sculpted wrinkles (0: none).
    pub wrinkle_height: f64,
    /// Wavelength of the wrinkles.
    pub wrinkle_wavelength: f64,
    /// Uniform scale of the part (the wrinkles are not scaled).
    pub scale: f64,
}

impl Default for SculptOptions {
    /// A 1.2 mm grid, wrinkles 0.3 mm high of 4 mm wavelength, full size.
    fn default() -> Self {
        SculptOptions { cell: 1.2, wrinkle_height: 0.3, wrinkle_wavelength: 4.0, scale: 1.0 }
    }
}

/// Smooth union of two signed distances (polynomial smooth minimum of width `k`).
fn smin(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

/// An approximate signed distance to the ellipsoid of centre `c` and radii `r`.
fn ellipsoid(p: &V3, c: V3, r: V3) -> f64 {
    let q = (p - c).component_div(&r);
    (q.norm() - 1.0) * r.min()
}

/// The signed distance to the capsule from `a` to `b` of radius `r`.
fn capsule(p: &V3, a: V3, b: V3, r: f64) -> f64 {
    let (pa, ba) = (p - a, b - a);
    let h = (pa.dot(&ba) / ba.norm_squared()).clamp(0.0, 1.0);
    (pa - ba * h).norm() - r
}

/// A smooth bump of height 1 and width `w` centred at `c`.
fn bump(p: &V3, c: V3, w: f64) -> f64 {
    (-(p - c).norm_squared() / (w * w)).exp()
}

fn check(name: &str, v: f64, allow_zero: bool) -> Result<()> {
    if v.is_finite() && (v > 0.0 || (allow_zero && v == 0.0)) {
        Ok(())
    } else {
        Err(Error::invalid_arg(
            name,
            format!(
                "must be a {} number, not {v}",
                if allow_zero { "non-negative" } else { "positive" }
            ),
        ))
    }
}

fn check_scan(o: &ScanOptions) -> Result<()> {
    check("cell", o.cell, false)?;
    check("noise", o.noise, true)?;
    check("scale", o.scale, false)
}

fn check_sculpt(o: &SculptOptions) -> Result<()> {
    check("cell", o.cell, false)?;
    check("wrinkle_height", o.wrinkle_height, true)?;
    check("wrinkle_wavelength", o.wrinkle_wavelength, false)?;
    check("scale", o.scale, false)
}

/// The bust's implicit, unit scale (mm): head, nose, brow, neck, shoulders.
fn bust(p: &V3) -> f64 {
    let head = ellipsoid(p, V3::new(0.0, 0.0, 88.0), V3::new(30.0, 34.0, 38.0));
    let nose = ellipsoid(p, V3::new(0.0, -33.0, 84.0), V3::new(5.0, 8.0, 11.0));
    let brow = ellipsoid(p, V3::new(0.0, -27.0, 100.0), V3::new(22.0, 8.0, 6.0));
    let neck = capsule(p, V3::new(0.0, 2.0, 30.0), V3::new(0.0, 2.0, 60.0), 16.0);
    let chest = ellipsoid(p, V3::new(0.0, 5.0, 18.0), V3::new(55.0, 28.0, 24.0));
    let face = smin(smin(head, nose, 4.0), brow, 5.0);
    smin(smin(face, neck, 10.0), chest, 12.0)
}

/// The rock's implicit, unit scale (mm): an ellipsoid with lobes of 25–60 mm.
fn rock(p: &V3) -> f64 {
    let base = ellipsoid(p, V3::zeros(), V3::new(48.0, 38.0, 30.0));
    let lobes = 4.0 * (p.x / 19.0 + 0.7).sin() * (p.y / 23.0 - 0.4).cos()
        + 3.0 * (p.z / 15.0 + p.x / 31.0).sin()
        + 2.0 * bump(p, V3::new(20.0, -20.0, 18.0), 18.0);
    base - lobes
}

/// Central-difference gradient of `f`, unit (or +z where it vanishes).
fn unit_gradient(f: &dyn Fn(&V3) -> f64, p: &V3, h: f64) -> V3 {
    let d = |e: V3| (f(&(p + e * h)) - f(&(p - e * h))) / (2.0 * h);
    V3::new(d(V3::x()), d(V3::y()), d(V3::z())).try_normalize(1e-300).unwrap_or_else(V3::z)
}

/// Moves vertex i by σ·gᵢ along the implicit's normal, gᵢ standard normal from (seed, i).
fn add_noise(mesh: &mut Mesh, f: &dyn Fn(&V3) -> f64, sigma: f64, seed: u64, h: f64) {
    if sigma == 0.0 {
        return;
    }
    for (i, p) in mesh.positions.iter_mut().enumerate() {
        let n = unit_gradient(f, p, h);
        *p += n * (sigma * gaussian(seed, i as u64));
    }
}

/// A standard normal deviate from (seed, index) (Box–Muller on two SplitMix64 draws).
fn gaussian(seed: u64, index: u64) -> f64 {
    let mix = |x: u64| {
        let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let a = mix(seed ^ index.wrapping_mul(0xD6E8_FEB8_6659_FD93));
    let b = mix(a);
    let u1 = ((a >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let u2 = (b >> 11) as f64 / (1u64 << 53) as f64;
    (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
}

/// A scanned bust (module table): 40–60k vertices with the defaults.
pub fn bust_scan(o: &ScanOptions) -> Result<Mesh> {
    check_scan(o)?;
    let s = o.scale;
    let f = move |p: &V3| bust(&(p / s)) * s;
    let mut mesh =
        polygonize(&f, V3::new(-60.0, -45.0, -10.0) * s, V3::new(60.0, 40.0, 130.0) * s, o.cell)?;
    add_noise(&mut mesh, &f, o.noise, o.seed, 0.1 * o.cell);
    Ok(mesh)
}

/// A scanned rock (module table): 40–60k vertices with the defaults.
pub fn rock_scan(o: &ScanOptions) -> Result<Mesh> {
    check_scan(o)?;
    let s = o.scale;
    let f = move |p: &V3| rock(&(p / s)) * s;
    let mut mesh =
        polygonize(&f, V3::new(-60.0, -50.0, -42.0) * s, V3::new(60.0, 50.0, 42.0) * s, o.cell)?;
    add_noise(&mut mesh, &f, o.noise, o.seed ^ 0x5EED, 0.1 * o.cell);
    Ok(mesh)
}

/// Skin folds: height `a`, wavelength `l`, running around the body's long axis (x), faded in
/// by `window` (0–1).
fn folds(p: &V3, a: f64, l: f64, window: f64) -> f64 {
    if a == 0.0 || window <= 0.0 {
        return 0.0;
    }
    let wobble = 1.5 * (p.y / 9.0).sin() + 1.0 * (p.z / 13.0).cos();
    a * window * (TAU * (p.x + wobble) / l).sin()
}

/// The creature's implicit (mm), wrinkles of height `a` and wavelength `l` included.
fn creature(p: &V3, a: f64, l: f64) -> f64 {
    let body = ellipsoid(p, V3::new(0.0, 0.0, 45.0), V3::new(45.0, 22.0, 20.0));
    let head = ellipsoid(p, V3::new(58.0, 0.0, 62.0), V3::new(16.0, 13.0, 14.0));
    let snout = ellipsoid(p, V3::new(72.0, 0.0, 58.0), V3::new(10.0, 8.0, 7.0));
    let neck = capsule(p, V3::new(30.0, 0.0, 50.0), V3::new(52.0, 0.0, 60.0), 10.0);
    let tail = capsule(p, V3::new(-40.0, 0.0, 48.0), V3::new(-72.0, 0.0, 62.0), 4.0);
    let mut legs = f64::INFINITY;
    for (x, y) in [(28.0, 12.0), (28.0, -12.0), (-28.0, 12.0), (-28.0, -12.0)] {
        legs = legs.min(capsule(p, V3::new(x, y, 38.0), V3::new(x * 1.05, y * 1.3, 5.0), 6.5));
    }
    let d = smin(smin(smin(smin(body, head, 6.0), snout, 3.0), neck, 6.0), tail, 4.0);
    let d = smin(d, legs, 5.0);
    // Folds over the back and the neck (above the body's mid-height), faded in over 10 mm.
    let window =
        ((p.z - 45.0) / 10.0).clamp(0.0, 1.0) * ((70.0 - p.x.abs()) / 10.0).clamp(0.0, 1.0);
    d - folds(p, a, l, window)
}

/// A sculpted creature (module table), without UVs: 40–60k vertices with the defaults.
pub fn sculpt_creature(o: &SculptOptions) -> Result<Mesh> {
    check_sculpt(o)?;
    let (s, a, l) = (o.scale, o.wrinkle_height, o.wrinkle_wavelength);
    let f = move |p: &V3| creature(&(p / s), a / s, l / s) * s;
    polygonize(&f, V3::new(-80.0, -30.0, -2.0) * s, V3::new(85.0, 30.0, 80.0) * s, o.cell)
}

/// The UV character's radius in direction `d` (unit), wrinkles included (mm).
fn head_radius(d: &V3, a: f64, l: f64) -> f64 {
    let base = 1.0 / ((d.x / 48.0).powi(2) + (d.y / 42.0).powi(2) + (d.z / 62.0).powi(2)).sqrt();
    let nose = 14.0 * (-(d - V3::new(0.0, -0.97, -0.05)).norm_squared() / 0.02).exp();
    let brow = 5.0 * (-((d.z - 0.3).powi(2) / 0.01 + d.x.powi(2) / 0.12)).exp() * (-d.y).max(0.0);
    let cheeks = [-1.0, 1.0]
        .iter()
        .map(|&sx| 6.0 * (-(d - V3::new(0.55 * sx, -0.75, -0.3)).norm_squared() / 0.05).exp())
        .sum::<f64>();
    // Forehead wrinkles: rings of latitude above the brow, on the face's side.
    let forehead = ((d.z - 0.4) / 0.1).clamp(0.0, 1.0) * ((0.85 - d.z) / 0.1).clamp(0.0, 1.0);
    let wrinkles = a * forehead * (-d.y).max(0.0) * (TAU * base * d.z.asin() / l).sin();
    base + nose + brow + cheeks + wrinkles
}

/// A sculpted, UV-mapped head (module table): 40–60k vertices with the defaults. UVs are
/// (longitude / 2π + ½, 1 − colatitude / π) about the vertical axis through the centre, with a
/// seam where the longitude wraps (the back of the head, −x); u runs east and v north, so the
/// chart is not mirrored.
pub fn uv_character(o: &SculptOptions) -> Result<Mesh> {
    check_sculpt(o)?;
    let (s, a, l) = (o.scale, o.wrinkle_height, o.wrinkle_wavelength);
    let f = move |p: &V3| {
        let q = p / s;
        let r = q.norm();
        if r < 1e-9 {
            return -40.0 * s;
        }
        (r - head_radius(&(q / r), a / s, l / s)) * s
    };
    let mut mesh =
        polygonize(&f, V3::new(-55.0, -65.0, -70.0) * s, V3::new(55.0, 50.0, 70.0) * s, o.cell)?;
    mesh.uv = Some(lat_long(&mesh));
    Ok(mesh)
}

/// Latitude–longitude UVs about the z axis, one value per vertex and a second copy (u + 1) for
/// the corners of faces that straddle the seam.
fn lat_long(mesh: &Mesh) -> CornerAttribute<Vector2<f64>> {
    let nv = mesh.num_vertices();
    let base: Vec<Vector2<f64>> = mesh
        .positions
        .iter()
        .map(|p| {
            let u = p.y.atan2(p.x) / TAU + 0.5;
            let v = 1.0 - (p.z / p.norm().max(1e-300)).clamp(-1.0, 1.0).acos() / PI;
            Vector2::new(u, v)
        })
        .collect();
    let mut values = base.clone();
    let mut wrapped: Vec<Option<u32>> = vec![None; nv];
    let mut corners = Vec::with_capacity(mesh.num_faces());
    for f in &mesh.faces {
        let us = f.map(|i| base[i as usize].x);
        let span = us.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - us.iter().cloned().fold(f64::INFINITY, f64::min);
        corners.push(f.map(|i| {
            let i = i as usize;
            if span > 0.5 && base[i].x < 0.5 {
                *wrapped[i].get_or_insert_with(|| {
                    values.push(base[i] + Vector2::new(1.0, 0.0));
                    (values.len() - 1) as u32
                })
            } else {
                i as u32
            }
        }));
    }
    CornerAttribute { values, corners }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_draws_have_unit_variance() {
        let n = 20000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for i in 0..n {
            let g = gaussian(7, i);
            s1 += g;
            s2 += g * g;
        }
        let mean = s1 / n as f64;
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((s2 / n as f64 - 1.0).abs() < 0.05);
    }
}
