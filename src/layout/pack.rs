//! Packing the charts into the unit square at one common scale.
//!
//! Every chart is first scaled so its UV area is its surface area (one UV unit is then about
//! one scene unit on every chart alike) and turned so its principal axis (of its vertices'
//! covariance) runs along u. The charts' bounding boxes, with a gap between them, are laid
//! on shelves by decreasing height (a shelf is about as wide as the square root of the
//! boxes' total area), and the whole layout is scaled by one factor into [0, 1]²: UV distances
//! stay proportional to lengths on the part in every chart (`uvfield` recovers the factor).

use nalgebra::{Matrix2, Vector2};

/// Packs `charts` (UV coordinates per chart, already area-scaled) in place; `gap` is the
/// space between boxes as a fraction of the square root of the total chart area. Returns the
/// factor applied after packing (UV = packed × factor).
pub(crate) fn pack(charts: &mut [Vec<Vector2<f64>>], gap: f64) -> f64 {
    let mut boxes: Vec<(f64, f64)> = Vec::with_capacity(charts.len());
    let mut total = 0.0;
    for uv in charts.iter_mut() {
        orient(uv);
        let (lo, hi) = bbox(uv);
        for p in uv.iter_mut() {
            *p -= lo;
        }
        let (w, h) = (hi.x - lo.x, hi.y - lo.y);
        total += w * h;
        boxes.push((w, h));
    }
    let pad = gap * total.sqrt();
    let mut order: Vec<usize> = (0..charts.len()).collect();
    order.sort_by(|&a, &b| boxes[b].1.total_cmp(&boxes[a].1).then(a.cmp(&b)));
    let padded: f64 = boxes.iter().map(|(w, h)| (w + pad) * (h + pad)).sum();
    let widest = boxes.iter().map(|b| b.0).fold(0.0, f64::max);
    let shelf_width = padded.sqrt().max(widest + pad);
    let (mut x, mut y, mut shelf_h) = (pad, pad, 0.0f64);
    let (mut width, mut height) = (0.0f64, 0.0f64);
    for &k in &order {
        let (w, h) = boxes[k];
        if x > pad && x + w + pad > shelf_width {
            y += shelf_h + pad;
            x = pad;
            shelf_h = 0.0;
        }
        for p in charts[k].iter_mut() {
            *p += Vector2::new(x, y);
        }
        x += w + pad;
        shelf_h = shelf_h.max(h);
        width = width.max(x);
        height = height.max(y + h + pad);
    }
    let side = width.max(height);
    let factor = if side > 0.0 && side.is_finite() { 1.0 / side } else { 1.0 };
    for uv in charts.iter_mut() {
        for p in uv.iter_mut() {
            *p *= factor;
        }
    }
    factor
}

fn bbox(uv: &[Vector2<f64>]) -> (Vector2<f64>, Vector2<f64>) {
    let mut lo = Vector2::repeat(f64::INFINITY);
    let mut hi = Vector2::repeat(f64::NEG_INFINITY);
    for p in uv {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    if !lo.x.is_finite() {
        return (Vector2::zeros(), Vector2::zeros());
    }
    (lo, hi)
}

/// Turns the chart so the principal axis of its vertices runs along u (a rotation: the
/// orientation of every triangle is kept).
fn orient(uv: &mut [Vector2<f64>]) {
    if uv.is_empty() {
        return;
    }
    let c = uv.iter().fold(Vector2::zeros(), |a, p| a + p) / uv.len() as f64;
    let mut m = Matrix2::zeros();
    for p in uv.iter() {
        let d = p - c;
        m += d * d.transpose();
    }
    // Angle of the principal axis of a symmetric 2×2 matrix.
    let th = 0.5 * (2.0 * m[(0, 1)]).atan2(m[(0, 0)] - m[(1, 1)]);
    if !th.is_finite() {
        return;
    }
    let (s, co) = (-th).sin_cos();
    for p in uv.iter_mut() {
        let d = *p - c;
        *p = Vector2::new(co * d.x - s * d.y, s * d.x + co * d.y);
    }
}
