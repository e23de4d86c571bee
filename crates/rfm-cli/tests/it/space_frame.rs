//! A frame in space through the binary (cases/table-frame.toml): compare,
//! diagnose (the loose corner joint hidden in the case's `[truth]` named
//! first), add it, update: the misfit falls to the noise and the joint's
//! values come back within their standard deviations of the truth's.

use std::path::PathBuf;
use std::process::Command;

use fe_model::{CaseFile, Dof};

fn rfm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

fn json(out: &std::process::Output) -> serde_json::Value {
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn the_table_frame_loop_finds_the_loose_corner_and_the_misfit_falls_to_the_noise() {
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/table-frame.toml");
    let truth = CaseFile::load(&case).unwrap().truth.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let c = case.to_str().unwrap();

    let compared = json(&rfm(&["compare", c, "--json"]));
    let rows = compared["modes"]["rows"].as_array().unwrap();
    assert!(rows.iter().filter(|r| !r["mac"].is_null()).count() >= 10, "{rows:?}");

    let new_case = dir.path().join("with-joint.toml");
    let d = json(&rfm(&["diagnose", c, "--json", "--apply", "1", "--out", new_case.to_str().unwrap()]));
    let top = &d["ranking"][0];
    assert_eq!(top["kind"], "flexible_joint", "{top}");
    assert_eq!((top["nodes"].clone(), top["elements"].clone()), (serde_json::json!([15]), serde_json::json!([27])));
    assert_eq!(top["significant"], true);
    assert!(top["description"].as_str().unwrap().contains("krx, kry, krz; non-viscous"), "{top}");
    // the data came from the truth: they are written beside the new case, which no longer has one
    assert!(dir.path().join("with-joint-measured.csv").exists());
    assert!(CaseFile::load(&new_case).unwrap().truth.is_none());

    let u =
        json(&rfm(&["update", new_case.to_str().unwrap(), "--json", "--out", dir.path().join("up").to_str().unwrap()]));
    assert_eq!(u["status"], "converged");
    let (nominal, after) = (d["nominal_misfit"].as_f64().unwrap(), u["residual"].as_f64().unwrap());
    assert!(nominal / after >= 10.0, "misfit {nominal} -> {after}");
    // the residual is the data's noise (1 % relative, complex)
    assert!((after / truth.noise - 1.0).abs() < 0.1, "residual {after} vs noise {}", truth.noise);

    // the joint's values against the truth's, in the run's own standard deviations
    let t = &truth.model;
    let spring = &t.springs()[t.spring_index("corner").unwrap()];
    let group = &t.groups()[t.group_index("corner").unwrap()];
    let want = |name: &str| match name.rsplit('.').next().unwrap() {
        "krx" => Some(spring.k[Dof::Rx]),
        "kry" => Some(spring.k[Dof::Ry]),
        "krz" => Some(spring.k[Dof::Rz]),
        "alpha" if name.contains("joint") => Some(group.alpha),
        "mu" => group.mu,
        _ => None,
    };
    let mut checked = 0;
    for p in u["uncertainty"]["parameters"].as_array().unwrap() {
        let name = p["name"].as_str().unwrap();
        let Some(truth) = want(name) else { continue };
        let z = (p["value"].as_f64().unwrap() / truth).ln().abs() / p["relative_std"].as_f64().unwrap();
        assert!(z < 3.0, "{name}: {p} vs the truth's {truth}");
        checked += 1;
    }
    // krx, kry, krz and the joint's alpha and mu: one group, or one per
    // direction (the truth has one; the data hold both within the noise)
    assert!(checked == 5 || checked == 9, "{checked} of krx, kry, krz and the joint's alpha and mu");
}
