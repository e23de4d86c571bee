//! FRF-based finite element model updating of non-viscously damped structures.
//!
//! The response function method (RFM) of Arora, Adhikari and Vijayan (2023)
//! updates stiffness, mass and exponential damping parameters so that model
//! receptances match measured ones. For a measured column `v` and relative
//! corrections `u_i = dp_i / p_i`,
//!
//! ```text
//! sum_i u_i R_FE (dZ/dp_i p_i) R_EX,v = R_FE,v - R_EX,v      (at measured rows)
//! ```
//!
//! stacked over frequency points, real and imaginary parts, solved by least
//! squares, iterated ([`response_function`]). The sensitivity columns come from
//! [`sensitivity`]: one sparse factorisation of `Z(w)` and one solve per
//! measured DOF and reference per frequency, then a short local product per
//! parameter, frequencies in parallel.
//!
//! A [`Study`] is a case file made ready: initial model, measured data (read,
//! or synthesised from the case's truth with seeded noise), parameters and
//! updating lines ([`freqsel`] chooses them away from resonances and
//! anti-resonances when asked).
//!
//! # Example
//!
//! ```
//! use damping::DampedSystem;
//! use fe_model::{Dof, DofRef, samples};
//! use frf::{Channel, synthesize};
//! use rfm_update::params::ParameterSet;
//! use rfm_update::response_function::{self, RfmOptions};
//!
//! // truth: the paper's two-material beam; model: steel group's mu and alpha off
//! let truth = DampedSystem::new(samples::two_material_cantilever()).unwrap();
//! let mut model = truth.clone();
//! let mu = model.model().quantity("group.steel.mu").unwrap();
//! let alpha = model.model().quantity("group.steel.alpha").unwrap();
//! model.set(mu, 0.3 * 631.12).unwrap();
//! model.set(alpha, 0.4e-5).unwrap();
//!
//! let tip = DofRef::new(31, Dof::Uy);
//! let channels: Vec<Channel> = (2..=31).map(|n| Channel::new(DofRef::new(n, Dof::Uy), tip)).collect();
//! let lines = [13.0, 27.0, 61.0, 95.0, 140.0, 190.0];
//! let measured = synthesize(&truth, &channels, &lines).unwrap();
//!
//! let params = ParameterSet::of_quantities(&model, &[mu, alpha]);
//! let result = response_function::run(&mut model, &params, &measured, &RfmOptions::default(), |_| {}).unwrap();
//! assert!((result.values[0] / 631.12 - 1.0).abs() < 1e-8);
//! assert!((result.values[1] / 1e-5 - 1.0).abs() < 1e-8);
//! ```
//!
//! # The whole workflow from a downstream crate
//!
//! Compare a case's model with its measured FRFs, diagnose what is missing,
//! add the recommended effect and update it by output error, with no code
//! of the `rfm` binary (which only parses arguments and renders these
//! results):
//!
//! ```
//! use fe_model::CaseFile;
//! use frf::correlation::BandSpec;
//! use rfm_update::comparison::{self, GainSource};
//! use rfm_update::diagnose::{self, DiagnoseOptions};
//! use rfm_update::Study;
//! use rfm_update::status::Status;
//!
//! let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../cases/tutorial/l-frame.toml"));
//! let study = Study::load(path).unwrap();
//! let measured = study.measured().to_receptance();
//!
//! // compare: FRF errors per channel and band, and the modes paired by MAC
//! let before = comparison::compare(study.system(), &measured, GainSource::None, &BandSpec::Auto).unwrap();
//! let modes = comparison::compare_modes(study.system(), &measured, &before.model.gains, 0.5).unwrap();
//! assert!(!modes.pairing.pairs.is_empty());
//!
//! // diagnose: every candidate effect fitted and ranked against the noise
//! let d = diagnose::diagnose(&study.case().model, &measured, &DiagnoseOptions::default()).unwrap();
//! let rank = d.recommended.expect("the tutorial's model lacks its bolted joint");
//! assert!(d.ranking[rank - 1].description.contains("joint at node 13"));
//!
//! // add it and update every parameter of the new case
//! let added = d.apply(study.case(), rank).unwrap().text_at(path).unwrap();
//! let next = Study::with_measured(CaseFile::parse(path, &added).unwrap(), study.measured().clone()).unwrap();
//! let updated = next.run_output_error(&next.output_error_options().unwrap(), |_| {}).unwrap();
//! assert_eq!(updated.status, Status::Converged);
//!
//! let after = comparison::compare(&updated.system, &measured, GainSource::None, &BandSpec::Auto).unwrap();
//! assert!(after.correlation.total.log_misfit < 0.1 * before.correlation.total.log_misfit);
//! ```

pub mod checks;
pub mod comparison;
pub mod diagnose;
pub mod error;
pub mod fix;
pub mod freqsel;
pub mod gain;
pub mod history;
pub mod jackknife;
pub mod lstsq;
pub mod measured;
pub mod output_error;
pub mod params;
pub mod response_function;
pub mod sensitivity;
pub mod status;
pub mod study;
pub mod uncertainty;
pub mod verdict;

pub use error::UpdateError;

/// Serialises a value through its `Display` form (DOF names such as `31:uy`).
#[cfg(feature = "serde")]
pub(crate) fn serialize_display<T: std::fmt::Display, S: serde::Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(v)
}

/// Serialises an optional value through its `Display` form (`null` when absent).
#[cfg(feature = "serde")]
pub(crate) fn serialize_option_display<T: std::fmt::Display, S: serde::Serializer>(
    v: &Option<T>,
    s: S,
) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => s.collect_str(v),
        None => s.serialize_none(),
    }
}
pub use study::{Method, ParameterReport, Study, UpdateOutcome};
