//! A mesh as an STL or PLY reader gives it ([`RawMesh`]: file vertices, triangles, optional
//! per-vertex UVs and normals) and its conversion into a validated [`Mesh`] with the same steps
//! as the OBJ loader: weld, drop zero-area faces, drop unreferenced vertices, scale, check the
//! structure — and the same [`LoadReport`].

use std::path::Path;

use nalgebra::{Vector2, Vector3};
use rayon::prelude::*;

use super::degenerate::{self, Counts};
use super::halfedge::HalfEdges;
use super::loaded::{DegeneratePolicy, LoadOptions, LoadReport, LoadedMesh, MeshFormat};
use super::scan::NONE;
use super::validate::{self, FileNames, Naming};
use super::{weld, CornerAttribute, Mesh};
use crate::limits::{MAX_COORDINATE, MIN_PART_SIZE};
use crate::{Error, Result};

/// File vertices and triangles before welding and validation.
#[derive(Clone, Debug, Default)]
pub(crate) struct RawMesh {
    /// Every vertex of the file, in file order (an STL has three per triangle).
    pub positions: Vec<Vector3<f64>>,
    /// Triangles (polygons already split into fans), indices into `positions`.
    pub faces: Vec<[u32; 3]>,
    /// 1-based line of each triangle's element in a text file, 0 in a binary one.
    pub face_line: Vec<u32>,
    /// Each triangle's element in the file's numbering (1-based STL triangle, 0-based PLY face).
    pub face_index: Vec<u32>,
    /// Texture coordinates per file vertex (PLY `u v`, `s t`, `texture_u texture_v`).
    pub uv: Option<Vec<Vector2<f64>>>,
    /// Normals per file vertex (PLY `nx ny nz`).
    pub normals: Option<Vec<Vector3<f64>>>,
    /// Polygons of more than three corners split into triangles.
    pub polygons_split: usize,
}

impl RawMesh {
    /// An empty mesh with room for `v` vertices and `f` triangles.
    pub fn with_capacity(v: usize, f: usize) -> Self {
        RawMesh {
            positions: Vec::with_capacity(v),
            faces: Vec::with_capacity(f),
            face_line: Vec::with_capacity(f),
            face_index: Vec::with_capacity(f),
            ..Default::default()
        }
    }

    /// Appends a triangle with its line and element number.
    pub fn push_face(&mut self, f: [u32; 3], line: u32, index: u32) {
        self.faces.push(f);
        self.face_line.push(line);
        self.face_index.push(index);
    }
}

/// Why a coordinate is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum ValueError {
    /// NaN or infinite.
    NonFinite,
    /// |x|·scale beyond [`MAX_COORDINATE`]; holds x.
    TooLarge(f64),
}

/// Checks a position: finite, and every |coordinate|·scale within [`MAX_COORDINATE`] (the OBJ
/// loader's bound).
pub(crate) fn check_position(p: &Vector3<f64>, scale: f64) -> std::result::Result<(), ValueError> {
    if !p.iter().all(|x| x.is_finite()) {
        return Err(ValueError::NonFinite);
    }
    match p.iter().find(|x| x.abs() * scale > MAX_COORDINATE) {
        Some(&x) => Err(ValueError::TooLarge(x)),
        None => Ok(()),
    }
}

