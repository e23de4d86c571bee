//! The numeric factorisation, per frequency: multifrontal, supernode by
//! supernode in postorder, with the pivot test that sends a line to the LU
//! fallback.

use num_complex::Complex64 as C64;

use super::super::{PIVOT_TOLERANCE, TinyPivot};
use super::dense::{factor_columns, l1, schur_update};
use super::{NumericSupernodal, SupernodalLdlt, ZERO};

impl SupernodalLdlt {
    /// Factorises `Z` given as values on the original pattern. Allocates
    /// nothing. On error, `num` holds no usable factorisation.
    ///
    /// The pivot test is the simplicial layout's: a pivot must be finite and
    /// above [`PIVOT_TOLERANCE`] times the larger of its row's largest entry
    /// of `Z` and the sum of the terms subtracted from it, `L[k, i]^2 d_i`
    /// over the columns `i < k`. The first part is tested as each pivot is
    /// formed; the sums are added up from each supernode's columns once they
    /// are factorised (bounding each term by `|L[k, i]|^2 (|re d_i| + |im
    /// d_i|)`), and the second part is tested when a supernode's columns
    /// are complete, before its update leaves it.
    pub(crate) fn factorize(&self, num: &mut NumericSupernodal, values: &[C64]) -> Result<(), TinyPivot> {
        let NumericSupernodal {
            values: l_val,
            d_inv,
            stack,
            work,
            local,
            rel,
            run_end,
            row_scale,
            subtracted,
            acc,
            ..
        } = num;
        for (k, &c) in self.perm.iter().enumerate() {
            let (o0, o1) = (self.orig_col_ptr[c], self.orig_col_ptr[c + 1]);
            row_scale[k] = values[o0..o1].iter().fold(0.0, |m: f64, &v| m.max(l1(v)));
        }
        subtracted.fill(0.0);
        let mut top = 0;
        for s in 0..self.n_super() {
            let (f, e, rows) = self.supernode(s);
            let (w, r) = (e - f, rows.len());
            let m = w + r;
            let block = &mut l_val[self.val_ptr[s]..self.val_ptr[s + 1]];
            block.fill(ZERO);
            // positions in the front: column c of C is c - f, row R[i] is w + i
            for (i, &g) in rows.iter().enumerate() {
                local[g as usize] = (w + i) as u32;
            }
            for j in f..e {
                let col = &mut block[(j - f) * m..(j - f + 1) * m];
                let (p0, p1) = (self.a_col_ptr[j], self.a_col_ptr[j + 1]);
                for (&i, &src) in self.a_row_idx[p0..p1].iter().zip(&self.a_src[p0..p1]) {
                    let i = i as usize;
                    let at = if i < e { i - f } else { local[i] as usize };
                    col[at] += values[src];
                }
            }

            // the children's update matrices, the top of the stack: their
            // columns in C are added into the front now, their columns in R
            // once this supernode's own update is made (above them)
            let children = &self.children[self.child_ptr[s]..self.child_ptr[s + 1]];
            let start = self.update_at[s];
            let (below, above) = stack.split_at_mut(top);
            for &c in children {
                let (c_rows, c_update) = self.child_update(c as usize, below);
                let (rel, runs) = relative(c_rows, f, e, local, rel, run_end);
                extend_add(c_update, rel, runs, 0..c_rows.partition_point(|&g| (g as usize) < e), block, m, w);
            }

            factor_columns(block, m, w, &mut d_inv[f..e], &row_scale[f..e], work)
                .map_err(|j| TinyPivot { index: f + j })?;
            // the terms these columns subtracted from the pivots below them,
            // summed by row first (contiguous), then added to those rows
            let acc = &mut acc[..m];
            acc.fill(0.0);
            for j in 0..w {
                let col = &block[j * m..(j + 1) * m];
                let d = l1(col[j]);
                for (a, v) in acc[j + 1..].iter_mut().zip(&col[j + 1..]) {
                    *a += v.norm_sqr() * d;
                }
            }
            for (k, &a) in subtracted[f..e].iter_mut().zip(&acc[..w]) {
                *k += a;
            }
            for (&g, &a) in rows.iter().zip(&acc[w..]) {
                subtracted[g as usize] += a;
            }
            for j in 0..w {
                let k = f + j;
                if !(l1(block[j * m + j]) > PIVOT_TOLERANCE * subtracted[k]) {
                    return Err(TinyPivot { index: k });
                }
            }

            if r > 0 {
                let update = &mut above[..r * r];
                schur_update(block, m, w, update, work);
                for &c in children {
                    let (c_rows, c_update) = self.child_update(c as usize, below);
                    let (rel, runs) = relative(c_rows, f, e, local, rel, run_end);
                    let split = c_rows.partition_point(|&g| (g as usize) < e);
                    extend_add(c_update, rel, runs, split..c_rows.len(), update, r, w);
                }
                // down over the children's, column by column (the lower
                // triangle is all that is read); each column moves down by
                // top - start, past no column still to move
                if start != top {
                    for j in 0..r {
                        stack.copy_within(top + j * r + j..top + (j + 1) * r, start + j * r + j);
                    }
                }
            }
            top = start + r * r;
        }
        Ok(())
    }
}

