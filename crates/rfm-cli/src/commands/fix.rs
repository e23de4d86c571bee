//! `rfm fix`: diagnose, add the recommended effect, update, and again,
//! until nothing significant remains; the case after every step, and a
//! report whose headline is the fall of the misfit.

use std::path::{Path, PathBuf};

use rfm_update::Study;
use rfm_update::fix::{CONSISTENT, FixOptions, FixOutcome, FixProgress, FixStop, fix as run_fix};

use super::{Result, print_masked, print_notes};
use crate::exit::Exit;
use crate::output::Outputs;
use crate::report::fix_report::step_file;
use crate::table::{Table, num};

/// The data a case synthesised from its `[truth]`, written beside the steps.
const DATA_FILE: &str = "measured.csv";

/// Options of the fix command.
pub struct FixArgs<'a> {
    /// The case file.
    pub case: &'a Path,
    /// The output folder.
    pub out: &'a Path,
    /// Most effects to add.
    pub steps: usize,
    /// Print JSON instead of tables.
    pub json: bool,
    /// How the report draws.
    pub report: crate::report::ReportOptions,
}

/// Whether the study's data are synthesised from its case's `[truth]`:
/// then `rfm fix` writes them once beside the steps, which read them there.
fn synthesises(study: &Study) -> bool {
    study.case().measurement.as_ref().and_then(|m| m.data.as_ref()).is_none()
}

/// Opens the outputs of `rfm fix` in `dir` for `steps` steps at most.
fn fix_outputs(study: &Study, steps: usize, dir: &Path) -> Result<Outputs> {
    // one more than the steps: the loop may end by replacing an early effect
    let mut names: Vec<String> = (0..=steps + 1).map(step_file).collect();
    names.extend(["results.json", "report.html"].map(String::from));
    if synthesises(study) {
        names.push(DATA_FILE.into());
    }
    let known: Vec<&str> = names.iter().map(String::as_str).collect();
    Ok(Outputs::folder(dir, &study.case().inputs(), &known)?)
}

/// The options of `rfm fix` on `study`: at most `steps` effects, each
/// diagnosis with the study's options, and where the study's data are
/// synthesised from its `[truth]`, `data` for the file the cases of the
/// steps read them from (written by [`save_fix`], which points the cases
/// at the file it writes).
pub fn fix_options(study: &Study, steps: usize, data: PathBuf) -> Result<FixOptions> {
    Ok(FixOptions {
        max_steps: steps,
        diagnose: study.diagnose_options(study.measured())?,
        data: synthesises(study).then_some(data),
        ..FixOptions::default()
    })
}

/// `rfm fix`: prints each step and the outcome (or `--json`) and writes the
/// cases of the steps, the results and the report.
pub fn fix(args: &FixArgs<'_>) -> Result<Exit> {
    let study = Study::load(args.case)?;
    let mut output = fix_outputs(&study, args.steps, args.out)?;
    print_notes(study.notes(), args.json)?;
    print_masked(&rfm_update::study::describe_masked(study.masked()), args.json)?;
    if !args.json {
        outln!("{}", study.case().model.title);
        outln!(
            "closing the loop on {} channels x {} lines ({} to {} Hz), at most {} steps",
            study.measured().channels().len(),
            study.measured().n_freq(),
            num(study.measured().frequencies_hz()[0]),
            num(*study.measured().frequencies_hz().last().expect("lines")),
            args.steps
        );
    }
    let opts = fix_options(&study, args.steps, output.path(DATA_FILE))?;
    let json = args.json;
    let outcome = run_fix(study.case(), study.measured(), &opts, |p| {
        if json {
            return;
        }
        for line in progress_lines(&p) {
            // an error here would be the same as at the next print, which reports it
            let _ = crate::print_line(format_args!("{line}"));
        }
    })?;
    if json {
        outln!("{}", serde_json::to_string_pretty(&outcome)?);
    } else {
        print_outcome(&outcome)?;
    }

    write_fix(&study, &outcome, &args.report, &mut output)?;
    let written = output.commit()?;
    if !json {
        outln!("\nwrote {} files into {}", written.len(), args.out.display());
        if outcome.final_case().is_some() {
            let last = if outcome.steps.is_empty() { 0 } else { outcome.steps.len() };
            outln!("the fixed model: {}", args.out.join(step_file(last)).display());
        }
    }
    Ok(fix_exit(&outcome))
}

