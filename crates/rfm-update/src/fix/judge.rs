//! The one rule by which the loop keeps a step (see [`super`]'s docs): the
//! evidence for the model after it over the model before it, every
//! parameter counted; the plausibility of the values its update reached;
//! and an update that reached a stationary point.

use crate::diagnose::{self, Diagnosis};
use crate::status::Status;
use crate::study::UpdateOutcome;

use super::{Added, State};

/// A fitted value whose noise-only relative standard deviation exceeds
/// this is not determined by the data (as in the diagnosis).
const UNDETERMINED_STD: f64 = 1.0;

/// The evidence against the data's noise.
#[derive(Clone, Copy, Debug)]
pub(super) struct Evidence {
    /// The data's relative noise (RMS per complex value).
    pub(super) noise: f64,
    /// The change of the information criterion below which a step is kept
    /// (the diagnosis's significance, -10).
    pub(super) significance: f64,
}

/// The verdict on a step tried.
#[derive(Clone, Debug)]
pub(super) struct Verdict {
    /// Its evidence over the model before it ([`diagnose::delta_bic`]).
    pub(super) delta_bic: f64,
    /// Why it is not kept; `None` when it passes.
    pub(super) rejected: Option<String>,
    /// The mode a resonator of the step left unexplained, when that is why
    /// it is not kept (see `fix/explains.rs`).
    pub(super) unexplained: Option<super::explains::Unexplained>,
}

impl Evidence {
    /// The verdict on `after` (the model with `effects` added, in order,
    /// each as its diagnosis ranked it, and everything updated) against the
    /// model `before`.
    pub(super) fn judge(&self, before: State, after: &Added, effects: &[(&Diagnosis, usize)]) -> Verdict {
        let k = after.outcome.parameters.len();
        let delta_bic = diagnose::delta_bic(before.misfit, before.k, &after.stats, k, self.noise);
        let rejected = if !stationary(&after.outcome) {
            Some(format!(
                "its update ended short of a stationary point ({}), even with what the data do not determine held",
                after.outcome.iteration_end.name()
            ))
        } else if !(delta_bic < self.significance) {
            Some(format!(
                "not significant on its own: dBIC {} with its {} parameter(s) counted (misfit {:.4e} -> {:.4e}), \
                 not below {}",
                crate::quantities::dbic_text(delta_bic),
                k.saturating_sub(before.k),
                before.misfit,
                after.stats.misfit,
                self.significance
            ))
        } else {
            implausible_after(effects, &after.outcome).map(|why| format!("implausible after its update: {why}"))
        };
        Verdict { delta_bic, rejected, unexplained: None }
    }

    /// The evidence for `b` over `a` (two models after the same step),
    /// judged against what the better of the two, `a`, leaves: within the
    /// significance of 0, the data cannot tell them apart.
    pub(super) fn between(&self, a: &Added, b: &Added) -> f64 {
        let n = a.stats.n as f64;
        let (ka, kb) = (a.outcome.parameters.len() as f64, b.outcome.parameters.len() as f64);
        n * (b.stats.misfit.powi(2) - a.stats.misfit.powi(2)) / a.stats.lack_of_fit(self.noise) + (kb - ka) * n.ln()
    }
}

/// Whether an update ended at a stationary point.
pub(super) fn stationary(outcome: &UpdateOutcome) -> bool {
    outcome.iteration_end == Status::Converged
}

/// The parameters an update did not determine (noise-only relative
/// standard deviation above one, or none at all).
pub(super) fn undetermined(outcome: &UpdateOutcome) -> Vec<String> {
    let Some(u) = &outcome.uncertainty else { return Vec::new() };
    u.parameters.iter().filter(|p| !(p.relative_std_noise <= UNDETERMINED_STD)).map(|p| p.name.clone()).collect()
}

/// The first of `effects` (diagnosis and rank of each) whose values after
/// the update in `outcome` are not plausible, with the reason: each
/// effect's candidate judges its own parameters at their updated values
/// ([`crate::diagnose::Candidate::implausible`]), those the update did not
/// determine left out, as the diagnosis does.
pub(super) fn implausible_after(effects: &[(&Diagnosis, usize)], outcome: &UpdateOutcome) -> Option<String> {
    let sd = |name: &str| {
        outcome
            .uncertainty
            .as_ref()
            .and_then(|u| u.parameters.iter().find(|p| p.name == name))
            .map(|p| p.relative_std_noise)
    };
    effects.iter().find_map(|&(d, rank)| {
        let r = &d.ranking[rank - 1];
        let c = &d.candidates[r.candidate];
        let (values, determined): (Vec<f64>, Vec<bool>) = r
            .parameters
            .iter()
            .map(|p| match outcome.parameters.iter().find(|q| q.name == p.name) {
                Some(q) => (q.updated, sd(&p.name).is_none_or(|s| s <= UNDETERMINED_STD)),
                None => (p.value, p.determined),
            })
            .unzip();
        c.implausible(&values, &determined).map(|why| format!("{} ({why})", r.description))
    })
}
