//! Sparse complex-symmetric `L D L^T` factorisation without pivoting.
//!
//! `Z(w)` is complex symmetric (`Z = Z^T`, not Hermitian), so it has, when its
//! leading pivots do not vanish, a factorisation `P Z P^T = L D L^T` with a
//! unit lower-triangular `L` and a diagonal `D`, both complex. faer offers
//! Hermitian `L D L^H` and LU, but not this; it costs about half an LU and
//! needs no row pivoting, so the sparsity structure is fixed once per pattern.
//!
//! Two layouts of `L` share the ordering (faer's approximate minimum
//! degree of the pattern, optional cliques of equations added to the
//! pattern analysed so that the selected inverse covers them) and the
//! pivot test, and [`Analysis`] picks one from the symbolic analysis:
//!
//! - **simplicial** ([`SymbolicLdlt`]): `L` by column, entry by entry;
//!   the numeric factorisation is up-looking (row `k` of `L` is a sparse
//!   triangular solve with the rows above it, along the precomputed row
//!   pattern), after T. A. Davis's LDL. Best where columns are short (beams
//!   and frames: a few multiply-adds per entry of `L`), where it has no
//!   overhead to amortise.
//! - **supernodal** ([`supernodal`]): runs of columns with one pattern
//!   below them stored as dense blocks, factorised multifrontally with
//!   dense kernels. Best where columns are long (shells and solids: hundreds
//!   of multiply-adds per entry), where the dense kernels run several times
//!   faster.
//!
//! Without pivoting the factorisation is only as stable as the pivots: a
//! pivot that is tiny against the matrix entries of its row, or against the
//! terms that were subtracted to form it, or that is not finite, aborts the
//! factorisation with [`TinyPivot`], and the caller falls back to LU with
//! partial pivoting.
//!
//! [`Analysis::selected_inverse`] computes `(P Z P^T)^-1` on the pattern of
//! `L` plus the diagonal from the factors, by the Takahashi equations,
//! for about the cost of the numeric factorisation.
//!
//! Right-hand sides are stored *row-interleaved* (`x[i * k + j]` is row `i`
//! of right-hand side `j`) in the solver's internal order: each elimination
//! step then updates `k` contiguous values, which the compiler vectorises,
//! instead of `k` strided ones.
//!
//! One file per operation of the simplicial layout: [`symbolic`] (the
//! shared ordering and elimination tree, and the pattern of `L`), [`factor`]
//! (the numeric factorisation), [`solve`] (the substitutions and their SIMD
//! kernels) and [`selected_inverse`]; the supernodal layout in [`supernodal`].

use fe_model::Pattern;
use num_complex::Complex64 as C64;

use crate::factor_kind::Layout;

mod factor;
mod selected_inverse;
mod solve;
mod supernodal;
mod symbolic;

pub(crate) use selected_inverse::NOT_IN_COLUMN;
pub use solve::mul_add;
use supernodal::{NumericSupernodal, SupernodalLdlt};

/// A pivot `d` is accepted when `|d| > PIVOT_TOLERANCE * scale`, where
/// `scale` is the larger of the largest entry of its row of `Z` and the sum of
/// the terms subtracted from the diagonal to form it (so at most about eight
/// digits can be lost to cancellation in any pivot). Norms are `|re| + |im|`.
pub(crate) const PIVOT_TOLERANCE: f64 = 1e-8;

/// The supernodal layout is chosen when one factorisation needs more than
/// this many multiply-adds per entry of `L` (see [`Analysis::new`]).
/// Measured on one thread (`cargo run --release -p frf --example layouts`):
/// the two layouts factorise and solve in the same time at 10 to 12
/// multiply-adds per entry (plates of 72 and 120 DOFs); the supernodal one
/// is 1.5 times faster at 16 to 22 (plates, frames with one element per
/// member) and 2 to 3 times faster from 40 on (plates of 2,500 DOFs and
/// more), the simplicial one 1.5 to 2.5 times faster at 4 to 9 (long beams,
/// frames with several elements per member).
pub(crate) const SUPERNODAL_MADDS_PER_ENTRY: f64 = 16.0;

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };

/// The factorisation met a pivot that is tiny or not finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TinyPivot {
    /// Position in the solver's internal order.
    pub(crate) index: usize,
}

/// The symbolic analysis in one of the two layouts; see the module docs.
#[derive(Clone, Debug)]
pub(crate) enum Analysis {
    Simplicial(SymbolicLdlt),
    Supernodal(SupernodalLdlt),
}

/// Numeric factors and buffers of one thread, in the layout of their
/// [`Analysis`].
#[derive(Clone, Debug)]
pub(crate) enum Factors {
    Simplicial(NumericLdlt),
    Supernodal(NumericSupernodal),
}

/// Scratch of the selected inverse, grown on first use.
#[derive(Clone, Debug, Default)]
pub(crate) struct InverseScratch {
    /// Simplicial: `n` entries of [`NOT_IN_COLUMN`].
    slot: Vec<u32>,
    /// Supernodal: dense blocks and row positions.
    work: Vec<C64>,
    rel: Vec<u32>,
}

