//! One parallel pass over a plain OBJ file that does the scanner's work ([`super::scan`]) and the
//! number parser's ([`super::parse`]) at once, for large files.
//!
//! The file is cut into chunks at line ends and every chunk is read on its own, counting its
//! statements from zero; the chunks are then joined in file order with the counts of the chunks
//! before them added, so the result does not depend on the thread count or the chunk size. A
//! chunk cannot know how many `v` came before it, so the pass takes only what it can join
//! exactly and gives up (`None`) on anything else: any error, non-ASCII text, negative
//! (relative) or forward face indices, `l` statements, a number `f64::from_str` refuses, a `w`
//! of zero or not finite. Vertex colours (`v x y z r g b [a]`) are read past, as the scanner
//! and the number parser read them. The loader then runs the two sequential passes, which
//! handle every file and report every error with its line. When it succeeds, the result is
//! exactly theirs ([`Scan`] field by field, [`Values`] bit for bit; unit tests below and
//! tests/mesh_parser_equivalence.rs).
//!
//! Forward references are found without the counts of earlier chunks: a corner index `i` of
//! kind K read when the chunk had seen `c` statements of kind K refers forward exactly when
//! `i ≥ before_K + c`, `before_K` being the count in earlier chunks; so each chunk keeps the
//! largest `i − c` per kind and the join compares it with `before_K`.

use rayon::prelude::*;

use super::parse::{line_chunks, number, position, Values};
use super::scan::{is_ignored_keyword, parse_int, Scan, ScanModel, NONE, UNNAMED};

/// Bytes per chunk for a file of `len` bytes: about 64 chunks, between 64 bytes and 1 MiB. Small
/// files are cut too, so the equivalence tests exercise the join.
fn chunk_size(len: usize) -> usize {
    (len / 64).clamp(64, 1 << 20)
}

/// Scans and parses `bytes`; `None` when the file needs the sequential passes.
pub(crate) fn scan_parallel(bytes: &[u8]) -> Option<(Scan, Values)> {
    scan_chunks(bytes, chunk_size(bytes.len()))
}

/// [`scan_parallel`] with a given chunk size (at least 1 byte; chunks end at line ends).
fn scan_chunks(bytes: &[u8], chunk: usize) -> Option<(Scan, Values)> {
    let bounds = line_chunks(bytes, chunk);
    let parts: Vec<Option<Part>> =
        bounds.par_windows(2).map(|w| Part::read(&bytes[w[0]..w[1]])).collect();
    let parts: Vec<Part> = parts.into_iter().collect::<Option<_>>()?;
    join(&parts)
}

/// An `o`/`g` statement, with the chunk's counts where it stands.
struct ObjectEvent {
    /// Triangle corners, `vt` and `vn` statements before it in the chunk.
    corners: usize,
    vt: usize,
    vn: usize,
    /// Whether a face came before it in the chunk, after the chunk's previous `o`/`g`.
    faces_before: bool,
    name: String,
}

/// What one chunk holds, counted from the chunk's start.
#[derive(Default)]
struct Part {
    /// Line ends in the chunk (its first line is this many lines after the previous chunk's).
    lines: usize,
    values: Values,
    corner_v: Vec<u32>,
    /// Empty while the chunk has no `vt` (`vn`) corner; then one entry per corner.
    corner_vt: Vec<u32>,
    corner_vn: Vec<u32>,
    /// 0-based line of every triangle's `f`, within the chunk.
    face_line: Vec<u32>,
    ignored_statements: usize,
    /// Whether a `v` statement has a vertex colour.
    colours: bool,
    objects: Vec<ObjectEvent>,
    /// Whether a face follows the chunk's last `o`/`g` (or its start, if none).
    faces_after: bool,
    /// Per kind (`v`, `vt`, `vn`): the largest `index − count so far` of the chunk's corners.
    reach: [i64; 3],
}

/// Lines of a chunk and the whitespace-separated tokens of each, in one pass over the bytes,
/// which also checks that every byte is printable ASCII or OBJ whitespace (`plain`). Lines are
/// the scanner's: the text split at `\n` after dropping one final `\n`.
struct Lines<'a> {
    bytes: &'a [u8],
    at: usize,
    /// Line ends (`\n`) passed so far.
    newlines: usize,
    /// Whether a byte that is neither printable ASCII nor whitespace was seen.
    bad: bool,
}

