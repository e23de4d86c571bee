//! The report of an updating run (`rfm update --out DIR`): the structure,
//! misfit and parameter values per iteration, the parameter table (also as
//! `parameters.csv`), error against frequency and per channel, the modes of
//! the updated model against the measured ones, before/after FRF overlays
//! of every channel, and `report.html` with all of it.

use std::path::{Path, PathBuf};

use frf::correlation::BandSpec;
use rfm_update::comparison::{self, GainSource};
use rfm_update::output_error::Gain;
use rfm_update::quantities::MisfitReport;
use rfm_update::status::Status;
use rfm_update::study::FrequencyTable;
use rfm_update::{Study, UpdateOutcome};

use super::html::{Block, Report, Section, Table, Tone};
use super::units::parameter_unit;
use super::{Data, ModelFrfs, ReportOptions, Result, gain_reports, gains_text, loop_story, plot, sig};
use crate::output::Outputs;
use crate::table::{self, num};

/// Writes the report files of an updating run into the run's outputs and
/// returns where `report.html` will be; `step` is this run's entry in the
/// case's history (the updated model's misfit over the band), `misfits`
/// the initial and the updated model's misfits with the noise.
pub(crate) fn write(
    study: &Study,
    outcome: &UpdateOutcome,
    step: &fe_model::HistoryEntry,
    misfits: &[MisfitReport; 2],
    out: &mut Outputs,
    case_path: &Path,
    opts: &ReportOptions,
) -> Result<PathBuf> {
    // the data as they were measured (accelerance per volt, say), which the
    // model's FRFs are converted to: what the overlays show
    let as_read = study.measured_as_read();
    let measured = &as_read;
    let unweighted = if outcome.coherence_weighted || study.line_weights(measured)?.is_some() {
        rfm_update::quantities::noise(&outcome.system, study.measured(), None)?
    } else {
        misfits[1].noise
    };
    let data = Data::new(measured, study.per_volt(), unweighted);
    let freqs = measured.frequencies_hz();
    // a model singular at a line (an RFM run that wandered off, an undamped
    // model on a resonance) is shown everywhere else, and the report says where
    let mut singular = Vec::new();
    let weights = study.line_weights(measured)?;
    let mut model = |label: &str,
                     colour,
                     sys: &damping::DampedSystem,
                     gains: GainSource<'_>,
                     misfit: MisfitReport|
     -> Result<ModelFrfs> {
        let estimated = match gains {
            GainSource::Estimated(g) => gain_reports(g),
            _ => Vec::new(),
        };
        let compared = comparison::compare(sys, measured, gains, &BandSpec::Auto)?;
        if !compared.model.singular_hz.is_empty() {
            singular.push(format!(
                "The {label}'s dynamic stiffness is singular to working precision at {} Hz: its FRFs there are left \
                 out of the figures and errors.",
                compared.model.singular_hz.iter().map(|&f| super::short(f)).collect::<Vec<_>>().join(", ")
            ));
        }
        let gains = compared.model.fitted.as_ref().map_or(estimated, |f| f.reports());
        Ok(ModelFrfs {
            label: label.into(),
            colour,
            frfs: compared.model.frfs,
            correlation: compared.correlation,
            gains,
            misfit: Some(misfit),
        })
    };
    // the initial model with the gains that fit it best, when the study
    // fits gains: without them it would sit the data's unknown level (tens
    // of dB on data per volt) off the curves
    let initial_gains = if outcome.gains.is_empty() {
        GainSource::None
    } else {
        GainSource::Fit { setting: study.gains(), weights: weights.as_deref() }
    };
    let models = [
        model("initial model", plot::INITIAL, study.system(), initial_gains, misfits[0])?,
        model("updated model", plot::UPDATED, &outcome.system, GainSource::Estimated(&outcome.gains), misfits[1])?,
    ];
    // each iterate with the gains that fit it, the last with those the
    // update estimated: the ends are the summary's initial and updated model
    let (all_lines_db, stride) = rfm_update::history::rms_db_per_iteration_with_gains(study, outcome, measured);
    let mut which_lines = if stride == 1 {
        "all measured lines".to_string()
    } else {
        format!("every {stride}th measured line (thinned to keep the report quick on a large model)")
    };
    if !outcome.gains.is_empty() {
        which_lines.push_str(
            ", each iterate times the gains that fit it best and the last (the updated model) times those the \
             update estimated",
        );
    }

    let mut report = Report::new(format!("{}: model updating", study.case().model.title));
    report.subtitle =
        Some(format!("rfm update, {} method, case file {}", method_name(&outcome.method), case_path.display()));
    let mut first = summary(study, outcome, &data, &models);
    for text in singular {
        first.push(Block::Text(text));
    }
    // the loop so far, when the case was written by an earlier step
    let history = &study.case().history;
    if !history.is_empty() {
        let steps = [history.clone(), vec![step.clone()]].concat();
        if let Some(fall) = loop_story::fall_figure(&steps, true, out)? {
            first.push(fall);
        }
    }
    let added = loop_story::highlights(history, outcome.system.model());
    first.push(super::structure_figure(
        outcome.system.model(),
        measured,
        &added,
        if added.is_empty() {
            "The updated model (its geometry is the initial model's)."
        } else {
            "The updated model (its geometry is the initial model's), each effect its history records as added \
             numbered and marked where it sits (a ring at a joint, a support or a mass, a broad band along the \
             elements of a changed region)."
        },
        out,
    )?);
    report.sections.push(first);

    let mut conv = Section::new("Convergence");
    let residuals: Vec<f64> = outcome.history.iter().map(|r| r.residual).collect();
    let (residual_label, residual_text) = residual_names(&outcome.method);
    conv.push(out.figure(
        "convergence",
        plot::convergence(residual_label, &residuals, Some(&all_lines_db))?,
        format!(
            "Top: {residual_text}, per iteration (iteration 0 is the initial model). Bottom: the RMS dB error of \
             the model at each iteration over {which_lines} and all channels, which shows whether fitting the \
             updating lines improved the whole band; its first and last points are the summary's RMS dB error of \
             the initial and the updated model."
        ),
    )?);
    let traces: Vec<plot::ParameterTrace> = outcome
        .parameters
        .iter()
        .enumerate()
        .map(|(i, p)| plot::ParameterTrace {
            name: p.name.clone(),
            ratios: outcome.history.iter().map(|r| r.values.get(i).copied().unwrap_or(f64::NAN) / p.initial).collect(),
            truth_ratio: p.truth.map(|t| t / p.initial),
        })
        .collect();
    conv.push(out.figure(
        "parameters",
        plot::parameter_history(&traces)?,
        "Each parameter divided by its initial value, per iteration (logarithmic axis). A parameter that \
         wanders far or keeps changing after the misfit has levelled off is poorly determined by the data.",
    )?);
    conv.push(out.table("iterations", iteration_table(outcome, &all_lines_db))?);
    report.sections.push(conv);

    let (params, csv) = parameter_table(outcome);
    out.write("parameters.csv", csv.as_bytes())?;
    let mut ps = Section::new("Parameters");
    ps.push(Block::Table(params));
    let basis = match &outcome.uncertainty {
        Some(u) => format!("Standard deviations {}.", u.shown_first),
        None => "No uncertainty is available for these values: the RFM's equation error has no noise model.".into(),
    };
    ps.push(Block::Text(basis));
    for w in &outcome.warnings {
        ps.push(Block::Text(format!("{w}.")));
    }
    if let Some(u) = &outcome.uncertainty {
        for w in u.parameters.iter().flat_map(|p| p.warnings.iter().map(move |w| format!("{}: {w}.", p.name))) {
            ps.push(Block::Text(w));
        }
        for w in &u.warnings {
            ps.push(Block::Text(format!("{w}.")));
        }
    }
    if !outcome.gains.is_empty() {
        // one setting per run: every gain is of a reference, or of a channel
        let per = outcome.gains[0].key.noun();
        let mut t = Table::new(&[per, "gain magnitude", "gain (dB)", "gain phase (deg)"]).caption(format!(
            "Fitted gain per {per}, estimated with the parameters: the updated model's FRFs are multiplied by it \
             before every comparison and figure of this report."
        ));
        for g in gain_reports(&outcome.gains) {
            t.row(vec![g.key.clone(), sig(g.magnitude, 4), format!("{:+.1}", g.magnitude_db), sig(g.phase_deg, 3)]);
        }
        ps.push(out.table("gains", t)?);
    }
    ps.push(out.table("natural-frequencies", frequency_table(outcome))?);
    report.sections.push(ps);

    let notes = vec![format!(
        "The initial and the updated model against the measured FRFs over all {} lines, not only the {} \
         updating lines.",
        freqs.len(),
        outcome.frequencies_hz.len()
    )];
    report.sections.push(super::correlation_section(&data, &models, opts, out, notes)?);
    let gains: Vec<_> = measured.channels().iter().map(|c| Gain::factor_of(&outcome.gains, c)).collect();
    let comparison =
        comparison::compare_modes(&outcome.system, measured, &gains, super::modes::MIN_MAC).map_err(|e| e.to_string());
    let mut modes = super::modes::section(
        comparison.as_ref(),
        "the updated model",
        outcome.system.model(),
        measured,
        misfits[1].consistent(),
        opts,
        out,
    )?;
    let band = (freqs.first().copied().unwrap_or(0.0), freqs.last().copied().unwrap_or(0.0));
    let table = super::natural_frequency_table(
        &[("initial".to_string(), study.system()), ("updated".to_string(), &outcome.system)],
        band,
        comparison.as_ref().ok(),
    );
    modes.push(out.table("modes-before-after", table)?);
    report.sections.push(modes);
    report.sections.push(super::overlay_section(&data, &models, &outcome.frequencies_hz, opts, out)?);
    report.sections.push(super::definitions_section());
    Ok(out.write("report.html", report.render().as_bytes())?)
}

