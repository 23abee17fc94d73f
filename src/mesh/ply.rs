//! Reading PLY files (ASCII, binary little- and big-endian) into a [`RawMesh`].
//!
//! # What is read
//!
//! * The `vertex` element: `x y z` (required, any numeric type), `nx ny nz` (optional: the
//!   file's normals), and the first complete pair of `u v`, `s t`, `texture_u texture_v`,
//!   `texture_s texture_t` (optional: the UVs).
//! * The `face` element: its list property `vertex_indices` (or `vertex_index`), 0-based;
//!   polygons are split into the fan `(c0, c1, c2), (c0, c2, c3), …`.
//! * Every other element and property is read past (their values must still be well-formed).
//!
//! # Checks
//!
//! The header is checked line by line. Before anything is allocated for an element its count
//! is bounded by [`MAX_FILE_VERTICES`] / [`MAX_FILE_TRIANGLES`] and by the bytes left in the
//! file (a binary element of fixed size must fit exactly; every element needs at least one
//! byte per value), so an absurd count is an error, never an allocation. Values are checked as
//! they are read: an integer type's range, finite coordinates within
//! [`MAX_COORDINATE`](crate::limits::MAX_COORDINATE), face indices within the vertex count,
//! list counts of at least 3. Every error names the element (0-based, as the face lists number
//! vertices) and the line (ASCII) or the byte offset (binary).

use std::path::Path;

use super::raw::RawMesh;
use crate::limits::{MAX_FILE_TRIANGLES, MAX_FILE_VERTICES};
use crate::{Error, Result};

mod data;

use data::{check_no_trailing_data, read_data};

/// The data layout after `end_header`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// A scalar type of the PLY header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The range of an integer type.
    fn range(self) -> (f64, f64) {
        match self {
            Scalar::I8 => (-128.0, 127.0),
            Scalar::U8 => (0.0, 255.0),
            Scalar::I16 => (-32768.0, 32767.0),
            Scalar::U16 => (0.0, 65535.0),
            Scalar::I32 => (-2147483648.0, 2147483647.0),
            Scalar::U32 => (0.0, 4294967295.0),
            _ => (f64::NEG_INFINITY, f64::INFINITY),
        }
    }
}

/// A property: a scalar, or a list (count type, item type).
#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List(Scalar, Scalar),
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    line: usize,
    properties: Vec<Property>,
}

impl Element {
    /// The byte size of one element when it has no list property.
    fn fixed_size(&self) -> Option<usize> {
        self.properties
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => Some(s.size()),
                Kind::List(..) => None,
            })
            .sum()
    }

    /// The fewest bytes one element can take (binary: a list with 0 items; ASCII: one digit and
    /// one separator per value).
    fn min_size(&self, enc: Encoding) -> usize {
        self.properties
            .iter()
            .map(|p| match (enc, p.kind) {
                (Encoding::Ascii, _) => 2,
                (_, Kind::Scalar(s)) => s.size(),
                (_, Kind::List(c, _)) => c.size(),
            })
            .sum::<usize>()
            .max(1)
    }

    fn find(&self, names: &[&str]) -> Option<usize> {
        self.properties.iter().position(|p| names.contains(&p.name.as_str()))
    }
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the data.
    data: usize,
    /// Line of the first data line (ASCII).
    data_line: usize,
}

fn parse_err(path: &Path, line: usize, message: String) -> Error {
    Error::Parse { path: path.to_owned(), line, message }
}

fn read_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(parse_err(
                path,
                line_no + 1,
                "unexpected end of file in the PLY header (no `end_header`)".into(),
            ));
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        line_no += 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(parse_err(path, line_no, "invalid UTF-8 in the PLY header".into()));
        };
        let words: Vec<&str> = text.split_ascii_whitespace().collect();
        let err = |m: String| parse_err(path, line_no, m);
        if line_no == 1 {
            // A UTF-8 byte-order mark before the magic is skipped.
            if text.trim_start_matches('\u{feff}').trim_end() != "ply" {
                return Err(err("not a PLY file: the first line is not `ply`".into()));
            }
            continue;
        }
        match words.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                if words.len() != 3 || words[2] != "1.0" {
                    return Err(err(format!("expected `format <encoding> 1.0`, found {text:?}")));
                }
                encoding = Some(match words[1] {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Little,
                    "binary_big_endian" => Encoding::Big,
                    w => {
                        return Err(err(format!(
                            "unknown PLY format {w:?}; expected ascii, binary_little_endian or \
                             binary_big_endian"
                        )))
                    }
                });
            }
            Some("element") => {
                if words.len() != 3 {
                    return Err(err(format!("expected `element <name> <count>`, found {text:?}")));
                }
                let count: usize = words[2].parse().map_err(|_| {
                    err(format!("element {:?}: count {:?} is not a number ≥ 0", words[1], words[2]))
                })?;
                elements.push(Element {
                    name: words[1].to_string(),
                    count,
                    line: line_no,
                    properties: Vec::new(),
                });
            }
            Some("property") => {
                let Some(el) = elements.last_mut() else {
                    return Err(err("`property` before any `element`".into()));
                };
                let scalar = |w: &str| {
                    Scalar::parse(w).ok_or_else(|| err(format!("unknown property type {w:?}")))
                };
                let kind = match words.as_slice() {
                    ["property", "list", c, t, _] => {
                        let c = scalar(c)?;
                        if !c.is_integer() {
                            return Err(err(format!("list count type {c:?} is not an integer")));
                        }
                        Kind::List(c, scalar(t)?)
                    }
                    ["property", t, _] => Kind::Scalar(scalar(t)?),
                    _ => {
                        return Err(err(format!(
                            "expected `property <type> <name>` or `property list <count type> \
                             <type> <name>`, found {text:?}"
                        )))
                    }
                };
                let name = words.last().expect("matched").to_string();
                el.properties.push(Property { name, kind });
            }
            Some("end_header") => break,
            Some(w) => return Err(err(format!("unknown PLY header keyword {w:?}"))),
        }
    }
    let Some(encoding) = encoding else {
        return Err(parse_err(path, line_no, "the PLY header has no `format` line".into()));
    };
    Ok(Header { encoding, elements, data: pos, data_line: line_no + 1 })
}

