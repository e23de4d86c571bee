//! Parameter uncertainty and identifiability at an output-error solution.
//!
//! With log-parameters `theta_i = ln(p_i / p_i0)` and covariance `C` of theta
//! (see [`crate::output_error`]), parameter `i` has relative standard deviation
//! `s_i = sqrt(C_ii)`, standard deviation about `p_i s_i`, and the 95 %
//! interval `p_i exp(-1.96 s_i) .. p_i exp(1.96 s_i)` (asymmetric, as a
//! positive parameter's should be). Correlations are `C_ij / sqrt(C_ii C_jj)`.
//!
//! Two standard deviations are reported. The noise-only one scales the
//! covariance by the data's noise variance (estimated from their roughness,
//! [`crate::diagnose::estimate_noise`], or from the residual when that is
//! smaller); it is right when the model explains the data down to their
//! noise. When it does not, the residual holds model
//! error as well, which is neither small nor independent from line to line,
//! and the noise-only value shrinks as `1 / sqrt(lines)` however wrong the
//! model. The standard deviation shown first ([`ParameterUncertainty::std`],
//! used in every "within N standard deviations" statement) therefore
//! includes model error: the noise-only one times at least
//! `sqrt(chi2 / dof)` (the covariance scaled by the residual variance the
//! fit leaves, when that is larger than the noise), times
//! `sqrt((1 + rho) / (1 - rho))` when the residuals at adjacent lines are
//! correlated with coefficient `rho` (an AR(1) residual of `n` values
//! carries the information of about `n (1 - rho) / (1 + rho)` independent
//! ones), where `rho` is larger than its noise-only spread `2 / sqrt(n)`.
//! Neither factor sees how model error pulls a parameter: a residual only
//! 1.3 times the noise can hold an error that moves a stiffness by many
//! noise-only standard deviations. Where either factor exceeds 1, the
//! standard deviation is at least the delete-a-block jackknife's
//! ([`crate::jackknife`]): the spread of the estimates with each part of
//! the band left out, which model error makes wide and noise does not.
//!
//! The data do not determine every parameter well. Each is flagged as weakly
//! determined, with the reason, when:
//! - its relative standard deviation exceeds 30 %;
//! - it is a relaxation parameter `mu` far above the measured band
//!   (`mu > 10 w_max`: the kernel is viscous there, mu barely matters) or
//!   far below it (`mu < w_min / 10`: only the product `alpha mu`, a
//!   stiffness, is seen);
//! - it ended on one of its bounds.
//!
//! The report also names pairs with correlation above 0.95 and, when the
//! scaled Jacobian is nearly singular, the parameter combination it cannot
//! resolve.

use fe_model::Quantity;

use crate::lstsq;
use crate::output_error::OeResult;
use crate::params::ParameterSet;

/// Uncertainty of one parameter.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ParameterUncertainty {
    /// Name.
    pub name: String,
    /// Fitted value.
    pub value: f64,
    /// Standard deviation including model error (physical units, first
    /// order): the one shown first; see the module docs.
    pub std: f64,
    /// Relative standard deviation including model error (standard
    /// deviation of `ln p`).
    pub relative_std: f64,
    /// Standard deviation from the noise alone (physical units).
    pub std_noise: f64,
    /// Relative standard deviation from the noise alone.
    pub relative_std_noise: f64,
    /// 95 % interval (from the standard deviation with model error).
    pub interval95: (f64, f64),
    /// Ended on a bound.
    pub at_bound: bool,
    /// False when any warning says the data determine it only weakly.
    pub well_determined: bool,
    /// Why it is weakly determined (empty when it is well determined).
    pub warnings: Vec<String>,
}

