//! The output-error estimator's options against known truths.

use damping::DampedSystem;
use fe_model::case::{GainKey, Gains};
use fe_model::{Dof, DofRef, samples};
use frf::{C64, Channel, FrfSet, NoiseModel, synthesize};
use rfm_update::output_error::{self, Misfit, OeData, OeOptions};
use rfm_update::params::ParameterSet;
use rfm_update::status::Status;

fn beam_data(truth: &DampedSystem, noise: f64) -> FrfSet {
    let tip = DofRef::new(31, Dof::Uy);
    let channels: Vec<Channel> = (4..=31).step_by(3).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
    let lines: Vec<f64> = (1..=200).map(|i| 2.0 * f64::from(i)).collect();
    let mut set = synthesize(truth, &channels, &lines).unwrap();
    NoiseModel::relative(noise, 17).apply(&mut set);
    set
}

/// Starts the steel group's damping away from the truth.
fn perturbed(truth: &DampedSystem) -> (DampedSystem, ParameterSet) {
    let mut model = truth.clone();
    let names = ["group.steel.mu", "group.steel.alpha", "group.aluminium.alpha"];
    let qs: Vec<_> = names.iter().map(|n| model.model().quantity(n).unwrap()).collect();
    for &q in &qs {
        let v = model.get(q);
        model.set(q, 0.5 * v).unwrap();
    }
    let params = ParameterSet::of_quantities(&model, &qs);
    (model, params)
}

#[test]
fn an_unknown_complex_gain_per_reference_is_estimated_with_the_parameters() {
    let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let mut data = beam_data(&truth, 0.0);
    let gain = C64::from_polar(0.37, 0.4);
    for c in 0..data.channels().len() {
        for v in data.channel_mut(c) {
            *v *= gain;
        }
    }
    let (mut model, params) = perturbed(&truth);
    let opts = OeOptions { gains: Gains::PerReference, ..OeOptions::default() };
    let r = output_error::run(&mut model, &params, &OeData { measured: &data, weights: None }, &opts, |_| {}).unwrap();
    assert_eq!(r.status, Status::Converged);
    assert!((r.gains[0].magnitude / 0.37 - 1.0).abs() < 1e-8, "{:?}", r.gains);
    assert!((r.gains[0].phase_deg - 0.4f64.to_degrees()).abs() < 1e-6, "{:?}", r.gains);
    for (&v, q) in r.values.iter().zip(params.quantities()) {
        let t = truth.get(*q);
        assert!((v / t - 1.0).abs() < 1e-7, "{v} vs {t}");
    }
    // without the gain the same data cannot be fitted
    let (mut model, params) = perturbed(&truth);
    let r = output_error::run(
        &mut model,
        &params,
        &OeData { measured: &data, weights: None },
        &OeOptions::default(),
        |_| {},
    )
    .unwrap();
    assert!(r.history.last().unwrap().residual > 0.3);
}

/// Each accelerometer with its own unknown sensitivity (magnitude and
/// phase): the gains per channel and the parameters are all recovered from
/// noise-free data, and one gain per reference cannot stand in for them.
#[test]
fn an_unknown_complex_gain_per_channel_is_estimated_with_the_parameters() {
    let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let mut data = beam_data(&truth, 0.0);
    let nc = data.channels().len();
    // spread over a decade and a half turn, none alike
    let gain = |c: usize| C64::from_polar(0.2 * 1.45f64.powi(c as i32), 0.3 - 0.17 * c as f64);
    for c in 0..nc {
        let g = gain(c);
        data.channel_mut(c).iter_mut().for_each(|v| *v *= g);
    }
    let (mut model, params) = perturbed(&truth);
    let opts = OeOptions { gains: Gains::PerChannel, ..OeOptions::default() };
    let r = output_error::run(&mut model, &params, &OeData { measured: &data, weights: None }, &opts, |_| {}).unwrap();
    assert_eq!(r.status, Status::Converged);
    assert_eq!(r.gains.len(), nc);
    for (c, (g, ch)) in r.gains.iter().zip(data.channels()).enumerate() {
        assert_eq!(g.key, GainKey::Channel(ch.response, ch.reference));
        assert!((g.factor() / gain(c) - 1.0).norm() < 1e-7, "channel {c}: {g:?} vs {}", gain(c));
    }
    for (&v, q) in r.values.iter().zip(params.quantities()) {
        let t = truth.get(*q);
        assert!((v / t - 1.0).abs() < 1e-7, "{v} vs {t}");
    }
    // the fitted gains, applied as reports and overlays apply them, make
    // the updated model's FRFs the data
    let mut frfs = synthesize(&model, data.channels(), data.frequencies_hz()).unwrap();
    output_error::Gain::apply_all(&r.gains, &mut frfs);
    for (a, b) in frfs.values().iter().zip(data.values()) {
        assert!((a / b - 1.0).norm() < 1e-6, "{a} vs {b}");
    }
    // one gain per reference leaves the channels' differences unexplained
    let (mut model, params) = perturbed(&truth);
    let opts = OeOptions { gains: Gains::PerReference, ..OeOptions::default() };
    let r = output_error::run(&mut model, &params, &OeData { measured: &data, weights: None }, &opts, |_| {}).unwrap();
    assert!(r.history.last().unwrap().residual > 0.1, "{}", r.history.last().unwrap().residual);
}

