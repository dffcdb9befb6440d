//! The preview as a local web page that refreshes itself, for a browser next to the editor.
//!
//! Owns: a tiny HTTP/1.1 server on 127.0.0.1 only (never another interface), serving the
//! page, the latest good sheet and the latest state (error text of a broken save or of a
//! sample whose scene fails, and the outcome of the scene pass). It is
//! bounded whatever the clients do: one thread, at most `MAX_CONNECTIONS` connections, a
//! deadline for each request and each response, a size limit on requests. Must not touch:
//! files (it serves what the watcher hands it from memory) or anything but loopback.

use anyhow::{Context, Result};
use serde_json::json;
use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How long a connection may take to send its whole request (not per read: a client trickling
/// one byte at a time must not hold its place forever).
const REQUEST_TIMEOUT: Duration = Duration::from_secs(5);
/// How long a client may take to read its whole response.
const RESPONSE_TIMEOUT: Duration = Duration::from_secs(10);
/// Requests are a line and a few headers; anything longer is not for us.
const MAX_REQUEST: usize = 16 * 1024;
/// Connections held at once. One thread serves them all, so silent or slow clients cost a
/// slot each, never a thread; when the slots are full the oldest unfinished request makes way
/// for the newcomer, so a flood of idle clients cannot keep a browser's request out.
const MAX_CONNECTIONS: usize = 64;
/// Pause of the serving loop when no connection moved (it only polls while some are open).
const IDLE_PAUSE: Duration = Duration::from_millis(2);

const PAGE: &str = r#"<!doctype html>
<html><head><meta charset="utf-8"><title>shmgen preview</title>
<style>
body { background: #1e1e1e; color: #ddd; font: 14px ui-monospace, monospace; margin: 12px; }
#error { color: #ff8a80; white-space: pre-wrap; }
#sheet { max-width: 100%; }
</style></head>
<body>
<div id="status">waiting for the first preview…</div>
<div id="scenes"></div>
<pre id="error"></pre>
<img id="sheet" alt="">
<script>
// Polls the watcher's state; reloads the sheet only when a new preview was written.
let seen = null;
async function poll() {
  try {
    const state = await (await fetch("state", { cache: "no-store" })).json();
    document.getElementById("error").textContent = state.error || "";
    document.getElementById("scenes").textContent = state.scenes || "";
    if (state.preview > 0) {
      document.getElementById("status").textContent = state.summary;
      if (state.preview !== seen) {
        seen = state.preview;
        document.getElementById("sheet").src = "preview.png?n=" + seen;
      }
    }
  } catch (e) {
    document.getElementById("status").textContent = "the watcher is not running";
  }
  setTimeout(poll, 400);
}
poll();
</script>
</body></html>
"#;

/// What the page shows: the latest good sheet and the error of the latest save, if broken.
#[derive(Default)]
struct State {
    png: Option<Arc<Vec<u8>>>,
    /// Counts good previews, so the page reloads the image only when it changed.
    preview: u64,
    summary: String,
    error: Option<String>,
    /// What the background pass over every sample's scene found, once it has.
    scenes: Option<String>,
}

/// A running server; the watcher publishes into it.
pub struct Server {
    state: Arc<Mutex<State>>,
    pub url: String,
}

impl Server {
    /// Listens on 127.0.0.1:`port` (0 picks a free port) and serves in the background.
    pub fn start(port: u16) -> Result<Server> {
        let listener = TcpListener::bind(SocketAddr::from((Ipv4Addr::LOCALHOST, port)))
            .with_context(|| format!("--serve {port}: cannot listen on 127.0.0.1:{port}"))?;
        let url = format!("http://{}/", listener.local_addr()?);
        let state = Arc::new(Mutex::new(State::default()));
        let shared = state.clone();
        std::thread::Builder::new()
            .name("preview-server".into())
            .spawn(move || {
                if let Err(e) = serve(&listener, &shared) {
                    eprintln!("the preview server stopped: {e}");
                }
            })
            .context("--serve: cannot start the server's thread")?;
        Ok(Server { state, url })
    }

    pub fn publish(&self, png: Vec<u8>, summary: String) {
        let mut state = self.state.lock().unwrap();
        state.png = Some(Arc::new(png));
        state.preview += 1;
        state.summary = summary;
        state.error = None;
        state.scenes = None;
    }

    pub fn fail(&self, error: String) {
        self.state.lock().unwrap().error = Some(error);
    }

    /// The scene pass over every sample of the latest sheet passed.
    pub fn scenes_checked(&self, line: String) {
        self.state.lock().unwrap().scenes = Some(line);
    }
}

/// One connection between accept and close.
struct Connection {
    stream: TcpStream,
    phase: Phase,
    /// When it is dropped if not finished: the whole request, then the whole response, each
    /// has its time, however the bytes trickle.
    deadline: Instant,
}

enum Phase {
    /// Reading the request head; the bytes so far.
    Request(Vec<u8>),
    /// Writing the response; its bytes and how many went out.
    Response { bytes: Vec<u8>, sent: usize },
}

/// What a round did to a connection.
#[derive(PartialEq)]
enum Step {
    Waiting,
    Moved,
    Done,
}

/// Serves every connection from this one thread: non-blocking sockets polled in rounds, so
/// the thread count never depends on the clients. Sleeps in `accept` while none is open.
fn serve(listener: &TcpListener, state: &Mutex<State>) -> std::io::Result<()> {
    let mut open: Vec<Connection> = Vec::new();
    loop {
        let mut moved = open.is_empty() && wait_for_client(listener, &mut open)?;
        moved |= accept_waiting(listener, &mut open);
        let now = Instant::now();
        open.retain_mut(|connection| {
            let step = connection.advance(state);
            moved |= step != Step::Waiting;
            step != Step::Done && now < connection.deadline
        });
        if !moved {
            std::thread::sleep(IDLE_PAUSE);
        }
    }
}

/// Blocks until a client connects and admits it; false if the accept failed (it is retried).
fn wait_for_client(listener: &TcpListener, open: &mut Vec<Connection>) -> std::io::Result<bool> {
    listener.set_nonblocking(false)?;
    let accepted = listener.accept();
    listener.set_nonblocking(true)?;
    Ok(match accepted {
        Ok((stream, _)) => admit(open, stream),
        Err(_) => false,
    })
}

/// Admits the clients waiting to be accepted, at most half the slots a round so that each
/// newcomer is read at least once before later ones can push it out.
fn accept_waiting(listener: &TcpListener, open: &mut Vec<Connection>) -> bool {
    let mut any = false;
    for _ in 0..MAX_CONNECTIONS / 2 {
        // WouldBlock: nobody waiting; any other error (a client gone before its accept, no
        // file descriptor left) is retried next round.
        let Ok((stream, _)) = listener.accept() else {
            break;
        };
        any |= admit(open, stream);
    }
    any
}

/// Adds a connection; when every slot is taken, the oldest one still sending its request
/// (else the oldest being answered) is closed to make room. `open` is in arrival order.
fn admit(open: &mut Vec<Connection>, stream: TcpStream) -> bool {
    if stream.set_nonblocking(true).is_err() {
        return false;
    }
    if open.len() >= MAX_CONNECTIONS {
        let oldest_request = open
            .iter()
            .position(|c| matches!(c.phase, Phase::Request(_)));
        open.remove(oldest_request.unwrap_or(0));
    }
    open.push(Connection {
        stream,
        phase: Phase::Request(Vec::new()),
        deadline: Instant::now() + REQUEST_TIMEOUT,
    });
    true
}

impl Connection {
    /// Reads or writes what the socket takes now, without blocking. A request just completed
    /// is answered in the same round.
    fn advance(&mut self, state: &Mutex<State>) -> Step {
        let head = match &mut self.phase {
            Phase::Response { bytes, sent } => {
                return write_available(&mut self.stream, bytes, sent);
            }
            Phase::Request(head) => head,
        };
        match read_available(&mut self.stream, head) {
            Err(_) => Step::Done,
            Ok(None) => Step::Waiting,
            Ok(Some(false)) => Step::Moved,
            Ok(Some(true)) => {
                let bytes = answer(head, state);
                let mut sent = 0;
                let step = write_available(&mut self.stream, &bytes, &mut sent);
                self.phase = Phase::Response { bytes, sent };
                self.deadline = Instant::now() + RESPONSE_TIMEOUT;
                if step == Step::Done {
                    Step::Done
                } else {
                    Step::Moved
                }
            }
        }
    }
}

/// Appends what the socket holds to `head`: None if nothing came, else whether the head is
/// complete (blank line seen, or the size limit reached: `answer` refuses it). A client that
/// hangs up before finishing its request is an error: there is nobody to answer.
fn read_available(stream: &mut TcpStream, head: &mut Vec<u8>) -> std::io::Result<Option<bool>> {
    let before = head.len();
    let mut buf = [0u8; 1024];
    while !head_complete(head) && head.len() < MAX_REQUEST {
        match stream.read(&mut buf) {
            Ok(0) => return Err(ErrorKind::UnexpectedEof.into()),
            Ok(n) => head.extend_from_slice(&buf[..n.min(MAX_REQUEST - head.len())]),
            Err(e) if e.kind() == ErrorKind::WouldBlock => break,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    if head.len() == before {
        return Ok(None);
    }
    Ok(Some(head_complete(head) || head.len() >= MAX_REQUEST))
}

fn head_complete(head: &[u8]) -> bool {
    head.windows(4).any(|w| w == b"\r\n\r\n")
}

/// Writes what the socket takes of `bytes[*sent..]`.
fn write_available(stream: &mut TcpStream, bytes: &[u8], sent: &mut usize) -> Step {
    let before = *sent;
    while *sent < bytes.len() {
        match stream.write(&bytes[*sent..]) {
            Ok(0) => return Step::Done,
            Ok(n) => *sent += n,
            Err(e) if e.kind() == ErrorKind::WouldBlock => break,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(_) => return Step::Done,
        }
    }
    if *sent == bytes.len() {
        Step::Done
    } else if *sent > before {
        Step::Moved
    } else {
        Step::Waiting
    }
}

/// The whole response (status line, headers, body) to a request head.
fn answer(head: &[u8], state: &Mutex<State>) -> Vec<u8> {
    let (status, kind, body) = if head_complete(head) {
        route(&String::from_utf8_lossy(head), state)
    } else {
        (
            "431 Request Header Fields Too Large",
            "text/plain; charset=utf-8",
            format!("requests are limited to {MAX_REQUEST} bytes\n").into_bytes(),
        )
    };
    let mut bytes = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )
    .into_bytes();
    bytes.extend_from_slice(&body);
    bytes
}

/// (status, content type, body) for a request.
fn route(head: &str, state: &Mutex<State>) -> (&'static str, &'static str, Vec<u8>) {
    const TEXT: &str = "text/plain; charset=utf-8";
    let mut words = head.split_whitespace();
    let (method, target) = (words.next().unwrap_or(""), words.next().unwrap_or(""));
    if method != "GET" {
        return ("405 Method Not Allowed", TEXT, b"GET only\n".to_vec());
    }
    if !loopback_host(head) {
        // A page elsewhere could point a DNS name at 127.0.0.1; only loopback names are served.
        return (
            "403 Forbidden",
            TEXT,
            b"loopback host names only\n".to_vec(),
        );
    }
    let path = target.split('?').next().unwrap_or("");
    let state = state.lock().unwrap();
    match path {
        "/" | "/index.html" => ("200 OK", "text/html; charset=utf-8", PAGE.into()),
        "/state" => {
            let body = json!({
                "preview": state.preview,
                "summary": state.summary,
                "error": state.error,
                "scenes": state.scenes,
            });
            ("200 OK", "application/json", body.to_string().into_bytes())
        }
        "/preview.png" => match &state.png {
            Some(png) => ("200 OK", "image/png", png.to_vec()),
            None => ("404 Not Found", TEXT, b"no preview yet\n".to_vec()),
        },
        _ => ("404 Not Found", TEXT, b"not found\n".to_vec()),
    }
}

/// Whether the Host header (if any) names this machine's loopback.
fn loopback_host(head: &str) -> bool {
    let host = head.lines().find_map(|line| {
        let (name, value) = line.split_once(':')?;
        name.eq_ignore_ascii_case("host").then(|| value.trim())
    });
    let Some(host) = host else {
        return true;
    };
    let name = match host.strip_prefix('[') {
        Some(v6) => v6.split(']').next().unwrap_or(""),
        None => host.split(':').next().unwrap_or(""),
    };
    matches!(name, "127.0.0.1" | "localhost" | "::1")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_loopback_host_names_are_served() {
        for ok in [
            "GET / HTTP/1.1\r\nHost: 127.0.0.1:8080\r\n\r\n",
            "GET / HTTP/1.1\r\nhost: localhost\r\n\r\n",
            "GET / HTTP/1.1\r\nHost: [::1]:9\r\n\r\n",
            "GET / HTTP/1.0\r\n\r\n",
        ] {
            assert!(loopback_host(ok), "{ok}");
        }
        assert!(!loopback_host(
            "GET / HTTP/1.1\r\nHost: evil.example:8080\r\n\r\n"
        ));
    }

    #[test]
    fn routes() {
        let state = Mutex::new(State::default());
        let get = |path: &str, state: &Mutex<State>| {
            route(
                &format!("GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"),
                state,
            )
        };
        assert!(get("/", &state).0.starts_with("200"));
        assert!(get("/preview.png", &state).0.starts_with("404"));
        assert!(get("/nope", &state).0.starts_with("404"));
        assert!(
            route("POST / HTTP/1.1\r\n\r\n", &state)
                .0
                .starts_with("405")
        );
        state.lock().unwrap().png = Some(Arc::new(vec![1, 2, 3]));
        assert_eq!(get("/preview.png?n=1", &state).2, vec![1, 2, 3]);
    }

    #[test]
    fn a_client_trickling_its_request_is_let_go_when_its_time_is_up() {
        let server = Server::start(0).unwrap();
        let address = server
            .url
            .trim_start_matches("http://")
            .trim_end_matches('/');
        let mut stream = TcpStream::connect(address).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_millis(200)))
            .unwrap();
        let start = Instant::now();
        // One byte of a request every 200 ms, never finishing: each read has data, so only a
        // deadline for the whole request ends it.
        // The bound after the deadline is generous: on a loaded machine the serving thread
        // may wait seconds for a core, and this test is about being let go, not promptness.
        let closed = loop {
            assert!(start.elapsed() < REQUEST_TIMEOUT * 4, "still held");
            if stream.write_all(b"G").is_err() {
                break start.elapsed();
            }
            match stream.read(&mut [0u8; 64]) {
                Ok(0) => break start.elapsed(),
                Err(e) if e.kind() == ErrorKind::WouldBlock || e.kind() == ErrorKind::TimedOut => {}
                Err(_) => break start.elapsed(),
                Ok(n) => panic!("answered an unfinished request with {n} bytes"),
            }
        };
        assert!(closed >= REQUEST_TIMEOUT, "closed after {closed:?}");
    }
}