/// What `rfm fix` prints as the loop goes, one line each (the Python
/// package's progress says the same).
pub fn progress_lines(p: &FixProgress<'_>) -> Vec<String> {
    match p {
        FixProgress::Checked { findings: [] } => {
            vec!["checked the data for set-up errors: none found".into()]
        }
        FixProgress::Checked { findings } => std::iter::once("checked the data for set-up errors:".to_string())
            .chain(findings.iter().map(|f| {
                let fix = if f.corrections.is_empty() { "" } else { " (corrected)" };
                format!("  {}{fix}", f.summary)
            }))
            .collect(),
        FixProgress::Declared { step } => vec![format!(
            "step 0: updated the case's own parameters ({}); misfit {:.4e} -> {:.4e}",
            step.status.name(),
            step.misfit_before,
            step.misfit_updated
        )],
        FixProgress::Diagnosed { step, diagnosis } => vec![match diagnosis.leader() {
            Some(l) => format!("diagnosis {}: {} stands out (dBIC {:.1})", step + 1, l.description, l.delta_bic),
            None if diagnosis.consistent() => format!("diagnosis {}: nothing significant", step + 1),
            None => format!("diagnosis {}: significant effects, none at plausible values", step + 1),
        }],
        FixProgress::LookedAhead { ahead, .. } => {
            let what = match &ahead.with {
                Some(with) => format!("{} with {with} (fitted together)", ahead.effect),
                None => ahead.effect.clone(),
            };
            vec![match &ahead.rejected {
                _ if ahead.misfit_ahead.is_nan() => {
                    format!("  tried {what}: {}", ahead.failed.as_deref().unwrap_or("failed"))
                }
                Some(why) => format!("  tried {what}: misfit {:.4e}, not kept: {why}", ahead.misfit_ahead),
                None => format!("  tried {what}: misfit {:.4e}, dBIC {:.1}", ahead.misfit_ahead, ahead.delta_bic),
            }]
        }
        FixProgress::Updated { step, effect, removed, misfit, status } => {
            let verb = if *removed { "took out" } else { "added" };
            vec![format!("step {}: {verb} {effect} and updated ({}); misfit {misfit:.4e}", step + 1, status.name())]
        }
    }
}

/// The exit code of `rfm fix`: success only when the loop ended with the
/// data explained down to their noise; a model that stays above it with
/// nothing the evidence singles out (or several effects it cannot tell
/// apart) is inadequate.
pub fn fix_exit(outcome: &FixOutcome) -> Exit {
    match outcome.stop {
        _ if outcome.explained() => Exit::Success,
        FixStop::ModelInadequate | FixStop::Ambiguous => Exit::ModelInadequate,
        _ => Exit::NotConverged,
    }
}

/// Writes the outputs of `rfm fix` (not yet committed).
fn write_fix(
    study: &Study,
    outcome: &FixOutcome,
    report: &crate::report::ReportOptions,
    output: &mut Outputs,
) -> Result<()> {
    let synthesised = synthesises(study);
    let data_file = synthesised.then(|| output.path(DATA_FILE));
    if synthesised {
        output.write(DATA_FILE, frf::io::csv::to_csv_string(study.measured()).as_bytes())?;
    }
    let cases = outcome
        .declared
        .iter()
        .map(|d| (0, &d.case))
        .chain(outcome.steps.iter().enumerate().map(|(k, s)| (k + 1, &s.case)));
    for (k, case) in cases {
        let name = step_file(k);
        let mut editor = case.clone();
        if let Some(data) = &data_file {
            editor.use_data(data);
        }
        let text = editor.text_at(&output.path(&name))?;
        output.write(&name, text.as_bytes())?;
    }
    output.write("results.json", serde_json::to_string_pretty(&outcome)?.as_bytes())?;
    crate::report::fix_report::write(study, outcome, &report.for_case(study.case()), output)?;
    Ok(())
}

