//! Structural checks of a loaded mesh: non-manifold edges and vertices, inconsistent face
//! orientation. Each problem becomes a one-line typed error naming the elements by their file
//! numbers (the 1-based `v` index and the line of the face).

use std::path::Path;

use rayon::prelude::*;

use super::halfedge::{EdgeKind, HalfEdges};
use super::topology::{nonmanifold_vertices_from_flags, vertex_flags};
use super::VertexId;
use crate::limits::MAX_EDGE_FACES;
use crate::{Error, Result};

/// The structural problems of a mesh.
#[derive(Clone, Debug, Default)]
pub(crate) struct Problems {
    /// One half-edge per edge with three or more faces.
    pub nonmanifold_edges: Vec<u32>,
    /// One half-edge per edge whose two faces traverse it in the same direction.
    pub inconsistent_edges: Vec<u32>,
    /// Vertices whose faces form several fans (on otherwise manifold edges).
    pub nonmanifold_vertices: Vec<VertexId>,
}

/// How a file format numbers its elements, for messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Naming {
    /// OBJ: faces by line, vertices by their 1-based `v` number.
    Obj,
    /// STL: faces by their 1-based triangle number (and line in ASCII), vertices by position.
    Stl,
    /// PLY: faces and vertices by their 0-based element number (as the face lists number
    /// vertices), and the line in ASCII.
    Ply,
}

impl Naming {
    /// A face, from its line (0 in a binary file) and its element number.
    pub(crate) fn face(self, line: u32, index: u32) -> String {
        let at = if line > 0 { format!(" (line {line})") } else { String::new() };
        match self {
            Naming::Obj => format!("line {line}"),
            Naming::Stl => format!("triangle {index}{at}"),
            Naming::Ply => format!("face element {index}{at}"),
        }
    }
}

/// How to name mesh elements in messages: by their numbers in the file.
pub(crate) struct FileNames<'a> {
    /// 1-based file vertex number of every mesh vertex.
    pub source_vertex: &'a [u32],
    /// 1-based line of every mesh face (0 in a binary file).
    pub face_line: &'a [u32],
    /// Element number of every mesh face (STL and PLY; empty for OBJ).
    pub face_index: &'a [u32],
    /// The file's numbering.
    pub naming: Naming,
    /// The file's vertex positions (an STL vertex is named by its position).
    pub file_positions: &'a [nalgebra::Vector3<f64>],
}

impl FileNames<'_> {
    fn vertex(&self, v: u32) -> String {
        let n = self.source_vertex.get(v as usize).copied().unwrap_or(v + 1);
        match self.naming {
            Naming::Obj => n.to_string(),
            Naming::Ply => (n - 1).to_string(),
            Naming::Stl => match self.file_positions.get(n as usize - 1) {
                Some(p) => crate::error::fmt_vec3(&[p.x, p.y, p.z]),
                None => n.to_string(),
            },
        }
    }

    fn face(&self, f: u32) -> String {
        let line = self.face_line.get(f as usize).copied();
        let index = self.face_index.get(f as usize).copied();
        match (self.naming, line, index) {
            (Naming::Obj, Some(l), _) => format!("line {l}"),
            (n, Some(l), Some(i)) => n.face(l, i),
            _ => format!("face {f}"),
        }
    }
}

/// The hint the loader's non-manifold errors end with; a scene names its own key instead
/// (`pipeline::load_part`).
pub(crate) const NONMANIFOLD_HINT: &str = "--allow-nonmanifold accepts them";

/// At most `FACES_LISTED` faces, then "… and N more".
const FACES_LISTED: usize = 4;

fn few(shown: &[String], total: usize) -> String {
    if total <= shown.len() {
        shown.join(", ")
    } else {
        format!("{} … and {} more", shown.join(", "), total - shown.len())
    }
}

/// Refuses an edge shared by more than [`MAX_EDGE_FACES`] faces (whatever is allowed).
fn check_edge_faces(path: &Path, he: &HalfEdges, names: &FileNames<'_>) -> Result<()> {
    match he.widest_edge() {
        Some((h, n)) if n > MAX_EDGE_FACES => {
            let faces = he.edge_faces(h);
            let lines: Vec<String> =
                faces.iter().take(FACES_LISTED).map(|f| names.face(f.0)).collect();
            Err(Error::NonManifold {
                path: path.to_owned(),
                message: format!(
                    "the edge between vertices {} and {} is shared by {n} faces ({}); at most \
                     {MAX_EDGE_FACES} faces may share an edge (limits::MAX_EDGE_FACES)",
                    names.vertex(he.origin(h)),
                    names.vertex(he.dest(h)),
                    few(&lines, n),
                ),
            })
        }
        _ => Ok(()),
    }
}

/// Finds every structural problem.
pub(crate) fn find_problems(he: &HalfEdges) -> Problems {
    let flags: Vec<u8> =
        (0..he.num_vertices() as u32).into_par_iter().map(|v| vertex_flags(he, v)).collect();
    Problems {
        nonmanifold_edges: he.edges_of_kind(EdgeKind::NonManifold),
        inconsistent_edges: he.edges_of_kind(EdgeKind::Inconsistent),
        nonmanifold_vertices: nonmanifold_vertices_from_flags(&flags),
    }
}

/// Refuses the mesh for the first problem found, unless allowed; an edge of more than
/// [`MAX_EDGE_FACES`] faces also when non-manifold edges are allowed.
pub(crate) fn check(
    path: &Path,
    he: &HalfEdges,
    p: &Problems,
    names: &FileNames<'_>,
    allow_nonmanifold: bool,
    allow_inconsistent: bool,
) -> Result<()> {
    if !allow_nonmanifold {
        if let Some(&h) = p.nonmanifold_edges.first() {
            let faces = he.edge_faces(h);
            let lines: Vec<String> =
                faces.iter().take(FACES_LISTED).map(|f| names.face(f.0)).collect();
            return Err(Error::NonManifold {
                path: path.to_owned(),
                message: format!(
                    "non-manifold edge between vertices {} and {} shared by {} faces ({}); {} \
                     such edge(s) in all ({NONMANIFOLD_HINT})",
                    names.vertex(he.origin(h)),
                    names.vertex(he.dest(h)),
                    faces.len(),
                    few(&lines, faces.len()),
                    p.nonmanifold_edges.len()
                ),
            });
        }
    }
    check_edge_faces(path, he, names)?;
    if !allow_inconsistent {
        if let Some(&h) = p.inconsistent_edges.first() {
            let faces = he.edge_faces(h);
            let lines: Vec<String> = faces.iter().map(|f| names.face(f.0)).collect();
            return Err(Error::InconsistentOrientation {
                path: path.to_owned(),
                message: format!(
                    "inconsistent face orientation: faces at {} both run from vertex {} to \
                     vertex {}; {} such edge(s) in all",
                    lines.join(" and "),
                    names.vertex(he.origin(h)),
                    names.vertex(he.dest(h)),
                    p.inconsistent_edges.len()
                ),
            });
        }
    }
    if !allow_nonmanifold {
        if let Some(&v) = p.nonmanifold_vertices.first() {
            return Err(Error::NonManifold {
                path: path.to_owned(),
                message: format!(
                    "non-manifold vertex {}: its faces form separate fans that touch only at \
                     it; {} such vertex(es) in all ({NONMANIFOLD_HINT})",
                    names.vertex(v.0),
                    p.nonmanifold_vertices.len()
                ),
            });
        }
    }
    Ok(())
}
