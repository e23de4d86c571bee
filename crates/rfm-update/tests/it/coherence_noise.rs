//! A weighted fit is judged against the noise weighted the same way: a
//! residual of weighted lines set beside the unweighted noise looks small
//! whatever the model error (the coherence weight is below 1 wherever the
//! coherence is below 0.999, and band weights may be too).

use std::path::Path;

use fe_model::CaseFile;
use frf::NoiseModel;
use rfm_update::Study;
use rfm_update::status::Status;

/// A 0.8 m steel strip clamped at node 1, driven at its tip, four
/// responses; only its damping is updated. The truth's `E` is `stiffer`
/// times the model's: a model error the damping cannot absorb. `more`:
/// lines added to its `[update]`.
fn case(stiffer: f64, more: &str) -> CaseFile {
    let text = format!(
        r#"
title = "strip with a stiffness the update cannot reach"
[materials]
steel = {{ E = 2.1e11, rho = 7850 }}
[sections]
strip = {{ b = 0.04, h = 0.006 }}
[groups.beam]
alpha = 2.0e-6
beta = 0.5
[[lines]]
from = [0.0, 0.0]
to = [0.8, 0.0]
elements = 8
material = "steel"
section = "strip"
group = "beam"
[[supports]]
node = 1
[measurement]
frequencies = {{ from = 5.0, to = 400.0, step = 0.5 }}
references = ["9:uy"]
responses = ["3:uy", "5:uy", "7:uy", "9:uy"]
[truth]
noise = 0.0
[truth.set]
"material.steel.E" = {}
"group.beam.alpha" = 3.0e-6
[update]
parameters = ["group.beam.alpha", "group.beam.beta"]
frequencies = {{ auto = 60 }}
method = "output-error"
{more}
"#,
        2.1e11 * stiffer
    );
    CaseFile::parse(Path::new("strip.toml"), &text).unwrap()
}

/// Coherence of a line: 0.99 over most of the band, falling below 40 Hz.
fn coherence(f: f64) -> f64 {
    0.99 - 0.6 * (-(f - 5.0) / 12.0).exp()
}

/// Relative noise 1 % at coherence 0.99, growing as `sqrt((1 - g) / g)`,
/// the relative standard deviation of an FRF estimate of coherence `g`.
const NOISE_AT_099: f64 = 0.01;

fn relative_noise(g: f64) -> f64 {
    NOISE_AT_099 * ((1.0 - g) / g).sqrt() / (0.01f64 / 0.99).sqrt()
}

/// The truth's receptances with that noise, and with `coherent` the
/// coherence attached; without, the noise is 1 % at every line.
fn study(stiffer: f64, more: &str, coherent: bool) -> Study {
    let case = case(stiffer, more);
    let measured = measured(&case, coherent, 0.0, 7);
    Study::with_measured(case, measured).unwrap()
}

/// The receptances of `case`'s truth with noise of seed `seed` that grows
/// as the coherence falls (with `coherent`, which attaches the coherence;
/// else 1 % at every line), times `1 + bias (1 - g / 0.99) e^(0.5 j)` at
/// coherence `g` (a bias where the coherence falls, as leakage or a
/// shaker's interaction leave it).
fn measured(case: &CaseFile, coherent: bool, bias: f64, seed: u64) -> frf::FrfSet {
    let spec = case.measurement.as_ref().unwrap();
    let clean = crate::truth_receptances(case);
    let mut unit = clean.clone();
    NoiseModel::relative(1.0, seed).apply(&mut unit);
    let mut measured = clean.clone();
    let mut coh = Vec::new();
    for c in 0..clean.channels().len() {
        for (k, &f) in spec.frequencies_hz.iter().enumerate() {
            let h = clean.get(c, k);
            let level = if coherent { relative_noise(coherence(f)) } else { NOISE_AT_099 };
            let biased = h * (1.0 + num_complex::Complex64::from_polar(bias * (1.0 - coherence(f) / 0.99), 0.5));
            measured.set(c, k, biased + level * (unit.get(c, k) - h));
            coh.push(coherence(f));
        }
    }
    if coherent {
        measured.set_coherence(coh).unwrap();
    }
    measured
}

/// The coherence weight of a line at 0.99 (`sqrt(g / (1 - g)) / 30`,
/// `rfm_update::study::line_weights_for`): the weighted residual of a right
/// model is about this times the noise there.
fn weight_at_099() -> f64 {
    (0.99f64 / 0.01).sqrt() / 30.0
}

/// The right model: the weighted residual is at the weighted noise (about
/// 1 % times the weight of coherence 0.99, 0.33), so the ratio is near 1,
/// not near 0.33 as against the unweighted noise.
#[test]
fn a_right_model_leaves_the_weighted_noise_under_coherence_weights() {
    let study = study(1.0, "", true);
    assert!(study.weighs_coherence());
    let o = study.run_output_error(&study.output_error_options().unwrap(), |_| {}).unwrap();
    assert!(o.coherence_weighted);
    let level = o.residual_noise.unwrap();
    let injected = NOISE_AT_099 * weight_at_099();
    assert!((level / injected - 1.0).abs() < 0.15, "weighted noise {level:.3e}, injected {injected:.3e}");
    let ratio = o.noise_ratio.unwrap();
    assert!((0.8..1.25).contains(&ratio), "a right model leaves {ratio:.2} times the noise");
    assert_eq!(o.status, Status::Converged);
}

