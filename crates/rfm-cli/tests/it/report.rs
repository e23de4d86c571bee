//! Reports of `rfm update --out`, `rfm compare --out` and `rfm fix`: the
//! files exist, the SVG figures are well-formed XML with the expected
//! content (every channel, the MAC matrix, the stabilisation diagram, the
//! structure with what was added), the HTML is self-contained, and the
//! numbers agree with the library's.

use std::path::Path;

use damping::DampedSystem;
use frf::correlation::{BandSpec, correlate};
use rfm_update::Study;

use super::fixtures::{
    case, clamp_update, rfm, svg_files, text, tutorial_applied_compare, tutorial_applied_update, tutorial_compare,
    tutorial_fix, tutorial_update,
};

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Checks that `doc` is a well-formed XML document with root `root`: every
/// tag closed in order, quoted attributes, only entity-escaped `&` in text.
/// Returns the element names in document order.
fn check_xml(doc: &str, root: &str) -> Result<Vec<String>, String> {
    let mut stack: Vec<String> = Vec::new();
    let mut names = Vec::new();
    let mut rest = doc;
    let mut seen_root = false;
    while let Some(lt) = rest.find('<') {
        let between = &rest[..lt];
        if stack.is_empty() && !between.trim().is_empty() {
            return Err(format!("text outside the root element: {between:?}"));
        }
        check_text(between)?;
        let after = &rest[lt..];
        if let Some(comment) = after.strip_prefix("<!--") {
            let end = comment.find("-->").ok_or("unterminated comment")?;
            rest = &comment[end + 3..];
            continue;
        }
        let gt = after.find('>').ok_or("unterminated tag")?;
        let tag = &after[1..gt];
        rest = &after[gt + 1..];
        if tag.starts_with('?') {
            continue;
        }
        if !tag.matches('"').count().is_multiple_of(2) {
            return Err(format!("unbalanced quotes in <{tag}>"));
        }
        if let Some(name) = tag.strip_prefix('/') {
            let open = stack.pop().ok_or_else(|| format!("</{name}> closes nothing"))?;
            if open != name.trim() {
                return Err(format!("</{name}> closes <{open}>"));
            }
            continue;
        }
        let name: String = tag.chars().take_while(|c| !c.is_whitespace() && *c != '/').collect();
        if name.is_empty() {
            return Err(format!("a tag without a name: <{tag}>"));
        }
        if stack.is_empty() {
            if seen_root {
                return Err(format!("a second root element <{name}>"));
            }
            if name != root {
                return Err(format!("the root is <{name}>, not <{root}>"));
            }
            seen_root = true;
        }
        names.push(name.clone());
        if !tag.ends_with('/') {
            stack.push(name);
        }
    }
    if !rest.trim().is_empty() {
        return Err(format!("text after the root element: {rest:?}"));
    }
    if let Some(open) = stack.pop() {
        return Err(format!("<{open}> is never closed"));
    }
    if !seen_root {
        return Err("no root element".into());
    }
    Ok(names)
}

fn check_text(t: &str) -> Result<(), String> {
    for (i, _) in t.match_indices('&') {
        let entity: String = t[i + 1..].chars().take_while(|c| *c != ';').collect();
        let known = ["amp", "lt", "gt", "quot", "apos"].contains(&entity.as_str()) || entity.starts_with('#');
        if !known || entity.len() > 8 {
            return Err(format!("an unescaped `&` in {t:?}"));
        }
    }
    Ok(())
}

/// Checks an SVG figure (well-formed, labelled, with the given texts) and
/// returns its text.
fn check_figure(path: &Path, must_contain: &[&str]) -> String {
    let svg = read(path);
    check_xml(&svg, "svg").unwrap_or_else(|e| panic!("{} is not well-formed: {e}", path.display()));
    assert!(svg.matches("<text").count() >= 5, "{} has too few labels", path.display());
    for s in must_contain {
        assert!(svg.contains(s), "{} lacks {s:?}", path.display());
    }
    svg
}

/// Checks an SVG figure of curves and returns its text.
fn check_svg(path: &Path, must_contain: &[&str]) -> String {
    let svg = check_figure(path, must_contain);
    assert!(svg.contains("<polyline"), "{} draws no curve", path.display());
    svg
}

/// `#RRGGBB` as plotters writes a colour.
fn hex(r: u8, g: u8, b: u8) -> String {
    format!("#{r:02X}{g:02X}{b:02X}")
}

