//! Reports and numbers that never contradict each other: one misfit per
//! model whichever command prints it, data per volt labelled per volt in
//! every report of a case, an update's convergence plot that agrees with
//! its summary, dBICs a person can read, a natural-frequency table before
//! and after each step, and outputs that keep what they hold (another
//! command's folder, the finished steps of an interrupted `rfm fix`, an
//! `--out` without `--apply`).

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use super::fixtures::{
    case, lap_compare, lap_fix, lap_update, rfm, text, tutorial_compare, tutorial_diagnose_report, tutorial_fix,
};

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The longest run of digits in `s` that is not the fraction of a number
/// (`-56161045` counts 8, `0.00429208` none: a value to six digits).
fn longest_digits(s: &str) -> usize {
    let mut longest = 0;
    let mut run = 0;
    let mut fraction = false;
    let mut previous = ' ';
    for c in s.chars() {
        if c.is_ascii_digit() {
            if run == 0 {
                fraction = previous == '.';
            }
            run += 1;
            if !fraction {
                longest = longest.max(run);
            }
        } else {
            run = 0;
        }
        previous = c;
    }
    longest
}

/// The rows of a CSV file the report wrote beside a table (no quoted
/// commas in the cells read here).
fn csv(p: &Path) -> Vec<Vec<String>> {
    read(p).lines().map(|l| l.split(',').map(str::to_string).collect()).collect()
}

/// The nominal model's misfit and the noise are the same numbers in the
/// terminal of `compare`, `diagnose` and `fix`, and in `compare.json`.
#[test]
fn one_model_has_one_misfit_in_every_command() {
    let compare = tutorial_compare();
    let diagnose = tutorial_diagnose_report();
    let fix = tutorial_fix();
    let json: serde_json::Value = serde_json::from_str(&read(&compare.dir.join("compare.json"))).unwrap();
    let (misfit, noise) = (json["misfit"]["misfit"].as_f64().unwrap(), json["misfit"]["noise"].as_f64().unwrap());
    // four significant digits, as every output prints a misfit
    let four = |v: f64| format!("{v:.prec$}", prec = (3 - v.log10().floor() as i32).max(0) as usize);
    let (m, n) = (four(misfit), four(noise));
    for (out, what) in [(&compare.output, "compare"), (&diagnose.output, "diagnose"), (&fix.output, "fix")] {
        let stdout = text(&out.stdout);
        assert!(
            stdout.contains(&m) && stdout.contains(&n),
            "{what} does not print misfit {m} and noise {n}:\n{stdout}"
        );
    }
    // the fix's JSON holds the same nominal misfit
    let fixed: serde_json::Value = serde_json::from_str(&read(&fix.dir.join("results.json"))).unwrap();
    let nominal = fixed["nominal_misfit"].as_f64().unwrap();
    assert!((nominal / misfit - 1.0).abs() < 1e-12, "fix {nominal} against compare {misfit}");
}

/// A dBIC of -56161044.7 is printed -56,161,045: no whole number of
/// seven digits or more in the terminal or the reports of a diagnosis and
/// a fix.
#[test]
fn no_dbic_is_printed_as_a_raw_run_of_digits() {
    assert_eq!((longest_digits("dBIC -56161044.7"), longest_digits("0.00429208 s, -56,161,045")), (8, 3));
    let diagnose = tutorial_diagnose_report();
    let fix = tutorial_fix();
    // the case-file lines the diagnosis proposes (indented) keep every digit of their values
    let ranking: String =
        text(&diagnose.output.stdout).lines().filter(|l| !l.starts_with("    ")).map(|l| format!("{l}\n")).collect();
    for (t, what) in [
        (ranking, "rfm diagnose"),
        (text(&fix.output.stdout), "rfm fix"),
        (read(&diagnose.dir.join("ranking.csv")), "ranking.csv"),
    ] {
        assert!(longest_digits(&t) < 7, "{what} prints a number of {} digits:\n{t}", longest_digits(&t));
    }
    assert!(text(&diagnose.output.stdout).contains("-56,161,045"), "{}", text(&diagnose.output.stdout));
    // the report's text (figures aside, whose path data are digits)
    for dir in [&diagnose.dir, &fix.dir] {
        let html = read(&dir.join("report.html"));
        let prose: String = html.split("<svg").map(|p| p.split("</svg>").last().unwrap_or("")).collect();
        assert!(longest_digits(&prose) < 7, "{}: a number of {} digits", dir.display(), longest_digits(&prose));
    }
}

