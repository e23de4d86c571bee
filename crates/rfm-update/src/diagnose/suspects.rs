//! Where the data point to an attached resonator that shows no mode of its
//! own.
//!
//! A resonator is offered where a check of the data finds a mode the
//! model lacks ([`super::CandidateOptions::resonator_hz`]). A heavily
//! damped one attached where the structure moves little makes no such
//! mode: its coupled mode is so wide (12 to 16 % damping on the lab
//! study's L-frame, trials 22 and 23) that the modal estimate finds no
//! stable pole at any order. What it leaves is a residual that is broad,
//! spread over a band tens of percent wide, and that lies between the
//! modes of the model and of the data, where no frequency shift or peak
//! height of a mode the model has can be to blame. Those bands are read
//! here, from the nominal model's residual at every measured line, so that
//! the diagnosis can offer resonators tuned to them; the nonlinear fit
//! moves the tuning from there (measured on trials 22 and 23: started 12 %
//! below or 16 % above its tuning, the fit found the truth's resonator, its
//! misfit at 0.9 times the noise), and the ranking's rules judge it as any
//! other candidate.

use fe_model::case::Gains;
use frf::FrfSet;

use super::lines::peaks;
use crate::error::UpdateError;

/// A band's residual, as the median over lines within this relative
/// distance of its middle: wide enough that the few lines of a shifted
/// lightly damped peak or of an antiresonance are outvoted, narrow against
/// the band a heavily damped resonator spreads over (on trials 22 and 23,
/// the residual exceeds ten times the noise over 100 to 150 Hz).
pub(crate) const HALF_WIDTH: f64 = 0.1;

/// Lines within this relative distance of a peak of the model or of the
/// data are the mode's own: a residual there is a shifted or mis-damped
/// mode, which the other candidates explain.
const NEAR_PEAK: f64 = 0.05;

/// A band is a resonator's suspect when its residual exceeds this multiple
/// of the noise. On the lab trials 22 and 23 the nominal model leaves 49 and
/// 31 times the noise at the band's middle; a model at the data leaves 1,
/// and the bound lies well above what the noise alone makes of a median.
pub(crate) const BROAD_RESIDUAL: f64 = 5.0;

/// Distinct bands are at least this factor apart in frequency.
const SEPARATION: f64 = 1.25;

/// Most bands read: the worst two.
const MAX_BANDS: usize = 2;

/// Fewest lines a band's median is read over.
const MIN_LINES: usize = 5;

