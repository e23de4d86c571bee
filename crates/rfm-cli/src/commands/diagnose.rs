//! `rfm diagnose`: which physical effect is missing from the model.

use std::path::{Path, PathBuf};

use fe_model::case::Gains;
use indicatif::ProgressBar;
use rfm_update::Study;
use rfm_update::diagnose::{Diagnosis, diagnose_with};
use rfm_update::study::{describe_masked, read_measured_for};

use super::{Result, WithNotes, print_masked, print_notes};
use crate::exit::Exit;
use crate::output::Outputs;
use crate::table::{Table, num, percent};

/// Options of the diagnose command.
pub(crate) struct DiagnoseArgs<'a> {
    pub(crate) case: &'a Path,
    pub(crate) measured: Option<&'a Path>,
    pub(crate) json: bool,
    pub(crate) apply: Option<usize>,
    pub(crate) out: Option<&'a Path>,
    pub(crate) top: usize,
    pub(crate) verbose: bool,
}

pub(crate) fn diagnose(args: &DiagnoseArgs<'_>) -> Result<Exit> {
    let mut study = Study::load(args.case)?;
    let mut inputs = study.case().inputs();
    inputs.extend(args.measured.map(Path::to_path_buf));
    let mut output = match (args.apply, args.out) {
        (Some(_), Some(out)) => Some(Outputs::file(out, &inputs)?),
        _ => None,
    };
    // A case whose data come from its [truth] cannot keep the truth once an
    // effect is added: a truth that adds the same joint or mass would add
    // it twice. The new case gets the synthesised data beside it instead
    // (as every step of `rfm fix` does), written before the case.
    let synthesised = args.measured.is_none()
        && study.case().measurement.as_ref().is_some_and(|m| m.data.is_none())
        && study.case().truth.is_some();
    let mut data_output = match (args.apply, args.out) {
        (Some(_), Some(out)) if synthesised => {
            let path = data_beside(out);
            Some((Outputs::file(&path, &inputs)?, path))
        }
        _ => None,
    };
    let (measured, notes) = match args.measured {
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
            print_notes(&notes, args.json)?;
            print_masked(&describe_masked(&read.masked), args.json)?;
            (read.set.to_receptance(), notes)
        }
        None => {
            print_notes(study.notes(), args.json)?;
            print_masked(&describe_masked(study.masked()), args.json)?;
            (study.measured().clone(), study.notes().to_vec())
        }
    };
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
    let opts = study.diagnose_options()?;
    let d = diagnose_with(&study.case().model, &measured, &opts, |stage| {
        let line = format!("{stage} ({:.2} s)", start.elapsed().as_secs_f64());
        if args.verbose {
            bar.suspend(|| eprintln!("{line}"));
        }
        bar.set_message(line);
    })?;
    bar.finish_and_clear();
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&WithNotes { notes: &notes, result: &d })?);
    } else {
        print_diagnosis(&d, args.top)?;
    }
    if let Some(rank) = args.apply {
        let out = args.out.ok_or("--apply needs --out FILE for the new case file")?;
        let data = data_output.as_ref().map(|(_, path)| path.clone());
        let editor = d.apply_with_data(study.case(), rank, data.as_deref())?;
        if let Some((mut data, path)) = data_output.take() {
            data.write_file(frf::io::csv::to_csv_string(study.measured()).as_bytes())?;
            data.commit()?;
            if !args.json {
                outln!("\nwrote {} with the data synthesised from the case's [truth]", path.display());
            }
        }
        let text = editor.text_at(out)?;
        let mut output = output.take().ok_or("--apply needs --out FILE for the new case file")?;
        output.write_file(text.as_bytes())?;
        output.commit()?;
        if !args.json {
            outln!("\nwrote {} with effect {rank} added", out.display());
        }
    }
    Ok(Exit::Success)
}

/// `NEW-measured.csv` beside the new case `NEW.toml`.
fn data_beside(case: &Path) -> PathBuf {
    let stem = case.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "case".into());
    case.with_file_name(format!("{stem}-measured.csv"))
}

fn print_diagnosis(d: &Diagnosis, top: usize) -> Result<()> {
    outln!(
        "noise level estimated from the data: {:.2} %; nominal model misfit: {:.2} % (RMS relative)\n",
        100.0 * d.noise,
        100.0 * d.nominal_misfit
    );
    if d.gains {
        outln!("every fit includes an unknown complex gain per reference; the leader's:");
        if let Some(l) = d.ranking.first() {
            for g in &l.gains {
                outln!(
                    "    {}: x{} ({:+.1} dB), {:+.1} deg",
                    g.reference,
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
        let note = match (&r.implausible_reason, r.fully_fitted) {
            (Some(why), _) => format!("implausible: {why}"),
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
         {} candidates tried)",
        d.tried
    );
    if !d.unfitted.is_empty() {
        outln!("{} candidates could not be fitted and are not ranked:", d.unfitted.len());
        for u in d.unfitted.iter().take(5) {
            outln!("    {}: {}", u.description, u.reason);
        }
        if d.unfitted.len() > 5 {
            outln!("    ... ({} more in --json)", d.unfitted.len() - 5);
        }
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
