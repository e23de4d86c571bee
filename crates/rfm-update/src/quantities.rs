//! The quantities every output of rfm reports, each defined once.
//!
//! A number that the terminal, `--json`, a report and the documentation all
//! show must mean the same thing in each and go by the same name: an
//! engineer who finds one quantity under two names, or two quantities under
//! one, stops trusting every number. This module holds, for each reported
//! quantity, its name, its JSON key, its unit and what it means
//! ([`Quantity`], listed in [`GLOSSARY`], the glossary every report ends
//! with), and the one function that computes it:
//!
//! | quantity | computed by |
//! |---|---|
//! | misfit | [`misfit`] (the diagnosis's [`crate::diagnose::log_misfit_with`] on [`MISFIT_LINES`] lines) |
//! | noise | [`noise`] (the diagnosis's [`crate::diagnose::estimate_noise_against_weighted`]) |
//! | x noise | [`times_noise`] |
//! | dB error | [`db_error`] (`frf`'s) |
//! | phase error | [`phase_error_deg`] (`frf`'s) |
//! | FRAC | [`frac`] (`frf`'s) |
//! | MAC | [`mac`] (`frf`'s) |
//! | dBIC | the diagnosis ([`crate::diagnose::Ranked::delta_bic`]); significant below [`SIGNIFICANT_DBIC`] |
//!
//! The misfit is always the same quantity: the RMS of `|ln(model /
//! measured)|` per complex value, the model times the gains that fit it
//! best when the data need gains, each value weighted as the fits weigh it
//! (by the measured coherence when the data carry it). What changes from
//! one use to another is only the set of lines it is taken over, and every
//! output says which: the misfit of a model ([`misfit`]) is over the
//! [`MISFIT_LINES`] lines the diagnosis reads (half of them at the
//! resonance peaks), the fit residual of an update over its fitted lines,
//! the misfit of a channel or band over its own lines.

use damping::DampedSystem;
use fe_model::case::Gains;
use frf::FrfSet;

pub use frf::correlation::{db_error, frac, phase_error_deg};
pub use frf::modal::mac;

use crate::diagnose;
use crate::error::UpdateError;

/// A reported quantity: its name wherever it is shown, its key in JSON,
/// its unit and its definition.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Quantity {
    /// The name in the terminal, the reports and the documentation.
    pub name: &'static str,
    /// The key in JSON documents.
    pub key: &'static str,
    /// Its unit (empty: a pure number).
    pub unit: &'static str,
    /// What it is, in a sentence or two (the glossary's text).
    pub definition: &'static str,
}

/// The misfit of a model against the measured FRFs ([`misfit`]).
pub const MISFIT: Quantity = Quantity {
    name: "misfit",
    key: "misfit",
    unit: "",
    definition: "the RMS of |ln(model / measured)| per complex value: magnitude (in nepers) and phase (in radians) \
                 errors together, the model times the gains that fit it best when the data need gains, each \
                 value weighted by its coherence when the data carry coherence. A model's misfit is taken over \
                 the 200 lines the diagnosis reads (half of them at the resonance peaks); a fit residual over \
                 the fit's lines; a channel's or band's over its own lines. A misfit of 0.1 is a magnitude error of \
                 0.87 dB alone, or a phase error of 5.7 deg alone.",
};

/// The noise level of the data ([`noise`]).
pub const NOISE: Quantity = Quantity {
    name: "noise",
    key: "noise",
    unit: "",
    definition: "the misfit that the data's own noise leaves: the RMS relative error per complex value, \
                 estimated from the roughness of the measured FRFs from line to line (or of their ratio to the \
                 model, where that is smoother), weighted as the misfit is. A model that is right but for the \
                 data's noise has a misfit of about the noise.",
};

/// A misfit as a multiple of the noise ([`times_noise`]).
pub const TIMES_NOISE: Quantity = Quantity {
    name: "x noise",
    key: "times_noise",
    unit: "",
    definition: "the misfit divided by the noise. Up to 1.5 the model explains the data down to their noise; \
                 above it, something the model lacks remains.",
};

/// The magnitude error of one value ([`db_error`]).
pub const DB_ERROR: Quantity = Quantity {
    name: "dB error",
    key: "db_error",
    unit: "dB",
    definition: "20 log10(|model| / |measured|) per value, positive when the model is too high; over a channel, \
                 a band or all values, its RMS (RMS dB error) and its mean (mean dB error: a uniform gain or \
                 calibration error shows here alone). A factor of 2 is 6.02 dB.",
};

