//! `host calibrate --port … --view` as the operator meets it: the live page in a real headless
//! browser (Debian's `chromium`), for a hand-held session (`--port sim-hand`) and a table session
//! (`--port sim`). Screenshots at the start, half way and the end go to
//! `target/view-screenshots/`; the page must keep up with the session (its update number and its
//! target those of the live state when it was drawn) and, at the end, show the numbers of the
//! command's own `--json` document.
//!
//! The screenshots are made by `cargo test -p host --test live_view`.

use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// One session and one browser at a time: two paced sessions and two browsers side by side on a
/// loaded machine starve the pages' polls.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The longest one browser run may take: a page's run is its virtual-time budget (3 to 6 s)
/// plus start-up, a few seconds on a loaded machine.
const BROWSER_DEADLINE: Duration = Duration::from_secs(90);

/// The longest a read of the page's server may wait.
const SERVER_DEADLINE: Duration = Duration::from_secs(30);

/// Kills a process group (the browser and its helpers), whatever state it is in.
fn kill_group(child: &Child) {
    let _ = Command::new("kill")
        .args(["-KILL", "--", &format!("-{}", child.id())])
        .stderr(Stdio::null())
        .status();
}

/// Where the screenshots go: `target/view-screenshots/`.
fn screenshot_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("target/tmp has a parent")
        .join("view-screenshots");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The browser, or `None` (said loudly) when the system has none.
fn chromium() -> Option<PathBuf> {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join("chromium"))
            .find(|p| p.is_file())
    });
    if found.is_none() {
        eprintln!(
            "\n\n*** SKIPPED: the live page's browser test needs Debian's `chromium` \
             (scripts/test-all.sh installs it: apt-get install chromium) ***\n\n"
        );
    }
    found
}

/// One GET on the page's server, the body.
fn get(port: u16, path: &str) -> String {
    let address = std::net::SocketAddr::from(([127, 0, 0, 1], port));
    let mut s =
        std::net::TcpStream::connect_timeout(&address, SERVER_DEADLINE).expect("the page's server");
    s.set_read_timeout(Some(SERVER_DEADLINE)).unwrap();
    s.set_write_timeout(Some(SERVER_DEADLINE)).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    let (head, body) = out.split_once("\r\n\r\n").expect("an HTTP answer");
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    body.to_string()
}

fn state(port: u16) -> Value {
    serde_json::from_str(&get(port, "/state.json")).expect("state.json is JSON")
}

/// A session under test: the command, its page's port, its stderr lines.
struct Session {
    child: Child,
    port: u16,
    chromium: PathBuf,
    profile: tempfile::TempDir,
    name: &'static str,
}

impl Session {
    fn start(chromium: PathBuf, name: &'static str, args: &[&str]) -> Session {
        let mut child = Command::new(env!("CARGO_BIN_EXE_host"))
            .args(["calibrate", "--view", "--json"])
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("BROWSER")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("host runs");
        let stderr = child.stderr.take().unwrap();
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
        let port = loop {
            let line = rx
                .recv_timeout(Duration::from_secs(60))
                .expect("host prints the page's address");
            if let Some(rest) = line.strip_prefix("live page: http://127.0.0.1:") {
                break rest
                    .split('/')
                    .next()
                    .and_then(|p| p.parse().ok())
                    .expect("a port");
            }
        };
        std::thread::spawn(move || while rx.recv().is_ok() {});
        Session {
            child,
            port,
            chromium,
            profile: tempfile::tempdir().unwrap(),
            name,
        }
    }

    fn url(&self) -> String {
        format!("http://127.0.0.1:{}/", self.port)
    }

    /// One headless run of the browser on the page, its standard output. The flags are those a
    /// closed network needs (no background connections, no component updates: on a machine
    /// without a route out they hang rather than fail), and the run has a deadline: a browser
    /// that does not finish is killed with its children and run once more, and a second hang
    /// fails the test, instead of holding the whole test run.
    fn browser(&self, extra: &[String]) -> String {
        // A headless run that hangs (its virtual time never settling while the live page keeps
        // its connection open) is chromium's, not the page's: it is killed and run once more; a
        // second hang fails the test. A run that finishes is judged by what it printed.
        for attempt in 1..=2 {
            if let Some(out) = self.browser_once(extra, attempt == 2) {
                return out;
            }
            eprintln!(
                "chromium did not finish within {} s: run again",
                BROWSER_DEADLINE.as_secs()
            );
        }
        unreachable!("the second run panics rather than return None")
    }

