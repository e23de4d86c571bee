//! Column-scaled least squares by singular value decomposition.
//!
//! Sensitivity columns of different parameters differ by orders of magnitude
//! (a relaxation parameter far above the band barely moves the FRF). Columns
//! are scaled to unit norm before the SVD, singular values below
//! `rcond * s_max` are dropped (those parameter combinations keep their
//! values), and the solution is scaled back.
//!
//! A fit's Jacobian is tall and thin (thousands of residuals, a few
//! parameters): [`solve_tall`] takes the SVD of the triangular factor of
//! its Householder QR instead (Chan's R-SVD), which has the same singular
//! values and right singular vectors (up to their signs) and costs a quarter
//! of the SVD of the whole matrix, most of which went into its left
//! singular vectors; the fits iterate with it.

use faer::Mat;

/// Solution of a scaled least-squares problem.
#[derive(Clone, Debug)]
pub struct LstsqSolution {
    /// Minimiser of `|A x - b|` (minimum norm in the scaled variables).
    pub x: Vec<f64>,
    /// Singular values of the column-scaled matrix, descending.
    pub singular_values: Vec<f64>,
    /// Number of singular values kept.
    pub rank: usize,
    /// Norm of each column of `A` (1 for all-zero columns).
    pub column_norms: Vec<f64>,
    /// `(A_s^T A_s)^+` in scaled variables (pseudo-inverse over kept directions).
    pub scaled_inverse_normal: Mat<f64>,
    /// Right singular vectors of the scaled matrix (columns), for reporting
    /// which combinations are poorly determined.
    pub v: Mat<f64>,
    /// `U^T b` for each kept singular value (index matches `singular_values`).
    utb: Vec<f64>,
    keep: Vec<usize>,
}

impl LstsqSolution {
    /// The Tikhonov-damped solution `min |A_s x_s - b|^2 + lambda |x_s|^2` in
    /// scaled variables, returned in unscaled variables (`lambda = 0` gives `x`).
    pub fn damped(&self, lambda: f64) -> Vec<f64> {
        let n = self.column_norms.len();
        let mut xs = vec![0.0; n];
        for &i in &self.keep {
            let s = self.singular_values[i];
            let coef = self.utb[i] * s / (s * s + lambda);
            for j in 0..n {
                xs[j] += coef * self.v[(j, i)];
            }
        }
        xs.iter().zip(&self.column_norms).map(|(x, c)| x / c).collect()
    }

    /// How much the undamped solution lowers `|A x - b|^2` (that is `|P b|^2`,
    /// the squared norm of `b`'s projection on the kept directions).
    pub fn predicted_reduction(&self) -> f64 {
        self.keep.iter().map(|&i| self.utb[i] * self.utb[i]).sum()
    }

    /// For each unknown, whether it takes part (component above 0.1 in the
    /// scaled variables) in a dropped direction: a combination the data
    /// cannot resolve, whose variance is unbounded rather than the zero the
    /// pseudo-inverse gives it. An all-zero column is always undetermined.
    pub fn undetermined(&self) -> Vec<bool> {
        let n = self.column_norms.len();
        let mut out = vec![false; n];
        for i in 0..self.v.ncols() {
            if self.keep.contains(&i) {
                continue;
            }
            for (j, flag) in out.iter_mut().enumerate() {
                if self.v[(j, i)].abs() > 0.1 {
                    *flag = true;
                }
            }
        }
        // a thin SVD of a tall matrix has n directions; with more unknowns
        // than rows, those beyond the rank are undetermined too
        if self.v.ncols() < n {
            for (j, flag) in out.iter_mut().enumerate() {
                let covered: f64 = self.keep.iter().map(|&i| self.v[(j, i)].powi(2)).sum();
                if covered < 0.99 {
                    *flag = true;
                }
            }
        }
        out
    }

    /// Largest kept singular value (0 when none is kept).
    pub fn largest_singular_value(&self) -> f64 {
        self.singular_values.first().copied().unwrap_or(0.0)
    }
}

