//! Loading OBJ files (tobj, or a parallel reader for large files) into a validated [`Mesh`];
//! [`load_mesh`] also reads STL and PLY (`stl.rs`, `ply.rs`), which then go through the same
//! steps (`raw.rs`) and give the same [`LoadReport`].
//!
//! # What the loaded mesh is
//!
//! * **Vertices** are the file's `v` entries **in file order**, minus the ones no (kept) face
//!   uses, minus the ones welded into an earlier one. [`LoadReport::source_vertex`] maps every
//!   mesh vertex back to its 1-based `v` number, and
//!   `file_vertices = vertices + unreferenced_vertices + welded_vertices`.
//! * **Faces** are the file's `f` statements in file order, polygons split into the fan
//!   `(c0, c1, c2), (c0, c2, c3), …` (as tobj does), minus dropped zero-area faces.
//!   [`LoadReport::face_line`] gives the line of every face.
//! * **UVs and normals** (`vt`, `vn`) are per-corner attributes ([`CornerAttribute`]). They are
//!   kept only when every corner of every kept face has one. UV values are deduplicated by
//!   exact value, so two corners share a UV index exactly when their UVs are equal.
//! * **Welding** (`weld = Some(tol)`, file units) merges vertices whose distance is at most
//!   `tol`, transitively; the cluster keeps the position and the place of its first vertex in
//!   the file (see [`super::weld`]). Only vertices used by the kept object take part.
//! * **Degenerate faces**: a face with a repeated vertex (after welding), collinear corners, or
//!   |(b − a) × (c − a)| ≤ 1e-12·ℓ², ℓ its longest edge (a sliver, collinear up to rounding;
//!   slivers of aspect up to ~1e11 are kept), computed on the edges scaled by their largest
//!   component (`degenerate.rs`). Dropped and counted, or an error, by [`DegeneratePolicy`].
//! * **Units**: positions are multiplied by `scale` and are then in `units`.
//!
//! Numbers are read as `f64` (tobj's `use_f64`).
//!
//! # How
//!
//! Two passes run side by side on the bytes of the file: tobj (numbers, objects), and a
//! scanner (`scan.rs`) that checks every statement with its line number and records the
//! file index of every face corner (tobj renumbers positions per object by first use). The
//! corners of the two agree one to one, which is checked.
//!
//! Files of [`PARALLEL_MIN_BYTES`] or more that stay within what it reproduces exactly (ASCII,
//! no forward face indices, no `l` statements) have their numbers read by a
//! parallel parser (`parse.rs`) instead of tobj, and their objects formed by the scanner the way
//! tobj forms them ([`ObjParser`]); the mesh, the report and every error are the same
//! (tests/mesh_parser_equivalence.rs). When the parallel parser meets a number it cannot read,
//! tobj reads the file and reports it. Most such files need only one pass: a parallel scan that
//! parses the numbers as it goes (`scan_parallel.rs`); it gives the two passes' result or gives
//! way to them.
//!
//! A `v` statement holds 3 numbers (x y z), 4 (x y z w: the position is (x, y, z)/w, w finite
//! and non-zero) or 6 to 7 (`x y z r g b [a]`: a vertex colour, as scan exports write it, read
//! and not used); any other count is refused naming the line. tobj cannot read colours (it
//! refuses `r g b a`, and a file where only some vertices have one), so a file with colours
//! has its numbers read by the parallel parser whichever [`ObjParser`] is chosen.

use std::path::Path;

use nalgebra::{Vector2, Vector3};
use rayon::prelude::*;

use super::degenerate::{self, Counts, Degeneracy};
use super::halfedge::HalfEdges;
use super::parse::{self, Values};
use super::raw::{compact_vertices, dedup_by_value, zero_area_message};
use super::scan::{self, Kind, Scan, NONE};
use super::scan_parallel;
use super::validate::{self, FileNames, Naming};
use super::{weld, CornerAttribute, Mesh};
use crate::{Error, Result};

pub use super::loaded::{DegeneratePolicy, LoadOptions, LoadReport, LoadedMesh, MeshFormat};

