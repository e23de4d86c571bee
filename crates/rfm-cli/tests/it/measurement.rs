//! The `[measurement]` keys that choose what of a data file every command
//! uses: `band`, `exclude`, and `frequencies` as lines of the data.

use std::path::{Path, PathBuf};
use std::process::Command;

fn rfm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

/// The tutorial case with its data file by absolute path and `extra` lines
/// in its `[measurement]` table.
fn case_with(dir: &Path, extra: &str) -> PathBuf {
    let tutorial = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial");
    let text = std::fs::read_to_string(tutorial.join("l-frame.toml")).unwrap();
    let data = tutorial.join("l-frame-measured.csv");
    // the tutorial names lines 2 to 600 Hz, every line of its data; the keys below choose among them
    let text = text
        .replace("frequencies = { from = 2.0, to = 600.0, step = 1.0 }\n", "")
        .replace("data = \"l-frame-measured.csv\"", &format!("data = \"{}\"\n{extra}", data.display()));
    let path = dir.join("case.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn compare_json(case: &Path) -> serde_json::Value {
    let out = rfm(&["compare", case.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn notes(doc: &serde_json::Value) -> Vec<String> {
    doc["notes"].as_array().unwrap().iter().map(|n| n.as_str().unwrap().to_string()).collect()
}

#[test]
fn the_band_and_exclusions_restrict_every_line_compared_and_say_so() {
    let dir = tempfile::tempdir().unwrap();
    // the data hold the lines 2, 3, ..., 600 Hz
    let doc = compare_json(&case_with(dir.path(), "band = [2.0, 240.0]\nexclude = [[49.0, 51.0]]"));
    let n = notes(&doc);
    assert!(n.iter().any(|x| x.contains("kept the 239 lines within the case's band 2 to 240 Hz, of 599")), "{n:?}");
    assert!(n.iter().any(|x| x.contains("left out 3 line(s) in the excluded band 49 to 51 Hz")), "{n:?}");
    let channels = doc["correlation"]["channels"].as_array().unwrap().len() as u64;
    assert_eq!(doc["correlation"]["total"]["values_used"].as_u64(), Some(236 * channels));
    // a measured mode near the band's top is paired with its model partner above the band, and says so
    let rows = doc["modes"]["rows"].as_array().unwrap();
    let above: Vec<&serde_json::Value> =
        rows.iter().filter(|r| r["model_hz"].as_f64().is_some_and(|f| f > 240.0)).collect();
    assert!(!above.is_empty(), "{rows:?}");
    for r in above {
        assert!(r["measured_hz"].as_f64().is_some(), "an unpaired model mode outside the band is listed: {r}");
        assert!(r["reading"].as_str().unwrap().contains("lies outside the band 2-240 Hz"), "{r}");
    }
}

#[test]
fn lines_the_data_lack_and_empty_bands_are_refused_where_they_are_written() {
    let dir = tempfile::tempdir().unwrap();
    for (extra, words) in [
        ("frequencies = [20.0, 20.5]", "20.5 Hz is not a line of"),
        ("band = [700.0, 800.0]", "the band 700 to 800 Hz holds none of the data's lines (2 to 600 Hz)"),
    ] {
        let case = case_with(dir.path(), extra);
        let out = rfm(&["compare", case.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{extra}: {stderr}");
        // the line after the data's: `extra` is written there
        assert!(stderr.contains("case.toml:45:") && stderr.contains(words), "{extra}: {stderr}");
    }
    // named lines of the data are used, and only they
    let doc = compare_json(&case_with(dir.path(), "frequencies = [20.0, 21.0, 30.0]"));
    let channels = doc["correlation"]["channels"].as_array().unwrap().len() as u64;
    assert_eq!(doc["correlation"]["total"]["values_used"].as_u64(), Some(3 * channels));
}
