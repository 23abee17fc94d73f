//! Fitting the primitives to the vertices of a set of planar regions (docs/math.md §3,
//! "Recognized surfaces"). A CAD export puts every vertex *on* its surface, so the fits are
//! exact up to the file's rounding; each is a linear least-squares problem in coordinates
//! centred on the points and scaled to unit spread, and each is judged afterwards by its
//! largest distance to the points.
//!
//! * **Sphere:** |q|² + D·q + E = 0 (Kåsa's algebraic fit), centre −D/2.
//! * **Cylinder:** the axis is the direction every chord's normal is perpendicular to (the
//!   least eigenvector of Σ nnᵀ: a strip between two rulings contains the ruling's
//!   direction), then a circle fitted to the points projected along it.
//! * **Surfaces of revolution** (cone, torus, sphere about an axis): a planar chord of a
//!   surface of revolution meshed along meridians and parallels is a symmetric trapezoid (or
//!   an isosceles triangle at a pole), so the line along its normal through its corners' mean
//!   lies in a meridian plane and meets the axis. The axis (a, ā) in Plücker coordinates
//!   minimises Σ (dᵢ·ā + mᵢ·a)² over those lines (dᵢ, mᵢ = cᵢ × dᵢ), |a| = 1 (Pottmann and
//!   Randrup 1998, "Rotational and helical surface approximation for reverse engineering"):
//!   ā = −M_dd⁻¹ M_mdᵀ a and a the least eigenvector of the Schur complement. The profile
//!   (ρ, h) of the points about that axis is then a line (cone) or a circle (torus; a sphere
//!   when its centre is on the axis).

use nalgebra::{Matrix2, Matrix3, Matrix4, SymmetricEigen, Vector2, Vector3, Vector4};

use super::primitive::Primitive;

type V3 = Vector3<f64>;

/// Points centred on their mean and scaled to unit RMS distance from it.
struct Normalized {
    centre: V3,
    scale: f64,
    q: Vec<V3>,
}

fn normalized(points: &[V3]) -> Option<Normalized> {
    if points.len() < 3 {
        return None;
    }
    let centre = points.iter().sum::<V3>() / points.len() as f64;
    let spread = (points.iter().map(|p| (p - centre).norm_squared()).sum::<f64>()
        / points.len() as f64)
        .sqrt();
    if !(spread > 0.0 && spread.is_finite()) {
        return None;
    }
    let q = points.iter().map(|p| (p - centre) / spread).collect();
    Some(Normalized { centre, scale: spread, q })
}

/// The eigenvector of the least eigenvalue of a symmetric 3 × 3 matrix, and the eigenvalues in
/// increasing order.
fn least_eigen(m: Matrix3<f64>) -> (V3, [f64; 3]) {
    let e = SymmetricEigen::new(m);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
    let v = e.eigenvectors.column(idx[0]).into_owned();
    (v, idx.map(|i| e.eigenvalues[i]))
}

/// A direction made unique up to its sign: its largest component positive.
fn canonical(v: V3) -> V3 {
    let k = v.iamax();
    if v[k] < 0.0 {
        -v
    } else {
        v
    }
}

/// The largest distance of the points from their best plane (0 for fewer than three).
pub fn flatness(points: &[V3]) -> f64 {
    let Some(n) = normalized(points) else { return 0.0 };
    let m: Matrix3<f64> = n.q.iter().map(|q| q * q.transpose()).sum();
    let (normal, _) = least_eigen(m);
    n.q.iter().map(|q| q.dot(&normal).abs()).fold(0.0, f64::max) * n.scale
}

/// The sphere through the points (Kåsa).
pub fn sphere(points: &[V3]) -> Option<Primitive> {
    let n = normalized(points)?;
    if n.q.len() < 4 {
        return None;
    }
    let mut a = Matrix4::zeros();
    let mut b = Vector4::zeros();
    for q in &n.q {
        let row = Vector4::new(q.x, q.y, q.z, 1.0);
        a += row * row.transpose();
        b -= row * q.norm_squared();
    }
    let x = a.cholesky()?.solve(&b);
    let c = V3::new(-0.5 * x[0], -0.5 * x[1], -0.5 * x[2]);
    let r2 = c.norm_squared() - x[3];
    if r2.is_nan() || r2 <= 0.0 {
        return None;
    }
    let center = n.centre + c * n.scale;
    Some(Primitive::Sphere { center: center.into(), radius: r2.sqrt() * n.scale })
}

