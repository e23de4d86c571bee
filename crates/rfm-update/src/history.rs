//! The misfit of every iterate of an update over the whole measured band,
//! not only at the updating lines: what a convergence plot shows. Each
//! iterate's parameter values are set on the initial model and its FRFs
//! synthesised and correlated with the data; on large models the lines are
//! thinned and the iterates spread so that this never costs much more than
//! the update itself.

use frf::FrfSet;
use frf::correlation::BandSpec;
#[cfg(test)]
use frf::correlation::correlate;

use crate::comparison::{GainSource, compare};
use crate::{Study, UpdateOutcome};

/// At most this many iterates are re-evaluated (evenly spread, first and
/// last included).
pub const MAX_ITERATIONS_EVALUATED: usize = 30;

/// Budget of the re-evaluation, in DOF x line solves: small models use every
/// line of every iterate, large ones a thinned grid.
const DOF_LINE_BUDGET: f64 = 1e8;

/// Every how many lines to evaluate `iterates` models of `dofs` DOFs within
/// `DOF_LINE_BUDGET`, keeping at least 20 lines per iterate.
pub fn line_stride(dofs: usize, iterates: usize, lines: usize) -> usize {
    let per_iterate = (DOF_LINE_BUDGET / dofs.max(1) as f64 / iterates.max(1) as f64).max(20.0);
    (lines as f64 / per_iterate).ceil().max(1.0) as usize
}

/// RMS magnitude error (dB) over the lines of `measured` of the model at
/// each iteration of `outcome` (NaN for the iterations not evaluated, see
/// [`MAX_ITERATIONS_EVALUATED`], and for an iterate the model cannot
/// evaluate), and the stride of the lines used (1 = all). The model's FRFs
/// are taken as they are, without gains (see [`rms_db_per_iteration_with_gains`]).
pub fn rms_db_per_iteration(study: &Study, outcome: &UpdateOutcome, measured: &FrfSet) -> (Vec<f64>, usize) {
    per_iteration(study, outcome, measured, false)
}

/// As [`rms_db_per_iteration`], each iterate's FRFs times the study's
/// gains as a report shows the initial and the updated model: the gains
/// that fit the iterate best (closed form, weighted by the study's line
/// weights), and for the last iterate, the updated model, those the update
/// estimated with it. So the first and the last value are the RMS dB
/// errors a comparison of the initial and of the updated model gives, and
/// data per volt are not drawn tens of dB off at every iteration. Without
/// gains it is [`rms_db_per_iteration`].
pub fn rms_db_per_iteration_with_gains(study: &Study, outcome: &UpdateOutcome, measured: &FrfSet) -> (Vec<f64>, usize) {
    per_iteration(study, outcome, measured, study.gains() != fe_model::case::Gains::None)
}

