//! `rfm diagnose`: which physical effect is missing from the model.

use std::path::{Path, PathBuf};

use fe_model::CaseFile;
use fe_model::case::Gains;
use frf::FrfSet;
use indicatif::ProgressBar;
use rfm_update::Study;
use rfm_update::diagnose::Diagnosis;
use rfm_update::fix::{CheckedDiagnosis, FixOptions, FixProgress, Prepared, diagnose_prepared};
use rfm_update::quantities;
use rfm_update::study::{describe_masked, read_measured_for};

use super::{Result, WithNotes, print_masked, print_notes};
use crate::exit::{Exit, Failure};
use crate::output::Outputs;
use crate::table::{self, Table, num, percent};

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
    /// Folder for the report of the ranking (`--report DIR`).
    pub report: Option<&'a Path>,
    /// Replace a report folder another command wrote.
    pub replace: bool,
    /// How the report draws.
    pub report_options: crate::report::ReportOptions,
}

/// `rfm diagnose`: prints the ranking (or `--json`), with `--apply` writes
/// the case with an effect added, and with `--report` a report of the
/// ranking.
pub fn diagnose(args: &DiagnoseArgs<'_>) -> Result<Exit> {
    // `--out` names the new case of `--apply`; alone it would write nothing
    if args.out.is_some() && args.apply.is_none() {
        return Err(Failure::new(
            Exit::Usage,
            "--out FILE is where --apply N writes the case with effect N added, and nothing is applied; give \
             --apply N to write it, or --report DIR for a report of the ranking",
        ));
    }
    let mut study = super::load_study(args.case)?;
    let mut inputs = study.case().inputs();
    inputs.extend(args.measured.map(Path::to_path_buf));
    let mut report_output = args
        .report
        .map(|dir| Outputs::folder(dir, &inputs, &["report.html"])?.of_command("diagnose", args.replace))
        .transpose()?;
    let mut outputs = match (args.apply, args.out) {
        (Some(_), Some(out)) => Some(apply_outputs(&study, args.measured, None, out)?),
        _ => None,
    };
    let read = read_data(&mut study, args.measured)?;
    let (measured, notes) = (&read.receptances, &read.notes);
    print_notes(notes, args.json)?;
    print_masked(&read.masked, args.json)?;
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
    let data_file = outputs.as_ref().and_then(|(_, data)| data.as_ref().map(|o| o.path.clone()));
    let (prepared, d) = run_diagnosis(
        &study,
        measured,
        data_file,
        &mut |p| {
            // the spinner says what runs; the findings and step 0 are printed with the ranking
            match p {
                FixProgress::Checked { .. } => bar.set_message("checked the data for set-up errors"),
                FixProgress::Declared { .. } => bar.set_message("updated the case's own [update] parameters (step 0)"),
                _ => {}
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
        outln!("{}", diagnosis_json(notes, &prepared, &d)?);
    } else {
        print_checks(&prepared)?;
        print_diagnosis(&d, args.top, prepared.declared.is_some())?;
        if let Some(line) =
            crate::report::mesh_sentence(prepared.mesh.as_ref(), prepared.noise, crate::report::MeshReading::Ranked)
        {
            outln!("\nnote: {line}");
        }
    }
    if let Some(mut output) = report_output.take() {
        let source = args.measured.map_or_else(
            || match study.case().measurement.as_ref().and_then(|m| m.data.as_ref()) {
                Some(p) => format!("measured file {}", crate::report::shown_path(p)),
                None => "synthesised from the case's truth model".to_string(),
            },
            |p| format!("measured file {}", p.display()),
        );
        let written = crate::report::diagnose_report::write(
            &study,
            &prepared,
            &d,
            (&read.as_read, &read.per_volt),
            &source,
            &args.report_options.for_case(study.case()),
            &mut output,
        )?;
        output.commit()?;
        if !args.json {
            outln!("\nwrote {} (figures and tables beside it)", written.display());
        }
    }
    if let Some(rank) = args.apply {
        let out = args.out.ok_or("--apply needs --out FILE for the new case file")?;
        let outputs = outputs.take().ok_or("--apply needs --out FILE for the new case file")?;
        let data = write_apply(&prepared.case, &d, rank, (out, args.measured), outputs)?;
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
    let report = CheckedDiagnosis {
        findings: &prepared.findings,
        declared: prepared.declared.as_ref(),
        mesh: prepared.mesh.as_ref(),
        diagnosis: d,
    };
    Ok(serde_json::to_string_pretty(&WithNotes { notes, result: &report })?)
}

/// The measured data `rfm diagnose` reads, and what is known of them.
struct DiagnosisData {
    /// As receptances: what the diagnosis fits.
    receptances: FrfSet,
    /// What reading them changed or passed over.
    notes: Vec<String>,
    /// What the case's mask left out of them.
    masked: Vec<String>,
    /// As they were measured (their kind), as the report draws them.
    as_read: FrfSet,
    /// The references whose data are per volt.
    per_volt: Vec<fe_model::DofRef>,
}

/// The measured receptances `rfm diagnose` fits: the file `measured` as
/// `--measured` reads it (the study's gains decided again for it), or the
/// study's own data; with the notes on reading them and what the case's
/// mask left out. A file that does not fit the case is refused with what
/// the case wants and what the file holds.
pub fn diagnosis_data(study: &mut Study, measured: Option<&Path>) -> Result<(FrfSet, Vec<String>, Vec<String>)> {
    let d = read_data(study, measured)?;
    Ok((d.receptances, d.notes, d.masked))
}

fn read_data(study: &mut Study, measured: Option<&Path>) -> Result<DiagnosisData> {
    Ok(match measured {
        Some(path) => {
            let read = read_measured_for(study.system(), path, study.case().measurement.as_ref())
                .map_err(|e| super::mismatch(e.into(), study.case().measurement.as_ref(), Some(path)))?;
            study.set_gains_for(&read)?;
            let mut notes = read.notes.clone();
            if study.gains() != Gains::None {
                notes.push(format!(
                    "model FRFs are multiplied by fitted gains ({}): {}",
                    study.gains(),
                    study.gains_reason()
                ));
            }
            DiagnosisData {
                receptances: read.set.to_receptance(),
                notes,
                masked: describe_masked(&read.masked),
                per_volt: read.per_volt_references(),
                as_read: read.set,
            }
        }
        None => DiagnosisData {
            receptances: study.measured().clone(),
            notes: study.notes().to_vec(),
            masked: describe_masked(study.masked()),
            as_read: study.measured_as_read(),
            per_volt: study.per_volt().to_vec(),
        },
    })
}

/// The outputs of `--apply` into `out`, opened before the diagnosis: the
/// case, and where the study's data come from its `[truth]` (and not from
/// `measured`), the data beside it; a copy of `carried` instead where given
/// (see [`write_applied`]).
fn apply_outputs(
    study: &Study,
    measured: Option<&Path>,
    carried: Option<&Path>,
    out: &Path,
) -> Result<(Outputs, Option<DataOutput>)> {
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
    let data = if let Some(file) = carried {
        // a file that lives no longer than the run (FRFs given in memory to
        // the Python package): a copy of it beside the new case
        let (ext, bytes) = super::carried_file(file)?;
        let path = data_beside(out, &ext);
        Some(DataOutput { output: Outputs::file(&path, &inputs)?, path, bytes, carried: true })
    } else if synthesised {
        let path = data_beside(out, "csv");
        let bytes = frf::io::csv::to_csv_string(study.measured()).into_bytes();
        Some(DataOutput { output: Outputs::file(&path, &inputs)?, path, bytes, carried: false })
    } else {
        None
    };
    Ok((output, data))
}

/// The data file written beside a new case: where, what, and whether it
/// is a copy of a file carried (else the data synthesised from the case's
/// `[truth]`).
struct DataOutput {
    output: Outputs,
    path: PathBuf,
    bytes: Vec<u8>,
    carried: bool,
}

/// Writes the case `base` (the study's case as the diagnosis saw it:
/// corrected, its own parameters updated) with the effect of `rank` added
/// as `out`, and the synthesised data beside it when it needs them;
/// returns their path.
fn write_apply(
    base: &CaseFile,
    d: &Diagnosis,
    rank: usize,
    (out, measured): (&Path, Option<&Path>),
    (mut output, data_output): (Outputs, Option<DataOutput>),
) -> Result<Option<PathBuf>> {
    let data = data_output.as_ref().map(|o| o.path.clone());
    let mut editor = d.apply_with_data(base, rank, data.as_deref())?;
    // the new case reads the data the diagnosis read, as the cases `rfm
    // update` and `rfm fix` write with `--measured` do: the file given, or
    // the copy of one carried
    if let Some(path) = data_output.as_ref().filter(|o| o.carried).map(|o| o.path.as_path()).or(measured) {
        editor.use_data(path);
    }
    if let Some(DataOutput { output: mut data, bytes, .. }) = data_output {
        data.write_file(&bytes)?;
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
/// (`CASE-measured.csv`, whose path is returned), each file all or nothing;
/// the new case reads `measured` where given. `carried`: a data file the
/// new case must not name, because it lives no longer than the caller
/// (FRFs given in memory to the Python package, written to a temporary
/// file): it is copied beside the new case (`CASE-measured.uff` or `.csv`,
/// as its extension), which reads the copy.
pub fn write_applied(
    study: &Study,
    base: &CaseFile,
    d: &Diagnosis,
    rank: usize,
    (measured, carried): (Option<&Path>, Option<&Path>),
    out: &Path,
) -> Result<Option<PathBuf>> {
    let outputs = apply_outputs(study, measured, carried, out)?;
    write_apply(base, d, rank, (out, measured), outputs)
}

/// `NEW-measured.EXT` beside the new case `NEW.toml`.
fn data_beside(case: &Path, ext: &str) -> PathBuf {
    let stem = case.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "case".into());
    case.with_file_name(format!("{stem}-measured.{ext}"))
}

/// Candidates whose fits failed listed in the text after the ranking; the
/// rest are in `--json`.
const UNFITTED_SHOWN: usize = 5;

/// The fuller variants not fitted because their plain twin was not among
/// the pre-screening's best, when there are any (the terminal's and the
/// report's line of candidates).
pub(crate) fn deferred_text(d: &Diagnosis) -> String {
    if d.deferred == 0 {
        return String::new();
    }
    format!(
        ", {} fuller variants (non-viscous damping, rotary inertia) not fitted: their plain twins were not among \
         the pre-screening's best",
        d.deferred
    )
}

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
    if p.findings.is_empty() {
        outln!("checked the data for set-up errors: none found\n");
    } else {
        outln!("findings about the data (corrected before the diagnosis when a correction is given):");
        for f in &p.findings {
            let fix = if f.corrections.is_empty() { "" } else { " [corrected]" };
            outln!("  - {}{fix}\n    {}", f.summary, f.evidence);
        }
        if p.corrected_misfit != p.nominal_misfit {
            outln!(
                "  the nominal model's misfit {} on the data as read, {} on the corrected data",
                table::misfit(p.nominal_misfit),
                table::misfit(p.corrected_misfit)
            );
        }
        outln!("");
    }
    if let Some(d) = &p.declared {
        outln!("{}; the diagnosis below is of the updated model\n", declared_text(d, p.noise));
    }
    Ok(())
}

/// Step 0 in one sentence, as `rfm diagnose` and its report say it.
pub(crate) fn declared_text(d: &rfm_update::fix::DeclaredStep, noise: f64) -> String {
    format!(
        "the case's own [update] parameters were updated first (step 0, {}): misfit {} -> {} ({} -> {} x the \
         noise), dBIC {}",
        d.status.name(),
        table::misfit(d.misfit_before),
        table::misfit(d.misfit_updated),
        table::times(quantities::times_noise(d.misfit_before, noise)),
        table::times(quantities::times_noise(d.misfit_updated, noise)),
        table::dbic(d.delta_bic)
    )
}

/// The ranking and what it recommends; `after_step0`: the model diagnosed
/// is the case's with its own parameters updated.
fn print_diagnosis(d: &Diagnosis, top: usize, after_step0: bool) -> Result<()> {
    outln!(
        "noise {}; misfit of the {} {} ({} x the noise), over the {} lines the diagnosis reads",
        table::misfit(d.noise),
        if after_step0 { "model after step 0" } else { "nominal model" },
        table::misfit(d.nominal_misfit),
        table::times(quantities::times_noise(d.nominal_misfit, d.noise)),
        quantities::MISFIT_LINES
    );
    if d.weighted {
        outln!(
            "(both, and every fit, weigh the lines as the update does: by the measured coherence, or the weights of the \
             lines at a noise floor, and any band weights)"
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
            for g in crate::report::gain_reports(&l.gains) {
                outln!("    {}", crate::report::gain_text(&g));
            }
        }
        outln!("");
    }
    let mut t = Table::new(&["rank", "effect", "explained", "dBIC", "significant", "", "fitted values"]);
    let shown = d.shown(top);
    for row in &shown {
        let (i, r) = (row.rank - 1, &d.ranking[row.rank - 1]);
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
        let alike = crate::report::alike_text(&row.alike);
        let note = match (note.is_empty(), alike.is_empty()) {
            (_, true) => note,
            (true, false) => alike,
            (false, false) => format!("{alike}; {note}"),
        };
        t.row(vec![
            format!("{}", i + 1),
            r.description.clone(),
            crate::report::percent(r.explained),
            table::dbic(r.delta_bic),
            if r.significant { "yes".into() } else { "no".into() },
            note,
            values,
        ]);
    }
    outln!("{}", t.render());
    outln!(
        "\n(explained: the share of the nominal model's squared misfit the effect removes; dBIC: the change of the \
         Bayesian information criterion, comparable only within one diagnosis; significant: dBIC below {}, very \
         strong evidence; {} candidates tried, {} of them replaced by a variant{}{})",
        quantities::SIGNIFICANT_DBIC,
        d.tried,
        d.superseded,
        deferred_text(d),
        if shown.iter().any(|r| !r.alike.is_empty()) {
            format!("; {}", crate::report::ALIKE_LEGEND)
        } else {
            String::new()
        }
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
            deferred: 0,
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

    /// Fuller variants left unfitted by the pre-screening are counted in
    /// the line of candidates (the terminal's and the report's) and in the
    /// JSON; none, nothing is said.
    #[test]
    fn deferred_variants_are_counted() {
        let mut d = diagnosis(Vec::new());
        assert_eq!(deferred_text(&d), "");
        d.deferred = 9723;
        assert_eq!(
            deferred_text(&d),
            ", 9723 fuller variants (non-viscous damping, rotary inertia) not fitted: their plain twins were not \
             among the pre-screening's best"
        );
        let json = serde_json::to_value(WithNotes { notes: &[], result: &d }).unwrap();
        assert_eq!(json["deferred"], 9723);
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
