//! `rfm diagnose`: which physical effect is missing from the model.

use std::path::{Path, PathBuf};

use fe_model::CaseFile;
use fe_model::case::Gains;
use frf::FrfSet;
use indicatif::ProgressBar;
use rfm_update::Study;
use rfm_update::diagnose::Diagnosis;
use rfm_update::fix::{CheckedDiagnosis, FixOptions, FixProgress, Prepared, diagnose_prepared};
use rfm_update::study::{describe_masked, read_measured_for};

use super::{Result, WithNotes, print_masked, print_notes};
use crate::exit::Exit;
use crate::output::Outputs;
use crate::table::{Table, num, percent};

/// Options of the diagnose command.
pub struct DiagnoseArgs<'a> {
    /// The case file.
    pub case: &'a Path,
    /// Measured FRFs instead of the case's.
    pub measured: Option<&'a Path>,
    /// Print JSON instead of tables.
    pub json: bool,
    /// Write the case with the effect of this rank added.
    pub apply: Option<usize>,
    /// The new case file of `apply`.
    pub out: Option<&'a Path>,
    /// Rows of the ranking to print.
    pub top: usize,
    /// Print each stage with its time.
    pub verbose: bool,
}

/// `rfm diagnose`: prints the ranking (or `--json`) and with `--apply`
/// writes the case with an effect added.
pub fn diagnose(args: &DiagnoseArgs<'_>) -> Result<Exit> {
    let mut study = Study::load(args.case)?;
    let mut outputs = match (args.apply, args.out) {
        (Some(_), Some(out)) => Some(apply_outputs(&study, args.measured, out)?),
        _ => None,
    };
    let (measured, notes, masked) = diagnosis_data(&mut study, args.measured)?;
    print_notes(&notes, args.json)?;
    print_masked(&masked, args.json)?;
    if !args.json {
        outln!("{}", study.case().model.title);
        outln!(
            "fitting every candidate effect to {} channels x {} lines ({} to {} Hz) ...",
            measured.channels().len(),
            measured.n_freq(),
            num(measured.frequencies_hz()[0]),
            num(*measured.frequencies_hz().last().expect("lines"))
        );
    }
    // a spinner on the terminal (hidden when stderr is not one) says which stage runs
    let bar = if args.json { ProgressBar::hidden() } else { ProgressBar::new_spinner() };
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    let start = std::time::Instant::now();
    let json = args.json;
    let data_file = outputs.as_ref().and_then(|(_, data)| data.as_ref().map(|(_, path)| path.clone()));
    let (prepared, d) = run_diagnosis(
        &study,
        &measured,
        data_file,
        &mut |p| {
            if let FixProgress::Declared { step } = p
                && !json
            {
                let line = format!(
                    "step 0: updated the case's own [update] parameters first ({}); misfit {:.4e} -> {:.4e}",
                    step.status.name(),
                    step.misfit_before,
                    step.misfit_updated
                );
                bar.suspend(|| eprintln!("{line}"));
            }
        },
        |stage| {
            let line = format!("{stage} ({:.2} s)", start.elapsed().as_secs_f64());
            if args.verbose {
                bar.suspend(|| eprintln!("{line}"));
            }
            bar.set_message(line);
        },
    )?;
    bar.finish_and_clear();
    if args.json {
        outln!("{}", diagnosis_json(&notes, &prepared, &d)?);
    } else {
        print_checks(&prepared)?;
        print_diagnosis(&d, args.top)?;
    }
    if let Some(rank) = args.apply {
        let out = args.out.ok_or("--apply needs --out FILE for the new case file")?;
        let outputs = outputs.take().ok_or("--apply needs --out FILE for the new case file")?;
        let data = write_apply(&study, &prepared.case, &d, rank, out, outputs)?;
        if !args.json {
            if let Some(path) = data {
                outln!("\nwrote {} with the data synthesised from the case's [truth]", path.display());
            }
            outln!("\nwrote {} with effect {rank} added", out.display());
        }
    }
    Ok(Exit::Success)
}