impl MeshFormat {
    /// The format of a file: by its content where that is unambiguous (a PLY's `ply` magic
    /// line; a binary STL whose size is exactly 84 + 50·n for the n at byte 80 and whose
    /// name ends in `.stl` or whose bytes are not text), else by its extension (`.obj`,
    /// `.stl`, `.ply`, case-insensitive). A file with any other extension (or none) is read by
    /// what it holds: an ASCII STL (`solid …`), or an OBJ (a `v`, `vt`, `vn`, `f`, `o`, `g`,
    /// … statement before any other text); anything else is refused naming the file and the
    /// extensions grainline reads. A UTF-8 byte-order mark is skipped.
    pub fn detect(path: &Path, bytes: &[u8]) -> Result<MeshFormat> {
        let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
        let text = bytes.strip_prefix(super::stl::BOM).unwrap_or(bytes);
        if text.starts_with(b"ply\n") || text.starts_with(b"ply\r\n") {
            return Ok(MeshFormat::Ply);
        }
        let binary_stl = super::stl::binary_count(bytes).is_some() && bytes.contains(&0);
        Ok(match ext.as_deref() {
            Some("stl") => MeshFormat::Stl,
            Some("ply") => MeshFormat::Ply,
            Some("obj") => MeshFormat::Obj,
            _ if binary_stl || super::stl::starts_with_solid(text) => MeshFormat::Stl,
            _ if scan::looks_like_obj(text) => MeshFormat::Obj,
            _ => return Err(unknown_format(path, ext.as_deref())),
        })
    }
}

/// Loads and validates a mesh file of any format grainline reads (OBJ, STL, PLY; chosen by
/// [`MeshFormat::detect`]). The mesh and report are what [`load_obj`] gives for an OBJ; for the
/// others see `stl.rs` and `ply.rs`: an STL's three vertices per triangle are welded exactly
/// (bit-identical positions) unless `options.weld` gives a tolerance, and PLY `u v` (`s t`,
/// `texture_u texture_v`) and `nx ny nz` vertex properties become the per-corner UVs and
/// normals. `options.object` applies to OBJ only (naming an object of another format is an
/// error).
pub fn load_mesh(path: &Path, options: &LoadOptions) -> Result<LoadedMesh> {
    check_options(options)?;
    // A FIFO or a device is refused before it is opened (opening a FIFO would block).
    crate::output::check_input_file(path)?;
    // A file named `.obj` is an OBJ unless it starts as a PLY: its first bytes decide, and the
    // OBJ reader reads it once (a 1 GB file of zeros was read whole twice to be refused).
    let obj_name = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if obj_name && MeshFormat::detect(path, &read_head(path, 16)?)? == MeshFormat::Obj {
        return load_obj(path, options);
    }
    let bytes = std::fs::read(path).map_err(|e| Error::Io { path: path.to_owned(), source: e })?;
    let format = MeshFormat::detect(path, &bytes)?;
    if format == MeshFormat::Obj {
        drop(bytes);
        return load_obj(path, options);
    }
    if let Some(name) = &options.object {
        return Err(Error::ObjectNotFound {
            path: path.to_owned(),
            name: name.clone(),
            available: format!("(none: objects are an OBJ notion, this is {})", format.as_str()),
        });
    }
    match format {
        MeshFormat::Stl => {
            let raw = super::stl::read(path, &bytes, options.scale)?;
            drop(bytes);
            super::raw::build(path, raw, options, format, Naming::Stl, Some(0.0))
        }
        _ => {
            let raw = super::ply::read(path, &bytes, options.scale)?;
            drop(bytes);
            super::raw::build(path, raw, options, format, Naming::Ply, None)
        }
    }
}

/// The error of a file whose extension and content name no mesh format grainline reads.
fn unknown_format(path: &Path, ext: Option<&str>) -> Error {
    let named = match ext {
        Some(e) => format!("its extension `.{e}` is not one grainline reads"),
        None => "it has no extension".to_string(),
    };
    Error::InvalidMesh {
        path: path.to_owned(),
        message: format!(
            "not a mesh file grainline can read: {named} (.obj, .stl, .ply), and its content is \
             none of an OBJ (`v`/`f` statements), an ASCII STL (`solid`), a binary STL (84 + 50·n \
             bytes) or a PLY (`ply` first line)"
        ),
    }
}