/// The middles (Hz) of up to two bands, the worst first, where the residual
/// of `model` (the nominal model's FRFs at the lines of `measured`, any
/// kind; a line it lacks is left out) is broad: its median over lines within 10 % exceeds
/// [`BROAD_RESIDUAL`] times `noise` at a line more than 5 % from every peak
/// of the model and of the data. The residual at a line is the RMS over
/// channels of the weighted `ln(H / M)`, with the gains of `gains` fitted
/// on every line first (`weights` channel-major, as the diagnosis's).
/// Each with its level (the median; the noise's units).
pub(crate) fn broad_residual_hz(
    measured: &FrfSet,
    model: &FrfSet,
    weights: Option<&[f64]>,
    gains: Gains,
    noise: f64,
) -> Result<Vec<(f64, f64)>, UpdateError> {
    // a line where the model is singular (left out of its synthesis) is
    // left out here too
    let all = measured.frequencies_hz();
    let present: Vec<usize> = (0..all.len()).filter(|&k| model.line_of(all[k]).is_some()).collect();
    let (reduced, reduced_weights);
    let (measured, weights) = if present.len() == all.len() {
        (measured, weights)
    } else {
        (reduced, reduced_weights) = super::select_lines(measured, weights, &present)?;
        (&reduced, reduced_weights.as_deref())
    };
    let f = measured.frequencies_hz();
    let (nf, nc) = (f.len(), measured.channels().len());
    let mut model = model.at_frequencies(f)?.converted(measured.kind());
    if gains != Gains::None {
        crate::gain::fit_gains(&model, measured, weights, gains)?.apply(&mut model);
    }
    // the residual at each line (NaN where no value counts)
    let residual: Vec<f64> = (0..nf)
        .map(|k| {
            let (mut sum, mut n) = (0.0, 0usize);
            for c in 0..nc {
                let (h, m) = (model.get(c, k), measured.get(c, k));
                let w = weights.map_or(1.0, |w| w[c * nf + k]);
                if m.norm() > 0.0 && w > 0.0 && h.norm() > 0.0 && h.re.is_finite() && h.im.is_finite() {
                    sum += (w * (h / m).ln()).norm_sqr();
                    n += 1;
                }
            }
            if n > 0 { (sum / n as f64).sqrt() } else { f64::NAN }
        })
        .collect();
    let peak_hz: Vec<f64> = peaks(&model).into_iter().chain(peaks(measured)).map(|(_, k)| f[k]).collect();
    let near_peak = |x: f64| peak_hz.iter().any(|&p| (x / p - 1.0).abs() <= NEAR_PEAK);
    let mut broad: Vec<(f64, f64)> = Vec::new();
    for k in 0..nf {
        if near_peak(f[k]) {
            continue;
        }
        let mut window: Vec<f64> = (0..nf)
            .filter(|&j| (f[j] / f[k] - 1.0).abs() <= HALF_WIDTH && residual[j].is_finite())
            .map(|j| residual[j])
            .collect();
        if window.len() < MIN_LINES {
            continue;
        }
        window.sort_by(f64::total_cmp);
        let median = window[window.len() / 2];
        if median > BROAD_RESIDUAL * noise {
            broad.push((median, f[k]));
        }
    }
    broad.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (level, hz) in broad {
        if out.len() == MAX_BANDS {
            break;
        }
        if out.iter().all(|&(g, _)| (hz / g).ln().abs() >= SEPARATION.ln()) {
            out.push((hz, level));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use damping::DampedSystem;
    use fe_model::{Dof, DofRef, Group, samples};
    use frf::{Channel, NoiseModel, synthesize};

    use super::*;

    /// A 10-element cantilever, measured across its axis at every other
    /// node over its tip, 1-400 Hz every 0.5 Hz, with 1 % noise.
    fn measured(model: &fe_model::Model, seed: u64) -> FrfSet {
        let tip = DofRef::new(11, Dof::Uy);
        let channels: Vec<Channel> = (3..=11).step_by(2).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
        let lines: Vec<f64> = (2..=800).map(|i| 0.5 * f64::from(i)).collect();
        let mut set = synthesize(&DampedSystem::new(model.clone()).unwrap(), &channels, &lines).unwrap();
        NoiseModel::relative(0.01, seed).apply(&mut set);
        set
    }

    fn model_at(sys: &DampedSystem, data: &FrfSet) -> FrfSet {
        synthesize(sys, data.channels(), data.frequencies_hz()).unwrap()
    }

    /// The model of the data leaves no band (its residual is the noise);
    /// the model without the heavily damped resonator the data hold (5 % of
    /// the beam's mass on a spring across the beam at mid-span, tuned
    /// between the second and third modes, at a loss factor of 0.3) leaves
    /// a band between those two modes, clear of both (a second lies on the
    /// shoulder of the second mode, which the resonator's mass lowers), and
    /// a reference gain on the data moves neither when the gains are
    /// fitted.
    #[test]
    fn a_heavily_damped_resonator_leaves_a_broad_band_near_its_tuning_and_the_truth_none() {
        let nominal = samples::cantilever(10);
        let m = 0.05 * nominal.total_mass();
        let tuned: f64 = 120.0;
        let mut truth = nominal.clone();
        let w = 2.0 * std::f64::consts::PI * tuned;
        let g = truth.add_group(Group::new("absorber").rayleigh(0.3 / w, 0.0)).unwrap();
        truth.add_node(99, 0.5, 0.0).unwrap();
        truth.add_spring("absorber", 6, Some(99), [0.0, m * w * w, 0.0], g).unwrap();
        truth.add_mass("absorber", 99, m, [0.0; 3], g).unwrap();
        truth.add_support(99, &[Dof::Ux, Dof::Rz]).unwrap();
        let data = measured(&truth, 5);
        let noise = 0.01;
        let t = DampedSystem::new(truth).unwrap();
        let n = DampedSystem::new(nominal).unwrap();
        assert_eq!(
            broad_residual_hz(&data, &model_at(&t, &data), None, Gains::None, noise).unwrap(),
            Vec::<(f64, f64)>::new()
        );
        let bands: Vec<f64> = broad_residual_hz(&data, &model_at(&n, &data), None, Gains::None, noise)
            .unwrap()
            .iter()
            .map(|b| b.0)
            .collect();
        // the nominal model's modes on either side of the tuning
        let modes: Vec<f64> =
            damping::complex_modes::complex_modes(&n).unwrap().oscillatory.iter().map(|m| m.frequency_hz).collect();
        let below = modes.iter().copied().filter(|&f| f < tuned).fold(0.0, f64::max);
        let above = modes.iter().copied().filter(|&f| f > tuned).fold(f64::INFINITY, f64::min);
        println!("bands {bands:?}, the model's modes {below:.1} and {above:.1} Hz around the tuning");
        assert!(!bands.is_empty() && bands.len() <= MAX_BANDS, "{bands:?}");
        assert!(bands.iter().any(|&b| b > below * (1.0 + NEAR_PEAK) && b < above * (1.0 - NEAR_PEAK)), "{bands:?}");
        let mut scaled = data.clone();
        for c in 0..scaled.channels().len() {
            for v in scaled.channel_mut(c) {
                *v *= frf::C64::from_polar(3.0, 0.7);
            }
        }
        let with_gain: Vec<f64> = broad_residual_hz(&scaled, &model_at(&n, &data), None, Gains::PerReference, noise)
            .unwrap()
            .iter()
            .map(|b| b.0)
            .collect();
        assert_eq!(with_gain, bands);
    }
}
