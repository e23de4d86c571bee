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

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::simplicial;
use faer::traits::pulp::{Arch, Simd, WithSimd};
use fe_model::Pattern;
use num_complex::Complex64 as C64;

use crate::solver::mul_add;

/// A pivot `d` is accepted when `|d| > PIVOT_TOLERANCE * scale`, where
/// `scale` is the larger of the largest entry of its row of `Z` and the sum of
/// the terms subtracted from the diagonal to form it (so at most about eight
/// digits can be lost to cancellation in any pivot). Norms are `|re| + |im|`.
pub(crate) const PIVOT_TOLERANCE: f64 = 1e-8;

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };

/// Marks a row that is not in the column of `L` being inverted; see
/// [`SymbolicLdlt::selected_inverse`].
pub(crate) const NOT_IN_COLUMN: u32 = u32::MAX;

/// Solution values smaller than this in magnitude are set to zero as each
/// row is finalised. Responses can decay by hundreds of orders of magnitude
/// across a large model (a long periodic structure in a stop band), and
/// arithmetic on subnormal numbers (below about 2.2e-308) is some hundred
/// times slower; values this small are far below anything physical.
const FLUSH_BELOW: f64 = 1e-200;

/// Sets parts of `row` smaller than [`FLUSH_BELOW`] to zero.
#[inline(always)]
fn flush_tiny(row: &mut [C64]) {
    for v in row {
        if v.re.abs() < FLUSH_BELOW {
            v.re = 0.0;
        }
        if v.im.abs() < FLUSH_BELOW {
            v.im = 0.0;
        }
    }
}

/// Whether both parts are finite.
#[inline(always)]
fn is_finite(z: C64) -> bool {
    z.re.is_finite() && z.im.is_finite()
}

