//! `cargo xtask <task>`: the project's automation.
//!
//! - `reproduce [CASE...]`: builds the `rfm` binary (release) and runs every
//!   case study of the paper under `cases/`, printing each table beside the
//!   paper's values and writing `target/reproduce/<case>/results.json`.

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
        _ => Err("usage: cargo xtask reproduce [CASE...]".to_string()),
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
