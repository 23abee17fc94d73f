//! The one SVG reader of grainline: panel outlines ([`crate::panel`]) and designer curves
//! ([`crate::edit::curve`]) are both read here.
//!
//! **Why usvg.** Two hand-written path parsers used to exist, and each got SVG wrong in its own
//! way (arcs refused by one, `rx` on a rect, `display: none`, character references, `<use>`,
//! CSS and `preserveAspectRatio` ignored by both). usvg (linebender's resvg project, well kept
//! and tested against the SVG test suite) resolves all of it into one tree of paths with
//! absolute transforms: shapes (`rect` with `rx`/`ry`, `circle`, `ellipse`, `line`,
//! `polyline`, `polygon`) become paths, arcs become cubic Béziers, `<use>` and `<symbol>`
//! are instantiated, styles (attributes, `style`, `<style>` sheets) are cascaded, units and
//! the root `viewBox` are folded into the transforms, and `display: none` elements are
//! dropped. Only its parser is built (no text, fonts, images or compression).
//!
//! **This module adds** what usvg leaves out: errors that name the file, the line and the
//! element (roxmltree reads the document first, so a syntax error gives its line; every shape
//! element is tagged with an id before usvg sees it, so a path in usvg's tree leads back to
//! its source element and line); refusal of negative sizes (`rect` width, `circle` r, …),
//! which usvg would skip silently; and flattening of the Béziers to within a tolerance with
//! Wang's bound on the chord count, `n = ⌈√(d(d−1)/8 · max‖Δ²P‖ / tol)⌉` (Wang, Zheng &
//! Sederberg, *Computer Graphics and Geometric Modeling*, 2nd ed., §10.5), in f64 after the
//! element's absolute transform.
//!
//! **Coordinates** are usvg's canvas: CSS pixels (96 per inch), y down, the root's `width` and
//! `height` (with `mm`, `cm`, `in`, `pt`, `pc`, `px` or no unit = px) giving the canvas size,
//! the `viewBox` mapped onto it by `preserveAspectRatio` (default `xMidYMid meet`). A root
//! without a `viewBox` and without both `width` and `height` has no defined size and is
//! refused. usvg stores path points as f32 (about 7 significant digits: 0.1 µm on a metre).
//! Elements in `defs`, `clipPath`, `mask`, `marker`, `pattern` and un-used `symbol`s draw
//! nothing and are not read; `visibility` and paint are not looked at (an outline drawn with
//! `fill="none"` still counts).

use std::collections::HashMap;
use std::path::Path;

use crate::{Error, Result};

mod check;

/// The SVG namespace, added to a root that has none (hand-written files often omit it).
const SVG_NS: &str = "http://www.w3.org/2000/svg";

/// Shape elements tagged with an id for messages.
const SHAPES: [&str; 7] = ["path", "rect", "circle", "ellipse", "line", "polyline", "polygon"];

/// Prefix of the ids given to shape elements without one.
const TAG: &str = "grainline-element-";

/// A flattened subpath in canvas pixels (y down).
#[derive(Clone, Debug, PartialEq)]
pub struct Subpath {
    /// Points, the start not repeated at the end of a closed subpath.
    pub points: Vec<[f64; 2]>,
    /// Closed with `Z` (or a closed shape: rect, circle, ellipse, polygon).
    pub closed: bool,
}

/// One drawn shape: its source element and its subpaths.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    /// `path element on line 7 (id "hole")`.
    pub element: String,
    /// 1-based line of the element's start tag.
    pub line: usize,
    /// Subpaths in drawing order; empty ones (a lone moveto) left out.
    pub subpaths: Vec<Subpath>,
}

/// A read SVG document.
#[derive(Clone, Debug, PartialEq)]
pub struct Drawing {
    /// Canvas size, CSS px (96 per inch).
    pub width_px: f64,
    /// See `width_px`.
    pub height_px: f64,
    /// Every shape, in document order (a `<use>` instance where it is used).
    pub shapes: Vec<Shape>,
}

