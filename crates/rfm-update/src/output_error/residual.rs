//! The residuals of the output-error fit and their Jacobian at a point:
//! weighted, relative or complex-log, with a gain per reference or per
//! channel; and the correlation of adjacent residuals.

use faer::Mat;
use fe_model::case::{GainKey, Gains};
use num_complex::Complex64 as C64;

use super::{Misfit, OeData, OeOptions, Response};
use crate::error::UpdateError;

/// The principal complex logarithm, with `ln |z|` from `|z|^2` where that
/// neither overflows nor underflows: `Complex::ln` takes `|z|` by `hypot`,
/// which dominated the misfit of the diagnosis's many small fits.
#[inline]
fn ln(z: C64) -> C64 {
    let r2 = z.norm_sqr();
    if r2.is_normal() { C64::new(0.5 * r2.ln(), z.im.atan2(z.re)) } else { z.ln() }
}

pub(super) struct Evaluator<'a> {
    pub(super) data: &'a OeData<'a>,
    pub(super) opts: &'a OeOptions,
    /// Gain index of each channel ([`crate::gain::gain_groups`]).
    pub(super) group_of: Vec<usize>,
    /// What each gain belongs to.
    pub(super) keys: Vec<GainKey>,
    pub(super) p0: Vec<f64>,
    /// The weight of each value, channel-major as the data (0 where the
    /// measured value is zero or not finite), read once: the diagnosis
    /// evaluates tens of thousands of fits.
    weights: Vec<f64>,
}

pub(super) struct Point {
    pub(super) residual: Vec<f64>,
    pub(super) cost_data: f64,
    pub(super) cost: f64,
    pub(super) jacobian: Option<Mat<f64>>,
}

impl<'a> Evaluator<'a> {
    pub(super) fn new(
        data: &'a OeData<'a>,
        opts: &'a OeOptions,
        group_of: Vec<usize>,
        keys: Vec<GainKey>,
        p0: Vec<f64>,
    ) -> Self {
        let m = data.measured;
        let nf = m.n_freq();
        let weights = (0..m.channels().len())
            .flat_map(|c| (0..nf).map(move |k| (c, k)))
            .map(|(c, k)| {
                let w = data.weights.map_or(1.0, |w| w[c * nf + k]);
                let v = m.get(c, k);
                if v.norm() > 0.0 && v.norm().is_finite() { w } else { 0.0 }
            })
            .collect();
        Evaluator { data, opts, group_of, keys, p0, weights }
    }

    pub(super) fn n_params(&self) -> usize {
        self.p0.len()
    }

    pub(super) fn n_gain(&self) -> usize {
        if self.opts.gains != Gains::None { 2 * self.keys.len() } else { 0 }
    }

    pub(super) fn weight(&self, c: usize, k: usize) -> f64 {
        self.weights[c * self.data.measured.n_freq() + k]
    }

    pub(super) fn n_data(&self) -> usize {
        2 * self.weights.iter().filter(|&&w| w > 0.0).count()
    }

    /// Sets the model to `theta` (structural part of `x`).
    pub(super) fn apply(&self, src: &mut impl Response, x: &[f64]) -> Result<(), UpdateError> {
        let values: Vec<f64> = self.p0.iter().zip(x).map(|(p, t)| p * t.exp()).collect();
        src.set(&values)
    }

    pub(super) fn gain(&self, x: &[f64], v: usize) -> C64 {
        if self.opts.gains != Gains::None {
            let n = self.n_params();
            C64::new(x[n + 2 * v], x[n + 2 * v + 1]).exp()
        } else {
            C64::new(1.0, 0.0)
        }
    }

