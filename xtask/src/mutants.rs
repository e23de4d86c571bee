//! `cargo xtask mutants`: does each numerical module's test suite catch
//! wrong equations?
//!
//! - `cargo xtask mutants` runs cargo-mutants (`cargo install cargo-mutants`)
//!   with `.cargo/mutants.toml`: the numerical modules only (element
//!   matrices, the damping kernel, `Z` and its derivatives, the
//!   sensitivities, the low-rank (Woodbury) update of the diagnosis, the FRF
//!   kind and unit conversions, the least squares and the covariance), each
//!   mutant tested by its own crate's unit and integration tests. Where
//!   cargo-nextest is installed it runs in two passes: every mutant against
//!   the quick tests, stopping at the first failure, then the mutants that
//!   pass missed against the full suites (`--iterate`). Results go to
//!   `<target>/mutants.out` (`missed.txt` lists the survivors). Further
//!   arguments make it one plain run of cargo-mutants with them: `--list` to
//!   see the mutants, `--iterate` to retest only those not caught last time,
//!   `-f FILE` to narrow the run. A whole run takes three to four hours on
//!   two cores (`docs/mutation-testing.md` has the last one's results).
//! - `cargo xtask mutants --classic` plants the classic equation bugs that
//!   cargo-mutants does not generate (it changes operators and return
//!   values, not coefficients), one at a time in a copy of the workspace,
//!   and fails unless the owning crate's tests catch each: a sign in the
//!   kernel derivative, a consistent-mass coefficient, the sign of the
//!   Woodbury update, the accelerance conversion, the covariance scale. It
//!   takes minutes.
//!
//! Both skip the studies of rfm-update's diagnosis ([`SLOW_TESTS`]: the
//! hidden-effect studies in the plane and in space, the held-out loop):
//! each takes a minute or more per run, and the low-rank update they
//! exercise is checked directly against whole candidate models by
//! `diagnose::local::tests::low_rank_updates_equal_the_candidate_models`
//! (for cargo-mutants the skips are in `.cargo/mutants.toml`; a test here
//! keeps the two lists, and that file's paths, true).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The tests both runs leave out (see the module docs), as libtest's
/// `--skip` filters.
const SLOW_TESTS: [&str; 3] =
    ["hidden_effects::diagnosis_names_hidden_effects_and_updating_recovers_them", "hidden_effects_3d::", "held_out::"];

/// A bug planted by hand: `from` becomes `to` everywhere in `file`.
struct Bug {
    what: &'static str,
    package: &'static str,
    file: &'static str,
    from: &'static str,
    to: &'static str,
}

/// The classic equation bugs of issue 15; each must fail its crate's tests.
const CLASSIC: [Bug; 5] = [
    Bug {
        what: "sign of the relaxation-parameter derivative of the kernel",
        package: "damping",
        file: "crates/damping/src/kernel.rs",
        from: "let c = J * omega * (J * omega * mu) / (den * den);",
        to: "let c = -J * omega * (J * omega * mu) / (den * den);",
    },
    Bug {
        what: "consistent mass coefficient 13L changed to 12L (kept symmetric)",
        package: "fe-model",
        file: "crates/fe-model/src/element.rs",
        from: " 13.0 * l, ",
        to: " 12.0 * l, ",
    },
    Bug {
        what: "sign of the Woodbury (low-rank) update of a candidate's receptance",
        package: "rfm-update",
        file: "crates/rfm-update/src/diagnose/local/response.rs",
        from: "h[c] -= (0..d).map(|i| x[i * k + r] * w.col[i]).sum::<C64>();",
        to: "h[c] += (0..d).map(|i| x[i * k + r] * w.col[i]).sum::<C64>();",
    },
    Bug {
        what: "accelerance conversion +w^2 instead of -w^2",
        package: "frf",
        file: "crates/frf/src/set.rs",
        from: "FrfKind::Accelerance => C64::new(-omega * omega, 0.0),",
        to: "FrfKind::Accelerance => C64::new(omega * omega, 0.0),",
    },
    Bug {
        what: "covariance doubled",
        package: "rfm-update",
        file: "crates/rfm-update/src/output_error/mod.rs",
        from: "sigma2 * sol.scaled_inverse_normal[(i, j)]",
        to: "2.0 * sigma2 * sol.scaled_inverse_normal[(i, j)]",
    },
];

/// Tests of rfm-update that take seconds to minutes and that the quick
/// first pass leaves out beside [`SLOW_TESTS`] (the second pass runs them
/// on the mutants the first pass missed), as nextest name patterns.
const QUICK_PASS_SKIPS: [&str; 3] = [
    "apply_every::",
    "hidden_effects::diagnosis_finds_nothing_significant_when_nothing_is_hidden",
    "hidden_effects::pre_screening_keeps_the_leader",
];

