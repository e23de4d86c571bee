//! TOML case files: the model, where the measured data comes from, the truth
//! of a simulated study, and what to update.
//!
//! The format is described with an annotated example in `docs/case-files.md`;
//! every case under `cases/` is a working example. Errors name the file, the
//! line and the column.
//!
//! One concern per file: `raw.rs` is the serde mirror of the TOML, `build.rs`
//! builds the model from it, `truth.rs`, `update.rs`, `check.rs` and
//! `measurement.rs` read the other tables into the types of `spec.rs` (and
//! `measurement.rs`), `dof_list.rs` and `frequencies.rs` the value syntaxes
//! they share; `edit.rs` edits a case's text. This file loads a case and
//! holds what they all use: the place of an error, and the suggestion of the
//! closest valid name.

use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::error::{CaseError, ModelError};
use crate::model::Model;

mod build;
mod check;
mod dof_list;
mod edit;
mod frequencies;
mod imported;
mod lookup;
mod measurement;
mod raw;
mod spec;
mod spring_axes;
#[cfg(test)]
mod tests;
mod truth;
mod update;

pub use build::MAX_LINE_ELEMENTS;
pub use dof_list::{parse_dof_list, parse_dof_range};
pub use edit::CaseEditor;
pub use measurement::{
    Calibration, CalibrationTarget, ChannelCorrection, ChannelMap, DEFAULT_COHERENCE_THRESHOLD, FittedGain, GainKey,
    Gains, MaskRule, MeasurementSpec, PairingSpec,
};
pub use spec::{
    BandWeight, CheckSpec, DiagnosisCheck, EFFECT_KINDS, FrequencyChoice, HistoryEntry, PaperSpec, RUN_STATUSES,
    RunCheck, TruthSpec, UpdateSpec,
};

use dof_list::parse_dof_refs;
use frequencies::parse_frequencies;
use measurement::parse_measurement;
use raw::one;

/// A loaded, validated case file.
#[derive(Clone, Debug)]
pub struct CaseFile {
    /// Path it was read from.
    pub path: PathBuf,
    /// Its text.
    pub source: String,
    /// Free-text description.
    pub description: Option<String>,
    /// The (initial) model.
    pub model: Model,
    /// Measurement description.
    pub measurement: Option<MeasurementSpec>,
    /// Truth of a simulated study.
    pub truth: Option<TruthSpec>,
    /// Updating setup.
    pub update: Option<UpdateSpec>,
    /// Published values.
    pub paper: Option<PaperSpec>,
    /// The misfit after each step that led to this case (`[[history]]`).
    pub history: Vec<HistoryEntry>,
    /// Acceptance of the case's results (`[check]`).
    pub check: Option<CheckSpec>,
    /// The files of `[imported]` (node file, DOF tables, matrices), resolved.
    pub imported_files: Vec<PathBuf>,
}

struct Ctx<'a> {
    path: &'a Path,
    source: &'a str,
}

impl Ctx<'_> {
    fn err(&self, span: Range<usize>, message: impl Into<String>) -> CaseError {
        CaseError::at(self.path, self.source, Some(span), message.into())
    }
    fn model_err(&self, span: Range<usize>, e: ModelError) -> CaseError {
        self.err(span, e.to_string())
    }
    /// An error about the file as a whole (no line to point at).
    fn whole(&self, message: impl Into<String>) -> CaseError {
        CaseError::at(self.path, self.source, None, message.into())
    }
}