/// The fix report has the natural frequencies and damping of the nominal
/// model and of the model after each step, beside the measured ones, as a
/// table and as CSV.
#[test]
fn the_fix_report_has_natural_frequencies_before_and_after_each_step() {
    let fix = tutorial_fix();
    let rows = csv(&fix.dir.join("modes-per-step.csv"));
    assert_eq!(
        rows[0],
        ["mode", "measured Hz", "measured zeta %", "nominal Hz", "nominal zeta %", "step 1 Hz", "step 1 zeta %"]
    );
    // four modes in the band; the joint brings mode 2 from 52.3 Hz to the measured 43.8 Hz
    assert_eq!(rows.len(), 1 + 4, "{rows:?}");
    let hz = |r: &[String], c: usize| r[c].parse::<f64>().unwrap();
    let (measured, nominal, fixed) = (hz(&rows[2], 1), hz(&rows[2], 3), hz(&rows[2], 5));
    assert!((nominal - measured).abs() > 5.0 && (fixed - measured).abs() < 0.05, "{:?}", rows[2]);
    assert!(read(&fix.dir.join("report.html")).contains("Natural frequencies and damping ratios"));
}

/// Data per volt (the lap joint) are labelled per volt in every report
/// of the case, all in the data's kind, with the gain the model's FRFs were
/// multiplied by; the update's convergence plot ends where its summary
/// does; and every report's fitted gains agree with the amplifier's 42 at
/// -30 degrees within what the model explains.
#[test]
fn reports_of_data_per_volt_agree_on_kind_unit_gain_and_convergence() {
    for (w, what) in [(lap_compare(), "compare"), (lap_update(), "update"), (lap_fix(), "fix")] {
        let d = w.dir.as_path();
        assert!(d.join("report.html").exists(), "{what}: {}", text(&w.output.stderr));
        let overlay = read(&d.join("frf-5uy-5uy.svg"));
        assert!(overlay.contains("Magnitude (dB re 1 m/s²/V)"), "{what}: the driving point is not labelled per volt");
        let html = read(&d.join("report.html"));
        for wrong in ["m/N", "m/s²/N", "receptance"] {
            assert!(!html.contains(wrong), "{what}: the report says {wrong}");
        }
        assert!(html.contains("accelerance per volt"), "{what}");
        let totals = csv(&d.join("totals.csv"));
        let gain = totals.iter().find(|r| r[0] == "gain applied").unwrap_or_else(|| panic!("{what}: {totals:?}"));
        assert!(gain[1..].iter().all(|g| g.starts_with("5:uy: x4")), "{what}: {gain:?}");
    }
    // the convergence figure's lower panel is the iteration table's last
    // column; its first and last values are the summary's RMS dB errors
    let d = lap_update().dir.as_path();
    let html = read(&d.join("report.html"));
    let row = html.split("RMS dB error, all lines</dt><dd>").nth(1).expect("the summary's error row");
    let summary: Vec<f64> = row
        .split("</dd>")
        .next()
        .unwrap()
        .split(" dB")
        .filter_map(|v| v.trim_start_matches(" -&gt; ").trim().parse().ok())
        .collect();
    assert_eq!(summary.len(), 2, "{row}");
    let iterations = csv(&d.join("iterations.csv"));
    let band: Vec<f64> = iterations[1..].iter().map(|r| r.last().unwrap().parse().unwrap()).collect();
    let (first, last) = (band[0], band[band.len() - 1]);
    for (got, want) in [(first, summary[0]), (last, summary[1])] {
        assert!((got - want).abs() <= 0.0051 * want.max(1.0), "convergence {got} dB against the summary's {want} dB");
    }
    assert!(last < 1.0, "the converged update is drawn {last} dB off");
}

