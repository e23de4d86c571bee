//! Which factorisation of `Z(w)` a workspace holds: a word shared by the
//! solver and its errors, kept apart so that neither imports the other for it.

/// Which factorisation a [`Workspace`](crate::Workspace) holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorKind {
    /// Complex-symmetric `L D L^T` (the normal case).
    Ldlt,
    /// Sparse LU with partial pivoting (the fallback).
    Lu,
}
