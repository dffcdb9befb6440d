//! The preview as a local web page that refreshes itself, for a browser next to the editor.
//!
//! Owns: a tiny HTTP/1.1 server on 127.0.0.1 only (never another interface), serving the
//! page, the latest good sheet and the latest state (error text of a broken save). Must not
//! touch: files (it serves what the watcher hands it from memory) or anything but loopback.

use anyhow::{Context, Result};
use serde_json::json;
use std::io::{Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How long a connection may take to send its request; a silent client must not hold a thread.
const REQUEST_TIMEOUT: Duration = Duration::from_secs(5);
/// Requests are a line and a few headers; anything longer is not for us.
const MAX_REQUEST: usize = 16 * 1024;

const PAGE: &str = r#"<!doctype html>
<html><head><meta charset="utf-8"><title>shmgen preview</title>
<style>
body { background: #1e1e1e; color: #ddd; font: 14px ui-monospace, monospace; margin: 12px; }
#error { color: #ff8a80; white-space: pre-wrap; }
#sheet { max-width: 100%; }
</style></head>
<body>
<div id="status">waiting for the first preview…</div>
<pre id="error"></pre>
<img id="sheet" alt="">
<script>
// Polls the watcher's state; reloads the sheet only when a new preview was written.
let seen = null;
async function poll() {
  try {
    const state = await (await fetch("state", { cache: "no-store" })).json();
    document.getElementById("error").textContent = state.error || "";
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
        std::thread::spawn(move || {
            for stream in listener.incoming().flatten() {
                let state = shared.clone();
                std::thread::spawn(move || {
                    // A client that hangs up early is its own business.
                    let _ = respond(stream, &state);
                });
            }
        });
        Ok(Server { state, url })
    }

    pub fn publish(&self, png: Vec<u8>, summary: String) {
        let mut state = self.state.lock().unwrap();
        state.png = Some(Arc::new(png));
        state.preview += 1;
        state.summary = summary;
        state.error = None;
    }

    pub fn fail(&self, error: String) {
        self.state.lock().unwrap().error = Some(error);
    }
}

fn respond(mut stream: TcpStream, state: &Mutex<State>) -> std::io::Result<()> {
    stream.set_read_timeout(Some(REQUEST_TIMEOUT))?;
    let head = read_head(&mut stream)?;
    let (status, kind, body) = route(&head, state);
    let header = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    );
    stream.write_all(header.as_bytes())?;
    stream.write_all(&body)?;
    stream.flush()
}

/// The request line and headers (up to the blank line).
fn read_head(stream: &mut TcpStream) -> std::io::Result<String> {
    let mut head = Vec::new();
    let mut buf = [0u8; 1024];
    while !head.windows(4).any(|w| w == b"\r\n\r\n") && head.len() < MAX_REQUEST {
        let n = stream.read(&mut buf)?;
        if n == 0 {
            break;
        }
        head.extend_from_slice(&buf[..n]);
    }
    Ok(String::from_utf8_lossy(&head).into_owned())
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
}