/// One object and the range of corners it covers in the file's corner list, with tobj's
/// values for it (`None`: the values come from the parallel parser, by file index).
struct Model {
    name: String,
    mesh: Option<tobj::Mesh>,
    start: usize,
    len: usize,
}

/// Which reader parses the numbers of an OBJ file (the scanner always checks its syntax).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ObjParser {
    /// The parallel parser for files of [`PARALLEL_MIN_BYTES`] or more, tobj below (the default).
    #[default]
    Auto,
    /// tobj, the reference reader.
    Tobj,
    /// The parallel parser whenever the file allows it (tobj otherwise).
    Parallel,
}

pub use crate::limits::MAX_COORDINATE;

/// Files of at least this many bytes are read by the parallel parser under [`ObjParser::Auto`].
pub const PARALLEL_MIN_BYTES: usize = 4 << 20;

/// Loads and validates an OBJ file (any format: [`load_mesh`]; see the module documentation for what the mesh is).
pub fn load_obj(path: &Path, options: &LoadOptions) -> Result<LoadedMesh> {
    load_obj_with(path, options, ObjParser::Auto)
}

/// The first `n` bytes of a file (fewer when it is shorter).
fn read_head(path: &Path, n: u64) -> Result<Vec<u8>> {
    use std::io::Read;
    let io = |e| Error::Io { path: path.to_owned(), source: e };
    let mut head = Vec::new();
    std::fs::File::open(path).map_err(io)?.take(n).read_to_end(&mut head).map_err(io)?;
    Ok(head)
}

/// How much of an OBJ file is looked at for binary data before the rest is read.
const OBJ_HEAD_BYTES: u64 = 64 << 10;

/// The bytes of an OBJ file, or only its first [`OBJ_HEAD_BYTES`] when they already hold
/// binary data outside comments: normalizing is line by line and the scanner checks each
/// line's text before anything else, so it refuses the head at the line (and with the error)
/// it would refuse the whole file at, without reading a large binary file (1 GB took 7 s and
/// 1 GB of memory to be refused).
fn read_obj_bytes(path: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
    let io = |e| Error::Io { path: path.to_owned(), source: e };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    (&mut file).take(OBJ_HEAD_BYTES).read_to_end(&mut bytes).map_err(io)?;
    let control = |b: &u8| *b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0b | 0x0c);
    let binary = bytes.iter().any(control) && scan::normalize(bytes.clone()).iter().any(control);
    if !binary {
        file.read_to_end(&mut bytes).map_err(io)?;
    }
    Ok(bytes)
}