/// Millimetres per CSS pixel.
pub const MM_PER_PX: f64 = 25.4 / 96.0;

struct Source {
    element: String,
    line: usize,
}

fn parse_error(name: &Path, line: usize, message: String) -> Error {
    Error::Parse { path: name.to_path_buf(), line, message }
}

/// The leading number of a length attribute (`"-3mm"` → −3), if any.
fn leading_number(v: &str) -> Option<f64> {
    let v = v.trim();
    let end = v
        .char_indices()
        .find(|&(i, c)| {
            !(c.is_ascii_digit()
                || c == '.'
                || ((c == '-' || c == '+') && (i == 0 || v[..i].ends_with(['e', 'E'])))
                || ((c == 'e' || c == 'E') && i > 0))
        })
        .map_or(v.len(), |(i, _)| i);
    v[..end].parse().ok()
}

/// The flattening tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// Canvas pixels.
    Px(f64),
    /// A fraction of the canvas's smaller side.
    OfCanvas(f64),
}

/// How to read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadOptions {
    /// Flattening tolerance.
    pub tolerance: Tolerance,
    /// Map the `viewBox` onto the whole canvas (`preserveAspectRatio="none"` on the root,
    /// replacing the file's own).
    pub stretch: bool,
}

/// The offset just after `<` and the tag name as written (with any prefix) of the element
/// starting at `start`.
fn after_name(text: &str, start: usize) -> usize {
    let raw = &text[start + 1..];
    start + 1 + raw.find(|c: char| c.is_whitespace() || c == '/' || c == '>').unwrap_or(raw.len())
}

/// Reads the shapes of an SVG document, flattened to within `tolerance_px` canvas pixels.
/// `name` is the file, for messages.
pub fn read(text: &str, name: &Path, tolerance_px: f64) -> Result<Drawing> {
    read_with(text, name, &ReadOptions { tolerance: Tolerance::Px(tolerance_px), stretch: false })
}

/// [`read`] with options.
pub fn read_with(text: &str, name: &Path, o: &ReadOptions) -> Result<Drawing> {
    let doc = parse_svg(text, name)?;
    let root = doc.root_element();
    let root_line = doc.text_pos_at(root.range().start).row as usize;
    let root_map = RootMap::of(&root, o.stretch).map_err(|m| parse_error(name, root_line, m))?;
    // Tag every shape element with an id (insertions into the text, applied back to front),
    // check the sizes usvg would skip silently, and add the namespace where it is missing.
    check::check_elements(&doc, name)?;
    let mut edits = Edits::default();
    let sources = tag_shapes(&doc, text, name, &mut edits)?;
    root_edits(&root, text, &root_map, &mut edits);
    let tagged = edits.apply(text);
    drop(doc);
    let tree = usvg_tree(&tagged, name)?;
    flatten_tree(&tree, &root_map, &sources, o, name)
}

/// The XML parser's options: DTDs (entities) allowed.
fn xml_options<'a>() -> usvg::roxmltree::ParsingOptions<'a> {
    usvg::roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() }
}

/// Parses the document and checks its root: an `<svg>` with a viewBox or a width and height.
fn parse_svg<'a>(text: &'a str, name: &Path) -> Result<usvg::roxmltree::Document<'a>> {
    let doc = usvg::roxmltree::Document::parse_with_options(text, xml_options())
        .map_err(|e| parse_error(name, e.pos().row as usize, format!("not a readable SVG: {e}")))?;
    let root = doc.root_element();
    if root.tag_name().name() != "svg" {
        return Err(parse_error(
            name,
            doc.text_pos_at(root.range().start).row as usize,
            format!("not an SVG document: the root element is <{}>", root.tag_name().name()),
        ));
    }
    let has = |k: &str| root.attribute(k).is_some();
    if !(has("viewBox") || (has("width") && has("height"))) {
        return Err(parse_error(
            name,
            doc.text_pos_at(root.range().start).row as usize,
            "the <svg> element has neither a viewBox nor a width and height, so its size and \
             units are unknown"
                .into(),
        ));
    }
    Ok(doc)
}

