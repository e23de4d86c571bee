//! Each command's output, files and exit codes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn rfm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

fn case(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases").join(format!("{name}.toml"))
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn update_prints_the_table_and_writes_results_json() {
    let dir = tempfile::tempdir().unwrap();
    let out = rfm(&["update", case("two-material-beam").to_str().unwrap(), "--out", dir.path().to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("group.aluminium.mu") && stdout.contains("paper"), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("results.json")).unwrap()).unwrap();
    assert_eq!(json["status"], "converged");
    for p in json["parameters"].as_array().unwrap() {
        for key in ["name", "initial", "updated", "truth"] {
            assert!(!p[key].is_null(), "results.json parameter lacks {key}: {p}");
        }
        let (u, t) = (p["updated"].as_f64().unwrap(), p["truth"].as_f64().unwrap());
        assert!(((u - t) / t).abs() < 1e-6);
    }
    assert!(json["residual"].as_f64().unwrap() < 1e-8);
}

#[test]
fn simulate_writes_a_csv_that_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("h.csv");
    let out = rfm(&[
        "simulate",
        case("monopile").to_str().unwrap(),
        "--out",
        file.to_str().unwrap(),
        "--noise",
        "0.02",
        "--seed",
        "3",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let set = frf::io::csv::read_csv(&file).unwrap();
    assert_eq!(set.channels().len(), 25);
    assert_eq!(set.n_freq(), 1200);
}

#[test]
fn a_bad_case_file_fails_with_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    let text_in =
        std::fs::read_to_string(case("two-material-beam")).unwrap().replace("group = \"steel\"", "group = \"stel\"");
    std::fs::write(&bad, &text_in).unwrap();
    let out = rfm(&["update", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    let line = text_in.lines().position(|l| l.contains("\"stel\"")).unwrap() + 1;
    assert!(err.contains(&format!("bad.toml:{line}:")), "{err}");
    assert!(err.contains("did you mean `steel`"), "{err}");
}

#[test]
fn outputs_never_overwrite_the_case_file() {
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("case.toml");
    std::fs::copy(case("monopile"), &copy).unwrap();
    let before = std::fs::read(&copy).unwrap();
    let out = rfm(&["simulate", copy.to_str().unwrap(), "--out", copy.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("refusing to overwrite an input"), "{}", text(&out.stderr));
    assert_eq!(std::fs::read(&copy).unwrap(), before);
    assert!(Path::new(&copy).exists());
}

/// The exit codes are documented once, in `docs/reliability.md`, and must
/// be the ones `rfm --help` prints from the binary's own table.
#[test]
fn the_documented_exit_codes_are_the_binarys() {
    let help = text(&rfm(&["--help"]).stdout);
    let from_help: Vec<(String, String)> = help
        .lines()
        .skip_while(|l| !l.starts_with("Exit codes:"))
        .skip(1)
        .filter_map(|l| l.trim().split_once("  ").map(|(c, m)| (c.to_string(), m.trim().to_string())))
        .collect();
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/reliability.md")).unwrap();
    let table = &doc[doc.find("## Exit codes").unwrap()..];
    let from_doc: Vec<(String, String)> = table
        .lines()
        .skip_while(|l| !l.starts_with("| code"))
        .skip(2)
        .take_while(|l| l.starts_with("| "))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split(" | ").map(str::trim).collect();
            (cells[0].to_string(), cells[1].to_string())
        })
        .collect();
    assert!(from_help.len() >= 13, "{help}");
    assert_eq!(from_doc, from_help);
    let codes: Vec<&str> = from_help.iter().map(|(c, _)| c.as_str()).collect();
    assert_eq!(codes, ["0", "1", "2", "3", "4", "5", "6", "7", "8", "9", "10", "11", "130"]);
}

/// A wrong command line exits with 2, the usage code of the table.
#[test]
fn a_wrong_command_line_exits_with_the_usage_code() {
    let out = rfm(&["update", "--no-such-flag"]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("--no-such-flag"));
}

/// The text block that follows the first `rfm ...` command containing
/// `command` in a markdown document.
fn printed_after(doc: &str, command: &str) -> Vec<String> {
    let start = doc.find(command).unwrap_or_else(|| panic!("the document shows no `{command}`"));
    let rest = &doc[start..];
    let block = &rest[rest.find("```text\n").expect("a text block follows") + 8..];
    block[..block.find("```").unwrap()].lines().map(str::to_string).collect()
}

/// The update output the walkthrough shows (step 4) is what the command
/// prints: every line of it appears, in order, in `rfm update`'s output for
/// the case it names. A figure in the docs that no command prints fails
/// here.
#[test]
fn the_walkthrough_shows_what_rfm_update_prints() {
    let doc =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../docs/walkthrough.md")).unwrap();
    let shown = printed_after(&doc, "rfm update cases/tutorial/l-frame-guess.toml");
    assert!(shown.len() > 10, "{shown:?}");
    let dir = tempfile::tempdir().unwrap();
    let out = rfm(&["update", case("tutorial/l-frame-guess").to_str().unwrap(), "--out", dir.path().to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let printed = text(&out.stdout);
    let mut lines = printed.lines();
    for line in shown.iter().filter(|l| !l.is_empty()) {
        assert!(
            lines.any(|p| p == line),
            "the walkthrough shows\n{line}\nwhich rfm update does not print (in this order):\n{printed}"
        );
    }
}
