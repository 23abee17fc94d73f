//! Reading a panel's closed loops from an SVG: path data, basic shapes, transforms and units
//! (see the module docs of [`crate::panel`]).

use std::path::Path;

use super::Loop;
use crate::{Error, Result};

type Affine = [f64; 6]; // x' = a x + c y + e, y' = b x + d y + f (SVG matrix order)

const IDENTITY: Affine = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0];

fn compose(m: &Affine, n: &Affine) -> Affine {
    // m ∘ n (n applied first).
    [
        m[0] * n[0] + m[2] * n[1],
        m[1] * n[0] + m[3] * n[1],
        m[0] * n[2] + m[2] * n[3],
        m[1] * n[2] + m[3] * n[3],
        m[0] * n[4] + m[2] * n[5] + m[4],
        m[1] * n[4] + m[3] * n[5] + m[5],
    ]
}

fn apply(m: &Affine, p: [f64; 2]) -> [f64; 2] {
    [m[0] * p[0] + m[2] * p[1] + m[4], m[1] * p[0] + m[3] * p[1] + m[5]]
}

/// Largest singular value of the linear part.
fn max_scale(m: &Affine) -> f64 {
    let (a, b, c, d) = (m[0], m[1], m[2], m[3]);
    let s1 = a * a + b * b + c * c + d * d;
    let det = a * d - b * c;
    (0.5 * (s1 + (s1 * s1 - 4.0 * det * det).max(0.0).sqrt())).sqrt()
}

/// Numbers of an attribute or path data (commas and whitespace separate; "1.5.5" is two).
fn numbers(s: &str) -> std::result::Result<Vec<f64>, String> {
    let mut sc = Scanner { s: s.as_bytes(), i: 0 };
    let mut out = Vec::new();
    loop {
        sc.skip_sep();
        if sc.i >= sc.s.len() {
            return Ok(out);
        }
        out.push(sc.number()?);
    }
}

struct Scanner<'a> {
    s: &'a [u8],
    i: usize,
}

impl Scanner<'_> {
    fn skip_sep(&mut self) {
        while self.i < self.s.len()
            && (self.s[self.i].is_ascii_whitespace() || self.s[self.i] == b',')
        {
            self.i += 1;
        }
    }

    fn number(&mut self) -> std::result::Result<f64, String> {
        self.skip_sep();
        let start = self.i;
        let s = self.s;
        let mut i = self.i;
        if i < s.len() && (s[i] == b'+' || s[i] == b'-') {
            i += 1;
        }
        let mut digits = false;
        while i < s.len() && s[i].is_ascii_digit() {
            i += 1;
            digits = true;
        }
        if i < s.len() && s[i] == b'.' {
            i += 1;
            while i < s.len() && s[i].is_ascii_digit() {
                i += 1;
                digits = true;
            }
        }
        if digits && i < s.len() && (s[i] == b'e' || s[i] == b'E') {
            let mut j = i + 1;
            if j < s.len() && (s[j] == b'+' || s[j] == b'-') {
                j += 1;
            }
            if j < s.len() && s[j].is_ascii_digit() {
                while j < s.len() && s[j].is_ascii_digit() {
                    j += 1;
                }
                i = j;
            }
        }
        let text = std::str::from_utf8(&s[start..i]).unwrap_or("");
        match text.parse::<f64>() {
            Ok(v) if digits && v.is_finite() => {
                self.i = i;
                Ok(v)
            }
            _ => Err(format!(
                "expected a number at {:?}",
                String::from_utf8_lossy(&s[start..(start + 12).min(s.len())])
            )),
        }
    }

    /// An arc flag: a single `0` or `1`, which may be followed directly by the next number.
    fn flag(&mut self) -> std::result::Result<bool, String> {
        self.skip_sep();
        match self.s.get(self.i) {
            Some(b'0') => {
                self.i += 1;
                Ok(false)
            }
            Some(b'1') => {
                self.i += 1;
                Ok(true)
            }
            _ => Err("expected an arc flag (0 or 1)".into()),
        }
    }
}

/// Subpaths of path data, flattened in user units to within `tol` (user units).
/// Returns (points, closed) per subpath.
/// A flattened subpath and whether it was closed with `Z`.
type Subpath = (Vec<[f64; 2]>, bool);

