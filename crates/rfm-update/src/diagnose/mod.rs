//! Diagnosis: which physical effect is missing from the model.
//!
//! Every candidate effect ([`candidates`]; attached resonators only where
//! [`CandidateOptions::resonator_hz`] names the frequencies of measured
//! modes the model lacks, and, on a small model of beams, where the nominal
//! model's residual is broad between the modes, as a heavily damped
//! resonator that shows no mode of its own leaves it: module `suspects`)
//! is fitted to the measured FRFs by
//! the output-error estimator on the complex-log misfit `ln(H / M)`, which
//! stays well behaved when a resonance is shifted by more than its width
//! (one linearised step from the nominal model does not: it ranks a 40 %
//! stiffness loss behind unrelated masses). Candidates are compared by the
//! Bayesian information criterion against what each candidate leaves:
//!
//! ```text
//! dBIC_c = (cost_c - cost_0) / s_c^2 + k_c ln(n)
//! ```
//!
//! `cost` is the sum of squared real residuals (`cost_0` for the nominal
//! model), `k_c` the candidate's number of parameters, `n` the number of real
//! residuals, and `s_c^2` the variance per real residual that a change of
//! the cost is judged against: the noise's, estimated from the data, or,
//! where the candidate leaves more than the noise, what it leaves, times the
//! lines per independent one that the residual's correlation between
//! adjacent lines makes ([`MisfitStats::lack_of_fit`]; the nominal model's
//! correlation stands for the candidate's). With the data at the noise this
//! is the plain criterion; where something no candidate explains dominates
//! (a real structure, a set-up error), a candidate must explain a share of
//! what remains, not of the noise, to count. An effect is *significant*
//! when `dBIC < -10` (very strong evidence); when none is, the model is
//! consistent with the data. `rfm fix` keeps a step by the same rule
//! ([`delta_bic`]).
//!
//! The noise level comes from the roughness of the measured FRFs: on a line
//! grid fine enough to resolve the structure's response, the second
//! difference of `ln M` across adjacent lines is noise plus a small smooth
//! part, and its median (robust to the few lines at sharp resonances) gives
//! the variance ([`estimate_noise`]). On a grid coarse against the peaks
//! the response itself is rough; the residual against the nominal model,
//! which shares its dynamics, is not, and its level is taken where it is
//! clearly the lower ([`estimate_noise_against`]).
//!
//! To stay fast with many candidates, all are first fitted briefly on a
//! coarse subset of lines (screening), and the leaders are then fitted fully
//! on the updating lines; the final ranking rests on the full fits only. A
//! large model has thousands of candidates (a mass at every node, damping
//! in every region): above [`DiagnoseOptions::prescreen_above`] of them, all
//! are first fitted with fewer iterations on fewer lines (pre-screening) and
//! only the best few hundred are screened; a fuller variant (non-viscous
//! damping, a mass's rotary inertia) is pre-screened through its plain
//! twin, and screened where that twin is among the best. Screening-only entries of the
//! ranking are scored on their own lines; screened ones come before
//! pre-screened ones.
//! On large models stiffness, mass and damping changes are first tried in
//! coarse windows; around the three leaders every window and in-line joint
//! is then tried too (on small models they are candidates from the start),
//! with the fuller variants of the leaders (a joint's translational
//! springs, a mass's rotary inertia, a lumped mass with its rotary inertia
//! at a resonator's node); the best are screened and fitted
//! fully, so that one weakened element is named as such and not as its
//! region or a mass at its node. Then a support or joint among the leaders
//! with springs in two or more DOFs gets a damping group per direction,
//! fitted fully from its own fit, so that a clamp that loses more in
//! rotation than in shear is not given one loss for both at the price of
//! biased stiffnesses. The leading stiffness changes get their twins,
//! fitted from where they ended: the same change of the bending stiffness
//! alone (a smaller second moment of area). A twin stays in the ranking
//! only when it beats its original by very strong evidence (`dBIC` lower
//! by 10); where the data cannot tell the two apart the plain change
//! stands. Last, each of the three leaders with a damping group of its own
//! (a support, joint, damping window or resonator) is fitted fully in its
//! other damping form from its own fit (a non-viscous form starting from a
//! kernel that relaxes ten times faster than the highest line, which damps
//! as the viscous one does): the non-viscous form's screening fit can stop
//! in a local minimum of its relaxation parameter, and a leader holding an
//! undetermined spring has no other form in the pool at all. The
//! information criterion ranks the two forms as any two candidates.
//!
//! A fitted parameter whose relative standard deviation exceeds one (its
//! value could as well be e times larger), or a spring that ran to its
//! upper bound, is *not determined* by the data. A spring of a support or
//! joint that is not determined is held rigid, and the candidate fitted
//! again without it: the axial spring of a clamp measured in bending says
//! nothing about the clamp; a spring with a group of its own (per
//! direction) takes its group's alpha and mu along. Plausibility is judged only on determined
//! values. The *recommended* effect is the first significant, plausible one
//! of the ranking.
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

mod apply;
pub mod candidates;
mod lines;
mod local;
mod search;
mod suspects;

/// The half-width of a band of broad residual (see [`broad_bands`]), relative to its middle.
pub(crate) use suspects::HALF_WIDTH as BAND_HALF_WIDTH;

use damping::DampedSystem;
use fe_model::case::Gains;
use frf::FrfSet;
use rayon::prelude::*;

pub use candidates::{Candidate, CandidateOptions, EffectKind, Role};

use self::lines::LineSet;
pub use self::lines::informative_lines;
use self::search::Pool;
use crate::error::UpdateError;
use crate::quantities::SIGNIFICANT_DBIC;

/// Relative noise level of measured FRFs (RMS of the relative error per
/// complex value), from the roughness of `ln M` over adjacent lines; see the
/// module docs. `None` when there are too few lines.
pub fn estimate_noise(measured: &FrfSet) -> Option<f64> {
    estimate_noise_weighted(measured, None)
}

/// [`estimate_noise`] of the weighted values `w ln M`: each second
/// difference is multiplied by the weight of its middle line
/// (`weights[c * n_freq + k]`, channel-major as the study's line weights;
/// lines of weight 0 are left out). With weights that vary slowly from line to line this is the
/// noise level of a residual weighted the same way, which is what a
/// weighted fit's residual must be compared with.
pub fn estimate_noise_weighted(measured: &FrfSet, weights: Option<&[f64]>) -> Option<f64> {
    estimate_noise_weighted_on(measured, weights, None)
}

/// [`estimate_noise_weighted`] for a misfit read on the lines `read_on`
/// (Hz, lines of `measured`; by default the misfit's, see [`with_floor`]).
fn estimate_noise_weighted_on(measured: &FrfSet, weights: Option<&[f64]>, read_on: Option<&[f64]>) -> Option<f64> {
    let nf = measured.n_freq();
    let known = floor_noise(measured, weights);
    let mut d2 = Vec::new();
    for c in 0..measured.channels().len() {
        if read_at_floor(known, c, nf) {
            continue;
        }
        let h = measured.channel(c);
        for k in 1..h.len().saturating_sub(1) {
            if h[k - 1].norm() == 0.0 || h[k].norm() == 0.0 || h[k + 1].norm() == 0.0 {
                continue;
            }
            let w = weights.map_or(1.0, |w| w[c * nf + k]);
            if w == 0.0 {
                continue;
            }
            let d = w * ((h[k + 1] / h[k]).ln() - (h[k] / h[k - 1]).ln());
            if d.re.is_finite() && d.im.is_finite() {
                d2.push(d.norm_sqr());
            }
        }
    }
    with_floor(measured, weights, known, level_of(d2), read_on)
}

