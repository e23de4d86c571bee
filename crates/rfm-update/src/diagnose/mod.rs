//! Diagnosis: which physical effect is missing from the model.
//!
//! Every candidate effect ([`candidates`]) is fitted to the measured FRFs by
//! the output-error estimator on the complex-log misfit `ln(H / M)`, which
//! stays well behaved when a resonance is shifted by more than its width
//! (one linearised step from the nominal model does not: it ranks a 40 %
//! stiffness loss behind unrelated masses). Candidates are compared by the
//! Bayesian information criterion with the noise variance estimated from the
//! data themselves:
//!
//! ```text
//! dBIC_c = (cost_c - cost_0) / s^2 + k_c ln(n)
//! ```
//!
//! `cost` is the sum of squared real residuals (`cost_0` for the nominal
//! model), `k_c` the candidate's number of parameters, `n` the number of real
//! residuals, `s^2` the noise variance per real residual. An effect is
//! *significant* when `dBIC < -10` (very strong evidence); when none is, the
//! model is consistent with the data.
//!
//! The noise level comes from the roughness of the measured FRFs: on a line
//! grid fine enough to resolve the structure's response, the second
//! difference of `ln M` across adjacent lines is noise plus a small smooth
//! part, and its median (robust to the few lines at sharp resonances) gives
//! the variance ([`estimate_noise`]).
//!
//! To stay fast with many candidates, all are first fitted briefly on a
//! coarse subset of lines (screening), and the leaders are then fitted fully
//! on the updating lines; the final ranking rests on the full fits only. A
//! large model has thousands of candidates (a mass at every node, damping
//! in every region): above [`DiagnoseOptions::prescreen_above`] of them, all
//! are first fitted with fewer iterations on fewer lines (pre-screening) and
//! only the best few hundred are screened. Screening-only entries of the
//! ranking are scored on their own lines; screened ones come before
//! pre-screened ones.
//! On large models stiffness and mass changes are candidates per region; the
//! two leaders' locations are then refined into per-element changes, which
//! are screened and the best four fitted fully, so that one weakened element
//! is named as such and not as its region or a mass at its node.
//!
//! Every fit is exact but none refactorises the candidate's model: a
//! candidate changes `Z` only on the few equations it touches, so its
//! receptances and sensitivities follow from the nominal model's by a
//! low-rank (Woodbury) update (module `local`), and one factorisation of the
//! nominal `Z` per line serves every candidate. A candidate is its change
//! and the part of the model the change touches, never a copy of the whole
//! model, so nothing per candidate grows with the model. A candidate
//! touching more than a few dozen equations is fitted on its own model
//! instead.

pub mod candidates;
mod local;

use damping::DampedSystem;
use frf::FrfSet;
use rayon::prelude::*;
use serde::Serialize;

pub use candidates::{Candidate, CandidateOptions, EffectKind};

use self::local::{LocalCandidate, LocalData};
use crate::error::UpdateError;
use crate::oe::{self, Misfit, OeData, OeOptions};
use crate::params::ParameterSet;

/// Relative noise level of measured FRFs (RMS of the relative error per
/// complex value), from the roughness of `ln M` over adjacent lines; see the
/// module docs. `None` when there are too few lines.
pub fn estimate_noise(measured: &FrfSet) -> Option<f64> {
    let mut d2 = Vec::new();
    for c in 0..measured.channels().len() {
        let h = measured.channel(c);
        for k in 1..h.len().saturating_sub(1) {
            if h[k - 1].norm() == 0.0 || h[k].norm() == 0.0 || h[k + 1].norm() == 0.0 {
                continue;
            }
            let d = (h[k + 1] / h[k]).ln() - (h[k] / h[k - 1]).ln();
            if d.re.is_finite() && d.im.is_finite() {
                d2.push(d.norm_sqr());
            }
        }
    }
    if d2.len() < 10 {
        return None;
    }
    d2.sort_by(f64::total_cmp);
    let median = d2[d2.len() / 2];
    // d = e(k+1) - 2 e(k) + e(k-1): E|d|^2 = 6 s^2, and the median of an
    // exponential variable is its mean times ln 2
    Some((median / (6.0 * std::f64::consts::LN_2)).sqrt())
}