/// Reads values from the data section, ASCII or binary, tracking where each element starts.
struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    encoding: Encoding,
    /// ASCII: the line of the entry being read (its values must all be on it); 0 for none.
    entry_line: usize,
}

impl Reader<'_> {
    /// Where the reader is, as a message prefix: the line (ASCII) or byte (binary).
    fn error(&self, at: (usize, usize), message: String) -> Error {
        match self.encoding {
            Encoding::Ascii => Error::Parse { path: self.path.to_owned(), line: at.0, message },
            _ => Error::BinaryFile { path: self.path.to_owned(), offset: at.1 as u64, message },
        }
    }

    /// The current place: (line, byte). In ASCII, the line of the next token.
    fn here(&mut self) -> (usize, usize) {
        if self.encoding == Encoding::Ascii {
            self.skip_blanks();
        }
        (self.line, self.pos)
    }

    fn skip_blanks(&mut self) {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            if self.bytes[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// One value of type `t`, as f64 (integers are exact in f64). `what` names it for messages.
    fn value(&mut self, t: Scalar, what: &dyn Fn() -> String) -> Result<f64> {
        match self.encoding {
            Encoding::Ascii => {
                self.skip_blanks();
                if self.entry_line != 0 && self.line != self.entry_line {
                    return Err(self.error(
                        (self.entry_line, self.pos),
                        format!(
                            "{} is missing: the line ends before it (an ASCII PLY entry holds \
                             all its values on one line)",
                            what()
                        ),
                    ));
                }
                let at = (self.line, self.pos);
                let start = self.pos;
                while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
                    self.pos += 1;
                }
                if start == self.pos {
                    return Err(self.error(
                        at,
                        format!("unexpected end of file: {} is missing (truncated file?)", what()),
                    ));
                }
                let tok = &self.bytes[start..self.pos];
                let s = std::str::from_utf8(tok).unwrap_or("");
                let x = if t.is_integer() {
                    s.parse::<i64>().ok().map(|i| i as f64)
                } else {
                    s.parse::<f64>().ok()
                };
                let shown: String = String::from_utf8_lossy(tok).chars().take(40).collect();
                let Some(x) = x else {
                    let ty = if t.is_integer() { "an integer" } else { "a number" };
                    return Err(
                        self.error(at, format!("{}: expected {ty}, found {shown:?}", what()))
                    );
                };
                let (lo, hi) = t.range();
                if x < lo || x > hi {
                    return Err(
                        self.error(at, format!("{}: {shown} is out of range for {t:?}", what()))
                    );
                }
                Ok(x)
            }
            enc => {
                let n = t.size();
                if self.pos + n > self.bytes.len() {
                    return Err(self.error(
                        (0, self.pos),
                        format!(
                            "unexpected end of file: {} is missing (truncated file: {} bytes)",
                            what(),
                            self.bytes.len()
                        ),
                    ));
                }
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(&self.bytes[self.pos..self.pos + n]);
                if enc == Encoding::Big {
                    b[..n].reverse();
                }
                self.pos += n;
                Ok(match t {
                    Scalar::I8 => f64::from(b[0] as i8),
                    Scalar::U8 => f64::from(b[0]),
                    Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
                    Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
                    Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                    Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                    Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                    Scalar::F64 => f64::from_le_bytes(b),
                })
            }
        }
    }
}

/// Which vertex properties carry what.
struct VertexLayout {
    xyz: [usize; 3],
    normal: Option<[usize; 3]>,
    uv: Option<[usize; 2]>,
}