/// The panel titles of a small-multiples figure (`1. H(...)...`), in order.
fn panel_titles(svg: &str) -> Vec<String> {
    svg.split('>')
        .filter_map(|t| t.split('<').next())
        .map(str::trim)
        .filter(|t| t.split_once(". H(").is_some_and(|(k, _)| k.parse::<usize>().is_ok()))
        .map(str::to_string)
        .collect()
}

/// Fails if the HTML loads anything from elsewhere or runs scripts.
fn check_self_contained(html: &str) {
    let lower = html.to_ascii_lowercase();
    for bad in ["<script", "<link", "@import", "url(", "<iframe", "<img", "src="] {
        assert!(!lower.contains(bad), "report.html contains `{bad}`");
    }
    for (i, _) in lower.match_indices("href=\"") {
        let target = &lower[i + 6..];
        assert!(target.starts_with('#'), "report.html links outside itself: {}", &target[..target.len().min(60)]);
    }
    // the SVG namespace is an identifier, not a resource; nothing else names a URL
    let urls = lower.matches("http://").count() + lower.matches("https://").count();
    assert_eq!(urls, lower.matches("xmlns=\"http://www.w3.org/2000/svg\"").count(), "report.html names a URL");
}

#[test]
fn update_out_writes_figures_parameters_and_a_self_contained_report() {
    let w = clamp_update();
    let out = &w.output;
    // the RFM stalls on this twin far above the noise: its outputs are
    // written, and the exit code says it stalled
    assert_eq!(out.status.code(), Some(8), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("stalled"), "{}", text(&out.stdout));
    assert!(text(&out.stderr).contains("exit code 8: stalled"), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("report.html"), "{}", text(&out.stdout));

    let d = w.dir.as_path();
    check_svg(&d.join("convergence.svg"), &["Iteration", "RFM residual", "RMS dB error over the band"]);
    let params =
        check_svg(&d.join("parameters.svg"), &["Value / initial value", "spring.clamp_r.kr", "group.clamp_x.alpha"]);
    check_svg(&d.join("error-vs-frequency.svg"), &["Frequency (Hz", "RMS phase error (deg)", "initial model"]);
    // categories as bars, one colour per model, nothing joining the channels
    let bars = check_figure(&d.join("channel-errors.svg"), &["FRAC", "3:uy", "7:uy"]);
    for colour in [hex(213, 94, 0), hex(0, 114, 178)] {
        assert!(bars.matches(&format!("fill=\"{colour}\"")).count() >= 2 * 5, "bars and dots of {colour}");
    }
    // the driving point large, and every channel in the small multiples, ticks for the updating lines
    assert!(d.join("frf-7uy-7uy.svg").exists());
    let all = check_svg(
        &d.join("frf-channels.svg"),
        &["Frequency (Hz", "measured", "initial model", "updated model", "updating lines (ticks on the axis)"],
    );
    assert_eq!(panel_titles(&all).len(), 5, "{:?}", panel_titles(&all));
    for p in svg_files(d).iter().filter(|p| p.file_name().unwrap().to_str().unwrap().starts_with("frf-")) {
        let svg = check_svg(p, &["deg", "dB", "Frequency (Hz"]);
        assert!(!svg.contains("<circle"), "{}: updating lines are ticks, not circles on the curve", p.display());
    }

    let html = read(&d.join("report.html"));
    check_self_contained(&html);
    // the same status words as the terminal, and no claim of uncertainty
    assert!(html.contains("stalled: no step lowers the misfit"), "the report does not say how the run ended");
    assert!(html.contains("No uncertainty is available"), "the report does not say the RFM has no uncertainty");
    assert!(!html.contains("within the noise"));
    let updated = read(&d.join("updated.toml"));
    assert!(updated.contains("status stalled,"), "updated.toml does not name the status");
    assert_eq!(html.matches("<svg").count(), svg_files(d).len(), "every figure is inline in the report");
    for heading in ["Summary", "Convergence", "Parameters", "FRF correlation", "Modes", "FRF overlays"] {
        assert!(html.contains(&format!("<h2>{heading}</h2>")), "report.html lacks the section {heading}");
    }
    // the HTML is well-formed apart from the void elements of its head
    let body = &html[html.find("<body>").unwrap()..html.find("</html>").unwrap()];
    check_xml(body, "body").unwrap_or_else(|e| panic!("report.html body: {e}"));

    // parameters.csv holds the values of results.json
    let json: serde_json::Value = serde_json::from_str(&read(&d.join("results.json"))).unwrap();
    let params_json = json["parameters"].as_array().unwrap();
    let csv = read(&d.join("parameters.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), params_json.len() + 1);
    assert!(lines[0].starts_with("parameter,unit,initial,updated"));
    for (line, p) in lines[1..].iter().zip(params_json) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[0], p["name"].as_str().unwrap());
        let updated: f64 = cells[3].parse().unwrap();
        let expect = p["updated"].as_f64().unwrap();
        assert!(((updated - expect) / expect).abs() < 1e-12, "{line}");
        assert!(html.contains(&format!("<td>{}</td>", cells[0])));
    }
    // each parameter in its own colour (the first ten are the palette's, solid)
    let palette = [(0, 114, 178), (213, 94, 0), (0, 158, 115), (204, 121, 167), (230, 159, 0), (86, 180, 233)];
    for (i, _) in params_json.iter().enumerate().take(palette.len()) {
        let (r, g, b) = palette[i];
        assert!(params.contains(&format!("stroke=\"{}\"", hex(r, g, b))), "parameter {i} has no line of its own");
    }
    // many updating lines are summarised, and listed folded away
    let n_lines = json["frequencies_hz"].as_array().unwrap().len();
    if n_lines > 12 {
        assert!(html.contains(&format!("<summary>The {n_lines} updating lines (Hz)</summary>")), "{n_lines} lines");
    }
}

