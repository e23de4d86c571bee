//! The poles of one model order: lag sums over the band (once, for the
//! highest order), the reduced normal equations, the block companion matrix
//! of `A(z)^T` and its eigenvalues mapped to `s = ln(z) / dt`.

use damping::eigen::{RealEigen, real_eigen};
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use num_complex::Complex64 as C64;

use super::{Arranged, Weighting};
use crate::set::FrfSet;

/// Lag sums of one response: `r[d]`, `s[d][i]`, `t[d][i][k]` for lags
/// `d = -p..=p` (stored at `d + p`); see the module docs.
pub(super) struct LagSums {
    pub(super) r: Vec<C64>,
    s: Vec<Vec<C64>>,
    t: Vec<Vec<C64>>,
}

pub(super) fn lag_sums(set: &FrfSet, arr: &Arranged, o: usize, dt: f64, p: usize, weighting: Weighting) -> LagSums {
    let m = arr.references.len();
    let nl = 2 * p + 1;
    let mut r = vec![C64::new(0.0, 0.0); nl];
    let mut s = vec![vec![C64::new(0.0, 0.0); m]; nl];
    let mut t = vec![vec![C64::new(0.0, 0.0); m * m]; nl];
    // the response's row at each line, read from the set (a copy of every
    // row would hold a copy of the data)
    let channels = &arr.index[o];
    let mut row = vec![C64::new(0.0, 0.0); m];
    let rms = (arr.lines.clone().flat_map(|k| channels.iter().map(move |&c| set.get(c, k).norm_sqr())).sum::<f64>()
        / arr.lines.len() as f64)
        .sqrt();
    for (f, k) in arr.lines.clone().enumerate() {
        for (v, &c) in row.iter_mut().zip(channels) {
            *v = set.get(c, k);
        }
        let mag = row.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
        // a line (or response) of zeros carries no information: weight 0
        let w2 = match weighting {
            Weighting::InverseMagnitude if mag > 0.0 => 1.0 / (mag * mag),
            Weighting::PerResponse if rms > 0.0 => 1.0 / (rms * rms),
            _ => 0.0,
        };
        let theta = arr.omega[f] * dt;
        for (li, d) in (-(p as i64)..=(p as i64)).enumerate() {
            let e = C64::from_polar(w2, theta * d as f64);
            r[li] += e;
            for i in 0..m {
                s[li][i] += e * row[i];
                let ci = row[i].conj();
                for k in 0..m {
                    t[li][i * m + k] += e * ci * row[k];
                }
            }
        }
    }
    LagSums { r, s, t }
}

/// Physical poles and participation vectors of order `p` from the reduced
/// normal equations.
pub(super) fn poles_of_order(
    sums: &[LagSums],
    m: usize,
    p: usize,
    pmax: usize,
    dt: f64,
) -> Result<Vec<(C64, Vec<C64>)>, &'static str> {
    let np = p + 1;
    let nm = m * np;
    let mut big = Mat::<f64>::zeros(nm, nm);
    for ls in sums {
        let lag = |d: i64| (d + pmax as i64) as usize;
        let mut rmat = Mat::<f64>::zeros(np, np);
        let mut smat = Mat::<f64>::zeros(np, nm);
        for r in 0..np {
            for q in 0..np {
                let d = lag(q as i64 - r as i64);
                rmat[(r, q)] = ls.r[d].re;
                for i in 0..m {
                    smat[(r, q * m + i)] = -ls.s[d][i].re;
                }
            }
        }
        let llt = rmat.llt(Side::Lower).map_err(|_| "the polynomial basis normal matrix is not positive definite")?;
        let rs = llt.solve(&smat);
        // T - S^T R^-1 S
        for r in 0..np {
            for i in 0..m {
                for q in 0..np {
                    let d = lag(q as i64 - r as i64);
                    for k in 0..m {
                        big[(r * m + i, q * m + k)] += ls.t[d][i * m + k].re;
                    }
                }
            }
        }
        let sts = smat.transpose() * &rs;
        big -= &sts;
    }
    let na = m * p;
    let maa = big.submatrix(0, 0, na, na).to_owned();
    let mab = big.submatrix(0, na, na, m).to_owned();
    // symmetric positive (semi-)definite: Cholesky, with LU as a fallback
    let alpha = match maa.llt(Side::Lower) {
        Ok(l) => -l.solve(&mab),
        Err(_) => -maa.partial_piv_lu().solve(&mab),
    };
    if alpha.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return Err("the reduced normal equations are singular");
    }
    // block companion of A(z)^T: first block row -alpha_{p-1}^T ... -alpha_0^T
    let mut comp = Mat::<f64>::zeros(na, na);
    for blk in 0..p {
        let r = p - 1 - blk; // power held by block column `blk`
        for i in 0..m {
            for k in 0..m {
                // alpha_r^T[i, k] = alpha_r[k, i]
                comp[(i, blk * m + k)] = -alpha[(r * m + k, i)];
            }
        }
    }
    for blk in 1..p {
        for i in 0..m {
            comp[(blk * m + i, (blk - 1) * m + i)] = 1.0;
        }
    }
    let RealEigen { re: s_re, im: s_im, vectors: u } =
        real_eigen(comp.as_ref()).map_err(|_| "the companion eigensolver did not converge")?;
    let mut out = Vec::new();
    let mut j = 0;
    while j < na {
        let pair = s_im[j] != 0.0 && j + 1 < na;
        let z = C64::new(s_re[j], s_im[j]);
        if !(z.re.is_finite() && z.im.is_finite()) {
            return Err("the companion eigensolver returned a non-finite value");
        }
        if pair {
            // eigenvector of z = s_re + j s_im: u_j + j u_{j+1}; of conj(z): its conjugate
            let (z, sign) = if z.im > 0.0 { (z, 1.0) } else { (z.conj(), -1.0) };
            let l: Vec<C64> = (0..m)
                .map(|i| {
                    let row = (p - 1) * m + i;
                    C64::new(u[(row, j)], sign * u[(row, j + 1)])
                })
                .collect();
            if z.norm() > 0.0 {
                out.push((z.ln() / dt, unit(l)));
            }
        }
        j += if pair { 2 } else { 1 };
    }
    Ok(out)
}

fn unit(mut v: Vec<C64>) -> Vec<C64> {
    let n = v.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
    if n > 0.0 {
        v.iter_mut().for_each(|x| *x /= n);
    }
    v
}
