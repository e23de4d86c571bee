//! Each command's output, files and exit codes.

use frf::FrfSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn rfm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

fn case(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases").join(format!("{name}.toml"))
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
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
    assert!(from_help.len() >= 14, "{help}");
    assert_eq!(from_doc, from_help);
    let codes: Vec<&str> = from_help.iter().map(|(c, _)| c.as_str()).collect();
    assert_eq!(codes, ["0", "1", "2", "3", "4", "5", "6", "7", "8", "9", "10", "11", "12", "130"]);
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

/// The diagnosis the walkthrough shows (step 2) is what the command prints:
/// every line of it, but for `...`, begins a line of `rfm diagnose`'s output
/// for the tutorial, in order (the document leaves out the fitted values
/// at the right of the table).
#[test]
fn the_walkthrough_shows_what_rfm_diagnose_prints() {
    let doc =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../docs/walkthrough.md")).unwrap();
    let shown = printed_after(&doc, "rfm diagnose cases/tutorial/l-frame.toml");
    assert!(shown.len() > 6, "{shown:?}");
    let out = rfm(&["diagnose", case("tutorial/l-frame").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let printed = text(&out.stdout);
    let mut lines = printed.lines();
    for line in shown.iter().filter(|l| !l.is_empty() && l.as_str() != "...") {
        assert!(
            lines.any(|p| p.starts_with(line.as_str())),
            "the walkthrough shows\n{line}\nwhich rfm diagnose does not print (in this order):\n{printed}"
        );
    }
}

/// The largest relative difference of two sets' values (and whether their
/// kinds, channels and lines agree).
fn max_relative_difference(a: &FrfSet, b: &FrfSet) -> f64 {
    assert_eq!((a.kind(), a.channels()), (b.kind(), b.channels()));
    for (x, y) in a.frequencies_hz().iter().zip(b.frequencies_hz()) {
        assert!((x - y).abs() <= 1e-12 * x.abs(), "line {x} vs {y}");
    }
    a.values().iter().zip(b.values()).map(|(x, y)| (x - y).norm() / y.norm()).fold(0.0, f64::max)
}

/// Reads a UFF file with pyuff, prints the largest relative difference of
/// its FRFs from the CSV of the same run, and writes the sets again.
const PYUFF_ROUND_TRIP: &str = r#"
import csv, sys
import numpy as np
import pyuff
uff, table, again = sys.argv[1:4]
rows = [r for r in csv.reader(open(table)) if r and not r[0].startswith('#')]
head, data = rows[0], np.array([[float(x) for x in r] for r in rows[1:]])
columns = {name[:-3]: data[:, j] + 1j * data[:, j + 1] for j, name in enumerate(head) if name.endswith('.re')}
sets = pyuff.UFF(uff).read_sets()
sets = sets if isinstance(sets, list) else [sets]
assert len(sets) == len(columns), (len(sets), len(columns))
axis = {1: 'ux', 2: 'uy', 6: 'rz'}
worst = 0.0
for s in sets:
    name = 'H(%d:%s,%d:%s)' % (s['rsp_node'], axis[s['rsp_dir']], s['ref_node'], axis[s['ref_dir']])
    want = columns[name]
    assert np.allclose(s['x'], data[:, 0], rtol=1e-12, atol=0), name
    worst = max(worst, float(np.max(np.abs(s['data'] - want) / np.abs(want))))
print(worst)
# written as ASCII: pyuff 2.5.8 writing 58b loses the first set (its own reader finds one less)
for s in sets:
    s['binary'] = 0
pyuff.UFF(again).write_sets(sets, mode='overwrite')
"#;

/// A truth written apart (a case of its own, with only the lines and
/// channels under `[measurement]`) is simulated as it stands; a command
/// that compares with a test refuses that case at its `[measurement]`
/// table, and compares once given the simulated file.
#[test]
fn a_case_without_data_is_simulated_and_compared_only_with_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let body = crate::fixtures::tutorial_text(|l| (!l.starts_with("data =")).then(|| l.to_string()));
    let case = dir.path().join("apart.toml");
    std::fs::write(&case, &body).unwrap();
    let (case, csv) = (case.to_str().unwrap(), dir.path().join("apart.csv"));
    let out = rfm(&["simulate", case, "--noise", "0.01", "--out", csv.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(frf::io::csv::read_csv(&csv).unwrap().channels().len(), 8);
    let out = rfm(&["compare", case, "--json"]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stderr));
    let line = body.lines().position(|l| l.trim() == "[measurement]").unwrap() + 1;
    let err = text(&out.stderr);
    assert!(err.contains(&format!("apart.toml:{line}:")) && err.contains("no `data` file"), "{err}");
    let out = rfm(&["compare", case, "--measured", csv.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // `fix` and `update` read a file given as well, and the cases they
    // write name it: the truth's data (the tutorial's joint) in a folder
    // of their own
    let truth = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial/l-frame-truth.toml");
    let lab = dir.path().join("lab");
    std::fs::create_dir(&lab).unwrap();
    let data = lab.join("run-2.uff");
    let out = rfm(&[
        "simulate",
        truth.to_str().unwrap(),
        "--truth",
        "--noise",
        "0.01",
        "--seed",
        "9",
        "--out",
        data.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let fixed = dir.path().join("fixed");
    let out = rfm(&["fix", case, "--measured", data.to_str().unwrap(), "--out", fixed.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("joint"), "{}", text(&out.stdout));
    let step = fixed.join("step-1.toml");
    assert!(read(&step).contains("data = \"../lab/run-2.uff\""), "{}", read(&step));
    assert!(!fixed.join("measured.csv").exists(), "data given as a file are not written again");
    let updated = dir.path().join("updated");
    let out = rfm(&["update", step.to_str().unwrap(), "--out", updated.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(read(&updated.join("updated.toml")).contains("data = \"../lab/run-2.uff\""));
    // and `update --measured` with other data reads those: the nominal's
    // own simulated data are far from the joint's, so the fit leaves more
    let again = dir.path().join("again");
    let out = rfm(&[
        "update",
        step.to_str().unwrap(),
        "--measured",
        csv.to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(read(&again.join("updated.toml")).contains("data = \"../apart.csv\""));
}

/// `simulate --out x.uff` writes UFF dataset 58 (ASCII, or 58b with
/// `--binary`) in each kind, which reads back as the CSV of the same run;
/// when pyuff is installed, pyuff reads rfm's files and writes them again,
/// and rfm reads those back too.
#[test]
fn simulate_writes_uff58_ascii_and_binary_that_read_back_in_every_kind() {
    let dir = tempfile::tempdir().unwrap();
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial/l-frame.toml");
    let case = case.to_str().unwrap();
    let pyuff = Command::new("python3").args(["-c", "import pyuff"]).output().is_ok_and(|o| o.status.success());
    if !pyuff {
        eprintln!("pyuff not installed (pip install pyuff): its round trip is skipped");
    }
    for kind in ["receptance", "mobility", "accelerance"] {
        let csv = dir.path().join(format!("{kind}.csv"));
        let out =
            rfm(&["simulate", case, "--kind", kind, "--noise", "0.01", "--seed", "5", "--out", csv.to_str().unwrap()]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let truth = frf::io::csv::read_csv(&csv).unwrap();
        assert_eq!(truth.kind().name(), kind);
        for (binary, tolerance) in [(false, 1e-12), (true, 0.0)] {
            let uff = dir.path().join(format!("{kind}-{binary}.uff"));
            let mut args = vec!["simulate", case, "--kind", kind, "--noise", "0.01", "--seed", "5", "--json"];
            args.extend(["--out", uff.to_str().unwrap()]);
            if binary {
                args.push("--binary");
            }
            let out = rfm(&args);
            assert!(out.status.success(), "{}", text(&out.stderr));
            let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            assert_eq!(
                (doc["kind"].as_str(), doc["channels"].as_u64(), doc["lines"].as_u64()),
                (Some(kind), Some(8), Some(599))
            );
            assert_eq!(doc["format"], if binary { "uff58b binary" } else { "uff58 ascii" });
            let bytes = std::fs::read(&uff).unwrap();
            // dataset 58 or 58b: never CSV text in a .uff file
            assert!(
                bytes.starts_with(b"    -1\n")
                    && String::from_utf8_lossy(&bytes[..40]).contains(if binary { "58b" } else { "58" })
            );
            let back = frf::io::load_measured(&uff, &[]).unwrap().set;
            let d = max_relative_difference(&back, &truth);
            assert!(d <= tolerance, "{kind}, binary {binary}: {d}");
            if pyuff {
                // pyuff reads rfm's file as written (compared in Python with the CSV, which
                // Python's csv module reads whole: its header is quoted) and writes it again
                let again = dir.path().join(format!("{kind}-{binary}-pyuff.uff"));
                let py = Command::new("python3")
                    .args([
                        "-c",
                        PYUFF_ROUND_TRIP,
                        uff.to_str().unwrap(),
                        csv.to_str().unwrap(),
                        again.to_str().unwrap(),
                    ])
                    .output()
                    .unwrap();
                assert!(py.status.success(), "pyuff: {}{}", text(&py.stdout), text(&py.stderr));
                let read = text(&py.stdout).trim().parse::<f64>().unwrap();
                assert!(read <= 1e-12, "{kind}, binary {binary}, read by pyuff: {read}");
                // pyuff writes complex doubles as %20.11e: 12 significant digits, each part
                // rounded by up to 5e-12 of itself, so up to sqrt(2) 5e-12 of the value
                let back = frf::io::load_measured(&again, &[]).unwrap().set;
                let d = max_relative_difference(&back, &truth);
                assert!(d <= 2f64.sqrt() * 5e-12, "{kind}, binary {binary}, written by pyuff: {d}");
            }
        }
    }
}

/// Numeric options are checked before any work: a noise that is not a
/// finite number of 0 or more, an unknown kind, an extension that names no
/// format.
#[test]
fn simulate_refuses_bad_options_with_the_usage_code() {
    let dir = tempfile::tempdir().unwrap();
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial/l-frame.toml");
    let case = case.to_str().unwrap();
    let out_csv = dir.path().join("h.csv");
    let out_dat = dir.path().join("h.dat");
    for (args, words) in [
        (
            vec!["--noise", "nan", "--out", out_csv.to_str().unwrap()],
            "--noise NaN: the relative noise level must be a finite number",
        ),
        (vec!["--noise=-0.1", "--out", out_csv.to_str().unwrap()], "--noise -0.1"),
        (vec!["--noise", "inf", "--out", out_csv.to_str().unwrap()], "--noise inf"),
        (vec!["--kind", "impedance", "--out", out_csv.to_str().unwrap()], "receptance, mobility or accelerance"),
        (vec!["--out", out_dat.to_str().unwrap()], ".uff or .unv for UFF dataset 58"),
        (vec!["--binary", "--out", out_csv.to_str().unwrap()], "--binary writes UFF 58b"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_rfm")).args(["simulate", case]).args(&args).output().unwrap();
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(words), "{args:?}: {stderr}");
        assert!(!out_csv.exists() && !out_dat.exists());
    }
}
