//! Output-error estimation: Levenberg-Marquardt on the FRF residual.
//!
//! The response function method's equation error has measured data on both
//! sides, which biases it when the data are noisy. The output-error
//! estimator instead minimises the misfit between model and measured FRFs
//! directly, over log-parameters `theta_i = ln(p_i / p_i0)` (so physical
//! parameters stay positive):
//!
//! ```text
//! cost(theta) = sum_{lines k, channels c} |rho_kc|^2  +  tau sum_i theta_i^2
//! rho_kc = w_kc (g_v H_kc - M_kc) / |M_kc|        (misfit "relative")
//! rho_kc = w_kc ln(g_v H_kc / M_kc)               (misfit "log": log-magnitude and phase)
//! ```
//!
//! with `H` the model receptance, `M` the measured one, `w_kc >= 0` line
//! weights (band weights, coherence; 0 masks a line) and `g_v = exp(a_v + j b_v)`
//! an optional unknown complex gain per reference or per channel `v` (FRFs
//! referenced to a shaker amplifier's voltage carry one per reference; an
//! accelerometer of unknown sensitivity one per channel). For
//! multiplicative noise of relative level `s`, both forms give residuals of
//! standard deviation about `s` per complex value, so the weighting is the
//! maximum-likelihood one.
//!
//! The log form is the default: far from the solution, where the model's
//! resonances sit where the data have none, the relative residual is
//! dominated by the model's own peaks (`|H| / |M|` in the hundreds) and the
//! iteration stalls, while `ln(H / M)` grows only logarithmically; from the
//! paper's initial values of the flexible-clamp twin (springs 20 times too
//! stiff) the log form reaches the truth and the relative form does not.
//! Near the solution the two agree to first order.
//!
//! The Jacobian comes from the shared sensitivity assembly: `(dH/dp) p = -S`
//! with the model's own column ([`crate::sensitivity::Hybrid::Model`]). Each
//! iteration solves the column-scaled, Tikhonov-damped Gauss-Newton system by
//! SVD; a step is taken only if it lowers the cost, with the damping raised
//! tenfold after each rejection and relaxed after each success. Bounds are
//! enforced by projecting the step; without user bounds each parameter stays
//! within a factor of 1e6 of its start, so that one the data do not
//! determine cannot wander off to zero or infinity (it ends on that bound,
//! and is reported there). Convergence is declared when the Gauss-Newton
//! step would lower the cost by less than a relative 1e-10, when an accepted
//! step gains less than a relative 1e-9, or when steps no longer change any
//! parameter by more than the tolerance.
//!
//! Parameters the data hardly separate (a joint's stiffness, damping and
//! relaxation together) make a long, curved, nearly flat valley, along which
//! Levenberg-Marquardt creeps: the f-frame twin needs about 1,700 steps to a
//! stationary point, the last 1,600 of which lower the chi-square
//! (`cost / s^2`) by about 2.5 in all. So the fit also stops (a stationary
//! point to within what the noise can show, [`OeResult::flat_valley`]), when
//! the chi-square fell by less than 0.5 over the last 10 steps (`OeOptions::stop_within_noise`, on by default; not
//! applied with Tikhonov regularisation, where the cost is not a
//! chi-square). A point whose chi-square is within a few units of the
//! minimum's lies well inside its joint confidence region, and the
//! covariance there reports the flat directions as undetermined.
//!
//! At the solution the covariance of `theta` is `s^2 (J^T J)^+` with `s^2` the
//! residual variance estimated from the fit; see [`crate::uncertainty`].

mod residual;
mod response;

use damping::DampedSystem;
use faer::Mat;
use fe_model::case::{FittedGain, GainKey, Gains};
use frf::{Channel, FrfSet, ZSolver};
use num_complex::Complex64 as C64;

pub(crate) use response::{Evaluated, Response};

use self::residual::{Evaluator, Point, adjacent_correlation};
use self::response::FullModel;
use crate::error::UpdateError;
use crate::lstsq;
use crate::params::ParameterSet;
use crate::sensitivity::ChannelPlan;
use crate::status::{IterationRecord, Status};

