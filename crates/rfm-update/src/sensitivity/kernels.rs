//! The vectorised products of step 4 for the blocks of one bucket.

use faer::traits::pulp::{Simd, WithSimd};
use frf::solver::mul_add;
use num_complex::Complex64 as C64;

use super::terms::{Item, TermTable};
use super::{MAX_BLOCK, NONE, ZERO};

/// Step 4 for the blocks of one bucket, every reference: for each used term,
/// `acc[ref, class, m] += R[m, eqs] (value U x)` over the block's equations.
/// Vectorised over the responses `m`, contiguous in each row.
pub(super) struct BucketProducts<'a> {
    pub(super) table: &'a TermTable,
    pub(super) items: &'a [Item],
    /// The solver row of `rows[0..k]`.
    pub(super) first_row: usize,
    /// Final solution rows `first_row..`, `k` values each.
    pub(super) rows: &'a [C64],
    pub(super) n_ref: usize,
    pub(super) n_resp: usize,
    pub(super) measured_at: &'a [u32],
    pub(super) measured: &'a [Option<C64>],
    /// `references x classes x responses`.
    pub(super) acc: &'a mut [C64],
}

impl WithSimd for BucketProducts<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let BucketProducts { table, items, first_row, rows, n_ref, n_resp, measured_at, measured, acc } = self;
        let k = n_ref + n_resp;
        let mut off = [0usize; MAX_BLOCK];
        let mut xb = [ZERO; MAX_BLOCK];
        let mut v = [ZERO; MAX_BLOCK];
        for item in items {
            let nb = item.nb as usize;
            for (o, &r) in off[..nb].iter_mut().zip(&item.rows[..nb]) {
                *o = (r as usize - first_row) * k;
            }
            for ri in 0..n_ref {
                // x at the block's equations: the hybrid or the model column
                for l in 0..nb {
                    let at = measured_at.get(item.rows[l] as usize).copied().unwrap_or(NONE);
                    let replaced = if at == NONE { None } else { measured[at as usize * n_ref + ri] };
                    xb[l] = replaced.unwrap_or(rows[off[l] + ri]);
                }
                for term in &table.terms[item.t0 as usize..item.t1 as usize] {
                    let unit = &table.units[term.unit as usize..term.unit as usize + nb * nb];
                    for (r, vr) in v[..nb].iter_mut().enumerate() {
                        let urow = &unit[r * nb..(r + 1) * nb];
                        *vr = urow.iter().zip(&xb[..nb]).fold(ZERO, |s, (&u, &x)| s + x * u) * term.value;
                    }
                    let at = (ri * table.n_classes + term.class as usize) * n_resp;
                    let sum = &mut acc[at..at + n_resp];
                    for (&o, &vr) in off[..nb].iter().zip(&v[..nb]) {
                        if vr != ZERO {
                            mul_add(simd, sum, vr, &rows[o + n_ref..o + k]);
                        }
                    }
                }
            }
        }
    }
}
