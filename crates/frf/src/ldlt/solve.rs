//! Forward and backward substitution with the factors, for right-hand sides
//! stored row-interleaved in the internal order, vectorised over the
//! right-hand sides; unit right-hand sides are made on the fly.

use faer::traits::pulp::{Arch, Simd, WithSimd};
use num_complex::Complex64 as C64;

use super::{NumericLdlt, SymbolicLdlt, ZERO};

/// Solution values smaller than this in magnitude are set to zero as each
/// row is finalised. Responses can decay by hundreds of orders of magnitude
/// across a large model (a long periodic structure in a stop band), and
/// arithmetic on subnormal numbers (below about 2.2e-308) is some hundred
/// times slower; values this small are far below anything physical.
const FLUSH_BELOW: f64 = 1e-200;

/// Sets parts of `row` smaller than [`FLUSH_BELOW`] to zero.
#[inline(always)]
pub(super) fn flush_tiny(row: &mut [C64]) {
    for v in row {
        if v.re.abs() < FLUSH_BELOW {
            v.re = 0.0;
        }
        if v.im.abs() < FLUSH_BELOW {
            v.im = 0.0;
        }
    }
}

impl SymbolicLdlt {
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
            within: None,
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
        within: Option<&[bool]>,
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
        let finite =
            Arch::new().dispatch(Substitution { sym: self, l_val, d_inv, x, k, units: Some(&units), within, visit });
        num.units = units;
        finite
    }
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
    /// The rows wanted (a closed set, [`SymbolicLdlt::reach`]): the
    /// backward sweep skips the others, which are then left undefined and
    /// not visited. With unit right-hand sides the forward sweep skips the
    /// rows outside the units' own reach, where the solution of `L y = b`
    /// is zero.
    within: Option<&'a [bool]>,
    /// Called with each row as it becomes final in the backward sweep.
    visit: V,
}

impl<V: FnMut(usize, &[C64])> WithSimd for Substitution<'_, V> {
    type Output = bool;

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> bool {
        let Substitution { sym, l_val, d_inv, x, k, units, within, mut visit } = self;
        let n = sym.n;
        // the rows where L y = b has non-zeros, when only some rows are
        // wanted: the unit rows' ancestors (a row elsewhere has none of
        // them among the columns of its row of L)
        let live = within.zip(units).map(|(_, units)| sym.reach(units.iter().map(|&(r, _)| r)));
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
                if live.as_ref().is_some_and(|live| !live[r]) {
                    continue;
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
            if within.is_some_and(|w| !w[j]) {
                continue;
            }
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
pub(super) fn scale<S: Simd>(simd: S, dst: &mut [C64], a: C64) {
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

/// `dst += a * src` over equal-length slices, vectorised: the update of the
/// solver's eliminations, shared with the sensitivity assembly's products.
#[inline(always)]
pub fn mul_add<S: Simd>(simd: S, dst: &mut [C64], a: C64, src: &[C64]) {
    let av = simd.splat_c64s(a);
    let (dh, dt) = S::as_mut_simd_c64s(dst);
    let (sh, st) = S::as_simd_c64s(src);
    for (d, s) in dh.iter_mut().zip(sh) {
        *d = simd.mul_add_c64s(av, *s, *d);
    }
    if !dt.is_empty() {
        let r = simd.mul_add_c64s(av, simd.partial_load_c64s(st), simd.partial_load_c64s(dt));
        simd.partial_store_c64s(dt, r);
    }
}
