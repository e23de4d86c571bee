//! The stages of the diagnosis over a pool of candidates: pre-screening,
//! screening, full fits, refinement around the leaders, a damping group per
//! direction for leading supports and joints, the twins of the leading
//! stiffness changes, and holding what the data cannot determine.
//! [`super::diagnose`] runs them in that order.

use std::collections::HashSet;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

use damping::DampedSystem;
use frf::FrfSet;
use rayon::prelude::*;

use super::candidates::{self, Candidate, CandidateOptions, EffectKind, Role};
use super::lines::LineSet;
use super::local::{LocalCandidate, LocalData, LocalForm, Slots};
use super::{DiagnoseOptions, FitStage};
use crate::error::UpdateError;
use crate::output_error::{self, Misfit, OeData, OeOptions};
use crate::params::ParameterSet;

/// The relative standard deviation (of the log-parameter) above which a
/// fitted value is not determined by the data: it could as well be e times
/// larger or smaller.
pub(crate) const UNDETERMINED_STD: f64 = 1.0;

/// One fit of one candidate.
#[derive(Clone, Debug)]
pub(crate) struct Fit {
    pub(crate) values: Vec<f64>,
    pub(crate) cost: f64,
    /// The nominal model's cost on the same lines.
    pub(crate) cost0: f64,
    /// Number of real residuals.
    pub(crate) n: usize,
    /// Lines fitted on (see [`super::informative_lines`]).
    pub(crate) lines: usize,
    pub(crate) relative_std: Vec<f64>,
    /// Per parameter: the data determine it (see [`determined`]).
    pub(crate) determined: Vec<bool>,
    /// The gains fitted with it (empty unless the line set fits gains).
    pub(crate) gains: Vec<output_error::Gain>,
}

/// Per parameter, whether the data determine it: a finite relative standard
/// deviation below [`UNDETERMINED_STD`], and for a spring not at its upper
/// bound (where it is as good as rigid and its sensitivity vanishes).
fn determined(c: &Candidate, r: &output_error::OeResult, relative_std: &[f64]) -> Vec<bool> {
    (0..c.parameters.len())
        .map(|i| {
            let rigid = matches!(c.roles[i], Role::Spring(_))
                && r.at_bound[i]
                && c.bounds[i].is_some_and(|(_, hi)| r.values[i] >= 0.5 * hi);
            relative_std[i].is_finite() && relative_std[i] <= UNDETERMINED_STD && !rigid
        })
        .collect()
}

/// The data and the local form of a candidate fitted by low-rank updates of
/// the nominal model (see module `local`).
type Local<'a> = Option<(&'a LocalData, &'a LocalCandidate)>;

/// Fits one candidate to a line set: by low-rank updates when `local` is
/// given, else on its whole model (the nominal model with the candidate's
/// change). The error says why the fit failed.
fn fit(
    candidate: &Candidate,
    nominal: &fe_model::Model,
    lines: &LineSet,
    local: Local<'_>,
    iterations: usize,
    start: Option<&[f64]>,
) -> Result<Fit, String> {
    let (mut sys, params) = match local {
        Some((_, lc)) => (lc.part.clone(), lc.params.clone()),
        None => {
            let model = candidate.model(nominal).map_err(|e| e.to_string())?;
            let sys = DampedSystem::new(model).map_err(|e| e.to_string())?;
            let params = ParameterSet::new(candidate.parameters_in(sys.model()).map_err(|e| e.to_string())?);
            (sys, params)
        }
    };
    if let Some(v) = start {
        params.set_values(&mut sys, v).map_err(|e| e.to_string())?;
    }
    // bounds must hold the start
    let now = params.values(&sys);
    let bounds = candidate.bounds.iter().zip(&now).map(|(b, &v)| b.map(|(lo, hi)| (lo.min(v), hi.max(v)))).collect();
    let opts = OeOptions {
        misfit: Misfit::Log,
        max_iterations: iterations,
        tolerance: 1e-6,
        bounds,
        gains: lines.gains,
        // the ranking reads the plain covariance only
        jackknife: false,
        ..OeOptions::default()
    };
    let data = OeData { measured: &lines.data, weights: lines.weights.as_deref() };
    let r = match local {
        Some((ld, lc)) => {
            let Some(mut response) = ld.response(lc, sys, lines.data.frequencies_hz()) else {
                return Err("the nominal model's low-rank data do not serve it".into());
            };
            output_error::run_with(&mut response, now, &data, &opts, |_| {})
        }
        None => output_error::run(&mut sys, &params, &data, &opts, |_| {}),
    }
    .map_err(|e| e.to_string())?;
    if !r.cost.is_finite() {
        return Err("its misfit is not finite".into());
    }
    let relative_std: Vec<f64> = (0..params.len()).map(|i| r.covariance[(i, i)].max(0.0).sqrt()).collect();
    let determined = determined(candidate, &r, &relative_std);
    Ok(Fit {
        values: r.values,
        cost: r.cost,
        cost0: lines.cost0,
        n: r.n_data,
        lines: lines.data.n_freq(),
        relative_std,
        determined,
        gains: r.gains,
    })
}

