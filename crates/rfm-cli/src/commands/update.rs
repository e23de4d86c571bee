//! `rfm update`: update the model's parameters against the measured FRFs.

use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use rfm_update::{Method, Study, UpdateOutcome};
use rfm_update::{
    response_function::RfmOptions,
    status::{IterationRecord, Status},
};

use rfm_update::quantities::{self, MisfitReport};

use super::{Result, print_masked, print_notes};
use crate::exit::{Exit, Failure};
use crate::output::Outputs;
use crate::table::{self, Table, num};

/// Command-line overrides of the case's `[update]` settings.
#[derive(Default)]
pub struct Overrides {
    /// Method name.
    pub method: Option<String>,
    /// Fit this many lines spread over the band.
    pub lines: Option<usize>,
    /// Iteration limit.
    pub max_iterations: Option<usize>,
}

/// `rfm update`: prints the iterations and the results (or `--json`) and
/// with `--out` writes them.
pub fn update(
    case: &Path,
    measured: Option<&Path>,
    out: Option<&Path>,
    replace: bool,
    json: bool,
    over: &Overrides,
    report: &crate::report::ReportOptions,
) -> Result<Exit> {
    let mut study = super::load_study_measured(case, measured)?;
    let mut output = out
        .map(|dir| Outputs::folder(dir, &study.case().inputs(), &UPDATE_OUTPUTS)?.of_command("update", replace))
        .transpose()?;
    let setup = UpdateSetup::new(&mut study, over)?;
    let (method, lines, max_iterations) = (setup.method, &setup.lines, setup.max_iterations);
    print_notes(study.notes(), json)?;
    print_masked(&rfm_update::study::describe_masked(study.masked()), json)?;
    if !json {
        outln!("{}", study.case().model.title);
        print_history(&study.case().history)?;
        let what = match method {
            Method::Rfm => "the response function method",
            Method::OutputError => "output-error Levenberg-Marquardt",
        };
        outln!(
            "updating {} parameters with {what} at {} lines ({} to {} Hz)",
            study.parameters().len(),
            lines.len(),
            num(lines[0]),
            num(lines[lines.len() - 1])
        );
        outln!("{:>5}  {:>12}  {:>10}", "iter", residual_name(method), "max step");
    }
    let bar = if json { ProgressBar::hidden() } else { ProgressBar::new(max_iterations as u64) };
    bar.set_style(
        ProgressStyle::with_template("{spinner} iteration {pos}/{len} {msg}").unwrap_or(ProgressStyle::default_bar()),
    );
    let on_iteration = |r: &IterationRecord| {
        if !json {
            let line = format!(
                "{:>5}  {:>12}  {:>10}",
                r.iteration,
                table::misfit(r.residual),
                table::significant(r.max_correction, 3)
            );
            // a hidden bar (output not a terminal) swallows println
            if bar.is_hidden() {
                // an error here would be the same as at the next print, which reports it
                let _ = crate::print_line(format_args!("{line}"));
            } else {
                bar.println(line)
            }
        }
        bar.set_position(r.iteration as u64);
        bar.set_message(format!("{} {}", residual_name(method), table::misfit(r.residual)));
    };
    let mut outcome = setup.run(&study, on_iteration)?;
    bar.finish_and_clear();
    let (step, misfits) = finish(&study, &mut outcome)?;
    if json {
        outln!("{}", json_of(&outcome, &misfits)?);
    } else {
        print_outcome(&outcome, method, &misfits)?;
        if !study.case().history.is_empty() {
            outln!("the misfit after each step, from the case's history to this update:");
            print_history(&[study.case().history.clone(), vec![step.clone()]].concat())?;
            if let (Some(ratio), true) = (outcome.noise_ratio, outcome.residual_noise != outcome.noise_estimate) {
                outln!(
                    "(misfits over the {} lines the diagnosis reads, weighted as the fit weighs its lines; the \
                     status, from the fit residual on its own lines: {} times the noise)",
                    misfits[1].lines,
                    table::times(ratio)
                );
            }
        }
    }
    if let Some(output) = output.take() {
        let [path, updated, report] = write_update(&study, &outcome, &step, &misfits, output, case, report, None)?;
        if !json {
            outln!("\nwrote {} and {}", path.display(), updated.display());
            outln!("wrote {} (figures beside it)", report.display());
        }
    }
    let exit = Exit::of_outcome(&outcome);
    if exit != Exit::Success {
        eprintln!("exit code {}: {}", exit.code(), exit.meaning());
    }
    Ok(exit)
}