pub(crate) fn mutants(args: &[String]) -> Result<(), String> {
    if args.iter().any(|a| a == "--classic") {
        return classic();
    }
    let installed = crate::cargo().args(["mutants", "--version"]).stdout(Stdio::null()).stderr(Stdio::null()).status();
    if !installed.is_ok_and(|s| s.success()) {
        return Err("cargo-mutants is not installed: cargo install cargo-mutants".into());
    }
    let target = crate::target_dir()?;
    let run = |extra: &[String]| -> Result<std::process::ExitStatus, String> {
        let mut cmd = crate::cargo();
        cmd.current_dir(crate::root()).arg("mutants").arg("--output").arg(&target).args(extra).args(args);
        cmd.status().map_err(|e| format!("cannot run cargo mutants: {e}"))
    };
    let nextest = crate::cargo().args(["nextest", "--version"]).stdout(Stdio::null()).stderr(Stdio::null()).status();
    // with arguments of their own (--list, -f FILE, --iterate) or without
    // nextest: one run with .cargo/mutants.toml, as a plain `cargo mutants`
    let status = if !args.is_empty() || !nextest.is_ok_and(|s| s.success()) {
        run(&[])?
    } else {
        // A mutant caught by a quick test costs its build and a second of
        // testing when the run stops at the first failure (nextest's
        // fail-fast); the full suite of rfm-update takes minutes whatever
        // fails. So a first pass tests every mutant with the quick tests,
        // and a second retests only those it missed with the full suites.
        let quick = target.join("mutants-quick.toml");
        std::fs::write(
            &quick,
            quick_config(
                &std::fs::read_to_string(crate::root().join(".cargo/mutants.toml"))
                    .map_err(|e| format!(".cargo/mutants.toml: {e}"))?,
            )?,
        )
        .map_err(|e| format!("{}: {e}", quick.display()))?;
        println!("first pass: every mutant against the quick tests (nextest, stopping at the first failure)");
        if run(&["--config".into(), quick.display().to_string()])?.success() {
            println!("the first pass caught every mutant");
            std::process::ExitStatus::default()
        } else {
            println!("second pass: the mutants the first pass missed against the full test suites");
            run(&["--iterate".into()])?
        }
    };
    println!("results: {}", target.join("mutants.out").display());
    // cargo-mutants exits non-zero when a mutant survived: pass that on
    if status.success() {
        Ok(())
    } else {
        Err(format!("cargo mutants: {status} (survivors in mutants.out/missed.txt)"))
    }
}

/// The first pass's configuration: `.cargo/mutants.toml` (its text
/// `config`) with nextest for the test tool and [`SLOW_TESTS`] and
/// [`QUICK_PASS_SKIPS`] left out by a filter expression.
fn quick_config(config: &str) -> Result<String, String> {
    let at = config
        .find("test_workspace")
        .ok_or(".cargo/mutants.toml: no `test_workspace` line, where the test settings begin")?;
    let filter = SLOW_TESTS
        .iter()
        .chain(&QUICK_PASS_SKIPS)
        .map(|t| format!("test(/{}/)", t.trim_end_matches("::")))
        .collect::<Vec<_>>()
        .join(" | ");
    Ok(format!(
        "{}test_workspace = false\ntest_tool = \"nextest\"\nadditional_cargo_test_args = [\"--lib\", \"--tests\", \"-E\", \"not ({filter})\"]\nminimum_test_timeout = 120\n",
        &config[..at]
    ))
}

/// Every file a test may read, copied into `dest` (not `target/`, `.git/`
/// or the fuzzing workspace).
fn copy_workspace(from: &Path, dest: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dest).map_err(|e| format!("{}: {e}", dest.display()))?;
    for entry in ["Cargo.toml", "Cargo.lock", ".cargo", "crates", "xtask", "cases", "docs", "README.md"] {
        copy_tree(&from.join(entry), &dest.join(entry))?;
    }
    Ok(())
}

fn copy_tree(from: &Path, to: &Path) -> Result<(), String> {
    let err = |e: std::io::Error| format!("copying {} to {}: {e}", from.display(), to.display());
    if from.is_dir() {
        std::fs::create_dir_all(to).map_err(err)?;
        for entry in std::fs::read_dir(from).map_err(err)? {
            let entry = entry.map_err(err)?;
            copy_tree(&entry.path(), &to.join(entry.file_name()))?;
        }
    } else if from.exists() {
        std::fs::copy(from, to).map_err(err)?;
    }
    Ok(())
}