/// The candidates of a diagnosis with their fits so far.
pub(crate) struct Pool<'a> {
    model: &'a fe_model::Model,
    nominal: &'a DampedSystem,
    pub(crate) candidates: Vec<Candidate>,
    /// Fuller variants left unfitted: their plain twin, through which they
    /// were pre-screened, was not among the best.
    pub(crate) deferred: Vec<usize>,
    locals: Vec<Option<LocalCandidate>>,
    /// The latest screening fit of each candidate.
    pub(crate) screened: Vec<Option<Fit>>,
    /// The full fit of each candidate, when it had one.
    pub(crate) full: Vec<Option<Fit>>,
    /// Why a candidate's last attempt at a fit failed, and at which stage
    /// (`None` once a later attempt succeeds).
    pub(crate) failure: Vec<Option<(FitStage, String)>>,
    /// Candidates superseded by a variant that holds what the data did not determine.
    pub(crate) superseded: Vec<bool>,
    /// Noise variance per real residual.
    s2: f64,
    /// Starting values of relaxation parameters tried in full fits (rad/s).
    mu_starts: Vec<f64>,
    /// The low-rank data the next stages will need (see [`Pool::plan`]).
    plan: Option<Plan>,
    /// The low-rank data last gathered by the plan.
    gathered: Mutex<Option<Arc<LocalData>>>,
    /// Where the time of the stages went, for the progress messages.
    pub(crate) clock: Clock,
    /// Gather the refinement's sets of equations with the screening's
    /// data (see [`search`]); off only where a test compares the two paths.
    pub(crate) anticipate: bool,
    /// Makes the fits of the candidates it picks fail at a stage: the
    /// failures a real search meets (a singular low-rank and whole-model
    /// system at a line, a misfit that is not finite) hang on floating-point
    /// coincidences that no test can place on chosen candidates.
    #[cfg(test)]
    pub(crate) forced_failure: Option<fn(&Candidate, FitStage) -> bool>,
}

impl<'a> Pool<'a> {
    pub(crate) fn new(model: &'a fe_model::Model, nominal: &'a DampedSystem, s2: f64, band_hz: (f64, f64)) -> Self {
        let (w_lo, w_hi) = (2.0 * std::f64::consts::PI * band_hz.0, 2.0 * std::f64::consts::PI * band_hz.1);
        // below, inside and above the band's middle, log-spaced
        let mu_starts = vec![3.0 * w_lo, (w_lo * w_hi).sqrt(), w_hi / 3.0];
        Pool {
            model,
            nominal,
            candidates: Vec::new(),
            deferred: Vec::new(),
            locals: Vec::new(),
            screened: Vec::new(),
            full: Vec::new(),
            failure: Vec::new(),
            superseded: Vec::new(),
            s2,
            mu_starts,
            plan: None,
            gathered: Mutex::new(None),
            clock: Clock::default(),
            anticipate: true,
            #[cfg(test)]
            forced_failure: None,
        }
    }

    /// Frees the search's working data (the candidates' local forms and
    /// the low-rank data gathered last) aside, once the fits are done.
    pub(crate) fn release(&mut self) {
        free_aside((
            std::mem::take(&mut self.locals),
            self.gathered.get_mut().unwrap_or_else(PoisonError::into_inner).take(),
        ));
    }

    /// Adds candidates; returns their indices.
    pub(crate) fn add(&mut self, new: Vec<Candidate>) -> Vec<usize> {
        let first = self.candidates.len();
        let t = Instant::now();
        let locals: Vec<Option<LocalCandidate>> =
            new.par_iter().map(|c| LocalCandidate::new(self.nominal, c)).collect();
        self.clock.forms.add(t);
        self.candidates.extend(new);
        self.locals.extend(locals);
        let n = self.candidates.len();
        self.screened.resize(n, None);
        self.full.resize(n, None);
        self.failure.resize(n, None);
        self.superseded.resize(n, false);
        (first..n).collect()
    }

    /// The descriptions of every candidate so far.
    pub(crate) fn descriptions(&self) -> HashSet<String> {
        self.candidates.iter().map(|c| c.description.clone()).collect()
    }

    /// `dBIC = (cost - cost0) / s^2 + k ln(n)`.
    pub(crate) fn bic(&self, f: &Fit, k: usize) -> f64 {
        (f.cost - f.cost0) / self.s2 + k as f64 * (f.n as f64).ln()
    }

    /// Fits `which` on `lines` with `iterations`, from their starting values
    /// (or `starts`), for `stage`; returns the fits in the order of `which`.
    fn fit_all(
        &self,
        stage: FitStage,
        lines: &LineSet,
        iterations: usize,
        which: &[usize],
        starts: &[Option<Vec<f64>>],
    ) -> Result<Vec<Result<Fit, String>>, UpdateError> {
        let data = self.local_data(lines, which)?;
        let fits = self.fit_on(stage, lines, &data, iterations, which, starts);
        free_aside(data);
        Ok(fits)
    }

    /// Plans the low-rank data of the next stages: the candidates of
    /// `which` on the lines of `sets`, gathered when a stage first asks for
    /// data that they serve (see [`Pool::local_data`]). Each gathering costs
    /// a factorisation of the nominal `Z` per line, the cost of a fit stage
    /// on a large model (a 100k-DOF frame's fits took a second where its
    /// factorisations took 20), while the stages ask for data on the same
    /// lines again and again (the screening, the starts of the relaxation
    /// parameters, the full fits and what follows them): one gathering per
    /// plan serves them all.
    pub(crate) fn plan(&mut self, sets: &[&LineSet], which: &[usize]) {
        self.plan_anticipating(sets, which, Vec::new());
    }

    /// As [`Pool::plan`], with the sets of equations of candidates not in
    /// the pool yet (`anticipated`: those a later stage may add) gathered
    /// as well, so that the data serve that stage too (see
    /// [`Pool::serves`]).
    fn plan_anticipating(&mut self, sets: &[&LineSet], which: &[usize], anticipated: Vec<LocalForm>) {
        let lines = lines_of(sets);
        let which = which.to_vec();
        let mut forms = self.forms(&which);
        forms.extend(&anticipated);
        let slots = Slots::of(&forms);
        self.plan = Some(Plan { lines, which, anticipated, slots });
        // the data of an earlier plan are not needed again
        free_aside(self.gathered.get_mut().unwrap_or_else(PoisonError::into_inner).take());
    }

    /// Whether the low-rank data gathered last serve the candidates of
    /// `which` on the lines of `sets`, so that a new plan for them would
    /// gather the same factorisations again for nothing.
    fn serves(&self, sets: &[&LineSet], which: &[usize]) -> bool {
        let gathered = self.gathered.lock().unwrap_or_else(PoisonError::into_inner);
        gathered.as_ref().is_some_and(|data| data.covers(&lines_of(sets), &self.forms(which)))
    }

