//! Voltage-referenced data: an unknown complex gain per reference (or per
//! channel) in compare, diagnose and update, whichever way the data arrive.
//!
//! The truth is independent of rfm's gain fit: the tutorial's measured
//! receptances (per newton) are turned into accelerances per volt here, by
//! `-w^2` and a chosen complex constant, so the fitted gain must be that
//! constant and every comparison must be the same for any constant.

use std::path::{Path, PathBuf};
use std::process::Command;

fn rfm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rfm")).args(args).output().expect("rfm runs")
}

fn tutorial() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/tutorial")
}

/// The tutorial's receptances as accelerances per volt, times `gain`
/// (magnitude, phase in degrees).
fn per_volt_accelerance(gain: (f64, f64)) -> String {
    per_volt_accelerance_each(|_| gain)
}

/// As [`per_volt_accelerance`], channel `c` (in the file's order) times
/// `gain(c)`: an amplifier's gain and each accelerometer's own error.
fn per_volt_accelerance_each(gain: impl Fn(usize) -> (f64, f64)) -> String {
    let text = std::fs::read_to_string(tutorial().join("l-frame-measured.csv")).unwrap();
    let mut out = String::from("# kind = accelerance\n# units = (m/s^2)/V\n");
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        if line.starts_with("frequency") {
            out.push_str(line);
            out.push('\n');
            continue;
        }
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let w2 = (2.0 * std::f64::consts::PI * v[0]).powi(2);
        let mut row = vec![v[0].to_string()];
        for (c, p) in v[1..].chunks(2).enumerate() {
            let (m, deg) = gain(c);
            let (gr, gi) = (m * deg.to_radians().cos(), m * deg.to_radians().sin());
            // (re + j im) (gr + j gi) (-w^2)
            let (re, im) = (p[0] * gr - p[1] * gi, p[0] * gi + p[1] * gr);
            row.push(format!("{:e}", -w2 * re));
            row.push(format!("{:e}", -w2 * im));
        }
        out.push_str(&row.join(","));
        out.push('\n');
    }
    out
}