/// Options of the diagnosis.
#[derive(Clone, Debug)]
pub struct DiagnoseOptions {
    /// Lines for the full fits.
    pub lines: usize,
    /// Above this many candidates, all are first fitted briefly on a few
    /// lines (pre-screening), and only the best `prescreen_keep` are screened.
    pub prescreen_above: usize,
    /// Candidates screened after pre-screening.
    pub prescreen_keep: usize,
    /// Lines for the pre-screening fits.
    pub prescreen_lines: usize,
    /// Iterations of a pre-screening fit.
    pub prescreen_iterations: usize,
    /// Lines for the screening fits.
    pub screen_lines: usize,
    /// Iterations of a screening fit.
    pub screen_iterations: usize,
    /// Candidates fitted fully after screening.
    pub keep: usize,
    /// Iterations of a full fit.
    pub iterations: usize,
    /// `dBIC` below which an effect is significant.
    pub significance: f64,
    /// Candidate generation options (the band is taken from the data).
    pub candidates: CandidateOptions,
}

/// Leaders (by full-fit misfit) whose locations are refined per element.
const REFINED_LEADERS: usize = 2;
/// Refined candidates fitted fully after screening.
const REFINED_FITS: usize = 4;

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            lines: 200,
            prescreen_above: 600,
            prescreen_keep: 300,
            prescreen_lines: 20,
            prescreen_iterations: 3,
            screen_lines: 60,
            screen_iterations: 6,
            keep: 8,
            iterations: 40,
            significance: -10.0,
            candidates: CandidateOptions::default(),
        }
    }
}

/// A fitted parameter of a candidate.
#[derive(Clone, Debug, Serialize)]
pub struct FittedParameter {
    /// Name (in the candidate's model).
    pub name: String,
    /// Fitted value.
    pub value: f64,
    /// Relative standard deviation from the fit.
    pub relative_std: f64,
}

/// One ranked candidate.
#[derive(Clone, Debug, Serialize)]
pub struct Ranked {
    /// Kind.
    pub kind: EffectKind,
    /// Plain-language description with location.
    pub description: String,
    /// Nodes where it acts.
    pub nodes: Vec<u32>,
    /// Elements where it acts.
    pub elements: Vec<u32>,
    /// DOFs it acts on (names).
    pub dof: Vec<String>,
    /// Fraction of the nominal misfit it explains (`1 - cost_c / cost_0`).
    pub explained: f64,
    /// Change of the information criterion (negative is better).
    pub delta_bic: f64,
    /// `delta_bic` below the significance threshold.
    pub significant: bool,
    /// Fitted values within their plausible ranges.
    pub plausible: bool,
    /// Why not, when not plausible.
    pub implausible_reason: Option<String>,
    /// Fitted parameters.
    pub parameters: Vec<FittedParameter>,
    /// Fitted on the full line set (false: screening only).
    pub fully_fitted: bool,
    /// Index of the candidate in [`Diagnosis::candidates`].
    #[serde(skip)]
    pub candidate: usize,
}

/// The outcome of a diagnosis.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    /// Estimated relative noise of the data (RMS per complex value).
    pub noise: f64,
    /// RMS residual of the nominal model on the fitted lines.
    pub nominal_misfit: f64,
    /// Number of real residuals of the full fits.
    pub n_residuals: usize,
    /// Candidates ranked: full fits by `delta_bic`, then screening-only ones.
    pub ranking: Vec<Ranked>,
    /// The candidates (same indices as [`Ranked::candidate`]).
    #[serde(skip)]
    pub candidates: Vec<Candidate>,
}