/// The relative noise of each value of `measured` as the reading of its
/// noise floor tells it (channel-major, [`FrfSet::floor_noise_values`];
/// NaN on a channel without a floor), when the values are weighted by the
/// floor's weights: `weights` given and no coherence (whose weights are
/// the inverse of the noise, so that the weighted values have one level
/// throughout).
fn floor_noise<'a>(measured: &'a FrfSet, weights: Option<&[f64]>) -> Option<&'a [f64]> {
    let n = measured.channels().len();
    if weights.is_none() || (0..n).any(|c| measured.coherence(c).is_some()) {
        return None;
    }
    // every channel's, or none: where the reading tells the noise of some
    // channels only, a level read over all of them is the surer
    measured.floor_noise_values().filter(|q| !q.iter().any(|q| q.is_nan()))
}

/// What raises a noise level read as a median of weighted values to the
/// RMS a fit's weighted residual leaves, when the weights are those of a
/// noise floor the data carry ([`frf::noise::ChannelFloor::spread`]; its
/// lines near the floor stay noisier than the others): the RMS of the
/// channels' spreads; 1 for data weighted by their coherence, or not
/// weighted.
fn floor_spread(measured: &FrfSet, weights: Option<&[f64]>) -> f64 {
    let n = measured.channels().len();
    if weights.is_none() || n == 0 || (0..n).any(|c| measured.coherence(c).is_some()) {
        return 1.0;
    }
    // attached to every channel or none
    (0..n)
        .map(|c| measured.floor_spread(c))
        .collect::<Option<Vec<f64>>>()
        .map_or(1.0, |spreads| (spreads.iter().map(|s| s * s).sum::<f64>() / n as f64).sqrt())
}

/// Whether channel `c`'s noise is the floor reading's (`known`, over `nf`
/// lines per channel), not its roughness's.
fn read_at_floor(known: Option<&[f64]>, c: usize, nf: usize) -> bool {
    known.is_some_and(|q| q.get(c * nf).is_some_and(|q| !q.is_nan()))
}

/// The noise level of values weighted by `weights`: `level`, read from the
/// roughness of the values as a median, times the RMS of the channels'
/// floor spreads ([`floor_spread`]); or, where the data carry a noise floor
/// whose reading tells the noise of every value (`known`, see
/// [`frf::noise::FloorWeights::noise`]), the RMS of `w q` for the noise `q`
/// of each value of weight `w` above 0 on the lines where the misfit is
/// read (`read_on`, by default the [`informative_lines`] of
/// [`crate::quantities::MISFIT_LINES`]): the noise a weighted residual
/// leaves there. A floor's noise differs from line to line as the inverse
/// of the modulus, and a weight of `(t / q)^2` leaves the weighted noise
/// `t^2 / q` of a line near the floor as high as the threshold `t` where
/// cleaner lines carry far less: over so many lines at a floor, a single
/// level read from the lines' roughness as a median is the noise of none
/// of them (on a strip whose receptance lies below a floor at 3e-3 of its
/// peak on most lines, the median read 0.0041 where the truth's weighted
/// residual left 0.037), and the lines beside the resonances, which read
/// it, hold mostly the dynamics.
fn with_floor(
    measured: &FrfSet,
    weights: Option<&[f64]>,
    known: Option<&[f64]>,
    level: Option<f64>,
    read_on: Option<&[f64]>,
) -> Option<f64> {
    let Some(known) = known else { return level.map(|l| l * floor_spread(measured, weights)) };
    let weights = weights.expect("a floor's noise is read for weighted values");
    let nf = measured.n_freq();
    let nc = measured.channels().len();
    let misfit_lines;
    let read_on = match read_on {
        Some(lines) => lines,
        None => {
            misfit_lines = informative_lines(measured, crate::quantities::MISFIT_LINES);
            &misfit_lines[..]
        }
    };
    let lines: Vec<usize> = read_on.iter().filter_map(|&f| measured.line_of(f)).collect();
    let (mut sum, mut n) = (0.0, 0usize);
    for i in (0..nc).flat_map(|c| lines.iter().map(move |&k| c * nf + k)) {
        let (w, q, m) = (weights[i], known[i], measured.values()[i]);
        if !(w > 0.0 && m.norm() > 0.0) {
            continue;
        }
        if !q.is_finite() {
            continue;
        }
        let s = w * q;
        sum += s * s;
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// The noise level from squared second differences `|e(k+1) - 2 e(k) +
/// e(k-1)|^2` of complex log values: `E|d|^2 = 6 s^2`, and the median of
/// an exponential variable is its mean times ln 2 (the median leaves the
/// few differences across a peak out). `None` below 10 of them.
fn level_of(mut d2: Vec<f64>) -> Option<f64> {
    if d2.len() < 10 {
        return None;
    }
    d2.sort_by(f64::total_cmp);
    let median = d2[d2.len() / 2];
    Some((median / (6.0 * std::f64::consts::LN_2)).sqrt())
}

/// Triplets of adjacent lines on which [`estimate_noise_against`] reads
/// the residual's roughness.
const NOISE_TRIPLETS: usize = 40;

/// The residual's level replaces the data's own below this fraction of it.
const CLEARLY_LOWER: f64 = 0.7;

/// The noise level of measured receptances read against a model of them:
/// [`estimate_noise`], or the same roughness of the residual `ln(M / H)`
/// against the model's receptances `H`, at up to 40 triplets of adjacent
/// lines spread over the band, where that is below 0.7 times it. The roughness of `ln M` alone is
/// the noise only where the FRFs are smooth from line to line; on lines
/// coarse against the peaks, or dense modes, it is mostly the dynamics (a
/// frame of 96k DOFs on 200 lines: 47 % read against 1 % injected, and
/// nothing was significant). A model close to the structure has the same
/// dynamics, and its residual is smooth but for the noise; where it is
/// not close, its residual is the rougher of the two, and the data's own
/// roughness stands.
pub fn estimate_noise_against(sys: &DampedSystem, measured: &FrfSet) -> Result<Option<f64>, UpdateError> {
    estimate_noise_against_weighted(sys, measured, None)
}

/// [`estimate_noise_against`] of weighted values, as
/// [`estimate_noise_weighted`] weighs them (each second difference by the
/// weight of its middle line, channel-major; lines of weight 0 left out).
pub fn estimate_noise_against_weighted(
    sys: &DampedSystem,
    measured: &FrfSet,
    weights: Option<&[f64]>,
) -> Result<Option<f64>, UpdateError> {
    estimate_noise_against_on(sys, measured, weights, None)
}

/// [`estimate_noise_against_weighted`] for a misfit read on the lines
/// `read_on` (Hz, lines of `measured`), where that is not the misfit's
/// ([`crate::quantities::misfit`]): for data at a noise floor, the noise of
/// each value differs from line to line, and a fit's residual on its own
/// lines is compared with the noise there.
pub fn estimate_noise_against_on(
    sys: &DampedSystem,
    measured: &FrfSet,
    weights: Option<&[f64]>,
    read_on: Option<&[f64]>,
) -> Result<Option<f64>, UpdateError> {
    let freqs = noise_lines(measured);
    // a triplet with a line where the model is singular is left out
    let (model, _) = frf::synthesize_regular(sys, measured.channels(), &freqs)?;
    Ok(noise_against(measured, weights, &model, read_on))
}

/// The lines of the triplets that [`estimate_noise_against`] reads (none
/// below three measured lines).
fn noise_lines(measured: &FrfSet) -> Vec<f64> {
    let lines = measured.frequencies_hz();
    noise_triplets(measured.n_freq()).1.iter().map(|&k| lines[k]).collect()
}

/// The centre lines of the noise triplets and all their lines (indices).
fn noise_triplets(nf: usize) -> (Vec<usize>, Vec<usize>) {
    triplets(nf, NOISE_TRIPLETS)
}

/// The centre lines of up to `most` triplets of adjacent lines spread
/// evenly over `nf` lines, and all their lines (indices).
fn triplets(nf: usize, most: usize) -> (Vec<usize>, Vec<usize>) {
    if nf < 3 {
        return (Vec::new(), Vec::new());
    }
    let count = most.min(nf / 3).max(1);
    let mut centres: Vec<usize> = (0..count).map(|i| 1 + i * (nf - 3) / (count - 1).max(1)).collect();
    centres.dedup();
    let mut idx: Vec<usize> = centres.iter().flat_map(|&k| [k - 1, k, k + 1]).collect();
    idx.sort_unstable();
    idx.dedup();
    (centres, idx)
}

/// Triplets of adjacent lines on which [`residual_roughness`] reads the
/// residual of a model near the data: a third of the lines of bands up to
/// 1,800 lines, so that the reading's own spread (a median of `3 c` squared
/// differences over `c` channels varies by about `2.9 / sqrt(3 c)` in
/// variance) stays near a percent, at the cost of one synthesis of those
/// lines.
const FLOOR_TRIPLETS: usize = 600;

/// The noise level read from the roughness of the residual `ln(M / H)`
/// against a model, on up to 600 triplets of adjacent lines spread over the
/// band (every line of bands up to 1,800 lines), weighted as
/// [`estimate_noise_weighted`] weighs; `None` below 10 usable triplets.
///
/// Against a model near the data the residual is the noise and a lack of
/// fit that varies slowly from line to line, whose second differences
/// vanish: the reading is then the noise's, where the data's own roughness
/// ([`estimate_noise`]) also holds the FRFs' curvature between lines and
/// reads high (on the lab study's cantilevers of 400 lines, 6 to 9 % above
/// the 1 % injected). Against a model far from the data the median leaves
/// out most lines near the peaks, where the residual is rough, and the
/// reading stays at the noise or above it.
pub fn residual_roughness(
    sys: &DampedSystem,
    measured: &FrfSet,
    weights: Option<&[f64]>,
) -> Result<Option<f64>, UpdateError> {
    let nf = measured.n_freq();
    let (centres, idx) = triplets(nf, FLOOR_TRIPLETS);
    let lines = measured.frequencies_hz();
    let freqs: Vec<f64> = idx.iter().map(|&k| lines[k]).collect();
    // a triplet with a line where the model is singular is left out
    let (model, _) = frf::synthesize_regular(sys, measured.channels(), &freqs)?;
    Ok(residual_level(measured, weights, &model, &centres, None))
}

/// The level of the residual's second differences at the triplets centred
/// on `centres`, the model's receptances given at their lines (a triplet
/// with a line the model lacks is left out).
fn residual_level(
    measured: &FrfSet,
    weights: Option<&[f64]>,
    model: &FrfSet,
    centres: &[usize],
    read_on: Option<&[f64]>,
) -> Option<f64> {
    let nf = measured.n_freq();
    let lines = measured.frequencies_hz();
    let model = model.converted(measured.kind());
    let known = floor_noise(measured, weights);
    let mut d2 = Vec::new();
    for c in 0..measured.channels().len() {
        if read_at_floor(known, c, nf) {
            continue;
        }
        for &k in centres {
            let w = weights.map_or(1.0, |w| w[c * nf + k]);
            if w == 0.0 {
                continue;
            }
            let r = |j: usize| {
                let h = model.get(c, model.line_of(lines[j])?);
                let m = measured.get(c, j);
                (m.norm() > 0.0 && h.norm() > 0.0).then(|| (m / h).ln())
            };
            let (Some(a), Some(b), Some(e)) = (r(k - 1), r(k), r(k + 1)) else { continue };
            let d = w * (e - 2.0 * b + a);
            if d.re.is_finite() && d.im.is_finite() {
                d2.push(d.norm_sqr());
            }
        }
    }
    with_floor(measured, weights, known, level_of(d2), read_on)
}

/// [`estimate_noise_against_weighted`] with the model's receptances given
/// at (at least) the lines of [`noise_lines`].
fn noise_against(measured: &FrfSet, weights: Option<&[f64]>, model: &FrfSet, read_on: Option<&[f64]>) -> Option<f64> {
    let own = estimate_noise_weighted_on(measured, weights, read_on);
    let nf = measured.n_freq();
    if nf < 3 {
        return own;
    }
    let (centres, _) = noise_triplets(nf);
    // the residual's level, read on fewer lines, only where it is clearly
    // lower: where both agree, the data's own (on every line) is the surer
    match (own, residual_level(measured, weights, model, &centres, read_on)) {
        (Some(a), Some(b)) if b < CLEARLY_LOWER * a => Some(b),
        (a, b) => a.or(b),
    }
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
    /// Candidates fitted fully after screening (besides the best of each kind).
    pub keep: usize,
    /// Iterations of a full fit.
    pub iterations: usize,
    /// `dBIC` below which an effect is significant.
    pub significance: f64,
    /// Candidate generation options (the band is taken from the data).
    pub candidates: CandidateOptions,
    /// Fit unknown complex gains (one per reference, or one per channel)
    /// with every candidate and with the nominal model (voltage-referenced
    /// data, uncalibrated sensors; see [`crate::gain`]): a level offset
    /// common to a gain's channels is then no symptom.
    pub gains: Gains,
    /// Residual weights at the measured lines, channel-major, as
    /// [`crate::Study::line_weights`] gives them (the measured coherence's
    /// and the case's band weights); `None`: all 1. The noise level is read
    /// from the values weighted the same way.
    pub weights: Option<Vec<f64>>,
}

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
            gains: Gains::None,
            weights: None,
        }
    }
}

