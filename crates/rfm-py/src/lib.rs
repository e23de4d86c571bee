//! The extension module `rfm._rfm` of the Python package `rfm`
//! (`python/rfm/`): a thin skin over the workspace's crates. It converts
//! types (numpy arrays to and from `frf::FrfSet`, Python dicts to case-file
//! TOML) and errors (to the exception classes of `rfm.errors`, with the
//! `rfm` command's messages), and calls the libraries and the commands'
//! non-printing parts in `rfm_cli`; it computes nothing itself.
//!
//! Every long call runs with the GIL released, on a rayon pool whose size
//! `set_num_threads` sets, and stops at the next stage on Ctrl-C
//! (`run.rs`).

mod case;
mod errors;
mod frf_data;
mod run;
mod workflow;

use pyo3::prelude::*;

/// The compiled part of the `rfm` package; use `import rfm`.
#[pymodule]
fn _rfm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<case::Case>()?;
    m.add_class::<workflow::Comparison>()?;
    m.add_class::<workflow::DiagnosisResult>()?;
    m.add_class::<workflow::UpdateResult>()?;
    m.add_class::<workflow::FixResult>()?;
    m.add_function(wrap_pyfunction!(load_case, m)?)?;
    m.add_function(wrap_pyfunction!(frf_data::read_measured, m)?)?;
    m.add_function(wrap_pyfunction!(frf_data::write_uff, m)?)?;
    m.add_function(wrap_pyfunction!(frf_data::write_csv, m)?)?;
    m.add_function(wrap_pyfunction!(workflow::compare, m)?)?;
    m.add_function(wrap_pyfunction!(workflow::diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(workflow::update, m)?)?;
    m.add_function(wrap_pyfunction!(workflow::fix, m)?)?;
    m.add_function(wrap_pyfunction!(run::set_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(run::get_num_threads, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

/// Loads and checks a case file.
#[pyfunction]
fn load_case(py: Python<'_>, path: std::path::PathBuf) -> PyResult<case::Case> {
    errors::raise(py, fe_model::CaseFile::load(&path).map(case::Case::new).map_err(errors::Error::from))
}