fn method_name(m: &str) -> String {
    match m {
        "rfm" => "response function".into(),
        other => other.to_string(),
    }
}

/// Axis label and caption wording of a method's own residual.
fn residual_names(method: &str) -> (&'static str, &'static str) {
    match method {
        "rfm" => (
            "RFM residual",
            "the RFM residual, the RMS of the relative differences |R_FE - R_EX| / |R_EX| at the updating lines \
             (what the response function method minimises)",
        ),
        _ => (
            "fit residual",
            "the fit residual, the misfit at the fitted lines weighted as the fit weighs them (what the \
             output-error fit minimises)",
        ),
    }
}

fn status_text(s: &Status) -> String {
    s.describe()
}

fn summary(study: &Study, outcome: &UpdateOutcome, data: &Data<'_>, models: &[ModelFrfs; 2]) -> Section {
    let (a, b) = (&models[0].correlation, &models[1].correlation);
    let measured = data.set;
    let f = measured.frequencies_hz();
    let source = match (&study.case().measurement.as_ref().and_then(|m| m.data.clone()), &study.case().truth) {
        (Some(path), _) => format!("measured file {}", super::shown_path(path)),
        (None, Some(t)) if t.noise > 0.0 => {
            format!(
                "synthesised from the case's truth model with {} % noise (seed {})",
                super::short(100.0 * t.noise),
                t.seed
            )
        }
        (None, Some(_)) => "synthesised from the case's truth model, noise-free".into(),
        (None, None) => "-".into(),
    };
    let iterations = outcome.history.last().map_or(0, |r| r.iteration);
    let first = outcome.history.first().map_or(f64::NAN, |r| r.residual);
    let mut s = Section::new("Summary");
    let (residual_label, _) = residual_names(&outcome.method);
    let misfit = match (models[0].misfit, models[1].misfit) {
        (Some(m0), Some(m1)) => {
            let times = match (m0.times_noise, m1.times_noise, m1.noise) {
                (Some(t0), Some(t1), Some(n)) => {
                    format!(" ({} -> {} x the noise, {})", table::times(t0), table::times(t1), table::misfit(n))
                }
                _ => String::new(),
            };
            format!(
                "{} -> {}{times}, over the {} lines the diagnosis reads",
                table::misfit(m0.misfit),
                table::misfit(m1.misfit),
                m1.lines
            )
        }
        _ => "-".into(),
    };
    let mut facts = vec![
        ("case".into(), study.case().path.display().to_string()),
        ("data".into(), source),
        (
            "measurement".into(),
            format!(
                "{} channels x {} lines, {} to {} Hz, {} ({})",
                measured.channels().len(),
                f.len(),
                super::short(f.first().copied().unwrap_or(0.0)),
                super::short(f.last().copied().unwrap_or(0.0)),
                data.quantity(),
                data.unit()
            ),
        ),
        ("method".into(), method_name(&outcome.method)),
        (
            "parameters".into(),
            outcome
                .parameters
                .iter()
                .map(|p| match parameter_unit(&p.name) {
                    "" | "-" => p.name.clone(),
                    unit => format!("{} ({unit})", p.name),
                })
                .collect::<Vec<_>>()
                .join(", "),
        ),
        ("updating lines".into(), lines_summary(&outcome.frequencies_hz)),
        ("status".into(), format!("{} after {iterations} iterations", status_text(&outcome.status))),
        ("misfit".into(), misfit),
        (
            format!("{residual_label} at the updating lines"),
            format!("{} -> {}", table::misfit(first), table::misfit(outcome.residual)),
        ),
        ("RMS dB error, all lines".into(), format!("{} dB -> {} dB", sig(a.total.rms_db, 3), sig(b.total.rms_db, 3))),
        (
            "RMS phase error, all lines".into(),
            format!("{} deg -> {} deg", sig(a.total.rms_phase_deg, 3), sig(b.total.rms_phase_deg, 3)),
        ),
        ("mean FRAC".into(), format!("{:.4} -> {:.4}", a.total.mean_frac, b.total.mean_frac)),
    ];
    if !models[1].gains.is_empty() {
        facts.push(("fitted gain".into(), gains_text(&models[1].gains)));
    }
    s.push(Block::Facts(facts));
    if outcome.frequencies_hz.len() > 12 {
        s.push(Block::Details {
            summary: format!("The {} updating lines (Hz)", outcome.frequencies_hz.len()),
            text: outcome.frequencies_hz.iter().map(|&v| super::short(v)).collect::<Vec<_>>().join(", "),
        });
    }
    let band = super::notable_bands(b, 1).first().map(|&i| &b.bands[i]);
    let channel = super::notable_channels(b, 1).first().map(|&i| &b.channels[i]);
    if b.total.log_misfit < super::NOTABLE_MISFIT {
        s.push(Block::Text(format!(
            "The updated model matches the measured FRFs over the whole band: RMS {} dB and {} deg.",
            sig(b.total.rms_db, 2),
            sig(b.total.rms_phase_deg, 2)
        )));
    } else if let (Some(band), Some(ch)) = (band, channel) {
        s.push(Block::Text(format!(
            "Where the updated model still misses most: the band {} ({} of the remaining misfit, RMS {} dB) \
             and channel {} (RMS {} dB, FRAC {:.3}).",
            band.band.label(),
            super::percent(band.share),
            sig(band.rms_db, 3),
            ch.channel,
            sig(ch.rms_db, 3),
            ch.frac
        )));
    }
    s
}

