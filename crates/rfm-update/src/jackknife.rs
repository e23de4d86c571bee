//! The delete-a-block jackknife of a least-squares fit over frequency lines:
//! the spread of the estimates the fit would give with each block of
//! adjacent lines left out.
//!
//! The covariance `sigma^2 (J^T J)^-1` is right when the residuals are
//! independent noise. When the model cannot represent the data, the residual
//! is model error as well, smooth along the lines and different from one
//! part of the band to another, and each part pulls the parameters its own
//! way. Leaving out one block of lines at a time and watching the estimate
//! move measures that directly, whatever the residual's correlation: blocks
//! of adjacent lines keep the correlation inside a block (the delete-a-group
//! jackknife for dependent data). It needs no model of the error; it
//! overstates the spread a little for independent noise, which is why the
//! uncertainty report uses it only where the residual shows model error
//! ([`crate::uncertainty`]).
//!
//! Each left-out estimate is one Gauss-Newton step from the full fit with
//! the block's rows removed: at the full optimum `J^T r = 0`, so without
//! block `k` the gradient is `-J_k^T r_k` and the step is
//! `argmin |J_(-k) d + r_(-k)|`. For a problem linear in its parameters the
//! step lands exactly on the refit without the block (the test below
//! checks it against refits solved from scratch).

use faer::Mat;

use crate::lstsq;

/// Number of blocks the lines are cut into (fewer when there are fewer than
/// [`MIN_LINES_PER_BLOCK`] lines per block).
pub const BLOCKS: usize = 16;

/// Fewest lines in a block.
pub const MIN_LINES_PER_BLOCK: usize = 2;

