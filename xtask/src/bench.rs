//! `cargo xtask bench`: quick versions of the sensitivity benchmarks, each
//! configuration in its own process, then the whole diagnosis end to end.

use std::path::Path;
use std::process::Command;

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

/// (e) A normal update end to end: `rfm update --method output-error` on
/// the tutorial and the paper's twins, best of three, with its status and
/// how many restarts it needed (restarts are made only when the first fit
/// ends above the noise or without converging; the issue allows a normal
/// update to become at most 3 times slower for them).
fn update_times() -> Result<(), String> {
    let rfm = crate::release_build(&["-p", "rfm-cli", "--bin", "rfm"], "rfm")?;
    println!("\nupdate end to end (rfm update --method output-error --json, best of 3):");
    println!("{:<32} {:>9} {:>9}  status", "case", "wall s", "restarts");
    for case in ["tutorial/l-frame-guess", "two-material-beam-noisy", "cantilever-flexible-clamp", "f-frame"] {
        let path = crate::root().join("cases").join(format!("{case}.toml"));
        let mut best = f64::INFINITY;
        let mut json = serde_json::Value::Null;
        for _ in 0..3 {
            let start = std::time::Instant::now();
            let out = Command::new(&rfm)
                .args(["update", path.to_str().unwrap_or_default(), "--method", "output-error", "--json"])
                .output()
                .map_err(|e| format!("cannot run {}: {e}", rfm.display()))?;
            best = best.min(start.elapsed().as_secs_f64());
            json = serde_json::from_slice(&out.stdout).map_err(|e| format!("{case}: no JSON result ({e})"))?;
        }
        let restarts = json["restarts"].as_array().map_or(0, Vec::len);
        println!("{case:<32} {best:>9.3} {restarts:>9}  {}", crate::check::status_name(&json));
    }
    Ok(())
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

/// Largest wall time of one line of the imported shell (e) on one thread
/// (ms): the target, a line of 99k DOFs with a shell mesh's fill
/// in half a second.
const SHELL_LINE_MS: f64 = 500.0;

/// faer's own supernodal `L D L^H` line (factorisation and 20 solves, one
/// thread) on the same shell when the issue was filed (ms: 285 + 123): the
/// target [`SHELL_LINE_MS`] was 1.23 times it. A host's speed moves both
/// (the same line took 769 ms on a slower day of the same machine), so the
/// bench also times faer on this host now and holds rfm's line to that
/// ratio of it.
const FAER_LINE_AT_FILING_MS: f64 = 408.0;

/// Wall times (ms) of one line of the imported shell on one thread, from
/// the `layouts` example of frf: rfm's supernodal layout and faer's `L D
/// L^H` of the same matrix (same pattern, ordering family and arithmetic),
/// each the factorisation plus a solve for 20 right-hand sides, best of 3.
fn shell_against_faer() -> Result<(f64, f64), String> {
    let exe = crate::release_build(&["-p", "frf", "--example", "layouts"], "layouts")?;
    let line = |layout: &str| -> Result<f64, String> {
        let out = Command::new(&exe)
            .args(["plate:128", "--rhs", "20", "--repeat", "3", "--layout", layout])
            .output()
            .map_err(|e| format!("cannot run layouts: {e}"))?;
        if !out.status.success() {
            return Err(format!("layouts --layout {layout} failed: {}", String::from_utf8_lossy(&out.stderr)));
        }
        let text = String::from_utf8_lossy(&out.stdout);
        // the row's last columns: factor, solve, CPU factor, CPU solve
        // (ms), then "yes" where the layout is the one the analysis picks
        let row = text.lines().nth(1).ok_or_else(|| format!("layouts printed no row: {text}"))?;
        let numbers: Vec<f64> = row.split_whitespace().filter_map(|t| t.parse().ok()).collect();
        match numbers[..] {
            [.., factor, solve, _, _] => Ok(factor + solve),
            _ => Err(format!("cannot read the layouts row {row:?}")),
        }
    };
    Ok((line("supernodal")?, line("faer")?))
}

/// The imported shell (e) against the beam of the same size (c), both on
/// one thread: what a line costs in all and per entry of the factor, split
/// into the numeric factorisation (per multiply-add, which a shell needs
/// tens of times more of per entry) and the rest (making `Z`, the solves and
/// the sensitivity assembly, per entry). Returns the bounds missed: the
/// shell's line within [`SHELL_LINE_MS`] and within the beam's cost per
/// factor entry, and each part within 1.5 times the beam's, so that an
/// imported model costs what its factor says and nothing more.
fn imported_against_beam(beam: &Point, shell: &Point) -> Vec<String> {
    let line = |p: &Point| p.num("ms_per_freq");
    let per_entry = |p: &Point| 1e6 * p.num("ms_per_freq") / p.num("factor_nnz");
    let rest = |p: &Point| 1e6 * (p.num("ms_per_freq") - p.num("factor_ms_per_freq")) / p.num("factor_nnz");
    let per_madd = |p: &Point| 1e6 * p.num("factor_ms_per_freq") / p.num("factor_madds");
    println!("\nper line on one thread, imported shell (e) against the beam (c), both 100k DOFs:");
    println!("{:<34} {:>12} {:>12} {:>7}  bound", "", "beam", "shell", "ratio");
    let mut missed = Vec::new();
    type Measure = fn(&Point) -> f64;
    for (what, f, relative, absolute) in [
        ("ms per line", line as Measure, None, Some(SHELL_LINE_MS)),
        ("ns per factor entry, in all", per_entry, Some(1.0), None),
        ("  Z, solves and assembly, per entry", rest, Some(1.5), None),
        ("  factorisation, per multiply-add", per_madd, Some(1.5), None),
    ] {
        let (b, s) = (f(beam), f(shell));
        let bound = match (relative, absolute) {
            (Some(r), _) => format!("shell <= {r} x beam"),
            (_, Some(a)) => format!("shell <= {a}"),
            _ => String::new(),
        };
        println!("{what:<34} {b:>12.4} {s:>12.4} {:>6.2}x  {bound}", s / b);
        if let Some(r) = relative
            && !(s <= r * b)
        {
            missed.push(format!("imported shell: {} {s:.4}, over {r} x the beam's {b:.4}", what.trim()));
        }
        if let Some(a) = absolute
            && !(s <= a)
        {
            missed.push(format!("imported shell: {} {s:.1}, over its bound of {a}", what.trim()));
        }
    }
    println!(
        "(factor layouts: beam {}, shell {}; multiply-adds per factor entry: beam {:.0}, shell {:.0})",
        beam.json["layout"].as_str().unwrap_or("?"),
        shell.json["layout"].as_str().unwrap_or("?"),
        beam.num("factor_madds") / beam.num("factor_nnz"),
        shell.num("factor_madds") / shell.num("factor_nnz")
    );
    missed
}

/// Wall time (s) within which `rfm fix` runs 3 steps on test-resolution
/// data (issue 35): an 8,000-line, 4-channel file of a 100-element beam
/// and a 3D frame measured at 44 channels from two references.
const FIX_SECONDS: f64 = 30.0;

/// The loop of `rfm fix` end to end (`fix_point`): 3 steps on each
/// workload, with its wall and CPU time and the load average the machine
/// ran it at. Returns the bounds missed: over [`FIX_SECONDS`], or a wrong
/// answer (a hidden effect not found, an effect added that is none of
/// them, or a final misfit above 1.5 times the noise), which fails however
/// fast it came.
fn fix_times() -> Result<Vec<String>, String> {
    let exe = release_example("fix_point")?;
    println!("\nthe loop of rfm fix, 3 steps, on test-resolution data (bound {FIX_SECONDS} s of wall time):");
    println!(
        "{:<26} {:>5} {:>8} {:>6} {:>8} {:>8} {:>16} {:>8}  effects at the end",
        "workload", "DOFs", "channels", "lines", "wall s", "CPU s", "load before", "x noise"
    );
    let mut missed = Vec::new();
    for model in ["beam", "tower"] {
        let p = bench_point(&exe, &format!("fix {model}"), &["--model", model, "--steps", "3"])?;
        let label = p.json["label"].as_str().unwrap_or("?").to_string();
        let effects: Vec<&str> =
            p.json["effects"].as_array().map(|a| a.iter().filter_map(|e| e.as_str()).collect()).unwrap_or_default();
        let right = p.json["right"].as_bool() == Some(true);
        println!(
            "{label:<26} {:>5} {:>8} {:>6} {:>8.1} {:>8.1} {:>16} {:>8.2}  {} {}",
            p.num("dofs"),
            p.num("channels"),
            p.num("freqs"),
            p.num("seconds"),
            p.num("cpu_seconds"),
            p.json["load_before"].as_str().unwrap_or("?"),
            p.num("misfit_over_noise"),
            effects.join("; "),
            if right { "(right)" } else { "(WRONG)" }
        );
        if !right {
            missed.push(format!(
                "fix {model}: the loop ended with [{}] at {:.2} times the noise, where it should find [{}] and nothing \
                 else within 1.5",
                effects.join("; "),
                p.num("misfit_over_noise"),
                p.json["hidden"].as_array().map_or(String::new(), |a| a
                    .iter()
                    .filter_map(|e| e.as_str())
                    .collect::<Vec<_>>()
                    .join("; "))
            ));
        }
        if !(p.num("seconds") <= FIX_SECONDS) {
            missed.push(format!(
                "fix {model}: 3 steps took {:.1} s ({:.1} s of CPU at a load average of {}), over its bound of \
                 {FIX_SECONDS} s",
                p.num("seconds"),
                p.num("cpu_seconds"),
                p.json["load_before"].as_str().unwrap_or("?")
            ));
        }
    }
    Ok(missed)
}

/// Builds an example of rfm-update in release mode; returns its path.
fn release_example(name: &str) -> Result<std::path::PathBuf, String> {
    crate::release_build(&["-p", "rfm-update", "--example", name], name)
}

pub(crate) fn bench(args: &[String]) -> Result<(), String> {
    if args.iter().any(|a| a == "--fix") {
        println!("machine: {}", machine());
        let missed = fix_times()?;
        return if missed.is_empty() { Ok(()) } else { Err(format!("missed bounds:\n  {}", missed.join("\n  "))) };
    }
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
    // an imported model of 100k DOFs with a shell's sparsity (six DOFs per
    // node, 30 non-zeros per inner row), against the beam of the same size
    let e = ["--model", "shell:128", "--freqs", "4", "--repeat", &r_c];
    rows.push(bench_point(&exe, "(e) 100k imported shell", &[&e[..], &common[..]].concat())?);
    // (c) and (e) again on one thread, where a line's cost is its own
    let one = ["--threads", "1"];
    rows.push(bench_point(&exe, "(c) 100k beam, 1 thread", &[&c[..], &common[..], &one[..]].concat())?);
    rows.push(bench_point(&exe, "(e) 100k shell, 1 thread", &[&e[..], &common[..], &one[..]].concat())?);
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
    let mut shell_bounds = imported_against_beam(&rows[5], &rows[6]);
    let (ours, faer) = shell_against_faer()?;
    let ratio = SHELL_LINE_MS / FAER_LINE_AT_FILING_MS;
    println!(
        "same shell, same host, now: rfm supernodal {ours:.0} ms, faer LDL^H {faer:.0} ms per line \
         (factor + 20 solves, one thread): {:.2}x, bound {ratio:.2}x (the issue's {SHELL_LINE_MS} ms \
         against faer's {FAER_LINE_AT_FILING_MS} ms when filed)",
        ours / faer
    );
    if !(ours <= ratio * faer) {
        shell_bounds.push(format!("imported shell: rfm's line {ours:.0} ms, over {ratio:.2} x faer's {faer:.0} ms"));
    }
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
        "{:<30} {:>6} {:>11} {:>6} {:>10} {:>8} {:>9}  leader",
        "configuration", "DOFs", "candidates", "lines", "total s", "CPU s", "peak MiB"
    );
    let mut wrong = Vec::new();
    // the issues' bounds on two cores: the 3k-DOF frame within 3 s, the
    // 10k-DOF frame within 10 s (interactive), the 100k-DOF frame within
    // 30 s (issue 35; 60 s before)
    let frames =
        [("3x3x4", None), ("5x5x5", None), ("8x8x8", Some(3.0)), ("10x11x15", Some(10.0)), ("32x34x15", Some(30.0))];
    for (frame, bound) in frames {
        let p = bench_point(&exe, &format!("frame {frame}"), &["--frame", frame])?;
        let right = p.json["found"].as_bool() == Some(true);
        if !right {
            wrong.push(format!(
                "frame {frame}: the diagnosis ranked \"{}\" first",
                p.json["leader"].as_str().unwrap_or("?")
            ));
        }
        if let Some(b) = bound
            && !(p.num("seconds") <= b)
        {
            wrong.push(format!("frame {frame}: the diagnosis took {:.2} s, over its bound of {b} s", p.num("seconds")));
        }
        let found = if right { "(right)" } else { "(WRONG)" };
        println!(
            "{:<30} {:>6} {:>11} {:>6} {:>10.2} {:>8.2} {:>9.1}  {} {found}",
            p.json["label"].as_str().unwrap_or("?"),
            p.num("dofs"),
            p.num("candidates"),
            p.num("freqs"),
            p.num("seconds"),
            p.num("cpu_seconds"),
            p.num("peak_kib") / 1024.0,
            p.json["leader"].as_str().unwrap_or("?"),
        );
    }
    // the bounds are on wall time for two cores; on a loaded machine the
    // CPU time (all threads) says what the diagnosis itself cost
    println!("(CPU s: summed over threads; load average after the diagnoses: {})", load_average());
    wrong.extend(fix_times()?);
    update_times()?;
    wrong.extend(shell_bounds);
    // a diagnosis that misses the hidden effect is a failure, however fast
    if !wrong.is_empty() {
        return Err(format!("missed bounds:\n  {}", wrong.join("\n  ")));
    }
    Ok(())
}
