//! Errors as Python exceptions: every library error becomes one of the
//! classes of `rfm.errors` (all under `rfm.RfmError`), with the message the
//! `rfm` command prints for it (`rfm_cli::Failure`, which renders a case
//! error with its file, line and column) and the command's exit code.

use fe_model::{CaseError, ModelError};
use frf::FrfError;
use pyo3::prelude::*;
use rfm_cli::{Exit, Failure};
use rfm_update::UpdateError;

/// Which exception class an error is raised as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Class {
    /// A case file or its values (`rfm.CaseError`, a `ValueError`).
    Case,
    /// Measured data (`rfm.DataError`, a `ValueError`).
    Data,
    /// Failed numerics (`rfm.NumericsError`).
    Numerics,
    /// Outputs not written (`rfm.OutputError`, an `OSError`).
    Output,
    /// A wrong argument of a function (`rfm.ArgumentError`, a `ValueError`).
    Argument,
    /// A bug (`rfm.RfmError`).
    Internal,
}

impl Class {
    fn name(self) -> &'static str {
        match self {
            Class::Case => "CaseError",
            Class::Data => "DataError",
            Class::Numerics => "NumericsError",
            Class::Output => "OutputError",
            Class::Argument => "ArgumentError",
            Class::Internal => "RfmError",
        }
    }

    /// The class of a command's failure, from its exit code (the command's
    /// own classification of the library error).
    fn of_exit(exit: Exit) -> Class {
        match exit {
            Exit::InvalidInput => Class::Data,
            Exit::Numerics => Class::Numerics,
            Exit::Output | Exit::Busy => Class::Output,
            Exit::Usage => Class::Argument,
            _ => Class::Internal,
        }
    }
}

/// An error on its way to Python: the class, the CLI's message and exit code.
#[derive(Debug)]
pub(crate) struct Error {
    class: Class,
    failure: Failure,
}

impl Error {
    /// An error of `class` with the exit code `exit`.
    pub(crate) fn new(class: Class, exit: Exit, message: impl Into<String>) -> Error {
        Error { class, failure: Failure::new(exit, message) }
    }

    /// A wrong argument (the command line's usage error).
    pub(crate) fn argument(message: impl Into<String>) -> Error {
        Error::new(Class::Argument, Exit::Usage, message)
    }

    /// Bad measured data given from Python.
    pub(crate) fn data(message: impl Into<String>) -> Error {
        Error::new(Class::Data, Exit::InvalidInput, message)
    }

    /// The exception, an instance of the `rfm.errors` class with
    /// `exit_code` set.
    pub(crate) fn into_pyerr(self, py: Python<'_>) -> PyErr {
        let raise = || -> PyResult<PyErr> {
            let class = py.import("rfm.errors")?.getattr(self.class.name())?;
            let value = class.call1((self.failure.message.clone(),))?;
            value.setattr("exit_code", self.failure.exit.code())?;
            Ok(PyErr::from_value(value))
        };
        raise().unwrap_or_else(|e| e)
    }
}

impl From<Failure> for Error {
    fn from(failure: Failure) -> Self {
        Error { class: Class::of_exit(failure.exit), failure }
    }
}

impl From<CaseError> for Error {
    fn from(e: CaseError) -> Self {
        Error { class: Class::Case, failure: e.into_failure() }
    }
}

impl From<ModelError> for Error {
    fn from(e: ModelError) -> Self {
        Error { class: Class::Case, failure: e.into_failure() }
    }
}

impl From<FrfError> for Error {
    fn from(e: FrfError) -> Self {
        Error::from(Failure::from(e))
    }
}

impl From<UpdateError> for Error {
    fn from(e: UpdateError) -> Self {
        let class = match &e {
            UpdateError::Case(_) | UpdateError::Model(_) | UpdateError::NoParameters | UpdateError::Method(_) => {
                Some(Class::Case)
            }
            UpdateError::Data(_) | UpdateError::Lines(_) => Some(Class::Data),
            UpdateError::Numerics(_) => Some(Class::Numerics),
            UpdateError::Frf(_) => None,
        };
        let failure = Failure::from(e);
        Error { class: class.unwrap_or(Class::of_exit(failure.exit)), failure }
    }
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::new(Class::Output, Exit::Output, e.to_string())
    }
}

/// The error of writing a file: a file system failure (or an input in
/// the way) is an output error, whatever the reader's classification of
/// the same error kind would be.
pub(crate) fn written(result: std::result::Result<(), FrfError>) -> Result<()> {
    result.map_err(|e| match e {
        FrfError::File(frf::FileError::Io { .. }) => Error::new(Class::Output, Exit::Output, e.to_string()),
        other => Error::from(other),
    })
}

/// The CLI's rendering of an error.
trait IntoFailure {
    fn into_failure(self) -> Failure;
}

impl<E> IntoFailure for E
where
    Failure: From<E>,
{
    fn into_failure(self) -> Failure {
        Failure::from(self)
    }
}

/// A result whose error becomes a Python exception.
pub(crate) type Result<T> = std::result::Result<T, Error>;

/// Raises `result`'s error as its Python exception.
pub(crate) fn raise<T>(py: Python<'_>, result: Result<T>) -> PyResult<T> {
    result.map_err(|e| e.into_pyerr(py))
}