/// The circle through 2D points (Kåsa): centre and radius.
fn circle(points: &[Vector2<f64>]) -> Option<(Vector2<f64>, f64)> {
    if points.len() < 3 {
        return None;
    }
    let mut a = Matrix3::zeros();
    let mut b = V3::zeros();
    for p in points {
        let row = V3::new(p.x, p.y, 1.0);
        a += row * row.transpose();
        b -= row * p.norm_squared();
    }
    let x = a.cholesky()?.solve(&b);
    let c = Vector2::new(-0.5 * x[0], -0.5 * x[1]);
    let r2 = c.norm_squared() - x[2];
    (r2 > 0.0 && r2.is_finite()).then(|| (c, r2.sqrt()))
}

/// The cylinder whose axis every chord normal in `normals` is perpendicular to, through the
/// points.
pub fn cylinder(points: &[V3], normals: &[V3]) -> Option<Primitive> {
    let n = normalized(points)?;
    if normals.len() < 2 {
        return None;
    }
    let m: Matrix3<f64> = normals.iter().map(|v| v * v.transpose()).sum();
    let (axis, ev) = least_eigen(m);
    if ev[1].is_nan() || ev[1] <= 1e-10 * ev[2] {
        return None; // one normal direction: no axis
    }
    let axis = canonical(axis);
    let f = crate::geometry::frames::Frame::from_normal(axis);
    let flat: Vec<Vector2<f64>> =
        n.q.iter().map(|q| Vector2::new(q.dot(&f.t), q.dot(&f.b))).collect();
    let (c, r) = circle(&flat)?;
    let point = n.centre + (f.t * c.x + f.b * c.y) * n.scale;
    Some(Primitive::Cylinder { point: point.into(), axis: axis.into(), radius: r * n.scale })
}

/// The axis of revolution (a point on it and its unit direction) that the normal `lines`
/// (a point and a unit direction each) meet best, or `None` when they do not fix one (fewer
/// than six lines, or lines all parallel to a plane, as a cylinder's are).
pub fn revolution_axis(lines: &[(V3, V3)]) -> Option<(V3, V3)> {
    if lines.len() < 6 {
        return None;
    }
    let origin = lines.iter().map(|l| l.0).sum::<V3>() / lines.len() as f64;
    let scale = (lines.iter().map(|l| (l.0 - origin).norm_squared()).sum::<f64>()
        / lines.len() as f64)
        .sqrt();
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    let (mut mm, mut md, mut dd) = (Matrix3::zeros(), Matrix3::zeros(), Matrix3::zeros());
    for (c, d) in lines {
        let m = ((c - origin) / scale).cross(d);
        mm += m * m.transpose();
        md += m * d.transpose();
        dd += d * d.transpose();
    }
    let (_, ev) = least_eigen(dd);
    if ev[0].is_nan() || ev[0] <= 1e-6 * ev[2] {
        return None; // normals in one plane: a cylinder (or a plane), not a cone or a torus
    }
    let dd_inv = dd.try_inverse()?;
    let schur = mm - md * dd_inv * md.transpose();
    let (a, _) = least_eigen(schur);
    let a = canonical(a);
    let a_bar = -dd_inv * md.transpose() * a;
    // The point of the axis nearest the origin: a × ā (with ā's part along a dropped).
    let a_bar = a_bar - a * a.dot(&a_bar);
    let point = origin + a.cross(&a_bar) * scale;
    (point.iter().all(|x| x.is_finite())).then_some((point, a))
}

