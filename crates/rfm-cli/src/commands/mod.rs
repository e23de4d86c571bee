//! One module per subcommand. Only this crate prints.

mod compare;
pub(crate) mod diagnose;
pub(crate) mod fix;
mod inspect;
mod simulate;
mod update;

use std::path::Path;

use fe_model::CaseFile;

use crate::exit::Failure;

pub use compare::{CompareArgs, CompareRun, compare};
pub use diagnose::{DiagnoseArgs, diagnose, diagnosis_data, diagnosis_json, run_diagnosis, write_applied};
pub use fix::{FixArgs, fix, fix_exit, fix_options, progress_lines as fix_progress_lines, save_fix};
pub use inspect::inspect;
pub use simulate::{SimulateArgs, simulate, synthesised};
pub use update::{
    Overrides as UpdateOverrides, UpdateSetup, finish_update, save_update, update, update_json, updated_case,
};

/// A command's result: its exit code, or why it failed (see [`Failure`]).
pub type Result<T> = std::result::Result<T, Failure>;

/// A data file to copy into an output (FRFs given in memory to the Python
/// package, written to a temporary file that the cases written must not
/// name): its extension (`csv` when it has none) and its bytes.
pub(crate) fn carried_file(file: &Path) -> Result<(String, Vec<u8>)> {
    let bytes = std::fs::read(file)
        .map_err(|e| Failure::input(format!("{}: cannot read the data to copy ({e})", file.display())))?;
    let ext = file.extension().map_or("csv".into(), |e| e.to_string_lossy().into_owned());
    Ok((ext, bytes))
}

pub(crate) fn load_case(path: &Path) -> Result<CaseFile> {
    Ok(CaseFile::load(path)?)
}

/// A case made ready ([`rfm_update::Study`]); a failure to read its
/// measured data says, besides what went wrong, what the case wants and
/// what the file holds, so that a wrong file is seen as such at once
/// rather than one symptom at a time.
pub(crate) fn load_study(path: &Path) -> Result<rfm_update::Study> {
    load_study_measured(path, None)
}

/// [`load_study`], reading the measured FRFs from `measured` when given
/// (`--measured`) instead of the case's own data or `[truth]`; the cases
/// the command writes then name that file ([`CaseFile::with_data`]).
pub(crate) fn load_study_measured(path: &Path, measured: Option<&Path>) -> Result<rfm_update::Study> {
    let case = load_case(path)?;
    match measured {
        Some(file) => study_of(case.with_data(file)?),
        None => study_of(case),
    }
}

/// [`load_study`] of a loaded case.
pub(crate) fn study_of(case: CaseFile) -> Result<rfm_update::Study> {
    let spec = case.measurement.clone();
    rfm_update::Study::from_case(case)
        .map_err(|e| mismatch(e.into(), spec.as_ref(), spec.as_ref().and_then(|s| s.data.as_deref())))
}

/// `failure` with what the case wants and what `file` holds, when it is
/// about that file (its message names it) and the file can be read as it is.
pub(crate) fn mismatch(
    failure: Failure,
    spec: Option<&fe_model::case::MeasurementSpec>,
    file: Option<&Path>,
) -> Failure {
    let (Some(spec), Some(file)) = (spec, file) else {
        return failure;
    };
    let name = file.display().to_string();
    if !failure.message.contains(&name) {
        return failure;
    }
    match inspect::file_holds(file) {
        Some(holds) => Failure {
            message: format!(
                "{}\n  the case wants {}\n  {} holds {holds}",
                failure.message,
                inspect::case_wants(spec),
                name
            ),
            ..failure
        },
        None => failure,
    }
}

/// Tells what the case's `[measurement] mask` left out of the measured data:
/// on standard output with the tables, on standard error beside `--json`
/// so that the JSON stays whole.
pub(crate) fn print_masked(masked: &[String], json: bool) -> Result<()> {
    if masked.is_empty() {
        return Ok(());
    }
    const SHOWN: usize = 10;
    let mut text =
        format!("left out of the measured data, as the case's [measurement] mask allows ({}):", masked.len());
    for m in masked.iter().take(SHOWN) {
        text.push_str(&format!("\n  - {m}"));
    }
    if masked.len() > SHOWN {
        text.push_str(&format!("\n  ... and {} more", masked.len() - SHOWN));
    }
    if json {
        eprintln!("{text}");
    } else {
        outln!("{text}");
    }
    Ok(())
}

/// A library result that does not carry them as JSON, with the notes on
/// how its measured data were read (units, gains, the test nodes paired by
/// coordinates, ...) under `notes`, as `results.json` and `compare --json`
/// have them.
#[derive(serde::Serialize)]
pub struct WithNotes<'a, T: serde::Serialize> {
    /// The notes on reading the measured data.
    pub notes: &'a [String],
    /// The result.
    #[serde(flatten)]
    pub result: &'a T,
}

/// Tells what reading the measured data changed or passed over (lines at
/// 0 Hz dropped, units scaled, kinds converted, datasets skipped), where
/// [`print_masked`] tells what the mask left out.
pub(crate) fn print_notes(notes: &[String], json: bool) -> Result<()> {
    if notes.is_empty() {
        return Ok(());
    }
    let mut text = format!("read from the measured data ({}):", notes.len());
    for n in notes {
        text.push_str(&format!("\n  - {n}"));
    }
    if json {
        eprintln!("{text}");
    } else {
        outln!("{text}");
    }
    Ok(())
}