/// The RMS dB error of each chosen iterate, with the study's gains when
/// `with_gains` (see [`rms_db_per_iteration_with_gains`]).
fn per_iteration(study: &Study, outcome: &UpdateOutcome, measured: &FrfSet, with_gains: bool) -> (Vec<f64>, usize) {
    let n = outcome.history.len();
    let chosen: Vec<usize> = if n <= MAX_ITERATIONS_EVALUATED {
        (0..n).collect()
    } else {
        let m = MAX_ITERATIONS_EVALUATED;
        let mut v: Vec<usize> = (0..m).map(|j| j * (n - 1) / (m - 1)).collect();
        v.dedup();
        v
    };
    let nf = measured.n_freq();
    let stride = line_stride(study.system().n(), chosen.len(), nf);
    let lines: Vec<usize> = (0..nf).step_by(stride).collect();
    let mut out = vec![f64::NAN; n];
    let Ok(measured) = measured.select_lines(&lines) else {
        return (out, stride);
    };
    let weights = if with_gains { study.line_weights(&measured) } else { Ok(None) };
    let Ok(weights) = weights else {
        return (out, stride);
    };
    let f = measured.frequencies_hz();
    let whole = BandSpec::Edges(vec![f[0], f[f.len() - 1]]);
    let params = study.parameter_set();
    for k in chosen {
        let mut sys = study.system().clone();
        if params.set_values(&mut sys, &outcome.history[k].values).is_err() {
            continue;
        }
        // an iterate the model cannot evaluate (singular) is simply not plotted
        let gains = match (with_gains, k + 1 == n) {
            (false, _) => GainSource::None,
            (true, true) => GainSource::Estimated(&outcome.gains),
            (true, false) => GainSource::Fit { setting: study.gains(), weights: weights.as_deref() },
        };
        if let Ok(c) = compare(&sys, &measured, gains, &whole)
            && c.model.singular_hz.is_empty()
        {
            out[k] = c.correlation.total.rms_db;
        }
    }
    (out, stride)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The last iterate re-evaluated from its recorded values is the
    /// updated model the run returned, correlated over the same lines by
    /// the route `rfm compare` takes; the first is the initial model.
    #[test]
    fn the_first_and_last_iterates_are_the_initial_and_the_updated_model() {
        let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../cases/two-material-beam.toml"));
        let study = Study::load(path).unwrap();
        let outcome = study.run_output_error(&study.output_error_options().unwrap(), |_| {}).unwrap();
        let measured = study.measured();
        let (db, stride) = rms_db_per_iteration(&study, &outcome, measured);
        assert_eq!(stride, 1);
        assert_eq!(db.len(), outcome.history.len());
        let f = measured.frequencies_hz();
        let whole = BandSpec::Edges(vec![f[0], f[f.len() - 1]]);
        for (sys, got) in [(study.system(), db[0]), (&outcome.system, db[db.len() - 1])] {
            let frfs = frf::synthesize(sys, measured.channels(), f).unwrap();
            let want = correlate(measured, &frfs, &whole).unwrap().total.rms_db;
            assert!((got - want).abs() <= 1e-9 * want.abs(), "{got} vs {want}");
        }
        assert!(db[db.len() - 1] < db[0]);
    }

    /// On data per volt (the lap-joint tutorial, an amplifier of 42 at -30
    /// deg), the first and last iterate with gains are the initial model
    /// with the gains that fit it and the updated model with the gains the
    /// update estimated, as a comparison of each gives them; without the
    /// gains every iterate reads the amplifier's 32 dB.
    #[test]
    fn with_gains_the_ends_are_the_comparisons_of_the_initial_and_updated_model() {
        let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../cases/tutorial"));
        let text = std::fs::read_to_string(dir.join("lap-joint.toml")).unwrap()
            + "\n[update]\nparameters = [\"group.beam.alpha\", \"material.steel.E\"]\nmethod = \"output-error\"\n";
        let case = fe_model::CaseFile::parse(&dir.join("lap-joint-alpha.toml"), &text).unwrap();
        let study = Study::from_case(case).unwrap();
        assert_ne!(study.gains(), fe_model::case::Gains::None);
        let outcome = study.run_output_error(&study.output_error_options().unwrap(), |_| {}).unwrap();
        let measured = study.measured_as_read();
        let (db, stride) = rms_db_per_iteration_with_gains(&study, &outcome, &measured);
        assert_eq!(stride, 1);
        let weights = study.line_weights(&measured).unwrap();
        let fit = GainSource::Fit { setting: study.gains(), weights: weights.as_deref() };
        let initial = compare(study.system(), &measured, fit, &BandSpec::Auto).unwrap().correlation.total.rms_db;
        let updated = compare(&outcome.system, &measured, GainSource::Estimated(&outcome.gains), &BandSpec::Auto)
            .unwrap()
            .correlation
            .total
            .rms_db;
        let last = db[db.len() - 1];
        assert!((db[0] - initial).abs() <= 1e-9 * initial, "{} against {initial}", db[0]);
        assert!((last - updated).abs() <= 1e-9 * updated, "{last} against {updated}");
        assert!(db[0] < 10.0 && last < db[0], "{db:?}");
        let (plain, _) = rms_db_per_iteration(&study, &outcome, &measured);
        assert!(plain.iter().all(|&v| v > 25.0), "{plain:?}");
    }

    #[test]
    fn small_models_use_every_line_and_large_ones_a_thinned_grid() {
        // the paper's beam: 90 DOFs, 9 iterates, 800 lines
        assert_eq!(line_stride(90, 9, 800), 1);
        // 100,000 DOFs, 30 iterates: 33 lines each, every 30th of 1000
        assert_eq!(line_stride(100_000, 30, 1000), 30);
        // never fewer than 20 lines per iterate
        assert_eq!(line_stride(10_000_000, 30, 1000), 50);
    }
}
