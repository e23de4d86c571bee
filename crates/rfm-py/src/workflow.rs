//! The workflow: `compare`, `diagnose`, `update`, `fix`, each a call of the
//! command's non-printing part in `rfm_cli` (so that a result's JSON is
//! the command's `--json` and its `save` writes the command's files), run
//! through [`crate::run::run`]. Measured data given as an `rfm.FrfData`
//! are written to a temporary file and read as `--measured` reads a file.

use std::path::{Path, PathBuf};

use fe_model::CaseFile;
use pyo3::prelude::*;
use rfm_cli::{CompareRun, FrequencyScale, ReportOptions, UpdateOverrides, UpdateSetup};
use rfm_update::diagnose::Diagnosis;
use rfm_update::fix::{FixOutcome, FixProgress, Prepared, fix as run_fix};
use rfm_update::{Study, UpdateOutcome};

use crate::case::Case;
use crate::errors::{Error, Result, raise};
use crate::frf_data::{Frfs, write_csv_file, write_uff_file};
use crate::run::run;

/// Measured data given from Python: a file, or FRFs in memory.
pub(crate) enum Measured {
    File(PathBuf),
    Data(Frfs),
}

impl<'py> FromPyObject<'_, 'py> for Measured {
    type Error = PyErr;

    fn extract(value: Borrowed<'_, 'py, PyAny>) -> PyResult<Self> {
        if let Ok(path) = value.extract::<PathBuf>() {
            return Ok(Measured::File(path));
        }
        Ok(Measured::Data(value.extract()?))
    }
}

/// A measured file to read as `--measured` reads one, and the case to read
/// it with.
struct Staged {
    path: PathBuf,
    case: CaseFile,
    /// The folder of a file written from FRFs in memory, removed when dropped.
    _dir: Option<tempfile::TempDir>,
}

/// Writes FRFs given in memory where the readers find them: binary UFF 58b
/// (every double as it is, coherence kept), read without the case's
/// channel map or pairing by coordinates (its directions are model DOFs
/// already, the inverse of the default map); FRFs per volt, which the UFF
/// writer does not label, as CSV (`SI/V`, without coherence).
fn stage(case: &CaseFile, measured: Measured) -> Result<Staged> {
    let data = match measured {
        Measured::File(path) => return Ok(Staged { path, case: case.clone(), _dir: None }),
        Measured::Data(data) => data,
    };
    let dir = tempfile::Builder::new().prefix("rfm-").tempdir()?;
    let mut case = case.clone();
    let path = if data.per_volt {
        if (0..data.set.channels().len()).any(|c| data.set.coherence(c).is_some()) {
            return Err(Error::data(
                "FRFs per volt with coherence cannot be given in memory yet (the CSV that carries `per volt` has no \
                 coherence): write them as a UFF file with their units and give its path",
            ));
        }
        let path = dir.path().join("frfdata-from-python.csv");
        write_csv_file(&data, &path)?;
        path
    } else {
        let path = dir.path().join("frfdata-from-python.uff");
        write_uff_file(&data, &path, true)?;
        if let Some(m) = case.measurement.as_mut() {
            m.map.clear();
            m.pairing = None;
        }
        path
    };
    Ok(Staged { path, case, _dir: Some(dir) })
}

/// The case reading `measured` instead of its own data or `[truth]`, as
/// the `--measured` of `rfm update` and `rfm fix` makes it: a file as it
/// is; FRFs in memory from a file written for them (in model DOFs, read
/// without the case's map), whose folder is kept, since the cases a
/// result gives read it, and whose path is returned too: a result's
/// `save` copies that file into its folder, so that the cases saved read
/// the copy, not a temporary file.
fn reading(case: &CaseFile, measured: Option<Measured>) -> Result<(CaseFile, Option<PathBuf>)> {
    let Some(measured) = measured else { return Ok((case.clone(), None)) };
    let staged = stage(case, measured)?;
    let Some(dir) = staged._dir else { return Ok((case.with_data(&staged.path)?, None)) };
    let _ = dir.keep();
    // (FRFs per volt are staged as rfm's CSV, which names model DOFs and
    // which no map reads either)
    Ok((case.with_model_dof_data(&staged.path)?, Some(staged.path)))
}

