//! Checks of the attributes usvg would read past silently: path data with a syntax error (SVG
//! draws up to the error), numbers beyond [`MAX_SVG_NUMBER`] (usvg keeps `f32`, which turns
//! them into infinity and drops the shape), and transforms that are not understood, not finite
//! or collapse the element. Each error names the file, the line, the element and the attribute.

use std::path::Path;
use std::str::FromStr;

use super::{describe_element, parse_error};
use crate::limits::{MAX_SVG_DEPTH, MAX_SVG_ELEMENTS, MAX_SVG_NUMBER, MAX_SVG_SELECTOR_WORK};
use crate::Result;

/// The number attributes of the shape elements.
const NUMBER_ATTRIBUTES: [&str; 13] =
    ["x", "y", "width", "height", "rx", "ry", "cx", "cy", "r", "x1", "y1", "x2", "y2"];

/// Checks every element's `transform` and every shape's coordinates (`d`, `points`, the number
/// attributes), after the document's size ([`check_budgets`]).
pub(super) fn check_elements(doc: &usvg::roxmltree::Document, name: &Path) -> Result<()> {
    check_budgets(doc, name)?;
    let root = doc.root_element();
    for node in doc.descendants().filter(|n| n.is_element() && *n != root) {
        let tag = node.tag_name().name();
        // The line only for a message: `text_pos_at` scans the text from its start.
        let at = |message: String| {
            let line = doc.text_pos_at(node.range().start).row as usize;
            parse_error(name, line, format!("{}: {message}", describe_element(&node, tag, line)))
        };
        if let Some(v) = node.attribute("transform") {
            check_transform(v).map_err(at)?;
        }
        if !super::SHAPES.contains(&tag) {
            continue;
        }
        for k in NUMBER_ATTRIBUTES {
            if let Some(x) = node.attribute(k).and_then(super::leading_number) {
                bounded(x).map_err(|m| at(format!("{k}: {m}")))?;
            }
        }
        if let Some(d) = node.attribute("d").filter(|_| tag == "path") {
            check_path_data(d).map_err(at)?;
        }
        if let Some(p) = node.attribute("points") {
            for (x, y) in svgtypes::PointsParser::from(p) {
                bounded(x).and(bounded(y)).map_err(|m| at(format!("points: {m}")))?;
            }
        }
    }
    Ok(())
}

/// A number within ±[`MAX_SVG_NUMBER`], or the message saying it is not.
fn bounded(x: f64) -> std::result::Result<(), String> {
    if x.is_finite() && x.abs() <= MAX_SVG_NUMBER {
        return Ok(());
    }
    Err(format!(
        "the coordinate {} is beyond ±{MAX_SVG_NUMBER:e}, the bound of SVG numbers \
         (limits::MAX_SVG_NUMBER)",
        crate::error::fmt_num(x)
    ))
}

/// A `transform` attribute: understood, finite, within the bound, and not collapsing.
fn check_transform(v: &str) -> std::result::Result<(), String> {
    let shown = crate::error::shorten(v);
    let t = svgtypes::Transform::from_str(v)
        .map_err(|e| format!("transform=\"{shown}\" is not understood ({e})"))?;
    let m = [t.a, t.b, t.c, t.d, t.e, t.f];
    if !m.iter().all(|x| x.is_finite()) {
        return Err(format!("transform=\"{shown}\" is not finite"));
    }
    if let Some(&x) = m.iter().find(|x| x.abs() > MAX_SVG_NUMBER) {
        return Err(format!("transform=\"{shown}\": {}", bounded(x).unwrap_err()));
    }
    if t.a * t.d - t.b * t.c == 0.0 {
        return Err(format!("transform=\"{shown}\" collapses the element (its determinant is 0)"));
    }
    Ok(())
}

/// A path's `d`: no syntax error (SVG would draw the path up to it), every number bounded.
fn check_path_data(d: &str) -> std::result::Result<(), String> {
    use svgtypes::PathSegment as S;
    for seg in svgtypes::PathParser::from(d) {
        let seg = seg.map_err(|e| syntax_error(d, &e))?;
        let numbers: &[f64] = match seg {
            S::MoveTo { x, y, .. } | S::LineTo { x, y, .. } | S::SmoothQuadratic { x, y, .. } => {
                &[x, y]
            }
            S::HorizontalLineTo { x, .. } => &[x],
            S::VerticalLineTo { y, .. } => &[y],
            S::CurveTo { x1, y1, x2, y2, x, y, .. } => &[x1, y1, x2, y2, x, y],
            S::SmoothCurveTo { x2, y2, x, y, .. } => &[x2, y2, x, y],
            S::Quadratic { x1, y1, x, y, .. } => &[x1, y1, x, y],
            S::EllipticalArc { rx, ry, x, y, .. } => &[rx, ry, x, y],
            S::ClosePath { .. } => &[],
        };
        for &x in numbers {
            bounded(x).map_err(|m| format!("d: {m}"))?;
        }
    }
    Ok(())
}

