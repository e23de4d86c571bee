//! Errors of the updating layer.

use fe_model::{CaseError, ModelError};
use frf::FrfError;

/// Why an updating run could not be set up or carried out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UpdateError {
    /// The case file is invalid.
    #[error("{}", .0.render())]
    Case(#[from] CaseError),
    /// The model is invalid.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// An FRF computation or data error.
    #[error(transparent)]
    Frf(#[from] FrfError),
    /// The numbers went wrong: a misfit or a model response that is not
    /// finite, with where it happened.
    #[error("{0}")]
    Numerics(String),
    /// Something the case asks for that this method cannot do.
    #[error("{0}")]
    Setup(String),
}
