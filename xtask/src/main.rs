//! `cargo xtask <task>`: the project's automation.
//!
//! - `reproduce [CASE...]`: builds the `rfm` binary (release) and runs every
//!   case study of the paper under `cases/` with the paper's RFM, printing
//!   each table beside the paper's values and writing
//!   `target/reproduce/<case>/results.json` and `report.html`; cases 3, 5 and
//!   6 again with the output-error estimator (`<case>-output-error/`); then
//!   the tutorial loop (`tutorial`: compare, diagnose, add the leading effect,
//!   update; it fails unless the misfit falls tenfold). A summary table ends
//!   the run: status, misfit, largest error against the truth, and for the
//!   output-error runs the largest distance from the truth in standard
//!   deviations over the parameters the data determine.
//! - `figures`: builds the `rfm` binary (release), writes the tutorial's
//!   compare and fix reports and the walkthrough's update report into
//!   `target/figures/`, and copies the figures the documentation shows into
//!   `docs/images/` (see [`FIGURES`]); `RFM_BIN=PATH` uses that `rfm`
//!   binary instead of building one.
//! - `bench [--full]`: builds the `bench_point` example of rfm-update
//!   (release) and runs quick versions of the sensitivity benchmarks, each
//!   configuration in its own process so that its peak memory is its own;
//!   prints a table (time per frequency line, CPU time, peak memory), the
//!   dense/sparse ratio and the fitted scaling exponents in the number of
//!   equations and of parameters. `--full` repeats each run more often.
//!   Then the whole diagnosis end to end on two small frames
//!   (`diagnose_point` example): candidates, time, and whether it named the
//!   hidden effect.

use std::ffi::OsStr;
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
        Some("figures") => figures(),
        _ => {
            Err("usage: cargo xtask reproduce [CASE... | tutorial] | cargo xtask figures | cargo xtask bench [--full]"
                .to_string())
        }
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

/// Cases also run with the output-error estimator: the noisy beam (the RFM is
/// biased there) and the two twins whose RFM iterations do not converge.
const OUTPUT_ERROR_CASES: [&str; 3] = ["two-material-beam-noisy", "cantilever-flexible-clamp", "f-frame"];

/// The tutorial: a model missing a joint and data from the frame that has it.
const TUTORIAL: &str = "tutorial";

/// One finished `rfm update` run, as its summary row.
struct Run {
    label: String,
    method: &'static str,
    json: serde_json::Value,
    report: PathBuf,
}

fn run_rfm(rfm: &Path, args: &[&std::ffi::OsStr], what: &str) -> Result<(), String> {
    let status = Command::new(rfm).args(args).status().map_err(|e| format!("cannot run {}: {e}", rfm.display()))?;
    if status.success() { Ok(()) } else { Err(format!("{what} failed")) }
}

fn read_json(path: &Path) -> Result<serde_json::Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// `rfm update CASE [--method output-error] --out OUT`, then its results.
fn update(rfm: &Path, case: &Path, out: &Path, method: &'static str, label: &str) -> Result<Run, String> {
    println!("\n==================== {label} ({method}) ====================");
    let args = [OsStr::new("update"), case.as_os_str(), OsStr::new("--method"), OsStr::new(method)];
    run_rfm(rfm, &[&args[..], &[OsStr::new("--out"), out.as_os_str()]].concat(), &format!("case {label} ({method})"))?;
    Ok(Run {
        label: label.to_string(),
        method,
        json: read_json(&out.join("results.json"))?,
        report: out.join("report.html"),
    })
}

