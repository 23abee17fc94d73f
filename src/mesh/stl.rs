//! Reading STL files, binary and ASCII, into a [`RawMesh`] (three unshared vertices per
//! triangle; the loader welds them).
//!
//! # Which kind
//!
//! A file is read as **binary** when its size is exactly 84 + 50·n bytes, n the little-endian
//! count at byte 80 — also when its 80-byte header starts with `solid`, as many exporters write
//! it. Otherwise a file that starts with `solid` and holds no control bytes (other than white
//! space) in its first 4 kB is read as **ASCII**; any other file is a binary STL whose count
//! does not match its size (truncated, or a wrong count), an error saying both numbers.
//!
//! # Binary
//!
//! 80-byte header, `u32` count, then per triangle: normal (3 × `f32`), three vertices
//! (3 × `f32` each), a `u16` attribute, all little-endian. The facet normal and the attribute
//! are ignored (normals are computed from the geometry).
//!
//! # ASCII
//!
//! `solid NAME`, then `facet [normal nx ny nz]`, `outer loop`, three or more `vertex x y z`,
//! `endloop`, `endfacet`, …, `endsolid [NAME]`; several solids may follow each other. Keywords
//! are matched without regard to case. Lines end at LF, CRLF or a lone CR, and a UTF-8
//! byte-order mark before `solid` is skipped. A loop of more than three vertices is split into the
//! fan `(v0, v1, v2), (v0, v2, v3), …`.
//!
//! Coordinates are `f32` in a binary file and read as `f64` from ASCII; −0 is read as +0 so
//! the exact weld joins them. Every error names the triangle (1-based, in file order) and, in
//! ASCII, the line.

use std::path::Path;

use nalgebra::Vector3;

use super::raw::{check_position, RawMesh, ValueError};
use crate::limits::MAX_FILE_TRIANGLES;
use crate::{Error, Result};

/// Bytes of the binary header (80) and count (4).
const HEADER: usize = 84;
/// Bytes of one binary triangle record.
const RECORD: usize = 50;
/// The UTF-8 byte-order mark some editors write before a text file.
pub(crate) const BOM: &[u8] = b"\xEF\xBB\xBF";

/// The triangle count of a binary STL if the file's size is exactly what it announces.
pub(crate) fn binary_count(bytes: &[u8]) -> Option<usize> {
    if bytes.len() < HEADER {
        return None;
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    (HEADER as u64 + RECORD as u64 * n as u64 == bytes.len() as u64).then_some(n)
}

/// Whether the bytes start (after blanks) with the ASCII STL keyword `solid`.
pub(crate) fn starts_with_solid(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
    bytes[start..].len() >= 5 && bytes[start..start + 5].eq_ignore_ascii_case(b"solid")
}

/// Reads an STL file's bytes. `scale` is the loader's scale (for the coordinate bound).
pub(crate) fn read(path: &Path, bytes: &[u8], scale: f64) -> Result<RawMesh> {
    if let Some(n) = binary_count(bytes) {
        return read_binary(path, bytes, n, scale);
    }
    // An ASCII STL holds no control bytes; a binary one (count, floats) nearly always does.
    // A UTF-8 byte-order mark before `solid` is skipped (lines are counted from it all the same).
    let text = bytes.strip_prefix(BOM).unwrap_or(bytes);
    if starts_with_solid(text) && !has_control_bytes(text) {
        return read_ascii(path, text, scale);
    }
    if bytes.len() < HEADER {
        return Err(Error::BinaryFile {
            path: path.to_owned(),
            offset: 0,
            message: format!(
                "{} bytes: too short for a binary STL (an 84-byte header) and not an ASCII STL \
                 (it does not start with `solid`)",
                bytes.len()
            ),
        });
    }
    Err(count_mismatch(path, bytes))
}

/// The error of a binary STL whose announced count does not match its size.
fn count_mismatch(path: &Path, bytes: &[u8]) -> Error {
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    let body = (bytes.len() - HEADER) as u64;
    let (whole, rest) = (body / RECORD as u64, body % RECORD as u64);
    let what = if whole < n { "truncated" } else { "longer than its header says" };
    let tail = if rest > 0 {
        format!(" and {rest} byte(s) of an incomplete triangle {}", whole + 1)
    } else {
        String::new()
    };
    Error::BinaryFile {
        path: path.to_owned(),
        offset: 80,
        message: format!(
            "binary STL {what}: the header announces {n} triangles ({} bytes) but the file has \
             {} bytes, room for {whole} triangle(s){tail}",
            HEADER as u64 + RECORD as u64 * n,
            bytes.len()
        ),
    }
}

/// Whether the first 4 kB hold a control byte other than white space (ASCII STL has none).
fn has_control_bytes(bytes: &[u8]) -> bool {
    bytes.iter().take(4096).any(|&b| (b < 0x20 && !b.is_ascii_whitespace()) || b == 0x7f)
}

fn read_binary(path: &Path, bytes: &[u8], n: usize, scale: f64) -> Result<RawMesh> {
    if n == 0 {
        return Err(Error::EmptyMesh {
            path: path.to_owned(),
            message: "binary STL with 0 triangles".into(),
        });
    }
    if n > MAX_FILE_TRIANGLES {
        return Err(Error::BinaryFile {
            path: path.to_owned(),
            offset: 80,
            message: format!(
                "{n} triangles: more than the {MAX_FILE_TRIANGLES} a mesh may have \
                 (limits::MAX_FILE_TRIANGLES)"
            ),
        });
    }
    // The size matches 84 + 50·n, so every allocation below is bounded by the file's size.
    let mut raw = RawMesh::with_capacity(3 * n, n);
    for t in 0..n {
        let rec = &bytes[HEADER + RECORD * t..HEADER + RECORD * (t + 1)];
        let f = |k: usize| {
            f64::from(f32::from_le_bytes([
                rec[4 * k],
                rec[4 * k + 1],
                rec[4 * k + 2],
                rec[4 * k + 3],
            ]))
        };
        for c in 0..3 {
            let p = Vector3::new(f(3 + 3 * c), f(4 + 3 * c), f(5 + 3 * c)).map(|x| x + 0.0);
            check_position(&p, scale).map_err(|e| Error::BinaryFile {
                path: path.to_owned(),
                offset: (HEADER + RECORD * t + 12 + 12 * c) as u64,
                message: format!("triangle {}: vertex {} {}", t + 1, c + 1, e.describe(scale)),
            })?;
            raw.positions.push(p);
        }
        let v = 3 * t as u32;
        raw.push_face([v, v + 1, v + 2], 0, t as u32 + 1);
    }
    Ok(raw)
}

/// A token of an ASCII file: its text and 1-based line.
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Tokens<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Tokens { bytes, pos: 0, line: 1 }
    }

    /// The next token and its line, or `None` at the end. Lines end at LF, CRLF or a lone CR.
    fn next(&mut self) -> Option<(&'a [u8], usize)> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            let b = self.bytes[self.pos];
            if b == b'\n' || (b == b'\r' && self.bytes.get(self.pos + 1) != Some(&b'\n')) {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= self.bytes.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some((&self.bytes[start..self.pos], self.line))
    }

    /// Skips the rest of the current line (a solid's name), up to its LF or CR.
    fn skip_line(&mut self) {
        while self.pos < self.bytes.len() && !matches!(self.bytes[self.pos], b'\n' | b'\r') {
            self.pos += 1;
        }
    }
}

