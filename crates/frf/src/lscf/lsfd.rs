//! The least-squares frequency-domain fit: with the selected poles fixed,
//! residues and upper and lower residuals per channel, then each mode's
//! shape as the rank-one factor of its residues.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor::{qr_in_place, qr_in_place_scratch, recommended_block_size};
use faer::linalg::triangular_solve::solve_upper_triangular_in_place;
use faer::{Mat, MatMut, Par};
use num_complex::Complex64 as C64;

use super::{Arranged, EstimatedMode, LscfError, ModalEstimate, OrderPoles};
use crate::set::FrfSet;

/// Lines of the band whose rows of the design matrix are factorised
/// together. The fit holds one block of rows, not the whole band: at
/// 494,000 lines the dense design matrix, its factorisation and the data
/// beside it took some 400 MB, and faer's threads for a matrix that tall
/// took 20 s on a loaded machine where this takes 0.2 s.
const BLOCK_LINES: usize = 1024;

/// The columns of the design matrix at `w` (rad/s), each the complex value
/// whose real and imaginary parts are its two rows: per selected pole the
/// real and imaginary parts of its residue, then the upper and lower
/// residuals.
fn basis(w: f64, selected: &[(C64, Vec<C64>, usize)], out: &mut [C64]) {
    let jw = C64::new(0.0, w);
    let nk = selected.len();
    for (k, (lambda, _, _)) in selected.iter().enumerate() {
        let g = 1.0 / (jw - lambda);
        let gc = 1.0 / (jw - lambda.conj());
        out[2 * k] = g + gc;
        out[2 * k + 1] = C64::new(0.0, 1.0) * (g - gc);
    }
    out[2 * nk] = C64::new(1.0, 0.0);
    out[2 * nk + 1] = C64::new(0.0, 1.0);
    out[2 * nk + 2] = 1.0 / (jw * jw);
    out[2 * nk + 3] = C64::new(0.0, 1.0) / (jw * jw);
}

/// The least-squares solution `x` of `A x = B` (`ncols` unknowns, `nrhs`
/// right-hand sides), whose `nrows` rows `rows(first, a, b)` writes
/// `block_rows` at a time (rows `first..first + a.nrows()` of `A` and `B`).
/// Each block is factorised under the triangle of the rows before it (the
/// `R` of a QR factorisation of all rows so far, `Q^T B` beside it), so
/// that one block is held whatever the number of rows; faer runs
/// sequentially, as everywhere in this crate. The rank is not checked: a
/// column of zeros gives non-finite values, as a dense factorisation does.
pub(super) fn lstsq_by_blocks(
    nrows: usize,
    ncols: usize,
    nrhs: usize,
    block_rows: usize,
    mut rows: impl FnMut(usize, MatMut<'_, f64>, MatMut<'_, f64>),
) -> Mat<f64> {
    let width = ncols + nrhs;
    // the triangle so far (zero at first), then the block's rows
    let mut w = Mat::<f64>::zeros(ncols + block_rows, width);
    let mut first = 0;
    while first < nrows {
        let len = block_rows.min(nrows - first);
        let mut fresh = w.as_mut().subrows_mut(ncols, len);
        fresh.fill(0.0);
        let (a, b) = fresh.split_at_col_mut(ncols);
        rows(first, a, b);
        let m = ncols + len;
        let size = m.min(width);
        let bs = recommended_block_size::<f64>(m, width);
        let mut householder = Mat::<f64>::zeros(bs, size);
        let mut mem = MemBuffer::new(qr_in_place_scratch::<f64>(m, width, bs, Par::Seq, Default::default()));
        let mut block = w.as_mut().subrows_mut(0, m);
        qr_in_place(block.as_mut(), householder.as_mut(), Par::Seq, MemStack::new(&mut mem), Default::default());
        // the new triangle: R's first rows, the Householder vectors under its diagonal cleared
        for j in 0..ncols {
            for i in j + 1..ncols {
                block[(i, j)] = 0.0;
            }
        }
        first += len;
    }
    let mut x = w.as_ref().submatrix(0, ncols, ncols, nrhs).to_owned();
    solve_upper_triangular_in_place(w.as_ref().submatrix(0, 0, ncols, ncols), x.as_mut(), Par::Seq);
    x
}