/// The phase error of one value ([`phase_error_deg`]).
pub const PHASE_ERROR: Quantity = Quantity {
    name: "phase error",
    key: "phase_error_deg",
    unit: "deg",
    definition: "arg(model / measured) in degrees, wrapped to (-180, 180]; over a channel, a band or all values, \
                 its RMS.",
};

/// The frequency response assurance criterion of one channel ([`frac`]).
pub const FRAC: Quantity = Quantity {
    name: "FRAC",
    key: "frac",
    unit: "",
    definition: "|sum conj(X) A|^2 / (sum |X|^2 sum |A|^2) over a channel's lines (X measured, A model, both in \
                 the data's kind): 1 when the two FRFs have the same shape up to a constant factor, falling \
                 towards 0 as peaks move apart.",
};

/// The modal assurance criterion of two mode shapes ([`mac`]).
pub const MAC: Quantity = Quantity {
    name: "MAC",
    key: "mac",
    unit: "",
    definition: "|a^H b|^2 / ((a^H a)(b^H b)) of a measured and a model mode shape at the measured responses: 1 \
                 for the same shape, 0 for orthogonal ones.",
};

/// The diagnosis's information criterion ([`crate::diagnose::Ranked::delta_bic`]).
pub const DBIC: Quantity = Quantity {
    name: "dBIC",
    key: "delta_bic",
    unit: "",
    definition: "the change of the Bayesian information criterion when a candidate effect is added: the fall of \
                 the squared misfit in units of the noise variance, plus ln(n) per fitted parameter (n real \
                 residuals). Negative is better; below -10 the evidence is very strong (significant). It grows \
                 with the number of lines and with the misfit over the noise, so only its differences between \
                 candidates of one diagnosis mean anything.",
};

/// Every quantity, in the order a glossary lists them.
pub const GLOSSARY: [Quantity; 8] = [MISFIT, NOISE, TIMES_NOISE, DB_ERROR, PHASE_ERROR, FRAC, MAC, DBIC];

/// The lines a model's [`misfit`] is taken over: the diagnosis's default
/// line count, so that `rfm compare`, `rfm diagnose`, `rfm fix` and `rfm
/// update` give one model one misfit.
pub const MISFIT_LINES: usize = 200;

/// A dBIC below this is significant (the diagnosis's default threshold,
/// [`crate::diagnose::DiagnoseOptions::significance`]).
pub const SIGNIFICANT_DBIC: f64 = -10.0;

/// Up to this many times the noise, a misfit is consistent with it
/// ([`crate::fix::CONSISTENT`]).
pub const CONSISTENT: f64 = crate::fix::CONSISTENT;

/// The [`MISFIT`] of `system` against the measured receptances, over the
/// [`MISFIT_LINES`] informative lines, after the gains of `gains` that fit
/// it best, weighted by `weights` (channel-major at the lines of
/// `measured`, as [`crate::Study::line_weights`]).
pub fn misfit(
    system: &DampedSystem,
    measured: &FrfSet,
    gains: Gains,
    weights: Option<&[f64]>,
) -> Result<f64, UpdateError> {
    diagnose::log_misfit_with(system, measured, MISFIT_LINES, gains, weights)
}

/// The [`NOISE`] of measured receptances, read against `system` as the
/// diagnosis reads it, weighted as [`misfit`] is; `None` with too few
/// usable values.
pub fn noise(system: &DampedSystem, measured: &FrfSet, weights: Option<&[f64]>) -> Result<Option<f64>, UpdateError> {
    diagnose::estimate_noise_against_weighted(system, measured, weights)
}

/// A misfit as a multiple of the noise ([`TIMES_NOISE`]); NaN without a
/// positive noise level.
pub fn times_noise(misfit: f64, noise: f64) -> f64 {
    if noise > 0.0 { misfit / noise } else { f64::NAN }
}

/// The RMS [`DB_ERROR`] that noise of level `noise` alone leaves: complex
/// noise of RMS `s` per value puts `s / sqrt(2)` into the logarithm of the
/// magnitude (in nepers) and as much into the phase (in radians).
pub fn noise_floor_db(noise: f64) -> f64 {
    20.0 / std::f64::consts::LN_10 * noise / std::f64::consts::SQRT_2
}

