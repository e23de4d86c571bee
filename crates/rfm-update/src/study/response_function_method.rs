//! The response function method on a study: its options from the case and
//! a run with the warnings its result needs.

use fe_model::case::Gains;

use super::{Method, Study, UpdateOutcome, describe_masked};
use crate::error::UpdateError;
use crate::verdict;
use crate::{
    response_function::{self, RfmOptions},
    status::IterationRecord,
};

impl Study {
    /// RFM options from the case's `[update]` section (iteration limit,
    /// tolerance; [`Self::run_rfm`] adds the bounds).
    pub fn rfm_options(&self) -> RfmOptions {
        let mut opts = RfmOptions::default();
        if let Some(spec) = self.case.update.as_ref() {
            if let Some(n) = spec.max_iterations {
                opts.max_iterations = n as usize;
            }
            if let Some(t) = spec.tolerance {
                opts.tolerance = t;
            }
        }
        opts
    }

    /// Runs the response function method from the initial model.
    pub fn run_rfm(
        &self,
        opts: &RfmOptions,
        on_iteration: impl FnMut(&IterationRecord),
    ) -> Result<UpdateOutcome, UpdateError> {
        if self.parameters.is_empty() {
            return Err(UpdateError::NoParameters);
        }
        if self.gains != Gains::None {
            return Err(UpdateError::Method(format!(
                "the response function method fits no gain, and this case needs {} gains ({}); update with the \
                 output-error method (`method = \"output-error\"` in [update], or --method output-error)",
                self.gains, self.gains_reason
            )));
        }
        let (lines, singular_note) = self.regular_lines(self.lines_for(Method::Rfm)?)?;
        let measured = self.measured.at_frequencies(&lines)?;
        self.check_initial(&measured)?;
        let mut sys = self.system.clone();
        let mut opts = opts.clone();
        if let Some(spec) = &self.case.update {
            opts.bounds = spec.bounds.clone();
        }
        let result = response_function::run(&mut sys, &self.parameter_set(), &measured, &opts, on_iteration)?;
        let mut warnings: Vec<String> = self
            .parameters
            .iter()
            .enumerate()
            .filter(|&(i, _)| result.at_bound[i])
            .map(|(i, p)| {
                let (lo, hi) = result.bounds[i];
                if opts.bounds.get(i).copied().flatten().is_some() {
                    format!("{} ended on its bound [{lo:e}, {hi:e}]", p.name)
                } else {
                    format!(
                        "{} ended a factor of {:e} from its initial value, the most the RFM allows without bounds of its own: the data do not determine it",
                        p.name,
                        response_function::DEFAULT_RANGE
                    )
                }
            })
            .collect();
        warnings.extend(result.unresolved.clone());
        let noise = crate::diagnose::estimate_noise_against(&self.system, &self.measured)?;
        if let Some(s) = noise.filter(|&s| s > verdict::RFM_NOISE_LIMIT) {
            warnings.push(format!(
                "the data's noise ({:.2} %) is above the {:.1} % where the RFM is biased (its equations have \
                 measured data on both sides): its values cannot be trusted; use --method output-error",
                100.0 * s,
                100.0 * verdict::RFM_NOISE_LIMIT
            ));
        }
        let noise_ratio = noise.filter(|&s| s > 0.0).map(|s| result.residual / s);
        let status = verdict::classify(&result.status, noise_ratio, None);
        let held = verdict::held(&status, &result.at_bound, &result.undetermined);
        let runaways = verdict::runaways(&self.parameter_names(), &self.system_values(), &result.values, &held);
        let status = verdict::with_parameters(status, !runaways.is_empty() || result.at_bound.contains(&true));
        warnings.extend(runaways);
        let first = result.history.first().map_or(f64::NAN, |r| r.residual);
        let worse_than_start = result.residual > first;
        if worse_than_start {
            warnings.push(format!(
                "the RFM made the misfit worse than the initial model's ({:.3e} -> {:.3e}): the updated model \
                 is not an improvement",
                first, result.residual
            ));
        }
        let natural_frequencies_hz = self.frequency_table(&sys);
        Ok(UpdateOutcome {
            natural_frequencies_hz,
            uncertainty: None,
            gains: Vec::new(),
            noise_estimate: noise,
            // the RFM's equations carry no line weights
            residual_noise: noise,
            masked: describe_masked(&self.masked),
            notes: self.notes.iter().cloned().chain(singular_note).collect(),
            warnings,
            noise_ratio,
            restarts: Vec::new(),
            worse_than_start,
            gain_setting: format!("{} ({})", self.gains, self.gains_reason),
            coherence_weighted: false,
            pairing: self.pairing.clone(),
            method: "rfm".into(),
            status,
            iteration_end: result.status.clone(),
            parameters: self.reports(&result.values),
            history: result.history,
            residual: result.residual,
            frequencies_hz: lines,
            system: sys,
        })
    }
}
