//! A fast pass over the text of an OBJ file: statement syntax with line numbers, and the file
//! indices of every face corner in file order.
//!
//! tobj parses the numbers but re-indexes positions per object in first-use order and reports
//! errors without a line. This pass gives the loader what tobj does not: the 0-based file
//! index (`v`, `vt`, `vn`) of every triangle corner after the same fan triangulation tobj does
//! (`(c0, c1, c2), (c0, c2, c3), …`), the line of every face, and one-line errors naming the
//! line. It runs beside tobj on another thread.
//!
//! It also records the objects as tobj forms them ([`ScanModel`]) and whether the file stays
//! within what the parallel number parser ([`super::parse`]) reproduces bit for bit
//! ([`Scan::parallel_ok`]).

use std::path::Path;

use crate::limits::MAX_POLYGON_CORNERS;
use crate::{Error, Result};

/// Marks a corner without a texture coordinate or normal.
pub(crate) const NONE: u32 = u32::MAX;

/// What the pass found.
#[derive(Debug, Default)]
pub(crate) struct Scan {
    /// Number of `v`, `vt` and `vn` statements.
    pub num_v: usize,
    pub num_vt: usize,
    pub num_vn: usize,
    /// File index of the position, texture coordinate and normal of every triangle corner.
    pub corner_v: Vec<u32>,
    pub corner_vt: Vec<u32>,
    pub corner_vn: Vec<u32>,
    /// 1-based line of the `f` statement of every triangle.
    pub face_line: Vec<u32>,
    /// Statements with an unknown keyword (ignored, as OBJ readers do).
    pub ignored_statements: usize,
    /// The objects as tobj forms them, in file order (always at least one).
    pub models: Vec<ScanModel>,
    /// False when the file has something only tobj handles exactly: non-ASCII bytes, face
    /// indices that refer forward, or `l` statements.
    pub parallel_ok: bool,
    /// Whether some `v` statement has a vertex colour (`x y z r g b [a]`). tobj cannot read
    /// such a file (it refuses `r g b a`, and fails when only some vertices have a colour), so
    /// its numbers are the parallel parser's whatever the reader chosen.
    pub colours: bool,
}

/// An object as tobj forms it: the faces from one `o`/`g` statement that follows a face (or
/// from the start of the file) to the next such statement (or the end).
#[derive(Debug, Default)]
pub(crate) struct ScanModel {
    /// The name of the last `o`/`g` statement before the faces (`unnamed_object` if none).
    pub name: String,
    /// First triangle corner (index into the corner lists).
    pub start: usize,
    /// Number of triangle corners.
    pub len: usize,
    /// Number of `vt` and `vn` statements before the object ends.
    pub vt_at_end: usize,
    pub vn_at_end: usize,
}

/// Which of the three index lists a face index refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    V,
    Vt,
    Vn,
}

impl Kind {
    fn keyword(self) -> &'static str {
        match self {
            Kind::V => "v",
            Kind::Vt => "vt",
            Kind::Vn => "vn",
        }
    }
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | 0x0b | 0x0c)
}

pub(crate) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|&b| is_space(b)).filter(|t| !t.is_empty())
}

/// Checks that a line is text: no control characters, valid UTF-8. True if it is not ASCII.
fn check_text(path: &Path, line_no: usize, line: &[u8]) -> Result<bool> {
    let mut non_ascii = false;
    for &b in line {
        if b < 0x20 && !is_space(b) {
            return Err(parse_err(
                path,
                line_no,
                format!("binary data (byte 0x{b:02x}); not an OBJ text file"),
            ));
        }
        non_ascii |= b >= 0x80;
    }
    if non_ascii && std::str::from_utf8(line).is_err() {
        return Err(parse_err(path, line_no, "invalid UTF-8; not an OBJ text file".into()));
    }
    Ok(non_ascii)
}

pub(crate) fn parse_err(path: &Path, line: usize, message: String) -> Error {
    Error::Parse { path: path.to_owned(), line, message }
}