/// Edits of the source text: insertions (offset, text) and removed ranges.
#[derive(Default)]
struct Edits {
    inserts: Vec<(usize, String)>,
    removals: Vec<std::ops::Range<usize>>,
}

impl Edits {
    /// The text with the edits applied.
    fn apply(self, text: &str) -> String {
        // The ranges do not overlap: an insertion is at a tag's name, a removal covers a whole
        // attribute.
        let mut edits: Vec<(std::ops::Range<usize>, String)> =
            self.inserts.into_iter().map(|(at, s)| (at..at, s)).collect();
        edits.extend(self.removals.into_iter().map(|r| (r, String::new())));
        // Front to back in one pass (replacing in place, back to front, moved the rest of the
        // text for every edit: quadratic in the shapes).
        // Edits at one place go in the order replacing back to front gave: the later first.
        let mut edits: Vec<(usize, (std::ops::Range<usize>, String))> =
            edits.into_iter().enumerate().collect();
        edits.sort_by_key(|(i, (r, _))| (r.start, r.end, std::cmp::Reverse(*i)));
        let mut tagged = String::with_capacity(text.len() + edits.len() * 32);
        let mut at = 0;
        for (_, (r, s)) in edits {
            tagged.push_str(&text[at..r.start]);
            tagged.push_str(&s);
            at = r.end;
        }
        tagged.push_str(&text[at..]);
        tagged
    }
}

/// How messages name a shape or `<use>` element on `line`.
fn describe_element(node: &usvg::roxmltree::Node, tag: &str, line: usize) -> String {
    let href = node.attributes().find(|a| a.name() == "href").map(|a| a.value());
    match (node.attribute("id"), href) {
        (_, Some(href)) if tag == "use" => {
            format!("use element on line {line} (href {href:?})")
        }
        (Some(id), _) => format!("{tag} element on line {line} (id {id:?})"),
        (None, _) => format!("{tag} element on line {line}"),
    }
}

/// Refuses the negative sizes of a `rect`, `circle` or `ellipse`, which usvg would skip
/// silently.
fn check_sizes(
    node: &usvg::roxmltree::Node,
    tag: &str,
    element: &str,
    name: &Path,
    line: usize,
) -> Result<()> {
    for k in ["width", "height", "r", "rx", "ry"] {
        if let Some(v) = node.attribute(k).and_then(leading_number) {
            if v < 0.0 && matches!(tag, "rect" | "circle" | "ellipse") {
                return Err(parse_error(
                    name,
                    line,
                    format!("{element}: {k}=\"{}\" is negative", node.attribute(k).unwrap_or("")),
                ));
            }
        }
    }
    Ok(())
}

/// Gives every shape element without one an id (an insertion into `edits`), checks the sizes,
/// and returns the source of every id.
fn tag_shapes(
    doc: &usvg::roxmltree::Document,
    text: &str,
    name: &Path,
    edits: &mut Edits,
) -> Result<HashMap<String, Source>> {
    let mut sources: HashMap<String, Source> = HashMap::new();
    // Line starts, for a line per shape in O(log n) (roxmltree's `text_pos_at` scans from the
    // document's start each time: 10⁴ rects took 8 s).
    let starts: Vec<usize> = std::iter::once(0)
        .chain(text.bytes().enumerate().filter(|&(_, b)| b == b'\n').map(|(i, _)| i + 1))
        .collect();
    for node in doc.descendants().filter(|n| n.is_element()) {
        let tag = node.tag_name().name();
        if !SHAPES.contains(&tag) && tag != "use" {
            continue;
        }
        let start = node.range().start;
        let line = starts.partition_point(|&l| l <= start);
        let element = describe_element(&node, tag, line);
        check_sizes(&node, tag, &element, name, line)?;
        let id = match node.attribute("id") {
            // An empty id cannot be replaced (a second `id` would be a syntax error): such an
            // element is read only as part of a `<use>` or a group with an id.
            Some("") => continue,
            // A `<use>` keeps its id in usvg's tree (the group it becomes); the elements it
            // instantiates lose theirs, and are named after it.
            Some(id) => id.to_string(),
            None => {
                let id = format!("{TAG}{start}");
                edits.inserts.push((after_name(text, start), format!(" id=\"{id}\"")));
                id
            }
        };
        sources.entry(id).or_insert(Source { element, line });
    }
    Ok(sources)
}

