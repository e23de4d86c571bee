//! The least-squares frequency-domain fit: with the selected poles fixed,
//! residues and upper and lower residuals per channel, then each mode's
//! shape as the rank-one factor of its residues.

use faer::Mat;
use faer::linalg::solvers::SolveLstsq;
use num_complex::Complex64 as C64;

use super::{Arranged, EstimatedMode, LscfError, ModalEstimate, OrderPoles};
use crate::set::FrfSet;

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
    // real design matrix: rows (Re, Im) of each line
    let mut a = Mat::<f64>::zeros(2 * nf, ncol);
    for (f, &w) in arr.omega.iter().enumerate() {
        let jw = C64::new(0.0, w);
        let mut put = |col: usize, v: C64| {
            a[(2 * f, col)] = v.re;
            a[(2 * f + 1, col)] = v.im;
        };
        for (k, (lambda, _, _)) in selected.iter().enumerate() {
            let g = 1.0 / (jw - lambda);
            let gc = 1.0 / (jw - lambda.conj());
            put(2 * k, g + gc);
            put(2 * k + 1, C64::new(0.0, 1.0) * (g - gc));
        }
        put(2 * nk, C64::new(1.0, 0.0));
        put(2 * nk + 1, C64::new(0.0, 1.0));
        put(2 * nk + 2, 1.0 / (jw * jw));
        put(2 * nk + 3, C64::new(0.0, 1.0) / (jw * jw));
    }
    // unit-norm columns keep the least-squares problem well conditioned
    let scale: Vec<f64> = (0..ncol).map(|c| a.col(c).norm_l2()).collect();
    for c in 0..ncol {
        if scale[c] > 0.0 {
            for r in 0..2 * nf {
                a[(r, c)] /= scale[c];
            }
        }
    }
    let mut b = Mat::<f64>::zeros(2 * nf, nch);
    for c in 0..nch {
        for (f, &k) in arr.lines.iter().enumerate() {
            let v = set.get(c, k);
            b[(2 * f, c)] = v.re;
            b[(2 * f + 1, c)] = v.im;
        }
    }
    let x = a.qr().solve_lstsq(&b);
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
            for &k in &arr.lines {
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
