//! What an updating run on a study returns, as stored with the results.

use damping::DampedSystem;

use super::{FrequencyTable, PairingReport, Study};
use crate::output_error::Gain;
use crate::status::{IterationRecord, Status};
use crate::uncertainty::UncertaintyReport;

/// One parameter's values for reporting.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ParameterReport {
    /// Dotted name.
    pub name: String,
    /// Initial value.
    pub initial: f64,
    /// Updated value.
    pub updated: f64,
    /// True value, when the case synthesises its data.
    pub truth: Option<f64>,
    /// Published value, when the case quotes a paper.
    pub paper: Option<f64>,
}

impl ParameterReport {
    /// `|updated - truth| / |truth|`, when the truth is known.
    pub fn relative_error(&self) -> Option<f64> {
        self.truth.map(|t| ((self.updated - t) / t).abs())
    }
}

/// The outcome of an updating run on a study.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct UpdateOutcome {
    /// Method used.
    pub method: String,
    /// How the run ended, judged against the noise (see [`crate::verdict`]).
    pub status: Status,
    /// How the iteration itself ended, before that judgement:
    /// [`Status::Converged`] at a stationary point (whatever its misfit),
    /// [`Status::Stalled`] where no step lowered the misfit short of one,
    /// [`Status::MaxIterations`] or [`Status::Failed`]. `rfm fix` keeps a
    /// step only when its update reached a stationary point.
    pub iteration_end: Status,
    /// Per-parameter values.
    pub parameters: Vec<ParameterReport>,
    /// Iteration history.
    pub history: Vec<IterationRecord>,
    /// Final residual (relative, over the updating lines).
    pub residual: f64,
    /// Lines used (Hz).
    pub frequencies_hz: Vec<f64>,
    /// Natural frequencies before and after.
    pub natural_frequencies_hz: FrequencyTable,
    /// Parameter uncertainty and identifiability (output-error method).
    pub uncertainty: Option<UncertaintyReport>,
    /// Fitted gains (per reference or per channel), when requested.
    pub gains: Vec<Gain>,
    /// Relative noise level of the measured data, estimated from their
    /// roughness and that of their residual against the updated model (see
    /// [`crate::diagnose::estimate_noise_against`]).
    pub noise_estimate: Option<f64>,
    /// The noise level weighted as the fit's residual is (by band and
    /// coherence weights; see [`crate::study::residual_noise_for`]): what
    /// [`UpdateOutcome::noise_ratio`] compares the residual with. Equal to
    /// `noise_estimate` for a fit without weights.
    pub residual_noise: Option<f64>,
    /// What the case's mask rules left out of the measured data, one line
    /// each (`non-finite: line 17, columns 4-5: H(3:uy,2:uy) at 20 Hz is NaN`).
    pub masked: Vec<String>,
    /// What reading the measured data changed or passed over, one line each
    /// (see [`Study::notes`]).
    pub notes: Vec<String>,
    /// What the data leave undetermined, for methods without an uncertainty
    /// report (the RFM): parameters that ended on a bound, the combination
    /// of parameters the sensitivity cannot separate; and for the RFM, why
    /// its result may not be trusted (noise above its limit, parameters
    /// that ran away, no uncertainty, a misfit worse than the start).
    pub warnings: Vec<String>,
    /// The final residual as a multiple of [`UpdateOutcome::residual_noise`]
    /// (what the status is decided on; `None` when the noise is unknown).
    pub noise_ratio: Option<f64>,
    /// The restarts of the output-error fit (empty when none were needed).
    pub restarts: Vec<Restart>,
    /// The update ended with a larger misfit than the initial model's.
    pub worse_than_start: bool,
    /// The gains fitted (`none`, `per-reference`, `per-channel`) and why.
    pub gain_setting: String,
    /// Whether the lines were weighted by the measured coherence.
    pub coherence_weighted: bool,
    /// How test nodes were paired with model nodes by coordinates.
    pub pairing: Vec<PairingReport>,
    /// The updated model.
    #[cfg_attr(feature = "serde", serde(skip))]
    pub system: DampedSystem,
}

/// One restart of the output-error fit from a spread start.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Restart {
    /// Residual RMS at the start.
    pub start_residual: f64,
    /// Residual RMS where it ended.
    pub residual: f64,
    /// Whether it was run to the end (the best of the short ones are).
    pub refined: bool,
}

/// One line per thing a mask rule left out: the rule, then where and why.
pub fn describe_masked(masked: &[frf::io::Masked]) -> Vec<String> {
    masked.iter().map(|m| format!("{}: {}", m.rule, m.detail)).collect()
}

impl Study {
    /// Reports for the given updated values.
    pub fn reports(&self, updated: &[f64]) -> Vec<ParameterReport> {
        let paper = self.case.paper.as_ref();
        self.parameters
            .iter()
            .zip(updated)
            .map(|(p, &u)| {
                let q = p.quantities[0];
                ParameterReport {
                    name: p.name.clone(),
                    initial: self.system.get(q),
                    updated: u,
                    truth: self.truth.as_ref().map(|t| t.get(q)),
                    paper: paper.and_then(|pp| pp.values.iter().find(|(pq, _)| *pq == q).map(|&(_, v)| v)),
                }
            })
            .collect()
    }
}
