//! The viewer's HTTP server: std::net, one connection at a time, on 127.0.0.1. Routes:
//! `GET /` the page; `GET /api/scene` the scene; `GET /api/simulate?duration=D` a run's
//! animation; `POST /api/drag` one drag move (a [`super::DragRequest`]).

use std::io::{self, BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::Duration;

use super::Viewer;

/// The largest request body read (a drag request is a few hundred bytes).
const MAX_BODY: usize = 1 << 20;

/// Answers requests until `requests` have been served (forever when `None`).
pub fn serve(
    listener: &TcpListener,
    viewer: &mut Viewer,
    requests: Option<usize>,
) -> io::Result<()> {
    for (served, stream) in listener.incoming().enumerate() {
        // A client that hangs up mid-request is its own problem, not the server's.
        let _ = handle(stream?, viewer);
        if requests.is_some_and(|n| served + 1 >= n) {
            break;
        }
    }
    Ok(())
}

struct Request {
    method: String,
    path: String,
    query: String,
    body: Vec<u8>,
}

fn read_request(stream: &TcpStream) -> io::Result<Request> {
    let mut reader = BufReader::new(stream);
    let mut line = String::new();
    reader.read_line(&mut line)?;
    let mut parts = line.split_whitespace();
    let method = parts.next().unwrap_or_default().to_string();
    let target = parts.next().unwrap_or("/");
    let (path, query) = target.split_once('?').unwrap_or((target, ""));
    let mut length = 0;
    loop {
        let mut header = String::new();
        if reader.read_line(&mut header)? == 0 || header.trim().is_empty() {
            break;
        }
        if let Some((name, value)) = header.split_once(':') {
            if name.trim().eq_ignore_ascii_case("content-length") {
                length = value.trim().parse().unwrap_or(0);
            }
        }
    }
    if length > MAX_BODY {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            "request too large",
        ));
    }
    let mut body = vec![0; length];
    reader.read_exact(&mut body)?;
    Ok(Request {
        method,
        path: path.to_string(),
        query: query.to_string(),
        body,
    })
}

/// How long a connection may stay silent. Browsers open connections ahead of need and may
/// leave them unused; one connection at a time, such a connection would hold up the others.
const IDLE: Duration = Duration::from_millis(300);

fn handle(mut stream: TcpStream, viewer: &mut Viewer) -> io::Result<()> {
    stream.set_read_timeout(Some(IDLE))?;
    let request = read_request(&stream)?;
    let (status, kind, body) = respond(&request, viewer);
    write!(
        stream,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    stream.write_all(body.as_bytes())?;
    stream.flush()
}

const JSON: &str = "application/json";

fn respond(request: &Request, viewer: &mut Viewer) -> (&'static str, &'static str, String) {
    let json = |result: Result<String, String>| match result {
        Ok(body) => ("200 OK", JSON, body),
        Err(message) => (
            "400 Bad Request",
            JSON,
            serde_json::json!({ "error": message }).to_string(),
        ),
    };
    match (request.method.as_str(), request.path.as_str()) {
        ("GET", "/" | "/index.html") => ("200 OK", "text/html; charset=utf-8", viewer.page(true)),
        ("GET", "/api/scene") => json(to_json(&viewer.scene)),
        ("GET", "/api/simulate") => json(
            duration(&request.query)
                .and_then(|d| viewer.simulate(d))
                .and_then(|animation| to_json(&animation)),
        ),
        ("POST", "/api/drag") => json(
            serde_json::from_slice(&request.body)
                .map_err(|e| format!("not a drag request: {e}"))
                .and_then(|drag| viewer.drag(&drag))
                .and_then(|response| to_json(&response)),
        ),
        _ => (
            "404 Not Found",
            "text/plain",
            format!("no page at {}\n", request.path),
        ),
    }
}

fn to_json(value: &impl serde::Serialize) -> Result<String, String> {
    serde_json::to_string(value).map_err(|e| e.to_string())
}

/// `duration=D` from the query, if there.
fn duration(query: &str) -> Result<Option<f64>, String> {
    let Some(value) = query
        .split('&')
        .find_map(|pair| pair.strip_prefix("duration="))
    else {
        return Ok(None);
    };
    match value.parse::<f64>() {
        Ok(d) if d.is_finite() && d > 0.0 => Ok(Some(d)),
        _ => Err(format!(
            "`duration` must be a positive number, not `{value}`"
        )),
    }
}