fn show(t: &[u8]) -> String {
    let s: String = String::from_utf8_lossy(t).chars().take(40).collect();
    format!("{s:?}")
}

/// An ASCII STL being read: its tokens, and the file for messages.
struct Ascii<'a> {
    path: &'a Path,
    tk: Tokens<'a>,
}

impl Ascii<'_> {
    fn err(&self, line: usize, message: String) -> Error {
        Error::Parse { path: self.path.to_owned(), line, message }
    }

    /// Expects keyword `kw` as the next token.
    fn expect(&mut self, kw: &str, ctx: &str) -> Result<usize> {
        match self.tk.next() {
            Some((t, l)) if t.eq_ignore_ascii_case(kw.as_bytes()) => Ok(l),
            Some((t, l)) => Err(self.err(l, format!("expected `{kw}` {ctx}, found {}", show(t)))),
            None => {
                Err(self
                    .err(self.tk.line, format!("unexpected end of file: expected `{kw}` {ctx}")))
            }
        }
    }

    fn number(&mut self, ctx: &str) -> Result<f64> {
        match self.tk.next() {
            Some((t, l)) => std::str::from_utf8(t)
                .ok()
                .and_then(|s| s.parse::<f64>().ok())
                .ok_or_else(|| self.err(l, format!("expected a number {ctx}, found {}", show(t)))),
            None => {
                Err(self
                    .err(self.tk.line, format!("unexpected end of file: expected a number {ctx}")))
            }
        }
    }

    /// After `facet`: the optional `normal nx ny nz` (ignored), then `outer loop`.
    fn facet_header(&mut self, ctx: &str) -> Result<()> {
        // `normal nx ny nz` (ignored) is optional.
        let mut next = self.tk.next();
        if let Some((t, _)) = next {
            if t.eq_ignore_ascii_case(b"normal") {
                for _ in 0..3 {
                    self.number(&format!("(facet normal) {ctx}"))?;
                }
                next = self.tk.next();
            }
        }
        match next {
            Some((t, _)) if t.eq_ignore_ascii_case(b"outer") => {}
            Some((t, l)) => {
                return Err(self.err(l, format!("expected `outer loop` {ctx}, found {}", show(t))))
            }
            None => {
                return Err(self
                    .err(self.tk.line, format!("unexpected end of file: expected `outer` {ctx}")))
            }
        }
        self.expect("loop", ctx)?;
        Ok(())
    }

    /// The `vertex x y z` lines of facet `triangles` up to its `endloop`, pushed to `raw`;
    /// returns their number (at least 3).
    fn facet_vertices(
        &mut self,
        raw: &mut RawMesh,
        triangles: u32,
        ctx: &str,
        scale: f64,
    ) -> Result<u32> {
        let mut corners = 0u32;
        loop {
            match self.tk.next() {
                Some((t, l)) if t.eq_ignore_ascii_case(b"vertex") => {
                    let mut p = Vector3::zeros();
                    for k in 0..3 {
                        p[k] = self.number(&format!("(vertex {}) {ctx}", corners + 1))? + 0.0;
                    }
                    check_position(&p, scale).map_err(|e| {
                        let message = format!(
                            "facet {triangles}: vertex {} {}",
                            corners + 1,
                            e.describe(scale)
                        );
                        Error::NonFinite { path: self.path.to_owned(), line: l, message }
                    })?;
                    raw.positions.push(p);
                    corners += 1;
                }
                Some((t, l)) if t.eq_ignore_ascii_case(b"endloop") => {
                    if corners < 3 {
                        return Err(self.err(
                            l,
                            format!("facet {triangles} has {corners} vertices; a facet needs 3"),
                        ));
                    }
                    return Ok(corners);
                }
                Some((t, l)) => {
                    return Err(self.err(
                        l,
                        format!("expected `vertex` or `endloop` {ctx}, found {}", show(t)),
                    ))
                }
                None => {
                    return Err(self.err(
                        self.tk.line,
                        format!("unexpected end of file {ctx} (truncated file?)"),
                    ))
                }
            }
        }
    }

    /// Facet `triangles` (its `facet` keyword on `line` read), from its normal to its
    /// `endfacet`, split into the fan of its vertices.
    fn facet(&mut self, raw: &mut RawMesh, triangles: u32, line: usize, scale: f64) -> Result<()> {
        let ctx = format!("in facet {triangles}");
        self.facet_header(&ctx)?;
        let first = raw.positions.len() as u32;
        let corners = self.facet_vertices(raw, triangles, &ctx, scale)?;
        self.expect("endfacet", &ctx)?;
        if corners > 3 {
            raw.polygons_split += 1;
        }
        for k in 1..corners - 1 {
            if raw.faces.len() >= MAX_FILE_TRIANGLES {
                return Err(self.err(
                    line,
                    format!(
                        "more than {MAX_FILE_TRIANGLES} triangles (limits::MAX_FILE_TRIANGLES)"
                    ),
                ));
            }
            raw.push_face([first, first + k, first + k + 1], line as u32, triangles);
        }
        Ok(())
    }
}

