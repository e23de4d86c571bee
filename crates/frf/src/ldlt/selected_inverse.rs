//! The selected inverse: `(P Z P^T)^-1` on the pattern of `L` plus the
//! diagonal, from the factors, by the Takahashi equations.

use num_complex::Complex64 as C64;

use super::{NumericLdlt, SymbolicLdlt, ZERO};

/// Marks a row that is not in the column of `L` being inverted; see
/// [`SymbolicLdlt::selected_inverse`].
pub(crate) const NOT_IN_COLUMN: u32 = u32::MAX;

/// Whether both parts are finite.
#[inline(always)]
fn is_finite(z: C64) -> bool {
    z.re.is_finite() && z.im.is_finite()
}

impl SymbolicLdlt {
    /// The internal rows `rows` and their ancestors in the elimination tree
    /// (the parent of a column is the first row of `L` below its diagonal),
    /// as a mask over the internal rows. The set is closed: the rows of
    /// `L`'s column `j` are ancestors of `j`, so the solution of `L^T x = y`
    /// on these rows, and the selected inverse on these columns, read
    /// nothing outside it.
    pub(crate) fn reach(&self, rows: impl IntoIterator<Item = usize>) -> Vec<bool> {
        let mut mask = vec![false; self.n];
        for r in rows {
            mask[r] = true;
        }
        // ascending: a column's parent comes after it, and is marked in turn
        for j in 0..self.n {
            let (c0, c1) = (self.l_col_ptr[j], self.l_col_ptr[j + 1]);
            if mask[j] && c0 < c1 {
                mask[self.l_row_idx[c0] as usize] = true;
            }
        }
        mask
    }

    /// Position in the column storage of `L` of the entry `(row, col)`,
    /// internal order, `row > col`; `None` when it is not in the pattern.
    pub(crate) fn lower_position(&self, row: usize, col: usize) -> Option<usize> {
        let start = self.l_col_ptr[col];
        let rows = &self.l_row_idx[start..self.l_col_ptr[col + 1]];
        rows.binary_search(&(row as u32)).ok().map(|p| start + p)
    }

    /// Selected inverse by the Takahashi equations: `B^-1` (`B = P Z P^T`,
    /// factorised in `num`) on the pattern of `L` plus the diagonal, written
    /// to `diag` (length `n`) and `lower` (the layout of `L`'s columns).
    /// `slot` is `n` entries of [`NOT_IN_COLUMN`] and is left so. Allocates
    /// nothing. Returns whether every entry is finite.
    ///
    /// From `B^-1 = L^-T D^-1 L^-1`, `L^T B^-1 = D^-1 L^-1` is lower
    /// triangular with diagonal `D^-1`. Reading its column `j` below and on
    /// the diagonal, with `S` the rows of `L`'s column `j`:
    ///
    /// ```text
    /// B^-1[S, j] = -B^-1[S, S] L[S, j]
    /// B^-1[j, j] = D^-1[j] - L[S, j]^T B^-1[S, j]
    /// ```
    ///
    /// Columns are computed from the last to the first, and every `B^-1[S, S]`
    /// needed is already known and in the pattern: the filled graph is
    /// chordal, so for `t` in `S` the rows of `S` below `t` are rows of
    /// `L`'s column `t`. The product walks `B^-1[S, S]` by its stored lower
    /// triangle: the entry `(r, t)`, `r > t`, contributes to row `t` through
    /// `L[r, j]` and to row `r` through `L[t, j]`.
    ///
    /// With `within` (a closed set of columns, [`Self::reach`]) only its
    /// columns are computed: a column reads only the columns of its rows,
    /// which are its ancestors in the elimination tree. The others are left
    /// as they were.
    pub(crate) fn selected_inverse(
        &self,
        num: &NumericLdlt,
        diag: &mut [C64],
        lower: &mut [C64],
        slot: &mut [u32],
        within: Option<&[bool]>,
    ) -> bool {
        let n = self.n;
        assert!(diag.len() == n && lower.len() == self.nnz_l() && slot.len() == n, "selected inverse of another size");
        let (l_val, d_inv) = (&num.l_val[..], &num.d_inv[..n]);
        let mut finite = true;
        for j in (0..n).rev() {
            if within.is_some_and(|w| !w[j]) {
                continue;
            }
            let (c0, c1) = (self.l_col_ptr[j], self.l_col_ptr[j + 1]);
            let rows = &self.l_row_idx[c0..c1];
            let l_j = &l_val[c0..c1];
            // columns right of j are final and read-only while column j is made
            let (head, done) = lower.split_at_mut(c1);
            let out = &mut head[c0..];
            out.fill(ZERO);
            let Some(&last) = rows.last() else {
                diag[j] = d_inv[j];
                finite &= is_finite(diag[j]);
                continue;
            };
            for (b, &r) in rows.iter().enumerate() {
                slot[r as usize] = b as u32;
            }
            for (a, (&t, &l_tj)) in rows.iter().zip(l_j).enumerate() {
                let t = t as usize;
                let mut acc = -diag[t] * l_tj;
                let (t0, t1) = (self.l_col_ptr[t], self.l_col_ptr[t + 1]);
                // rows of column t below the last row of S cannot be in S
                for (&r, &z) in self.l_row_idx[t0..t1].iter().zip(&done[t0 - c1..t1 - c1]) {
                    if r > last {
                        break;
                    }
                    let b = slot[r as usize];
                    if b != NOT_IN_COLUMN {
                        let b = b as usize;
                        out[b] -= z * l_tj;
                        acc -= z * l_j[b];
                    }
                }
                out[a] += acc;
            }
            let mut d = d_inv[j];
            for ((&r, &l), &v) in rows.iter().zip(l_j).zip(out.iter()) {
                d -= l * v;
                slot[r as usize] = NOT_IN_COLUMN;
                finite &= is_finite(v);
            }
            diag[j] = d;
            finite &= is_finite(d);
        }
        finite
    }
}