fn reproduce(cases: &[String]) -> Result<(), String> {
    let mut names: Vec<String> = if cases.is_empty() {
        PAPER_CASES.iter().chain(&[TUTORIAL]).map(|s| s.to_string()).collect()
    } else {
        cases.to_vec()
    };
    let tutorial = names.iter().any(|n| n == TUTORIAL);
    names.retain(|n| n != TUTORIAL);
    let rfm = build_cli()?;
    let base = root().join("target/reproduce");
    let mut runs = Vec::new();
    for name in &names {
        let case = root().join("cases").join(format!("{name}.toml"));
        if !case.exists() {
            return Err(format!("no case file {}", case.display()));
        }
        runs.push(update(&rfm, &case, &base.join(name), "rfm", name)?);
        if OUTPUT_ERROR_CASES.contains(&name.as_str()) {
            runs.push(update(&rfm, &case, &base.join(format!("{name}-output-error")), "output-error", name)?);
        }
    }
    let loop_summary = if tutorial { Some(tutorial_loop(&rfm, &base.join(TUTORIAL), &mut runs)?) } else { None };

    println!("\n==================== summary ====================");
    println!(
        "{:<32} {:>12} {:>14} {:>11} {:>20} {:>18}",
        "case", "method", "status", "misfit", "max error vs truth", "max |z| (std)"
    );
    for run in &runs {
        let json = &run.json;
        let status = json["status"].as_str().map(str::to_string).unwrap_or_else(|| json["status"].to_string());
        let residual = json["residual"].as_f64().unwrap_or(f64::NAN);
        let params = json["parameters"].as_array().cloned().unwrap_or_default();
        let max_err = params
            .iter()
            .filter_map(|p| {
                let (u, t) = (p["updated"].as_f64()?, p["truth"].as_f64()?);
                Some(((u - t) / t).abs())
            })
            .fold(f64::NAN, f64::max);
        // distance from the truth in standard deviations, over the parameters the data determine
        let unc = json["uncertainty"]["parameters"].as_array().cloned().unwrap_or_default();
        let (mut max_z, mut undetermined) = (f64::NAN, 0);
        for (p, u) in params.iter().zip(&unc) {
            if u["well_determined"].as_bool() != Some(true) {
                undetermined += 1;
                continue;
            }
            if let (Some(v), Some(t), Some(s)) =
                (p["updated"].as_f64(), p["truth"].as_f64(), u["relative_std"].as_f64())
            {
                max_z = f64::max(max_z, (v / t).ln().abs() / s);
            }
        }
        let z = if unc.is_empty() || max_z.is_nan() {
            // no uncertainty (RFM) or no truth to measure against
            "-".to_string()
        } else if undetermined > 0 {
            format!("{max_z:.2} ({undetermined} undet.)")
        } else {
            format!("{max_z:.2}")
        };
        let err = if max_err.is_nan() { "-".to_string() } else { format!("{max_err:.2e}") };
        println!("{:<32} {:>12} {:>14} {residual:>11.3e} {err:>20} {z:>18}", run.label, run.method, status);
    }
    if let Some(text) = loop_summary {
        println!("\n{text}");
    }
    println!("\nreports (self-contained HTML with the figures; open in a browser):");
    for run in runs.iter().filter(|r| r.report.exists()) {
        println!("  {}", run.report.display());
    }
    if tutorial {
        println!("  {}", base.join(TUTORIAL).join("compare/report.html").display());
    }
    println!("\nresults: {}", base.display());
    Ok(())
}

/// The walkthrough of `docs/walkthrough.md`: compare the tutorial model with
/// its data, diagnose, add the leading effect, update, and check that the
/// misfit falls at least tenfold.
fn tutorial_loop(rfm: &Path, out: &Path, runs: &mut Vec<Run>) -> Result<String, String> {
    let case = root().join("cases/tutorial/l-frame.toml");
    println!("\n==================== tutorial: compare ====================");
    let compare = out.join("compare");
    run_rfm(rfm, &[OsStr::new("compare"), case.as_os_str(), OsStr::new("--out"), compare.as_os_str()], "rfm compare")?;

    println!("\n==================== tutorial: diagnose ====================");
    let added = out.join("l-frame-with-effect.toml");
    let diagnosis = Command::new(rfm)
        .args([OsStr::new("diagnose"), case.as_os_str(), OsStr::new("--json"), OsStr::new("--apply"), OsStr::new("1")])
        .args([OsStr::new("--out"), added.as_os_str()])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", rfm.display()))?;
    if !diagnosis.status.success() {
        return Err(format!("rfm diagnose failed:\n{}", String::from_utf8_lossy(&diagnosis.stderr)));
    }
    let json: serde_json::Value = serde_json::from_slice(&diagnosis.stdout).map_err(|e| format!("diagnosis: {e}"))?;
    let path = out.join("diagnosis.json");
    std::fs::write(&path, &diagnosis.stdout).map_err(|e| format!("{}: {e}", path.display()))?;
    let ranking = json["ranking"].as_array().cloned().unwrap_or_default();
    println!("{:>4}  {:<56} {:>10} {:>12}", "rank", "effect", "explained", "significant");
    for (i, c) in ranking.iter().take(5).enumerate() {
        let explained = 100.0 * c["explained"].as_f64().unwrap_or(f64::NAN);
        let description = c["description"].as_str().unwrap_or("?");
        println!("{:>4}  {description:<56} {explained:>9.2}% {:>12}", i + 1, c["significant"]);
    }
    let leader = ranking.first().ok_or("the diagnosis ranked no candidate")?;
    if leader["significant"].as_bool() != Some(true) {
        return Err("the tutorial's diagnosis found no significant effect".into());
    }
    println!("wrote {} with the leading effect added", added.display());

    let run = update(rfm, &added, &out.join("update"), "output-error", "tutorial (effect added)")?;
    // both are RMS FRF misfits per residual over the measured channels (the
    // diagnosis over every line, the update over its chosen lines)
    let nominal = json["nominal_misfit"].as_f64().unwrap_or(f64::NAN);
    let last = run.json["residual"].as_f64().unwrap_or(f64::NAN);
    runs.push(run);
    let fall = nominal / last;
    if !(fall >= 10.0) {
        return Err(format!("tutorial: the misfit fell only {fall:.1} times (from {nominal:.3e} to {last:.3e})"));
    }
    Ok(format!(
        "tutorial: the diagnosis named \"{}\" first; with it added and updated the misfit fell\n\
         {fall:.0} times, from {nominal:.3e} (nominal model) to {last:.3e}",
        leader["description"].as_str().unwrap_or("?"),
    ))
}