/// The updating lines in a few words: all of them when few, else how many
/// and over what range (the list is folded under the summary).
fn lines_summary(f: &[f64]) -> String {
    match (f.first(), f.last()) {
        _ if f.len() <= 12 => format!("{} Hz", f.iter().map(|&v| super::short(v)).collect::<Vec<_>>().join(", ")),
        (Some(a), Some(b)) => format!(
            "{} lines from {} to {} Hz (ticks on the overlays' frequency axes; listed below)",
            f.len(),
            super::short(*a),
            super::short(*b)
        ),
        _ => "none".into(),
    }
}

fn iteration_table(outcome: &UpdateOutcome, all_lines_db: &[f64]) -> Table {
    let residual = format!("{} at the updating lines", residual_names(&outcome.method).0);
    let mut t = Table::new(&[
        "iteration",
        &residual,
        "max |du/u| of the step",
        "limited",
        "rank",
        "damping lambda",
        "RMS dB error over the band",
    ])
    .caption(
        "The iteration history (each row is the model after the step that led to it); the RMS dB error as the \
         convergence figure's lower panel draws it.",
    );
    for (r, db) in outcome.history.iter().zip(all_lines_db) {
        t.row(vec![
            r.iteration.to_string(),
            table::misfit(r.residual),
            sig(r.max_correction, 3),
            r.limited.to_string(),
            r.rank.to_string(),
            sig(r.lambda, 3),
            sig(*db, 3),
        ]);
    }
    t
}

