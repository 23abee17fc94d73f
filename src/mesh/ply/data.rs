//! The data section of a PLY file: every element's entries read in order, the vertices and
//! the face lists kept, and the faces checked against the vertex count at the end.

use std::path::Path;

use nalgebra::{Vector2, Vector3};

use super::{Element, Encoding, Header, Kind, MeshElements, Reader, VertexLayout};
use crate::limits::{MAX_FILE_TRIANGLES, MAX_POLYGON_CORNERS};
use crate::mesh::raw::{check_position, RawMesh};
use crate::{Error, Result};

/// One entry of an element in the data section: which, and where it starts.
struct Entry<'e> {
    el: &'e Element,
    /// The entry's index within its element.
    i: usize,
    /// Where it starts: (line, byte).
    at: (usize, usize),
    /// The list property whose items are kept (the face element's indices).
    keep: Option<usize>,
}

/// The values of one entry: a value per property (a list's count for a list), and the items of
/// the kept list.
#[derive(Default)]
struct EntryValues {
    values: Vec<f64>,
    list: Vec<f64>,
}

/// Reads the values of one entry into `out`.
fn read_entry(rd: &mut Reader, entry: &Entry, out: &mut EntryValues) -> Result<()> {
    let (el, i, at) = (entry.el, entry.i, entry.at);
    out.values.clear();
    out.list.clear();
    for (j, p) in el.properties.iter().enumerate() {
        let name = || format!("{} element {i}: property {:?}", el.name, p.name);
        match p.kind {
            Kind::Scalar(t) => out.values.push(rd.value(t, &name)?),
            Kind::List(c, t) => {
                let n = rd.value(c, &|| format!("{}: list count", name()))?;
                if n < 0.0 || n > MAX_POLYGON_CORNERS as f64 {
                    return Err(rd.error(
                        at,
                        format!(
                            "{}: list count {n} is not in [0, {MAX_POLYGON_CORNERS}] \
                             (limits::MAX_POLYGON_CORNERS)",
                            name()
                        ),
                    ));
                }
                let keep = entry.keep == Some(j);
                for k in 0..n as usize {
                    let x = rd.value(t, &|| format!("{}: item {k}", name()))?;
                    if keep {
                        out.list.push(x);
                    }
                }
                out.values.push(n);
            }
        }
    }
    Ok(())
}

/// What the data section gives: the vertices, and the face lists, kept until every vertex is
/// read (faces may come first).
pub(super) struct Collected {
    layout: VertexLayout,
    /// The loader's scale (for the coordinate bound).
    scale: f64,
    raw: RawMesh,
    uv: Option<Vec<Vector2<f64>>>,
    normals: Option<Vec<Vector3<f64>>>,
    /// The indices of all faces in one array.
    face_idx: Vec<u32>,
    /// Per face: (element, line, byte, start in `face_idx`).
    face_meta: Vec<(u32, usize, usize, usize)>,
}

impl Collected {
    fn new(layout: VertexLayout, scale: f64, vertices: usize, faces: usize) -> Self {
        let raw = RawMesh::with_capacity(vertices, faces);
        let uv = layout.uv.map(|_| Vec::with_capacity(vertices));
        let normals = layout.normal.map(|_| Vec::with_capacity(vertices));
        let face_meta = Vec::with_capacity(faces);
        Collected { layout, scale, raw, uv, normals, face_idx: Vec::new(), face_meta }
    }

    /// Keeps a vertex entry's position, UV and normal, checked.
    fn push_vertex(&mut self, rd: &Reader, entry: &Entry, values: &[f64]) -> Result<()> {
        let (i, at, layout, scale) = (entry.i, entry.at, &self.layout, self.scale);
        let p = Vector3::new(values[layout.xyz[0]], values[layout.xyz[1]], values[layout.xyz[2]]);
        check_position(&p, scale)
            .map_err(|err| rd.error(at, format!("vertex element {i} {}", err.describe(scale))))?;
        self.raw.positions.push(p);
        if let (Some(uv), Some([a, b])) = (self.uv.as_mut(), layout.uv) {
            let t = Vector2::new(values[a], values[b]);
            if !t.iter().all(|x| x.is_finite()) {
                return Err(rd.error(
                    at,
                    format!(
                        "vertex element {i} has a non-finite (NaN or infinite) texture coordinate"
                    ),
                ));
            }
            uv.push(t);
        }
        if let (Some(ns), Some([a, b, c])) = (self.normals.as_mut(), layout.normal) {
            let n = Vector3::new(values[a], values[b], values[c]);
            if !n.iter().all(|x| x.is_finite()) {
                return Err(rd.error(
                    at,
                    format!("vertex element {i} has a non-finite (NaN or infinite) normal"),
                ));
            }
            ns.push(n);
        }
        Ok(())
    }

