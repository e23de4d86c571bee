//! The output-error estimator on a study: its options from the case and a
//! run that restarts from spread starts when the fit ends above the noise.

use super::{FrequencyTable, Method, Restart, Study, UpdateOutcome, describe_masked};
use crate::error::UpdateError;
use crate::output_error::{self, Misfit, OeData, OeOptions};
use crate::status::{IterationRecord, Status};
use crate::uncertainty;
use crate::verdict;

/// Restart fits of a few steps each; the best are then run to the end.
const RESTART_STEPS: usize = 15;
/// How many of the short restarts are run to the end.
const RESTARTS_REFINED: usize = 2;
/// Restart starts spread by up to this factor either way from the initial values.
const RESTART_SPREAD: f64 = 10.0;
/// Short restarts that must come back to the first fit's minimum before
/// [`Study::fit_output_error`] takes that minimum as confirmed.
const CONFIRMING_RESTARTS: usize = 2;

/// What a run makes besides the fit.
#[derive(Clone, Copy)]
struct Scope {
    /// The natural-frequency table of the reports.
    natural_frequencies: bool,
    /// Restarts stop once [`CONFIRMING_RESTARTS`] of them reach the first
    /// fit's minimum again (see [`Study::fit_output_error`]).
    stop_when_confirmed: bool,
}

impl Study {
    /// Output-error options from the case's `[update]` section, with the
    /// study's gains ([`Study::gains`]: per reference or per channel).
    pub fn output_error_options(&self) -> Result<OeOptions, UpdateError> {
        let mut opts = OeOptions { gains: self.gains, ..OeOptions::default() };
        if let Some(spec) = self.case.update.as_ref() {
            if let Some(n) = spec.max_iterations {
                opts.max_iterations = n as usize;
            }
            if let Some(t) = spec.tolerance {
                opts.tolerance = t;
            }
            opts.regularization = spec.regularization.unwrap_or(0.0);
            opts.bounds = spec.bounds.clone();
            if let Some((m, span)) = &spec.misfit {
                opts.misfit = Misfit::parse(m).ok_or_else(|| {
                    UpdateError::Case(
                        self.case.error(Some(span.clone()), format!("unknown misfit `{m}` (relative or log)")),
                    )
                })?;
            }
        }
        Ok(opts)
    }

    /// Runs the output-error estimator from the initial model, with the
    /// case's options (bounds, regularisation, gains, weights, misfit form).
    pub fn run_output_error(
        &self,
        opts: &OeOptions,
        on_iteration: impl FnMut(&IterationRecord),
    ) -> Result<UpdateOutcome, UpdateError> {
        self.output_error_run(opts, Scope { natural_frequencies: true, stop_when_confirmed: false }, on_iteration)
    }

    /// The fit of [`Study::run_output_error`] and what judging it needs
    /// (the status, the values and their uncertainty, the updated system),
    /// as `rfm fix` judges tens of updates that no report shows:
    ///
    /// - without the table of natural frequencies that reports show (its
    ///   dense eigensolutions of the initial and the updated model cost as
    ///   much as the fit itself on a beam of 300 DOFs): `natural_frequencies_hz`
    ///   is empty, of kind `not computed`;
    /// - restarting only while the first fit is in doubt: the short restarts
    ///   from spread starts are made one after the other, and once two of
    ///   them have stopped at a stationary point at the first fit's minimum
    ///   (within [`verdict::SAME_MINIMUM`] above its cost, and not below it
    ///   by more than a chi-square of 0.5, which the noise cannot show),
    ///   that minimum is confirmed (`model_inadequate`, the first fit kept)
    ///   and the others are not made. Otherwise (a restart lower by more
    ///   than that, or fewer than two back at the minimum) all are made and
    ///   the two best run to the end, as [`Study::run_output_error`] does.
    ///   On the beam of `cargo xtask bench`, two restarts confirmed the
    ///   minimum of four of the five restarted look-aheads of the last step,
    ///   where the restarts had taken a sixth of the loop's time.
    ///
    /// Otherwise as [`Study::run_output_error`].
    pub fn fit_output_error(&self, opts: &OeOptions) -> Result<UpdateOutcome, UpdateError> {
        self.output_error_run(opts, Scope { natural_frequencies: false, stop_when_confirmed: true }, |_| {})
    }