/// The diagnosis `rfm diagnose` makes of `study` against `data` (see
/// [`rfm_update::fix::diagnose_prepared`]): the data checked for set-up
/// errors and corrected, the case's own `[update]` parameters updated
/// (step 0), then the model after them diagnosed. `data_file`: where the
/// data of a case that synthesises them from its `[truth]` will be written,
/// so that the corrections found can be written into the case that reads
/// them. `progress` hears of the checks and step 0, `stage` of each stage
/// of the diagnosis.
pub fn run_diagnosis(
    study: &Study,
    data: &FrfSet,
    data_file: Option<PathBuf>,
    progress: &mut impl FnMut(FixProgress<'_>),
    stage: impl FnMut(&str),
) -> Result<(Prepared, Diagnosis)> {
    let opts = FixOptions { diagnose: study.diagnose_options(data)?, data: data_file, ..FixOptions::default() };
    Ok(diagnose_prepared(study.case(), data, &opts, progress, stage)?)
}

/// What `rfm diagnose --json` prints: the notes on reading the data, the
/// findings about them, step 0 and the diagnosis.
pub fn diagnosis_json(notes: &[String], prepared: &Prepared, d: &Diagnosis) -> Result<String> {
    let report = CheckedDiagnosis { findings: &prepared.findings, declared: prepared.declared.as_ref(), diagnosis: d };
    Ok(serde_json::to_string_pretty(&WithNotes { notes, result: &report })?)
}

/// The measured receptances `rfm diagnose` fits: the file `measured` as
/// `--measured` reads it (the study's gains decided again for it), or the
/// study's own data; with the notes on reading them and what the case's
/// mask left out.
pub fn diagnosis_data(study: &mut Study, measured: Option<&Path>) -> Result<(FrfSet, Vec<String>, Vec<String>)> {
    Ok(match measured {
        Some(path) => {
            let read = read_measured_for(study.system(), path, study.case().measurement.as_ref())?;
            study.set_gains_for(&read)?;
            let mut notes = read.notes.clone();
            if study.gains() != Gains::None {
                notes.push(format!(
                    "model FRFs are multiplied by fitted gains ({}): {}",
                    study.gains(),
                    study.gains_reason()
                ));
            }
            (read.set.to_receptance(), notes, describe_masked(&read.masked))
        }
        None => (study.measured().clone(), study.notes().to_vec(), describe_masked(study.masked())),
    })
}

/// The outputs of `--apply` into `out`, opened before the diagnosis: the
/// case, and where the study's data come from its `[truth]` (and not from
/// `measured`), the data beside it.
fn apply_outputs(study: &Study, measured: Option<&Path>, out: &Path) -> Result<(Outputs, Option<(Outputs, PathBuf)>)> {
    let mut inputs = study.case().inputs();
    inputs.extend(measured.map(Path::to_path_buf));
    let output = Outputs::file(out, &inputs)?;
    // A case whose data come from its [truth] cannot keep the truth once an
    // effect is added: a truth that adds the same joint or mass would add
    // it twice. The new case gets the synthesised data beside it instead
    // (as every step of `rfm fix` does), written before the case.
    let synthesised = measured.is_none()
        && study.case().measurement.as_ref().is_some_and(|m| m.data.is_none())
        && study.case().truth.is_some();
    let data = if synthesised {
        let path = data_beside(out);
        Some((Outputs::file(&path, &inputs)?, path))
    } else {
        None
    };
    Ok((output, data))
}

/// Writes the case `base` (the study's case as the diagnosis saw it:
/// corrected, its own parameters updated) with the effect of `rank` added
/// as `out`, and the synthesised data beside it when it needs them;
/// returns their path.
fn write_apply(
    study: &Study,
    base: &CaseFile,
    d: &Diagnosis,
    rank: usize,
    out: &Path,
    (mut output, data_output): (Outputs, Option<(Outputs, PathBuf)>),
) -> Result<Option<PathBuf>> {
    let data = data_output.as_ref().map(|(_, path)| path.clone());
    let editor = d.apply_with_data(base, rank, data.as_deref())?;
    if let Some((mut data, _)) = data_output {
        data.write_file(frf::io::csv::to_csv_string(study.measured()).as_bytes())?;
        data.commit()?;
    }
    let text = editor.text_at(out)?;
    output.write_file(text.as_bytes())?;
    output.commit()?;
    Ok(data)
}

/// Writes what `rfm diagnose --apply RANK --out CASE` writes for the
/// diagnosis `d` of `study` (made from the study's own data when `measured`
/// is `None`, else from that file; `base` the case it was made of, see
/// [`run_diagnosis`]): the case with the effect of rank `rank` added, and
/// when the study's data come from its `[truth]`, those data beside it
/// (`CASE-measured.csv`, whose path is returned), each file all or nothing.
pub fn write_applied(
    study: &Study,
    base: &CaseFile,
    d: &Diagnosis,
    rank: usize,
    measured: Option<&Path>,
    out: &Path,
) -> Result<Option<PathBuf>> {
    let outputs = apply_outputs(study, measured, out)?;
    write_apply(study, base, d, rank, out, outputs)
}

/// `NEW-measured.csv` beside the new case `NEW.toml`.
fn data_beside(case: &Path) -> PathBuf {
    let stem = case.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "case".into());
    case.with_file_name(format!("{stem}-measured.csv"))
}