/// Uncertainty of a whole fit.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct UncertaintyReport {
    /// Per parameter.
    pub parameters: Vec<ParameterUncertainty>,
    /// Correlation matrix of the parameters (row-major, square).
    pub correlation: Vec<Vec<f64>>,
    /// Warnings about combinations of parameters.
    pub warnings: Vec<String>,
    /// Estimated RMS residual per complex value (the noise level the fit
    /// leaves, relative for the relative and log misfits).
    pub residual_rms: f64,
    /// Which standard deviation `std` is, in words (shown with the table).
    pub shown_first: String,
    /// `chi2 / dof`: the residual variance over the noise variance (`None`
    /// when the noise is unknown).
    pub chi2_per_dof: Option<f64>,
    /// Correlation of the residuals at adjacent lines.
    pub residual_correlation: f64,
    /// `std / std_noise`, the same for every parameter.
    pub inflation: f64,
}

/// The factor by which the standard deviation with model error exceeds the
/// noise-only one, for a residual RMS per complex value `residual_rms`,
/// noise level `noise`, lag-one residual correlation `rho` over `n` real
/// residuals; see the module docs.
pub fn model_error_inflation(residual_rms: f64, noise: Option<f64>, rho: f64, n: usize) -> f64 {
    let lack_of_fit = noise.filter(|&s| s > 0.0).map_or(1.0, |s| (residual_rms / s).max(1.0));
    let spread = 2.0 / (n.max(1) as f64).sqrt();
    let correlated = if rho > spread {
        let r = rho.min(0.999);
        ((1.0 + r) / (1.0 - r)).sqrt()
    } else {
        1.0
    };
    lack_of_fit * correlated
}

