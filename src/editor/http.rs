//! The editor's HTTP/1.1 connections, bounded in every dimension a client controls.
//!
//! One request per connection (every response says `Connection: close`), read by a thread of
//! its own, with:
//! - at most [`MAX_CONNECTIONS`] connections handled at once: one more is answered `503` at
//!   once and closed, on the accepting thread, so half-open or stalled clients cannot grow the
//!   threads or the memory (200 stalled connections used to keep 211 threads and grow the
//!   process from 71 to 259 MB);
//! - the request line and headers within [`HEAD_TIMEOUT`] in all (not per read: a client that
//!   sends a byte every few seconds is cut off too) and [`MAX_HEAD`] bytes: else `408` / `431`;
//! - a body announced by `Content-Length` (no chunked uploads: `411`), at most
//!   [`MAX_BODY`] (`413`, decided before reading), read within
//!   [`BODY_TIMEOUT`];
//! - writes that give up after [`WRITE_TIMEOUT`] on a client that does not read;
//! - work cancelled when the client goes: the handler runs on a thread of its own inside a
//!   [`Cancel`] scope while the connection's thread looks at the socket every
//!   [`WATCH_INTERVAL`]; when the client has closed the connection (end of stream, or a reset)
//!   the flag is set, the handler's work stops at its next check point ([`crate::cancel`]),
//!   nothing is answered, and the slot is given back as soon as the handler has returned. A
//!   client that half-closes its side after the request is taken as gone too (as Go's
//!   `net/http` does); bytes sent after the request are read and dropped (one request per
//!   connection).

use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use crate::cancel::Cancel;

/// The largest request body read (bytes).
pub const MAX_BODY: usize = 1 << 20;
/// Most connections handled at once; more are answered 503 and closed.
pub const MAX_CONNECTIONS: usize = 32;
/// Time for the request line and headers, in all.
pub const HEAD_TIMEOUT: Duration = Duration::from_secs(10);
/// Time for the body, in all.
pub const BODY_TIMEOUT: Duration = Duration::from_secs(30);
/// Time a response's write may block.
pub const WRITE_TIMEOUT: Duration = Duration::from_secs(30);
/// Most bytes of the request line and headers.
pub const MAX_HEAD: usize = 16 << 10;
/// How often the socket of a request being answered is looked at for a client that left.
pub const WATCH_INTERVAL: Duration = Duration::from_millis(100);

/// A request as read: method, target, headers in order, body.
#[derive(Clone, Debug, Default)]
pub struct Request {
    /// `GET`, `POST`, … as sent.
    pub method: String,
    /// The request target as sent (`/api/state?after=3`).
    pub target: String,
    /// Header names and values, in order (values trimmed).
    pub headers: Vec<(String, String)>,
    /// The body (empty without `Content-Length`).
    pub body: Vec<u8>,
}

impl Request {
    /// The values of the headers named `name` (case-insensitive).
    pub fn values(&self, name: &str) -> Vec<&str> {
        self.headers
            .iter()
            .filter(|(k, _)| k.eq_ignore_ascii_case(name))
            .map(|(_, v)| v.as_str())
            .collect()
    }
}

