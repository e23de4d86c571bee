//! The small dense kernels of the low-rank evaluation, on row-major complex
//! matrices of a few dozen rows (faer's dispatch costs more than the
//! arithmetic at this size).

use num_complex::Complex64 as C64;

use super::ZERO;

/// LU factorisation with partial pivoting of a row-major `n x n` matrix in
/// place (unit lower and upper triangles share the storage). Returns false
/// when a pivot is zero or not finite.
pub(super) fn lu_in_place(a: &mut [C64], n: usize, piv: &mut [usize]) -> bool {
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i * n + k].norm_sqr().total_cmp(&a[j * n + k].norm_sqr())).expect("k < n");
        piv[k] = p;
        if p != k {
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
        }
        let pivot = a[k * n + k];
        if pivot.norm_sqr() == 0.0 || !(pivot.re.is_finite() && pivot.im.is_finite()) {
            return false;
        }
        let inv = pivot.inv();
        let (head, tail) = a.split_at_mut((k + 1) * n);
        let row_k = &head[k * n..];
        for row in tail.chunks_exact_mut(n) {
            let l = row[k] * inv;
            row[k] = l;
            if l != ZERO {
                for j in k + 1..n {
                    row[j] -= l * row_k[j];
                }
            }
        }
    }
    true
}

/// Solves `A X = B` with the LU of [`lu_in_place`]; `b` is row-major `n x k`
/// and is overwritten by `X`.
pub(super) fn lu_solve(a: &[C64], n: usize, piv: &[usize], b: &mut [C64], k: usize) {
    for i in 0..n {
        if piv[i] != i {
            for j in 0..k {
                b.swap(i * k + j, piv[i] * k + j);
            }
        }
    }
    for i in 0..n {
        let (head, tail) = b.split_at_mut(i * k);
        let bi = &mut tail[..k];
        for m in 0..i {
            let l = a[i * n + m];
            if l != ZERO {
                for (v, &u) in bi.iter_mut().zip(&head[m * k..m * k + k]) {
                    *v -= l * u;
                }
            }
        }
    }
    for i in (0..n).rev() {
        let (head, tail) = b.split_at_mut((i + 1) * k);
        let bi = &mut head[i * k..];
        for m in i + 1..n {
            let u = a[i * n + m];
            if u != ZERO {
                let off = (m - i - 1) * k;
                for (v, &w) in bi.iter_mut().zip(&tail[off..off + k]) {
                    *v -= u * w;
                }
            }
        }
        let inv = a[i * n + i].inv();
        bi.iter_mut().for_each(|v| *v *= inv);
    }
}

/// Solves `A^T x = b` for one column with the LU of [`lu_in_place`]
/// (`P A = L U`, so `A^T = U^T L^T P`); `b` is overwritten by `x`.
pub(super) fn lu_solve_transposed(a: &[C64], n: usize, piv: &[usize], b: &mut [C64]) {
    for i in 0..n {
        let mut v = b[i];
        for m in 0..i {
            v -= a[m * n + i] * b[m];
        }
        b[i] = v / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut v = b[i];
        for m in i + 1..n {
            v -= a[m * n + i] * b[m];
        }
        b[i] = v;
    }
    for i in (0..n).rev() {
        b.swap(i, piv[i]);
    }
}

/// Condenses a local matrix `q` (`(d + e)^2`, row-major) onto `D`:
/// `T^T q T` with `T = [I; -G]`, written to `out` (`d x d`).
pub(super) fn condense(q: &[C64], g: &[C64], d: usize, e: usize, out: &mut [C64]) {
    let n = d + e;
    for i in 0..d {
        for j in 0..d {
            out[i * d + j] = q[i * n + j];
        }
    }
    if e == 0 {
        return;
    }
    // out -= Q_AB G + G^T Q_BA, then out += G^T Q_BB G
    for i in 0..d {
        for m in 0..e {
            let (qab, gmi) = (q[i * n + d + m], g[m * d + i]);
            let (g_row, qba_row) = (&g[m * d..m * d + d], &q[(d + m) * n..(d + m) * n + d]);
            for ((o, &gj), &qj) in out[i * d..i * d + d].iter_mut().zip(g_row).zip(qba_row) {
                *o -= qab * gj + gmi * qj;
            }
        }
    }
    for m in 0..e {
        for l in 0..e {
            let qbb = q[(d + m) * n + d + l];
            if qbb == ZERO {
                continue;
            }
            for i in 0..d {
                let gi = g[m * d + i] * qbb;
                for j in 0..d {
                    out[i * d + j] += gi * g[l * d + j];
                }
            }
        }
    }
}
