//! The live page's server: one HTML page built into the binary (`page.html`, no CDN, no build
//! step) and the state it polls (`/state.json`), on 127.0.0.1 only, answering only requests
//! addressed to the loopback by name (`Host: 127.0.0.1:PORT` or `localhost:PORT`), so that a web
//! page elsewhere cannot read it through a rebound DNS name. Read-only: nothing it serves acts on
//! the device.
//!
//! `tiny_http` serves it: a small, synchronous HTTP/1.1 server (no async runtime, a handful of
//! dependencies, maintained under tiny-http on GitHub), which is all a page polled a few times a
//! second by one browser needs; hand-parsing HTTP on a `TcpListener` would repeat what it does
//! (request lines, headers, keep-alive, chunking) without a measured gain.

use super::Live;
use std::sync::Arc;
use std::thread::JoinHandle;

/// Longest wait of a `?after=` request for a newer state.
const LONG_POLL: std::time::Duration = std::time::Duration::from_millis(250);

/// The page, built into the binary.
const PAGE: &str = include_str!("page.html");

/// Why the page could not be served.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// No port on the loopback could be bound, or no thread started to serve it.
    #[error("cannot serve the live page on 127.0.0.1")]
    Bind(#[source] Box<dyn std::error::Error + Send + Sync>),
}

/// A running page server; stops when dropped.
pub struct ViewServer {
    server: Arc<tiny_http::Server>,
    thread: Option<JoinHandle<()>>,
    port: u16,
}

impl ViewServer {
    /// Serves `live` on a free port of 127.0.0.1.
    pub fn start(live: Live) -> Result<ViewServer, ViewError> {
        let server = tiny_http::Server::http("127.0.0.1:0").map_err(ViewError::Bind)?;
        let port = server
            .server_addr()
            .to_ip()
            .map(|a| a.port())
            .ok_or_else(|| ViewError::Bind("the server has no IP address".into()))?;
        let server = Arc::new(server);
        let serving = Arc::clone(&server);
        let thread = std::thread::Builder::new()
            .name("view".into())
            .spawn(move || {
                for request in serving.incoming_requests() {
                    let _ = answer(request, &live, port);
                }
            })
            .map_err(|e| ViewError::Bind(Box::new(e)))?;
        Ok(ViewServer {
            server,
            thread: Some(thread),
            port,
        })
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/", self.port)
    }

    /// The port it listens on.
    pub fn port(&self) -> u16 {
        self.port
    }
}

impl Drop for ViewServer {
    fn drop(&mut self) {
        self.server.unblock();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Whether a request's `Host` names this server on the loopback.
pub(crate) fn host_allowed(host: Option<&str>, port: u16) -> bool {
    let Some(host) = host else {
        return false;
    };
    let host = host.trim().to_ascii_lowercase();
    host == format!("127.0.0.1:{port}") || host == format!("localhost:{port}")
}

fn answer(request: tiny_http::Request, live: &Live, port: u16) -> std::io::Result<()> {
    use tiny_http::{Header, Method, Response};
    let host = request
        .headers()
        .iter()
        .find(|h| h.field.equiv("Host"))
        .map(|h| h.value.as_str().to_string());
    let header = |k: &str, v: &str| Header::from_bytes(k.as_bytes(), v.as_bytes()).ok();
    let respond = |request: tiny_http::Request, code: u16, kind: &str, body: String| {
        let mut r = Response::from_string(body).with_status_code(code);
        for h in [
            header("Content-Type", kind),
            header("Cache-Control", "no-store"),
            header("X-Content-Type-Options", "nosniff"),
            header("Content-Security-Policy", "default-src 'self'; style-src 'self' 'unsafe-inline'; script-src 'self' 'unsafe-inline'"),
        ]
        .into_iter()
        .flatten()
        {
            r.add_header(h);
        }
        request.respond(r)
    };
    let text = "text/plain; charset=utf-8";
    if !host_allowed(host.as_deref(), port) {
        return respond(
            request,
            403,
            text,
            format!("this page answers only at 127.0.0.1:{port} or localhost:{port}\n"),
        );
    }
    if !matches!(request.method(), Method::Get | Method::Head) {
        return respond(request, 405, text, "the live page is read-only\n".into());
    }
    let path = request.url().split('?').next().unwrap_or("").to_string();
    match path.as_str() {
        "/" | "/index.html" => respond(request, 200, "text/html; charset=utf-8", PAGE.into()),
        "/state.json" => {
            // `?after=N` waits (briefly) for an update past N: the page sees each change as it
            // comes without polling faster.
            let after = request
                .url()
                .split_once("?after=")
                .and_then(|(_, n)| n.parse::<u64>().ok());
            if let Some(n) = after {
                let until = std::time::Instant::now() + LONG_POLL;
                while live.seq() <= n && std::time::Instant::now() < until {
                    std::thread::sleep(std::time::Duration::from_millis(10));
                }
            }
            let body = live.snapshot().to_string();
            respond(request, 200, "application/json", body)
        }
        _ => respond(request, 404, text, "not found\n".into()),
    }
}

/// Opens `url` in the user's browser where there is one to open: `$BROWSER`, else `xdg-open` when
/// a display is set. Returns whether one was started.
pub(crate) fn open_in_browser(url: &str) -> bool {
    let browser = std::env::var_os("BROWSER").filter(|b| !b.is_empty());
    let display = std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty())
        || std::env::var_os("WAYLAND_DISPLAY").is_some_and(|d| !d.is_empty());
    let program = match (browser, display) {
        (Some(b), _) => b,
        (None, true) => "xdg-open".into(),
        (None, false) => return false,
    };
    std::process::Command::new(program)
        .arg(url)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};

    fn get(port: u16, host: &str, path: &str) -> String {
        let mut s = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
        write!(
            s,
            "GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"
        )
        .unwrap();
        let mut out = String::new();
        s.read_to_string(&mut out).unwrap();
        out
    }

    #[test]
    fn serves_the_page_and_state_only_to_the_loopback_by_name() {
        let live = Live::new();
        let server = ViewServer::start(live.clone()).unwrap();
        let port = server.port();
        assert!(server.url().starts_with("http://127.0.0.1:"));
        let page = get(port, &format!("127.0.0.1:{port}"), "/");
        assert!(page.starts_with("HTTP/1.1 200"), "{page}");
        assert!(page.contains("<canvas"), "the page is served");
        live.say("hello");
        let state = get(port, &format!("localhost:{port}"), "/state.json");
        assert!(state.contains("\"hello\""), "{state}");
        for bad in [
            format!("evil.example:{port}"),
            "127.0.0.1:1".to_string(),
            format!("127.0.0.1.nip.io:{port}"),
        ] {
            let r = get(port, &bad, "/state.json");
            assert!(r.starts_with("HTTP/1.1 403"), "{bad}: {r}");
        }
        assert!(!host_allowed(None, port));
    }

    #[test]
    fn only_reads() {
        let live = Live::new();
        let server = ViewServer::start(live).unwrap();
        let port = server.port();
        let mut s = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
        write!(
            s,
            "POST /state.json HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"
        )
        .unwrap();
        let mut out = String::new();
        s.read_to_string(&mut out).unwrap();
        assert!(out.starts_with("HTTP/1.1 405"), "{out}");
    }
}