/// The root's edits: the namespace where it is missing, and its size, viewBox, aspect ratio and
/// transform replaced by a size in user units.
fn root_edits(root: &usvg::roxmltree::Node, text: &str, root_map: &RootMap, edits: &mut Edits) {
    if root.tag_name().namespace().is_none() {
        edits.inserts.push((after_name(text, root.range().start), format!(" xmlns=\"{SVG_NS}\"")));
    }
    // The root's size, viewBox, aspect ratio and transform are applied here in f64 (usvg
    // keeps transforms in f32): usvg sees a root of the viewBox's size in user units, so its
    // coordinates are the user units themselves.
    for k in ["width", "height", "viewBox", "preserveAspectRatio", "transform"] {
        if let Some(a) = root.attribute_node(k) {
            edits.removals.push(a.range());
        }
    }
    edits.inserts.push((
        after_name(text, root.range().start),
        format!(" width=\"{}\" height=\"{}\"", root_map.view[2], root_map.view[3]),
    ));
}

/// usvg's tree of the tagged text.
fn usvg_tree(tagged: &str, name: &Path) -> Result<usvg::Tree> {
    let doc = usvg::roxmltree::Document::parse_with_options(tagged, xml_options())
        .map_err(|e| parse_error(name, 0, format!("not a readable SVG: {e}")))?;
    // No file is read on the document's behalf, and no embedded image decoded.
    let opt = usvg::Options {
        resources_dir: None,
        image_href_resolver: usvg::ImageHrefResolver {
            resolve_data: Box::new(|_, _, _| None),
            resolve_string: Box::new(|_, _| None),
        },
        ..usvg::Options::default()
    };
    usvg::Tree::from_xmltree(&doc, &opt).map_err(|e| {
        let message = match e {
            usvg::Error::InvalidSize => {
                "the <svg> element's width, height or viewBox is not a positive size".to_string()
            }
            usvg::Error::ElementsLimitReached => {
                "more than 1 000 000 elements (usvg's limit)".to_string()
            }
            e => format!("not a readable SVG: {e}"),
        };
        parse_error(name, 1, message)
    })
}

/// The drawing of usvg's tree: its shapes flattened to the tolerance, in canvas pixels.
fn flatten_tree(
    tree: &usvg::Tree,
    root_map: &RootMap,
    sources: &HashMap<String, Source>,
    o: &ReadOptions,
    name: &Path,
) -> Result<Drawing> {
    let (w, h) = (root_map.width, root_map.height);
    let tolerance_px = match o.tolerance {
        Tolerance::Px(t) => t,
        Tolerance::OfCanvas(t) => t * w.min(h),
    };
    let mut shapes = Vec::new();
    let mut left = crate::limits::MAX_SVG_POINTS;
    collect(tree.root(), &root_map.to_canvas, sources, None, tolerance_px, &mut left, &mut shapes);
    for s in &shapes {
        if s.subpaths
            .iter()
            .flat_map(|p| &p.points)
            .any(|q| !(q[0].is_finite() && q[1].is_finite()))
        {
            let message = format!(
                "{}: a coordinate is not finite after the transforms and the viewBox (beyond \
                 f32's range, 3.4e38, in usvg)",
                s.element
            );
            return Err(parse_error(name, s.line, message));
        }
    }
    if left == 0 {
        return Err(parse_error(
            name,
            0,
            format!(
                "the drawing flattens to more than {:.0e} points at this tolerance \
                 ({} px); coarsen the tolerance or simplify the drawing",
                crate::limits::MAX_SVG_POINTS as f64,
                crate::error::fmt_num(tolerance_px)
            ),
        ));
    }
    Ok(Drawing { width_px: w, height_px: h, shapes })
}