/// "syntax error in its path data (d) at character 17 (`x`): …": svgtypes' message, with the
/// text from the position it gives (1-based, in characters).
fn syntax_error(d: &str, e: &svgtypes::Error) -> String {
    let pos = match *e {
        svgtypes::Error::UnexpectedData(p)
        | svgtypes::Error::InvalidNumber(p)
        | svgtypes::Error::InvalidChar(_, p)
        | svgtypes::Error::InvalidString(_, p) => Some(p),
        _ => None,
    };
    let from: String = match pos {
        Some(p) => d.chars().skip(p.saturating_sub(1)).take(12).collect(),
        None => String::new(),
    };
    let context = if from.is_empty() { String::new() } else { format!(" (at {from:?})") };
    format!(
        "syntax error in its path data (d): {e}{context}; SVG would draw the path only up to it"
    )
}

/// Refuses, before usvg reads it, a document of more than [`MAX_SVG_ELEMENTS`] elements,
/// nested deeper than [`MAX_SVG_DEPTH`], or whose `<style>` sheets would take more than
/// [`MAX_SVG_SELECTOR_WORK`] steps to match: a selector of k descendant (or `~` sibling)
/// combinators is matched by trying the ancestors (or earlier siblings) of each element in
/// every combination, up to Σ_{j ≤ k} C(D + 1, j) for a depth D, so a 395-byte selector took
/// seconds.
/// Each error names the file and the line of the element at fault.
fn check_budgets(doc: &usvg::roxmltree::Document, name: &Path) -> Result<()> {
    let line_of = |n: &usvg::roxmltree::Node| doc.text_pos_at(n.range().start).row as usize;
    let mut elements = 0usize;
    let mut deepest = 0usize;
    let mut widest = 0usize;
    for node in doc.descendants().filter(|n| n.is_element()) {
        elements += 1;
        if elements > MAX_SVG_ELEMENTS {
            return Err(parse_error(
                name,
                line_of(&node),
                format!(
                    "more than {MAX_SVG_ELEMENTS} elements (limits::MAX_SVG_ELEMENTS); simplify \
                     the drawing"
                ),
            ));
        }
        let depth = node.ancestors().skip(1).filter(|a| a.is_element()).count();
        if depth > MAX_SVG_DEPTH {
            return Err(parse_error(
                name,
                line_of(&node),
                format!(
                    "elements nested {depth} deep, deeper than {MAX_SVG_DEPTH} \
                     (limits::MAX_SVG_DEPTH)"
                ),
            ));
        }
        deepest = deepest.max(depth);
        widest = widest.max(node.children().filter(|c| c.is_element()).count());
    }
    let (deepest, widest) = (deepest as f64, widest as f64);
    for style in doc.descendants().filter(|n| n.is_element() && n.tag_name().name() == "style") {
        let css: String = style.children().filter_map(|c| c.text()).collect();
        let work: f64 = selectors(&css)
            .map(|(d, w)| {
                let n = elements as f64;
                n * chains(deepest + 1.0, d as f64) * chains(widest + 1.0, w as f64)
            })
            .sum();
        if work > MAX_SVG_SELECTOR_WORK {
            return Err(parse_error(
                name,
                line_of(&style),
                format!(
                    "its style sheet's selectors would take about {work:.1e} steps to match on \
                     {elements} elements, beyond {MAX_SVG_SELECTOR_WORK:.0e} \
                     (limits::MAX_SVG_SELECTOR_WORK); use fewer combinators per selector"
                ),
            ));
        }
    }
    Ok(())
}

/// Per selector of a style sheet, its backtracking combinators: (descendant, general sibling
/// `~`). The child `>` and adjacent `+` combinators try one element each.
fn selectors(css: &str) -> impl Iterator<Item = (usize, usize)> + '_ {
    let mut rest = css;
    std::iter::from_fn(move || {
        // The text before each `{` (after the last `}`) is a selector list; comments and
        // at-rules' blocks are counted as selectors too (an over-estimate, never an under-).
        let open = rest.find('{')?;
        let head = &rest[..open];
        let head = head.rfind('}').map_or(head, |i| &head[i + 1..]);
        rest = rest[open + 1..].find('}').map_or("", |i| &rest[open + 1 + i + 1..]);
        Some(head.split(',').map(combinators).collect::<Vec<_>>())
    })
    .flatten()
}

/// The backtracking combinators of one selector: (descendant, general sibling).
fn combinators(selector: &str) -> (usize, usize) {
    let spaced = selector.replace('>', " > ").replace('+', " + ").replace('~', " ~ ");
    let (mut descendant, mut sibling) = (0, 0);
    let mut previous_compound = false;
    for token in spaced.split_whitespace() {
        match token {
            "~" => {
                sibling += 1;
                previous_compound = false;
            }
            ">" | "+" => previous_compound = false,
            _ => {
                if previous_compound {
                    descendant += 1;
                }
                previous_compound = true;
            }
        }
    }
    (descendant, sibling)
}

/// The partial matches a backtracking matcher may try for k combinators over n candidates:
/// Σ_{j ≤ k} C(n, j) (all 2ⁿ when k ≥ n: a selector longer than the nesting still tries
/// every prefix before it fails), in floating point.
fn chains(n: f64, k: f64) -> f64 {
    let mut c = 1.0;
    let mut sum = 1.0;
    let mut i = 0.0;
    while i < k.min(n) {
        c = c * (n - i) / (i + 1.0);
        sum += c;
        i += 1.0;
    }
    sum
}
