//! `rfm.Case`: a case file, loaded and checked by `fe_model::CaseFile`.

use std::path::{Path, PathBuf};

use fe_model::CaseFile;
use frf::FrfKind;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::{Error, Result, raise};
use crate::frf_data::Frfs;
use crate::run;

/// A case: the model, its measurement and what to update, as a case file
/// (TOML) describes them. Made by `rfm.load_case`, `Case.from_toml` or
/// `Case.from_dict`; every error names the file, line and column.
#[pyclass(module = "rfm._rfm", frozen)]
pub(crate) struct Case {
    pub(crate) file: CaseFile,
}

impl Case {
    pub(crate) fn new(file: CaseFile) -> Case {
        Case { file }
    }
}

/// The path a case made from text is known by: `name` in the current
/// folder, so that its data files resolve from there.
fn text_path(path: Option<PathBuf>) -> PathBuf {
    path.unwrap_or_else(|| PathBuf::from("<string>.toml"))
}

/// A Python value as TOML: dicts as tables, lists and tuples as arrays.
fn toml_value(value: &Bound<'_, PyAny>, at: &str) -> Result<toml::Value> {
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.extract().map_err(|_| Error::argument(at.to_string()))?));
    }
    if value.is_instance_of::<PyInt>() {
        let v: i64 = value.extract().map_err(|_| Error::argument(format!("{at}: the integer is too large")))?;
        return Ok(toml::Value::Integer(v));
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract().map_err(|_| Error::argument(at.to_string()))?));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(value.extract().map_err(|_| Error::argument(at.to_string()))?));
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in dict.iter() {
            let key: String =
                k.extract().map_err(|_| Error::argument(format!("{at}: the keys of a table must be strings")))?;
            let inner = if at.is_empty() { key.clone() } else { format!("{at}.{key}") };
            table.insert(key, toml_value(&v, &inner)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = value.extract().map_err(|_| Error::argument(at.to_string()))?;
        return items
            .iter()
            .enumerate()
            .map(|(i, v)| toml_value(v, &format!("{at}[{i}]")))
            .collect::<Result<Vec<_>>>()
            .map(toml::Value::Array);
    }
    // numpy scalars and other numbers
    if let Ok(v) = value.extract::<f64>() {
        return Ok(toml::Value::Float(v));
    }
    let type_name = value.get_type().name().map(|n| n.to_string()).unwrap_or_default();
    Err(Error::argument(format!("{at}: a {type_name} has no TOML form (use dicts, lists, str, int, float, bool)")))
}

#[pymethods]
impl Case {
    /// A case from the text of a case file; `path` (not read) names it in
    /// messages, and its folder is where relative data files are found
    /// (default: `<string>.toml` in the current folder).
    #[staticmethod]
    #[pyo3(signature = (text, path=None))]
    fn from_toml(py: Python<'_>, text: &str, path: Option<PathBuf>) -> PyResult<Case> {
        let path = text_path(path);
        raise(py, CaseFile::parse(&path, text).map(Case::new).map_err(Error::from))
    }

    /// A case from a dict laid out as the case file's tables (as
    /// `tomllib.load` gives them); `path` as for `from_toml`.
    #[staticmethod]
    #[pyo3(signature = (tables, path=None))]
    fn from_dict(py: Python<'_>, tables: &Bound<'_, PyDict>, path: Option<PathBuf>) -> PyResult<Case> {
        let text = raise(
            py,
            toml_value(tables.as_any(), "").and_then(|v| {
                toml::to_string(&v).map_err(|e| Error::argument(format!("the dict has no TOML form: {e}")))
            }),
        )?;
        Case::from_toml(py, &text, path)
    }

    /// The file the case was read from (or the name it was given).
    #[getter]
    fn path(&self) -> PathBuf {
        self.file.path.clone()
    }

    /// The model's title.
    #[getter]
    fn title(&self) -> String {
        self.file.model.title.clone()
    }

    /// The case file's text.
    fn to_toml(&self) -> String {
        self.file.source.clone()
    }

    /// The names of the parameters the case updates.
    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.file.update.as_ref().map(|u| u.parameters.iter().map(|p| p.name.clone()).collect()).unwrap_or_default()
    }

    /// Writes the case file to `path` (its data and geometry paths made
    /// relative to the new folder), never over one of its inputs.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        raise(py, save_case(&self.file, &path))
    }

    /// The model's FRFs (or the truth's) at the case's measurement lines
    /// and channels, as `rfm simulate` writes them, with the same noise for
    /// the same seed.
    #[pyo3(signature = (truth=false, noise=0.0, seed=0, kind="receptance"))]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        truth: bool,
        noise: f64,
        seed: u64,
        kind: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let file = &self.file;
        let set = run::run(py, None, |_| simulate(file, truth, noise, seed, kind))?;
        Frfs { set, per_volt: false }.to_python(py)
    }

    /// The measured FRFs the case compares with (its data file read as the
    /// case reads it, or the data synthesised from its `[truth]`), in the
    /// kind they were measured in.
    fn measured<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let file = self.file.clone();
        let (set, per_volt) = run::run(py, None, move |_| {
            let study = rfm_update::Study::from_case(file)?;
            Ok((study.measured_as_read(), !study.per_volt().is_empty()))
        })?;
        Frfs { set, per_volt }.to_python(py)
    }

    fn __repr__(&self) -> String {
        format!("Case({:?}, path={:?})", self.file.model.title, self.file.path.display().to_string())
    }
}

pub(crate) fn save_case(file: &CaseFile, path: &Path) -> Result<()> {
    let text = file.editor()?.text_at(path)?;
    crate::errors::written(frf::io::atomic_write(path, text.as_bytes(), &file.inputs()))
}

/// What `rfm simulate` synthesises, in memory (`rfm_cli::synthesised`).
fn simulate(file: &CaseFile, truth: bool, noise: f64, seed: u64, kind: &str) -> Result<frf::FrfSet> {
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(Error::argument(format!(
            "noise {noise}: the relative noise level must be a finite number, 0 or more (0.01 = 1 %)"
        )));
    }
    let kind = FrfKind::parse(kind)
        .ok_or_else(|| Error::argument(format!("kind {kind}: receptance, mobility or accelerance")))?;
    Ok(rfm_cli::synthesised(file, truth, noise, seed, kind)?)
}
