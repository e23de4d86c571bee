//! A model against measured FRFs, as `rfm compare` and the reports show it:
//! the model's FRFs on the measured channels and lines, in the data's kind
//! and times the gains the data carry ([`model_frfs`]), their errors per
//! channel and band ([`compare`]), and the modes paired by MAC with the
//! gains taken out of the data first ([`compare_modes`]).
//!
//! Data per volt (or from an uncalibrated sensor) differ from the model's
//! FRFs per newton by an unknown complex factor per reference or per
//! channel: compared without it, a 40 dB offset reads as a wrong model.
//! The gains are either fitted in closed form to the model at hand
//! ([`GainSource::Fit`], what `rfm compare` does) or those an output-error
//! update estimated with its parameters ([`GainSource::Estimated`]).

use damping::DampedSystem;
use fe_model::case::Gains;
use frf::correlation::{BandSpec, Correlation, correlate};
use frf::{C64, ComparisonError, FrfSet, ModalComparison, synthesize_regular};

use crate::error::UpdateError;
use crate::gain::{FittedGains, fit_gains};
use crate::output_error::Gain;

/// Where the gains of a comparison come from.
#[derive(Clone, Copy, Debug)]
pub enum GainSource<'a> {
    /// No gains: the model's FRFs as they are.
    None,
    /// The gains of `setting` that bring the model closest to the data
    /// ([`fit_gains`]), the lines weighted by `weights` (channel-major, as
    /// [`crate::Study::line_weights`] gives them).
    Fit {
        /// Per reference, per channel or none.
        setting: Gains,
        /// Residual weights, `None` for equal weights.
        weights: Option<&'a [f64]>,
    },
    /// Gains an output-error update estimated.
    Estimated(&'a [Gain]),
}

/// A model's FRFs as they are compared with measured ones.
#[derive(Clone, Debug)]
pub struct ModelFrfs {
    /// The FRFs on the measured channels and lines, in the measured kind,
    /// each channel times its gain; NaN at the lines of `singular_hz`.
    pub frfs: FrfSet,
    /// The gain each channel was multiplied by (1 without gains).
    pub gains: Vec<C64>,
    /// The gains fitted in closed form, with [`GainSource::Fit`].
    pub fitted: Option<FittedGains>,
    /// Lines (Hz) where the model's dynamic stiffness is singular to
    /// working precision (an updating run that wandered off, an undamped
    /// model on a resonance): left out of correlations and figures.
    pub singular_hz: Vec<f64>,
}

/// A model's FRFs with their errors against the measured ones.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// The model's FRFs as compared.
    pub model: ModelFrfs,
    /// Errors per channel and band ([`correlate`]).
    pub correlation: Correlation,
}

/// The FRFs of `system` on the channels and lines of `measured`, in its
/// kind, times the gains `gains` gives (see [`ModelFrfs`]).
pub fn model_frfs(system: &DampedSystem, measured: &FrfSet, gains: GainSource<'_>) -> Result<ModelFrfs, UpdateError> {
    let (frfs, singular_hz) = synthesize_regular(system, measured.channels(), measured.frequencies_hz())?;
    let mut frfs = frfs.converted(measured.kind());
    let (per_channel, fitted) = match gains {
        GainSource::None => (vec![C64::new(1.0, 0.0); measured.channels().len()], None),
        GainSource::Fit { setting, weights } => {
            let fitted = fit_gains(&frfs, measured, weights, setting)?;
            ((0..measured.channels().len()).map(|c| fitted.of_channel(c)).collect(), Some(fitted))
        }
        GainSource::Estimated(gains) => (measured.channels().iter().map(|c| Gain::factor_of(gains, c)).collect(), None),
    };
    for (c, &g) in per_channel.iter().enumerate() {
        if g != C64::new(1.0, 0.0) {
            frfs.channel_mut(c).iter_mut().for_each(|v| *v *= g);
        }
    }
    Ok(ModelFrfs { frfs, gains: per_channel, fitted, singular_hz })
}

/// The model's FRFs ([`model_frfs`]) and their errors against `measured`
/// per channel and per band of `bands`.
pub fn compare(
    system: &DampedSystem,
    measured: &FrfSet,
    gains: GainSource<'_>,
    bands: &BandSpec,
) -> Result<Comparison, UpdateError> {
    let model = model_frfs(system, measured, gains)?;
    let correlation = correlate(measured, &model.frfs, bands)?;
    Ok(Comparison { model, correlation })
}