impl<'a> Lines<'a> {
    /// The next line, its tokens as `(start, end)` within it in `toks`; `None` at the end.
    fn next(&mut self, toks: &mut Vec<(usize, usize)>) -> Option<&'a [u8]> {
        let bytes = self.bytes;
        if self.at >= bytes.len() {
            return None;
        }
        toks.clear();
        let start = self.at;
        let (mut i, mut tok, mut bad) = (start, usize::MAX, false);
        while i < bytes.len() {
            let c = bytes[i];
            // Outside 0x20..0x80 and not one of \t \n 0x0b 0x0c \r.
            bad |= (c.wrapping_sub(0x20) >= 0x60) & (c.wrapping_sub(9) >= 5);
            if c == b'\n' {
                self.newlines += 1;
                break;
            }
            // The scanner's whitespace: space, \t, 0x0b, 0x0c, \r (\n is handled above).
            if c == b' ' || c.wrapping_sub(9) < 5 {
                if tok != usize::MAX {
                    toks.push((tok - start, i - start));
                    tok = usize::MAX;
                    // A line past the corner budget: the sequential scanner refuses it.
                    if toks.len() > crate::limits::MAX_POLYGON_CORNERS + 1 {
                        (self.bad, self.at) = (true, bytes.len());
                        return None;
                    }
                }
            } else if tok == usize::MAX {
                tok = i;
            }
            i += 1;
        }
        if tok != usize::MAX {
            toks.push((tok - start, i - start));
        }
        // The keyword and more than the budget of corners (the last one ends at the line end).
        if toks.len() > crate::limits::MAX_POLYGON_CORNERS + 1 {
            (self.bad, self.at) = (true, bytes.len());
            return None;
        }
        self.bad |= bad;
        self.at = i + 1;
        Some(&bytes[start..i])
    }
}

impl Part {
    fn read(chunk: &[u8]) -> Option<Part> {
        let mut p = Part { reach: [i64::MIN; 3], ..Default::default() };
        let mut lines = Lines { bytes: chunk, at: 0, newlines: 0, bad: false };
        let (mut toks, mut corners) = (Vec::new(), Vec::new());
        let mut line_no = 0;
        while let Some(line) = lines.next(&mut toks) {
            p.statement(line_no, line, &toks, &mut corners)?;
            line_no += 1;
        }
        if lines.bad {
            return None;
        }
        p.lines = lines.newlines;
        Some(p)
    }

    fn statement(
        &mut self,
        line_no: u32,
        line: &[u8],
        toks: &[(usize, usize)],
        corners: &mut Vec<[u32; 3]>,
    ) -> Option<()> {
        let count = toks.len();
        let mut toks = toks.iter().map(|&(a, b)| &line[a..b]);
        let Some(kw) = toks.next() else { return Some(()) };
        match kw {
            // `x y z`, `x y z w` or `x y z r g b [a]`, read as the number parser reads them.
            b"v" => {
                self.values.v.push(position(&mut toks)?);
                // The keyword and more than x y z w: a colour.
                self.colours |= count > 5;
            }
            b"vt" => {
                let (a, b) = (toks.next()?, toks.next()?);
                if toks.nth(1).is_some() {
                    return None;
                }
                self.values.vt.push([number(a)?, number(b)?]);
            }
            b"vn" => {
                let (a, b, c) = (toks.next()?, toks.next()?, toks.next()?);
                if toks.next().is_some() {
                    return None;
                }
                self.values.vn.push([number(a)?, number(b)?, number(c)?]);
            }
            b"f" => {
                corners.clear();
                for tok in toks {
                    corners.push(self.corner(tok)?);
                }
                if corners.len() < 3 {
                    return None;
                }
                self.face(line_no, corners);
                self.faces_after = true;
            }
            b"o" | b"g" => {
                // As the scanner (and tobj) name it: the rest of the raw line after its first
                // character, trimmed.
                let name = String::from_utf8_lossy(line.get(1..).unwrap_or_default());
                let name = name.trim();
                self.objects.push(ObjectEvent {
                    corners: self.corner_v.len(),
                    vt: self.values.vt.len(),
                    vn: self.values.vn.len(),
                    faces_before: self.faces_after,
                    name: if name.is_empty() { UNNAMED.into() } else { name.into() },
                });
                self.faces_after = false;
            }
            b"usemtl" if toks.next().is_none() => return None,
            b"l" => return None,
            _ if kw[0] == b'#' => {}
            _ if is_ignored_keyword(kw) => {
                if !matches!(kw, b"s" | b"usemtl" | b"mtllib") {
                    self.ignored_statements += 1;
                }
            }
            _ => return None,
        }
        Some(())
    }

