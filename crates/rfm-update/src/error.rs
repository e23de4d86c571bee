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
    /// The measured data cannot serve what the case asks (a channel or
    /// line it names is missing, the band leaves nothing, too few lines,
    /// no coherence to weight by, an FRF that is zero everywhere).
    #[error("{0}")]
    Data(String),
    /// The updating lines the case designates are not lines of the data.
    #[error("{0}")]
    Lines(String),
    /// The case has no `[update]` parameters to update.
    #[error("the case has no [update] parameters")]
    NoParameters,
    /// Something asked of a method that it cannot do (gains the response
    /// function method does not fit, a rank the ranking lacks, a loop of
    /// no steps).
    #[error("{0}")]
    Method(String),
}