/// The axis of a cone or a cylinder from its chords (a point on it and its unit direction):
/// every chord of a surface of revolution between the same two parallels makes the same angle
/// with the axis, so the chords' unit normals lie on one small circle of the sphere, in the
/// plane `n · a = c`; and every normal line meets the axis (at one point for a band). `None`
/// when the normals do not fix a plane (fewer than three distinct ones).
pub fn band_axis(lines: &[(V3, V3)]) -> Option<(V3, V3)> {
    if lines.len() < 3 {
        return None;
    }
    let mean = lines.iter().map(|l| l.1).sum::<V3>() / lines.len() as f64;
    let m: Matrix3<f64> = lines.iter().map(|l| (l.1 - mean) * (l.1 - mean).transpose()).sum();
    let (a, ev) = least_eigen(m);
    if !(ev[1] > 1e-12 && ev[0] <= 1e-6 * ev[2]) {
        return None;
    }
    let a = canonical(a);
    // The point nearest every normal line, pulled slightly towards the lines' mean point (the
    // system is singular along the axis when the lines meet it at several heights).
    let centre = lines.iter().map(|l| l.0).sum::<V3>() / lines.len() as f64;
    let mut lhs = Matrix3::zeros();
    let mut rhs = V3::zeros();
    for (c, d) in lines {
        let q = Matrix3::identity() - d * d.transpose();
        lhs += q;
        rhs += q * (c - centre);
    }
    let eps = 1e-9 * lhs.trace();
    let p = (lhs + Matrix3::identity() * eps).cholesky()?.solve(&rhs);
    let point = centre + p;
    point.iter().all(|x| x.is_finite()).then_some((point, a))
}

/// The profile of the points about the axis: (ρ, h) per point.
fn profile(points: &[V3], o: &V3, a: &V3) -> Vec<Vector2<f64>> {
    points
        .iter()
        .map(|p| {
            let v = p - o;
            let h = v.dot(a);
            Vector2::new((v - a * h).norm(), h)
        })
        .collect()
}

/// The cone about the axis (`o`, `a`) through the points: a line fitted to their profile.
pub fn cone(points: &[V3], o: &V3, a: &V3) -> Option<Primitive> {
    let prof = profile(points, o, a);
    let mean = prof.iter().sum::<Vector2<f64>>() / prof.len() as f64;
    let m: Matrix2<f64> = prof.iter().map(|p| (p - mean) * (p - mean).transpose()).sum();
    let e = SymmetricEigen::new(m);
    let k = if e.eigenvalues[0] > e.eigenvalues[1] { 0 } else { 1 };
    let mut d = e.eigenvectors.column(k).into_owned();
    if d.y < 0.0 {
        d = -d;
    }
    // d = (dρ, dh): the ruling. Along the axis (dρ = 0) it is a cylinder, across it a plane.
    let (mut axis, mut dir) = (*a, d);
    if dir.x < 0.0 {
        // ρ shrinks as h grows: the cone opens the other way.
        axis = -axis;
        dir = Vector2::new(-dir.x, dir.y);
    }
    let half_angle = dir.x.atan2(dir.y.abs());
    // The apex: where the ruling's line reaches ρ = 0 (h along the original axis).
    let t = -mean.x / d.x;
    let h_apex = mean.y + t * d.y;
    let apex = o + a * h_apex;
    let prim = Primitive::Cone { apex: apex.into(), axis: axis.into(), half_angle };
    prim.is_sound(0.0, f64::INFINITY).then_some(prim)
}

/// The torus (or, with its profile circle centred on the axis, the sphere) about the axis
/// (`o`, `a`) through the points: a circle fitted to their profile.
pub fn torus(points: &[V3], o: &V3, a: &V3, tolerance: f64) -> Option<Primitive> {
    let prof = profile(points, o, a);
    let mean = prof.iter().sum::<Vector2<f64>>() / prof.len() as f64;
    let s =
        (prof.iter().map(|p| (p - mean).norm_squared()).sum::<f64>() / prof.len() as f64).sqrt();
    if s.is_nan() || s <= 0.0 {
        return None;
    }
    let scaled: Vec<Vector2<f64>> = prof.iter().map(|p| (p - mean) / s).collect();
    let (c, r) = circle(&scaled)?;
    let (c, r) = (mean + c * s, r * s);
    let center = o + a * c.y;
    if c.x.abs() <= tolerance {
        return Some(Primitive::Sphere { center: center.into(), radius: r });
    }
    (c.x > 0.0).then_some(Primitive::Torus {
        center: center.into(),
        axis: (*a).into(),
        major: c.x,
        minor: r,
    })
}