fn report_options(frequency_axis: &str) -> Result<ReportOptions> {
    let frequency_scale = match frequency_axis {
        "auto" => FrequencyScale::Auto,
        "log" => FrequencyScale::Log,
        "linear" => FrequencyScale::Linear,
        other => return Err(Error::argument(format!("frequency_axis `{other}`: auto, log or linear"))),
    };
    Ok(ReportOptions { frequency_scale, ..ReportOptions::default() })
}

/// The case of a case editor's text, as a file at `target` would hold it.
fn case_at(editor: &fe_model::CaseEditor, target: &Path) -> Result<Case> {
    let text = editor.text_at(target)?;
    Ok(Case::new(CaseFile::parse(target, &text)?))
}

/// A path beside `case` named `CASE-what.toml` (not written).
fn beside(case: &CaseFile, what: &str) -> PathBuf {
    let stem = case.path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "case".into());
    case.path.with_file_name(format!("{stem}-{what}.toml"))
}

/// A case's data written as CSV into a temporary folder, for the cases a
/// result makes in memory from a case that synthesises its data from its
/// `[truth]` (they read the data instead).
fn data_file(study: &Study) -> Result<(tempfile::TempDir, PathBuf)> {
    let dir = tempfile::Builder::new().prefix("rfm-").tempdir()?;
    let path = dir.path().join("measured.csv");
    crate::errors::written(frf::io::atomic_write(
        &path,
        frf::io::csv::to_csv_string(study.measured()).as_bytes(),
        &[],
    ))?;
    Ok((dir, path))
}

// ---------------------------------------------------------------- compare

/// The result of `rfm.compare` (Python wraps it in `rfm.Comparison`).
#[pyclass(module = "rfm._rfm", frozen)]
pub(crate) struct Comparison {
    run: CompareRun,
}

/// `rfm compare`: the case's model against its measured data (or `measured`).
#[pyfunction]
#[pyo3(signature = (case, measured=None, bands="auto".to_string(), progress=None))]
pub(crate) fn compare(
    py: Python<'_>,
    case: &Case,
    measured: Option<Measured>,
    bands: String,
    progress: Option<Py<PyAny>>,
) -> PyResult<Comparison> {
    let file = &case.file;
    let run = run(py, progress, move |p| {
        let staged = measured.map(|m| stage(file, m)).transpose()?;
        p.say("comparing the model with the measured FRFs");
        let (case, files) = match &staged {
            Some(s) => (s.case.clone(), vec![s.path.clone()]),
            None => (file.clone(), Vec::new()),
        };
        Ok(CompareRun::new(&file.path, case, &files, &bands)?)
    })?;
    Ok(Comparison { run })
}

#[pymethods]
impl Comparison {
    /// What `rfm compare --json` prints.
    fn json(&self, py: Python<'_>) -> PyResult<String> {
        raise(py, self.run.json().map_err(Error::from))
    }

    /// Writes what `rfm compare --out DIR` writes; returns the files.
    #[pyo3(signature = (folder, frequency_axis="auto"))]
    fn save(&self, py: Python<'_>, folder: PathBuf, frequency_axis: &str) -> PyResult<Vec<PathBuf>> {
        let opts = raise(py, report_options(frequency_axis))?;
        let run = &self.run;
        crate::run::run(py, None, |_| Ok(run.save(&folder, &opts)?))
    }