    fn forms(&self, which: &[usize]) -> Vec<&LocalForm> {
        which.iter().filter_map(|&i| self.locals[i].as_ref().map(|l| &l.form)).collect()
    }

    /// The nominal model's low-rank data on `lines` for the candidates of
    /// `which`: those gathered for the plan when they serve them (gathered
    /// now if the plan serves them), else gathered for these alone.
    fn local_data(&self, lines: &LineSet, which: &[usize]) -> Result<Arc<LocalData>, UpdateError> {
        let forms = self.forms(which);
        let (channels, freqs) = (lines.data.channels(), lines.data.frequencies_hz());
        let mut gathered = self.gathered.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(data) = gathered.as_ref()
            && data.covers(freqs, &forms)
        {
            return Ok(Arc::clone(data));
        }
        if let Some(plan) = &self.plan
            && freqs.iter().all(|f| plan.lines.contains(f))
            && forms.iter().all(|f| plan.slots.find(&f.eqs).is_some())
        {
            let t = Instant::now();
            let mut planned = self.forms(&plan.which);
            planned.extend(&plan.anticipated);
            let data = Arc::new(LocalData::new(self.nominal, channels, &plan.lines, &planned)?);
            self.clock.gather.add_lines(t, plan.lines.len());
            *gathered = Some(Arc::clone(&data));
            return Ok(data);
        }
        let t = Instant::now();
        let data = Arc::new(LocalData::new(self.nominal, channels, freqs, &forms)?);
        self.clock.gather.add_lines(t, freqs.len());
        Ok(data)
    }

    /// Fits `which` on `lines` by `data` (from [`Self::local_data`] for
    /// these candidates), each from its start where given.
    fn fit_on(
        &self,
        stage: FitStage,
        lines: &LineSet,
        data: &LocalData,
        iterations: usize,
        which: &[usize],
        starts: &[Option<Vec<f64>>],
    ) -> Vec<Result<Fit, String>> {
        let t = Instant::now();
        let fits = which
            .par_iter()
            .zip(starts)
            .map(|(&i, start)| {
                let c = &self.candidates[i];
                #[cfg(test)]
                if self.forced_failure.is_some_and(|fail| fail(c, stage)) {
                    return Err(format!("made to fail by the test at {stage}"));
                }
                #[cfg(not(test))]
                let _ = stage;
                let local = self.locals[i].as_ref().map(|l| (data, l));
                let start = start.as_deref();
                // a low-rank update that cannot be evaluated (a singular
                // local system at some line) falls back to the whole model
                let attempt = |local, start| fit(c, self.model, lines, local, iterations, start);
                attempt(local, start)
                    .or_else(|e| if local.is_some() { attempt(None, start) } else { Err(e) })
                    .or_else(|e| if start.is_some() { attempt(None, None) } else { Err(e) })
            })
            .collect();
        self.clock.fits.add_lines(t, which.len());
        fits
    }

    /// Screens `which` (at `stage`, pre-screening or screening): a short fit
    /// on `lines` from the starting values, and with `factor_starts` from
    /// [`factor_starts`] too, keeping the best. A candidate whose fit fails
    /// keeps the fit of an earlier stage, if any.
    pub(crate) fn screen(
        &mut self,
        stage: FitStage,
        lines: &LineSet,
        iterations: usize,
        which: &[usize],
        factor_starts: bool,
    ) -> Result<(), UpdateError> {
        // the best fit from the alternative starts and the candidate's own,
        // where it has alternatives; the others fitted from their own
        let best = if factor_starts { self.try_factor_starts(stage, lines, iterations, which)? } else { Vec::new() };
        let rest: Vec<usize> = (0..which.len()).filter(|&k| best.get(k).is_none_or(Option::is_none)).collect();
        let subset: Vec<usize> = rest.iter().map(|&k| which[k]).collect();
        let fits = self.fit_all(stage, lines, iterations, &subset, &vec![None; subset.len()])?;
        let from_best = best.into_iter().enumerate().filter_map(|(k, f)| f.map(|f| (which[k], Ok(f))));
        for (i, f) in subset.into_iter().zip(fits).chain(from_best) {
            match f {
                Ok(f) => {
                    self.screened[i] = Some(f);
                    self.failure[i] = None;
                }
                Err(why) => self.failure[i] = Some((stage, why)),
            }
        }
        Ok(())
    }

    /// Fits `which` fully on `lines`, each warm-started from its screening
    /// fit (or from `starts` where given). A candidate with a relaxation
    /// parameter is first fitted briefly on the `coarse` lines from each of
    /// [`Pool::mu_starts`] in its place as well, and fitted fully from the
    /// best of those: the misfit of a relaxation parameter has local minima
    /// (a kernel relaxing below the band acts as a stiffening, one above it
    /// as viscous damping, and a fit started on the wrong side stays there).
    pub(crate) fn full_fit(
        &mut self,
        lines: &LineSet,
        coarse: &LineSet,
        iterations: (usize, usize),
        which: &[usize],
        starts: Option<Vec<Option<Vec<f64>>>>,
    ) -> Result<(), UpdateError> {
        let (full_iterations, short_iterations) = iterations;
        let mut starts = starts
            .unwrap_or_else(|| which.iter().map(|&i| self.screened[i].as_ref().map(|f| f.values.clone())).collect());
        let with_mu: Vec<usize> =
            (0..which.len()).filter(|&k| self.candidates[which[k]].roles.contains(&Role::Mu)).collect();
        if !with_mu.is_empty() {
            let subset: Vec<usize> = with_mu.iter().map(|&k| which[k]).collect();
            let base: Vec<Vec<f64>> = with_mu
                .iter()
                .map(|&k| starts[k].clone().unwrap_or_else(|| self.candidates[which[k]].start_values()))
                .collect();
            let mut best: Vec<Option<Fit>> = vec![None; with_mu.len()];
            let data = self.local_data(coarse, &subset)?;
            for m in std::iter::once(None).chain(self.mu_starts.clone().into_iter().map(Some)) {
                let tries: Vec<Option<Vec<f64>>> = with_mu
                    .iter()
                    .zip(&base)
                    .map(|(&k, b)| {
                        let mut s = b.clone();
                        if let Some(m) = m {
                            let c = &self.candidates[which[k]];
                            (0..c.roles.len()).filter(|&p| c.roles[p] == Role::Mu).for_each(|p| s[p] = m);
                        }
                        Some(s)
                    })
                    .collect();
                let fits = self.fit_on(FitStage::FullFit, coarse, &data, short_iterations, &subset, &tries);
                for (slot, f) in best.iter_mut().zip(fits) {
                    if let Ok(f) = f
                        && slot.as_ref().is_none_or(|b| f.cost < b.cost)
                    {
                        *slot = Some(f);
                    }
                }
            }
            for (&k, b) in with_mu.iter().zip(best) {
                if let Some(b) = b {
                    starts[k] = Some(b.values);
                }
            }
        }
        for (&i, f) in which.iter().zip(self.fit_all(FitStage::FullFit, lines, full_iterations, which, &starts)?) {
            match f {
                Ok(f) => {
                    self.full[i] = Some(f);
                    self.failure[i] = None;
                }
                Err(why) => self.failure[i] = Some((FitStage::FullFit, why)),
            }
        }
        Ok(())
    }

