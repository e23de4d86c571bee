//! `rfm fix`: diagnose, add the recommended effect, update, and again,
//! until nothing significant remains; the case after every step, and a
//! report whose headline is the misfit after each step.
//!
//! Each step's case is committed into the output folder as soon as the
//! step is done ([`Outputs::checkpoint`]), with `fix-progress.json`: an
//! interrupted run leaves the steps it finished, and `--resume` goes on
//! from the last of them.

use std::path::{Path, PathBuf};

use fe_model::case::CaseEditor;
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
pub struct FixArgs<'a> {
    /// The case file.
    pub case: &'a Path,
    /// The output folder.
    pub out: &'a Path,
    /// Measured data to use instead of the case's (`--measured`).
    pub measured: Option<&'a Path>,
    /// Most effects to add.
    pub steps: usize,
    /// Print JSON instead of tables.
    pub json: bool,
    /// Replace a folder another command wrote.
    pub replace: bool,
    /// Go on from the steps an interrupted run left in `out`.
    pub resume: bool,
    /// How the report draws.
    pub report: crate::report::ReportOptions,
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
    /// The step files finished, in order (`step-0.toml` first when the
    /// case's own parameters were updated).
    steps: Vec<String>,
}

impl Progress {
    /// The effects added by the finished steps (step 0 adds none).
    fn effects_done(&self) -> usize {
        self.steps.iter().filter(|s| **s != step_file(0)).count()
    }
}

/// Where a run starts: the case's own, or the last step an interrupted run
/// left (`--resume`).
struct Start {
    /// The study of the case the loop starts from.
    study: Study,
    /// Effects added by the steps earlier runs finished into the folder.
    done: usize,
    /// The files of those steps (and their data), to be kept in the new
    /// outputs.
    carried: Vec<(String, Vec<u8>)>,
}

