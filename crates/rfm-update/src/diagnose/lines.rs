//! The lines a diagnosis fits on: the most informative lines of the data
//! ([`informative_lines`]), and a set of them with the nominal model's
//! misfit there ([`LineSet`]), against which every candidate's fit is
//! judged.

use fe_model::case::Gains;
use frf::FrfSet;

use crate::error::UpdateError;

/// `n` lines of a measured set that carry most of what the data can tell
/// (the lines the diagnosis fits and [`super::log_misfit`] measures on):
/// up to half of them at and around the resonance peaks (where damping
/// and small frequency shifts show, on a line grid that an even spread
/// would step across), the rest spread evenly over the band. Peaks are
/// local maxima of the sum over channels of `ln |M|`, ranked by prominence.
pub fn informative_lines(measured: &FrfSet, n: usize) -> Vec<f64> {
    let lines = measured.frequencies_hz();
    if n >= lines.len() {
        return lines.to_vec();
    }
    let nl = lines.len();
    let mut peaks = peaks(measured);
    peaks.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut idx: Vec<usize> = Vec::new();
    'peaks: for &(_, k) in &peaks {
        for j in k.saturating_sub(2)..=(k + 2).min(nl - 1) {
            if idx.len() >= n / 2 {
                break 'peaks;
            }
            idx.push(j);
        }
    }
    idx.sort_unstable();
    idx.dedup();
    let rest = n - idx.len();
    let mut m = rest;
    // enough evenly spread lines that, with the peaks', n are distinct
    while m <= nl {
        let mut all = idx.clone();
        all.extend((0..m).map(|i| (i as f64 * (nl - 1) as f64 / (m - 1).max(1) as f64).round() as usize));
        all.sort_unstable();
        all.dedup();
        if all.len() >= n || m == nl {
            return all.into_iter().map(|k| lines[k]).collect();
        }
        m += (n - all.len()).max(1);
    }
    lines.to_vec()
}

/// The resonance peaks of a set: local maxima of the mean over channels
/// of `ln |M|` that stand more than 1 (a factor of e) above the lowest
/// level within eight lines either side, as (that prominence, line index).
pub(crate) fn peaks(set: &FrfSet) -> Vec<(f64, usize)> {
    let nl = set.n_freq();
    let nc = set.channels().len();
    let level: Vec<f64> = (0..nl)
        .map(|k| (0..nc).map(|c| set.get(c, k).norm().max(f64::MIN_POSITIVE).ln()).sum::<f64>() / nc.max(1) as f64)
        .collect();
    // prominence: the height above the lowest level within a few peak widths
    const REACH: usize = 8;
    (1..nl.saturating_sub(1))
        .filter(|&k| level[k] > level[k - 1] && level[k] >= level[k + 1])
        .map(|k| {
            let lo = k.saturating_sub(REACH);
            let hi = (k + REACH + 1).min(nl);
            let floor = level[lo..hi].iter().copied().fold(f64::INFINITY, f64::min);
            (level[k] - floor, k)
        })
        .filter(|&(p, _)| p > 1.0)
        .collect()
}

/// The correlation between adjacent lines of channel-major residuals
/// (`nf` lines per channel; `None` values skipped), real and imaginary
/// parts pooled: `sum r_k r_k+1 / sum r_k^2`, clamped to `0..=0.95` (a
/// negative one is noise, and one of 1 would count no line as independent).
pub(crate) fn lag_correlation(r: &[Option<num_complex::Complex64>], nf: usize) -> f64 {
    let (mut lag, mut all) = (0.0, 0.0);
    for channel in r.chunks(nf.max(1)) {
        for pair in channel.windows(2) {
            if let (Some(a), Some(b)) = (pair[0], pair[1]) {
                lag += a.re * b.re + a.im * b.im;
            }
        }
        all += channel.iter().flatten().map(|e| e.norm_sqr()).sum::<f64>();
    }
    if all > 0.0 { (lag / all).clamp(0.0, 0.95) } else { 0.0 }
}

/// A line set with the nominal model's cost on it.
pub(crate) struct LineSet {
    pub(crate) data: FrfSet,
    pub(crate) cost0: f64,
    /// Real residuals.
    pub(crate) n: usize,
    /// The gains every fit on these lines fits (and `cost0` is the nominal
    /// model's after its best gains).
    pub(crate) gains: Gains,
    /// Residual weights at these lines, channel-major (`None`: all 1).
    pub(crate) weights: Option<Vec<f64>>,
    /// The correlation of the nominal model's weighted residuals between
    /// adjacent lines of a channel (real and imaginary parts alike): about
    /// 0 for noise, towards 1 for the smooth residual of a model error.
    pub(crate) lag_correlation: f64,
}

impl LineSet {
    /// The `n_lines` most informative lines of `measured` with the nominal
    /// model's cost there; `nominal` holds the nominal model's FRFs at (at
    /// least) those lines, `weights` the residual weights at the lines of
    /// `measured` (channel-major; `None`: all 1).
    pub(crate) fn with_model(
        measured: &FrfSet,
        n_lines: usize,
        gains: Gains,
        nominal: &FrfSet,
        weights: Option<&[f64]>,
    ) -> Result<Self, UpdateError> {
        let lines = informative_lines(measured, n_lines);
        let data = measured.at_frequencies(&lines)?;
        let mut model = nominal.at_frequencies(&lines)?;
        let weights: Option<Vec<f64>> = weights.map(|w| {
            let (nf, at): (usize, Vec<usize>) =
                (measured.n_freq(), lines.iter().map(|&f| measured.line_of(f).expect("a measured line")).collect());
            (0..data.channels().len()).flat_map(|c| at.iter().map(move |&k| w[c * nf + k])).collect()
        });
        if gains != Gains::None {
            // the closed-form gains of the nominal model: its misfit is what no gain removes
            let model_kind = model.converted(data.kind());
            let fitted = crate::gain::fit_gains(&model_kind, &data, weights.as_deref(), gains)?;
            fitted.apply(&mut model);
        }
        let (mut cost, mut n) = (0.0, 0);
        let nf = data.n_freq();
        // weighted residuals, `None` where a value does not count
        let mut r: Vec<Option<num_complex::Complex64>> = Vec::with_capacity(data.values().len());
        for (i, (h, m)) in model.values().iter().zip(data.values()).enumerate() {
            let w = weights.as_ref().map_or(1.0, |w| w[i]);
            // a line where the model is singular has no receptance to compare
            // (see `synthesize_regular`): it is left out, as a zero measurement is
            if m.norm() > 0.0 && w > 0.0 && h.re.is_finite() && h.im.is_finite() {
                let e = w * (h / m).ln();
                cost += e.norm_sqr();
                n += 2;
                r.push(Some(e));
            } else {
                r.push(None);
            }
        }
        if !cost.is_finite() {
            return Err(UpdateError::Data("the nominal model's misfit is not finite at the measured lines".into()));
        }
        Ok(LineSet { data, cost0: cost, n, gains, weights, lag_correlation: lag_correlation(&r, nf) })
    }
}