    /// The screening fits of the candidates of `which` that have
    /// [`factor_starts`] (one stiffness factor, mass factor or lumped
    /// mass): from their own start and from each of those, the best kept
    /// (`None` for the other candidates). A change large enough to move
    /// modes across several others (a 40 % stiffness loss, a mass of a few
    /// percent in a frame in space with clustered modes) leaves a fit
    /// started from the nominal model in a local minimum next to its start.
    fn try_factor_starts(
        &self,
        stage: FitStage,
        lines: &LineSet,
        iterations: usize,
        which: &[usize],
    ) -> Result<Vec<Option<Fit>>, UpdateError> {
        let others: Vec<Vec<Vec<f64>>> = which.iter().map(|&i| factor_starts(&self.candidates[i])).collect();
        let with: Vec<usize> = (0..which.len()).filter(|&k| !others[k].is_empty()).collect();
        let mut best: Vec<Option<Fit>> = vec![None; which.len()];
        if with.is_empty() {
            return Ok(best);
        }
        let rounds = others.iter().map(Vec::len).max().unwrap_or(0);
        let data = self.local_data(lines, &with.iter().map(|&k| which[k]).collect::<Vec<_>>())?;
        // round 0 from each candidate's own start, then its alternatives
        for r in 0..=rounds {
            let ks: Vec<usize> = with.iter().copied().filter(|&k| r <= others[k].len()).collect();
            let subset: Vec<usize> = ks.iter().map(|&k| which[k]).collect();
            let tries: Vec<Option<Vec<f64>>> = ks.iter().map(|&k| (r > 0).then(|| others[k][r - 1].clone())).collect();
            for (&k, f) in ks.iter().zip(self.fit_on(stage, lines, &data, iterations, &subset, &tries)) {
                if let Ok(f) = f
                    && best[k].as_ref().is_none_or(|b| f.cost < b.cost)
                {
                    best[k] = Some(f);
                }
            }
        }
        Ok(best)
    }