fn flatten_path(d: &str, tol: f64) -> std::result::Result<Vec<Subpath>, String> {
    let mut sc = Scanner { s: d.as_bytes(), i: 0 };
    let mut subs: Vec<(Vec<[f64; 2]>, bool)> = Vec::new();
    let mut cur = [0.0, 0.0];
    let mut start = [0.0, 0.0];
    let mut last_ctrl: Option<(u8, [f64; 2])> = None; // (kind 'C' or 'Q', control point)
    let mut cmd: Option<u8> = None;
    loop {
        sc.skip_sep();
        if sc.i >= sc.s.len() {
            break;
        }
        let c = sc.s[sc.i];
        if c.is_ascii_alphabetic() {
            sc.i += 1;
            cmd = Some(c);
            if c == b'Z' || c == b'z' {
                if let Some(s) = subs.last_mut() {
                    s.1 = true;
                }
                cur = start;
                last_ctrl = None;
                cmd = None;
                continue;
            }
        }
        let Some(k) = cmd else {
            return Err(format!("path data must start with a command, found {:?}", c as char));
        };
        let rel = k.is_ascii_lowercase();
        let off = |p: [f64; 2], cur: [f64; 2]| if rel { [p[0] + cur[0], p[1] + cur[1]] } else { p };
        let pt = |sc: &mut Scanner| -> std::result::Result<[f64; 2], String> {
            let x = sc.number()?;
            sc.skip_sep();
            let y = sc.number()?;
            Ok([x, y])
        };
        let upper = k.to_ascii_uppercase();
        match upper {
            b'M' => {
                let p = off(pt(&mut sc)?, cur);
                subs.push((vec![p], false));
                cur = p;
                start = p;
                // Further pairs are implicit line-tos.
                cmd = Some(if rel { b'l' } else { b'L' });
                last_ctrl = None;
                continue;
            }
            _ if subs.is_empty() || subs.last().is_some_and(|s| s.1) => {
                // A drawing command after Z (or first) starts at the current point.
                subs.push((vec![cur], false));
            }
            _ => {}
        }
        let pts = &mut subs.last_mut().expect("a subpath").0;
        match upper {
            b'L' => {
                let p = off(pt(&mut sc)?, cur);
                pts.push(p);
                cur = p;
                last_ctrl = None;
            }
            b'H' => {
                let x = sc.number()?;
                cur = [if rel { cur[0] + x } else { x }, cur[1]];
                pts.push(cur);
                last_ctrl = None;
            }
            b'V' => {
                let y = sc.number()?;
                cur = [cur[0], if rel { cur[1] + y } else { y }];
                pts.push(cur);
                last_ctrl = None;
            }
            b'C' | b'S' => {
                let c1 = if upper == b'C' {
                    off(pt(&mut sc)?, cur)
                } else {
                    match last_ctrl {
                        Some((b'C', q)) => [2.0 * cur[0] - q[0], 2.0 * cur[1] - q[1]],
                        _ => cur,
                    }
                };
                let c2 = off(pt(&mut sc)?, cur);
                let p = off(pt(&mut sc)?, cur);
                bezier(pts, &[cur, c1, c2, p], tol);
                last_ctrl = Some((b'C', c2));
                cur = p;
            }
            b'Q' | b'T' => {
                let c1 = if upper == b'Q' {
                    off(pt(&mut sc)?, cur)
                } else {
                    match last_ctrl {
                        Some((b'Q', q)) => [2.0 * cur[0] - q[0], 2.0 * cur[1] - q[1]],
                        _ => cur,
                    }
                };
                let p = off(pt(&mut sc)?, cur);
                bezier(pts, &[cur, c1, p], tol);
                last_ctrl = Some((b'Q', c1));
                cur = p;
            }
            b'A' => {
                let rx = sc.number()?;
                sc.skip_sep();
                let ry = sc.number()?;
                sc.skip_sep();
                let rot = sc.number()?;
                let large = sc.flag()?;
                let sweep = sc.flag()?;
                sc.skip_sep();
                let p = off(pt(&mut sc)?, cur);
                arc(pts, cur, p, rx, ry, rot, large, sweep, tol);
                cur = p;
                last_ctrl = None;
            }
            _ => return Err(format!("unknown path command {:?}", k as char)),
        }
    }
    Ok(subs)
}