/// Candidates whose fits failed listed in the text after the ranking; the
/// rest are in `--json`.
const UNFITTED_SHOWN: usize = 5;

/// How many candidates' fits failed, how many of them are left out of the
/// ranking, and the first few with the stage and the reason (nothing when
/// every fit succeeded).
fn unfitted_lines(d: &Diagnosis) -> Vec<String> {
    if d.unfitted.is_empty() {
        return Vec::new();
    }
    let ranked = d.unfitted.iter().filter(|u| u.ranked).count();
    let mut out = vec![format!(
        "{} of {} candidates could not be fitted: {} not ranked, {ranked} ranked by an earlier, shorter fit:",
        d.unfitted.len(),
        d.tried,
        d.unfitted.len() - ranked
    )];
    for u in d.unfitted.iter().take(UNFITTED_SHOWN) {
        let place = if u.ranked { ", ranked as screened only" } else { "" };
        out.push(format!("    {} ({} failed{place}): {}", u.description, u.stage, u.reason));
    }
    if d.unfitted.len() > UNFITTED_SHOWN {
        out.push(format!("    ... ({} more in --json, under `unfitted`)", d.unfitted.len() - UNFITTED_SHOWN));
    }
    out
}

/// What was found about the data and corrected, and step 0, before the ranking.
fn print_checks(p: &Prepared) -> Result<()> {
    if !p.findings.is_empty() {
        outln!("findings about the data (corrected before the diagnosis when a correction is given):");
        for f in &p.findings {
            let fix = if f.corrections.is_empty() { "" } else { " [corrected]" };
            outln!("  - {}{fix}\n    {}", f.summary, f.evidence);
        }
        outln!("");
    }
    if let Some(d) = &p.declared {
        outln!(
            "the case's own [update] parameters were updated first (step 0, {}): misfit {:.2} % -> {:.2} % (RMS relative); \
             the diagnosis below is of the updated model",
            d.status.name(),
            100.0 * d.misfit_before,
            100.0 * d.misfit_updated
        );
        outln!("");
    }
    Ok(())
}