impl CaseFile {
    /// Reads and validates a case file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, CaseError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| CaseError {
            file: path.to_path_buf(),
            location: None,
            message: format!("cannot read the case file: {e}"),
            snippet: None,
        })?;
        let source = crate::text::decode(&bytes).map_err(|e| CaseError {
            file: path.to_path_buf(),
            location: Some(crate::error::Location { line: e.line, column: e.column }),
            message: e.to_string(),
            snippet: None,
        })?;
        Self::parse(path, source)
    }

    /// The files a run of this case reads: the case file itself, its
    /// measured data file and test geometry, and its imported matrices and
    /// tables. Outputs must never be written over them.
    pub fn inputs(&self) -> Vec<PathBuf> {
        let data = self.measurement.as_ref().and_then(|m| m.data.clone());
        let geometry = self.measurement.as_ref().and_then(|m| m.geometry.clone());
        std::iter::once(self.path.clone()).chain(data).chain(geometry).chain(self.imported_files.clone()).collect()
    }

    /// Parses case-file text; `path` is used in messages and to resolve data files.
    pub fn parse(path: &Path, source: &str) -> Result<Self, CaseError> {
        let ctx = Ctx { path, source };
        let raw: raw::RawCase = toml::from_str(source)
            .map_err(|e| CaseError::at(path, source, e.span(), with_suggestion(e.message().trim_end())))?;
        let dimension = build::dimension(&ctx, &raw)?;
        let mut model = Model::with_dimension(raw.title.as_deref().unwrap_or("untitled"), dimension);
        build::build_model(&ctx, &raw, &mut model)?;
        for (name, v) in &raw.set {
            let q = model.quantity(name).map_err(|e| ctx.model_err(v.span(), e))?;
            model.set(q, *v.get_ref()).map_err(|e| ctx.model_err(v.span(), e))?;
        }
        // Assemble once so that structural errors are reported at load time.
        crate::assembly::Assembly::new(&model).map_err(|e| ctx.whole(e.to_string()))?;

        let measurement = raw.measurement.as_ref().map(|m| parse_measurement(&ctx, m, &model)).transpose()?;
        let truth = raw.truth.as_ref().map(|t| truth::parse_truth(&ctx, t, &model)).transpose()?;
        let update = raw.update.as_ref().map(|u| update::parse_update(&ctx, u, &model)).transpose()?;
        let paper = raw
            .paper
            .as_ref()
            .map(|p| {
                let p = p.get_ref();
                let values = truth::resolve_values(&ctx, &p.values, &model)?;
                Ok::<_, CaseError>(PaperSpec {
                    source: p.source.clone(),
                    values,
                    frequencies_hz: p.frequencies_hz.clone(),
                    note: p.note.clone(),
                })
            })
            .transpose()?;
        let history = raw
            .history
            .iter()
            .map(|h| {
                let r = h.get_ref();
                let bad = |v: f64| !(v.is_finite() && v >= 0.0);
                if bad(r.misfit) || r.noise.is_some_and(bad) {
                    return Err(ctx.err(h.span(), "a history entry's misfit and noise must be finite and not negative"));
                }
                if let Some(e) = r.effect.as_deref().filter(|e| !EFFECT_KINDS.contains(e)) {
                    let hint = hint(e, &EFFECT_KINDS, "effects");
                    return Err(ctx.err(h.span(), format!("a history entry names the unknown effect `{e}`{hint}")));
                }
                Ok(HistoryEntry {
                    step: r.step.clone(),
                    misfit: r.misfit,
                    noise: r.noise,
                    effect: r.effect.clone(),
                    nodes: r.nodes.clone(),
                    elements: r.elements.clone(),
                })
            })
            .collect::<Result<Vec<_>, CaseError>>()?;
        let check =
            raw.check.as_ref().map(|c| check::parse_check(&ctx, c, truth.as_ref(), update.as_ref())).transpose()?;
        Ok(CaseFile {
            path: path.to_path_buf(),
            source: source.to_string(),
            description: raw.description,
            model,
            measurement,
            truth,
            update,
            paper,
            history,
            check,
            imported_files: raw.imported.as_ref().map(|i| imported::files(&ctx, i)).unwrap_or_default(),
        })
    }

    /// Whether the case gives something to compare with: a `data` file, or
    /// a `[truth]` to synthesise the data from. A measurement with neither
    /// is only the lines and channels to synthesise (`rfm simulate` of a
    /// model written apart); the error, located at `[measurement]`, is for
    /// the commands that compare.
    pub fn measured_source(&self) -> Result<(), CaseError> {
        match &self.measurement {
            Some(m) if m.data.is_none() && self.truth.is_none() => {
                let message = "the measurement has no `data` file and the case has no [truth] to synthesise it from";
                Err(m.place.as_ref().map_or_else(|| self.error(None, message), |p| p.with_message(message)))
            }
            _ => Ok(()),
        }
    }

    /// A located error about this file (for checks done by higher layers).
    pub fn error(&self, span: Option<Range<usize>>, message: impl Into<String>) -> CaseError {
        CaseError::at(&self.path, &self.source, span, message.into())
    }
}

/// A serde message about an unknown key (`unknown field `alpah`, expected
/// one of `alpha`, `beta`, ...`) with the closest valid key suggested.
fn with_suggestion(message: &str) -> String {
    let Some(rest) = message.strip_prefix("unknown field `") else { return message.to_string() };
    let Some((word, expected)) = rest.split_once('`') else { return message.to_string() };
    // the valid keys are the backquoted names after the unknown one
    let valid: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
    match crate::suggest::closest(word, valid.iter().copied()) {
        Some(best) => format!("{message}; did you mean `{best}`?"),
        None => message.to_string(),
    }
}

/// The end of a message about a name that is not one of `valid`: the
/// closest valid name (`; did you mean `beam`?`), or the list of them
/// introduced by `listed` (` (defined: steel, aluminium)`).
fn hint(word: &str, valid: &[&str], listed: &str) -> String {
    match crate::suggest::closest(word, valid.iter().copied()) {
        Some(best) => format!("; did you mean `{best}`?"),
        None => format!(" ({listed}: {})", if valid.is_empty() { "none".into() } else { valid.join(", ") }),
    }
}