/// Form of the residual; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Misfit {
    /// `(H - M) / |M|`.
    Relative,
    /// `ln(H / M)`.
    Log,
}

impl Misfit {
    /// Parses `relative` or `log`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "relative" => Some(Misfit::Relative),
            "log" => Some(Misfit::Log),
            _ => None,
        }
    }
}

/// Steps over which the chi-square gain is tested against the noise.
const NOISE_WINDOW: usize = 10;
/// Chi-square gain over [`NOISE_WINDOW`] steps below which the fit stops
/// ([`OeResult::flat_valley`]): less than the noise can show.
pub(crate) const NOISE_WINDOW_GAIN: f64 = 0.5;

/// Options of the output-error estimator.
#[derive(Clone, Debug)]
pub struct OeOptions {
    /// Residual form.
    pub misfit: Misfit,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Converged when no parameter changes by more than this (relative) in a step.
    pub tolerance: f64,
    /// Tikhonov weight `tau` on `theta_i^2`.
    pub regularization: f64,
    /// Bounds per parameter in physical units (`None`: unbounded).
    pub bounds: Vec<Option<(f64, f64)>>,
    /// Unknown complex gains to estimate: none, one per reference or one
    /// per channel ([`crate::gain`]).
    pub gains: Gains,
    /// Relative singular-value cut-off.
    pub rcond: f64,
    /// Stop when the last steps gain less than the noise can show
    /// ([`OeResult::flat_valley`]); off, the fit runs to a stationary point
    /// or the iteration limit.
    pub stop_within_noise: bool,
    /// Restarts from spread starts when the fit ends above the noise or
    /// without converging (see [`crate::study::Study::run_output_error`]);
    /// 0: none.
    pub restarts: usize,
    /// Compute [`OeResult::jackknife`] (a solve per left-out block of
    /// lines); off where only the fit and its plain covariance are read,
    /// as in the diagnosis's tens of thousands of candidate fits.
    pub jackknife: bool,
}

impl Default for OeOptions {
    fn default() -> Self {
        OeOptions {
            misfit: Misfit::Log,
            max_iterations: 100,
            tolerance: 1e-8,
            regularization: 0.0,
            bounds: Vec::new(),
            gains: Gains::None,
            rcond: 1e-12,
            stop_within_noise: true,
            restarts: 6,
            jackknife: true,
        }
    }
}

/// A fitted gain of one reference or one channel.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Gain {
    /// What it multiplies: a reference's channels (`1:uy`) or one channel
    /// (`H(31:uy,1:uy)`).
    #[cfg_attr(feature = "serde", serde(serialize_with = "crate::serialize_display"))]
    pub key: GainKey,
    /// Magnitude of the gain.
    pub magnitude: f64,
    /// Phase of the gain (degrees).
    pub phase_deg: f64,
}

impl Gain {
    /// The complex factor.
    pub fn factor(&self) -> C64 {
        C64::from_polar(self.magnitude, self.phase_deg.to_radians())
    }

    /// The gain as a case file keeps it (`fitted_gains`).
    pub fn fitted(&self) -> FittedGain {
        FittedGain { key: self.key, magnitude: self.magnitude, phase_deg: self.phase_deg }
    }

    /// Whether this gain multiplies `channel`: every channel of its
    /// reference, or its one channel.
    pub fn applies_to(&self, channel: &Channel) -> bool {
        match self.key {
            GainKey::Reference(r) => channel.reference == r,
            GainKey::Channel(response, reference) => channel.response == response && channel.reference == reference,
        }
    }

    /// The product of the gains in `gains` that multiply `channel` (1 when
    /// none does).
    pub fn factor_of(gains: &[Gain], channel: &Channel) -> C64 {
        gains.iter().filter(|g| g.applies_to(channel)).map(Gain::factor).product()
    }

