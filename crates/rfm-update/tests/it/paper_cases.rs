//! The paper's case studies, run from the case files under `cases/`.

use std::path::PathBuf;

use rfm_update::Study;
use rfm_update::rfm::{RfmOptions, Status};

fn case(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases").join(format!("{name}.toml"))
}

/// Table 1 of Arora, Adhikari and Vijayan (2023): the RFM recovers the true
/// damping of the two-material beam from the paper's initial values.
#[test]
fn two_material_beam_recovers_table_1_exactly() {
    let study = Study::load(&case("two-material-beam")).unwrap();
    let outcome = study.run_rfm(&RfmOptions::default(), |_| {}).unwrap();
    assert_eq!(outcome.status, Status::Converged);
    let table1 = [
        ("group.steel.mu", 631.12),
        ("group.aluminium.mu", 38274.0),
        ("group.steel.alpha", 1e-5),
        ("group.aluminium.alpha", 3e-5),
        ("group.steel.beta", 0.1),
        ("group.aluminium.beta", 0.2),
    ];
    for (name, value) in table1 {
        let p = outcome.parameters.iter().find(|p| p.name == name).unwrap();
        let err = ((p.updated - value) / value).abs();
        assert!(err < 1e-6, "{name}: updated {} vs Table 1 {value} (relative error {err:.1e})", p.updated);
        assert_eq!(p.paper, Some(value));
    }
    assert!(outcome.history.len() <= 12, "took {} iterations", outcome.history.len() - 1);
}

#[test]
fn monopile_recovers_the_submerged_relaxation_parameter_from_a_viscous_start() {
    let study = Study::load(&case("monopile")).unwrap();
    let outcome = study.run_rfm(&RfmOptions::default(), |_| {}).unwrap();
    assert_eq!(outcome.status, Status::Converged);
    let p = &outcome.parameters[0];
    assert!(p.relative_error().unwrap() < 1e-5, "{p:?}");
}

#[test]
fn every_paper_case_loads_and_has_truth_and_parameters() {
    for name in [
        "two-material-beam",
        "two-material-beam-high-damping",
        "two-material-beam-noisy",
        "monopile",
        "cantilever-flexible-clamp",
        "f-frame",
    ] {
        let study = Study::load(&case(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(study.truth.is_some(), "{name}");
        assert!(!study.parameters.is_empty(), "{name}");
        assert!(!study.update_frequencies_hz.is_empty(), "{name}");
        // the chosen lines are lines of the data and avoid its resonances
        for f in &study.update_frequencies_hz {
            assert!(study.measured.line_of(*f).is_some(), "{name}: {f} Hz");
        }
    }
}
