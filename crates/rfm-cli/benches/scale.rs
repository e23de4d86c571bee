//! How `rfm` scales with the size of the measured data (issue 14): reading
//! a CSV file with many channels (`rfm inspect`, as JSON and as text), and
//! comparing a model with many lines (`rfm compare`, with and without the
//! report). Each run
//! is one process of the release binary, timed from outside, with its peak
//! resident memory read from `/proc` while it runs.
//!
//! ```text
//! cargo bench -p rfm-cli --bench scale                       # the sizes of the issue
//! cargo bench -p rfm-cli --bench scale -- channels=500000   # one size
//! cargo bench -p rfm-cli --bench scale -- lines=494000 --out
//! ```
//!
//! The targets of the issue: 500,000 CSV channels in under 10 s, and
//! `compare` on 494,000 lines x 10 channels in under 30 s, growing linearly.
//! Timing belongs here, never in a test.

use std::fmt::Write as _;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A CSV file of `n` channels (responses at nodes 2.., reference 1:uy) on
/// three lines.
fn many_channels(n: usize) -> String {
    let mut text = String::from("# kind = receptance\nfrequency_hz");
    for i in 0..n {
        let _ = write!(text, ",H({}:uy,1:uy).re,H({}:uy,1:uy).im", i + 2, i + 2);
    }
    text.push('\n');
    for k in 1..=3 {
        let _ = write!(text, "{}", 10 * k);
        for _ in 0..n {
            text.push_str(",1e-6,2e-7");
        }
        text.push('\n');
    }
    text
}

/// A CSV file of `lines` lines from 0.5 to 400 Hz for the 10 channels of
/// [`CASE`]: four lightly damped modes, different at each response.
fn many_lines(lines: usize) -> String {
    let mut text = String::from("# kind = receptance\nfrequency_hz");
    for r in 2..12 {
        let _ = write!(text, ",H({r}:uy,11:uy).re,H({r}:uy,11:uy).im");
    }
    text.push('\n');
    for k in 0..lines {
        let f = 0.5 + k as f64 * 400.0 / lines as f64;
        let _ = write!(text, "{f:.6}");
        for i in 0..10 {
            let (mut re, mut im) = (0.0, 0.0);
            for fn_hz in [8.0, 51.0, 143.0, 280.0] {
                // 1 / (1 - r^2 + 2 j zeta r)
                let r: f64 = f / fn_hz;
                let (a, b) = (1.0 - r * r, 0.02 * r);
                let d = a * a + b * b;
                let g = 1e-6 * (i + 1) as f64;
                re += g * a / d;
                im -= g * b / d;
            }
            let _ = write!(text, ",{re:.6e},{im:.6e}");
        }
        text.push('\n');
    }
    text
}

/// A 10-element cantilever measured at nodes 2-11 over the tip, compared
/// at every line of the data (no `frequencies`: with `frequencies = [1.0]`
/// a compare used one line whatever the size, and failed where 1 Hz was not
/// a line).
const CASE: &str = include_str!("scale-case.toml");

/// What one run of `rfm` took.
struct Run {
    wall: Duration,
    /// User and system time of all its threads: on a machine shared with
    /// other work, the wall time grows with the load, this does not.
    cpu: Duration,
    /// Peak resident memory (MiB).
    peak_mib: f64,
}

impl std::fmt::Display for Run {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:>7.2} s ({:>6.2} s CPU), peak {:>6.0} MiB",
            self.wall.as_secs_f64(),
            self.cpu.as_secs_f64(),
            self.peak_mib
        )
    }
}

/// User plus system time of process `pid` so far, from `/proc/PID/stat`
/// (fields 14 and 15, in clock ticks of 1/100 s, Linux's `USER_HZ`).
fn cpu_time(pid: u32) -> Option<Duration> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // the fields after the command name, which is in parentheses and may hold spaces
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: u64 = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
    Some(Duration::from_millis(10 * ticks))
}

/// Runs `rfm` with `args`: its wall time, CPU time and peak resident memory.
fn timed(args: &[&str]) -> Run {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_rfm"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rfm runs");
    let status_file = format!("/proc/{}/status", child.id());
    let mut peak_kib = 0u64;
    let mut cpu = Duration::ZERO;
    loop {
        // the last reading before the exit misses at most the 5 ms of one poll
        cpu = cpu_time(child.id()).unwrap_or(cpu).max(cpu);
        // VmHWM is the peak so far: the last reading before the exit is the peak
        if let Some(kib) = std::fs::read_to_string(&status_file).ok().and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        }) {
            peak_kib = peak_kib.max(kib);
        }
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let elapsed = start.elapsed();
    let out = child.wait_with_output().expect("rfm ends");
    assert!(out.status.success(), "rfm {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    Run { wall: elapsed, cpu, peak_mib: peak_kib as f64 / 1024.0 }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let pick = |key: &str| -> Vec<usize> {
        args.iter().filter_map(|a| a.strip_prefix(key)?.strip_prefix('=')?.parse().ok()).collect()
    };
    let (mut channels, mut lines) = (pick("channels"), pick("lines"));
    if channels.is_empty() && lines.is_empty() {
        channels = vec![100_000, 200_000, 500_000];
        lines = vec![100_000, 200_000, 494_000];
    }
    let report = args.iter().any(|a| a == "--out");
    let dir = tempfile::tempdir().expect("a scratch folder");
    let d = dir.path();
    for &n in &channels {
        let path = d.join("channels.csv");
        std::fs::write(&path, many_channels(n)).expect("write");
        let path = path.to_str().expect("utf-8 path");
        println!("inspect --json, {n:>7} CSV channels x 3 lines: {}", timed(&["inspect", "--json", path]));
        println!("inspect (text), {n:>7} CSV channels x 3 lines: {}", timed(&["inspect", path]));
    }
    let case = d.join("case.toml");
    std::fs::write(&case, CASE).expect("write");
    for &n in &lines {
        std::fs::write(d.join("lines.csv"), many_lines(n)).expect("write");
        let case = case.to_str().expect("utf-8 path");
        println!("compare, {n:>7} lines x 10 channels:        {}", timed(&["compare", case]));
        if report {
            let out = d.join("out");
            let run = timed(&["compare", case, "--out", out.to_str().expect("utf-8")]);
            let html = std::fs::metadata(out.join("report.html")).expect("a report").len();
            println!("compare --out, {n:>7} lines:               {run}, report.html {:.2} MB", html as f64 / 1e6);
        }
    }
}