/// The files `rfm update --out` writes besides the figures.
const UPDATE_OUTPUTS: [&str; 3] = ["results.json", "updated.toml", "report.html"];

/// An update as `rfm update` sets it up: the method, the updating lines and
/// the iteration limit, the case's or the command line's.
pub struct UpdateSetup {
    /// The updating method.
    pub method: Method,
    /// The updating lines (Hz).
    pub lines: Vec<f64>,
    /// The iteration limit.
    pub max_iterations: usize,
}

impl UpdateSetup {
    /// Sets up the update of `study` with the overrides of the command
    /// line (the study's lines change when `over` gives their number).
    pub fn new(study: &mut Study, over: &Overrides) -> Result<UpdateSetup> {
        if over.lines == Some(0) {
            return Err(Failure::new(Exit::Usage, "--lines 0: give at least one measured line to fit"));
        }
        if let Some(n) = over.lines
            && study.case().update.is_some()
        {
            study.set_update_frequencies(fe_model::case::FrequencyChoice::Lines(n))?;
        }
        let method = over.method.as_deref();
        if study.case().update.is_none() {
            return Err("the case has no [update] section".into());
        }
        let method = match method {
            Some(m) => {
                Method::parse(m).ok_or_else(|| format!("unknown method `{m}` (available: rfm, output-error)"))?
            }
            None => study.checked_method().map_err(|e| e.to_string())?,
        };
        let lines = study.lines_for(method)?;
        let max_iterations = over.max_iterations.unwrap_or(match method {
            Method::Rfm => study.rfm_options().max_iterations,
            Method::OutputError => study.output_error_options()?.max_iterations,
        });
        Ok(UpdateSetup { method, lines, max_iterations })
    }

    /// Runs the update, calling `on_iteration` after every iteration.
    pub fn run(&self, study: &Study, on_iteration: impl FnMut(&IterationRecord)) -> Result<UpdateOutcome> {
        Ok(match self.method {
            Method::Rfm => {
                let opts = RfmOptions { max_iterations: self.max_iterations, ..study.rfm_options() };
                study.run_rfm(&opts, on_iteration)?
            }
            Method::OutputError => {
                let mut opts = study.output_error_options()?;
                opts.max_iterations = self.max_iterations;
                study.run_output_error(&opts, on_iteration)?
            }
        })
    }
}

/// What `rfm update` adds to an update's outcome before printing it: the
/// misfit over the whole band against the initial model's (an update that
/// made it worse is marked so), and the entry of the case's history the
/// updated case gets, which it returns.
pub fn finish_update(study: &Study, outcome: &mut UpdateOutcome) -> Result<fe_model::HistoryEntry> {
    Ok(finish(study, outcome)?.0)
}

/// [`finish_update`], with the initial and the updated model's misfits.
fn finish(study: &Study, outcome: &mut UpdateOutcome) -> Result<(fe_model::HistoryEntry, [MisfitReport; 2])> {
    let misfits = misfits(study, outcome)?;
    let [initial, updated] = misfits;
    // worse than the start over the whole band, not only at the fitted lines
    if updated.misfit > WORSE_BY * initial.misfit && !outcome.worse_than_start {
        outcome.worse_than_start = true;
        outcome.warnings.push(format!(
            "the update made the misfit over the band worse than the initial model's ({} -> {}): the updated \
             model is not an improvement",
            table::misfit(initial.misfit),
            table::misfit(updated.misfit)
        ));
    }
    let step = fe_model::HistoryEntry {
        step: format!("updated ({})", outcome.method),
        misfit: updated.misfit,
        noise: updated.noise,
        ..fe_model::HistoryEntry::default()
    };
    Ok((step, misfits))
}

/// The initial and the updated model's misfits over the diagnosis's lines
/// (the misfit the case's history speaks of), weighted as the diagnosis
/// weighs them (the fit's line weights), against the one noise level read
/// against the updated model.
fn misfits(study: &Study, outcome: &UpdateOutcome) -> Result<[MisfitReport; 2]> {
    let weights = study.line_weights(study.measured())?;
    let (measured, weights) = (study.measured(), weights.as_deref());
    let noise = quantities::noise(&outcome.system, measured, weights)?;
    let gains = study.gains();
    let misfit = quantities::misfit(&outcome.system, measured, gains, weights)?;
    let misfit_initial = quantities::misfit(study.system(), measured, gains, weights)?;
    let report_of = |m: f64| MisfitReport {
        misfit: m,
        noise,
        times_noise: noise.map(|n| quantities::times_noise(m, n)),
        lines: HISTORY_LINES.min(measured.n_freq()),
        weighted: weights.is_some(),
    };
    Ok([report_of(misfit_initial), report_of(misfit)])
}

