//! The supernodal layout of the complex-symmetric `L D L^T` factorisation:
//! columns of `L` with the same pattern below their diagonal block are
//! stored together as one dense block, and factorised, solved and inverted
//! with dense kernels.
//!
//! A model whose factor has full columns (a shell or solid mesh: hundreds
//! of multiply-adds per entry of `L`) spends nearly all of its
//! factorisation in updates of one column by another. Done entry by entry,
//! as the simplicial layout does, they run at a few GFlop/s; grouped into
//! supernodes they are dense matrix products, which faer runs at several
//! times that. faer's own supernodal `L D L^H` cannot be used: it
//! conjugates, and keeps `D` real.
//!
//! - The symbolic analysis (once per pattern, [`symbolic`]): the shared
//!   fill-reducing ordering, postordered so that every subtree of the
//!   elimination tree is a run of consecutive columns, and faer's supernodal
//!   symbolic Cholesky (its partition into supernodes, relaxed to merge
//!   small ones, and the rows of each below its diagonal block).
//! - The numeric factorisation ([`factor`]) is multifrontal: supernode `s`,
//!   with columns `C` and rows below `R`, assembles its front (the entries of
//!   `Z` in its columns and the update matrices its children left), factors
//!   its columns with a dense unpivoted `L D L^T` ([`dense`]), and leaves
//!   the update `-L[R, C] D L[R, C]^T` for its parent. Update matrices live
//!   on a stack whose size the analysis knows (the postorder makes the
//!   children of a supernode the top of the stack when it is reached).
//! - The solves ([`solve`]) run supernode by supernode: a dense triangular
//!   solve with the diagonal block and a matrix product with the block
//!   below it.
//! - The selected inverse ([`selected_inverse`]) is the Takahashi
//!   recurrence by blocks.
//!
//! Values of supernode `s` are stored column-major, `(|C| + |R|) x |C|`,
//! the diagonal block first (its strict lower part is `L`, its diagonal
//! `D`, its strict upper part unused), then the rows `R`.

use num_complex::Complex64 as C64;

mod dense;
mod factor;
mod selected_inverse;
mod solve;
mod symbolic;

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };

/// Supernodal symbolic analysis of a symmetric pattern; see the module docs.
#[derive(Clone, Debug)]
pub(crate) struct SupernodalLdlt {
    n: usize,
    /// `perm[new] = old`.
    perm: Vec<usize>,
    /// `perm_inv[old] = new`.
    perm_inv: Vec<usize>,
    /// Column pointers of the original pattern (for row scales).
    orig_col_ptr: Vec<usize>,
    /// Lower triangle of `P Z P^T` by column: rows (`>= j`) and the position
    /// of each entry in the original values array.
    a_col_ptr: Vec<usize>,
    a_row_idx: Vec<u32>,
    a_src: Vec<usize>,
    /// First column of each supernode, and `n` last (`n_super + 1`).
    begin: Vec<usize>,
    /// Rows of each supernode below its diagonal block, ascending:
    /// `rows[row_ptr[s]..row_ptr[s + 1]]`.
    row_ptr: Vec<usize>,
    rows: Vec<u32>,
    /// Offset of each supernode's block in the values (`n_super + 1`).
    val_ptr: Vec<usize>,
    /// Supernode of each column.
    super_of: Vec<u32>,
    /// Children of each supernode in the supernodal elimination tree,
    /// ascending: `children[child_ptr[s]..child_ptr[s + 1]]`.
    child_ptr: Vec<usize>,
    children: Vec<u32>,
    /// Where the update matrix of each supernode lies on the stack once it
    /// is made (its children's lay from there up when it was reached).
    update_at: Vec<usize>,
    /// Entries of the stack at its highest.
    stack_len: usize,
    /// Largest `|R|`, `|C|` and `|R| |C|` of a supernode.
    max_rows: usize,
    max_cols: usize,
    max_rows_cols: usize,
    /// Entries of `L` below the diagonal and multiply-adds of one
    /// factorisation, in the elimination's own pattern (the explicit zeros
    /// of relaxed supernodes not counted).
    nnz_exact: usize,
    madds_exact: u64,
}