    /// Multiplies every channel of `frfs` by the gains that apply to it
    /// (what the fit compared with the data).
    pub fn apply_all(gains: &[Gain], frfs: &mut FrfSet) {
        for c in 0..frfs.channels().len() {
            let g = Gain::factor_of(gains, &frfs.channels()[c]);
            if g != C64::new(1.0, 0.0) {
                frfs.channel_mut(c).iter_mut().for_each(|v| *v *= g);
            }
        }
    }
}

/// Outcome of an output-error fit.
#[derive(Clone, Debug)]
pub struct OeResult {
    /// How the iteration ended: [`Status::Converged`] at a stationary point
    /// (whatever the residual; the study compares it with the noise),
    /// [`Status::Stalled`], [`Status::MaxIterations`] or [`Status::Failed`].
    pub status: Status,
    /// The fit stopped because its last steps lowered the chi-square by less
    /// than the noise can show (a long flat valley; `status` is then
    /// [`Status::Converged`]).
    pub flat_valley: bool,
    /// Fitted parameter values.
    pub values: Vec<f64>,
    /// Fitted gains (empty unless requested).
    pub gains: Vec<Gain>,
    /// Iteration records (`residual` is the RMS weighted residual).
    pub history: Vec<IterationRecord>,
    /// Final data cost (weighted sum of squares, without regularisation).
    pub cost: f64,
    /// Number of real residuals that carry weight.
    pub n_data: usize,
    /// Covariance of `(theta, gain parameters)` at the solution.
    pub covariance: Mat<f64>,
    /// Estimated residual variance per real residual.
    pub sigma2: f64,
    /// Covariance of `(theta, gain parameters)` by the delete-a-block
    /// jackknife over the lines ([`crate::jackknife`]): the spread that
    /// model error gives the estimates. `None` when not asked for
    /// ([`OeOptions::jackknife`]), with regularisation, or with too
    /// few lines.
    pub jackknife: Option<Mat<f64>>,
    /// Singular values of the column-scaled Jacobian at the solution.
    pub singular_values: Vec<f64>,
    /// Right singular vectors of the scaled Jacobian (columns), to name
    /// parameter combinations the data cannot determine.
    pub v: Mat<f64>,
    /// Parameters that ended on a bound.
    pub at_bound: Vec<bool>,
    /// Correlation of the residuals at adjacent lines (same channel, real
    /// and imaginary parts), `sum r_k r_k+1 / sum r_k^2`: near 0 for noise,
    /// near 1 when a smooth misfit the model cannot represent remains.
    pub residual_correlation: f64,
}

/// The data of a fit: measured receptances at the fitted lines and weights.
#[derive(Clone, Debug)]
pub struct OeData<'a> {
    /// Measured receptance (its lines are the fitted lines).
    pub measured: &'a FrfSet,
    /// Weights, channel-major like the data (`None`: all 1).
    pub weights: Option<&'a [f64]>,
}

fn project(x: &mut [f64], lo: &[f64], hi: &[f64]) {
    for ((v, l), h) in x.iter_mut().zip(lo).zip(hi) {
        *v = v.clamp(*l, *h);
    }
}

/// Fits `params` of `sys` (updated in place) to the measured data; see the
/// module docs. `on_iteration` sees each record as it is made.
pub fn run(
    sys: &mut DampedSystem,
    params: &ParameterSet,
    data: &OeData<'_>,
    opts: &OeOptions,
    on_iteration: impl FnMut(&IterationRecord),
) -> Result<OeResult, UpdateError> {
    let p0 = params.values(sys);
    let mut src = FullModel {
        solver: ZSolver::new(sys.assembly().pattern())?,
        plan: ChannelPlan::new(sys, data.measured.channels())?,
        sys,
        params,
    };
    run_with(&mut src, p0, data, opts, on_iteration)
}

