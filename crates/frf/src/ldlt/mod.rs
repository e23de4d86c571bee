//! Sparse complex-symmetric `L D L^T` factorisation without pivoting.
//!
//! `Z(w)` is complex symmetric (`Z = Z^T`, not Hermitian), so it has, when its
//! leading pivots do not vanish, a factorisation `P Z P^T = L D L^T` with a
//! unit lower-triangular `L` and a diagonal `D`, both complex. faer offers
//! Hermitian `L D L^H` and LU, but not this; it costs about half an LU and
//! needs no row pivoting, so the sparsity structure is fixed once per pattern.
//!
//! - [`SymbolicLdlt`] (once per pattern): a fill-reducing ordering (faer's
//!   approximate minimum degree), the elimination tree and the pattern of `L`
//!   (faer's simplicial symbolic Cholesky), and the row structure of `L` for
//!   the up-looking numeric factorisation below. Optional cliques of
//!   equations are added to the pattern analysed (not to the values), so
//!   that the selected inverse covers them.
//! - [`NumericLdlt`] (per thread): the values of `L` and `D^-1`, a dense work
//!   vector and a solve buffer, all reused from one frequency to the next.
//!
//! The numeric factorisation is up-looking (row `k` of `L` is a sparse
//! triangular solve with the rows above it, along the precomputed row
//! pattern), after T. A. Davis's LDL. Without pivoting it is only as stable
//! as the pivots: a pivot that is tiny against the matrix entries of its row,
//! or against the terms that were subtracted to form it, or that is not
//! finite, aborts the factorisation with [`TinyPivot`], and the caller falls
//! back to LU with partial pivoting.
//!
//! [`SymbolicLdlt::selected_inverse`] computes `(P Z P^T)^-1` on the pattern
//! of `L` plus the diagonal from the factors, by the Takahashi equations,
//! for about the cost of the numeric factorisation.
//!
//! Right-hand sides are stored *row-interleaved* (`x[i * k + j]` is row `i`
//! of right-hand side `j`) in the solver's internal order: each elimination
//! step then updates `k` contiguous values, which the compiler vectorises,
//! instead of `k` strided ones.
//!
//! One file per operation: [`symbolic`] (ordering, elimination tree and the
//! pattern of `L`), [`factor`] (the numeric factorisation), [`solve`] (the
//! substitutions and their SIMD kernels) and [`selected_inverse`].

use num_complex::Complex64 as C64;

mod factor;
mod selected_inverse;
mod solve;
mod symbolic;

pub(crate) use selected_inverse::NOT_IN_COLUMN;
pub use solve::mul_add;

/// A pivot `d` is accepted when `|d| > PIVOT_TOLERANCE * scale`, where
/// `scale` is the larger of the largest entry of its row of `Z` and the sum of
/// the terms subtracted from the diagonal to form it (so at most about eight
/// digits can be lost to cancellation in any pivot). Norms are `|re| + |im|`.
pub(crate) const PIVOT_TOLERANCE: f64 = 1e-8;

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };

/// The factorisation met a pivot that is tiny or not finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TinyPivot {
    /// Position in the solver's internal order.
    pub(crate) index: usize,
}

/// Symbolic analysis of a symmetric pattern; see the module docs.
#[derive(Clone, Debug)]
pub(crate) struct SymbolicLdlt {
    n: usize,
    /// `perm[new] = old`.
    perm: Vec<usize>,
    /// `perm_inv[old] = new`.
    perm_inv: Vec<usize>,
    /// Column pointers of the original pattern (for row scales).
    orig_col_ptr: Vec<usize>,
    /// Upper triangle of `P Z P^T` by column: rows (`<= j`, ascending) and the
    /// position of each entry in the original values array.
    a_col_ptr: Vec<usize>,
    a_row_idx: Vec<u32>,
    a_src: Vec<usize>,
    /// Strictly lower `L` by column, rows ascending.
    l_col_ptr: Vec<usize>,
    l_row_idx: Vec<u32>,
    /// Row structure of strictly lower `L`: for row `k`, the columns `i < k`
    /// (ascending, a topological order of the elimination tree) and the
    /// position of `L[k, i]` in the column storage.
    lt_row_ptr: Vec<usize>,
    lt_col: Vec<u32>,
    lt_pos: Vec<usize>,
}