    /// `v`, `v/vt`, `v//vn` or `v/vt/vn` with positive indices, as 0-based indices.
    fn corner(&mut self, tok: &[u8]) -> Option<[u32; 3]> {
        let mut out = [NONE; 3];
        let counts = [self.values.v.len(), self.values.vt.len(), self.values.vn.len()];
        for (k, part) in tok.split(|&b| b == b'/').enumerate() {
            if k >= 3 || (part.is_empty() && k == 0) {
                return None;
            }
            if part.is_empty() {
                continue;
            }
            let x = parse_int(part)?;
            if x <= 0 || x > u32::MAX as i64 {
                return None;
            }
            out[k] = (x - 1) as u32;
            self.reach[k] = self.reach[k].max(x - 1 - counts[k] as i64);
        }
        Some(out)
    }

    /// The fan `(c0, c1, c2), (c0, c2, c3), …` of a face, as the scanner makes it.
    fn face(&mut self, line_no: u32, corners: &[[u32; 3]]) {
        let before = self.corner_v.len();
        let c0 = corners[0];
        for k in 1..corners.len() - 1 {
            for c in [c0, corners[k], corners[k + 1]] {
                self.corner_v.push(c[0]);
            }
            self.face_line.push(line_no);
        }
        for (list, slot) in [(&mut self.corner_vt, 1), (&mut self.corner_vn, 2)] {
            let any = corners.iter().any(|c| c[slot] != NONE);
            if list.is_empty() && !any {
                continue;
            }
            list.resize(before, NONE);
            for k in 1..corners.len() - 1 {
                list.extend([c0[slot], corners[k][slot], corners[k + 1][slot]]);
            }
        }
    }
}

/// Joins the chunks in file order (see the module documentation); `None` on a forward index.
fn join(parts: &[Part]) -> Option<(Scan, Values)> {
    let mut scan = Scan { parallel_ok: true, ..Default::default() };
    let mut values = Values::default();
    // Object state, as the scanner keeps it.
    let (mut name, mut start, mut has_faces) = (UNNAMED.to_string(), 0usize, false);
    let (mut line, mut corners) = (1u32, 0usize);
    let any_vt = parts.iter().any(|p| !p.corner_vt.is_empty());
    let any_vn = parts.iter().any(|p| !p.corner_vn.is_empty());
    for p in parts {
        let before = [scan.num_v, scan.num_vt, scan.num_vn];
        if (0..3).any(|k| p.reach[k] >= before[k] as i64) {
            return None;
        }
        for e in &p.objects {
            if has_faces || e.faces_before {
                scan.models.push(ScanModel {
                    name: std::mem::take(&mut name),
                    start,
                    len: corners + e.corners - start,
                    vt_at_end: before[1] + e.vt,
                    vn_at_end: before[2] + e.vn,
                });
                start = corners + e.corners;
            }
            has_faces = false;
            name.clone_from(&e.name);
        }
        has_faces |= p.faces_after;
        scan.num_v += p.values.v.len();
        scan.num_vt += p.values.vt.len();
        scan.num_vn += p.values.vn.len();
        scan.ignored_statements += p.ignored_statements;
        scan.colours |= p.colours;
        scan.face_line.extend(p.face_line.iter().map(|&l| l + line));
        line += p.lines as u32;
        corners += p.corner_v.len();
    }
    scan.models.push(ScanModel {
        name,
        start,
        len: corners - start,
        vt_at_end: scan.num_vt,
        vn_at_end: scan.num_vn,
    });
    scan.corner_v = concat(parts, |p| &p.corner_v, None);
    if any_vt {
        scan.corner_vt = concat(parts, |p| &p.corner_vt, Some(NONE));
    }
    if any_vn {
        scan.corner_vn = concat(parts, |p| &p.corner_vn, Some(NONE));
    }
    values.v = concat(parts, |p| &p.values.v, None);
    values.vt = concat(parts, |p| &p.values.vt, None);
    values.vn = concat(parts, |p| &p.values.vn, None);
    Some((scan, values))
}