    fn output_error_run(
        &self,
        opts: &OeOptions,
        scope: Scope,
        on_iteration: impl FnMut(&IterationRecord),
    ) -> Result<UpdateOutcome, UpdateError> {
        if self.parameters.is_empty() {
            return Err(UpdateError::NoParameters);
        }
        let (lines, singular_note) = self.regular_lines(self.lines_for(Method::OutputError)?)?;
        let measured = self.measured.at_frequencies(&lines)?;
        self.check_initial(&measured)?;
        let weights = self.weights(&measured)?;
        let params = self.parameter_set();
        let mut sys = self.system.clone();
        let data = OeData { measured: &measured, weights: weights.as_deref() };
        // the residual is weighted (band and coherence weights): its noise
        // must be weighted the same way, or a coherence below 0.999, whose
        // weight is below 1, makes any residual look small beside the noise
        let noise = self.residual_noise(&measured)?;
        let ratio = |r: &output_error::OeResult| noise.filter(|&s| s > 0.0).map(|s| (2.0 * r.sigma2).sqrt() / s);
        let first = output_error::run(&mut sys, &params, &data, opts, on_iteration)?;
        let settled = |r: &output_error::OeResult| {
            r.status == Status::Converged && ratio(r).is_none_or(|x| x <= verdict::RESTART_ABOVE)
        };
        let mut restarts = Vec::new();
        let mut agree = None;
        let mut history = first.history.clone();
        let mut result = first;
        if !settled(&result) && opts.restarts > 0 && !matches!(result.status, Status::Failed(_)) {
            // restarts spread in log space around the initial values, a few
            // steps each; the best are run to the end and the lowest kept
            let p_init = params.values(&self.system);
            let bounds: Vec<(f64, f64)> = p_init
                .iter()
                .enumerate()
                .map(|(i, &p)| opts.bounds.get(i).copied().flatten().unwrap_or((p / 1e6, p * 1e6)))
                .collect();
            let fit = |start: &[f64], o: &OeOptions| -> Option<output_error::OeResult> {
                let mut s = self.system.clone();
                params.set_values(&mut s, start).ok()?;
                output_error::run(&mut s, &params, &data, o, |_| {}).ok().filter(|r| r.cost.is_finite())
            };
            // a short fit's values and cost are read, never its spread
            let short = OeOptions { max_iterations: RESTART_STEPS, jackknife: false, ..opts.clone() };
            // back at the first fit's minimum: stopped at a stationary
            // point less than SAME_MINIMUM above its cost, and not below it
            // by more than the noise can show (the chi-square gain at which
            // a fit itself stops in a flat valley)
            let (first_cost, first_sigma2) = (result.cost, result.sigma2);
            let lower =
                |t: &output_error::OeResult| first_cost - t.cost > output_error::NOISE_WINDOW_GAIN * first_sigma2;
            let confirms = |t: &output_error::OeResult| {
                t.status == Status::Converged && !lower(t) && t.cost - first_cost <= verdict::SAME_MINIMUM * first_cost
            };
            // confirmed by two, and none found lower (then all are made and refined)
            let confirmed = |tried: &[output_error::OeResult]| {
                scope.stop_when_confirmed
                    && !tried.iter().any(lower)
                    && tried.iter().filter(|t| confirms(t)).count() >= CONFIRMING_RESTARTS
            };
            let mut tried: Vec<output_error::OeResult> = Vec::new();
            for i in 1..=opts.restarts {
                tried.extend(fit(&verdict::spread_start(&p_init, &bounds, i, RESTART_SPREAD), &short));
                if confirmed(&tried) {
                    break;
                }
            }
            let confirmed = confirmed(&tried);
            tried.sort_by(|a, b| a.cost.total_cmp(&b.cost));
            // a confirmed minimum has nothing to refine: the restarts came back to it
            let refined = if confirmed { 0 } else { RESTARTS_REFINED.min(tried.len()) };
            for t in &tried[refined..] {
                restarts.push(Restart {
                    start_residual: t.history[0].residual,
                    residual: t.history.last().map_or(f64::NAN, |r| r.residual),
                    refined: false,
                });
            }
            let mut ends = vec![result.cost];
            if confirmed {
                ends.extend(tried.iter().filter(|t| confirms(t)).map(|t| t.cost));
            }
            for t in tried.into_iter().take(refined) {
                let Some(r) = fit(&t.values, opts) else { continue };
                restarts.push(Restart {
                    start_residual: t.history[0].residual,
                    residual: r.history.last().map_or(f64::NAN, |x| x.residual),
                    refined: true,
                });
                ends.push(r.cost);
                if r.cost < result.cost {
                    let offset = history.len();
                    history.extend(r.history.iter().cloned().map(|mut rec| {
                        rec.iteration += offset;
                        rec
                    }));
                    result = r;
                }
            }
            let best = result.cost;
            let same = ends.iter().filter(|&&c| (c - best) <= verdict::SAME_MINIMUM * best).count();
            agree = Some(same >= 2);
            params.set_values(&mut sys, &result.values)?;
        }
        let noise_ratio = ratio(&result);
        let status = verdict::classify(&result.status, noise_ratio, agree);
        let band = (lines[0], lines[lines.len() - 1]);
        let report = uncertainty::analyse(&params, &result, band, noise);
        let natural_frequencies_hz =
            if scope.natural_frequencies { self.frequency_table(&sys) } else { FrequencyTable::not_computed() };
        let first_residual = history.first().map_or(f64::NAN, |r| r.residual);
        let residual = result.history.last().map_or(f64::NAN, |r| r.residual);
        Ok(UpdateOutcome {
            method: "output-error".into(),
            status,
            iteration_end: result.status.clone(),
            parameters: self.reports(&result.values),
            residual,
            history,
            frequencies_hz: lines,
            natural_frequencies_hz,
            uncertainty: Some(report),
            gains: result.gains,
            noise_estimate: crate::diagnose::estimate_noise_against(&sys, &self.measured)?,
            residual_noise: noise,
            masked: describe_masked(&self.masked),
            notes: self.notes.iter().cloned().chain(singular_note).collect(),
            warnings: Vec::new(),
            noise_ratio,
            restarts,
            worse_than_start: residual > first_residual,
            gain_setting: format!("{} ({})", self.gains, self.gains_reason),
            coherence_weighted: weights.is_some() && self.weighs_coherence(),
            pairing: self.pairing.clone(),
            system: sys,
        })
    }
}