/// Numeric factors and buffers of one thread; see the module docs.
#[derive(Clone, Debug, Default)]
pub(crate) struct NumericLdlt {
    l_val: Vec<C64>,
    d_inv: Vec<C64>,
    y: Vec<C64>,
    /// Row-interleaved right-hand sides in the internal order.
    pub(crate) buf: Vec<C64>,
    /// Sorted unit right-hand sides of [`SymbolicLdlt::solve_units`].
    pub(crate) units: Vec<(usize, usize)>,
    /// Internal rows of unit right-hand sides (caller's scratch).
    pub(crate) buf_rows: Vec<usize>,
}

impl SymbolicLdlt {
    /// Matrix dimension.
    pub(crate) fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries of `L` below the diagonal.
    pub(crate) fn nnz_l(&self) -> usize {
        self.l_row_idx.len()
    }

    /// Complex multiply-adds of one numeric factorisation: column `j` of
    /// `L`, with `c` entries below the diagonal, is scaled by its pivot (`c`)
    /// and updates the `c (c + 1) / 2` entries of the trailing matrix its
    /// rows pair up (`c (c + 3) / 2` in all). It grows with the square of the
    /// column counts, where [`Self::nnz_l`] grows with their sum.
    pub(crate) fn multiply_adds(&self) -> u64 {
        self.l_col_ptr.windows(2).map(|w| (w[1] - w[0]) as u64).map(|c| c * (c + 3) / 2).sum()
    }

    /// `perm[new] = old`.
    pub(crate) fn perm(&self) -> &[usize] {
        &self.perm
    }

    /// `perm_inv[old] = new`.
    pub(crate) fn perm_inv(&self) -> &[usize] {
        &self.perm_inv
    }