/// [`load_obj`] with a choice of number reader; every choice gives the same mesh, report and
/// errors (the parallel parser is only faster).
pub fn load_obj_with(path: &Path, options: &LoadOptions, parser: ObjParser) -> Result<LoadedMesh> {
    check_options(options)?;
    // A FIFO or a device is refused before it is opened (opening a FIFO would block).
    crate::output::check_input_file(path)?;
    let bytes = read_obj_bytes(path)?;
    // BOM, CR-only line ends, `\` continuations and trailing comments, for both readers.
    let bytes = scan::normalize(bytes);
    let parallel = match parser {
        ObjParser::Auto => bytes.len() >= PARALLEL_MIN_BYTES,
        ObjParser::Tobj => false,
        ObjParser::Parallel => true,
    };
    // One parallel pass when the file allows it; otherwise the scanner beside a number reader.
    if parallel {
        if let Some((scanned, values)) = scan_parallel::scan_parallel(&bytes) {
            if parallel_fits(&scanned, &values) {
                let models = scanned_models(&scanned);
                return Builder {
                    path,
                    bytes: &bytes,
                    scan: &scanned,
                    models: &models,
                    values: Some(&values),
                    options,
                }
                .build();
            }
        }
    }
    let (scanned, numbers) = rayon::join(
        || scan::scan(path, &bytes),
        || match parallel {
            true => Numbers::Parallel(parse::values(&bytes)),
            false => Numbers::Tobj(run_tobj(&bytes)),
        },
    );
    let scanned = scanned?;
    let parsed = match numbers {
        Numbers::Parallel(Some(v)) if parallel_fits(&scanned, &v) => Ok(v),
        // tobj cannot read vertex colours: the number parser reads them whatever the choice
        // (tobj reports a number it cannot read).
        _ if scanned.colours => match parse::values(&bytes) {
            Some(v) if same_counts(&scanned, &v) => Ok(v),
            _ => Err(run_tobj(&bytes)),
        },
        Numbers::Parallel(_) => Err(run_tobj(&bytes)),
        Numbers::Tobj(t) => Err(t),
    };
    let (models, values) = match parsed {
        Ok(values) => (scanned_models(&scanned), Some(values)),
        Err(tobj) => {
            let models = tobj.map_err(|e| scan::locate_tobj_error(path, &bytes, e))?;
            (align(path, &scanned, models)?, None)
        }
    };
    Builder {
        path,
        bytes: &bytes,
        scan: &scanned,
        models: &models,
        values: values.as_ref(),
        options,
    }
    .build()
}

/// The numbers of a file as one of the two readers gives them.
enum Numbers {
    Parallel(Option<Values>),
    Tobj(std::result::Result<Vec<tobj::Model>, tobj::LoadError>),
}

/// Whether the parallel parser's values (and the scanner's objects) are what tobj would give:
/// the file stays within what they reproduce, and every object with faces that uses `vt`
/// (`vn`) comes after at least one `vt` (`vn`) statement, as tobj requires.
fn parallel_fits(scan: &Scan, values: &Values) -> bool {
    let counts = same_counts(scan, values);
    let attrs = scan.models.iter().all(|m| {
        m.len == 0
            || ((scan.corner_vt.is_empty() || m.vt_at_end > 0)
                && (scan.corner_vn.is_empty() || m.vn_at_end > 0))
    });
    scan.parallel_ok && counts && attrs
}

/// Whether the number parser read as many `v`, `vt` and `vn` as the scanner counted.
fn same_counts(scan: &Scan, values: &Values) -> bool {
    values.v.len() == scan.num_v && values.vt.len() == scan.num_vt && values.vn.len() == scan.num_vn
}

fn scanned_models(scan: &Scan) -> Vec<Model> {
    let m = |m: &scan::ScanModel| Model {
        name: m.name.clone(),
        mesh: None,
        start: m.start,
        len: m.len,
    };
    scan.models.iter().map(m).collect()
}

fn check_options(o: &LoadOptions) -> Result<()> {
    let (lo, hi) = crate::limits::MESH_SCALE_RANGE;
    if !(o.scale.is_finite() && (lo..=hi).contains(&o.scale)) {
        return Err(Error::invalid_arg(
            "scale",
            format!(
                "{} is not in [1e-12, 1e12] (limits::MESH_SCALE_RANGE)",
                crate::error::fmt_num(o.scale)
            ),
        ));
    }
    if let Some(t) = o.weld {
        if !(t.is_finite() && t >= 0.0) {
            return Err(Error::invalid_arg("weld", format!("{t} is not a distance ≥ 0")));
        }
    }
    Ok(())
}

fn run_tobj(bytes: &[u8]) -> Result<Vec<tobj::Model>, tobj::LoadError> {
    // tobj's optional features (merging, reordering) add fields; they stay off.
    #[allow(clippy::needless_update)]
    let opts = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = std::io::Cursor::new(bytes);
    let (models, _materials) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))?;
    Ok(models)
}

