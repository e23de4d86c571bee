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

#[test]
fn apply_without_out_fails_with_a_message() {
    let out = rfm(&["diagnose", tutorial().to_str().unwrap(), "--apply", "1"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--apply needs --out"));
}