/// The figures of `docs/`: (report, figure in it, name under `docs/images/`).
/// `update` is the walkthrough's update from its hand-written guess.
const FIGURES: [(&str, &str, &str); 10] = [
    ("compare", "frf-23uy-23uy.svg", "tutorial-before-23uy.svg"),
    ("compare", "error-vs-frequency.svg", "tutorial-error-before.svg"),
    ("compare", "frf-channels.svg", "tutorial-channels.svg"),
    ("compare", "mac-matrix.svg", "tutorial-mac.svg"),
    ("compare", "stabilisation.svg", "tutorial-stabilisation.svg"),
    ("compare", "mode-shapes.svg", "tutorial-mode-shapes.svg"),
    ("fix", "misfit-steps.svg", "tutorial-fix-misfit.svg"),
    ("fix", "structure.svg", "tutorial-fix-structure.svg"),
    ("update", "convergence.svg", "tutorial-convergence.svg"),
    ("update", "frf-23uy-23uy.svg", "tutorial-after-23uy.svg"),
];

/// The walkthrough's guess (`docs/walkthrough.md`, section 3): the tutorial
/// case with the lines of the walkthrough's first `toml` block added, its
/// measured data named by absolute path so that the case can live elsewhere.
fn walkthrough_guess() -> Result<String, String> {
    let read = |p: &Path| std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()));
    let doc = read(&root().join("docs/walkthrough.md"))?;
    let start = doc.find("```toml\n").ok_or("docs/walkthrough.md has no toml block")? + "```toml\n".len();
    let len = doc[start..].find("```").ok_or("docs/walkthrough.md: an unclosed toml block")?;
    let tutorial = root().join("cases/tutorial");
    let case = read(&tutorial.join("l-frame.toml"))?;
    let data = tutorial.join("l-frame-measured.csv");
    let case = case.replace("data = \"l-frame-measured.csv\"", &format!("data = {:?}", data.display().to_string()));
    Ok(format!("{case}\n{}", &doc[start..start + len]))
}