    /// The measured FRFs, in the kind they were measured in.
    fn measured<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Frfs { set: self.run.measured().clone(), per_volt: false }.to_python(py)
    }

    /// The MAC matrix of the measured modes (rows) against the model's
    /// (columns) with their frequencies in Hz, or None when the modes could
    /// not be compared.
    #[allow(clippy::type_complexity)]
    fn mac(&self) -> Option<(Vec<Vec<f64>>, Vec<f64>, Vec<f64>)> {
        let m = self.run.modes().ok()?;
        let hz = |modes: &[frf::Mode]| modes.iter().map(|x| x.frequency_hz).collect();
        Some((m.pairing.mac.clone(), hz(&m.measured), hz(&m.model)))
    }

    /// The model's FRFs on the measured channels and lines, times the
    /// fitted gains.
    fn model<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Frfs { set: self.run.model_frfs().clone(), per_volt: false }.to_python(py)
    }
}

// --------------------------------------------------------------- diagnose

/// The result of `rfm.diagnose` (Python wraps it in `rfm.Diagnosis`).
#[pyclass(module = "rfm._rfm", frozen)]
pub(crate) struct DiagnosisResult {
    study: Study,
    /// The data checked and corrected and the case's own parameters
    /// updated: the case the diagnosis is of.
    prepared: Prepared,
    diagnosis: Diagnosis,
    notes: Vec<String>,
    /// The measured file given, as `--measured`.
    measured: Option<PathBuf>,
    /// Whether that file was written for FRFs given in memory (its folder
    /// is kept for the cases `apply` gives; `save` copies it beside the
    /// case it writes).
    carried: bool,
}

/// `rfm diagnose`: every candidate effect fitted and ranked.
#[pyfunction]
#[pyo3(signature = (case, measured=None, progress=None))]
pub(crate) fn diagnose(
    py: Python<'_>,
    case: &Case,
    measured: Option<Measured>,
    progress: Option<Py<PyAny>>,
) -> PyResult<DiagnosisResult> {
    let file = &case.file;
    run(py, progress, move |p| {
        let staged = measured.map(|m| stage(file, m)).transpose()?;
        let case = staged.as_ref().map_or_else(|| file.clone(), |s| s.case.clone());
        let mut study = Study::from_case(case)?;
        p.checkpoint();
        let path = staged.as_ref().map(|s| s.path.clone());
        let (data, notes, _masked) = rfm_cli::diagnosis_data(&mut study, path.as_deref())?;
        let (prepared, diagnosis) = rfm_cli::run_diagnosis(&study, &data, None, &mut |_| {}, |stage| p.say(stage))?;
        let carried = staged.and_then(|s| s._dir).map(tempfile::TempDir::keep).is_some();
        Ok(DiagnosisResult { study, prepared, diagnosis, notes, measured: path, carried })
    })
}

#[pymethods]
impl DiagnosisResult {
    /// What `rfm diagnose --json` prints.
    fn json(&self, py: Python<'_>) -> PyResult<String> {
        raise(py, rfm_cli::diagnosis_json(&self.notes, &self.prepared, &self.diagnosis).map_err(Error::from))
    }

    /// The case with the effect of `rank` added, in memory (a case whose
    /// data come from its `[truth]` reads them from a temporary file).
    fn apply(&self, py: Python<'_>, rank: usize) -> PyResult<Case> {
        raise(py, self.applied(rank))
    }

    /// Writes what `rfm diagnose --apply RANK --out PATH` writes; returns
    /// the data file written beside it, if any.
    fn save(&self, py: Python<'_>, path: PathBuf, rank: usize) -> PyResult<Option<PathBuf>> {
        let (study, d, measured) = (&self.study, &self.diagnosis, self.measured.as_deref());
        let carried = measured.filter(|_| self.carried);
        let base = &self.prepared.case;
        run(py, None, |_| Ok(rfm_cli::write_applied(study, base, d, rank, (measured, carried), &path)?))
    }
}

