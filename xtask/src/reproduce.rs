//! `cargo xtask reproduce`: the paper's case studies and the loops
//! (compare, diagnose, add, update) of the tutorial and the frame in space,
//! each held to its case file's `[check]` table.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use fe_model::CaseFile;
use fe_model::case::RunCheck;

use crate::check;

/// The paper's case studies, in the paper's order: the names in
/// `cases/paper-cases.txt`, the one list of them (rfm-update's tests read it
/// too).
fn paper_cases() -> impl Iterator<Item = &'static str> {
    include_str!("../../cases/paper-cases.txt").lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#'))
}

/// Cases beyond the paper's, run as they are: a model imported from
/// another code's matrices (`docs/imported-models.md`).
const MORE_CASES: [&str; 1] = ["imported/table"];

/// The loops: a name (as `reproduce` takes it) and its case, a model
/// missing an effect and data with it (a data file, or the case's
/// `[truth]`), held to the case's `[check.diagnosis]`. The tutorial's is
/// the walkthrough of `docs/walkthrough.md`; the lap joint's that of
/// `docs/walkthrough-test-data.md` (test data per volt, with coherence);
/// the table's is a frame in space with a loose corner joint.
const LOOPS: [(&str, &str); 3] = [
    ("tutorial", "cases/tutorial/l-frame.toml"),
    ("lap-joint", "cases/tutorial/lap-joint.toml"),
    ("table-frame", "cases/table-frame.toml"),
];

/// One finished `rfm update` run, as its summary row, with the check it was
/// held to and what it missed.
struct Run {
    label: String,
    method: &'static str,
    json: serde_json::Value,
    report: PathBuf,
    /// `None` when the case sets no check for this run.
    failures: Option<Vec<String>>,
}

/// The exit codes of `rfm update` when the fit ended without converging but
/// wrote its results (rfm's exit table: not converged, stalled, model
/// inadequate, local minimum, worse than the start, run-away): the case's
/// `[check]` judges the status, so reproduce reads the results rather than
/// stopping. A test keeps it equal to the codes `docs/reliability.md` says
/// write their results.
const WRITTEN_NOT_CONVERGED: [i32; 6] = [5, 8, 9, 10, 11, 12];

fn run_rfm(rfm: &Path, args: &[&OsStr], what: &str) -> Result<(), String> {
    let status = Command::new(rfm).args(args).status().map_err(|e| format!("cannot run {}: {e}", rfm.display()))?;
    match status.code() {
        Some(0) => Ok(()),
        Some(code) if WRITTEN_NOT_CONVERGED.contains(&code) && args.first() == Some(&OsStr::new("update")) => Ok(()),
        _ => Err(format!("{what} failed ({status})")),
    }
}

fn read_json(path: &Path) -> Result<serde_json::Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// `rfm update CASE --method METHOD --out OUT`, then its results, held to
/// `check` (with the truth's noise level for its `noise` entry).
fn update(
    rfm: &Path,
    case: &Path,
    out: &Path,
    method: &'static str,
    label: &str,
    check: Option<(&RunCheck, Option<f64>)>,
) -> Result<Run, String> {
    println!("\n==================== {label} ({method}) ====================");
    let args = [OsStr::new("update"), case.as_os_str(), OsStr::new("--method"), OsStr::new(method)];
    run_rfm(rfm, &[&args[..], &[OsStr::new("--out"), out.as_os_str()]].concat(), &format!("case {label} ({method})"))?;
    let json = read_json(&out.join("results.json"))?;
    let failures = check.map(|(c, noise)| check::run_failures(c, &json, noise));
    Ok(Run { label: label.to_string(), method, json, report: out.join("report.html"), failures })
}