/// As [`run`], for any [`Response`] starting at the parameter values `p0`;
/// the response is left at the final values.
pub(crate) fn run_with(
    src: &mut impl Response,
    p0: Vec<f64>,
    data: &OeData<'_>,
    opts: &OeOptions,
    mut on_iteration: impl FnMut(&IterationRecord),
) -> Result<OeResult, UpdateError> {
    let measured = data.measured;
    if let Some(w) = data.weights
        && w.len() != measured.values().len()
    {
        return Err(UpdateError::Method(format!("{} weights for {} data values", w.len(), measured.values().len())));
    }
    let (group_of, keys) = crate::gain::gain_groups(measured.channels(), opts.gains);
    let ev = Evaluator::new(data, opts, group_of, keys, p0);
    let (n, ng) = (ev.n_params(), ev.n_gain());
    let n_data = ev.n_data();
    let m_free = n + ng;
    if n_data == 0 {
        return Err(UpdateError::Data("every measured value has zero weight".into()));
    }
    // bounds in theta; gains are unbounded
    let mut lo = vec![f64::NEG_INFINITY; n + ng];
    let mut hi = vec![f64::INFINITY; n + ng];
    for i in 0..n {
        match opts.bounds.get(i).copied().flatten() {
            Some((l, h)) => {
                lo[i] = (l / ev.p0[i]).ln();
                hi[i] = (h / ev.p0[i]).ln();
            }
            None => {
                lo[i] = -(1e6f64.ln());
                hi[i] = 1e6f64.ln();
            }
        }
    }
    let mut x = vec![0.0; n + ng];
    if opts.gains != Gains::None {
        // start each gain at its least-squares value for the initial model
        ev.apply(src, &x)?;
        let (model, _) = src.evaluate(measured.frequencies_hz(), false).ok_or_else(|| {
            UpdateError::Numerics(
                "the initial model cannot be evaluated at the updating lines (a singular or non-finite dynamic \
                     stiffness)"
                    .into(),
            )
        })?;
        for v in 0..ev.keys.len() {
            let (mut num, mut den) = (C64::new(0.0, 0.0), 0.0);
            for c in (0..measured.channels().len()).filter(|&c| ev.group_of[c] == v) {
                for k in 0..measured.n_freq() {
                    let (h, m) = (model[k][c], measured.get(c, k));
                    let w = ev.weight(c, k) / m.norm().max(1e-300);
                    num += h.conj() * m * w * w;
                    den += h.norm_sqr() * w * w;
                }
            }
            if den > 0.0 && num.norm() > 0.0 {
                let g = (num / den).ln();
                x[n + 2 * v] = g.re;
                x[n + 2 * v + 1] = g.im;
            }
        }
    }
    let mut point = ev.eval(src, &x, true).ok_or_else(|| {
        UpdateError::Numerics(
            "the initial model cannot be evaluated at the updating lines (a singular or non-finite dynamic stiffness)"
                .into(),
        )
    })?;
    if !point.cost.is_finite() {
        return Err(UpdateError::Numerics(format!(
            "the misfit of the initial model is {}: its receptances or the measured ones are not finite numbers",
            point.cost
        )));
    }
    let record = |iteration: usize, p: &Point, x: &[f64], max_step: f64, lambda: f64, rank: usize| IterationRecord {
        iteration,
        residual: (p.cost_data / (n_data as f64 / 2.0)).sqrt(),
        max_correction: max_step,
        limited: 0,
        rank,
        lambda,
        values: ev.p0.iter().zip(x).map(|(p, t)| p * t.exp()).collect(),
    };
    let mut history = vec![record(0, &point, &x, 0.0, 0.0, n + ng)];
    on_iteration(&history[0]);
    let mut lambda = 0.0;
    let mut status = Status::MaxIterations;
    let mut flat_valley = false;
    // data misfit after each accepted step, for the test against the noise
    let mut costs = vec![point.cost_data];
    for iteration in 1..=opts.max_iterations {
        let jac = point.jacobian.as_ref().expect("points kept have a Jacobian");
        let minus_r: Vec<f64> = point.residual.iter().map(|v| -v).collect();
        // the step only: by the SVD of the QR's R factor, a quarter of the cost
        let sol = lstsq::solve_tall(jac, &minus_r, opts.rcond);
        // first-order optimality: the Gauss-Newton step would gain almost nothing
        let predicted = sol.predicted_reduction();
        if predicted <= 1e-10 * point.cost {
            status = Status::Converged;
            break;
        }
        let smax2 = sol.largest_singular_value().powi(2);
        let mut accepted = None;
        for _ in 0..20 {
            let mut step = if lambda == 0.0 { sol.x.clone() } else { sol.damped(lambda) };
            // at most a factor of 100 per step in any parameter
            for s in step.iter_mut().take(n) {
                *s = s.clamp(-(100f64.ln()), 100f64.ln());
            }
            let mut trial: Vec<f64> = x.iter().zip(&step).map(|(a, b)| a + b).collect();
            project(&mut trial, &lo, &hi);
            if let Some(p) = ev.eval(src, &trial, src.cheap_jacobian())
                && p.cost < point.cost
            {
                accepted = Some((trial, p));
                lambda = if lambda <= 1e-9 * smax2 { 0.0 } else { lambda / 10.0 };
                break;
            }
            lambda = if lambda == 0.0 { 1e-4 * smax2 } else { lambda * 10.0 };
        }
        let Some((trial, trial_point)) = accepted else {
            // no step lowers the cost: at the optimum to working precision
            status = if predicted <= 1e-6 * point.cost { Status::Converged } else { Status::Stalled };
            break;
        };
        let max_step = trial.iter().zip(&x).take(n).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let relative_gain = (point.cost - trial_point.cost) / point.cost;
        x = trial;
        point = match trial_point.jacobian {
            Some(_) => trial_point,
            None => match ev.eval(src, &x, true) {
                Some(p) => p,
                None => {
                    status = Status::Failed("the model cannot be evaluated at the accepted step".into());
                    break;
                }
            },
        };
        let rec = record(iteration, &point, &x, max_step, lambda, sol.rank);
        on_iteration(&rec);
        history.push(rec);
        if max_step < opts.tolerance || relative_gain < 1e-9 {
            status = Status::Converged;
            break;
        }
        // A fit in a long, flat valley (parameters the data hardly separate)
        // can creep for thousands of steps. Stop when the chi-square fell by
        // less than NOISE_WINDOW_GAIN over the last NOISE_WINDOW steps: no
        // measurement with this noise could tell the points apart.
        costs.push(point.cost_data);
        if opts.stop_within_noise && costs.len() > NOISE_WINDOW && opts.regularization == 0.0 {
            let sigma2 = point.cost_data / (n_data as f64 - m_free as f64).max(1.0);
            let gain = (costs[costs.len() - 1 - NOISE_WINDOW] - point.cost_data) / sigma2;
            if gain < NOISE_WINDOW_GAIN {
                status = Status::Converged;
                flat_valley = true;
                break;
            }
        }
    }
    // leave the system at the final point and analyse it
    let final_point = match point.jacobian {
        Some(_) => point,
        None => {
            ev.eval(src, &x, true).ok_or_else(|| UpdateError::Numerics("the final model cannot be evaluated".into()))?
        }
    };
    ev.apply(src, &x)?;
    let at_bound: Vec<bool> = (0..n).map(|i| (x[i] - lo[i]).abs() < 1e-9 || (x[i] - hi[i]).abs() < 1e-9).collect();
    let jac = final_point.jacobian.as_ref().expect("final point has a Jacobian");
    let sol = lstsq::solve(jac, &vec![0.0; jac.nrows()], opts.rcond);
    let free = (0..n).filter(|&i| !at_bound[i]).count() + ng;
    let dof = (n_data as f64 - free as f64).max(1.0);
    let sigma2 = final_point.cost_data / dof;
    let covariance = covariance(&sol, sigma2);
    let residual_correlation =
        adjacent_correlation(&final_point.residual, measured.n_freq(), measured.channels().len());
    let jackknife = if opts.jackknife && opts.regularization == 0.0 {
        let fixed: Vec<bool> = (0..jac.ncols()).map(|j| j < n && at_bound[j]).collect();
        crate::jackknife::block_covariance(
            jac,
            &final_point.residual,
            measured.n_freq(),
            measured.channels().len(),
            &fixed,
            opts.rcond,
        )
    } else {
        None
    };
    let gains = (0..ev.keys.len())
        .filter(|_| opts.gains != Gains::None)
        .map(|v| {
            let g = ev.gain(&x, v);
            Gain { key: ev.keys[v], magnitude: g.norm(), phase_deg: g.arg().to_degrees() }
        })
        .collect();
    Ok(OeResult {
        status,
        flat_valley,
        values: ev.p0.iter().zip(&x).map(|(p, t)| p * t.exp()).collect(),
        gains,
        history,
        cost: final_point.cost_data,
        n_data,
        covariance,
        sigma2,
        jackknife,
        singular_values: sol.singular_values.clone(),
        v: sol.v.clone(),
        at_bound,
        residual_correlation,
    })
}