fn print_diagnosis(d: &Diagnosis, top: usize) -> Result<()> {
    outln!(
        "noise level estimated from the data: {:.2} %; nominal model misfit: {:.2} % (RMS relative)",
        100.0 * d.noise,
        100.0 * d.nominal_misfit
    );
    if d.weighted {
        outln!(
            "(both, and every fit, weigh the lines as the update does: by the measured coherence and any band weights)"
        );
    }
    if !d.singular_hz.is_empty() {
        let list = d.singular_hz.iter().map(|f| format!("{f} Hz")).collect::<Vec<_>>().join(", ");
        outln!("left out: {list}, where the model's dynamic stiffness is singular (an undamped mode on the line)");
    }
    outln!("");
    if d.gains != Gains::None {
        let per = if d.gains == Gains::PerChannel { "channel" } else { "reference" };
        outln!("every fit includes an unknown complex gain per {per}; the leader's:");
        if let Some(l) = d.ranking.first() {
            for g in &l.gains {
                outln!(
                    "    {}: x{} ({:+.1} dB), {:+.1} deg",
                    g.key,
                    num(g.magnitude),
                    20.0 * g.magnitude.log10(),
                    g.phase_deg
                );
            }
        }
        outln!("");
    }
    let mut t = Table::new(&["rank", "effect", "explained", "dBIC", "significant", "fitted values", ""]);
    for (i, r) in d.ranking.iter().enumerate().take(top) {
        let values = r
            .parameters
            .iter()
            .map(|p| {
                if p.determined {
                    format!("{} = {} (+-{})", p.name, num(p.value), percent(p.relative_std))
                } else {
                    format!("{} = {} (not determined)", p.name, num(p.value))
                }
            })
            .chain(r.held.iter().map(|h| format!("{h} held (not determined)")))
            .collect::<Vec<_>>()
            .join(", ");
        let full_fit_failed = d.unfitted.iter().any(|u| u.ranked && u.description == r.description);
        let note = match (&r.implausible_reason, r.fully_fitted) {
            (Some(why), _) => format!("implausible: {why}"),
            (None, false) if full_fit_failed => "screened only: its full fit failed".into(),
            (None, false) => "screened only".into(),
            (None, true) => String::new(),
        };
        t.row(vec![
            format!("{}", i + 1),
            r.description.clone(),
            format!("{:.1} %", 100.0 * r.explained),
            format!("{:.1}", r.delta_bic),
            if r.significant { "yes".into() } else { "no".into() },
            values,
            note,
        ]);
    }
    outln!("{}", t.render());
    outln!(
        "\n(dBIC: change of the Bayesian information criterion; below -10 the evidence is very strong; \
         {} candidates tried, {} of them replaced by a variant)",
        d.tried,
        d.superseded
    );
    for line in unfitted_lines(d) {
        outln!("{line}");
    }
    match d.recommended {
        None if d.consistent() => {
            outln!("\nNo candidate explains the misfit beyond the noise: the model is consistent with the data.")
        }
        None => outln!(
            "\nSome effects are significant, but none at plausible values: the missing effect may not be among the candidates."
        ),
        Some(rank) => {
            let leader = &d.ranking[rank - 1];
            outln!("\nMost likely missing (rank {rank}): {}.", leader.description);
            let (text, set) = d.proposal(rank)?;
            outln!("Add it to the case file with these lines:\n");
            for l in text.lines() {
                outln!("    {l}");
            }
            if !set.is_empty() {
                outln!("    [set]    # merge into the case's [set] table");
                for (k, v) in &set {
                    outln!("    \"{k}\" = {v:e}");
                }
            }
            outln!("\nor let rfm write the new case: rfm diagnose CASE --apply {rank} --out NEW.toml");
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use rfm_update::diagnose::{EffectKind, FitStage, Ranked, Unfitted};

    use super::*;
    use crate::commands::WithNotes;

    fn diagnosis(unfitted: Vec<Unfitted>) -> Diagnosis {
        let ranked = Ranked {
            kind: EffectKind::StiffnessChange,
            gains: Vec::new(),
            description: "stiffness change of element 3".into(),
            nodes: Vec::new(),
            elements: vec![3],
            dof: Vec::new(),
            damping: None,
            explained: 0.4,
            misfit: 0.02,
            lines: 60,
            delta_bic: -30.0,
            significant: true,
            plausible: true,
            implausible_reason: None,
            parameters: Vec::new(),
            held: Vec::new(),
            fully_fitted: false,
            candidate: 0,
        };
        Diagnosis {
            noise: 0.01,
            nominal_misfit: 0.1,
            n_residuals: 400,
            ranking: vec![ranked],
            recommended: None,
            tried: 40,
            superseded: 2,
            gains: Gains::None,
            weighted: false,
            unfitted,
            singular_hz: Vec::new(),
            candidates: Vec::new(),
        }
    }

    fn failed(description: &str, stage: FitStage, ranked: bool) -> Unfitted {
        Unfitted { description: description.into(), reason: format!("singular at {description}"), stage, ranked }
    }

    /// The text tells how many fits failed, how many of those are not
    /// ranked, and the first few with stage and reason; the JSON lists all.
    #[test]
    fn failed_fits_are_counted_in_the_text_and_listed_in_the_json() {
        let mut unfitted = vec![failed("stiffness change of element 3", FitStage::FullFit, true)];
        unfitted.extend((1..=6).map(|n| failed(&format!("lumped mass at node {n}"), FitStage::Screening, false)));
        let d = diagnosis(unfitted);
        let text = unfitted_lines(&d);
        assert_eq!(
            text[0],
            "7 of 40 candidates could not be fitted: 6 not ranked, 1 ranked by an earlier, shorter fit:"
        );
        assert_eq!(
            text[1],
            "    stiffness change of element 3 (full fit failed, ranked as screened only): \
             singular at stiffness change of element 3"
        );
        assert_eq!(text[2], "    lumped mass at node 1 (screening failed): singular at lumped mass at node 1");
        assert_eq!(text.len(), 1 + UNFITTED_SHOWN + 1, "{text:#?}");
        assert_eq!(text[UNFITTED_SHOWN + 1], "    ... (2 more in --json, under `unfitted`)");
        assert!(unfitted_lines(&diagnosis(Vec::new())).is_empty());

        let json = serde_json::to_value(WithNotes { notes: &[], result: &d }).unwrap();
        let listed = json["unfitted"].as_array().expect("unfitted in the JSON");
        assert_eq!(listed.len(), 7);
        assert_eq!(
            listed[0],
            serde_json::json!({
                "description": "stiffness change of element 3",
                "reason": "singular at stiffness change of element 3",
                "stage": "full-fit",
                "ranked": true,
            })
        );
        assert_eq!(listed[6]["stage"], "screening");
        assert_eq!((json["tried"].as_u64(), json["superseded"].as_u64()), (Some(40), Some(2)));
    }
}