/// The largest distance from the points to the surface.
pub fn max_residual(prim: &Primitive, points: &[V3]) -> f64 {
    points.iter().map(|p| prim.signed_distance(p).abs()).fold(0.0, f64::max)
}

/// The RMS distance from the points to the surface.
pub fn rms_residual(prim: &Primitive, points: &[V3]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    (points.iter().map(|p| prim.signed_distance(p).powi(2)).sum::<f64>() / points.len() as f64)
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_points_give_exact_primitives() {
        // A cone: half-angle 0.4 about (0, 0.6, 0.8) from (1, 2, 3).
        let (apex, a) = (V3::new(1.0, 2.0, 3.0), V3::new(0.0, 0.6, 0.8));
        let f = crate::geometry::frames::Frame::from_normal(a);
        let mut pts = Vec::new();
        let mut lines = Vec::new();
        for j in 0..12 {
            let th = j as f64 * 0.5;
            let r = f.t * th.cos() + f.b * th.sin();
            for h in [2.0, 3.0, 4.5] {
                pts.push(apex + a * h + r * (h * 0.4f64.tan()));
            }
            // Normal lines from several parallels: from one alone they all pass through one
            // point of the axis, and any line through it meets them all.
            let n = r * 0.4f64.cos() - a * 0.4f64.sin();
            let h = [2.0, 3.0, 4.5][j % 3];
            lines.push((apex + a * h + r * (h * 0.4f64.tan()), n));
        }
        let (o, axis) = revolution_axis(&lines).unwrap();
        assert!(axis.cross(&a).norm() < 1e-9);
        assert!((o - apex).cross(&a).norm() < 1e-9);
        let c = cone(&pts, &o, &axis).unwrap();
        assert!(max_residual(&c, &pts) < 1e-9, "{c:?}");
        match c {
            Primitive::Cone { half_angle, apex: q, .. } => {
                assert!((half_angle - 0.4).abs() < 1e-9);
                assert!((V3::from(q) - apex).norm() < 1e-8);
            }
            _ => unreachable!(),
        }
        // A sphere and a cylinder.
        let s: Vec<V3> = (0..20)
            .map(|k| {
                let (u, v) = (k as f64 * 0.7, k as f64 * 0.31);
                V3::new(2.0, -1.0, 0.5)
                    + V3::new(u.cos() * v.cos(), u.sin() * v.cos(), v.sin()) * 7.0
            })
            .collect();
        match sphere(&s).unwrap() {
            Primitive::Sphere { radius, .. } => assert!((radius - 7.0).abs() < 1e-9),
            _ => unreachable!(),
        }
    }
}

#[cfg(test)]
mod band_tests {
    use super::*;

    /// A cone band of 36 trapezoids between two rings, as a turned part's chamfer: the axis
    /// from the chords' normal lines, then the cone.
    #[test]
    fn a_cone_band_of_chords_is_a_cone() {
        let n = 36;
        let ring = |rho: f64, z: f64| -> Vec<V3> {
            (0..n)
                .map(|j| {
                    let t = std::f64::consts::TAU * j as f64 / n as f64;
                    V3::new(rho * t.cos(), rho * t.sin(), z)
                })
                .collect()
        };
        let (a, b) = (ring(12.0, 58.5), ring(10.5, 60.0));
        let mut pts = a.clone();
        pts.extend(b.iter().copied());
        let mut lines = Vec::new();
        let mut normals = Vec::new();
        for j in 0..n {
            let k = (j + 1) % n;
            let q = [a[j], a[k], b[k], b[j]];
            let c = q.iter().sum::<V3>() / 4.0;
            let nn = (q[1] - q[0]).cross(&(q[2] - q[0])).normalize();
            lines.push((c, nn));
            normals.push(nn);
        }
        let (o, axis) = band_axis(&lines).expect("axis");
        eprintln!("axis {o:?} {axis:?}");
        let c = cone(&pts, &o, &axis).expect("cone");
        eprintln!("{c:?} residual {}", max_residual(&c, &pts));
        assert!(max_residual(&c, &pts) < 1e-9);
        assert!(cylinder(&pts, &normals).is_none_or(|c| max_residual(&c, &pts) > 1e-3));
    }
}