impl Diagnosis {
    /// The case-file lines that add ranked effect `rank`: the text to append
    /// and the `[set]` entries to merge.
    pub fn proposal(&self, rank: usize) -> (String, Vec<(String, f64)>) {
        let r = &self.ranking[rank];
        let values: Vec<f64> = r.parameters.iter().map(|p| p.value).collect();
        self.candidates[r.candidate].case_lines(&values)
    }

    /// The case text with ranked effect `rank` added at its fitted values.
    /// When the case has no `[update]` section, one is appended that updates
    /// the effect's parameters by output error. The result is reloaded and
    /// checked to carry the fitted values.
    pub fn case_text(&self, case: &fe_model::CaseFile, rank: usize) -> Result<String, UpdateError> {
        let r = self.ranking.get(rank).ok_or_else(|| UpdateError::Setup(format!("there is no rank {}", rank + 1)))?;
        let c = &self.candidates[r.candidate];
        let (snippet, set) = self.proposal(rank);
        let mut text = match &c.edit {
            candidates::Edit::Support { node, .. } => case.without_supports_at(*node)?,
            _ => case.source.clone(),
        };
        if !snippet.is_empty() {
            text.push_str(&format!(
                "\n# Added by rfm diagnose: {} (explains {:.1} % of the misfit)\n",
                r.description,
                100.0 * r.explained
            ));
            text.push_str(&snippet);
        }
        if case.update.is_none() {
            let names: Vec<String> = r.parameters.iter().map(|p| format!("\"{}\"", p.name)).collect();
            text.push_str(&format!("\n[update]\nparameters = [{}]\nmethod = \"output-error\"\n", names.join(", ")));
        }
        let mut reparsed = fe_model::CaseFile::parse(&case.path, &text)?;
        if !set.is_empty() {
            text = reparsed.with_values(&set, &format!("{} (rfm diagnose)", r.description))?;
            reparsed = fe_model::CaseFile::parse(&case.path, &text)?;
        }
        for p in &r.parameters {
            let param = reparsed.model.parameter(&p.name)?;
            let got = reparsed.model.get(param.quantities[0]);
            if (got - p.value).abs() > 1e-12 * p.value.abs() {
                return Err(UpdateError::Setup(format!("{} reads back as {got}, not {}", p.name, p.value)));
            }
        }
        Ok(text)
    }

    /// The best significant, plausible candidate, if any.
    pub fn leader(&self) -> Option<&Ranked> {
        self.ranking.iter().find(|r| r.fully_fitted && r.significant && r.plausible)
    }

    /// True when no candidate is significant: the model is consistent with the data.
    pub fn consistent(&self) -> bool {
        !self.ranking.iter().any(|r| r.fully_fitted && r.significant)
    }
}

fn spread(lines: &[f64], n: usize) -> Vec<f64> {
    if n >= lines.len() {
        return lines.to_vec();
    }
    let mut idx: Vec<usize> =
        (0..n).map(|i| (i as f64 * (lines.len() - 1) as f64 / (n - 1).max(1) as f64).round() as usize).collect();
    idx.dedup();
    idx.into_iter().map(|k| lines[k]).collect()
}

struct Fit {
    values: Vec<f64>,
    cost: f64,
    /// The nominal model's cost on the same lines.
    cost0: f64,
    /// Number of real residuals.
    n: usize,
    relative_std: Vec<f64>,
}

/// The data and the local form of a candidate fitted by low-rank updates of
/// the nominal model (see module `local`).
type Local<'a> = Option<(&'a LocalData, &'a LocalCandidate)>;