impl Analysis {
    /// Orders and analyses a symmetric pattern (both triangles stored, rows
    /// sorted, diagonal present) in the given layout, or in the one its
    /// factor calls for: supernodal when a factorisation needs more than
    /// [`SUPERNODAL_MADDS_PER_ENTRY`] multiply-adds per entry of `L` (the
    /// columns are then long enough for dense kernels to pay), simplicial
    /// otherwise.
    ///
    /// The ordering and the pattern of `L` are those of the pattern with
    /// every pair of equations within each clique added (caller's numbering,
    /// an index out of range is an error), so that `L + L^T` covers each
    /// clique and the selected inverse holds every entry of `Z^-1` between
    /// its equations. The added pairs are structural zeros: values are still
    /// read on the original pattern.
    pub(crate) fn new(pattern: &Pattern, cliques: &[Vec<usize>], layout: Option<Layout>) -> Result<Self, String> {
        let ordering = symbolic::order(pattern, cliques)?;
        let layout = layout.unwrap_or_else(|| {
            let analysed = ordering.augmented.as_ref().unwrap_or(pattern);
            let (ptr, rows, _) = symbolic::permuted_upper(analysed, &ordering.perm, &ordering.perm_inv);
            let (_, counts) = symbolic::elimination_tree(pattern.n(), &ptr, &rows);
            let (nnz, madds) = counts.iter().fold((0.0, 0.0), |(nnz, madds), &c| {
                let below = c as f64 - 1.0;
                (nnz + below, madds + below * (below + 3.0) / 2.0)
            });
            if madds > SUPERNODAL_MADDS_PER_ENTRY * nnz { Layout::Supernodal } else { Layout::Simplicial }
        });
        Ok(match layout {
            Layout::Simplicial => Analysis::Simplicial(SymbolicLdlt::from_ordering(pattern, ordering)?),
            Layout::Supernodal => Analysis::Supernodal(SupernodalLdlt::from_ordering(pattern, ordering)?),
        })
    }

    /// The layout.
    pub(crate) fn layout(&self) -> Layout {
        match self {
            Analysis::Simplicial(_) => Layout::Simplicial,
            Analysis::Supernodal(_) => Layout::Supernodal,
        }
    }

    /// Matrix dimension.
    pub(crate) fn n(&self) -> usize {
        match self {
            Analysis::Simplicial(a) => a.n(),
            Analysis::Supernodal(a) => a.n(),
        }
    }

    /// Entries of `L` below the diagonal as stored (the supernodal layout
    /// stores explicit zeros where it merged supernodes of nearly equal
    /// patterns).
    pub(crate) fn nnz_stored(&self) -> usize {
        match self {
            Analysis::Simplicial(a) => a.nnz_l(),
            Analysis::Supernodal(a) => a.nnz_stored(),
        }
    }

    /// Entries of `L` below the diagonal in the elimination's pattern.
    pub(crate) fn nnz_exact(&self) -> usize {
        match self {
            Analysis::Simplicial(a) => a.nnz_l(),
            Analysis::Supernodal(a) => a.nnz_exact(),
        }
    }

    /// Complex multiply-adds of one numeric factorisation in the
    /// elimination's pattern: column `j` of `L`, with `c` entries below the
    /// diagonal, is scaled by its pivot (`c`) and updates the `c (c + 1) / 2`
    /// entries of the trailing matrix its rows pair up (`c (c + 3) / 2` in
    /// all). It grows with the square of the column counts, where
    /// [`Self::nnz_exact`] grows with their sum.
    pub(crate) fn multiply_adds(&self) -> u64 {
        match self {
            Analysis::Simplicial(a) => a.multiply_adds(),
            Analysis::Supernodal(a) => a.multiply_adds(),
        }
    }

    /// `perm[new] = old`.
    pub(crate) fn perm(&self) -> &[usize] {
        match self {
            Analysis::Simplicial(a) => a.perm(),
            Analysis::Supernodal(a) => a.perm(),
        }
    }

    /// `perm_inv[old] = new`.
    pub(crate) fn perm_inv(&self) -> &[usize] {
        match self {
            Analysis::Simplicial(a) => a.perm_inv(),
            Analysis::Supernodal(a) => a.perm_inv(),
        }
    }

    /// Empty numeric storage of the right sizes.
    pub(crate) fn numeric(&self) -> Factors {
        match self {
            Analysis::Simplicial(a) => Factors::Simplicial(a.numeric()),
            Analysis::Supernodal(a) => Factors::Supernodal(a.numeric()),
        }
    }

    /// Factorises `Z` given as values on the original pattern. Allocates
    /// nothing. On error, `num` holds no usable factorisation.
    pub(crate) fn factorize(&self, num: &mut Factors, values: &[C64]) -> Result<(), TinyPivot> {
        match (self, num) {
            (Analysis::Simplicial(a), Factors::Simplicial(f)) => a.factorize(f, values),
            (Analysis::Supernodal(a), Factors::Supernodal(f)) => a.factorize(f, values),
            _ => unreachable!("factors of another layout"),
        }
    }

