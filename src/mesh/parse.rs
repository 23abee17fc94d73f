//! A parallel reader of the numbers of an OBJ file (`v`, `vt`, `vn`), for large files.
//!
//! The file is cut into chunks at line ends; every chunk is read on its own thread and the
//! chunks' values are joined in file order, so the result does not depend on the thread count.
//! Numbers are parsed exactly as tobj parses them (`f64::from_str` on the whitespace-separated
//! tokens, `v x y z w` divided by `w`, only the first two numbers of a `vt`), so on the files it
//! accepts it gives tobj's values bit for bit. It gives up (returns `None`) on anything tobj
//! would refuse (a bad number, `w = 0`) and on a `w` that is not finite, which the scanner
//! refuses; the loader then runs tobj, whose error it reports.
//! It also reads what tobj cannot, vertex colours (`v x y z r g b [a]`, the colour not used).
//! Statement syntax, indices and line numbers are the scanner's job (`scan.rs`).

use rayon::prelude::*;

/// Bytes per chunk (cut at the next line end).
const CHUNK: usize = 1 << 20;

/// The `v`, `vt` and `vn` values of a file, in file order.
#[derive(Debug, Default)]
pub(crate) struct Values {
    pub v: Vec<[f64; 3]>,
    pub vt: Vec<[f64; 2]>,
    pub vn: Vec<[f64; 3]>,
}

/// Chunk boundaries of `bytes`: 0, then the end of the line that holds byte `at + chunk` for
/// each chunk start `at` (so every chunk ends at a line end, the last at the end of the text).
pub(crate) fn line_chunks(bytes: &[u8], chunk: usize) -> Vec<usize> {
    let mut bounds = vec![0];
    let mut at = 0;
    while at < bytes.len() {
        let end = (at + chunk.max(1)).min(bytes.len());
        let end = match bytes[end..].iter().position(|&b| b == b'\n') {
            Some(k) => end + k + 1,
            None => bytes.len(),
        };
        bounds.push(end);
        at = end;
    }
    bounds
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | 0x0b | 0x0c)
}

/// Reads every `v`, `vt` and `vn` statement; `None` if a number does not parse or `w` is 0.
pub(crate) fn values(bytes: &[u8]) -> Option<Values> {
    let bounds = line_chunks(bytes, CHUNK);
    let parts: Vec<Option<Values>> =
        bounds.par_windows(2).map(|w| chunk_values(&bytes[w[0]..w[1]])).collect();
    let mut out = Values::default();
    let total = |f: fn(&Values) -> usize| parts.iter().flatten().map(f).sum::<usize>();
    out.v.reserve_exact(total(|p| p.v.len()));
    out.vt.reserve_exact(total(|p| p.vt.len()));
    out.vn.reserve_exact(total(|p| p.vn.len()));
    for p in parts {
        let p = p?;
        out.v.extend_from_slice(&p.v);
        out.vt.extend_from_slice(&p.vt);
        out.vn.extend_from_slice(&p.vn);
    }
    Some(out)
}

pub(crate) fn number(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// The first `N` numbers of a statement's arguments.
fn numbers<'a, const N: usize>(toks: &mut impl Iterator<Item = &'a [u8]>) -> Option<[f64; N]> {
    let mut out = [0.0; N];
    for x in &mut out {
        *x = number(toks.next()?)?;
    }
    Some(out)
}

/// The position of a `v` statement from the numbers after `v`: `x y z`; `x y z w`, the
/// position (x, y, z)/w (tobj's division), `None` unless `w` is finite and non-zero; or
/// `x y z r g b [a]`, a vertex colour, `None` unless its values are numbers (they are not used).
/// Any other count is `None` (the scanner refuses it, naming the line).
pub(crate) fn position<'a>(toks: &mut impl Iterator<Item = &'a [u8]>) -> Option<[f64; 3]> {
    let mut p = numbers::<3>(toks)?;
    let Some(first) = toks.next() else { return Some(p) };
    let first = number(first)?;
    let mut colour = 1;
    for t in toks {
        number(t)?;
        colour += 1;
    }
    match colour {
        1 if first != 0.0 && first.is_finite() => {
            for c in &mut p {
                *c /= first;
            }
            Some(p)
        }
        3 | 4 => Some(p),
        _ => None,
    }
}

fn chunk_values(chunk: &[u8]) -> Option<Values> {
    let mut out = Values::default();
    for line in chunk.split(|&b| b == b'\n') {
        let start = line.iter().position(|&b| !is_space(b)).unwrap_or(line.len());
        let line = &line[start..];
        if line.first() != Some(&b'v') {
            continue;
        }
        let mut toks = line.split(|&b| is_space(b)).filter(|t| !t.is_empty());
        match toks.next() {
            Some(b"v") => out.v.push(position(&mut toks)?),
            Some(b"vt") => out.vt.push(numbers::<2>(&mut toks)?),
            Some(b"vn") => out.vn.push(numbers::<3>(&mut toks)?),
            _ => {}
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forms_and_failures() {
        let v =
            values(b"# c\nv 1 2 3\r\n\tv  1e2 -0.5 +.25 2\nvt 0.5 1 9\nvn 0 0 1\nvx 1\n").unwrap();
        assert_eq!(v.v, vec![[1.0, 2.0, 3.0], [50.0, -0.25, 0.125]]);
        assert_eq!(v.vt, vec![[0.5, 1.0]]);
        assert_eq!(v.vn, vec![[0.0, 0.0, 1.0]]);
        assert!(values(b"v 1 2 x\n").is_none());
        assert!(values(b"v 1 2 3 0\n").is_none());
        assert!(values(b"v 1 2 3 inf\n").is_none());
        // Colours are read past, never as a weight; 5 or 8 numbers, or a bad colour, fail.
        let v = values(b"v 1 2 3 0 0.5 1\nv 4 5 6 0 0 0 1\nv 2 4 6 2\n").unwrap();
        assert_eq!(v.v, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [1.0, 2.0, 3.0]]);
        for bad in ["v 1 2 3 1 1\n", "v 1 2 3 1 1 1 1 1\n", "v 1 2 3 1 x 1\n"] {
            assert!(values(bad.as_bytes()).is_none(), "{bad}");
        }
    }
}
