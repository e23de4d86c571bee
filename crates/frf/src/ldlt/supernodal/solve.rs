//! Forward and backward substitution with the supernodal factors, for
//! right-hand sides stored row-interleaved in the internal order: within a
//! supernode a dense triangular solve, and below it one matrix product.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_unit_lower_triangular_in_place_with_conj, solve_unit_upper_triangular_in_place_with_conj,
};
use faer::traits::pulp::{Arch, Simd, WithSimd};
use faer::{Accum, Conj, MatMut, MatRef, Par};
use num_complex::Complex64 as C64;

use super::super::solve::{flush_tiny, mul_add, scale};
use super::{NumericSupernodal, SupernodalLdlt, ZERO};

const ONE: C64 = C64 { re: 1.0, im: 0.0 };
const MINUS_ONE: C64 = C64 { re: -1.0, im: 0.0 };

impl SupernodalLdlt {
    /// Solves `P Z P^T X = B` in place for `k` right-hand sides stored
    /// row-interleaved in the internal order (`x.len() == n * k`). Returns
    /// whether every entry of the solution is finite.
    pub(crate) fn solve_in_place(&self, num: &mut NumericSupernodal, x: &mut [C64], k: usize) -> bool {
        assert_eq!(x.len(), self.n * k, "right-hand sides must be n x k, row-interleaved");
        if k == 0 {
            return true;
        }
        self.substitute(num, x, k, 0, |_, _| {})
    }

    /// As [`Self::solve_in_place`] for unit right-hand sides, which need not
    /// be written beforehand: column `j` is the unit vector at internal row
    /// `rows[j]`. Every entry of `x` is overwritten. `visit(r, &x[r * k..])`
    /// is called for each internal row `r`, from the last to the first, as
    /// soon as rows `r..n` are final.
    pub(crate) fn solve_units<V: FnMut(usize, &[C64])>(
        &self,
        num: &mut NumericSupernodal,
        rows: &[usize],
        x: &mut [C64],
        visit: V,
    ) -> bool {
        let k = rows.len();
        assert_eq!(x.len(), self.n * k, "solutions must be n x k, row-interleaved");
        if k == 0 {
            return true;
        }
        x.fill(ZERO);
        for (j, &r) in rows.iter().enumerate() {
            x[r * k + j] = ONE;
        }
        let first = rows.iter().copied().min().unwrap_or(0);
        self.substitute(num, x, k, first, visit)
    }

    /// The substitutions; rows above `first` are zero on entry, so the
    /// supernodes that end above it are skipped in the forward sweep.
    fn substitute<V: FnMut(usize, &[C64])>(
        &self,
        num: &mut NumericSupernodal,
        x: &mut [C64],
        k: usize,
        first: usize,
        mut visit: V,
    ) -> bool {
        let NumericSupernodal { values, d_inv, gathered, .. } = num;
        if gathered.len() < self.max_rows * k {
            gathered.resize(self.max_rows * k, ZERO);
        }
        let arch = Arch::new();
        // forward, L y = b, then y <- D^-1 y
        let first_super = self.super_of.get(first).map_or(self.n_super(), |&s| s as usize);
        for s in first_super..self.n_super() {
            let (f, e, rows) = self.supernode(s);
            let (w, r) = (e - f, rows.len());
            let block = MatRef::from_column_major_slice(&values[self.val_ptr[s]..self.val_ptr[s + 1]], w + r, w);
            let (head, tail) = x.split_at_mut(e * k);
            let xs = &mut head[f * k..];
            solve_unit_lower_triangular_in_place_with_conj(
                block.submatrix(0, 0, w, w),
                Conj::No,
                MatMut::from_row_major_slice_mut(xs, w, k),
                Par::Seq,
            );
            flush_tiny(xs);
            if r > 0 {
                let t = &mut gathered[..r * k];
                matmul(
                    MatMut::from_row_major_slice_mut(t, r, k),
                    Accum::Replace,
                    block.submatrix(w, 0, r, w),
                    MatRef::from_row_major_slice(xs, w, k),
                    ONE,
                    Par::Seq,
                );
                arch.dispatch(Scatter { x: tail, e, k, rows, t });
            }
            arch.dispatch(ScaleRows { xs, d: &d_inv[f..e] });
        }
        // backward, L^T x = y
        let mut finite = true;
        for s in (0..self.n_super()).rev() {
            let (f, e, rows) = self.supernode(s);
            let (w, r) = (e - f, rows.len());
            let block = MatRef::from_column_major_slice(&values[self.val_ptr[s]..self.val_ptr[s + 1]], w + r, w);
            let (head, tail) = x.split_at_mut(e * k);
            let xs = &mut head[f * k..];
            if r > 0 {
                let t = &mut gathered[..r * k];
                for (dst, &g) in t.chunks_exact_mut(k).zip(rows) {
                    let at = (g as usize - e) * k;
                    dst.copy_from_slice(&tail[at..at + k]);
                }
                matmul(
                    MatMut::from_row_major_slice_mut(xs, w, k),
                    Accum::Add,
                    block.submatrix(w, 0, r, w).transpose(),
                    MatRef::from_row_major_slice(t, r, k),
                    MINUS_ONE,
                    Par::Seq,
                );
            }
            solve_unit_upper_triangular_in_place_with_conj(
                block.submatrix(0, 0, w, w).transpose(),
                Conj::No,
                MatMut::from_row_major_slice_mut(xs, w, k),
                Par::Seq,
            );
            flush_tiny(xs);
            finite &= xs.iter().all(|v| v.re.is_finite() && v.im.is_finite());
            for row in (f..e).rev() {
                visit(row, &x[row * k..]);
            }
        }
        finite
    }
}

/// `x[R[i]] -= t[i]` for the rows `R` of a supernode (`t` is `|R| x k`,
/// row-major; `x` starts at row `e`, below the supernode).
struct Scatter<'a> {
    x: &'a mut [C64],
    e: usize,
    k: usize,
    rows: &'a [u32],
    t: &'a [C64],
}

impl WithSimd for Scatter<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Scatter { x, e, k, rows, t } = self;
        for (src, &g) in t.chunks_exact(k).zip(rows) {
            let at = (g as usize - e) * k;
            mul_add(simd, &mut x[at..at + k], MINUS_ONE, src);
        }
    }
}

/// Row `j` of `xs` (`d.len()` rows, row-major) times `d[j]`.
struct ScaleRows<'a> {
    xs: &'a mut [C64],
    d: &'a [C64],
}

impl WithSimd for ScaleRows<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let k = self.xs.len() / self.d.len();
        for (row, &d) in self.xs.chunks_exact_mut(k).zip(self.d) {
            scale(simd, row, d);
        }
    }
}
