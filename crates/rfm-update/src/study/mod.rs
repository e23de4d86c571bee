//! A study: a case file turned into a model, measured data and an updating
//! set-up, ready for a solver.
//!
//! This file makes the study (loading, the initial model's check, gains);
//! beside it, one concern per file: `lines.rs` the updating lines,
//! `weights.rs` the residual weights, `response_function_method.rs` and
//! `output_error.rs` the two runs, `outcome.rs` what they return and
//! `natural_frequencies.rs` the table of natural frequencies in it.

mod lines;
mod natural_frequencies;
mod outcome;
mod output_error;
mod response_function_method;
mod weights;

use damping::DampedSystem;
use fe_model::case::{FrequencyChoice, Gains, MeasurementSpec};
use fe_model::{CaseFile, DofRef, Parameter};
use frf::{Channel, FrfKind, FrfSet, NoiseModel};

pub use crate::measured::read_measured_for;
pub use natural_frequencies::{FrequencyTable, MAX_UNDAMPED_DOFS, natural_frequencies};
pub use outcome::{ParameterReport, Restart, UpdateOutcome, describe_masked};
pub use weights::{line_weights_for, residual_noise_for};

use crate::error::UpdateError;
use crate::gain;
use crate::params::ParameterSet;

/// An updating method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
pub enum Method {
    /// The response function method (the paper's).
    Rfm,
    /// Output-error Levenberg-Marquardt with uncertainty.
    OutputError,
}

impl Method {
    /// Parses `rfm` or `output-error`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "rfm" => Some(Method::Rfm),
            "output-error" | "oe" => Some(Method::OutputError),
            _ => None,
        }
    }

    /// The name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Method::Rfm => "rfm",
            Method::OutputError => "output-error",
        }
    }
}

/// A case made ready for updating.
///
/// Its parts agree with one another: the system is the case's model, the
/// measured data are receptances on the case's channels, the gains are
/// decided from the case and the data, and the updating lines are those the
/// case chooses among the measured lines. So they are read through
/// accessors, and changed only by the methods that keep them agreeing
/// ([`Study::set_update_frequencies`], [`Study::set_gains_for`]).
#[derive(Clone, Debug)]
pub struct Study {
    case: CaseFile,
    system: DampedSystem,
    truth: Option<DampedSystem>,
    measured: FrfSet,
    parameters: Vec<Parameter>,
    update_frequencies_hz: Vec<f64>,
    masked: Vec<frf::io::Masked>,
    notes: Vec<String>,
    measured_kind: FrfKind,
    gains: Gains,
    gains_reason: String,
    per_volt: Vec<DofRef>,
    pairing: Vec<PairingReport>,
}

/// A test node paired with a model node by coordinates, as stored with the
/// results (`[measurement] pair = "coordinates"`).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct PairingReport {
    /// Test node label.
    pub test_node: i64,
    /// Model node.
    pub model_node: u32,
    /// Distance in the model's plane (m).
    pub distance_m: f64,
    /// Its test directions as model DOFs (`+Z -> uy`).
    pub directions: Vec<String>,
}

impl PairingReport {
    /// The reports of a reader's pairing.
    pub fn of(paired: &[frf::io::uff::PairedNode]) -> Vec<PairingReport> {
        paired
            .iter()
            .map(|p| PairingReport {
                test_node: p.test_node,
                model_node: p.model_node,
                distance_m: p.distance_m,
                directions: p.directions.clone(),
            })
            .collect()
    }
}

fn channels_of(m: &MeasurementSpec) -> Vec<Channel> {
    m.channels().into_iter().map(|(resp, r)| Channel::new(resp, r)).collect()
}

impl Study {
    /// Loads a case file and prepares the study.
    pub fn load(path: &std::path::Path) -> Result<Self, UpdateError> {
        Self::from_case(CaseFile::load(path)?)
    }