/// Solves `min |A x - b|` with column scaling and SVD truncation at `rcond`.
pub fn solve(a: &Mat<f64>, b: &[f64], rcond: f64) -> LstsqSolution {
    let (m, n) = (a.nrows(), a.ncols());
    assert_eq!(b.len(), m);
    let column_norms: Vec<f64> = (0..n)
        .map(|j| {
            let s = (0..m).map(|i| a[(i, j)] * a[(i, j)]).sum::<f64>().sqrt();
            if s > 0.0 && s.is_finite() { s } else { 1.0 }
        })
        .collect();
    let scaled = Mat::from_fn(m, n, |i, j| a[(i, j)] / column_norms[j]);
    let svd = scaled.thin_svd().expect("SVD of a finite matrix converges");
    let (u, s, v) = (svd.U(), svd.S(), svd.V());
    let k = s.dim();
    let singular_values: Vec<f64> = (0..k).map(|i| s[i]).collect();
    let utb: Vec<f64> = (0..k).map(|i| (0..m).map(|r| u[(r, i)] * b[r]).sum()).collect();
    finish(singular_values, utb, v.to_owned(), column_norms, rcond)
}

/// Solves `min |A x - b|` as [`solve`] does, by the SVD of the triangular
/// factor `R` of a Householder QR of the column-scaled `A` (`A_s = Q R`,
/// `R = U_R S V^T`, `U^T b = U_R^T Q^T b`): the same solution, singular
/// values, rank, damped solutions and covariance to round-off, with right
/// singular vectors that may differ from [`solve`]'s in sign. For tall
/// matrices (more rows than columns; otherwise it is [`solve`]).
pub fn solve_tall(a: &Mat<f64>, b: &[f64], rcond: f64) -> LstsqSolution {
    let (m, n) = (a.nrows(), a.ncols());
    assert_eq!(b.len(), m);
    if m <= n {
        return solve(a, b, rcond);
    }
    let column_norms: Vec<f64> = (0..n)
        .map(|j| {
            let s = (0..m).map(|i| a[(i, j)] * a[(i, j)]).sum::<f64>().sqrt();
            if s > 0.0 && s.is_finite() { s } else { 1.0 }
        })
        .collect();
    // the scaled columns, one after the other, reduced in place to R and
    // the Householder vectors below it; b along with them to Q^T b
    let mut cols: Vec<f64> =
        (0..n).flat_map(|j| (0..m).map(move |i| (i, j))).map(|(i, j)| a[(i, j)] / column_norms[j]).collect();
    let mut qtb = b.to_vec();
    for j in 0..n {
        let (done, rest) = cols.split_at_mut((j + 1) * m);
        let x = &mut done[j * m + j..(j + 1) * m];
        let norm = dot(x, x).sqrt();
        if norm == 0.0 {
            continue;
        }
        // H = I - tau v v^T with v = (1, x[1..] / (alpha - beta)) takes x to (beta, 0, ...)
        let alpha = x[0];
        let beta = if alpha >= 0.0 { -norm } else { norm };
        let scale = 1.0 / (alpha - beta);
        x[1..].iter_mut().for_each(|v| *v *= scale);
        let tau = (beta - alpha) / beta;
        x[0] = 1.0;
        let v: &[f64] = x;
        for k in 0..n - j - 1 {
            let y = &mut rest[k * m + j..(k + 1) * m];
            let s = tau * dot(v, y);
            y.iter_mut().zip(v).for_each(|(y, v)| *y -= s * v);
        }
        let y = &mut qtb[j..];
        let s = tau * dot(v, y);
        y.iter_mut().zip(v).for_each(|(y, v)| *y -= s * v);
        done[j * m + j] = beta;
    }
    let r = Mat::from_fn(n, n, |i, j| if i <= j { cols[j * m + i] } else { 0.0 });
    let svd = r.thin_svd().expect("SVD of a finite matrix converges");
    let (u, s, v) = (svd.U(), svd.S(), svd.V());
    let singular_values: Vec<f64> = (0..n).map(|i| s[i]).collect();
    let utb: Vec<f64> = (0..n).map(|i| (0..n).map(|r| u[(r, i)] * qtb[r]).sum()).collect();
    finish(singular_values, utb, v.to_owned(), column_norms, rcond)
}

