//! The response function method (RFM) extended to exponential damping
//! (Arora, Adhikari and Vijayan 2023, eqs. 8-21).
//!
//! From `Z_EX = Z_FE + dZ` and `Z R = I` for model and structure,
//! `R_FE dZ R_EX,v = R_FE,v - R_EX,v` for a measured column `v` (eq. 12).
//! Writing `dZ = sum_i (dZ/dp_i) p_i u_i` with relative corrections
//! `u_i = dp_i / p_i` (eq. 14) gives, at the measured rows and chosen lines,
//!
//! ```text
//! sum_i u_i [R_FE (dZ/dp_i p_i) R_EX,v]  =  R_FE,v - R_EX,v
//! ```
//!
//! real and imaginary parts stacked into one real least-squares problem
//! (eqs. 19-21), solved with column scaling and SVD truncation
//! ([`crate::lstsq`]); then `p_i <- p_i (1 + u_i)` and repeat. Unmeasured
//! entries of `R_EX,v` take the current model's values at each pass.
//!
//! Each equation (one channel at one line) is divided by `|R_EX|` there
//! before stacking, so that the least squares weighs relative, not absolute,
//! differences; the misfit the iteration reports and lowers is the matching
//! RMS relative difference ([`relative_residual`]). Receptances across a
//! band differ by orders of magnitude (the quasi-static lines of the
//! two-material beam are 600 times larger than its highest ones), and the
//! round-off of a computed or measured FRF is relative to its size: unweighted,
//! the largest receptances set both the fit and its noise, and parameters
//! that only the small ones see (a relaxation parameter far above the band)
//! stop about 1e-7 from the truth on noise-free data, where the round-off of
//! the low lines swamps them. Weighted, Table 1 of the paper is recovered to
//! about 1e-10. With consistent data the weighting does not move the
//! solution, only how round-off and noise enter it.
//!
//! Two safeguards beyond the paper keep the iteration on track when the
//! model starts far from the data (resonances shifted by more than their
//! width, parameters acting on unmeasured DOFs), where the linearised step
//! can be far too long:
//!
//! - the step is accepted only if it lowers the FRF misfit at the updating
//!   lines; otherwise it is damped, Levenberg-Marquardt style (Tikhonov
//!   regularisation `lambda` in the column-scaled variables, raised tenfold
//!   per rejection and relaxed tenfold after each success), until it does;
//! - no parameter changes by more than a factor of 100 in one step (so none
//!   changes sign); the limit applies per parameter, so that one poorly
//!   determined parameter asking for a huge change does not stall the others.
//!
//! When the full step lowers the misfit, as it does near the solution, the
//! iteration is exactly the paper's.
//!
//! Bounds from the case (`[update] bounds`), or else a factor of
//! [`DEFAULT_RANGE`] either way from the initial value, clip each new value;
//! a parameter that ends on one is flagged in [`RfmResult::at_bound`]. At the returned
//! iterate the column-scaled sensitivity's singular values tell whether the
//! data determine every parameter: [`RfmResult::unresolved`] names the
//! combination along the weakest direction when its singular value is below
//! 1e-6 of the largest (the same test as the output-error uncertainty).

use damping::DampedSystem;
use faer::Mat;
use frf::{FrfSet, ZSolver};

use crate::error::UpdateError;
use crate::params::ParameterSet;
use crate::sensitivity::{self, ChannelPlan, FrequencyBlock, Hybrid};
use crate::status::{IterationRecord, Status};

/// Options of the RFM iteration.
#[derive(Clone, Debug)]
pub struct RfmOptions {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Converged when the largest relative correction is below this.
    pub tolerance: f64,
    /// Relative singular-value cut-off of the least-squares solve.
    pub rcond: f64,
    /// Stalled when this many iterations in a row fail to lower the best
    /// residual by 1 %.
    pub stall_iterations: usize,
    /// Bounds per parameter in physical units (`None` or missing: within a
    /// factor of [`DEFAULT_RANGE`] of the initial value).
    pub bounds: Vec<Option<(f64, f64)>>,
}

