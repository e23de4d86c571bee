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

/// A 4-element cantilever whose damping is updated from synthesised data:
/// a complete `update --out` takes a few tens of milliseconds, so that many
/// runs can be killed at random points of it. `iterations` changes the
/// results, and so every output file.
fn quick_case(dir: &Path, name: &str, iterations: usize) -> PathBuf {
    let text = format!(
        r#"title = "quick beam"

[materials]
steel = {{ E = 2.0e11, rho = 7800 }}

[sections]
bar = {{ b = 0.05, h = 0.01 }}

[groups.beam]
alpha = 1e-5
beta = 0.5

[[lines]]
from = [0.0, 0.0]
to = [1.0, 0.0]
elements = 4
material = "steel"
section = "bar"
group = "beam"

[[supports]]
node = 1

[truth]
[truth.set]
"group.beam.alpha" = 2e-5

[measurement]
frequencies = {{ from = 10.0, to = 100.0, step = 10.0 }}
references = ["5:uy"]
responses = ["3:uy", "5:uy"]

[update]
parameters = ["group.beam.alpha", "group.beam.beta"]
max_iterations = {iterations}
"#
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `rfm update CASE --out OUT` to its end.
fn update_into(case: &Path, out: &Path) -> std::process::Output {
    rfm().args(["update", case.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap()
}

/// What lies beside `out` in its parent folder, other than `out` and the cases.
fn beside(out: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(out.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "out" && !n.ends_with(".toml"))
        .collect();
    names.sort();
    names
}

/// A tiny deterministic generator (xorshift), for kill times that differ
/// from run to run but are the same in every test run.
struct Xorshift(u64);

impl Xorshift {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// SIGKILL cannot be caught: whatever point of a run it hits, the output
/// folder must hold the complete old set or the complete new set, and the
/// next run must remove what the killed one left beside it.
#[test]
fn sigkill_at_random_points_leaves_the_complete_old_or_new_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let one = quick_case(dir.path(), "one.toml", 1);
    let two = quick_case(dir.path(), "two.toml", 3);
    let out = dir.path().join("out");
    // the two complete sets, and how long a whole run takes
    assert_eq!(update_into(&one, &out).status.code(), Some(5));
    let set_one = contents(&out);
    let start = std::time::Instant::now();
    let done = update_into(&two, &out);
    let run_time = start.elapsed();
    assert!(matches!(done.status.code(), Some(0 | 5)), "{}", String::from_utf8_lossy(&done.stderr));
    let set_two = contents(&out);
    assert_ne!(set_one, set_two, "the two runs must write different outputs");
    assert_eq!(set_one.keys().collect::<Vec<_>>(), set_two.keys().collect::<Vec<_>>());

    let mut random = Xorshift(0x9e37_79b9_7f4a_7c15);
    let (mut old_kept, mut new_found, mut leftovers) = (0, 0, 0);
    const RUNS: usize = 40;
    for run in 0..RUNS {
        // each run writes the other set over the one in place
        let before = contents(&out);
        let (case, after) = if before == set_one { (&two, &set_two) } else { (&one, &set_one) };
        let mut child = rfm()
            .args(["update", case.to_str().unwrap(), "--out", out.to_str().unwrap()])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // from the start of the process to past a whole run, so that about
        // half the kills fall before the commit and half after
        std::thread::sleep(run_time.mul_f64(2.0 * random.unit()));
        let _ = child.kill();
        child.wait().unwrap();
        let now = contents(&out);
        if now == before {
            old_kept += 1;
        } else if now == *after {
            new_found += 1;
        } else {
            panic!(
                "run {run}: the folder holds neither the complete old nor the complete new outputs: {:?}",
                now.keys()
            );
        }
        if !beside(&out).is_empty() {
            leftovers += 1;
        }
    }
    eprintln!(
        "{RUNS} runs killed: {old_kept} left the old outputs, {new_found} the new ones, {leftovers} left a staging folder or lock"
    );
    // the kills fell both before and after the commit
    assert!(old_kept > 0 && new_found > 0, "old {old_kept}, new {new_found}");
    // the next run cleans what the killed ones left
    let last = update_into(&one, &out);
    assert_eq!(last.status.code(), Some(5), "{}", String::from_utf8_lossy(&last.stderr));
    assert_eq!(contents(&out), set_one);
    assert!(beside(&out).is_empty(), "{:?}", beside(&out));
    assert!(contents(&out).keys().all(|n| !n.contains(".tmp-") && !n.contains("rfm-staging")));
}

/// A second run into an output folder that a first run is writing refuses
/// at once (exit 7) and touches nothing; an interrupted first run removes
/// its staging folder and lock.
#[test]
fn a_second_run_into_the_same_output_is_refused_while_the_first_runs() {
    let dir = tempfile::tempdir().unwrap();
    let case = slow_case(dir.path());
    let quick = quick_case(dir.path(), "quick.toml", 1);
    let out = dir.path().join("out");
    assert_eq!(update_into(&quick, &out).status.code(), Some(5));
    let before = contents(&out);
    let mut first = rfm()
        .args(["update", case.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // the lock is taken before any computing: the first printed line is enough
    let mut lines = BufReader::new(first.stdout.take().unwrap()).lines();
    lines.next().unwrap().unwrap();
    let second = update_into(&quick, &out);
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(7), "{stderr}");
    assert!(stderr.contains(&format!("another rfm run (process {}) is writing into it", first.id())), "{stderr}");
    assert_eq!(contents(&out), before);
    let kill = Command::new("kill").args(["-TERM", &first.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let _rest: Vec<String> = lines.map_while(Result::ok).collect();
    let result = first.wait_with_output().unwrap();
    assert_eq!(result.status.code(), Some(130), "{}", String::from_utf8_lossy(&result.stderr));
    assert_eq!(contents(&out), before);
    assert!(beside(&out).is_empty(), "{:?}", beside(&out));
}

/// A write that fails part-way (here a file-size limit, as a full disk
/// would) leaves the earlier outputs whole and nothing beside them, at
/// every fill level; with room enough, the new set appears whole.
#[test]
fn a_write_that_fails_part_way_leaves_the_earlier_outputs_whole() {
    let dir = tempfile::tempdir().unwrap();
    let one = quick_case(dir.path(), "one.toml", 1);
    let two = quick_case(dir.path(), "two.toml", 3);
    let out = dir.path().join("out");
    // three iterations may converge (0) or not (5): either writes the outputs
    assert!(matches!(update_into(&two, &out).status.code(), Some(0 | 5)));
    let set_two = contents(&out);
    assert_eq!(update_into(&one, &out).status.code(), Some(5));
    let set_one = contents(&out);
    let mut failed = 0;
    // file-size limits in blocks of 512 bytes: from results.json not fitting
    // to everything fitting; SIGXFSZ is ignored so that the write fails with
    // an error, as it would with ENOSPC
    for blocks in [1, 4, 16, 64, 256, 100_000] {
        let script = format!(
            "ulimit -f {blocks}; trap '' XFSZ; exec {} update {} --out {}",
            env!("CARGO_BIN_EXE_rfm"),
            two.display(),
            out.display()
        );
        let result = Command::new("sh").args(["-c", &script]).output().unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        match result.status.code() {
            Some(6) => {
                failed += 1;
                assert!(
                    stderr.contains("cannot write") && stderr.contains("nothing of this run was written"),
                    "{stderr}"
                );
                assert_eq!(contents(&out), set_one, "limit {blocks}");
            }
            Some(0 | 5) => {
                assert_eq!(contents(&out), set_two, "limit {blocks}");
                assert_eq!(update_into(&one, &out).status.code(), Some(5));
            }
            other => panic!("limit {blocks}: exit {other:?}: {stderr}"),
        }
        assert!(beside(&out).is_empty(), "limit {blocks}: {:?}", beside(&out));
    }
    assert!(failed >= 3, "only {failed} of the limits made a write fail");
}

/// An output whose name is known only once it is written (a figure, the
/// parameters table) is checked against the inputs before anything moves
/// into place: here the measured data sit in the output folder under the
/// name of the parameters table.
#[test]
fn an_input_named_like_a_late_output_is_refused_before_anything_moves() {
    let dir = tempfile::tempdir().unwrap();
    let quick = quick_case(dir.path(), "quick.toml", 1);
    let out = dir.path().join("out");
    let data = out.join("parameters.csv");
    let made =
        rfm().args(["simulate", quick.to_str().unwrap(), "--truth", "--out", data.to_str().unwrap()]).output().unwrap();
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    let text =
        std::fs::read_to_string(&quick).unwrap().replace("[truth]\n[truth.set]\n\"group.beam.alpha\" = 2e-5\n", "");
    let case = dir.path().join("measured.toml");
    std::fs::write(
        &case,
        text.replace(
            "responses = [\"3:uy\", \"5:uy\"]",
            "responses = [\"3:uy\", \"5:uy\"]\ndata = \"out/parameters.csv\"",
        ),
    )
    .unwrap();
    let before = contents(&out);
    let result = update_into(&case, &out);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(6), "{stderr}");
    assert!(stderr.contains("parameters.csv: refusing to overwrite an input file"), "{stderr}");
    assert_eq!(contents(&out), before);
    assert!(beside(&out).is_empty(), "{:?}", beside(&out));
}