/// Collects the paths under `g`; `via` is the `<use>` they are an instance of, if any.
fn collect(
    g: &usvg::Group,
    root: &Affine,
    sources: &HashMap<String, Source>,
    via: Option<&Source>,
    tol: f64,
    left: &mut usize,
    out: &mut Vec<Shape>,
) {
    for node in g.children() {
        if *left == 0 {
            return;
        }
        match node {
            usvg::Node::Group(g) => {
                let inner = sources.get(g.id()).filter(|s| s.element.starts_with("use ")).or(via);
                collect(g, root, sources, inner, tol, left, out)
            }
            usvg::Node::Path(p) => {
                // Instances of a `<use>` are named after it; paths usvg makes itself
                // (markers) have no id, and draw nothing of ours.
                let Some(src) = sources.get(p.id()).or(via) else { continue };
                let t = p.abs_transform();
                let m = compose(root, &[t.sx, t.ky, t.kx, t.sy, t.tx, t.ty].map(f64::from));
                let subpaths = flatten(p.data(), &m, tol, left);
                out.push(Shape { element: src.element.clone(), line: src.line, subpaths });
            }
            _ => {}
        }
    }
}

/// `[a, b, c, d, e, f]`: x' = a x + c y + e, y' = b x + d y + f (SVG matrix order).
type Affine = [f64; 6];

/// m ∘ n (n applied first).
fn compose(m: &Affine, n: &Affine) -> Affine {
    [
        m[0] * n[0] + m[2] * n[1],
        m[1] * n[0] + m[3] * n[1],
        m[0] * n[2] + m[2] * n[3],
        m[1] * n[2] + m[3] * n[3],
        m[0] * n[4] + m[2] * n[5] + m[4],
        m[1] * n[4] + m[3] * n[5] + m[5],
    ]
}

/// The root's mapping from user units to the canvas (CSS px), in f64.
struct RootMap {
    /// Canvas size, px.
    width: f64,
    height: f64,
    /// The viewBox (x, y, w, h) in user units.
    view: [f64; 4],
    /// User units → canvas px: the root's `transform` after the viewBox mapping.
    to_canvas: Affine,
}

