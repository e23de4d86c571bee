//! The RFM says when it cannot be trusted; the statuses never call a fit
//! far above the noise converged.

use std::path::PathBuf;

use fe_model::CaseFile;
use rfm_update::Study;
use rfm_update::status::Status;

fn beam(noise: f64) -> Study {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/two-material-beam-noisy.toml");
    let mut case = CaseFile::load(&path).unwrap();
    case.truth.as_mut().unwrap().noise = noise;
    Study::from_case(case).unwrap()
}

/// At 1 % noise the RFM is biased: it warns, suggests the output-error
/// method and gives no uncertainty (the terminal says so); it is called
/// converged only if its residual is within 1.5 times the noise.
#[test]
fn the_rfm_warns_above_its_noise_limit_and_gives_no_uncertainty() {
    let study = beam(0.01);
    let o = study.run_rfm(&study.rfm_options(), |_| {}).unwrap();
    assert!(
        o.warnings.iter().any(|w| w.contains("where the RFM is biased") && w.contains("--method output-error")),
        "{:?}",
        o.warnings
    );
    assert!(o.uncertainty.is_none());
    let ratio = o.noise_ratio.unwrap();
    assert_eq!(o.status == Status::Converged, ratio <= 1.5, "{:?} at {ratio:.2} times the noise", o.status);
}

/// Noise-free data: no noise warning (Table 1's case converges exactly).
#[test]
fn the_rfm_does_not_warn_about_noise_on_clean_data() {
    let study = beam(0.0);
    let o = study.run_rfm(&study.rfm_options(), |_| {}).unwrap();
    assert!(!o.warnings.iter().any(|w| w.contains("where the RFM is biased")), "{:?}", o.warnings);
}

/// A model that cannot represent the data (the beam's stiffness fixed 5 %
/// off, only damping updated): the output-error fit ends far above the
/// noise, its restarts confirm the minimum, and it is called
/// `model_inadequate`, never converged; its standard deviations include the
/// model error, larger than the noise-only ones by at least the residual
/// over the noise.
#[test]
fn a_confirmed_minimum_above_the_noise_is_model_inadequate_with_inflated_uncertainty() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/two-material-beam-noisy.toml");
    let mut case = CaseFile::load(&path).unwrap();
    case.truth.as_mut().unwrap().noise = 0.01;
    let mut model = case.model.clone();
    let e = model.quantity("material.steel.E").unwrap();
    model.set(e, 1.05 * model.get(e)).unwrap();
    case.model = model;
    case.update.as_mut().unwrap().frequencies = Some(fe_model::case::FrequencyChoice::Lines(80));
    let study = Study::from_case(case).unwrap();
    let o = study.run_output_error(&study.output_error_options().unwrap(), |_| {}).unwrap();
    let ratio = o.noise_ratio.unwrap();
    assert!(ratio > 3.0, "the stiffness error leaves only {ratio:.2} times the noise");
    assert_eq!(o.status, Status::ModelInadequate, "at {ratio:.1} times the noise");
    assert!(!o.restarts.is_empty());
    let u = o.uncertainty.unwrap();
    assert!(u.inflation >= ratio * 0.999, "inflation {} below the lack of fit {ratio}", u.inflation);
    for p in &u.parameters {
        assert!(p.relative_std >= p.relative_std_noise * ratio * 0.999, "{}", p.name);
    }
}

/// The monopile's mu starts 2e4 times its truth on purpose (viscous in
/// practice) and the RFM brings it there from exact data: a move of a factor
/// of 5e-5 that the data hold (the misfit falls to 1e-13) is an estimate, not
/// a run-away, and the run is converged.
#[test]
fn a_far_move_to_a_value_the_data_hold_is_no_runaway() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/monopile.toml");
    let study = Study::load(&path).unwrap();
    let o = study.run_rfm(&study.rfm_options(), |_| {}).unwrap();
    let p = &o.parameters[0];
    assert!(p.updated / p.initial < 1e-4, "{} -> {}", p.initial, p.updated);
    assert!(!o.warnings.iter().any(|w| w.contains("run-away")), "{:?}", o.warnings);
    assert_eq!(o.status, Status::Converged);
}

/// At 6 % noise the RFM's misfit ends within the noise with the aluminium's
/// beta on the bound it may not pass (a factor of 1e6 from its start): the
/// run is a run-away, never converged.
#[test]
fn an_rfm_parameter_on_its_bound_makes_the_run_a_runaway() {
    let study = beam(0.06);
    let o = study.run_rfm(&study.rfm_options(), |_| {}).unwrap();
    assert!(o.noise_ratio.unwrap() <= 1.5, "{:?}", o.noise_ratio);
    assert!(o.warnings.iter().any(|w| w.starts_with("group.aluminium.beta ended a factor of 1e6")), "{:?}", o.warnings);
    assert_eq!(o.status, Status::Runaway);
}