    /// Solves `P Z P^T X = B` in place for `k` right-hand sides stored
    /// row-interleaved in the internal order (`x.len() == n * k`). Returns
    /// whether every entry of the solution is finite.
    pub(crate) fn solve_in_place(&self, num: &mut Factors, x: &mut [C64], k: usize) -> bool {
        match (self, num) {
            (Analysis::Simplicial(a), Factors::Simplicial(f)) => a.solve_in_place(f, x, k),
            (Analysis::Supernodal(a), Factors::Supernodal(f)) => a.solve_in_place(f, x, k),
            _ => unreachable!("factors of another layout"),
        }
    }

    /// As [`Self::solve_in_place`] for unit right-hand sides, which need not
    /// be written beforehand: column `j` is the unit vector at internal row
    /// `rows[j]`. Every entry of `x` is overwritten.
    ///
    /// `visit(r, &x[r * k..])` is called for each internal row `r`, from the
    /// last to the first, as soon as rows `r..n` are final (while they are
    /// still in cache).
    ///
    /// With `within` (from [`Self::reach`]) the simplicial layout solves
    /// only for its rows, and visits only them; the others are left
    /// undefined. The supernodal layout solves for every row.
    pub(crate) fn solve_units<V: FnMut(usize, &[C64])>(
        &self,
        num: &mut Factors,
        rows: &[usize],
        x: &mut [C64],
        within: Option<&[bool]>,
        visit: V,
    ) -> bool {
        match (self, num) {
            (Analysis::Simplicial(a), Factors::Simplicial(f)) => a.solve_units(f, rows, x, within, visit),
            (Analysis::Supernodal(a), Factors::Supernodal(f)) => a.solve_units(f, rows, x, visit),
            _ => unreachable!("factors of another layout"),
        }
    }

    /// The internal rows `rows` and every row the solution there, or the
    /// selected inverse between them, depends on (their ancestors in the
    /// elimination tree), as a mask over the internal rows; `None` in the
    /// supernodal layout, whose solves and inversions cover every row.
    pub(crate) fn reach(&self, rows: impl IntoIterator<Item = usize>) -> Option<Vec<bool>> {
        match self {
            Analysis::Simplicial(a) => Some(a.reach(rows)),
            Analysis::Supernodal(_) => None,
        }
    }

    /// Length of a selected inverse's values.
    pub(crate) fn inverse_len(&self) -> usize {
        match self {
            Analysis::Simplicial(a) => a.n() + a.nnz_l(),
            Analysis::Supernodal(a) => a.values_len(),
        }
    }

    /// Position in a selected inverse's values of the entry `(p, q)`
    /// (internal order, either triangle), or `None` when it is not stored.
    pub(crate) fn inverse_position(&self, p: usize, q: usize) -> Option<usize> {
        let (row, col) = (p.max(q), p.min(q));
        match self {
            Analysis::Simplicial(_) if row == col => Some(row),
            Analysis::Simplicial(a) => a.lower_position(row, col).map(|pos| a.n() + pos),
            Analysis::Supernodal(a) => a.position(row, col),
        }
    }

    /// Selected inverse: `B^-1` (`B = P Z P^T`, factorised in `num`) on the
    /// pattern of the factor, written to `out` (length
    /// [`Self::inverse_len`], read through [`Self::inverse_position`]).
    /// Allocates nothing once `scratch` has been used with this analysis.
    /// Returns whether every entry is finite.
    ///
    /// With `within` (from [`Self::reach`]) the simplicial layout inverts
    /// only its columns (the entries between its rows); the supernodal
    /// layout inverts every column.
    pub(crate) fn selected_inverse(
        &self,
        num: &Factors,
        out: &mut [C64],
        scratch: &mut InverseScratch,
        within: Option<&[bool]>,
    ) -> bool {
        match (self, num) {
            (Analysis::Simplicial(a), Factors::Simplicial(f)) => {
                if scratch.slot.len() != a.n() {
                    scratch.slot = vec![NOT_IN_COLUMN; a.n()];
                }
                let (diag, lower) = out.split_at_mut(a.n());
                a.selected_inverse(f, diag, lower, &mut scratch.slot, within)
            }
            (Analysis::Supernodal(a), Factors::Supernodal(f)) => {
                a.selected_inverse(f, out, &mut scratch.work, &mut scratch.rel)
            }
            _ => unreachable!("factors of another layout"),
        }
    }
}

/// Simplicial symbolic analysis of a symmetric pattern; see the module docs.
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

/// Simplicial numeric factors and buffers of one thread; see the module
/// docs.
#[derive(Clone, Debug, Default)]
pub(crate) struct NumericLdlt {
    l_val: Vec<C64>,
    d_inv: Vec<C64>,
    y: Vec<C64>,
    /// Sorted unit right-hand sides of [`SymbolicLdlt::solve_units`].
    units: Vec<(usize, usize)>,
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
            units: Vec::new(),
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