fn vertex_layout(path: &Path, el: &Element) -> Result<VertexLayout> {
    let scalar = |names: &[&str]| -> Result<Option<usize>> {
        match el.find(names) {
            Some(i) => match el.properties[i].kind {
                Kind::Scalar(_) => Ok(Some(i)),
                Kind::List(..) => Err(parse_err(
                    path,
                    el.line,
                    format!("vertex property {:?} is a list; expected a number", names[0]),
                )),
            },
            None => Ok(None),
        }
    };
    let mut xyz = [0; 3];
    for (k, n) in ["x", "y", "z"].iter().enumerate() {
        xyz[k] = scalar(&[n])?.ok_or_else(|| {
            parse_err(path, el.line, format!("the vertex element has no property {n:?}"))
        })?;
    }
    let normal = match (scalar(&["nx"])?, scalar(&["ny"])?, scalar(&["nz"])?) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    let mut uv = None;
    for (u, v) in [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")] {
        if let (Some(a), Some(b)) = (scalar(&[u])?, scalar(&[v])?) {
            uv = Some([a, b]);
            break;
        }
    }
    Ok(VertexLayout { xyz, normal, uv })
}

/// The two elements a mesh is read from, and where their data sits in each entry.
struct MeshElements {
    /// Index of the `vertex` element.
    vertex: usize,
    /// Index of the `face` element.
    face: usize,
    /// The face element's property holding the vertex indices.
    list: usize,
    layout: VertexLayout,
}

/// Finds the `vertex` and `face` elements and checks their properties.
fn mesh_elements(path: &Path, header: &Header) -> Result<MeshElements> {
    let vertex = header.elements.iter().position(|e| e.name == "vertex");
    let face = header.elements.iter().position(|e| e.name == "face");
    let (Some(vi), Some(fi)) = (vertex, face) else {
        let missing = if vertex.is_none() { "vertex" } else { "face" };
        return Err(Error::EmptyMesh {
            path: path.to_owned(),
            message: format!(
                "the PLY header declares no `{missing}` element (grainline reads triangle meshes, \
                 not point clouds)"
            ),
        });
    };
    let velem = &header.elements[vi];
    let felem = &header.elements[fi];
    let layout = vertex_layout(path, velem)?;
    let Some(list) = felem.find(&["vertex_indices", "vertex_index"]) else {
        return Err(parse_err(
            path,
            felem.line,
            "the face element has no list property `vertex_indices`".into(),
        ));
    };
    let Kind::List(_, index_type) = felem.properties[list].kind else {
        return Err(parse_err(
            path,
            felem.line,
            "face property `vertex_indices` is not a list".into(),
        ));
    };
    if !index_type.is_integer() {
        return Err(parse_err(
            path,
            felem.line,
            format!(
                "face property `vertex_indices` holds {index_type:?}; expected an integer type"
            ),
        ));
    }
    Ok(MeshElements { vertex: vi, face: fi, list, layout })
}

/// Bounds the vertex and face counts by the limits, before anything is allocated for them.
fn check_limits(path: &Path, velem: &Element, felem: &Element) -> Result<()> {
    if velem.count > MAX_FILE_VERTICES {
        return Err(parse_err(
            path,
            velem.line,
            format!(
                "{} vertices: more than the {MAX_FILE_VERTICES} a mesh may have \
                 (limits::MAX_FILE_VERTICES)",
                velem.count
            ),
        ));
    }
    if felem.count > MAX_FILE_TRIANGLES {
        return Err(parse_err(
            path,
            felem.line,
            format!(
                "{} faces: more than the {MAX_FILE_TRIANGLES} triangles a mesh may have \
                 (limits::MAX_FILE_TRIANGLES)",
                felem.count
            ),
        ));
    }
    Ok(())
}

/// Every element's count against the bytes left: the fewest bytes all elements can take.
fn check_data_size(path: &Path, bytes: &[u8], header: &Header) -> Result<()> {
    let left = bytes.len() - header.data;
    let mut need: u128 = 0;
    for el in &header.elements {
        need += el.count as u128 * el.min_size(header.encoding) as u128;
        let exact = header.encoding != Encoding::Ascii && el.fixed_size().is_some();
        let what = if exact { "" } else { "at least " };
        if need > left as u128 + 1 {
            return Err(parse_err(
                path,
                el.line,
                format!(
                    "element {:?} with {} entries needs {what}{need} bytes of data with the \
                     elements before it, but the file has {left} after its header (truncated \
                     file, or a wrong count)",
                    el.name, el.count
                ),
            ));
        }
    }
    Ok(())
}

/// Reads a PLY file's bytes. `scale` is the loader's scale (for the coordinate bound).
pub(crate) fn read(path: &Path, bytes: &[u8], scale: f64) -> Result<RawMesh> {
    let header = read_header(path, bytes)?;
    let mesh = mesh_elements(path, &header)?;
    check_limits(path, &header.elements[mesh.vertex], &header.elements[mesh.face])?;
    check_data_size(path, bytes, &header)?;
    let mut rd = Reader {
        path,
        bytes,
        pos: header.data,
        line: header.data_line,
        encoding: header.encoding,
        entry_line: 0,
    };
    let collected = read_data(&mut rd, &header, mesh, scale)?;
    check_no_trailing_data(&mut rd)?;
    collected.into_mesh(path, rd.encoding)
}