/// E 0.15 % off (the resonances 0.075 % off, about a tenth of their
/// half-power width): the weighted residual is 3.4 times the weighted noise,
/// and the run is not called converged (against the unweighted noise it
/// was: 1.04 times it).
#[test]
fn a_model_error_under_coherence_weights_is_not_within_the_noise() {
    let study = study(1.0015, "", true);
    let o = study.run_output_error(&study.output_error_options().unwrap(), |_| {}).unwrap();
    let ratio = o.noise_ratio.unwrap();
    assert!(ratio > 2.0, "a 0.15 % stiffness error leaves only {ratio:.2} times the noise");
    assert_ne!(o.status, Status::Converged, "at {ratio:.2} times the noise");
    // the uncertainty's lack of fit is the same ratio
    let u = o.uncertainty.unwrap();
    assert!(u.inflation >= 0.999 * ratio, "inflation {} below the lack of fit {ratio}", u.inflation);
}

/// Band weights are the user's, not the noise's: the noise of the weighted
/// residual is the data's times their RMS over the fitted values (here
/// `sqrt((0.2^2 + 1) / 2)` of 1 % for a weight of 0.2 on half the band), not
/// the roughness of the weighted data, whose median the low-weighted half
/// would pull down to the weight's level.
#[test]
fn band_weights_scale_the_noise_by_their_rms() {
    let study = study(1.0, "[[update.weights]]\nfrom = 5.0\nto = 202.0\nweight = 0.2", false);
    let o = study.run_output_error(&study.output_error_options().unwrap(), |_| {}).unwrap();
    assert!(!o.coherence_weighted);
    let fitted = study.measured_at_update_lines().unwrap();
    let low = fitted.frequencies_hz().iter().filter(|&&f| f <= 202.0).count() as f64;
    let share = low / fitted.n_freq() as f64;
    let expected = NOISE_AT_099 * (share * 0.04 + (1.0 - share)).sqrt();
    let level = o.residual_noise.unwrap();
    assert!((level / expected - 1.0).abs() < 0.15, "weighted noise {level:.3e}, expected {expected:.3e}");
    let ratio = o.noise_ratio.unwrap();
    assert!((0.8..1.25).contains(&ratio), "a right model leaves {ratio:.2} times the noise");
    assert_eq!(o.status, Status::Converged);
}

/// The diagnosis weighs lines by their coherence too. A stiffness loss in
/// element 5 of the strip (all else as the model), measured with a bias
/// where the coherence falls (below 40 Hz: 12 % at 5 Hz, as leakage or a
/// shaker's interaction would leave it) and noise that grows there:
/// weighted, the noise is read at the weighted level and the loss leads
/// and explains the data to the noise (0.96 x); equally weighted it leads
/// too but leaves the bias as a symptom, 2.5 times the noise, that the
/// loop would go on to explain with effects that are not there.
#[test]
fn the_diagnosis_weighs_lines_by_their_coherence() {
    let mut case = case(1.0, "");
    let q = case.truth.as_ref().unwrap().model.quantity("element.5.stiffness").unwrap();
    let truth = &mut case.truth.as_mut().unwrap().model;
    truth.set(q, 0.6).unwrap();
    // the model's damping: the loss is all that differs
    let alpha = truth.quantity("group.beam.alpha").unwrap();
    truth.set(alpha, 2.0e-6).unwrap();
    let measured = measured(&case, true, 0.2, 11);
    let study = Study::with_measured(case, measured.clone()).unwrap();
    let opts = study.diagnose_options(&measured).unwrap();
    assert!(opts.weights.is_some(), "coherence weights by default");
    let weighted = rfm_update::diagnose::diagnose(&study.case().model, &measured, &opts).unwrap();
    let leader = weighted.leader().map(|l| l.description.clone());
    let right = |d: &Option<String>| d.as_deref().is_some_and(|d| d.contains("element 5") || d.contains("elements 5"));
    assert!(right(&leader), "weighted, the loss leads: {leader:?}");
    let injected = NOISE_AT_099 * weight_at_099();
    assert!((weighted.noise / injected - 1.0).abs() < 0.3, "noise {:.3e}, injected {injected:.3e}", weighted.noise);
    let plain = rfm_update::diagnose::DiagnoseOptions { weights: None, ..opts };
    let unweighted = rfm_update::diagnose::diagnose(&study.case().model, &measured, &plain).unwrap();
    let left = |d: &rfm_update::diagnose::Diagnosis| d.leader().unwrap().misfit / d.noise;
    let (w, u) = (left(&weighted), left(&unweighted));
    println!("the loss leaves {w:.2} x the noise weighted, {u:.2} x equally weighted");
    assert!(w < 1.3, "weighted, the loss explains the data to the noise: {w:.2} x");
    assert!(u > 1.5, "equally weighted, the bias is left as a symptom (else this test shows nothing): {u:.2} x");
}