/// Plants each bug of [`CLASSIC`] in turn in a copy of the workspace and
/// runs the owning crate's tests (sharing cargo's target directory, where
/// the copy's crates build beside the original's).
fn classic() -> Result<(), String> {
    let target = crate::target_dir()?;
    let copy = target.join("mutants-classic").join("workspace");
    if copy.exists() {
        std::fs::remove_dir_all(&copy).map_err(|e| format!("{}: {e}", copy.display()))?;
    }
    copy_workspace(&crate::root(), &copy)?;
    let mut missed = Vec::new();
    for bug in &CLASSIC {
        let path = copy.join(bug.file);
        let original = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let planted = plant(&original, bug)?;
        std::fs::write(&path, &planted).map_err(|e| format!("{}: {e}", path.display()))?;
        println!("\n{} ({}): {}", bug.what, bug.package, bug.file);
        let result = run_tests(&copy, &target, bug.package);
        std::fs::write(&path, &original).map_err(|e| format!("{}: {e}", path.display()))?;
        let (passed, failing) = result?;
        if passed {
            println!("  MISSED: every test of {} passes", bug.package);
            missed.push(bug.what);
        } else {
            println!("  caught by {}", failing.join(", "));
        }
    }
    if missed.is_empty() {
        println!("\nall {} classic bugs are caught", CLASSIC.len());
        Ok(())
    } else {
        Err(format!("no test catches: {}", missed.join("; ")))
    }
}

/// The file with the bug planted, or an error when its text is gone (the
/// code changed: update [`CLASSIC`]).
fn plant(original: &str, bug: &Bug) -> Result<String, String> {
    if !original.contains(bug.from) {
        return Err(format!(
            "{}: `{}` is no longer in the file; update CLASSIC in xtask/src/mutants.rs",
            bug.file, bug.from
        ));
    }
    Ok(original.replace(bug.from, bug.to))
}

/// `cargo test -p PACKAGE --lib --tests` in `copy`: whether it passed, and
/// the tests that failed. A build failure is an error: a planted bug must
/// compile.
fn run_tests(copy: &Path, target: &PathBuf, package: &str) -> Result<(bool, Vec<String>), String> {
    let manifest = copy.join("Cargo.toml");
    let base = |cmd: &mut Command| {
        cmd.env("CARGO_TARGET_DIR", target)
            .arg("test")
            .arg("--manifest-path")
            .arg(&manifest)
            .args(["-p", package, "--lib", "--tests"]);
    };
    let mut build = crate::cargo();
    base(&mut build);
    let built = build.arg("--no-run").status().map_err(|e| format!("cannot run cargo: {e}"))?;
    if !built.success() {
        return Err(format!("the planted bug in {package} does not compile"));
    }
    let mut test = crate::cargo();
    base(&mut test);
    let out = test
        .arg("--")
        .args(SLOW_TESTS.iter().flat_map(|t| ["--skip", t]))
        .stderr(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let failing =
        text.lines().filter_map(|l| l.strip_prefix("test ")?.strip_suffix(" ... FAILED").map(str::to_string)).collect();
    Ok((out.status.success(), failing))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each classic bug still names code that exists once or twice (the
    /// mass coefficient appears in two symmetric places), so that the
    /// `--classic` run plants what it says.
    #[test]
    fn every_classic_bug_applies_to_the_current_code() {
        for bug in &CLASSIC {
            let text = std::fs::read_to_string(crate::root().join(bug.file)).unwrap();
            let count = text.matches(bug.from).count();
            assert!((1..=2).contains(&count), "{}: `{}` found {count} times", bug.file, bug.from);
            assert_ne!(plant(&text, bug).unwrap(), text);
        }
        assert!(plant("nothing here", &CLASSIC[0]).unwrap_err().contains("no longer in the file"));
    }

    /// `.cargo/mutants.toml` names files that exist (a module moved into a
    /// folder would otherwise drop out of the run without a word) and skips
    /// the same tests as `--classic`.
    #[test]
    fn the_mutants_config_names_existing_files_and_the_same_skips() {
        let text = std::fs::read_to_string(crate::root().join(".cargo/mutants.toml")).unwrap();
        let quoted = |l: &str| l.trim().strip_prefix('"').and_then(|r| r.split('"').next()).map(str::to_string);
        let files: Vec<String> = text.lines().filter_map(quoted).filter(|q| q.starts_with("crates/")).collect();
        assert!(files.len() >= 10, "{files:?}");
        for f in &files {
            assert!(crate::root().join(f).is_file(), ".cargo/mutants.toml examines {f}, which does not exist");
        }
        let skips: Vec<String> = text
            .lines()
            .filter_map(|l| l.trim().strip_prefix("\"--skip\", "))
            .filter_map(|r| r.strip_prefix('"')?.split('"').next().map(str::to_string))
            .collect();
        assert_eq!(skips, SLOW_TESTS.map(str::to_string));
        // the first pass examines the same files with the quick tests
        let quick = quick_config(&text).unwrap();
        let examined = |t: &str| t.lines().filter_map(quoted).filter(|q| q.starts_with("crates/")).count();
        assert_eq!(examined(&quick), files.len());
        for t in SLOW_TESTS.iter().chain(&QUICK_PASS_SKIPS) {
            assert!(quick.contains(&format!("test(/{}/)", t.trim_end_matches("::"))), "{t}");
        }
        assert!(quick.contains("test_tool = \"nextest\""));
    }
}
