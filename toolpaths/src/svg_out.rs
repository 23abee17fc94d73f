//! SVG export of the strokes on the UV layout (the flat sheet), with the `svg` crate.
//!
//! * `width`/`height` in mm and a `viewBox` in the same units, so 1 user unit = 1 mm;
//!   V points up in UV and down in SVG, so `y = v_max + margin − v`.
//! * Inkscape layers (`<g inkscape:groupmode="layer">`): `strokes` (one `<path>` per stroke
//!   piece, in cutting order and direction, `stroke-width` = brush width), `outlines` (chart
//!   boundaries, optional) and `travel` (pen-up moves between strokes, optional).
//! * No timestamps or random ids; attributes are written sorted by the `svg` crate and
//!   numbers with fixed decimals, so the bytes are reproducible.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use svg::node::element::{Group, Path, Title};
use svg::Document;

use crate::error::{non_negative, Result};
use crate::gcode::num;
use crate::geom::Vec2;
use crate::mesh::{Domain, NONE};
use crate::plan::Plan;

/// SVG options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[serde(deny_unknown_fields)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
pub struct SvgOptions {
    /// Draw the chart outlines layer. Default true.
    pub outlines: bool,
    /// Draw the travel layer. Default false.
    pub travel: bool,
    /// Margin around the UV bounding box, mm. Default 2.
    pub margin: f64,
    /// Document title. Default "grainline strokes".
    pub title: String,
    /// Decimals for coordinates. Default 3.
    pub decimals: usize,
}

impl Default for SvgOptions {
    fn default() -> Self {
        SvgOptions {
            outlines: true,
            travel: false,
            margin: 2.0,
            title: "grainline strokes".into(),
            decimals: 3,
        }
    }
}

impl SvgOptions {
    /// Reject a negative or non-finite `margin` and `decimals` outside 1..=6.
    pub fn validate(&self) -> Result<()> {
        non_negative("svg.margin", self.margin)?;
        if !(1..=6).contains(&self.decimals) {
            return Err(crate::error::ToolpathError::InvalidOption {
                name: "svg.decimals",
                value: self.decimals as f64,
                reason: "must be between 1 and 6",
            });
        }
        Ok(())
    }
}

fn layer(id: &str) -> Group {
    Group::new()
        .set("id", id)
        .set("inkscape:groupmode", "layer")
        .set("inkscape:label", id)
        .set("fill", "none")
        .set("stroke-linecap", "round")
        .set("stroke-linejoin", "round")
}

/// Closed chart boundary loops (chained boundary edges), in a deterministic order.
pub(crate) fn boundary_loops(dom: &Domain) -> Vec<Vec<Vec2>> {
    let mut next: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for (f, nb) in dom.neighbors.iter().enumerate() {
        let t = dom.tris[f];
        for i in 0..3 {
            if nb[i] == NONE {
                next.entry(t[(i + 1) % 3]).or_default().push(t[(i + 2) % 3]);
            }
        }
    }
    let mut loops = Vec::new();
    while let Some((&start, _)) = next.iter().find(|(_, v)| !v.is_empty()) {
        let mut pts = vec![dom.uv[start as usize]];
        let mut cur = start;
        while let Some(n) = next.get_mut(&cur).and_then(|l| l.pop()) {
            pts.push(dom.uv[n as usize]);
            cur = n;
            if cur == start {
                break;
            }
        }
        next.retain(|_, v| !v.is_empty());
        loops.push(pts);
    }
    loops
}

/// Render the plan's strokes (UV) as an SVG document string.
pub fn write_svg(dom: &Domain, plan: &Plan, o: &SvgOptions) -> Result<String> {
    non_negative("svg.margin", o.margin)?;
    let dp = o.decimals.clamp(1, 6);
    let b = dom.bbox();
    let w = b[1][0] - b[0][0] + 2.0 * o.margin;
    let h = b[1][1] - b[0][1] + 2.0 * o.margin;
    let x = |p: Vec2| num(p[0] - b[0][0] + o.margin, dp);
    let y = |p: Vec2| num(b[1][1] + o.margin - p[1], dp);
    let d_of = |pts: &[Vec2], close: bool| {
        let mut d = String::with_capacity(pts.len() * 16);
        for (i, p) in pts.iter().enumerate() {
            d.push_str(if i == 0 { "M" } else { " L" });
            d.push_str(&x(*p));
            d.push(' ');
            d.push_str(&y(*p));
        }
        if close {
            d.push_str(" Z");
        }
        d
    };
    let mut doc = Document::new()
        .set("xmlns:inkscape", "http://www.inkscape.org/namespaces/inkscape")
        .set("width", format!("{}mm", num(w, dp)))
        .set("height", format!("{}mm", num(h, dp)))
        .set("viewBox", format!("0 0 {} {}", num(w, dp), num(h, dp)))
        .add(Title::new(o.title.clone()));
    if o.outlines {
        let mut g = layer("outlines").set("stroke", "#808080").set("stroke-width", "0.1");
        for l in boundary_loops(dom) {
            let closed = l.len() > 2 && l[0] == l[l.len() - 1];
            let pts = if closed { &l[..l.len() - 1] } else { &l[..] };
            g = g.add(Path::new().set("d", d_of(pts, closed)));
        }
        doc = doc.add(g);
    }
    // One strokes layer per sheet (charts overlapping in UV, flat mode); a single sheet
    // keeps the layer name `strokes`.
    let n_sheets = plan.passes.iter().map(|p| p.sheet + 1).max().unwrap_or(1);
    for sheet in 0..n_sheets {
        let name =
            if sheet == 0 { "strokes".to_string() } else { format!("strokes-sheet-{sheet}") };
        let mut g = layer(&name).set("stroke", "#000000").set("stroke-width", num(plan.width, dp));
        for pass in plan.passes.iter().filter(|p| p.sheet == sheet) {
            for piece in &pass.uv {
                if piece.len() >= 2 {
                    g = g.add(Path::new().set("d", d_of(piece, false)));
                }
            }
        }
        doc = doc.add(g);
    }
    if o.travel {
        let mut g = layer("travel").set("stroke", "#ff0000").set("stroke-width", "0.1");
        let mut prev: Option<Vec2> = None;
        for pass in &plan.passes {
            let pieces: Vec<&Vec<Vec2>> = pass.uv.iter().filter(|p| !p.is_empty()).collect();
            for piece in pieces {
                if let Some(p) = prev {
                    g = g.add(Path::new().set("d", d_of(&[p, piece[0]], false)));
                }
                prev = Some(piece[piece.len() - 1]);
            }
        }
        doc = doc.add(g);
    }
    Ok(format!("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n{doc}\n"))
}