/// A response: status, headers (beyond `Content-Length` and `Connection`), body.
#[derive(Clone, Debug)]
pub struct Response {
    /// The status code.
    pub status: u16,
    /// Headers.
    pub headers: Vec<(&'static str, String)>,
    /// The body.
    pub body: Vec<u8>,
}

impl Response {
    /// A JSON `{"error": message}` answer with `status`.
    pub fn error(status: u16, message: &str) -> Response {
        let body = serde_json::json!({ "error": message }).to_string().into_bytes();
        Response { status, headers: vec![("Content-Type", "application/json".into())], body }
    }
}

/// A connection slot, given back when dropped.
struct Slot(Arc<AtomicUsize>);

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Accepts connections on `listener` for ever, each answered by `handler` on a thread of its
/// own, at most [`MAX_CONNECTIONS`] at once.
pub fn serve<F>(listener: TcpListener, handler: F)
where
    F: Fn(&Request) -> Response + Send + Sync + 'static,
{
    let handler = Arc::new(handler);
    let active = Arc::new(AtomicUsize::new(0));
    for stream in listener.incoming() {
        let Ok(stream) = stream else { continue };
        if active.fetch_add(1, Ordering::AcqRel) >= MAX_CONNECTIONS {
            active.fetch_sub(1, Ordering::AcqRel);
            refuse(stream);
            continue;
        }
        let slot = Slot(Arc::clone(&active));
        let handler = Arc::clone(&handler);
        let spawned = std::thread::Builder::new()
            .name("editor-http".into())
            .spawn(move || connection(stream, &*handler, slot));
        // A thread that cannot start drops its slot and its stream (the client sees a close).
        drop(spawned);
    }
}

/// Answers a connection beyond the bound 503 without waiting on it (on the accepting thread):
/// what it has sent is read past without blocking, so the close does not reset the answer.
fn refuse(mut stream: TcpStream) {
    let busy = format!("busy: {MAX_CONNECTIONS} connections are open; try again");
    let r = Response::error(503, &busy);
    let head = format!(
        "HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\n\
         Content-Length: {}\r\nConnection: close\r\n\r\n",
        r.body.len()
    );
    let _ = stream.set_nonblocking(true);
    let mut sink = [0u8; 4096];
    while matches!(stream.read(&mut sink), Ok(n) if n > 0) {}
    let _ = stream.write_all(&[head.as_bytes(), &r.body].concat());
    let _ = stream.shutdown(Shutdown::Write);
}

/// Reads one request, answers it (unless the client left meanwhile), closes.
fn connection<F: Fn(&Request) -> Response + Sync>(stream: TcpStream, handler: &F, _slot: Slot) {
    let _ = stream.set_write_timeout(Some(WRITE_TIMEOUT));
    let response = match read_request(&stream) {
        Ok(rq) => {
            let head = rq.method == "HEAD";
            if let Some(r) = answer_watching(&stream, handler, &rq) {
                respond(&stream, &r, head);
            }
            return;
        }
        Err(Some(r)) => r,
        Err(None) => return,
    };
    respond(&stream, &response, false);
}

/// Runs `handler` on a thread of its own inside a [`Cancel`] scope and watches `stream`
/// meanwhile; `None` when the client left (the work was cancelled and has returned).
fn answer_watching<F: Fn(&Request) -> Response + Sync>(
    stream: &TcpStream,
    handler: &F,
    rq: &Request,
) -> Option<Response> {
    let cancel = Cancel::new();
    let cancel = &cancel;
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        let work =
            std::thread::Builder::new().name("editor-work".into()).spawn_scoped(scope, move || {
                let r = cancel.scope(|| handler(rq));
                let _ = tx.send(r);
            });
        if work.is_err() {
            return Some(Response::error(503, "busy: cannot start a thread for the request"));
        }
        let _ = stream.set_nonblocking(true);
        let answer = loop {
            match rx.recv_timeout(WATCH_INTERVAL) {
                Ok(r) => break Some(r),
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    break Some(Response::error(500, "internal error"))
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
            }
            if client_gone(stream) {
                cancel.cancel();
                // The scope joins the handler: it returns at its next check point.
                break None;
            }
        };
        let _ = stream.set_nonblocking(false);
        answer
    })
}

/// Whether the client of a non-blocking `stream` has closed it (end of stream or an error);
/// bytes it still sends are read and dropped.
fn client_gone(mut stream: &TcpStream) -> bool {
    let mut sink = [0u8; 4096];
    // A bounded number of reads: a client that keeps sending is looked at again next time.
    for _ in 0..16 {
        match stream.read(&mut sink) {
            Ok(0) => return true,
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return false,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => return true,
        }
    }
    false
}

/// Writes `r` (without its body for a HEAD) and closes the connection.
fn respond(mut stream: &TcpStream, r: &Response, head: bool) {
    let mut out = format!("HTTP/1.1 {} {}\r\n", r.status, reason(r.status));
    for (k, v) in &r.headers {
        out += &format!("{k}: {v}\r\n");
    }
    out += &format!("Content-Length: {}\r\nConnection: close\r\n\r\n", r.body.len());
    let mut bytes = out.into_bytes();
    if !head {
        bytes.extend_from_slice(&r.body);
    }
    let _ = stream.write_all(&bytes);
    let _ = stream.flush();
    let _ = stream.shutdown(Shutdown::Write);
    // Read what the client still sends for a moment, so the close does not reset the answer.
    let _ = stream.set_read_timeout(Some(Duration::from_millis(200)));
    let mut sink = [0u8; 4096];
    let deadline = Instant::now() + Duration::from_millis(500);
    while Instant::now() < deadline && matches!(stream.read(&mut sink), Ok(n) if n > 0) {}
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        204 => "No Content",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        409 => "Conflict",
        411 => "Length Required",
        413 => "Content Too Large",
        414 => "URI Too Long",
        415 => "Unsupported Media Type",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        _ => "Error",
    }
}

