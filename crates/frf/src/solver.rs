//! Sparse factorisation of `Z(w)` once per frequency.
//!
//! [`ZSolver`] holds the symbolic analysis (fill-reducing ordering and
//! elimination structure) of the model's sparsity pattern, computed once and
//! shared by every frequency and iteration. Each thread owns a [`Workspace`]
//! with the numeric factors and scratch memory, reused from one frequency to
//! the next, so the hot loop allocates nothing. faer runs sequentially inside;
//! parallelism is over frequencies (rayon) in the callers.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{LuRef, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par};
use fe_model::Pattern;
use num_complex::Complex64 as C64;

use crate::error::FrfError;

/// Symbolic factorisation of a model's `Z` pattern; see the module docs.
#[derive(Clone, Debug)]
pub struct ZSolver {
    pattern: SymbolicSparseColMat<usize>,
    lu: SymbolicLu<usize>,
}

/// Per-thread numeric factors and scratch memory.
pub struct Workspace {
    numeric: NumericLu<usize, C64>,
    buffer: MemBuffer,
    capacity: StackReq,
    factorized: bool,
}

impl ZSolver {
    /// Analyses a pattern (once per model).
    pub fn new(pattern: &Pattern) -> Result<Self, FrfError> {
        let symbolic = SymbolicSparseColMat::new_checked(
            pattern.n,
            pattern.n,
            pattern.col_ptr.clone(),
            None,
            pattern.row_idx.clone(),
        );
        let lu = factorize_symbolic_lu(symbolic.as_ref(), Default::default())
            .map_err(|e| FrfError::Factorization(format!("{e:?}")))?;
        Ok(ZSolver { pattern: symbolic, lu })
    }

    /// Matrix dimension.
    pub fn n(&self) -> usize {
        self.pattern.nrows()
    }

    /// A fresh workspace for one thread.
    pub fn workspace(&self) -> Workspace {
        let capacity = self
            .lu
            .factorize_numeric_lu_scratch::<C64>(Par::Seq, Default::default())
            .or(self.lu.solve_in_place_scratch::<C64>(1, Par::Seq));
        Workspace { numeric: NumericLu::new(), buffer: MemBuffer::new(capacity), capacity, factorized: false }
    }

    /// Factorises `Z` given as values on the pattern. `freq_hz` is only used
    /// in the error message.
    pub fn factorize(&self, ws: &mut Workspace, values: &[C64], freq_hz: f64) -> Result<(), FrfError> {
        ws.factorized = false;
        if values.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
            return Err(FrfError::BadFrequency { freq_hz });
        }
        let mat = SparseColMatRef::new(self.pattern.as_ref(), values);
        self.lu
            .factorize_numeric_lu(&mut ws.numeric, mat, Par::Seq, MemStack::new(&mut ws.buffer), Default::default())
            .map_err(|_| FrfError::Singular { freq_hz })?;
        ws.factorized = true;
        Ok(())
    }

    /// Solves `Z x = b` in place for every column of `rhs`, with the factors in
    /// `ws`. Returns [`FrfError::Singular`] when the solution is not finite
    /// (faer signals a numerically singular matrix only through NaN or inf).
    pub fn solve_in_place(&self, ws: &mut Workspace, mut rhs: MatMut<'_, C64>, freq_hz: f64) -> Result<(), FrfError> {
        assert!(ws.factorized, "solve called before a successful factorize");
        let need = self.lu.solve_in_place_scratch::<C64>(rhs.ncols(), Par::Seq);
        if need.size_bytes() > ws.capacity.size_bytes() {
            ws.capacity = ws.capacity.or(need);
            ws.buffer = MemBuffer::new(ws.capacity);
        }
        LuRef::new_unchecked(&self.lu, &ws.numeric).solve_in_place_with_conj(
            Conj::No,
            rhs.as_mut(),
            Par::Seq,
            MemStack::new(&mut ws.buffer),
        );
        for j in 0..rhs.ncols() {
            for i in 0..rhs.nrows() {
                let v = rhs[(i, j)];
                if !(v.re.is_finite() && v.im.is_finite()) {
                    return Err(FrfError::Singular { freq_hz });
                }
            }
        }
        Ok(())
    }
}