/// Analyses an output-error result; `band_hz` is the fitted band, `noise`
/// the data's relative noise level when known.
pub fn analyse(params: &ParameterSet, result: &OeResult, band_hz: (f64, f64), noise: Option<f64>) -> UncertaintyReport {
    let n = params.len();
    let c = &result.covariance;
    let residual_rms = (2.0 * result.sigma2).sqrt();
    // the covariance is scaled by the residual variance: rescale it to the
    // noise's for the noise-only value
    // noise for the noise-only value, when the fit leaves more than that
    // (below it, the residual's own variance is the better noise estimate)
    let to_noise = noise.filter(|&s| s > 0.0 && residual_rms > 0.0).map_or(1.0, |s| (s / residual_rms).min(1.0));
    let inflation = model_error_inflation(residual_rms, noise, result.residual_correlation, result.n_data / 2);
    let (w_min, w_max) = (2.0 * std::f64::consts::PI * band_hz.0, 2.0 * std::f64::consts::PI * band_hz.1);
    let mut out = Vec::with_capacity(n);
    for (i, p) in params.params().iter().enumerate() {
        let value = result.values[i];
        let s_noise = c[(i, i)].max(0.0).sqrt() * to_noise;
        // where the residual shows model error, the spread of the estimates
        // over the band's parts too, when it is the larger
        let s_jack = result.jackknife.as_ref().filter(|_| inflation > 1.0).map_or(0.0, |j| j[(i, i)].max(0.0).sqrt());
        let s = (s_noise * inflation).max(s_jack);
        let mut warnings = Vec::new();
        if result.at_bound[i] {
            warnings.push("ended on its bound; its uncertainty is not meaningful".to_string());
        }
        if !s.is_finite() {
            warnings.push("not determined by the data at all: the FRFs do not depend on it".to_string());
        } else if s > 10.0 {
            warnings.push("not determined by the data at all (its standard deviation is unbounded)".to_string());
        } else if s > 0.3 {
            warnings.push(format!("poorly determined by the data (+-{:.0} % at one standard deviation)", 100.0 * s));
        }
        if let Quantity::GroupMu(_) = p.quantities[0] {
            if value > 10.0 * w_max {
                warnings.push(format!(
                    "mu = {value:.4e} rad/s lies far above the measured band (up to {w_max:.4e} rad/s): the kernel is nearly viscous there and mu shows only through a second-order effect"
                ));
            } else if value < w_min / 10.0 {
                warnings.push(format!(
                    "mu = {value:.4e} rad/s lies far below the measured band (from {w_min:.4e} rad/s): the kernel acts as a stiffness alpha*mu*K there; alpha and mu are not separable"
                ));
            }
        }
        out.push(ParameterUncertainty {
            name: p.name.clone(),
            value,
            std: value * s,
            relative_std: s,
            std_noise: value * s_noise,
            relative_std_noise: s_noise,
            interval95: if s.is_finite() {
                (value * (-1.96 * s).exp(), value * (1.96 * s).exp())
            } else {
                (0.0, f64::INFINITY)
            },
            at_bound: result.at_bound[i],
            well_determined: warnings.is_empty(),
            warnings,
        });
    }
    let correlation: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let d = (c[(i, i)] * c[(j, j)]).sqrt();
                    if d > 0.0 {
                        c[(i, j)] / d
                    } else if i == j {
                        1.0
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let mut warnings = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            if correlation[i][j].abs() > 0.95 {
                warnings.push(format!(
                    "{} and {} are strongly correlated (rho = {:+.3}): the data determine a combination of them, not each",
                    out[i].name, out[j].name, correlation[i][j]
                ));
            }
        }
    }
    let names: Vec<String> = out.iter().map(|p| p.name.clone()).collect();
    if let Some(w) = lstsq::unresolved_combination(&result.singular_values, &result.v, &names) {
        warnings.push(w);
    }
    let chi2_per_dof = noise.filter(|&s| s > 0.0).map(|s| (residual_rms / s).powi(2));
    let shown_first = if inflation > 1.0 {
        format!(
            "with model error: the noise-only standard deviation times {inflation:.2} (the fit leaves {:.2} times the \
             noise, adjacent residuals correlated {:.2}){}",
            chi2_per_dof.map_or(1.0, f64::sqrt),
            result.residual_correlation,
            if result.jackknife.is_some() {
                ", or the spread of the estimates with each block of adjacent lines left out (jackknife) where that is larger"
            } else {
                ""
            }
        )
    } else {
        "with model error, which adds nothing here: the residual is at the noise level and uncorrelated".to_string()
    };
    UncertaintyReport {
        parameters: out,
        correlation,
        warnings,
        residual_rms,
        shown_first,
        chi2_per_dof,
        residual_correlation: result.residual_correlation,
        inflation,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inflation_is_the_lack_of_fit_times_the_correlation_of_adjacent_residuals() {
        // at the noise and white: nothing added
        assert_eq!(model_error_inflation(0.01, Some(0.01), 0.0, 400), 1.0);
        assert_eq!(model_error_inflation(0.008, Some(0.01), 0.05, 400), 1.0);
        // 10 times the noise: at least sqrt(chi2 / dof) = 10
        assert!((model_error_inflation(0.1, Some(0.01), 0.0, 400) - 10.0).abs() < 1e-12);
        // correlated residuals: fewer independent lines, (1 + rho) / (1 - rho) = 19
        let f = model_error_inflation(0.1, Some(0.01), 0.9, 400);
        assert!((f - 10.0 * 19f64.sqrt()).abs() < 1e-9, "{f}");
        // unknown noise: the correlation alone
        assert!((model_error_inflation(0.1, None, 0.6, 400) - 2.0).abs() < 1e-12);
        // a noise level of zero is no noise level: the correlation alone
        assert!((model_error_inflation(0.1, Some(0.0), 0.6, 400) - 2.0).abs() < 1e-12);
        // a correlation within white noise's spread 2 / sqrt(n), at its edge too, adds nothing
        assert_eq!(model_error_inflation(0.1, None, 0.5, 16), 1.0);
        assert!(model_error_inflation(0.1, None, 0.51, 16) > 1.7);
    }

    /// An output-error result with the given covariance of the
    /// log-parameters, residual RMS `r` over `n_data` real residuals,
    /// lag-one correlation `rho` and jackknife covariance.
    fn fit(values: [f64; 2], cov: [[f64; 2]; 2], r: f64, n_data: usize, rho: f64, jack: Option<[f64; 2]>) -> OeResult {
        use faer::Mat;
        OeResult {
            status: crate::status::Status::Converged,
            flat_valley: false,
            values: values.to_vec(),
            gains: Vec::new(),
            history: Vec::new(),
            cost: 0.0,
            n_data,
            covariance: Mat::from_fn(2, 2, |i, j| cov[i][j]),
            sigma2: r * r / 2.0,
            jackknife: jack.map(|d| Mat::from_fn(2, 2, |i, j| if i == j { d[i] } else { 0.0 })),
            singular_values: Vec::new(),
            v: Mat::zeros(2, 0),
            at_bound: vec![false, true],
            residual_correlation: rho,
        }
    }

    /// The standard deviations, intervals, correlations and flags of
    /// `analyse` against the module docs' formulas, worked by hand.
    #[test]
    fn analyse_scales_to_the_noise_inflates_for_model_error_and_flags_as_documented() {
        let sys = damping::DampedSystem::new(fe_model::samples::two_material_cantilever()).unwrap();
        let q = |n: &str| sys.model().quantity(n).unwrap();
        let params = ParameterSet::of_quantities(&sys, &[q("group.steel.mu"), q("group.steel.alpha")]);
        // the band 2..100 Hz: w_min = 4 pi, w_max = 200 pi rad/s
        let band = (2.0, 100.0);
        let w_max = 200.0 * std::f64::consts::PI;
        // relative sd 0.02 and 0.1 at the residual's variance, correlated 0.98
        let cov = [[4e-4, 1.96e-3], [1.96e-3, 1e-2]];
        let values = [5.0 * w_max, 2e-5];
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-12;

        // the residual twice the noise, white: noise-only sd half the
        // residual's, shown sd twice that (the lack of fit)
        let rep = analyse(&params, &fit(values, cov, 0.02, 200, 0.0, None), band, Some(0.01));
        let p = &rep.parameters;
        assert!(close(p[0].relative_std_noise, 0.01) && close(p[1].relative_std_noise, 0.05), "{p:?}");
        assert!(close(p[0].relative_std, 0.02) && close(p[1].relative_std, 0.1));
        assert!(close(p[0].std, values[0] * 0.02) && close(p[1].std_noise, values[1] * 0.05));
        assert!(close(rep.inflation, 2.0) && close(rep.chi2_per_dof.unwrap(), 4.0));
        assert!(
            rep.shown_first.starts_with(
                "with model error: the noise-only standard deviation times 2.00 (the fit leaves 2.00 times"
            ),
            "{}",
            rep.shown_first
        );
        let (lo, hi) = p[1].interval95;
        assert!(close(lo, 2e-5 * (-0.196f64).exp()) && close(hi, 2e-5 * 0.196f64.exp()));
        assert!(close(rep.correlation[0][1], 0.98) && close(rep.correlation[1][0], 0.98));
        assert_eq!((rep.correlation[0][0], rep.correlation[1][1]), (1.0, 1.0));
        // one warning for the one pair (none for a parameter with itself)
        let pairs: Vec<_> = rep.warnings.iter().filter(|w| w.contains("strongly correlated")).collect();
        assert!(pairs.len() == 1 && pairs[0].contains("(rho = +0.980)"), "{:?}", rep.warnings);
        // the second parameter ended on its bound; the first is within the band's reach
        assert!(p[0].warnings.is_empty() && p[0].well_determined, "{:?}", p[0].warnings);
        assert!(p[1].warnings.iter().any(|w| w.contains("ended on its bound")) && !p[1].well_determined);

        // noise above the residual: the residual's variance is the noise's, nothing inflated
        for noise in [Some(0.04), None, Some(0.0)] {
            let rep = analyse(&params, &fit(values, cov, 0.02, 200, 0.0, None), band, noise);
            let p = &rep.parameters;
            assert!(close(p[0].relative_std_noise, 0.02) && close(p[0].relative_std, 0.02), "{noise:?}: {p:?}");
            assert_eq!(rep.inflation, 1.0, "{noise:?}");
            assert!(rep.shown_first.contains("which adds nothing here"), "{noise:?}: {}", rep.shown_first);
            // a noise level of zero is no noise level: no chi2
            assert_eq!(rep.chi2_per_dof.is_some(), noise == Some(0.04), "{noise:?}");
        }

        // correlated residuals over n_data / 2 = 100 complex values (spread
        // 0.2): 0.15 adds nothing, 0.3 adds sqrt(1.3 / 0.7)
        let quiet = analyse(&params, &fit(values, cov, 0.02, 200, 0.15, None), band, None);
        assert_eq!(quiet.inflation, 1.0);
        let loud = analyse(&params, &fit(values, cov, 0.02, 200, 0.3, None), band, None);
        assert!(close(loud.inflation, (1.3f64 / 0.7).sqrt()));

        // the jackknife's spread counts only where model error shows
        let jack = Some([0.09, 0.09]);
        let white = analyse(&params, &fit(values, cov, 0.02, 200, 0.0, jack), band, None);
        assert!(close(white.parameters[0].relative_std, 0.02));
        let off = analyse(&params, &fit(values, cov, 0.02, 200, 0.3, jack), band, None);
        assert!(close(off.parameters[0].relative_std, 0.3) && close(off.parameters[1].relative_std, 0.3));

        // the first fit with another covariance, white residuals and no noise level
        let with_cov = |cov: [[f64; 2]; 2]| analyse(&params, &fit(values, cov, 0.02, 200, 0.0, None), band, None);
        // how well determined: 0.5 poorly, 20 unbounded, infinite not at all
        for (var, words) in [
            (0.25, "poorly determined by the data (+-50 %"),
            (400.0, "its standard deviation is unbounded"),
            (f64::INFINITY, "the FRFs do not depend on it"),
        ] {
            let rep = with_cov([[var, 0.0], [0.0, 1e-2]]);
            assert!(rep.parameters[0].warnings.iter().any(|w| w.contains(words)), "{words}: {:?}", rep.parameters[0]);
        }
        let rep = with_cov([[f64::INFINITY, 0.0], [0.0, 1e-2]]);
        assert_eq!(rep.parameters[0].interval95, (0.0, f64::INFINITY));
        // exactly 0.3 (sqrt(0.09) is 0.3 in floating point) is not yet poor
        let rep = with_cov([[0.09, 0.0], [0.0, 1e-2]]);
        assert_eq!(rep.parameters[0].relative_std, 0.3);
        assert!(rep.parameters[0].warnings.is_empty(), "{:?}", rep.parameters[0]);
        // a standard deviation of exactly 10 is still a number, +-1000 %
        let rep = with_cov([[100.0, 0.0], [0.0, 1e-2]]);
        assert!(rep.parameters[0].warnings.iter().any(|w| w.contains("+-1000 %")), "{:?}", rep.parameters[0]);

        // a parameter the fit pins exactly (zero variance) correlates with
        // nothing and fully with itself, not 0 / 0
        let rep = with_cov([[0.0, 0.0], [0.0, 1e-2]]);
        assert_eq!(rep.correlation, vec![vec![1.0, 0.0], vec![0.0, 1.0]]);
        // correlated 0.95 exactly is not yet "strongly"
        let rep = with_cov([[1.0, 0.95], [0.95, 1.0]]);
        assert_eq!(rep.correlation[0][1], 0.95);
        assert!(!rep.warnings.iter().any(|w| w.contains("strongly correlated")), "{:?}", rep.warnings);

        // mu beyond ten times the band's top, or below a tenth of its bottom
        // (at those limits exactly, within reach)
        let w_min = 4.0 * std::f64::consts::PI;
        for (mu, words) in [
            (10.01 * w_max, Some("lies far above the measured band")),
            (9.99 * w_max, None),
            (10.0 * w_max, None),
            (0.0999 * w_min, Some("lies far below the measured band")),
            (0.1001 * w_min, None),
            (w_min / 10.0, None),
        ] {
            let rep = analyse(&params, &fit([mu, 2e-5], cov, 0.02, 200, 0.0, None), band, None);
            let w = &rep.parameters[0].warnings;
            match words {
                Some(words) => assert!(w.iter().any(|x| x.contains(words)), "mu {mu}: {w:?}"),
                None => assert!(w.is_empty(), "mu {mu}: {w:?}"),
            }
        }
    }
}