    /// `which` ordered by their screening: fits on more residuals first
    /// (screened before pre-screened), then by `dBIC`. Unscreened ones are left out.
    pub(crate) fn by_screening(&self, which: &[usize]) -> Vec<usize> {
        // the keys first (a large model sorts 60,000 of them several times,
        // and a key per comparison cost a logarithm each time); stable, as
        // before, so that equal keys keep the order of `which`
        let mut keyed: Vec<(usize, f64, usize)> = which
            .iter()
            .filter_map(|&i| {
                self.screened[i].as_ref().map(|f| (f.n, self.bic(f, self.candidates[i].parameters.len()), i))
            })
            .collect();
        keyed.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.total_cmp(&b.1)));
        keyed.into_iter().map(|(.., i)| i).collect()
    }

    /// The fully fitted candidates (not superseded), by `dBIC`.
    pub(crate) fn by_full_fit(&self) -> Vec<usize> {
        let mut order: Vec<usize> =
            (0..self.candidates.len()).filter(|&i| self.full[i].is_some() && !self.superseded[i]).collect();
        let key = |i: usize| self.bic(self.full[i].as_ref().expect("filtered"), self.candidates[i].parameters.len());
        order.sort_by(|&a, &b| key(a).total_cmp(&key(b)));
        order
    }

    /// The leaders to fit fully: the best `keep` by screening, and the best
    /// of each kind not among them, so that one effect's many windows
    /// cannot crowd out every other kind.
    pub(crate) fn leaders(&self, order: &[usize], keep: usize) -> Vec<usize> {
        let mut out: Vec<usize> = order.iter().copied().take(keep).collect();
        let mut kinds: HashSet<EffectKind> = out.iter().map(|&i| self.candidates[i].kind).collect();
        for &i in order {
            if kinds.insert(self.candidates[i].kind) {
                out.push(i);
            }
        }
        out
    }

    /// Candidates around the best fully fitted ones (see
    /// [`candidates::refine`]), added to the pool; returns their indices.
    pub(crate) fn refine(&mut self, opts: &CandidateOptions, leaders: usize) -> Vec<usize> {
        let order = self.by_full_fit();
        let best: Vec<&Candidate> = order.iter().take(leaders).map(|&i| &self.candidates[i]).collect();
        let new = candidates::refine(self.model, opts, &best, &self.descriptions());
        self.add(new)
    }

    /// The twins ([`candidates::twins`]) of the best `leaders` stiffness
    /// changes by full fit, added to the pool: their indices, the indices
    /// of their originals, and their starting values (where their originals
    /// ended).
    pub(crate) fn twins(&mut self, opts: &CandidateOptions, leaders: usize) -> Twins {
        let tried = self.descriptions();
        let leading: Vec<usize> = self
            .by_full_fit()
            .into_iter()
            .filter(|&i| self.candidates[i].kind == EffectKind::StiffnessChange)
            .take(leaders)
            .collect();
        let of: Vec<&Candidate> = leading.iter().map(|&i| &self.candidates[i]).collect();
        let (mut twins, mut originals, mut starts) = (Vec::new(), Vec::new(), Vec::new());
        for (k, t) in candidates::twins(self.model, opts, &of) {
            if !tried.contains(&t.description) && !twins.iter().any(|o: &Candidate| o.description == t.description) {
                let i = leading[k];
                starts.push(self.full[i].as_ref().map(|f| f.values.clone()));
                originals.push(i);
                twins.push(t);
            }
        }
        Twins { twins: self.add(twins), originals, starts }
    }

    /// Drops each fitted twin that does not beat its original by
    /// [`TWIN_EVIDENCE`]: where the data cannot tell the two apart (a
    /// cantilever measured across its axis never stretches), the change
    /// stays the plain one the user would write first.
    pub(crate) fn keep_better_twins(&mut self, twins: &[usize], originals: &[usize]) {
        for (&twin, &original) in twins.iter().zip(originals) {
            let score = |i: usize| self.full[i].as_ref().map(|f| self.bic(f, self.candidates[i].parameters.len()));
            if let (Some(a), Some(b)) = (score(twin), score(original))
                && a > b - TWIN_EVIDENCE
            {
                self.superseded[twin] = true;
            }
        }
    }

    /// The per-direction variants (see [`candidates::per_direction_variant`])
    /// of those of the best `leaders` fully fitted candidates that are
    /// supports or joints, started from their fits, added to the pool;
    /// returns their indices.
    pub(crate) fn per_direction(&mut self, leaders: usize) -> Vec<usize> {
        let mut tried = self.descriptions();
        let mut new = Vec::new();
        for i in self.by_full_fit().into_iter().take(leaders) {
            let fit = self.full[i].as_ref().expect("fully fitted");
            if let Some(v) = candidates::per_direction_variant(self.model, &self.candidates[i], &fit.values)
                && tried.insert(v.description.clone())
            {
                new.push(v);
            }
        }
        self.add(new)
    }

    /// The other damping form ([`candidates::other_form`]) of each of the
    /// best `leaders` full fits that has one, with its starting values:
    /// the leader's fitted values, and a new relaxation parameter where
    /// the form starts it. A form the pool holds already is fitted from
    /// there too when only its screening fit was made (it may have stopped
    /// in a local minimum of its relaxation parameter); one fitted fully
    /// already is left as it is. Returns the indices to fit and their starts.
    pub(crate) fn other_forms(
        &mut self,
        opts: &CandidateOptions,
        leaders: usize,
    ) -> (Vec<usize>, Vec<Option<Vec<f64>>>) {
        let (mut which, mut starts) = (Vec::new(), Vec::new());
        let mut new: Vec<(Candidate, Vec<f64>)> = Vec::new();
        for i in self.by_full_fit().into_iter().take(leaders) {
            let leader = &self.candidates[i];
            let Some(c) = candidates::other_form(self.model, leader, opts.band_hz) else { continue };
            let fit = self.full[i].as_ref().expect("fully fitted");
            let own = c.start_values();
            let start: Vec<f64> = (0..c.parameters.len())
                .map(|p| leader.parameters.iter().position(|n| *n == c.parameters[p]).map_or(own[p], |q| fit.values[q]))
                .collect();
            match self.candidates.iter().position(|o| o.description == c.description) {
                Some(j)
                    if self.full[j].is_none()
                        && !which.contains(&j)
                        && self.candidates[j].parameters == c.parameters =>
                {
                    which.push(j);
                    starts.push(Some(start));
                }
                Some(_) => {}
                None if new.iter().any(|(o, _)| o.description == c.description) => {}
                None => new.push((c, start)),
            }
        }
        let (made, made_starts): (Vec<Candidate>, Vec<Vec<f64>>) = new.into_iter().unzip();
        which.extend(self.add(made));
        starts.extend(made_starts.into_iter().map(Some));
        (which, starts)
    }

    /// For every full fit with parameters the data do not determine, the
    /// variant that holds them (see [`Candidate::holding`]) is fitted fully
    /// from the determined values and supersedes the fuller one, once its
    /// own full fit succeeded: a variant whose fit fails is counted among
    /// the failures, and the fuller one stays in the ranking. With `only`,
    /// just those full fits are looked at.
    pub(crate) fn hold_undetermined(
        &mut self,
        lines: &LineSet,
        coarse: &LineSet,
        iterations: (usize, usize),
        only: Option<&[usize]>,
    ) -> Result<(), UpdateError> {
        let mut fits: Vec<(usize, Vec<f64>)> = Vec::new();
        let mut new: Vec<(Candidate, Vec<f64>)> = Vec::new();
        // (fuller candidate, description of the variant holding its undetermined parameters)
        let mut held_by: Vec<(usize, String)> = Vec::new();
        for i in self.by_full_fit() {
            if only.is_some_and(|o| !o.contains(&i)) {
                continue;
            }
            let f = self.full[i].as_ref().expect("fully fitted");
            let held: Vec<usize> = (0..f.determined.len()).filter(|&p| !f.determined[p]).collect();
            if held.is_empty() {
                continue;
            }
            let Some(h) = self.candidates[i].holding(self.model, &held) else { continue };
            // the held variant fits the parameters it does not hold, in
            // order (a variant per direction left with one spring renames them)
            let original = &self.candidates[i].parameters;
            let start: Vec<f64> =
                (0..original.len()).filter(|&p| !h.held.contains(&original[p])).map(|p| f.values[p]).collect();
            assert_eq!(start.len(), h.parameters.len(), "the held variant fits a subset");
            let description = h.description.clone();
            // the held variant may be a candidate of its own already (a plain mass)
            match self.candidates.iter().position(|c| c.description == h.description) {
                Some(j) if self.full[j].is_none() && !fits.iter().any(|(k, _)| *k == j) => fits.push((j, start)),
                Some(_) => {}
                None if new.iter().any(|(c, _)| c.description == h.description) => {}
                None => new.push((h, start)),
            }
            held_by.push((i, description));
        }
        for (h, start) in new {
            let j = self.add(vec![h])[0];
            fits.push((j, start));
        }
        let (which, starts): (Vec<usize>, Vec<Option<Vec<f64>>>) = fits.into_iter().map(|(j, s)| (j, Some(s))).unzip();
        if !which.is_empty() {
            self.full_fit(lines, coarse, iterations, &which, Some(starts))?;
        }
        for (i, description) in held_by {
            let variant = self.candidates.iter().position(|c| c.description == description);
            if variant.is_some_and(|j| self.full[j].is_some()) {
                self.superseded[i] = true;
            }
        }
        Ok(())
    }
}