/// Pairs tobj's models with the scanner's corners, checking that they agree.
fn align(path: &Path, scan: &Scan, models: Vec<tobj::Model>) -> Result<Vec<Model>> {
    let mut start = 0;
    let mut out = Vec::with_capacity(models.len());
    for m in models {
        let n = m.mesh.indices.len();
        let ok_vt = scan.corner_vt.is_empty() || m.mesh.texcoord_indices.len() == n;
        let ok_vn = scan.corner_vn.is_empty() || m.mesh.normal_indices.len() == n;
        if !ok_vt || !ok_vn {
            return Err(internal(path, "tobj returned attribute indices of the wrong length"));
        }
        out.push(Model { name: m.name, mesh: Some(m.mesh), start, len: n });
        start += n;
    }
    if start != scan.corner_v.len() {
        return Err(internal(
            path,
            &format!("tobj read {start} face corners, the scanner {}", scan.corner_v.len()),
        ));
    }
    Ok(out)
}

fn internal(path: &Path, what: &str) -> Error {
    Error::Parse { path: path.to_owned(), line: 0, message: format!("unsupported OBJ: {what}") }
}

struct Builder<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    scan: &'a Scan,
    models: &'a [Model],
    /// The parallel parser's values, for models without tobj's.
    values: Option<&'a Values>,
    options: &'a LoadOptions,
}

