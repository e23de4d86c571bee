//! Unknown complex gains of measured FRFs.
//!
//! FRFs referenced to a shaker amplifier's drive voltage (or to an
//! uncalibrated force gauge) are the structure's FRFs times an unknown
//! complex constant per reference: the amplifier's and shaker's force per
//! volt, with their phase. An accelerometer whose sensitivity is off adds
//! one per channel. Compared as they are, such data make a model look tens
//! of decibels off everywhere, and a diagnosis "explains" the offset with
//! kilograms of missing mass. Every command therefore multiplies the
//! model's FRFs by fitted gains before it compares them, when the case asks
//! for it or the data are per volt ([`decide`]).
//!
//! With the complex-log misfit the gain is linear in its logarithm, so the
//! best gain of a group of values (a reference's channels, or one channel)
//! has a closed form ([`log_gain`]): with `H` the model's and `M` the
//! measured values, and `w` the residual weights (the misfit is
//! `sum w^2 |ln(g H / M)|^2`),
//!
//! ```text
//! ln g = sum_k w_k^2 ln(M_k / H_k) / sum_k w_k^2
//! ```
//!
//! the weighted mean of the log ratios; the imaginary part (the phase) is a
//! mean on the circle, since the phases of `M / H` are known only modulo a
//! turn. A candidate fit, an update step or a comparison can thus fit the
//! gains exactly at every evaluation, at the cost of one pass over the data.

use fe_model::DofRef;
use fe_model::case::{FittedGain, GainKey, Gains, MeasurementSpec, UpdateSpec};
use frf::{Channel, FrfSet};
use num_complex::Complex64 as C64;

use crate::error::UpdateError;

/// The `ln g` (a complex logarithm: log-magnitude plus `j` phase) that
/// minimises `sum w^2 |ln(g H / M)|^2` over the triples `(H, M, w)` of
/// model value, measured value and residual weight; `None` when no triple
/// counts (a zero or non-finite value, or a weight that is not positive,
/// leaves its triple out).
///
/// The log-magnitude is the weighted mean of `ln |M / H|`. The phase
/// residuals are wrapped to half a turn, so their least-squares centre is a
/// mean on the circle: it starts at the direction of the weighted sum of
/// unit phasors and is refined by the weighted mean of the wrapped
/// residuals, which is the least-squares phase whenever the residuals lie
/// within half a turn of it.
pub fn log_gain(values: impl IntoIterator<Item = (C64, C64, f64)>) -> Option<C64> {
    let usable = |v: C64| v.re.is_finite() && v.im.is_finite() && v.norm() > 0.0;
    let mut logs: Vec<(C64, f64)> = Vec::new();
    for (h, m, w) in values {
        if usable(h) && usable(m) && w > 0.0 && w.is_finite() {
            logs.push(((m / h).ln(), w));
        }
    }
    // the weights relative to the largest, squared: the gain does not
    // depend on their scale, and squares of weights near the ends of the
    // f64 range would underflow to a total of zero or overflow to infinity
    let largest = logs.iter().map(|&(_, w)| w).fold(0.0, f64::max);
    for (_, w) in &mut logs {
        *w = (*w / largest).powi(2);
    }
    if logs.is_empty() {
        return None;
    }
    // at least 1: the largest weight's own square
    let total: f64 = logs.iter().map(|(_, w2)| w2).sum();
    let magnitude = logs.iter().map(|(z, w2)| w2 * z.re).sum::<f64>() / total;
    let phasor: C64 = logs.iter().map(|(z, w2)| C64::from_polar(*w2, z.im)).sum();
    let mut phase = if phasor.norm() > 0.0 { phasor.arg() } else { 0.0 };
    let wrap = |x: f64| (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    // a few steps of the mean of wrapped residuals settle it to round-off
    for _ in 0..4 {
        phase += logs.iter().map(|(z, w2)| w2 * wrap(z.im - phase)).sum::<f64>() / total;
    }
    Some(C64::new(magnitude, wrap(phase)))
}

/// Which gain each channel takes: its group index, and the key of each group
/// (its reference, or the channel), in order of first appearance.
pub fn gain_groups(channels: &[Channel], gains: Gains) -> (Vec<usize>, Vec<GainKey>) {
    let mut keys: Vec<GainKey> = Vec::new();
    let mut index: std::collections::HashMap<GainKey, usize> = std::collections::HashMap::new();
    let mut of = Vec::with_capacity(channels.len());
    for c in channels {
        let key = match gains {
            Gains::PerChannel => GainKey::Channel(c.response, c.reference),
            Gains::PerReference | Gains::None => GainKey::Reference(c.reference),
        };
        let i = *index.entry(key).or_insert_with(|| {
            keys.push(key);
            keys.len() - 1
        });
        of.push(i);
    }
    (of, keys)
}

/// Gains fitted to a pair of FRF sets.
#[derive(Clone, Debug, PartialEq)]
pub struct FittedGains {
    /// Per reference or per channel.
    pub setting: Gains,
    /// What each gain belongs to.
    pub keys: Vec<GainKey>,
    /// The gains.
    pub values: Vec<C64>,
    /// The gain of each channel of the sets they were fitted to.
    group_of: Vec<usize>,
}

/// A fitted gain for reports and `results.json`.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct GainReport {
    /// `1:uy` or `H(31:uy,1:uy)`.
    pub key: String,
    /// Magnitude (measured over model: the data's units per newton).
    pub magnitude: f64,
    /// Magnitude in dB.
    pub magnitude_db: f64,
    /// Phase (degrees).
    pub phase_deg: f64,
}

