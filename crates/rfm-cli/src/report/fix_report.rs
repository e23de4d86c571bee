//! The report of the loop (`rfm fix --out DIR`): its headline is the misfit
//! after each step against the noise, with each step's dBIC, why the loop
//! stopped, what remains unexplained and the effects the data could not
//! tell apart, beside the structure with each added effect marked where it
//! sits; then what was set right before the model was blamed (the findings
//! about the data, step 0), each step's effect, the others tried and its
//! updated parameters, what still stands out, the nominal and final models
//! against the measured FRFs (in the data's own kind and unit, corrected as
//! the findings say, each model times the gains that fit it), and the final
//! model's modes against the measured ones with the natural frequencies and
//! damping of every step's model. The terminal says the same in
//! `commands/fix.rs`.

use std::path::PathBuf;

use frf::correlation::BandSpec;
use rfm_update::Study;
use rfm_update::comparison::{self, GainSource};
use rfm_update::diagnose::Ranked;
use rfm_update::fix::{CONSISTENT, FixOutcome, LookAhead};
use rfm_update::quantities::{self, MisfitReport};

use super::html::{Block, Report, Section, Table, Tone};
use super::plot::structure::Highlight;
use super::units::parameter_unit;
use super::{Data, ModelFrfs, ReportOptions, Result, gain_reports, gains_text, loop_story, plot};
use crate::output::Outputs;
use crate::table::{self, num, percent};

/// The name of the case file written after step `k` (1-based; 0 for the
/// case's own parameters updated before any effect is added): the
/// command writes it, the report names it beside the step (here, below the
/// command, so that the two do not import each other).
pub(crate) fn step_file(k: usize) -> String {
    format!("step-{k}.toml")
}

/// The steps an earlier, interrupted run into the same folder finished,
/// when this run resumed after them (`rfm fix --resume`).
pub(crate) struct Resumed {
    /// Whether this run resumed an earlier one at all.
    pub(crate) earlier: bool,
    /// How many effects its finished steps added.
    pub(crate) steps: usize,
    /// The history of the case this run started from (the last of them):
    /// the misfit after each of the earlier steps.
    pub(crate) history: Vec<fe_model::HistoryEntry>,
}

/// How an effect is marked on the structure (see [`loop_story::highlight_kind`]).
pub(crate) fn highlight(e: &Ranked) -> Highlight {
    let kind = loop_story::highlight_kind(Some(e.kind), !e.elements.is_empty());
    Highlight { label: e.description.clone(), kind, nodes: e.nodes.clone(), elements: e.elements.clone(), number: None }
}

/// An effect in a few words for an axis label (see [`loop_story::short_effect`]).
fn short_effect(e: &Ranked) -> String {
    loop_story::short_effect(Some(e.kind), &e.nodes, &e.elements)
}

/// The dBIC of each of [`FixOutcome::stages`], formatted as the terminal
/// and the report show it: step 0's and each update's own evidence (the
/// model after it over the model before, both updated), blank for the
/// stages that fit nothing.
pub(crate) fn stage_dbics(o: &FixOutcome) -> Vec<String> {
    let mut bics: Vec<String> = vec![String::new()];
    if o.findings.iter().any(|f| !f.corrections.is_empty()) {
        bics.push(String::new());
    }
    if let Some(d) = &o.declared {
        bics.push(table::dbic(d.delta_bic));
    }
    for s in &o.steps {
        bics.push(String::new());
        bics.push(table::dbic(s.delta_bic));
        if s.corrected_misfit.is_some() {
            bics.push(String::new());
        }
    }
    bics
}

/// What a stage updated again from a better start says ([`Refit`]).
pub(crate) fn refit_text(r: &rfm_update::fix::Refit, times: impl Fn(f64) -> String) -> String {
    format!(
        "its first update ended at {} ({} x noise), in a local minimum: the next effect tried, {}, reached {} but \
         was not needed there (dBIC {} without it at the values its fit reached, not below {}); it was not added, \
         and every parameter was updated again from those values (the misfit above)",
        table::misfit(r.first_misfit),
        times(r.first_misfit),
        r.found_by,
        table::misfit(r.misfit_with_it),
        table::dbic(r.delta_bic_there),
        quantities::SIGNIFICANT_DBIC
    )
}