/// Writes what `rfm fix --out DIR` writes for `outcome` (the loop on
/// `study` with at most `steps` effects) into `dir`, all or nothing: the
/// case after every step (`step-1.toml`, ...), `results.json`,
/// `report.html` and the figures, and the data synthesised from the case's
/// `[truth]` (`measured.csv`) where the steps read them; returns the files.
pub fn save_fix(
    study: &Study,
    outcome: &FixOutcome,
    steps: usize,
    dir: &Path,
    report: &crate::report::ReportOptions,
) -> Result<Vec<PathBuf>> {
    let mut output = fix_outputs(study, steps, dir)?;
    write_fix(study, outcome, report, &mut output)?;
    Ok(output.commit()?)
}

fn print_outcome(o: &FixOutcome) -> Result<()> {
    let corrected: Vec<_> = o.findings.iter().filter(|f| !f.corrections.is_empty()).collect();
    if !o.findings.is_empty() {
        outln!("\nfindings about the data (set-up errors are corrected before the model is fitted):");
        for f in &o.findings {
            let fix = if f.corrections.is_empty() { "" } else { " [corrected in the case]" };
            outln!("  - {}{fix}\n    {}", f.summary, f.evidence);
        }
    }
    if !corrected.is_empty() {
        outln!("  the corrections are written under [[measurement.corrections]] in every step's case");
    }
    outln!("\nthe misfit after each step (RMS of ln(model/measured) per value):");
    let mut t = Table::new(&["step", "misfit", "(dB)", "x noise", "dBIC of the step"]);
    let mut bics: Vec<String> = vec![String::new(); 1];
    if o.findings.iter().any(|f| !f.corrections.is_empty()) {
        bics.push(String::new());
    }
    if let Some(d) = &o.declared {
        bics.push(format!("{:.1}", d.delta_bic));
    }
    for s in &o.steps {
        bics.push(String::new());
        bics.push(format!("{:.1}", s.delta_bic));
    }
    for ((label, m), bic) in o.stages().into_iter().zip(bics) {
        t.row(vec![label, format!("{m:.4e}"), format!("{:.1}", 20.0 * m.log10()), format!("{:.1}", m / o.noise), bic]);
    }
    outln!("{}", t.render());
    outln!("noise level estimated from the data: {:.3e}", o.noise);
    outln!("\nstopped: {}", o.stop_reason);
    let last = o.final_misfit();
    if o.explained() {
        outln!(
            "the final misfit is {:.2} times the noise: the model explains the data down to their noise",
            last / o.noise
        );
    } else if last <= CONSISTENT * o.noise {
        outln!("the final misfit is {:.2} times the noise", last / o.noise);
    } else {
        outln!("the final misfit is {:.1} times the noise; what remains unexplained:", last / o.noise);
        for r in &o.remains {
            outln!("  - {r}");
        }
    }
    let last_update = match (o.steps.last(), &o.declared) {
        (Some(s), _) => Some((&s.parameters, &s.uncertainty)),
        (None, Some(d)) => Some((&d.parameters, &d.uncertainty)),
        (None, None) => None,
    };
    if let Some((parameters, uncertainty)) = last_update {
        // the standard deviation shown is the one that includes model error
        // (the residual beyond the noise), which equals the noise's alone when
        // the fit reaches the noise
        let inflated = uncertainty.as_ref().is_some_and(|u| u.inflation > 1.0);
        outln!(
            "\nparameters after the last update (relative standard deviation{}):",
            if inflated { ", widened for the misfit beyond the noise" } else { " from the noise" }
        );
        let mut t = Table::new(&["parameter", "value", "+-1 sd"]);
        for (i, p) in parameters.iter().enumerate() {
            let sd = uncertainty
                .as_ref()
                .and_then(|u| u.parameters.get(i))
                .map_or("-".to_string(), |u| crate::table::percent(u.relative_std));
            t.row(vec![p.name.clone(), num(p.updated), sd]);
        }
        outln!("{}", t.render());
    }
    if let Some(e) = &o.diagnosis_error {
        outln!("\nthe diagnosis of the final model failed, so what remains is not known: {e}");
    } else if o.significant_remains
        && let Some(r) = o.remaining.first()
    {
        outln!("\nstill significant in the last diagnosis: {} (dBIC {:.1})", r.description, r.delta_bic);
    }
    Ok(())
}
