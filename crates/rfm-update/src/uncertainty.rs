//! Parameter uncertainty and identifiability at an output-error solution.
//!
//! With log-parameters `theta_i = ln(p_i / p_i0)` and covariance `C` of theta
//! (see [`crate::oe`]), parameter `i` has relative standard deviation
//! `s_i = sqrt(C_ii)`, standard deviation about `p_i s_i`, and the 95 %
//! interval `p_i exp(-1.96 s_i) .. p_i exp(1.96 s_i)` (asymmetric, as a
//! positive parameter's should be). Correlations are `C_ij / sqrt(C_ii C_jj)`.
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

use faer::Mat;
use fe_model::Quantity;
use serde::Serialize;

use crate::oe::OeResult;
use crate::params::ParameterSet;

/// Uncertainty of one parameter.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterUncertainty {
    /// Name.
    pub name: String,
    /// Fitted value.
    pub value: f64,
    /// Standard deviation (physical units, first order).
    pub std: f64,
    /// Relative standard deviation (standard deviation of `ln p`).
    pub relative_std: f64,
    /// 95 % interval.
    pub interval95: (f64, f64),
    /// Ended on a bound.
    pub at_bound: bool,
    /// False when any warning says the data determine it only weakly.
    pub well_determined: bool,
    /// Why it is weakly determined (empty when it is well determined).
    pub warnings: Vec<String>,
}

/// Uncertainty of a whole fit.
#[derive(Clone, Debug, Serialize)]
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
}

/// Analyses an output-error result; `band_hz` is the fitted band.
pub fn analyse(params: &ParameterSet, result: &OeResult, band_hz: (f64, f64)) -> UncertaintyReport {
    let n = params.len();
    let c = &result.covariance;
    let (w_min, w_max) = (2.0 * std::f64::consts::PI * band_hz.0, 2.0 * std::f64::consts::PI * band_hz.1);
    let mut out = Vec::with_capacity(n);
    for (i, p) in params.params().iter().enumerate() {
        let value = result.values[i];
        let s = c[(i, i)].max(0.0).sqrt();
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
    if let Some(w) = unresolved_combination(&result.singular_values, &result.v, &names) {
        warnings.push(w);
    }
    UncertaintyReport { parameters: out, correlation, warnings, residual_rms: (2.0 * result.sigma2).sqrt() }
}

/// Names the parameter combination along the weakest direction of a
/// column-scaled sensitivity matrix (singular values `sv`, right singular
/// vectors as the columns of `v`, one row per parameter of `names`) when it
/// is nearly singular: its smallest singular value is below 1e-6 of the
/// largest. Also used for the response function method.
pub(crate) fn unresolved_combination(sv: &[f64], v: &Mat<f64>, names: &[String]) -> Option<String> {
    let n = names.len();
    let smax = sv.first().copied()?;
    let (k, &smin) = sv.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    if smax == 0.0 || smin > 1e-6 * smax {
        return None;
    }
    let mut parts: Vec<(f64, usize)> = (0..n.min(v.nrows())).map(|i| (v[(i, k)], i)).collect();
    parts.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
    let terms: Vec<String> = parts
        .iter()
        .take(3)
        .filter(|(c, _)| c.abs() > 0.1)
        .map(|(c, i)| format!("{:+.2} ln({})", c, names[*i]))
        .collect();
    Some(format!(
        "the data cannot separate the combination {} (singular value ratio {:.1e})",
        terms.join(" "),
        smin / smax
    ))
}
