//! `cargo xtask <task>`: the project's automation.
//!
//! - `reproduce [CASE...]`: builds the `rfm` binary (release) and runs every
//!   case study of the paper under `cases/` with the paper's RFM, printing
//!   each table beside the paper's values and writing
//!   `<target>/reproduce/<case>/results.json` and `report.html`; a case whose
//!   `[check]` table has an `output-error` entry runs again with the
//!   output-error estimator (`<case>-output-error/`); then the tutorial loop
//!   (`tutorial`: compare, diagnose, add the leading effect, update). A
//!   summary table ends the run: status, misfit, largest error against the
//!   truth, for the output-error runs the largest distance from the truth in
//!   standard deviations over the parameters the data determine, and whether
//!   the run met its case's `[check]`. Every missed check is printed, and the
//!   task exits non-zero when any was missed.
//! - `figures`: builds the `rfm` binary (release), writes the tutorial's
//!   compare and fix reports and the walkthrough's update report into
//!   `<target>/figures/`, and copies the figures the documentation shows into
//!   `docs/images/` (see `figures.rs`); `RFM_BIN=PATH` uses that `rfm`
//!   binary instead of building one.
//! - `bench [--full]`: builds the `bench_point` example of rfm-update
//!   (release) and runs quick versions of the sensitivity benchmarks, each
//!   configuration in its own process so that its peak memory is its own;
//!   prints a table (time per frequency line, CPU time, peak memory), the
//!   dense/sparse ratio and the fitted scaling exponents in the number of
//!   equations and of parameters. `--full` repeats each run more often.
//!   Then the whole diagnosis end to end on frames of 225 to 96,186 DOFs
//!   (`diagnose_point` example): candidates, time, and whether it named the
//!   hidden effect; it exits non-zero when a diagnosis names the wrong one
//!   or misses its time bound (3k DOFs 3 s, 10k 10 s, 100k 60 s). Then
//!   the loop of `rfm fix` (3 steps, `fix_point` example) on an 8,000-line,
//!   4-channel beam and a 44-channel frame in space, each within 30 s and
//!   with the right answer. `--fix` runs the loop's benchmark alone.
//! - `heldout`: the statistical studies (held-out loop, hidden effects, lab
//!   study) at the size their criteria ask for; `cargo test` runs them
//!   reduced (see `heldout.rs`). CI runs both.
//! - `montecarlo [N]`: how many of `N` seeds (100) of the flexible-clamp and
//!   f-frame twins at 1 % noise the output-error fit brings to the global
//!   minimum (see `montecarlo.rs`).
//! - `mutants [ARGS...]`: the mutation check of the numerical modules with
//!   cargo-mutants (see `mutants.rs`).
//!
//! Binaries are found through cargo's target directory (`CARGO_TARGET_DIR`
//! and cargo's configuration are honoured): `cargo build
//! --message-format=json` names each executable it builds.

mod bench;
mod check;
mod figures;
mod heldout;
mod montecarlo;
mod mutants;
mod reproduce;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("xtask lives in the workspace").to_path_buf()
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("reproduce") => reproduce::reproduce(&args[1..]),
        Some("bench") => bench::bench(&args[1..]),
        Some("mutants") => mutants::mutants(&args[1..]),
        Some("heldout") => heldout::heldout(&args[1..]),
        Some("figures") => figures::figures(),
        Some("montecarlo") => montecarlo::montecarlo(&args[1..]),
        _ => Err("usage: cargo xtask reproduce [CASE... | tutorial] | cargo xtask bench [--full | --fix] | \
                  cargo xtask heldout | cargo xtask figures | cargo xtask montecarlo [N] | \
                  cargo xtask mutants [--list | cargo-mutants options]"
            .to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Cargo's target directory for the workspace, as `cargo metadata` reports
/// it (`CARGO_TARGET_DIR` or the configured one, else `<root>/target`).
fn target_dir() -> Result<PathBuf, String> {
    let out = cargo()
        .current_dir(root())
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !out.status.success() {
        return Err("cargo metadata failed".into());
    }
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).map_err(|e| format!("cargo metadata: {e}"))?;
    json["target_directory"]
        .as_str()
        .map(PathBuf::from)
        .ok_or_else(|| "cargo metadata names no target directory".into())
}

/// Builds in release mode with `args` (which select one executable target)
/// and returns the path of the executable `name`, as cargo reports it.
fn release_build(args: &[&str], name: &str) -> Result<PathBuf, String> {
    let out = cargo()
        .current_dir(root())
        .args(["build", "--release", "--message-format=json-render-diagnostics"])
        .args(args)
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !out.status.success() {
        return Err(format!("building {name} failed"));
    }
    executable_in(&String::from_utf8_lossy(&out.stdout), name)
        .ok_or_else(|| format!("cargo built no executable named {name}"))
}

/// The executable of target `name` among cargo's JSON build messages.
fn executable_in(messages: &str, name: &str) -> Option<PathBuf> {
    messages
        .lines()
        .filter_map(|line| serde_json::from_str::<serde_json::Value>(line).ok())
        .filter(|m| m["reason"] == "compiler-artifact" && m["target"]["name"] == name)
        .find_map(|m| m["executable"].as_str().map(PathBuf::from))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_executable_is_read_from_cargo_messages_not_assumed() {
        let messages = concat!(
            r#"{"reason":"compiler-artifact","target":{"name":"frf","kind":["lib"]},"executable":null}"#,
            "\nnot json\n",
            r#"{"reason":"compiler-artifact","target":{"name":"rfm","kind":["bin"]},"executable":"/elsewhere/release/rfm"}"#,
            "\n",
            r#"{"reason":"build-finished","success":true}"#,
        );
        assert_eq!(executable_in(messages, "rfm"), Some(PathBuf::from("/elsewhere/release/rfm")));
        assert_eq!(executable_in(messages, "frf"), None);
        assert_eq!(executable_in(messages, "bench_point"), None);
    }
}
