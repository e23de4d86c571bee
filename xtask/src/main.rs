//! `cargo xtask <task>`: the project's automation.
//!
//! - `reproduce [CASE...]`: builds the `rfm` binary (release) and runs every
//!   case study of the paper under `cases/`, printing each table beside the
//!   paper's values and writing `target/reproduce/<case>/results.json`.
//! - `bench [--full]`: builds the `bench_point` example of rfm-update
//!   (release) and runs quick versions of the sensitivity benchmarks, each
//!   configuration in its own process so that its peak memory is its own;
//!   prints a table (time per frequency line, CPU time, peak memory), the
//!   dense/sparse ratio and the fitted scaling exponents in the number of
//!   equations and of parameters. `--full` repeats each run more often.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// The paper's case studies, in the paper's order.
const PAPER_CASES: [&str; 6] = [
    "two-material-beam",
    "two-material-beam-high-damping",
    "two-material-beam-noisy",
    "monopile",
    "cantilever-flexible-clamp",
    "f-frame",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("xtask lives in the workspace").to_path_buf()
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("reproduce") => reproduce(&args[1..]),
        Some("bench") => bench(&args[1..]),
        _ => Err("usage: cargo xtask reproduce [CASE...] | cargo xtask bench [--full]".to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

fn build_cli() -> Result<PathBuf, String> {
    let status = cargo()
        .current_dir(root())
        .args(["build", "--release", "--quiet", "-p", "rfm-cli"])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err("building rfm failed".into());
    }
    Ok(root().join("target/release/rfm"))
}

fn reproduce(cases: &[String]) -> Result<(), String> {
    let names: Vec<String> =
        if cases.is_empty() { PAPER_CASES.iter().map(|s| s.to_string()).collect() } else { cases.to_vec() };
    let rfm = build_cli()?;
    let mut summary = Vec::new();
    for name in &names {
        let case = root().join("cases").join(format!("{name}.toml"));
        if !case.exists() {
            return Err(format!("no case file {}", case.display()));
        }
        let out = root().join("target/reproduce").join(name);
        println!("\n==================== {name} ====================");
        let status = Command::new(&rfm)
            .arg("update")
            .arg(&case)
            .arg("--out")
            .arg(&out)
            .status()
            .map_err(|e| format!("cannot run {}: {e}", rfm.display()))?;
        if !status.success() {
            return Err(format!("case {name} failed"));
        }
        let results = out.join("results.json");
        let text = std::fs::read_to_string(&results).map_err(|e| format!("{}: {e}", results.display()))?;
        let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", results.display()))?;
        summary.push((name.clone(), json));
    }
    println!("\n==================== summary ====================");
    println!("{:<32} {:>10} {:>12} {:>22}", "case", "status", "residual", "max error vs truth");
    for (name, json) in &summary {
        let status = json["status"].as_str().map(str::to_string).unwrap_or_else(|| json["status"].to_string());
        let residual = json["residual"].as_f64().unwrap_or(f64::NAN);
        let max_err = json["parameters"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|p| {
                let (u, t) = (p["updated"].as_f64()?, p["truth"].as_f64()?);
                Some(((u - t) / t).abs())
            })
            .fold(0.0, f64::max);
        println!("{name:<32} {status:>10} {residual:>12.3e} {max_err:>22.2e}");
    }
    println!("\nreports (self-contained HTML with the figures; open in a browser):");
    for (name, _) in &summary {
        let report = root().join("target/reproduce").join(name).join("report.html");
        if report.exists() {
            println!("  {}", report.display());
        }
    }
    println!("\nresults: {}", root().join("target/reproduce").display());
    Ok(())
}

/// One `bench_point` run: what the table shows about it.
struct Point {
    name: String,
    json: serde_json::Value,
}

impl Point {
    fn num(&self, key: &str) -> f64 {
        self.json[key].as_f64().unwrap_or(f64::NAN)
    }
}

fn bench_point(exe: &Path, name: &str, args: &[&str]) -> Result<Point, String> {
    let out = Command::new(exe).args(args).output().map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    if !out.status.success() {
        return Err(format!(
            "{name}: bench_point {} failed:\n{}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().last().ok_or_else(|| format!("{name}: no output"))?;
    let json = serde_json::from_str(line).map_err(|e| format!("{name}: {e} in {line}"))?;
    Ok(Point { name: name.to_string(), json })
}

/// Least-squares slope of log(y) against log(x).
fn loglog_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

fn first_line(path: &str, prefix: &str) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text.lines().find(|l| l.starts_with(prefix))?;
    Some(line.split_once(':').map_or(line, |(_, v)| v).trim().to_string())
}

fn machine() -> String {
    let cpus = std::thread::available_parallelism().map_or(0, |n| n.get());
    let model = first_line("/proc/cpuinfo", "model name").unwrap_or_else(|| "unknown CPU".into());
    let mem = first_line("/proc/meminfo", "MemTotal").unwrap_or_default();
    format!("{cpus} CPUs ({model}), {mem} memory")
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

fn bench(args: &[String]) -> Result<(), String> {
    let full = args.iter().any(|a| a == "--full");
    let status = cargo()
        .current_dir(root())
        .args(["build", "--release", "--quiet", "-p", "rfm-update", "--example", "bench_point"])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err("building bench_point failed".into());
    }
    let exe = root().join("target/release/examples/bench_point");
    let reps = |quick: u32, more: u32| if full { more } else { quick }.to_string();
    println!("machine: {}", machine());
    println!("load average before: {}", load_average());

    // the benchmark configurations (a)-(d), quick versions
    let (r_a, r_b, r_c) = (reps(20, 100), reps(5, 20), reps(2, 5));
    let mut rows = Vec::new();
    rows.push(bench_point(&exe, "(a) paper beam", &["--model", "paper", "--repeat", &r_a])?);
    let common = ["--params", "30", "--measured", "20"];
    let b_fast = ["--model", "beam:690", "--freqs", "20", "--repeat", &r_b];
    rows.push(bench_point(&exe, "(b) 2k beam, sparse", &[&b_fast[..], &common[..]].concat())?);
    let b_dense = ["--model", "beam:690", "--freqs", "1", "--repeat", "1", "--naive"];
    rows.push(bench_point(&exe, "(b) 2k beam, dense", &[&b_dense[..], &common[..]].concat())?);
    let c = ["--model", "beam:34483", "--freqs", "10", "--repeat", &r_c];
    rows.push(bench_point(&exe, "(c) 100k beam", &[&c[..], &common[..]].concat())?);
    let d = ["--model", "frame:10x11x15", "--params", "1000", "--measured", "20", "--freqs", "200", "--repeat", "1"];
    rows.push(bench_point(&exe, "(d) diagnosis frame", &d)?);

    // scaling in N at 30 parameters, and in parameters at 10k equations
    let mut in_n = Vec::new();
    for elements in [4310, 8620, 17_241, 34_483] {
        let model = format!("beam:{elements}");
        let a = ["--model", &model, "--freqs", "10", "--repeat", &r_c];
        in_n.push(bench_point(&exe, &format!("N sweep, {elements} elements"), &[&a[..], &common[..]].concat())?);
    }
    let mut in_p = Vec::new();
    for params in [30, 100, 300, 1000] {
        let p = params.to_string();
        let a = ["--model", "frame:10x11x15", "--params", &p, "--measured", "20", "--freqs", "20", "--repeat", &r_b];
        in_p.push(bench_point(&exe, &format!("parameter sweep, {params}"), &a)?);
    }
    println!("load average after: {}", load_average());

    println!(
        "\n{:<26} {:>8} {:>7} {:>6} {:>13} {:>13} {:>10} {:>10}",
        "configuration", "DOFs", "params", "lines", "ms per line", "CPU ms/line", "total s", "peak MiB"
    );
    for p in rows.iter().chain(&in_n).chain(&in_p) {
        println!(
            "{:<26} {:>8} {:>7} {:>6} {:>13.3} {:>13.3} {:>10.3} {:>10.1}",
            p.name,
            p.num("dofs"),
            p.num("params"),
            p.num("freqs"),
            p.num("ms_per_freq"),
            p.num("cpu_ms_per_freq"),
            p.num("seconds"),
            p.num("peak_kib") / 1024.0,
        );
    }
    let ratio = rows[2].num("ms_per_freq") / rows[1].num("ms_per_freq");
    println!("\n(b) dense / sparse time per line: {ratio:.0}x");
    // exponents from wall time and from CPU time (all threads), which a
    // busy machine disturbs less
    let fit = |points: &[Point], x: &str, y: &str| {
        loglog_slope(&points.iter().map(|p| (p.num(x), p.num(y))).collect::<Vec<_>>())
    };
    println!(
        "time per line ~ N^{:.2} (wall), N^{:.2} (CPU): long beam, 30 parameters, 12.5k-100k DOFs",
        fit(&in_n, "dofs", "ms_per_freq"),
        fit(&in_n, "dofs", "cpu_ms_per_freq")
    );
    println!(
        "time per line ~ P^{:.2} (wall), P^{:.2} (CPU): 10k-DOF frame, 30-1000 parameters",
        fit(&in_p, "params", "ms_per_freq"),
        fit(&in_p, "params", "cpu_ms_per_freq")
    );
    let (p0, p1) = (&in_p[0], &in_p[in_p.len() - 1]);
    let marginal = |y: &str| 1e3 * (p1.num(y) - p0.num(y)) / (p1.num("params") - p0.num("params"));
    println!(
        "marginal cost per parameter per line: {:.2} us (wall), {:.2} us (CPU)",
        marginal("ms_per_freq"),
        marginal("cpu_ms_per_freq")
    );
    println!("(wall: best run, rayon over lines; CPU: that run's time on the CPU summed over threads)");
    Ok(())
}