/// Reads into `buf` until `done(buf)` or the deadline; `Err(None)` when the client closed
/// before sending anything.
fn read_until(
    mut stream: &TcpStream,
    buf: &mut Vec<u8>,
    deadline: Instant,
    limit: usize,
    done: impl Fn(&[u8]) -> bool,
) -> Result<(), Option<Response>> {
    let mut chunk = [0u8; 8192];
    while !done(buf) {
        let now = Instant::now();
        if now >= deadline {
            return Err(Some(Response::error(408, "the request took too long to arrive")));
        }
        let _ = stream.set_read_timeout(Some(deadline - now));
        match stream.read(&mut chunk) {
            Ok(0) if buf.is_empty() => return Err(None),
            Ok(0) => return Err(Some(Response::error(400, "the request ends early"))),
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) if buf.is_empty() => return Err(None),
            Err(_) => {
                return Err(Some(Response::error(408, "the request took too long to arrive")))
            }
        }
        if buf.len() > limit {
            return Err(Some(Response::error(431, "the request's headers are too large")));
        }
    }
    Ok(())
}

/// The end of the head (after its blank line) in `buf`, if it is there.
fn head_end(buf: &[u8]) -> Option<usize> {
    buf.windows(4).position(|w| w == b"\r\n\r\n").map(|i| i + 4)
}

/// Reads one request within the bounds, or the answer refusing it (`None`: nothing to answer).
fn read_request(stream: &TcpStream) -> Result<Request, Option<Response>> {
    let mut buf = Vec::new();
    let deadline = Instant::now() + HEAD_TIMEOUT;
    read_until(stream, &mut buf, deadline, MAX_HEAD, |b| head_end(b).is_some())?;
    let end = head_end(&buf).unwrap_or(buf.len());
    let mut rq = parse_head(&buf[..end - 4]).map_err(|m| Some(Response::error(400, m)))?;
    if rq.values("Transfer-Encoding").iter().any(|v| !v.eq_ignore_ascii_case("identity")) {
        return Err(Some(Response::error(
            411,
            "a body needs a Content-Length (no chunked bodies)",
        )));
    }
    let length = match rq.values("Content-Length").as_slice() {
        [] => 0,
        [v] => v.parse::<usize>().map_err(|_| Some(Response::error(400, "bad Content-Length")))?,
        _ => return Err(Some(Response::error(400, "several Content-Length headers"))),
    };
    if length > MAX_BODY {
        return Err(Some(Response::error(413, &format!("a body is at most {MAX_BODY} bytes"))));
    }
    let mut body = buf.split_off(end);
    let deadline = Instant::now() + BODY_TIMEOUT;
    read_until(stream, &mut body, deadline, MAX_BODY + MAX_HEAD, |b| b.len() >= length)?;
    body.truncate(length);
    rq.body = body;
    Ok(rq)
}

/// The request line and headers (without the blank line).
fn parse_head(head: &[u8]) -> Result<Request, &'static str> {
    let text = std::str::from_utf8(head).map_err(|_| "the request's head is not text")?;
    let mut lines = text.split("\r\n");
    let line = lines.next().unwrap_or("");
    let parts: Vec<&str> = line.split(' ').collect();
    let [method, target, version] = parts.as_slice() else {
        return Err("the request line is not `METHOD TARGET HTTP/1.1`");
    };
    let token = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphabetic());
    if !token(method) || target.is_empty() || !version.starts_with("HTTP/1.") {
        return Err("the request line is not `METHOD TARGET HTTP/1.1`");
    }
    let mut headers = Vec::new();
    for l in lines {
        let Some((k, v)) = l.split_once(':') else { return Err("a header line without `:`") };
        let name_ok = !k.is_empty() && k.bytes().all(|b| b.is_ascii_graphic() && b != b':');
        if !name_ok || headers.len() >= 100 {
            return Err("a malformed header, or more than 100");
        }
        headers.push((k.to_string(), v.trim().to_string()));
    }
    Ok(Request { method: method.to_string(), target: target.to_string(), headers, body: vec![] })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heads_are_parsed_strictly() {
        let rq = parse_head(b"GET /a?b=1 HTTP/1.1\r\nHost: x:1\r\nX-Y:  z ").unwrap();
        assert_eq!((rq.method.as_str(), rq.target.as_str()), ("GET", "/a?b=1"));
        assert_eq!(rq.values("host"), ["x:1"]);
        assert_eq!(rq.values("x-y"), ["z"]);
        for bad in
            [&b"GET"[..], b"GET / HTTP/1.1\r\nBroken", b"\x00\x01 / HTTP/1.1", b"G T / HTTP/1.1"]
        {
            assert!(parse_head(bad).is_err(), "{:?}", String::from_utf8_lossy(bad));
        }
    }
}
