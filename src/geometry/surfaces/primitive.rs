//! The analytic surfaces a CAD part is made of — planes, cylinders, cones, spheres and tori —
//! with their distance, normal and shape operator (docs/math.md §3, "Recognized surfaces").
//!
//! Every normal here is the surface's *outward* one in its own sense (away from the axis, the
//! centre or the tube's core; a plane's as fitted); a caller orients it by the faces it lies
//! under. The shape operator is S = dn/dp, the derivative of that unit normal along the
//! surface, a symmetric map of the tangent plane written as a 3 × 3 world matrix that is zero
//! along n. The Weingarten map of math.md §1 in a frame [t, b, n] is W = −[tᵀSt tᵀSb; bᵀSt
//! bᵀSb] (W = C for the height z = ½xᵀCx above the tangent plane): a sphere of radius R with
//! outward normals has S = (I − nnᵀ)/R and principal curvatures +1/R.

use nalgebra::{Matrix3, Vector3};

type V3 = Vector3<f64>;

/// The kind of a recognized surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceKind {
    /// A plane.
    Plane,
    /// A circular cylinder: fillets along straight edges, bends, hole walls, turned diameters.
    Cylinder,
    /// A circular cone: chamfers and tapers of turned parts.
    Cone,
    /// A sphere: ball ends, domed knobs.
    Sphere,
    /// A torus: a fillet or a round turned about an axis.
    Torus,
}

impl SurfaceKind {
    /// The kind's name as the reports write it.
    pub fn as_str(self) -> &'static str {
        match self {
            SurfaceKind::Plane => "plane",
            SurfaceKind::Cylinder => "cylinder",
            SurfaceKind::Cone => "cone",
            SurfaceKind::Sphere => "sphere",
            SurfaceKind::Torus => "torus",
        }
    }
}

/// An analytic surface with its parameters (directions are unit vectors).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Primitive {
    /// The plane `n · p = offset`.
    Plane {
        /// Unit normal.
        normal: [f64; 3],
        /// `n · p` on the plane.
        offset: f64,
    },
    /// The points at `radius` from the line through `point` along `axis`.
    Cylinder {
        /// A point of the axis.
        point: [f64; 3],
        /// Unit direction of the axis.
        axis: [f64; 3],
        /// Radius.
        radius: f64,
    },
    /// The cone with its apex at `apex`, opening along `axis` with `half_angle` between the
    /// axis and its rulings: ρ = h tan(half_angle), h = (p − apex) · axis.
    Cone {
        /// The apex.
        apex: [f64; 3],
        /// Unit direction the cone opens along.
        axis: [f64; 3],
        /// Half-angle, radians, in (0, π/2).
        half_angle: f64,
    },
    /// The points at `radius` from `center`.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
    },
    /// `(ρ − major)² + h² = minor²` about the axis through `center` along `axis`.
    Torus {
        /// Centre, on the axis.
        center: [f64; 3],
        /// Unit direction of the axis.
        axis: [f64; 3],
        /// Distance from the axis to the tube's core circle.
        major: f64,
        /// Radius of the tube.
        minor: f64,
    },
}

/// The radial unit vector of `p` from the axis through `o` along `a`, and the distance ρ.
fn radial(p: &V3, o: &V3, a: &V3) -> (V3, f64) {
    let v = p - o;
    let r = v - a * v.dot(a);
    let rho = r.norm();
    if rho > 0.0 {
        (r / rho, rho)
    } else {
        // On the axis: any direction across it.
        (crate::geometry::frames::Frame::from_normal(*a).t, 0.0)
    }
}

impl Primitive {
    /// The kind.
    pub fn kind(&self) -> SurfaceKind {
        match self {
            Primitive::Plane { .. } => SurfaceKind::Plane,
            Primitive::Cylinder { .. } => SurfaceKind::Cylinder,
            Primitive::Cone { .. } => SurfaceKind::Cone,
            Primitive::Sphere { .. } => SurfaceKind::Sphere,
            Primitive::Torus { .. } => SurfaceKind::Torus,
        }
    }