fn show(t: &[u8]) -> String {
    let s = String::from_utf8_lossy(t);
    let s: String = s.chars().take(40).collect();
    format!("{s:?}")
}

/// Iterates over `(1-based line number, line bytes without the newline)`.
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    let n = if bytes.last() == Some(&b'\n') { bytes.len() - 1 } else { bytes.len() };
    bytes[..n].split(|&b| b == b'\n').enumerate().map(|(i, l)| (i + 1, l))
}

/// Keywords of the OBJ format that carry no data grainline uses.
pub(crate) fn is_ignored_keyword(kw: &[u8]) -> bool {
    kw.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'_')
        && kw.first().is_some_and(|b| b.is_ascii_alphabetic())
}

/// Whether a text reads as an OBJ: its first statement (after blank and `#` comment lines)
/// starts with an OBJ keyword (`v`, `vt`, `vn`, `vp`, `f`, `l`, `p`, `o`, `g`, `s`, `mtllib`,
/// `usemtl`). Used for a file whose extension names no format.
pub(crate) fn looks_like_obj(text: &[u8]) -> bool {
    const KEYWORDS: [&[u8]; 12] =
        [b"v", b"vt", b"vn", b"vp", b"f", b"l", b"p", b"o", b"g", b"s", b"mtllib", b"usemtl"];
    text.split(|&b| b == b'\n' || b == b'\r')
        .map(|line| tokens(line).next())
        .find(|first| first.is_some_and(|t| !t.starts_with(b"#")))
        .flatten()
        .is_some_and(|kw| KEYWORDS.contains(&kw))
}

/// A forward reference (index beyond the count so far), checked against the totals at the end.
struct Forward {
    line: u32,
    kind: Kind,
    index: u32,
}

struct Scanner<'a> {
    path: &'a Path,
    out: Scan,
    corners: Vec<[u32; 3]>,
    forward: Vec<Forward>,
    /// The object being read: its name, first corner and whether it has a face yet.
    model_name: String,
    model_start: usize,
    model_has_faces: bool,
}

/// Runs the pass over a whole file.
pub(crate) fn scan(path: &Path, bytes: &[u8]) -> Result<Scan> {
    let mut s = Scanner {
        path,
        out: Scan { parallel_ok: true, ..Default::default() },
        corners: Vec::new(),
        forward: Vec::new(),
        model_name: UNNAMED.into(),
        model_start: 0,
        model_has_faces: false,
    };
    s.out.corner_v.reserve(bytes.len() / 8);
    for (line_no, line) in lines(bytes) {
        s.statement(line_no, line)?;
    }
    s.check_forward()?;
    s.end_model();
    s.out.parallel_ok &= s.forward.is_empty();
    let need_vt = s.out.corner_vt.iter().any(|&t| t != NONE);
    let need_vn = s.out.corner_vn.iter().any(|&t| t != NONE);
    if !need_vt {
        s.out.corner_vt = Vec::new();
    }
    if !need_vn {
        s.out.corner_vn = Vec::new();
    }
    Ok(s.out)
}

/// tobj's name of an object without one.
pub(crate) const UNNAMED: &str = "unnamed_object";