/// A stage label of a resumed run with its step number counted from the
/// first run's start: `updated after step 1` after 2 earlier steps reads
/// `updated after step 3`; its step 0 updates the parameters of the
/// steps before again.
pub(crate) fn renumbered(label: &str, done: usize) -> String {
    let after = |prefix: &str, rest: &str| -> Option<String> {
        let (n, tail) = rest.split_once(' ').map_or((rest, ""), |(n, t)| (n, t));
        let n = n.parse::<usize>().ok()?;
        Some(format!("{prefix}{}{}{tail}", n + done, if tail.is_empty() { "" } else { " " }))
    };
    if let Some(r) = label.strip_prefix("updated after step ").and_then(|rest| after("updated after step ", rest)) {
        return r;
    }
    if let Some(r) =
        label.strip_prefix("data corrected after step ").and_then(|rest| after("data corrected after step ", rest))
    {
        return r;
    }
    match label {
        "nominal" => format!("after step {done} (where this run resumed)"),
        // the case it resumed from declares every parameter so far
        "the case's own parameters updated (step 0)" => "every parameter updated again (where it resumed)".into(),
        _ => label.to_string(),
    }
}

/// The stages of [`FixOutcome::stages`] in a few words for the figure's
/// axis, the steps numbered after `offset` earlier ones.
fn short_stages(o: &FixOutcome, offset: usize) -> Vec<String> {
    let mut v = Vec::new();
    if o.findings.iter().any(|f| !f.corrections.is_empty()) {
        v.push("data corrected".to_string());
    }
    if o.declared.is_some() {
        v.push(if offset > 0 { "updated again" } else { "step 0" }.to_string());
    }
    for (k, s) in o.steps.iter().enumerate() {
        let sign = if s.removed { "-" } else { "+" };
        let k = k + offset;
        v.push(format!("{sign} {}: {}", k + 1, short_effect(&s.effect)));
        v.push(format!("updated {}", k + 1));
        if s.corrected_misfit.is_some() {
            v.push(format!("corrected {}", k + 1));
        }
    }
    v
}

/// A table of effects tried (the alternatives of a step, or those the data
/// could not tell apart), with the misfit each left and its evidence.
fn tried_table(tried: &[LookAhead], noise: f64, caption: &str) -> Table {
    let times = |m: f64| table::times(quantities::times_noise(m, noise));
    let mut t = Table::new(&["effect", "misfit after it", "x noise", "dBIC", "why not kept"]).caption(caption);
    for a in tried {
        let effect = match &a.with {
            Some(with) => format!("{} together with {with}", a.effect),
            None => a.effect.clone(),
        };
        let why = a.rejected.clone().unwrap_or_else(|| "kept".into());
        let tone = if a.equally_good { Tone::Good } else { Tone::Plain };
        match &a.failed {
            Some(e) => t.row_toned(vec![
                (effect, Tone::Plain),
                (format!("could not be added: {e}"), Tone::Plain),
                ("-".into(), Tone::Plain),
                ("-".into(), Tone::Plain),
                (why, Tone::Plain),
            ]),
            None => t.row_toned(vec![
                (effect, tone),
                (table::misfit(a.misfit_ahead), Tone::Plain),
                (times(a.misfit_ahead), Tone::Plain),
                (table::dbic(a.delta_bic), Tone::Plain),
                (why, Tone::Plain),
            ]),
        }
    }
    t
}

