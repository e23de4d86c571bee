//! `rfm fix` on the lab's acceptance cases: data a test lab produces, made
//! by rfm-update's lab generator (`crates/rfm-update/tests/it/lab.rs`, which
//! shares no code with the diagnosis) and committed with their right
//! answers (`expect.txt`). Each case is run as a user runs it, and its
//! `--json` outcome is read against the answer:
//!
//! - `lab/flipped-channel`: an accelerometer mounted upside down and a
//!   40 g mass the model lacks. The channel is reported as inverted and
//!   corrected, then the mass is found at its node.
//! - `lab/tip-resonator`: a 50 g tuned-mass damper at a cantilever's tip
//!   (the data have one mode more than the model): the extra mode is
//!   reported and a resonator is added at the tip.
//! - `lab/damping-form`: non-viscous material damping at three times the
//!   nominal viscous guess, its parameters declared under `[update]`: step
//!   0 updates them and nothing is added.
//! - `tutorial/lab-frame`: an L-frame with an inverted channel and an 86 g
//!   non-viscous resonator (the tutorial's walkthrough on test-like data).
//!
//! Each must end at most 1.5 times the noise with exit 0, and the true
//! masses and stiffnesses lie within 3 reported standard deviations.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::fixtures::{rfm, text};

/// A lab case: its case file and its answers.
fn lab_case(name: &str) -> (PathBuf, toml::Table) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let (case, expect) = if let Some(tutorial) = name.strip_prefix("tutorial/") {
        let dir = root.join("../../cases/tutorial");
        (dir.join(format!("{tutorial}.toml")), dir.join(format!("{tutorial}-expect.txt")))
    } else {
        let dir = root.join("tests/it/cases").join(name);
        (dir.join("nominal.toml"), dir.join("expect.txt"))
    };
    let expect = std::fs::read_to_string(&expect).unwrap_or_else(|e| panic!("{}: {e}", expect.display()));
    (case, expect.parse().unwrap_or_else(|e| panic!("{name}'s expect.txt: {e}")))
}

/// `rfm fix CASE --json --out DIR`: the exit code and the outcome.
fn run_fix(case: &Path, dir: &Path) -> (i32, Value) {
    let out = rfm(&["fix", case.to_str().expect("UTF-8"), "--json", "--out", dir.to_str().expect("UTF-8")]);
    let outcome: Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}\n{}", text(&out.stdout), text(&out.stderr)));
    (out.status.code().expect("an exit code"), outcome)
}

/// The lab's family names as the tool's effect kinds (a mass change of
/// elements also adds mass).
fn kinds(family: &str) -> &'static [&'static str] {
    match family {
        "lumped_mass" => &["lumped_mass", "mass_change"],
        "resonator" => &["resonator"],
        "flexible_joint" => &["flexible_joint"],
        "flexible_support" => &["flexible_support"],
        other => panic!("no test here for the family {other}"),
    }
}

fn numbers(v: &Value) -> Vec<u64> {
    v.as_array().map_or_else(Vec::new, |a| a.iter().filter_map(Value::as_u64).collect())
}