/// The parameter table for the report and as CSV.
fn parameter_table(outcome: &UpdateOutcome) -> (Table, String) {
    let has_truth = outcome.parameters.iter().any(|p| p.truth.is_some());
    let has_paper = outcome.parameters.iter().any(|p| p.paper.is_some());
    let unc = outcome.uncertainty.as_ref();
    let mut header = vec!["parameter", "unit", "initial", "updated", "updated / initial"];
    if unc.is_some() {
        header.extend(["std (%)", "95 % interval", "determined"]);
    }
    if has_truth {
        header.extend(["truth", "error vs truth"]);
    }
    if has_paper {
        header.push("paper");
    }
    let mut t = Table::new(&header).caption(if unc.is_some() {
        "Parameter values before and after updating, with the relative standard deviation and 95 % interval \
         of the fit; `weakly` marks a parameter the data do not determine well (reasons below)."
    } else {
        "Parameter values before and after updating."
    });
    // the CSV has one value per cell and plain names
    let mut csv_header = vec!["parameter", "unit", "initial", "updated", "updated/initial"];
    if unc.is_some() {
        csv_header.extend(["relative_std", "interval95_low", "interval95_high", "well_determined"]);
    }
    if has_truth {
        csv_header.extend(["truth", "relative_error"]);
    }
    if has_paper {
        csv_header.push("paper");
    }
    let mut csv = csv_header.join(",");
    csv.push('\n');
    for p in &outcome.parameters {
        let mut row = vec![
            (p.name.clone(), Tone::Plain),
            (parameter_unit(&p.name).to_string(), Tone::Plain),
            (num(p.initial), Tone::Plain),
            (num(p.updated), Tone::Plain),
            (sig(p.updated / p.initial, 4), Tone::Plain),
        ];
        let mut line = vec![
            p.name.clone(),
            parameter_unit(&p.name).to_string(),
            format!("{:e}", p.initial),
            format!("{:e}", p.updated),
            format!("{:e}", p.updated / p.initial),
        ];
        if let Some(u) = unc.and_then(|u| u.parameters.iter().find(|u| u.name == p.name)) {
            let tone = if u.well_determined { Tone::Good } else { Tone::Bad };
            row.push((sig(100.0 * u.relative_std, 2), Tone::Plain));
            let (lo, hi) = u.interval95;
            row.push((format!("{} .. {}", super::trimmed(sig(lo, 3)), super::trimmed(sig(hi, 3))), Tone::Plain));
            row.push((if u.well_determined { "yes" } else { "weakly" }.to_string(), tone));
            line.push(format!("{:e}", u.relative_std));
            line.push(format!("{:e}", u.interval95.0));
            line.push(format!("{:e}", u.interval95.1));
            line.push(u.well_determined.to_string());
        } else if unc.is_some() {
            row.extend(std::iter::repeat_n((String::new(), Tone::Plain), 3));
            line.extend(std::iter::repeat_n(String::new(), 4));
        }
        if has_truth {
            let err = p.relative_error();
            let tone = match err {
                Some(e) if e > 0.05 => Tone::Bad,
                Some(e) if e < 1e-3 => Tone::Good,
                _ => Tone::Plain,
            };
            row.push((p.truth.map(num).unwrap_or_default(), Tone::Plain));
            row.push((err.map(|e| super::trimmed(sig(e, 2))).unwrap_or_default(), tone));
            line.push(p.truth.map(|v| format!("{v:e}")).unwrap_or_default());
            line.push(err.map(|v| format!("{v:e}")).unwrap_or_default());
        }
        if has_paper {
            row.push((p.paper.map(num).unwrap_or_default(), Tone::Plain));
            line.push(p.paper.map(|v| format!("{v:e}")).unwrap_or_default());
        }
        t.row_toned(row);
        csv.push_str(&line.join(","));
        csv.push('\n');
    }
    (t, csv)
}