/// The RMS [`PHASE_ERROR`] (degrees) that noise of level `noise` alone
/// leaves (see [`noise_floor_db`]).
pub fn noise_floor_deg(noise: f64) -> f64 {
    (noise / std::f64::consts::SQRT_2).to_degrees()
}

/// A model's misfit with the noise it is read against, as every JSON
/// document that reports a model's misfit holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MisfitReport {
    /// The [`MISFIT`] over [`MisfitReport::lines`] lines.
    pub misfit: f64,
    /// The [`NOISE`] of the data (`None`: too few values to estimate it).
    pub noise: Option<f64>,
    /// The misfit in units of the noise ([`TIMES_NOISE`]).
    pub times_noise: Option<f64>,
    /// The lines the misfit is taken over.
    pub lines: usize,
    /// Each value weighted (by the coherence, or band weights).
    pub weighted: bool,
}

impl MisfitReport {
    /// The misfit of `system` against measured receptances and the noise
    /// level read against it ([`misfit`], [`noise`]).
    pub fn of(
        system: &DampedSystem,
        measured: &FrfSet,
        gains: Gains,
        weights: Option<&[f64]>,
    ) -> Result<MisfitReport, UpdateError> {
        let misfit = misfit(system, measured, gains, weights)?;
        let noise = noise(system, measured, weights)?;
        Ok(MisfitReport {
            misfit,
            noise,
            times_noise: noise.map(|n| times_noise(misfit, n)),
            lines: MISFIT_LINES.min(measured.n_freq()),
            weighted: weights.is_some(),
        })
    }

    /// Within [`CONSISTENT`] times the noise: the model explains the data
    /// down to their noise.
    pub fn consistent(&self) -> bool {
        self.times_noise.is_some_and(|t| t <= CONSISTENT)
    }
}

#[cfg(test)]
mod tests {
    use fe_model::{Dof, DofRef, samples};
    use frf::{C64, Channel, NoiseModel, synthesize};

    use super::*;