/// A fitted parameter of a candidate.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct FittedParameter {
    /// Name (in the candidate's model).
    pub name: String,
    /// What it is.
    pub role: Role,
    /// Fitted value.
    pub value: f64,
    /// Relative standard deviation from the fit (noise only).
    pub relative_std: f64,
    /// The data determine it (see the module docs); a value that is not
    /// determined is shown but not judged for plausibility.
    pub determined: bool,
}

/// One ranked candidate.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Ranked {
    /// Kind.
    pub kind: EffectKind,
    /// The unknown gains fitted with it (empty unless the diagnosis fits
    /// gains: [`DiagnoseOptions::gains`]).
    pub gains: Vec<crate::output_error::Gain>,
    /// Plain-language description with location.
    pub description: String,
    /// Nodes where it acts.
    pub nodes: Vec<u32>,
    /// Elements where it acts.
    pub elements: Vec<u32>,
    /// DOFs it acts on (names).
    pub dof: Vec<String>,
    /// The damping form of its own group (`viscous`, `non-viscous`), for
    /// joints, supports and damping windows.
    pub damping: Option<&'static str>,
    /// Fraction of the nominal misfit it explains (`1 - cost_c / cost_0`).
    pub explained: f64,
    /// RMS of `ln(model / measured)` per complex value with the effect
    /// added at its fitted values, on the lines it was fitted on.
    pub misfit: f64,
    /// How many lines it was fitted on: [`informative_lines`] of the
    /// measured data (the full fits use [`DiagnoseOptions::lines`], the
    /// screening fewer), so that [`log_misfit`] with this number gives
    /// `misfit` again for the model with the effect added.
    pub lines: usize,
    /// Change of the information criterion (negative is better).
    pub delta_bic: f64,
    /// `delta_bic` below the significance threshold.
    pub significant: bool,
    /// Fitted values within their plausible ranges (determined values only).
    pub plausible: bool,
    /// Why not, when not plausible.
    pub implausible_reason: Option<String>,
    /// Fitted parameters.
    pub parameters: Vec<FittedParameter>,
    /// Parameters of a fuller variant that the data did not determine,
    /// held at their rigid or nominal value (a support's axial spring).
    pub held: Vec<String>,
    /// Fitted on the full line set (false: screening only).
    pub fully_fitted: bool,
    /// Index of the candidate in [`Diagnosis::candidates`].
    #[cfg_attr(feature = "serde", serde(skip))]
    pub candidate: usize,
}

/// The stage of the search at which a candidate's fit failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize), serde(rename_all = "kebab-case"))]
pub enum FitStage {
    /// The brief fits of every candidate of a large model on a few lines.
    PreScreening,
    /// The short fits on the screening lines.
    Screening,
    /// The full fits on the diagnosis's lines.
    FullFit,
}