impl Builder<'_> {
    /// The position of corner `k` of model `m`.
    fn position(&self, m: &Model, k: usize) -> Vector3<f64> {
        match (&m.mesh, self.values) {
            (Some(mesh), _) => {
                let (l, p) = (3 * mesh.indices[k] as usize, &mesh.positions);
                Vector3::new(p[l], p[l + 1], p[l + 2])
            }
            (None, Some(v)) => Vector3::from(v.v[self.scan.corner_v[m.start + k] as usize]),
            (None, None) => Vector3::repeat(f64::NAN),
        }
    }

    /// The texture coordinates of model `m` by corner: how many corners have one, and the value
    /// of corner `k` (tobj's count is 0 for an object read before any `vt`).
    fn texcoord_count(&self, m: &Model) -> usize {
        m.mesh.as_ref().map_or(m.len, |mesh| mesh.texcoord_indices.len())
    }

    fn texcoord(&self, m: &Model, k: usize) -> Vector2<f64> {
        match (&m.mesh, self.values) {
            (Some(mesh), _) => {
                let (l, tc) = (2 * mesh.texcoord_indices[k] as usize, &mesh.texcoords);
                Vector2::new(tc[l], tc[l + 1])
            }
            (None, Some(v)) => Vector2::from(v.vt[self.scan.corner_vt[m.start + k] as usize]),
            (None, None) => Vector2::repeat(f64::NAN),
        }
    }

    fn normal_count(&self, m: &Model) -> usize {
        m.mesh.as_ref().map_or(m.len, |mesh| mesh.normal_indices.len())
    }

    fn normal(&self, m: &Model, k: usize) -> Vector3<f64> {
        match (&m.mesh, self.values) {
            (Some(mesh), _) => {
                let (l, n) = (3 * mesh.normal_indices[k] as usize, &mesh.normals);
                Vector3::new(n[l], n[l + 1], n[l + 2])
            }
            (None, Some(v)) => Vector3::from(v.vn[self.scan.corner_vn[m.start + k] as usize]),
            (None, None) => Vector3::repeat(f64::NAN),
        }
    }

    fn build(&self) -> Result<LoadedMesh> {
        let mut report = LoadReport {
            file_vertices: self.scan.num_v,
            file_triangles: self.scan.face_line.len(),
            ignored_statements: self.scan.ignored_statements,
            objects: self.object_names(),
            ..Default::default()
        };
        report.polygons_split = count_split_polygons(&self.scan.face_line);
        let selected = self.select()?;
        let positions = self.file_positions(&selected)?;
        let used = used_vertices(self.scan.num_v, &self.scan.corner_v, self.models, &selected);
        let rep = match self.options.weld {
            Some(tol) => weld::weld_map(&positions, &used, tol),
            None => (0..self.scan.num_v as u32).collect(),
        };
        let (tris, dropped) = self.triangles(&selected, &rep, &positions)?;
        report.dropped_degenerate_faces = dropped.total();
        if tris.is_empty() {
            return Err(self.empty(&dropped));
        }
        let (new_id, source) = compact_vertices(self.scan.num_v, &tris, &self.scan.corner_v, &rep);
        report.welded_vertices =
            (0..self.scan.num_v).filter(|&i| used[i] && rep[i] as usize != i).count();
        report.unreferenced_vertices = self.scan.num_v - source.len() - report.welded_vertices;
        let scale = self.options.scale;
        let mut mesh = Mesh {
            positions: source.par_iter().map(|&i| positions[i as usize] * scale).collect(),
            faces: tris
                .par_iter()
                .map(|&t| {
                    let c = |k: usize| {
                        new_id[rep[self.scan.corner_v[3 * t as usize + k] as usize] as usize]
                    };
                    [c(0), c(1), c(2)]
                })
                .collect(),
            units: self.options.units,
            ..Default::default()
        };
        super::raw::check_part_size(self.path, &mesh.positions, scale)?;
        report.face_line = tris.par_iter().map(|&t| self.scan.face_line[t as usize]).collect();
        report.source_vertex = source.par_iter().map(|&i| i + 1).collect();
        (mesh.uv, report.corners_without_uv) = self.uvs(&tris)?;
        mesh.normals = self.normals(&tris)?;
        self.validate(&mesh, &mut report)?;
        Ok(LoadedMesh { mesh, report })
    }

    fn object_names(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for m in self.models {
            if m.len > 0 && !names.contains(&m.name) {
                names.push(m.name.clone());
            }
        }
        names
    }

    /// Indices of the selected models.
    fn select(&self) -> Result<Vec<usize>> {
        let Some(name) = &self.options.object else { return Ok((0..self.models.len()).collect()) };
        let sel: Vec<usize> =
            (0..self.models.len()).filter(|&m| &self.models[m].name == name).collect();
        if sel.is_empty() {
            let names = self.object_names();
            let available = if names.is_empty() { "(none)".to_string() } else { names.join(", ") };
            return Err(Error::ObjectNotFound {
                path: self.path.to_owned(),
                name: name.clone(),
                available,
            });
        }
        Ok(sel)
    }

    /// Positions by file index (NaN where unused), checked finite where used.
    fn file_positions(&self, selected: &[usize]) -> Result<Vec<Vector3<f64>>> {
        let mut pos = vec![Vector3::repeat(f64::NAN); self.scan.num_v];
        for &m in selected {
            let m = &self.models[m];
            for k in 0..m.len {
                let v = self.position(m, k);
                if !v.iter().all(|x| x.is_finite()) {
                    let i = self.scan.corner_v[m.start + k] as usize;
                    return Err(self.non_finite(Kind::V, i, "vertex"));
                }
                if let Some(&x) = v.iter().find(|x| x.abs() * self.options.scale > MAX_COORDINATE) {
                    let i = self.scan.corner_v[m.start + k] as usize;
                    return Err(self.too_large(i, x));
                }
                pos[self.scan.corner_v[m.start + k] as usize] = v;
            }
        }
        Ok(pos)
    }

    fn non_finite(&self, kind: Kind, index: usize, what: &str) -> Error {
        Error::NonFinite {
            path: self.path.to_owned(),
            line: scan::line_of(self.bytes, kind, index),
            message: format!("{what} {} has a non-finite (NaN or infinite) value", index + 1),
        }
    }

    fn too_large(&self, index: usize, x: f64) -> Error {
        let scale = self.options.scale;
        let scaled = if scale == 1.0 { String::new() } else { format!(" (×{scale} scale)") };
        Error::NonFinite {
            path: self.path.to_owned(),
            line: scan::line_of(self.bytes, Kind::V, index),
            message: format!(
                "vertex {} has a coordinate {x:e}{scaled} beyond ±{MAX_COORDINATE:e}: areas and \
                 normals of its faces would overflow to infinity",
                index + 1
            ),
        }
    }

    fn empty(&self, dropped: &Counts) -> Error {
        let message = if dropped.total() > 0 {
            zero_area_message(dropped, self.options)
        } else if self.options.object.is_some() {
            "the selected object has no faces".to_string()
        } else {
            "no faces: empty mesh".to_string()
        };
        Error::EmptyMesh { path: self.path.to_owned(), message }
    }

    /// Kept triangles (indices into the file's triangles) and the degenerate ones dropped.
    fn triangles(
        &self,
        selected: &[usize],
        rep: &[u32],
        pos: &[Vector3<f64>],
    ) -> Result<(Vec<u32>, Counts)> {
        let cv = &self.scan.corner_v;
        let corners = |t: usize| [0, 1, 2].map(|k| rep[cv[3 * t + k] as usize]);
        let mut kept = Vec::with_capacity(self.scan.face_line.len());
        let mut bad = Vec::new();
        let mut counts = Counts::default();
        for &m in selected {
            let m = &self.models[m];
            let range = m.start / 3..(m.start + m.len) / 3;
            let kinds: Vec<Option<Degeneracy>> = range
                .clone()
                .into_par_iter()
                .map(|t| degenerate::classify(corners(t), pos))
                .collect();
            for (t, d) in range.zip(kinds) {
                match d {
                    Some(kind) => {
                        counts.add(kind, corners(t), pos);
                        bad.push(t as u32);
                    }
                    None => kept.push(t as u32),
                }
            }
        }
        if !bad.is_empty() && self.options.degenerate == DegeneratePolicy::Error {
            let lines: Vec<String> = bad
                .iter()
                .take(5)
                .map(|&t| format!("line {}", self.scan.face_line[t as usize]))
                .collect();
            return Err(Error::DegenerateFaces {
                path: self.path.to_owned(),
                message: format!(
                    "{} degenerate face(s), at {}: they {}",
                    bad.len(),
                    lines.join(", "),
                    counts.describe()
                ),
            });
        }
        Ok((kept, counts))
    }

    /// Per-corner UVs if every kept corner has one, and the number of corners without.
    fn uvs(&self, tris: &[u32]) -> Result<(Option<CornerAttribute<Vector2<f64>>>, usize)> {
        let cvt = &self.scan.corner_vt;
        if cvt.is_empty() {
            return Ok((None, 0));
        }
        let missing =
            tris.iter().map(|&t| (0..3).filter(|&k| cvt[3 * t as usize + k] == NONE).count()).sum();
        if missing > 0 {
            return Ok((None, missing));
        }
        let mut vals = vec![Vector2::repeat(f64::NAN); self.scan.num_vt];
        for m in self.models {
            for k in 0..self.texcoord_count(m) {
                let i = cvt[m.start + k];
                if i != NONE {
                    vals[i as usize] = self.texcoord(m, k);
                }
            }
        }
        for &t in tris {
            for k in 0..3 {
                let i = cvt[3 * t as usize + k] as usize;
                if !vals[i].all_finite() {
                    return Err(self.non_finite(Kind::Vt, i, "texture coordinate"));
                }
            }
        }
        let canon = dedup_by_value(&vals);
        let attr =
            self.corner_attribute(tris, cvt, &vals, Some(&canon), Kind::Vt, "texture coordinate")?;
        Ok((Some(attr), 0))
    }

    fn normals(&self, tris: &[u32]) -> Result<Option<CornerAttribute<Vector3<f64>>>> {
        let cvn = &self.scan.corner_vn;
        if cvn.is_empty() || tris.iter().any(|&t| (0..3).any(|k| cvn[3 * t as usize + k] == NONE)) {
            return Ok(None);
        }
        let mut vals = vec![Vector3::repeat(f64::NAN); self.scan.num_vn];
        for m in self.models {
            for k in 0..self.normal_count(m) {
                let i = cvn[m.start + k];
                if i != NONE {
                    vals[i as usize] = self.normal(m, k);
                }
            }
        }
        self.corner_attribute(tris, cvn, &vals, None, Kind::Vn, "normal").map(Some)
    }

    /// Builds a corner attribute from file-indexed values: the used values (after mapping
    /// through `canon`) compacted in file order.
    fn corner_attribute<T: Copy + AllFinite>(
        &self,
        tris: &[u32],
        corner: &[u32],
        vals: &[T],
        canon: Option<&[u32]>,
        kind: Kind,
        what: &str,
    ) -> Result<CornerAttribute<T>> {
        let c = |i: u32| canon.map_or(i, |m| m[i as usize]);
        let mut new_id = vec![NONE; vals.len()];
        for &t in tris {
            for k in 0..3 {
                new_id[c(corner[3 * t as usize + k]) as usize] = 0;
            }
        }
        let mut values = Vec::new();
        for (i, id) in new_id.iter_mut().enumerate() {
            if *id == 0 {
                if !vals[i].all_finite() {
                    return Err(self.non_finite(kind, i, what));
                }
                *id = values.len() as u32;
                values.push(vals[i]);
            }
        }
        let corners = tris
            .iter()
            .map(|&t| [0, 1, 2].map(|k| new_id[c(corner[3 * t as usize + k]) as usize]))
            .collect();
        Ok(CornerAttribute { values, corners })
    }

    fn validate(&self, mesh: &Mesh, report: &mut LoadReport) -> Result<()> {
        let he = HalfEdges::new(mesh.num_vertices(), &mesh.faces)?;
        let problems = validate::find_problems(&he);
        report.nonmanifold_edges = problems.nonmanifold_edges.len();
        report.nonmanifold_vertices = problems.nonmanifold_vertices.len();
        report.inconsistent_orientation_edges = problems.inconsistent_edges.len();
        let names = FileNames {
            source_vertex: &report.source_vertex,
            face_line: &report.face_line,
            face_index: &[],
            naming: Naming::Obj,
            file_positions: &[],
        };
        validate::check(
            self.path,
            &he,
            &problems,
            &names,
            self.options.allow_nonmanifold,
            self.options.allow_inconsistent_orientation,
        )
    }
}