/// The pre-screening, screening and full fits of a first pass of
/// candidates, then the refinement and the holding; see the module docs of
/// [`super`]. `nominal` holds the nominal model's FRFs at every line of the
/// line sets.
pub(crate) fn search(
    pool: &mut Pool<'_>,
    measured: &FrfSet,
    nominal: &FrfSet,
    full: &LineSet,
    opts: &DiagnoseOptions,
    copts: &CandidateOptions,
    trace: &mut dyn FnMut(&str),
) -> Result<(), UpdateError> {
    let weights = opts.weights.as_deref();
    let coarse = LineSet::with_model(measured, opts.screen_lines, opts.gains, nominal, weights)?;
    let t = Instant::now();
    let generated = candidates::generate(pool.model, copts);
    let generation = t.elapsed().as_secs_f64();
    let all = pool.add(generated);
    trace(&format!("generated {} candidates ({generation:.2} s): {}", all.len(), pool.clock.since_last()));
    let to_screen = if all.len() > opts.prescreen_above {
        let pre = LineSet::with_model(measured, opts.prescreen_lines, opts.gains, nominal, weights)?;
        // a fuller variant (non-viscous damping, a mass's rotary inertia)
        // waits for its plain twin: pre-screened only through it, and
        // screened beside it when the twin is among the best
        let plain = plain_twins(&pool.candidates, &all);
        let first: Vec<usize> = all.iter().zip(&plain).filter(|(_, p)| p.is_none()).map(|(&i, _)| i).collect();
        pool.screen(FitStage::PreScreening, &pre, opts.prescreen_iterations, &first, false)?;
        trace(&format!(
            "pre-screened {} candidates on {} lines ({} fuller variants wait for their plain twins): {}",
            first.len(),
            pre.data.n_freq(),
            all.len() - first.len(),
            pool.clock.since_last()
        ));
        let mut best = pool.by_screening(&first);
        best.truncate(opts.prescreen_keep);
        let chosen: HashSet<usize> = best.iter().copied().collect();
        for (&i, p) in all.iter().zip(&plain) {
            match p {
                Some(p) if chosen.contains(p) => best.push(i),
                Some(_) => pool.deferred.push(i),
                None => {}
            }
        }
        best
    } else {
        all.clone()
    };
    // the alternative starts of stiffness and mass changes where there are
    // few candidates (a large model's screen keeps its time)
    let factor_starts = all.len() <= opts.prescreen_above;
    // one gathering for the screening and the full fits of its leaders: the
    // candidates screened and the best of each kind so far (the leaders
    // come from them unless their screening fails)
    let mut planned = to_screen.clone();
    let leaders = pool.leaders(&pool.by_screening(&all), opts.keep);
    planned.extend(&leaders);
    // After pre-screening, the refinement below will add candidates around
    // the best three full fits, and those come from these leaders: their
    // sets of equations are gathered now too (a few hundred small cliques,
    // local to a few places), so that the refinement finds its data here
    // rather than in a second pass over every full line, a factorisation,
    // solves and a selected inverse each (13 s of 88 of CPU on the 100k-DOF
    // frame). Where the full fits lead elsewhere, the refinement gathers
    // its own as before.
    let anticipated = if pool.anticipate && all.len() > opts.prescreen_above {
        let around: Vec<&Candidate> = leaders.iter().map(|&i| &pool.candidates[i]).collect();
        let tried = pool.descriptions();
        let nominal = pool.nominal;
        candidates::refine(pool.model, copts, &around, &tried)
            .par_iter()
            .filter_map(|c| LocalCandidate::new(nominal, c).map(|l| l.form))
            .collect()
    } else {
        Vec::new()
    };
    pool.plan_anticipating(&[&coarse, full], &planned, anticipated);
    pool.screen(FitStage::Screening, &coarse, opts.screen_iterations, &to_screen, factor_starts)?;
    trace(&format!(
        "screened {} candidates on {} lines: {}",
        to_screen.len(),
        coarse.data.n_freq(),
        pool.clock.since_last()
    ));
    let order = pool.by_screening(&all);
    let keep = pool.leaders(&order, opts.keep);
    pool.full_fit(full, &coarse, (opts.iterations, opts.screen_iterations), &keep, None)?;
    trace(&format!("fitted the best {} on {} lines: {}", keep.len(), full.data.n_freq(), pool.clock.since_last()));

    // around the leaders: fuller variants, and on large models finer windows
    let refined = pool.refine(copts, REFINED_LEADERS);
    if !refined.is_empty() {
        // one gathering for the refined candidates and the variants and
        // twins of every candidate fitted fully (on the same equations)
        let mut planned = refined.clone();
        planned.extend(pool.by_full_fit());
        if !pool.serves(&[&coarse, full], &planned) {
            pool.plan(&[&coarse, full], &planned);
        }
        pool.screen(FitStage::Screening, &coarse, opts.screen_iterations, &refined, factor_starts)?;
        let best: Vec<usize> = pool.by_screening(&refined).into_iter().take(REFINED_FITS).collect();
        pool.full_fit(full, &coarse, (opts.iterations, opts.screen_iterations), &best, None)?;
        trace(&format!(
            "refined around the leaders: {} candidates, {} fitted: {}",
            refined.len(),
            best.len(),
            pool.clock.since_last()
        ));
    }
    // a support or joint among the leaders with one damping group per
    // direction: fitted fully from its leader's fit, beside the refined
    // candidates rather than competing with them for a full fit (it
    // screens as well as its leader and would crowd out the windows)
    let variants = pool.per_direction(REFINED_LEADERS);
    if !variants.is_empty() {
        pool.full_fit(full, &coarse, (opts.iterations, opts.screen_iterations), &variants, None)?;
        trace(&format!(
            "fitted {} variants with a damping group per direction: {}",
            variants.len(),
            pool.clock.since_last()
        ));
    }
    // the twins of the leading stiffness changes, started where those ended
    let Twins { twins, originals, starts } = pool.twins(copts, TWINNED_LEADERS);
    if !twins.is_empty() {
        pool.full_fit(full, &coarse, (opts.iterations, opts.screen_iterations), &twins, Some(starts))?;
        pool.keep_better_twins(&twins, &originals);
        trace(&format!("fitted {} twins of the leaders: {}", twins.len(), pool.clock.since_last()));
    }
    pool.hold_undetermined(full, &coarse, (opts.iterations, opts.screen_iterations), None)?;
    trace(&format!("held what the data do not determine: {}", pool.clock.since_last()));
    // the other damping form of the leaders, started where they ended
    let (forms, starts) = pool.other_forms(copts, REFINED_LEADERS);
    if !forms.is_empty() {
        pool.full_fit(full, &coarse, (opts.iterations, opts.screen_iterations), &forms, Some(starts))?;
        trace(&format!("fitted {} leaders in their other damping form: {}", forms.len(), pool.clock.since_last()));
        // a form's new relaxation parameter can leave a spring it damps
        // undetermined (a clamp's per-direction non-viscous form on a
        // beam: its ky at 165 % and that group's mu at 3.5e21, unheld)
        pool.hold_undetermined(full, &coarse, (opts.iterations, opts.screen_iterations), Some(&forms))?;
    }
    Ok(())
}