/// Fits one candidate to `measured` (`cost0`: the nominal model's cost on
/// it): by low-rank updates when `local` is given, else on its whole model
/// (the nominal model with the candidate's change).
fn fit(
    candidate: &Candidate,
    nominal: &fe_model::Model,
    (measured, cost0): (&FrfSet, f64),
    local: Local<'_>,
    iterations: usize,
    start: Option<&[f64]>,
) -> Option<Fit> {
    let (mut sys, params) = match local {
        Some((_, lc)) => (lc.part.clone(), lc.params.clone()),
        None => {
            let sys = DampedSystem::new(candidate.model(nominal).ok()?).ok()?;
            let params = ParameterSet::new(candidate.parameters_in(sys.model()).ok()?);
            (sys, params)
        }
    };
    if let Some(v) = start {
        params.set_values(&mut sys, v).ok()?;
    }
    // bounds must hold the start
    let now = params.values(&sys);
    let bounds = candidate.bounds.iter().zip(&now).map(|(b, &v)| b.map(|(lo, hi)| (lo.min(v), hi.max(v)))).collect();
    let opts =
        OeOptions { misfit: Misfit::Log, max_iterations: iterations, tolerance: 1e-6, bounds, ..OeOptions::default() };
    let data = OeData { measured, weights: None };
    let r = match local {
        Some((ld, lc)) => {
            let mut response = ld.response(lc, sys);
            oe::run_with(&mut response, now, &data, &opts, |_| {}).ok()?
        }
        None => oe::run(&mut sys, &params, &data, &opts, |_| {}).ok()?,
    };
    let relative_std = (0..params.len()).map(|i| r.covariance[(i, i)].max(0.0).sqrt()).collect();
    Some(Fit { values: r.values, cost: r.cost, cost0, n: r.n_data, relative_std })
}

fn nominal_cost(sys: &DampedSystem, measured: &FrfSet) -> Result<(f64, usize), UpdateError> {
    let model = frf::synthesize(sys, measured.channels(), measured.frequencies_hz())?;
    let (mut cost, mut n) = (0.0, 0);
    for (h, m) in model.values().iter().zip(measured.values()) {
        if m.norm() > 0.0 {
            cost += (h / m).ln().norm_sqr();
            n += 2;
        }
    }
    Ok((cost, n))
}