fn read_ascii(path: &Path, bytes: &[u8], scale: f64) -> Result<RawMesh> {
    let mut rd = Ascii { path, tk: Tokens::new(bytes) };
    let mut raw = RawMesh::default();
    let mut triangles = 0u32;
    let mut in_solid = false;
    loop {
        let Some((t, line)) = rd.tk.next() else {
            if raw.faces.is_empty() {
                return Err(Error::EmptyMesh {
                    path: path.to_owned(),
                    message: "ASCII STL without facets".into(),
                });
            }
            // A missing final `endsolid` is tolerated.
            return Ok(raw);
        };
        if t.eq_ignore_ascii_case(b"solid") && !in_solid {
            rd.tk.skip_line();
            in_solid = true;
            continue;
        }
        if t.eq_ignore_ascii_case(b"endsolid") && in_solid {
            rd.tk.skip_line();
            in_solid = false;
            continue;
        }
        if !t.eq_ignore_ascii_case(b"facet") || !in_solid {
            let want = if in_solid { "`facet` or `endsolid`" } else { "`solid`" };
            return Err(rd.err(line, format!("expected {want}, found {}", show(t))));
        }
        triangles += 1;
        if raw.faces.len() >= MAX_FILE_TRIANGLES {
            return Err(rd.err(
                line,
                format!("more than {MAX_FILE_TRIANGLES} triangles (limits::MAX_FILE_TRIANGLES)"),
            ));
        }
        rd.facet(&mut raw, triangles, line, scale)?;
    }
}

/// What an invalid coordinate is, for the readers' messages.
impl ValueError {
    /// The message tail: `has a non-finite …` or `has a coordinate … beyond …`.
    pub(crate) fn describe(&self, scale: f64) -> String {
        match *self {
            ValueError::NonFinite => "has a non-finite (NaN or infinite) coordinate".into(),
            ValueError::TooLarge(x) => {
                let scaled =
                    if scale == 1.0 { String::new() } else { format!(" (×{scale} scale)") };
                format!(
                    "has a coordinate {x:e}{scaled} beyond ±{:e}: areas and normals of its faces \
                     would overflow to infinity",
                    crate::limits::MAX_COORDINATE
                )
            }
        }
    }
}
