//! Dense kernels of the supernodal factorisation: the unpivoted
//! complex-symmetric `L D L^T` of a supernode's columns (with the pivot
//! test against the row's scale), and the update they leave for the rows
//! below them. No conjugation anywhere: faer's products are called on plain
//! views.

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::traits::pulp::{Arch, Simd, WithSimd};
use faer::{Accum, MatMut, MatRef, Par};
use num_complex::Complex64 as C64;

use super::super::PIVOT_TOLERANCE;
use super::super::solve::{mul_add, scale};

/// Blocks of at most this many columns are factorised column by column;
/// wider ones are split in two, and the left half's update of the right
/// half is a matrix product (where nearly all the work of a wide block
/// goes).
const BASE: usize = 16;

const MINUS_ONE: C64 = C64 { re: -1.0, im: 0.0 };

/// `|re| + |im|`: a cheap norm within a factor sqrt(2) of the modulus.
#[inline(always)]
pub(super) fn l1(z: C64) -> f64 {
    z.re.abs() + z.im.abs()
}

/// Factorises the `w` columns of the column-major `m x w` block (`m >= w`,
/// the diagonal block on top) in place, as `L D L^T` restricted to them: on
/// return the strict lower part holds `L`, the diagonal `D`, and `d_inv`
/// its inverse. A pivot that is not finite or not above
/// [`PIVOT_TOLERANCE`] times its row's scale stops the factorisation: the
/// error is its column. `work` holds at least `w * w / 4` values.
pub(super) fn factor_columns(
    block: &mut [C64],
    m: usize,
    w: usize,
    d_inv: &mut [C64],
    row_scale: &[f64],
    work: &mut [C64],
) -> Result<(), usize> {
    debug_assert!(block.len() == m * w && m >= w && d_inv.len() == w && row_scale.len() == w);
    factor_range(block, m, 0, w, d_inv, row_scale, work)
}

/// Factorises columns `c0..c0 + wc`, which every column left of `c0` has
/// already updated.
fn factor_range(
    block: &mut [C64],
    m: usize,
    c0: usize,
    wc: usize,
    d_inv: &mut [C64],
    row_scale: &[f64],
    work: &mut [C64],
) -> Result<(), usize> {
    if wc <= BASE {
        return Arch::new().dispatch(Unblocked { block, m, c0, wc, d_inv, row_scale });
    }
    let h = wc / 2;
    factor_range(block, m, c0, h, d_inv, row_scale, work)?;
    update_right(block, m, c0, h, wc - h, work);
    factor_range(block, m, c0 + h, wc - h, d_inv, row_scale, work)
}

/// Subtracts from columns `c1..c1 + w2` (`c1 = c0 + h`), rows `c1..m`, the
/// contribution of the factorised columns `c0..c1`: `L[c1.., :] D L[c1..c1 +
/// w2, :]^T`, lower triangle only in the diagonal part.
fn update_right(block: &mut [C64], m: usize, c0: usize, h: usize, w2: usize, work: &mut [C64]) {
    let c1 = c0 + h;
    let (left, right) = block.split_at_mut(c1 * m);
    let l = MatRef::from_column_major_slice_with_stride(&left[c0 * m..], m, h, m);
    let top = l.submatrix(c1, 0, w2, h);
    let below = l.submatrix(c1 + w2, 0, m - c1 - w2, h);
    // the top rows times D
    let mut scaled = MatMut::from_column_major_slice_mut(&mut work[..w2 * h], w2, h);
    for t in 0..h {
        let d = left[(c0 + t) * m + c0 + t];
        for i in 0..w2 {
            scaled[(i, t)] = top[(i, t)] * d;
        }
    }
    let dst = MatMut::from_column_major_slice_with_stride_mut(&mut right[..w2 * m], m, w2, m);
    let (square, rect) = dst.subrows_mut(c1, m - c1).split_at_row_mut(w2);
    let scaled = scaled.as_ref();
    triangular::matmul(
        square,
        BlockStructure::TriangularLower,
        Accum::Add,
        top,
        BlockStructure::Rectangular,
        scaled.transpose(),
        BlockStructure::Rectangular,
        MINUS_ONE,
        Par::Seq,
    );
    matmul(rect, Accum::Add, below, scaled.transpose(), MINUS_ONE, Par::Seq);
}

/// Writes to the `r x r` column-major `update` (lower triangle; the strict
/// upper one is left as it was) the update the factorised `m x w` block
/// leaves for its rows below the diagonal block (`r = m - w`): `-L[R, C] D
/// L[R, C]^T`. `work` holds at least `r w` values.
pub(super) fn schur_update(block: &[C64], m: usize, w: usize, update: &mut [C64], work: &mut [C64]) {
    let r = m - w;
    let l = MatRef::from_column_major_slice(block, m, w);
    let below = l.submatrix(w, 0, r, w);
    let mut scaled = MatMut::from_column_major_slice_mut(&mut work[..r * w], r, w);
    for t in 0..w {
        let d = block[t * m + t];
        for i in 0..r {
            scaled[(i, t)] = below[(i, t)] * d;
        }
    }
    let u = MatMut::from_column_major_slice_mut(&mut update[..r * r], r, r);
    triangular::matmul(
        u,
        BlockStructure::TriangularLower,
        Accum::Replace,
        below,
        BlockStructure::Rectangular,
        scaled.as_ref().transpose(),
        BlockStructure::Rectangular,
        MINUS_ONE,
        Par::Seq,
    );
}

