//! The viewer's HTTP server: std::net, on 127.0.0.1. Routes: `GET /` the page;
//! `GET /api/scene` the scene; `GET /api/simulate?duration=D` a run's animation;
//! `POST /api/drag` one drag move (a [`super::DragRequest`]).
//!
//! Each connection is read and answered on a thread of its own (at most `MAX_CONNECTIONS` at
//! once, each given `IDLE` to send its request), so a silent connection (browsers open some
//! ahead of need) holds up no other. The requests themselves are computed one at a time on the
//! thread that owns the [`Viewer`] (its names are interned per thread), each bounded in time:
//! a served simulation makes at most `MAX_FRAMES` outputs in at most `MAX_STEPS` steps.

use std::io::{self, BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use super::Viewer;
use crate::prepare::settings::SettingsChanges;

/// The largest request body read (a drag request is a few hundred bytes).
const MAX_BODY: usize = 1 << 20;
/// The most connections read or answered at once; further ones are told to come back (503).
pub const MAX_CONNECTIONS: usize = 256;
/// How long a connection may stay silent while sending its request, or not take its answer.
pub const IDLE: Duration = Duration::from_secs(5);
/// The most outputs (animation frames) of a served simulation.
pub const MAX_FRAMES: f64 = 100_000.0;
/// The most step attempts of a served simulation (a few seconds of the slowest mechanisms).
pub const MAX_STEPS: usize = 200_000;

/// A request read from a connection, and where its answer goes.
struct Job {
    request: Request,
    answer: mpsc::Sender<Response>,
}

type Response = (&'static str, &'static str, String);

/// Answers requests until `requests` have been answered (forever when `None`).
pub fn serve(
    listener: &TcpListener,
    viewer: &mut Viewer,
    requests: Option<usize>,
) -> io::Result<()> {
    let (jobs, queue) = mpsc::channel::<Job>();
    let stopping = Arc::new(AtomicBool::new(false));
    let accepting = listener.try_clone()?;
    let acceptor = {
        let stopping = Arc::clone(&stopping);
        std::thread::spawn(move || accept(&accepting, &jobs, &stopping))
    };
    for (answered, job) in queue.iter().enumerate() {
        // A client that hung up is its own problem, not the server's.
        let _ = job.answer.send(respond(&job.request, viewer));
        if requests.is_some_and(|n| answered + 1 >= n) {
            break;
        }
    }
    // Wake the acceptor from `accept` so that it sees it is to stop.
    stopping.store(true, Ordering::SeqCst);
    drop(queue);
    let _ = TcpStream::connect(listener.local_addr()?);
    acceptor
        .join()
        .map_err(|_| io::Error::other("the connection acceptor panicked"))?
}

/// Accepts connections, each read and answered on a thread of its own.
fn accept(
    listener: &TcpListener,
    jobs: &mpsc::Sender<Job>,
    stopping: &AtomicBool,
) -> io::Result<()> {
    let open = Arc::new(AtomicUsize::new(0));
    for stream in listener.incoming() {
        if stopping.load(Ordering::SeqCst) {
            break;
        }
        let Ok(mut stream) = stream else { continue };
        if open.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
            open.fetch_sub(1, Ordering::SeqCst);
            let _ = stream.set_write_timeout(Some(IDLE));
            let body = "too many connections at once; try again\n";
            let _ = write_response(
                &mut stream,
                ("503 Service Unavailable", "text/plain", body.to_string()),
            );
            continue;
        }
        let (jobs, open) = (jobs.clone(), Arc::clone(&open));
        std::thread::spawn(move || {
            let _ = converse(stream, &jobs);
            open.fetch_sub(1, Ordering::SeqCst);
        });
    }
    Ok(())
}

/// Reads one request, has it answered by the viewer's thread, and writes the answer.
fn converse(mut stream: TcpStream, jobs: &mpsc::Sender<Job>) -> io::Result<()> {
    stream.set_read_timeout(Some(IDLE))?;
    stream.set_write_timeout(Some(IDLE))?;
    let request = read_request(&stream)?;
    let (answer, answered) = mpsc::channel();
    jobs.send(Job { request, answer })
        .map_err(|_| io::Error::other("the server is stopping"))?;
    let response = answered
        .recv()
        .map_err(|_| io::Error::other("the server is stopping"))?;
    write_response(&mut stream, response)
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

fn write_response(stream: &mut TcpStream, (status, kind, body): Response) -> io::Result<()> {
    write!(
        stream,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    stream.write_all(body.as_bytes())?;
    stream.flush()
}

const JSON: &str = "application/json";

fn respond(request: &Request, viewer: &mut Viewer) -> Response {
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
                .and_then(|d| bounded_simulation(viewer, d))
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

/// The settings of a served simulation of `duration` (else the program's): refused beyond
/// `MAX_FRAMES` outputs, stopped with a failure after `MAX_STEPS` step attempts, so that no
/// request holds the server for long.
fn bounded_simulation(
    viewer: &mut Viewer,
    duration: Option<f64>,
) -> Result<super::scene::Animation, String> {
    let settings = &viewer.prepared.settings;
    let duration = duration.unwrap_or(settings.duration);
    let frames = duration / settings.output;
    if frames > MAX_FRAMES {
        return Err(format!(
            "a simulation of {duration} s with an output every {} s makes {frames:.0} frames; the viewer runs at most {MAX_FRAMES} (a longer run: `lsdc simulate --format json`, then `lsdc view --results`)",
            settings.output
        ));
    }
    viewer.simulate_with(&SettingsChanges {
        duration: Some(duration),
        max_steps: Some(settings.max_steps.min(MAX_STEPS)),
        ..SettingsChanges::default()
    })
}
