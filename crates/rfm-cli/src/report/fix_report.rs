//! The report of the loop (`rfm fix --out DIR`): its headline is the misfit
//! after each step against the noise, beside the structure with each added
//! effect marked where it sits; then each step's effect and updated
//! parameters, what still stands out, the nominal and final models against
//! the measured FRFs, and the final model's modes against the measured ones.

use std::path::PathBuf;

use frf::correlation::BandSpec;
use rfm_update::Study;
use rfm_update::comparison::{self, GainSource};
use rfm_update::diagnose::Ranked;
use rfm_update::fix::{CONSISTENT, FixOutcome};

use super::html::{Block, Report, Section, Table, Tone};
use super::plot::structure::Highlight;
use super::{ModelFrfs, ReportOptions, Result, loop_story, plot, sig};
use crate::output::Outputs;
use crate::table::{num, percent};

/// The name of the case file written after step `k` (1-based): the
/// command writes it, the report names it beside the step (here, below the
/// command, so that the two do not import each other).
pub(crate) fn step_file(k: usize) -> String {
    format!("step-{k}.toml")
}

/// How an effect is marked on the structure (see [`loop_story::highlight_kind`]).
fn highlight(e: &Ranked) -> Highlight {
    let kind = loop_story::highlight_kind(Some(e.kind), !e.elements.is_empty());
    Highlight { label: e.description.clone(), kind, nodes: e.nodes.clone(), elements: e.elements.clone() }
}

/// An effect in a few words for an axis label (see [`loop_story::short_effect`]).
fn short_effect(e: &Ranked) -> String {
    loop_story::short_effect(Some(e.kind), &e.nodes, &e.elements)
}

