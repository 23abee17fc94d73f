//! The axis of a part's largest body of revolution, from its recognized surfaces: what a
//! rotary fixture's `axis: "auto"` holds a turned CAD part on (docs/math.md §3, "Recognized
//! surfaces").
//!
//! Cylinders, cones and tori are grouped by their axes (directions within 0.1°, each one's
//! axis point within 10⁻⁴ of the part's size of the group's line); a sphere joins the group
//! whose line passes through its centre, and a plane whose normal is along a group's axis
//! (an end face, a shoulder) counts in that group's area. The group of largest area is the
//! body; it is the part's axis when that area is at least 90 % of the part's (a turned part;
//! a prismatic part with holes or fillets, or a bent sheet, has none).

use nalgebra::Vector3;

use super::primitive::Primitive;
use super::Surfaces;

type V3 = Vector3<f64>;

/// Directions within this angle are one axis.
const AXIS_ANGLE_DEG: f64 = 0.1;

/// Axis lines within this share of the part's size are one axis.
const AXIS_OFFSET: f64 = 1e-4;

/// The least share of the part's area the body must cover.
pub const MIN_SHARE: f64 = 0.9;

/// A body of revolution: its axis and what lies on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RevolutionAxis {
    /// A point of the axis.
    pub point: V3,
    /// Unit direction.
    pub direction: V3,
    /// Area of the surfaces about it (with the planes across it).
    pub area: f64,
    /// Its share of the part's area.
    pub share: f64,
}

struct Group {
    point: V3,
    direction: V3,
    area: f64,
}

/// The axis of the largest body of revolution among `s`'s surfaces (module docs); `None` when
/// there is none or it covers less than [`MIN_SHARE`] of `total_area`, the part's. `size` is
/// the part's size (its bounding box's diagonal).
pub fn largest_body_of_revolution(
    s: &Surfaces,
    size: f64,
    total_area: f64,
) -> Option<RevolutionAxis> {
    let cos = AXIS_ANGLE_DEG.to_radians().cos();
    let near = AXIS_OFFSET * size;
    let off_line = |g: &Group, p: &V3| (p - g.point).cross(&g.direction).norm();
    let mut groups: Vec<Group> = Vec::new();
    for surf in &s.surfaces {
        let Some((point, direction)) = surf.primitive.axis() else { continue };
        match groups
            .iter_mut()
            .find(|g| g.direction.dot(&direction).abs() >= cos && off_line(g, &point) <= near)
        {
            Some(g) => g.area += surf.area,
            None => groups.push(Group { point, direction, area: surf.area }),
        }
    }
    for surf in &s.surfaces {
        let on = |g: &Group| match surf.primitive {
            Primitive::Sphere { center, .. } => off_line(g, &center.into()) <= near,
            Primitive::Plane { normal, .. } => g.direction.dot(&V3::from(normal)).abs() >= cos,
            _ => false,
        };
        if let Some(g) = groups.iter_mut().find(|g| on(g)) {
            g.area += surf.area;
        }
    }
    let best = groups.into_iter().max_by(|a, b| a.area.total_cmp(&b.area))?;
    let share = best.area / total_area;
    (share >= MIN_SHARE && share.is_finite()).then_some(RevolutionAxis {
        point: best.point,
        direction: best.direction,
        area: best.area,
        share,
    })
}
