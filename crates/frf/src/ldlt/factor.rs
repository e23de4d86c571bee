//! The numeric factorisation, per frequency: up-looking (row `k` of `L` is a
//! sparse triangular solve with the rows above it, along the precomputed
//! row pattern), after T. A. Davis's LDL, with the pivot test that sends a
//! line to the LU fallback.

use num_complex::Complex64 as C64;

use super::{NumericLdlt, PIVOT_TOLERANCE, SymbolicLdlt, TinyPivot, ZERO};

/// `|re| + |im|`: a cheap norm within a factor sqrt(2) of the modulus.
#[inline(always)]
fn l1(z: C64) -> f64 {
    z.re.abs() + z.im.abs()
}

impl SymbolicLdlt {
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
}