/// Header and rows of the natural-frequency table (mode, initial, updated,
/// truth and paper when known), shared by the terminal and the report.
pub(crate) fn frequency_rows(nf: &FrequencyTable) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let mut header = vec!["mode", "initial (Hz)", "updated (Hz)"];
    if nf.truth.is_some() {
        header.push("truth (Hz)");
    }
    if nf.paper.is_some() {
        header.push("paper (Hz)");
    }
    let n = nf.initial.len().max(nf.updated.len()).max(nf.paper.as_ref().map_or(0, Vec::len));
    let cell = |v: Option<&f64>| v.map(|f| format!("{f:.2}")).unwrap_or_default();
    let rows = (0..n)
        .map(|k| {
            let mut row = vec![format!("{}", k + 1), cell(nf.initial.get(k)), cell(nf.updated.get(k))];
            if let Some(tr) = &nf.truth {
                row.push(cell(tr.get(k)));
            }
            if let Some(p) = &nf.paper {
                row.push(cell(p.get(k)));
            }
            row
        })
        .collect();
    (header, rows)
}

fn frequency_table(outcome: &UpdateOutcome) -> Table {
    let nf = &outcome.natural_frequencies_hz;
    let caption = match nf.kind.as_str() {
        "damped" => "Natural frequencies of the damped model's complex modes in the measured band.".to_string(),
        "undamped" => "Undamped natural frequencies in the measured band.".to_string(),
        _ => format!(
            "Natural frequencies not computed: {} equations, above the {} the dense modal analyses take.",
            outcome.system.n(),
            rfm_update::study::MAX_UNDAMPED_DOFS
        ),
    };
    let (header, rows) = frequency_rows(nf);
    let mut t = Table::new(&header).caption(&caption);
    for row in rows {
        t.row(row);
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn many_updating_lines_are_summarised_and_few_listed() {
        assert_eq!(lines_summary(&[10.0, 20.5]), "10, 20.5 Hz");
        let many: Vec<f64> = (1..=200).map(|k| 3.0 * f64::from(k)).collect();
        let s = lines_summary(&many);
        assert!(s.starts_with("200 lines from 3 to 600 Hz"), "{s}");
        assert!(!s.contains("9,"), "{s}");
    }
}
