//! What a `Study` keeps consistent: the updating lines follow the case's
//! choice of them, set only through `Study::set_update_frequencies`.

use std::path::PathBuf;

use fe_model::case::FrequencyChoice;
use rfm_update::{Method, Study, UpdateError};

fn case(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases").join(format!("{name}.toml"))
}

#[test]
fn the_updating_lines_follow_the_case_and_a_refused_choice_changes_nothing() {
    let mut study = Study::load(&case("two-material-beam")).unwrap();
    assert_eq!(study.update_frequencies_hz(), study.lines_for(study.method()).unwrap());
    study.set_update_frequencies(FrequencyChoice::Lines(7)).unwrap();
    assert_eq!(study.update_frequencies_hz().len(), 7);
    assert_eq!(study.update_frequencies_hz(), study.lines_for(Method::OutputError).unwrap());
    assert_eq!(study.measured_at_update_lines().unwrap().frequencies_hz(), study.update_frequencies_hz());

    let f = study.measured().frequencies_hz();
    let between = 0.5 * (f[0] + f[1]);
    match study.set_update_frequencies(FrequencyChoice::List(vec![between])) {
        Err(UpdateError::Lines(m)) => {
            assert_eq!(m, format!("updating point {between} Hz is not a line of the measured data"))
        }
        other => panic!("expected UpdateError::Lines, got {other:?}"),
    }
    assert_eq!(study.update_frequencies_hz().len(), 7);
    assert_eq!(study.case().update.as_ref().unwrap().frequencies, Some(FrequencyChoice::Lines(7)));
}

#[test]
fn a_case_without_an_update_has_no_updating_lines_to_set() {
    let mut study = Study::load(&case("tutorial/l-frame")).unwrap();
    assert!(study.case().update.is_none() && study.update_frequencies_hz().is_empty());
    match study.set_update_frequencies(FrequencyChoice::Lines(5)) {
        Err(UpdateError::Case(e)) => {
            assert_eq!(e.message, "the case has no [update] section to choose updating lines for")
        }
        other => panic!("expected UpdateError::Case, got {other:?}"),
    }
    assert!(study.update_frequencies_hz().is_empty());
}

/// The fit `rfm fix` judges its steps by is the run `rfm update` makes, to
/// the bit, without the natural frequencies (two dense eigensolutions) that
/// only a report reads.
#[test]
fn a_fit_without_natural_frequencies_is_the_run_without_them() {
    let study = Study::load(&case("two-material-beam-noisy")).unwrap();
    let opts = study.output_error_options().unwrap();
    let run = study.run_output_error(&opts, |_| {}).unwrap();
    let fit = study.fit_output_error(&opts).unwrap();
    assert_eq!(run.natural_frequencies_hz.kind, "damped");
    assert!(!run.natural_frequencies_hz.updated.is_empty() && !run.natural_frequencies_hz.initial.is_empty());
    let nf = &fit.natural_frequencies_hz;
    assert_eq!(nf.kind, "not computed");
    assert!(nf.initial.is_empty() && nf.updated.is_empty() && nf.truth.is_none() && nf.paper.is_none());
    assert_eq!((&fit.status, &fit.iteration_end, fit.residual), (&run.status, &run.iteration_end, run.residual));
    let values = |o: &rfm_update::UpdateOutcome| o.parameters.iter().map(|p| p.updated).collect::<Vec<f64>>();
    assert_eq!(values(&fit), values(&run));
    let sd = |o: &rfm_update::UpdateOutcome| {
        o.uncertainty.as_ref().unwrap().parameters.iter().map(|p| p.relative_std).collect::<Vec<f64>>()
    };
    assert_eq!(sd(&fit), sd(&run));
    assert_eq!(
        (fit.history.len(), fit.restarts.len(), fit.noise_ratio),
        (run.history.len(), run.restarts.len(), run.noise_ratio)
    );
}

/// The fit `rfm fix` judges its steps by restarts only while its first fit
/// is in doubt. The tutorial's L-frame without its corner joint, updated in
/// its damping alone, leaves a hundred times the noise: restarts from
/// spread starts come back to the first fit's minimum, two of them confirm
/// it (`model_inadequate`) and the other four are not made, and the
/// outcome is the first fit's, where `rfm update` makes every restart and
/// refines two to the same minimum.
#[test]
fn the_loops_fit_stops_restarting_once_two_restarts_confirm_its_minimum() {
    let path = case("tutorial/l-frame");
    let text = std::fs::read_to_string(&path).unwrap()
        + "\n[update]\nparameters = [\"group.frame.alpha\", \"group.frame.beta\"]\nmethod = \"output-error\"\n";
    let study = Study::from_case(fe_model::CaseFile::parse(&path, &text).unwrap()).unwrap();
    let opts = study.output_error_options().unwrap();
    let values = |o: &rfm_update::UpdateOutcome| o.parameters.iter().map(|p| p.updated).collect::<Vec<f64>>();
    let run = study.run_output_error(&opts, |_| {}).unwrap();
    assert_eq!(run.status, rfm_update::status::Status::ModelInadequate);
    assert!(run.noise_ratio.unwrap() > 10.0, "{:?}", run.noise_ratio);
    assert_eq!((run.restarts.len(), run.restarts.iter().filter(|r| r.refined).count()), (6, 2));
    let fit = study.fit_output_error(&opts).unwrap();
    assert_eq!(fit.status, rfm_update::status::Status::ModelInadequate);
    assert_eq!(fit.restarts.len(), 2, "{:?}", fit.restarts);
    assert!(fit.restarts.iter().all(|r| !r.refined));
    let first = study.fit_output_error(&rfm_update::output_error::OeOptions { restarts: 0, ..opts.clone() }).unwrap();
    assert_eq!(values(&fit), values(&first));
    for (a, b) in values(&fit).iter().zip(values(&run)) {
        assert!((a / b - 1.0).abs() < 1e-3, "{a} against {b}");
    }
}