/// Diagnoses a model against measured receptances (all measured lines; the
/// fits use subsets of them). Candidates are fitted in parallel.
pub fn diagnose(model: &fe_model::Model, measured: &FrfSet, opts: &DiagnoseOptions) -> Result<Diagnosis, UpdateError> {
    let lines = measured.frequencies_hz();
    if lines.len() < 10 {
        return Err(UpdateError::Setup("diagnosis needs at least 10 measured lines".into()));
    }
    let noise = estimate_noise(measured)
        .ok_or_else(|| UpdateError::Setup("too few usable measured values to estimate the noise level".into()))?;
    // a noise floor for noise-free data keeps the criterion finite
    let s2 = (noise * noise / 2.0).max(1e-20);
    let full = measured.at_frequencies(&spread(lines, opts.lines))?;
    let coarse = measured.at_frequencies(&spread(lines, opts.screen_lines))?;
    let nominal = DampedSystem::new(model.clone())?;
    let (cost0_full, n_full) = nominal_cost(&nominal, &full)?;
    let (cost0_coarse, _) = nominal_cost(&nominal, &coarse)?;
    let mut copts = opts.candidates.clone();
    copts.band_hz = (lines[0], lines[lines.len() - 1]);
    let candidates = candidates::generate(model, &copts);
    let bic = |cost: f64, cost0: f64, n: usize, k: usize| (cost - cost0) / s2 + k as f64 * (n as f64).ln();

    // Candidates that change Z only locally are fitted by exact low-rank
    // updates of the nominal model (see `local`), the others on their own.
    let mut locals: Vec<Option<LocalCandidate>> =
        candidates.par_iter().map(|c| LocalCandidate::new(&nominal, c)).collect();
    let local_data = |set: &FrfSet, locals: &[&Option<LocalCandidate>]| {
        let forms: Vec<_> = locals.iter().filter_map(|l| l.as_ref().map(|l| &l.form)).collect();
        LocalData::new(&nominal, set.channels(), set.frequencies_hz(), &forms)
    };
    // Fits `which` of `candidates` on the lines of `set` (`cost0`: the
    // nominal model's cost there), from their starting values.
    let screen = |set: &FrfSet,
                  cost0: f64,
                  iterations: usize,
                  candidates: &[Candidate],
                  locals: &[Option<LocalCandidate>],
                  which: &[usize]|
     -> Result<Vec<(usize, Option<Fit>)>, UpdateError> {
        let data = local_data(set, &which.iter().map(|&i| &locals[i]).collect::<Vec<_>>())?;
        Ok(which
            .par_iter()
            .map(|&i| {
                let (c, local) = (&candidates[i], locals[i].as_ref().map(|l| (&data, l)));
                // a low-rank update that cannot be evaluated (a singular
                // local system at some line) falls back to the whole model
                let f = fit(c, model, (set, cost0), local, iterations, None)
                    .or_else(|| local.and_then(|_| fit(c, model, (set, cost0), None, iterations, None)));
                (i, f)
            })
            .collect())
    };
    // full fits, warm-started from screening
    let full_fit = |candidates: &[Candidate],
                    locals: &[Option<LocalCandidate>],
                    screened: &[Option<Fit>],
                    which: &[usize]|
     -> Result<Vec<(usize, Option<Fit>)>, UpdateError> {
        let data = local_data(&full, &which.iter().map(|&i| &locals[i]).collect::<Vec<_>>())?;
        Ok(which
            .par_iter()
            .map(|&i| {
                let local = locals[i].as_ref().map(|l| (&data, l));
                let start = screened[i].as_ref().map(|f| f.values.as_slice());
                let f = fit(&candidates[i], model, (&full, cost0_full), local, opts.iterations, start)
                    .or_else(|| fit(&candidates[i], model, (&full, cost0_full), None, opts.iterations, start))
                    .or_else(|| fit(&candidates[i], model, (&full, cost0_full), None, opts.iterations, None));
                (i, f)
            })
            .collect())
    };
    // fits on more residuals first (screened before pre-screened), then by dBIC
    let by_rank = |screened: &[Option<Fit>], candidates: &[Candidate], order: &mut Vec<usize>| {
        let key = |i: usize| {
            let f = screened[i].as_ref().expect("only fitted candidates are ranked");
            (f.n, bic(f.cost, f.cost0, f.n, candidates[i].parameters.len()))
        };
        order.sort_by(|&a, &b| {
            let ((na, sa), (nb, sb)) = (key(a), key(b));
            nb.cmp(&na).then(sa.total_cmp(&sb))
        });
    };

    // pre-screening of many candidates, then screening
    let all: Vec<usize> = (0..candidates.len()).collect();
    let mut screened: Vec<Option<Fit>> = (0..candidates.len()).map(|_| None).collect();
    let to_screen = if candidates.len() > opts.prescreen_above {
        let pre = measured.at_frequencies(&spread(lines, opts.prescreen_lines))?;
        let (cost0_pre, _) = nominal_cost(&nominal, &pre)?;
        for (i, f) in screen(&pre, cost0_pre, opts.prescreen_iterations, &candidates, &locals, &all)? {
            screened[i] = f;
        }
        let mut best: Vec<usize> = all.iter().copied().filter(|&i| screened[i].is_some()).collect();
        by_rank(&screened, &candidates, &mut best);
        best.truncate(opts.prescreen_keep);
        best
    } else {
        all
    };
    for (i, f) in screen(&coarse, cost0_coarse, opts.screen_iterations, &candidates, &locals, &to_screen)? {
        if f.is_some() {
            screened[i] = f;
        }
    }
    let mut order: Vec<usize> = (0..candidates.len()).filter(|&i| screened[i].is_some()).collect();
    by_rank(&screened, &candidates, &mut order);
    let keep: Vec<usize> = order.iter().copied().take(opts.keep).collect();
    let mut full_fits = full_fit(&candidates, &locals, &screened, &keep)?;

    // The leaders' locations are refined into per-element stiffness and mass
    // changes (see `candidates::neighbourhood`): on large models those were
    // tried only per region.
    let mut by_cost: Vec<&(usize, Option<Fit>)> = full_fits.iter().filter(|(_, f)| f.is_some()).collect();
    by_cost.sort_by(|a, b| a.1.as_ref().expect("some").cost.total_cmp(&b.1.as_ref().expect("some").cost));
    let tried = |kind: EffectKind, e: u32| candidates.iter().any(|c| c.kind == kind && c.elements == [e]);
    let mut beams: Vec<usize> = Vec::new();
    for (i, _) in by_cost.into_iter().take(REFINED_LEADERS) {
        for b in candidates::neighbourhood(model, &candidates[*i]) {
            let id = model.beams()[b].id.0;
            let both_tried = tried(EffectKind::StiffnessChange, id) && tried(EffectKind::MassChange, id);
            if !beams.contains(&b) && !both_tried {
                beams.push(b);
            }
        }
    }
    let refined = candidates::per_element(model, &beams);
    let refined_locals: Vec<Option<LocalCandidate>> =
        refined.par_iter().map(|c| LocalCandidate::new(&nominal, c)).collect();
    // screened like the others; the best few fitted fully
    let all_refined: Vec<usize> = (0..refined.len()).collect();
    let refined_screened =
        screen(&coarse, cost0_coarse, opts.screen_iterations, &refined, &refined_locals, &all_refined)?;
    let first_refined = candidates.len();
    let mut candidates = candidates;
    candidates.extend(refined);
    locals.extend(refined_locals);
    screened.extend(refined_screened.into_iter().map(|(_, f)| f));
    let mut new: Vec<usize> = (first_refined..candidates.len()).filter(|&i| screened[i].is_some()).collect();
    by_rank(&screened, &candidates, &mut new);
    let best_new: Vec<usize> = new.iter().copied().take(REFINED_FITS).collect();
    full_fits.extend(full_fit(&candidates, &locals, &screened, &best_new)?);
    order.extend(new);
    by_rank(&screened, &candidates, &mut order);

    let ranked = |i: usize, f: &Fit, n: usize, fully: bool| {
        let c = &candidates[i];
        let cost0 = f.cost0;
        let delta_bic = bic(f.cost, cost0, n, c.parameters.len());
        let implausible_reason = c.implausible(&f.values);
        Ranked {
            kind: c.kind,
            description: c.description.clone(),
            nodes: c.nodes.clone(),
            elements: c.elements.clone(),
            dof: c.dofs.iter().map(|d| d.to_string()).collect(),
            explained: (1.0 - f.cost / cost0).max(0.0),
            delta_bic,
            significant: delta_bic < opts.significance,
            plausible: implausible_reason.is_none(),
            implausible_reason,
            parameters: c
                .parameters
                .iter()
                .zip(&f.values)
                .zip(&f.relative_std)
                .map(|((name, &value), &relative_std)| FittedParameter { name: name.clone(), value, relative_std })
                .collect(),
            fully_fitted: fully,
            candidate: i,
        }
    };
    let mut ranking: Vec<Ranked> =
        full_fits.iter().filter_map(|(i, f)| f.as_ref().map(|f| ranked(*i, f, n_full.max(f.n), true))).collect();
    ranking.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    let fitted: Vec<usize> = ranking.iter().map(|r| r.candidate).collect();
    ranking.extend(order.iter().filter(|i| !fitted.contains(i)).map(|&i| {
        let f = screened[i].as_ref().expect("filtered");
        ranked(i, f, f.n, false)
    }));
    Ok(Diagnosis {
        noise,
        nominal_misfit: (cost0_full / (n_full as f64 / 2.0)).sqrt(),
        n_residuals: n_full,
        ranking,
        candidates,
    })
}