/// The jackknife covariance of the parameters of a least-squares fit at its
/// optimum, from the Jacobian `jac` and residual `residual` laid out as the
/// output-error evaluator writes them (real parts `[line * nc + channel]`
/// for `nf` lines and `nc` channels, then the imaginary parts in the same
/// order). Columns flagged in `fixed` (parameters held on a bound) do not
/// move. `None` when the lines are too few for [`MIN_LINES_PER_BLOCK`] in
/// at least 4 blocks.
pub fn block_covariance(
    jac: &Mat<f64>,
    residual: &[f64],
    nf: usize,
    nc: usize,
    fixed: &[bool],
    rcond: f64,
) -> Option<Mat<f64>> {
    let m = jac.ncols();
    assert_eq!(jac.nrows(), 2 * nf * nc, "two real rows per line and channel");
    assert_eq!(residual.len(), jac.nrows());
    let k = BLOCKS.min(nf / MIN_LINES_PER_BLOCK);
    if k < 4 {
        return None;
    }
    let block_of = |line: usize| line * k / nf;
    let steps: Vec<Vec<f64>> = (0..k)
        .map(|b| {
            let rows: Vec<usize> = (0..jac.nrows()).filter(|&r| block_of((r % (nf * nc)) / nc) != b).collect();
            let a = Mat::from_fn(rows.len(), m, |i, j| {
                if fixed.get(j).copied().unwrap_or(false) { 0.0 } else { jac[(rows[i], j)] }
            });
            let minus_r: Vec<f64> = rows.iter().map(|&r| -residual[r]).collect();
            lstsq::solve(&a, &minus_r, rcond).x
        })
        .collect();
    let mean: Vec<f64> = (0..m).map(|j| steps.iter().map(|d| d[j]).sum::<f64>() / k as f64).collect();
    let scale = (k - 1) as f64 / k as f64;
    Some(Mat::from_fn(m, m, |i, j| scale * steps.iter().map(|d| (d[i] - mean[i]) * (d[j] - mean[j])).sum::<f64>()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight line `y = a + b f` fitted to the values of a curve at `nf`
    /// lines (one channel, real and imaginary parts both the curve).
    fn line_fit(nf: usize, curve: impl Fn(f64) -> f64) -> (Mat<f64>, Vec<f64>, Vec<f64>) {
        let f: Vec<f64> = (0..nf).map(|i| i as f64 / (nf - 1) as f64).collect();
        let rows = 2 * nf;
        let jac = Mat::from_fn(rows, 2, |r, j| if j == 0 { 1.0 } else { f[r % nf] });
        let y: Vec<f64> = (0..rows).map(|r| curve(f[r % nf])).collect();
        let fit = lstsq::solve(&jac, &y, 1e-12).x;
        // residual = model - data
        let residual: Vec<f64> = (0..rows).map(|r| fit[0] + fit[1] * f[r % nf] - y[r]).collect();
        (jac, residual, fit)
    }

    /// For a problem linear in its parameters, each left-out step is the
    /// refit without the block, solved from scratch here; the covariance is
    /// the textbook jackknife of those refits.
    #[test]
    fn the_left_out_steps_are_the_refits_without_each_block() {
        let nf = 40;
        let (jac, residual, fit) = line_fit(nf, |f| (3.0 * f).sin() + 0.2 * f * f);
        let cov = block_covariance(&jac, &residual, nf, 1, &[false, false], 1e-12).unwrap();
        let k = BLOCKS;
        let f: Vec<f64> = (0..nf).map(|i| i as f64 / (nf - 1) as f64).collect();
        let refits: Vec<Vec<f64>> = (0..k)
            .map(|b| {
                let keep: Vec<usize> = (0..2 * nf).filter(|&r| (r % nf) * k / nf != b).collect();
                // normal equations of the line through the kept points, by hand
                let (mut s0, mut s1, mut s2, mut t0, mut t1) = (0.0, 0.0, 0.0, 0.0, 0.0);
                for &r in &keep {
                    let x = f[r % nf];
                    let y = (3.0 * x).sin() + 0.2 * x * x;
                    s0 += 1.0;
                    s1 += x;
                    s2 += x * x;
                    t0 += y;
                    t1 += x * y;
                }
                let det = s0 * s2 - s1 * s1;
                let a = (s2 * t0 - s1 * t1) / det;
                let bb = (s0 * t1 - s1 * t0) / det;
                vec![a - fit[0], bb - fit[1]]
            })
            .collect();
        let mean: Vec<f64> = (0..2).map(|j| refits.iter().map(|d| d[j]).sum::<f64>() / k as f64).collect();
        for i in 0..2 {
            for j in 0..2 {
                let want =
                    (k - 1) as f64 / k as f64 * refits.iter().map(|d| (d[i] - mean[i]) * (d[j] - mean[j])).sum::<f64>();
                assert!(
                    (cov[(i, j)] - want).abs() <= 1e-9 * want.abs().max(1e-12),
                    "{i},{j}: {} vs {want}",
                    cov[(i, j)]
                );
            }
        }
    }

    /// A model that cannot follow the data gives a spread far beyond what
    /// the same residual would give as independent noise; data the model
    /// follows exactly give none; a fixed column does not move.
    #[test]
    fn model_error_spreads_the_estimates_and_an_exact_fit_does_not() {
        let nf = 64;
        let (jac, residual, _) = line_fit(nf, |f| (6.0 * f).sin());
        let cov = block_covariance(&jac, &residual, nf, 1, &[false, false], 1e-12).unwrap();
        // the noise-only variance of the slope: sigma^2 (J^T J)^-1
        let sigma2 = residual.iter().map(|r| r * r).sum::<f64>() / (2 * nf - 2) as f64;
        let sol = lstsq::solve(&jac, &vec![0.0; 2 * nf], 1e-12);
        let var_slope = sigma2 * sol.scaled_inverse_normal[(1, 1)] / sol.column_norms[1].powi(2);
        assert!(cov[(1, 1)] > 2.0 * var_slope, "{} vs {var_slope}", cov[(1, 1)]);

        let (jac, residual, _) = line_fit(nf, |f| 1.0 + 2.0 * f);
        let exact = block_covariance(&jac, &residual, nf, 1, &[false, false], 1e-12).unwrap();
        assert!(exact[(0, 0)].abs() < 1e-20 && exact[(1, 1)].abs() < 1e-20);

        let (jac, residual, _) = line_fit(nf, |f| (6.0 * f).sin());
        let held = block_covariance(&jac, &residual, nf, 1, &[false, true], 1e-12).unwrap();
        assert_eq!(held[(1, 1)], 0.0);
    }

    #[test]
    fn too_few_lines_give_none() {
        let (jac, residual, _) = line_fit(7, |f| f * f);
        assert!(block_covariance(&jac, &residual, 7, 1, &[false, false], 1e-12).is_none());
    }
}
