//! `rfm fix`: diagnose, add the recommended effect, update, and again,
//! until nothing significant remains; the case after every step, and a
//! report whose headline is the misfit after each step.
//!
//! Each step's case is committed into the output folder as soon as the
//! step is done ([`Outputs::checkpoint`]), with `fix-progress.json`: an
//! interrupted run leaves the steps it finished, and `--resume` goes on
//! from the last of them.

use std::path::{Path, PathBuf};

use rfm_update::Study;
use rfm_update::fix::{CONSISTENT, FixOptions, FixOutcome, FixProgress, FixStop, fix as run_fix};
use rfm_update::quantities;
use serde::{Deserialize, Serialize};

use super::{Result, print_masked, print_notes};
use crate::exit::{Exit, Failure};
use crate::output::Outputs;
use crate::report::fix_report::{Resumed, step_file};
use crate::table::{self, Table, num};

/// The data a case synthesised from its `[truth]`, written beside the steps.
const DATA_FILE: &str = "measured.csv";

/// What a run that has not finished has done so far, beside its steps.
const PROGRESS_FILE: &str = "fix-progress.json";

/// Options of the fix command.
pub(crate) struct FixArgs<'a> {
    pub(crate) case: &'a Path,
    pub(crate) out: &'a Path,
    pub(crate) steps: usize,
    pub(crate) json: bool,
    /// Replace a folder another command wrote.
    pub(crate) replace: bool,
    /// Go on from the steps an interrupted run left in `out`.
    pub(crate) resume: bool,
    pub(crate) report: crate::report::ReportOptions,
}

/// `fix-progress.json`: the case the run started from and the steps it
/// has finished, so that `--resume` can check it goes on with the same case
/// and knows where to start.
#[derive(Serialize, Deserialize)]
struct Progress {
    /// The case file as given.
    case: String,
    /// Its text when the run started: a resumed run refuses a changed case.
    case_text: String,
    /// The step files finished, in order.
    steps: Vec<String>,
}

/// Where a run starts: the case's own, or the last step an interrupted run
/// left (`--resume`).
struct Start {
    /// The study of the case the loop starts from.
    study: Study,
    /// Steps finished by earlier runs into the folder.
    done: usize,
    /// Their files' text, to be kept in the new outputs.
    carried: Vec<(String, Vec<u8>)>,
}

fn start(args: &FixArgs<'_>, case_text: &str) -> Result<Start> {
    if !args.resume {
        return Ok(Start { study: super::load_study(args.case)?, done: 0, carried: Vec::new() });
    }
    let path = args.out.join(PROGRESS_FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Failure::new(
            Exit::Usage,
            format!(
                "{}: nothing to resume ({e}): an interrupted rfm fix leaves it beside its steps; run without --resume",
                path.display()
            ),
        )
    })?;
    let progress: Progress =
        serde_json::from_str(&text).map_err(|e| format!("{}: not a progress file of rfm fix: {e}", path.display()))?;
    if progress.case_text != case_text {
        return Err(Failure::new(
            Exit::Usage,
            format!(
                "{}: the run it records started from {} as it was then, and {} has changed since; run without \
                 --resume to start again",
                path.display(),
                progress.case,
                args.case.display()
            ),
        ));
    }
    let Some(last) = progress.steps.last() else {
        return Err(Failure::new(
            Exit::Usage,
            format!("{}: no step finished yet; run without --resume", path.display()),
        ));
    };
    if progress.steps.len() >= args.steps {
        return Err(Failure::new(
            Exit::Usage,
            format!(
                "{} holds {} finished steps, as many as --steps {} asks for; give more steps to go on",
                args.out.display(),
                progress.steps.len(),
                args.steps
            ),
        ));
    }
    let mut carried = Vec::new();
    for name in progress.steps.iter().map(String::as_str).chain([DATA_FILE]) {
        match std::fs::read(args.out.join(name)) {
            Ok(bytes) => carried.push((name.to_string(), bytes)),
            Err(_) if name == DATA_FILE => {}
            Err(e) => return Err(format!("{}: {e}", args.out.join(name).display()).into()),
        }
    }
    Ok(Start { study: super::load_study(&args.out.join(last))?, done: progress.steps.len(), carried })
}

