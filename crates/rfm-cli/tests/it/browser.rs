//! Every report kind in a real browser: headless Chromium loads each
//! `report.html` with the network switched off, and then each of its SVG
//! figures as a document of its own. The check fails on any console error,
//! script exception or failed load, on any request that leaves the file,
//! on a figure that renders empty, and on an SVG the browser's XML parser
//! rejects.
//!
//! Chromium is driven over its DevTools protocol. Where it is not installed
//! (CI has only the Rust toolchain) the test says so and passes; set
//! `RFM_CHROMIUM` to a browser binary to use another one.

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use tungstenite::{Message, WebSocket};

use super::fixtures::{
    clamp_update, lap_compare, lap_fix, lap_update, svg_files, text, tutorial_applied_update, tutorial_compare,
    tutorial_diagnose_report, tutorial_fix, tutorial_update,
};

/// The Chromium binary: `RFM_CHROMIUM`, else the first of the usual names on `PATH`.
fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("RFM_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable"]
        .iter()
        .flat_map(|name| std::env::split_paths(&path).map(move |dir| dir.join(name)))
        .find(|p| p.is_file())
}

/// How long one page may take to load.
const PAGE_TIMEOUT: Duration = Duration::from_secs(60);

/// A headless Chromium with one page, attached over the DevTools protocol.
struct Browser {
    child: Child,
    ws: WebSocket<TcpStream>,
    session: String,
    next_id: u64,
    /// Events received since the last [`Browser::load`].
    events: Vec<Value>,
    _profile: tempfile::TempDir,
}

/// What loading a page showed.
struct Loaded {
    /// Console errors, exceptions, failed loads.
    errors: Vec<String>,
    /// Requests for anything but the file itself.
    requests: Vec<String>,
}

