//! The selected inverse on supernodes: the Takahashi recurrence by blocks.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_inverse::invert_unit_lower_triangular;
use faer::linalg::triangular_solve::solve_unit_upper_triangular_in_place_with_conj;
use faer::{Accum, Conj, MatMut, MatRef, Par};
use num_complex::Complex64 as C64;

use super::{NumericSupernodal, SupernodalLdlt, ZERO};

const ONE: C64 = C64 { re: 1.0, im: 0.0 };
const MINUS_ONE: C64 = C64 { re: -1.0, im: 0.0 };

impl SupernodalLdlt {
    /// `B^-1` (`B = P Z P^T`, factorised in `num`) on the stored pattern of
    /// the factor, written to `out` in the layout of the factor's values
    /// (each supernode's diagonal block by its lower triangle). `work` and
    /// `rel` are scratch, grown as needed. Returns whether every entry is
    /// finite.
    ///
    /// With `C` the columns of a supernode, `R` its rows below, `L11` its
    /// unit lower diagonal block, `L21` the block below and `D` its pivots,
    /// the rows `C` of `L^T B^-1 = D^-1 L^-1` (lower triangular, with
    /// diagonal blocks `D^-1 L11^-1`) read, in the columns `R` and `C`:
    ///
    /// ```text
    /// B^-1[R, C] = -B^-1[R, R] L21 L11^-1
    /// B^-1[C, C] = L11^-T (D^-1 L11^-1 - L21^T B^-1[R, C])
    /// ```
    ///
    /// Supernodes are inverted from the last to the first, and `B^-1[R, R]`
    /// is then known and stored: the rows of a supernode below its columns
    /// are rows of every supernode above it that holds one of them.
    pub(crate) fn selected_inverse(
        &self,
        num: &NumericSupernodal,
        out: &mut [C64],
        work: &mut Vec<C64>,
        rel: &mut Vec<u32>,
    ) -> bool {
        assert_eq!(out.len(), self.values_len(), "selected inverse of another size");
        let need = self.max_rows * self.max_rows + self.max_cols * self.max_cols;
        if work.len() < need {
            work.resize(need, ZERO);
        }
        if rel.len() < self.max_rows {
            rel.resize(self.max_rows, 0);
        }
        let mut finite = true;
        for s in (0..self.n_super()).rev() {
            let (f, e, rows) = self.supernode(s);
            let (w, r) = (e - f, rows.len());
            let m = w + r;
            let l = MatRef::from_column_major_slice(&num.values[self.val_ptr[s]..self.val_ptr[s + 1]], m, w);
            let (l11, l21) = (l.submatrix(0, 0, w, w), l.submatrix(w, 0, r, w));
            let (head, done) = out.split_at_mut(self.val_ptr[s + 1]);
            let o = &mut head[self.val_ptr[s]..];
            let (g_buf, m_buf) = work.split_at_mut(self.max_rows * self.max_rows);
            if r > 0 {
                let g = &mut g_buf[..r * r];
                self.gather(rows, done, self.val_ptr[s + 1], g, &mut rel[..r]);
                let g = MatRef::from_column_major_slice(g, r, r);
                // B^-1[R, C] = -(B^-1[R, R] L21) L11^-1, by L11^T X^T = Y^T
                let mut below = MatMut::from_column_major_slice_with_stride_mut(&mut o[w..], r, w, m);
                matmul(below.as_mut(), Accum::Replace, g, l21, MINUS_ONE, Par::Seq);
                solve_unit_upper_triangular_in_place_with_conj(
                    l11.transpose(),
                    Conj::No,
                    below.transpose_mut(),
                    Par::Seq,
                );
            }
            // B^-1[C, C] = L11^-T (D^-1 L11^-1 - L21^T B^-1[R, C])
            let mut mm = MatMut::from_column_major_slice_mut(&mut m_buf[..w * w], w, w);
            invert_unit_lower_triangular(mm.as_mut(), l11, Par::Seq);
            for j in 0..w {
                for i in 0..j {
                    mm[(i, j)] = ZERO;
                }
                mm[(j, j)] = ONE;
            }
            for i in 0..w {
                let d = num.d_inv[f + i];
                for j in 0..=i {
                    mm[(i, j)] *= d;
                }
            }
            if r > 0 {
                let below = MatRef::from_column_major_slice_with_stride(&o[w..], r, w, m);
                matmul(mm.as_mut(), Accum::Add, l21.transpose(), below, MINUS_ONE, Par::Seq);
            }
            solve_unit_upper_triangular_in_place_with_conj(l11.transpose(), Conj::No, mm.as_mut(), Par::Seq);
            for j in 0..w {
                for i in j..w {
                    o[j * m + i] = mm[(i, j)];
                }
            }
            finite &= o[..m * w].iter().all(|v| v.re.is_finite() && v.im.is_finite());
        }
        finite
    }

    /// `B^-1[R, R]` for the rows `R` of a supernode, as a full column-major
    /// `|R| x |R|` matrix `g`, from the supernodes above it (`done` holds the
    /// values from offset `done_at` on). The columns of `R` are taken in
    /// runs that lie in one supernode `t`, whose front holds every later row
    /// of `R`: their positions there are found once per run, by merging.
    fn gather(&self, rows: &[u32], done: &[C64], done_at: usize, g: &mut [C64], pos: &mut [u32]) {
        let r = rows.len();
        let mut b = 0;
        while b < r {
            let t = self.super_of[rows[b] as usize] as usize;
            let (ft, et, t_rows) = self.supernode(t);
            let mt = et - ft + t_rows.len();
            // positions in t's front of the rows R[b..]
            let mut q = 0;
            for a in b..r {
                let g_row = rows[a];
                pos[a] = if (g_row as usize) < et {
                    g_row - ft as u32
                } else {
                    while t_rows[q] < g_row {
                        q += 1;
                    }
                    (et - ft + q) as u32
                };
            }
            let t_vals = &done[self.val_ptr[t] - done_at..self.val_ptr[t + 1] - done_at];
            while b < r && (rows[b] as usize) < et {
                let col = &t_vals[(rows[b] as usize - ft) * mt..];
                for a in b..r {
                    let v = col[pos[a] as usize];
                    g[a + b * r] = v;
                    g[b + a * r] = v;
                }
                b += 1;
            }
        }
    }
}
