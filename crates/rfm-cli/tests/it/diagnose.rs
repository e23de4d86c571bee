//! The tutorial loop through the binary: diagnose, add the effect, update.

use std::path::PathBuf;
use std::process::Command;

fn rfm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

fn tutorial() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial/l-frame.toml")
}

#[test]
fn tutorial_diagnosis_names_the_joint_and_updating_cuts_the_misfit_tenfold() {
    let dir = tempfile::tempdir().unwrap();
    let case = tutorial();
    let new_case = dir.path().join("with-joint.toml");
    let out = rfm(&["diagnose", case.to_str().unwrap(), "--json", "--apply", "1", "--out", new_case.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let d: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let top = &d["ranking"][0];
    assert_eq!(top["kind"], "flexible_joint", "{top}");
    assert_eq!(top["nodes"], serde_json::json!([13]));
    assert_eq!(top["significant"], true);
    for key in ["kind", "nodes", "elements", "dof", "explained", "significant"] {
        assert!(!top[key].is_null(), "diagnosis JSON lacks {key}");
    }
    let nominal = d["nominal_misfit"].as_f64().unwrap();
    let text = std::fs::read_to_string(&new_case).unwrap();
    assert!(text.contains("[[joints]]") && text.contains("[update]"), "{text}");

    let out = rfm(&["update", new_case.to_str().unwrap(), "--json", "--out", dir.path().join("up").to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let u: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let after = u["residual"].as_f64().unwrap();
    assert!(nominal / after >= 10.0, "misfit {nominal} -> {after}");
    // the hidden joint (see l-frame-truth.toml): kr = 2e4, alpha = 1e-4
    let kr = &u["uncertainty"]["parameters"][0];
    let z = (kr["value"].as_f64().unwrap() / 2.0e4).ln().abs() / kr["relative_std"].as_f64().unwrap();
    assert!(z < 3.0, "kr {kr}");
    assert!(dir.path().join("up/updated.toml").exists());
}

/// `--apply` with `--measured FILE`: the new case reads FILE, the data its
/// effect was fitted to and its history's misfits are of, as the cases
/// `rfm update` and `rfm fix` write with `--measured` do (it named the
/// case's own data before).
#[test]
fn a_case_applied_from_other_data_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run-2.csv");
    std::fs::copy(tutorial().with_file_name("l-frame-measured.csv"), &run).unwrap();
    let new_case = dir.path().join("cases").join("with-joint.toml");
    std::fs::create_dir_all(new_case.parent().unwrap()).unwrap();
    let (case, run_s, new_s) = (tutorial(), run.to_str().unwrap(), new_case.to_str().unwrap());
    let out = rfm(&["diagnose", case.to_str().unwrap(), "--measured", run_s, "--apply", "1", "--out", new_s]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&new_case).unwrap();
    assert!(text.contains("data = \"../run-2.csv\""), "{text}");
    // and nothing is written beside it
    assert_eq!(std::fs::read_dir(new_case.parent().unwrap()).unwrap().count(), 1);
    let out = rfm(&["compare", new_s, "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn apply_without_out_fails_with_a_message() {
    let out = rfm(&["diagnose", tutorial().to_str().unwrap(), "--apply", "1"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--apply needs --out"));
}

/// The test-data tutorial (docs/walkthrough-test-data.md): voltage-referenced
/// accelerance with coherence; the diagnosis fits the amplifier's gain with
/// every candidate and names the lap joint of lap-joint-truth.toml
/// (kr = 2e3 at node 9, gain 42 N/V at -30 degrees).
#[test]
fn lap_joint_tutorial_names_the_joint_and_the_amplifier_gain() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial");
    let out = rfm(&["inspect", dir.join("lap-joint-measured.uff").to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("per volt (`m/s^2` / `V`)"));
    let out = rfm(&["diagnose", dir.join("lap-joint.toml").to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let d: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let top = &d["ranking"][0];
    assert!(top["description"].as_str().unwrap().starts_with("flexible, lossy in-line joint at node 9"), "{top}");
    let kr = &top["parameters"][0];
    let z = (kr["value"].as_f64().unwrap() / 2.0e3).ln().abs() / kr["relative_std"].as_f64().unwrap();
    assert!(z < 3.0, "kr {kr}");
    let g = &top["gains"][0];
    assert!((g["magnitude"].as_f64().unwrap() / 42.0 - 1.0).abs() < 0.01, "{g}");
    assert!((g["phase_deg"].as_f64().unwrap() + 30.0).abs() < 1.0, "{g}");
}
