//! The report of a diagnosis (`rfm diagnose --report DIR`): what the checks
//! found about the data (with the evidence and the correction applied),
//! step 0 (the case's own parameters updated), the noise and the diagnosed
//! model's misfit, the structure with the leading candidates marked where
//! they act, the ranking (also as CSV), and, when an effect is recommended,
//! the diagnosed model and the model with it added at its fitted values
//! against the measured FRFs (corrected as the findings say).

use std::path::PathBuf;

use frf::correlation::BandSpec;
use rfm_update::Study;
use rfm_update::comparison::{self, GainSource};
use rfm_update::diagnose::Diagnosis;
use rfm_update::fix::Prepared;
use rfm_update::quantities::{self, MisfitReport};

use super::html::{Block, Report, Section, Table, Tone};
use super::plot::structure::Highlight;
use super::{Data, ModelFrfs, ReportOptions, Result, gain_reports, gains_text, plot};
use crate::output::Outputs;
use crate::table::{self, num, percent};

/// Leading candidates marked on the structure.
const MARKED: usize = 5;

/// Rows of the ranking in the report (the CSV holds every one).
const RANKED_ROWS: usize = 40;

/// Writes the report of diagnosis `d` of `study`'s model, as `prepared`
/// made it ready (the data corrected, the case's own parameters updated),
/// against the measured FRFs as read (`as_read`, per volt at the references
/// `per_volt`; from `source`), and returns where `report.html` will be.
pub(crate) fn write(
    study: &Study,
    prepared: &Prepared,
    d: &Diagnosis,
    (as_read, per_volt): (&frf::FrfSet, &[fe_model::DofRef]),
    source: &str,
    opts: &ReportOptions,
    out: &mut Outputs,
) -> Result<PathBuf> {
    // the model the diagnosis read: corrected and its own parameters updated
    let case = &prepared.case;
    let diagnosed = damping::DampedSystem::new(case.model.clone())?;
    // the data as they were measured (their kind), corrected as the findings say
    let corrected = rfm_update::checks::corrected(as_read, &prepared.findings)?;
    let unweighted = if d.weighted { quantities::noise(&diagnosed, &prepared.data, None)? } else { Some(d.noise) };
    let data = &Data::new(&corrected, per_volt, unweighted);
    let mut report = Report::new(format!("{}: what is missing", case.model.title));
    report.subtitle = Some(format!("rfm diagnose, case file {}", study.case().path.display()));
    let measured = data.set;
    let f = measured.frequencies_hz();

    let mut summary = Section::new("Summary");
    let mut facts = vec![
        ("case".to_string(), study.case().path.display().to_string()),
        ("data".into(), source.to_string()),
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
        ("noise".into(), table::misfit(d.noise)),
        (
            if prepared.declared.is_some() {
                "misfit of the model diagnosed (after step 0)"
            } else {
                "misfit of the nominal model"
            }
            .into(),
            format!(
                "{} ({} x the noise), over the {} lines the diagnosis reads{}",
                table::misfit(d.nominal_misfit),
                table::times(quantities::times_noise(d.nominal_misfit, d.noise)),
                quantities::MISFIT_LINES.min(f.len()),
                if d.weighted { ", each value weighted by its coherence" } else { "" }
            ),
        ),
        (
            "candidates".into(),
            format!(
                "{} tried, {} replaced by a variant{}",
                d.tried,
                d.superseded,
                crate::commands::diagnose::deferred_text(d)
            ),
        ),
    ];
    if let Some(l) = d.ranking.first().filter(|l| !l.gains.is_empty()) {
        facts.push(("gain fitted with the first".into(), gains_text(&gain_reports(&l.gains))));
    }
    summary.push(Block::Facts(facts));
    let before = super::setup::Before {
        noise: prepared.noise,
        nominal: prepared.nominal_misfit,
        corrected: prepared.corrected_misfit,
    };
    for block in super::setup::blocks(&prepared.findings, prepared.declared.as_ref(), before, out)? {
        summary.push(block);
    }
    summary.push(Block::Text(match d.leader() {
        Some(l) => format!(
            "Most likely missing (rank {}): {}. It explains {:.1} % of the nominal model's squared misfit and leaves \
             {} ({} x the noise).",
            d.recommended.unwrap_or(1),
            l.description,
            100.0 * l.explained,
            table::misfit(l.misfit),
            table::times(quantities::times_noise(l.misfit, d.noise))
        ),
        None if d.consistent() => {
            "No candidate explains the misfit beyond the noise: the model is consistent with the data.".into()
        }
        None => "Some effects are significant, but none at plausible values: the missing effect may not be among \
                 the candidates."
            .into(),
    }));
    if let Some(b) = super::mesh_text(prepared.mesh.as_ref(), prepared.noise, super::MeshReading::Ranked) {
        summary.push(b);
    }
    // the leading candidates where they act, numbered by their rank
    let mut marked: Vec<Highlight> = Vec::new();
    for (i, r) in d.ranking.iter().enumerate().filter(|(_, r)| r.fully_fitted && r.significant && r.plausible) {
        if marked.len() == MARKED {
            break;
        }
        let mut h = super::fix_report::highlight(r);
        h.number = Some(i + 1);
        if !marked.iter().any(|m| m.nodes == h.nodes && m.elements == h.elements) {
            marked.push(h);
        }
    }
    summary.push(super::structure_figure(
        &case.model,
        measured,
        &marked,
        if marked.is_empty() {
            "The model diagnosed: no candidate is both significant and plausible."
        } else {
            "The model diagnosed with the leading significant, plausible candidates (distinct places, at most five) \
             marked where they act, each numbered by its rank (a ring at a joint, a support or a mass, a broad band \
             along the elements of a changed region)."
        },
        out,
    )?);
    report.sections.push(summary);

    let mut ranking = Section::new("The ranking");
    let mut t = Table::new(&["rank", "effect", "explained", "dBIC", "significant", "plausible", "fitted values"])
        .caption(format!(
            "Every candidate fitted to the data, best first; explained: the share of the nominal model's squared \
             misfit it removes; significant: dBIC below {} (very strong evidence; dBIC compares candidates of this \
             diagnosis only); plausible: its fitted values within their ranges. Only significant, plausible, fully \
             fitted candidates are recommended; \"screened only\" ones were fitted briefly on fewer lines.",
            quantities::SIGNIFICANT_DBIC
        ));
    let mut csv = Table::new(&t.header.iter().map(String::as_str).collect::<Vec<_>>());
    // the table folds the variants alike into their best row; the CSV holds every rank
    let shown = d.shown(RANKED_ROWS);
    for (i, r) in d.ranking.iter().enumerate() {
        let values = r
            .parameters
            .iter()
            .map(|p| {
                let unit = super::units::parameter_unit(&p.name);
                let unit = if unit.is_empty() || unit == "-" { String::new() } else { format!(" {unit}") };
                if p.determined {
                    format!("{} = {}{unit} (+-{})", p.name, num(p.value), percent(p.relative_std))
                } else {
                    format!("{} = {}{unit} (not determined)", p.name, num(p.value))
                }
            })
            .chain(r.held.iter().map(|h| format!("{h} held (not determined)")))
            .collect::<Vec<_>>()
            .join(", ");
        let plausible = match (&r.implausible_reason, r.fully_fitted) {
            (Some(why), _) => format!("no: {why}"),
            (None, false) => "yes (screened only)".into(),
            (None, true) => "yes".into(),
        };
        let recommended = d.recommended == Some(i + 1);
        let row = vec![
            (format!("{}", i + 1), Tone::Plain),
            (r.description.clone(), if recommended { Tone::Good } else { Tone::Plain }),
            (super::percent(r.explained), Tone::Plain),
            (table::dbic(r.delta_bic), Tone::Plain),
            ((if r.significant { "yes" } else { "no" }).to_string(), Tone::Plain),
            (plausible, if r.implausible_reason.is_some() { Tone::Bad } else { Tone::Plain }),
            (values, Tone::Plain),
        ];
        csv.row(row.iter().map(|(c, _)| c.clone()).collect());
        if let Some(s) = shown.iter().find(|s| s.rank == i + 1) {
            let mut row = row;
            let alike = super::alike_text(&s.alike);
            if !alike.is_empty() {
                row[1].0 = format!("{} ({alike})", row[1].0);
            }
            t.row_toned(row);
        }
    }
    out.write("ranking.csv", csv.to_csv().as_bytes())?;
    let folded: usize = shown.iter().map(|s| s.alike.len()).sum();
    t.caption = t.caption.map(|c| {
        let alike = if folded > 0 { format!(" ({}: {folded} folded)", super::ALIKE_LEGEND) } else { String::new() };
        format!("{c} The first {} rows of {} ranks{alike}; every rank is in ranking.csv.", shown.len(), d.ranking.len())
    });
    ranking.push(Block::Table(t));
    report.sections.push(ranking);

    if let Some(rank) = d.recommended {
        // a case whose data come from its [truth] gets the effect without
        // the truth (which may add it too); only the model is read here
        let synthesised = case.measurement.as_ref().is_some_and(|m| m.data.is_none());
        let placeholder = case.path.with_file_name("measured.csv");
        let added = d.apply_with_data(case, rank, synthesised.then_some(placeholder.as_path()))?;
        let text = added.text_at(&case.path)?;
        let with = damping::DampedSystem::new(fe_model::CaseFile::parse(&case.path, &text)?.model)?;
        let weights = study.line_weights(measured)?;
        let gains = match d.gains {
            fe_model::case::Gains::None => GainSource::None,
            setting => GainSource::Fit { setting, weights: weights.as_deref() },
        };
        let misfit = |m: f64| MisfitReport {
            misfit: m,
            noise: Some(d.noise),
            times_noise: Some(quantities::times_noise(m, d.noise)),
            lines: quantities::MISFIT_LINES.min(f.len()),
            weighted: d.weighted,
        };
        let model = |label: String, colour, sys: &damping::DampedSystem, m: f64| -> Result<ModelFrfs> {
            let c = comparison::compare(sys, measured, gains, &BandSpec::Auto)?;
            if let Some(&freq_hz) = c.model.singular_hz.first() {
                return Err(frf::FrfError::Singular { freq_hz }.into());
            }
            Ok(ModelFrfs {
                label,
                colour,
                frfs: c.model.frfs,
                correlation: c.correlation,
                gains: c.model.fitted.as_ref().map_or_else(Vec::new, |g| g.reports()),
                misfit: Some(misfit(m)),
            })
        };
        let leader = &d.ranking[rank - 1];
        let models = [
            model("model diagnosed".into(), plot::INITIAL, &diagnosed, d.nominal_misfit)?,
            model(format!("with rank {rank} added"), plot::UPDATED, &with, leader.misfit)?,
        ];
        let notes = vec![format!(
            "The model diagnosed, and the model with the recommended effect ({}) added at its fitted values, \
             against the measured FRFs.",
            leader.description
        )];
        report.sections.push(super::correlation_section(data, &models, opts, out, notes)?);
        report.sections.push(super::overlay_section(data, &models, &[], opts, out)?);
    }
    report.sections.push(super::definitions_section());
    Ok(out.write("report.html", report.render().as_bytes())?)
}
