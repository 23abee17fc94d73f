//! `grainline edit`: an interactive editor in the browser (issue 16).
//!
//! A local HTTP server ([`server`] on [`http`], bounded connections) serves a page ([`assets`]: HTML, the
//! page's script and three.js, all embedded in the binary) that shows the part in WebGL
//! shaded with the scene's anisotropic BRDF and the current grain, the key light's highlight
//! curves over it, and drives the scene's tools with the mouse. Each change of the edit list
//! is solved off the request thread by the [`session`]'s solver thread — the latest request
//! wins, stale results are dropped — exactly as `grainline run` would solve a scene file
//! holding the same edits; saving writes that scene file.
//!
//! Safety on a designer's machine ([`server`]): the server binds 127.0.0.1 only; refuses a
//! request whose `Host` is not its own address (DNS rebinding) and a write (`POST`) whose
//! `Origin` is not its own page; serves only its embedded assets and the scene's own files
//! under fixed names (no path from the URL ever reaches the file system); answers a malformed
//! request with a 4xx and keeps running; bounds every connection's time, headers and body,
//! and the number of connections handled at once ([`http`]), and cancels a request's work
//! when its client goes; checks every edit and light from the page with the scene file's own
//! checks, and an edit's refinement against its budget when it arrives.

pub mod assets;
pub mod drag;
pub mod http;
pub mod server;
pub mod session;

use std::path::Path;
use std::sync::Arc;

use serde_json::json;

use crate::edit::WarpKind;
use crate::{Error, Result};
pub use session::{Base, Change, ExportKind, PageStrokes, Part, Session, Solved, StateView};

/// Options of [`Editor::bind`].
#[derive(Clone, Debug, Default)]
pub struct EditorOptions {
    /// The port on 127.0.0.1 (0: a free one).
    pub port: u16,
}

/// A bound editor: the session prepared, the socket listening, not yet serving.
pub struct Editor {
    session: Arc<Session>,
    listener: std::net::TcpListener,
    port: u16,
}

impl Editor {
    /// Reads and prepares the scene, then binds 127.0.0.1:`port`.
    pub fn bind(scene: &Path, options: &EditorOptions) -> Result<Editor> {
        let session = Arc::new(Session::open(scene)?);
        let addr = std::net::SocketAddr::from(([127, 0, 0, 1], options.port));
        let listener = std::net::TcpListener::bind(addr).map_err(|e| Error::Io {
            path: std::path::PathBuf::from(addr.to_string()),
            source: std::io::Error::other(format!("cannot listen: {e}")),
        })?;
        let port = listener.local_addr().map_or(options.port, |a| a.port());
        Ok(Editor { session, listener, port })
    }

    /// The page's address, `http://127.0.0.1:PORT/`.
    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/", self.port)
    }

    /// The port listened on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// The session.
    pub fn session(&self) -> &Arc<Session> {
        &self.session
    }

    /// Serves until the process ends (the binary's signal handler ends it on SIGINT /
    /// SIGTERM). Starts the solver thread (which solves the scene's own edits first).
    pub fn run(self) -> Result<()> {
        let s = Arc::clone(&self.session);
        std::thread::Builder::new()
            .name("editor-solver".into())
            .spawn(move || s.solver_loop())
            .map_err(|e| Error::invalid_arg("edit", format!("cannot start the solver: {e}")))?;
        let ctx = server::Context::new(Arc::clone(&self.session), self.port);
        http::serve(self.listener, move |rq| server::handle(&ctx, rq));
        Ok(())
    }
}