impl Scanner<'_> {
    /// Closes the current object (tobj's `pop_model`).
    fn end_model(&mut self) {
        let end = self.out.corner_v.len();
        self.out.models.push(ScanModel {
            name: self.model_name.clone(),
            start: self.model_start,
            len: end - self.model_start,
            vt_at_end: self.out.num_vt,
            vn_at_end: self.out.num_vn,
        });
        self.model_start = end;
        self.model_has_faces = false;
    }

    /// An `o` or `g` statement: tobj names the object by the rest of the line after its first
    /// character, trimmed.
    fn object(&mut self, line: &[u8]) {
        if self.model_has_faces {
            self.end_model();
        }
        let name = String::from_utf8_lossy(line.get(1..).unwrap_or_default());
        let name = name.trim();
        self.model_name = if name.is_empty() { UNNAMED.into() } else { name.into() };
    }

    fn statement(&mut self, line_no: usize, line: &[u8]) -> Result<()> {
        if check_text(self.path, line_no, line)? {
            self.out.parallel_ok = false;
        }
        let mut toks = tokens(line);
        let Some(kw) = toks.next() else { return Ok(()) };
        match kw {
            b"v" => {
                self.vertex(line_no, toks)?;
                self.out.num_v += 1;
            }
            b"vt" => {
                let n = toks.count();
                if !(2..=3).contains(&n) {
                    return Err(self.truncated(line_no, "texture coordinate", "2 values", n));
                }
                self.out.num_vt += 1;
            }
            b"vn" => {
                let n = toks.count();
                if n != 3 {
                    return Err(self.truncated(line_no, "normal", "3 components", n));
                }
                self.out.num_vn += 1;
            }
            b"f" => {
                self.face(line_no, toks)?;
                self.model_has_faces = true;
            }
            b"l" => {
                self.out.parallel_ok = false;
                self.model_has_faces = true;
                self.corners_of(line_no, toks)?;
                if self.corners.len() > 2 {
                    return Err(parse_err(
                        self.path,
                        line_no,
                        "polyline `l` with more than 2 vertices is not supported".into(),
                    ));
                }
            }
            b"usemtl" if toks.next().is_none() => {
                return Err(parse_err(self.path, line_no, "usemtl without a name".into()));
            }
            b"o" | b"g" => self.object(line),
            _ if kw[0] == b'#' => {}
            _ if is_ignored_keyword(kw) => {
                if !matches!(kw, b"o" | b"g" | b"s" | b"usemtl" | b"mtllib") {
                    self.out.ignored_statements += 1;
                }
            }
            _ => {
                return Err(parse_err(
                    self.path,
                    line_no,
                    format!("unexpected text {}; not an OBJ statement", show(kw)),
                ))
            }
        }
        Ok(())
    }

    /// A `v` statement: `x y z`; `x y z w`, homogeneous, the position (x, y, z)/w, so `w` must
    /// be a finite non-zero number; or `x y z r g b [a]`, a vertex colour (scan exports write
    /// it), whose values must be numbers and are not used. The coordinates themselves are the
    /// number reader's (tobj or [`super::parse`]).
    fn vertex<'t>(&mut self, line_no: usize, toks: impl Iterator<Item = &'t [u8]>) -> Result<()> {
        let mut rest: [&[u8]; 4] = [&[]; 4];
        let mut n = 0;
        for t in toks {
            if (3..7).contains(&n) {
                rest[n - 3] = t;
            }
            n += 1;
        }
        let number = |t: &[u8]| match super::parse::number(t) {
            Some(x) => Ok(x),
            None => Err(parse_err(self.path, line_no, format!("bad number {}", show(t)))),
        };
        match n {
            3 => {}
            4 => {
                let w = number(rest[0])?;
                if w == 0.0 || !w.is_finite() {
                    let w = if w == 0.0 { "zero".to_string() } else { format!("{w}") };
                    return Err(parse_err(
                        self.path,
                        line_no,
                        format!(
                            "vertex weight w is {w}; the position is (x, y, z)/w, so w must be \
                             finite and non-zero"
                        ),
                    ));
                }
            }
            6 | 7 => {
                for &t in &rest[..n - 3] {
                    number(t)?;
                }
                self.out.colours = true;
            }
            _ => {
                let hint = if n < 3 { " (truncated line?)" } else { "" };
                return Err(parse_err(
                    self.path,
                    line_no,
                    format!(
                        "vertex with {n} numbers; a vertex takes 3 (x y z), 4 (x y z w) \
                         or 6 to 7 (x y z r g b [a], the colour not used){hint}"
                    ),
                ));
            }
        }
        Ok(())
    }

    fn truncated(&self, line_no: usize, what: &str, need: &str, n: usize) -> Error {
        parse_err(self.path, line_no, format!("{what} needs {need}, found {n} (truncated line?)"))
    }

    fn face<'t>(&mut self, line_no: usize, toks: impl Iterator<Item = &'t [u8]>) -> Result<()> {
        self.corners_of(line_no, toks)?;
        let n = self.corners.len();
        if n < 3 {
            return Err(parse_err(
                self.path,
                line_no,
                format!("face with {n} corners; a face needs at least 3 (truncated line?)"),
            ));
        }
        let c0 = self.corners[0];
        for k in 1..n - 1 {
            for c in [c0, self.corners[k], self.corners[k + 1]] {
                self.out.corner_v.push(c[0]);
                self.out.corner_vt.push(c[1]);
                self.out.corner_vn.push(c[2]);
            }
            self.out.face_line.push(line_no as u32);
        }
        Ok(())
    }

    fn corners_of<'t>(
        &mut self,
        line_no: usize,
        toks: impl Iterator<Item = &'t [u8]>,
    ) -> Result<()> {
        self.corners.clear();
        for tok in toks {
            if self.corners.len() == MAX_POLYGON_CORNERS {
                return Err(parse_err(
                    self.path,
                    line_no,
                    format!(
                        "face with more than {MAX_POLYGON_CORNERS} corners \
                         (limits::MAX_POLYGON_CORNERS)"
                    ),
                ));
            }
            let c = self.corner(line_no, tok)?;
            self.corners.push(c);
        }
        Ok(())
    }

    /// Parses `v`, `v/vt`, `v//vn` or `v/vt/vn` into 0-based file indices.
    fn corner(&mut self, line_no: usize, tok: &[u8]) -> Result<[u32; 3]> {
        let mut out = [NONE; 3];
        let kinds = [Kind::V, Kind::Vt, Kind::Vn];
        for (k, part) in tok.split(|&b| b == b'/').enumerate() {
            if k >= 3 {
                return Err(self.bad_corner(line_no, tok));
            }
            if part.is_empty() {
                if k == 0 {
                    return Err(self.bad_corner(line_no, tok));
                }
                continue;
            }
            let Some(x) = parse_int(part) else { return Err(self.bad_corner(line_no, tok)) };
            out[k] = self.resolve(line_no, kinds[k], x)?;
        }
        Ok(out)
    }

    fn bad_corner(&self, line_no: usize, tok: &[u8]) -> Error {
        parse_err(
            self.path,
            line_no,
            format!("bad face corner {}; expected v, v/vt, v//vn or v/vt/vn", show(tok)),
        )
    }

    fn count(&self, kind: Kind) -> usize {
        match kind {
            Kind::V => self.out.num_v,
            Kind::Vt => self.out.num_vt,
            Kind::Vn => self.out.num_vn,
        }
    }

    /// Turns a 1-based (or negative, relative) OBJ index into a 0-based one.
    fn resolve(&mut self, line_no: usize, kind: Kind, x: i64) -> Result<u32> {
        let count = self.count(kind) as i64;
        let idx = if x > 0 { x - 1 } else { count + x };
        if x == 0 || idx < 0 || idx >= u32::MAX as i64 {
            return Err(Error::IndexOutOfRange {
                path: self.path.to_owned(),
                line: line_no,
                message: out_of_range_msg(kind, x, count as usize),
            });
        }
        if idx >= count {
            self.forward.push(Forward { line: line_no as u32, kind, index: idx as u32 });
        }
        Ok(idx as u32)
    }

    fn check_forward(&self) -> Result<()> {
        for f in &self.forward {
            let count = self.count(f.kind);
            if f.index as usize >= count {
                return Err(Error::IndexOutOfRange {
                    path: self.path.to_owned(),
                    line: f.line as usize,
                    message: out_of_range_msg(f.kind, f.index as i64 + 1, count),
                });
            }
        }
        Ok(())
    }
}