pub(crate) fn reproduce(cases: &[String]) -> Result<(), String> {
    let mut names: Vec<String> = if cases.is_empty() {
        paper_cases().chain(MORE_CASES).chain(LOOPS.map(|(name, _)| name)).map(str::to_string).collect()
    } else {
        cases.to_vec()
    };
    let loops: Vec<(&str, PathBuf)> = LOOPS
        .iter()
        .filter(|(name, _)| names.iter().any(|n| n == name))
        .map(|&(name, path)| (name, crate::root().join(path)))
        .collect();
    names.retain(|n| !LOOPS.iter().any(|(name, _)| name == n));
    // read every case (and its checks) before the long build and runs, so
    // that a mistake in one is reported at once, with its line
    let mut loaded = Vec::new();
    for name in &names {
        let path = crate::root().join("cases").join(format!("{name}.toml"));
        if !path.exists() {
            return Err(format!("no case file {}", path.display()));
        }
        loaded.push((name, CaseFile::load(&path).map_err(|e| e.to_string())?));
    }
    let mut loop_checks = Vec::new();
    for (name, path) in &loops {
        let case = CaseFile::load(path).map_err(|e| e.to_string())?;
        let check =
            case.check.and_then(|c| c.diagnosis).ok_or(format!("{} has no [check.diagnosis]", path.display()))?;
        loop_checks.push((*name, path, check));
    }

    let rfm = crate::release_build(&["-p", "rfm-cli", "--bin", "rfm"], "rfm")?;
    println!("running {}", rfm.display());
    let started = Instant::now();
    let base = crate::target_dir()?.join("reproduce");
    let mut runs = Vec::new();
    for (name, case) in &loaded {
        let checks = case.check.clone().unwrap_or_default();
        let noise = case.truth.as_ref().map(|t| t.noise);
        let rfm_check = checks.rfm.as_ref().map(|c| (c, noise));
        runs.push(update(&rfm, &case.path, &base.join(name), "rfm", name, rfm_check)?);
        if let Some(c) = &checks.output_error {
            let out = base.join(format!("{name}-output-error"));
            runs.push(update(&rfm, &case.path, &out, "output-error", name, Some((c, noise)))?);
        }
    }
    let mut loop_summaries = Vec::new();
    for (name, path, check) in &loop_checks {
        loop_summaries.push(diagnosis_loop(&rfm, name, path, &base.join(name), check, &mut runs)?);
    }

    println!("\n==================== summary ====================");
    println!(
        "{:<32} {:>12} {:>14} {:>11} {:>20} {:>18} {:>8}",
        "case", "method", "status", "misfit", "max error vs truth", "max |z| (std)", "check"
    );
    for run in &runs {
        let json = &run.json;
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
        let verdict = match &run.failures {
            None => "-",
            Some(f) if f.is_empty() => "pass",
            Some(_) => "FAIL",
        };
        println!(
            "{:<32} {:>12} {:>14} {residual:>11.3e} {err:>20} {z:>18} {verdict:>8}",
            run.label,
            run.method,
            check::status_name(json)
        );
    }
    for text in &loop_summaries {
        println!("\n{text}");
    }
    println!("\nreports (self-contained HTML with the figures; open in a browser):");
    for run in runs.iter().filter(|r| r.report.exists()) {
        println!("  {}", run.report.display());
    }
    for (name, ..) in &loop_checks {
        println!("  {}", base.join(name).join("compare/report.html").display());
    }
    println!("\nresults: {}", base.display());
    println!("time after the build: {:.0} s", started.elapsed().as_secs_f64());

    // "-" in the check column: the case file sets no check for that run
    println!("\nchecks ([check] of each case file; `-` above: none set for that run):");
    let mut missed = 0;
    for run in &runs {
        let Some(failures) = &run.failures else { continue };
        for f in failures {
            println!("  FAIL {} ({}): {f}", run.label, run.method);
        }
        missed += failures.len();
    }
    let checked = runs.iter().filter(|r| r.failures.is_some()).count();
    if missed > 0 {
        return Err(format!("{missed} check(s) missed (listed above)"));
    }
    println!("  all {checked} checked runs pass");
    Ok(())
}