pub(crate) fn fix(args: &FixArgs<'_>) -> Result<Exit> {
    let case_text = std::fs::read_to_string(args.case).unwrap_or_default();
    let Start { study, done, carried } = start(args, &case_text)?;
    // the data every written case reads: the case's own file, or the data
    // synthesised from its [truth], written once beside the steps
    let synthesised = study.case().measurement.as_ref().and_then(|m| m.data.as_ref()).is_none();
    // one more than the steps: the loop may end by replacing an early effect
    let mut names: Vec<String> = (done + 1..=args.steps + 1).map(step_file).collect();
    names.extend(["results.json", "report.html"].map(String::from));
    if synthesised {
        names.push(DATA_FILE.into());
    }
    let known: Vec<&str> = names.iter().map(String::as_str).collect();
    // the inputs of a resumed run (its last step's case and data) are files
    // of the folder, staged again below rather than replaced: the case's own
    // inputs are the ones to protect
    let inputs: Vec<PathBuf> = super::load_case(args.case)?.inputs();
    let mut output = Outputs::folder(args.out, &inputs, &known)?.of_command("fix", args.replace || args.resume)?;
    for (name, bytes) in &carried {
        output.write(name, bytes)?;
    }
    print_notes(study.notes(), args.json)?;
    print_masked(&rfm_update::study::describe_masked(study.masked()), args.json)?;
    if !args.json {
        outln!("{}", study.case().model.title);
        if done > 0 {
            outln!("resuming after step {done} of the run in {}", args.out.display());
        }
        outln!(
            "closing the loop on {} channels x {} lines ({} to {} Hz), at most {} steps",
            study.measured().channels().len(),
            study.measured().n_freq(),
            num(study.measured().frequencies_hz()[0]),
            num(*study.measured().frequencies_hz().last().expect("lines")),
            args.steps - done
        );
    }
    let opts = FixOptions {
        max_steps: args.steps - done,
        diagnose: study.diagnose_options(study.measured())?,
        data: synthesised.then(|| output.path(DATA_FILE)),
        ..FixOptions::default()
    };
    let data_file = synthesised.then(|| output.path(DATA_FILE));
    if synthesised {
        output.write(DATA_FILE, frf::io::csv::to_csv_string(study.measured()).as_bytes())?;
    }
    let json = args.json;
    let mut finished: Vec<String> = carried.iter().filter(|(n, _)| n != DATA_FILE).map(|(n, _)| n.clone()).collect();
    // the first failure to keep a step; the loop goes on, and it is
    // reported when the loop ends
    let mut kept: std::result::Result<(), Failure> = Ok(());
    let outcome = run_fix(study.case(), study.measured(), &opts, |p| {
        let line = match p {
            FixProgress::Diagnosed { step, diagnosis } => match diagnosis.leader() {
                Some(l) => format!(
                    "diagnosis {}: {} stands out (dBIC {})",
                    done + step + 1,
                    l.description,
                    table::dbic(l.delta_bic)
                ),
                None if diagnosis.consistent() => format!("diagnosis {}: nothing significant", done + step + 1),
                None => format!("diagnosis {}: significant effects, none at plausible values", done + step + 1),
            },
            FixProgress::LookedAhead { ahead, .. } => match (&ahead.failed, &ahead.with) {
                (Some(why), _) => format!("  looking one step ahead from {}: could not add it ({why})", ahead.effect),
                (None, Some(with)) => format!(
                    "  the best pair fitted together: {} with {with}: misfit {}",
                    ahead.effect,
                    table::misfit(ahead.misfit_ahead)
                ),
                (None, None) => format!(
                    "  looking one step ahead from {}: misfit {} after it and its best follower",
                    ahead.effect,
                    table::misfit(ahead.misfit_ahead)
                ),
            },
            FixProgress::Updated { step, effect, removed, misfit, status } => {
                let verb = if removed { "took out" } else { "added" };
                format!(
                    "step {}: {verb} {effect} and updated ({}); misfit {}",
                    done + step + 1,
                    status.name(),
                    table::misfit(misfit)
                )
            }
            FixProgress::StepDone { index, done: step } => {
                if kept.is_ok() {
                    let name = step_file(done + index + 1);
                    kept = keep_step(&mut output, &name, step, data_file.as_deref(), &mut finished, args, &case_text);
                }
                return;
            }
        };
        if !json {
            // an error here would be the same as at the next print, which reports it
            let _ = crate::print_line(format_args!("{line}"));
        }
    })?;
    kept?;
    if json {
        outln!("{}", serde_json::to_string_pretty(&outcome)?);
    } else {
        print_outcome(&outcome, done)?;
    }

    for (k, s) in outcome.steps.iter().enumerate() {
        let name = step_file(done + k + 1);
        output.write(&name, step_text(s, &output.path(&name), data_file.as_deref())?.as_bytes())?;
    }
    output.write("results.json", serde_json::to_string_pretty(&outcome)?.as_bytes())?;
    // a finished run leaves nothing to resume
    output.forget(PROGRESS_FILE)?;
    let resumed = Resumed { steps: done, history: if done > 0 { study.case().history.clone() } else { Vec::new() } };
    crate::report::fix_report::write(&study, &outcome, &resumed, &args.report.for_case(study.case()), &mut output)?;
    let written = output.commit()?;
    if !json {
        outln!("\nwrote {} files into {}", written.len(), args.out.display());
        if let Some(last) = (done + outcome.steps.len()).checked_sub(1) {
            outln!("the fixed model: {}", args.out.join(step_file(last + 1)).display());
        }
    }
    // success only when the loop ended with the data explained down to their noise
    let explained = outcome.stop == FixStop::NothingSignificant && outcome.final_misfit() <= CONSISTENT * outcome.noise;
    Ok(if explained { Exit::Success } else { Exit::NotConverged })
}