/// `sigma2 (J^T J)^+` from the column-scaled SVD of the Jacobian `J`, with
/// unbounded variance in the directions the data cannot resolve (the
/// pseudo-inverse would report zero there).
fn covariance(sol: &lstsq::LstsqSolution, sigma2: f64) -> Mat<f64> {
    let m = sol.column_norms.len();
    let undetermined = sol.undetermined();
    Mat::from_fn(m, m, |i, j| {
        if i == j && undetermined[i] {
            f64::INFINITY
        } else if undetermined[i] || undetermined[j] {
            0.0
        } else {
            sigma2 * sol.scaled_inverse_normal[(i, j)] / (sol.column_norms[i] * sol.column_norms[j])
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Columns `c`, `c` again (the data see only the sum of the first two
    /// unknowns) and `d`, not orthogonal to `c`: the first two have
    /// unbounded variance and no covariance with anything, the third the
    /// variance of the problem with columns `c` and `d`, `sigma2 |c|^2 /
    /// (|c|^2 |d|^2 - (c.d)^2)`.
    #[test]
    fn covariance_is_unbounded_where_the_data_cannot_resolve_and_sigma2_times_the_inverse_elsewhere() {
        let (c, d) = ([1.0, 2.0, 0.0, 1.0], [1.0e3, 0.0, 3.0e3, 2.0e3]);
        let a = Mat::from_fn(4, 3, |i, j| if j < 2 { c[i] } else { d[i] });
        let sol = lstsq::solve(&a, &[1.0, -1.0, 0.5, 2.0], 1e-10);
        assert_eq!(sol.undetermined(), vec![true, true, false]);
        let sigma2 = 0.3;
        let cov = covariance(&sol, sigma2);
        assert_eq!((cov[(0, 0)], cov[(1, 1)]), (f64::INFINITY, f64::INFINITY));
        for (i, j) in [(0, 1), (1, 0), (0, 2), (2, 0), (1, 2), (2, 1)] {
            assert_eq!(cov[(i, j)], 0.0, "({i}, {j})");
        }
        let dot = |x: &[f64; 4], y: &[f64; 4]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
        let want = sigma2 * dot(&c, &c) / (dot(&c, &c) * dot(&d, &d) - dot(&c, &d).powi(2));
        assert!((cov[(2, 2)] / want - 1.0).abs() < 1e-10, "{} against {want}", cov[(2, 2)]);
    }

    /// A [`Response`] that delegates to another, says whether its Jacobian
    /// is cheap as told, and counts the evaluations.
    struct Counted<'r, R> {
        inner: &'r mut R,
        cheap: bool,
        evaluations: usize,
    }

    impl<R: Response> Response for Counted<'_, R> {
        fn set(&mut self, values: &[f64]) -> Result<(), UpdateError> {
            self.inner.set(values)
        }

        fn evaluate(&mut self, lines: &[f64], jacobian: bool) -> Option<response::Evaluated> {
            self.evaluations += 1;
            self.inner.evaluate(lines, jacobian)
        }

        fn cheap_jacobian(&self) -> bool {
            self.cheap
        }
    }

    /// A whole model's trial steps evaluated with their sensitivities
    /// ([`FullModel`] says its Jacobian is cheap) take the fit through the
    /// same iterates, bit for bit, as trial steps evaluated by their
    /// receptances alone with the sensitivities made once a step is
    /// accepted, and the fit evaluates the model fewer times: an accepted
    /// step needs no second evaluation. With a gain per reference, whose
    /// start is fitted to the receptances of the first evaluation.
    #[test]
    fn trial_steps_with_their_sensitivities_make_the_same_iterates_in_fewer_evaluations() {
        use fe_model::{Dof, DofRef, samples};
        use frf::{Channel, NoiseModel};
        let truth = DampedSystem::new(samples::cantilever(12)).unwrap();
        let tip = DofRef::new(13, Dof::Uy);
        let channels: Vec<Channel> = [5, 9, 13].iter().map(|&n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
        let lines: Vec<f64> = (1..=120).map(|i| 4.0 * f64::from(i)).collect();
        let mut data = frf::synthesize(&truth, &channels, &lines).unwrap();
        NoiseModel::relative(0.01, 5).apply(&mut data);
        let names = ["group.beam.alpha", "group.beam.beta", "element.4.stiffness", "element.10.mass"];
        let start = [0.4, 2.5, 0.7, 1.3];
        let fit = |cheap: bool, gains: Gains| {
            let mut sys = truth.clone();
            let params = ParameterSet::new(names.iter().map(|n| sys.model().parameter(n).unwrap()).collect());
            let p0: Vec<f64> = params.values(&sys).iter().zip(start).map(|(v, f)| v * f).collect();
            params.set_values(&mut sys, &p0).unwrap();
            let mut full = FullModel {
                solver: ZSolver::new(sys.assembly().pattern()).unwrap(),
                plan: ChannelPlan::new(&sys, data.channels()).unwrap(),
                sys: &mut sys,
                params: &params,
            };
            let mut counted = Counted { inner: &mut full, cheap, evaluations: 0 };
            let opts = OeOptions { gains, ..OeOptions::default() };
            let r = run_with(&mut counted, p0, &OeData { measured: &data, weights: None }, &opts, |_| {}).unwrap();
            (r, counted.evaluations)
        };
        for gains in [Gains::None, Gains::PerReference] {
            let ((cheap, n_cheap), (dear, n_dear)) = (fit(true, gains), fit(false, gains));
            assert!(cheap.history.len() > 5, "a fit of several steps: {}", cheap.history.len());
            assert_eq!(cheap.history.len(), dear.history.len());
            for (a, b) in cheap.history.iter().zip(&dear.history) {
                assert_eq!(
                    (a.residual, &a.values, a.lambda),
                    (b.residual, &b.values, b.lambda),
                    "step {}",
                    a.iteration
                );
            }
            assert_eq!((cheap.values, cheap.cost, cheap.status), (dear.values, dear.cost, dear.status));
            assert_eq!(cheap.gains.len(), dear.gains.len());
            // every accepted step saved an evaluation
            assert_eq!(n_dear - n_cheap, cheap.history.len() - 1, "{n_cheap} against {n_dear} evaluations");
        }
    }

    /// A gain multiplies exactly the channels of its reference, by its
    /// magnitude and phase.
    #[test]
    fn a_gain_multiplies_the_channels_of_its_reference_only() {
        use fe_model::{Dof, DofRef};
        let (a, b) = (DofRef::new(3, Dof::Uy), DofRef::new(5, Dof::Uy));
        let channels = vec![frf::Channel::new(a, a), frf::Channel::new(b, a), frf::Channel::new(a, b)];
        let mut set = FrfSet::zeros(vec![10.0, 20.0], channels, frf::FrfKind::Receptance).unwrap();
        for c in 0..3 {
            set.channel_mut(c).iter_mut().for_each(|v| *v = C64::new(1.0, 0.0));
        }
        Gain::apply_all(&[Gain { key: GainKey::Reference(a), magnitude: 2.0, phase_deg: 90.0 }], &mut set);
        for c in 0..2 {
            for v in set.channel(c) {
                assert!((v - C64::new(0.0, 2.0)).norm() < 1e-15, "{v}");
            }
        }
        assert!(set.channel(2).iter().all(|v| *v == C64::new(1.0, 0.0)));
    }
}