impl RootMap {
    /// SVG 2 §8.2 (`viewBox` and `preserveAspectRatio`); lengths in CSS px at 96 per inch.
    fn of(root: &usvg::roxmltree::Node, stretch: bool) -> std::result::Result<RootMap, String> {
        use std::str::FromStr;
        use svgtypes::{Align, LengthUnit};
        let view = match root.attribute("viewBox") {
            Some(v) => {
                let b = view_box(v)?;
                Some(b)
            }
            None => None,
        };
        let length = |k: &str, of_view: Option<f64>| -> std::result::Result<Option<f64>, String> {
            let Some(v) = root.attribute(k) else { return Ok(None) };
            let l =
                svgtypes::Length::from_str(v).map_err(|_| format!("{k}={v:?} is not a length"))?;
            let per = match l.unit {
                LengthUnit::None | LengthUnit::Px => 1.0,
                LengthUnit::In => 96.0,
                LengthUnit::Cm => 96.0 / 2.54,
                LengthUnit::Mm => 96.0 / 25.4,
                LengthUnit::Pt => 96.0 / 72.0,
                LengthUnit::Pc => 16.0,
                LengthUnit::Percent => match of_view {
                    Some(w) => w / 100.0,
                    None => return Err(format!("{k}={v:?} is relative, and there is no viewBox")),
                },
                LengthUnit::Em | LengthUnit::Ex => {
                    return Err(format!("{k}={v:?}: use mm, cm, in, pt, pc or px"))
                }
            };
            let x = l.number * per;
            if !(x.is_finite() && x > 0.0) {
                return Err(format!("{k}={v:?} must be a positive length"));
            }
            Ok(Some(x))
        };
        let width = length("width", view.map(|b| b[2]))?;
        let height = length("height", view.map(|b| b[3]))?;
        let (w, h) = match (width, height, view) {
            (Some(w), Some(h), _) => (w, h),
            (w, h, Some(b)) => (w.unwrap_or(b[2]), h.unwrap_or(b[3])),
            _ => return Err("the <svg> element needs a viewBox or a width and height".into()),
        };
        let view = view.unwrap_or([0.0, 0.0, w, h]);
        let aspect = match root.attribute("preserveAspectRatio") {
            Some(v) => svgtypes::AspectRatio::from_str(v)
                .map_err(|_| format!("preserveAspectRatio={v:?} is not understood"))?,
            None => svgtypes::AspectRatio::default(),
        };
        let (sx, sy) = (w / view[2], h / view[3]);
        let (sx, sy, tx, ty) = if stretch || aspect.align == Align::None {
            (sx, sy, 0.0, 0.0)
        } else {
            let s = if aspect.slice { sx.max(sy) } else { sx.min(sy) };
            let (fx, fy) = match aspect.align {
                Align::XMinYMin => (0.0, 0.0),
                Align::XMidYMin => (0.5, 0.0),
                Align::XMaxYMin => (1.0, 0.0),
                Align::XMinYMid => (0.0, 0.5),
                Align::XMidYMid | Align::None => (0.5, 0.5),
                Align::XMaxYMid => (1.0, 0.5),
                Align::XMinYMax => (0.0, 1.0),
                Align::XMidYMax => (0.5, 1.0),
                Align::XMaxYMax => (1.0, 1.0),
            };
            (s, s, fx * (w - s * view[2]), fy * (h - s * view[3]))
        };
        let fit = [sx, 0.0, 0.0, sy, tx - sx * view[0], ty - sy * view[1]];
        let own = match root.attribute("transform") {
            Some(v) => {
                let t = svgtypes::Transform::from_str(v)
                    .map_err(|_| format!("transform={v:?} is not understood"))?;
                [t.a, t.b, t.c, t.d, t.e, t.f]
            }
            None => [1.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        };
        if !own.iter().all(|x| x.is_finite()) {
            return Err("the root's transform is not finite".into());
        }
        Ok(RootMap { width: w, height: h, view, to_canvas: compose(&own, &fit) })
    }
}

/// A root's `viewBox`: four finite numbers, its width and height positive.
fn view_box(v: &str) -> std::result::Result<[f64; 4], String> {
    let numbers: Vec<f64> = v
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f64>().map_err(|_| format!("viewBox={v:?} is not four numbers")))
        .collect::<std::result::Result<_, _>>()?;
    let Ok(b) = <[f64; 4]>::try_from(numbers) else {
        return Err(format!("viewBox={v:?} is not four numbers"));
    };
    if !b.iter().all(|x| x.is_finite()) {
        return Err(format!("viewBox={v:?} is not finite"));
    }
    if b[2] == 0.0 && b[3] == 0.0 {
        return Err(format!("viewBox={v:?} has a zero width and height: it shows nothing"));
    }
    for (k, what) in [(2, "width"), (3, "height")] {
        if b[k] == 0.0 {
            return Err(format!("viewBox={v:?} has a zero {what}: it shows nothing"));
        }
        if b[k] < 0.0 {
            return Err(format!("viewBox={v:?} has a negative {what}"));
        }
    }
    Ok(b)
}