impl DiagnosisResult {
    fn applied(&self, rank: usize) -> Result<Case> {
        let case = &self.prepared.case;
        let synthesised = self.measured.is_none()
            && case.measurement.as_ref().is_some_and(|m| m.data.is_none())
            && case.truth.is_some();
        let data = synthesised.then(|| data_file(&self.study)).transpose()?;
        let mut editor = self.diagnosis.apply_with_data(case, rank, data.as_ref().map(|d| d.1.as_path()))?;
        // the data the diagnosis read, as `save` writes the case (the case's
        // own data file would be read without its map when the FRFs were
        // given in memory)
        if let Some(measured) = &self.measured {
            editor.use_data(measured);
        }
        let applied = case_at(&editor, &beside(case, &format!("effect-{rank}")))?;
        // the case reads the data: their folder is left for the system to clean
        if let Some((dir, _)) = data {
            let _ = dir.keep();
        }
        Ok(applied)
    }
}

// ----------------------------------------------------------------- update

/// The result of `rfm.update` (Python wraps it in `rfm.UpdateResult`).
#[pyclass(module = "rfm._rfm", frozen)]
pub(crate) struct UpdateResult {
    study: Study,
    outcome: UpdateOutcome,
    step: fe_model::HistoryEntry,
    /// The file written for FRFs given in memory (see [`reading`]).
    carried: Option<PathBuf>,
}