    /// Prepares a study from a loaded case: synthesises measured data from the
    /// truth (with noise) or reads it from the data file, and resolves the
    /// updating lines.
    pub fn from_case(case: CaseFile) -> Result<Self, UpdateError> {
        let system = DampedSystem::new(case.model.clone())?;
        let spec = case
            .measurement
            .as_ref()
            .ok_or_else(|| UpdateError::Case(case.error(None, "the case has no [measurement] section")))?;
        let truth = case.truth.as_ref().map(|t| DampedSystem::new(t.model.clone())).transpose()?;
        let channels = channels_of(spec);
        let mut grid = spec.frequencies_hz.clone();
        if let (Some(update), None) = (&case.update, &spec.data) {
            // synthesised data: make sure the chosen points are lines of it
            if let Some(FrequencyChoice::List(points)) = &update.frequencies {
                grid.extend(points.iter().copied());
                grid.sort_by(f64::total_cmp);
                grid.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * b.abs());
            }
        }
        let mut masked = Vec::new();
        let mut notes = Vec::new();
        let mut measured_kind = FrfKind::Receptance;
        let mut per_volt = Vec::new();
        let mut pairing = Vec::new();
        let measured = match (&spec.data, &case.truth, &truth) {
            (Some(path), _, _) => {
                let mut read = read_measured_for(&system, path, Some(spec))?;
                masked = read.masked.clone();
                notes = read.notes.iter().map(|n| format!("{}: {n}", path.display())).collect();
                notes.extend(weights::attach_floor_weights(&mut read.set).map(|n| format!("{}: {n}", path.display())));
                measured_kind = read.set.kind();
                per_volt = read.per_volt_references();
                pairing = PairingReport::of(&read.pairing);
                let set = read.set.to_receptance();
                let index = set.channel_indices();
                let idx = channels
                    .iter()
                    .map(|c| {
                        index.get(c).copied().ok_or_else(|| {
                            UpdateError::Data(format!(
                                "{}: the data has no channel {c} that the case lists",
                                path.display()
                            ))
                        })
                    })
                    .collect::<Result<Vec<usize>, _>>()?;
                set.select_channels(&idx)
            }
            (None, Some(spec_t), Some(truth)) => {
                let mut set = frf::synthesize(truth, &channels, &grid)?;
                NoiseModel { relative: spec_t.noise, floor: spec_t.floor, seed: spec_t.seed }.apply(&mut set);
                notes.extend(weights::attach_floor_weights(&mut set));
                set
            }
            _ => {
                return Err(case.measured_source().err().map_or_else(
                    || UpdateError::Data("the case gives no measured data and no [truth]".into()),
                    UpdateError::Case,
                ));
            }
        };
        let parameters = case.update.as_ref().map(|u| u.parameters.clone()).unwrap_or_default();
        let (gains, gains_reason) = gain::decide(Some(spec), case.update.as_ref(), &per_volt)?;
        if gains != Gains::None {
            notes.push(format!("model FRFs are multiplied by fitted gains ({gains}): {gains_reason}"));
        }
        let mut study = Study {
            case,
            system,
            truth,
            measured,
            parameters,
            update_frequencies_hz: Vec::new(),
            masked,
            notes,
            measured_kind,
            gains,
            gains_reason,
            per_volt,
            pairing,
        };
        if study.case.update.is_some() {
            study.update_frequencies_hz = study.lines_for(study.method())?;
        }
        Ok(study)
    }

    /// Prepares a study from a loaded case and measured receptances that the
    /// caller holds (the loop of [`crate::fix`] keeps one data set while the
    /// model grows). The channels must be those of the case's measurement.
    /// The case's truth, if any, is not built: the data are given.
    pub fn with_measured(case: CaseFile, mut measured: FrfSet) -> Result<Self, UpdateError> {
        let notes = weights::attach_floor_weights(&mut measured).into_iter().collect();
        let system = DampedSystem::new(case.model.clone())?;
        let parameters = case.update.as_ref().map(|u| u.parameters.clone()).unwrap_or_default();
        // the data's per-volt references are not known here: the caller that
        // read them sets `gains` (see `gain::decide`) when they differ
        let (gains, gains_reason) = gain::decide(case.measurement.as_ref(), case.update.as_ref(), &[])?;
        let mut study = Study {
            case,
            system,
            truth: None,
            measured,
            parameters,
            update_frequencies_hz: Vec::new(),
            masked: Vec::new(),
            notes,
            measured_kind: FrfKind::Receptance,
            gains,
            gains_reason,
            per_volt: Vec::new(),
            pairing: Vec::new(),
        };
        if study.case.update.is_some() {
            study.update_frequencies_hz = study.lines_for(study.method())?;
        }
        Ok(study)
    }

    /// The case file.
    pub fn case(&self) -> &CaseFile {
        &self.case
    }

    /// The initial model.
    pub fn system(&self) -> &DampedSystem {
        &self.system
    }

    /// The truth model of a simulated study.
    pub fn truth(&self) -> Option<&DampedSystem> {
        self.truth.as_ref()
    }

    /// Measured receptances on the measurement lines.
    pub fn measured(&self) -> &FrfSet {
        &self.measured
    }

    /// Parameters to update (empty when the case has no `[update]`).
    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// Lines used for updating (Hz) by the case's method: the case's
    /// choice, else the method's default ([`Study::lines_for`]); empty when
    /// the case has no `[update]`.
    pub fn update_frequencies_hz(&self) -> &[f64] {
        &self.update_frequencies_hz
    }

    /// What the case's `[measurement] mask` left out of the measured file.
    pub fn masked(&self) -> &[frf::io::Masked] {
        &self.masked
    }

    /// What reading the measured file changed or passed over (lines at
    /// 0 Hz dropped, units scaled, kinds converted, datasets skipped), one
    /// line each, to be shown and stored with the results.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The kind of the measured data as read ([`Study::measured`] itself
    /// is receptance, for the updating methods); comparisons are made in
    /// it, whichever way the data arrive.
    pub fn measured_kind(&self) -> FrfKind {
        self.measured_kind
    }

    /// The unknown gains every comparison and fit of this study applies to
    /// the model's FRFs ([`crate::gain`]): `Gains::None` for per-newton data
    /// unless the case asks for gains.
    pub fn gains(&self) -> Gains {
        self.gains
    }

    /// Why those gains, in words (for the notes and reports).
    pub fn gains_reason(&self) -> &str {
        &self.gains_reason
    }

    /// The references whose data are per volt (uncalibrated).
    pub fn per_volt(&self) -> &[DofRef] {
        &self.per_volt
    }

    /// How the test nodes were paired with the model's by coordinates
    /// (empty unless the case asks for it).
    pub fn pairing(&self) -> &[PairingReport] {
        &self.pairing
    }

    /// Sets the case's `[update] frequencies` to `choice` and the updating
    /// lines with it ([`Study::update_frequencies_hz`]), so that both
    /// methods and every output fit the lines it designates. Refused
    /// (`UpdateError::Case`) when the case has no `[update]`, and as
    /// [`Study::lines_for`] refuses a choice that designates no measured line.
    pub fn set_update_frequencies(&mut self, choice: FrequencyChoice) -> Result<(), UpdateError> {
        let Some(update) = self.case.update.as_mut() else {
            return Err(UpdateError::Case(
                self.case.error(None, "the case has no [update] section to choose updating lines for"),
            ));
        };
        let before = update.frequencies.replace(choice);
        match self.lines_for(self.method()) {
            Ok(lines) => {
                self.update_frequencies_hz = lines;
                Ok(())
            }
            Err(e) => {
                // a refused choice leaves the study as it was
                self.case.update.as_mut().expect("checked above").frequencies = before;
                Err(e)
            }
        }
    }

    /// The updating method the case asks for (`rfm` when it does not say).
    pub fn method(&self) -> Method {
        match self.case.update.as_ref().and_then(|u| u.method.as_ref()).map(|m| m.0.as_str()) {
            Some("output-error") => Method::OutputError,
            _ => Method::Rfm,
        }
    }

    /// Checks the case's method name; returns it parsed.
    pub fn checked_method(&self) -> Result<Method, UpdateError> {
        match self.case.update.as_ref().and_then(|u| u.method.as_ref()) {
            None => Ok(Method::Rfm),
            Some((m, span)) => Method::parse(m).ok_or_else(|| {
                UpdateError::Case(
                    self.case.error(Some(span.clone()), format!("unknown method `{m}` (available: rfm, output-error)")),
                )
            }),
        }
    }

    /// Parameter names.
    pub fn parameter_names(&self) -> Vec<String> {
        self.parameters.iter().map(|p| p.name.clone()).collect()
    }

    /// The parameters as a set for the solvers.
    pub fn parameter_set(&self) -> ParameterSet {
        ParameterSet::new(self.parameters.clone())
    }

    /// The measured data at the updating lines.
    pub fn measured_at_update_lines(&self) -> Result<FrfSet, UpdateError> {
        Ok(self.measured.at_frequencies(&self.update_frequencies_hz)?)
    }

    /// Evaluates the initial model at the lines of `measured`, so that a
    /// model that cannot be evaluated is refused with the reason and the
    /// line before any iteration (the solvers would only see that the
    /// misfit is not a number).
    pub fn check_initial(&self, measured: &FrfSet) -> Result<(), UpdateError> {
        let model = frf::synthesize(&self.system, measured.channels(), measured.frequencies_hz())?;
        for (c, channel) in model.channels().iter().enumerate() {
            if let Some(k) = model.channel(c).iter().position(|v| !(v.re.is_finite() && v.im.is_finite())) {
                return Err(UpdateError::Numerics(format!(
                    "the initial model's receptance {channel} at {} Hz is {}: a value of the model is out of the \
                     range double precision holds (a modulus, density, stiffness or damping coefficient many \
                     orders of magnitude off?)",
                    model.frequencies_hz()[k],
                    model.get(c, k)
                )));
            }
        }
        if model.values().iter().all(|v| v.norm_sqr() == 0.0) {
            return Err(UpdateError::Numerics(format!(
                "the initial model's receptances are zero at every updating line ({} to {} Hz): a value of the \
                 model is out of the range double precision holds (a modulus or stiffness many orders of \
                 magnitude too large?)",
                model.frequencies_hz()[0],
                model.frequencies_hz()[model.n_freq() - 1]
            )));
        }
        let synthesised = self.case.measurement.as_ref().is_some_and(|m| m.data.is_none());
        for (c, channel) in measured.channels().iter().enumerate() {
            if synthesised && measured.channel(c).iter().all(|v| v.norm_sqr() == 0.0) {
                return Err(UpdateError::Numerics(format!(
                    "the FRF {channel} synthesised from the case's truth model is zero at every updating line: a \
                     value of the truth model is out of the range double precision holds"
                )));
            }
            if measured.channel(c).iter().all(|v| v.norm_sqr() == 0.0) {
                return Err(UpdateError::Data(format!(
                    "the measured FRF {channel} is zero at every updating line: a relative misfit cannot be formed"
                )));
            }
        }
        Ok(())
    }

    /// Decides the gains again for measured data read from another file
    /// (`--measured`): from the case and that file's per-volt references,
    /// as [`Study::from_case`] does for the case's own data.
    pub fn set_gains_for(&mut self, read: &frf::io::Measured) -> Result<(), UpdateError> {
        self.per_volt = read.per_volt_references();
        (self.gains, self.gains_reason) =
            gain::decide(self.case.measurement.as_ref(), self.case.update.as_ref(), &self.per_volt)?;
        Ok(())
    }

    /// The diagnosis options of this study for `measured` (its data, or
    /// other data on its channels): the defaults, with the study's gains
    /// (per reference or per channel) fitted with every candidate, and the
    /// residual weights of [`Study::line_weights`] at the lines of
    /// `measured` (the coherence's, by default when the data carry it).
    pub fn diagnose_options(&self, measured: &FrfSet) -> Result<crate::diagnose::DiagnoseOptions, UpdateError> {
        let weights = self.line_weights(measured)?;
        Ok(crate::diagnose::DiagnoseOptions { gains: self.gains, weights, ..Default::default() })
    }

    /// The measured FRFs in the kind they were measured in (`measured` is
    /// receptance): what comparisons show.
    pub fn measured_as_read(&self) -> FrfSet {
        self.measured.converted(self.measured_kind)
    }

    /// Fits this study's gains ([`Study::gains`]) to `model` (the model's
    /// FRFs on the channels and lines of `measured`, in any kind) against
    /// `measured`, weighted by [`Study::line_weights`].
    pub fn fit_gains(&self, model: &FrfSet, measured: &FrfSet) -> Result<gain::FittedGains, UpdateError> {
        let model = if model.kind() == measured.kind() { model.clone() } else { model.converted(measured.kind()) };
        let weights = self.line_weights(measured)?;
        gain::fit_gains(&model, measured, weights.as_deref(), self.gains)
    }

    /// The initial values of the updating parameters.
    pub fn system_values(&self) -> Vec<f64> {
        self.parameter_set().values(&self.system)
    }
}
