//! The residual weights of a study's fits: band weights from `[update]`
//! times the measured coherence's, or, for data without coherence, the
//! weights of the lines at an additive noise floor
//! ([`frf::noise::floor_weights`], attached when the data are read).

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
    /// scaled to 1 there), or for data without coherence the noise floor's
    /// weights the data carry; channel-major, `None` when all are 1. Used by the
    /// output-error fit, the gain fits and the comparison.
    pub fn line_weights(&self, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
        line_weights_for(&self.case, measured)
    }

    /// Line weights of the output-error fit (see [`Study::line_weights`]).
    pub fn weights(&self, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
        self.line_weights(measured)
    }

    /// The noise level the weighted residual of a fit to `fitted` (lines of
    /// this study's data) is compared with (see [`residual_noise_for`]).
    pub fn residual_noise(&self, fitted: &FrfSet) -> Result<Option<f64>, UpdateError> {
        residual_noise_for(&self.case, &self.system, &self.measured, fitted)
    }
}

/// The residual weights of a case's measured data `measured` (see
/// [`Study::line_weights`]): band weights times the coherence weight,
/// whenever the data carry coherence unless `[update] coherence = false`,
/// or else the weights of the lines at a noise floor the data carry.
pub fn line_weights_for(case: &CaseFile, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
    let noise = noise_weights(case, measured)?;
    Ok(match (band_weights(case, measured), noise) {
        (None, None) => None,
        (Some(w), None) | (None, Some(w)) => Some(w),
        (Some(band), Some(noise)) => Some(band.iter().zip(&noise).map(|(b, c)| b * c).collect()),
    })
}

/// The weights of the data's noise: the coherence's where the data carry
/// coherence ([`coherence_weights`]), else those of the lines at a noise
/// floor that the data carry ([`frf::noise::floor_weights`], attached to
/// every channel or none); channel-major.
fn noise_weights(case: &CaseFile, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
    let coherence = coherence_weights(case, measured)?;
    let n = measured.channels().len();
    if coherence.is_some() || (0..n).any(|c| measured.coherence(c).is_some()) {
        return Ok(coherence);
    }
    Ok((0..n).map(|c| measured.floor_weights(c)).collect::<Option<Vec<_>>>().map(|w| w.concat()))
}

/// The `[update]` band weights at the lines of `measured`, channel-major;
/// `None` when the case gives none.
fn band_weights(case: &CaseFile, measured: &FrfSet) -> Option<Vec<f64>> {
    let bands = case.update.as_ref().map_or(&[][..], |u| &u.weights[..]);
    if bands.is_empty() {
        return None;
    }
    let per_line: Vec<f64> = measured
        .frequencies_hz()
        .iter()
        .map(|&f| bands.iter().filter(|b| b.from <= f && f <= b.to).map(|b| b.weight).product())
        .collect();
    Some(per_line.repeat(measured.channels().len()))
}

/// The coherence weights `sqrt(g / (1 - g))` (capped at coherence 0.999
/// and scaled to 1 there) at the lines of `measured`, channel-major, a
/// channel without coherence weighted 1; `None` when the data carry no
/// coherence or the case turns the weighting off.
fn coherence_weights(case: &CaseFile, measured: &FrfSet) -> Result<Option<Vec<f64>>, UpdateError> {
    let asked = case.update.as_ref().and_then(|u| u.coherence);
    let has = (0..measured.channels().len()).any(|c| measured.coherence(c).is_some());
    if asked == Some(true) && !has {
        return Err(UpdateError::Data(
            "coherence weighting is requested ([update] coherence = true) but the measured data carry no \
             coherence"
                .into(),
        ));
    }
    if !(asked.unwrap_or(true) && has) {
        return Ok(None);
    }
    let nf = measured.n_freq();
    let mut w = vec![1.0; nf * measured.channels().len()];
    for (c, chunk) in w.chunks_mut(nf).enumerate() {
        if let Some(coh) = measured.coherence(c) {
            for (wk, &g) in chunk.iter_mut().zip(coh) {
                let g = g.clamp(0.0, 0.999);
                *wk = (g / (1.0 - g)).sqrt().min(30.0) / 30.0;
            }
        }
    }
    Ok(Some(w))
}