/// Frees `what` on a thread of its own. The low-rank data of a large
/// model's stage are gigabytes (the 100k-DOF frame's pre-screening held
/// 3 GiB), and handing their pages back to the system took over a second
/// of the diagnosis's time on its own thread; nothing waits for it.
pub(crate) fn free_aside<T: Send + 'static>(what: T) {
    // where no thread can be had, the refused closure frees it here
    let _ = std::thread::Builder::new().name("rfm-free".into()).spawn(move || drop(what));
}

/// Per candidate of `which`, its plain twin among them where it is a
/// fuller variant of one: a window, support or joint with non-viscous
/// damping (a relaxation parameter more) of the same one with viscous
/// damping, or a lumped mass with its rotary inertia of the mass alone at
/// its node. On a large model the pre-screening fits the plain one only
/// (the 100k-DOF frame's 8,568 non-viscous windows took a third of its
/// fits, at 8 evaluations each against 5.4 for their viscous twins) and
/// screens the fuller one where the plain one is among the best: the place
/// is what the pre-screening chooses, and a relaxation parameter fitted
/// from its start in three iterations on twenty lines says little about
/// the form.
fn plain_twins(candidates: &[Candidate], which: &[usize]) -> Vec<Option<usize>> {
    let fuller = |r: &Role| matches!(r, Role::Mu | Role::Inertia);
    let key = |c: &Candidate| {
        let kind = if c.kind == EffectKind::NonViscousDamping { EffectKind::ViscousDamping } else { c.kind };
        let roles: Vec<Role> = c.roles.iter().copied().filter(|r| !fuller(r)).collect();
        (kind, c.nodes.clone(), c.elements.clone(), roles)
    };
    let plain: std::collections::HashMap<_, usize> =
        which.iter().filter(|&&i| !candidates[i].roles.iter().any(fuller)).map(|&i| (key(&candidates[i]), i)).collect();
    which
        .iter()
        .map(|&i| {
            let c = &candidates[i];
            if c.roles.iter().any(fuller) { plain.get(&key(c)).copied() } else { None }
        })
        .collect()
}

/// Other starting values of a candidate of one stiffness factor (a loss of
/// 10 % to 70 % of the nominal stiffness), mass factor (1.5 and 2 times
/// the nominal mass) or lumped mass, with its rotary inertia or without
/// (0.3 % to 10 % of the structure's mass, beside its own 0.1 %), spread
/// over the plausible range so that one of them starts in the basin of the
/// truth; a resonator's own ([`Candidate::other_starts`]); none for other
/// candidates.
fn factor_starts(c: &Candidate) -> Vec<Vec<f64>> {
    let start = c.start_values();
    let scales: &[f64] = match c.roles.as_slice() {
        [Role::StiffnessFactor] => &[0.3, 0.45, 0.6, 0.75, 0.9],
        [Role::MassFactor] => &[1.5, 2.0],
        // a mass with its rotary inertia: both scaled together
        [Role::Mass] | [Role::Mass, Role::Inertia] => &[3.0, 10.0, 30.0, 100.0],
        _ => return c.other_starts(),
    };
    scales.iter().map(|f| start.iter().map(|v| v * f).collect()).collect()
}

/// Wall time spent in one kind of work, and how much of it was done.
#[derive(Default)]
pub(crate) struct Timer {
    nanos: AtomicU64,
    calls: AtomicU64,
    items: AtomicU64,
}

impl Timer {
    /// Adds the time since `start` as one call.
    fn add(&self, start: Instant) {
        self.add_lines(start, 0);
    }

    /// Adds the time since `start` as one call over `items` (lines gathered, fits made).
    fn add_lines(&self, start: Instant, items: usize) {
        let ns = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.nanos.fetch_add(ns, Ordering::Relaxed);
        self.calls.fetch_add(1, Ordering::Relaxed);
        self.items.fetch_add(items as u64, Ordering::Relaxed);
    }

    /// Seconds, calls and items since the last take, and starts again.
    fn take(&self) -> (f64, u64, u64) {
        let ns = self.nanos.swap(0, Ordering::Relaxed);
        (ns as f64 * 1e-9, self.calls.swap(0, Ordering::Relaxed), self.items.swap(0, Ordering::Relaxed))
    }
}