#[test]
fn an_active_bound_holds_and_is_reported() {
    let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let data = beam_data(&truth, 0.005);
    let (mut model, params) = perturbed(&truth);
    // the steel mu is 631 in truth; keep it below 400
    let start = params.values(&model);
    let opts = OeOptions { bounds: vec![Some((1.0, 400.0)), None, None], ..OeOptions::default() };
    let r = output_error::run(&mut model, &params, &OeData { measured: &data, weights: None }, &opts, |_| {}).unwrap();
    assert!(start[0] <= 400.0);
    assert!((r.values[0] - 400.0).abs() < 1e-9, "{}", r.values[0]);
    assert_eq!(r.at_bound, vec![true, false, false]);
}

#[test]
fn band_weights_of_zero_mask_corrupted_lines() {
    let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let mut data = beam_data(&truth, 0.0);
    // corrupt the lines above 300 Hz (a broken sensor band)
    let nf = data.n_freq();
    let bad: Vec<usize> = (0..nf).filter(|&k| data.frequencies_hz()[k] > 300.0).collect();
    for c in 0..data.channels().len() {
        for &k in &bad {
            let v = data.get(c, k);
            data.set(c, k, v * 3.0);
        }
    }
    let mut weights = vec![1.0; data.values().len()];
    for c in 0..data.channels().len() {
        for &k in &bad {
            weights[c * nf + k] = 0.0;
        }
    }
    let (mut model, params) = perturbed(&truth);
    let opts = OeOptions { misfit: Misfit::Log, ..OeOptions::default() };
    let r = output_error::run(&mut model, &params, &OeData { measured: &data, weights: Some(&weights) }, &opts, |_| {})
        .unwrap();
    for (&v, q) in r.values.iter().zip(params.quantities()) {
        let t = truth.get(*q);
        assert!((v / t - 1.0).abs() < 1e-6, "{v} vs {t}");
    }
    assert_eq!(r.n_data, 2 * data.channels().len() * (nf - bad.len()));
}

/// Inverse of a small symmetric positive definite matrix by Gauss-Jordan
/// elimination (the test's own, independent of the solver's SVD).
fn inverse(a: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = a.len();
    let mut m: Vec<Vec<f64>> = a
        .iter()
        .enumerate()
        .map(|(i, row)| row.iter().copied().chain((0..n).map(|j| f64::from(i == j))).collect())
        .collect();
    for c in 0..n {
        let p = m[c][c];
        m[c].iter_mut().for_each(|v| *v /= p);
        for r in (0..n).filter(|&r| r != c) {
            let f = m[r][c];
            let pivot_row = m[c].clone();
            m[r].iter_mut().zip(&pivot_row).for_each(|(v, pv)| *v -= f * pv);
        }
    }
    m.into_iter().map(|row| row[n..].to_vec()).collect()
}

/// The covariance of the log-parameters the fit reports is the Gauss-Newton
/// one, `s^2 (J^T J)^-1` with `s^2 = cost / (n - m)`, built here from
/// scratch: the residuals `ln(H / M)` (real and imaginary parts) of
/// synthesised FRFs and their Jacobian by central differences in `ln p`. A
/// covariance scaled wrongly (doubled, or with the wrong number of degrees
/// of freedom) fails; so does one from a wrong Jacobian.
#[test]
fn covariance_is_the_gauss_newton_one_with_a_finite_difference_jacobian() {
    let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
    let data = beam_data(&truth, 0.01);
    let (mut model, params) = perturbed(&truth);
    let opts = OeOptions { misfit: Misfit::Log, ..OeOptions::default() };
    let fit =
        output_error::run(&mut model, &params, &OeData { measured: &data, weights: None }, &opts, |_| {}).unwrap();
    assert_eq!(fit.status, Status::Converged);
    assert!(fit.at_bound.iter().all(|b| !b));
    let residuals = |values: &[f64]| -> Vec<f64> {
        let mut sys = model.clone();
        params.set_values(&mut sys, values).unwrap();
        let h = synthesize(&sys, data.channels(), data.frequencies_hz()).unwrap();
        h.values().iter().zip(data.values()).flat_map(|(h, m)| [(h / m).ln().re, (h / m).ln().im]).collect()
    };
    let r0 = residuals(&fit.values);
    let (n, m) = (r0.len(), fit.values.len());
    assert_eq!(n, fit.n_data);
    let cost: f64 = r0.iter().map(|r| r * r).sum();
    assert!((cost / fit.cost - 1.0).abs() < 1e-9, "cost {cost} vs the fit's {}", fit.cost);
    let s2 = cost / (n - m) as f64;
    // about the injected noise: 1 % relative per complex value, so 0.01^2 / 2 per real residual
    assert!((s2 / (0.01f64.powi(2) / 2.0) - 1.0).abs() < 0.1, "s^2 {s2}");
    let step = 1e-5;
    let jacobian: Vec<Vec<f64>> = (0..m)
        .map(|i| {
            let at = |sign: f64| {
                let mut v = fit.values.clone();
                v[i] *= (sign * step).exp();
                residuals(&v)
            };
            let (plus, minus) = (at(1.0), at(-1.0));
            plus.iter().zip(&minus).map(|(p, q)| (p - q) / (2.0 * step)).collect()
        })
        .collect();
    let normal: Vec<Vec<f64>> = (0..m)
        .map(|i| (0..m).map(|j| jacobian[i].iter().zip(&jacobian[j]).map(|(a, b)| a * b).sum()).collect())
        .collect();
    let inv = inverse(&normal);
    for i in 0..m {
        for j in 0..m {
            let expect = s2 * inv[i][j];
            let scale = s2 * (inv[i][i] * inv[j][j]).sqrt();
            assert!(
                (fit.covariance[(i, j)] - expect).abs() <= 1e-4 * scale,
                "C[{i}][{j}] = {} vs {expect} from finite differences",
                fit.covariance[(i, j)]
            );
        }
    }
}