    /// The misfit is the diagnosis's on its default lines, and its
    /// significance threshold the diagnosis's default: one model, one
    /// number, whichever command prints it.
    #[test]
    fn the_misfit_and_threshold_are_the_diagnosis_defaults() {
        let d = diagnose::DiagnoseOptions::default();
        assert_eq!(MISFIT_LINES, d.lines);
        assert_eq!(SIGNIFICANT_DBIC, d.significance);
        let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
        let tip = DofRef::new(31, Dof::Uy);
        let channels: Vec<Channel> = [16, 31].iter().map(|&n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
        let lines: Vec<f64> = (1..=400).map(f64::from).collect();
        let measured = synthesize(&truth, &channels, &lines).unwrap();
        let mut model = truth.clone();
        let e = model.model().quantity("group.steel.alpha").unwrap();
        model.set(e, 2e-5).unwrap();
        let direct = diagnose::log_misfit(&model, &measured, 200).unwrap();
        assert_eq!(misfit(&model, &measured, Gains::None, None).unwrap(), direct);
        assert!(direct > 0.01, "{direct}");
    }

    /// With 1 % noise on the truth's FRFs the truth's misfit is about the
    /// noise, the noise level read is about 1 %, and the report puts the
    /// two together; a model with a wrong stiffness sits many times above.
    #[test]
    fn the_truth_sits_at_the_noise_and_a_wrong_model_far_above_it() {
        let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
        let tip = DofRef::new(31, Dof::Uy);
        let channels: Vec<Channel> =
            [8, 16, 24, 31].iter().map(|&n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
        let lines: Vec<f64> = (1..=800).map(|k| 0.5 * f64::from(k)).collect();
        let mut measured = synthesize(&truth, &channels, &lines).unwrap();
        NoiseModel { relative: 0.01, floor: 0.0, seed: 7 }.apply(&mut measured);
        let at_truth = MisfitReport::of(&truth, &measured, Gains::None, None).unwrap();
        let noise = at_truth.noise.unwrap();
        assert!((noise / 0.01 - 1.0).abs() < 0.2, "noise {noise}");
        assert!((at_truth.misfit / 0.01 - 1.0).abs() < 0.2, "misfit {}", at_truth.misfit);
        assert!(at_truth.consistent(), "{at_truth:?}");
        assert_eq!(at_truth.lines, 200);
        let mut wrong = truth.clone();
        let e = wrong.model().quantity("material.steel.E").unwrap();
        wrong.set(e, 1.8e11).unwrap();
        let off = MisfitReport::of(&wrong, &measured, Gains::None, None).unwrap();
        assert!(off.times_noise.unwrap() > 10.0, "{off:?}");
        assert!(!off.consistent());
    }

    /// The noise floors are what complex noise of that level puts into
    /// the magnitude and the phase: a sample of a million values.
    #[test]
    fn noise_floors_match_a_sample_of_complex_noise() {
        let mut set = frf::FrfSet::zeros(
            (1..=1000).map(f64::from).collect(),
            (1..=1000).map(|n| Channel::new(DofRef::new(n, Dof::Uy), DofRef::new(1, Dof::Uy))).collect(),
            frf::FrfKind::Receptance,
        )
        .unwrap();
        for c in 0..set.channels().len() {
            set.channel_mut(c).iter_mut().for_each(|v| *v = C64::new(1.0, 0.0));
        }
        NoiseModel { relative: 0.02, floor: 0.0, seed: 3 }.apply(&mut set);
        let (mut db2, mut ph2, mut n) = (0.0, 0.0, 0.0);
        for c in 0..set.channels().len() {
            for &v in set.channel(c) {
                db2 += db_error(v, C64::new(1.0, 0.0)).powi(2);
                ph2 += phase_error_deg(v, C64::new(1.0, 0.0)).powi(2);
                n += 1.0;
            }
        }
        let (db, ph) = ((db2 / n).sqrt(), (ph2 / n).sqrt());
        assert!((db / noise_floor_db(0.02) - 1.0).abs() < 0.01, "{db} dB against {}", noise_floor_db(0.02));
        assert!((ph / noise_floor_deg(0.02) - 1.0).abs() < 0.01, "{ph} deg against {}", noise_floor_deg(0.02));
        assert!(times_noise(0.03, 0.0).is_nan());
        assert_eq!(times_noise(0.03, 0.02), 1.5);
    }

    /// Every quantity has a name, a key and a definition, none twice.
    #[test]
    fn the_glossary_names_each_quantity_once() {
        let mut names: Vec<&str> = GLOSSARY.iter().map(|q| q.name).collect();
        let mut keys: Vec<&str> = GLOSSARY.iter().map(|q| q.key).collect();
        names.sort_unstable();
        names.dedup();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!((names.len(), keys.len()), (GLOSSARY.len(), GLOSSARY.len()));
        assert!(GLOSSARY.iter().all(|q| q.definition.len() > 40));
    }
}

/// A dBIC as every output prints it (terminal, JSON messages, reports):
/// one decimal below 1,000 in size, where the threshold of -10 is near,
/// else a whole number with its thousands grouped (`-56,161,045`: a raw
/// `-56161044.7` cannot be compared at a glance); `-` when not a number.
pub fn dbic_text(v: f64) -> String {
    if !v.is_finite() {
        "-".into()
    } else if v.abs() < 1000.0 {
        let s = format!("{v:.1}");
        if s == "-0.0" { "0.0".into() } else { s }
    } else {
        grouped(v.round())
    }
}

/// A whole number with its thousands grouped by commas: `-56,161,045`.
pub fn grouped(v: f64) -> String {
    let digits = format!("{:.0}", v.abs());
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    if v < 0.0 && digits != "0" { format!("-{out}") } else { out }
}

#[cfg(test)]
mod dbic_text_tests {
    #[test]
    fn large_values_are_grouped_and_small_ones_keep_a_decimal() {
        assert_eq!(super::dbic_text(-56_161_044.7), "-56,161,045");
        assert_eq!(super::dbic_text(2247.5), "2,248");
        assert_eq!(super::dbic_text(-9.96), "-10.0");
        assert_eq!(super::dbic_text(-0.01), "0.0");
        assert_eq!(super::dbic_text(999.94), "999.9");
        assert_eq!(super::dbic_text(f64::NAN), "-");
        assert_eq!(super::grouped(0.0), "0");
        assert_eq!(super::grouped(-100.0), "-100");
    }
}