    /// Empty numeric storage of the right sizes.
    pub(crate) fn numeric(&self) -> NumericLdlt {
        NumericLdlt {
            l_val: vec![ZERO; self.nnz_l()],
            d_inv: vec![ZERO; self.n],
            y: vec![ZERO; self.n],
            buf: Vec::new(),
            units: Vec::new(),
            buf_rows: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use fe_model::Pattern;

    use super::symbolic::with_clique_pairs;
    use super::*;

    /// Tridiagonal pattern and values with a dominant complex diagonal.
    fn tridiagonal(n: usize) -> (Pattern, Vec<C64>) {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut vals = Vec::new();
        for c in 0..n {
            for r in c.saturating_sub(1)..(c + 2).min(n) {
                row_idx.push(r);
                let v = if r == c { C64::new(4.0 + c as f64, 0.5) } else { C64::new(-1.0, 0.2 * (r + c) as f64) };
                vals.push(v);
            }
            col_ptr.push(row_idx.len());
        }
        (Pattern::new(n, col_ptr, row_idx).unwrap(), vals)
    }

    #[test]
    fn tridiagonal_solution_has_small_residual_and_no_fill() {
        let n = 50;
        let (pat, vals) = tridiagonal(n);
        let sym = SymbolicLdlt::new(&pat, &[]).unwrap();
        assert_eq!(sym.nnz_l(), n - 1, "a tridiagonal matrix has no fill under AMD");
        let mut num = sym.numeric();
        sym.factorize(&mut num, &vals).unwrap();
        let k = 3;
        let b: Vec<C64> = (0..n * k).map(|t| C64::new(t as f64 % 7.0, 1.0 - (t % 3) as f64)).collect();
        // permute b into internal order, solve, permute back
        let mut x = vec![ZERO; n * k];
        for new in 0..n {
            x[new * k..(new + 1) * k].copy_from_slice(&b[sym.perm()[new] * k..][..k]);
        }
        assert!(sym.solve_in_place(&num, &mut x, k));
        let mut sol = vec![ZERO; n * k];
        for old in 0..n {
            sol[old * k..(old + 1) * k].copy_from_slice(&x[sym.perm_inv()[old] * k..][..k]);
        }
        for j in 0..k {
            for c in 0..n {
                let mut r = -b[c * k + j];
                for p in pat.col_ptr()[c]..pat.col_ptr()[c + 1] {
                    r += vals[p] * sol[pat.row_idx()[p] * k + j];
                }
                assert!(r.norm() < 1e-13 * b[c * k + j].norm().max(1.0), "row {c} rhs {j}: {r}");
            }
        }
    }

    #[test]
    fn clique_pairs_are_added_once_to_both_triangles() {
        let (pat, _) = tridiagonal(9);
        // a repeated equation, an overlap with the pattern and a singleton
        let cliques = vec![vec![0, 4, 8, 4], vec![3, 4], vec![6]];
        let aug = with_clique_pairs(&pat, &cliques).unwrap();
        let mut expected = std::collections::BTreeSet::new();
        for c in 0..pat.n() {
            for &r in &pat.row_idx()[pat.col_ptr()[c]..pat.col_ptr()[c + 1]] {
                expected.insert((c, r));
            }
        }
        for clique in &cliques {
            for &a in clique {
                for &b in clique {
                    expected.insert((a, b));
                }
            }
        }
        let mut got = Vec::new();
        for c in 0..aug.n() {
            for &r in &aug.row_idx()[aug.col_ptr()[c]..aug.col_ptr()[c + 1]] {
                got.push((c, r));
            }
        }
        assert_eq!(got, expected.into_iter().collect::<Vec<_>>(), "sorted by column, then row, without repeats");
        let e = with_clique_pairs(&pat, &[vec![2, 9]]).unwrap_err();
        assert!(e.contains(&format!("clique equation 9 is not below {}", pat.n())), "{e}");
    }

    /// The fill and the multiply-adds of the analysis against a dense
    /// elimination in the same order: on a 7 x 6 five-point grid, whose
    /// factor fills in (unlike a band's).
    #[test]
    fn fill_and_multiply_adds_equal_a_dense_elimination() {
        let (nx, ny) = (7, 6);
        let n = nx * ny;
        let (mut col_ptr, mut row_idx) = (vec![0], Vec::new());
        for c in 0..n {
            let (x, y) = (c % nx, c / nx);
            let mut rows = vec![c];
            if x > 0 {
                rows.push(c - 1);
            }
            if x + 1 < nx {
                rows.push(c + 1);
            }
            if y > 0 {
                rows.push(c - nx);
            }
            if y + 1 < ny {
                rows.push(c + nx);
            }
            rows.sort_unstable();
            row_idx.extend(rows);
            col_ptr.push(row_idx.len());
        }
        let pat = Pattern::new(n, col_ptr, row_idx).unwrap();
        let sym = SymbolicLdlt::new(&pat, &[]).unwrap();
        // the pattern in the analysis's order, eliminated densely
        let mut filled = vec![vec![false; n]; n];
        for c in 0..n {
            for &r in pat.rows(c) {
                filled[sym.perm_inv()[r]][sym.perm_inv()[c]] = true;
            }
        }
        let (mut nnz, mut madds) = (0, 0u64);
        for j in 0..n {
            let below: Vec<usize> = (j + 1..n).filter(|&i| filled[i][j]).collect();
            for &a in &below {
                for &b in &below {
                    filled[a][b] = true;
                }
            }
            let c = below.len() as u64;
            nnz += below.len();
            madds += c * (c + 3) / 2;
        }
        assert!(nnz > 2 * n, "the grid fills in: {nnz} entries below the diagonal");
        assert_eq!(sym.nnz_l(), nnz);
        assert_eq!(sym.multiply_adds(), madds);
    }

    #[test]
    fn a_zero_leading_pivot_is_reported() {
        // [[0, 1], [1, 0]]: nonsingular, but no LDL^T without pivoting
        let pat = Pattern::new(2, vec![0, 2, 4], vec![0, 1, 0, 1]).unwrap();
        let vals = [ZERO, C64::new(1.0, 0.0), C64::new(1.0, 0.0), ZERO];
        let sym = SymbolicLdlt::new(&pat, &[]).unwrap();
        let mut num = sym.numeric();
        assert_eq!(sym.factorize(&mut num, &vals), Err(TinyPivot { index: 0 }));
    }
}