    /// The axis (a point on it and its unit direction) of a surface of revolution; `None` for
    /// a plane or a sphere.
    pub fn axis(&self) -> Option<(V3, V3)> {
        match *self {
            Primitive::Cylinder { point, axis, .. } => Some((point.into(), axis.into())),
            Primitive::Cone { apex, axis, .. } => Some((apex.into(), axis.into())),
            Primitive::Torus { center, axis, .. } => Some((center.into(), axis.into())),
            _ => None,
        }
    }

    /// The radius a report gives: the cylinder's, the sphere's, the torus's tube; 0 for a
    /// plane and a cone.
    pub fn radius(&self) -> f64 {
        match *self {
            Primitive::Cylinder { radius, .. } | Primitive::Sphere { radius, .. } => radius,
            Primitive::Torus { minor, .. } => minor,
            _ => 0.0,
        }
    }

    /// Signed distance of `p` from the surface, positive on the side its normal points to.
    pub fn signed_distance(&self, p: &V3) -> f64 {
        match *self {
            Primitive::Plane { normal, offset } => V3::from(normal).dot(p) - offset,
            Primitive::Cylinder { point, axis, radius } => {
                radial(p, &point.into(), &axis.into()).1 - radius
            }
            Primitive::Cone { apex, axis, half_angle } => {
                let a = V3::from(axis);
                let h = (p - V3::from(apex)).dot(&a);
                let rho = radial(p, &apex.into(), &a).1;
                rho * half_angle.cos() - h * half_angle.sin()
            }
            Primitive::Sphere { center, radius } => (p - V3::from(center)).norm() - radius,
            Primitive::Torus { center, axis, major, minor } => {
                let a = V3::from(axis);
                let h = (p - V3::from(center)).dot(&a);
                let rho = radial(p, &center.into(), &a).1;
                (rho - major).hypot(h) - minor
            }
        }
    }

    /// The outward unit normal at the point of the surface nearest `p` (module docs).
    pub fn normal_at(&self, p: &V3) -> V3 {
        match *self {
            Primitive::Plane { normal, .. } => normal.into(),
            Primitive::Cylinder { point, axis, .. } => radial(p, &point.into(), &axis.into()).0,
            Primitive::Cone { apex, axis, half_angle } => {
                let a = V3::from(axis);
                let r = radial(p, &apex.into(), &a).0;
                r * half_angle.cos() - a * half_angle.sin()
            }
            Primitive::Sphere { center, .. } => {
                let v = p - V3::from(center);
                v.try_normalize(0.0).unwrap_or_else(V3::z)
            }
            Primitive::Torus { center, axis, major, .. } => {
                let (c, a) = (V3::from(center), V3::from(axis));
                let core = c + radial(p, &c, &a).0 * major;
                let v = p - core;
                v.try_normalize(0.0).unwrap_or(a)
            }
        }
    }