/// Where the diagnosis's time goes, stage by stage (wall time; the fits of
/// a stage run in parallel, so their time is the stage's, not summed over
/// threads): the candidates' local forms, the gatherings of the nominal
/// model's low-rank data (a factorisation, solves and a selected inverse per
/// line) and the fits. Read by the progress messages, which say where each
/// stage's time went; nothing is decided by it.
#[derive(Default)]
pub(crate) struct Clock {
    forms: Timer,
    gather: Timer,
    fits: Timer,
}

impl Clock {
    /// What the work since the last call took, in words, and starts again.
    pub(crate) fn since_last(&self) -> String {
        let (forms, _, _) = self.forms.take();
        let (gather, gatherings, lines) = self.gather.take();
        let (fits, _, fitted) = self.fits.take();
        let mut out = format!("fits {fits:.2} s ({fitted} fits)");
        if gatherings > 0 {
            out += &format!(", low-rank data {gather:.2} s ({gatherings} gathering(s), {lines} lines)");
        }
        if forms > 0.0 {
            out += &format!(", local forms {forms:.2} s");
        }
        out
    }
}

/// The low-rank data planned for the next stages (see [`Pool::plan`]).
struct Plan {
    /// The lines of every line set the stages fit on.
    lines: Vec<f64>,
    which: Vec<usize>,
    /// The local forms of candidates a later stage may add.
    anticipated: Vec<LocalForm>,
    slots: Slots,
}

/// The distinct lines of `sets`, sorted.
fn lines_of(sets: &[&LineSet]) -> Vec<f64> {
    let mut lines: Vec<f64> = sets.iter().flat_map(|s| s.data.frequencies_hz().iter().copied()).collect();
    lines.sort_by(f64::total_cmp);
    lines.dedup();
    lines
}

/// Twins of candidates added by [`Pool::twins`].
pub(crate) struct Twins {
    twins: Vec<usize>,
    originals: Vec<usize>,
    starts: Vec<Option<Vec<f64>>>,
}

/// How much lower a twin's `dBIC` must be than its original's for the twin
/// to stay in the ranking: the threshold of very strong evidence.
const TWIN_EVIDENCE: f64 = 10.0;

/// Leading stiffness changes (by full-fit `dBIC`) whose twins are fitted.
const TWINNED_LEADERS: usize = 3;
/// Leaders (by full-fit `dBIC`) around which candidates are refined.
const REFINED_LEADERS: usize = 3;
/// Refined candidates fitted fully after screening.
const REFINED_FITS: usize = 10;

#[cfg(test)]
mod tests {
    use super::*;

    /// The first lumped mass.
    fn masses_at(all: &[Candidate]) -> usize {
        all.iter().position(|c| c.kind == EffectKind::LumpedMass).expect("a lumped mass")
    }

    /// On a frame large enough for coarse windows, every non-viscous window
    /// (and support or joint) and every mass with its rotary inertia waits
    /// for a plain twin of the same place: the same elements and nodes,
    /// viscous or without the inertia, and otherwise the same parameters;
    /// plain candidates wait for nothing.
    #[test]
    fn fuller_variants_find_their_plain_twins() {
        let model = fe_model::samples::frame_grid(2, 2, 4);
        let all = candidates::generate(&model, &CandidateOptions::default());
        let which: Vec<usize> = (0..all.len()).collect();
        let plain = plain_twins(&all, &which);
        let (mut windows, mut masses) = (0, 0);
        for (c, p) in all.iter().zip(&plain) {
            let fuller = c.roles.iter().any(|r| matches!(r, Role::Mu | Role::Inertia));
            // an existing group's relaxation (a joint as modelled) may have no plain twin
            let Some(p) = p else {
                assert!(!fuller || c.kind != EffectKind::LumpedMass, "{} has no plain twin", c.description);
                assert!(!fuller || c.kind != EffectKind::NonViscousDamping, "{} has no plain twin", c.description);
                continue;
            };
            assert!(fuller, "{} is plain yet waits for {}", c.description, all[*p].description);
            let t = &all[*p];
            assert_eq!((&t.nodes, &t.elements), (&c.nodes, &c.elements), "{} and {}", c.description, t.description);
            assert_eq!(t.parameters.len() + 1, c.parameters.len(), "{} and {}", c.description, t.description);
            match c.kind {
                EffectKind::NonViscousDamping => {
                    assert_eq!(t.kind, EffectKind::ViscousDamping);
                    windows += 1;
                }
                EffectKind::LumpedMass => {
                    assert!(t.kind == EffectKind::LumpedMass && !t.roles.contains(&Role::Inertia));
                    masses += 1;
                }
                _ => assert_eq!(t.kind, c.kind, "{} and {}", c.description, t.description),
            }
        }
        let count = |k: EffectKind| all.iter().filter(|c| c.kind == k).count();
        assert_eq!(windows, count(EffectKind::NonViscousDamping));
        let others = plain.iter().flatten().count() - windows - masses;
        assert!(windows > 10 && others > 10, "{windows} windows, {others} supports and joints");
        // the masses with their rotary inertia come with the refinement
        let refined =
            candidates::refine(&model, &CandidateOptions::default(), &[&all[masses_at(&all)]], &HashSet::new());
        let mut pool: Vec<Candidate> = all.clone();
        pool.extend(refined);
        let which: Vec<usize> = (0..pool.len()).collect();
        let plain = plain_twins(&pool, &which);
        let with_inertia = (0..pool.len()).filter(|&i| pool[i].roles.contains(&Role::Inertia)).collect::<Vec<_>>();
        assert!(!with_inertia.is_empty(), "the refinement of a mass offers its rotary inertia");
        for i in with_inertia {
            let t = &pool[plain[i].unwrap_or_else(|| panic!("{} has no plain twin", pool[i].description))];
            assert!(t.kind == EffectKind::LumpedMass && t.nodes == pool[i].nodes && !t.roles.contains(&Role::Inertia));
        }
    }
}