/// The parts' lists one after the other, copied in parallel. With `pad`, a part whose list is
/// empty (a chunk without `vt` or `vn` corners) contributes one `pad` per triangle corner.
fn concat<T: Copy + Default + Send + Sync>(
    parts: &[Part],
    list: impl Fn(&Part) -> &Vec<T> + Sync,
    pad: Option<T>,
) -> Vec<T> {
    let padded = |p: &Part| pad.is_some() && list(p).is_empty();
    let len = |p: &Part| if padded(p) { p.corner_v.len() } else { list(p).len() };
    let mut out = vec![T::default(); parts.iter().map(len).sum()];
    let mut slices = Vec::with_capacity(parts.len());
    let mut rest = out.as_mut_slice();
    for p in parts {
        let (head, tail) = rest.split_at_mut(len(p));
        slices.push(head);
        rest = tail;
    }
    slices.into_par_iter().zip(parts).for_each(|(dst, p)| match pad {
        Some(x) if padded(p) => dst.fill(x),
        _ => dst.copy_from_slice(list(p)),
    });
    out
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::mesh::{parse, scan};

    /// The two sequential passes' result, as a comparable text (`{:?}` of an `f64` is exact).
    fn sequential(text: &str) -> Option<String> {
        let s = scan::scan(Path::new("t.obj"), text.as_bytes()).ok()?;
        let v = parse::values(text.as_bytes())?;
        Some(format!("{s:?}\n{v:?}"))
    }

    /// Every chunk size from 1 byte (a chunk per line) to the whole file agrees with the
    /// sequential passes whenever it does not give way to them.
    fn check(text: &str, expect_fast: bool) {
        let want = sequential(text);
        for chunk in [1, 2, 3, 5, 8, 13, 21, 40, 100, 1 << 20] {
            let got = scan_chunks(text.as_bytes(), chunk);
            assert_eq!(got.is_some(), expect_fast, "chunk {chunk}:\n{text}");
            if let Some((s, v)) = got {
                assert_eq!(Some(format!("{s:?}\n{v:?}")), want, "chunk {chunk}:\n{text}");
            }
        }
    }

    #[test]
    fn agrees_with_the_sequential_passes() {
        let quads = "# a quad and a triangle\nv 0 0 0\nv 1 0 0 2\nv 1 1 0\n\nv 0 1 0\r\n\
                     f 1 2 3 4\nf 1 3 4\n";
        check(quads, true);
        let attrs = "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0 0\nvt 1 1\n\
                     vn 0 0 1\no first\nusemtl m\ns 1\nf 1/1/1 2/2/1 3/3/1\ng\nf 1//1 2//1 3//1\n\
                     o  second  \nvp 1 2\n  o lead\nf 1 2 3\ng empty\ng last\nv 0 0 1\n\
                     f 1/3 2/2 4/1\n";
        check(attrs, true);
        // Objects with no faces between them are renamed, not closed; vt counted per object.
        let objects = "o a\no b\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no c\nvt 0 0\nf 3 2 1\n";
        check(objects, true);
        check("", true);
        check("v 0 0 0\n   \n\t\n\nv 1 1 1\r\nv 2 2 2", true);
        check("v 0 0 0\n", true);
        // Vertex colours (`r g b`, `r g b a`), on some vertices only, beside a `w`.
        let colours = "v 0 0 0 1 0 0\nv 1 0 0 2\nv 1 1 0 0.5 0.5 0.5 1\nv 0 1 0\nf 1 2 3 4\n";
        check(colours, true);
    }

    #[test]
    fn gives_way_on_what_it_does_not_join() {
        for text in [
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\n", // relative indices
            "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 1 1 0\n",    // a forward index
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 4\n",    // out of range
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2\n",      // a polyline
            "v 0 0 0 1 0\n",                           // 5 numbers
            "v 0 0 0 1 0 0 1 1\n",                     // 8 numbers
            "v 0 0 0 1 red 0\n",                       // a colour that is not a number
            "v 0 0 0 0\n",                             // w = 0
            "v 0 0 0 inf\n",                           // w not finite
            "v 0 0 x\n",                               // a bad number
            "v 0 0\n",                                 // a truncated line
            "vt 0 0 0 0\n",                            // too many values
            "vn 0 0 1 1\n",                            // too many components
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2\n",      // a face with 2 corners
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3/1/1/1\n", // a bad corner
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 0\n",    // index 0
            "o caf\u{e9}\n",                           // non-ASCII
            "v 0 0 0\n\u{1}\n",                        // binary
            "usemtl\n",                                // usemtl without a name
            "v 0 0 0\n%%\n",                           // not a statement
        ] {
            assert!(scan_chunks(text.as_bytes(), 4).is_none(), "{text}");
            assert!(scan_chunks(text.as_bytes(), 1 << 20).is_none(), "{text}");
        }
    }

    #[test]
    fn a_grid_in_many_chunk_sizes() {
        let n = 12;
        let mut text = String::from("o grid\n");
        for j in 0..n {
            for i in 0..n {
                text += &format!("v {} {} {:.3e}\nvt {} {}\n", i, j, 0.1 * (i * j) as f64, i, j);
            }
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i + 1;
                text += &format!(
                    "f {a}/{a} {}/{} {}/{} {}/{}\n",
                    a + 1,
                    a + 1,
                    a + n + 1,
                    a + n + 1,
                    a + n,
                    a + n
                );
            }
        }
        check(&text, true);
    }
}