impl Default for RfmOptions {
    fn default() -> Self {
        RfmOptions { max_iterations: 50, tolerance: 1e-6, rcond: 1e-10, stall_iterations: 5, bounds: Vec::new() }
    }
}

/// Outcome of an RFM run.
#[derive(Clone, Debug)]
pub struct RfmResult {
    /// Records: initial model, then one per iteration.
    pub history: Vec<IterationRecord>,
    /// How it ended.
    pub status: Status,
    /// Final parameter values (the best iterate unless converged).
    pub values: Vec<f64>,
    /// Residual of the final values.
    pub residual: f64,
    /// Parameters whose final value lies on one of their bounds.
    pub at_bound: Vec<bool>,
    /// The bounds each parameter was kept within: its own, or a factor of
    /// [`DEFAULT_RANGE`] either way from its initial value.
    pub bounds: Vec<(f64, f64)>,
    /// Singular values of the column-scaled sensitivity at the returned
    /// iterate, descending (empty if it was never solved for).
    pub singular_values: Vec<f64>,
    /// The parameter combination the data cannot separate, when the scaled
    /// sensitivity is nearly singular (see the module docs).
    pub unresolved: Option<String>,
    /// The parameters that take part in that combination.
    pub undetermined: Vec<bool>,
}

/// Without bounds of its own, a parameter stays within this factor of its
/// initial value either way, as in the output-error estimator: one that the
/// data do not determine cannot run off by ten orders of magnitude and more
/// (as the joints of the f-frame twin did), and it is reported on that bound.
pub const DEFAULT_RANGE: f64 = 1e6;

/// The bounds each parameter is kept within: its own, or a factor of
/// [`DEFAULT_RANGE`] around its initial value.
fn effective_bounds(initial: &[f64], given: &[Option<(f64, f64)>]) -> Vec<(f64, f64)> {
    initial
        .iter()
        .enumerate()
        .map(|(i, &p)| given.get(i).copied().flatten().unwrap_or((p / DEFAULT_RANGE, p * DEFAULT_RANGE)))
        .collect()
}

/// Clips each value into its bounds.
fn clip(values: &mut [f64], bounds: &[(f64, f64)]) {
    for (v, &(lo, hi)) in values.iter_mut().zip(bounds) {
        *v = v.clamp(lo, hi);
    }
}

/// The weight of each equation, `1 / |R_EX|`, channel by channel
/// (`weights[c][k]`). A measured value of exactly zero has no relative
/// error; its equation is weighed by its channel's RMS magnitude instead, so
/// that it neither vanishes nor dominates.
fn weights(measured: &FrfSet) -> Vec<Vec<f64>> {
    (0..measured.channels().len())
        .map(|c| {
            let values = measured.channel(c);
            let rms = (values.iter().map(|m| m.norm_sqr()).sum::<f64>() / values.len().max(1) as f64).sqrt();
            values
                .iter()
                .map(|m| {
                    let size = if m.norm() > 0.0 { m.norm() } else { rms };
                    if size > 0.0 { 1.0 / size } else { 1.0 }
                })
                .collect()
        })
        .collect()
}

/// RMS of `|R_FE - R_EX| / |R_EX|` over the channels and lines of a set of
/// blocks (see the module docs for why relative).
pub fn relative_residual(blocks: &[FrequencyBlock], measured: &FrfSet) -> f64 {
    weighted_residual(blocks, measured, &weights(measured))
}

/// [`relative_residual`] with the weights of [`weights`] made once.
fn weighted_residual(blocks: &[FrequencyBlock], measured: &FrfSet, w: &[Vec<f64>]) -> f64 {
    let mut sum = 0.0;
    for (k, b) in blocks.iter().enumerate() {
        for (c, &h) in b.model.iter().enumerate() {
            sum += ((h - measured.get(c, k)) * w[c][k]).norm_sqr();
        }
    }
    (sum / (blocks.len() * measured.channels().len()).max(1) as f64).sqrt()
}