/// Appends a flattened Bézier of degree 2 or 3 (Wang's bound on the chord count).
fn bezier(out: &mut Vec<[f64; 2]>, p: &[[f64; 2]], tol: f64) {
    let deg = p.len() - 1;
    let mut m: f64 = 0.0;
    for i in 0..deg - 1 {
        let dx = p[i][0] - 2.0 * p[i + 1][0] + p[i + 2][0];
        let dy = p[i][1] - 2.0 * p[i + 1][1] + p[i + 2][1];
        m = m.max(dx.hypot(dy));
    }
    let n = ((deg * (deg - 1)) as f64 / 8.0 * m / tol).sqrt().ceil().clamp(1.0, 10_000.0) as usize;
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

/// Chords per full turn so that the sagitta stays within `tol` on radius `r`.
fn arc_steps(r: f64, sweep: f64, tol: f64) -> usize {
    let max_step =
        if tol >= r { std::f64::consts::FRAC_PI_2 } else { 2.0 * (1.0 - tol / r).acos() };
    (sweep.abs() / max_step.max(1e-6)).ceil().clamp(1.0, 100_000.0) as usize
}

/// Appends a flattened SVG elliptical arc (endpoint → centre parameterization, SVG 1.1 F.6.5).
#[allow(clippy::too_many_arguments)]
fn arc(
    out: &mut Vec<[f64; 2]>,
    p0: [f64; 2],
    p1: [f64; 2],
    rx: f64,
    ry: f64,
    rot_deg: f64,
    large: bool,
    sweep: bool,
    tol: f64,
) {
    let (mut rx, mut ry) = (rx.abs(), ry.abs());
    if rx == 0.0 || ry == 0.0 || p0 == p1 {
        if p0 != p1 {
            out.push(p1);
        }
        return;
    }
    let (sin, cos) = rot_deg.to_radians().sin_cos();
    let dx = 0.5 * (p0[0] - p1[0]);
    let dy = 0.5 * (p0[1] - p1[1]);
    let x1 = cos * dx + sin * dy;
    let y1 = -sin * dx + cos * dy;
    let lambda = (x1 / rx).powi(2) + (y1 / ry).powi(2);
    if lambda > 1.0 {
        rx *= lambda.sqrt();
        ry *= lambda.sqrt();
    }
    let num = (rx * rx * ry * ry - rx * rx * y1 * y1 - ry * ry * x1 * x1).max(0.0);
    let den = rx * rx * y1 * y1 + ry * ry * x1 * x1;
    let mut coef = if den > 0.0 { (num / den).sqrt() } else { 0.0 };
    if large == sweep {
        coef = -coef;
    }
    let cx1 = coef * rx * y1 / ry;
    let cy1 = -coef * ry * x1 / rx;
    let cx = cos * cx1 - sin * cy1 + 0.5 * (p0[0] + p1[0]);
    let cy = sin * cx1 + cos * cy1 + 0.5 * (p0[1] + p1[1]);
    let ang = |ux: f64, uy: f64| uy.atan2(ux);
    let t0 = ang((x1 - cx1) / rx, (y1 - cy1) / ry);
    let t1 = ang((-x1 - cx1) / rx, (-y1 - cy1) / ry);
    let tau = std::f64::consts::TAU;
    let mut dt = t1 - t0;
    if sweep && dt < 0.0 {
        dt += tau;
    } else if !sweep && dt > 0.0 {
        dt -= tau;
    }
    let n = arc_steps(rx.max(ry), dt, tol);
    for k in 1..n {
        let t = t0 + dt * k as f64 / n as f64;
        let (x, y) = (rx * t.cos(), ry * t.sin());
        out.push([cos * x - sin * y + cx, sin * x + cos * y + cy]);
    }
    out.push(p1);
}

fn ellipse_loop(cx: f64, cy: f64, rx: f64, ry: f64, tol: f64) -> Vec<[f64; 2]> {
    let tau = std::f64::consts::TAU;
    let n = arc_steps(rx.max(ry), tau, tol).max(3);
    (0..n)
        .map(|k| {
            let t = tau * k as f64 / n as f64;
            [cx + rx * t.cos(), cy + ry * t.sin()]
        })
        .collect()
}

/// Parses a `transform` attribute.
fn parse_transform(s: &str) -> std::result::Result<Affine, String> {
    let mut m = IDENTITY;
    let mut rest = s.trim();
    while !rest.is_empty() {
        let open = rest.find('(').ok_or_else(|| format!("bad transform {s:?}"))?;
        let close = rest.find(')').ok_or_else(|| format!("bad transform {s:?}"))?;
        let name = rest[..open].trim().trim_start_matches(',').trim();
        let v = numbers(&rest[open + 1..close])?;
        let t: Affine = match (name, v.len()) {
            ("matrix", 6) => [v[0], v[1], v[2], v[3], v[4], v[5]],
            ("translate", 1) => [1.0, 0.0, 0.0, 1.0, v[0], 0.0],
            ("translate", 2) => [1.0, 0.0, 0.0, 1.0, v[0], v[1]],
            ("scale", 1) => [v[0], 0.0, 0.0, v[0], 0.0, 0.0],
            ("scale", 2) => [v[0], 0.0, 0.0, v[1], 0.0, 0.0],
            ("rotate", 1) | ("rotate", 3) => {
                let (sn, cs) = v[0].to_radians().sin_cos();
                let r = [cs, sn, -sn, cs, 0.0, 0.0];
                if v.len() == 3 {
                    let to = [1.0, 0.0, 0.0, 1.0, v[1], v[2]];
                    let back = [1.0, 0.0, 0.0, 1.0, -v[1], -v[2]];
                    compose(&to, &compose(&r, &back))
                } else {
                    r
                }
            }
            ("skewX", 1) => [1.0, 0.0, v[0].to_radians().tan(), 1.0, 0.0, 0.0],
            ("skewY", 1) => [1.0, v[0].to_radians().tan(), 0.0, 1.0, 0.0, 0.0],
            _ => return Err(format!("unsupported transform {name}({})", &rest[open + 1..close])),
        };
        m = compose(&m, &t);
        rest = rest[close + 1..].trim();
    }
    Ok(m)
}

/// A length attribute in mm (`None` for a missing attribute).
fn length_mm(v: &str) -> std::result::Result<f64, String> {
    let v = v.trim();
    let split = v.find(|c: char| c.is_ascii_alphabetic() || c == '%').unwrap_or(v.len());
    let (num, unit) = v.split_at(split);
    let x: f64 = num.trim().parse().map_err(|_| format!("bad length {v:?}"))?;
    let per = match unit.trim() {
        "mm" => 1.0,
        "cm" => 10.0,
        "in" => 25.4,
        "pt" => 25.4 / 72.0,
        "pc" => 25.4 / 6.0,
        "px" | "" => 25.4 / 96.0,
        u => return Err(format!("unsupported unit {u:?} in {v:?} (use mm, cm, in, pt, pc or px)")),
    };
    if !(x.is_finite() && x > 0.0) {
        return Err(format!("length {v:?} must be > 0"));
    }
    Ok(x * per)
}

/// Reads the closed loops of an SVG document, in mm with Y up (see the module docs).
/// `name` is the file for messages.
pub fn read_svg_loops(text: &str, name: &Path, tolerance: f64) -> Result<Vec<Loop>> {
    let bad = |message: String| Error::Parse { path: name.to_path_buf(), line: 0, message };
    let parser = svg::read(text).map_err(|e| bad(e.to_string()))?;
    use svg::node::element::tag::Type;
    use svg::parser::Event;
    let mut stack: Vec<Affine> = Vec::new(); // transforms of open groups
    let mut root: Option<Affine> = None;
    let mut skip_depth = 0usize;
    let mut loops = Vec::new();
    let mut element_no = 0usize;
    for ev in parser {
        let (tag, ty, attrs) = match ev {
            Event::Error(e) => return Err(bad(format!("not a readable SVG: {e}"))),
            Event::Tag(tag, ty, attrs) => (tag, ty, attrs),
            _ => continue,
        };
        let ignored = matches!(tag, "defs" | "clipPath" | "mask" | "symbol" | "pattern" | "marker");
        if ty == Type::End {
            if ignored {
                skip_depth = skip_depth.saturating_sub(1);
            } else if skip_depth == 0 && (tag == "g" || tag == "svg" || tag == "a") {
                stack.pop();
            }
            continue;
        }
        if ignored {
            if ty == Type::Start {
                skip_depth += 1;
            }
            continue;
        }
        if skip_depth > 0 {
            continue;
        }
        let get = |k: &str| attrs.get(k).map(|v| v.to_string());
        let own = match get("transform") {
            Some(t) => parse_transform(&t).map_err(|m| bad(format!("<{tag}>: {m}")))?,
            None => IDENTITY,
        };
        let parent = stack.last().copied().unwrap_or(IDENTITY);
        if tag == "svg" && root.is_none() {
            let vb = get("viewBox").map(|v| numbers(&v)).transpose().map_err(bad)?;
            let w = get("width").filter(|s| !s.trim().ends_with('%'));
            let h = get("height").filter(|s| !s.trim().ends_with('%'));
            let w = w.map(|s| length_mm(&s)).transpose().map_err(|m| bad(format!("width: {m}")))?;
            let h =
                h.map(|s| length_mm(&s)).transpose().map_err(|m| bad(format!("height: {m}")))?;
            let px = 25.4 / 96.0;
            // user units → mm with y down, then flip y about the viewport's bottom.
            let m = match vb.as_deref() {
                Some([x0, y0, vw, vh]) if *vw > 0.0 && *vh > 0.0 => {
                    let (ww, hh) = (w.unwrap_or(vw * px), h.unwrap_or(vh * px));
                    let s = (ww / vw).min(hh / vh);
                    let (ox, oy) = (0.5 * (ww - s * vw), 0.5 * (hh - s * vh));
                    [s, 0.0, 0.0, -s, ox - s * x0, hh - oy + s * y0]
                }
                Some(v) => {
                    return Err(bad(format!(
                        "viewBox must be four numbers with positive size, got {v:?}"
                    )))
                }
                None => [px, 0.0, 0.0, -px, 0.0, h.unwrap_or(0.0)],
            };
            let m = compose(&m, &own);
            root = Some(m);
            if ty == Type::Start {
                stack.push(m);
            }
            continue;
        }
        let m = compose(&parent, &own);
        if tag == "g" || tag == "a" || tag == "svg" {
            if ty == Type::Start {
                stack.push(m);
            }
            continue;
        }
        if !matches!(tag, "path" | "polygon" | "polyline" | "line" | "rect" | "circle" | "ellipse")
        {
            continue;
        }
        element_no += 1;
        let element = match get("id") {
            Some(id) => format!("{tag} element #{element_no} (id {id:?})"),
            None => format!("{tag} element #{element_no}"),
        };
        let ebad = |m: String| bad(format!("{element}: {m}"));
        let tol = tolerance / max_scale(&m).max(1e-300);
        let num = |k: &str| -> Result<f64> {
            match get(k) {
                None => Ok(0.0),
                Some(v) => numbers(&v)
                    .ok()
                    .and_then(|n| (n.len() == 1).then(|| n[0]))
                    .ok_or_else(|| ebad(format!("attribute {k}={v:?} is not a number"))),
            }
        };
        let subs: Vec<(Vec<[f64; 2]>, bool)> = match tag {
            "path" => {
                let d = get("d").unwrap_or_default();
                flatten_path(&d, tol).map_err(&ebad)?
            }
            "polygon" | "polyline" => {
                let v = numbers(&get("points").unwrap_or_default()).map_err(&ebad)?;
                if v.len() % 2 != 0 {
                    return Err(ebad("odd number of coordinates in points".into()));
                }
                let p: Vec<[f64; 2]> = v.chunks(2).map(|c| [c[0], c[1]]).collect();
                vec![(p, tag == "polygon")]
            }
            "line" => {
                return Err(ebad("a line is an open outline; use a closed path".into()));
            }
            "rect" => {
                let (x, y, w, h) = (num("x")?, num("y")?, num("width")?, num("height")?);
                vec![(vec![[x, y], [x + w, y], [x + w, y + h], [x, y + h]], true)]
            }
            "circle" => {
                let r = num("r")?;
                vec![(ellipse_loop(num("cx")?, num("cy")?, r, r, tol), true)]
            }
            _ => {
                let (rx, ry) = (num("rx")?, num("ry")?);
                vec![(ellipse_loop(num("cx")?, num("cy")?, rx, ry, tol), true)]
            }
        };
        for (k, (pts, closed)) in subs.into_iter().enumerate() {
            let mut p: Vec<[f64; 2]> = pts.iter().map(|q| apply(&m, *q)).collect();
            p.dedup_by(|a, b| (a[0] - b[0]).hypot(a[1] - b[1]) <= 1e-9);
            if p.len() < 2 {
                continue; // a lone moveto draws nothing
            }
            let gap = (p[0][0] - p[p.len() - 1][0]).hypot(p[0][1] - p[p.len() - 1][1]);
            if !closed && gap > 1e-6 {
                let e = p[p.len() - 1];
                return Err(ebad(format!(
                    "subpath {} is open: it ends at ({:.3}, {:.3}) mm, {gap:.3} mm from its start; \
                     close it (Z)",
                    k + 1,
                    e[0],
                    e[1]
                )));
            }
            if gap <= 1e-9 {
                p.pop();
            }
            if p.len() < 3 {
                return Err(ebad(format!("subpath {} encloses no area", k + 1)));
            }
            loops.push(Loop { points: p, element: element.clone() });
        }
    }
    if root.is_none() {
        return Err(bad("not an SVG document (no <svg> element)".into()));
    }
    if loops.is_empty() {
        return Err(bad(
            "no closed outline: no path, polygon, rect, circle or ellipse with an area".into(),
        ));
    }
    Ok(loops)
}