impl std::fmt::Display for FitStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FitStage::PreScreening => "pre-screening",
            FitStage::Screening => "screening",
            FitStage::FullFit => "full fit",
        })
    }
}

/// A candidate whose last fit failed, and why.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Unfitted {
    /// The candidate.
    pub description: String,
    /// Why its fit failed.
    pub reason: String,
    /// The stage whose fit failed.
    pub stage: FitStage,
    /// Still ranked, by the fit of an earlier stage (a candidate whose full
    /// fit failed stays in the ranking as screened only); when false it is
    /// not in the ranking at all.
    pub ranked: bool,
}

/// The outcome of a diagnosis.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Diagnosis {
    /// Estimated relative noise of the data (RMS per complex value).
    pub noise: f64,
    /// RMS residual of the nominal model on the fitted lines.
    pub nominal_misfit: f64,
    /// Number of real residuals of the full fits.
    pub n_residuals: usize,
    /// Candidates ranked: full fits by `delta_bic`, then screening-only ones.
    pub ranking: Vec<Ranked>,
    /// The rank (1-based) of the recommended effect: the first significant,
    /// plausible, fully fitted one; `None` when there is none.
    pub recommended: Option<usize>,
    /// How many candidates were tried.
    pub tried: usize,
    /// How many of them gave way to a variant: one that holds what the data
    /// do not determine, or a twin that did not beat its original.
    pub superseded: usize,
    /// How many fuller variants (non-viscous damping, a mass's rotary
    /// inertia) were left unfitted on a large model because their plain
    /// twin, through which they were pre-screened, was not among the best
    /// (see [`DiagnoseOptions::prescreen_above`]).
    pub deferred: usize,
    /// The unknown gains every fit (and the nominal misfit) fitted.
    #[cfg_attr(feature = "serde", serde(serialize_with = "crate::serialize_display"))]
    pub gains: Gains,
    /// Whether the fits, the misfits and the noise level weigh the lines
    /// ([`DiagnoseOptions::weights`]: the coherence's, or band weights).
    pub weighted: bool,
    /// Candidates whose last fit failed, with the stage and the reason:
    /// every candidate tried is ranked, superseded by a variant that holds
    /// what the data do not determine, or here (or both, when it is ranked
    /// by an earlier stage's fit).
    pub unfitted: Vec<Unfitted>,
    /// Lines (Hz) left out because the model's dynamic stiffness is
    /// singular there (a lightly damped mode on the line): no receptance of
    /// the model exists to compare.
    pub singular_hz: Vec<f64>,
    /// The candidates (same indices as [`Ranked::candidate`]).
    #[cfg_attr(feature = "serde", serde(skip))]
    pub candidates: Vec<Candidate>,
}

impl Diagnosis {
    /// The recommended effect (see [`Diagnosis::recommended`]).
    pub fn leader(&self) -> Option<&Ranked> {
        self.recommended.map(|r| &self.ranking[r - 1])
    }

    /// True when no candidate is significant: the model is consistent with the data.
    pub fn consistent(&self) -> bool {
        !self.ranking.iter().any(|r| r.fully_fitted && r.significant)
    }

    /// The first `top` rows of the ranking as the terminal and the reports
    /// show them (see [`shown_ranking`]).
    pub fn shown(&self, top: usize) -> Vec<ShownRank> {
        shown_ranking(&self.ranking, self.recommended, top)
    }
}

/// A row of the ranking as it is shown: the candidate of rank `rank`
/// (1-based), and the ranks below it folded into its row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShownRank {
    /// Its rank in [`Diagnosis::ranking`] (1-based).
    pub rank: usize,
    /// The ranks folded into it: variants it does not differ from.
    pub alike: Vec<usize>,
}

/// The first `top` rows of `ranking` as they are shown. A candidate that
/// is the same effect as one shown above it (the same kind at the same
/// nodes and elements, in the same directions, with the same damping form
/// and the same parameters), as plausible and as fully fitted, whose dBIC
/// is within the significance threshold's magnitude ([`SIGNIFICANT_DBIC`])
/// of that one's, is folded into its row: it differs only in the values
/// its fit started from (a resonator at one node offered at several
/// tunings), and the data do not tell the two apart. Variants that differ
/// in form (viscous or not, bending or all stiffness, one direction or
/// two) keep rows of their own: which form the data prefer is what the
/// ranking shows. The `recommended` rank is always a row of its own.
/// Ranks keep their numbers, so that any of them can be applied.
pub fn shown_ranking(ranking: &[Ranked], recommended: Option<usize>, top: usize) -> Vec<ShownRank> {
    let mut rows: Vec<ShownRank> = Vec::new();
    for (i, r) in ranking.iter().enumerate() {
        let rank = i + 1;
        let names = |x: &Ranked| x.parameters.iter().map(|p| p.name.clone()).chain(x.held.clone()).collect::<Vec<_>>();
        let same = |o: &Ranked| {
            o.kind == r.kind
                && o.nodes == r.nodes
                && o.elements == r.elements
                && o.dof == r.dof
                && o.damping == r.damping
                && names(o) == names(r)
                && o.plausible == r.plausible
                && o.fully_fitted == r.fully_fitted
                && (o.delta_bic - r.delta_bic).abs() <= SIGNIFICANT_DBIC.abs()
        };
        if recommended != Some(rank)
            && let Some(row) = rows.iter_mut().find(|row| same(&ranking[row.rank - 1]))
        {
            row.alike.push(rank);
            continue;
        }
        if rows.len() == top {
            // a later rank may still fold into a row shown
            continue;
        }
        rows.push(ShownRank { rank, alike: Vec::new() });
    }
    rows
}

/// The misfit the diagnosis, `rfm fix` and the case history speak of: the
/// RMS of `ln(H / M)` per complex value of a system's receptances `H`
/// against measured ones `M`, on `lines` lines spread over the measured band.
pub fn log_misfit(sys: &DampedSystem, measured: &FrfSet, lines: usize) -> Result<f64, UpdateError> {
    log_misfit_with(sys, measured, lines, Gains::None, None)
}

/// As [`log_misfit`], after the model's FRFs are multiplied by the gains
/// (`gains`: per reference or per channel) that fit them best (see
/// [`crate::gain`]), each value weighted by `weights` (at the lines of
/// `measured`, channel-major, as [`DiagnoseOptions::weights`]; the
/// diagnosis's misfits are weighted so).
pub fn log_misfit_with(
    sys: &DampedSystem,
    measured: &FrfSet,
    lines: usize,
    gains: Gains,
    weights: Option<&[f64]>,
) -> Result<f64, UpdateError> {
    Ok(misfit_stats(sys, measured, lines, gains, weights)?.misfit)
}

/// What the evidence reads of a model's misfit on a line set: the misfit
/// (RMS of `ln(H / M)` per complex value, after the best gains, weighted),
/// the number of real residuals, and the correlation of the residuals
/// between adjacent lines (see [`MisfitStats::lack_of_fit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MisfitStats {
    /// RMS of `ln(H / M)` per complex value.
    pub misfit: f64,
    /// Real residuals.
    pub n: usize,
    /// Correlation of the residuals between adjacent lines, `0..=0.95`.
    pub lag_correlation: f64,
}