/// Stacks `S u = R_FE - R_EX`, each equation divided by `|R_EX|`, into a
/// real system (real parts, then imaginary).
fn stack(blocks: &[FrequencyBlock], measured: &FrfSet, w: &[Vec<f64>], params: &ParameterSet) -> (Mat<f64>, Vec<f64>) {
    let n_params = params.len();
    let n_ch = measured.channels().len();
    let rows = blocks.len() * n_ch;
    let mut a = Mat::<f64>::zeros(2 * rows, n_params);
    let mut b = vec![0.0; 2 * rows];
    for (k, blk) in blocks.iter().enumerate() {
        let sens = params.combine(blk);
        for c in 0..n_ch {
            let r = k * n_ch + c;
            let w = w[c][k];
            let d = (blk.model[c] - measured.get(c, k)) * w;
            b[r] = d.re;
            b[rows + r] = d.im;
            for i in 0..n_params {
                a[(r, i)] = sens[(c, i)].re * w;
                a[(rows + r, i)] = sens[(c, i)].im * w;
            }
        }
    }
    (a, b)
}

/// Limits each relative correction so that `1 + u` stays within
/// `[1/100, 100]`; returns the number of corrections limited.
fn guard(u: &mut [f64]) -> usize {
    let mut limited = 0;
    for x in u.iter_mut() {
        let clamped = x.clamp(0.01 - 1.0, 100.0 - 1.0);
        if clamped != *x {
            limited += 1;
            *x = clamped;
        }
    }
    limited
}

/// The misfit of [`relative_residual`] for the current model at the
/// measured lines, or `None` when the model cannot be evaluated (singular at
/// some line).
fn misfit(sys: &DampedSystem, solver: &ZSolver, measured: &FrfSet, w: &[Vec<f64>]) -> Option<f64> {
    let model = frf::synthesize_with(sys, solver, measured.channels(), measured.frequencies_hz()).ok()?;
    let mut sum = 0.0;
    for (c, row) in w.iter().enumerate() {
        for (k, &w) in row.iter().enumerate() {
            sum += ((model.get(c, k) - measured.get(c, k)) * w).norm_sqr();
        }
    }
    Some((sum / model.values().len().max(1) as f64).sqrt()).filter(|r| r.is_finite())
}

