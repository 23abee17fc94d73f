//! The editor's HTTP routes and the rules every request passes first.
//!
//! Rules, in order (each refusal is a 4xx with a JSON `{"error": …}` body; the server goes on):
//! 1. the request target is an origin-form path (`/…`, at most 2 KiB): else 400;
//! 2. exactly one `Host` header, equal to `127.0.0.1:PORT` or `localhost:PORT` of this server:
//!    else 403 (a page on another name that resolves to 127.0.0.1 — DNS rebinding — gets
//!    nothing);
//! 3. a `POST` carries `Origin: http://127.0.0.1:PORT` (or `localhost`), `Content-Type:
//!    application/json`, and no `Sec-Fetch-Site` other than `same-origin`: else 403 / 415
//!    (another site's page cannot write);
//! 4. only `GET`, `HEAD` and `POST`: else 405; a body of at most 1 MiB: else 413 (the
//!    connection's own bounds — time, header size, concurrent connections — are
//!    [`super::http`]'s);
//! 5. the path is one of a fixed table (embedded assets, the API, `/files/scene.json`): else
//!    404. No part of a URL is ever used as a file path, so there is nothing to traverse.
//!
//! Routes:
//! - `GET /` and `/assets/…`: the page ([`super::assets`]);
//! - `GET /api/info`: [`super::info_json`]; `GET /api/mesh[?part=ID]`: [`super::mesh_bytes`]
//!   of the part numbered ID (0, the part as loaded, by default; 404 when the session no
//!   longer holds it);
//! - `GET /api/state[?after=V]`: [`super::StateView`], waiting up to 10 s for a solve newer
//!   than V;
//! - `GET /api/grain?version=V`: [`super::grain_bytes`] of version V (409 when it is not one of
//!   the last solved ones, [`super::session::RECENT_KEPT`]); `GET /api/field.json?version=V`:
//!   its FIELD.json; `GET /api/strokes?version=V`: [`super::strokes_bytes`], the strokes
//!   `grainline run` traces for it and the as-brushed grain (400 naming the key to add when
//!   the part has no UV layout);
//! - `GET /files/scene.json`: the scene file as it is on disk;
//! - `POST /api/edit` `{"action": "preview" | "commit" | "cancel", "edit": {…}}`,
//!   `POST /api/undo`, `POST /api/redo`, `POST /api/save` (body `{}`; anything else is a 400
//!   and nothing is saved): the new state;
//! - `POST /api/light {"direction": [x, y, z]}`: the key light (directional) points towards
//!   it — a scene change, undone like an edit and saved into `lights`; the new state;
//! - `POST /api/export {"what": "svg" | "gcode" | "glb"}`: [`Session::export`] writes that
//!   file for the committed edits (the path the scene names, else beside the scene file);
//!   `{"written": PATH}`.

use std::sync::Arc;
use std::time::Duration;

use serde::Deserialize;
use serde_json::json;

use super::http::{Request, Response};
use super::session::{Change, ExportKind, Session};

/// The longest request target (bytes).
pub const MAX_TARGET: usize = 2048;
/// How long `GET /api/state?after=V` waits for a newer solve.
pub const LONG_POLL: Duration = Duration::from_secs(10);

/// What every request thread shares.
pub struct Context {
    session: Arc<Session>,
    hosts: [String; 2],
    origins: [String; 2],
}

impl Context {
    /// The routes of `session` on 127.0.0.1:`port`.
    pub fn new(session: Arc<Session>, port: u16) -> Context {
        Context {
            session,
            hosts: [format!("127.0.0.1:{port}"), format!("localhost:{port}")],
            origins: [format!("http://127.0.0.1:{port}"), format!("http://localhost:{port}")],
        }
    }
}

/// A response before it is sent.
struct Reply {
    status: u16,
    content_type: &'static str,
    body: Vec<u8>,
}

impl Reply {
    fn ok(content_type: &'static str, body: Vec<u8>) -> Reply {
        Reply { status: 200, content_type, body }
    }
    fn json(value: &serde_json::Value) -> Reply {
        Reply::ok("application/json", value.to_string().into_bytes())
    }
    fn error(status: u16, message: impl Into<String>) -> Reply {
        let body = json!({ "error": message.into() }).to_string().into_bytes();
        Reply { status, content_type: "application/json", body }
    }
}