/// Checks `o` against the case's first answer and returns what it read.
fn check(name: &str) {
    let (case, expect) = lab_case(name);
    let dir = tempfile::tempdir().expect("a folder");
    let (code, o) = run_fix(&case, &dir.path().join("out"));
    let answer = expect["answer"].as_array().expect("[[answer]]")[0].as_table().expect("an answer");
    let noise = o["noise"].as_f64().expect("noise");
    let steps = o["steps"].as_array().expect("steps");
    let last = steps.last().map_or_else(
        || o["declared"]["misfit_updated"].as_f64().unwrap_or_else(|| o["corrected_misfit"].as_f64().expect("misfit")),
        |s| s["corrected_misfit"].as_f64().unwrap_or_else(|| s["misfit_updated"].as_f64().expect("misfit")),
    );
    println!("{name}: exit {code}, {:.2} x noise, stop {}", last / noise, o["stop"]);
    assert_eq!(code, 0, "{name}: {}", o["stop_reason"]);
    assert!(last <= 1.5 * noise, "{name}: the loop ends {:.2} times the noise", last / noise);

    // the data's errors reported (extra modes are evidence, not errors of the data)
    let findings: Vec<&Value> =
        o["findings"].as_array().expect("findings").iter().filter(|f| f["kind"] != "extra_mode").collect();
    let expected = answer.get("findings").and_then(|f| f.as_array()).cloned().unwrap_or_default();
    assert_eq!(findings.len(), expected.len(), "{name}: findings {findings:?}");
    for e in &expected {
        let channel = e["channel"].as_str().expect("a channel");
        let kind = match e["kind"].as_str() {
            Some("polarity") => "inverted_polarity",
            other => panic!("no test here for the finding {other:?}"),
        };
        assert!(
            findings
                .iter()
                .any(|f| f["kind"] == kind && f["channels"].as_array().is_some_and(|c| c.contains(&channel.into()))),
            "{name}: {kind} on {channel} not among {findings:?}"
        );
    }

    // the effects: each expected one added at its node (or the next), no other
    let effects = o["effects"].as_array().expect("effects");
    let expected = answer.get("effects").and_then(|f| f.as_array()).cloned().unwrap_or_default();
    assert_eq!(
        effects.len(),
        expected.len(),
        "{name}: effects {:?}",
        effects.iter().map(|e| &e["description"]).collect::<Vec<_>>()
    );
    for e in &expected {
        let family = e["family"].as_str().expect("a family");
        let nodes: Vec<u64> =
            e["nodes"].as_array().expect("nodes").iter().map(|n| n.as_integer().expect("a node") as u64).collect();
        let added = effects
            .iter()
            .find(|x| {
                kinds(family).contains(&x["kind"].as_str().unwrap_or(""))
                    && numbers(&x["nodes"]).iter().any(|n| nodes.iter().any(|m| n.abs_diff(*m) <= 1))
            })
            .unwrap_or_else(|| panic!("{name}: no {family} at {nodes:?} among {effects:?}"));
        println!("{name}: {}", added["description"]);
        // the true mass and stiffnesses within 3 standard deviations of the last update
        let uncertainty = &steps.last().expect("a step")["uncertainty"]["parameters"];
        for (key, truth) in e["values"].as_table().expect("values") {
            if !matches!(key.as_str(), "m" | "kx" | "ky" | "kz") {
                continue;
            }
            let truth = truth.as_float().expect("a value");
            let p = uncertainty
                .as_array()
                .expect("the update's uncertainty")
                .iter()
                .find(|p| p["name"].as_str().is_some_and(|n| n.ends_with(&format!(".{key}"))))
                .unwrap_or_else(|| panic!("{name}: no parameter {key} in {uncertainty}"));
            let (value, std) = (p["value"].as_f64().expect("a value"), p["std"].as_f64().expect("a std"));
            println!("{name}: {key} = {value:.5e} +- {std:.2e} (truth {truth:.5e})");
            assert!((value - truth).abs() <= 3.0 * std, "{name}: {key} = {value} +- {std}, truth {truth}");
        }
    }

    // each step's case tells its own story: the history of the case before
    // it, then the step (at the misfit it started from) and its update as
    // that step, ending at the step's misfit (a revision rebuilt from the
    // nominal case once read as step 3 from its screening fit)
    for (k, s) in steps.iter().enumerate() {
        let n = k + 1;
        let written = dir.path().join("out").join(format!("step-{n}.toml"));
        let text = std::fs::read_to_string(&written).expect("the step's case");
        let history = text.parse::<toml::Table>().expect("TOML")["history"].as_array().expect("a history").clone();
        let labels: Vec<&str> = history.iter().map(|h| h["step"].as_str().expect("a label")).collect();
        let updates: Vec<&str> = labels
            .iter()
            .copied()
            .filter(|l| l.strip_prefix("updated after step ").is_some_and(|r| r.parse::<usize>().is_ok()))
            .collect();
        let want: Vec<String> = (1..=n).map(|i| format!("updated after step {i}")).collect();
        assert_eq!(updates, want, "{name}: step {n}'s history {labels:?}");
        let end = history.last().expect("an entry")["misfit"].as_float().expect("a misfit");
        let misfit = s["corrected_misfit"].as_f64().unwrap_or_else(|| s["misfit_updated"].as_f64().expect("misfit"));
        assert!((end / misfit - 1.0).abs() < 1e-9, "{name}: step {n}'s history ends at {end}, the step at {misfit}");
    }

    // declared parameters: updated at step 0 to their true values
    if let Some(declared) = answer.get("declared").and_then(|d| d.as_table()) {
        let updated = o["declared"]["parameters"].as_array().expect("a step 0");
        for (key, truth) in declared {
            let truth = truth.as_float().expect("a value");
            let p = updated
                .iter()
                .find(|p| p["name"] == key.as_str())
                .unwrap_or_else(|| panic!("{name}: {key} not updated"));
            let value = p["updated"].as_f64().expect("a value");
            println!("{name}: {key} = {value:.5e} (truth {truth:.5e})");
            assert!((value / truth - 1.0).abs() < 0.05, "{name}: {key} = {value}, truth {truth}");
        }
    }
}

#[test]
fn an_inverted_channel_is_corrected_before_the_mass_is_found() {
    check("lab/flipped-channel");
}

#[test]
fn a_tuned_mass_damper_is_found_as_a_resonator() {
    check("lab/tip-resonator");
}

#[test]
fn a_damping_model_form_error_is_the_declared_parameters_own() {
    check("lab/damping-form");
}

#[test]
fn the_tutorial_lab_frame_is_corrected_and_its_resonator_found() {
    check("tutorial/lab-frame");
}