/// `|re| + |im|`: a cheap norm within a factor sqrt(2) of the modulus.
#[inline(always)]
fn l1(z: C64) -> f64 {
    z.re.abs() + z.im.abs()
}

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
    /// Orders and analyses a symmetric pattern (both triangles stored, rows
    /// sorted, diagonal present).
    ///
    /// The ordering and the pattern of `L` are those of the pattern with
    /// every pair of equations within each clique added (caller's numbering,
    /// an index out of range is an error), so that `L + L^T` covers each clique
    /// and the selected inverse holds every entry of `Z^-1` between its
    /// equations. The added pairs are structural zeros: values are still
    /// read on the original pattern. With no cliques this is the plain
    /// analysis of `pattern`.
    pub(crate) fn new(pattern: &Pattern, cliques: &[Vec<usize>]) -> Result<Self, String> {
        let n = pattern.n;
        if u32::try_from(n).is_err() {
            return Err(format!("{n} equations exceed the solver's 32-bit row indices"));
        }
        let augmented = if cliques.is_empty() { None } else { Some(with_clique_pairs(pattern, cliques)?) };
        let analysed = augmented.as_ref().unwrap_or(pattern);

        // upper triangle of the analysed pattern, for the ordering
        let mut up_ptr = Vec::with_capacity(n + 1);
        let mut up_idx = Vec::with_capacity(analysed.nnz() / 2 + n);
        up_ptr.push(0);
        for c in 0..n {
            let rows = &analysed.row_idx[analysed.col_ptr[c]..analysed.col_ptr[c + 1]];
            up_idx.extend(rows.iter().copied().take_while(|&r| r <= c));
            up_ptr.push(up_idx.len());
        }
        let mut perm = vec![0usize; n];
        let mut perm_inv = vec![0usize; n];
        {
            let upper = SymbolicSparseColMatRef::new_checked(n, n, &up_ptr, None, &up_idx);
            let mut mem = MemBuffer::new(amd::order_scratch::<usize>(n, up_idx.len()));
            amd::order(&mut perm, &mut perm_inv, upper, amd::Control::default(), MemStack::new(&mut mem))
                .map_err(|e| format!("ordering failed: {e:?}"))?;
        }
        drop((up_ptr, up_idx));

        // the numeric factorisation reads the values of the original pattern
        let (a_col_ptr, a_row_usize, a_src) = permuted_upper(pattern, &perm, &perm_inv);
        let a_row_idx: Vec<u32> = a_row_usize.iter().map(|&i| i as u32).collect();
        // while the elimination tree and L come from the analysed one
        let (e_col_ptr, e_row_idx) = match &augmented {
            Some(aug) => {
                let (ptr, rows, _) = permuted_upper(aug, &perm, &perm_inv);
                (ptr, rows)
            }
            None => (a_col_ptr.clone(), a_row_usize),
        };
        drop(augmented);
        let nnz_e = e_row_idx.len();

        // elimination tree, column counts and the pattern of L (faer)
        let l_symbolic = {
            let upper = SymbolicSparseColMatRef::new_checked(n, n, &e_col_ptr, None, &e_row_idx);
            let mut etree = vec![0isize; n];
            let mut counts = vec![0usize; n];
            let mut mem = MemBuffer::new(
                simplicial::prefactorize_symbolic_cholesky_scratch::<usize>(n, nnz_e)
                    .or(simplicial::factorize_simplicial_symbolic_cholesky_scratch::<usize>(n)),
            );
            let etree_ref =
                simplicial::prefactorize_symbolic_cholesky(&mut etree, &mut counts, upper, MemStack::new(&mut mem));
            simplicial::factorize_simplicial_symbolic_cholesky(upper, etree_ref, &counts, MemStack::new(&mut mem))
                .map_err(|e| format!("symbolic factorisation failed: {e:?}"))?
        };
        drop((e_col_ptr, e_row_idx));

        // strictly lower part (faer stores the diagonal first in each column)
        let (f_ptr, f_idx) = (l_symbolic.col_ptr(), l_symbolic.row_idx());
        let mut l_col_ptr = Vec::with_capacity(n + 1);
        let mut l_row_idx = Vec::with_capacity(f_idx.len() - n);
        l_col_ptr.push(0);
        for j in 0..n {
            let col = &f_idx[f_ptr[j]..f_ptr[j + 1]];
            if col.first() != Some(&j) {
                return Err("symbolic factor without its diagonal".into());
            }
            let below = &col[1..];
            if below.windows(2).any(|w| w[0] >= w[1]) || below.first().is_some_and(|&r| r <= j) {
                return Err("symbolic factor rows are not sorted".into());
            }
            l_row_idx.extend(below.iter().map(|&r| r as u32));
            l_col_ptr.push(l_row_idx.len());
        }
        drop(l_symbolic);

        // row structure by a counting transpose: columns visited in ascending
        // order, so each row lists its columns ascending
        let nnz_l = l_row_idx.len();
        let mut lt_row_ptr = vec![0usize; n + 1];
        for &r in &l_row_idx {
            lt_row_ptr[r as usize + 1] += 1;
        }
        for k in 0..n {
            lt_row_ptr[k + 1] += lt_row_ptr[k];
        }
        let mut next = lt_row_ptr[..n].to_vec();
        let mut lt_col = vec![0u32; nnz_l];
        let mut lt_pos = vec![0usize; nnz_l];
        for i in 0..n {
            for p in l_col_ptr[i]..l_col_ptr[i + 1] {
                let k = l_row_idx[p] as usize;
                let q = next[k];
                next[k] += 1;
                lt_col[q] = i as u32;
                lt_pos[q] = p;
            }
        }

        Ok(SymbolicLdlt {
            n,
            perm,
            perm_inv,
            orig_col_ptr: pattern.col_ptr.clone(),
            a_col_ptr,
            a_row_idx,
            a_src,
            l_col_ptr,
            l_row_idx,
            lt_row_ptr,
            lt_col,
            lt_pos,
        })
    }

    /// Matrix dimension.
    pub(crate) fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries of `L` below the diagonal.
    pub(crate) fn nnz_l(&self) -> usize {
        self.l_row_idx.len()
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

    /// Factorises `Z` given as values on the original pattern. Allocates
    /// nothing. On error, `num` holds no usable factorisation.
    pub(crate) fn factorize(&self, num: &mut NumericLdlt, values: &[C64]) -> Result<(), TinyPivot> {
        let n = self.n;
        let NumericLdlt { l_val, d_inv, y, .. } = num;
        let (l_val, d_inv, y) = (&mut l_val[..], &mut d_inv[..n], &mut y[..n]);
        y.fill(ZERO);
        for k in 0..n {
            // scatter column k of the permuted upper triangle (rows <= k)
            let (a0, a1) = (self.a_col_ptr[k], self.a_col_ptr[k + 1]);
            for (&i, &src) in self.a_row_idx[a0..a1].iter().zip(&self.a_src[a0..a1]) {
                y[i as usize] = values[src];
            }
            let mut d = y[k];
            y[k] = ZERO;
            // row k of L by a sparse triangular solve along its pattern
            let mut subtracted = 0.0;
            let (r0, r1) = (self.lt_row_ptr[k], self.lt_row_ptr[k + 1]);
            for (&i, &pos) in self.lt_col[r0..r1].iter().zip(&self.lt_pos[r0..r1]) {
                let i = i as usize;
                let yi = y[i];
                y[i] = ZERO;
                let start = self.l_col_ptr[i];
                // rows of column i above k: they all lie in row k's pattern
                for (&r, &l) in self.l_row_idx[start..pos].iter().zip(&l_val[start..pos]) {
                    y[r as usize] -= l * yi;
                }
                let lki = yi * d_inv[i];
                l_val[pos] = lki;
                let t = lki * yi;
                d -= t;
                subtracted += l1(t);
            }
            let c = self.perm[k];
            let (o0, o1) = (self.orig_col_ptr[c], self.orig_col_ptr[c + 1]);
            let row_scale = values[o0..o1].iter().fold(0.0, |m: f64, &v| m.max(l1(v)));
            let scale = row_scale.max(subtracted);
            let size = l1(d);
            if !(size > PIVOT_TOLERANCE * scale) || !size.is_finite() {
                return Err(TinyPivot { index: k });
            }
            d_inv[k] = d.inv();
        }
        Ok(())
    }

    /// Solves `P Z P^T X = B` in place for `k` right-hand sides stored
    /// row-interleaved in the internal order (`x.len() == n * k`). Returns
    /// whether every entry of the solution is finite.
    pub(crate) fn solve_in_place(&self, num: &NumericLdlt, x: &mut [C64], k: usize) -> bool {
        assert_eq!(x.len(), self.n * k, "right-hand sides must be n x k, row-interleaved");
        if k == 0 {
            return true;
        }
        let (l_val, d_inv) = (&num.l_val, &num.d_inv);
        Arch::new().dispatch(Substitution {
            sym: self,
            l_val,
            d_inv,
            x,
            k,
            units: None,
            visit: |_: usize, _: &[C64]| {},
        })
    }

    /// As [`Self::solve_in_place`] for unit right-hand sides, which need not
    /// be written beforehand: column `j` is the unit vector at internal row
    /// `rows[j]`. Every entry of `x` is overwritten.
    ///
    /// `visit(r, &x[r * k..])` is called for each internal row `r`, from the
    /// last to the first, as soon as rows `r..n` are final (while they are
    /// still in cache).
    pub(crate) fn solve_units<V: FnMut(usize, &[C64])>(
        &self,
        num: &mut NumericLdlt,
        rows: &[usize],
        x: &mut [C64],
        visit: V,
    ) -> bool {
        let k = rows.len();
        assert_eq!(x.len(), self.n * k, "solutions must be n x k, row-interleaved");
        if k == 0 {
            return true;
        }
        let mut units = std::mem::take(&mut num.units);
        units.clear();
        units.extend(rows.iter().enumerate().map(|(j, &r)| (r, j)));
        units.sort_unstable();
        let (l_val, d_inv) = (&num.l_val, &num.d_inv);
        let finite = Arch::new().dispatch(Substitution { sym: self, l_val, d_inv, x, k, units: Some(&units), visit });
        num.units = units;
        finite
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
    pub(crate) fn selected_inverse(
        &self,
        num: &NumericLdlt,
        diag: &mut [C64],
        lower: &mut [C64],
        slot: &mut [u32],
    ) -> bool {
        let n = self.n;
        assert!(diag.len() == n && lower.len() == self.nnz_l() && slot.len() == n, "selected inverse of another size");
        let (l_val, d_inv) = (&num.l_val[..], &num.d_inv[..n]);
        let mut finite = true;
        for j in (0..n).rev() {
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

/// `pattern` with every pair of equations within each clique added: both
/// triangles, rows sorted and unique. Clique indices must be below `n`.
fn with_clique_pairs(pattern: &Pattern, cliques: &[Vec<usize>]) -> Result<Pattern, String> {
    let n = pattern.n;
    if let Some(eq) = cliques.iter().flatten().copied().find(|&eq| eq >= n) {
        return Err(format!("clique equation {eq} is not below {n}"));
    }
    // room for the original rows and every clique row (duplicates included),
    // then each column sorted and compacted in place
    let mut room: Vec<usize> = (0..n).map(|c| pattern.col_ptr[c + 1] - pattern.col_ptr[c]).collect();
    for clique in cliques {
        for &c in clique {
            room[c] += clique.len();
        }
    }
    let mut start = Vec::with_capacity(n + 1);
    start.push(0);
    for c in 0..n {
        start.push(start[c] + room[c]);
    }
    drop(room);
    let mut rows = vec![0usize; start[n]];
    let mut next = start[..n].to_vec();
    for c in 0..n {
        let col = &pattern.row_idx[pattern.col_ptr[c]..pattern.col_ptr[c + 1]];
        rows[next[c]..next[c] + col.len()].copy_from_slice(col);
        next[c] += col.len();
    }
    for clique in cliques {
        for &c in clique {
            rows[next[c]..next[c] + clique.len()].copy_from_slice(clique);
            next[c] += clique.len();
        }
    }
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0);
    let mut kept = 0;
    for c in 0..n {
        rows[start[c]..next[c]].sort_unstable();
        let mut last = None;
        // kept <= p throughout, so the compaction never overwrites a row
        // that is still to be read
        for p in start[c]..next[c] {
            let r = rows[p];
            if last != Some(r) {
                rows[kept] = r;
                kept += 1;
                last = Some(r);
            }
        }
        col_ptr.push(kept);
    }
    rows.truncate(kept);
    Ok(Pattern { n, col_ptr, row_idx: rows })
}

/// Upper triangle of `P A P^T` by column, rows ascending, for a symmetric
/// pattern `A` with both triangles stored: column pointers, rows, and the
/// position of each entry in `A`'s values.
///
/// New rows `i` are walked in order; each entry `(r, perm[i])` of `A` with
/// `j = perm_inv[r] >= i` is `B[j, i] = B[i, j]` by symmetry, appended to
/// column `j`, so every column receives its rows in ascending order.
fn permuted_upper(pattern: &Pattern, perm: &[usize], perm_inv: &[usize]) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let n = pattern.n;
    let mut col_ptr = vec![0usize; n + 1];
    for i in 0..n {
        let c = perm[i];
        for &r in &pattern.row_idx[pattern.col_ptr[c]..pattern.col_ptr[c + 1]] {
            let j = perm_inv[r];
            if j >= i {
                col_ptr[j + 1] += 1;
            }
        }
    }
    for j in 0..n {
        col_ptr[j + 1] += col_ptr[j];
    }
    let nnz = col_ptr[n];
    let mut next = col_ptr[..n].to_vec();
    let mut rows = vec![0usize; nnz];
    let mut src = vec![0usize; nnz];
    for i in 0..n {
        let c = perm[i];
        for p in pattern.col_ptr[c]..pattern.col_ptr[c + 1] {
            let j = perm_inv[pattern.row_idx[p]];
            if j >= i {
                rows[next[j]] = i;
                src[next[j]] = p;
                next[j] += 1;
            }
        }
    }
    (col_ptr, rows, src)
}

/// Forward and backward substitution, vectorised over the right-hand sides
/// with the widest instructions the CPU offers (chosen at run time).
struct Substitution<'a, V> {
    sym: &'a SymbolicLdlt,
    l_val: &'a [C64],
    d_inv: &'a [C64],
    x: &'a mut [C64],
    k: usize,
    /// Unit right-hand sides `(internal row, column)`, sorted, made on the
    /// fly; `None` when `x` holds the right-hand sides.
    units: Option<&'a [(usize, usize)]>,
    /// Called with each row as it becomes final in the backward sweep.
    visit: V,
}

impl<V: FnMut(usize, &[C64])> WithSimd for Substitution<'_, V> {
    type Output = bool;

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> bool {
        let Substitution { sym, l_val, d_inv, x, k, units, mut visit } = self;
        let n = sym.n;
        // forward, L y = b, by rows: row r gathers the final rows above it
        // (close to it for a banded matrix, so in cache), and is written once
        let mut next_unit = 0;
        for r in 0..n {
            let (head, tail) = x.split_at_mut(r * k);
            let xr = &mut tail[..k];
            if let Some(units) = units {
                xr.fill(ZERO);
                if next_unit == 0 && units.first().is_some_and(|&(first, _)| r < first) {
                    continue; // above the first unit row everything is zero
                }
                while let Some(&(_, j)) = units.get(next_unit).filter(|&&(row, _)| row == r) {
                    xr[j] = C64::new(1.0, 0.0);
                    next_unit += 1;
                }
            }
            let (q0, q1) = (sym.lt_row_ptr[r], sym.lt_row_ptr[r + 1]);
            for (&i, &pos) in sym.lt_col[q0..q1].iter().zip(&sym.lt_pos[q0..q1]) {
                let i = i as usize * k;
                mul_add(simd, xr, -l_val[pos], &head[i..i + k]);
            }
            flush_tiny(xr);
        }
        // D^-1 and backward, L^T x = D^-1 y: column j of L is row j of L^T,
        // so row j gathers the rows below it, which are final
        let mut finite = true;
        for j in (0..n).rev() {
            let (head, tail) = x.split_at_mut((j + 1) * k);
            let xj = &mut head[j * k..];
            scale(simd, xj, d_inv[j]);
            let (p0, p1) = (sym.l_col_ptr[j], sym.l_col_ptr[j + 1]);
            for (&r, &l) in sym.l_row_idx[p0..p1].iter().zip(&l_val[p0..p1]) {
                let off = (r as usize - j - 1) * k;
                mul_add(simd, xj, -l, &tail[off..off + k]);
            }
            flush_tiny(xj);
            finite &= xj.iter().all(|v| v.re.is_finite() && v.im.is_finite());
            visit(j, &x[j * k..]);
        }
        finite
    }
}