    /// One run of [`Self::browser`]: `None` when the browser hung and was killed (a panic on the
    /// `last` attempt).
    fn browser_once(&self, extra: &[String], last: bool) -> Option<String> {
        use std::os::unix::process::CommandExt;
        let out_path = self.profile.path().join("browser.out");
        let err_path = self.profile.path().join("browser.err");
        let mut child = Command::new(&self.chromium)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-dev-shm-usage",
                "--disable-quic",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--disable-extensions",
                "--hide-scrollbars",
                "--no-first-run",
            ])
            .arg(format!("--user-data-dir={}", self.profile.path().display()))
            .args(extra)
            .args(
                (!extra.iter().any(|e| e.starts_with("--virtual-time-budget")))
                    .then_some("--virtual-time-budget=3000"),
            )
            .arg(self.url())
            .stdin(Stdio::null())
            .stdout(std::fs::File::create(&out_path).unwrap())
            .stderr(std::fs::File::create(&err_path).unwrap())
            .process_group(0)
            .spawn()
            .expect("chromium runs");
        let start = Instant::now();
        let status = loop {
            if let Some(status) = child.try_wait().unwrap() {
                break status;
            }
            if start.elapsed() > BROWSER_DEADLINE {
                kill_group(&child);
                let _ = child.wait();
                assert!(
                    !last,
                    "chromium did not finish within {} s, twice ({extra:?}); its stderr:\n{}",
                    BROWSER_DEADLINE.as_secs(),
                    std::fs::read_to_string(&err_path).unwrap_or_default()
                );
                return None;
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        // The browser's helpers may outlive it in its group.
        kill_group(&child);
        assert!(
            status.success(),
            "chromium: {}",
            std::fs::read_to_string(&err_path).unwrap_or_default()
        );
        Some(std::fs::read_to_string(&out_path).unwrap())
    }

    /// A screenshot of the page now, and its DOM, checked against the live state: the page shows an
    /// update at least as new as the state before the browser opened it, and the target of that
    /// moment.
    fn look(&self, stage: &str, moving: bool) -> String {
        // A page that polls but no longer draws is caught by `look_across_a_change`: its update
        // number would never pass the step's.
        let before = state(self.port);
        let png = screenshot_dir().join(format!("{}-{stage}.png", self.name));
        let height = if moving { 1000 } else { 1700 };
        self.browser(&[
            format!("--screenshot={}", png.display()),
            format!("--window-size=1280,{height}"),
        ]);
        assert!(
            std::fs::metadata(&png)
                .map(|m| m.len() > 10_000)
                .unwrap_or(false),
            "{} was not written",
            png.display()
        );
        let dom = self.browser(&["--dump-dom".to_string(), "--window-size=1280,1000".into()]);
        let after = state(self.port);
        let seq: u64 = attribute(&dom, "data-seq")
            .parse()
            .expect("the page shows its update number");
        let s0 = before["seq"].as_u64().unwrap();
        let s1 = after["seq"].as_u64().unwrap();
        assert!(
            seq >= s0 && seq <= s1,
            "{stage}: the page shows update {seq}, the session was at {s0}..{s1}: it does not keep up"
        );
        // The page kept polling while open and, while the session moves, showed it moving.
        let polls: u64 = attribute(&dom, "data-polls").parse().unwrap();
        assert!(
            polls >= 3,
            "{stage}: the page polled {polls} times: it stopped updating"
        );
        // Shown at or after the current step began: the page shows its target.
        let step_seq = after["step_seq"].as_u64().unwrap();
        if seq >= step_seq {
            assert_eq!(
                text_of(&dom, "target-label"),
                target_label(&after),
                "{stage}: the page's target is stale (update {seq}, step since {step_seq})"
            );
        }
        dom
    }

    /// Opens the page until it stays open across a change of step (the page's first update before
    /// the step began, its last after): it must then show the new target, not the one it loaded
    /// with.
    fn look_across_a_change(&self) {
        let start = Instant::now();
        for _ in 0..60 {
            assert!(
                start.elapsed() < Duration::from_secs(300),
                "in 300 s the page never stayed open across a change of step"
            );
            assert_eq!(
                state(self.port)["phase"],
                "recording",
                "the session ended before the page was seen across a change of step"
            );
            // A longer budget keeps the page open (and polling) longer.
            let dom = self.browser(&[
                "--dump-dom".to_string(),
                "--virtual-time-budget=6000".into(),
            ]);
            let after = state(self.port);
            let seq: u64 = attribute(&dom, "data-seq").parse().unwrap();
            let first: u64 = attribute(&dom, "data-first-seq").parse().unwrap();
            let step_seq = after["step_seq"].as_u64().unwrap();
            eprintln!("look: page {first}..{seq}, step since {step_seq}");
            if first < step_seq && step_seq <= seq {
                assert_eq!(
                    text_of(&dom, "target-label"),
                    target_label(&after),
                    "the page kept the target it loaded with across a change of step"
                );
                return;
            }
        }
        panic!("in 60 looks the page never stayed open across a change of step");
    }

    fn wait_for(&self, what: &str, done: impl Fn(&Value) -> bool) -> Value {
        let start = Instant::now();
        loop {
            let s = state(self.port);
            if done(&s) {
                return s;
            }
            assert!(
                start.elapsed() < Duration::from_secs(300),
                "no {what} within 300 s: {s}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Closes standard input (the page stops being served) and returns the `--json` document.
    fn finish(mut self) -> Value {
        drop(self.child.stdin.take());
        let mut out = String::new();
        self.child
            .stdout
            .take()
            .unwrap()
            .read_to_string(&mut out)
            .unwrap();
        let status = self.child.wait().unwrap();
        assert!(status.success(), "host calibrate failed: {status}");
        serde_json::from_str(&out).expect("--json prints one document")
    }
}

/// A session the test gave up on does not outlive it.
impl Drop for Session {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// The label of the state's current target, as the page writes it ("—" without one).
fn target_label(s: &Value) -> String {
    s["step"]["target"]["label"]
        .as_str()
        .unwrap_or("—")
        .to_string()
}

/// The value of the first `name="…"` attribute in `html`.
fn attribute(html: &str, name: &str) -> String {
    let at = html.find(&format!("{name}=\"")).expect(name) + name.len() + 2;
    html[at..].split('"').next().unwrap_or_default().to_string()
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&amp;", "&")
}

/// The text inside the element with `id`.
fn text_of(html: &str, id: &str) -> String {
    let at = html.find(&format!("id=\"{id}\"")).expect(id);
    let open = at + html[at..].find('>').unwrap() + 1;
    unescape(html[open..].split('<').next().unwrap_or_default())
}

/// The texts of the cells of the parameter row named `name`, by class.
fn parameter_cell(html: &str, name: &str, class: &str) -> String {
    let row = html
        .find(&format!(
            "data-name=\"{}\"",
            name.replace('&', "&amp;").replace('"', "&quot;")
        ))
        .unwrap_or_else(|| panic!("the page has no row for {name}"));
    let end = row + html[row..].find("</tr>").unwrap();
    let cell = row
        + html[row..end]
            .find(&format!("class=\"{class}\""))
            .expect(class);
    let open = cell + html[cell..].find('>').unwrap() + 1;
    unescape(html[open..].split('<').next().unwrap_or_default())
}

/// Every parameter of the document, its value and 1σ, as the page shows them (six significant
/// digits), and the verdict, the files and the next commands.
fn check_result(dom: &str, doc: &Value) {
    let params = doc["parameters"].as_array().expect("parameters");
    assert!(!params.is_empty());
    for p in params {
        let name = p["name"].as_str().unwrap();
        let close = |shown: &str, want: f64| {
            let v: f64 = shown
                .parse()
                .unwrap_or_else(|_| panic!("{name}: '{shown}' is not a number"));
            assert!(
                (v - want).abs() <= 5e-6 * want.abs() + 1e-300,
                "{name}: the page shows {v}, the document says {want}"
            );
        };
        close(
            &parameter_cell(dom, name, "value"),
            p["value"].as_f64().unwrap(),
        );
        match p["sigma"].as_f64() {
            Some(s) => close(&parameter_cell(dom, name, "sigma"), s),
            None => assert_eq!(parameter_cell(dom, name, "sigma"), "undetermined"),
        }
        assert_eq!(
            parameter_cell(dom, name, "unit"),
            p["unit"].as_str().unwrap()
        );
    }
    let verdict = if doc["passed"].as_bool().unwrap() {
        "PASS"
    } else {
        "FAIL"
    };
    assert_eq!(text_of(dom, "verdict"), verdict);
    let toml = doc["files"]["calibration_toml"].as_str().unwrap();
    assert!(dom.contains(toml), "the page names {toml}");
    assert!(
        dom.contains("host export --calibration"),
        "the next command"
    );
}

/// A plan file of the first `n` hand-held aims, `seconds` each.
fn short_hand_plan(dir: &Path, n: usize, seconds: f64) -> PathBuf {
    let mut plan = recording::session::builtin::load_plan("hand").unwrap();
    plan.segments.truncate(n);
    for s in &mut plan.segments {
        s.duration_s = Some(seconds);
    }
    let path = dir.join("plan.toml");
    std::fs::write(&path, plan.to_toml()).unwrap();
    path
}

#[test]
fn the_hand_held_page_follows_the_session_in_a_browser() {
    let Some(chromium) = chromium() else { return };
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let plan = short_hand_plan(dir.path(), 10, 1.0);
    let out = dir.path().join("out");
    let s = Session::start(
        chromium,
        "hand",
        &[
            "--port",
            "sim-hand",
            "--plan",
            plan.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    s.wait_for("recording", |v| {
        v["phase"] == "recording" && !v["step"].is_null()
    });
    let start = s.look("1-start", true);
    assert_eq!(text_of(&start, "positions-planned"), "10");
    assert_eq!(text_of(&start, "positions-needed"), "9");
    let first: u64 = attribute(&start, "data-seq").parse().unwrap();
    s.look_across_a_change();

    s.wait_for("half the positions", |v| {
        v["progress"]["positions_done"].as_u64() >= Some(5)
    });
    let half = s.look("2-half", true);
    let later: u64 = attribute(&half, "data-seq").parse().unwrap();
    assert!(
        later > first,
        "the page stopped updating ({first} → {later})"
    );
    let done: u64 = text_of(&half, "positions-done").parse().unwrap();
    assert!(done >= 5, "{done} positions shown half way");
    // An offset output's directions are known from six positions on: the sphere has them.
    let st = state(s.port);
    assert!(st["live"]["up_b"].is_array() || done < 6, "{st}");

    s.wait_for("the result", |v| v["phase"] == "done");
    let end = s.look("3-end", false);
    // Nothing is open once the session is over: what is left was not visited.
    assert_eq!(text_of(&half, "open-label"), "open targets, best first:");
    assert_eq!(text_of(&end, "open-label"), "targets not visited:");
    let doc = s.finish();
    check_result(&end, &doc);
    // The live hand-held session's gyro, fitted from the hand's turns, is on the page.
    assert!(
        doc["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["name"].as_str().is_some_and(|n| n.starts_with("gyro_g_"))),
        "the document has the gyro: {}",
        doc["parameters"]
    );
}

#[test]
fn the_table_page_follows_the_session_in_a_browser() {
    let Some(chromium) = chromium() else { return };
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let s = Session::start(
        chromium,
        "table",
        &[
            "--port",
            "sim",
            "--plan",
            "quick-oblique",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    s.wait_for("recording", |v| {
        v["phase"] == "recording" && !v["step"].is_null()
    });
    let start = s.look("1-start", true);
    assert_eq!(text_of(&start, "segments-planned"), "12");
    let first: u64 = attribute(&start, "data-seq").parse().unwrap();
    // A table step lasts about 1.5 s: looked for from the start, while most are still to come.
    s.look_across_a_change();

    s.wait_for("half the segments", |v| {
        v["progress"]["segments_done"].as_u64() >= Some(6)
    });
    let half = s.look("2-half", true);
    let later: u64 = attribute(&half, "data-seq").parse().unwrap();
    assert!(
        later > first,
        "the page stopped updating ({first} → {later})"
    );

    s.wait_for("the result", |v| v["phase"] == "done");
    let end = s.look("3-end", false);
    let doc = s.finish();
    check_result(&end, &doc);
}