/// Answers one request; never panics on its content.
pub fn handle(ctx: &Context, rq: &Request) -> Response {
    let reply = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| route(ctx, rq)))
        .unwrap_or_else(|_| Reply::error(500, "internal error"));
    let is_html = reply.content_type.starts_with("text/html");
    let mut headers = vec![
        ("Content-Type", reply.content_type.to_string()),
        ("Cache-Control", "no-store".into()),
        ("X-Content-Type-Options", "nosniff".into()),
        ("X-Frame-Options", "DENY".into()),
        ("Referrer-Policy", "no-referrer".into()),
        ("Cross-Origin-Resource-Policy", "same-origin".into()),
    ];
    if is_html {
        headers.push((
            "Content-Security-Policy",
            "default-src 'none'; script-src 'self'; style-src 'self'; connect-src 'self'; \
             img-src 'self' data: blob:; base-uri 'none'; form-action 'none'; \
             frame-ancestors 'none'"
                .into(),
        ));
    }
    Response { status: reply.status, headers, body: reply.body }
}

fn route(ctx: &Context, rq: &Request) -> Reply {
    let target = rq.target.clone();
    if target.len() > MAX_TARGET {
        return Reply::error(414, "request target too long");
    }
    if !target.starts_with('/') || target.starts_with("//") {
        return Reply::error(400, "the request target must be a path");
    }
    let hosts = rq.values("Host");
    match hosts.as_slice() {
        [h] if ctx.hosts.iter().any(|o| o.eq_ignore_ascii_case(h)) => {}
        [] => return Reply::error(400, "no Host header"),
        _ => return Reply::error(403, "wrong Host: this server answers only its own address"),
    }
    let (path, query) = match target.split_once('?') {
        Some((p, q)) => (p.to_string(), q.to_string()),
        None => (target.clone(), String::new()),
    };
    match rq.method.as_str() {
        "GET" | "HEAD" => get(ctx, &path, &query),
        "POST" => {
            if let Some(r) = check_write(ctx, rq) {
                return r;
            }
            post(ctx, &path, &rq.body)
        }
        _ => Reply::error(405, "only GET, HEAD and POST"),
    }
}

/// The cross-origin rules of a write; `None` when it may go on.
fn check_write(ctx: &Context, rq: &Request) -> Option<Reply> {
    let origins = rq.values("Origin");
    match origins.as_slice() {
        [o] if ctx.origins.iter().any(|x| x.eq_ignore_ascii_case(o)) => {}
        _ => return Some(Reply::error(403, "cross-origin write refused (Origin)")),
    }
    if rq.values("Sec-Fetch-Site").iter().any(|s| !s.eq_ignore_ascii_case("same-origin")) {
        return Some(Reply::error(403, "cross-origin write refused (Sec-Fetch-Site)"));
    }
    let json_type = rq.values("Content-Type").iter().any(|t| {
        t.split(';').next().is_some_and(|m| m.trim().eq_ignore_ascii_case("application/json"))
    });
    if !json_type {
        return Some(Reply::error(415, "a write is application/json"));
    }
    None
}

/// The value of `key` in a query string of `k=v` pairs, as a number.
fn query_u64(query: &str, key: &str) -> Result<Option<u64>, Reply> {
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
        if k == key {
            return v
                .parse::<u64>()
                .map(Some)
                .map_err(|_| Reply::error(400, format!("{key}: expected a number")));
        }
    }
    Ok(None)
}