/// Numeric factors and buffers of one thread; see the module docs.
#[derive(Clone, Debug, Default)]
pub(crate) struct NumericSupernodal {
    /// The supernodes' blocks.
    values: Vec<C64>,
    d_inv: Vec<C64>,
    /// Update matrices, column-major `|R| x |R|`, lower triangle used
    /// (the strict upper one holds garbage).
    stack: Vec<C64>,
    /// Dense scratch: a block times `D`.
    work: Vec<C64>,
    /// Position of each row of the current supernode in its front.
    local: Vec<u32>,
    /// A child's rows' positions in its parent's front, and the end of the
    /// run of consecutive positions from each.
    rel: Vec<u32>,
    run_end: Vec<u32>,
    /// Per row: the largest entry of its row of `Z`, and the sum of the
    /// terms subtracted from its pivot (`|re| + |im|` norms).
    row_scale: Vec<f64>,
    subtracted: Vec<f64>,
    /// Per row of a supernode's block: the terms its columns subtract.
    acc: Vec<f64>,
    /// Rows `R` of one supernode times the right-hand sides.
    gathered: Vec<C64>,
}

impl SupernodalLdlt {
    /// Matrix dimension.
    pub(crate) fn n(&self) -> usize {
        self.n
    }

    /// Number of supernodes.
    fn n_super(&self) -> usize {
        self.begin.len() - 1
    }

    /// Columns `C` (a range) and rows below `R` of supernode `s`.
    #[inline]
    fn supernode(&self, s: usize) -> (usize, usize, &[u32]) {
        (self.begin[s], self.begin[s + 1], &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]])
    }

    /// Number of stored entries below the diagonal: the strict lower part
    /// of each diagonal block and the rows below it, explicit zeros of
    /// relaxed supernodes included.
    pub(crate) fn nnz_stored(&self) -> usize {
        (0..self.n_super())
            .map(|s| {
                let (f, e, rows) = self.supernode(s);
                let w = e - f;
                w * (w - 1) / 2 + w * rows.len()
            })
            .sum()
    }

    /// Entries of `L` below the diagonal in the elimination's pattern.
    pub(crate) fn nnz_exact(&self) -> usize {
        self.nnz_exact
    }

    /// Complex multiply-adds of one numeric factorisation in the
    /// elimination's pattern (as the simplicial layout counts them).
    pub(crate) fn multiply_adds(&self) -> u64 {
        self.madds_exact
    }

    /// `perm[new] = old`.
    pub(crate) fn perm(&self) -> &[usize] {
        &self.perm
    }

    /// `perm_inv[old] = new`.
    pub(crate) fn perm_inv(&self) -> &[usize] {
        &self.perm_inv
    }

    /// Length of the values of a factorisation or a selected inverse.
    pub(crate) fn values_len(&self) -> usize {
        self.val_ptr[self.n_super()]
    }

    /// Empty numeric storage of the right sizes.
    pub(crate) fn numeric(&self) -> NumericSupernodal {
        NumericSupernodal {
            values: vec![ZERO; self.values_len()],
            d_inv: vec![ZERO; self.n],
            stack: vec![ZERO; self.stack_len],
            work: vec![ZERO; self.max_rows_cols.max(self.max_cols * self.max_cols)],
            local: vec![u32::MAX; self.n],
            rel: vec![0; self.max_rows],
            run_end: vec![0; self.max_rows],
            row_scale: vec![0.0; self.n],
            subtracted: vec![0.0; self.n],
            acc: vec![0.0; self.max_rows + self.max_cols],
            gathered: Vec::new(),
        }
    }

    /// Position in the values of the entry `(row, col)`, internal order,
    /// `row >= col`; `None` when it is not stored.
    pub(crate) fn position(&self, row: usize, col: usize) -> Option<usize> {
        debug_assert!(row >= col);
        let s = self.super_of[col] as usize;
        let (f, e, rows) = self.supernode(s);
        let m = e - f + rows.len();
        let at = self.val_ptr[s] + (col - f) * m;
        if row < e {
            return Some(at + row - f);
        }
        rows.binary_search(&(row as u32)).ok().map(|i| at + e - f + i)
    }
}