fn start(args: &FixArgs<'_>, case_text: &str) -> Result<Start> {
    if !args.resume {
        return Ok(Start {
            study: super::load_study_measured(args.case, args.measured)?,
            done: 0,
            carried: Vec::new(),
        });
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
    let done = progress.effects_done();
    if done >= args.steps {
        return Err(Failure::new(
            Exit::Usage,
            format!(
                "{} holds {done} finished steps, as many as --steps {} asks for; give more steps to go on",
                args.out.display(),
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
    let study = super::load_study(&args.out.join(last))?;
    // the steps read the data the run started with; other data given now
    // would go on from fits made to those
    if let Some(given) = args.measured {
        let read = study.case().measurement.as_ref().and_then(|m| m.data.as_deref());
        // one file by device and inode, as the outputs are told from the inputs
        let same = |a: &Path, b: &Path| frf::io::FileId::of(a).is_some_and(|a| Some(a) == frf::io::FileId::of(b));
        if !read.is_some_and(|r| same(r, given)) {
            return Err(Failure::new(
                Exit::Usage,
                format!(
                    "--measured {}: the steps in {} were fitted to {}; resume with those data, or run without \
                     --resume to start again",
                    given.display(),
                    args.out.display(),
                    read.map_or("the case's truth".into(), |r| r.display().to_string())
                ),
            ));
        }
    }
    Ok(Start { study, done, carried })
}

/// Whether the study's data are synthesised from its case's `[truth]`:
/// then `rfm fix` writes them once beside the steps, which read them there.
fn synthesises(study: &Study) -> bool {
    study.case().measurement.as_ref().and_then(|m| m.data.as_ref()).is_none()
}

/// Opens the outputs of `rfm fix` in `dir` for `steps` steps at most, and
/// the files `more`, protecting `inputs`; a folder another command wrote is
/// refused unless `replace`.
fn fix_outputs(
    inputs: &[PathBuf],
    synthesised: bool,
    steps: usize,
    dir: &Path,
    replace: bool,
    more: &[&str],
) -> Result<Outputs> {
    // step 0 and one more than the steps: the loop may end by replacing an early effect
    let mut names: Vec<String> = (0..=steps + 1).map(step_file).collect();
    names.extend(["results.json", "report.html"].map(String::from));
    if synthesised {
        names.push(DATA_FILE.into());
    }
    names.extend(more.iter().map(|n| n.to_string()));
    let known: Vec<&str> = names.iter().map(String::as_str).collect();
    Ok(Outputs::folder(dir, inputs, &known)?.of_command("fix", replace)?)
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
/// cases of the steps, the results and the report; each step's case is
/// kept in the folder as soon as the step is done.
pub fn fix(args: &FixArgs<'_>) -> Result<Exit> {
    let case_text = std::fs::read_to_string(args.case).unwrap_or_default();
    let Start { study, done, carried } = start(args, &case_text)?;
    let synthesised = synthesises(&study);
    // the inputs of a resumed run (its last step's case and data) are files
    // of the folder, staged again below rather than replaced: the case's own
    // inputs are the ones to protect
    let inputs: Vec<PathBuf> = super::load_case(args.case)?.inputs();
    let mut output = fix_outputs(&inputs, synthesised, args.steps, args.out, args.replace || args.resume, &[])?;
    for (name, bytes) in &carried {
        output.write(name, bytes)?;
    }
    print_notes(study.notes(), args.json)?;
    print_masked(&rfm_update::study::describe_masked(study.masked()), args.json)?;
    if !args.json {
        outln!("{}", study.case().model.title);
        if !carried.is_empty() {
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
    let opts = fix_options(&study, args.steps - done, output.path(DATA_FILE))?;
    let data_file = opts.data.clone();
    if synthesised {
        output.write(DATA_FILE, frf::io::csv::to_csv_string(study.measured()).as_bytes())?;
    }
    let json = args.json;
    let mut finished: Vec<String> = carried.iter().filter(|(n, _)| n != DATA_FILE).map(|(n, _)| n.clone()).collect();
    let resumed = !carried.is_empty();
    // the first failure to keep a step; the loop goes on, and it is
    // reported when the loop ends
    let mut kept: std::result::Result<(), Failure> = Ok(());
    let outcome = run_fix(study.case(), study.measured(), &opts, |p| {
        // a resumed run's step 0 updates the last kept step's parameters
        // again; its case stays the earlier run's step 0
        let keep = match &p {
            FixProgress::Declared { step } if !resumed => Some((step_file(0), &step.case)),
            FixProgress::StepDone { index, done: step } => Some((step_file(done + index + 1), &step.case)),
            _ => None,
        };
        if let Some((name, case)) = keep
            && kept.is_ok()
        {
            kept = keep_step(&mut output, &name, case, data_file.as_deref(), &mut finished, args, &case_text);
        }
        if json {
            return;
        }
        for line in progress_lines_after(&p, done) {
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
    let resumed = Resumed {
        earlier: resumed,
        steps: done,
        history: if resumed { study.case().history.clone() } else { Vec::new() },
    };
    write_fix(&study, &outcome, &resumed, &args.report, &mut output, None)?;
    // a finished run leaves nothing to resume
    output.forget(PROGRESS_FILE)?;
    let written = output.commit()?;
    if !json {
        outln!("\nwrote {} files into {}", written.len(), args.out.display());
        let last = done + outcome.steps.len();
        if last > 0 || outcome.declared.is_some() {
            outln!("the fixed model: {}", args.out.join(step_file(last)).display());
        }
    }
    let exit = fix_exit(&outcome);
    if exit != Exit::Success {
        eprintln!("exit code {}: {}", exit.code(), exit.meaning());
    }
    Ok(exit)
}

/// The text of a step's case written at `path`, reading the data written
/// beside it when the first case synthesised them.
fn step_text(case: &CaseEditor, path: &Path, data: Option<&Path>) -> Result<String> {
    let mut editor = case.clone();
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
    case: &CaseEditor,
    data: Option<&Path>,
    finished: &mut Vec<String>,
    args: &FixArgs<'_>,
    case_text: &str,
) -> std::result::Result<(), Failure> {
    output.write(name, step_text(case, &output.path(name), data)?.as_bytes())?;
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

/// What `rfm fix` prints as the loop goes, one line each (the Python
/// package's progress says the same).
pub fn progress_lines(p: &FixProgress<'_>) -> Vec<String> {
    progress_lines_after(p, 0)
}

/// [`progress_lines`] of a run that resumed after `done` steps of an
/// earlier one: its steps and diagnoses are numbered from the first run's
/// start.
fn progress_lines_after(p: &FixProgress<'_>, done: usize) -> Vec<String> {
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
            "{} ({}); misfit {} -> {}, dBIC {}",
            if done == 0 {
                "step 0: updated the case's own parameters"
            } else {
                "updated every parameter of the steps before again (where this run resumed)"
            },
            step.status.name(),
            table::misfit(step.misfit_before),
            table::misfit(step.misfit_updated),
            table::dbic(step.delta_bic)
        )],
        FixProgress::Diagnosed { step, diagnosis } => vec![match diagnosis.leader() {
            Some(l) => format!(
                "diagnosis {}: {} stands out (dBIC {})",
                done + step + 1,
                l.description,
                table::dbic(l.delta_bic)
            ),
            None if diagnosis.consistent() => format!("diagnosis {}: nothing significant", done + step + 1),
            None => format!("diagnosis {}: significant effects, none at plausible values", done + step + 1),
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
                Some(why) => format!("  tried {what}: misfit {}, not kept: {why}", table::misfit(ahead.misfit_ahead)),
                None => format!(
                    "  tried {what}: misfit {}, dBIC {}",
                    table::misfit(ahead.misfit_ahead),
                    table::dbic(ahead.delta_bic)
                ),
            }]
        }
        FixProgress::Updated { step, effect, removed, misfit, status } => {
            let verb = if *removed { "took out" } else { "added" };
            vec![format!(
                "step {}: {verb} {effect} and updated ({}); misfit {}",
                done + step + 1,
                status.name(),
                table::misfit(*misfit)
            )]
        }
        FixProgress::Refitted { step, refit, misfit, status } => vec![format!(
            "  {} was not needed at its own fit (dBIC {} there): {} updated again from where that fit ended ({}); \
             misfit {} -> {}",
            refit.found_by,
            table::dbic(refit.delta_bic_there),
            if *step == 0 { "the case's own parameters".to_string() } else { format!("step {}", done + step) },
            status.name(),
            table::misfit(refit.first_misfit),
            table::misfit(*misfit)
        )],
        FixProgress::Redone { step, effects } => vec![format!(
            "{} undone ({}): chosen on data corrected after it, made again on the corrected data",
            if effects.len() == 1 {
                format!("step {}", done + step + 1)
            } else {
                format!("steps {} to {}", done + step + 1, done + step + effects.len())
            },
            effects.join(", ")
        )],
        // the step was announced by `Updated`; this one is for keeping it
        FixProgress::StepDone { done: step, .. } => match &step.removed_because {
            Some(why) => vec![format!("  taken out: {why}")],
            None => Vec::new(),
        },
    }
}

/// The exit code of `rfm fix`: success only when the loop ended with the
/// data explained down to their noise; a model that stays above it with
/// nothing the evidence singles out (or several effects it cannot tell
/// apart) is inadequate; one that stays above it when the steps asked for
/// are done, or when the model after the last could not be diagnosed, is
/// not converged (the meaning of its code says both).
pub fn fix_exit(outcome: &FixOutcome) -> Exit {
    match outcome.stop {
        _ if outcome.explained() => Exit::Success,
        FixStop::ModelInadequate | FixStop::Ambiguous | FixStop::MeshTooCoarse => Exit::ModelInadequate,
        _ => Exit::NotConverged,
    }
}

/// Writes the outputs of `rfm fix` (not yet committed): the case of every
/// step (step 0's unless the run resumed, numbered after the `resumed`
/// steps), the synthesised data, `results.json` and the report.
fn write_fix(
    study: &Study,
    outcome: &FixOutcome,
    resumed: &Resumed,
    report: &crate::report::ReportOptions,
    output: &mut Outputs,
    carried: Option<(&str, &[u8])>,
) -> Result<()> {
    // the data the steps' cases read from the folder: a copy of a file
    // carried, or those synthesised from the case's `[truth]`
    let csv = (carried.is_none() && synthesises(study)).then(|| frf::io::csv::to_csv_string(study.measured()));
    let data = carried.or(csv.as_deref().map(|c| (DATA_FILE, c.as_bytes())));
    let data_file = data.map(|(name, bytes)| output.write(name, bytes)).transpose()?;
    let declared = outcome.declared.iter().filter(|_| !resumed.earlier);
    let cases = declared
        .map(|d| (0, &d.case))
        .chain(outcome.steps.iter().enumerate().map(|(k, s)| (resumed.steps + k + 1, &s.case)));
    for (k, case) in cases {
        let name = step_file(k);
        output.write(&name, step_text(case, &output.path(&name), data_file.as_deref())?.as_bytes())?;
    }
    output.write("results.json", serde_json::to_string_pretty(&outcome)?.as_bytes())?;
    crate::report::fix_report::write(study, outcome, resumed, &report.for_case(study.case()), output)?;
    Ok(())
}

/// Writes what `rfm fix --out DIR` writes for `outcome` (the loop on
/// `study` with at most `steps` effects) into `dir`, all or nothing: the
/// case after every step (`step-0.toml` for the case's own parameters,
/// `step-1.toml`, ...), `results.json`, `report.html` and the figures, and
/// the data synthesised from the case's `[truth]` (`measured.csv`) where
/// the steps read them; returns the files. A folder another command wrote
/// is refused, as `rfm fix` without `--replace` refuses it. `carried`: the
/// study's data file when the cases must not name it, because it lives no
/// longer than the caller (FRFs given in memory to the Python package,
/// written to a temporary file): it is copied into the folder
/// (`measured.uff` or `measured.csv`, as its extension) and the cases read
/// the copy.
pub fn save_fix(
    study: &Study,
    outcome: &FixOutcome,
    steps: usize,
    (dir, carried): (&Path, Option<&Path>),
    report: &crate::report::ReportOptions,
) -> Result<Vec<PathBuf>> {
    let carried = carried.map(carried_data).transpose()?;
    let names: Vec<&str> = carried.iter().map(|(name, _)| name.as_str()).collect();
    let mut output = fix_outputs(&study.case().inputs(), synthesises(study), steps, dir, false, &names)?;
    let resumed = Resumed { earlier: false, steps: 0, history: Vec::new() };
    let carried = carried.as_ref().map(|(name, bytes)| (name.as_str(), bytes.as_slice()));
    write_fix(study, outcome, &resumed, report, &mut output, carried)?;
    Ok(output.commit()?)
}

/// The name a copy of the data file `file` takes in an output folder
/// (`measured.` and its extension), and its bytes.
pub(crate) fn carried_data(file: &Path) -> Result<(String, Vec<u8>)> {
    let (ext, bytes) = super::carried_file(file)?;
    Ok((format!("measured.{ext}"), bytes))
}

fn print_outcome(o: &FixOutcome, done: usize) -> Result<()> {
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
    outln!(
        "\nthe misfit after each step (RMS of |ln(model/measured)| per complex value, over the {} lines the diagnosis reads):",
        quantities::MISFIT_LINES
    );
    let mut t = Table::new(&["step", "misfit", "x noise", "dBIC of the step"]);
    for ((label, m), bic) in o.stages().into_iter().zip(crate::report::fix_report::stage_dbics(o)) {
        let label = if done == 0 { label } else { crate::report::fix_report::renumbered(&label, done) };
        t.row(vec![label, table::misfit(m), table::times(quantities::times_noise(m, o.noise)), bic]);
    }
    outln!("{}", t.render());
    outln!("noise level estimated from the data: {}", table::misfit(o.noise));
    outln!(
        "(dBIC of the step: the evidence for the model after it over the model before, both updated; below {} it is significant)",
        quantities::SIGNIFICANT_DBIC
    );
    // (when the mesh stopped the loop above the noise, it is in what remains)
    if let Some(line) = crate::report::mesh_sentence(o.mesh.as_ref(), o.noise, crate::report::mesh_reading(o))
        && (o.stop != FixStop::MeshTooCoarse || o.explained())
    {
        outln!("\nnote: {line}");
    }
    outln!("\nstopped: {}", o.stop_reason);
    let last = o.final_misfit();
    let times = table::times(quantities::times_noise(last, o.noise));
    if o.explained() {
        outln!("the final misfit is {times} times the noise: the model explains the data down to their noise");
    } else if last <= CONSISTENT * o.noise {
        outln!("the final misfit is {times} times the noise");
    } else {
        outln!("the final misfit is {times} times the noise; what remains unexplained:");
        for r in &o.remains {
            outln!("  - {r}");
        }
    }
    if !o.equally_good.is_empty() {
        outln!("\neffects at different places that explain the data equally well (the data cannot tell them apart):");
        for a in &o.equally_good {
            outln!("  - {}: misfit {}, dBIC {}", a.effect, table::misfit(a.misfit_ahead), table::dbic(a.delta_bic));
        }
    }
    let last_update = match (o.steps.last(), &o.declared) {
        (Some(s), _) => Some((&s.parameters, &s.uncertainty, s.effect.gains.as_slice())),
        (None, Some(d)) => Some((&d.parameters, &d.uncertainty, &[][..])),
        (None, None) => None,
    };
    if let Some((parameters, uncertainty, gains)) = last_update {
        // the standard deviation shown is the one that includes model error
        // (the residual beyond the noise), which equals the noise's alone when
        // the fit reaches the noise
        let inflated = uncertainty.as_ref().is_some_and(|u| u.inflation > 1.0);
        outln!(
            "\nparameters after the last update (relative standard deviation{}):",
            if inflated { ", widened for the misfit beyond the noise" } else { " from the noise" }
        );
        let mut t = Table::new(&["parameter", "unit", "value", "+-1 sd"]);
        for (i, p) in parameters.iter().enumerate() {
            let sd = uncertainty
                .as_ref()
                .and_then(|u| u.parameters.get(i))
                .map_or("-".to_string(), |u| crate::table::percent(u.relative_std));
            let unit = crate::report::units::parameter_unit(&p.name);
            t.row(vec![p.name.clone(), unit.to_string(), num(p.updated), sd]);
        }
        outln!("{}", t.render());
        // the data's level: every misfit above is after the gains that fit the model best
        for g in crate::report::gain_reports(gains) {
            outln!("gain fitted with the last effect: {}", crate::report::gain_text(&g));
        }
    }
    if let Some(e) = &o.diagnosis_error {
        outln!("\nthe diagnosis of the final model failed, so what remains is not known: {e}");
    } else if o.significant_remains
        && let Some(r) = o.remaining.first()
    {
        let why = if o.stop == FixStop::MeshTooCoarse {
            "; not added: what it fits, the model meshed finer explains without a parameter"
        } else {
            ""
        };
        outln!("\nstill significant in the last diagnosis: {} (dBIC {}){why}", r.description, table::dbic(r.delta_bic));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The progress file is read back as written, and step 0 adds no effect.
    #[test]
    fn progress_round_trips() {
        let p = Progress {
            case: "a.toml".into(),
            case_text: "x = 1\n".into(),
            steps: vec!["step-0.toml".into(), "step-1.toml".into()],
        };
        let back: Progress = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back.effects_done(), 1);
        assert_eq!((back.case, back.case_text, back.steps), (p.case, p.case_text, p.steps));
    }

    /// A step made again on corrected data is announced by its number and
    /// effect, numbered from the first run's start when the run resumed.
    #[test]
    fn an_undone_step_is_named() {
        let one = FixProgress::Redone { step: 1, effects: vec!["lumped mass at node 4".into()] };
        assert_eq!(
            progress_lines_after(&one, 0),
            [
                "step 2 undone (lumped mass at node 4): chosen on data corrected after it, made again on the corrected data"
            ]
        );
        let two = FixProgress::Redone { step: 0, effects: vec!["a".into(), "b".into()] };
        assert!(progress_lines_after(&two, 2)[0].starts_with("steps 3 to 4 undone (a, b): "));
    }
}