/// The noise level that the weighted residual of a fit to `fitted` (lines
/// of `measured`, the case's data) is compared with: the noise weighted as
/// the residual is. The coherence weight is the inverse of an FRF
/// estimate's relative standard deviation up to a constant, so the
/// weighted values have one noise level throughout (the noise of data at
/// a floor differs from line to line, and is read on the fitted lines from
/// the floor: [`crate::diagnose::estimate_noise_against_on`]), estimated
/// from their roughness over every measured line, and from that of their
/// residual against the model `sys` where that is lower (on lines coarse
/// against the peaks the data's own roughness is mostly the dynamics;
/// [`crate::diagnose::estimate_noise_against_weighted`]); the band weights
/// are the user's and multiply it by their RMS over the fitted values.
pub fn residual_noise_for(
    case: &CaseFile,
    sys: &damping::DampedSystem,
    measured: &FrfSet,
    fitted: &FrfSet,
) -> Result<Option<f64>, UpdateError> {
    let noise = noise_weights(case, measured)?;
    let on = Some(fitted.frequencies_hz());
    let Some(level) = crate::diagnose::estimate_noise_against_on(sys, measured, noise.as_deref(), on)? else {
        return Ok(None);
    };
    let Some(band) = band_weights(case, fitted) else { return Ok(Some(level)) };
    let weights = line_weights_for(case, fitted)?.unwrap_or_else(|| vec![1.0; band.len()]);
    let values = (0..fitted.channels().len()).flat_map(|c| fitted.channel(c).iter().copied());
    let (sum, n) = band
        .iter()
        .zip(&weights)
        .zip(values)
        .filter(|&((_, &w), m)| w > 0.0 && m.norm() > 0.0 && m.norm().is_finite())
        .fold((0.0, 0usize), |(sum, n), ((b, _), _)| (sum + b * b, n + 1));
    Ok((n > 0).then(|| level * (sum / n as f64).sqrt()))
}

/// Finds the lines at an additive noise floor of data without coherence
/// ([`frf::noise::floor_weights`]) and attaches their weights to `set`
/// (carried by every set selected from it); returns the note that says
/// so, `None` when the data carry coherence or weights already, or have no
/// such lines. Call it on the data as measured (their kind as read).
pub(crate) fn attach_floor_weights(set: &mut FrfSet) -> Option<String> {
    let n = set.channels().len();
    if (0..n).any(|c| set.coherence(c).is_some() || set.floor_weights(c).is_some()) {
        return None;
    }
    let found = frf::noise::floor_weights(set)?;
    set.set_floor_weights(found.weights.clone(), found.noise.clone(), found.spreads()).expect("one weight per value");
    let per: Vec<String> = found
        .channels
        .iter()
        .zip(set.channels())
        .filter_map(|(f, ch)| f.map(|f| format!("{ch} {} lines (floor {:.3e})", f.lines, f.floor)))
        .collect();
    let lines: usize = found.channels.iter().flatten().map(|f| f.lines).sum();
    // where the floor covers much of a channel, a fit's misfit above the
    // noise may be the data's: a strip's receptance at a floor of 3e-4 of
    // its peak (45 % of the lines) left 2.6 times the noise with the right
    // model
    let covered: Vec<String> = found
        .channels
        .iter()
        .zip(set.channels())
        .filter(|(f, _)| f.is_some_and(|f| 4 * f.lines > set.n_freq()))
        .map(|(_, ch)| ch.to_string())
        .collect();
    let warning = if covered.is_empty() {
        String::new()
    } else {
        format!(
            "; the floor covers over a quarter of the lines of {}: what a fit leaves above the noise may be the \
             data's rather than the model's (measure in the kind whose floor lies lowest against the response, \
             or give the coherence)",
            covered.join(", ")
        )
    };
    Some(format!(
        "{lines} lines of {} channels read at an additive noise floor (their relative noise over 5 % and 5 times \
         the channel's cleanest) are weighted down: {}{warning}",
        per.len(),
        per.join(", ")
    ))
}
