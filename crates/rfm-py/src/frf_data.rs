//! `rfm.FrfData` (a Python class holding numpy arrays, `rfm/_frf.py`) to and
//! from `frf::FrfSet`, and the readers and writers of measured files.
//!
//! An `FrfSet` is a list of channels (response over reference); `FrfData`
//! is the matrix `h[line, output, input]` of SDynPy's and pyFBS's numpy
//! functions, over the outputs and inputs the channels name, in the order
//! they first appear. A channel the set lacks is NaN in the matrix, and a
//! matrix entry that is NaN at every line is no channel of the set.

use std::collections::HashMap;
use std::path::PathBuf;

use fe_model::{Dof, DofRef};
use frf::io::uff::{Encoding, UffWriteOptions};
use frf::{Channel, FrfKind, FrfSet};
use num_complex::Complex64 as C64;
use numpy::ndarray::{Array1, Array3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray3};
use pyo3::prelude::*;

use crate::case::Case;
use crate::errors::{Error, Result, raise};

/// FRFs on model DOFs with what their level is relative to.
#[derive(Clone, Debug)]
pub(crate) struct Frfs {
    /// The FRFs.
    pub(crate) set: FrfSet,
    /// Per volt (a voltage reference) rather than per newton.
    pub(crate) per_volt: bool,
}

/// The SI units of a kind, per newton or per volt.
fn units(kind: FrfKind, per_volt: bool) -> String {
    let numerator = match kind {
        FrfKind::Receptance => "m",
        FrfKind::Mobility => "m/s",
        FrfKind::Accelerance => "m/s^2",
    };
    format!("{numerator}/{}", if per_volt { "V" } else { "N" })
}

/// A DOF as Python gives it: `(node, "uy")`, or with a UFF direction code
/// (1 to 6 for +X .. +RZ) instead of the name.
fn dof_of(node: u32, direction: &Bound<'_, PyAny>) -> Result<DofRef> {
    let dof = if let Ok(code) = direction.extract::<i64>() {
        match code {
            1 => Dof::Ux,
            2 => Dof::Uy,
            3 => Dof::Uz,
            4 => Dof::Rx,
            5 => Dof::Ry,
            6 => Dof::Rz,
            _ => return Err(Error::data(format!("direction {code} of node {node}: UFF codes 1 to 6 are +X .. +RZ"))),
        }
    } else {
        let name: String = direction.extract().map_err(|_| {
            Error::data(format!("the direction of node {node} is neither a name (uy) nor a code (1-6)"))
        })?;
        name.parse().map_err(|e: String| Error::data(format!("node {node}: {e}")))?
    };
    Ok(DofRef::new(node, dof))
}

fn dofs_of(list: &Bound<'_, PyAny>, what: &str) -> Result<Vec<DofRef>> {
    let pairs: Vec<(u32, Bound<'_, PyAny>)> =
        list.extract().map_err(|_| Error::data(format!("`{what}` must be a list of (node, direction) pairs")))?;
    pairs.iter().map(|(n, d)| dof_of(*n, d)).collect()
}

impl<'py> FromPyObject<'_, 'py> for Frfs {
    type Error = PyErr;

    fn extract(data: Borrowed<'_, 'py, PyAny>) -> PyResult<Self> {
        let py = data.py();
        raise(py, frfs_of(&data))
    }
}