trait AllFinite {
    fn all_finite(&self) -> bool;
}

impl<const D: usize> AllFinite for nalgebra::SVector<f64, D> {
    fn all_finite(&self) -> bool {
        self.iter().all(|x| x.is_finite())
    }
}

/// Triangles whose face line equals the previous one come from one polygon.
fn count_split_polygons(face_line: &[u32]) -> usize {
    let mut n = 0;
    for (k, w) in face_line.windows(2).enumerate() {
        let starts_run = k == 0 || face_line[k - 1] != w[0];
        if w[0] == w[1] && starts_run {
            n += 1;
        }
    }
    n
}

fn used_vertices(
    num_v: usize,
    corner_v: &[u32],
    models: &[Model],
    selected: &[usize],
) -> Vec<bool> {
    let mut used = vec![false; num_v];
    for &m in selected {
        let m = &models[m];
        for &v in &corner_v[m.start..m.start + m.len] {
            used[v as usize] = true;
        }
    }
    used
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fits(text: &str) -> bool {
        let scan = scan::scan(Path::new("t.obj"), text.as_bytes()).unwrap();
        parse::values(text.as_bytes()).is_some_and(|v| parallel_fits(&scan, &v))
    }

    #[test]
    fn parallel_reader_takes_plain_files_only() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        assert!(fits(&format!("{tri}o a\nf 1 2 3\ng b\nf -3 -2 -1\n")));
        assert!(fits(&format!("{tri}vt 0 0\nf 1/1 2/1 3/1\r\n")));
        // Vertex colours are the parallel parser's only.
        assert!(fits("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 1 1 1 0.5\nf 1 2 3\n"));
        // A forward index, a polyline, non-ASCII text, and an object with faces
        // before the first `vt` of a file whose faces use `vt`: tobj reads these.
        assert!(!fits(&format!("f 1 2 3\n{tri}")));
        assert!(!fits(&format!("{tri}l 1 2\nf 1 2 3\n")));

        assert!(!fits(&format!("# \u{e9}\n{tri}f 1 2 3\n")));
        assert!(!fits(&format!("{tri}f 1 2 3\no b\nvt 0 0\nf 1/1 2/1 3/1\n")));
    }
}