impl FittedGains {
    /// No gains (every channel's is 1).
    pub fn none(channels: &[Channel]) -> FittedGains {
        FittedGains { setting: Gains::None, keys: Vec::new(), values: Vec::new(), group_of: vec![0; channels.len()] }
    }

    /// The gain of channel `c` of the sets they were fitted to.
    pub fn of_channel(&self, c: usize) -> C64 {
        self.values.get(self.group_of[c]).copied().unwrap_or(C64::new(1.0, 0.0))
    }

    /// Multiplies each channel of `set` (the model's FRFs, with the
    /// channels of the fit in the same order) by its gain.
    pub fn apply(&self, set: &mut FrfSet) {
        if self.values.is_empty() {
            return;
        }
        for c in 0..set.channels().len() {
            let g = self.of_channel(c);
            for v in set.channel_mut(c) {
                *v *= g;
            }
        }
    }

    /// The gains as a case file keeps them (`fitted_gains`).
    pub fn as_fitted(&self) -> Vec<FittedGain> {
        self.keys
            .iter()
            .zip(&self.values)
            .map(|(&key, g)| FittedGain { key, magnitude: g.norm(), phase_deg: g.arg().to_degrees() })
            .collect()
    }

    /// The gains for reports.
    pub fn reports(&self) -> Vec<GainReport> {
        self.keys
            .iter()
            .zip(&self.values)
            .map(|(key, g)| GainReport {
                key: key.to_string(),
                magnitude: g.norm(),
                magnitude_db: 20.0 * g.norm().log10(),
                phase_deg: g.arg().to_degrees(),
            })
            .collect()
    }
}

/// Fits the gains of `setting` that bring `model` closest to `measured` in
/// the complex-log misfit ([`log_gain`] per group). The sets hold the same
/// channels on the same lines, in any kind (a common factor `(j w)^p`
/// cancels in `M / H` only when both are of one kind, so the model must be
/// converted to the data's kind first); `weights` are the residual weights,
/// channel-major, as [`crate::Study::line_weights`] gives them. A group with
/// no usable value keeps the gain 1.
pub fn fit_gains(
    model: &FrfSet,
    measured: &FrfSet,
    weights: Option<&[f64]>,
    setting: Gains,
) -> Result<FittedGains, UpdateError> {
    if setting == Gains::None {
        return Ok(FittedGains::none(measured.channels()));
    }
    if model.kind() != measured.kind() || model.channels() != measured.channels() || model.n_freq() != measured.n_freq()
    {
        return Err(UpdateError::Data(format!(
            "gains are fitted between sets of one kind, channels and lines; got a {} model of {} channels x {} lines \
             against a {} measurement of {} x {}",
            model.kind(),
            model.channels().len(),
            model.n_freq(),
            measured.kind(),
            measured.channels().len(),
            measured.n_freq()
        )));
    }
    let nf = measured.n_freq();
    let (group_of, keys) = gain_groups(measured.channels(), setting);
    let values = (0..keys.len())
        .map(|g| {
            let triples = (0..measured.channels().len()).filter(|&c| group_of[c] == g).flat_map(|c| {
                (0..nf).map(move |k| (model.get(c, k), measured.get(c, k), weights.map_or(1.0, |w| w[c * nf + k])))
            });
            log_gain(triples).map_or(C64::new(1.0, 0.0), C64::exp)
        })
        .collect();
    Ok(FittedGains { setting, keys, values, group_of })
}