/// Writes the tutorial's compare and fix reports and the walkthrough's
/// update report, and copies [`FIGURES`] into `docs/images/`, so that every
/// figure the documentation shows is what the tool draws today.
fn figures() -> Result<(), String> {
    // a binary already built (`RFM_BIN=target/debug/rfm`) spares the release build
    let rfm = match std::env::var_os("RFM_BIN") {
        Some(bin) => PathBuf::from(bin),
        None => build_cli()?,
    };
    let case = root().join("cases/tutorial/l-frame.toml");
    let base = root().join("target/figures");
    std::fs::create_dir_all(&base).map_err(|e| format!("{}: {e}", base.display()))?;
    let guess = base.join("l-frame-guess.toml");
    std::fs::write(&guess, walkthrough_guess()?).map_err(|e| format!("{}: {e}", guess.display()))?;
    for (command, case) in [("compare", &case), ("fix", &case), ("update", &guess)] {
        println!("rfm {command} {} --out {}", case.display(), base.join(command).display());
        let out = Command::new(&rfm)
            .args([OsStr::new(command), case.as_os_str(), OsStr::new("--out"), base.join(command).as_os_str()])
            .output()
            .map_err(|e| format!("cannot run {}: {e}", rfm.display()))?;
        if !out.status.success() {
            return Err(format!("rfm {command} failed:\n{}", String::from_utf8_lossy(&out.stderr)));
        }
    }
    let images = root().join("docs/images");
    for (report, figure, name) in FIGURES {
        let (from, to) = (base.join(report).join(figure), images.join(name));
        std::fs::copy(&from, &to).map_err(|e| format!("{} -> {}: {e}", from.display(), to.display()))?;
        println!("wrote {}", to.display());
    }
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

/// Builds an example of rfm-update in release mode; returns its path.
fn release_example(name: &str) -> Result<PathBuf, String> {
    let status = cargo()
        .current_dir(root())
        .args(["build", "--release", "--quiet", "-p", "rfm-update", "--example", name])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("building {name} failed"));
    }
    Ok(root().join("target/release/examples").join(name))
}

fn bench(args: &[String]) -> Result<(), String> {
    let full = args.iter().any(|a| a == "--full");
    let exe = release_example("bench_point")?;
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

    // (d) above is the diagnosis's sensitivity workload, one linearised pass
    // over 1,000 candidate parameters; the diagnosis itself fits every
    // candidate nonlinearly (by low-rank updates of the nominal model):
    // measured here end to end
    let exe = release_example("diagnose_point")?;
    println!("\nwhole diagnosis (nonlinear fit of every candidate), a 40 % stiffness loss hidden in one element:");
    println!(
        "{:<30} {:>6} {:>11} {:>6} {:>10} {:>9}  leader",
        "configuration", "DOFs", "candidates", "lines", "total s", "peak MiB"
    );
    for frame in ["3x3x4", "5x5x5", "8x8x8", "10x11x15"] {
        let p = bench_point(&exe, &format!("frame {frame}"), &["--frame", frame])?;
        let found = if p.json["found"].as_bool() == Some(true) { "(right)" } else { "(WRONG)" };
        println!(
            "{:<30} {:>6} {:>11} {:>6} {:>10.2} {:>9.1}  {} {found}",
            p.json["label"].as_str().unwrap_or("?"),
            p.num("dofs"),
            p.num("candidates"),
            p.num("freqs"),
            p.num("seconds"),
            p.num("peak_kib") / 1024.0,
            p.json["leader"].as_str().unwrap_or("?"),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every image the README and `docs/` show is one `cargo xtask figures`
    /// draws, and is there: a figure nobody can redraw would drift from
    /// what the tool draws.
    #[test]
    fn every_image_the_documentation_shows_is_drawn_by_figures() {
        let mut pages = vec![root().join("README.md")];
        for e in std::fs::read_dir(root().join("docs")).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "md") {
                pages.push(p);
            }
        }
        let drawn: Vec<&str> = FIGURES.iter().map(|f| f.2).collect();
        let mut shown = 0;
        for page in &pages {
            let text = std::fs::read_to_string(page).unwrap();
            for (i, _) in text.match_indices("images/") {
                let rest = &text[i + "images/".len()..];
                let name = &rest[..rest.find([')', '"', ' ', '\n']).unwrap_or(rest.len())];
                assert!(
                    drawn.contains(&name),
                    "{} shows images/{name}, which cargo xtask figures does not draw",
                    page.display()
                );
                assert!(root().join("docs/images").join(name).is_file(), "docs/images/{name} is missing");
                shown += 1;
            }
        }
        assert!(shown >= FIGURES.len(), "only {shown} images shown");
    }

    #[test]
    fn the_walkthrough_guess_adds_the_joint_and_names_the_data_by_absolute_path() {
        let guess = walkthrough_guess().unwrap();
        assert!(guess.contains("[[joints]]") && guess.contains("[update]"), "{guess}");
        let data = root().join("cases/tutorial/l-frame-measured.csv");
        assert!(guess.contains(&format!("data = {:?}", data.display().to_string())), "{guess}");
    }
}