/// Writes the report files of the loop through `out` and returns where
/// `report.html` will be.
pub(crate) fn write(
    study: &Study,
    outcome: &FixOutcome,
    resumed: &Resumed,
    opts: &ReportOptions,
    out: &mut Outputs,
) -> Result<PathBuf> {
    let offset = resumed.steps;
    let system_of = |case: &fe_model::case::CaseEditor| -> Result<damping::DampedSystem> {
        let text = case.text_at(&study.case().path)?;
        Ok(damping::DampedSystem::new(fe_model::CaseFile::parse(&study.case().path, &text)?.model)?)
    };
    // the model after step 0 and after each step; the last has every effect added
    let declared_system = outcome.declared.as_ref().map(|d| system_of(&d.case)).transpose()?;
    let step_systems = outcome.steps.iter().map(|s| system_of(&s.case)).collect::<Result<Vec<_>>>()?;
    let fixed = step_systems.last().or(declared_system.as_ref());
    let mut report = Report::new(format!("{}: closing the loop", study.case().model.title));
    report.subtitle = Some(format!(
        "rfm fix, case file {}: {} effect(s) added{}; {}",
        study.case().path.display(),
        outcome.effects.len(),
        if offset > 0 { format!(" after the {offset} of an earlier run it resumed") } else { String::new() },
        outcome.stop.describe()
    ));

    // a resumed run's stages follow the earlier run's, as the case it
    // started from records them
    let mut stages: Vec<(String, f64)> = resumed.history.iter().map(|h| (h.step.clone(), h.misfit)).collect();
    let mut bics: Vec<String> = vec![String::new(); resumed.history.len()];
    let skip = usize::from(resumed.earlier);
    stages.extend(
        outcome
            .stages()
            .into_iter()
            .skip(skip)
            .map(|(label, m)| (if offset > 0 { renumbered(&label, offset) } else { label }, m)),
    );
    bics.extend(stage_dbics(outcome).into_iter().skip(skip));
    let mut fall = Section::new("The misfit after each step");
    let earlier: Vec<String> = if resumed.earlier {
        resumed.history.iter().map(|h| h.step.chars().take(24).collect()).collect()
    } else {
        vec!["nominal".to_string()]
    };
    let short: Vec<String> = earlier.into_iter().chain(short_stages(outcome, offset)).collect();
    let misfits: Vec<f64> = stages.iter().map(|(_, m)| *m).collect();
    fall.push(out.figure(
        "misfit-steps",
        plot::misfit_steps(&short, &misfits, outcome.noise, CONSISTENT)?,
        format!(
            "The misfit (RMS of |ln(model / measured)| per complex value, over the {} lines the diagnosis reads) of \
             the nominal model (and where there were any, on the data corrected as the findings below say, and \
             after updating the case's own parameters, step 0), after adding each effect at its diagnosed values \
             (numbered as on the structure below), and after updating every parameter together. The green band runs from the noise level \
             estimated from the data ({}) to {CONSISTENT} times it: a misfit inside it is consistent with the noise.",
            quantities::MISFIT_LINES,
            table::misfit(outcome.noise)
        ),
    )?);
    // the effects in the fixed model (a replaced one is not), those of an
    // earlier run first
    let drawn = fixed.map_or(&study.case().model, |f| f.model());
    let mut highlights: Vec<Highlight> = loop_story::highlights(&resumed.history, drawn);
    highlights.extend(outcome.effects.iter().map(highlight));
    fall.push(super::structure_figure(
        drawn,
        study.measured(),
        &highlights,
        if highlights.is_empty() {
            "Nothing was added: the model after the last update."
        } else {
            "The model after the last step, each added effect numbered by its step and marked where it sits (a \
             ring at a joint, a support or a mass, a broad band along the elements of a changed region, a mass on \
             a spring for a resonator)."
        },
        out,
    )?);
    let mut t = Table::new(&["step", "misfit", "x noise", "dBIC of the step"]).caption(format!(
        "The misfit of each stage and its multiple of the noise ({}); green within {CONSISTENT} times it. The dBIC \
         of a step is its own evidence: the model after it against the model before, both updated, every parameter \
         counted; a step is kept only when it is below {} (significant).",
        table::misfit(outcome.noise),
        quantities::SIGNIFICANT_DBIC
    ));
    for ((label, m), bic) in stages.iter().zip(bics) {
        let tone = if *m <= CONSISTENT * outcome.noise { Tone::Good } else { Tone::Plain };
        t.row_toned(vec![
            (label.clone(), Tone::Plain),
            (table::misfit(*m), tone),
            (table::times(quantities::times_noise(*m, outcome.noise)), tone),
            (bic, Tone::Plain),
        ]);
    }
    fall.push(out.table("steps", t)?);
    let last = outcome.final_misfit();
    let times = table::times(quantities::times_noise(last, outcome.noise));
    fall.push(Block::Text(if outcome.explained() {
        format!("The final misfit is {times} times the noise: the model explains the data down to their noise.")
    } else if last <= CONSISTENT * outcome.noise {
        format!("The final misfit is {times} times the noise.")
    } else {
        format!("The final misfit is {times} times the noise: something the model lacks remains.")
    }));
    fall.push(Block::Facts(vec![("stopped".into(), outcome.stop_reason.clone())]));
    // (said once: above the noise, it is among what remains)
    let in_remains = outcome.remains.iter().any(|r| r.starts_with("the mesh:"));
    if let Some(b) =
        super::mesh_text(outcome.mesh.as_ref(), outcome.noise, super::mesh_reading(outcome)).filter(|_| !in_remains)
    {
        fall.push(b);
    }
    if !outcome.remains.is_empty() {
        fall.push(Block::Text(format!("What remains unexplained: {}.", outcome.remains.join("; "))));
    }
    if !outcome.equally_good.is_empty() {
        fall.push(out.table(
            "equally-good",
            tried_table(
                &outcome.equally_good,
                outcome.noise,
                "Effects at different places that explain the data equally well: the evidence between them is not \
                 significant, so the data cannot tell them apart (more channels, or a band with more modes, may).",
            ),
        )?);
    }
    report.sections.push(fall);

    let mut setup = Section::new("Before the model was blamed: the data and the case's own parameters");
    let before = super::setup::Before {
        noise: outcome.noise,
        nominal: outcome.nominal_misfit,
        corrected: outcome.corrected_misfit,
    };
    for block in super::setup::blocks(&outcome.findings, outcome.declared.as_ref(), before, out)? {
        setup.push(block);
    }
    report.sections.push(setup);

    for (k, s) in outcome.steps.iter().enumerate() {
        let k = k + offset;
        let e = &s.effect;
        let title = match &s.replaced {
            _ if s.removed => format!("Step {}: {} taken out again", k + 1, e.description),
            Some(r) => format!("Step {}: {} instead of {r}", k + 1, e.description),
            None => format!("Step {}: {}", k + 1, e.description),
        };
        let mut sec = Section::new(title);
        let times = |m: f64| table::times(quantities::times_noise(m, outcome.noise));
        let mut facts = vec![
            ("explained".into(), format!("{} of the squared misfit before it", super::percent(e.explained))),
            ("dBIC in the diagnosis".into(), format!("{} (against the other candidates)", table::dbic(e.delta_bic))),
            (
                "dBIC of the step".into(),
                if s.removed {
                    format!(
                        "{} (the model without the effect against the model with it, both updated: an effect stays \
                         only while it would be significant added to the model without it)",
                        table::dbic(s.delta_bic)
                    )
                } else {
                    format!(
                        "{} (the model after the step against the model before, both updated; significant below {})",
                        table::dbic(s.delta_bic),
                        quantities::SIGNIFICANT_DBIC
                    )
                },
            ),
            ("misfit with it".into(), format!("{} ({} x noise)", table::misfit(s.misfit_added), times(s.misfit_added))),
            (
                "after the update".into(),
                format!(
                    "{} ({} x noise), {}",
                    table::misfit(s.misfit_updated),
                    times(s.misfit_updated),
                    s.status.name()
                ),
            ),
        ];
        if let Some(why) = &s.removed_because {
            facts.push(("why taken out".into(), why.clone()));
        }
        if let Some(m) = s.corrected_misfit {
            facts.push((
                "after the data found wrong since were corrected".into(),
                format!("{} ({} x noise), every parameter updated again", table::misfit(m), times(m)),
            ));
        }
        if let Some(r) = &s.refit {
            facts.push(("updated again".into(), refit_text(r, times)));
        }
        facts.push(("case file".into(), step_file(k + 1)));
        if !e.gains.is_empty() {
            facts.push(("gain fitted with it".into(), gains_text(&gain_reports(&e.gains))));
        }
        sec.push(Block::Facts(facts));
        if !s.alternatives.is_empty() {
            sec.push(Block::Table(tried_table(
                &s.alternatives,
                outcome.noise,
                "The other effects tried at this step, each added and every parameter updated (a pair fitted \
                 together where the best single effect left more than three times the noise), with the evidence for \
                 it over the model before the step and why it was not kept.",
            )));
        }
        if !e.held.is_empty() {
            sec.push(Block::Text(format!(
                "Held at their rigid or nominal value because the data do not determine them: {}.",
                e.held.join(", ")
            )));
        }
        let mut t = Table::new(&["parameter", "unit", "diagnosed", "updated", "+-1 sd (noise)"])
            .caption("Every parameter updated at this step: the effects added so far and the case's own.");
        for (i, p) in s.parameters.iter().enumerate() {
            let diagnosed = e.parameters.iter().find(|f| f.name == p.name).map_or("-".to_string(), |f| num(f.value));
            let sd = s
                .uncertainty
                .as_ref()
                .and_then(|u| u.parameters.get(i))
                .map_or("-".to_string(), |u| percent(u.relative_std));
            t.row(vec![p.name.clone(), parameter_unit(&p.name).to_string(), diagnosed, num(p.updated), sd]);
        }
        sec.push(out.table(&format!("step-{}-parameters", k + 1), t)?);
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
    let mut t = Table::new(&["effect", "explained", "dBIC", "significant", "plausible"]).caption(format!(
        "The leaders of the diagnosis of the final model; significant: dBIC below {} (see the glossary).",
        quantities::SIGNIFICANT_DBIC
    ));
    for r in &outcome.remaining {
        t.row(vec![
            r.description.clone(),
            super::percent(r.explained),
            table::dbic(r.delta_bic),
            if r.significant { "yes".into() } else { "no".into() },
            if r.plausible { "yes".into() } else { r.implausible_reason.clone().unwrap_or_default() },
        ]);
    }
    rest.push(out.table("remaining", t)?);
    report.sections.push(rest);

    // the nominal and the final model against the data as they were
    // measured (the kind and unit compare and update show), corrected as
    // the findings say, each times the gains that bring it closest to them
    // when the case fits gains
    let as_read = rfm_update::checks::corrected(&study.measured_as_read(), &outcome.findings)?;
    let measured = &as_read;
    let corrected = rfm_update::checks::corrected(study.measured(), &outcome.findings)?;
    // read as the loop reads it: against the nominal and the fixed model,
    // the lower (the data's own roughness reads high over dense modes; a
    // model near the structure leaves only the noise in its residual)
    let mut unweighted = quantities::noise(study.system(), &corrected, None)?;
    if let Some(f) = fixed
        && let Some(n) = quantities::noise(f, &corrected, None)?
    {
        unweighted = Some(unweighted.map_or(n, |u| u.min(n)));
    }
    let data = Data::new(measured, study.per_volt(), unweighted);
    let weights = study.line_weights(measured)?;
    let gains = match study.gains() {
        fe_model::case::Gains::None => GainSource::None,
        setting => GainSource::Fit { setting, weights: weights.as_deref() },
    };
    let report_of = |m: f64| MisfitReport {
        misfit: m,
        noise: Some(outcome.noise),
        times_noise: Some(quantities::times_noise(m, outcome.noise)),
        lines: quantities::MISFIT_LINES.min(measured.n_freq()),
        weighted: weights.is_some(),
    };
    let model = |label: &str, colour, sys: &damping::DampedSystem, misfit: f64| -> Result<(ModelFrfs, Vec<frf::C64>)> {
        let compared = comparison::compare(sys, measured, gains, &BandSpec::Auto)?;
        if let Some(&freq_hz) = compared.model.singular_hz.first() {
            return Err(frf::FrfError::Singular { freq_hz }.into());
        }
        let frfs = ModelFrfs {
            label: label.into(),
            colour,
            frfs: compared.model.frfs,
            correlation: compared.correlation,
            gains: compared.model.fitted.as_ref().map_or_else(Vec::new, |f| f.reports()),
            misfit: Some(report_of(misfit)),
        };
        Ok((frfs, compared.model.gains))
    };
    let start_label = if offset > 0 { format!("model after step {offset}") } else { "nominal model".to_string() };
    let (nominal, mut last_gains) = model(&start_label, plot::INITIAL, study.system(), outcome.corrected_misfit)?;
    let mut models = vec![nominal];
    if let Some(f) = fixed {
        let (fixed_frfs, gains) = model("fixed model", plot::UPDATED, f, outcome.final_misfit())?;
        models.push(fixed_frfs);
        last_gains = gains;
    }
    let mut notes = vec![if outcome.findings.iter().any(|f| !f.corrections.is_empty()) {
        "The nominal model and the model after the last step against the measured FRFs, corrected as the findings \
         about the data say."
            .to_string()
    } else {
        "The nominal model and the model after the last step against the measured FRFs.".to_string()
    }];
    if !matches!(gains, GainSource::None) {
        notes.push(format!(
            "Each model's FRFs are multiplied by the unknown complex gains that fit it best: {}.",
            models
                .iter()
                .map(|m| format!("the {} by {}", m.label, gains_text(&m.gains)))
                .collect::<Vec<_>>()
                .join("; ")
        ));
    }
    report.sections.push(super::correlation_section(&data, &models, opts, out, notes)?);
    let last_system = fixed.unwrap_or(study.system());
    let comparison =
        comparison::compare_modes(last_system, measured, &last_gains, super::modes::MIN_MAC).map_err(|e| e.to_string());
    let against = if fixed.is_some() { "the fixed model" } else { "the nominal model" };
    let mut modes = super::modes::section(
        comparison.as_ref(),
        against,
        last_system.model(),
        measured,
        last <= CONSISTENT * outcome.noise,
        opts,
        out,
    )?;
    let f = measured.frequencies_hz();
    let band = (f.first().copied().unwrap_or(0.0), f.last().copied().unwrap_or(0.0));
    let first = if offset > 0 { format!("step {offset}") } else { "nominal".to_string() };
    let mut systems: Vec<(String, &damping::DampedSystem)> = vec![(first, study.system())];
    if let (Some(d), false) = (&declared_system, resumed.earlier) {
        systems.push(("step 0".into(), d));
    }
    systems.extend(step_systems.iter().enumerate().map(|(k, s)| (format!("step {}", k + offset + 1), s)));
    let table = super::natural_frequency_table(&systems, band, comparison.as_ref().ok());
    modes.push(out.table("modes-per-step", table)?);
    report.sections.push(modes);
    report.sections.push(super::overlay_section(&data, &models, &[], opts, out)?);
    report.sections.push(super::definitions_section());
    Ok(out.write("report.html", report.render().as_bytes())?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resumed_runs_stages_count_from_the_first_runs_start() {
        assert_eq!(renumbered("updated after step 1", 2), "updated after step 3");
        assert_eq!(renumbered("data corrected after step 1 and updated", 2), "data corrected after step 3 and updated");
        assert_eq!(renumbered("nominal", 2), "after step 2 (where this run resumed)");
        assert_eq!(renumbered("+ lumped mass at node 9", 2), "+ lumped mass at node 9");
        assert_eq!(
            renumbered("the case's own parameters updated (step 0)", 2),
            "every parameter updated again (where it resumed)"
        );
    }
}