fn frfs_of(data: &Bound<'_, PyAny>) -> Result<Frfs> {
    let attr = |name: &str| data.getattr(name).map_err(|_| Error::data(format!("not an rfm.FrfData: no `{name}`")));
    let freq: PyReadonlyArray1<'_, f64> =
        attr("freq")?.extract().map_err(|_| Error::data("`freq` must be a 1-D float64 array (Hz)"))?;
    let h: PyReadonlyArray3<'_, C64> = attr("h")?
        .extract()
        .map_err(|_| Error::data("`h` must be a complex128 array of shape (n_freq, n_out, n_in)"))?;
    let outputs = dofs_of(&attr("outputs")?, "outputs")?;
    let inputs = dofs_of(&attr("inputs")?, "inputs")?;
    let kind_name: String = attr("kind")?.extract().map_err(|_| Error::data("`kind` must be a string"))?;
    let kind = FrfKind::parse(&kind_name)
        .ok_or_else(|| Error::data(format!("kind `{kind_name}`: receptance, mobility or accelerance")))?;
    let units_name: String = attr("units")?.extract().map_err(|_| Error::data("`units` must be a string"))?;
    let per_volt = units_name.trim().ends_with("/V");
    if units_name.trim() != units(kind, per_volt) {
        return Err(Error::data(format!(
            "units `{units_name}`: the values of an FrfData are SI, `{}` or `{}` for a {kind}",
            units(kind, false),
            units(kind, true)
        )));
    }
    let coherence = attr("coherence")?;
    let coherence: Option<PyReadonlyArray3<'_, f64>> = if coherence.is_none() {
        None
    } else {
        Some(
            coherence
                .extract()
                .map_err(|_| Error::data("`coherence` must be a float64 array shaped as `h`, or None"))?,
        )
    };
    let freq = freq.as_array();
    let h = h.as_array();
    let shape = (freq.len(), outputs.len(), inputs.len());
    if h.dim() != shape {
        return Err(Error::data(format!(
            "`h` has shape {:?}; (n_freq, n_out, n_in) is {shape:?} for {} lines, {} outputs and {} inputs",
            h.shape(),
            shape.0,
            shape.1,
            shape.2
        )));
    }
    let coherence = coherence.as_ref().map(|c| c.as_array());
    if let Some(c) = &coherence
        && c.dim() != shape
    {
        return Err(Error::data(format!("`coherence` has shape {:?}; `h` has {shape:?}", c.shape())));
    }
    // reference-major, as a case lists its channels; an entry NaN at every
    // line (in either part: numpy's `nan` is `nan+0j`) is no channel
    let mut pairs = Vec::new();
    for (i, &r) in inputs.iter().enumerate() {
        for (o, &m) in outputs.iter().enumerate() {
            if (0..shape.0).any(|k| !(h[[k, o, i]].re.is_nan() || h[[k, o, i]].im.is_nan())) {
                pairs.push((o, i, Channel::new(m, r)));
            }
        }
    }
    let channels = pairs.iter().map(|p| p.2).collect();
    let mut set = FrfSet::zeros(freq.to_vec(), channels, kind)?;
    let mut values = Vec::new();
    for (c, &(o, i, _)) in pairs.iter().enumerate() {
        for k in 0..shape.0 {
            set.set(c, k, h[[k, o, i]]);
            if let Some(coh) = &coherence {
                values.push(coh[[k, o, i]]);
            }
        }
    }
    if coherence.is_some() {
        set.set_coherence(values)?;
    }
    Ok(Frfs { set, per_volt })
}

impl Frfs {
    /// The `rfm.FrfData` of these FRFs.
    pub(crate) fn to_python<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let set = &self.set;
        let mut outputs: Vec<DofRef> = Vec::new();
        let mut inputs: Vec<DofRef> = Vec::new();
        for c in set.channels() {
            if !outputs.contains(&c.response) {
                outputs.push(c.response);
            }
            if !inputs.contains(&c.reference) {
                inputs.push(c.reference);
            }
        }
        let out_index: HashMap<DofRef, usize> = outputs.iter().enumerate().map(|(i, d)| (*d, i)).collect();
        let in_index: HashMap<DofRef, usize> = inputs.iter().enumerate().map(|(i, d)| (*d, i)).collect();
        let nf = set.n_freq();
        let mut h = Array3::from_elem((nf, outputs.len(), inputs.len()), C64::new(f64::NAN, f64::NAN));
        let has_coherence = (0..set.channels().len()).any(|c| set.coherence(c).is_some());
        let mut coherence = has_coherence.then(|| Array3::from_elem(h.dim(), f64::NAN));
        for (c, ch) in set.channels().iter().enumerate() {
            let (o, i) = (out_index[&ch.response], in_index[&ch.reference]);
            for (k, v) in set.channel(c).iter().enumerate() {
                h[[k, o, i]] = *v;
            }
            if let (Some(coh), Some(values)) = (coherence.as_mut(), set.coherence(c)) {
                for (k, v) in values.iter().enumerate() {
                    coh[[k, o, i]] = *v;
                }
            }
        }
        let pairs =
            |dofs: &[DofRef]| -> Vec<(u32, &'static str)> { dofs.iter().map(|d| (d.node.0, d.dof.name())).collect() };
        let class = py.import("rfm")?.getattr("FrfData")?;
        let kwargs = pyo3::types::PyDict::new(py);
        kwargs.set_item("freq", Array1::from(set.frequencies_hz().to_vec()).into_pyarray(py))?;
        kwargs.set_item("h", h.into_pyarray(py))?;
        kwargs.set_item("outputs", pairs(&outputs))?;
        kwargs.set_item("inputs", pairs(&inputs))?;
        kwargs.set_item("kind", set.kind().name())?;
        kwargs.set_item("units", units(set.kind(), self.per_volt))?;
        kwargs.set_item("coherence", coherence.map(|c| c.into_pyarray(py)))?;
        class.call((), Some(&kwargs))
    }
}

