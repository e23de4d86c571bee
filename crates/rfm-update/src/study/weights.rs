//! The residual weights of a study's fits: band weights from `[update]`
//! times the measured coherence's.

use fe_model::CaseFile;
use frf::FrfSet;

use super::Study;
use crate::error::UpdateError;

impl Study {
    /// Whether the fits weight lines by the measured coherence: by default
    /// whenever the data carry it, unless `[update] coherence = false`.
    pub fn weighs_coherence(&self) -> bool {
        let asked = self.case.update.as_ref().and_then(|u| u.coherence);
        asked.unwrap_or(true) && (0..self.measured.channels().len()).any(|c| self.measured.coherence(c).is_some())
    }

    /// Residual weights for `measured` (lines of this study's data): the
    /// `[update]` band weights times the coherence weight
    /// `sqrt(g / (1 - g))`, the inverse of an FRF estimate's relative
    /// standard deviation up to a constant (capped at coherence 0.999 and
    /// scaled to 1 there); channel-major, `None` when all are 1. Used by the
    /// output-error fit, the gain fits and the comparison.
    pub fn line_weights(&self, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
        line_weights_for(&self.case, measured)
    }

    /// Line weights of the output-error fit (see [`Study::line_weights`]).
    pub fn weights(&self, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
        self.line_weights(measured)
    }
}

/// The residual weights of a case's measured data `measured` (see
/// [`Study::line_weights`]): band weights times the coherence weight,
/// whenever the data carry coherence unless `[update] coherence = false`.
pub fn line_weights_for(case: &CaseFile, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
    let bands = case.update.as_ref().map_or(&[][..], |u| &u.weights[..]);
    let asked = case.update.as_ref().and_then(|u| u.coherence);
    let has = (0..measured.channels().len()).any(|c| measured.coherence(c).is_some());
    if asked == Some(true) && !has {
        return Err(UpdateError::Data(
            "coherence weighting is requested ([update] coherence = true) but the measured data carry no \
             coherence"
                .into(),
        ));
    }
    let coherence = asked.unwrap_or(true) && has;
    if bands.is_empty() && !coherence {
        return Ok(None);
    }
    let nf = measured.n_freq();
    let mut w = vec![1.0; nf * measured.channels().len()];
    for (c, chunk) in w.chunks_mut(nf).enumerate() {
        for (k, wk) in chunk.iter_mut().enumerate() {
            let f = measured.frequencies_hz()[k];
            for b in bands.iter().filter(|b| b.from <= f && f <= b.to) {
                *wk *= b.weight;
            }
            if coherence && let Some(coh) = measured.coherence(c) {
                let g = coh[k].clamp(0.0, 0.999);
                *wk *= (g / (1.0 - g)).sqrt().min(30.0) / 30.0;
            }
        }
    }
    Ok(Some(w))
}
