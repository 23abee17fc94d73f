//! A panel's closed loops from an SVG (read by [`crate::svg_read`], the one SVG reader): in
//! millimetres with Y up (see the module docs of [`crate::panel`]).

use std::path::Path;

use super::Loop;
use crate::svg_read::{self, MM_PER_PX};
use crate::{Error, Result};

/// Reads the closed loops of an SVG document, in mm with Y up: `X = x · 25.4/96`,
/// `Y = (H − y) · 25.4/96` for a canvas point (x, y) px of a canvas H px tall, so the part is
/// not mirrored. Curves are flattened to within `tolerance` mm. `name` is the file for
/// messages.
pub fn read_svg_loops(text: &str, name: &Path, tolerance: f64) -> Result<Vec<Loop>> {
    let drawing = svg_read::read(text, name, tolerance / MM_PER_PX)?;
    let h = drawing.height_px;
    let mut loops = Vec::new();
    for shape in &drawing.shapes {
        let bad = |message: String| Error::Parse {
            path: name.to_path_buf(),
            line: shape.line,
            message: format!("{}: {message}", shape.element),
        };
        let several = shape.subpaths.len() > 1;
        for (k, sub) in shape.subpaths.iter().enumerate() {
            let mut p: Vec<[f64; 2]> =
                sub.points.iter().map(|q| [q[0] * MM_PER_PX, (h - q[1]) * MM_PER_PX]).collect();
            p.dedup_by(|a, b| (a[0] - b[0]).hypot(a[1] - b[1]) <= 1e-9);
            if p.len() < 2 {
                continue; // a lone moveto draws nothing
            }
            let gap = (p[0][0] - p[p.len() - 1][0]).hypot(p[0][1] - p[p.len() - 1][1]);
            if !sub.closed && gap > 1e-6 {
                let e = p[p.len() - 1];
                return Err(bad(format!(
                    "subpath {} is open: it ends at ({:.3}, {:.3}) mm, {gap:.3} mm from its \
                     start; close it (Z)",
                    k + 1,
                    e[0],
                    e[1]
                )));
            }
            if gap <= 1e-6 {
                p.pop();
            }
            if p.len() < 3 {
                return Err(bad(format!("subpath {} encloses no area", k + 1)));
            }
            let element = if several {
                format!("subpath {} of {}", k + 1, shape.element)
            } else {
                shape.element.clone()
            };
            loops.push(Loop { points: p, element, line: shape.line });
        }
    }
    if loops.is_empty() {
        return Err(Error::Parse {
            path: name.to_path_buf(),
            line: 0,
            message: "no closed outline: no path, polygon, rect, circle or ellipse with an area"
                .into(),
        });
    }
    Ok(loops)
}