/// What the page needs to know once: units, material, lights, camera, tone map, symmetry,
/// brush defaults and ranges (`GET /api/info`).
pub fn info_json(session: &Session) -> serde_json::Value {
    let scene = session.scene();
    let p = session.prepared();
    let (lo, hi) = p.mesh.positions.iter().fold(
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
        |(mut lo, mut hi), v| {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
            (lo, hi)
        },
    );
    let diag = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2))
        .sqrt()
        .max(1e-9);
    let radius = scene
        .edits
        .iter()
        .find_map(|e| match e {
            crate::edit::Edit::Bend(w) | crate::edit::Edit::Expand(w) => Some(w.radius),
            crate::edit::Edit::Stencil(s) => Some(s.radius),
            _ => None,
        })
        .unwrap_or(diag / 10.0);
    let render = scene.render.clone().unwrap_or_default();
    let key = crate::render::key_light_index(&scene.lights);
    let lighting = &p.field_options.lighting;
    // Fresnel presets resolved to (η, k), as the preview evaluates them.
    use crate::render::brdf::fresnel::FresnelTerm;
    let fresnel = match FresnelTerm::new(&scene.material.fresnel) {
        FresnelTerm::One => json!({ "kind": "none" }),
        FresnelTerm::Schlick(f0) => json!({ "kind": "schlick", "f0": f0 }),
        FresnelTerm::Conductor(eta, k) => json!({ "kind": "conductor", "eta": eta, "k": k }),
    };
    json!({
        "fresnel": fresnel,
        "format": "grainline-editor-info",
        "version": 1,
        "scene": session.path().display().to_string(),
        "mesh": p.mesh_name,
        "units": p.mesh.units.as_str(),
        "vertices": p.mesh.num_vertices(),
        "faces": p.mesh.num_faces(),
        "symmetry": match p.field_options.symmetry {
            crate::highlight::Symmetry::Line => "line",
            crate::highlight::Symmetry::Oriented => "oriented",
        },
        "material": scene.material,
        "lights": scene.lights,
        "key_light": key,
        "key_light_direction": [lighting.light.x, lighting.light.y, lighting.light.z],
        "view": scene.view,
        "tone_map": render.tone_map,
        "exposure": render.exposure,
        "background": render.background,
        "bbox": [lo, hi],
        "diagonal": diag,
        "radius": radius,
        "strength": {
            "bend": session::Session::strength_range(WarpKind::Bend),
            "expand": session::Session::strength_range(WarpKind::Expand),
        },
    })
}

/// The mesh of a prepared part for the page, little-endian: `u32` vertex count n, `u32` face
/// count f, `f32` positions (3n), `f32` unit normals (3n), `u32` corner indices (3f).
pub fn mesh_bytes(p: &crate::pipeline::Prepared) -> Vec<u8> {
    let (n, f) = (p.mesh.num_vertices(), p.mesh.num_faces());
    let mut out = Vec::with_capacity(8 + 24 * n + 12 * f);
    out.extend((n as u32).to_le_bytes());
    out.extend((f as u32).to_le_bytes());
    for v in &p.mesh.positions {
        for c in v.iter() {
            out.extend((*c as f32).to_le_bytes());
        }
    }
    for fr in &p.field.geometry.frames {
        for c in fr.n.iter() {
            out.extend((*c as f32).to_le_bytes());
        }
    }
    for face in &p.mesh.faces {
        for c in face {
            out.extend(c.to_le_bytes());
        }
    }
    out
}

/// A solved field for the page, little-endian: `u32` n, `u32` segment count s, `u32` critical
/// count c, `u32` the id of the part it was solved on ([`Part::id`]: the page loads that
/// part's mesh, `GET /api/mesh?part=ID`, when it shows another), `f32` grain (3n), `f32`
/// segments (6s: two world points each), `u32` critical vertices (c).
pub fn grain_bytes(s: &Solved) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + 12 * s.u.len() + 24 * s.segments.len());
    let id = s.part.id as usize;
    for k in [s.u.len(), s.segments.len(), s.critical.len(), id] {
        out.extend((k as u32).to_le_bytes());
    }
    put_le(&mut out, s.u.as_flattened(), f32::to_le_bytes);
    put_le(&mut out, s.segments.as_flattened(), f32::to_le_bytes);
    put_le(&mut out, &s.critical, u32::to_le_bytes);
    out
}

/// Appends `values` to `out`, four little-endian bytes each.
fn put_le<T: Copy>(out: &mut Vec<u8>, values: &[T], bytes: fn(T) -> [u8; 4]) {
    let start = out.len();
    out.resize(start + 4 * values.len(), 0);
    for (b, &v) in out[start..].chunks_exact_mut(4).zip(values) {
        b.copy_from_slice(&bytes(v));
    }
}

/// `GET /api/strokes`: the strokes and the as-brushed grain of a solved field ([`PageStrokes`]),
/// little-endian: `u32` strokes S, points P, vertices N, the part's id; S `u32` point counts;
/// P × 3 `f32` points (world); N × 3 `f32` as-brushed directions (zero where unbrushed).
pub fn strokes_bytes(t: &PageStrokes, part: u32) -> Vec<u8> {
    let points: usize = t.strokes.iter().map(Vec::len).sum();
    let mut out = Vec::with_capacity(16 + 4 * t.strokes.len() + 12 * (points + t.brushed_u.len()));
    for k in [t.strokes.len(), points, t.brushed_u.len(), part as usize] {
        out.extend((k as u32).to_le_bytes());
    }
    for s in &t.strokes {
        out.extend((s.len() as u32).to_le_bytes());
    }
    for v in t.strokes.iter().flatten().chain(&t.brushed_u) {
        for c in v {
            out.extend(c.to_le_bytes());
        }
    }
    out
}
