//! Integration tests of rfm-update.

mod apply_every;
mod bending_loss;
mod calibration;
mod coherence_noise;
mod damping_form;
mod fast_vs_naive;
mod held_out;
mod hidden_effects;
mod hidden_effects_3d;
mod lab;
mod lab_study;
mod mesh;
mod noise_estimate;
mod noise_floor;
mod numerics;
mod output_error;
mod paper_cases;
mod per_direction;
mod resonators;
mod sensitivity;
mod setup_checks;
mod singular_lines;
mod study;
mod trust;
mod truths;

/// Whether the statistical studies run at the size their criteria ask for:
/// `cargo xtask heldout` sets `RFM_STUDY=full` (and CI runs it); `cargo
/// test` runs each study at a reduced size that goes through every
/// behaviour and checks the rates, not the counts.
pub(crate) fn full_study() -> bool {
    std::env::var("RFM_STUDY").is_ok_and(|v| v == "full")
}

/// A study's size: `var` when set, else `full` under [`full_study`], else
/// `reduced`.
pub(crate) fn study_size(var: &str, reduced: usize, full: usize) -> usize {
    std::env::var(var).ok().and_then(|v| v.parse().ok()).unwrap_or(if full_study() { full } else { reduced })
}

/// The receptances of a case's truth (its `[truth.set]` applied) on the
/// case's measured channels and lines, without noise.
pub(crate) fn truth_receptances(case: &fe_model::CaseFile) -> frf::FrfSet {
    let spec = case.measurement.as_ref().expect("a [measurement]");
    let channels: Vec<frf::Channel> =
        spec.references.iter().flat_map(|&r| spec.responses.iter().map(move |&m| frf::Channel::new(m, r))).collect();
    let truth = damping::DampedSystem::new(case.truth.as_ref().expect("a [truth]").model.clone()).unwrap();
    frf::synthesize(&truth, &channels, &spec.frequencies_hz).unwrap()
}