    /// Keeps a face entry's vertex indices (checked against the vertex count at the end).
    fn push_face(&mut self, rd: &Reader, entry: &Entry, list_values: &[f64]) -> Result<()> {
        let (i, at) = (entry.i, entry.at);
        let (face_idx, face_meta) = (&mut self.face_idx, &mut self.face_meta);
        if list_values.len() < 3 {
            return Err(rd.error(
                at,
                format!(
                    "face element {i} has {} vertex indices; a face needs at least 3",
                    list_values.len()
                ),
            ));
        }
        if face_idx.len() - 2 * face_meta.len() + list_values.len() > MAX_FILE_TRIANGLES + 2 {
            return Err(rd.error(
                at,
                format!(
                    "face element {i}: more than {MAX_FILE_TRIANGLES} triangles \
                     (limits::MAX_FILE_TRIANGLES)"
                ),
            ));
        }
        face_meta.push((i as u32, at.0, at.1, face_idx.len()));
        face_idx.extend(list_values.iter().map(|&x| {
            if (0.0..u32::MAX as f64).contains(&x) {
                x as u32
            } else {
                u32::MAX
            }
        }));
        Ok(())
    }

    /// Checks the faces' indices against the vertex count and splits the faces into the
    /// fans of the mesh.
    pub(super) fn into_mesh(self, path: &Path, encoding: Encoding) -> Result<RawMesh> {
        let Collected { mut raw, uv, normals, face_idx, face_meta, .. } = self;
        let nv = raw.positions.len() as u32;
        for (m, &(i, line, offset, start)) in face_meta.iter().enumerate() {
            let end = face_meta.get(m + 1).map_or(face_idx.len(), |x| x.3);
            let idx = &face_idx[start..end];
            if let Some((k, &bad)) = idx.iter().enumerate().find(|(_, &v)| v >= nv) {
                let shown = if bad == u32::MAX {
                    "negative or too large".to_string()
                } else {
                    bad.to_string()
                };
                let message = format!(
                    "face element {i}: vertex index {k} is {shown}; the file has {nv} vertices \
                     (indices 0 to {})",
                    nv.saturating_sub(1)
                );
                return Err(match encoding {
                    Encoding::Ascii => {
                        Error::IndexOutOfRange { path: path.to_owned(), line, message }
                    }
                    _ => {
                        Error::BinaryFile { path: path.to_owned(), offset: offset as u64, message }
                    }
                });
            }
            if idx.len() > 3 {
                raw.polygons_split += 1;
            }
            let line = if encoding == Encoding::Ascii { line as u32 } else { 0 };
            for k in 1..idx.len() - 1 {
                raw.push_face([idx[0], idx[k], idx[k + 1]], line, i);
            }
        }
        raw.uv = uv;
        raw.normals = normals;
        Ok(raw)
    }
}

/// Reads every element's entries, keeping the vertices and the face lists.
pub(super) fn read_data(
    rd: &mut Reader,
    header: &Header,
    mesh: MeshElements,
    scale: f64,
) -> Result<Collected> {
    let (velem, felem) = (&header.elements[mesh.vertex], &header.elements[mesh.face]);
    let mut out = Collected::new(mesh.layout, scale, velem.count, felem.count);
    let mut values = EntryValues::default();
    for (e, el) in header.elements.iter().enumerate() {
        let keep = (e == mesh.face).then_some(mesh.list);
        for i in 0..el.count {
            let at = rd.here();
            let entry = Entry { el, i, at, keep };
            if rd.encoding == Encoding::Ascii {
                rd.entry_line = at.0;
            }
            read_entry(rd, &entry, &mut values)?;
            check_line_end(rd, &entry)?;
            if e == mesh.vertex {
                out.push_vertex(rd, &entry, &values.values)?;
            } else if e == mesh.face {
                out.push_face(rd, &entry, &values.list)?;
            }
        }
    }
    Ok(out)
}

/// ASCII: refuses values left on an entry's line after its last property.
fn check_line_end(rd: &mut Reader, entry: &Entry) -> Result<()> {
    if rd.encoding != Encoding::Ascii {
        return Ok(());
    }
    while rd.pos < rd.bytes.len() && matches!(rd.bytes[rd.pos], b' ' | b'\t' | 0x0b | 0x0c) {
        rd.pos += 1;
    }
    match rd.bytes.get(rd.pos) {
        None | Some(b'\n') | Some(b'\r') => Ok(()),
        Some(_) => Err(rd.error(
            entry.at,
            format!(
                "{} element {} has more values on its line than its {} properties (and list \
                 counts) call for",
                entry.el.name,
                entry.i,
                entry.el.properties.len()
            ),
        )),
    }
}

/// Refuses data after the last element (ASCII: other than blanks).
pub(super) fn check_no_trailing_data(rd: &mut Reader) -> Result<()> {
    if rd.encoding == Encoding::Ascii {
        rd.skip_blanks();
    }
    if rd.pos < rd.bytes.len() {
        let at = rd.here();
        return Err(rd.error(
            at,
            format!(
                "{} byte(s) of data after the last element: the header's counts do not match the \
                 data",
                rd.bytes.len() - rd.pos
            ),
        ));
    }
    Ok(())
}
