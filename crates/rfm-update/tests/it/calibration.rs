//! Calibration of the reported standard deviations by seeded Monte Carlo:
//! over repeated noisy data sets, the truth must fall within one reported
//! standard deviation about 68 % of the time and within two about 95 %.

use std::path::PathBuf;

use fe_model::CaseFile;
use fe_model::case::FrequencyChoice;
use rfm_update::Study;

/// `|ln(updated / truth)|` in units of the reported standard deviation
/// of `ln p`, for the well-determined parameters of each trial.
fn z_scores(trials: u64) -> Vec<f64> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases/two-material-beam-noisy.toml");
    let base = CaseFile::load(&path).unwrap();
    let mut z = Vec::new();
    for seed in 1..=trials {
        let mut case = base.clone();
        let truth = case.truth.as_mut().unwrap();
        truth.noise = 0.01;
        truth.seed = 1000 + seed;
        case.update.as_mut().unwrap().frequencies = Some(FrequencyChoice::Lines(60));
        let study = Study::from_case(case).unwrap();
        let outcome = study.run_output_error(&study.output_error_options().unwrap(), |_| {}).unwrap();
        let unc = outcome.uncertainty.unwrap();
        for (p, u) in outcome.parameters.iter().zip(&unc.parameters) {
            if u.well_determined {
                z.push((p.updated / p.truth.unwrap()).ln().abs() / u.relative_std);
            }
        }
    }
    z
}

fn coverage(z: &[f64], k: f64) -> f64 {
    z.iter().filter(|&&z| z <= k).count() as f64 / z.len() as f64
}

/// 1-sigma coverage must lie in [0.55, 0.80] and 2-sigma in [0.88, 0.995]
/// (68.3 % and 95.4 % for an honest Gaussian estimate). The same sample
/// with the covariance doubled or halved (standard deviations times or over
/// sqrt 2) must fail the same bounds: the test can tell.
#[test]
fn reported_standard_deviations_cover_the_truth_as_often_as_they_claim() {
    let z = z_scores(40);
    assert!(z.len() >= 80, "only {} well-determined estimates", z.len());
    let within = |z: &[f64]| {
        let (c1, c2) = (coverage(z, 1.0), coverage(z, 2.0));
        ((0.55..=0.80).contains(&c1) && (0.88..=0.995).contains(&c2), c1, c2)
    };
    let (ok, c1, c2) = within(&z);
    eprintln!("coverage over {} estimates: 1 sd {c1:.3}, 2 sd {c2:.3}", z.len());
    assert!(ok, "1-sigma coverage {c1:.3} (want 0.55-0.80), 2-sigma {c2:.3} (want 0.88-0.995)");
    for scale in [2f64, 0.5] {
        let scaled: Vec<f64> = z.iter().map(|z| z / scale.sqrt()).collect();
        let (ok, c1, c2) = within(&scaled);
        assert!(!ok, "with the covariance times {scale} the coverage ({c1:.3}, {c2:.3}) still passes");
    }
}