/// Runs the RFM on `sys` (updated in place) against measured receptances at
/// the lines of `measured`. `on_iteration` sees each record as it is made.
pub fn run(
    sys: &mut DampedSystem,
    params: &ParameterSet,
    measured: &FrfSet,
    opts: &RfmOptions,
    mut on_iteration: impl FnMut(&IterationRecord),
) -> Result<RfmResult, UpdateError> {
    let solver = ZSolver::new(sys.assembly().pattern())?;
    let plan = ChannelPlan::new(sys, measured.channels())?;
    let freqs = measured.frequencies_hz().to_vec();
    let weights = weights(measured);
    let values = |sys: &DampedSystem| params.values(sys);
    let mut history: Vec<IterationRecord> = Vec::new();
    let mut best: (f64, Vec<f64>) = (f64::INFINITY, values(sys));
    let bounds = effective_bounds(&best.1, &opts.bounds);
    let mut status = Status::MaxIterations;
    let mut since_best = 0;
    let mut lambda = 0.0;
    let mut converged = false;
    // (max |u|, corrections limited, rank, lambda) of the step just taken
    let mut last_step = (0.0, 0, params.len(), 0.0);
    // singular values and right singular vectors at the best iterate
    let mut best_svd: (Vec<f64>, Mat<f64>) = (Vec::new(), Mat::zeros(0, 0));
    for iteration in 0..=opts.max_iterations {
        let blocks =
            match sensitivity::assemble(sys, &solver, &plan, params.quantities(), &freqs, Hybrid::Measured(measured)) {
                Ok(b) => b,
                Err(e) => {
                    status = Status::Failed(e.to_string());
                    break;
                }
            };
        let residual = weighted_residual(&blocks, measured, &weights);
        if !residual.is_finite() {
            // a NaN misfit must never pass for convergence (its step may be zero)
            if iteration == 0 {
                return Err(UpdateError::Numerics(format!(
                    "the misfit of the initial model is {residual}: its receptances or the measured ones are not \
                     finite numbers at the updating lines"
                )));
            }
            status = Status::Failed(format!("the misfit became {residual} at iteration {iteration}"));
            break;
        }
        let (max_correction, limited, rank, step_lambda) = last_step;
        let record = IterationRecord {
            iteration,
            residual,
            max_correction,
            limited,
            rank,
            lambda: step_lambda,
            values: values(sys),
        };
        on_iteration(&record);
        history.push(record);
        if residual.is_finite() && residual < 0.99 * best.0 {
            since_best = 0;
        } else {
            since_best += 1;
        }
        let at_best = residual.is_finite() && residual < best.0;
        if at_best {
            best = (residual, values(sys));
        }
        if converged {
            status = Status::Converged;
            break;
        }
        if since_best >= opts.stall_iterations {
            status = Status::Stalled;
            break;
        }
        if iteration == opts.max_iterations {
            break;
        }
        let (a, b) = stack(&blocks, measured, &weights, params);
        let sol = crate::lstsq::solve(&a, &b, opts.rcond);
        if sol.rank == 0 {
            // a zero step would pass for convergence
            status = Status::Failed("the misfit does not change with any parameter (zero sensitivity)".into());
            break;
        }
        if at_best {
            best_svd = (sol.singular_values.clone(), sol.v.clone());
        }
        let current = values(sys);
        let mut full = sol.x.clone();
        let full_limited = guard(&mut full);
        let full_max = full.iter().map(|x| x.abs()).fold(0.0, f64::max);
        if !full_max.is_finite() {
            status = Status::Failed("the least-squares step is not finite".into());
            break;
        }
        if full_max < opts.tolerance {
            // converged: take the (tiny) paper step and stop after recording it
            let mut next: Vec<f64> = current.iter().zip(&full).map(|(p, u)| p * (1.0 + u)).collect();
            clip(&mut next, &bounds);
            params.set_values(sys, &next)?;
            last_step = (full_max, full_limited, sol.rank, 0.0);
            converged = true;
            continue;
        }
        let smax2 = sol.largest_singular_value().powi(2);
        let mut accepted = false;
        for _ in 0..16 {
            let mut u = if lambda == 0.0 { sol.x.clone() } else { sol.damped(lambda) };
            let limited = guard(&mut u);
            let mut next: Vec<f64> = current.iter().zip(&u).map(|(p, u)| p * (1.0 + u)).collect();
            clip(&mut next, &bounds);
            let trial = params.set_values(sys, &next).ok().and_then(|()| misfit(sys, &solver, measured, &weights));
            if trial.is_some_and(|r| r < residual) {
                last_step = (u.iter().map(|x| x.abs()).fold(0.0, f64::max), limited, sol.rank, lambda);
                lambda = if lambda <= 1e-9 * smax2 { 0.0 } else { lambda / 10.0 };
                accepted = true;
                break;
            }
            params.set_values(sys, &current)?;
            lambda = if lambda == 0.0 { 1e-6 * smax2 } else { lambda * 10.0 };
        }
        if !accepted {
            status = Status::Stalled;
            break;
        }
    }
    if status != Status::Converged {
        params.set_values(sys, &best.1)?;
    }
    let final_values = values(sys);
    let residual = if status == Status::Converged { history.last().map_or(f64::NAN, |r| r.residual) } else { best.0 };
    let at_bound = final_values
        .iter()
        .zip(&bounds)
        .map(|(&v, &(lo, hi))| (v - lo).abs() <= 1e-9 * lo.abs() || (v - hi).abs() <= 1e-9 * hi.abs())
        .collect();
    let names: Vec<String> = params.params().iter().map(|p| p.name.clone()).collect();
    let unresolved = crate::lstsq::unresolved_combination(&best_svd.0, &best_svd.1, &names);
    let undetermined = crate::lstsq::unresolved_parameters(&best_svd.0, &best_svd.1, names.len());
    Ok(RfmResult {
        history,
        status,
        values: final_values,
        residual,
        at_bound,
        bounds,
        singular_values: best_svd.0,
        unresolved,
        undetermined,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::{Dof, DofRef};
    use frf::{Channel, FrfKind};
    use num_complex::Complex64 as C64;

    /// Two channels a million times apart in size, one line each: the model
    /// is 1 % off on the small one and exact on the large one.
    fn blocks_and_data(small: C64, large: C64) -> (Vec<FrequencyBlock>, FrfSet) {
        let channels = vec![
            Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(2, Dof::Uy)),
            Channel::new(DofRef::new(3, Dof::Uy), DofRef::new(2, Dof::Uy)),
        ];
        let mut measured = FrfSet::zeros(vec![10.0], channels, FrfKind::Receptance).unwrap();
        measured.set(0, 0, small);
        measured.set(1, 0, large);
        let block = FrequencyBlock { freq_hz: 10.0, model: vec![small * 1.01, large], sens: Mat::zeros(2, 0) };
        (vec![block], measured)
    }

    #[test]
    fn residual_is_the_rms_relative_difference_whatever_the_sizes() {
        let (blocks, measured) = blocks_and_data(C64::new(0.0, 1e-9), C64::new(-3e-3, 4e-3));
        // sqrt((0.01^2 + 0) / 2), independent of the absolute sizes
        assert!((relative_residual(&blocks, &measured) - 0.01 / 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn a_zero_measurement_is_weighed_by_its_channel_size() {
        let channels = vec![
            Channel::new(DofRef::new(2, Dof::Uy), DofRef::new(2, Dof::Uy)),
            Channel::new(DofRef::new(3, Dof::Uy), DofRef::new(2, Dof::Uy)),
        ];
        let mut measured = FrfSet::zeros(vec![10.0, 20.0], channels, FrfKind::Receptance).unwrap();
        measured.set(0, 1, C64::new(3.0, 4.0));
        let w = weights(&measured);
        // channel 0: RMS of (0, 5) is 5 / sqrt 2
        assert!((w[0][0] - 2f64.sqrt() / 5.0).abs() < 1e-15);
        assert!((w[0][1] - 0.2).abs() < 1e-15);
        // a channel of zeros has no size at all: weight 1, never infinite
        assert_eq!(w[1], vec![1.0, 1.0]);
    }

    #[test]
    fn every_status_is_a_name_case_checks_may_use() {
        let all = [
            Status::Converged,
            Status::ModelInadequate,
            Status::LocalMinimum,
            Status::Stalled,
            Status::MaxIterations,
            Status::Runaway,
            Status::Failed("x".into()),
        ];
        // a new variant breaks this match: add it to `all` and to RUN_STATUSES
        for s in &all {
            match s {
                Status::Converged
                | Status::ModelInadequate
                | Status::LocalMinimum
                | Status::Stalled
                | Status::MaxIterations
                | Status::Runaway
                | Status::Failed(_) => {}
            }
        }
        let names: Vec<String> = all
            .iter()
            .map(|s| match serde_json::to_value(s).unwrap() {
                serde_json::Value::String(name) => name,
                // a status with a payload is an object keyed by its name
                serde_json::Value::Object(o) => o.keys().next().unwrap().clone(),
                other => panic!("{other}"),
            })
            .collect();
        assert_eq!(names, fe_model::case::RUN_STATUSES);
        let by_name: Vec<&str> = all.iter().map(Status::name).collect();
        assert_eq!(by_name, fe_model::case::RUN_STATUSES);
    }
}