/// `dst *= a`.
#[inline(always)]
fn scale<S: Simd>(simd: S, dst: &mut [C64], a: C64) {
    let av = simd.splat_c64s(a);
    let (dh, dt) = S::as_mut_simd_c64s(dst);
    for d in dh.iter_mut() {
        *d = simd.mul_c64s(av, *d);
    }
    if !dt.is_empty() {
        let r = simd.mul_c64s(av, simd.partial_load_c64s(dt));
        simd.partial_store_c64s(dt, r);
    }
}

#[cfg(test)]
mod tests {
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
        (Pattern { n, col_ptr, row_idx }, vals)
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
                for p in pat.col_ptr[c]..pat.col_ptr[c + 1] {
                    r += vals[p] * sol[pat.row_idx[p] * k + j];
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
        for c in 0..pat.n {
            for &r in &pat.row_idx[pat.col_ptr[c]..pat.col_ptr[c + 1]] {
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
        for c in 0..aug.n {
            for &r in &aug.row_idx[aug.col_ptr[c]..aug.col_ptr[c + 1]] {
                got.push((c, r));
            }
        }
        assert_eq!(got, expected.into_iter().collect::<Vec<_>>(), "sorted by column, then row, without repeats");
        let e = with_clique_pairs(&pat, &[vec![2, 9]]).unwrap_err();
        assert!(e.contains(&format!("clique equation 9 is not below {}", pat.n)), "{e}");
    }

    #[test]
    fn a_zero_leading_pivot_is_reported() {
        // [[0, 1], [1, 0]]: nonsingular, but no LDL^T without pivoting
        let pat = Pattern { n: 2, col_ptr: vec![0, 2, 4], row_idx: vec![0, 1, 0, 1] };
        let vals = [ZERO, C64::new(1.0, 0.0), C64::new(1.0, 0.0), ZERO];
        let sym = SymbolicLdlt::new(&pat, &[]).unwrap();
        let mut num = sym.numeric();
        assert_eq!(sym.factorize(&mut num, &vals), Err(TinyPivot { index: 0 }));
    }
}