/// The update of a loop against its check's `status` and the case whose
/// `[truth]` made its data (`[check.diagnosis]`'s `truth`), as
/// [`check::loop_update_failures`]; nothing when the check sets neither.
/// The true values of the compared parameters are written into `results`
/// for the summary's columns.
fn loop_update_failures(check: &fe_model::case::DiagnosisCheck, results: &mut serde_json::Value) -> Vec<String> {
    let Some(path) = &check.truth else {
        if check.status.is_empty() {
            return Vec::new();
        }
        return check::loop_update_failures(check, results, &[], None);
    };
    let truth = match CaseFile::load(path) {
        Ok(case) => case.truth,
        Err(e) => return vec![format!("the truth {}: {e}", path.display())],
    };
    let Some(truth) = truth else { return vec![format!("the truth {} has no [truth]", path.display())] };
    let values: Vec<Result<f64, String>> = check
        .compare
        .iter()
        .map(|(_, name)| truth.model.quantity(name).map(|q| truth.model.get(q)).map_err(|e| e.to_string()))
        .collect();
    let failures = check::loop_update_failures(check, results, &values, Some(truth.noise));
    if let Some(params) = results["parameters"].as_array_mut() {
        for ((name, _), value) in check.compare.iter().zip(&values) {
            if let (Some(p), Ok(v)) = (params.iter_mut().find(|p| p["name"].as_str() == Some(name)), value) {
                p["truth"] = serde_json::Value::from(*v);
            }
        }
    }
    failures
}

/// One of the [`LOOPS`] (the tutorial's is the walkthrough of
/// `docs/walkthrough.md`): compare the model with its data, diagnose, add
/// the leading effect, update, and hold the result to the case's
/// `[check.diagnosis]`.
fn diagnosis_loop(
    rfm: &Path,
    name: &str,
    case: &Path,
    out: &Path,
    check: &fe_model::case::DiagnosisCheck,
    runs: &mut Vec<Run>,
) -> Result<String, String> {
    println!("\n==================== {name}: compare ====================");
    let compare = out.join("compare");
    run_rfm(rfm, &[OsStr::new("compare"), case.as_os_str(), OsStr::new("--out"), compare.as_os_str()], "rfm compare")?;

    println!("\n==================== {name}: diagnose ====================");
    let stem = case.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let added = out.join(format!("{stem}-with-effect.toml"));
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
    if !added.exists() {
        return Err(format!("rfm diagnose --apply 1 wrote no {}", added.display()));
    }
    println!("wrote {} with the leading effect added", added.display());

    let mut run = update(rfm, &added, &out.join("update"), "output-error", &format!("{name} (effect added)"), None)?;
    // both are RMS FRF misfits per residual over the measured channels (the
    // diagnosis over every line, the update over its chosen lines)
    let nominal = json["nominal_misfit"].as_f64().unwrap_or(f64::NAN);
    let last = run.json["residual"].as_f64().unwrap_or(f64::NAN);
    let mut failures = check::diagnosis_failures(check, &json, last);
    failures.extend(loop_update_failures(check, &mut run.json));
    run.failures = Some(failures);
    runs.push(run);
    let leader = ranking.first().and_then(|l| l["description"].as_str()).unwrap_or("?");
    Ok(format!(
        "{name}: the diagnosis named \"{leader}\" first; with it added and updated the misfit fell\n\
         {:.0} times, from {nominal:.3e} (nominal model) to {last:.3e}",
        nominal / last,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every code of rfm's exit table that says the results are written
    /// (`docs/reliability.md`, which a test of rfm keeps equal to the
    /// binary's table) is one reproduce reads on, and no other.
    #[test]
    fn reproduce_reads_the_results_of_every_code_that_writes_them() {
        let doc = std::fs::read_to_string(crate::root().join("docs/reliability.md")).unwrap();
        let table = &doc[doc.find("## Exit codes").unwrap()..];
        let written: Vec<i32> = table
            .lines()
            .skip_while(|l| !l.starts_with("| code"))
            .skip(2)
            .take_while(|l| l.starts_with("| "))
            .filter(|l| l.contains(" written") && !l.contains("not written"))
            .map(|l| l.trim_matches('|').split(" | ").next().unwrap().trim().parse().unwrap())
            .filter(|&code| code != 0)
            .collect();
        assert_eq!(written, WRITTEN_NOT_CONVERGED);
    }
}