/// `rfm update`: the case's parameters updated.
#[pyfunction]
#[pyo3(signature = (case, measured=None, method=None, lines=None, iterations=None, progress=None))]
pub(crate) fn update(
    py: Python<'_>,
    case: &Case,
    measured: Option<Measured>,
    method: Option<String>,
    lines: Option<usize>,
    iterations: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<UpdateResult> {
    let file = &case.file;
    run(py, progress, move |p| {
        let (case, carried) = reading(file, measured)?;
        let mut study = Study::from_case(case)?;
        let setup = UpdateSetup::new(&mut study, &UpdateOverrides { method, lines, max_iterations: iterations })?;
        let mut outcome = setup.run(&study, |r| {
            p.say(&format!(
                "iteration {}: misfit {:.4e}, largest step {:.3e}",
                r.iteration, r.residual, r.max_correction
            ))
        })?;
        p.checkpoint();
        let step = rfm_cli::finish_update(&study, &mut outcome)?;
        Ok(UpdateResult { study, outcome, step, carried })
    })
}

#[pymethods]
impl UpdateResult {
    /// What `rfm update --json` prints.
    fn json(&self, py: Python<'_>) -> PyResult<String> {
        raise(py, rfm_cli::update_json(&self.study, &self.outcome).map_err(Error::from))
    }

    /// Writes what `rfm update --out DIR` writes; returns the paths of
    /// `results.json`, `updated.toml` and `report.html`.
    #[pyo3(signature = (folder, frequency_axis="auto"))]
    fn save(&self, py: Python<'_>, folder: PathBuf, frequency_axis: &str) -> PyResult<Vec<PathBuf>> {
        let opts = raise(py, report_options(frequency_axis))?;
        let (study, outcome, step) = (&self.study, &self.outcome, &self.step);
        let case = study.case().path.clone();
        let into = (folder.as_path(), self.carried.as_deref());
        run(py, None, |_| Ok(rfm_cli::save_update(study, outcome, step, &case, into, &opts)?.to_vec()))
    }

    /// The updated case (`updated.toml`), in memory.
    fn case(&self, py: Python<'_>) -> PyResult<Case> {
        raise(
            py,
            rfm_cli::updated_case(&self.study, &self.outcome, &self.step)
                .map_err(Error::from)
                .and_then(|e| case_at(&e, &beside(self.study.case(), "updated"))),
        )
    }

    /// The exit code `rfm update` would end with, and its meaning.
    fn exit(&self) -> (u8, &'static str) {
        let exit = rfm_cli::Exit::of_outcome(&self.outcome);
        (exit.code(), exit.meaning())
    }
}

// -------------------------------------------------------------------- fix

/// The result of `rfm.fix` (Python wraps it in `rfm.FixResult`).
#[pyclass(module = "rfm._rfm", frozen)]
pub(crate) struct FixResult {
    study: Study,
    outcome: FixOutcome,
    steps: usize,
    /// The file written for FRFs given in memory (see [`reading`]).
    carried: Option<PathBuf>,
}

/// What the loop did, as `rfm fix` prints it.
fn fix_line(p: &FixProgress<'_>) -> String {
    rfm_cli::fix_progress_lines(p).join("\n")
}

/// `rfm fix`: diagnose, add the recommended effect, update, and again.
#[pyfunction]
#[pyo3(signature = (case, measured=None, steps=3, progress=None))]
pub(crate) fn fix(
    py: Python<'_>,
    case: &Case,
    measured: Option<Measured>,
    steps: usize,
    progress: Option<Py<PyAny>>,
) -> PyResult<FixResult> {
    if !(1..=20).contains(&steps) {
        return Err(Error::argument(format!("steps {steps}: from 1 to 20")).into_pyerr(py));
    }
    let file = &case.file;
    run(py, progress, move |p| {
        let (case, carried) = reading(file, measured)?;
        let study = Study::from_case(case)?;
        p.checkpoint();
        let (dir, data) = data_file(&study)?;
        let opts = rfm_cli::fix_options(&study, steps, data)?;
        // the steps' cases read the data synthesised from the case's
        // `[truth]` from that file, and outlive the result (`FixResult.case`
        // kept, the result dropped): it is kept, as `Diagnosis.apply` keeps
        // its own, and left for the system to clean
        if opts.data.is_some() {
            let _ = dir.keep();
        }
        let outcome = run_fix(study.case(), study.measured(), &opts, |e| p.say(&fix_line(&e)))?;
        Ok(FixResult { study, outcome, steps, carried })
    })
}

#[pymethods]
impl FixResult {
    /// What `rfm fix --json` prints.
    fn json(&self, py: Python<'_>) -> PyResult<String> {
        raise(py, serde_json::to_string_pretty(&self.outcome).map_err(|e| Error::from(rfm_cli::Failure::from(e))))
    }

    /// Writes what `rfm fix --out DIR` writes; returns the files.
    #[pyo3(signature = (folder, frequency_axis="auto"))]
    fn save(&self, py: Python<'_>, folder: PathBuf, frequency_axis: &str) -> PyResult<Vec<PathBuf>> {
        let opts = raise(py, report_options(frequency_axis))?;
        let (study, outcome, steps) = (&self.study, &self.outcome, self.steps);
        let into = (folder.as_path(), self.carried.as_deref());
        run(py, None, |_| Ok(rfm_cli::save_fix(study, outcome, steps, into, &opts)?))
    }

    /// The case after each step, in memory.
    fn step_cases(&self, py: Python<'_>) -> PyResult<Vec<Case>> {
        let case = self.study.case();
        raise(
            py,
            self.outcome
                .steps
                .iter()
                .enumerate()
                .map(|(k, s)| case_at(&s.case, &beside(case, &format!("step-{}", k + 1))))
                .collect(),
        )
    }

    /// The misfit after the last step (the nominal model's without steps).
    fn final_misfit(&self) -> f64 {
        self.outcome.final_misfit()
    }

    /// The misfit at every stage of the loop, labelled as `rfm fix` prints
    /// them: the nominal model's, then after adding and after updating
    /// each effect.
    fn stages(&self) -> Vec<(String, f64)> {
        self.outcome.stages()
    }

    /// The exit code `rfm fix` would end with, and its meaning.
    fn exit(&self) -> (u8, &'static str) {
        let exit = rfm_cli::fix_exit(&self.outcome);
        (exit.code(), exit.meaning())
    }
}