/// `rfm compare --out DIR` into the folder of an update refuses before any
/// work and leaves it; `--replace` replaces it.
#[test]
fn a_folder_of_another_commands_results_is_kept_unless_replace_is_given() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("results");
    let case = case("tutorial/l-frame-guess");
    let up = rfm(&["update", case.to_str().unwrap(), "--out", out.to_str().unwrap(), "--iterations", "1"]);
    assert!(out.join("updated.toml").exists(), "{}", text(&up.stderr));
    let before = read(&out.join("updated.toml"));
    let cmp = rfm(&["compare", case.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(cmp.status.code(), Some(6), "{}", text(&cmp.stderr));
    let e = text(&cmp.stderr);
    assert!(e.contains("holds the results of `rfm update`") && e.contains("--replace"), "{e}");
    assert_eq!(read(&out.join("updated.toml")), before);
    let cmp = rfm(&["compare", case.to_str().unwrap(), "--out", out.to_str().unwrap(), "--replace"]);
    assert!(cmp.status.success(), "{}", text(&cmp.stderr));
    assert!(out.join("compare.json").exists() && !out.join("updated.toml").exists());
}

/// `rfm diagnose CASE --out FILE` without `--apply` would write nothing:
/// it is refused, saying what to give, before the diagnosis runs.
#[test]
fn diagnose_out_without_apply_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let new = dir.path().join("new.toml");
    let out = rfm(&["diagnose", case("tutorial/l-frame").to_str().unwrap(), "--out", new.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    let e = text(&out.stderr);
    assert!(e.contains("--apply N") && e.contains("--report DIR"), "{e}");
    assert!(!new.exists());
}

/// A data file that is not the case's says so at once: the error lists
/// what the case wants and what the file holds.
#[test]
fn a_wrong_data_file_says_what_the_case_wants_and_what_the_file_holds() {
    let frame = case("tutorial/l-frame");
    let lap_data = frame.with_file_name("lap-joint-measured.uff");
    let out = rfm(&["compare", frame.to_str().unwrap(), "--measured", lap_data.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stderr));
    let e = text(&out.stderr);
    assert!(
        e.contains("the case wants 8 channels: responses") && e.contains("at reference 23:uy"),
        "the case's channels are not listed:\n{e}"
    );
    assert!(
        e.contains(
            "holds 4 channels (universal file, test DOFs): responses 5:+Z, 9:+Z, 13:+Z, 17:+Z at reference 5:+Z"
        ) && e.contains("accelerance per volt"),
        "the file's channels are not listed:\n{e}"
    );
}

/// An interrupted `rfm fix` keeps the steps it finished, and `--resume`
/// goes on from them: the step file stays as it was, and the run ends
/// with the report of the whole loop.
#[cfg(unix)]
#[test]
fn an_interrupted_fix_keeps_its_finished_steps_and_resumes_from_them() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fix");
    let case = case("tutorial/l-frame");
    let mut child = Command::new(env!("CARGO_BIN_EXE_rfm"))
        .args(["fix", case.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rfm fix starts");
    // interrupt it as soon as its first step is kept (it then diagnoses
    // the fixed model for some seconds more)
    let step = out.join("step-1.toml");
    let deadline = Instant::now() + Duration::from_secs(600);
    while !step.exists() && Instant::now() < deadline && child.try_wait().expect("the child").is_none() {
        std::thread::sleep(Duration::from_millis(20));
    }
    let interrupted = child.try_wait().expect("the child").is_none();
    if interrupted {
        // the child this test started, by its id
        let pid = child.id().to_string();
        assert!(Command::new("kill").args(["-INT", &pid]).status().expect("kill runs").success());
    }
    let output = child.wait_with_output().expect("rfm fix ends");
    assert!(step.exists(), "no step kept: {}", text(&output.stderr));
    let kept = read(&step);
    fe_model::CaseFile::load(&step).expect("the kept step is a case that loads");
    if !interrupted {
        // the loop was done before the interrupt could come: nothing to resume
        return;
    }
    assert_eq!(output.status.code(), Some(130), "{}", text(&output.stderr));
    let e = text(&output.stderr);
    assert!(e.contains("the 1 finished step(s) are in") && e.contains("--resume"), "{e}");
    assert!(out.join("fix-progress.json").exists() && !out.join("report.html").exists());
    // the steps were fitted to the case's data: others given now are refused
    let other = crate::fixtures::case("tutorial/lab-frame").with_file_name("lab-frame-measured.csv");
    let refused = rfm(&[
        "fix",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--resume",
        "--measured",
        other.to_str().unwrap(),
    ]);
    assert_eq!(refused.status.code(), Some(2), "{}", text(&refused.stderr));
    assert!(text(&refused.stderr).contains("were fitted to"), "{}", text(&refused.stderr));
    let resumed = rfm(&["fix", case.to_str().unwrap(), "--out", out.to_str().unwrap(), "--resume"]);
    assert!(resumed.status.success(), "{}", text(&resumed.stderr));
    assert!(text(&resumed.stdout).contains("resuming after step 1"), "{}", text(&resumed.stdout));
    assert_eq!(read(&step), kept, "the resumed run rewrote the kept step");
    assert!(out.join("report.html").exists() && !out.join("fix-progress.json").exists());
    let html = read(&out.join("report.html"));
    assert!(html.contains("after the 1 of an earlier run it resumed"), "the report does not say it resumed");
    // a finished run has nothing to resume
    let again = rfm(&["fix", case.to_str().unwrap(), "--out", out.to_str().unwrap(), "--resume"]);
    assert_eq!(again.status.code(), Some(2), "{}", text(&again.stderr));
    assert!(text(&again.stderr).contains("nothing to resume"), "{}", text(&again.stderr));
}

/// A case with a `[[resonators]]` entry: the lab trial's cantilever with a
/// 50 g resonator at its tip (crates/rfm-cli/tests/it/cases/lab/tip-resonator,
/// whose truth has it as a spring, a mass and a support), given here as a
/// resonator 20 % too stiff, its stiffness and damping declared under
/// `[update]`. `rfm update` brings it to the noise, and `rfm diagnose
/// --report` updates it first (step 0) and finds nothing missing; both
/// reports name its parameters with their units, and draw it.
#[test]
fn a_case_with_a_resonator_is_updated_and_diagnosed_with_its_reports() {
    let lab = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/it/cases/lab/tip-resonator");
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(lab.join("measured.csv"), dir.path().join("measured.csv")).unwrap();
    let truth = read(&lab.join("truth.toml"));
    let value = |key: &str, after: &str| -> f64 {
        let from = truth.find(after).unwrap_or_else(|| panic!("{after} in the truth"));
        let line = truth[from..].lines().find(|l| l.starts_with(key)).unwrap_or_else(|| panic!("{key}"));
        line.split('=').nth(1).unwrap().trim().parse().unwrap()
    };
    let (ky, alpha, m) =
        (value("ky", "name = \"resonator\""), value("alpha", "[groups.resonator]"), value("m =", "[[masses]]"));
    let case = dir.path().join("with-resonator.toml");
    let text_of_case = format!(
        "{}\n[groups.tmd]\nalpha = {alpha:e}\n\n[[resonators]]\nname = \"tmd\"\nnode = 21\nm = {m:e}\nky = {:e}\n\
         group = \"tmd\"\n\n[update]\nparameters = [\"spring.tmd.ky\", \"group.tmd.alpha\"]\nmethod = \"output-error\"\n",
        read(&lab.join("nominal.toml")),
        1.2 * ky
    );
    std::fs::write(&case, text_of_case).unwrap();
    let c = case.to_str().unwrap();

    let up = dir.path().join("up");
    let updated = rfm(&["update", c, "--out", up.to_str().unwrap()]);
    assert!(updated.status.success(), "{}\n{}", text(&updated.stdout), text(&updated.stderr));
    let results: serde_json::Value = serde_json::from_str(&read(&up.join("results.json"))).unwrap();
    assert!(results["misfit"]["times_noise"].as_f64().unwrap() <= 1.5, "{}", results["misfit"]);
    let fitted = results["parameters"].as_array().unwrap();
    let ky_fitted = fitted.iter().find(|p| p["name"] == "spring.tmd.ky").expect("ky updated")["updated"].as_f64();
    assert!((ky_fitted.unwrap() / ky - 1.0).abs() < 0.02, "ky {ky_fitted:?} against the truth's {ky}");
    let html = read(&up.join("report.html"));
    assert!(html.contains("spring.tmd.ky") && html.contains("N/m"), "the update report does not name ky in N/m");

    let report = dir.path().join("diagnosis");
    let diagnosed = rfm(&["diagnose", c, "--report", report.to_str().unwrap()]);
    let stdout = text(&diagnosed.stdout);
    assert!(diagnosed.status.success(), "{stdout}\n{}", text(&diagnosed.stderr));
    assert!(stdout.contains("(step 0, converged)"), "{stdout}");
    assert!(stdout.contains("the model is consistent with the data"), "{stdout}");
    let html = read(&report.join("report.html"));
    for said in ["step 0", "spring.tmd.ky", "N/m", "checked for set-up errors", "none found"] {
        assert!(html.contains(said), "the diagnosis report does not say {said}");
    }
    // the structure drawn with the resonator's mass beside its node: one
    // square more than the nominal model's (which has no mass) and no
    // support drawn where it hangs
    let structure = |dir: &Path| {
        let svg = read(&dir.join("structure.svg"));
        (
            svg.lines().filter(|l| l.starts_with("<rect")).count(),
            svg.lines().filter(|l| l.starts_with("<polygon")).count(),
        )
    };
    let plain = dir.path().join("plain");
    std::fs::write(dir.path().join("plain.toml"), read(&lab.join("nominal.toml"))).unwrap();
    let compared = rfm(&["compare", dir.path().join("plain.toml").to_str().unwrap(), "--out", plain.to_str().unwrap()]);
    assert!(compared.status.success(), "{}", text(&compared.stderr));
    let ((squares, polygons), (plain_squares, plain_polygons)) = (structure(&report), structure(&plain));
    assert_eq!((squares, polygons), (plain_squares + 1, plain_polygons), "the resonator as a mass on a spring");
}

/// `rfm fix` on a lab trial (`cases/lab/NAME` beside these tests) in a
/// fresh folder: the run, its output folder.
fn lab_fix(name: &str) -> (std::process::Output, tempfile::TempDir) {
    let lab = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/it/cases/lab").join(name);
    let dir = tempfile::tempdir().unwrap();
    for f in ["nominal.toml", "measured.csv"] {
        std::fs::copy(lab.join(f), dir.path().join(f)).unwrap();
    }
    let (case, out) = (dir.path().join("nominal.toml"), dir.path().join("fix"));
    (rfm(&["fix", case.to_str().unwrap(), "--out", out.to_str().unwrap()]), dir)
}

/// The text of a report as a reader sees it: figures out, tags out,
/// entities decoded as the reports write them, runs of white space one space.
fn prose(html: &str) -> String {
    let no_figures: String = html.split("<svg").map(|p| p.split("</svg>").last().unwrap_or("")).collect();
    let mut out = String::new();
    let mut in_tag = false;
    for c in no_figures.chars() {
        match c {
            '<' => in_tag = true,
            '>' => {
                in_tag = false;
                out.push(' ');
            }
            c if !in_tag => out.push(c),
            _ => {}
        }
    }
    let out = out
        .replace("&amp;", "&")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&#39;", "'");
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The cells after `label` of the row of `printed` that starts with it
/// (runs of white space one space).
fn row(printed: &str, label: &str) -> Vec<String> {
    let line = printed
        .lines()
        .map(squeezed)
        .find(|l| l.starts_with(&format!("{label} ")))
        .unwrap_or_else(|| panic!("no row `{label}` in\n{printed}"));
    line[label.len()..].split_whitespace().map(str::to_string).collect()
}

/// `cell` read as a number (thousands grouped or not), checked against
/// `value` to the precision it is printed with; the cell as printed.
fn printed_as(cell: &str, value: f64) -> String {
    let read: f64 = cell.replace(',', "").parse().unwrap_or_else(|_| panic!("`{cell}` is no number"));
    let precision = if cell.contains(',') { 0.5 } else { 5e-4 * value.abs() };
    assert!((read - value).abs() <= precision, "{cell} printed for {value}");
    cell.to_string()
}

/// A trial with an inverted channel and a missing mass: the terminal, the
/// JSON and the report tell the same story. The finding with its evidence
/// and the correction applied, the misfit on the data as read and on the
/// corrected data, each step's dBIC, the stop's reason in full; the step's
/// case carries the correction.
#[test]
fn the_fix_report_shows_the_findings_and_each_steps_dbic_as_the_terminal_does() {
    let (run, dir) = lab_fix("flipped-channel");
    let stdout = text(&run.stdout);
    assert!(run.status.success(), "{stdout}\n{}", text(&run.stderr));
    let out = dir.path().join("fix");
    let json: serde_json::Value = serde_json::from_str(&read(&out.join("results.json"))).unwrap();
    let finding = &json["findings"][0];
    assert_eq!(finding["kind"], "inverted_polarity", "{}", json["findings"]);
    assert_eq!(finding["corrections"][0]["sign"], -1.0);
    let report = prose(&read(&out.join("report.html")));
    // the terminal's words and numbers, in the report
    let (summary, evidence) = (finding["summary"].as_str().unwrap(), finding["evidence"].as_str().unwrap());
    let reason = json["stop_reason"].as_str().unwrap();
    for said in [summary, evidence, reason] {
        assert!(stdout.contains(said), "the terminal does not say {said}:\n{stdout}");
        assert!(report.contains(said), "the report does not say {said}");
    }
    assert!(report.contains("H(5:uy,21:uy): sign inverted"), "the correction applied is not shown");
    for (label, key) in [("nominal", "nominal_misfit"), ("nominal, on the corrected data", "corrected_misfit")] {
        let shown = printed_as(&row(&stdout, label)[0], json[key].as_f64().unwrap());
        assert!(report.contains(&format!("{label} {shown}")), "the report lacks `{label} {shown}`");
    }
    let step = &json["steps"][0];
    let dbic = step["delta_bic"].as_f64().unwrap();
    assert!(dbic < -10.0, "{dbic}");
    // misfit, x noise, dBIC of the step
    let cells = row(&stdout, "updated after step 1");
    let shown = printed_as(&cells[2], dbic);
    assert!(report.contains(&format!("updated after step 1 {} {} {shown}", cells[0], cells[1])), "{cells:?}");
    assert!(report.contains(&format!("dBIC of the step {shown}")), "the report lacks the step's dBIC {shown}");
    assert!(read(&out.join("step-1.toml")).contains("[[measurement.corrections]]"));
}

/// A trial whose damping is the case's own parameters' business: step 0
/// updates them and nothing is added. The report shows step 0 as the
/// terminal does (the misfit before and after, its dBIC, the parameters
/// with their units), and its case is written as step-0.toml.
#[test]
fn the_fix_report_shows_step_0_as_the_terminal_does() {
    let (run, dir) = lab_fix("damping-form");
    let stdout = text(&run.stdout);
    assert!(run.status.success(), "{stdout}\n{}", text(&run.stderr));
    let out = dir.path().join("fix");
    let json: serde_json::Value = serde_json::from_str(&read(&out.join("results.json"))).unwrap();
    let declared = &json["declared"];
    let before = printed_as(&row(&stdout, "nominal")[0], declared["misfit_before"].as_f64().unwrap());
    let cells = row(&stdout, "the case's own parameters updated (step 0)");
    let after = printed_as(&cells[0], declared["misfit_updated"].as_f64().unwrap());
    let dbic = printed_as(&cells[2], declared["delta_bic"].as_f64().unwrap());
    let report = prose(&read(&out.join("report.html")));
    assert!(stdout.contains(&format!("misfit {before} -> {after}, dBIC {dbic}")), "{stdout}");
    assert!(report.contains(&format!("misfit {before} -> {after}")), "the report lacks step 0's misfits");
    assert!(report.contains(&format!("dBIC of step 0 {dbic}")), "the report lacks step 0's dBIC {dbic}");
    assert!(report.contains("group.structure.mu 1/s"), "step 0's parameters with their units");
    assert!(stdout.contains("the fixed model:") && stdout.contains("step-0.toml"), "{stdout}");
    assert!(out.join("step-0.toml").exists() && !out.join("step-1.toml").exists());
}

/// `s` with each run of white space one space.
fn squeezed(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}