/// The tutorial case reading `data`, written into `dir`, with `extra` lines
/// appended to its `[measurement]` table.
fn case_with(dir: &Path, name: &str, data: &str, extra: &str) -> PathBuf {
    let text = std::fs::read_to_string(tutorial().join("l-frame.toml")).unwrap();
    let text = text.replace("data = \"l-frame-measured.csv\"", &format!("data = \"{data}\"\n{extra}"));
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn json(out: &std::process::Output) -> serde_json::Value {
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// `rfm diagnose --json` of `case` twice: on its own data (`v1.csv`),
/// applying the leader to `applied.toml` in `dir`, and on `v2.csv` in `dir`
/// (`--measured`); the two documents and the applied case.
fn diagnose_twice(dir: &Path, case: &Path) -> (serde_json::Value, serde_json::Value, PathBuf) {
    let applied = dir.join("applied.toml");
    let a =
        json(&rfm(&["diagnose", case.to_str().unwrap(), "--json", "--apply", "1", "--out", applied.to_str().unwrap()]));
    let v2 = dir.join("v2.csv");
    let b = json(&rfm(&["diagnose", case.to_str().unwrap(), "--json", "--measured", v2.to_str().unwrap()]));
    (a, b, applied)
}

/// The leader's first value is the same from both diagnoses; the applied
/// case keeps the gain `setting`, and its update (into `up` beside it) fits
/// them: the update's document and `updated.toml`.
fn same_leader_then_update(
    a: &serde_json::Value,
    b: &serde_json::Value,
    applied: &Path,
    setting: &str,
) -> (serde_json::Value, String) {
    let (ka, kb) = (f(&a["ranking"][0]["parameters"][0]["value"]), f(&b["ranking"][0]["parameters"][0]["value"]));
    assert!((ka / kb - 1.0).abs() < 1e-3, "{ka} vs {kb}");
    let text = std::fs::read_to_string(applied).unwrap();
    assert!(text.contains(&format!("gains = \"{setting}\"")), "{text}");
    let out_dir = applied.parent().unwrap().join("up");
    let u = json(&rfm(&["update", applied.to_str().unwrap(), "--json", "--out", out_dir.to_str().unwrap()]));
    assert!(u["gain_setting"].as_str().unwrap().starts_with(setting), "{u}");
    (u, std::fs::read_to_string(out_dir.join("updated.toml")).unwrap())
}

/// A fitted gain of a JSON document within 1 % and 1 degree of `want`
/// (magnitude, phase in degrees; phases compared modulo a turn).
fn assert_gain_near(fitted: &serde_json::Value, want: (f64, f64), what: &str) {
    assert!((f(&fitted["magnitude"]) / want.0 - 1.0).abs() < 0.01, "{what}: {fitted} vs {want:?}");
    let dphase = (f(&fitted["phase_deg"]) - want.1).rem_euclid(360.0);
    assert!(dphase.min(360.0 - dphase) < 1.0, "{what}: {fitted} vs {want:?}");
}

#[test]
fn compare_fits_the_gain_of_per_volt_data_the_same_from_the_case_and_from_measured() {
    let dir = tempfile::tempdir().unwrap();
    let (g1, g2) = ((150.0, 40.0), (0.02, -120.0));
    std::fs::write(dir.path().join("v1.csv"), per_volt_accelerance(g1)).unwrap();
    std::fs::write(dir.path().join("v2.csv"), per_volt_accelerance(g2)).unwrap();
    let case = case_with(dir.path(), "v1.toml", "v1.csv", "");
    let from_case = json(&rfm(&["compare", case.to_str().unwrap(), "--json"]));
    let v2 = dir.path().join("v2.csv");
    let from_file = json(&rfm(&["compare", case.to_str().unwrap(), "--json", "--measured", v2.to_str().unwrap()]));
    // no Rust shapes in the document
    let text = from_case.to_string();
    assert!(!text.contains("\"Ok\"") && !text.contains("\"Err\""), "{text}");
    for doc in [&from_case, &from_file] {
        assert!(doc["gain_setting"].as_str().unwrap().starts_with("per-reference"), "{doc}");
        assert_eq!(doc["kind"], "accelerance");
        assert!(doc["notes"].as_array().unwrap().iter().any(|n| n.as_str().unwrap().contains("per volt")), "{doc}");
    }
    // the comparison does not depend on the constant, nor on how the data arrive
    let (a, b) = (&from_case["correlation"]["total"], &from_file["correlation"]["total"]);
    for key in ["log_misfit", "rms_db", "mean_frac", "rms_phase_deg"] {
        assert!((f(&a[key]) - f(&b[key])).abs() <= 1e-9 * f(&a[key]).abs().max(1e-12), "{key}: {a} vs {b}");
    }
    // a level offset common to the reference is taken by the gain: no mean dB error is left
    assert!(f(&a["mean_db"]).abs() < 1e-9, "{a}");
    // the two fitted gains differ by the ratio of the constants
    let (ga, gb) = (&from_case["gains"][0], &from_file["gains"][0]);
    assert_eq!(ga["key"], "23:uy");
    assert!((f(&ga["magnitude"]) / f(&gb["magnitude"]) / (g1.0 / g2.0) - 1.0).abs() < 1e-9, "{ga} {gb}");
    let dphase = (f(&ga["phase_deg"]) - f(&gb["phase_deg"]) - (g1.1 - g2.1)).rem_euclid(360.0);
    assert!(dphase.min(360.0 - dphase) < 1e-7, "{ga} {gb}");
}

#[test]
fn gains_none_is_refused_for_per_volt_data_where_it_is_written() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("v.csv"), per_volt_accelerance((10.0, 0.0))).unwrap();
    let case = case_with(dir.path(), "v.toml", "v.csv", "gains = \"none\"");
    let out = rfm(&["compare", case.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("v.toml:46:9") && stderr.contains("23:uy are per volt"), "{stderr}");
    assert!(stderr.contains("calibration"), "{stderr}");
    // a calibration in N/V makes the data per newton: no gain is fitted then
    let case = case_with(dir.path(), "c.toml", "v.csv", "calibration = { \"23:uy\" = \"0.1 V/N\" }");
    let doc = json(&rfm(&["compare", case.to_str().unwrap(), "--json"]));
    assert!(doc["gains"].as_array().unwrap().is_empty() && doc["gain_setting"].as_str().unwrap().starts_with("none"));
    assert!(doc["notes"].as_array().unwrap().iter().any(|n| n.as_str().unwrap().contains("per volt to per newton")));
}

/// The acceptance test of the issue: the same leader with `data =` and
/// with `--measured`, whatever the constant; the gains go into the applied
/// case and into `updated.toml`.
#[test]
fn diagnosis_of_per_volt_data_names_the_joint_whatever_the_gain_and_keeps_the_gains() {
    let dir = tempfile::tempdir().unwrap();
    let (g1, g2) = ((150.0, 40.0), (3.0e-3, 170.0));
    std::fs::write(dir.path().join("v1.csv"), per_volt_accelerance(g1)).unwrap();
    std::fs::write(dir.path().join("v2.csv"), per_volt_accelerance(g2)).unwrap();
    let case = case_with(dir.path(), "v1.toml", "v1.csv", "");
    let (a, b, applied) = diagnose_twice(dir.path(), &case);
    for (d, g) in [(&a, g1), (&b, g2)] {
        assert_eq!(d["gains"], "per-reference");
        let top = &d["ranking"][0];
        // the hidden joint (l-frame-truth.toml): kr = 2e4 at node 13
        assert_eq!((top["kind"].as_str().unwrap(), &top["nodes"]), ("flexible_joint", &serde_json::json!([13])));
        let gain = &top["gains"][0];
        assert_gain_near(gain, g, "the reference");
    }
    let text = std::fs::read_to_string(&applied).unwrap();
    assert!(text.contains("fitted_gains = { \"23:uy\" = ["), "{text}");
    let (_, updated) = same_leader_then_update(&a, &b, &applied, "per-reference");
    let line = updated.lines().find(|l| l.starts_with("fitted_gains")).expect("fitted_gains in updated.toml");
    let mag: f64 = line.split('[').nth(1).unwrap().split(',').next().unwrap().trim().parse().unwrap();
    assert!((mag / g1.0 - 1.0).abs() < 0.01, "{line}");
    // written paths are relative to the written file: it can be moved with its data
    assert!(updated.contains("data = \"../v1.csv\""), "{updated}");
}

/// Every accelerometer with its own unknown sensitivity on top of the
/// amplifier's gain: with `gains = "per-channel"` the diagnosis still names
/// the hidden joint, the same whatever the constants, and the update
/// recovers each channel's gain; the applied and updated cases keep them.
#[test]
fn per_channel_gains_are_fitted_by_diagnose_and_update() {
    let dir = tempfile::tempdir().unwrap();
    // amplifier 150 at 40 deg; sensors within +-30 % and +-8 deg of nominal
    let gain = |c: usize| (150.0 * (0.7 + 0.075 * c as f64), 40.0 + 2.0 * c as f64 - 8.0);
    let other = |c: usize| (0.02 * (1.3 - 0.07 * c as f64), -120.0 - 1.5 * c as f64);
    std::fs::write(dir.path().join("v1.csv"), per_volt_accelerance_each(gain)).unwrap();
    std::fs::write(dir.path().join("v2.csv"), per_volt_accelerance_each(other)).unwrap();
    let case = case_with(dir.path(), "v1.toml", "v1.csv", "gains = \"per-channel\"");
    let (a, b, applied) = diagnose_twice(dir.path(), &case);
    for (d, g) in [(&a, &gain as &dyn Fn(usize) -> (f64, f64)), (&b, &other)] {
        assert_eq!(d["gains"], "per-channel");
        let top = &d["ranking"][0];
        assert_eq!((top["kind"].as_str().unwrap(), &top["nodes"]), ("flexible_joint", &serde_json::json!([13])));
        let gains = top["gains"].as_array().unwrap();
        assert_eq!(gains.len(), 8, "{gains:?}");
        assert_eq!(gains[0]["key"], "H(15:uy,23:uy)");
        for (c, fitted) in gains.iter().enumerate() {
            assert_gain_near(fitted, g(c), &format!("channel {c}"));
        }
    }
    let text = std::fs::read_to_string(&applied).unwrap();
    assert!(text.contains("\"H(13:ux,23:uy)\" = ["), "{text}");
    let (u, updated) = same_leader_then_update(&a, &b, &applied, "per-channel");
    let fitted = u["gains"].as_array().unwrap();
    assert_eq!(fitted.len(), 8);
    for (c, fitted) in fitted.iter().enumerate() {
        assert!((f(&fitted["magnitude"]) / gain(c).0 - 1.0).abs() < 0.01, "channel {c}: {fitted}");
    }
    let line = updated.lines().find(|l| l.starts_with("fitted_gains")).expect("fitted_gains in updated.toml");
    assert_eq!(line.matches("\"H(").count(), 8, "{line}");
}

/// Lines of poor coherence hardly move the fitted gain: the gain is the
/// coherence-weighted mean of `ln(M/H)`, computed here from its definition.
#[test]
fn compare_weights_the_gain_fit_by_the_measured_coherence() {
    use frf::io::uff::{self, DataAxis, Encoding, UffWriteOptions};
    let dir = tempfile::tempdir().unwrap();
    let case = tutorial().join("l-frame.toml");
    let model_csv = dir.path().join("model.csv");
    let out = rfm(&["simulate", case.to_str().unwrap(), "--kind", "accelerance", "--out", model_csv.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut set = frf::io::csv::read_csv(&model_csv).unwrap();
    let (nc, nf) = (set.channels().len(), set.n_freq());
    let g = frf::C64::from_polar(80.0, 0.5);
    let mut coherence = Vec::with_capacity(nc * nf);
    for c in 0..nc {
        let lines = set.frequencies_hz().to_vec();
        for (v, f) in set.channel_mut(c).iter_mut().zip(&lines) {
            // below 100 Hz the data are ten times off, with a coherence of 0.05
            let poor = *f < 100.0;
            *v *= if poor { g * 10.0 } else { g };
            coherence.push(if poor { 0.05 } else { 0.99 });
        }
    }
    set.set_coherence(coherence.clone()).unwrap();
    let mut functions = uff::frf_set_to_functions(&set, &UffWriteOptions::default()).unwrap();
    for f in functions.iter_mut().filter(|f| f.header.function_type == uff::FUNCTION_FRF) {
        f.header.denominator = DataAxis::new(0, "Voltage", "V");
    }
    std::fs::write(dir.path().join("v.uff"), uff::encode(&functions, Encoding::Ascii).unwrap()).unwrap();
    let case = case_with(dir.path(), "v.toml", "v.uff", "");
    let doc = json(&rfm(&["compare", case.to_str().unwrap(), "--json"]));
    let n = doc["notes"].as_array().unwrap();
    assert!(n.iter().any(|x| x.as_str().unwrap().contains("weighted by its measured coherence")), "{n:?}");
    // the weight of a line: sqrt(g / (1 - g)), capped at 30, per residual; squared in the misfit
    let w2 = |coh: f64| ((coh / (1.0 - coh)).sqrt().min(30.0) / 30.0).powi(2);
    let (mut num, mut den) = (0.0, 0.0);
    for &coh in &coherence {
        let log_ratio = g.norm().ln() + if coh < 0.5 { 10f64.ln() } else { 0.0 };
        num += w2(coh) * log_ratio;
        den += w2(coh);
    }
    let want = (num / den).exp();
    let got = f(&doc["gains"][0]["magnitude"]);
    assert!((got / want - 1.0).abs() < 1e-9, "gain {got}, weighted mean {want}");
    // and unweighted it would be far off: 98 of 599 lines are ten times off
    assert!(want / g.norm() - 1.0 < 1e-3, "{want}");
}

/// The first curve of `colour` with more than 50 points in an SVG figure
/// (the magnitude panel is drawn first), as (x, y) pixels.
fn svg_curve(svg: &str, colour: &str) -> Vec<(i64, i64)> {
    svg.split("<polyline")
        .filter(|p| p.contains(&format!("stroke=\"{colour}\"")))
        .filter_map(|p| p.split("points=\"").nth(1)?.split('"').next())
        .map(|pts| {
            pts.split_whitespace()
                .filter_map(|xy| {
                    let (x, y) = xy.split_once(',')?;
                    Some((x.parse().ok()?, y.parse().ok()?))
                })
                .collect::<Vec<(i64, i64)>>()
        })
        .find(|c| c.len() > 50)
        .unwrap_or_else(|| panic!("no curve of colour {colour}"))
}

/// The median vertical distance in pixels between two curves, over the
/// points they share in x.
fn median_gap(a: &[(i64, i64)], b: &[(i64, i64)]) -> i64 {
    let ya: std::collections::HashMap<i64, i64> = a.iter().copied().collect();
    let mut gaps: Vec<i64> = b.iter().filter_map(|(x, y)| Some((y - ya.get(x)?).abs())).collect();
    assert!(gaps.len() > 50, "the curves share {} points", gaps.len());
    gaps.sort_unstable();
    gaps[gaps.len() / 2]
}

/// On data measured as accelerance per volt (the test-data tutorial), the
/// overlays draw the model in the data's kind with its fitted gain: in
/// `compare` the model sat 60 to 130 dB off the measured curve when it was
/// drawn as receptance, and in the update report the initial model, drawn
/// without a gain, sat the gain's level (tens of dB) off.
#[test]
fn overlays_of_data_per_volt_draw_the_model_in_their_kind_and_level() {
    let dir = tempfile::tempdir().unwrap();
    for f in ["lap-joint.toml", "lap-joint-measured.uff"] {
        std::fs::copy(tutorial().join(f), dir.path().join(f)).unwrap();
    }
    let case = dir.path().join("lap-joint.toml");
    let cmp = dir.path().join("cmp");
    let out = rfm(&["compare", case.to_str().unwrap(), "--out", cmp.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // the driving point's figure: measured in black, the model in blue
    let svg = std::fs::read_to_string(cmp.join("frf-5uy-5uy.svg")).unwrap();
    let gap = median_gap(&svg_curve(&svg, "#A0A0A0"), &svg_curve(&svg, "#0072B2"));
    assert!(gap < 20, "compare: the model is drawn a median {gap} px from the measured curve");
    // the diagnosed joint added (its fitted gain with it), then updated: the
    // initial model's level error over all lines is that of a fitted gain
    let applied = dir.path().join("with-joint.toml");
    let out = rfm(&["diagnose", case.to_str().unwrap(), "--apply", "1", "--out", applied.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let up = dir.path().join("up");
    let out = rfm(&["update", applied.to_str().unwrap(), "--out", up.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let html = std::fs::read_to_string(up.join("report.html")).unwrap();
    let row = html.split("RMS dB error, all lines</dt><dd>").nth(1).expect("the summary's error row");
    let initial_db: f64 = row.split(" dB").next().unwrap().trim().parse().unwrap();
    assert!(initial_db < 3.0, "update report: the initial model is {initial_db} dB off over all lines");
    // the mode readings see every mode of the band, in the data divided by the fitted gains
    let fix = dir.path().join("fix");
    // (exit 5: the misfit left is 2.4 times the median noise, which grows where the coherence falls)
    let out = rfm(&["fix", case.to_str().unwrap(), "--out", fix.to_str().unwrap()]);
    assert!(fix.join("report.html").exists(), "{}", String::from_utf8_lossy(&out.stderr));
    for report in [cmp.join("report.html"), up.join("report.html"), fix.join("report.html")] {
        let html = std::fs::read_to_string(&report).unwrap();
        assert!(!html.contains("not seen"), "{}: a mode is not seen", report.display());
    }
    // the initial model of the update and the nominal model of the fix, each
    // with the gains that fit it (the fix report drew the nominal model
    // without them, the amplifier's level off the measured curve)
    for (dir, what) in [(&up, "update report: the initial model"), (&fix, "fix report: the nominal model")] {
        let svg = std::fs::read_to_string(dir.join("frf-5uy-5uy.svg")).unwrap();
        let gap = median_gap(&svg_curve(&svg, "#A0A0A0"), &svg_curve(&svg, "#D55E00"));
        assert!(gap < 20, "{what} is drawn a median {gap} px from the measured curve");
    }
}

/// The lap joint's data per volt (cases/tutorial): the mode reading of
/// `compare` estimates the measured modes from the data divided by the
/// fitted gains. Left with the amplifier's phase, the first mode (7.4 Hz,
/// a fiftieth of the band, narrower than the line spacing, weakly driven)
/// was not seen: no rational function with real coefficients fits a
/// constant phase, and its pole drifted from order to order.
#[test]
fn compare_reads_every_mode_of_data_per_volt_with_the_amplifier_phase_removed() {
    let truth = fe_model::CaseFile::load(tutorial().join("lap-joint-truth.toml")).unwrap().truth.unwrap();
    let modes = damping::complex_modes(&damping::DampedSystem::new(truth.model).unwrap()).unwrap().oscillatory;
    let exact: Vec<(f64, f64)> =
        modes.iter().filter(|m| m.frequency_hz < 400.0).map(|m| (m.frequency_hz, m.damping_ratio)).collect();
    assert_eq!(exact.len(), 4, "{exact:?}");
    let case = tutorial().join("lap-joint.toml");
    let d = json(&rfm(&["compare", case.to_str().unwrap(), "--json"]));
    let rows = d["modes"]["rows"].as_array().expect("the mode table");
    // every model mode of the band paired with a measured one, and nothing else
    assert_eq!(rows.len(), exact.len(), "{rows:#?}");
    for (row, (hz, zeta)) in rows.iter().zip(&exact) {
        assert!(!row["model_hz"].is_null() && !row["measured_hz"].is_null(), "{row}");
        let (measured, damping) = (f(&row["measured_hz"]), f(&row["measured_damping_ratio"]));
        eprintln!("measured {measured:.4} Hz, zeta {damping:.5}; the truth's {hz:.4} Hz, {zeta:.5}");
        assert!((measured / hz - 1.0).abs() < 2e-3, "measured {measured} Hz, the truth's mode {hz} Hz: {row}");
        // the first mode's half-power bandwidth is a seventh of the line
        // spacing, with 10 % noise where the coherence falls: its damping
        // is what the lines determine least
        let tol = if *hz < 10.0 { 0.15 } else { 0.05 };
        assert!((damping / zeta - 1.0).abs() < tol, "measured zeta {damping}, the truth's {zeta}: {row}");
        assert!(f(&row["mac"]) > 0.99, "{row}");
    }
}