fn get(ctx: &Context, path: &str, query: &str) -> Reply {
    if let Some(a) = super::assets::find(path) {
        return Reply::ok(a.content_type, a.bytes.to_vec());
    }
    let s = &ctx.session;
    match path {
        "/api/info" => Reply::json(&super::info_json(s)),
        "/api/mesh" => {
            let id = match query_u64(query, "part") {
                Ok(id) => id.unwrap_or(0),
                Err(r) => return r,
            };
            match u32::try_from(id).ok().and_then(|id| s.part_by_id(id)) {
                Some(part) => {
                    Reply::ok("application/octet-stream", super::mesh_bytes(&part.prepared))
                }
                None => Reply::error(404, "no such part"),
            }
        }
        "/api/state" => {
            let after = match query_u64(query, "after") {
                Ok(a) => a,
                Err(r) => return r,
            };
            let view = s.view(after, LONG_POLL);
            Reply::json(&serde_json::to_value(view).unwrap_or_default())
        }
        "/api/strokes" => {
            let version = match query_u64(query, "version") {
                Ok(v) => v,
                Err(r) => return r,
            };
            let Some(solved) = s.solved(version) else {
                return Reply::error(409, "that version is not one of the last solved ones");
            };
            match s.traced(&solved) {
                Ok(t) => {
                    Reply::ok("application/octet-stream", super::strokes_bytes(t, solved.part.id))
                }
                Err(e) => Reply::error(400, e.to_string()),
            }
        }
        "/api/grain" | "/api/field.json" => {
            let version = match query_u64(query, "version") {
                Ok(v) => v,
                Err(r) => return r,
            };
            match s.solved(version) {
                Some(solved) if path == "/api/grain" => {
                    Reply::ok("application/octet-stream", super::grain_bytes(&solved))
                }
                Some(solved) => match s.field_json(&solved) {
                    Ok(b) => Reply::ok("application/json", b.to_vec()),
                    Err(e) => Reply::error(500, e.to_string()),
                },
                None => Reply::error(409, "that version is not one of the last solved ones"),
            }
        }
        // No icon: an empty answer instead of a 404 in the page's console.
        "/favicon.ico" => Reply { status: 204, content_type: "image/x-icon", body: Vec::new() },
        "/files/scene.json" => match crate::output::read_bounded(
            s.path(),
            crate::limits::MAX_SCENE_BYTES,
            "a scene file",
        ) {
            Ok(b) => Reply::ok("application/json", b),
            Err(e) => Reply::error(404, format!("the scene file: {e}")),
        },
        _ => Reply::error(404, "not found"),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightRequest {
    direction: [f64; 3],
}

/// `POST /api/save`'s body: `{}` (anything else is refused, and nothing is saved).
fn save_request(body: &[u8]) -> Result<(), String> {
    let map: serde_json::Map<String, serde_json::Value> =
        serde_json::from_slice(body).map_err(|e| e.to_string())?;
    match map.keys().next() {
        Some(k) => Err(format!("unknown field `{k}`")),
        None => Ok(()),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExportRequest {
    what: ExportKind,
}

/// `POST /api/export {"what": "svg" | "gcode" | "glb"}`: [`Session::export`]; a scene that
/// cannot make the file gets a 400 naming the key to add or fix, a failed write a 500.
fn export(s: &Session, body: &[u8]) -> Reply {
    let rq: ExportRequest = match serde_json::from_slice(body) {
        Ok(r) => r,
        Err(e) => return Reply::error(400, format!("the request: {e} (what: svg, gcode or glb)")),
    };
    match s.export(rq.what) {
        Ok(p) => Reply::json(&json!({ "written": p.display().to_string() })),
        Err(e @ crate::Error::Io { .. }) => Reply::error(500, format!("exporting: {e}")),
        Err(e) => Reply::error(400, e.to_string()),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EditRequest {
    action: String,
    #[serde(default)]
    edit: Option<serde_json::Value>,
}

fn post(ctx: &Context, path: &str, body: &[u8]) -> Reply {
    let s = &ctx.session;
    let change = match path {
        "/api/edit" => {
            let rq: EditRequest = match serde_json::from_slice(body) {
                Ok(r) => r,
                Err(e) => return Reply::error(400, format!("the request: {e}")),
            };
            let edit = match rq.edit.map(serde_json::from_value::<crate::edit::Edit>) {
                None => None,
                Some(Ok(e)) => Some(e),
                Some(Err(e)) => return Reply::error(400, format!("edit: {e}")),
            };
            match (rq.action.as_str(), edit) {
                ("preview", Some(e)) => Change::Preview(e),
                ("commit", Some(e)) => Change::Commit(e),
                ("cancel", None) => Change::Cancel,
                _ => {
                    return Reply::error(
                        400,
                        "action: \"preview\" or \"commit\" with an edit, or \"cancel\"",
                    )
                }
            }
        }
        "/api/export" => return export(s, body),
        "/api/light" => match serde_json::from_slice::<LightRequest>(body) {
            Ok(r) => Change::Light(r.direction),
            Err(e) => return Reply::error(400, format!("the request: {e}")),
        },
        "/api/undo" => Change::Undo,
        "/api/redo" => Change::Redo,
        "/api/save" => {
            if let Err(e) = save_request(body) {
                return Reply::error(400, format!("the request: {e} (/api/save takes {{}})"));
            }
            return match s.save() {
                Ok(p) => {
                    let view = s.view(None, Duration::ZERO);
                    Reply::json(&json!({ "saved": p.display().to_string(), "state": view }))
                }
                Err(e) => Reply::error(500, format!("saving: {e}")),
            };
        }
        _ => return Reply::error(404, "not found"),
    };
    match s.change(change) {
        Ok(_) => {
            Reply::json(&serde_json::to_value(s.view(None, Duration::ZERO)).unwrap_or_default())
        }
        Err(e) => Reply::error(400, e.to_string()),
    }
}
