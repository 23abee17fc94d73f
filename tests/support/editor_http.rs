//! The HTTP harness of the editor's server tests (tests/editor_server.rs,
//! tests/editor_light_tool.rs; included with `#[path]`): a real `grainline edit` on `--port 0`
//! and raw HTTP over TCP, no client library that might tidy a request up.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use serde_json::Value;

pub struct Server {
    pub child: Child,
    pub port: u16,
    pub dir: PathBuf,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        // Kept when the test failed, to look at.
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

/// The small scene of the tests: a cylinder brushed around, no edits.
pub const SCENE: &str = r#"{"mesh": "part.obj", "view": {"eye": [0, -300, 0]},
            "lights": [{"type": "directional", "direction": [0.3, -0.5, 1]}],
            "field": {"init": "uv", "symmetry": "line", "output": "field.json"}}"#;

/// The cylinder (32 × 8 quads) and the scene `text` in their own directory.
pub fn scene_dir_with(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("grainline-editor-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cylinder = grainline::generate::cylinder(30.0, 80.0, 32, 8);
    std::fs::write(dir.join("part.obj"), grainline::mesh::write::obj_string(&cylinder, "t"))
        .unwrap();
    std::fs::write(dir.join("scene.json"), text).unwrap();
    dir
}

pub fn start(name: &str) -> Server {
    start_with(name, SCENE)
}

pub fn start_with(name: &str, text: &str) -> Server {
    start_in(scene_dir_with(name, text))
}

/// The editor on `dir/scene.json`.
pub fn start_in(dir: PathBuf) -> Server {
    start_in_env(dir, &[])
}

/// The editor on `dir/scene.json` with these environment variables.
pub fn start_in_env(dir: PathBuf, env: &[(&str, &str)]) -> Server {
    let mut child = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "edit", "--port", "0"])
        .arg(dir.join("scene.json"))
        .envs(env.iter().copied())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let line = line.trim_end();
    let port = line
        .strip_prefix("http://127.0.0.1:")
        .and_then(|r| r.strip_suffix('/'))
        .and_then(|p| p.parse::<u16>().ok())
        .unwrap_or_else(|| panic!("first stdout line {line:?} is not http://127.0.0.1:PORT/"));
    assert_ne!(port, 0);
    Server { child, port, dir }
}

/// Sends `request` as is; the status code (None: the connection closed without one) and body.
pub fn raw(port: u16, request: &[u8]) -> (Option<u16>, String) {
    let (status, body) = raw_bytes(port, request);
    (status, String::from_utf8_lossy(&body).to_string())
}

/// [`raw`] with the body as bytes.
pub fn raw_bytes(port: u16, request: &[u8]) -> (Option<u16>, Vec<u8>) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let _ = s.write_all(request);
    let mut buf = Vec::new();
    let _ = s.read_to_end(&mut buf);
    let split = buf.windows(4).position(|w| w == b"\r\n\r\n");
    let (head, body) = match split {
        Some(i) => (String::from_utf8_lossy(&buf[..i]).to_string(), buf[i + 4..].to_vec()),
        None => (String::from_utf8_lossy(&buf).to_string(), Vec::new()),
    };
    let status = head.split_whitespace().nth(1).and_then(|c| c.parse().ok());
    let chunked = head
        .lines()
        .any(|l| l.to_ascii_lowercase().starts_with("transfer-encoding:") && l.contains("chunked"));
    let body = if chunked { dechunk(&body) } else { body };
    (status, body)
}

/// The body of a `Transfer-Encoding: chunked` response (RFC 9112 §7.1).
pub fn dechunk(mut rest: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    while let Some(i) = rest.windows(2).position(|w| w == b"\r\n") {
        let size = String::from_utf8_lossy(&rest[..i]).to_string();
        let n = usize::from_str_radix(size.split(';').next().unwrap().trim(), 16).unwrap();
        if n == 0 {
            break;
        }
        let after = &rest[i + 2..];
        out.extend_from_slice(&after[..n]);
        rest = &after[n + 2..];
    }
    out
}

pub fn get_with_host(port: u16, path: &str, host: &str) -> (Option<u16>, String) {
    raw(
        port,
        format!("GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n").as_bytes(),
    )
}

pub fn get(port: u16, path: &str) -> (Option<u16>, String) {
    get_with_host(port, path, &format!("127.0.0.1:{port}"))
}

pub fn post(
    port: u16,
    path: &str,
    headers: &[(&str, String)],
    body: &str,
) -> (Option<u16>, String) {
    let mut rq = format!("POST {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n");
    for (k, v) in headers {
        rq.push_str(&format!("{k}: {v}\r\n"));
    }
    rq.push_str(&format!("Content-Length: {}\r\n\r\n{body}", body.len()));
    raw(port, rq.as_bytes())
}

pub fn own(port: u16) -> Vec<(&'static str, String)> {
    vec![
        ("Origin", format!("http://127.0.0.1:{port}")),
        ("Content-Type", "application/json".to_string()),
    ]
}

pub fn state(port: u16) -> Value {
    let (s, b) = get(port, "/api/state");
    assert_eq!(s, Some(200), "{b}");
    serde_json::from_str(&b).unwrap()
}

pub fn solved(port: u16) -> u64 {
    let mut after = 0;
    for _ in 0..60 {
        let st: Value =
            serde_json::from_str(&get(port, &format!("/api/state?after={after}")).1).unwrap();
        if let Some(e) = st["error"].as_array() {
            assert!(e[0] != st["version"], "the solve failed: {}", e[1]);
        }
        if st["solved_version"] == st["version"] {
            return st["version"].as_u64().unwrap();
        }
        after = st["solved_version"].as_u64().unwrap_or(0);
    }
    panic!("never solved");
}

pub fn get_bytes(port: u16, path: &str) -> (Option<u16>, Vec<u8>) {
    let host = format!("127.0.0.1:{port}");
    raw_bytes(
        port,
        format!("GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n").as_bytes(),
    )
}

/// Saves the session's scene (`POST /api/save`) and runs `grainline run` on it; the scene's path.
pub fn save_and_run(srv: &Server) -> PathBuf {
    let p = srv.port;
    assert_eq!(post(p, "/api/save", &own(p), "{}").0, Some(200));
    let scene = srv.dir.join("scene.json");
    let run = Command::new(env!("CARGO_BIN_EXE_grainline"))
        .args(["--quiet", "run"])
        .arg(&scene)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    scene
}
