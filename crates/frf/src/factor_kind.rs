//! Which factorisation of `Z(w)` a workspace holds, and how its `L D L^T`
//! factor is laid out: words shared by the solver, its factorisations and
//! its errors, kept apart so that none imports another for them.

/// Which factorisation a [`Workspace`](crate::Workspace) holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorKind {
    /// Complex-symmetric `L D L^T` (the normal case).
    Ldlt,
    /// Sparse LU with partial pivoting (the fallback).
    Lu,
}

/// How the `L D L^T` factor of a [`ZSolver`](crate::ZSolver) is stored and
/// computed; chosen from the symbolic analysis unless asked for
/// ([`ZSolver::with_layout`](crate::ZSolver::with_layout)). Both give the
/// same factors to round-off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Column by column, entry by entry: for factors with short columns
    /// (beams and frames), where it has no overhead to amortise.
    Simplicial,
    /// Runs of columns with one pattern as dense blocks, with dense kernels:
    /// for factors with long columns (shell and solid meshes), where those
    /// run several times faster.
    Supernodal,
}
