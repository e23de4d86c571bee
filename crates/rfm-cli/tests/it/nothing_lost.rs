//! Nothing is lost: outputs never replace inputs, an interrupted run leaves
//! earlier outputs as they were, and a closed pipe is not a crash.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn rfm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rfm"))
}

fn cases() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases")
}

/// Every file under `dir` with its bytes.
fn contents(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap())
        })
        .collect()
}

/// The two-material beam with 150 elements per half, fitted by output-error
/// at all 800 lines: about 0.4 s per iteration in a test build, for many
/// iterations.
fn slow_case(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(cases().join("two-material-beam.toml"))
        .unwrap()
        .replace("elements = 15\n", "elements = 150\n")
        .replace("from = 16\n", "from = 151\n")
        .replace("references = [\"31:uy\"]", "references = [\"301:uy\"]")
        .replace("responses = [\"2..31:uy\"]", "responses = [\"151:uy\", \"301:uy\"]")
        .replace("method = \"rfm\"", "method = \"output-error\"")
        .replace("frequencies = { auto = 10 }", "frequencies = { lines = 800 }")
        .replace("max_iterations = 30", "max_iterations = 1000")
        .replace("tolerance = 1e-6", "tolerance = 1e-30");
    let path = dir.join("slow.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn ctrl_c_during_an_update_leaves_the_earlier_outputs_as_they_were_and_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    let case = slow_case(dir.path());
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    for (name, text) in [("results.json", "{\"earlier\": true}"), ("updated.toml", "# earlier"), ("report.html", "x")] {
        std::fs::write(out.join(name), text).unwrap();
    }
    let before = contents(&out);
    let mut child = rfm()
        .args(["update", case.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // wait until the first iteration is done: the run is well under way
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let mut seen = Vec::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        let first = line.split_whitespace().next() == Some("1");
        seen.push(line);
        if first {
            break;
        }
    }
    assert!(seen.last().is_some_and(|l| l.trim_start().starts_with("1 ")), "{seen:?}");
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let rest: Vec<String> = lines.map_while(Result::ok).collect();
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    assert!(!rest.iter().any(|l| l.contains("wrote")), "{rest:?}");
    assert_eq!(contents(&out), before, "the output folder changed");
}

#[test]
fn a_closed_standard_output_ends_the_command_quietly() {
    let case = cases().join("two-material-beam.toml");
    let mut child =
        rfm().args(["compare", case.to_str().unwrap()]).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    // the reader goes away before the first line: every print meets a broken pipe
    drop(child.stdout.take());
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
}

#[test]
fn a_closed_standard_output_still_lets_a_run_write_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("h.csv");
    let case = cases().join("monopile.toml");
    let mut child = rfm()
        .args(["simulate", case.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let result = child.wait_with_output().unwrap();
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    assert_eq!(frf::io::csv::read_csv(&out).unwrap().n_freq(), 1200);
}

/// Every command that writes refuses to write over the case file or its
/// measured data, and leaves them as they were.
#[test]
fn no_command_writes_over_the_case_or_its_measured_data() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for name in ["l-frame.toml", "l-frame-measured.csv"] {
        std::fs::copy(cases().join("tutorial").join(name), d.join(name)).unwrap();
    }
    let before = contents(d);
    let case = d.join("l-frame.toml");
    let data = d.join("l-frame-measured.csv");
    let (case_s, data_s, dir_s) = (case.to_str().unwrap(), data.to_str().unwrap(), d.to_str().unwrap());
    // updated.toml over the case: the case is named so in the output folder
    let as_updated = d.join("updated.toml");
    std::fs::copy(&case, &as_updated).unwrap();
    let before_updated = std::fs::read(&as_updated).unwrap();
    let d_as_updated = as_updated.to_str().unwrap();
    let runs: Vec<Vec<&str>> = vec![
        vec!["simulate", case_s, "--out", data_s],
        vec!["simulate", case_s, "--out", case_s],
        vec!["diagnose", case_s, "--apply", "1", "--out", case_s],
        vec!["update", d_as_updated, "--out", dir_s],
    ];
    for args in runs {
        let result = rfm().args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{args:?}");
        assert!(stderr.contains("refusing to overwrite an input"), "{args:?}: {stderr}");
    }
    // refused before any work: nothing was written at all
    let mut after = contents(d);
    assert_eq!(after.remove("updated.toml"), Some(before_updated));
    assert_eq!(after, before);
}