/// Which gains a measurement needs, and why, in words for the notes:
///
/// - the case's `[measurement] gains`, when it gives one (`none` is refused
///   while a reference is per volt and uncalibrated: a per-volt FRF compared
///   as it is would be read as the structure's);
/// - `per-reference` when `[update] gains = true` (the older spelling);
/// - `per-reference` when a reference is per volt;
/// - `none` otherwise.
pub fn decide(
    measurement: Option<&MeasurementSpec>,
    update: Option<&UpdateSpec>,
    per_volt: &[DofRef],
) -> Result<(Gains, String), UpdateError> {
    let volts = || per_volt.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ");
    let asked = measurement.and_then(|m| m.gains);
    let place = measurement.and_then(|m| m.gains_place.clone());
    let located = |msg: String| match &place {
        Some(p) => UpdateError::Case(p.with_message(msg)),
        None => UpdateError::Method(msg),
    };
    let legacy = update.is_some_and(|u| u.gains);
    match asked {
        Some(Gains::None) if legacy => {
            Err(located("`gains = \"none\"` contradicts `[update] gains = true`; keep one of them".to_string()))
        }
        Some(Gains::None) if !per_volt.is_empty() => Err(located(format!(
            "`gains = \"none\"`, but the data of reference(s) {} are per volt: their level is the structure's times \
             an unknown gain; fit it (`gains = \"per-reference\"`, the default for such data) or give the force \
             gauge's sensitivity (`calibration = {{ \"{}\" = \"10.2 mV/N\" }}`)",
            volts(),
            per_volt[0]
        ))),
        Some(g) => Ok((g, format!("the case asks for gains = \"{g}\""))),
        None if legacy => Ok((Gains::PerReference, "the case's [update] gains = true".into())),
        None if !per_volt.is_empty() => Ok((
            Gains::PerReference,
            format!("the data of reference(s) {} are per volt (a voltage, not a force, is the reference)", volts()),
        )),
        None => Ok((Gains::None, "the data are per newton".into())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::Dof;

    /// The independent truth: the misfit evaluated on a grid fine enough to
    /// place its minimum to 1e-6, by brute force.
    fn brute_force(triples: &[(C64, C64, f64)]) -> C64 {
        let cost = |a: f64, b: f64| {
            triples.iter().map(|&(h, m, w)| (w * (C64::new(a, b).exp() * h / m).ln()).norm_sqr()).sum::<f64>()
        };
        let (mut a, mut b) = (0.0, 0.0);
        let mut best = f64::INFINITY;
        for i in -400..=400 {
            for j in -400..=400 {
                let (x, y) = (f64::from(i) * 0.01, f64::from(j) * std::f64::consts::PI / 400.0);
                let c = cost(x, y);
                if c < best {
                    (best, a, b) = (c, x, y);
                }
            }
        }
        // refine by shrinking the grid around the best point
        let (mut da, mut db) = (0.01, std::f64::consts::PI / 400.0);
        for _ in 0..30 {
            let mut moved = (a, b);
            for (x, y) in [(a + da, b), (a - da, b), (a, b + db), (a, b - db)] {
                let c = cost(x, y);
                if c < best {
                    best = c;
                    moved = (x, y);
                }
            }
            if moved == (a, b) {
                da /= 2.0;
                db /= 2.0;
            }
            (a, b) = moved;
        }
        C64::new(a, b)
    }

    fn noisy(n: usize, gain: C64, seed: u64) -> Vec<(C64, C64, f64)> {
        // a deterministic, irregular sequence stands in for noise
        let r = |k: usize, s: u64| ((k as f64 * 12.9898 + s as f64 * 78.233).sin() * 43_758.545).fract() - 0.5;
        (0..n)
            .map(|k| {
                let h = C64::from_polar(1e-4 / (1.0 + k as f64), -(k as f64) * 0.37);
                let e = C64::new(0.1 * r(k, seed), 0.1 * r(k, seed + 1));
                (h, gain * h * e.exp(), 0.5 + r(k, seed + 2).abs())
            })
            .collect()
    }

    #[test]
    fn an_exact_gain_is_recovered_to_round_off_whatever_its_phase() {
        for (mag, phase_deg) in [(100.0, 0.0), (0.012, -179.5), (3.0, 179.9), (1e3, 90.0)] {
            let g = C64::from_polar(mag, f64::to_radians(phase_deg));
            let triples: Vec<(C64, C64, f64)> =
                (0..50).map(|k| C64::from_polar(1.0 + k as f64, 0.3 * k as f64)).map(|h| (h, g * h, 1.0)).collect();
            let got = log_gain(triples).unwrap().exp();
            assert!((got - g).norm() <= 1e-12 * g.norm(), "{got} vs {g}");
        }
    }

    #[test]
    fn with_noise_and_weights_the_closed_form_is_the_least_squares_minimum() {
        for (gain, seed) in [(C64::from_polar(40.0, 2.0), 1), (C64::from_polar(0.5, -3.1), 7)] {
            let t = noisy(60, gain, seed);
            let closed = log_gain(t.iter().copied()).unwrap();
            let brute = brute_force(&t);
            assert!((closed - brute).norm() < 1e-6, "{closed} vs {brute}");
            // and it is the weighted mean of the log ratios, by its definition
            let w2: f64 = t.iter().map(|x| x.2 * x.2).sum();
            let mean = t.iter().map(|&(h, m, w)| w * w * (m / h).ln().re).sum::<f64>() / w2;
            assert!((closed.re - mean).abs() < 1e-12);
        }
        assert_eq!(log_gain([(C64::new(0.0, 0.0), C64::new(1.0, 0.0), 1.0)]), None);
        assert_eq!(log_gain([(C64::new(1.0, 0.0), C64::new(1.0, 0.0), 0.0)]), None);
    }

    /// The gain does not change when every weight is scaled, down to
    /// weights whose squares underflow and up to ones whose squares
    /// overflow; triples that cannot count are left out, not averaged in.
    #[test]
    fn the_gain_is_the_same_whatever_the_scale_of_the_weights() {
        let t = noisy(40, C64::from_polar(3.0, 0.7), 3);
        let one = log_gain(t.iter().copied()).unwrap();
        for scale in [1e-170, 1e-3, 1e3, 1e170] {
            let scaled = log_gain(t.iter().map(|&(h, m, w)| (h, m, w * scale))).unwrap();
            assert!((scaled - one).norm() < 1e-13, "weights x {scale:e}: {scaled} vs {one}");
        }
        let zero = C64::new(0.0, 0.0);
        let spoilt = [(zero, C64::new(1.0, 0.0), 1.0), (C64::new(1.0, 0.0), C64::new(f64::NAN, 0.0), 1.0)];
        let with = log_gain(t.iter().copied().chain(spoilt).chain([(t[0].0, t[0].1, 0.0)])).unwrap();
        assert_eq!(with, one);
    }

    /// Residual phases on both sides of half a turn: their mean on the
    /// circle is half a turn, where their plain mean (from a start at zero
    /// phase) would be zero.
    #[test]
    fn phases_either_side_of_half_a_turn_give_half_a_turn() {
        let pi = std::f64::consts::PI;
        let t: Vec<(C64, C64, f64)> = (0..20)
            .map(|k| {
                let h = C64::from_polar(1.0 + k as f64, 0.2 * k as f64);
                let side = if k % 2 == 0 { pi - 0.05 } else { -pi + 0.05 };
                (h, h * C64::from_polar(2.0, side), 1.0)
            })
            .collect();
        let g = log_gain(t.iter().copied()).unwrap();
        assert!((g.im.abs() - pi).abs() < 1e-12, "phase {} rad", g.im);
        assert!((g.re - 2f64.ln()).abs() < 1e-12);
        let brute = brute_force(&t);
        assert!((C64::new(0.0, g.im).exp() - C64::new(0.0, brute.im).exp()).norm() < 1e-6, "{g} vs {brute}");
    }

    #[test]
    fn gains_are_fitted_per_reference_or_per_channel_and_applied() {
        let d = |n: u32| DofRef::new(n, Dof::Uy);
        let channels = vec![Channel::new(d(2), d(1)), Channel::new(d(3), d(1)), Channel::new(d(3), d(4))];
        let lines = vec![10.0, 20.0, 30.0];
        let mut model = FrfSet::zeros(lines.clone(), channels.clone(), frf::FrfKind::Accelerance).unwrap();
        for c in 0..3 {
            for k in 0..3 {
                model.set(c, k, C64::new(1.0 + c as f64, k as f64 - 1.5));
            }
        }
        let true_gain = [C64::new(10.0, 1.0), C64::new(10.0, 1.0), C64::new(-0.2, 0.3)];
        let mut measured = model.clone();
        for (c, g) in true_gain.iter().enumerate() {
            for v in measured.channel_mut(c) {
                *v *= g;
            }
        }
        let f = fit_gains(&model, &measured, None, Gains::PerReference).unwrap();
        assert_eq!(f.keys, vec![GainKey::Reference(d(1)), GainKey::Reference(d(4))]);
        let mut fitted = model.clone();
        f.apply(&mut fitted);
        for (a, b) in fitted.values().iter().zip(measured.values()) {
            assert!((a - b).norm() < 1e-12 * b.norm(), "{a} vs {b}");
        }
        let per = fit_gains(&model, &measured, None, Gains::PerChannel).unwrap();
        assert_eq!(per.keys.len(), 3);
        assert_eq!(per.as_fitted()[2].key, GainKey::Channel(d(3), d(4)));
        let none = fit_gains(&model, &measured, None, Gains::None).unwrap();
        assert_eq!(none.of_channel(1), C64::new(1.0, 0.0));
        // sets that differ in any one of kind, channels and lines are refused
        let refused = |other: &FrfSet| {
            let e = fit_gains(other, &measured, None, Gains::PerReference).unwrap_err();
            assert!(
                matches!(&e, UpdateError::Data(m) if m.contains("gains are fitted between sets of one kind")),
                "{e}"
            );
        };
        refused(&model.converted(frf::FrfKind::Receptance));
        refused(&model.select_channels(&[0, 1]));
        refused(&model.select_lines(&[0, 2]).unwrap());
    }

    /// The weights are read per channel and line: values of weight zero
    /// take no part, so a gain fitted where a second gain hides in the
    /// zero-weighted values is the first one exactly.
    #[test]
    fn weights_are_read_at_their_channel_and_line() {
        let d = |n: u32| DofRef::new(n, Dof::Uy);
        let channels = vec![Channel::new(d(2), d(1)), Channel::new(d(3), d(1))];
        let lines = vec![10.0, 20.0, 30.0, 40.0];
        let mut model = FrfSet::zeros(lines, channels, frf::FrfKind::Receptance).unwrap();
        for c in 0..2 {
            for k in 0..4 {
                model.set(c, k, C64::new(1.0 + c as f64, 0.5 * k as f64 - 1.0));
            }
        }
        let (g, other) = (C64::new(3.0, -1.0), C64::new(0.2, 0.7));
        // channel-major weights: channel 0's last two lines and channel 1's first line carry `other`
        let weights = [1.0, 2.0, 0.0, 0.0, 0.0, 0.5, 1.0, 3.0];
        let mut measured = model.clone();
        for c in 0..2 {
            for k in 0..4 {
                let gain = if weights[c * 4 + k] > 0.0 { g } else { other };
                measured.set(c, k, model.get(c, k) * gain);
            }
        }
        let f = fit_gains(&model, &measured, Some(&weights), Gains::PerReference).unwrap();
        assert!((f.values[0] / g - 1.0).norm() < 1e-12, "{} against {g}", f.values[0]);
        // equally weighted, the hidden gain pulls the fit away
        let equal = fit_gains(&model, &measured, None, Gains::PerReference).unwrap();
        assert!((equal.values[0] / g - 1.0).norm() > 0.1);
    }

    #[test]
    fn per_volt_data_fit_gains_unless_the_case_says_otherwise_and_none_is_refused_for_them() {
        let r = [DofRef::new(1, Dof::Uy)];
        assert_eq!(decide(None, None, &r).unwrap().0, Gains::PerReference);
        assert!(decide(None, None, &r).unwrap().1.contains("1:uy are per volt"));
        assert_eq!(decide(None, None, &[]).unwrap().0, Gains::None);
    }
}