/// Columns `c0..c0 + wc` of a block one by one (left-looking within them):
/// column `j` subtracts `L[j.., t] d_t L[j, t]` for each `t` in `c0..j`, then
/// its pivot is tested and the entries below it divided by it.
struct Unblocked<'a> {
    block: &'a mut [C64],
    m: usize,
    c0: usize,
    wc: usize,
    d_inv: &'a mut [C64],
    row_scale: &'a [f64],
}

impl WithSimd for Unblocked<'_> {
    type Output = Result<(), usize>;

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> Result<(), usize> {
        let Unblocked { block, m, c0, wc, d_inv, row_scale } = self;
        for j in c0..c0 + wc {
            let (left, right) = block.split_at_mut(j * m);
            let col_j = &mut right[j..m];
            for t in c0..j {
                let col_t = &left[t * m..(t + 1) * m];
                let coef = -(col_t[j] * col_t[t]);
                mul_add(simd, col_j, coef, &col_t[j..]);
            }
            let d = col_j[0];
            let size = l1(d);
            if !(size > PIVOT_TOLERANCE * row_scale[j]) || !size.is_finite() {
                return Err(j);
            }
            let inv = d.inv();
            d_inv[j] = inv;
            scale(simd, &mut col_j[1..], inv);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dense complex-symmetric matrix with a dominant diagonal, as an
    /// `m x w` block of its first `w` columns, and the whole matrix.
    fn symmetric(m: usize, seed: u64) -> Vec<C64> {
        let mut state = seed;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut a = vec![C64::new(0.0, 0.0); m * m];
        for j in 0..m {
            for i in j..m {
                let v = if i == j { C64::new(2.0 + m as f64 * 0.5, next()) } else { C64::new(next(), next()) };
                a[i + j * m] = v;
                a[j + i * m] = v;
            }
        }
        a
    }

    /// The factors of the first `w` columns and the Schur complement of the
    /// rest rebuild the matrix: `L D L^T` on the columns, and `A[R, R] = S +
    /// L[R, C] D L[R, C]^T` below.
    #[test]
    fn columns_and_update_rebuild_the_matrix() {
        for (m, w) in [(1, 1), (5, 3), (40, 40), (70, 37), (90, 18)] {
            let a = symmetric(m, (m * 31 + w) as u64);
            let mut block = a[..m * w].to_vec();
            let mut d_inv = vec![C64::new(0.0, 0.0); w];
            let scale = vec![1.0; w];
            let mut work = vec![C64::new(0.0, 0.0); m * w];
            factor_columns(&mut block, m, w, &mut d_inv, &scale, &mut work).unwrap();
            // the update added to A[R, R] makes the Schur complement
            let r = m - w;
            let mut update = vec![C64::new(f64::NAN, 0.0); r * r];
            schur_update(&block, m, w, &mut update, &mut work);
            for j in 0..r {
                for i in j..r {
                    update[i + j * r] += a[(w + i) + (w + j) * m];
                }
            }
            let l = |i: usize, t: usize| if i == t { C64::new(1.0, 0.0) } else { block[i + t * m] };
            for j in 0..m {
                for i in j..m {
                    let mut rebuilt: C64 = (0..w.min(j + 1)).map(|t| l(i, t) * block[t + t * m] * l(j, t)).sum();
                    if j >= w {
                        rebuilt += update[(i - w) + (j - w) * r];
                    }
                    let err = (rebuilt - a[i + j * m]).norm();
                    assert!(err < 1e-12 * m as f64, "m {m} w {w} ({i}, {j}): {err:e}");
                }
            }
            for t in 0..w {
                assert!((d_inv[t] * block[t + t * m] - 1.0).norm() < 1e-14);
            }
        }
    }

    #[test]
    fn a_pivot_tiny_against_its_row_scale_is_reported_by_its_column() {
        // [[1, 1], [1, 1 + 1e-10]] at scale 1: the second pivot is 1e-10
        let one = C64::new(1.0, 0.0);
        let mut block = vec![one, one, one, C64::new(1.0 + 1e-10, 0.0)];
        let mut d_inv = vec![C64::new(0.0, 0.0); 2];
        let mut work = vec![C64::new(0.0, 0.0); 4];
        assert_eq!(factor_columns(&mut block, 2, 2, &mut d_inv, &[1.0, 1.0], &mut work), Err(1));
        let mut block = vec![C64::new(f64::NAN, 0.0)];
        assert_eq!(factor_columns(&mut block, 1, 1, &mut d_inv[..1], &[1.0], &mut work), Err(0));
    }
}