#[test]
fn an_output_error_report_shows_the_uncertainty_of_each_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let case_file = case("cantilever-flexible-clamp");
    let out = rfm(&[
        "update",
        case_file.to_str().unwrap(),
        "--method",
        "output-error",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_str(&read(&dir.path().join("results.json"))).unwrap();
    let unc = json["uncertainty"]["parameters"].as_array().expect("output-error reports uncertainty");
    let csv = read(&dir.path().join("parameters.csv"));
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    for (line, u) in csv.lines().skip(1).zip(unc) {
        let cells: Vec<&str> = line.split(',').collect();
        let s: f64 = cells[col("relative_std")].parse().unwrap();
        // JSON has no infinity: a direction the data cannot resolve is written as null there and "inf" in the CSV.
        match u["relative_std"].as_f64() {
            Some(expect) => assert!((s - expect).abs() <= 1e-12 * expect.abs().max(1e-300), "{line}"),
            None => {
                assert!(u["relative_std"].is_null() && s.is_infinite(), "{line}");
                assert!(!u["well_determined"].as_bool().unwrap(), "{line}");
            }
        }
        assert_eq!(cells[col("well_determined")], u["well_determined"].as_bool().unwrap().to_string());
    }
    let html = read(&dir.path().join("report.html"));
    check_self_contained(&html);
    assert!(html.contains(">95 % interval</th>") && html.contains(">determined</th>"));
    check_svg(&dir.path().join("convergence.svg"), &["fit residual"]);
}

#[test]
fn compare_json_agrees_with_the_library() {
    let case_file = case("two-material-beam");
    let out = rfm(&["compare", case_file.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    let c = &json["correlation"];

    let study = Study::load(&case_file).unwrap();
    let model = DampedSystem::new(study.case().model.clone()).unwrap();
    let frfs = frf::synthesize(&model, study.measured().channels(), study.measured().frequencies_hz()).unwrap();
    let lib = correlate(study.measured(), &frfs, &BandSpec::Auto).unwrap();

    let close = |a: &serde_json::Value, b: f64| {
        let a = a.as_f64().unwrap_or_else(|| panic!("not a number: {a}"));
        (a - b).abs() <= 1e-12 * b.abs().max(1e-12)
    };
    assert!(close(&c["total"]["rms_db"], lib.total.rms_db));
    assert!(close(&c["total"]["rms_phase_deg"], lib.total.rms_phase_deg));
    assert!(close(&c["total"]["mean_frac"], lib.total.mean_frac));
    assert!(close(&c["total"]["log_misfit"], lib.total.log_misfit));
    let channels = c["channels"].as_array().unwrap();
    assert_eq!(channels.len(), lib.channels.len());
    for (j, l) in channels.iter().zip(&lib.channels) {
        assert_eq!(j["channel"], l.channel.to_string());
        assert!(close(&j["rms_db"], l.rms_db) && close(&j["frac"], l.frac) && close(&j["share"], l.share));
    }
    let bands = c["bands"].as_array().unwrap();
    assert_eq!(bands.len(), lib.bands.len());
    assert!(bands.len() >= 4, "one band per resonance of the beam in 0-400 Hz");
    for (j, l) in bands.iter().zip(&lib.bands) {
        assert!(close(&j["lo_hz"], l.band.lo_hz) && close(&j["rms_db"], l.rms_db));
    }
    let worst = lib.worst_channels(1)[0];
    assert_eq!(c["worst_channels"][0], lib.channels[worst].channel.to_string());
    // the paper's initial damping errors show: a measurable but not gross misfit
    assert!(lib.total.rms_db > 0.5 && lib.total.rms_db < 5.0, "{}", lib.total.rms_db);
}

#[test]
fn compare_reads_a_measured_file_and_writes_a_report_with_given_bands() {
    let dir = tempfile::tempdir().unwrap();
    let case_file = case("cantilever-flexible-clamp");
    let data = dir.path().join("measured.csv");
    let sim = rfm(&[
        "simulate",
        case_file.to_str().unwrap(),
        "--truth",
        "--noise",
        "0.02",
        "--seed",
        "9",
        "--out",
        data.to_str().unwrap(),
    ]);
    assert!(sim.status.success(), "{}", text(&sim.stderr));
    let report_dir = dir.path().join("report");
    let out = rfm(&[
        "compare",
        case_file.to_str().unwrap(),
        "--measured",
        data.to_str().unwrap(),
        "--bands",
        "1,100,300,1000",
        "--out",
        report_dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("per channel") && stdout.contains("per band") && stdout.contains("<- worst"), "{stdout}");

    let json: serde_json::Value = serde_json::from_str(&read(&report_dir.join("compare.json"))).unwrap();
    assert!(json["measured"].as_str().unwrap().contains("measured.csv"));
    let bands = json["correlation"]["bands"].as_array().unwrap();
    assert_eq!(bands.len(), 3);
    assert_eq!(bands.iter().map(|b| b["lines"].as_u64().unwrap()).sum::<u64>(), 1000);
    assert_eq!(json["correlation"]["channels"].as_array().unwrap().len(), 5);

    check_svg(&report_dir.join("error-vs-frequency.svg"), &["RMS dB error"]);
    check_figure(&report_dir.join("channel-errors.svg"), &["Channel (response DOF)"]);
    check_svg(&report_dir.join("frf-7uy-7uy.svg"), &["measured", "model", "Phase (deg)"]);
    let html = read(&report_dir.join("report.html"));
    check_self_contained(&html);
    assert!(html.contains("<h2>FRF correlation</h2>") && html.contains("measured.csv"));
    assert!(html.contains("1-100 Hz") && html.contains("300-1000 Hz"), "the given band edges label the table");
}

#[test]
fn compare_refuses_bad_bands_and_missing_files_with_a_message() {
    let case_file = case("cantilever-flexible-clamp");
    let out = rfm(&["compare", case_file.to_str().unwrap(), "--bands", "0,fifty"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("`fifty` is not a frequency"), "{}", text(&out.stderr));
    let out = rfm(&["compare", case_file.to_str().unwrap(), "--bands", "2000,3000"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("no measured line"), "{}", text(&out.stderr));
    let out = rfm(&["compare", case_file.to_str().unwrap(), "--measured", "/nonexistent/h.csv"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("/nonexistent/h.csv"), "{}", text(&out.stderr));
}

#[test]
fn the_xml_check_rejects_what_it_should() {
    assert!(check_xml("<svg><g><text>a &amp; b</text></g></svg>", "svg").is_ok());
    let refused = |doc: &str| check_xml(doc, "svg").unwrap_err();
    assert_eq!(refused("<svg><g></svg>"), "</svg> closes <g>");
    assert_eq!(refused("<svg><text>a & b</text></svg>"), "an unescaped `&` in \"a & b\"");
    assert_eq!(refused("<svg a=\"1></svg>"), "unbalanced quotes in <svg a=\"1>");
    assert_eq!(refused("<html></html>"), "the root is <html>, not <svg>");
    assert_eq!(refused("<svg/><svg/>"), "a second root element <svg>");
    assert_eq!(refused("<svg><g>"), "<g> is never closed");
    assert_eq!(refused("<svg></svg>tail"), "text after the root element: \"tail\"");
}

/// Case 1's initial model differs from its truth only in damping: every
/// measured mode must pair with its model mode (MAC near 1, frequency within
/// half a percent) and read as a damping error; the report carries the table.
#[test]
fn compare_reads_each_mode_of_a_damping_only_error_as_damping() {
    let dir = tempfile::tempdir().unwrap();
    let out =
        rfm(&["compare", case("two-material-beam").to_str().unwrap(), "--json", "--out", dir.path().to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = doc["modes"]["rows"].as_array().unwrap_or_else(|| panic!("no mode table: {}", doc["modes"]));
    assert!(rows.len() >= 5, "{rows:?}");
    for r in rows {
        assert!(r["mac"].as_f64().unwrap() > 0.99, "{r}");
        assert!(r["frequency_error_pct"].as_f64().unwrap().abs() < 0.5, "{r}");
        assert!(r["reading"].as_str().unwrap().contains("damping error"), "{r}");
    }
    let html = read(&dir.path().join("report.html"));
    assert!(html.contains("Modes") && html.contains("a damping error"));
}

/// The RFM diverges on the f-frame twin and leaves a model whose dynamic
/// stiffness is singular to working precision near one of its resonances.
/// The run still ends with its results and a report (the figures leave that
/// line out and say so), instead of failing after the results were written.
#[test]
fn a_diverged_rfm_run_still_writes_its_report() {
    let dir = tempfile::tempdir().unwrap();
    let out =
        rfm(&["update", case("f-frame").to_str().unwrap(), "--method", "rfm", "--out", dir.path().to_str().unwrap()]);
    // written, with the code of a run that stalled above the noise
    assert_eq!(out.status.code(), Some(8), "{}", text(&out.stderr));
    let json: serde_json::Value = serde_json::from_str(&read(&dir.path().join("results.json"))).unwrap();
    assert_eq!(json["status"], "stalled");
    check_self_contained(&read(&dir.path().join("report.html")));
}

/// The tutorial's compare report: every one of its 8 channels, worst first
/// by the misfit of compare.json; the MAC matrix with the pairing of the
/// mode table; the stabilisation diagram; the paired shapes; the structure
/// with every measured DOF.
#[test]
fn the_tutorial_compare_report_shows_every_channel_the_modes_and_the_structure() {
    let w = tutorial_compare();
    assert!(w.output.status.success(), "{}", text(&w.output.stderr));
    let d = w.dir.as_path();
    let json: serde_json::Value = serde_json::from_str(&read(&d.join("compare.json"))).unwrap();
    let channels = json["correlation"]["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 8);
    let mut by_misfit: Vec<(f64, String)> = channels
        .iter()
        .map(|c| (c["log_misfit"].as_f64().unwrap(), c["channel"].as_str().unwrap().to_string()))
        .collect();
    by_misfit.sort_by(|a, b| b.0.total_cmp(&a.0));

    let all =
        check_svg(&d.join("frf-channels.svg"), &["Every channel (8), worst first", "Frequency (Hz, logarithmic)"]);
    let titles = panel_titles(&all);
    assert_eq!(titles.len(), 8, "{titles:?}");
    for (k, (t, (_, ch))) in titles.iter().zip(&by_misfit).enumerate() {
        assert!(t.starts_with(&format!("{}. {ch}", k + 1)), "panel {} is {t}, not {ch}", k + 1);
    }
    assert_eq!(all.matches(">\nmeasured\n<").count(), 1, "one legend for all panels");
    check_svg(&d.join("error-vs-frequency.svg"), &["Frequency (Hz, logarithmic)"]);

    let rows = json["modes"]["rows"].as_array().unwrap_or_else(|| panic!("no modes: {}", json["modes"]));
    let pairs = rows.iter().filter(|r| !r["mac"].is_null()).count();
    let measured = rows.iter().filter(|r| !r["measured_hz"].is_null()).count();
    assert!(pairs >= 4, "{rows:?}");
    let mac = check_figure(&d.join("mac-matrix.svg"), &["measured modes", "model modes", "paired"]);
    assert_eq!(
        mac.matches("stroke=\"#000000\" stroke-width=\"3\"").count(),
        pairs + 1,
        "an outline per pair, and the legend's"
    );
    for r in rows.iter().filter(|r| !r["measured_hz"].is_null()) {
        let f = r["measured_hz"].as_f64().unwrap();
        assert!(mac.contains(&format!(": {f:.1} Hz\n<")), "no row for the mode at {f:.1} Hz");
    }
    let stab =
        check_figure(&d.join("stabilisation.svg"), &["Model order", "identified mode", "stable (and participation)"]);
    assert!(stab.matches(&format!("fill=\"{}\"", hex(0, 114, 178))).count() >= 5 * measured, "columns of stable poles");
    let shapes = check_figure(&d.join("mode-shapes.svg"), &["undeformed", "model", "measured"]);
    assert_eq!(shapes.matches("\nMeasured mode ").count(), pairs, "one panel per pair");

    let structure = check_figure(&d.join("structure.svg"), &["measured response", "excitation"]);
    // an arrowhead per measured response (8 translations) and one for the excitation
    assert_eq!(structure.matches("<polygon").count(), 9);
    for node in ["15", "23", "5", "13"] {
        assert!(structure.contains(&format!(">\n{node}\n<")), "node {node} is not labelled");
    }

    let html = read(&d.join("report.html"));
    check_self_contained(&html);
    assert_eq!(html.matches("<svg").count(), svg_files(d).len(), "every figure is inline in the report");
    for heading in ["Summary", "FRF correlation", "Modes", "FRF overlays"] {
        assert!(html.contains(&format!("<h2>{heading}</h2>")), "report.html lacks the section {heading}");
    }
}

/// The loop's report on the tutorial: the misfit per step, the structure
/// with the joint it added marked at the corner, the modes of the fixed
/// model and all 8 channels before and after.
#[test]
fn the_tutorial_fix_report_marks_the_added_joint_where_it_sits() {
    let w = tutorial_fix();
    let d = w.dir.as_path();
    assert!(d.join("report.html").exists(), "{}", text(&w.output.stderr));
    let json: serde_json::Value = serde_json::from_str(&read(&d.join("results.json"))).unwrap();
    let first = &json["steps"][0]["effect"];
    assert_eq!(first["kind"], "flexible_joint", "{first}");
    let description = first["description"].as_str().unwrap();

    // each step named on the axis, numbered as on the structure
    check_svg(&d.join("misfit-steps.svg"), &["nominal", "+ 1: joint at node 13", "updated 1"]);
    let structure = check_figure(&d.join("structure.svg"), &["The structure and what was added"]);
    assert!(structure.contains(&format!("1: {description}")), "the legend names the joint: {description}");
    // a ring in the first step's colour, and its badge
    assert!(structure.contains(&format!("stroke=\"{}\"", hex(204, 37, 41))), "no ring for the joint");
    assert!(structure.contains(&format!("fill=\"{}\"", hex(204, 37, 41))), "no badge for the joint");
    assert!(structure.contains(">\n13\n<"), "the corner node is labelled");

    let all = check_svg(&d.join("frf-channels.svg"), &["nominal model", "fixed model"]);
    assert_eq!(panel_titles(&all).len(), 8);
    check_figure(&d.join("mac-matrix.svg"), &["measured modes"]);
    check_figure(&d.join("stabilisation.svg"), &["Model order"]);
    check_figure(&d.join("mode-shapes.svg"), &["MAC"]);
    let html = read(&d.join("report.html"));
    check_self_contained(&html);
    assert_eq!(html.matches("<svg").count(), svg_files(d).len());
    for heading in ["The misfit after each step", "Modes", "FRF overlays"] {
        assert!(html.contains(&format!("<h2>{heading}</h2>")), "report.html lacks the section {heading}");
    }
}

/// The reports of a case written by `rfm diagnose --apply` tell the loop so
/// far from the case's history: the misfit per step (and, for the update,
/// after it) and the structure with the added joint marked at the corner;
/// with every channel, the MAC matrix and the stabilisation diagram.
#[test]
fn the_reports_of_an_applied_case_show_the_loop_so_far() {
    for (w, steps, kind) in [
        (tutorial_applied_update(), &["nominal", "+ 1: joint at node 13", "updated"][..], "update"),
        (tutorial_applied_compare(), &["nominal", "+ 1: joint at node 13"][..], "compare"),
    ] {
        assert!(w.output.status.success(), "{kind}: {}", text(&w.output.stderr));
        let d = w.dir.as_path();
        let fall = check_svg(&d.join("misfit-steps.svg"), steps);
        // the compare report draws the history alone, the update's adds itself
        assert_eq!(fall.contains(">\nupdated\n<"), kind == "update", "{kind}");
        let structure = check_figure(&d.join("structure.svg"), &["The structure and what was added"]);
        assert!(structure.contains("1: flexible, lossy joint at node 13"), "{kind}: the legend names the joint");
        assert!(structure.contains(&format!("stroke=\"{}\"", hex(204, 37, 41))), "{kind}: no ring for the joint");
        let all = check_svg(&d.join("frf-channels.svg"), &["measured"]);
        assert_eq!(panel_titles(&all).len(), 8, "{kind}");
        check_figure(&d.join("mac-matrix.svg"), &["measured modes"]);
        check_figure(&d.join("stabilisation.svg"), &["Model order"]);
        let html = read(&d.join("report.html"));
        check_self_contained(&html);
        assert!(html.contains("as its [[history]] records them"), "{kind}: the fall's caption");
    }
    // a case without a history draws neither
    let plain = tutorial_compare();
    assert!(!plain.dir.join("misfit-steps.svg").exists());
    assert!(read(&plain.dir.join("structure.svg")).contains("The structure and its measured DOFs"));
}

/// The walkthrough's update: every channel before and after, its 200
/// updating lines as ticks on the axes (no marks on the curves) and folded
/// in the summary.
#[test]
fn the_tutorial_update_report_shows_every_channel_and_ticks_its_updating_lines() {
    let w = tutorial_update();
    assert!(w.output.status.success(), "{}", text(&w.output.stderr));
    let d = w.dir.as_path();
    let json: serde_json::Value = serde_json::from_str(&read(&d.join("results.json"))).unwrap();
    let lines = json["frequencies_hz"].as_array().map_or(0, Vec::len);
    assert!(lines > 12, "{lines} updating lines");
    let all = check_svg(
        &d.join("frf-channels.svg"),
        &["initial model", "updated model", "updating lines (ticks on the axis)"],
    );
    assert_eq!(panel_titles(&all).len(), 8);
    assert!(!all.contains("<circle"), "updating lines are ticks, not marks on the curves");
    // a tick per updating line in each magnitude panel, as far as the
    // panel's pixel columns tell them apart (lines a pixel apart share
    // one): short vertical black paths, none drawn twice
    let ticks: Vec<&str> = all
        .lines()
        .filter(|l| l.starts_with("<polyline") && l.contains("stroke=\"#000000\" stroke-width=\"1\""))
        .collect();
    let mut at: Vec<&str> = ticks.iter().filter_map(|l| l.split("points=\"").nth(1)?.split(' ').next()).collect();
    at.sort_unstable();
    at.dedup();
    assert_eq!(at.len(), ticks.len(), "two ticks at one place");
    assert!((8 * lines / 2..=8 * lines).contains(&ticks.len()), "{} ticks for {lines} lines in 8 panels", ticks.len());
    let html = read(&d.join("report.html"));
    check_self_contained(&html);
    assert!(html.contains(&format!("{lines} lines from")), "the summary names how many lines");
    assert!(html.contains(&format!("<summary>The {lines} updating lines (Hz)</summary>")), "the lines are folded");
    for name in ["structure.svg", "mac-matrix.svg", "stabilisation.svg", "mode-shapes.svg", "parameters.svg"] {
        assert!(d.join(name).is_file(), "no {name}");
    }
}

/// `--frequency-axis linear` draws linear axes where the default would be
/// logarithmic, and an unknown scale is refused with the choices.
#[test]
fn the_frequency_axis_can_be_linear_and_a_bad_choice_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let case_file = case("cantilever-flexible-clamp");
    let out = rfm(&[
        "compare",
        case_file.to_str().unwrap(),
        "--frequency-axis",
        "linear",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    for name in ["frf-channels.svg", "error-vs-frequency.svg", "stabilisation.svg"] {
        let svg = check_figure(&dir.path().join(name), &["Frequency (Hz)"]);
        assert!(!svg.contains("logarithmic"), "{name}");
    }
    let out = rfm(&["compare", case_file.to_str().unwrap(), "--frequency-axis", "octave"]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    let e = text(&out.stderr);
    assert!(e.contains("auto") && e.contains("log") && e.contains("linear"), "{e}");
}