/// Reads measured FRFs (UFF dataset 58, ASCII or binary, or rfm's CSV):
/// with a case, as the case reads its data (its channel map, mask,
/// calibrations, band and exclusions); without, test directions `+X` ..
/// `+RZ` as `ux` .. `rz` of the node of the same number. Returns the FRFs
/// in the file's kind and the notes on reading them.
#[pyfunction]
#[pyo3(signature = (path, case=None))]
pub(crate) fn read_measured<'py>(
    py: Python<'py>,
    path: PathBuf,
    case: Option<&Case>,
) -> PyResult<(Bound<'py, PyAny>, Vec<String>)> {
    let case = case.map(|c| c.file.clone());
    let read = raise(
        py,
        py.detach(|| -> Result<frf::io::Measured> {
            Ok(match &case {
                Some(case) => {
                    let system = damping::DampedSystem::new(case.model.clone())?;
                    rfm_update::study::read_measured_for(&system, &path, case.measurement.as_ref())?
                }
                None => frf::io::load_measured_opts(
                    &path,
                    &frf::io::ReadOptions { dimension: fe_model::Dimension::Spatial, ..Default::default() },
                )?,
            })
        }),
    )?;
    let per_volt = read.units.iter().filter(|u| u.per_volt).count();
    if per_volt > 0 && per_volt < read.units.len() {
        return Err(Error::data(format!(
            "{}: {per_volt} of its {} channels are per volt and the others per newton; an FrfData holds one or the \
             other (read it with its case, whose calibrations make them alike)",
            path.display(),
            read.units.len()
        ))
        .into_pyerr(py));
    }
    let frfs = Frfs { set: read.set, per_volt: per_volt > 0 };
    Ok((frfs.to_python(py)?, read.notes))
}

/// Writes FRFs as UFF dataset 58 (ASCII, or binary 58b), complex double,
/// responses and references as `+X` .. `+RZ` of their nodes.
#[pyfunction]
#[pyo3(signature = (data, path, binary=false))]
pub(crate) fn write_uff(py: Python<'_>, data: Frfs, path: PathBuf, binary: bool) -> PyResult<()> {
    raise(py, write_uff_file(&data, &path, binary))
}

pub(crate) fn write_uff_file(data: &Frfs, path: &std::path::Path, binary: bool) -> Result<()> {
    if data.per_volt {
        return Err(Error::data(format!(
            "{}: FRFs per volt cannot be written as UFF here (the writer labels them per newton); write them as \
             CSV with write_csv",
            path.display()
        )));
    }
    let encoding = if binary { Encoding::BINARY } else { Encoding::Ascii };
    crate::errors::written(frf::io::uff::write_uff(
        &data.set,
        path,
        &UffWriteOptions { encoding, ..UffWriteOptions::default() },
        &[],
    ))
}

/// Writes FRFs as rfm's CSV (every digit of a double; no coherence).
#[pyfunction]
pub(crate) fn write_csv(py: Python<'_>, data: Frfs, path: PathBuf) -> PyResult<()> {
    raise(py, write_csv_file(&data, &path))
}

pub(crate) fn write_csv_file(data: &Frfs, path: &std::path::Path) -> Result<()> {
    let text = frf::io::csv::to_csv_string_as(&data.set, data.per_volt);
    crate::errors::written(frf::io::atomic_write(path, text.as_bytes(), &[]))
}
