//! What the end of an updating run means: the residual compared with the
//! noise of the data, and for the output-error fit, restarts that tell a
//! global minimum from a local one.
//!
//! An iteration that stops has found a point where no step helps; that
//! alone says nothing about whether the model explains the data. For
//! multiplicative noise of relative level `s`, the RMS residual per complex
//! value of a model that explains the data is about `s` (both misfit forms,
//! see [`crate::output_error`], and the RFM's relative misfit). So a run is called
//! [`Status::Converged`] only when its residual is within [`NOISE_FACTOR`]
//! times the noise estimated from the data
//! ([`crate::diagnose::estimate_noise_against`]). Above it, the fit either sits in a
//! local minimum (restarts from spread starts find a lower one, or disagree)
//! or the model cannot represent the data (restarts end at the same
//! minimum: [`Status::ModelInadequate`]).

use crate::status::Status;

/// A residual up to this many times the noise is consistent with it.
pub const NOISE_FACTOR: f64 = 1.5;

/// The output-error fit restarts when its residual exceeds this many times
/// the noise, stricter than [`NOISE_FACTOR`]: a local minimum close above the
/// noise (the flexible-clamp twin has them at 1.2-1.5 times) is cheap to
/// escape, while a fit at the global minimum sits at about 0.9-1.05 times
/// the roughness estimate of the noise.
pub const RESTART_ABOVE: f64 = 1.1;

/// Two minima whose costs differ by less than this fraction are taken as the
/// same minimum when restarts are compared.
pub const SAME_MINIMUM: f64 = 0.01;

/// Above this relative noise level the response function method is biased
/// (its equation error has measured data on both sides): at 1 % noise it
/// drove the two-material beam's parameters far off in every seed tried.
pub const RFM_NOISE_LIMIT: f64 = 0.002;

/// A parameter moved by more than this factor from its start is flagged.
pub const RUNAWAY_FACTOR: f64 = 100.0;

/// The status of a run from how its iteration ended (`raw`: converged,
/// stalled, iteration limit or failed), its residual as a multiple of the
/// noise (`None` when the noise is unknown) and, when restarts were made,
/// whether they agree about the minimum.
pub fn classify(raw: &Status, noise_ratio: Option<f64>, restarts_agree: Option<bool>) -> Status {
    let within = noise_ratio.is_none_or(|r| r <= NOISE_FACTOR);
    match raw {
        Status::Failed(_) | Status::MaxIterations => raw.clone(),
        _ if within => Status::Converged,
        _ => match restarts_agree {
            Some(true) => Status::ModelInadequate,
            Some(false) => Status::LocalMinimum,
            None => Status::Stalled,
        },
    }
}

/// Whether the data hold each parameter where a run left it: the run ends
/// within the noise (`status` is [`Status::Converged`], so the values
/// explain the data) and the parameter is neither on a bound (`at_bound`)
/// nor part of a combination the data cannot separate (`undetermined`).
pub fn held(status: &Status, at_bound: &[bool], undetermined: &[bool]) -> Vec<bool> {
    let within = *status == Status::Converged;
    at_bound.iter().zip(undetermined).map(|(&bound, &loose)| within && !bound && !loose).collect()
}

/// One warning per parameter that moved by more than [`RUNAWAY_FACTOR`]
/// either way from its initial value where the data do not hold it
/// (`held`, see [`held`]). How far a parameter moved says nothing by itself:
/// the monopile's mu starts 2e4 times its truth on purpose and the RFM brings
/// it there, to a misfit of 1e-13; a parameter the data hold is an estimate
/// however far it came.
pub fn runaways(names: &[String], initial: &[f64], updated: &[f64], held: &[bool]) -> Vec<String> {
    names
        .iter()
        .zip(initial.iter().zip(updated))
        .zip(held)
        .filter_map(|((name, (&p0, &p)), &held)| {
            let factor = p / p0;
            (!held && !(1.0 / RUNAWAY_FACTOR..=RUNAWAY_FACTOR).contains(&factor)).then(|| {
                format!("{name} moved by a factor of {factor:.3e} from its initial value: a run-away, not an estimate")
            })
        })
        .collect()
}

/// The status of a run whose values may include a parameter on its bound or
/// run away (`untrusted`): a run that would be converged is
/// [`Status::Runaway`], as its misfit within the noise does not make such a
/// value an estimate; any other keeps its status, already not a success.
pub fn with_parameters(status: Status, untrusted: bool) -> Status {
    match status {
        Status::Converged if untrusted => Status::Runaway,
        other => other,
    }
}

/// Point `i` (from 1) of the Halton sequence in base `base`: a spread of
/// points in `[0, 1)` that fills the space evenly for every prefix.
pub(crate) fn halton(mut i: usize, base: usize) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= base as f64;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