impl MisfitStats {
    /// The variance per complex value against which a change of the misfit
    /// is judged: the noise's, or, where the model leaves more than the
    /// noise, what it leaves, times the lines per independent one that the
    /// residual's correlation makes (`(1 + rho) / (1 - rho)`). A smooth
    /// residual of a model error varies far less from line to line than
    /// noise, so that the lines it is read on are not independent; and an
    /// effect that lowers a misfit dominated by something no candidate
    /// explains must lower it by a share of that, not by a share of the
    /// noise, to count as evidence.
    ///
    /// Only the part above the noise is a model error's, and only that part
    /// is widened by the correlation: `noise^2 + (misfit^2 - noise^2)+ (1 +
    /// rho) / (1 - rho)`. A misfit within the noise is noise (its lag
    /// correlation is the sampling's or the fit's), and the variance grows
    /// continuously from the noise's as the misfit leaves it: widening the
    /// whole misfit judged candidates that all reach the noise each against
    /// a variance of its own (two variants of a support 1.6e-6 apart in
    /// misfit came out 1,686 apart in dBIC, the wrong one first).
    pub fn lack_of_fit(&self, noise: f64) -> f64 {
        let rho = self.lag_correlation.clamp(0.0, 0.99);
        let excess = (self.misfit * self.misfit - noise * noise).max(0.0);
        noise * noise + excess * (1.0 + rho) / (1.0 - rho)
    }
}

/// The change of the information criterion from a model of misfit `before`
/// with `k_before` parameters to one of misfit `after` with `k_after`,
/// against data of relative noise `noise`:
/// `n (m_after^2 - m_before^2) / v + (k_after - k_before) ln n`, with `v`
/// the variance [`MisfitStats::lack_of_fit`] of the model after. Negative
/// favours the model after; below the diagnosis's significance (-10) the
/// evidence for it is very strong. The one rule by which the diagnosis
/// calls a candidate significant and `rfm fix` keeps a step.
pub fn delta_bic(before: f64, k_before: usize, after: &MisfitStats, k_after: usize, noise: f64) -> f64 {
    let n = after.n as f64;
    n * (after.misfit * after.misfit - before * before) / after.lack_of_fit(noise)
        + (k_after as f64 - k_before as f64) * n.ln()
}

/// [`log_misfit_with`] and what else the evidence reads of the misfit
/// ([`MisfitStats`]).
pub fn misfit_stats(
    sys: &DampedSystem,
    measured: &FrfSet,
    lines: usize,
    gains: Gains,
    weights: Option<&[f64]>,
) -> Result<MisfitStats, UpdateError> {
    let at = informative_lines(measured, lines);
    // a line where the model is singular is left out of the misfit
    let (model, _) = frf::synthesize_regular(sys, measured.channels(), &at)?;
    let set = LineSet::with_model(measured, lines, gains, &model, weights)?;
    Ok(MisfitStats {
        misfit: (set.cost0 / (set.n as f64 / 2.0)).sqrt(),
        n: set.n,
        lag_correlation: set.lag_correlation,
    })
}

/// Pieces each beam is cut into by [`mesh_check`].
pub const MESH_CHECK_PARTS: usize = 2;

/// Largest model (DOFs, before refining) [`mesh_check`] refines: its cost
/// is two syntheses at the lines the diagnosis reads, one of them of a
/// model twice the size; a model of that size is meshed for its band as a
/// rule (and an imported model's blocks are not refined at all).
pub const MESH_CHECK_DOFS: usize = 10_000;

/// What a model's mesh decides of its FRFs: the model against the same
/// model with every beam cut into [`MESH_CHECK_PARTS`] elements
/// ([`fe_model::Model::refined`]), at the lines the diagnosis reads. A
/// coarse mesh is a model error of its own that no candidate effect is:
/// effects fitted to it stand for the mesh, not for physics (a flexible
/// clamp softening an L-frame meshed 12 + 10 elements against data of the
/// same frame meshed four times finer, at 2-3000 Hz).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MeshCheck {
    /// Pieces each beam was cut into.
    pub parts: usize,
    /// What the refinement moves the model's FRFs by: the RMS of
    /// `ln(H_refined / H)` per complex value (the misfit's measure).
    pub change: f64,
    /// The model's misfit against the data.
    pub misfit: f64,
    /// The refined model's misfit against the data (gains fitted alike).
    pub refined_misfit: f64,
}

impl MeshCheck {
    /// The mesh decides part of what the model leaves: refining it moves
    /// the FRFs by more than the data's `noise`, and towards the data (data
    /// made by the model as meshed, a synthetic study's, move away).
    pub fn visible(&self, noise: f64) -> bool {
        self.change > noise && self.refined_misfit < self.misfit
    }

    /// The mesh accounts for what the model leaves: the refinement is
    /// [`Self::visible`] and brings the misfit within `consistent` times
    /// the `noise` with no parameter added, so an effect fitted to what is
    /// left stands for the mesh.
    pub fn explains(&self, noise: f64, consistent: f64) -> bool {
        self.visible(noise) && self.refined_misfit <= consistent * noise
    }

    /// In words, for reports and terminals.
    pub fn describe(&self, noise: f64) -> String {
        let x = |v: f64| crate::quantities::times_noise(v, noise);
        format!(
            "the mesh: with every element cut in {} the model's FRFs move by {:.2} times the noise, and its misfit goes \
             from {:.2} to {:.2} times the noise",
            self.parts,
            x(self.change),
            x(self.misfit),
            x(self.refined_misfit)
        )
    }
}

/// The model against itself with a finer mesh ([`MeshCheck`]), over the
/// `lines` most informative lines of `measured`, with `gains` and
/// `weights` as the diagnosis fits them; `None` for a model without beams
/// or above [`MESH_CHECK_DOFS`]. The check only advises: where the model
/// or its refinement cannot be evaluated it is `None` too, and the
/// commands go on without it (the model's own failure is theirs to
/// report, where they evaluate it).
pub fn mesh_check(
    model: &fe_model::Model,
    measured: &FrfSet,
    lines: usize,
    gains: Gains,
    weights: Option<&[f64]>,
) -> Option<MeshCheck> {
    mesh_check_or_err(model, measured, lines, gains, weights).ok().flatten()
}

fn mesh_check_or_err(
    model: &fe_model::Model,
    measured: &FrfSet,
    lines: usize,
    gains: Gains,
    weights: Option<&[f64]>,
) -> Result<Option<MeshCheck>, UpdateError> {
    if model.beams().is_empty() {
        return Ok(None);
    }
    let sys = DampedSystem::new(model.clone())?;
    if sys.n() > MESH_CHECK_DOFS {
        return Ok(None);
    }
    let refined = DampedSystem::new(model.refined(MESH_CHECK_PARTS)?)?;
    let at = informative_lines(measured, lines);
    let (h, _) = frf::synthesize_regular(&sys, measured.channels(), &at)?;
    let (hr, _) = frf::synthesize_regular(&refined, measured.channels(), &at)?;
    // over the values both models give (a line where either is singular
    // is left out, as the misfit leaves it out)
    let (sum, count) = h.values().iter().zip(hr.values()).fold((0.0, 0usize), |(s, n), (a, b)| {
        let e = (b / a).ln();
        if e.re.is_finite() && e.im.is_finite() { (s + e.norm_sqr(), n + 1) } else { (s, n) }
    });
    if count == 0 {
        return Ok(None);
    }
    let misfit = |set: &FrfSet| -> Result<f64, UpdateError> {
        let s = LineSet::with_model(measured, lines, gains, set, weights)?;
        Ok((s.cost0 / (s.n as f64 / 2.0)).sqrt())
    };
    Ok(Some(MeshCheck {
        parts: MESH_CHECK_PARTS,
        change: (sum / count as f64).sqrt(),
        misfit: misfit(&h)?,
        refined_misfit: misfit(&hr)?,
    }))
}

/// Diagnoses a model against measured receptances (all measured lines; the
/// fits use subsets of them). Candidates are fitted in parallel.
pub fn diagnose(model: &fe_model::Model, measured: &FrfSet, opts: &DiagnoseOptions) -> Result<Diagnosis, UpdateError> {
    diagnose_with(model, measured, opts, |_| {})
}

/// As [`diagnose`], telling `progress` in a few words when each stage of
/// the search is done (for a long run's progress display).
pub fn diagnose_with(
    model: &fe_model::Model,
    measured: &FrfSet,
    opts: &DiagnoseOptions,
    mut progress: impl FnMut(&str),
) -> Result<Diagnosis, UpdateError> {
    diagnose_in(model, measured, opts, &mut progress, |_| {})
}