/// The measured modes paired with `system`'s by MAC of at least `min_mac`
/// ([`frf::compare_modes`]), the data divided by each channel's gain
/// first (`gains`, as [`ModelFrfs::gains`]), so that the modal estimator
/// sees FRFs per newton and the measured shapes come on the model's
/// scale. An amplifier's phase in FRFs per volt is a constant complex
/// factor that no rational function with real coefficients fits: the
/// estimator would bend its poles to make up for it, and a weak mode's
/// damping drift from order to order until it is not seen.
pub fn compare_modes(
    system: &DampedSystem,
    measured: &FrfSet,
    gains: &[C64],
    min_mac: f64,
) -> Result<ModalComparison, ComparisonError> {
    frf::compare_modes(system, &per_newton(measured, gains), min_mac)
}

/// `measured` with each channel divided by its gain.
fn per_newton(measured: &FrfSet, gains: &[C64]) -> FrfSet {
    let mut out = measured.clone();
    for (c, &g) in gains.iter().enumerate().take(out.channels().len()) {
        if g != C64::new(1.0, 0.0) {
            out.channel_mut(c).iter_mut().for_each(|v| *v /= g);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::case::GainKey;
    use fe_model::{Dof, DofRef};
    use frf::{Channel, FrfKind, synthesize};

    fn beam() -> DampedSystem {
        DampedSystem::new(fe_model::samples::two_material_cantilever()).unwrap()
    }

    /// Accelerance of the beam at its tip and mid-span per tip force,
    /// times 40 at +30 deg (a volt-referenced amplifier).
    fn per_volt_data(sys: &DampedSystem) -> (FrfSet, C64) {
        let tip = DofRef::new(31, Dof::Uy);
        let channels = [Channel::new(tip, tip), Channel::new(DofRef::new(16, Dof::Uy), tip)];
        let lines: Vec<f64> = (2..=300).map(f64::from).collect();
        let mut data = synthesize(sys, &channels, &lines).unwrap().converted(FrfKind::Accelerance);
        let g = C64::from_polar(40.0, 30f64.to_radians());
        for c in 0..2 {
            data.channel_mut(c).iter_mut().for_each(|v| *v *= g);
        }
        (data, g)
    }

    #[test]
    fn fitted_gains_bring_the_true_model_onto_data_per_volt() {
        let sys = beam();
        let (data, g) = per_volt_data(&sys);
        let fit = GainSource::Fit { setting: Gains::PerReference, weights: None };
        let c = compare(&sys, &data, fit, &BandSpec::Auto).unwrap();
        assert_eq!(c.model.frfs.kind(), FrfKind::Accelerance);
        for &gc in &c.model.gains {
            assert!((gc / g - 1.0).norm() < 1e-10, "{gc} against {g}");
        }
        assert!(c.correlation.total.log_misfit < 1e-9, "{}", c.correlation.total.log_misfit);
        assert!(c.model.singular_hz.is_empty());
        // without the gain the same model is 32 dB and 30 deg off everywhere
        let plain = compare(&sys, &data, GainSource::None, &BandSpec::Auto).unwrap();
        let expected = g.ln().norm();
        assert!((plain.correlation.total.log_misfit / expected - 1.0).abs() < 1e-9);
    }

    #[test]
    fn estimated_gains_multiply_the_channels_of_their_reference_only() {
        let sys = beam();
        let (data, g) = per_volt_data(&sys);
        let gains = [
            Gain { key: GainKey::Reference(DofRef::new(31, Dof::Uy)), magnitude: 40.0, phase_deg: 30.0 },
            Gain { key: GainKey::Reference(DofRef::new(16, Dof::Uy)), magnitude: 3.0, phase_deg: 0.0 },
        ];
        let m = model_frfs(&sys, &data, GainSource::Estimated(&gains)).unwrap();
        assert!(m.fitted.is_none());
        for c in 0..2 {
            assert!((m.gains[c] / g - 1.0).norm() < 1e-12);
            for k in 0..data.n_freq() {
                assert!((m.frfs.get(c, k) / data.get(c, k) - 1.0).norm() < 1e-9, "channel {c} line {k}");
            }
        }
    }

    #[test]
    fn modes_are_estimated_from_the_data_divided_by_their_gains() {
        let sys = beam();
        let (data, g) = per_volt_data(&sys);
        let divided = per_newton(&data, &[g, g]);
        let per_newton = synthesize(&sys, data.channels(), data.frequencies_hz()).unwrap();
        for k in 0..data.n_freq() {
            let want = per_newton.converted(FrfKind::Accelerance).get(1, k);
            assert!((divided.get(1, k) / want - 1.0).norm() < 1e-9);
        }
        let modes = compare_modes(&sys, &data, &[g, g], 0.5).unwrap();
        assert!(!modes.pairing.pairs.is_empty());
        for p in &modes.pairing.pairs {
            let (fm, fa) = (modes.measured[p.measured].frequency_hz, modes.model[p.model].frequency_hz);
            assert!((fm / fa - 1.0).abs() < 1e-3, "{fm} Hz against {fa} Hz");
        }
    }
}