fn out_of_range_msg(kind: Kind, x: i64, count: usize) -> String {
    let kw = kind.keyword();
    format!("face refers to {kw} {x}, but the file has {count} `{kw}` entries")
}

pub(crate) fn parse_int(s: &[u8]) -> Option<i64> {
    let (neg, digits) = match s.first()? {
        b'-' => (true, &s[1..]),
        b'+' => (false, &s[1..]),
        _ => (false, s),
    };
    if digits.is_empty() || digits.len() > 15 {
        return None;
    }
    let mut v: i64 = 0;
    for &d in digits {
        if !d.is_ascii_digit() {
            return None;
        }
        v = v * 10 + (d - b'0') as i64;
    }
    Some(if neg { -v } else { v })
}

/// The 1-based line of the `index`-th (0-based) statement of `kind`.
pub(crate) fn line_of(bytes: &[u8], kind: Kind, index: usize) -> usize {
    let kw = kind.keyword().as_bytes();
    lines(bytes).filter(|(_, l)| tokens(l).next() == Some(kw)).nth(index).map_or(0, |(n, _)| n)
}

/// Finds the line behind an error tobj reported without one: the first number tobj cannot
/// parse (as `f32`), or a `w` of zero (the scanner has checked `w` and colours already).
pub(crate) fn locate_tobj_error(path: &Path, bytes: &[u8], err: tobj::LoadError) -> Error {
    for (line_no, line) in lines(bytes) {
        let mut toks = tokens(line);
        let need = match toks.next() {
            // x y z, and w when it is the fourth and last number (not a colour's red).
            Some(b"v") => 3 + usize::from(tokens(line).count() == 5),
            Some(b"vt") => 2,
            Some(b"vn") => 3,
            _ => continue,
        };
        for (k, t) in toks.take(need).enumerate() {
            let parsed = std::str::from_utf8(t).ok().and_then(|s| s.parse::<f32>().ok());
            match parsed {
                None => {
                    return parse_err(path, line_no, format!("bad number {}", show(t)));
                }
                Some(w) if k == 3 && w == 0.0 => {
                    return parse_err(path, line_no, "vertex weight w is zero".into());
                }
                _ => {}
            }
        }
    }
    parse_err(path, 0, format!("OBJ reader: {err}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(text: &str) -> Result<Scan> {
        scan(Path::new("t.obj"), text.as_bytes())
    }

    #[test]
    fn quad_fan_and_negative_indices() {
        let s = run("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n").unwrap();
        assert_eq!(s.corner_v, vec![0, 1, 2, 0, 2, 3]);
        assert_eq!(s.face_line, vec![5, 5]);
        assert!(s.corner_vt.is_empty());
    }

    #[test]
    fn errors_carry_lines() {
        let e = run("v 0 0 0\nv 1 0\n").unwrap_err();
        assert!(matches!(e, Error::Parse { line: 2, .. }), "{e}");
        let e = run("v 0 0 0\nf 1 2 3\n").unwrap_err();
        assert!(matches!(e, Error::IndexOutOfRange { line: 2, .. }), "{e}");
        let e = run("v 0 0 0\n\u{1}\u{2}\n").unwrap_err();
        assert!(matches!(e, Error::Parse { line: 2, .. }), "{e}");
    }

    #[test]
    fn vertex_forms() {
        let s = run("v 0 0 0\nv 1 0 0 2\nv 0 1 0 1 1 1\nv 0 0 1 1 1 1 1\n").unwrap();
        assert_eq!((s.num_v, s.colours, s.parallel_ok), (4, true, true));
        assert!(!run("v 0 0 0 2\n").unwrap().colours);
        for (text, want) in [
            ("v 0 0 0\nv 1 0 0 1 1\n", "vertex with 5 numbers"),
            ("v 0 0 0\nv 1 0 0 1 1 1 1 1\n", "vertex with 8 numbers"),
            ("v 0 0 0\nv 1 0 0 -0\n", "vertex weight w is zero"),
            ("v 0 0 0\nv 1 0 0 -inf\n", "vertex weight w is -inf"),
            ("v 0 0 0\nv 1 0 0 w\n", "bad number \"w\""),
            ("v 0 0 0\nv 1 0 0 1 x 1\n", "bad number \"x\""),
        ] {
            let e = run(text).unwrap_err();
            assert!(matches!(e, Error::Parse { line: 2, .. }), "{e}");
            assert!(e.to_string().contains(want), "{e}");
        }
    }
}

/// Rewrites the forms exporters write into the plain OBJ text both readers parse, keeping
/// every statement on its physical line (so line numbers in errors stay the editor's):
///
/// * a UTF-8 byte-order mark at the start is removed;
/// * a CR not followed by LF (classic Mac line endings) ends the line, as LF;
/// * a trailing comment — `#` at the start of a line or after a space or tab, to the end of
///   the line — is removed (a `#` inside a word, as in `o part#2`, stays);
/// * a line ending in `\` (after the comment is removed, trailing spaces allowed) continues on
///   the next: the two are joined with a space on the first line and the second is left empty.
///
/// Returns the input unchanged (no copy) when it has none of these forms.
pub(crate) fn normalize(bytes: Vec<u8>) -> Vec<u8> {
    let bom = bytes.starts_with(b"\xEF\xBB\xBF");
    let lone_cr =
        bytes.iter().enumerate().any(|(i, &b)| b == b'\r' && bytes.get(i + 1) != Some(&b'\n'));
    let backslash = bytes.contains(&b'\\');
    let comment = bytes.windows(2).any(|w| matches!(w[0], b' ' | b'\t') && w[1] == b'#');
    if !(bom || lone_cr || backslash || comment) {
        return bytes;
    }
    let body = if bom { &bytes[3..] } else { &bytes[..] };
    let mut out = Vec::with_capacity(body.len());
    // Newlines owed by continued lines, written when the logical line ends.
    let mut owed = 0usize;
    let mut i = 0;
    while i < body.len() {
        // One physical line: [i, end), terminated by LF, CRLF, CR or the end of the text.
        let end =
            body[i..].iter().position(|&b| b == b'\n' || b == b'\r').map_or(body.len(), |p| i + p);
        let next = match body.get(end) {
            Some(b'\r') if body.get(end + 1) == Some(&b'\n') => end + 2,
            Some(_) => end + 1,
            None => end,
        };
        let mut line = &body[i..end];
        if let Some(p) = (0..line.len())
            .find(|&k| line[k] == b'#' && (k == 0 || matches!(line[k - 1], b' ' | b'\t')))
        {
            line = &line[..p];
        }
        let trimmed =
            line.len() - line.iter().rev().take_while(|&&b| b == b' ' || b == b'\t').count();
        if trimmed > 0 && line[trimmed - 1] == b'\\' && next > end {
            out.extend_from_slice(&line[..trimmed - 1]);
            out.push(b' ');
            owed += 1;
        } else {
            out.extend_from_slice(line);
            if next > end {
                out.push(b'\n');
            }
            out.extend(std::iter::repeat_n(b'\n', owed));
            owed = 0;
        }
        i = next;
    }
    out.extend(std::iter::repeat_n(b'\n', owed));
    out
}

#[cfg(test)]
mod normalize_tests {
    use super::normalize;

    fn n(s: &str) -> String {
        String::from_utf8(normalize(s.as_bytes().to_vec())).unwrap()
    }

    #[test]
    fn exporter_forms_become_plain_lines_on_their_own_line_numbers() {
        assert_eq!(n("\u{feff}v 0 0 0\n"), "v 0 0 0\n");
        assert_eq!(n("v 0 0 0\rv 1 0 0\r\nf 1 2 3\r"), "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
        assert_eq!(n("f 1 2 \\\n 3\nv 1 2 3\n"), "f 1 2   3\n\nv 1 2 3\n");
        assert_eq!(n("f 1 \\  \n2 \\\n3"), "f 1  2  3\n\n");
        assert_eq!(n("v 0 0 0 # origin\n# all\no part#2\n"), "v 0 0 0 \n\no part#2\n");
        assert_eq!(n("f 1 2 3 # not continued \\\nv 0 0 0\n"), "f 1 2 3 \nv 0 0 0\n");
        let plain = "v 0 0 0\r\nf 1 2 3\n";
        assert_eq!(n(plain), plain);
    }
}