/// `x . y`, in four interleaved sums (which the compiler vectorises).
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (xc, yc) = (x.chunks_exact(4), y.chunks_exact(4));
    let tail: f64 = xc.remainder().iter().zip(yc.remainder()).map(|(a, b)| a * b).sum();
    for (a, b) in xc.zip(yc) {
        for l in 0..4 {
            acc[l] += a[l] * b[l];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// The solution from the scaled problem's singular values, `U^T b` and
/// right singular vectors (columns of `v`).
fn finish(singular_values: Vec<f64>, utb: Vec<f64>, v: Mat<f64>, column_norms: Vec<f64>, rcond: f64) -> LstsqSolution {
    let (k, n) = (singular_values.len(), column_norms.len());
    let smax = singular_values.iter().copied().fold(0.0, f64::max);
    let keep: Vec<usize> = (0..k).filter(|&i| singular_values[i] > rcond * smax && singular_values[i] > 0.0).collect();
    let mut xs = vec![0.0; n];
    for &i in &keep {
        let coef = utb[i] / singular_values[i];
        for j in 0..n {
            xs[j] += coef * v[(j, i)];
        }
    }
    let mut inv = Mat::<f64>::zeros(n, n);
    for &i in &keep {
        let w = 1.0 / (singular_values[i] * singular_values[i]);
        for r in 0..n {
            for c in 0..n {
                inv[(r, c)] += w * v[(r, i)] * v[(c, i)];
            }
        }
    }
    let x = xs.iter().zip(&column_norms).map(|(x, s)| x / s).collect();
    LstsqSolution { x, singular_values, rank: keep.len(), column_norms, scaled_inverse_normal: inv, v, utb, keep }
}

/// A parameter whose component along the unresolved direction exceeds this
/// takes part in the combination the data cannot separate.
const IN_COMBINATION: f64 = 0.1;

/// The index of the smallest singular value with it and the largest, when
/// the smallest is below 1e-6 of the largest (a nearly singular problem).
fn weakest_direction(sv: &[f64]) -> Option<(usize, f64, f64)> {
    let smax = sv.first().copied()?;
    let (k, &smin) = sv.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    (!(smax == 0.0 || smin > 1e-6 * smax)).then_some((k, smin, smax))
}

/// Which of `n` parameters take part in the weakest direction when the
/// problem is nearly singular (the combination [`unresolved_combination`]
/// names, which prints the three largest parts); all false when it is not.
pub(crate) fn unresolved_parameters(sv: &[f64], v: &Mat<f64>, n: usize) -> Vec<bool> {
    match weakest_direction(sv) {
        Some((k, _, _)) => (0..n).map(|i| i < v.nrows() && v[(i, k)].abs() > IN_COMBINATION).collect(),
        None => vec![false; n],
    }
}

/// Names the parameter combination along the weakest direction of a
/// column-scaled sensitivity matrix (singular values `sv`, right singular
/// vectors as the columns of `v`, one row per parameter of `names`) when it
/// is nearly singular: its smallest singular value is below 1e-6 of the
/// largest. Used by the response function method and the output-error
/// uncertainty.
pub(crate) fn unresolved_combination(sv: &[f64], v: &Mat<f64>, names: &[String]) -> Option<String> {
    let n = names.len();
    let (k, smin, smax) = weakest_direction(sv)?;
    let mut parts: Vec<(f64, usize)> = (0..n.min(v.nrows())).map(|i| (v[(i, k)], i)).collect();
    parts.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
    let terms: Vec<String> = parts
        .iter()
        .take(3)
        .filter(|(c, _)| c.abs() > IN_COMBINATION)
        .map(|(c, i)| format!("{:+.2} ln({})", c, names[*i]))
        .collect();
    Some(format!(
        "the data cannot separate the combination {} (singular value ratio {:.1e})",
        terms.join(" "),
        smin / smax
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn badly_scaled_full_rank_system_is_solved_exactly() {
        // columns differ by 1e12 in scale
        let a = Mat::from_fn(5, 2, |i, j| if j == 0 { (i + 1) as f64 * 1e6 } else { ((i * i) as f64 + 1.0) * 1e-6 });
        let x_true = [2e-6, 3e5];
        let b: Vec<f64> = (0..5).map(|i| a[(i, 0)] * x_true[0] + a[(i, 1)] * x_true[1]).collect();
        let s = solve(&a, &b, 1e-12);
        assert_eq!(s.rank, 2);
        for (x, t) in s.x.iter().zip(x_true) {
            assert!((x - t).abs() <= 1e-10 * t.abs(), "{x} vs {t}");
        }
    }

    #[test]
    fn damped_solution_shrinks_towards_zero_and_matches_normal_equations() {
        let a = Mat::from_fn(6, 3, |i, j| ((i * 3 + j) as f64).sin() + if i == j { 2.0 } else { 0.0 });
        let b: Vec<f64> = (0..6).map(|i| (i as f64).cos()).collect();
        let s = solve(&a, &b, 1e-14);
        assert_eq!(s.damped(0.0), s.x);
        let lambda = 0.3;
        let x = s.damped(lambda);
        // (A_s^T A_s + lambda I) x_s = A_s^T b with A_s = A D^-1, x_s = D x
        let d = &s.column_norms;
        for r in 0..3 {
            let mut lhs = lambda * x[r] * d[r];
            let mut rhs = 0.0;
            for i in 0..6 {
                let ar = a[(i, r)] / d[r];
                lhs += ar * (0..3).map(|c| a[(i, c)] * x[c]).sum::<f64>();
                rhs += ar * b[i];
            }
            assert!((lhs - rhs).abs() < 1e-12, "row {r}: {lhs} vs {rhs}");
        }
        let norm = |v: &[f64]| v.iter().zip(d).map(|(x, c)| (x * c).powi(2)).sum::<f64>();
        assert!(norm(&s.damped(10.0)) < norm(&x) && norm(&x) < norm(&s.x));
    }

    #[test]
    fn unknowns_in_dropped_directions_are_undetermined() {
        let a = Mat::from_fn(4, 3, |i, j| match j {
            0 => (i + 1) as f64,
            1 => 0.0,
            _ => ((i * i) as f64).cos(),
        });
        let s = solve(&a, &[1.0, 0.0, 2.0, 1.0], 1e-10);
        assert_eq!(s.undetermined(), vec![false, true, false]);
    }

    #[test]
    fn zero_and_duplicate_columns_get_no_update_along_the_null_space() {
        let a = Mat::from_fn(4, 3, |i, j| match j {
            0 => (i + 1) as f64,
            1 => 0.0,
            _ => 2.0 * (i + 1) as f64,
        });
        let b = vec![1.0, 2.0, 3.0, 4.0];
        let s = solve(&a, &b, 1e-10);
        assert_eq!(s.rank, 1);
        assert_eq!(s.x[1], 0.0);
        // minimum-norm split between the two proportional columns (scaled variables)
        let fit: Vec<f64> = (0..4).map(|i| a[(i, 0)] * s.x[0] + a[(i, 2)] * s.x[2]).collect();
        for (f, t) in fit.iter().zip(&b) {
            assert!((f - t).abs() < 1e-12);
        }
    }

    /// `solve_tall` against `solve` on one problem: the same rank, kept
    /// directions, singular values, solution, damped solutions, predicted
    /// reduction, covariance and undetermined unknowns, to round-off: both
    /// are backward stable, so they agree to the working precision times
    /// the condition of the kept directions (its square for the covariance).
    fn same_as_the_svd_of_the_whole(a: &Mat<f64>, b: &[f64], rcond: f64) {
        let (full, tall) = (solve(a, b, rcond), solve_tall(a, b, rcond));
        let smallest = full.keep.iter().map(|&i| full.singular_values[i]).fold(f64::INFINITY, f64::min);
        let cond = full.largest_singular_value() / smallest;
        let close = |x: f64, y: f64, what: &str| {
            assert!((x - y).abs() <= 1e-10 * x.abs().max(y.abs()).max(1e-300), "{what}: {x} against {y}")
        };
        assert_eq!((full.rank, &full.keep, full.undetermined()), (tall.rank, &tall.keep, tall.undetermined()));
        for (x, y) in full.singular_values.iter().zip(&tall.singular_values) {
            // dropped directions' singular values are round-off of both
            if *x > 1e-8 * full.largest_singular_value() {
                close(*x, *y, "singular value");
            }
        }
        // vectors to round-off of their largest component
        let same = |x: &[f64], y: &[f64], what: &str| {
            let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in x.iter().zip(y) {
                assert!((a - b).abs() <= 1e-13 * cond.max(100.0) * scale, "{what}: {x:?} against {y:?}");
            }
        };
        for lambda in [0.0, 1e-6, 0.3, 10.0] {
            same(&full.damped(lambda), &tall.damped(lambda), "damped solution");
        }
        same(&full.x, &tall.x, "solution");
        close(full.predicted_reduction(), tall.predicted_reduction(), "predicted reduction");
        let n = a.ncols();
        let scale = (0..n).map(|i| full.scaled_inverse_normal[(i, i)].abs()).fold(0.0, f64::max);
        for r in 0..n {
            for c in 0..n {
                let (x, y) = (full.scaled_inverse_normal[(r, c)], tall.scaled_inverse_normal[(r, c)]);
                assert!((x - y).abs() <= 1e-13 * cond.max(100.0).powi(2) * scale, "({r}, {c}): {x} against {y}");
            }
        }
    }

    #[test]
    fn the_svd_of_the_r_factor_solves_as_the_svd_of_the_whole() {
        // tall, columns scaled over twelve orders of magnitude, full rank
        let a = Mat::from_fn(500, 6, |i, j| {
            let t = i as f64 * 0.013;
            (t * (j + 1) as f64).sin() * 10f64.powi(2 * j as i32 - 6) + if i % 7 == j { 0.1 } else { 0.0 }
        });
        let b: Vec<f64> = (0..500).map(|i| (i as f64 * 0.7).cos()).collect();
        same_as_the_svd_of_the_whole(&a, &b, 1e-12);
        // a zero column and two proportional ones: rank 2 of 4
        let a = Mat::from_fn(40, 4, |i, j| match j {
            0 => (i + 1) as f64,
            1 => 0.0,
            2 => -3.0 * (i + 1) as f64,
            _ => ((i * i) as f64).cos(),
        });
        let b: Vec<f64> = (0..40).map(|i| (i as f64).sin()).collect();
        same_as_the_svd_of_the_whole(&a, &b, 1e-10);
        assert_eq!(solve_tall(&a, &b, 1e-10).rank, 2);
        // nearly dependent columns, kept at a tight cut-off
        let a = Mat::from_fn(80, 3, |i, j| {
            let t = i as f64 / 80.0;
            match j {
                0 => t,
                1 => t + 1e-7 * t * t,
                _ => 1.0 - t,
            }
        });
        let b: Vec<f64> = (0..80).map(|i| (i as f64 / 9.0).exp().ln_1p()).collect();
        same_as_the_svd_of_the_whole(&a, &b, 1e-12);
        // as wide as it is tall: the plain SVD
        let a = Mat::from_fn(3, 3, |i, j| ((i * 3 + j) as f64).sin() + if i == j { 2.0 } else { 0.0 });
        same_as_the_svd_of_the_whole(&a, &[1.0, -2.0, 0.5], 1e-12);
    }
}