/// The least-squares frequency-domain fit of residues and residual terms.
pub(super) fn lsfd(
    set: &FrfSet,
    arr: &Arranged,
    selected: Vec<(C64, Vec<C64>, usize)>,
    stabilisation: Vec<OrderPoles>,
    band_hz: (f64, f64),
) -> Result<ModalEstimate, LscfError> {
    let nf = arr.lines.len();
    let nk = selected.len();
    let ncol = 2 * nk + 4;
    let nch = set.channels().len();
    // unit-norm columns keep the least-squares problem well conditioned
    let mut values = vec![C64::new(0.0, 0.0); ncol];
    let mut sq = vec![0.0; ncol];
    for &w in &arr.omega {
        basis(w, &selected, &mut values);
        for (s, v) in sq.iter_mut().zip(&values) {
            *s += v.norm_sqr();
        }
    }
    let scale: Vec<f64> = sq.iter().map(|s| s.sqrt()).collect();
    // real rows (Re, Im) of each line, a block of lines at a time
    let x = lstsq_by_blocks(2 * nf, ncol, nch, 2 * BLOCK_LINES, |first, mut a, mut b| {
        for r in (0..a.nrows()).step_by(2) {
            let f = (first + r) / 2;
            basis(arr.omega[f], &selected, &mut values);
            for (col, v) in values.iter().enumerate() {
                let s = if scale[col] > 0.0 { scale[col] } else { 1.0 };
                a[(r, col)] = v.re / s;
                a[(r + 1, col)] = v.im / s;
            }
            for c in 0..nch {
                let v = set.get(c, arr.lines.start + f);
                b[(r, c)] = v.re;
                b[(r + 1, c)] = v.im;
            }
        }
    });
    if x.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return Err(LscfError::ResidueFit);
    }
    let coef = |col: usize, c: usize| x[(col, c)] / if scale[col] > 0.0 { scale[col] } else { 1.0 };
    let upper_residuals: Vec<C64> = (0..nch).map(|c| C64::new(coef(2 * nk, c), coef(2 * nk + 1, c))).collect();
    let lower_residuals: Vec<C64> = (0..nch).map(|c| C64::new(coef(2 * nk + 2, c), coef(2 * nk + 3, c))).collect();

    let mut modes = Vec::with_capacity(nk);
    for (k, (pole, participation, stable_orders)) in selected.into_iter().enumerate() {
        let residues: Vec<C64> = (0..nch).map(|c| C64::new(coef(2 * k, c), coef(2 * k + 1, c))).collect();
        let (shape, scaled) = shape_from_residues(arr, &residues, &participation);
        let w = pole.norm();
        modes.push(EstimatedMode {
            pole,
            frequency_hz: w / (2.0 * std::f64::consts::PI),
            damping_ratio: -pole.re / w,
            stable_orders,
            participation,
            residues,
            shape,
            scaled,
        });
    }
    let mut out = ModalEstimate {
        modes,
        stabilisation,
        channels: set.channels().to_vec(),
        responses: arr.responses.clone(),
        references: arr.references.clone(),
        band_hz,
        upper_residuals,
        lower_residuals,
        fit_error: Vec::new(),
    };
    out.fit_error = (0..nch)
        .map(|c| {
            let (mut num, mut den) = (0.0, 0.0);
            for k in arr.lines.clone() {
                let h = set.get(c, k);
                num += (h - out.synthesize(c, set.frequencies_hz()[k])).norm_sqr();
                den += h.norm_sqr();
            }
            if den > 0.0 { (num / den).sqrt() } else { num.sqrt() }
        })
        .collect();
    Ok(out)
}

