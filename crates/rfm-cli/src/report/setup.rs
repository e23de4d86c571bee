//! What `rfm diagnose` and `rfm fix` set right before they blame the model,
//! as their reports show it: the findings about the data (each with its
//! evidence and the correction applied) and step 0 (the case's own
//! `[update]` parameters updated, with the misfit before and after). The
//! terminal says the same in `commands/diagnose.rs` and `commands/fix.rs`.

use rfm_update::checks::{Correction, Finding};
use rfm_update::fix::DeclaredStep;
use rfm_update::quantities;

use super::html::{Block, Table, Tone};
use super::units::parameter_unit;
use super::{Outputs, Result};
use crate::table::{self, num, percent};

/// The misfits the findings and step 0 are read against: the data's noise,
/// the nominal model's misfit on the data as read and on the corrected data.
#[derive(Clone, Copy)]
pub(crate) struct Before {
    /// The noise level of the data.
    pub(crate) noise: f64,
    /// The nominal model's misfit on the data as read.
    pub(crate) nominal: f64,
    /// ... and on the corrected data.
    pub(crate) corrected: f64,
}

/// A correction in words, as the case's `[[measurement.corrections]]`
/// entry applies it: `H(5:uy, 23:uy) multiplied by -1`.
pub(crate) fn correction_text(c: &Correction) -> String {
    let mut what = Vec::new();
    if c.sign < 0.0 {
        what.push("sign inverted".to_string());
    }
    if (c.scale - 1.0).abs() > 1e-12 {
        what.push(format!("scaled by {}", table::significant(c.scale, 4)));
    }
    if let Some(d) = c.measured_at {
        what.push(format!("read as measured at {d}"));
    }
    if what.is_empty() {
        what.push("kept as measured".into());
    }
    format!("H({},{}): {}", c.response, c.reference, what.join(", "))
}

/// The report's blocks on the findings and step 0 (nothing when there are
/// neither): a table of the findings with their evidence and corrections
/// (also as `findings.csv`), and step 0's misfits and updated parameters
/// (also as `step-0-parameters.csv`).
pub(crate) fn blocks(
    findings: &[Finding],
    declared: Option<&DeclaredStep>,
    before: Before,
    out: &mut Outputs,
) -> Result<Vec<Block>> {
    let mut blocks = Vec::new();
    let times = |m: f64| table::times(quantities::times_noise(m, before.noise));
    if findings.is_empty() {
        blocks.push(Block::Text(
            "The data were checked for set-up errors (inverted, swapped or misplaced channels, calibration \
             outliers, measured modes the model lacks) before the model was blamed: none found."
                .into(),
        ));
    } else {
        let mut t = Table::new(&[
            "finding",
            "channels",
            "what",
            "evidence",
            "correction applied",
            "misfit of the channels",
        ])
        .caption(
            "What the checks found about the data before the model was blamed. A set-up error with a correction \
                 is corrected in the data every later fit reads, and the correction is written into the case under \
                 [[measurement.corrections]]; the misfit of the channels concerned before and after it. A measured \
                 mode the model lacks has no correction: it is left for the diagnosis.",
        );
        for f in findings {
            let corrections = if f.corrections.is_empty() {
                "none".to_string()
            } else {
                f.corrections.iter().map(correction_text).collect::<Vec<_>>().join("; ")
            };
            let when = if f.found_after_step > 0 {
                format!(" (found after step {})", f.found_after_step)
            } else {
                String::new()
            };
            let misfit = if f.misfit_before.is_finite() && f.misfit_after.is_finite() && !f.corrections.is_empty() {
                format!("{} -> {}", table::misfit(f.misfit_before), table::misfit(f.misfit_after))
            } else if f.misfit_before.is_finite() {
                table::misfit(f.misfit_before)
            } else {
                "-".into()
            };
            let tone = if f.corrections.is_empty() { Tone::Plain } else { Tone::Good };
            t.row_toned(vec![
                (format!("{}{when}", f.kind.name().replace('_', " ")), Tone::Plain),
                (f.channels.join(", "), Tone::Plain),
                (f.summary.clone(), Tone::Plain),
                (f.evidence.clone(), Tone::Plain),
                (corrections, tone),
                (misfit, Tone::Plain),
            ]);
        }
        blocks.push(out.table("findings", t)?);
        if findings.iter().any(|f| !f.corrections.is_empty()) {
            blocks.push(Block::Text(format!(
                "The nominal model's misfit is {} ({} x the noise) on the data as read and {} ({} x the noise) on the \
                 corrected data.",
                table::misfit(before.nominal),
                times(before.nominal),
                table::misfit(before.corrected),
                times(before.corrected)
            )));
        }
    }
    if let Some(d) = declared {
        blocks.push(Block::Facts(vec![
            (
                "step 0".into(),
                format!(
                    "the case's own [update] parameters updated before any effect is added ({}; case file step-0.toml \
                     in rfm fix)",
                    d.status.name()
                ),
            ),
            (
                "misfit".into(),
                format!(
                    "{} -> {} ({} -> {} x the noise)",
                    table::misfit(d.misfit_before),
                    table::misfit(d.misfit_updated),
                    times(d.misfit_before),
                    times(d.misfit_updated)
                ),
            ),
            (
                "dBIC of step 0".into(),
                format!(
                    "{} (the evidence for the updated values over the given ones; significant below {})",
                    table::dbic(d.delta_bic),
                    quantities::SIGNIFICANT_DBIC
                ),
            ),
        ]));
        if let Some(r) = &d.refit {
            blocks.push(Block::Facts(vec![("updated again".into(), super::fix_report::refit_text(r, times))]));
        }
        let mut t = Table::new(&["parameter", "unit", "given", "updated", "+-1 sd"])
            .caption("Step 0: the parameters the case declares under [update], updated first.");
        for (i, p) in d.parameters.iter().enumerate() {
            let sd = d
                .uncertainty
                .as_ref()
                .and_then(|u| u.parameters.get(i))
                .map_or("-".to_string(), |u| percent(u.relative_std));
            t.row(vec![p.name.clone(), parameter_unit(&p.name).to_string(), num(p.initial), num(p.updated), sd]);
        }
        blocks.push(out.table("step-0-parameters", t)?);
    }
    Ok(blocks)
}

#[cfg(test)]
mod tests {
    use fe_model::{Dof, DofRef};

    use super::*;

    #[test]
    fn a_correction_says_what_it_does_to_the_channel() {
        let (r, f) = (DofRef::new(5, Dof::Uy), DofRef::new(23, Dof::Uy));
        let c = Correction { response: r, reference: f, sign: -1.0, scale: 1.0, measured_at: None };
        assert_eq!(correction_text(&c), format!("H({r},{f}): sign inverted"));
        let c = Correction { scale: 0.8, sign: 1.0, measured_at: Some(DofRef::new(6, Dof::Uy)), ..c };
        assert_eq!(
            correction_text(&c),
            format!("H({r},{f}): scaled by 0.8, read as measured at {}", DofRef::new(6, Dof::Uy))
        );
    }
}
