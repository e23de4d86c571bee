//! Errors of the FRF layer.

use std::path::PathBuf;

use fe_model::DofRef;

use crate::factor_kind::FactorKind;

/// An FRF computation or data error.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrfError {
    /// A channel names a node the model does not have.
    #[error("{dof} is not a DOF of the model (no such node)")]
    UnknownDof {
        /// The DOF.
        dof: DofRef,
    },
    /// A channel is at a supported (fixed) DOF, where the response is zero.
    #[error("{dof} is held fixed by a support; it cannot be excited or measured")]
    FixedDof {
        /// The DOF.
        dof: DofRef,
    },
    /// `Z(w)` is singular at a frequency (an undamped model on a resonance).
    #[error(
        "the dynamic stiffness is singular at {freq_hz} Hz (an undamped or very lightly damped model evaluated on a resonance?)"
    )]
    Singular {
        /// The frequency.
        freq_hz: f64,
    },
    /// A selected inverse was asked of a workspace without `L D L^T`
    /// factors: the factorisation fell back to LU at that frequency (a tiny
    /// pivot), or none succeeded. Solve for unit right-hand sides instead.
    #[error("the selected inverse needs L D L^T factors, but the workspace holds {}", held_factors(.held))]
    NoLdltFactors {
        /// The factorisation held, if any.
        held: Option<FactorKind>,
    },
    /// A clique given to [`ZSolver::with_cliques`](crate::ZSolver::with_cliques)
    /// names an equation the pattern does not have.
    #[error("clique {clique} names equation {eq}, but the pattern has {n} equations")]
    CliqueOutOfRange {
        /// Index of the clique in the list.
        clique: usize,
        /// The equation.
        eq: usize,
        /// Number of equations.
        n: usize,
    },
    /// The sparse factorisation failed for another reason.
    #[error("sparse factorisation failed: {0}")]
    Factorization(String),
    /// `Z(w)` has an entry that is not finite at a (valid) frequency: some
    /// value of the model overflows when stiffness, mass and damping are
    /// combined.
    #[error(
        "the dynamic stiffness at {freq_hz} Hz has an entry that is not a finite number (equation {equation}): a \
         value of the model (a modulus, density, stiffness, mass or damping coefficient) is so large that K, M or \
         the damping overflow; check the case's values"
    )]
    NonFiniteZ {
        /// The frequency.
        freq_hz: f64,
        /// The first equation (row of `Z`) with a non-finite entry.
        equation: usize,
    },
    /// A frequency that is not positive and finite.
    #[error("frequency {freq_hz} Hz is not positive and finite")]
    BadFrequency {
        /// The frequency.
        freq_hz: f64,
    },
    /// Reading or writing a file failed.
    #[error("{}: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A data file's content is malformed.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line (or byte offset for binary data, see the message).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Data that cannot be written in the requested format (a number too
    /// wide for its fixed-width field, complex FRFs as a real type, ...).
    #[error("cannot write {format}: {message}")]
    Unwritable {
        /// The format (`UFF dataset 58`).
        format: &'static str,
        /// Why.
        message: String,
    },
    /// Two FRF sets that should match do not.
    #[error("{0}")]
    Mismatch(String),
}

fn held_factors(held: &Option<FactorKind>) -> &'static str {
    match held {
        Some(FactorKind::Lu) => "an LU factorisation (the fallback after a tiny pivot)",
        Some(FactorKind::Ldlt) => "L D L^T factors",
        None => "no factorisation",
    }
}