/// Writes the report files of the loop through `out` and returns where
/// `report.html` will be.
pub(crate) fn write(study: &Study, outcome: &FixOutcome, opts: &ReportOptions, out: &mut Outputs) -> Result<PathBuf> {
    // the model after the last step, with every effect added
    let fixed = match outcome.steps.last() {
        Some(s) => {
            let text = s.case.text_at(&study.case().path)?;
            Some(damping::DampedSystem::new(fe_model::CaseFile::parse(&study.case().path, &text)?.model)?)
        }
        None => None,
    };
    let mut report = Report::new(format!("{}: closing the loop", study.case().model.title));
    report.subtitle = Some(format!(
        "rfm fix, case file {}: {} effect(s) added; {}",
        study.case().path.display(),
        outcome.steps.len(),
        outcome.stop.describe()
    ));

    let stages = outcome.stages();
    let mut fall = Section::new("The fall of the misfit");
    let short: Vec<String> = std::iter::once("nominal".to_string())
        .chain(outcome.steps.iter().enumerate().flat_map(|(k, s)| {
            let sign = if s.removed { "-" } else { "+" };
            [format!("{sign} {}: {}", k + 1, short_effect(&s.effect)), format!("updated {}", k + 1)]
        }))
        .collect();
    let misfits: Vec<f64> = stages.iter().map(|(_, m)| *m).collect();
    fall.push(out.figure(
        "misfit-steps",
        plot::misfit_steps(&short, &misfits, outcome.noise, CONSISTENT)?,
        format!(
            "The misfit (RMS of ln(model / measured) per complex value, over {} lines spread across the band) of \
             the nominal model, after adding each effect at its diagnosed values (numbered as on the structure \
             below), and after updating every added parameter together. The green band runs from the noise level estimated from the data to {CONSISTENT} \
             times it: a misfit inside it is consistent with the noise.",
            rfm_update::diagnose::DiagnoseOptions::default().lines
        ),
    )?);
    // the effects in the fixed model (a replaced one is not)
    let highlights: Vec<Highlight> = outcome.effects.iter().map(highlight).collect();
    let drawn = fixed.as_ref().map_or(&study.case().model, |f| f.model());
    fall.push(super::structure_figure(
        drawn,
        study.measured(),
        &highlights,
        if highlights.is_empty() {
            "Nothing was added: the nominal model."
        } else {
            "The model after the last step, each added effect numbered by its step and marked where it sits (a \
             ring at a joint, a support or a mass, a broad band along the elements of a changed region)."
        },
        out,
    )?);
    let mut t = Table::new(&["step", "misfit", "(dB)", "x noise"]);
    for (label, m) in &stages {
        let tone = if *m <= CONSISTENT * outcome.noise { Tone::Good } else { Tone::Plain };
        t.row_toned(vec![
            (label.clone(), Tone::Plain),
            (sig(*m, 4), tone),
            (format!("{:.1}", 20.0 * m.log10()), Tone::Plain),
            (format!("{:.1}", m / outcome.noise), tone),
        ]);
    }
    fall.push(Block::Table(t));
    let last = outcome.final_misfit();
    fall.push(Block::Text(if last <= CONSISTENT * outcome.noise {
        format!(
            "The final misfit is {:.2} times the noise: the model explains the data down to their noise.",
            last / outcome.noise
        )
    } else {
        format!(
            "The final misfit is {:.1} times the noise: something the candidate effects cannot represent remains.",
            last / outcome.noise
        )
    }));
    fall.push(Block::Text(format!("The loop stopped because {}.", outcome.stop.describe())));
    report.sections.push(fall);

    for (k, s) in outcome.steps.iter().enumerate() {
        let e = &s.effect;
        let title = match &s.replaced {
            _ if s.removed => format!("Step {}: {} taken out again", k + 1, e.description),
            Some(r) => format!("Step {}: {} instead of {r}", k + 1, e.description),
            None => format!("Step {}: {}", k + 1, e.description),
        };
        let mut sec = Section::new(title);
        sec.push(Block::Facts(vec![
            ("explained".into(), format!("{:.1} % of the misfit before it", 100.0 * e.explained)),
            ("dBIC".into(), format!("{:.1} (below -10: very strong evidence)", e.delta_bic)),
            (
                "misfit with it".into(),
                format!("{} ({:.1} x noise)", sig(s.misfit_added, 4), s.misfit_added / outcome.noise),
            ),
            (
                "after the update".into(),
                format!(
                    "{} ({:.1} x noise), {}",
                    sig(s.misfit_updated, 4),
                    s.misfit_updated / outcome.noise,
                    s.status.name()
                ),
            ),
            ("case file".into(), step_file(k + 1)),
        ]));
        if !s.alternatives.is_empty() {
            let mut t = Table::new(&["first effect tried", "misfit after it and its best follower", "x noise"])
                .caption(
                    "The best single effect left more than three times the noise, so two effects may hide at once: \
                 the pairs of the leading effects were added and updated together (the best pair is shown), and \
                 unless it reached the noise each leader was added and updated, the data diagnosed again; the \
                 pair, or the leader whose best follower, left the smallest misfit was kept.",
                );
            for a in &s.alternatives {
                let effect = match &a.with {
                    Some(with) => format!("{} together with {with}", a.effect),
                    None => a.effect.clone(),
                };
                match &a.failed {
                    Some(why) => t.row(vec![effect, format!("could not be added: {why}"), "-".into()]),
                    None => {
                        t.row(vec![effect, sig(a.misfit_ahead, 4), format!("{:.1}", a.misfit_ahead / outcome.noise)])
                    }
                }
            }
            sec.push(Block::Table(t));
        }
        if !e.held.is_empty() {
            sec.push(Block::Text(format!(
                "Held at their rigid or nominal value because the data do not determine them: {}.",
                e.held.join(", ")
            )));
        }
        let mut t = Table::new(&["parameter", "diagnosed", "updated", "+-1 sd (noise)"])
            .caption("Every parameter updated at this step: the effects added so far and the case's own.");
        for (i, p) in s.parameters.iter().enumerate() {
            let diagnosed = e.parameters.iter().find(|f| f.name == p.name).map_or("-".to_string(), |f| num(f.value));
            let sd = s
                .uncertainty
                .as_ref()
                .and_then(|u| u.parameters.get(i))
                .map_or("-".to_string(), |u| percent(u.relative_std));
            t.row(vec![p.name.clone(), diagnosed, num(p.updated), sd]);
        }
        sec.push(Block::Table(t));
        report.sections.push(sec);
    }

    let mut rest = Section::new("What the last diagnosis finds");
    rest.push(Block::Text(if let Some(e) = &outcome.diagnosis_error {
        format!("The diagnosis of the final model failed, so what remains is not known: {e}.")
    } else if outcome.significant_remains {
        "Some candidates are still significant in the diagnosis of the final model:".to_string()
    } else {
        "No candidate is significant in the diagnosis of the final model.".to_string()
    }));
    let mut t = Table::new(&["effect", "explained", "dBIC", "plausible"]);
    for r in &outcome.remaining {
        t.row(vec![
            r.description.clone(),
            format!("{:.1} %", 100.0 * r.explained),
            format!("{:.1}", r.delta_bic),
            if r.plausible { "yes".into() } else { r.implausible_reason.clone().unwrap_or_default() },
        ]);
    }
    rest.push(Block::Table(t));
    report.sections.push(rest);

    // the nominal and the final model against the data, each times the
    // gains that bring it closest to them when the case fits gains
    let measured = study.measured();
    let weights = study.line_weights(measured)?;
    let gains = match study.gains() {
        fe_model::case::Gains::None => GainSource::None,
        setting => GainSource::Fit { setting, weights: weights.as_deref() },
    };
    let model = |label: &str, colour, sys: &damping::DampedSystem| -> Result<(ModelFrfs, Vec<frf::C64>)> {
        let compared = comparison::compare(sys, measured, gains, &BandSpec::Auto)?;
        if let Some(&freq_hz) = compared.model.singular_hz.first() {
            return Err(frf::FrfError::Singular { freq_hz }.into());
        }
        let frfs =
            ModelFrfs { label: label.into(), colour, frfs: compared.model.frfs, correlation: compared.correlation };
        Ok((frfs, compared.model.gains))
    };
    let (nominal, mut last_gains) = model("nominal model", plot::INITIAL, study.system())?;
    let mut models = vec![nominal];
    if let Some(f) = &fixed {
        let (fixed_frfs, gains) = model("fixed model", plot::UPDATED, f)?;
        models.push(fixed_frfs);
        last_gains = gains;
    }
    let mut notes = vec!["The nominal model and the model after the last step against the measured FRFs.".to_string()];
    if !matches!(gains, GainSource::None) {
        notes.push("Each model's FRFs are multiplied by the unknown complex gains that fit it best.".to_string());
    }
    report.sections.push(super::correlation_section(measured, &models, opts, out, notes)?);
    let last_system = fixed.as_ref().unwrap_or(study.system());
    let comparison =
        comparison::compare_modes(last_system, measured, &last_gains, super::modes::MIN_MAC).map_err(|e| e.to_string());
    let against = if fixed.is_some() { "the fixed model" } else { "the nominal model" };
    report.sections.push(super::modes::section(
        comparison.as_ref(),
        against,
        last_system.model(),
        measured,
        opts,
        out,
    )?);
    report.sections.push(super::overlay_section(measured, &models, &[], opts, out)?);
    report.sections.push(super::definitions_section());
    Ok(out.write("report.html", report.render().as_bytes())?)
}