impl Browser {
    fn launch(exe: &Path) -> Browser {
        let profile = tempfile::tempdir().expect("a profile folder");
        // the flags that keep Chromium from reaching out to the network on
        // its own (updates, sync, field trials), and a new empty profile
        let mut child = Command::new(exe)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--disable-extensions",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("{} does not start: {e}", exe.display()));
        let stderr = child.stderr.take().expect("stderr is piped");
        let (tx, rx) = std::sync::mpsc::channel();
        // read the debugging address, then keep draining stderr so that
        // the browser never blocks on a full pipe
        std::thread::spawn(move || {
            let mut sent = false;
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if !sent && let Some(url) = line.strip_prefix("DevTools listening on ") {
                    let _ = tx.send(url.trim().to_string());
                    sent = true;
                }
            }
        });
        let url = rx.recv_timeout(Duration::from_secs(60)).expect("Chromium prints its DevTools address");
        let host = url.trim_start_matches("ws://").split('/').next().expect("host:port").to_string();
        let stream = TcpStream::connect(&host).expect("the DevTools port accepts");
        stream.set_read_timeout(Some(Duration::from_secs(5))).expect("a read timeout");
        let (ws, _) = tungstenite::client(url.as_str(), stream).expect("the DevTools websocket opens");
        let mut b = Browser { child, ws, session: String::new(), next_id: 0, events: Vec::new(), _profile: profile };
        let target = b.call_browser("Target.createTarget", json!({ "url": "about:blank" }));
        let id = target["targetId"].as_str().expect("a target id").to_string();
        let attached = b.call_browser("Target.attachToTarget", json!({ "targetId": id, "flatten": true }));
        b.session = attached["sessionId"].as_str().expect("a session id").to_string();
        for domain in ["Page.enable", "Runtime.enable", "Log.enable", "Network.enable"] {
            b.call(domain, json!({}));
        }
        // offline: a report that needs the network fails to load something
        b.call(
            "Network.emulateNetworkConditions",
            json!({ "offline": true, "latency": 0, "downloadThroughput": -1, "uploadThroughput": -1 }),
        );
        b
    }

    /// Sends a command (to the page's session when `session`) and returns
    /// its result, keeping the events that arrive meanwhile.
    fn send(&mut self, method: &str, params: Value, session: bool) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut msg = json!({ "id": id, "method": method, "params": params });
        if session {
            msg["sessionId"] = json!(self.session);
        }
        self.ws.send(Message::text(msg.to_string())).expect("a DevTools command is sent");
        let deadline = Instant::now() + PAGE_TIMEOUT;
        loop {
            let v = self.next_message(deadline).unwrap_or_else(|| panic!("no answer to {method}"));
            if v["id"].as_u64() == Some(id) {
                if let Some(e) = v.get("error") {
                    panic!("{method} failed: {e}");
                }
                return v["result"].clone();
            }
            self.events.push(v);
        }
    }

    fn call_browser(&mut self, method: &str, params: Value) -> Value {
        self.send(method, params, false)
    }

    fn call(&mut self, method: &str, params: Value) -> Value {
        self.send(method, params, true)
    }

    /// The next message, or `None` at the deadline.
    fn next_message(&mut self, deadline: Instant) -> Option<Value> {
        while Instant::now() < deadline {
            match self.ws.read() {
                Ok(Message::Text(t)) => return Some(serde_json::from_str(t.as_str()).expect("DevTools sends JSON")),
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                Err(e) => panic!("the DevTools connection failed: {e}"),
            }
        }
        None
    }

    /// Loads `path` and waits for its load event.
    fn load(&mut self, path: &Path) -> Loaded {
        self.events.clear();
        let url = format!("file://{}", path.canonicalize().expect("the file exists").display());
        let nav = self.call("Page.navigate", json!({ "url": url }));
        assert!(nav.get("errorText").is_none(), "{}: {}", path.display(), nav["errorText"]);
        let deadline = Instant::now() + PAGE_TIMEOUT;
        while !self.events.iter().any(|e| e["method"] == "Page.loadEventFired") {
            let v = self.next_message(deadline).unwrap_or_else(|| panic!("{} never finished loading", path.display()));
            self.events.push(v);
        }
        // a round trip, so that messages logged during the load have arrived
        self.call("Runtime.evaluate", json!({ "expression": "1" }));
        let mut errors = Vec::new();
        let mut requests = Vec::new();
        for e in &self.events {
            let p = &e["params"];
            match e["method"].as_str().unwrap_or("") {
                "Runtime.consoleAPICalled" if p["type"] == "error" || p["type"] == "assert" => {
                    errors.push(format!("console: {}", p["args"]));
                }
                "Runtime.exceptionThrown" => errors.push(format!("exception: {}", p["exceptionDetails"])),
                "Log.entryAdded" if p["entry"]["level"] == "error" => {
                    errors.push(format!("log: {}", p["entry"]["text"]));
                }
                "Network.loadingFailed" => errors.push(format!("failed load: {}", p["errorText"])),
                "Network.requestWillBeSent" => {
                    let u = p["request"]["url"].as_str().unwrap_or("").to_string();
                    if u != url {
                        requests.push(u);
                    }
                }
                _ => {}
            }
        }
        Loaded { errors, requests }
    }

    /// Evaluates `expression` (which returns a JSON string) in the page.
    fn eval(&mut self, expression: &str) -> Value {
        let r = self.call("Runtime.evaluate", json!({ "expression": expression, "returnByValue": true }));
        let s = r["result"]["value"].as_str().unwrap_or_else(|| panic!("{expression} returned {r}"));
        serde_json::from_str(s).expect("the page returns JSON")
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        // the browser this test started, by its own handle
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Loads one report folder: `report.html`, then every SVG beside it.
/// Returns the headings of the report.
fn check_report(b: &mut Browser, dir: &Path, what: &str) -> Vec<String> {
    let html = dir.join("report.html");
    let loaded = b.load(&html);
    assert!(loaded.errors.is_empty(), "{what}: {:?}", loaded.errors);
    assert!(loaded.requests.is_empty(), "{what} asks for {:?}", loaded.requests);
    let page = b.eval(
        "JSON.stringify({ ready: document.readyState, scripts: document.scripts.length, images: document.images.length, \
         figures: [...document.querySelectorAll('figure svg')].map(s => { const r = s.getBoundingClientRect(); \
         return [r.width, r.height]; }), headings: [...document.querySelectorAll('h2')].map(h => h.textContent) })",
    );
    assert_eq!(page["ready"], "complete", "{what}");
    assert_eq!(page["scripts"], 0, "{what} has scripts");
    assert_eq!(page["images"], 0, "{what} has images to load");
    let figures = page["figures"].as_array().expect("figures");
    let files = svg_files(dir);
    assert_eq!(figures.len(), files.len(), "{what}: every figure inline");
    for (f, size) in files.iter().zip(figures) {
        let (w, h) = (size[0].as_f64().unwrap_or(0.0), size[1].as_f64().unwrap_or(0.0));
        assert!(w > 300.0 && h > 100.0, "{what}: a figure renders {w} x {h}");
        let loaded = b.load(f);
        assert!(loaded.errors.is_empty(), "{}: {:?}", f.display(), loaded.errors);
        assert!(loaded.requests.is_empty(), "{} asks for {:?}", f.display(), loaded.requests);
        // the browser's own XML parser: an SVG it rejects shows a parser error instead
        let doc = b.eval(
            "JSON.stringify({ root: document.documentElement.localName, ns: document.documentElement.namespaceURI, \
             errors: document.getElementsByTagNameNS('*', 'parsererror').length })",
        );
        assert_eq!(doc["root"], "svg", "{} is not an SVG document: {doc}", f.display());
        assert_eq!(doc["ns"], "http://www.w3.org/2000/svg", "{}", f.display());
        assert_eq!(doc["errors"], 0, "{} is not well-formed XML", f.display());
    }
    page["headings"].as_array().expect("headings").iter().map(|h| h.as_str().unwrap_or("").to_string()).collect()
}

/// What a loaded report shows a reader: its text (every text node, tables,
/// captions and the text of its figures, each apart), the terms its
/// glossary defines, and the y-axis labels of its FRF figures.
struct Shown {
    text: String,
    glossary: Vec<String>,
    axes: Vec<String>,
}

fn shown(b: &mut Browser, dir: &Path) -> Shown {
    // the report itself (a check of its figures leaves the last one loaded)
    let loaded = b.load(&dir.join("report.html"));
    assert!(loaded.errors.is_empty(), "{}: {:?}", dir.display(), loaded.errors);
    let page = b.eval(
        "JSON.stringify({ text: (() => { const w = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT); \
         const out = []; while (w.nextNode()) out.push(w.currentNode.textContent); return out.join(' '); })(), \
         glossary: [...document.querySelectorAll('section')].filter(s => s.querySelector('h2')?.textContent === \
         'How to read this report').flatMap(s => [...s.querySelectorAll('dt')].map(d => d.textContent)), \
         axes: [...document.querySelectorAll('svg text')].map(t => t.textContent.trim()).filter(t => t.startsWith('Magnitude')) })",
    );
    let list = |v: &Value| {
        v.as_array().map_or(Vec::new(), |a| a.iter().filter_map(|x| x.as_str().map(String::from)).collect())
    };
    Shown {
        text: page["text"].as_str().unwrap_or("").to_string(),
        glossary: list(&page["glossary"]),
        axes: list(&page["axes"]),
    }
}

/// Every report ends with the glossary of every reported quantity, under
/// the names the tool gives them, and prints no raw number of seven digits
/// or more (a dBIC of -56161044.7 reads as -56,161,045).
fn check_glossary_and_numbers(s: &Shown, what: &str) {
    for q in rfm_update::quantities::GLOSSARY {
        assert!(
            s.glossary.iter().any(|g| g.starts_with(q.name)),
            "{what}: the glossary lacks {}: {:?}",
            q.name,
            s.glossary
        );
    }
    // whole numbers only: the fraction of a small value may hold zeros (0.00429208)
    let mut digits = 0;
    for part in s.text.split(|c: char| !c.is_ascii_digit() && c != '.') {
        let whole = part.split('.').next().unwrap_or("");
        digits = digits.max(whole.len());
    }
    assert!(digits < 7, "{what}: a number of {digits} digits is printed unformatted");
}

#[test]
fn every_report_kind_loads_offline_in_chromium_without_console_errors() {
    let Some(exe) = chromium() else {
        eprintln!(
            "skipped: no Chromium found (install chromium or set RFM_CHROMIUM to check the reports in a browser)"
        );
        return;
    };
    let compare = tutorial_compare();
    assert!(compare.output.status.success(), "{}", text(&compare.output.stderr));
    let fix = tutorial_fix();
    assert!(fix.dir.join("report.html").exists(), "{}", text(&fix.output.stderr));
    let update = clamp_update();
    assert!(update.dir.join("report.html").exists(), "{}", text(&update.output.stderr));

    let mut b = Browser::launch(&exe);
    // a page that fails must fail the check: a missing image is a failed load
    let bad = tempfile::tempdir().unwrap();
    let page = bad.path().join("bad.html");
    std::fs::write(
        &page,
        "<!DOCTYPE html><title>x</title><img src=\"missing.png\"><img src=\"https://example.com/a.png\">",
    )
    .unwrap();
    let loaded = b.load(&page);
    assert!(!loaded.errors.is_empty(), "a missing image goes unnoticed");
    assert!(loaded.requests.iter().any(|r| r.starts_with("https://example.com")), "{:?}", loaded.requests);

    let headings = check_report(&mut b, &compare.dir, "the compare report");
    for h in ["Summary", "FRF correlation", "Modes", "FRF overlays"] {
        assert!(headings.iter().any(|x| x == h), "compare lacks {h}: {headings:?}");
    }
    let headings = check_report(&mut b, &fix.dir, "the fix report");
    for h in [
        "The misfit after each step",
        "Before the model was blamed: the data and the case's own parameters",
        "Modes",
        "FRF overlays",
    ] {
        assert!(headings.iter().any(|x| x == h), "fix lacks {h}: {headings:?}");
    }
    // a stalled update (the clamp), a converged one (the walkthrough's) and
    // one of a case with a history (the tutorial with the joint applied)
    let converged = tutorial_update();
    assert!(converged.output.status.success(), "{}", text(&converged.output.stderr));
    let applied = tutorial_applied_update();
    assert!(applied.output.status.success(), "{}", text(&applied.output.stderr));
    for (dir, what) in [
        (&update.dir, "the stalled update report"),
        (&converged.dir, "the converged update report"),
        (&applied.dir, "the update report of an applied case"),
    ] {
        let headings = check_report(&mut b, dir, what);
        for h in ["Summary", "Convergence", "Parameters", "Modes", "FRF overlays"] {
            assert!(headings.iter().any(|x| x == h), "{what} lacks {h}: {headings:?}");
        }
        check_glossary_and_numbers(&shown(&mut b, dir), what);
    }
    let diagnosis = tutorial_diagnose_report();
    assert!(diagnosis.output.status.success(), "{}", text(&diagnosis.output.stderr));
    let headings = check_report(&mut b, &diagnosis.dir, "the diagnosis report");
    for h in ["Summary", "The ranking", "FRF correlation", "FRF overlays"] {
        assert!(headings.iter().any(|x| x == h), "the diagnosis report lacks {h}: {headings:?}");
    }
    let s = shown(&mut b, &diagnosis.dir);
    check_glossary_and_numbers(&s, "the diagnosis report");
    assert!(s.text.contains("1: flexible, lossy joint at node 13"), "the leader is not marked on the structure");
    let s = shown(&mut b, &fix.dir);
    check_glossary_and_numbers(&s, "the fix report");
    assert!(
        s.text.contains("Natural frequencies and damping ratios")
            && s.text.contains("nominal Hz")
            && s.text.contains("step 1 Hz"),
        "the fix report has no natural frequencies before and after the step"
    );
    // the loop's story as the terminal tells it: each step's dBIC, why it
    // stopped, and the data checked before the model was blamed
    for said in ["dBIC of the step", "-56,161,045", "stopped", "nothing significant remains", "none found"] {
        assert!(s.text.contains(said), "the fix report does not say {said}");
    }
    assert!(text(&fix.output.stdout).contains("dBIC of the step"), "{}", text(&fix.output.stdout));
}

/// The lap-joint tutorial is measured as accelerance per volt, with an
/// amplifier's gain: its compare, update and fix reports all draw and label
/// the data as measured, in m/s²/V, and show the gain the model's FRFs were
/// multiplied by; none draws them as receptance or per newton.
#[test]
fn reports_of_data_per_volt_are_labelled_per_volt_with_their_gain() {
    let Some(exe) = chromium() else {
        eprintln!(
            "skipped: no Chromium found (install chromium or set RFM_CHROMIUM to check the reports in a browser)"
        );
        return;
    };
    let reports = [
        (lap_compare(), "the lap-joint compare report"),
        (lap_update(), "the lap-joint update report"),
        (lap_fix(), "the lap-joint fix report"),
    ];
    let mut b = Browser::launch(&exe);
    for (w, what) in reports {
        assert!(w.dir.join("report.html").exists(), "{what}: {}", text(&w.output.stderr));
        check_report(&mut b, &w.dir, what);
        let s = shown(&mut b, &w.dir);
        check_glossary_and_numbers(&s, what);
        assert!(!s.axes.is_empty() && s.axes.iter().all(|a| a == "Magnitude (dB re 1 m/s²/V)"), "{what}: {:?}", s.axes);
        for wrong in ["m/N", "m/s²/N", "receptance"] {
            assert!(!s.text.contains(wrong), "{what} says {wrong}");
        }
        assert!(s.text.contains("accelerance per volt"), "{what} does not name the data's quantity");
        assert!(s.text.contains("gain applied") && s.text.contains("5:uy: x4"), "{what} does not show the gain");
    }
}
