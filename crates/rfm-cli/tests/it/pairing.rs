//! `[measurement] pair = "coordinates"`: test nodes of a universal file
//! paired with model nodes by the coordinates of its dataset 15, through
//! the binary.

use std::path::Path;
use std::process::Command;

use frf::io::uff::{self, Encoding, UffWriteOptions};

fn rfm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

const BEAM: &str = include_str!("cases/pairing-beam.toml");

/// The model's FRFs as a universal file whose test nodes are 100 + the
/// model's, with their coordinates (dataset 15, in metres, 10 mm off the
/// model's plane where the sensors sit); `y5` is the y of test node 105.
fn write_test_file(dir: &Path, y5: f64) -> std::path::PathBuf {
    std::fs::write(dir.join("sim.toml"), format!("{BEAM}[truth]\n")).unwrap();
    let csv = dir.join("sim.csv");
    let out = rfm(&["simulate", dir.join("sim.toml").to_str().unwrap(), "--out", csv.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let set = frf::io::csv::read_csv(&csv).unwrap();
    let mut functions = uff::frf_set_to_functions(&set, &UffWriteOptions::default()).unwrap();
    for f in &mut functions {
        f.header.response.node += 100;
        f.header.reference.node += 100;
    }
    let mut bytes = uff::encode(&functions, Encoding::Ascii).unwrap();
    bytes.extend(b"    -1\n    15\n");
    bytes.extend(b"       103         0         0         1  5.00100E-01  1.00000E-03  1.00000E-02\n");
    bytes.extend(
        format!("       105         0         0         1  1.00000E+00 {:12.5E}  1.00000E-02\n", y5).as_bytes(),
    );
    bytes.extend(b"    -1\n");
    let path = dir.join("test.uff");
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn test_nodes_are_paired_with_model_nodes_by_their_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    write_test_file(dir.path(), 0.0);
    let case = dir.path().join("case.toml");
    let text = BEAM.replace(
        "frequencies = { from = 5.0, to = 200.0, step = 5.0 }\n",
        "data = \"test.uff\"\npair = \"coordinates\"\ntolerance = 0.005\n",
    );
    std::fs::write(&case, text).unwrap();
    let out = rfm(&["compare", case.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let notes: Vec<&str> = doc["notes"].as_array().unwrap().iter().map(|n| n.as_str().unwrap()).collect();
    assert!(
        notes.iter().any(
            |n| n.contains("paired 2 test node(s) with model nodes by coordinates within 5 mm: 103 -> 3, 105 -> 5")
        ),
        "{notes:?}"
    );
    assert!(notes.iter().any(|n| n.contains("no dataset 164")), "{notes:?}");
    // the data are the model's own FRFs: paired right, nothing is left
    let channels: Vec<&str> =
        doc["correlation"]["channels"].as_array().unwrap().iter().map(|c| c["channel"].as_str().unwrap()).collect();
    assert_eq!(channels, ["H(3:uy,5:uy)", "H(5:uy,5:uy)"]);
    assert!(doc["correlation"]["total"]["log_misfit"].as_f64().unwrap() < 1e-9, "{doc}");
}

#[test]
fn a_test_node_far_from_every_model_node_is_refused_with_its_line() {
    let dir = tempfile::tempdir().unwrap();
    // node 105 sits 20 mm beside the beam's tip: beyond the 5 mm tolerance
    write_test_file(dir.path(), 0.02);
    let case = dir.path().join("case.toml");
    let text = BEAM.replace(
        "frequencies = { from = 5.0, to = 200.0, step = 5.0 }\n",
        "data = \"test.uff\"\npair = \"coordinates\"\ntolerance = 0.005\n",
    );
    std::fs::write(&case, text).unwrap();
    let out = rfm(&["compare", case.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("test.uff:") && stderr.contains("test node 105"), "{stderr}");
    assert!(stderr.contains("20.0 mm from the nearest model node 5"), "{stderr}");
}

/// The map used is kept with the results: in `results.json` of `rfm update`
/// and in the document of `rfm diagnose --json`, under `notes`.
#[test]
fn the_pairing_used_is_written_into_the_results() {
    let dir = tempfile::tempdir().unwrap();
    write_test_file(dir.path(), 0.0);
    let case = dir.path().join("case.toml");
    let text = BEAM
        .replace(
            "frequencies = { from = 5.0, to = 200.0, step = 5.0 }\n",
            "data = \"test.uff\"\npair = \"coordinates\"\ntolerance = 0.005\n",
        )
        // a model 5 % too stiff, for the update to have something to do
        .replace("[groups.beam]\nalpha = 1e-5\n", "[groups.beam]\nalpha = 1e-5\nstiffness = 1.05\n")
        + "[update]\nparameters = [\"group.beam.stiffness\"]\n";
    std::fs::write(&case, text).unwrap();
    let map = "paired 2 test node(s) with model nodes by coordinates within 5 mm: 103 -> 3, 105 -> 5";
    let has_map =
        |doc: &serde_json::Value| doc["notes"].as_array().unwrap().iter().any(|n| n.as_str().unwrap().contains(map));

    let out_dir = dir.path().join("updated");
    let out = rfm(&["update", case.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("results.json")).unwrap()).unwrap();
    assert!(has_map(&results), "{}", results["notes"]);

    let out = rfm(&["diagnose", case.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(has_map(&doc), "{}", doc["notes"]);
    // the diagnosis itself is there beside them
    assert!(doc["ranking"].as_array().is_some_and(|r| !r.is_empty()), "{doc}");
}