impl SupernodalLdlt {
    /// The rows of supernode `c` below its columns and its update matrix on
    /// the stack `below`.
    #[inline]
    fn child_update<'a>(&'a self, c: usize, below: &'a [C64]) -> (&'a [u32], &'a [C64]) {
        let (_, _, c_rows) = self.supernode(c);
        let rc = c_rows.len();
        (c_rows, &below[self.update_at[c]..self.update_at[c] + rc * rc])
    }
}

/// Positions in the front of supernode `f..e` of a child's rows: below `w =
/// e - f` a column of the supernode, from `w` on `w` plus the row's place
/// among the supernode's rows below (`local`); and for each row, the end of
/// the run of rows from it whose positions are consecutive (the six DOFs of
/// a node, whole blocks of a mesh's rows), which [`extend_add`] adds as
/// slices.
#[inline]
fn relative<'a>(
    c_rows: &[u32],
    f: usize,
    e: usize,
    local: &[u32],
    rel: &'a mut [u32],
    run_end: &'a mut [u32],
) -> (&'a [u32], &'a [u32]) {
    let rc = c_rows.len();
    let (rel, run_end) = (&mut rel[..rc], &mut run_end[..rc]);
    for (p, &g) in rel.iter_mut().zip(c_rows) {
        let g = g as usize;
        *p = if g < e { (g - f) as u32 } else { local[g] };
    }
    for a in (0..rc).rev() {
        run_end[a] = if a + 1 < rc && rel[a + 1] == rel[a] + 1 { run_end[a + 1] } else { a as u32 + 1 };
    }
    (rel, run_end)
}

/// Adds columns `cols` of a child's update matrix (`rc x rc`, lower
/// triangle) into its parent's front: `rel[a]` is the position of the
/// child's row `a` in the front, below `w` a column of the parent's block,
/// from `w` on a row of the parent's update matrix (at `w` plus its row),
/// and rows `a..run_end[a]` have consecutive positions. The child's rows
/// are ascending, so the columns of the update matrix that fall in the
/// parent's block come first, then those in its update matrix: `dst` is
/// the block (`ld = m` rows) for the first, the parent's update matrix (`ld
/// = r`, positions shifted by `w`) for the second.
fn extend_add(
    child: &[C64],
    rel: &[u32],
    run_end: &[u32],
    cols: std::ops::Range<usize>,
    dst: &mut [C64],
    ld: usize,
    w: usize,
) {
    let rc = rel.len();
    for b in cols {
        let src = &child[b * rc..(b + 1) * rc];
        let cb = rel[b] as usize;
        let (col, shift) = if cb < w {
            (&mut dst[cb * ld..(cb + 1) * ld], 0)
        } else {
            (&mut dst[(cb - w) * ld..(cb - w + 1) * ld], w)
        };
        let mut a = b;
        while a < rc {
            let end = run_end[a] as usize;
            let p = rel[a] as usize - shift;
            for (d, &v) in col[p..p + end - a].iter_mut().zip(&src[a..end]) {
                *d += v;
            }
            a = end;
        }
    }
}