    /// The shape operator S = dn/dp of the outward normal at the surface point nearest `p`
    /// (module docs); zero along the normal.
    pub fn shape_at(&self, p: &V3) -> Matrix3<f64> {
        let outer = |u: V3| u * u.transpose();
        match *self {
            Primitive::Plane { .. } => Matrix3::zeros(),
            Primitive::Cylinder { point, axis, radius } => {
                // Curvature 1/R around the axis, none along it.
                let a = V3::from(axis);
                let (r, _) = radial(p, &point.into(), &a);
                outer(a.cross(&r)) / radius
            }
            Primitive::Cone { apex, axis, half_angle } => {
                // n turns with the azimuth only: cos α / ρ around, none along the rulings.
                let a = V3::from(axis);
                let (r, _) = radial(p, &apex.into(), &a);
                let n = self.normal_at(p);
                let q = self.nearest(p, &n);
                let rho = radial(&q, &apex.into(), &a).1;
                if rho > 0.0 {
                    outer(a.cross(&r)) * (half_angle.cos() / rho)
                } else {
                    Matrix3::zeros()
                }
            }
            Primitive::Sphere { radius, .. } => {
                let n = self.normal_at(p);
                (Matrix3::identity() - outer(n)) / radius
            }
            Primitive::Torus { center, axis, major, minor } => {
                // Along the meridian 1/r; around the axis cos φ / ρ = (ρ − R)/(r ρ).
                let (c, a) = (V3::from(center), V3::from(axis));
                let n = self.normal_at(p);
                let q = self.nearest(p, &n);
                let (r, rho) = radial(&q, &c, &a);
                let around = a.cross(&r);
                let meridian = n.cross(&around);
                let k_around = if rho > 0.0 { (rho - major) / (minor * rho) } else { 0.0 };
                outer(meridian) / minor + outer(around) * k_around
            }
        }
    }

    /// The point of the surface nearest `p`, given the normal there.
    pub fn nearest(&self, p: &V3, n: &V3) -> V3 {
        p - n * self.signed_distance(p)
    }

    /// Whether every number of the primitive is finite and its size within `limit` (a fit
    /// that degenerates — collinear points, a radius near zero or far beyond the part — is
    /// not a surface grainline reads).
    pub fn is_sound(&self, min_radius: f64, max_radius: f64) -> bool {
        let ok = |x: f64| x.is_finite() && x >= min_radius && x <= max_radius;
        let finite = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
        match self {
            Primitive::Plane { normal, offset } => finite(normal) && offset.is_finite(),
            Primitive::Cylinder { point, axis, radius } => {
                finite(point) && finite(axis) && ok(*radius)
            }
            Primitive::Cone { apex, axis, half_angle } => {
                finite(apex)
                    && finite(axis)
                    && half_angle.is_finite()
                    && *half_angle > 1e-3
                    && *half_angle < std::f64::consts::FRAC_PI_2 - 1e-3
            }
            Primitive::Sphere { center, radius } => finite(center) && ok(*radius),
            Primitive::Torus { center, axis, major, minor } => {
                finite(center) && finite(axis) && ok(*minor) && major.is_finite() && *major > 0.0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shape operator's eigenvalues in the tangent plane against the principal curvatures
    /// of each surface, by finite differences of the normal.
    #[test]
    fn shape_operators_are_the_normals_derivatives() {
        let prims = [
            Primitive::Cylinder { point: [1.0, 2.0, 3.0], axis: [0.0, 0.6, 0.8], radius: 4.0 },
            Primitive::Cone { apex: [0.0, 0.0, -5.0], axis: [0.0, 0.0, 1.0], half_angle: 0.5 },
            Primitive::Sphere { center: [1.0, -1.0, 0.5], radius: 3.0 },
            Primitive::Torus {
                center: [0.0, 0.0, 0.0],
                axis: [1.0, 0.0, 0.0],
                major: 5.0,
                minor: 1.5,
            },
        ];
        let probe = V3::new(2.0, 3.5, 1.0);
        for prim in prims {
            let n = prim.normal_at(&probe);
            let q = prim.nearest(&probe, &n);
            assert!(prim.signed_distance(&q).abs() < 1e-9, "{prim:?}");
            let s = prim.shape_at(&q);
            assert!((s * n).norm() < 1e-9, "{prim:?}");
            let f = crate::geometry::frames::Frame::from_normal(n);
            for t in [f.t, f.b, (f.t + f.b).normalize()] {
                let h = 1e-5;
                let (a, b) = (q + t * h, q - t * h);
                let (na, nb) = (prim.normal_at(&a), prim.normal_at(&b));
                let fd = (na - nb) / (2.0 * h);
                assert!((fd - s * t).norm() < 1e-5, "{prim:?}: {fd:?} vs {:?}", s * t);
            }
        }
    }
}