/// What `rfm update --json` prints and `results.json` holds for `outcome`
/// (finished by [`finish_update`]) of `study`.
pub fn update_json(study: &Study, outcome: &UpdateOutcome) -> Result<String> {
    json_of(outcome, &misfits(study, outcome)?)
}

fn json_of(outcome: &UpdateOutcome, misfits: &[MisfitReport; 2]) -> Result<String> {
    let doc = UpdateJson { misfit_initial: misfits[0], misfit: misfits[1], outcome };
    Ok(serde_json::to_string_pretty(&doc)?)
}

/// Writes the outputs of `rfm update --out` and commits them; returns the
/// paths of `results.json`, `updated.toml` and `report.html`.
#[allow(clippy::too_many_arguments)]
fn write_update(
    study: &Study,
    outcome: &UpdateOutcome,
    step: &fe_model::HistoryEntry,
    misfits: &[MisfitReport; 2],
    mut output: Outputs,
    case: &Path,
    report: &crate::report::ReportOptions,
    carried: Option<(&str, &[u8])>,
) -> Result<[PathBuf; 3]> {
    let path = output.write("results.json", json_of(outcome, misfits)?.as_bytes())?;
    let data = match carried {
        Some((name, bytes)) => Some(output.write(name, bytes)?),
        None => None,
    };
    let updated = write_updated_model(study, outcome, step, &mut output, data.as_deref())?;
    let report = crate::report::update_report::write(
        study,
        outcome,
        step,
        misfits,
        &mut output,
        case,
        &report.for_case(study.case()),
    )?;
    output.commit()?;
    Ok([path, updated, report])
}

/// Writes what `rfm update --out DIR` writes for `outcome` (finished by
/// [`finish_update`], which gave `step`) into `dir`, all or nothing:
/// `results.json`, `updated.toml`, `report.html` and the figures. `case`
/// is the case file's path as the report names it. A folder another
/// command wrote is refused, as `rfm update` without `--replace` refuses it.
/// `carried`: the study's data file when `updated.toml` must not name it,
/// because it lives no longer than the caller (FRFs given in memory to the
/// Python package, written to a temporary file): it is copied into the
/// folder (`measured.uff` or `measured.csv`, as its extension) and the
/// updated case reads the copy.
pub fn save_update(
    study: &Study,
    outcome: &UpdateOutcome,
    step: &fe_model::HistoryEntry,
    case: &Path,
    (dir, carried): (&Path, Option<&Path>),
    report: &crate::report::ReportOptions,
) -> Result<[PathBuf; 3]> {
    let carried = carried.map(super::fix::carried_data).transpose()?;
    let mut known: Vec<&str> = UPDATE_OUTPUTS.to_vec();
    known.extend(carried.iter().map(|(name, _)| name.as_str()));
    let output = Outputs::folder(dir, &study.case().inputs(), &known)?.of_command("update", false)?;
    let carried = carried.as_ref().map(|(name, bytes)| (name.as_str(), bytes.as_slice()));
    write_update(study, outcome, step, &misfits(study, outcome)?, output, case, report, carried)
}

/// What `--json` prints and `results.json` holds: the library's outcome
/// with the initial and the updated model's misfits over the diagnosis's
/// lines (the numbers the case's history and `rfm diagnose` give).
#[derive(serde::Serialize)]
struct UpdateJson<'a> {
    /// The initial model's misfit and the noise.
    misfit_initial: MisfitReport,
    /// The updated model's misfit and the noise.
    misfit: MisfitReport,
    #[serde(flatten)]
    outcome: &'a UpdateOutcome,
}

/// What the method minimises, as the iteration table names it: the
/// output-error fit's residual is the misfit at the fitted lines, the
/// RFM's a relative residual of its own.
fn residual_name(method: Method) -> &'static str {
    match method {
        Method::Rfm => "RFM residual",
        Method::OutputError => "fit residual",
    }
}

/// Writes the case with the updated values as `DIR/updated.toml`.
fn write_updated_model(
    study: &Study,
    outcome: &UpdateOutcome,
    step: &fe_model::HistoryEntry,
    output: &mut Outputs,
    data: Option<&Path>,
) -> Result<std::path::PathBuf> {
    let mut editor = updated_case(study, outcome, step)?;
    if let Some(data) = data {
        editor.use_data(data);
    }
    let text = editor.text_at(&output.path("updated.toml"))?;
    Ok(output.write("updated.toml", text.as_bytes())?)
}