    /// Residuals (and optionally the Jacobian) at `x`; `None` when the model
    /// cannot be evaluated there.
    pub(super) fn eval(&self, src: &mut impl Response, x: &[f64], jacobian: bool) -> Option<Point> {
        self.apply(src, x).ok()?;
        let m = self.data.measured;
        let lines = m.frequencies_hz();
        let (nf, nc, n) = (lines.len(), m.channels().len(), self.n_params());
        let ncol = n + self.n_gain();
        // model FRFs [line][channel] and per-parameter sensitivities
        let (model, sens) = src.evaluate(lines, jacobian)?;
        if model.len() != nf || model.iter().any(|h| h.len() != nc) {
            return None;
        }
        let n_reg = if self.opts.regularization > 0.0 { n } else { 0 };
        let rows = nf * nc;
        let mut residual = vec![0.0; 2 * rows + n_reg];
        let mut jac = jacobian.then(|| Mat::<f64>::zeros(2 * rows + n_reg, ncol));
        let mut cost_data = 0.0;
        // each gain once, not once per value
        let gains: Vec<C64> = (0..self.keys.len().max(1)).map(|v| self.gain(x, v)).collect();
        for k in 0..nf {
            for c in 0..nc {
                let w = self.weight(c, k);
                if w == 0.0 {
                    continue;
                }
                let r = k * nc + c;
                let g = gains[self.group_of[c]];
                let h = model[k][c];
                let meas = m.get(c, k);
                let rho = match self.opts.misfit {
                    Misfit::Relative => w * (g * h - meas) / meas.norm(),
                    Misfit::Log => w * ln(g * h / meas),
                };
                if !(rho.re.is_finite() && rho.im.is_finite()) {
                    return None;
                }
                residual[r] = rho.re;
                residual[rows + r] = rho.im;
                cost_data += rho.norm_sqr();
            }
        }
        if let (Some(j), Some(s)) = (jac.as_mut(), sens.as_ref()) {
            // column by column, each written in order: the values of a line
            // and channel scattered over the columns in turn were most of
            // the evaluation on many channels (the same numbers either way)
            for i in 0..n {
                for k in 0..nf {
                    for c in 0..nc {
                        let w = self.weight(c, k);
                        if w == 0.0 {
                            continue;
                        }
                        let r = k * nc + c;
                        let d = match self.opts.misfit {
                            Misfit::Relative => -w * gains[self.group_of[c]] * s[k][(c, i)] / m.get(c, k).norm(),
                            Misfit::Log => -w * s[k][(c, i)] / model[k][c],
                        };
                        j[(r, i)] = d.re;
                        j[(rows + r, i)] = d.im;
                    }
                }
            }
            if self.opts.gains != Gains::None {
                // a gain's two columns: its log-magnitude and its phase, on its channels only
                for v in 0..self.keys.len() {
                    let members: Vec<usize> = (0..nc).filter(|&c| self.group_of[c] == v).collect();
                    for part in 0..2 {
                        let i = n + 2 * v + part;
                        for k in 0..nf {
                            for &c in &members {
                                let w = self.weight(c, k);
                                if w == 0.0 {
                                    continue;
                                }
                                let r = k * nc + c;
                                let da = match self.opts.misfit {
                                    Misfit::Relative => w * gains[v] * model[k][c] / m.get(c, k).norm(),
                                    Misfit::Log => C64::new(w, 0.0),
                                };
                                let d = if part == 0 { da } else { da * C64::new(0.0, 1.0) };
                                j[(r, i)] = d.re;
                                j[(rows + r, i)] = d.im;
                            }
                        }
                    }
                }
            }
        }
        let mut cost = cost_data;
        if n_reg > 0 {
            let s = self.opts.regularization.sqrt();
            for i in 0..n {
                residual[2 * rows + i] = s * x[i];
                cost += (s * x[i]).powi(2);
                if let Some(j) = jac.as_mut() {
                    j[(2 * rows + i, i)] = s;
                }
            }
        }
        Some(Point { residual, cost_data, cost, jacobian: jac })
    }
}

/// Lag-one correlation along the lines of residuals laid out as the
/// evaluator writes them (real parts `[line * nc + channel]`, then the
/// imaginary parts); see [`super::OeResult::residual_correlation`].
pub(super) fn adjacent_correlation(residual: &[f64], nf: usize, nc: usize) -> f64 {
    let rows = nf * nc;
    let (mut num, mut den) = (0.0, 0.0);
    for part in [0, rows] {
        for c in 0..nc {
            for k in 0..nf {
                let r = residual[part + k * nc + c];
                den += r * r;
                if k + 1 < nf {
                    num += r * residual[part + (k + 1) * nc + c];
                }
            }
        }
    }
    if den > 0.0 { num / den } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacent_correlation_is_one_for_a_smooth_misfit_and_small_for_noise() {
        let (nf, nc) = (200, 2);
        let smooth: Vec<f64> = (0..2 * nf * nc).map(|i| 1.0 + 1e-3 * (i / nc) as f64).collect();
        assert!(adjacent_correlation(&smooth, nf, nc) > 0.99);
        // alternating signs along the lines: anti-correlated
        let alternating: Vec<f64> = (0..2 * nf * nc).map(|i| if (i / nc) % 2 == 0 { 1.0 } else { -1.0 }).collect();
        assert!(adjacent_correlation(&alternating, nf, nc) < -0.99);
        let mut state = 12345u64;
        let noise: Vec<f64> = (0..2 * nf * nc)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        assert!(adjacent_correlation(&noise, nf, nc).abs() < 0.1);
    }

    /// The fast logarithm agrees with `Complex::ln` over every magnitude a
    /// ratio of receptances can take, including where `|z|^2` would
    /// overflow or underflow, and on both sides of the branch cut.
    #[test]
    fn fast_log_equals_the_complex_log() {
        for mag in [1e-300, 1e-160, 1e-20, 1e-3, 0.5, 1.0, 3.0, 1e40, 1e160, 1e300] {
            for angle in [-3.1, -2.0, -0.3, 0.0, 0.7, 1.6, 3.0, std::f64::consts::PI] {
                let z = C64::from_polar(mag, angle);
                let (got, want) = (ln(z), z.ln());
                assert!((got - want).norm() <= 1e-14 * want.norm().max(1.0), "ln({z}) = {got}, want {want}");
            }
        }
        let below_cut = C64::new(-2.0, -0.0);
        assert_eq!(ln(below_cut).im, below_cut.ln().im);
    }
}