/// The first primes, one Halton base per parameter (repeated beyond).
const PRIMES: [usize; 16] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53];

/// Start `i` (from 1) of the restarts: each parameter of `center` times a
/// factor between `1 / spread` and `spread`, spread evenly in log space
/// (Halton), then clipped into its bounds.
pub(crate) fn spread_start(center: &[f64], bounds: &[(f64, f64)], i: usize, spread: f64) -> Vec<f64> {
    center
        .iter()
        .enumerate()
        .map(|(j, &p)| {
            let u = halton(i, PRIMES[j % PRIMES.len()]);
            let v = p * (spread.ln() * (2.0 * u - 1.0)).exp();
            let (lo, hi) = bounds[j];
            v.clamp(lo, hi)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn converged_only_within_the_noise() {
        let stopped = Status::Converged;
        assert_eq!(classify(&stopped, Some(1.2), None), Status::Converged);
        assert_eq!(classify(&stopped, Some(1.49), Some(true)), Status::Converged);
        assert_eq!(classify(&stopped, None, None), Status::Converged);
        // a stationary point far above the noise is never called converged
        assert_eq!(classify(&stopped, Some(125.8), Some(true)), Status::ModelInadequate);
        assert_eq!(classify(&stopped, Some(125.8), Some(false)), Status::LocalMinimum);
        assert_eq!(classify(&stopped, Some(1.51), None), Status::Stalled);
        assert_eq!(classify(&Status::Stalled, Some(0.9), None), Status::Converged);
        assert_eq!(classify(&Status::Stalled, Some(3.0), None), Status::Stalled);
        // the limit and a failure stay what they are, even within the noise
        assert_eq!(classify(&Status::MaxIterations, Some(0.9), Some(true)), Status::MaxIterations);
        let failed = Status::Failed("x".into());
        assert_eq!(classify(&failed, Some(0.9), None), failed);
    }

    #[test]
    fn parameters_moved_more_than_a_hundredfold_are_flagged() {
        let names: Vec<String> = ["a", "b", "c", "d"].iter().map(|s| s.to_string()).collect();
        let w = runaways(&names, &[1.0, 1.0, 2.0, 1e-5], &[99.0, 0.009, 2.0, 1e10], &[false; 4]);
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].starts_with("b moved by a factor of 9.000e-3"), "{w:?}");
        assert!(w[1].starts_with("d moved by a factor of 1.000e15"), "{w:?}");
    }

    /// A parameter the data hold is an estimate however far it moved; one on
    /// a bound, in an unresolved combination or of a run above the noise is not.
    #[test]
    fn a_far_move_the_data_hold_is_no_runaway() {
        let names: Vec<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
        let (start, end) = ([34120.0, 1.0, 1.0], [1.706, 1e6, 1e-3]);
        let held_all = held(&Status::Converged, &[false, false, false], &[false, false, false]);
        assert_eq!(held_all, [true, true, true]);
        assert!(runaways(&names, &start, &end, &held_all).is_empty());
        let some = held(&Status::Converged, &[false, true, false], &[false, false, true]);
        let w = runaways(&names, &start, &end, &some);
        assert!(w.len() == 2 && w[0].starts_with("b moved") && w[1].starts_with("c moved"), "{w:?}");
        let above = held(&Status::Stalled, &[false; 3], &[false; 3]);
        assert_eq!(runaways(&names, &start, &end, &above).len(), 3);
    }

    #[test]
    fn a_converged_run_with_an_untrusted_parameter_is_a_runaway() {
        assert_eq!(with_parameters(Status::Converged, true), Status::Runaway);
        assert_eq!(with_parameters(Status::Converged, false), Status::Converged);
        assert_eq!(with_parameters(Status::Stalled, true), Status::Stalled);
        assert_eq!(with_parameters(Status::MaxIterations, true), Status::MaxIterations);
    }

    #[test]
    fn spread_starts_cover_the_range_in_log_space_and_keep_to_bounds() {
        let center = [1.0, 100.0];
        let bounds = [(0.5, 2.0), (1e-6, 1e6)];
        let starts: Vec<Vec<f64>> = (1..=8).map(|i| spread_start(&center, &bounds, i, 10.0)).collect();
        for s in &starts {
            assert!((0.5..=2.0).contains(&s[0]), "{s:?}");
            assert!((10.0..=1000.0).contains(&s[1]), "{s:?}");
        }
        // both sides of the centre, and no two starts alike
        assert!(starts.iter().any(|s| s[1] < 50.0) && starts.iter().any(|s| s[1] > 200.0));
        for (a, b) in starts.iter().zip(starts.iter().skip(1)) {
            assert_ne!(a, b);
        }
        assert_eq!(halton(1, 2), 0.5);
        assert_eq!(halton(3, 2), 0.75);
        assert!((halton(2, 3) - 2.0 / 3.0).abs() < 1e-15);
    }
}