/// The case `rfm update` writes as `updated.toml`: the updated values with
/// a comment on the run, the gains it estimated, and `step` in its history.
pub fn updated_case(
    study: &Study,
    outcome: &UpdateOutcome,
    step: &fe_model::HistoryEntry,
) -> Result<fe_model::case::CaseEditor> {
    let values = rfm_update::params::quantity_values(study.parameters(), outcome.system.model());
    let times = step
        .noise
        .filter(|n| *n > 0.0)
        .map_or(String::new(), |n| format!(", {} x the noise", table::times(quantities::times_noise(step.misfit, n))));
    let mut comment = format!(
        "Updated by rfm ({}, status {}, misfit {}{times}, as the last [[history]] entry records it) from {}",
        outcome.method,
        outcome.status.name(),
        table::misfit(step.misfit),
        study.case().path.display()
    );
    if outcome.worse_than_start {
        comment.push_str(
            "\nWARNING: this update made the misfit WORSE than the initial model's: these values are not an improvement",
        );
    }
    let mut editor = study.case().editor()?;
    editor.set_values(&values, &comment)?;
    if study.gains() != fe_model::case::Gains::None {
        // the next run (diagnose, compare, update) fits the gains too; their values are kept
        let fitted: Vec<fe_model::case::FittedGain> = outcome.gains.iter().map(|g| g.fitted()).collect();
        editor.set_gains(study.gains(), &fitted)?;
    }
    editor.push_history(step)?;
    Ok(editor)
}

/// A band misfit this many times the initial model's is worse than the
/// start: a fit that starts at its optimum (values from `rfm diagnose
/// --apply`) may move the band misfit by far less, its fitted lines not
/// being the band's.
const WORSE_BY: f64 = 1.01;

/// Lines of the misfit in the case history (as in `rfm diagnose`).
const HISTORY_LINES: usize = quantities::MISFIT_LINES;

/// The misfit after each step of a case's history, and as a multiple of
/// the noise.
fn print_history(history: &[fe_model::HistoryEntry]) -> Result<()> {
    if history.is_empty() {
        return Ok(());
    }
    let mut t = Table::new(&["step", "misfit", "x noise"]);
    for h in history {
        let times = h
            .noise
            .filter(|&n| n > 0.0)
            .map_or("-".to_string(), |n| table::times(quantities::times_noise(h.misfit, n)));
        t.row(vec![h.step.clone(), table::misfit(h.misfit), times]);
    }
    outln!("{}\n", t.render());
    Ok(())
}

/// The noise level the residual is compared with, and when the fit weights
/// its lines, how it relates to the data's own.
fn noise_level(outcome: &UpdateOutcome, noise: f64) -> String {
    match outcome.noise_estimate {
        Some(plain) if plain != noise => format!(
            "{} under the fit's {} weights, as its residual is (the data's, unweighted: {})",
            table::misfit(noise),
            if outcome.coherence_weighted { "coherence" } else { "line" },
            table::misfit(plain)
        ),
        _ => format!("estimated from the data {}", table::misfit(noise)),
    }
}