fn apply(m: &Affine, p: [f64; 2]) -> [f64; 2] {
    [m[0] * p[0] + m[2] * p[1] + m[4], m[1] * p[0] + m[3] * p[1] + m[5]]
}

/// Flattens a path (points in its own coordinates) after the transform `m`, to within `tol`.
/// `left` is the budget of points still allowed; 0 when it ran out (the result is then cut).
fn flatten(
    path: &usvg::tiny_skia_path::Path,
    m: &Affine,
    tol: f64,
    left: &mut usize,
) -> Vec<Subpath> {
    use usvg::tiny_skia_path::PathSegment;
    let mut subs: Vec<Subpath> = Vec::new();
    let mut cur: Option<Vec<[f64; 2]>> = None;
    let pt = |p: usvg::tiny_skia_path::Point| apply(m, [f64::from(p.x), f64::from(p.y)]);
    let finish = |cur: &mut Option<Vec<[f64; 2]>>, closed: bool, subs: &mut Vec<Subpath>| {
        if let Some(mut points) = cur.take() {
            if closed && points.len() > 1 && points.first() == points.last() {
                points.pop();
            }
            if points.len() >= 2 {
                subs.push(Subpath { points, closed });
            }
        }
    };
    for seg in path.segments() {
        if *left == 0 {
            break;
        }
        *left -= 1;
        match seg {
            PathSegment::MoveTo(p) => {
                finish(&mut cur, false, &mut subs);
                cur = Some(vec![pt(p)]);
            }
            PathSegment::LineTo(p) => cur.get_or_insert_with(Vec::new).push(pt(p)),
            PathSegment::QuadTo(c, p) => {
                let pts = cur.get_or_insert_with(Vec::new);
                let p0 = pts.last().copied().unwrap_or(pt(c));
                bezier(pts, &[p0, pt(c), pt(p)], tol, left);
            }
            PathSegment::CubicTo(c1, c2, p) => {
                let pts = cur.get_or_insert_with(Vec::new);
                let p0 = pts.last().copied().unwrap_or(pt(c1));
                bezier(pts, &[p0, pt(c1), pt(c2), pt(p)], tol, left);
            }
            PathSegment::Close => finish(&mut cur, true, &mut subs),
        }
    }
    finish(&mut cur, false, &mut subs);
    subs
}

/// Appends a flattened Bézier of degree 2 or 3 (Wang's bound on the chord count, at most
/// 10 000 chords).
fn bezier(out: &mut Vec<[f64; 2]>, p: &[[f64; 2]], tol: f64, left: &mut usize) {
    let deg = p.len() - 1;
    let mut m: f64 = 0.0;
    for i in 0..deg - 1 {
        let dx = p[i][0] - 2.0 * p[i + 1][0] + p[i + 2][0];
        let dy = p[i][1] - 2.0 * p[i + 1][1] + p[i + 2][1];
        m = m.max(dx.hypot(dy));
    }
    let n = ((deg * (deg - 1)) as f64 / 8.0 * m / tol).sqrt().ceil();
    let n = if n.is_finite() { n.clamp(1.0, 10_000.0) as usize } else { 1 };
    if n > *left {
        *left = 0;
        return;
    }
    *left -= n;
    for k in 1..=n {
        let t = k as f64 / n as f64;
        let s = 1.0 - t;
        let q = if deg == 3 {
            let w = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
            [0, 1].map(|c| (0..4).map(|i| w[i] * p[i][c]).sum::<f64>())
        } else {
            let w = [s * s, 2.0 * s * t, t * t];
            [0, 1].map(|c| (0..3).map(|i| w[i] * p[i][c]).sum::<f64>())
        };
        out.push(q);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leading_numbers_of_lengths() {
        assert_eq!(leading_number("-3mm"), Some(-3.0));
        assert_eq!(leading_number(" 2.5e1px"), Some(25.0));
        assert_eq!(leading_number("1e-1"), Some(0.1));
        assert_eq!(leading_number("mm"), None);
    }
}