/// The rank-one factor `psi` of the residues `R[o, i] = psi_o l_i`, scaled
/// with the driving points when there are any.
fn shape_from_residues(arr: &Arranged, residues: &[C64], participation: &[C64]) -> (Vec<C64>, bool) {
    let ll: f64 = participation.iter().map(|v| v.norm_sqr()).sum();
    let mut psi: Vec<C64> = arr
        .index
        .iter()
        .map(|row| row.iter().zip(participation).map(|(&c, l)| residues[c] * l.conj()).sum::<C64>() / ll)
        .collect();
    // driving points: l_i = c psi_ref(i), choose c^2 in the least-squares sense
    let (mut num, mut den) = (C64::new(0.0, 0.0), 0.0);
    for (i, r) in arr.references.iter().enumerate() {
        if let Some(o) = arr.responses.iter().position(|x| x == r) {
            num += psi[o].conj() * participation[i];
            den += psi[o].norm_sqr();
        }
    }
    let big = |v: &[C64]| v.iter().copied().max_by(|x, y| x.norm().total_cmp(&y.norm())).unwrap_or_default();
    if den > 0.0 && num.norm() > 0.0 {
        // psi' = psi sqrt(c2) makes psi'_ref = l'_i with l' = l / sqrt(c2)
        let c2 = num / den;
        let mut f = c2.sqrt();
        if (big(&psi) * f).re < 0.0 {
            f = -f;
        }
        psi.iter_mut().for_each(|v| *v *= f);
        (psi, true)
    } else {
        let b = big(&psi);
        if b.norm() > 0.0 {
            psi.iter_mut().for_each(|v| *v /= b);
        }
        (psi, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::linalg::solvers::SolveLstsq;

    /// A tall least-squares problem with entries spread over a few decades.
    fn problem(nrows: usize, ncols: usize, nrhs: usize) -> (Mat<f64>, Mat<f64>) {
        // a frequency of its own per column: independent columns
        let a = Mat::from_fn(nrows, ncols, |i, j| (i as f64 * 0.013 * (j + 1) as f64).sin() * 10f64.powi(j as i32 % 3));
        let b = Mat::from_fn(nrows, nrhs, |i, j| (i as f64 * 0.002 * (j + 2) as f64).cos() + i as f64 * 1e-4);
        (a, b)
    }

    #[test]
    fn blocks_of_rows_give_the_dense_least_squares_solution() {
        let (a, b) = problem(5003, 7, 3);
        let dense = a.qr().solve_lstsq(&b);
        let mut seen = Vec::new();
        let x = lstsq_by_blocks(5003, 7, 3, 64, |first, mut ab, mut bb| {
            seen.push((first, ab.nrows()));
            ab.copy_from(a.submatrix(first, 0, ab.nrows(), 7));
            bb.copy_from(b.submatrix(first, 0, bb.nrows(), 3));
        });
        // every row once, in order, at most a block at a time
        assert!(seen.iter().all(|&(_, n)| n <= 64));
        assert_eq!(seen.iter().map(|&(_, n)| n).sum::<usize>(), 5003);
        assert!(seen.windows(2).all(|w| w[1].0 == w[0].0 + w[0].1));
        let err = (&x - &dense).norm_l2() / dense.norm_l2();
        assert!(err < 1e-12, "relative difference {err:.1e}");
    }

    #[test]
    fn a_column_of_zeros_gives_non_finite_values() {
        let (mut a, b) = problem(300, 4, 1);
        a.col_mut(2).fill(0.0);
        let x = lstsq_by_blocks(300, 4, 1, 64, |first, mut ab, mut bb| {
            ab.copy_from(a.submatrix(first, 0, ab.nrows(), 4));
            bb.copy_from(b.submatrix(first, 0, bb.nrows(), 1));
        });
        assert!(x.col(0).iter().any(|v| !v.is_finite()), "{x:?}");
    }
}