fn print_outcome(outcome: &UpdateOutcome, method: Method, misfits: &[MisfitReport; 2]) -> Result<()> {
    let status = outcome.status.name();
    let first = outcome.history.first().map_or(f64::NAN, |r| r.residual);
    outln!(
        "{status} after {} iterations; {} {} -> {} on the {} fitted lines",
        outcome.history.len().saturating_sub(1),
        residual_name(method),
        table::misfit(first),
        table::misfit(outcome.residual),
        outcome.frequencies_hz.len()
    );
    let [before, after] = misfits;
    let times = match (before.times_noise, after.times_noise, after.noise) {
        (Some(a), Some(b), Some(n)) => {
            format!(" ({} -> {} x the noise, {})", table::times(a), table::times(b), table::misfit(n))
        }
        _ => String::new(),
    };
    outln!(
        "misfit {} -> {}{times}, over the {} lines the diagnosis reads\n",
        table::misfit(before.misfit),
        table::misfit(after.misfit),
        after.lines
    );
    outln!("{}: {}\n", outcome.status.name(), outcome.status.meaning());
    let unc = outcome.uncertainty.as_ref();
    let has_truth = outcome.parameters.iter().any(|p| p.truth.is_some());
    let has_paper = outcome.parameters.iter().any(|p| p.paper.is_some());
    let mut header = vec!["parameter", "unit", "initial", "updated"];
    if unc.is_some() {
        header.extend(["+-1 sd", "95 % interval"]);
    }
    if has_truth {
        header.extend(["truth", "error"]);
        if unc.is_some() {
            header.push("error/sd");
        }
    }
    if has_paper {
        header.push("paper");
    }
    header.push("");
    let mut t = Table::new(&header);
    for (i, p) in outcome.parameters.iter().enumerate() {
        let u = unc.map(|u| &u.parameters[i]);
        let unit = crate::report::units::parameter_unit(&p.name);
        let mut row = vec![p.name.clone(), unit.to_string(), num(p.initial), num(p.updated)];
        if let Some(u) = u {
            if u.relative_std > 10.0 {
                row.push("unbounded".into());
                row.push("-".into());
            } else {
                row.push(num(u.std));
                row.push(format!("{} .. {}", num(u.interval95.0), num(u.interval95.1)));
            }
        }
        if has_truth {
            row.push(p.truth.map(num).unwrap_or_default());
            row.push(p.relative_error().map(|e| format!("{e:.1e}")).unwrap_or_default());
            if let Some(u) = u {
                // in log space, consistent with the asymmetric interval
                let z = p.truth.map(|t| (p.updated / t).ln().abs() / u.relative_std.max(1e-300));
                row.push(z.map(|z| format!("{z:.2}")).unwrap_or_default());
            }
        }
        if has_paper {
            row.push(p.paper.map(num).unwrap_or_default());
        }
        row.push(if u.is_some_and(|u| !u.well_determined) { "weakly determined".into() } else { String::new() });
        t.row(row);
    }
    outln!("{}", t.render());
    if let Some(u) = unc {
        outln!("standard deviations {}", u.shown_first);
        if u.inflation > 1.0 {
            let noise_only: Vec<String> = outcome
                .parameters
                .iter()
                .zip(&u.parameters)
                .map(|(p, q)| format!("{} {}", p.name, num(q.std_noise)))
                .collect();
            outln!("noise-only standard deviations (too small here): {}", noise_only.join(", "));
        }
        let notes: Vec<String> = u
            .parameters
            .iter()
            .flat_map(|p| p.warnings.iter().map(move |w| format!("{}: {w}", p.name)))
            .chain(u.warnings.iter().cloned())
            .collect();
        if !notes.is_empty() {
            outln!("\nwhat the data determine only weakly:");
            for n in notes {
                outln!("  - {n}");
            }
        }
    }
    if unc.is_none() {
        outln!(
            "\nno uncertainty is available for these values: the RFM's equation error has no noise model \
             (--method output-error gives standard deviations)"
        );
    }
    if let (Some(noise), Some(ratio)) = (outcome.residual_noise, outcome.noise_ratio) {
        let times = table::times(ratio);
        let reading = match outcome.status {
            _ if ratio <= rfm_update::verdict::NOISE_FACTOR => {
                format!("the fit residual is {times} times it: the model explains the data down to their noise")
            }
            Status::ModelInadequate => format!(
                "the fit residual is {times} times it at a minimum its restarts confirm: something the parameters cannot represent remains (try rfm diagnose on the updated case)"
            ),
            _ => format!(
                "the fit residual is {times} times it; it is not known to be the best fit ({})",
                outcome.status.name()
            ),
        };
        outln!("\nnoise level {}: {reading}", noise_level(outcome, noise));
    }
    if !outcome.restarts.is_empty() {
        let ends: Vec<String> = outcome.restarts.iter().map(|r| table::misfit(r.residual)).collect();
        outln!(
            "restarts from {} spread starts (residual RMS where they ended: {})",
            outcome.restarts.len(),
            ends.join(", ")
        );
    }
    if !outcome.warnings.is_empty() {
        outln!("\nwhat the data determine only weakly, and what not to trust:");
        for w in &outcome.warnings {
            outln!("  - {w}");
        }
    }
    for g in crate::report::gain_reports(&outcome.gains) {
        outln!("fitted gain (per {}): {}", outcome.gains[0].key.noun(), crate::report::gain_text(&g));
    }
    let nf = &outcome.natural_frequencies_hz;
    if nf.kind == "none" {
        outln!(
            "\nnatural frequencies: not computed ({} equations, above the {} the dense modal analyses take)",
            outcome.system.n(),
            rfm_update::study::MAX_UNDAMPED_DOFS
        );
        return Ok(());
    }
    let (header, rows) = crate::report::update_report::frequency_rows(nf);
    let mut t = Table::new(&header);
    for row in rows {
        t.row(row);
    }
    outln!("\n{} natural frequencies in the measured band\n{}", nf.kind, t.render());
    Ok(())
}