/// Refuses a part smaller than [`MIN_PART_SIZE`] across (its bounding box's diagonal, in the
/// mesh's units after `scale`).
pub(super) fn check_part_size(path: &Path, positions: &[Vector3<f64>], scale: f64) -> Result<()> {
    let (lo, hi) = positions.iter().fold(
        (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    let diagonal = (hi - lo).norm();
    if positions.is_empty() || diagonal >= MIN_PART_SIZE {
        return Ok(());
    }
    let scaled = if scale == 1.0 { String::new() } else { format!(" (after ×{scale} scale)") };
    Err(Error::InvalidMesh {
        path: path.to_owned(),
        message: format!(
            "the part is {} across{scaled}: smaller than the {MIN_PART_SIZE:e} grainline \
             computes with (its curvatures would overflow; limits::MIN_PART_SIZE) — give the \
             coordinates in a smaller unit",
            crate::error::fmt_num(diagonal)
        ),
    })
}

/// Builds the validated mesh of a [`RawMesh`]. `default_weld` is the weld used when the
/// options give none (STL: `Some(0.0)`, the exact weld).
pub(crate) fn build(
    path: &Path,
    raw: RawMesh,
    options: &LoadOptions,
    format: MeshFormat,
    naming: Naming,
    default_weld: Option<f64>,
) -> Result<LoadedMesh> {
    let nv = raw.positions.len();
    let corner_v: Vec<u32> = raw.faces.iter().flatten().copied().collect();
    let mut used = vec![false; nv];
    for &v in &corner_v {
        used[v as usize] = true;
    }
    let rep = match options.weld.or(default_weld) {
        Some(tol) => weld::weld_map(&raw.positions, &used, tol),
        None => (0..nv as u32).collect(),
    };
    let corners = |t: usize| raw.faces[t].map(|v| rep[v as usize]);
    let flags: Vec<Option<degenerate::Degeneracy>> = (0..raw.faces.len())
        .into_par_iter()
        .map(|t| degenerate::classify(corners(t), &raw.positions))
        .collect();
    let tris: Vec<u32> =
        (0..raw.faces.len() as u32).filter(|&t| flags[t as usize].is_none()).collect();
    let mut counts = Counts::default();
    for (t, kind) in flags.iter().enumerate() {
        if let Some(kind) = kind {
            counts.add(*kind, corners(t), &raw.positions);
        }
    }
    let dropped = counts.total();
    let face_name = |t: usize| naming.face(raw.face_line[t], raw.face_index[t]);
    if dropped > 0 && options.degenerate == DegeneratePolicy::Error {
        let bad: Vec<usize> = (0..raw.faces.len()).filter(|&t| flags[t].is_some()).collect();
        let names: Vec<String> = bad.iter().take(5).map(|&t| face_name(t)).collect();
        return Err(Error::DegenerateFaces {
            path: path.to_owned(),
            message: format!(
                "{} degenerate face(s), at {}: they {}",
                bad.len(),
                names.join(", "),
                counts.describe()
            ),
        });
    }
    if tris.is_empty() {
        let message = if dropped > 0 {
            zero_area_message(&counts, options)
        } else {
            "no faces: empty mesh".to_string()
        };
        return Err(Error::EmptyMesh { path: path.to_owned(), message });
    }
    let (new_id, source) = compact_vertices(nv, &tris, &corner_v, &rep);
    let welded = (0..nv).filter(|&i| used[i] && rep[i] as usize != i).count();
    let mut report = LoadReport {
        format,
        file_vertices: nv,
        welded_vertices: welded,
        unreferenced_vertices: nv - source.len() - welded,
        dropped_degenerate_faces: dropped,
        file_triangles: raw.faces.len(),
        polygons_split: raw.polygons_split,
        ..Default::default()
    };
    let scale = options.scale;
    let mut mesh = Mesh {
        positions: source.iter().map(|&i| raw.positions[i as usize] * scale).collect(),
        faces: tris
            .iter()
            .map(|&t| raw.faces[t as usize].map(|v| new_id[rep[v as usize] as usize]))
            .collect(),
        units: options.units,
        ..Default::default()
    };
    check_part_size(path, &mesh.positions, scale)?;
    report.face_line = tris.iter().map(|&t| raw.face_line[t as usize]).collect();
    report.face_index = tris.iter().map(|&t| raw.face_index[t as usize]).collect();
    report.source_vertex = source.iter().map(|&i| i + 1).collect();
    if let Some(uv) = &raw.uv {
        let canon = dedup_by_value(uv);
        mesh.uv = Some(corner_attribute(&raw.faces, &tris, uv, Some(&canon)));
    }
    if let Some(n) = &raw.normals {
        mesh.normals = Some(corner_attribute(&raw.faces, &tris, n, None));
    }
    let he = HalfEdges::new(mesh.num_vertices(), &mesh.faces)?;
    let problems = validate::find_problems(&he);
    report.nonmanifold_edges = problems.nonmanifold_edges.len();
    report.nonmanifold_vertices = problems.nonmanifold_vertices.len();
    report.inconsistent_orientation_edges = problems.inconsistent_edges.len();
    let names = FileNames {
        source_vertex: &report.source_vertex,
        face_line: &report.face_line,
        face_index: &report.face_index,
        naming,
        file_positions: &raw.positions,
    };
    validate::check(
        path,
        &he,
        &problems,
        &names,
        options.allow_nonmanifold,
        options.allow_inconsistent_orientation,
    )?;
    Ok(LoadedMesh { mesh, report })
}

/// A per-corner attribute from per-file-vertex values: the used values (after `canon`)
/// compacted in file order.
fn corner_attribute<T: Copy>(
    faces: &[[u32; 3]],
    tris: &[u32],
    vals: &[T],
    canon: Option<&[u32]>,
) -> CornerAttribute<T> {
    const NONE: u32 = u32::MAX;
    let c = |i: u32| canon.map_or(i, |m| m[i as usize]);
    let mut new_id = vec![NONE; vals.len()];
    for &t in tris {
        for v in faces[t as usize] {
            new_id[c(v) as usize] = 0;
        }
    }
    let mut values = Vec::new();
    for (i, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = values.len() as u32;
            values.push(vals[i]);
        }
    }
    let corners = tris.iter().map(|&t| faces[t as usize].map(|v| new_id[c(v) as usize])).collect();
    CornerAttribute { values, corners }
}

/// "no faces left: all N faces have zero area" (or are slivers), naming the weld tolerance when
/// one was given (a tolerance beyond the part's size merges every vertex into one).
pub(super) fn zero_area_message(counts: &Counts, options: &LoadOptions) -> String {
    let weld = match options.weld {
        Some(t) if t > 0.0 => format!(
            " after welding vertices within {} (mesh.weld, --weld): is the tolerance larger \
             than the part's edges?",
            crate::error::fmt_num(t)
        ),
        _ => String::new(),
    };
    format!("no faces left: all {} faces {}{weld}", counts.total(), counts.describe())
}

/// New index (file order) of every vertex used by a kept triangle, and the file index of each.
pub(super) fn compact_vertices(
    num_v: usize,
    tris: &[u32],
    corner_v: &[u32],
    rep: &[u32],
) -> (Vec<u32>, Vec<u32>) {
    let mut new_id = vec![NONE; num_v];
    for &t in tris {
        for k in 0..3 {
            new_id[rep[corner_v[3 * t as usize + k] as usize] as usize] = 0;
        }
    }
    let mut source = Vec::new();
    for (i, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = source.len() as u32;
            source.push(i as u32);
        }
    }
    (new_id, source)
}

/// For every value, the first (smallest) index holding a bit-identical value.
pub(super) fn dedup_by_value(vals: &[Vector2<f64>]) -> Vec<u32> {
    let mut keyed: Vec<(u64, u64, u32)> = vals
        .par_iter()
        .enumerate()
        .map(|(i, v)| ((v.x + 0.0).to_bits(), (v.y + 0.0).to_bits(), i as u32))
        .collect();
    keyed.par_sort_unstable();
    let mut canon = vec![0u32; vals.len()];
    let mut k = 0;
    while k < keyed.len() {
        let first = keyed[k];
        let mut j = k;
        while j < keyed.len() && (keyed[j].0, keyed[j].1) == (first.0, first.1) {
            canon[keyed[j].2 as usize] = first.2;
            j += 1;
        }
        k = j;
    }
    canon
}