/// As [`diagnose_with`], with `prepare` given the pool before the search
/// (where the tests make chosen fits fail).
fn diagnose_in(
    model: &fe_model::Model,
    measured: &FrfSet,
    opts: &DiagnoseOptions,
    progress: &mut dyn FnMut(&str),
    prepare: impl FnOnce(&mut Pool<'_>),
) -> Result<Diagnosis, UpdateError> {
    let lines = measured.frequencies_hz();
    if lines.len() < 10 {
        return Err(UpdateError::Data(format!(
            "diagnosis needs at least 10 measured lines, the data have {}",
            lines.len()
        )));
    }
    let weights = opts.weights.as_deref();
    if let Some(w) = weights
        && w.len() != measured.channels().len() * lines.len()
    {
        return Err(UpdateError::Data(format!(
            "the diagnosis has {} weights for {} channels x {} lines",
            w.len(),
            measured.channels().len(),
            lines.len()
        )));
    }
    if let Some(&f) = opts.candidates.resonator_hz.iter().find(|f| !(f.is_finite() && **f > 0.0)) {
        return Err(UpdateError::Data(format!("a resonator's frequency must be positive and finite, got {f} Hz")));
    }
    let nominal = DampedSystem::new(model.clone())?;
    // the nominal model at every line read below, in one synthesis (on a
    // 96k-DOF frame, 2 s saved against one per line set)
    let read_of = |measured: &FrfSet| {
        let mut read: Vec<f64> = noise_lines(measured);
        for n in [opts.lines, opts.screen_lines, opts.prescreen_lines] {
            read.extend(informative_lines(measured, n));
        }
        read.sort_by(f64::total_cmp);
        read.dedup();
        read
    };
    let (mut at_lines, singular) = frf::synthesize_regular(&nominal, measured.channels(), &read_of(measured))?;
    // a lightly damped model evaluated on its own resonance is singular
    // there: that line is left out of the diagnosis (and said), not the
    // diagnosis stopped
    let (reduced, reduced_weights);
    let (measured, weights) = if singular.is_empty() {
        (measured, weights)
    } else {
        let keep: Vec<usize> = (0..lines.len()).filter(|&k| !singular.contains(&lines[k])).collect();
        (reduced, reduced_weights) = select_lines(measured, weights, &keep)?;
        (&reduced, reduced_weights.as_deref())
    };
    if !singular.is_empty() {
        // the lines chosen from what is left differ from those chosen with it
        at_lines = frf::synthesize_regular(&nominal, measured.channels(), &read_of(measured))?.0;
    }
    let lines = measured.frequencies_hz();
    let noise = noise_against(measured, weights, &at_lines, None)
        .ok_or_else(|| UpdateError::Data("too few usable measured values to estimate the noise level".into()))?;
    // a noise floor for noise-free data keeps the criterion finite
    let s2 = (noise * noise / 2.0).max(1e-20);
    let full = LineSet::with_model(measured, opts.lines, opts.gains, &at_lines, weights)?;
    let mut copts = opts.candidates.clone();
    copts.band_hz = (lines[0], lines[lines.len() - 1]);
    set_up_places(&mut copts, measured);
    for (hz, _) in broad_bands(&nominal, measured, weights, opts.gains, noise, copts.per_element_limit)? {
        if !copts.resonator_hz.iter().any(|&g| (hz / g - 1.0).abs() < SAME_TUNING) {
            copts.resonator_hz.push(hz);
        }
    }
    let mut pool = Pool::new(model, &nominal, s2, copts.band_hz);
    prepare(&mut pool);
    search::search(&mut pool, measured, &at_lines, &full, opts, &copts, progress)?;
    let mut d = rank(pool, noise, &full, opts);
    d.singular_hz = singular;
    Ok(d)
}

/// `measured` and its channel-major `weights` at the lines `keep` (indices,
/// ascending).
pub(crate) fn select_lines(
    measured: &FrfSet,
    weights: Option<&[f64]>,
    keep: &[usize],
) -> Result<(FrfSet, Option<Vec<f64>>), UpdateError> {
    let nf = measured.n_freq();
    let weights = weights
        .map(|w| (0..measured.channels().len()).flat_map(|c| keep.iter().map(move |&k| w[c * nf + k])).collect());
    Ok((measured.select_lines(keep)?, weights))
}

/// A band whose middle lies within this relative distance of a frequency
/// resonators are tuned to already adds none: the fit moves the tuning
/// further than that (see `suspects`).
const SAME_TUNING: f64 = 0.1;

/// The middles (Hz) of the bands where the residual of `sys` is broad
/// between the modes, each with its level (see `suspects`): where a
/// heavily damped resonator that shows no mode of its own points at
/// itself, and where such a resonator, once added, leaves none. Read only
/// on a model of beams small enough to get every candidate from the start
/// (up to `per_element_limit` elements,
/// [`CandidateOptions::per_element_limit`]): the resonators tuned to them
/// go to every node that can move, and the model is synthesised at every
/// measured line to find them, neither of which a large model can afford.
/// None on a large or an imported model.
pub(crate) fn broad_bands(
    sys: &DampedSystem,
    measured: &FrfSet,
    weights: Option<&[f64]>,
    gains: Gains,
    noise: f64,
    per_element_limit: usize,
) -> Result<Vec<(f64, f64)>, UpdateError> {
    let beams = sys.model().beams().len();
    if beams == 0 || beams > per_element_limit {
        return Ok(Vec::new());
    }
    let (at_all, _) = frf::synthesize_regular(sys, measured.channels(), measured.frequencies_hz())?;
    suspects::broad_residual_hz(measured, &at_all, weights, gains, noise)
}

/// The places of the test's own hardware, from the data where the caller
/// names none: the drive points (the references in a translation, where a
/// shaker's armature and suspension load the structure) and the response
/// nodes (where the sensors' masses sit).
fn set_up_places(copts: &mut CandidateOptions, measured: &FrfSet) {
    if copts.drive_points.is_empty() {
        let mut drives: Vec<(u32, fe_model::Dof)> = measured
            .channels()
            .iter()
            .filter(|c| c.reference.dof.is_translation())
            .map(|c| (c.reference.node.0, c.reference.dof))
            .collect();
        drives.sort_unstable();
        drives.dedup();
        copts.drive_points = drives;
    }
    if copts.sensor_nodes.is_empty() {
        let mut nodes: Vec<u32> = measured.channels().iter().map(|c| c.response.node.0).collect();
        nodes.sort_unstable();
        nodes.dedup();
        copts.sensor_nodes = nodes;
    }
}

/// The ranking of a finished search.
fn rank(mut pool: Pool<'_>, noise: f64, full: &LineSet, opts: &DiagnoseOptions) -> Diagnosis {
    pool.release();
    // each candidate judged against what it leaves (see `delta_bic`), with
    // the correlation of the nominal model's residual standing for its own
    let evidence = |f: &search::Fit, k: usize| {
        let after =
            MisfitStats { misfit: (f.cost / (f.n as f64 / 2.0)).sqrt(), n: f.n, lag_correlation: full.lag_correlation };
        delta_bic((f.cost0 / (f.n as f64 / 2.0)).sqrt(), 0, &after, k, noise)
    };
    let ranked = |i: usize, f: &search::Fit, fully: bool| {
        let c = &pool.candidates[i];
        let delta_bic = evidence(f, c.parameters.len());
        let implausible_reason = c.implausible(&f.values, &f.determined);
        Ranked {
            kind: c.kind,
            gains: f.gains.clone(),
            // at its fitted values: a resonator's names its fitted tuning
            description: c.description_at(&f.values),
            nodes: c.nodes.clone(),
            elements: c.elements.clone(),
            dof: c.dofs.iter().map(|d| d.to_string()).collect(),
            damping: c.damping(),
            explained: (1.0 - f.cost / f.cost0).max(0.0),
            misfit: (f.cost / (f.n as f64 / 2.0)).sqrt(),
            lines: f.lines,
            delta_bic,
            significant: delta_bic < opts.significance,
            plausible: implausible_reason.is_none(),
            implausible_reason,
            parameters: (0..c.parameters.len())
                .map(|p| FittedParameter {
                    name: c.parameters[p].clone(),
                    role: c.roles[p],
                    value: f.values[p],
                    relative_std: f.relative_std[p],
                    determined: f.determined[p],
                })
                .collect(),
            held: c.held.clone(),
            fully_fitted: fully,
            candidate: i,
        }
    };
    let fully = pool.by_full_fit();
    let mut ranking: Vec<Ranked> =
        fully.iter().map(|&i| ranked(i, pool.full[i].as_ref().expect("fully fitted"), true)).collect();
    // stable: candidates of equal evidence keep the search's order
    ranking.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    let rest: Vec<usize> =
        (0..pool.candidates.len()).filter(|&i| pool.full[i].is_none() && !pool.superseded[i]).collect();
    // (in parallel: a large model ranks tens of thousands of screening
    // fits, a second on one thread at the end of the diagnosis)
    let screened: Vec<Ranked> = pool
        .by_screening(&rest)
        .par_iter()
        .map(|&i| ranked(i, pool.screened[i].as_ref().expect("screened"), false))
        .collect();
    ranking.extend(screened);
    let recommended = ranking.iter().position(|r| r.fully_fitted && r.significant && r.plausible).map(|r| r + 1);
    // a ranked candidate is listed under the description it is ranked with
    let ranked: std::collections::HashMap<usize, &str> =
        ranking.iter().map(|r| (r.candidate, r.description.as_str())).collect();
    let unfitted = (0..pool.candidates.len())
        .filter_map(|i| {
            let (stage, reason) = pool.failure[i].clone()?;
            Some(Unfitted {
                description: ranked.get(&i).map_or_else(|| pool.candidates[i].description.clone(), |d| d.to_string()),
                reason,
                stage,
                ranked: ranked.contains_key(&i),
            })
        })
        .collect();
    Diagnosis {
        noise,
        nominal_misfit: (full.cost0 / (full.n as f64 / 2.0)).sqrt(),
        n_residuals: full.n,
        ranking,
        recommended,
        tried: pool.candidates.len(),
        superseded: pool.superseded.iter().filter(|&&s| s).count(),
        deferred: pool.deferred.len(),
        gains: full.gains,
        weighted: full.weights.is_some(),
        unfitted,
        singular_hz: Vec::new(),
        candidates: pool.candidates,
    }
}

#[cfg(test)]
mod tests {
    use damping::DampedSystem;
    use fe_model::{Dof, DofRef, Group, samples};
    use frf::{Channel, NoiseModel, synthesize};

    use super::*;

    fn ranked(kind: EffectKind, nodes: &[u32], delta_bic: f64, plausible: bool) -> Ranked {
        Ranked {
            kind,
            gains: Vec::new(),
            description: format!("{kind:?} at {nodes:?}"),
            nodes: nodes.to_vec(),
            elements: Vec::new(),
            dof: Vec::new(),
            damping: None,
            explained: 0.9,
            misfit: 0.02,
            lines: 200,
            delta_bic,
            significant: delta_bic < SIGNIFICANT_DBIC,
            plausible,
            implausible_reason: (!plausible).then(|| "too heavy".to_string()),
            parameters: Vec::new(),
            held: Vec::new(),
            fully_fitted: true,
            candidate: 0,
        }
    }

    /// Fits of one effect at one place whose dBIC differ by no more than
    /// the significance threshold fold into the best one's row (the
    /// lap-joint tutorial's resonators at node 9 from several tunings);
    /// another place, kind or damping form, an implausible twin, a larger
    /// difference or the recommended rank keep rows of their own, and
    /// `top` counts rows.
    #[test]
    fn variants_the_data_do_not_tell_apart_share_a_row() {
        use EffectKind::{LumpedMass, Resonator};
        let ranking = vec![
            ranked(EffectKind::FlexibleJoint, &[9], -12_000_000.0, true),
            ranked(Resonator, &[9], -1643.0, true),
            ranked(Resonator, &[9], -1640.0, true),
            ranked(Resonator, &[9], -1636.0, true),
            ranked(Resonator, &[8], -1635.0, true),
            Ranked { damping: Some("non-viscous"), ..ranked(Resonator, &[9], -1635.0, true) },
            ranked(Resonator, &[9], -1633.0, false),
            ranked(Resonator, &[9], -1634.0, true),
            ranked(Resonator, &[9], -1600.0, true),
            ranked(LumpedMass, &[9], -634.0, true),
            ranked(LumpedMass, &[9], -630.0, true),
        ];
        let rows = |recommended, top| -> Vec<(usize, Vec<usize>)> {
            shown_ranking(&ranking, recommended, top).into_iter().map(|r| (r.rank, r.alike)).collect()
        };
        assert_eq!(
            rows(Some(1), 10),
            vec![(1, vec![]), (2, vec![3, 4, 8]), (5, vec![]), (6, vec![]), (7, vec![]), (9, vec![]), (10, vec![11])]
        );
        // the recommended rank is shown even where it would fold
        assert_eq!(rows(Some(3), 10)[1..3], [(2, vec![4, 8]), (3, vec![])]);
        // top counts the rows shown; later ranks still fold into them
        assert_eq!(rows(None, 2), vec![(1, vec![]), (2, vec![3, 4, 8])]);
    }

    /// Fits made to fail at each stage are counted with their stage and
    /// reason, and every other candidate stays ranked: screenings that fail
    /// leave the candidate out of the ranking, a full fit that fails leaves
    /// it ranked as screened only, and a variant holding what the data do
    /// not determine supersedes its fuller candidate only when its own fit
    /// succeeded.
    #[test]
    fn candidates_whose_fits_fail_are_counted_and_the_rest_ranked() {
        // a cantilever on a flexible, lossy clamp, measured across its axis:
        // the clamp's axial spring is not determined, so its held variant is fitted
        let nominal = samples::cantilever(10);
        let mut truth = nominal.clone();
        truth.remove_support(1);
        let g = truth.add_group(Group::new("clamp").rayleigh(3e-4, 0.0)).unwrap();
        truth.add_spring("clamp", 1, None, [1e12, 1e10, 2e4], g).unwrap();
        let tip = DofRef::new(11, Dof::Uy);
        let channels: Vec<Channel> = (3..=11).step_by(2).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
        let lines: Vec<f64> = (2..=400).map(|i| 0.75 * f64::from(i)).collect();
        let mut measured = synthesize(&DampedSystem::new(truth).unwrap(), &channels, &lines).unwrap();
        NoiseModel::relative(0.01, 3).apply(&mut measured);

        fn fail(c: &Candidate, stage: FitStage) -> bool {
            match stage {
                FitStage::Screening => c.kind == EffectKind::LumpedMass,
                FitStage::FullFit => c.kind == EffectKind::StiffnessChange || !c.held.is_empty(),
                FitStage::PreScreening => false,
            }
        }
        let opts = DiagnoseOptions::default();
        let d = diagnose_in(&nominal, &measured, &opts, &mut |_| {}, |pool| pool.forced_failure = Some(fail)).unwrap();

        let masses = d.candidates.iter().filter(|c| c.kind == EffectKind::LumpedMass).count();
        let held = d.candidates.iter().filter(|c| !c.held.is_empty()).count();
        let stiffness_ranked: Vec<&Ranked> =
            d.ranking.iter().filter(|r| r.kind == EffectKind::StiffnessChange).collect();
        assert!(masses > 0 && held > 0, "{masses} masses, {held} held variants: nothing to fail");
        for u in &d.unfitted {
            assert!(u.reason.contains(&format!("made to fail by the test at {}", u.stage)), "{u:?}");
        }
        let count = |stage: FitStage, ranked: bool| {
            d.unfitted.iter().filter(|u| u.stage == stage && u.ranked == ranked).count()
        };
        // every mass fails its screening and is left out of the ranking
        assert_eq!(count(FitStage::Screening, false), masses, "{:#?}", d.unfitted);
        assert!(d.ranking.iter().all(|r| r.kind != EffectKind::LumpedMass));
        // every held variant fails its full fit and has no screening to fall back on
        assert_eq!(count(FitStage::FullFit, false), held, "{:#?}", d.unfitted);
        // the stiffness changes fitted fully fail and stay ranked as screened only
        let full_failed = count(FitStage::FullFit, true);
        assert!(full_failed > 0, "{:#?}", d.unfitted);
        assert!(stiffness_ranked.iter().all(|r| !r.fully_fitted));
        assert_eq!(
            d.unfitted.iter().filter(|u| u.ranked).count(),
            full_failed,
            "only full fits fail for ranked candidates"
        );
        assert_eq!(d.unfitted.len(), masses + held + full_failed);
        // the clamp whose held variant failed keeps its own full fit
        let clamp = d.ranking.iter().find(|r| r.kind == EffectKind::FlexibleSupport && r.fully_fitted);
        let clamp = clamp.expect("the fuller clamp stays ranked when its held variant fails");
        assert!(clamp.held.is_empty() && clamp.parameters.iter().any(|p| !p.determined), "{clamp:?}");
        assert!(d.leader().is_some_and(|l| l.kind == EffectKind::FlexibleSupport), "{:?}", d.ranking.first());
        // every candidate tried is ranked, superseded or unfitted
        let unranked = d.unfitted.iter().filter(|u| !u.ranked).count();
        assert_eq!(d.tried, d.ranking.len() + d.superseded + unranked + d.deferred);
    }
}

#[cfg(test)]
mod determinism_tests {
    use damping::DampedSystem;
    use fe_model::{Dof, samples};
    use frf::{Channel, NoiseModel, synthesize};

    use super::*;

    /// The frame of `diagnose_point` at a small size (`bays`, `storeys`,
    /// `per` elements per member): a 40 % stiffness loss in the middle of
    /// the first floor beam, 12 measured translations, 1 % noise; returns
    /// the nominal model and the data.
    pub(super) fn small_frame(bays: usize, storeys: usize, per: usize) -> (fe_model::Model, FrfSet) {
        let nominal = samples::frame_grid(bays, storeys, per);
        let sys = DampedSystem::new(nominal.clone()).unwrap();
        let element = (((bays + 1) + bays / 2) * per + per / 2 + 1) as u32;
        let mut truth = nominal.clone();
        let q = truth.quantity(&format!("element.{element}.stiffness")).unwrap();
        truth.set(q, 0.6).unwrap();
        let dofs = sys.assembly().dofs();
        let uy: Vec<_> = (0..sys.n()).map(|eq| dofs.dof_of(eq)).filter(|d| d.dof == Dof::Uy).collect();
        let measured: Vec<_> = (0..12).map(|i| uy[(2 * i + 1) * uy.len() / 24]).collect();
        let channels: Vec<Channel> = measured.iter().map(|&r| Channel::new(r, measured[6])).collect();
        let top = 1.2 * crate::study::natural_frequencies(&sys, 1e6).0[5];
        let lines: Vec<f64> = (1..=200).map(|k| top * k as f64 / 200.0).collect();
        let mut data = synthesize(&DampedSystem::new(truth).unwrap(), &channels, &lines).unwrap();
        NoiseModel::relative(0.01, 7).apply(&mut data);
        (nominal, data)
    }

    /// Listening to the stages changes nothing: the same candidates and the
    /// same ranking, value for value, with a callback that reads every
    /// message (as `diagnose_point --verbose` prints them) and without one,
    /// and from one run to the next (the fits run in parallel; a result that
    /// hung on their order would differ between runs).
    #[test]
    fn listening_to_the_stages_changes_nothing() {
        let (nominal, data) = small_frame(2, 2, 3);
        let opts = DiagnoseOptions::default();
        let quiet = diagnose(&nominal, &data, &opts).unwrap();
        let mut heard = Vec::new();
        let verbose = diagnose_with(&nominal, &data, &opts, |s| heard.push(s.to_string())).unwrap();
        let again = diagnose(&nominal, &data, &opts).unwrap();
        assert!(heard.len() >= 4 && heard.iter().any(|s| s.contains("fits")), "{heard:?}");
        for other in [&verbose, &again] {
            assert_eq!(quiet.candidates.len(), other.candidates.len());
            assert_eq!(quiet.ranking.len(), other.ranking.len());
            for (a, b) in quiet.ranking.iter().zip(&other.ranking) {
                assert_eq!(a.description, b.description);
                assert_eq!(a.delta_bic.to_bits(), b.delta_bic.to_bits(), "{}", a.description);
                let values = |r: &Ranked| r.parameters.iter().map(|p| p.value.to_bits()).collect::<Vec<_>>();
                assert_eq!(values(a), values(b), "{}", a.description);
            }
        }
    }

    /// The refinement's candidates, gathered with the screening's data on
    /// a pre-screened model with coarse windows, are fitted as they are when the refinement
    /// gathers its own: the same candidates, the same ranking (to
    /// round-off: the factorisation's ordering differs with its cliques),
    /// and no second gathering.
    #[test]
    fn anticipated_refinement_data_fit_as_their_own() {
        // members of 12 elements, so that the refinement's windows reach
        // beyond the coarse ones screened
        let (nominal, data) = small_frame(2, 2, 12);
        // coarse windows first and the refinement's every window around the
        // leaders, as on a large model
        let mut opts = DiagnoseOptions { prescreen_above: 0, prescreen_keep: 20, ..DiagnoseOptions::default() };
        opts.candidates.per_element_limit = 8;
        let run = |anticipate: bool| {
            let mut heard = Vec::new();
            let d = diagnose_in(&nominal, &data, &opts, &mut |s: &str| heard.push(s.to_string()), |pool| {
                pool.anticipate = anticipate;
            })
            .unwrap();
            let refined = heard.into_iter().find(|s| s.starts_with("refined around")).expect("a refinement");
            (d, refined)
        };
        let ((own, own_msg), (early, early_msg)) = (run(false), run(true));
        assert!(own_msg.contains("gathering"), "{own_msg}");
        assert!(!early_msg.contains("gathering"), "the refinement gathered again: {early_msg}");
        assert_eq!(own.candidates.len(), early.candidates.len());
        assert_eq!(own.ranking.len(), early.ranking.len());
        for (a, b) in own.ranking.iter().zip(&early.ranking).take(20) {
            assert_eq!(a.description, b.description);
            assert!((a.delta_bic - b.delta_bic).abs() <= 1e-8 * a.delta_bic.abs(), "{}", a.description);
        }
        assert_eq!(own.ranking[0].kind, EffectKind::StiffnessChange, "{}", own.ranking[0].description);
    }
}

#[cfg(test)]
mod lack_of_fit_tests {
    use super::MisfitStats;

    /// The variance is the noise's within the noise, continuous where the
    /// misfit leaves it, and the whole misfit's widened by the correlation
    /// far above it.
    #[test]
    fn the_variance_grows_from_the_noise_and_widens_only_the_excess() {
        let at = |misfit: f64, rho: f64| MisfitStats { misfit, n: 1000, lag_correlation: rho }.lack_of_fit(0.01);
        assert_eq!(at(0.009, 0.9), 1e-4);
        assert_eq!(at(0.01, 0.9), 1e-4);
        assert!((at(0.01 * (1.0 + 1e-9), 0.9) - 1e-4).abs() < 1e-10, "continuous at the noise");
        let far = at(1.0, 0.5);
        assert!((far / 3.0 - 1.0).abs() < 1e-3, "{far}: (1 + rho) / (1 - rho) = 3 times the misfit's");
        // anti-correlated residuals are not read as less than independent
        assert_eq!(at(0.02, -0.5), 4e-4);
    }
}