/// The text of a step's case written at `path`, reading the data written
/// beside it when the first case synthesised them.
fn step_text(step: &rfm_update::fix::FixStep, path: &Path, data: Option<&Path>) -> Result<String> {
    let mut editor = step.case.clone();
    if let Some(data) = data {
        editor.use_data(data);
    }
    Ok(editor.text_at(path)?)
}

/// Commits a finished step's case into the output folder at once, with the
/// progress so far, so that an interrupted run keeps it.
fn keep_step(
    output: &mut Outputs,
    name: &str,
    step: &rfm_update::fix::FixStep,
    data: Option<&Path>,
    finished: &mut Vec<String>,
    args: &FixArgs<'_>,
    case_text: &str,
) -> std::result::Result<(), Failure> {
    output.write(name, step_text(step, &output.path(name), data)?.as_bytes())?;
    finished.push(name.to_string());
    let progress =
        Progress { case: args.case.display().to_string(), case_text: case_text.to_string(), steps: finished.clone() };
    output.write(PROGRESS_FILE, serde_json::to_string_pretty(&progress)?.as_bytes())?;
    output.checkpoint()?;
    crate::output::note_checkpoint(format!(
        "the {} finished step(s) are in {} (rfm fix ... --resume goes on from them)",
        finished.len(),
        args.out.display()
    ));
    Ok(())
}

fn print_outcome(o: &FixOutcome, done: usize) -> Result<()> {
    outln!(
        "\nthe misfit after each step (RMS of |ln(model/measured)| per complex value, over the {} lines the diagnosis reads):",
        quantities::MISFIT_LINES
    );
    let mut t = Table::new(&["step", "misfit", "x noise"]);
    for (label, m) in o.stages() {
        let label = if done == 0 { label } else { renumbered(&label, done) };
        t.row(vec![label, table::misfit(m), table::times(quantities::times_noise(m, o.noise))]);
    }
    outln!("{}", t.render());
    outln!("noise level estimated from the data: {}", table::misfit(o.noise));
    outln!("\nstopped: {}", o.stop.describe());
    let last = o.final_misfit();
    let times = table::times(quantities::times_noise(last, o.noise));
    if last <= CONSISTENT * o.noise {
        outln!("the final misfit is {times} times the noise: the model explains the data down to their noise");
    } else {
        outln!("the final misfit is {times} times the noise: something the candidates cannot represent remains");
    }
    if let Some(s) = o.steps.last() {
        // the standard deviation shown is the one that includes model error
        // (the residual beyond the noise), which equals the noise's alone when
        // the fit reaches the noise
        let inflated = s.uncertainty.as_ref().is_some_and(|u| u.inflation > 1.0);
        outln!(
            "\nparameters after the last update (relative standard deviation{}):",
            if inflated { ", widened for the misfit beyond the noise" } else { " from the noise" }
        );
        let mut t = Table::new(&["parameter", "unit", "value", "+-1 sd"]);
        for (i, p) in s.parameters.iter().enumerate() {
            let sd = s
                .uncertainty
                .as_ref()
                .and_then(|u| u.parameters.get(i))
                .map_or("-".to_string(), |u| crate::table::percent(u.relative_std));
            let unit = crate::report::units::parameter_unit(&p.name);
            t.row(vec![p.name.clone(), unit.to_string(), num(p.updated), sd]);
        }
        outln!("{}", t.render());
        // the data's level: every misfit above is after the gains that fit the model best
        for g in crate::report::gain_reports(&s.effect.gains) {
            outln!("gain fitted with the last effect: {}", crate::report::gain_text(&g));
        }
    }
    if let Some(e) = &o.diagnosis_error {
        outln!("\nthe diagnosis of the final model failed, so what remains is not known: {e}");
    } else if o.significant_remains
        && let Some(r) = o.remaining.first()
    {
        outln!("\nstill significant in the last diagnosis: {} (dBIC {})", r.description, table::dbic(r.delta_bic));
    }
    Ok(())
}

/// A stage label of a resumed run with its step number counted from the
/// first run's start: `updated after step 1` after 2 earlier steps reads
/// `updated after step 3`.
fn renumbered(label: &str, done: usize) -> String {
    match label.strip_prefix("updated after step ").and_then(|n| n.parse::<usize>().ok()) {
        Some(n) => format!("updated after step {}", n + done),
        None if label == "nominal" => format!("after step {done} (where this run resumed)"),
        None => label.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resumed_runs_stages_count_from_the_first_runs_start() {
        assert_eq!(renumbered("updated after step 1", 2), "updated after step 3");
        assert_eq!(renumbered("nominal", 2), "after step 2 (where this run resumed)");
        assert_eq!(renumbered("+ lumped mass at node 9", 2), "+ lumped mass at node 9");
    }

    /// The progress file is read back as written.
    #[test]
    fn progress_round_trips() {
        let p = Progress { case: "a.toml".into(), case_text: "x = 1\n".into(), steps: vec!["step-1.toml".into()] };
        let back: Progress = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!((back.case, back.case_text, back.steps), (p.case, p.case_text, p.steps));
    }
}
